//! What the finger felt over one candidate, pass by pass ([`Felt`]): the votes, widths,
//! crossings, vetoes and doubts the touch step adds and the print check completes, and that
//! the judge step decides on.

use crackbot_tactile::model::Doubt;
use crackbot_tactile::online::SlideVerdict;

use super::rules::{doubted_no_crack_with_dip, Rules};
use crate::inspect::doubts::CrackDoubt;

/// Where a pass crossed a crack, mm on the plate, and the crack's extent along the pass.
pub(crate) type Crossing = ([f64; 2], Option<[[f64; 2]; 2]>);

/// The class with the most votes (the last of those tied; 0 when there are none).
pub(crate) fn top_class(votes: &[f64]) -> usize {
    votes
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .map_or(0, |(i, _)| i)
}

/// What the finger felt over one candidate (or one stroke-long piece of a tactile row): the
/// recognition votes and width verdicts of its passes, where they crossed it, and what the
/// print check's raised passes read.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Felt {
    /// Recognition votes per class, summed over the passes.
    pub(crate) votes: Vec<f64>,
    /// The slides (link ids) of its passes.
    pub(crate) slides: Vec<u32>,
    /// Each pass's width verdict: its class and the vote's 10–90 % range, mm.
    pub(crate) widths: Vec<(f64, [f64; 2])>,
    /// Doubts raised, in words.
    pub(crate) doubts: Vec<CrackDoubt>,
    /// Where the passes that stood for a crack crossed it.
    pub(crate) crossings: Vec<Crossing>,
    /// Passes read as something other than a crack (a doubted "no crack" over a deep dip
    /// does not count).
    pub(crate) vetoes: usize,
    /// Passes with a dead or saturated channel.
    pub(crate) unknown: usize,
    /// Passes judged.
    pub(crate) passes: usize,
    /// The print check's ratio that decides ([`crate::inspect::Evidence::height_ratio`]).
    pub(crate) height_ratio: Option<f64>,
    /// The print check's ratio of each raised pass.
    pub(crate) print_ratios: Vec<f64>,
    /// Each raised pass's floor ratio, where the first print ratio was in doubt.
    pub(crate) floor_ratios: Vec<Option<f64>>,
    /// The print check's raised pass was stopped before it could judge the crossing (before
    /// it had passed it, or with no ratio from what it read): something stands there.
    pub(crate) stands: bool,
}

/// One judged pass, as the rules read it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PassReading<'a> {
    /// The recognition verdict (`None`: too short to classify).
    pub(crate) verdict: Option<&'a SlideVerdict>,
    /// The width verdict's class and the vote's 10–90 % range, mm.
    pub(crate) width: Option<(f64, [f64; 2])>,
    /// The confidence of the pass's proximity dip (`None`: no dip).
    pub(crate) dip_confidence: Option<f64>,
    /// Where the pass crossed what it felt.
    pub(crate) crossing: Crossing,
    /// The pass was over a candidate (not a piece of a tactile row).
    pub(crate) on_candidate: bool,
    /// The first slide of the pass's classification unit (named in doubts).
    pub(crate) slide: u32,
}

impl Felt {
    /// Nothing felt yet, with `classes` vote counters.
    pub(crate) fn new(classes: usize) -> Felt {
        Felt {
            votes: vec![0.0; classes],
            ..Felt::default()
        }
    }

    /// Adds one pass: its slides, vote, doubts, width, and its crossing where it stands for a
    /// crack (read as one, or a doubted "no crack" over a deep dip), a veto where not.
    pub(crate) fn add_pass(&mut self, slides: &[u32], pass: &PassReading<'_>, rules: &Rules) {
        self.slides.extend_from_slice(slides);
        self.passes += 1;
        if let Some(v) = pass.verdict {
            for (acc, x) in self.votes.iter_mut().zip(&v.votes) {
                *acc += x;
            }
            // A dead or saturated channel makes the slide unusable; a novel surface is
            // reported as a doubt (the simulated finger is still unlike the real one, see
            // models/tactile/MODEL_CARD.md) but its vote counts.
            if matches!(
                v.doubt,
                Some(Doubt::DeadChannel { .. } | Doubt::OutOfRange { .. })
            ) {
                self.unknown += 1;
            }
            if let Some(d) = &v.doubt {
                self.doubts.push(CrackDoubt::Pass {
                    slide: pass.slide,
                    doubt: d.into(),
                });
            }
            let doubted_dip = pass.on_candidate
                && doubted_no_crack_with_dip(
                    v,
                    rules.no_crack_class,
                    pass.dip_confidence,
                    (rules.weak_no_crack, rules.dip_outweighs_doubt),
                );
            if v.class as usize == rules.crack_class || doubted_dip {
                self.crossings.push(pass.crossing);
            } else {
                self.vetoes += 1;
            }
            if doubted_dip {
                self.doubts.push(CrackDoubt::DoubtedNoCrack {
                    slide: pass.slide,
                    confidence: v.confidence,
                    dip_confidence: pass.dip_confidence.unwrap_or(0.0),
                });
            }
        }
        if let Some(w) = pass.width {
            self.widths.push(w);
        }
    }

    /// The contact passes read the candidate as a crack: the vote (or a "no crack" vote whose
    /// every pass was doubted over a deep dip), a judged pass, a crossing, and the proximity
    /// dip a crack makes (unless not required). The print check comes after.
    pub(crate) fn reads_as_crack(&self, rules: &Rules) -> bool {
        let top = top_class(&self.votes);
        (top == rules.crack_class || (Some(top) == rules.no_crack_class && self.vetoes == 0))
            && self.unknown < self.passes
            && !self.crossings.is_empty()
            && (self.crossings.iter().any(|c| c.1.is_some()) || !rules.require_dip)
    }
}
