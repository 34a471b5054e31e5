//! `crackbot calibrate target`: the printable target and its description.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use crackbot_calib_target::{print::write_png, TargetSpec};

/// Arguments of `crackbot calibrate target`.
#[derive(Debug, Args)]
pub struct TargetArgs {
    /// Folder for target.png and target.toml.
    #[arg(long, default_value = "out/target")]
    pub out: PathBuf,
    /// Printing resolution, pixels per millimetre (23.622 = 600 dpi).
    #[arg(long, default_value_t = 23.622)]
    pub px_per_mm: f64,
    /// Tags across.
    #[arg(long)]
    pub cols: Option<u32>,
    /// Tags up.
    #[arg(long)]
    pub rows: Option<u32>,
    /// Side of a tag's black square, mm.
    #[arg(long)]
    pub tag_mm: Option<f64>,
    /// White space between tags, mm (at least a quarter of --tag-mm).
    #[arg(long)]
    pub gap_mm: Option<f64>,
    /// Id of the bottom-left tag.
    #[arg(long)]
    pub first_id: Option<u32>,
    /// White paper around the grid, mm.
    #[arg(long)]
    pub margin_mm: Option<f64>,
}

/// Writes the target's PNG and TOML.
pub fn run(a: &TargetArgs) -> Result<()> {
    let d = TargetSpec::default();
    let spec = TargetSpec {
        cols: a.cols.unwrap_or(d.cols),
        rows: a.rows.unwrap_or(d.rows),
        tag_mm: a.tag_mm.unwrap_or(d.tag_mm),
        gap_mm: a.gap_mm.unwrap_or(d.gap_mm),
        first_id: a.first_id.unwrap_or(d.first_id),
        margin_mm: a.margin_mm.unwrap_or(d.margin_mm),
        ..d
    };
    spec.check()?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let png = a.out.join("target.png");
    let img = write_png(&spec, a.px_per_mm, &png)?;
    let toml = a.out.join("target.toml");
    spec.save(&toml)?;
    let (lo, hi) = spec.sheet_mm();
    println!(
        "{}: {} × {} px at {} px/mm ({:.0} dpi): a sheet of {:.1} × {:.1} mm, {} × {} tag36h11 tags \
         (ids {}–{}) of {} mm",
        png.display(),
        img.width(),
        img.height(),
        a.px_per_mm,
        a.px_per_mm * 25.4,
        hi[0] - lo[0],
        hi[1] - lo[1],
        spec.cols,
        spec.rows,
        spec.first_id,
        spec.first_id + spec.cols * spec.rows - 1,
        spec.tag_mm
    );
    println!(
        "{}: its description (pass it as --target). Print at 100 % and check one tag's black \
         square measures {} mm; if not, write the measured size into tag_mm.",
        toml.display(),
        spec.tag_mm
    );
    Ok(())
}
