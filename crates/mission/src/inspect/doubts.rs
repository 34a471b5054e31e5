//! Why a pass or a crack is doubted ([`PassDoubt`], [`CrackDoubt`]), as the report keeps them:
//! objects tagged by `kind` in the JSON, sentences in the text.

use crackbot_tactile::model::Doubt;
use serde::Serialize;

/// How an unjudged pass's doubt begins (a stroke whose ends read unlike each other).
pub const NOT_JUDGED: &str = "not judged";

/// Why a pass's verdict is not to be trusted (the recognition model's own doubt), or why the
/// pass was not judged. In the JSON report, an object tagged by `kind`.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PassDoubt {
    /// A channel the model uses did not move over the pass.
    DeadChannel {
        /// `D1`, `D2`, `D3` or `P`.
        channel: &'static str,
    },
    /// Too many samples outside the training range (saturation, another mounting).
    OutOfRange {
        /// The channel with most samples out.
        channel: &'static str,
        /// Share of the pass's samples out of range.
        fraction: f64,
    },
    /// Too many windows unlike any the model learned (a surface unlike training).
    Novel {
        /// Share of novel windows.
        fraction: f64,
    },
    /// The vote is weak.
    LowConfidence {
        /// The winning class's vote, 0–1.
        confidence: f64,
    },
    /// Not judged: the stroke's ends read unlike each other (not both the sound surface), so
    /// the candidate was stroked again beside it.
    NotJudged {
        /// The proximity channel at the stroke's two ends, counts.
        end_counts: [f64; 2],
        /// How far along the candidate the stroke was made again, mm.
        moved_mm: f64,
    },
}

impl From<&Doubt> for PassDoubt {
    fn from(d: &Doubt) -> PassDoubt {
        match *d {
            Doubt::DeadChannel { channel } => PassDoubt::DeadChannel { channel },
            Doubt::OutOfRange { channel, fraction } => PassDoubt::OutOfRange { channel, fraction },
            Doubt::Novel { fraction } => PassDoubt::Novel { fraction },
            Doubt::LowConfidence { confidence } => PassDoubt::LowConfidence { confidence },
        }
    }
}

impl std::fmt::Display for PassDoubt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PassDoubt::DeadChannel { channel } => write!(f, "channel {channel} did not move"),
            PassDoubt::OutOfRange { channel, fraction } => write!(
                f,
                "{:.0} % of the samples outside the training range (channel {channel})",
                100.0 * fraction
            ),
            PassDoubt::Novel { fraction } => write!(
                f,
                "a surface unlike training: {:.0} % of the windows unlike any learned",
                100.0 * fraction
            ),
            PassDoubt::LowConfidence { confidence } => {
                write!(f, "a weak vote ({confidence:.2})")
            }
            PassDoubt::NotJudged {
                end_counts: [e0, e1],
                moved_mm,
            } => write!(
                f,
                "{NOT_JUDGED}: the stroke's ends read {e0:.0} and {e1:.0} counts, not both the \
                 sound surface; stroked again {moved_mm:.1} mm along the candidate"
            ),
        }
    }
}

/// A doubt raised over a candidate, pass by pass or by the print check. In the JSON report, an
/// object tagged by `kind`; its text ([`std::fmt::Display`]) says it in words.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum CrackDoubt {
    /// A pass's verdict was doubted.
    Pass {
        /// The pass (slide id).
        slide: u32,
        /// Why.
        doubt: PassDoubt,
    },
    /// A pass read "no crack" but doubted it, over a proximity dip deep enough to stand for a
    /// crack; the print check decides.
    DoubtedNoCrack {
        /// The pass.
        slide: u32,
        /// Its "no crack" vote, 0–1.
        confidence: f64,
        /// Its dip's confidence, 0–1.
        dip_confidence: f64,
    },
    /// The print check's raised pass was stopped: something stands under the line.
    RaisedPassStopped {
        /// Where, mm along the pass.
        at_mm: f64,
        /// The pass's length, mm.
        length_mm: f64,
        /// How far the proximity channel rose above the sound surface, counts.
        rise_counts: f64,
    },
    /// The surface at the line stood above the plate: the raised pass was made again higher.
    SurfaceRise {
        /// How far above the plate, mm.
        rise_mm: f64,
        /// The height the pass was made again at, mm.
        height_mm: f64,
    },
    /// The raised pass made again higher was stopped; the first pass's ratio stands.
    RaisedAgainStopped {
        /// Where, mm along it.
        at_mm: f64,
        /// The rise, counts.
        rise_counts: f64,
    },
    /// One of the raised passes made because the first ratio was in doubt was stopped.
    RaisedInDoubtStopped {
        /// Which pass (2 and up).
        pass: usize,
        /// Where, mm along it.
        at_mm: f64,
        /// The rise, counts.
        rise_counts: f64,
        /// Passes the ratio rests on.
        passes: usize,
    },
    /// The first print ratio lay near the threshold: several passes' mean decides.
    RatioInDoubt {
        /// The first pass's print ratio.
        first: f64,
        /// The print check's threshold.
        threshold: f64,
        /// How near it the first ratio had to lie to be in doubt.
        within: f64,
        /// Passes whose mean decides.
        passes: usize,
    },
    /// A contact stroke the print check could not compare with.
    UnusableStroke {
        /// Why.
        reason: String,
    },
}

impl std::fmt::Display for CrackDoubt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CrackDoubt::Pass { slide, doubt } => write!(f, "slide {slide}: {doubt}"),
            CrackDoubt::DoubtedNoCrack {
                slide,
                confidence,
                dip_confidence,
            } => write!(
                f,
                "slide {slide}: read as no crack ({confidence:.2}), doubted; its proximity dip \
                 ({dip_confidence:.2}) stands for a crack"
            ),
            CrackDoubt::RaisedPassStopped {
                at_mm,
                length_mm,
                rise_counts,
            } => write!(
                f,
                "the raised pass was stopped {at_mm:.1} mm along its {length_mm:.1} mm: the \
                 proximity fibre read {rise_counts:.0} counts above the sound surface, \
                 something stands under the line"
            ),
            CrackDoubt::SurfaceRise { rise_mm, height_mm } => write!(
                f,
                "the surface at the line stood {rise_mm:.2} mm above the plate: the raised pass \
                 was made again {height_mm:.2} mm up"
            ),
            CrackDoubt::RaisedAgainStopped { at_mm, rise_counts } => write!(
                f,
                "the raised pass made again was stopped {at_mm:.1} mm along: the proximity \
                 fibre read {rise_counts:.0} counts above the sound surface; the first pass's \
                 ratio stands"
            ),
            CrackDoubt::RaisedInDoubtStopped {
                pass,
                at_mm,
                rise_counts,
                passes,
            } => write!(
                f,
                "raised pass {pass} was stopped {at_mm:.1} mm along: the proximity fibre read \
                 {rise_counts:.0} counts above the sound surface; the print ratio rests on \
                 {passes} passes"
            ),
            CrackDoubt::RatioInDoubt {
                first,
                threshold,
                within,
                passes,
            } => write!(
                f,
                "the first raised pass's print ratio {first:.3} was within {within} of \
                 {threshold}: the mean of {passes} passes' print and floor ratios decides"
            ),
            CrackDoubt::UnusableStroke { reason } => write!(f, "{reason}"),
        }
    }
}

/// A crack's width as the finger felt it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Width {
    /// The mean of the passes' width classes, mm.
    pub mm: f64,
    /// The mean of their votes' 10–90 % ranges, mm ([`ReportedCrack::width_range_mm`]).
    pub range_mm: [f64; 2],
}
