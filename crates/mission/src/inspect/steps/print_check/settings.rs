//! The print check's section of the configuration, `[print_check]`: the raised pass's height
//! (0: no check), the threshold that tells a print from a crack, when a ratio is in doubt and
//! how many passes settle it, the guard against what stands under the line, and the pass's
//! overrun and speed.

use crackbot_tactile::print_check;
use serde::{Deserialize, Serialize};

use crate::MissionError;

/// Height of the print check's raised pass by default, mm above the plate: high enough that a
/// 0.5–4 mm deep crack's floor darkens the fibre by a clearly smaller share than in contact,
/// low enough that the sound surface still reads about 27 counts above the fibre's dark level.
pub const PRINT_CHECK_HEIGHT_MM: f64 = 2.0;
/// The print check's raised pass is stopped (the arm lifts to its travel height) when the
/// proximity channel rises this far above the level it read at the pass's start, counts:
/// something under the line is closer to the fibre than the plate. On the simulated trial
/// scenes 9000–9119 at real time, raised passes over sound surface, cracks, prints and bumps up
/// to 1.2 mm rose at most 12 counts above their level, passes over screw heads 258–466 counts
/// (heads 2.2–3.6 mm tall, which the finger 2 mm up would strike; the simulator does not model
/// that collision). For the fitted fibre, 40 counts is something about 1.1 mm tall under it
/// (`crates/research/EXPERIMENTS.md`, "Raised passes stop over what stands under them"). The
/// level is the pass's own first 20 samples: a head already in view at the pass's start raises
/// it, and the pass is then stopped later than it should be.
pub const RAISED_PASS_GUARD_COUNTS: f64 = 40.0;
/// A raised pass stopped by [`RAISED_PASS_GUARD_COUNTS`] judges its candidate only if it had
/// gone this far past where the strokes crossed the crack (along the pass), mm: the fibre's
/// look-ahead (1.8 mm) and spot have then seen the whole crossing, and what it read gives a
/// ratio. Stopped sooner, or without a ratio, what stands under the line may be the candidate,
/// which is rejected as "something standing above the plate" (a crack does not stand up; a
/// screw's rim can look and feel like one).
pub const RAISED_PASS_CLEAR_MM: f64 = 2.5;
/// The print check's raised pass is made again, back along its line, where the surface at the
/// line stands more than this far above the plate it was held over ([`surface_rise_mm`]), mm,
/// and the first pass reads a print ([`print_check::PRINT_RATIO`]): held level over a bump's
/// flank or a curved part, the fibre is nearer the surface than the check's height, and a crack
/// keeps more of its dip, as a print does (one that reads a crack nearer would read one all the
/// more at the check's height). Made again that much higher, by at most
/// [`MAX_SURFACE_RISE_MM`]. A surface below the plate (a fibre farther than the height) is left
/// alone: a crack then keeps less of its dip and ink all of it, so the two only lie farther
/// apart; and the level beside a dip 2–5 mm wide reads 0.3–0.7 mm low on flat plates. Replayed
/// on the saved passes of 3288 candidates of the trial runs 11460–12419 (real time), 5 on flat
/// plates and 12 near bumps rose more than 0.3 mm (flat plates: 99 % under 0.03 mm), among them
/// two cracks on a bump's flank rejected as prints at 0.94 and 0.89.
/// Missions run again on those scenes and three fresh sets, made again whatever the first pass
/// read: four cracks and a print set right, four prints beside bumps and a crack set wrong (the
/// dip over the flank's sloping level misread 2.3–2.9 mm up); the crack and two of the prints
/// had first passes that read a crack, as did the print set right, and are now left to them
/// (`crates/research/EXPERIMENTS.md`, "The raised pass as high above the surface as the check
/// needs").
pub const SURFACE_RISE_TOLERANCE_MM: f64 = 0.3;
/// The most a raised pass made again is raised above the print check's height, mm (a
/// surface that much higher stops a first pass: [`RAISED_PASS_GUARD_COUNTS`]).
pub const MAX_SURFACE_RISE_MM: f64 = 1.5;

/// A print ratio within this of [`print_check::PRINT_RATIO`] is measured again: the raised pass
/// is made back and forth, up to [`PRINT_CHECK_PASSES_IN_DOUBT`] times in all (two where they
/// settle, [`PRINT_RATIO_SETTLED`]), and the mean over the passes of each one's print ratio
/// and floor ratio ([`print_check::floor_ratio`]) decides (the print ratio alone where a pass
/// gives no floor ratio). On the simulated trials 9420–9539 (speed-up 2), four raised passes
/// over every candidate read a median 0.012 apart (a crack's and a print's ratios lie 0.22
/// apart), and the mean of four put 3 candidates on the wrong side of the threshold where the
/// first pass alone put 8; every one of the 8 first read within 0.02 of it, but for one crack
/// at 1.07. What four passes leave is not the raised pass's
/// noise but the estimate's own bias on narrow marks: replayed offline on the saved passes of
/// 2010 candidates over a crack or a print (looked-at trial runs 9300–9899, real time), the
/// print ratio put 35 on the wrong side of the threshold, the mean with the floor ratio where
/// the first ratio was in doubt 24 (12 right that were wrong, 1 wrong that was right;
/// `crates/research/EXPERIMENTS.md`, "Two estimates of a ratio in doubt").
pub const PRINT_RATIO_DOUBT: f64 = 0.08;
/// Most raised passes in all over a candidate whose first print ratio is in doubt
/// ([`PRINT_RATIO_DOUBT`]): an even number, as many each way.
pub const PRINT_CHECK_PASSES_IN_DOUBT: usize = 4;
/// After each pair of raised passes in doubt (one each way), the passes stop where their mean
/// (of print and floor ratios) lies at least this far from [`print_check::PRINT_RATIO`]. Replayed
/// offline on the 347 candidates over a crack or a print measured in doubt (four passes each) in
/// five trial runs at real time (seeds 9540–10019, 9900–10019 twice), stopping after two where
/// they lay 0.03–0.06 from the threshold judged every candidate as four passes did (8 on the
/// wrong side either way); at 0.05, 305 of them stopped after two
/// (`crates/research/EXPERIMENTS.md`, "Two estimates of a ratio in doubt").
pub const PRINT_RATIO_SETTLED: f64 = 0.05;

/// How far the print check's raised pass runs past each end of the candidate's stroke, mm (the
/// default of the planner's [`crackbot_planner::RaisedPass`]; `[plan.planner]`'s
/// `raised_pass` replaces it and the speed below).
pub const PRINT_CHECK_OVERRUN_MM: f64 = 1.5;
/// Speed of the print check's raised pass, mm/s (or the manipulator's travel limit, if lower):
/// 0.1 mm between the sensor's samples, a tenth of the fibre's spot.
pub const PRINT_CHECK_SPEED_MM_S: f64 = 40.0;

/// How the print check measures and decides: `[print_check]` of the configuration file. Each
/// field's default is the constant it names, with the measurement behind it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PrintCheckConfig {
    /// Fused missions: a candidate the finger confirmed is passed over once more with the
    /// finger raised this high (mm above the plate, not touching), and rejected as a print when
    /// its proximity dip keeps its share of the signal there ([`print_check`]: ink darkens the
    /// fibre alike at every height, a crack's floor less when the fibre is farther). `None` (0
    /// in the file): no raised pass. [`PRINT_CHECK_HEIGHT_MM`].
    #[serde(with = "crate::inspect::off::at_zero")]
    pub height_mm: Option<f64>,
    /// Above this print ratio, a print ([`print_check::PRINT_RATIO`]).
    pub print_ratio: f64,
    /// [`PRINT_RATIO_DOUBT`].
    pub ratio_doubt: f64,
    /// [`PRINT_CHECK_PASSES_IN_DOUBT`].
    pub passes_in_doubt: usize,
    /// [`PRINT_RATIO_SETTLED`].
    pub ratio_settled: f64,
    /// [`RAISED_PASS_GUARD_COUNTS`].
    pub guard_counts: f64,
    /// [`RAISED_PASS_CLEAR_MM`].
    pub clear_mm: f64,
    /// [`SURFACE_RISE_TOLERANCE_MM`].
    pub surface_rise_tolerance_mm: f64,
    /// [`MAX_SURFACE_RISE_MM`].
    pub max_surface_rise_mm: f64,
    /// [`PRINT_CHECK_OVERRUN_MM`] (the plan's own `raised_pass`, where given, replaces it and
    /// the speed).
    pub overrun_mm: f64,
    /// [`PRINT_CHECK_SPEED_MM_S`].
    pub speed_mm_s: f64,
}

impl Default for PrintCheckConfig {
    fn default() -> Self {
        PrintCheckConfig {
            height_mm: Some(PRINT_CHECK_HEIGHT_MM),
            print_ratio: print_check::PRINT_RATIO,
            ratio_doubt: PRINT_RATIO_DOUBT,
            passes_in_doubt: PRINT_CHECK_PASSES_IN_DOUBT,
            ratio_settled: PRINT_RATIO_SETTLED,
            guard_counts: RAISED_PASS_GUARD_COUNTS,
            clear_mm: RAISED_PASS_CLEAR_MM,
            surface_rise_tolerance_mm: SURFACE_RISE_TOLERANCE_MM,
            max_surface_rise_mm: MAX_SURFACE_RISE_MM,
            overrun_mm: PRINT_CHECK_OVERRUN_MM,
            speed_mm_s: PRINT_CHECK_SPEED_MM_S,
        }
    }
}

impl PrintCheckConfig {
    /// Refuses a setting out of range, naming it.
    pub fn check(&self) -> Result<(), MissionError> {
        if let Some(h) = self.height_mm {
            print_check_height(h)?;
        }
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let at_least_zero = |v: f64| v.is_finite() && v >= 0.0;
        let passes = self.passes_in_doubt as f64;
        let checks = [
            (
                "print_check.print_ratio",
                self.print_ratio,
                positive(self.print_ratio),
                "a number > 0",
            ),
            (
                "print_check.ratio_doubt",
                self.ratio_doubt,
                at_least_zero(self.ratio_doubt),
                "a number ≥ 0",
            ),
            (
                "print_check.passes_in_doubt",
                passes,
                (1..=16).contains(&self.passes_in_doubt),
                "1–16",
            ),
            (
                "print_check.ratio_settled",
                self.ratio_settled,
                at_least_zero(self.ratio_settled),
                "a number ≥ 0",
            ),
            (
                "print_check.guard_counts",
                self.guard_counts,
                positive(self.guard_counts),
                "a number > 0",
            ),
            (
                "print_check.clear_mm",
                self.clear_mm,
                at_least_zero(self.clear_mm),
                "a number ≥ 0",
            ),
            (
                "print_check.surface_rise_tolerance_mm",
                self.surface_rise_tolerance_mm,
                at_least_zero(self.surface_rise_tolerance_mm),
                "a number ≥ 0",
            ),
            (
                "print_check.max_surface_rise_mm",
                self.max_surface_rise_mm,
                at_least_zero(self.max_surface_rise_mm),
                "a number ≥ 0",
            ),
            (
                "print_check.overrun_mm",
                self.overrun_mm,
                at_least_zero(self.overrun_mm),
                "a number ≥ 0",
            ),
            (
                "print_check.speed_mm_s",
                self.speed_mm_s,
                positive(self.speed_mm_s),
                "a number > 0",
            ),
        ];
        for (field, value, ok, allowed) in checks {
            if !ok {
                return Err(MissionError::Setting {
                    field,
                    value,
                    allowed,
                });
            }
        }
        Ok(())
    }
}

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
            field: "print_check.height_mm",
            value: h,
            allowed: "0 (off) or 0.5–20 mm",
        })
    }
}
