//! A mission's configuration: one nested, serde-typed value ([`InspectConfig`]) with a section per
//! layer and step, written as a TOML file (`crackbot run --config mission.toml`,
//! `crackbot run --print-config`) and checked once into a [`CheckedConfig`] before anything
//! moves.
//!
//! | section | what | type (defined with its step) |
//! |---|---|---|
//! | `mode` | `fused`, `vision` or `tactile` | [`InspectMode`] |
//! | `[rig]` | hardware or the simulator, the site, speed-up, seed | [`RigConfig`] |
//! | `[perceive]` | the detector, its scores, what is touched | [`PerceiveConfig`] |
//! | `[plan]` | the planner's settings, the tactile scan's γ | [`PlanConfig`] |
//! | `[touch]` | the tactile models, the shallowest dip, strokes made again | [`TouchConfig`] |
//! | `[print_check]` | the raised pass, the print threshold, ratios in doubt | [`PrintCheckConfig`] |
//! | `[judge]` | the dip a crack needs, doubted "no crack" verdicts | [`JudgeConfig`] |
//! | `[pieces]` | pieces of one crack joined | [`PiecesConfig`] |
//! | `[output]` | the folder, the log, the live view | [`OutputConfig`] |
//!
//! A file names only what it changes: every key it leaves out keeps its default (on the
//! simulator, the scene's site; on hardware, the site file's). A key the configuration does not
//! have, or a value of the wrong type, is an error naming the key; a value out of range is
//! refused by [`InspectConfig::check`], naming it as `section.key`.

use std::ops::Deref;
use std::path::{Path, PathBuf};

#[cfg(feature = "sim")]
use crackbot_sim::Scene;
use serde::{Deserialize, Serialize};

use super::report::InspectMode;
use super::rig::settings::{Hardware, OutputConfig, RigConfig};
use super::rig::site::Site;
use super::steps::{
    JudgeConfig, PerceiveConfig, PiecesConfig, PlanConfig, PrintCheckConfig, TouchConfig,
};
use crate::error::io_err;
use crate::MissionError;

/// Settings of a mission, a section per step (see the [module docs](self)).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InspectConfig {
    /// Tactile, vision or fused.
    pub mode: InspectMode,
    /// What it runs on and where.
    pub rig: RigConfig,
    /// The camera and the detector.
    pub perceive: PerceiveConfig,
    /// The plan.
    pub plan: PlanConfig,
    /// The contact strokes.
    pub touch: TouchConfig,
    /// The print check's raised passes.
    pub print_check: PrintCheckConfig,
    /// The verdicts.
    pub judge: JudgeConfig,
    /// Pieces of one crack.
    pub pieces: PiecesConfig,
    /// The report, recordings and log.
    pub output: OutputConfig,
}

#[cfg(feature = "sim")]
impl InspectConfig {
    /// A fused mission on the simulated rig over `scene` with the committed models, writing
    /// into `out_dir`.
    pub fn new(scene: Scene, out_dir: impl Into<PathBuf>) -> Self {
        let mut config = InspectConfig::at(Site::of_scene(&scene), out_dir);
        config.rig.set_scene(scene);
        config
    }

    /// The simulated scene, if one was given.
    pub fn scene(&self) -> Option<&Scene> {
        self.rig.scene()
    }

    /// Simulates `scene`, and takes its site (name, manipulator, fibre) for the mission's.
    pub fn set_scene(&mut self, scene: Scene) {
        self.rig.set_scene(scene);
    }
}

impl InspectConfig {
    /// A fused mission at `site` with the committed models, writing into `out_dir`; on
    /// hardware, set [`RigConfig::hardware`] ([`InspectConfig::on_hardware`]).
    pub fn at(site: Site, out_dir: impl Into<PathBuf>) -> Self {
        InspectConfig {
            mode: InspectMode::Fused,
            plan: PlanConfig::at(&site),
            rig: RigConfig::at(site),
            perceive: PerceiveConfig::default(),
            touch: TouchConfig::new(),
            print_check: PrintCheckConfig::default(),
            judge: JudgeConfig::default(),
            pieces: PiecesConfig::default(),
            output: OutputConfig::new(out_dir),
        }
    }

    /// A fused mission on `hardware` at `site`, writing into `out_dir`.
    pub fn on_hardware(hardware: Hardware, site: Site, out_dir: impl Into<PathBuf>) -> Self {
        let mut config = InspectConfig::at(site, out_dir);
        config.rig.hardware = Some(hardware);
        config
    }

    /// Refuses a setting out of range ([`MissionError::Setting`] names it as `section.key`),
    /// else the configuration as checked: what [`crate::inspect::run_inspection`] takes.
    pub fn check(&self) -> Result<CheckedConfig, MissionError> {
        self.rig.check()?;
        self.perceive.check()?;
        self.plan.check()?;
        self.touch.check()?;
        self.print_check.check()?;
        self.judge.check()?;
        self.pieces.check()?;
        #[cfg(feature = "ros2")]
        if let (Some(domain), false) = (self.output.ros2_domain, self.output.mcap) {
            return Err(MissionError::Setting {
                field: "output.ros2_domain",
                value: f64::from(domain),
                allowed:
                    "only with the log on (output.mcap = true): the live topics are its messages",
            });
        }
        Ok(CheckedConfig(self.clone()))
    }

    /// This configuration with the TOML `text` (from the file `from`, named in errors) laid over it:
    /// every key the text gives replaces this one's, the rest stay. The scene and injected
    /// faults are not the file's and stay as they are. Not checked: see [`Self::check`].
    pub fn overlaid(&self, text: &str, from: &Path) -> Result<InspectConfig, MissionError> {
        let file_err = |key: Option<String>, source| MissionError::ConfigFile {
            path: from.to_path_buf(),
            key,
            source: Box::new(source),
        };
        let given: toml::Table = toml::from_str(text).map_err(|e| file_err(None, e))?;
        let mut merged =
            toml::Table::try_from(self).map_err(|source| MissionError::ConfigWrite {
                source: Box::new(source),
            })?;
        merge(&mut merged, given);
        let mut config: InspectConfig =
            serde_path_to_error::deserialize(toml::Value::Table(merged)).map_err(|e| {
                let key = e.path().to_string();
                file_err(Some(key), e.into_inner())
            })?;
        config.rig.keep_unfiled(&self.rig);
        Ok(config)
    }

    /// [`Self::overlaid`] with the file at `path`.
    pub fn overlaid_file(&self, path: &Path) -> Result<InspectConfig, MissionError> {
        let text = std::fs::read_to_string(path).map_err(|e| io_err(path, e))?;
        self.overlaid(&text, path)
    }

    /// The configuration as a TOML file, each key with what it is and where its default comes
    /// from in a comment ([`super::config_doc::COMMENTS`]).
    pub fn to_commented_toml(&self) -> Result<String, MissionError> {
        let table = toml::Table::try_from(self).map_err(|source| MissionError::ConfigWrite {
            source: Box::new(source),
        })?;
        Ok(super::config_doc::commented(&table))
    }
}

/// `given` laid over `base`: tables merge key by key, any other value replaces.
fn merge(base: &mut toml::Table, given: toml::Table) {
    for (k, v) in given {
        match (base.get_mut(&k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(g)) => merge(b, g),
            (_, v) => {
                base.insert(k, v);
            }
        }
    }
}

/// A configuration whose every setting was checked once ([`InspectConfig::check`]); a
/// mission takes nothing else. It reads as the [`InspectConfig`] it holds.
#[derive(Debug, Clone)]
pub struct CheckedConfig(InspectConfig);

impl Deref for CheckedConfig {
    type Target = InspectConfig;
    fn deref(&self) -> &InspectConfig {
        &self.0
    }
}

impl CheckedConfig {
    /// The configuration, to change and check again.
    pub fn into_inner(self) -> InspectConfig {
        self.0
    }
}

#[cfg(all(test, feature = "sim"))]
mod tests {
    use super::*;
    use crate::inspect::steps::plan::{TOUCH_MARGIN_MM, TOUCH_MIN_STROKE_MM};
    use crate::inspect::steps::print_check::PRINT_CHECK_HEIGHT_MM;
    use crackbot_planner::{Candidate, Limits, Planner, Workspace};

    fn default_config() -> InspectConfig {
        InspectConfig::new(Scene::builtin_default(), "unused")
    }

    #[test]
    fn strokes_reach_as_far_as_the_proximity_fibre_sees_and_no_further() {
        let scene = Scene::builtin_default();
        let o = &scene.sensor.optics;
        let reach = Site::of_scene(&scene).fibre.reach_mm();
        // The fitted fibre looks 1.8 mm ahead of the tip over a 1.13 mm spot.
        assert!((reach - (o.proximity_offset_mm + o.proximity_spot_mm / 2.0)).abs() < 1e-12);
        assert!((2.0..3.0).contains(&reach), "{reach}");
        let config = InspectConfig::new(scene.clone(), "unused");
        assert_eq!(config.plan.planner.reach_mm, reach);
        assert!(reach < scene.sensor.finger.tip_radius_mm);
        assert_eq!(config.print_check.height_mm, Some(PRINT_CHECK_HEIGHT_MM));

        // A 3 mm crack across the middle of the plate: the stroke starts and ends reach +
        // margin beyond its edges; a 0.1 mm one gets the shortest stroke.
        let planner = Planner::new(
            Workspace::new(0.0, 200.0, 0.0, 100.0).unwrap(),
            Limits::default(),
            config.plan.planner.clone(),
        )
        .unwrap();
        for (width, stroke) in [
            (3.0, 3.0 + 2.0 * (reach + TOUCH_MARGIN_MM)),
            (0.1, TOUCH_MIN_STROKE_MM),
        ] {
            let c = Candidate::from_axis(1, [[100.0, 30.0], [100.0, 70.0]], Some(width), 0.9);
            let plan = planner.targeted(&[c]).unwrap();
            let s = &plan.slides[0];
            assert!(
                (s.stroke_mm - stroke).abs() < 1e-9,
                "{width} mm: {}",
                s.stroke_mm
            );
        }
    }

    #[test]
    fn a_setting_out_of_range_is_refused_by_its_key() {
        let good = default_config();
        good.check().unwrap();
        let refused = |change: &dyn Fn(&mut InspectConfig)| {
            let mut c = good.clone();
            change(&mut c);
            match c.check() {
                Err(MissionError::Setting { field, .. }) => field,
                other => panic!("{other:?}"),
            }
        };
        assert_eq!(
            refused(&|c| c.touch.min_dip_counts = -1.0),
            "touch.min_dip_counts"
        );
        assert_eq!(
            refused(&|c| c.touch.min_dip_counts = f64::NAN),
            "touch.min_dip_counts"
        );
        assert_eq!(
            refused(&|c| c.print_check.height_mm = Some(0.1)),
            "print_check.height_mm"
        );
        assert_eq!(
            refused(&|c| c.print_check.passes_in_doubt = 0),
            "print_check.passes_in_doubt"
        );
        assert_eq!(
            refused(&|c| c.judge.doubted_dip_confidence = Some(1.5)),
            "judge.doubted_dip_confidence"
        );
        assert_eq!(
            refused(&|c| c.pieces.gap_mm = Some(f64::INFINITY)),
            "pieces.gap_mm"
        );
        assert_eq!(
            refused(&|c| c.pieces.trace_gap_mm = Some(-0.5)),
            "pieces.trace_gap_mm"
        );
        assert_eq!(refused(&|c| c.rig.speedup = 0.0), "rig.speedup");
        assert_eq!(refused(&|c| c.plan.gamma = 1.0), "plan.gamma");
        assert_eq!(
            refused(&|c| c.perceive.min_score = 1.5),
            "perceive.min_score"
        );
        // Off is not out of range.
        let mut off = good.clone();
        off.print_check.height_mm = None;
        off.judge.doubted_dip_confidence = None;
        off.pieces.gap_mm = None;
        off.pieces.trace_gap_mm = None;
        off.check().unwrap();
    }

    #[test]
    fn a_file_changes_what_it_names_and_nothing_else() {
        let base = default_config();
        let text = "mode = \"vision\"\n[print_check]\nheight_mm = 0\nprint_ratio = 0.9\n\
                    [pieces]\ntrace_gap_mm = -1\n[rig]\nspeedup = 4\n";
        let c = base.overlaid(text, Path::new("m.toml")).unwrap();
        assert_eq!(c.mode, InspectMode::Vision);
        assert_eq!(c.print_check.height_mm, None);
        assert_eq!(c.print_check.print_ratio, 0.9);
        assert_eq!(c.print_check.guard_counts, base.print_check.guard_counts);
        assert_eq!(c.pieces.trace_gap_mm, None);
        assert_eq!(c.pieces.gap_mm, base.pieces.gap_mm);
        assert_eq!(c.rig.speedup, 4.0);
        // What the file cannot hold stays: the scene, the site it gave.
        assert!(c.scene().is_some());
        assert_eq!(c.rig.site, base.rig.site);
        assert_eq!(c.plan, base.plan);
        c.check().unwrap();
    }

    #[test]
    fn the_printed_configuration_reads_back_as_itself() {
        let base = default_config();
        let text = base.to_commented_toml().unwrap();
        assert!(text.contains("[print_check]"), "{text}");
        assert!(text.contains("# "), "{text}");
        let again = base.overlaid(&text, Path::new("printed.toml")).unwrap();
        assert_eq!(
            toml::Table::try_from(&again).unwrap(),
            toml::Table::try_from(&base).unwrap()
        );
        // From the defaults of another site too: the file is complete.
        let other = InspectConfig::at(Site::default(), "elsewhere");
        let from_other = other.overlaid(&text, Path::new("printed.toml")).unwrap();
        assert_eq!(
            toml::Table::try_from(&from_other).unwrap(),
            toml::Table::try_from(&base).unwrap()
        );
    }

    #[test]
    fn unknown_keys_wrong_types_and_broken_files_are_refused_naming_the_key() {
        let base = default_config();
        let err = |text: &str| match base.overlaid(text, Path::new("m.toml")) {
            Err(e @ MissionError::ConfigFile { .. }) => {
                assert!(e.to_string().contains("m.toml"), "{e}");
                e.to_string()
            }
            other => panic!("{text:?}: {other:?}"),
        };
        let m = err("[print_check]\nhieght_mm = 2\n");
        assert!(m.contains("print_check") && m.contains("hieght_mm"), "{m}");
        let m = err("[touch]\nmin_dip_counts = \"forty\"\n");
        assert!(m.contains("touch.min_dip_counts"), "{m}");
        let m = err("[plan.planner]\npasses = -2\n");
        assert!(m.contains("plan.planner.passes"), "{m}");
        let m = err("[colour]\nred = 1\n");
        assert!(m.contains("colour"), "{m}");
        let m = err("mode = \"sideways\"\n");
        assert!(m.contains("mode"), "{m}");
        let m = err("[print_check\nheight_mm = 2\n");
        assert!(!m.is_empty());
        // A value in range by type but not by value: the check names it.
        let c = base
            .overlaid("[judge]\ndoubted_dip_confidence = 3\n", Path::new("m.toml"))
            .unwrap();
        assert!(matches!(
            c.check(),
            Err(MissionError::Setting {
                field: "judge.doubted_dip_confidence",
                ..
            })
        ));
    }
}
