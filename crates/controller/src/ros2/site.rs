//! What the controller reads of the site file (the robot's `--site FILE`, TOML): the arm's box
//! and speeds (`[arm]`, the limits every command is checked against) and where the plate lies
//! in the arm's base frame (`[surface]`, [`SurfaceFrame`]). Other tables are the robot's and are
//! left alone; [`write_surface`] replaces `[surface]` only, keeping the file's comments.

use std::path::Path;

use serde::Deserialize;

use crate::limits::Limits;
use crate::motion::frame::{FrameError, SurfaceFrame};

/// The site file's `[arm]` table (the robot reads the same keys).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(default)]
pub struct ArmTable {
    /// Lower corner of the reachable box on the surface, mm `[x, y]`.
    pub workspace_min_mm: [f64; 2],
    /// Upper corner, mm.
    pub workspace_max_mm: [f64; 2],
    /// Slide speed, mm/s (slides up to 4 times it are accepted).
    pub slide_speed_mm_s: f64,
    /// Travel speed, mm/s (moves up to twice it are accepted).
    pub travel_speed_mm_s: f64,
}

impl Default for ArmTable {
    fn default() -> Self {
        ArmTable {
            workspace_min_mm: [0.0, 0.0],
            workspace_max_mm: [200.0, 100.0],
            slide_speed_mm_s: 3.89,
            travel_speed_mm_s: 50.0,
        }
    }
}

#[derive(Debug, Deserialize)]
struct SiteFile {
    #[serde(default)]
    arm: ArmTable,
    surface: Option<SurfaceFrame>,
}

/// The controller's share of a site.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmSite {
    /// The limits (the simulated arm's rule: travel up to twice, slides up to four times the
    /// site's speeds).
    pub limits: Limits,
    /// Where the plate lies in the base frame, checked.
    pub surface: SurfaceFrame,
}

/// A site file the controller cannot use.
#[derive(Debug, thiserror::Error)]
pub enum SiteError {
    /// Not readable.
    #[error("reading the site file {path}: {source}")]
    Read {
        /// The file.
        path: String,
        /// Why.
        source: std::io::Error,
    },
    /// Not TOML, or a table holds a wrong key.
    #[error("the site file {path}: {source}")]
    Parse {
        /// The file.
        path: String,
        /// Why.
        source: Box<toml_edit::TomlError>,
    },
    /// Not TOML, or a table holds a wrong key.
    #[error("the site file {path}: {source}")]
    Value {
        /// The file.
        path: String,
        /// Why.
        source: Box<toml::de::Error>,
    },
    /// No `[surface]`: the plate was never registered.
    #[error("the site file {path} has no [surface] table: register the plate first (crackbot-controller register)")]
    NoSurface {
        /// The file.
        path: String,
    },
    /// `[surface]` holds broken values.
    #[error("the site file {path}: {source}")]
    Surface {
        /// The file.
        path: String,
        /// Why.
        source: FrameError,
    },
    /// `[arm]` holds a box or speeds that cannot be.
    #[error("the site file {path}: arm.{key} = {value} cannot be ({why})")]
    Arm {
        /// The file.
        path: String,
        /// Which key.
        key: &'static str,
        /// Its value.
        value: f64,
        /// Why.
        why: &'static str,
    },
    /// The file could not be written.
    #[error("writing the site file {path}: {source}")]
    Write {
        /// The file.
        path: String,
        /// Why.
        source: std::io::Error,
    },
}

fn limits_of(arm: &ArmTable, path: &str) -> Result<Limits, SiteError> {
    let bad = |key, value, why| SiteError::Arm {
        path: path.to_string(),
        key,
        value,
        why,
    };
    for k in 0..2 {
        let (lo, hi) = (arm.workspace_min_mm[k], arm.workspace_max_mm[k]);
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(bad(
                "workspace_max_mm",
                hi,
                "finite and above workspace_min_mm",
            ));
        }
    }
    for (key, v) in [
        ("slide_speed_mm_s", arm.slide_speed_mm_s),
        ("travel_speed_mm_s", arm.travel_speed_mm_s),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(bad(key, v, "a positive speed"));
        }
    }
    Ok(Limits {
        min_mm: arm.workspace_min_mm,
        max_mm: arm.workspace_max_mm,
        max_travel_speed_mm_s: 2.0 * arm.travel_speed_mm_s,
        max_slide_speed_mm_s: 4.0 * arm.slide_speed_mm_s,
    })
}

/// Reads the arm's limits and the registered surface from a site file.
pub fn load(path: &Path) -> Result<ArmSite, SiteError> {
    let p = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|source| SiteError::Read {
        path: p.clone(),
        source,
    })?;
    let file: SiteFile = toml::from_str(&text).map_err(|e| SiteError::Value {
        path: p.clone(),
        source: Box::new(e),
    })?;
    let surface = file
        .surface
        .ok_or_else(|| SiteError::NoSurface { path: p.clone() })?
        .checked()
        .map_err(|source| SiteError::Surface {
            path: p.clone(),
            source,
        })?;
    Ok(ArmSite {
        limits: limits_of(&file.arm, &p)?,
        surface,
    })
}

/// Writes `surface` as the site file's `[surface]` table, keeping everything else (a missing
/// file is created).
pub fn write_surface(path: &Path, surface: &SurfaceFrame) -> Result<(), SiteError> {
    let p = path.display().to_string();
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
        Err(source) => return Err(SiteError::Read { path: p, source }),
    };
    let mut doc: toml_edit::DocumentMut = text.parse().map_err(|e| SiteError::Parse {
        path: p.clone(),
        source: Box::new(e),
    })?;
    let array = |v: &[f64]| {
        let mut a = toml_edit::Array::new();
        for x in v {
            a.push(*x);
        }
        toml_edit::value(a)
    };
    let mut table = toml_edit::Table::new();
    table.decor_mut().set_prefix(
        "\n# Where the plate lies in the arm's base frame (crackbot-controller register).\n",
    );
    table["origin_m"] = array(&surface.origin_m);
    table["rotation_xyzw"] = array(&surface.rotation_xyzw);
    table["tool_xyzw"] = array(&surface.tool_xyzw);
    doc["surface"] = toml_edit::Item::Table(table);
    std::fs::write(path, doc.to_string()).map_err(|source| SiteError::Write { path: p, source })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_surface_is_written_into_a_site_file_keeping_its_comments_and_read_back() {
        let dir = tempfile::tempdir().expect("dir");
        let path = dir.path().join("site.toml");
        std::fs::write(
            &path,
            "# tank 3\nname = \"tank 3\"\n\n[arm]\nworkspace_max_mm = [300.0, 150.0] # measured\n\n[fibre]\ndark_counts = 215.0\n",
        )
        .expect("write");
        assert!(matches!(load(&path), Err(SiteError::NoSurface { .. })));
        let frame = SurfaceFrame {
            origin_m: [0.5, -0.125, 0.03],
            rotation_xyzw: [0.0, 0.0, 0.38268343236508984, 0.9238795325112867],
            ..SurfaceFrame::default()
        };
        write_surface(&path, &frame).expect("write surface");
        let text = std::fs::read_to_string(&path).expect("read");
        assert!(
            text.contains("# measured") && text.contains("dark_counts = 215.0"),
            "{text}"
        );
        let site = load(&path).expect("load");
        assert_eq!(site.surface.origin_m, frame.origin_m);
        assert_eq!(site.limits.max_mm, [300.0, 150.0]);
        assert!((site.limits.max_slide_speed_mm_s - 4.0 * 3.89).abs() < 1e-12);
        // Written again: one [surface] table, the new values.
        let moved = SurfaceFrame {
            origin_m: [0.6, 0.0, 0.0],
            ..frame
        };
        write_surface(&path, &moved).expect("again");
        let text = std::fs::read_to_string(&path).expect("read");
        assert_eq!(text.matches("[surface]").count(), 1, "{text}");
        assert_eq!(load(&path).expect("load").surface.origin_m, [0.6, 0.0, 0.0]);
        std::fs::write(
            &path,
            "[surface]\norigin_m = [0.0, 0.0, 0.0]\nrotation_xyzw = [0.0, 0.0, 0.0, 3.0]\n",
        )
        .expect("write");
        let e = load(&path).unwrap_err().to_string();
        assert!(e.contains("rotation_xyzw has length 3.0000"), "{e}");
    }
}
