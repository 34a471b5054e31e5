//! What a mission knows of the place it inspects: the arm's reachable box and speeds, and the
//! finger's proximity fibre. On hardware it comes from a site file (`--site FILE`, TOML); on
//! the simulator from the scene ([`Site::of_scene`]). The camera's calibration is the
//! hardware's ([`super::Hardware::homography`]).
//!
//! ```toml
//! name = "tank 3, north wall"
//!
//! [arm]
//! workspace_min_mm = [0.0, 0.0]
//! workspace_max_mm = [200.0, 100.0]
//! slide_speed_mm_s = 3.89
//! travel_speed_mm_s = 50.0
//! stroke_mm = 16.0
//!
//! [fibre]          # crackbot_fibre::ProximityFibre; left out: the calibrated finger
//! dark_counts = 215.0
//! ```

use std::path::Path;

use crackbot_fibre::ProximityFibre;
use serde::{Deserialize, Serialize};

use crate::error::io_err;
use crate::MissionError;

/// The place a mission inspects, as the mission needs to know it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Site {
    /// Its name, for the report.
    #[serde(default)]
    pub name: String,
    /// The arm's reachable box and speeds.
    #[serde(default)]
    pub arm: ArmLimits,
    /// The finger's proximity fibre.
    #[serde(default)]
    pub fibre: ProximityFibre,
    /// Where the plate lies in the arm's base frame: the controller's (`crackbot-controller
    /// register` writes it, `crackbot-controller --arm ros2` reads it); the robot keeps it as is.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface: Option<toml::Table>,
}

/// The arm's reachable box on the surface and its speeds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ArmLimits {
    /// Lower corner of the reachable box on the surface, mm `[x, y]`.
    pub workspace_min_mm: [f64; 2],
    /// Upper corner, mm `[x, y]`.
    pub workspace_max_mm: [f64; 2],
    /// Speed of a tactile slide, mm/s (the paper: about 3.89 mm/s).
    pub slide_speed_mm_s: f64,
    /// Speed of moves between slides (finger lifted), mm/s.
    pub travel_speed_mm_s: f64,
    /// Longest slide stroke, mm (the paper: about 16 mm).
    pub stroke_mm: f64,
}

/// The built-in scene's arm (`crates/sim/scenes/default.toml`).
impl Default for ArmLimits {
    fn default() -> Self {
        ArmLimits {
            workspace_min_mm: [0.0, 0.0],
            workspace_max_mm: [200.0, 100.0],
            slide_speed_mm_s: 3.89,
            travel_speed_mm_s: 50.0,
            stroke_mm: 16.0,
        }
    }
}

/// The built-in scene's site: its arm and the calibrated fibre.
impl Default for Site {
    fn default() -> Self {
        Site {
            name: "default site".into(),
            arm: ArmLimits::default(),
            fibre: ProximityFibre::default(),
            surface: None,
        }
    }
}

impl Site {
    /// A site file (TOML, see the [module docs](self)), checked.
    pub fn load(path: &Path) -> Result<Site, MissionError> {
        let text = std::fs::read_to_string(path).map_err(|e| io_err(path, e))?;
        let site: Site = toml::from_str(&text).map_err(|source| MissionError::SiteFile {
            path: path.to_path_buf(),
            source: Box::new(source),
        })?;
        site.checked()
    }

    /// The site if every field is in range: a box of positive size, speeds and the stroke
    /// finite and positive, the fibre's fields in range.
    pub fn checked(self) -> Result<Site, MissionError> {
        let a = &self.arm;
        for (k, axis) in ["workspace_x", "workspace_y"].into_iter().enumerate() {
            let (lo, hi) = (a.workspace_min_mm[k], a.workspace_max_mm[k]);
            if !(lo.is_finite() && hi.is_finite() && hi > lo) {
                return Err(MissionError::Setting {
                    field: axis,
                    value: hi - lo,
                    allowed:
                        "a box of positive, finite size (workspace_max_mm above workspace_min_mm)",
                });
            }
        }
        for (field, value) in [
            ("slide_speed_mm_s", a.slide_speed_mm_s),
            ("travel_speed_mm_s", a.travel_speed_mm_s),
            ("stroke_mm", a.stroke_mm),
        ] {
            if !(value.is_finite() && value > 0.0 && value <= 1000.0) {
                return Err(MissionError::Setting {
                    field,
                    value,
                    allowed: "(0, 1000]",
                });
            }
        }
        self.fibre.checked()?;
        Ok(self)
    }
}

#[cfg(feature = "sim")]
impl Site {
    /// What the mission knows of a simulated scene: its name, its manipulator and its
    /// sensor's proximity fibre.
    pub fn of_scene(scene: &crackbot_sim::Scene) -> Site {
        let m = &scene.manipulator;
        Site {
            name: scene.name.clone(),
            arm: ArmLimits {
                workspace_min_mm: [m.workspace_min_mm[0], m.workspace_min_mm[1]],
                workspace_max_mm: [m.workspace_max_mm[0], m.workspace_max_mm[1]],
                slide_speed_mm_s: m.slide_speed_mm_s,
                travel_speed_mm_s: m.travel_speed_mm_s,
                stroke_mm: m.stroke_mm,
            },
            fibre: scene.sensor.optics.fibre(),
            surface: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_site_file_loads_with_defaults_for_what_it_leaves_out() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("site.toml");
        std::fs::write(
            &path,
            "name = \"tank 3\"\n[arm]\nworkspace_max_mm = [400.0, 300.0]\n[fibre]\ndark_counts = 230.0\n",
        )
        .unwrap();
        let site = Site::load(&path).unwrap();
        assert_eq!(site.name, "tank 3");
        assert_eq!(site.arm.workspace_max_mm, [400.0, 300.0]);
        assert_eq!(site.arm.stroke_mm, 16.0);
        assert_eq!(site.fibre.dark_counts, 230.0);
        assert_eq!(site.fibre.peak_mm, ProximityFibre::default().peak_mm);
    }

    #[test]
    fn bad_site_files_are_refused_naming_what_is_wrong() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("site.toml");
        let load = |text: &str| {
            std::fs::write(&path, text).unwrap();
            Site::load(&path)
        };
        match load("[arm]\nworkspace_min_mm = [10.0, 0.0]\nworkspace_max_mm = [5.0, 100.0]\n") {
            Err(MissionError::Setting { field, .. }) => assert_eq!(field, "workspace_x"),
            other => panic!("{other:?}"),
        }
        match load("[arm]\ntravel_speed_mm_s = -1.0\n") {
            Err(MissionError::Setting { field, value, .. }) => {
                assert_eq!((field, value), ("travel_speed_mm_s", -1.0));
            }
            other => panic!("{other:?}"),
        }
        match load("[fibre]\npeak_mm = 0.0\n") {
            Err(MissionError::Fibre(crackbot_fibre::FibreError::Setting { field, .. })) => {
                assert_eq!(field, "peak_mm");
            }
            other => panic!("{other:?}"),
        }
        match load("[arm]\nspeed = 3\n") {
            Err(e @ MissionError::SiteFile { .. }) => {
                assert!(e.to_string().contains("speed"), "{e}");
            }
            other => panic!("{other:?}"),
        }
        match Site::load(&dir.path().join("absent.toml")) {
            Err(MissionError::Io { path, .. }) => assert!(path.ends_with("absent.toml")),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn the_default_site_is_the_built_in_scenes() {
        assert_eq!(
            Site::of_scene(&crackbot_sim::Scene::builtin_default()),
            Site {
                name: crackbot_sim::Scene::builtin_default().name,
                ..Site::default()
            }
        );
    }
}
