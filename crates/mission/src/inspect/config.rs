//! What a mission is told: its mode, its site, hardware or simulated scene, models and the
//! settings of every step, with their defaults and the checks that refuse a setting out of
//! range.

use std::net::SocketAddr;
use std::path::PathBuf;

#[cfg(feature = "sim")]
use crackbot_controller::{ControllerClock, Faults};
use crackbot_planner::Settings;
#[cfg(feature = "sim")]
use crackbot_sim::Scene;
use serde::Serialize;

use super::pieces::{PIECE_GAP_MM, PIECE_TRACE_GAP_MM};
use super::site::Site;
use crate::MissionError;

/// What the mission uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum InspectMode {
    /// Touch only: scan rows over the whole workspace.
    Tactile,
    /// Look only: the detector's candidates are the result.
    Vision,
    /// Look, then touch every candidate (the papers' method).
    Fused,
}

impl InspectMode {
    /// The mode's name as the command line spells it (what [`std::str::FromStr`] reads).
    pub fn as_str(self) -> &'static str {
        match self {
            InspectMode::Tactile => "tactile",
            InspectMode::Vision => "vision",
            InspectMode::Fused => "fused",
        }
    }
}

impl std::str::FromStr for InspectMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "tactile" => Ok(InspectMode::Tactile),
            "vision" => Ok(InspectMode::Vision),
            "fused" => Ok(InspectMode::Fused),
            _ => Err(format!("unknown mode {s:?}: tactile, vision or fused")),
        }
    }
}

/// What the finger touches of what the camera saw.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CandidateSource {
    /// Every crack a detection holds, on its centre line (`crackbot_vision::crack_map`, "Where
    /// to touch"): cracks that the detection's dilation joined are touched one by one.
    Cracks,
    /// Every detection once, across the middle of its main axis: fewer strokes, but of cracks
    /// that run close together or cross only one is touched.
    Detections,
}

impl std::str::FromStr for CandidateSource {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "cracks" => Ok(CandidateSource::Cracks),
            "detections" => Ok(CandidateSource::Detections),
            _ => Err(format!(
                "unknown candidate source {s:?}: cracks or detections"
            )),
        }
    }
}

/// Real hardware in place of the simulated parts.
#[derive(Debug, Clone)]
pub struct Hardware {
    /// The sensor's serial device (or a pseudo-terminal).
    pub serial: String,
    /// The manipulator controller's UDP address.
    pub controller: SocketAddr,
    /// This host's UDP address for the link (the controller sends to it).
    pub bind: SocketAddr,
    /// The link's pre-shared key file (mode 0600).
    pub key_file: PathBuf,
    /// The camera: a V4L2 device, a video file or stream URL, or an image file
    /// ([`crackbot_vision::camera::CameraSource::parse`]).
    pub camera: Option<PathBuf>,
    /// The camera's pixel → surface calibration (`crackbot homography fit`).
    pub homography: Option<PathBuf>,
}

/// Settings of a mission.
#[derive(Debug, Clone)]
pub struct InspectConfig {
    /// Real hardware; `None`: the simulated controller and sensor over the scene (feature
    /// `sim`).
    pub hardware: Option<Hardware>,
    /// What the mission knows of the place: the arm's box and speeds, the finger's fibre.
    pub site: Site,
    /// The simulated scene ([`InspectConfig::new`], [`InspectConfig::set_scene`]).
    #[cfg(feature = "sim")]
    scene: Option<Scene>,
    /// Tactile, vision or fused.
    pub mode: InspectMode,
    /// Where the report and every recording go.
    pub out_dir: PathBuf,
    /// The deployed recognition model.
    pub recognition_model: PathBuf,
    /// The deployed width model.
    pub width_model: PathBuf,
    /// The ONNX detector (fused and vision modes).
    pub detector_model: Option<PathBuf>,
    /// Vision missions: detections below this score are not reported.
    pub min_score: f32,
    /// Fused missions: detections below this score are not touched. Lower than
    /// [`min_score`](Self::min_score): the finger confirms or rejects what the camera proposes,
    /// so a weak detection costs a slide, not a false report.
    pub proposal_min_score: f32,
    /// What the finger touches (fused) and what is reported (vision).
    pub candidates: CandidateSource,
    /// A crack is confirmed only where a pass that the recognition model read as a crack also
    /// shows the proximity dip a crack makes ([`crackbot_tactile::localise`]: every pass over
    /// the authors' 1–10 mm cracks shows one, 72 of 72 to 73 of 76 per plate, and none over the
    /// flat plate); a flat print the model takes for a crack often does not. `false`: the vote
    /// alone decides.
    pub require_dip: bool,
    /// Fused missions: the print check. A candidate the finger confirmed is passed over once
    /// more with the finger raised this high (mm above the plate, not touching), and rejected
    /// as a print when its proximity dip keeps its share of the signal there
    /// ([`crackbot_tactile::print_check`]: ink darkens the fibre alike at every height, a
    /// crack's floor less when the fibre is farther). `None`: no raised pass.
    pub print_check_mm: Option<f64>,
    /// Shallowest proximity dip that counts as one for [`require_dip`](Self::require_dip),
    /// counts ([`crackbot_tactile::localise::LocaliseConfig::min_depth_counts`], 100 there).
    /// With the print check on, the gate needs to stop only surfaces that do not darken the
    /// fibre at all, so it is lower by default ([`MIN_DIP_COUNTS`]); without it, 100 keeps
    /// more faint prints out.
    pub min_dip_counts: f64,
    /// Fused missions with the print check: a pass over a candidate that the recognition model
    /// read as "no crack" while doubting its own verdict (a surface unlike training, or a weak
    /// vote: [`Doubt::Novel`], [`Doubt::LowConfidence`], or a confidence below
    /// [`WEAK_NO_CRACK_CONFIDENCE`]) still counts as crossing a crack when
    /// its proximity dip is at least this confident
    /// ([`crackbot_tactile::localise::CrackExtent::confidence`]); the print check then decides.
    /// `None`: the model's verdict always stands. See [`DOUBTED_DIP_CONFIDENCE`].
    pub doubted_dip_confidence: Option<f64>,
    /// Fused missions: confirmed candidates whose detections continue each other across a gap
    /// of at most this much (mm, within 40° of one direction) are reported as one crack
    /// ([`PIECE_GAP_MM`]); `None` reports every confirmed candidate.
    pub piece_gap_mm: Option<f64>,
    /// Fused missions: two confirmed candidates are also one crack when the straight line
    /// between the points where their strokes met it runs along both and over the detector's
    /// crack map, off it for at most this much (mm, [`PIECE_TRACE_GAP_MM`]); candidates joined
    /// by `piece_gap_mm` must then also have that line on the map but for their gap plus this
    /// much. `None` joins by the detections' geometry alone.
    pub piece_trace_gap_mm: Option<f64>,
    /// Simulation speed-up (1: real time).
    pub speedup: f64,
    /// Seed of the simulated sensor and camera.
    pub seed: u64,
    /// The planner's settings (slide speed, margins, passes…).
    pub planner: Settings,
    /// γ of the tactile-only scan (the paper's eq. 2).
    pub gamma: f64,
    /// Mean crack length of the tactile-only scan, mm (the paper's eq. 1 on real masks).
    pub mean_crack_length_mm: f64,
    /// The simulated controller's clock (offset, drift injected).
    #[cfg(feature = "sim")]
    pub clock: ControllerClock,
    /// Faults injected into the simulated controller.
    #[cfg(feature = "sim")]
    pub faults: Faults,
    /// Link packet faults injected on the host's side.
    pub host_link_faults: Option<crackbot_link::FaultConfig>,
    /// Write the mission's log, `mission.mcap` in [`out_dir`](Self::out_dir) (on by default):
    /// every channel a front end sees, stamped with the host's clock (`crackbot-mcap`).
    pub mcap: bool,
    /// Serve the log's channels live over the Foxglove WebSocket protocol on this address
    /// (port 0: any free one; the feature `foxglove`). `None`: no live server.
    #[cfg(feature = "foxglove")]
    pub foxglove: Option<std::net::SocketAddr>,
}

/// Shortest stroke across a candidate by default, mm (or the scene's manipulator stroke, if
/// shorter).
pub const TOUCH_MIN_STROKE_MM: f64 = 6.0;
/// Sound surface beyond a candidate's edge and the finger's reach on each side of its stroke by
/// default, mm.
pub const TOUCH_MARGIN_MM: f64 = 0.5;

/// Height of the print check's raised pass by default, mm above the plate: high enough that a
/// 0.5–4 mm deep crack's floor darkens the fibre by a clearly smaller share than in contact,
/// low enough that the sound surface still reads about 27 counts above the fibre's dark level.
pub const PRINT_CHECK_HEIGHT_MM: f64 = 2.0;
/// The print check's height from a user's value (mm): 0 turns the check off; otherwise it must
/// lie in 0.5–20 mm (below, the finger would drag over the plate's roughness; above, the
/// sound surface reads within a few counts of the fibre's dark level).
pub fn print_check_height(h: f64) -> Result<Option<f64>, MissionError> {
    if h == 0.0 {
        Ok(None)
    } else if (0.5..=20.0).contains(&h) {
        Ok(Some(h))
    } else {
        Err(MissionError::Setting {
            field: "print_check_mm",
            value: h,
            allowed: "0 (off) or 0.5–20 mm",
        })
    }
}

/// Shallowest proximity dip a confirmed crack needs by default, counts: the simulated 0.5–0.9 mm
/// cracks of the trial scenes dip 52–88 counts (the localiser's default of 100 rejected them),
/// flat surface read as a crack 14 (seeds 1000–1029, `EXPERIMENTS.md`, "Prints told by two
/// heights"); the authors' flat plate's proximity channel spans 18–22 counts in a slide.
pub const MIN_DIP_COUNTS: f64 = 40.0;

/// Least confidence of the proximity dip that lets a pass stand for a crack although the
/// recognition model read "no crack" and doubted it ([`InspectConfig::doubted_dip_confidence`]).
/// On the simulated trial scenes every such verdict over a crack was doubted, and so were those
/// over prints and flat surface, while the committed model had learned the real finger alone
/// (until 2026-11-27; since, weak "no crack" verdicts count as doubted,
/// [`WEAK_NO_CRACK_CONFIDENCE`]). The dips told them apart: over cracks their confidence was
/// 0.64–0.82 (13 of 14 passes at speed-up 8, seeds 8000–8359; 11 of 11 at real time,
/// 8360–8431), over prints mostly below 0.6 (26 of 33 and 15 of 16), and what passes goes on to
/// the print check (`crates/research/EXPERIMENTS.md`, 'A doubted "no crack" over a deep dip goes
/// to the print check').
pub const DOUBTED_DIP_CONFIDENCE: f64 = 0.6;

/// [`InspectConfig::doubted_dip_confidence`] from a user's value: 0 turns the rule off;
/// otherwise it must lie in (0, 1].
pub fn doubted_dip_confidence(c: f64) -> Result<Option<f64>, MissionError> {
    if c == 0.0 {
        Ok(None)
    } else {
        dip_confidence_in_range(c).map(Some)
    }
}

/// `c` when it lies in (0, 1], else an error naming the setting.
fn dip_confidence_in_range(c: f64) -> Result<f64, MissionError> {
    if c.is_finite() && c > 0.0 && c <= 1.0 {
        Ok(c)
    } else {
        Err(MissionError::Setting {
            field: "doubted_dip_confidence",
            value: c,
            allowed: "(0, 1]",
        })
    }
}

#[cfg(feature = "sim")]
impl InspectConfig {
    /// A fused mission on the simulated rig over `scene` with the committed models, writing
    /// into `out_dir`.
    pub fn new(scene: Scene, out_dir: impl Into<PathBuf>) -> Self {
        let mut config = InspectConfig::at(Site::of_scene(&scene), out_dir);
        config.scene = Some(scene);
        config
    }

    /// The simulated scene, if one was given.
    pub fn scene(&self) -> Option<&Scene> {
        self.scene.as_ref()
    }

    /// Simulates `scene`, and takes its site (name, manipulator, fibre) for the mission's.
    pub fn set_scene(&mut self, scene: Scene) {
        self.site = Site::of_scene(&scene);
        self.scene = Some(scene);
    }
}

impl InspectConfig {
    /// A fused mission at `site` with the committed models, writing into `out_dir`; on
    /// hardware, set [`hardware`](Self::hardware) ([`InspectConfig::on_hardware`]).
    pub fn at(site: Site, out_dir: impl Into<PathBuf>) -> Self {
        let settings = Settings {
            travel_speed_mm_s: site.arm.travel_speed_mm_s,
            // Strokes across the crack at the speed of the authors' recordings the tactile
            // models were trained on (4.6 mm/s, the simulator's fit to them:
            // crates/sim/docs/calibration.md). One stroke per candidate: on the simulated
            // trials it was as accurate as the authors' four (forth and back, twice) at a third
            // of the time. Each stroke starts and ends 0.5 mm beyond what the finger can feel of
            // the crack (its proximity fibre's reach, 2.4 mm past the crack's edge; was the
            // tip's 4.4 mm radius), at least 6 mm in all (not the paper's 16 mm): on 60 trial
            // scenes more cracks confirmed and 19-23 % faster (EXPERIMENTS.md, "Strokes as long
            // as the finger's reach").
            slide_speed_mm_s: crackbot_planner::SIM_SLIDE_SPEED_MM_S,
            passes: 1,
            margin_mm: TOUCH_MARGIN_MM,
            min_margin_mm: TOUCH_MARGIN_MM,
            assumed_width_mm: 2.0,
            min_stroke_mm: TOUCH_MIN_STROKE_MM.min(site.arm.stroke_mm),
            reach_mm: site.fibre.reach_mm(),
            settle_s: 0.1,
            ..Settings::default()
        };
        InspectConfig {
            hardware: None,
            site,
            #[cfg(feature = "sim")]
            scene: None,
            mode: InspectMode::Fused,
            out_dir: out_dir.into(),
            recognition_model: crackbot_datasets::model_path("tactile/recognition.ctm"),
            width_model: crackbot_datasets::model_path("tactile/width.ctm"),
            detector_model: None,
            min_score: 0.3,
            proposal_min_score: 0.3,
            candidates: CandidateSource::Cracks,
            require_dip: true,
            print_check_mm: Some(PRINT_CHECK_HEIGHT_MM),
            min_dip_counts: MIN_DIP_COUNTS,
            doubted_dip_confidence: Some(DOUBTED_DIP_CONFIDENCE),
            piece_gap_mm: Some(PIECE_GAP_MM),
            piece_trace_gap_mm: Some(PIECE_TRACE_GAP_MM),
            speedup: 1.0,
            seed: 7,
            planner: settings,
            gamma: 0.5,
            mean_crack_length_mm: crackbot_planner::paper_mean_length_mm(148.06, 480.0, 100.0),
            #[cfg(feature = "sim")]
            clock: ControllerClock::default(),
            #[cfg(feature = "sim")]
            faults: Faults::default(),
            host_link_faults: None,
            mcap: true,
            #[cfg(feature = "foxglove")]
            foxglove: None,
        }
    }

    /// A fused mission on `hardware` at `site`, writing into `out_dir`.
    pub fn on_hardware(hardware: Hardware, site: Site, out_dir: impl Into<PathBuf>) -> Self {
        InspectConfig {
            hardware: Some(hardware),
            ..InspectConfig::at(site, out_dir)
        }
    }
}

impl InspectConfig {
    /// Refuses a setting out of range ([`MissionError::Setting`] names it): the shallowest dip,
    /// the print check's height, the dip confidence that outweighs a doubt, the pieces' gaps.
    pub fn check(&self) -> Result<(), MissionError> {
        let at_least_zero = |field: &'static str, value: f64| {
            if value.is_finite() && value >= 0.0 {
                Ok(())
            } else {
                Err(MissionError::Setting {
                    field,
                    value,
                    allowed: "a number ≥ 0",
                })
            }
        };
        self.site.clone().checked()?;
        at_least_zero("min_dip_counts", self.min_dip_counts)?;
        if let Some(h) = self.print_check_mm {
            print_check_height(h)?;
        }
        if let Some(c) = self.doubted_dip_confidence {
            dip_confidence_in_range(c)?;
        }
        if let Some(g) = self.piece_gap_mm {
            at_least_zero("piece_gap_mm", g)?;
        }
        if let Some(d) = self.piece_trace_gap_mm {
            at_least_zero("piece_trace_gap_mm", d)?;
        }
        Ok(())
    }
}

#[cfg(all(test, feature = "sim"))]
mod tests {
    use super::*;
    use crackbot_planner::{Candidate, Limits, Planner, Workspace};

    #[test]
    fn the_print_check_height_is_off_at_zero_and_refused_out_of_range() {
        assert_eq!(print_check_height(0.0).unwrap(), None);
        assert_eq!(print_check_height(2.0).unwrap(), Some(2.0));
        for bad in [0.2, -1.0, 25.0, f64::NAN, f64::INFINITY] {
            let e = print_check_height(bad).unwrap_err();
            assert!(
                matches!(e, MissionError::Setting { field: "print_check_mm", value, .. } if value.to_bits() == bad.to_bits()),
                "{e}"
            );
        }
        assert_eq!(
            InspectConfig::new(Scene::builtin_default(), "/tmp").print_check_mm,
            Some(PRINT_CHECK_HEIGHT_MM)
        );
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
        assert_eq!(config.planner.reach_mm, reach);
        assert!(reach < scene.sensor.finger.tip_radius_mm);

        // A 3 mm crack across the middle of the plate: the stroke starts and ends reach +
        // margin beyond its edges; a 0.1 mm one gets the shortest stroke.
        let planner = Planner::new(
            Workspace::new(0.0, 200.0, 0.0, 100.0).unwrap(),
            Limits::default(),
            config.planner.clone(),
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
    fn a_setting_out_of_range_is_refused_by_name() {
        let good = InspectConfig::new(Scene::builtin_default(), "unused");
        good.check().unwrap();
        let refused = |change: &dyn Fn(&mut InspectConfig)| {
            let mut c = good.clone();
            change(&mut c);
            match c.check() {
                Err(MissionError::Setting { field, .. }) => field,
                other => panic!("{other:?}"),
            }
        };
        assert_eq!(refused(&|c| c.min_dip_counts = -1.0), "min_dip_counts");
        assert_eq!(refused(&|c| c.min_dip_counts = f64::NAN), "min_dip_counts");
        assert_eq!(refused(&|c| c.print_check_mm = Some(0.1)), "print_check_mm");
        assert_eq!(
            refused(&|c| c.doubted_dip_confidence = Some(1.5)),
            "doubted_dip_confidence"
        );
        assert_eq!(
            refused(&|c| c.piece_gap_mm = Some(f64::INFINITY)),
            "piece_gap_mm"
        );
        assert_eq!(
            refused(&|c| c.piece_trace_gap_mm = Some(-0.5)),
            "piece_trace_gap_mm"
        );
        // Off is not out of range.
        let mut off = good.clone();
        off.print_check_mm = None;
        off.doubted_dip_confidence = None;
        off.piece_gap_mm = None;
        off.piece_trace_gap_mm = None;
        off.check().unwrap();
        let e = refused(&|c| c.min_dip_counts = -1.0);
        assert_eq!(e, "min_dip_counts");
    }
}
