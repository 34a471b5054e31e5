//! The physics simulator (`crackbot-sim`) as the emulated board's analog front end.

use crackbot_sim::calibrate::calibrated_sensor;
use crackbot_sim::experiment::Samples;
use crackbot_sim::run::{Sample, SlideLine, SlideSim};
use crackbot_sim::surface::{Feature, Point, Surface};
use crackbot_sim::{Integrator, Scene, SensorParams, SimError};

use crate::SignalSource;

/// Distance from the start of the first stroke to the near edge of the crack, mm.
pub const CRACK_LEAD_IN_MM: f64 = 7.0;
/// The paper's stroke length, mm.
pub const PAPER_STROKE_MM: f64 = 16.0;
/// The paper's sliding speed, mm/s.
pub const PAPER_SPEED_MM_S: f64 = 3.89;

/// Reflectivity of the calibration plate (white PLA), which [`SimSource::new`] slides on.
const CALIBRATION_PLATE_REFLECTIVITY: f64 = 1.0;

/// A [`SignalSource`] driven by the physics simulator: the simulated finger slides back and
/// forth along a line of a plate ([`SlideSim`]) and every call returns the simulated channel
/// values before the ADC ([`Sample::analog`], counts of D1, D2, D3, P); the emulator's ADC
/// then rounds and clamps them as for any source.
///
/// **Pacing.** Each call to [`SignalSource::sample`] advances the simulation by exactly one
/// sample, 1/400 s ([`crackbot_sim::run::SAMPLE_RATE_HZ`]); the `t` argument is ignored. The
/// source is paced by its caller: the emulator's 400 Hz ticks (at another `--rate` the
/// simulated slide runs proportionally faster or slower than real time).
///
/// **Errors.** `sample` cannot return an error. If the simulation fails (the integrator cannot
/// take a step), the source does not panic: it logs the error once with `tracing::error`, keeps
/// it for [`SimSource::error`], and from then on returns the last good value for every call
/// (zeros if no sample ever succeeded). Callers that care check [`SimSource::error`] after a
/// run (the `&mut SimSource` is itself a [`SignalSource`], so the caller can keep the source).
#[derive(Debug)]
pub struct SimSource {
    sim: SlideSim,
    last: Option<Sample>,
    samples: u64,
    error: Option<SimError>,
}

impl SimSource {
    /// `sensor` sliding along `line` on `surface` (on the calibration plate's material,
    /// reflectivity 1), integrated with `integrator`; noise, drift and per-recording changes are
    /// drawn from `seed`.
    pub fn new(
        surface: &Surface,
        line: &SlideLine,
        sensor: &SensorParams,
        integrator: Integrator,
        seed: u64,
    ) -> Result<Self, SimError> {
        let sim = SlideSim::new(
            surface,
            CALIBRATION_PLATE_REFLECTIVITY,
            line,
            sensor,
            integrator,
            seed,
        )?;
        Ok(Self::from_sim(sim))
    }

    /// Wraps a simulation set up by the caller (e.g. on another plate material).
    pub fn from_sim(sim: SlideSim) -> Self {
        SimSource {
            sim,
            last: None,
            samples: 0,
            error: None,
        }
    }

    /// The paper's width experiment as a live signal: the calibrated sensor
    /// ([`calibrated_sensor`]) sliding with the paper's 16 mm strokes at 3.89 mm/s across one
    /// straight crack of `width_mm` (0: a flat plate) on a 200 × 100 mm plate, each stroke
    /// starting 7 mm before the crack's near edge. The crack has the simulated samples' depth
    /// and walls ([`Samples::default`]); the integrator is the default one.
    pub fn over_crack(width_mm: f64, seed: u64) -> Result<Self, SimError> {
        let (surface, line) = crack_plate(width_mm)?;
        Self::new(
            &surface,
            &line,
            &calibrated_sensor(),
            Integrator::default(),
            seed,
        )
    }

    /// Slides across the first crack of `scene` (in the order of its `features`): the line
    /// crosses the crack at right angles at the middle of its polyline (by length), starting
    /// 7 mm before its near edge, with the scene's manipulator stroke and speed, its sensor and
    /// its plate material's reflectivity.
    pub fn across_first_crack(scene: &Scene, seed: u64) -> Result<Self, SimError> {
        let line = line_across_first_crack(scene)?;
        let sim = SlideSim::new(
            &scene.surface(),
            scene.plate.material.reflectivity,
            &line,
            &scene.sensor,
            Integrator::default(),
            seed,
        )?;
        Ok(Self::from_sim(sim))
    }

    /// The simulation's error, if it failed; from then on the source holds its last good value.
    pub fn error(&self) -> Option<&SimError> {
        self.error.as_ref()
    }

    /// The last sample the simulation produced (with its ground truth: tip position, forces…).
    pub fn last_sample(&self) -> Option<&Sample> {
        self.last.as_ref()
    }

    /// Samples simulated successfully so far.
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// The simulation.
    pub fn sim(&self) -> &SlideSim {
        &self.sim
    }
}

impl SignalSource for SimSource {
    /// Advances the simulation by one 1/400 s sample; `t` is ignored (see [`SimSource`]).
    fn sample(&mut self, _t: f64) -> [f64; 4] {
        if self.error.is_none() {
            match self.sim.next_sample() {
                Ok(s) => {
                    self.samples += 1;
                    self.last = Some(s);
                }
                Err(e) => {
                    tracing::error!(
                        samples = self.samples,
                        "the simulation failed, holding the last channel values: {e}"
                    );
                    self.error = Some(e);
                }
            }
        }
        self.last.map_or([0.0; 4], |s| s.analog)
    }
}

/// The plate of [`SimSource::over_crack`] and its slide line.
fn crack_plate(width_mm: f64) -> Result<(Surface, SlideLine), SimError> {
    if !(width_mm.is_finite() && (0.0..=50.0).contains(&width_mm)) {
        return Err(SimError::setting(
            "crack_width_mm",
            width_mm,
            "in [0, 50] mm",
        ));
    }
    let samples = Samples::default();
    let crack_x = 100.0;
    let surface = Surface {
        size_mm: [200.0, 100.0],
        features: vec![Feature::Crack {
            path: vec![[crack_x, 0.0], [crack_x, 100.0]],
            width_mm,
            depth_mm: samples.crack_depth_mm,
            edge_radius_mm: 0.3,
            wall_angle_deg: samples.crack_wall_angle_deg,
        }],
    };
    let line = SlideLine {
        start: [crack_x - width_mm / 2.0 - CRACK_LEAD_IN_MM, 50.0],
        direction: [1.0, 0.0],
        stroke_mm: PAPER_STROKE_MM,
        speed_mm_s: PAPER_SPEED_MM_S,
    };
    Ok((surface, line))
}

/// The slide line of [`SimSource::across_first_crack`].
fn line_across_first_crack(scene: &Scene) -> Result<SlideLine, SimError> {
    let (index, path, width_mm) = scene
        .features
        .iter()
        .enumerate()
        .find_map(|(k, f)| match f {
            Feature::Crack { path, width_mm, .. } => Some((k, path, *width_mm)),
            _ => None,
        })
        .ok_or_else(|| SimError::NoCrack {
            scene: scene.name.clone(),
        })?;
    let (mid, tangent) = polyline_midpoint(path).ok_or_else(|| {
        let points: Vec<String> = path
            .iter()
            .map(|p| format!("[{}, {}]", p[0], p[1]))
            .collect();
        SimError::setting(
            format!("features[{index}].path"),
            format!("[{}]", points.join(", ")),
            "a path of non-zero length (the first crack is the one slid across)",
        )
    })?;
    let normal = [-tangent[1], tangent[0]];
    let back = width_mm.max(0.0) / 2.0 + CRACK_LEAD_IN_MM;
    Ok(SlideLine {
        start: [mid[0] - back * normal[0], mid[1] - back * normal[1]],
        direction: normal,
        stroke_mm: scene.manipulator.stroke_mm,
        speed_mm_s: scene.manipulator.slide_speed_mm_s,
    })
}

/// The point halfway along `path` (by length) and the unit tangent of the segment it lies on.
fn polyline_midpoint(path: &[Point]) -> Option<(Point, Point)> {
    let len = |s: &[Point]| ((s[1][0] - s[0][0]).powi(2) + (s[1][1] - s[0][1]).powi(2)).sqrt();
    let total: f64 = path.windows(2).map(len).sum();
    if !(total.is_finite() && total > 0.0) {
        return None;
    }
    let mut left = total / 2.0;
    let mut last = None;
    for s in path.windows(2) {
        let l = len(s);
        if l <= 0.0 {
            continue;
        }
        let u = (left / l).min(1.0);
        let tangent = [(s[1][0] - s[0][0]) / l, (s[1][1] - s[0][1]) / l];
        let point = [
            s[0][0] + u * (s[1][0] - s[0][0]),
            s[0][1] + u * (s[1][1] - s[0][1]),
        ];
        if left <= l {
            return Some((point, tangent));
        }
        // Rounding can leave a sliver past the last segment: its end is the midpoint then.
        last = Some((point, tangent));
        left -= l;
    }
    last
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_the_simulators_analog_channels_for_the_same_seed() {
        let (surface, line) = crack_plate(5.0).expect("plate");
        let mut sim = SlideSim::new(
            &surface,
            1.0,
            &line,
            &calibrated_sensor(),
            Integrator::default(),
            42,
        )
        .expect("sim");
        let mut source = SimSource::over_crack(5.0, 42).expect("source");
        for k in 0..800 {
            let expected = sim.next_sample().expect("sample").analog;
            // `t` is ignored: any value gives the next sample.
            assert_eq!(source.sample(-1.0), expected, "sample {k}");
        }
        assert_eq!(source.samples(), 800);
        assert!(source.error().is_none());
        let other = SimSource::over_crack(5.0, 43).expect("source").sample(0.0);
        assert_ne!(
            other,
            SimSource::over_crack(5.0, 42).expect("source").sample(0.0)
        );
    }

    /// Proximity swing over one slide (a stroke forth and back), counts.
    fn proximity_swing(width_mm: f64) -> f64 {
        let mut source = SimSource::over_crack(width_mm, 3).expect("source");
        let n = (source.sim().slide_time() * f64::from(crackbot_protocol::SAMPLE_RATE_HZ)).ceil()
            as usize;
        let p: Vec<f64> = (0..n).map(|_| source.sample(0.0)[3]).collect();
        assert!(source.error().is_none(), "{:?}", source.error());
        // Robust range: 2nd to 98th percentile.
        let mut sorted = p.clone();
        sorted.sort_by(f64::total_cmp);
        sorted[n * 98 / 100] - sorted[n * 2 / 100]
    }

    #[test]
    fn the_crack_shows_on_the_proximity_channel_and_a_flat_plate_does_not() {
        let crack = proximity_swing(5.0);
        let flat = proximity_swing(0.0);
        assert!(crack > 100.0, "5 mm crack: proximity swing {crack}");
        assert!(flat < 50.0, "flat plate: proximity swing {flat}");
    }

    #[test]
    fn a_failing_simulation_holds_the_last_value_and_reports_the_error() {
        let (surface, line) = crack_plate(5.0).expect("plate");
        // Explicit Euler with one step per sample cannot carry the stiff contact.
        let mut source = SimSource::new(
            &surface,
            &line,
            &calibrated_sensor(),
            Integrator::SymplecticEuler { substeps: 1 },
            1,
        )
        .expect("source");
        let values: Vec<[f64; 4]> = (0..4000).map(|_| source.sample(0.0)).collect();
        let error = source.error().expect("the explicit integrator must fail");
        assert!(error.to_string().contains("integration failed"), "{error}");
        let good = source.samples() as usize;
        assert!(good < values.len());
        let held = source.last_sample().map_or([0.0; 4], |s| s.analog);
        assert!(values[good..].iter().all(|v| *v == held));
    }

    #[test]
    fn bad_widths_are_rejected() {
        for w in [-1.0, f64::NAN, 80.0] {
            let err = SimSource::over_crack(w, 1).err();
            assert!(
                matches!(
                    &err,
                    Some(SimError::Setting { field, .. }) if field == "crack_width_mm"
                ),
                "{w}: {err:?}"
            );
        }
    }

    #[test]
    fn scene_line_crosses_the_first_crack_at_right_angles() {
        let scene = Scene::builtin_default();
        let line = line_across_first_crack(&scene).expect("line");
        let Some(Feature::Crack { path, width_mm, .. }) = scene
            .features
            .iter()
            .find(|f| matches!(f, Feature::Crack { .. }))
        else {
            panic!("the default scene has a crack");
        };
        let (mid, tangent) = polyline_midpoint(path).expect("midpoint");
        let dot = line.direction[0] * tangent[0] + line.direction[1] * tangent[1];
        assert!(dot.abs() < 1e-12);
        let back = ((mid[0] - line.start[0]).powi(2) + (mid[1] - line.start[1]).powi(2)).sqrt();
        assert!((back - (width_mm / 2.0 + CRACK_LEAD_IN_MM)).abs() < 1e-9);
        let mut source = SimSource::across_first_crack(&scene, 1).expect("source");
        for _ in 0..100 {
            source.sample(0.0);
        }
        assert!(source.error().is_none());
        let err = line_across_first_crack(&Scene {
            features: Vec::new(),
            name: "bare".into(),
            ..scene
        })
        .unwrap_err();
        assert!(
            matches!(&err, SimError::NoCrack { scene } if scene == "bare"),
            "{err:?}"
        );
        assert!(err.to_string().contains("no crack"), "{err}");
    }

    #[test]
    fn midpoint_of_a_bent_polyline() {
        let (mid, tangent) =
            polyline_midpoint(&[[0.0, 0.0], [4.0, 0.0], [4.0, 2.0]]).expect("midpoint");
        assert_eq!(mid, [3.0, 0.0]);
        assert_eq!(tangent, [1.0, 0.0]);
        let (mid, tangent) = polyline_midpoint(&[[0.0, 0.0], [0.0, 0.0], [0.0, 2.0]]).expect("m");
        assert_eq!(mid, [0.0, 1.0]);
        assert_eq!(tangent, [0.0, 1.0]);
        assert!(polyline_midpoint(&[[1.0, 1.0], [1.0, 1.0]]).is_none());
    }
}
