//! The judge step: from what the finger felt over a candidate, pass by pass, to a verdict —
//! confirmed as a crack, or rejected with the reason. Pure functions of [`Felt`] and [`Rules`],
//! tested without sockets or threads.

use crackbot_planner::Candidate;

use super::felt::{top_class, Crossing, Felt};
use super::rules::Rules;
use crate::inspect::doubts::Width;
use crate::inspect::report::{Evidence, RejectedCandidate, ReportedCrack};

/// Why the finger rejected a candidate.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Rejection {
    /// Dead or saturated channels on every pass: the finger could not judge.
    Unjudged,
    /// Read as a crack, but the raised pass was stopped before it could judge the crossing.
    Standing,
    /// Read as a crack, but its print ratio is below what the shallowest crack gives.
    NeitherCrackNorPrint {
        /// The print ratio.
        ratio: f64,
    },
    /// The print check: its dip keeps its share of the signal raised.
    Print {
        /// The print ratio.
        ratio: f64,
    },
    /// Read as a crack without the proximity dip a crack makes.
    NoDip,
    /// Read as another class.
    Other,
}

/// The verdict on what was felt over one candidate.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Judgement {
    /// A crack: where the passes crossed it (mean), the extent along the first pass that
    /// located one, and the mean width verdict and its spread.
    Crack {
        /// Where, mm on the plate.
        position_mm: [f64; 2],
        /// Along the pass, where it starts and ends.
        extent_mm: Option<[[f64; 2]; 2]>,
        /// The width ([`Width`]).
        width: Option<Width>,
    },
    /// Not a crack.
    Rejected(Rejection),
}

/// The judge's verdict on `f`, with the class reported and its share of the votes.
pub(crate) fn judge(f: &Felt, rules: &Rules) -> (Judgement, usize, f64) {
    let total: f64 = f.votes.iter().sum();
    let reads = f.reads_as_crack(rules);
    let class = if reads {
        rules.crack_class
    } else {
        top_class(&f.votes)
    };
    let confidence = if total > 0.0 {
        f.votes[class] / total
    } else {
        0.0
    };
    let print = f.height_ratio.is_some_and(|r| r > rules.print_ratio);
    // Below what the shallowest crack gives: something else brightened the raised pass.
    let too_low = f
        .height_ratio
        .zip(rules.ratio_floor)
        .is_some_and(|(r, least)| r < rules.implausible_share * least);
    let judgement = if reads && !print && !f.stands && !too_low {
        Judgement::Crack {
            position_mm: mean_crossing(&f.crossings),
            extent_mm: f.crossings.iter().find_map(|c| c.1),
            width: mean_width(&f.widths),
        }
    } else {
        Judgement::Rejected(if f.unknown >= f.passes {
            Rejection::Unjudged
        } else if reads && f.stands {
            Rejection::Standing
        } else if reads && too_low {
            Rejection::NeitherCrackNorPrint {
                ratio: f.height_ratio.unwrap_or(0.0),
            }
        } else if print {
            Rejection::Print {
                ratio: f.height_ratio.unwrap_or(1.0),
            }
        } else if class == rules.crack_class && !f.crossings.is_empty() {
            Rejection::NoDip
        } else {
            Rejection::Other
        })
    };
    (judgement, class, confidence)
}

/// The mean of the crossings' points (NaN where there are none; a confirmed crack has one).
fn mean_crossing(crossings: &[Crossing]) -> [f64; 2] {
    let n = crossings.len() as f64;
    [
        crossings.iter().map(|c| c.0[0]).sum::<f64>() / n,
        crossings.iter().map(|c| c.0[1]).sum::<f64>() / n,
    ]
}

/// The width of a confirmed crack: the mean of its passes' width classes, and the mean of
/// their votes' 10–90 % ranges ([`crackbot_tactile::online::vote_range_mm`]).
fn mean_width(widths: &[(f64, [f64; 2])]) -> Option<Width> {
    if widths.is_empty() {
        return None;
    }
    let n = widths.len() as f64;
    let (mut mm, mut lo, mut hi) = (0.0, 0.0, 0.0);
    for (w, [a, b]) in widths {
        mm += w / n;
        lo += a / n;
        hi += b / n;
    }
    Some(Width {
        mm,
        range_mm: [lo, hi],
    })
}

impl Rejection {
    /// What the finger felt instead, in words (`class` is the name of the top class), as the
    /// report's `felt` says it, with the print check's height from `rules`.
    pub(crate) fn felt(&self, class: &str, rules: &Rules) -> String {
        let height = rules.print_check_mm.unwrap_or(0.0);
        match self {
            Rejection::Unjudged => "unknown".into(),
            Rejection::Standing => "something standing above the plate: the raised pass was \
                                    stopped before it could judge the crossing"
                .into(),
            Rejection::NeitherCrackNorPrint { ratio } => format!(
                "neither a crack nor a print: its proximity dip keeps {:.0} % of its share \
                 with the finger raised {height} mm, less than the shallowest crack's {:.0} %; \
                 something else was in the fibre's view",
                100.0 * ratio,
                100.0 * rules.ratio_floor.unwrap_or(0.0)
            ),
            Rejection::Print { ratio } => format!(
                "a print: its proximity dip keeps {:.0} % of its share with the finger raised \
                 {height} mm",
                100.0 * ratio
            ),
            Rejection::NoDip => format!("{class} without a proximity dip"),
            Rejection::Other => class.to_string(),
        }
    }
}

/// The judge step over every candidate (and tactile row piece) felt: confirmed cracks, and
/// the candidates rejected with what the finger felt instead (row pieces that are not cracks
/// are not listed). `names` are the recognition model's classes.
pub(crate) fn judge_all(
    felt: Vec<(u64, Felt)>,
    candidates: &[(Candidate, f64)],
    rules: &Rules,
    names: &[String],
) -> (Vec<ReportedCrack>, Vec<RejectedCandidate>) {
    let (mut cracks, mut rejected) = (Vec::new(), Vec::new());
    for (key, f) in felt {
        let (judgement, class, confidence) = judge(&f, rules);
        let name = names.get(class).cloned().unwrap_or_default();
        let detection = candidates.iter().find(|(c, _)| c.id == key);
        match judgement {
            Judgement::Crack {
                position_mm,
                extent_mm,
                width,
            } => cracks.push(ReportedCrack {
                candidate: detection.map(|(c, _)| c.id),
                position_mm,
                extent_mm,
                class: name,
                width_mm: width.map(|w| w.mm),
                width_range_mm: width.map(|w| w.range_mm),
                confidence,
                evidence: Evidence {
                    detector_score: detection.map(|d| d.1),
                    slides: f.slides,
                    votes: f.votes,
                    doubts: f.doubts,
                    height_ratio: f.height_ratio,
                    print_ratios: f.print_ratios,
                    floor_ratios: f.floor_ratios,
                    pieces: Vec::new(),
                },
            }),
            Judgement::Rejected(why) => {
                if let Some((c, score)) = detection {
                    rejected.push(RejectedCandidate {
                        candidate: c.id,
                        position_mm: c.centre_mm,
                        felt: why.felt(&name, rules),
                        detector_score: *score,
                        slides: f.slides,
                        height_ratio: f.height_ratio,
                        print_ratios: f.print_ratios,
                        floor_ratios: f.floor_ratios,
                        votes: f.votes,
                    });
                }
            }
        }
    }
    (cracks, rejected)
}

#[cfg(test)]
mod tests {
    use super::super::felt::PassReading;
    use super::super::rules::{IMPLAUSIBLE_RATIO_SHARE, WEAK_NO_CRACK_CONFIDENCE};
    use super::*;
    use crate::inspect::doubts::CrackDoubt;
    use crackbot_tactile::model::Doubt;
    use crackbot_tactile::online::SlideVerdict;

    /// A verdict of `class` (0 "no crack", 1 "crack") with `doubt`.
    fn verdict(class: u32, doubt: Option<Doubt>, confidence: f64) -> SlideVerdict {
        let mut votes = vec![0.1; 4];
        votes[class as usize] = 0.8;
        SlideVerdict {
            class,
            name: String::new(),
            label: f64::from(class),
            confidence,
            votes,
            width: None,
            windows: 100,
            segmented: true,
            segment: (0, 200),
            novel_fraction: 0.0,
            doubt,
            samples: 200,
        }
    }

    fn rules() -> Rules {
        Rules {
            crack_class: 1,
            no_crack_class: Some(0),
            require_dip: true,
            dip_outweighs_doubt: Some(DOUBTED_DIP),
            print_check_mm: Some(2.0),
            ratio_floor: Some(0.37),
            print_ratio: crackbot_tactile::print_check::PRINT_RATIO,
            weak_no_crack: WEAK_NO_CRACK_CONFIDENCE,
            implausible_share: IMPLAUSIBLE_RATIO_SHARE,
        }
    }

    const DOUBTED_DIP: f64 = 0.6;

    /// What was felt over one candidate from passes of `(class, doubt, dip confidence)`, each
    /// crossing at x = 10 + its index, mm.
    fn felt(passes: &[(u32, Option<Doubt>, Option<f64>)], rules: &Rules) -> Felt {
        let mut f = Felt::new(4);
        for (i, (class, doubt, dip)) in passes.iter().enumerate() {
            let v = verdict(*class, doubt.clone(), 0.8);
            let x = 10.0 + i as f64;
            let pass = PassReading {
                verdict: Some(&v),
                width: Some((1.0 + i as f64, [0.5 + i as f64, 2.0 + i as f64])),
                dip_confidence: *dip,
                crossing: ([x, 5.0], dip.map(|_| [[x - 0.5, 5.0], [x + 0.5, 5.0]])),
                on_candidate: true,
                slide: i as u32 + 1,
            };
            f.add_pass(&[i as u32 + 1], &pass, rules);
        }
        f
    }

    #[test]
    fn a_crack_vote_over_a_dip_is_a_crack_where_the_passes_crossed_it() {
        let r = rules();
        let f = felt(&[(1, None, Some(0.9)), (1, None, Some(0.7))], &r);
        assert_eq!(f.slides, vec![1, 2]);
        assert_eq!((f.passes, f.vetoes, f.unknown), (2, 0, 0));
        let (j, class, confidence) = judge(&f, &r);
        assert_eq!(class, 1);
        assert!((confidence - 0.8 / 1.1).abs() < 1e-12, "{confidence}");
        assert_eq!(
            j,
            Judgement::Crack {
                position_mm: [10.5, 5.0],
                extent_mm: Some([[9.5, 5.0], [10.5, 5.0]]),
                width: Some(Width {
                    mm: 1.5,
                    range_mm: [1.0, 2.5],
                }),
            }
        );
    }

    #[test]
    fn without_a_dip_a_crack_vote_is_rejected_unless_the_vote_alone_decides() {
        let mut r = rules();
        let f = felt(&[(1, None, None)], &r);
        let (j, _, _) = judge(&f, &r);
        assert_eq!(j, Judgement::Rejected(Rejection::NoDip));
        assert_eq!(
            Rejection::NoDip.felt("crack", &r),
            "crack without a proximity dip"
        );
        r.require_dip = false;
        assert!(matches!(
            judge(&f, &r).0,
            Judgement::Crack {
                extent_mm: None,
                ..
            }
        ));
    }

    #[test]
    fn the_print_check_rejects_prints_and_ratios_no_crack_gives() {
        let r = rules();
        let mut f = felt(&[(1, None, Some(0.9))], &r);
        let at = |ratio: f64, f: &mut Felt| {
            f.height_ratio = Some(ratio);
            judge(f, &r).0
        };
        assert!(matches!(at(0.5, &mut f), Judgement::Crack { .. }));
        assert_eq!(
            at(0.95, &mut f),
            Judgement::Rejected(Rejection::Print { ratio: 0.95 })
        );
        // Below 0.8 of the shallowest crack's 0.37: neither.
        assert_eq!(
            at(0.2, &mut f),
            Judgement::Rejected(Rejection::NeitherCrackNorPrint { ratio: 0.2 })
        );
        assert!(matches!(at(0.3, &mut f), Judgement::Crack { .. }));
        assert_eq!(
            Rejection::Print { ratio: 0.95 }.felt("crack", &r),
            "a print: its proximity dip keeps 95 % of its share with the finger raised 2 mm"
        );
        assert!(Rejection::NeitherCrackNorPrint { ratio: 0.2 }
            .felt("crack", &r)
            .contains("20 %"));
    }

    #[test]
    fn something_standing_or_dead_channels_reject_and_say_so() {
        let r = rules();
        let mut f = felt(&[(1, None, Some(0.9))], &r);
        f.stands = true;
        assert_eq!(judge(&f, &r).0, Judgement::Rejected(Rejection::Standing));
        let dead = Some(Doubt::DeadChannel { channel: "P" });
        let f = felt(&[(1, dead.clone(), Some(0.9)), (1, dead, Some(0.9))], &r);
        assert_eq!(f.unknown, 2);
        assert_eq!(judge(&f, &r).0, Judgement::Rejected(Rejection::Unjudged));
        assert_eq!(Rejection::Unjudged.felt("crack", &r), "unknown");
    }

    #[test]
    fn a_doubted_no_crack_over_a_deep_dip_counts_as_a_crossing_on_a_candidate_only() {
        let r = rules();
        let novel = Some(Doubt::Novel { fraction: 0.4 });
        let f = felt(&[(0, novel.clone(), Some(0.8))], &r);
        assert_eq!((f.crossings.len(), f.vetoes), (1, 0));
        assert!(
            f.doubts
                .iter()
                .any(|d| matches!(d, CrackDoubt::DoubtedNoCrack { slide: 1, .. })),
            "{:?}",
            f.doubts
        );
        // Its top class is "no crack", but no pass vetoed it: it reads as a crack.
        assert!(f.reads_as_crack(&r));
        assert!(matches!(judge(&f, &r).0, Judgement::Crack { .. }));
        // An undoubted "no crack", or one over a shallow dip, vetoes.
        let f = felt(&[(0, None, Some(0.8))], &r);
        assert_eq!((f.crossings.len(), f.vetoes), (0, 1));
        assert_eq!(judge(&f, &r).0, Judgement::Rejected(Rejection::Other));
        let f = felt(&[(1, None, Some(0.9)), (0, novel.clone(), Some(0.3))], &r);
        assert_eq!(f.vetoes, 1);
        // On a tactile row's piece (no candidate) the verdict always stands.
        let v = verdict(0, novel, 0.8);
        let mut row = Felt::new(4);
        let pass = PassReading {
            verdict: Some(&v),
            width: None,
            dip_confidence: Some(0.9),
            crossing: ([0.0, 0.0], Some([[0.0, 0.0], [1.0, 0.0]])),
            on_candidate: false,
            slide: 1,
        };
        row.add_pass(&[1], &pass, &r);
        assert_eq!((row.crossings.len(), row.vetoes), (0, 1));
    }
}
