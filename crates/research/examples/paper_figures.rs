//! Eq. 1 over folders of binary crack masks (PNG, non-zero = crack), and what eq. 2 makes of it
//! on a 200 × 100 mm plate. Without arguments: the real masks of `../shared/data/cracks`
//! (crackforest and uav75, train and val).
//!
//! ```text
//! cargo run --release -p crackbot-research --example paper_figures [-- DIR ...]
//! ```

use std::path::PathBuf;

use crackbot_planner::{mean_crack_length, scan_rows_count, BinaryMask, PAPER_EQ1};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut dirs: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    if dirs.is_empty() {
        let cracks = crackbot_datasets::require(crackbot_datasets::CRACKS);
        dirs = ["crackforest", "uav75"]
            .iter()
            .map(|d| cracks.join(d).join("masks"))
            .collect();
    }
    println!(
        "| masks | N_c | Ā px | w̄ px | L̄ px | L̄ / H | L̄ mm (h = 100) | N_s γ = 0.25 / 0.5 / 0.75 |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let p = PAPER_EQ1;
    println!(
        "| paper | {} | {} | {} | {} | {:.3} (of 480 px) | {:.2} | 13 / 7 / 5 |",
        p.n_c,
        p.mean_area_px,
        p.mean_width_px,
        p.mean_length_px,
        p.mean_length_px / p.camera_height_px,
        p.mean_length_px / p.camera_height_px * 100.0
    );
    for dir in dirs {
        let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")))
            .collect();
        files.sort();
        let mut masks = Vec::with_capacity(files.len());
        for f in &files {
            let img = image::open(f)?.to_luma8();
            let (w, h) = img.dimensions();
            masks.push(BinaryMask::new(
                w as usize,
                h as usize,
                img.pixels().map(|p| p.0[0] > 0).collect(),
            )?);
        }
        let e = mean_crack_length(masks)?;
        let l_mm = e.mean_length_mm(100.0);
        let ns: Vec<String> = [0.25, 0.5, 0.75]
            .iter()
            .map(|g| scan_rows_count(100.0, *g, l_mm).map(|n| n.to_string()))
            .collect::<Result<_, _>>()?;
        println!(
            "| {} | {} | {:.1} | {:.2} | {:.1} | {:.3} | {:.1} | {} |",
            dir.display(),
            e.n_c,
            e.mean_area_px,
            e.mean_width_px,
            e.mean_length_px,
            e.mean_length_fraction_of_height,
            l_mm,
            ns.join(" / ")
        );
    }
    Ok(())
}
