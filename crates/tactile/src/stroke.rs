//! What one stroke's proximity channel says about the surface under it, as pure functions of
//! its samples and positions: where a stroke that also crossed a second crack or a print beside
//! its candidate has the candidate's own dip ([`own_dip`]), whether the stroke's two ends read
//! alike ([`ends_agree`]), and a tactile row cut into stroke-long pieces ([`split_by_travel`]).
//! The mission's touch step decides with them; nothing here moves an arm.

use std::ops::Range;

use crate::localise::{centred_moving_average, localise, CrackExtent, LocaliseConfig};

/// A candidate stroke's dip wider than the candidate (its detected width, or the planner's
/// assumed one) by more than this, mm, is looked at for several dips
/// ([`SEPARATE_DIPS_GAP_MM`]): the stroke also crossed a second crack or a print beside the
/// candidate, and the localiser, which counts everything between a dip's first and last sample
/// below half depth (a wide crack's middle can come back up), put the candidate between them. On
/// the simulated trial scenes 9540–9659 (real time), two such strokes (9566, 9570) put their
/// crack's report between two cracks 4.3–4.9 mm apart, 1.5 and 1.0 mm off its crack (9570: a
/// false report and a missed crack). Where the channel does not come back to the surface
/// between the dips (9325), or the detection spans both (9396), nothing changes.
pub const SEPARATE_DIPS_EXCESS_MM: f64 = 2.0;
/// Dips are separate where the smoothed proximity channel comes back within this share of the
/// dip's depth of the sound surface's level …
pub const SEPARATE_DIPS_BACK_SHARE: f64 = 0.15;
/// … for at least this much of the stroke's travel, mm. The dip nearest the candidate's axis is
/// then localised alone.
pub const SEPARATE_DIPS_GAP_MM: f64 = 0.5;

/// When a candidate's stroke is looked at for several dips, and when they are apart
/// ([`own_dip`]); the defaults are the constants above.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SeparateDips {
    /// [`SEPARATE_DIPS_EXCESS_MM`].
    pub excess_mm: f64,
    /// [`SEPARATE_DIPS_BACK_SHARE`].
    pub back_share: f64,
    /// [`SEPARATE_DIPS_GAP_MM`].
    pub gap_mm: f64,
}

impl Default for SeparateDips {
    fn default() -> Self {
        SeparateDips {
            excess_mm: SEPARATE_DIPS_EXCESS_MM,
            back_share: SEPARATE_DIPS_BACK_SHARE,
            gap_mm: SEPARATE_DIPS_GAP_MM,
        }
    }
}

/// Consecutive pieces of a pass, each covering `stroke_mm` of travel (tactile rows); a remainder
/// shorter than half a stroke joins the last piece.
pub fn split_by_travel(positions: &[f64], stroke_mm: f64) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = 0;
    for (i, &x) in positions.iter().enumerate() {
        if (x - positions[start]).abs() >= stroke_mm {
            out.push((start, i));
            start = i;
        }
    }
    if positions.len() > start {
        let short = positions
            .last()
            .is_some_and(|&x| (x - positions[start]).abs() < stroke_mm / 2.0);
        match out.last_mut() {
            // A short remainder joins the piece before it.
            Some(last) if short => last.1 = positions.len(),
            _ => out.push((start, positions.len())),
        }
    }
    out
}

/// Samples at each end of a stroke whose proximity level stands for the surface there (0.05 s
/// at 400 Hz, about 0.2 mm at the paper's speed).
const END_SAMPLES: usize = 20;

/// The proximity channel at a stroke's two ends: the medians of its first and last
/// [`END_SAMPLES`], counts; `None` for a stroke of fewer than three times as many samples.
pub fn end_levels(p: &[f64]) -> Option<[f64; 2]> {
    if p.len() < 3 * END_SAMPLES {
        return None;
    }
    let median = |v: &[f64]| {
        let mut v = v.to_vec();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    Some([
        median(&p[..END_SAMPLES]),
        median(&p[p.len() - END_SAMPLES..]),
    ])
}

/// Whether a stroke's two ends read alike: the darker end's signal above the fibre's dark
/// level is at least `share` of the brighter end's. A stroke is planned to start and end on
/// sound surface; one whose ends differ more began or ended on something else (another crack
/// or a print beside the candidate, a bump's flank, a screw head, a crack wider than its
/// stroke). A stroke too short to tell agrees.
pub fn ends_agree(p: &[f64], dark: f64, share: f64) -> bool {
    match end_levels(p) {
        Some([a, b]) => {
            let (lo, hi) = ((a.min(b) - dark).max(0.0), (a.max(b) - dark).max(0.0));
            lo >= share * hi
        }
        None => true,
    }
}

/// Where one stroke's proximity dip is several dips apart — the smoothed P back within
/// `back_share` of the dip's depth of the sound surface's level for at least `gap_mm` of travel
/// between them (a second crack or a print beside the candidate) — the samples around the dip
/// nearest `near_mm` along the stroke: from halfway across the gap before it to halfway across
/// the gap after it. `None` where there is one dip, or `along` is not one pass (it must run one
/// way). `p` is the proximity channel, `baseline` and `depth` the stroke's dip as the localiser
/// read it (counts).
pub fn nearest_of_several_dips(
    p: &[f64],
    along: &[f64],
    baseline: f64,
    depth: f64,
    near_mm: f64,
    back_share: f64,
    gap_mm: f64,
) -> Option<Range<usize>> {
    let n = p.len();
    if n != along.len() || n < 3 || depth.is_nan() || depth <= 0.0 {
        return None;
    }
    let rising = along[n - 1] >= along[0];
    if along
        .windows(2)
        .any(|w| if rising { w[1] < w[0] } else { w[1] > w[0] })
    {
        return None;
    }
    // The localiser's own smoothing.
    let smooth =
        centred_moving_average(p.iter().copied(), LocaliseConfig::default().smooth_samples);
    let low = baseline - 0.5 * depth;
    let back = baseline - back_share * depth;
    // Runs of samples below half depth, as index ranges.
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for (i, &v) in smooth.iter().enumerate() {
        if v < low {
            match runs.last_mut() {
                Some(r) if r.1 == i => r.1 = i + 1,
                _ => runs.push((i, i + 1)),
            }
        }
    }
    // Runs joined into dips unless P came back to the surface for `gap_mm` between them.
    let mut dips: Vec<(usize, usize)> = Vec::new();
    for r in runs {
        let apart = dips.last().is_some_and(|d| {
            let up: Vec<usize> = (d.1..r.0).filter(|&i| smooth[i] >= back).collect();
            match (up.first(), up.last()) {
                (Some(&a), Some(&b)) => (along[b] - along[a]).abs() >= gap_mm,
                _ => false,
            }
        });
        match dips.last_mut() {
            Some(d) if !apart => d.1 = r.1,
            _ => dips.push(r),
        }
    }
    if dips.len() < 2 {
        return None;
    }
    let centre = |d: &(usize, usize)| 0.5 * (along[d.0] + along[d.1 - 1]);
    let k = (0..dips.len()).min_by(|&a, &b| {
        (centre(&dips[a]) - near_mm)
            .abs()
            .total_cmp(&(centre(&dips[b]) - near_mm).abs())
    })?;
    let from = if k == 0 {
        0
    } else {
        (dips[k - 1].1 + dips[k].0) / 2
    };
    let to = if k + 1 == dips.len() {
        n
    } else {
        (dips[k].1 + dips[k + 1].0) / 2
    };
    Some(from..to)
}

/// A candidate's own dip where its stroke also crossed a second crack or a print beside it:
/// where the localiser's one dip (`extent`, over the stroke's `samples` at positions `along`)
/// is wider than the candidate (`candidate_width_mm`) by more than `dips.excess_mm`
/// ([`SEPARATE_DIPS_EXCESS_MM`]) and the stroke's dips lie apart ([`nearest_of_several_dips`]
/// with `dips`' share and gap), the samples around the one nearest the candidate (`near_mm`
/// along the stroke) and that dip localised alone. `None` otherwise: the stroke's dip is the
/// candidate's. The mission reports the candidate where this dip lies and judges its print
/// check on these samples.
pub fn own_dip(
    samples: &[[f64; 4]],
    along: &[f64],
    extent: &CrackExtent,
    candidate_width_mm: f64,
    near_mm: f64,
    config: &LocaliseConfig,
    dips: &SeparateDips,
) -> Option<(Range<usize>, CrackExtent)> {
    if samples.len() != along.len() || extent.width_mm <= candidate_width_mm + dips.excess_mm {
        return None;
    }
    let p: Vec<f64> = samples.iter().map(|v| v[3]).collect();
    let r = nearest_of_several_dips(
        &p,
        along,
        extent.baseline_counts,
        extent.depth_counts,
        near_mm,
        dips.back_share,
        dips.gap_mm,
    )?;
    let own = localise(&samples[r.clone()], &along[r.clone()], config)
        .ok()
        .flatten()?;
    Some((r, own))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn of_two_separate_dips_the_one_nearest_the_candidate_is_taken() {
        // 10 mm at 0.01 mm a sample; the surface reads 500, dips 200 deep.
        let along: Vec<f64> = (0..1000).map(|i| f64::from(i) * 0.01).collect();
        let trace = |dips: &[(f64, f64, f64)]| -> Vec<f64> {
            along
                .iter()
                .map(|&x| {
                    dips.iter().fold(
                        500.0,
                        |p: f64, &(a, b, level)| {
                            if (a..b).contains(&x) {
                                p.min(level)
                            } else {
                                p
                            }
                        },
                    )
                })
                .collect()
        };
        let two = trace(&[(2.5, 3.5, 300.0), (6.5, 7.5, 300.0)]);
        let r = nearest_of_several_dips(&two, &along, 500.0, 200.0, 7.2, 0.15, 0.5).unwrap();
        assert!(along[r.start] > 3.5 && along[r.start] < 6.5, "{r:?}");
        assert_eq!(r.end, along.len());
        let r = nearest_of_several_dips(&two, &along, 500.0, 200.0, 2.0, 0.15, 0.5).unwrap();
        assert_eq!(r.start, 0);
        assert!(along[r.end - 1] > 3.5 && along[r.end - 1] < 6.5, "{r:?}");
        // One dip, or two whose middle stays below the surface (a wide crack's floor coming
        // back up part way), or a gap shorter than asked: one dip.
        let one = trace(&[(4.0, 6.0, 300.0)]);
        assert_eq!(
            nearest_of_several_dips(&one, &along, 500.0, 200.0, 5.0, 0.15, 0.5),
            None
        );
        let wide = trace(&[(2.5, 7.5, 450.0), (2.5, 3.5, 300.0), (6.5, 7.5, 300.0)]);
        assert_eq!(
            nearest_of_several_dips(&wide, &along, 500.0, 200.0, 5.0, 0.15, 0.5),
            None
        );
        let close = trace(&[(2.5, 4.7, 300.0), (5.0, 7.5, 300.0)]);
        assert_eq!(
            nearest_of_several_dips(&close, &along, 500.0, 200.0, 5.0, 0.15, 0.5),
            None
        );
        // Positions that turn back are not one pass.
        let mut back = along.clone();
        back[500] = 0.0;
        assert_eq!(
            nearest_of_several_dips(&two, &back, 500.0, 200.0, 7.2, 0.15, 0.5),
            None
        );
        // Nothing to read: no depth, lengths that differ.
        assert_eq!(
            nearest_of_several_dips(&two, &along, 500.0, 0.0, 7.2, 0.15, 0.5),
            None
        );
        assert_eq!(
            nearest_of_several_dips(&two[1..], &along, 500.0, 200.0, 7.2, 0.15, 0.5),
            None
        );
    }

    #[test]
    fn a_stroke_whose_ends_read_unlike_each_other_disagrees() {
        let dark = 280.0;
        let stroke = |a: f64, b: f64| {
            let mut p = vec![a; 40];
            p.extend(vec![300.0; 40]);
            p.extend(vec![b; 40]);
            p
        };
        assert!(ends_agree(&stroke(500.0, 480.0), dark, 0.6));
        assert!(ends_agree(&stroke(500.0, 420.0), dark, 0.6)); // 140 of 220
        assert!(!ends_agree(&stroke(500.0, 400.0), dark, 0.6)); // 120 of 220
        assert!(!ends_agree(&stroke(330.0, 500.0), dark, 0.6));
        // Below the dark level counts as no signal; too short to tell agrees.
        assert!(!ends_agree(&stroke(270.0, 500.0), dark, 0.6));
        assert!(ends_agree(&[300.0; 50], dark, 0.6));
        assert_eq!(end_levels(&[1.0; 59]), None);
        let mut p = vec![1.0; 30];
        p.extend(vec![2.0; 30]);
        assert_eq!(end_levels(&p), Some([1.0, 2.0]));
    }

    #[test]
    fn rows_are_cut_into_stroke_long_pieces_without_a_short_tail() {
        let x: Vec<f64> = (0..=350).map(|i| f64::from(i) * 0.1).collect(); // 0–35 mm
                                                                           // 0–16, then 16–35: the 3 mm tail joins the second piece.
        assert_eq!(split_by_travel(&x, 16.0), vec![(0, 160), (160, 351)]);
        let x: Vec<f64> = (0..=300).map(|i| f64::from(i) * 0.1).collect(); // 0–30 mm
        assert_eq!(split_by_travel(&x, 16.0), vec![(0, 160), (160, 301)]);
        let x: Vec<f64> = (0..=450).map(|i| f64::from(i) * 0.1).collect(); // 0–45 mm
        assert_eq!(
            split_by_travel(&x, 16.0),
            vec![(0, 160), (160, 320), (320, 451)]
        );
        assert!(split_by_travel(&[], 16.0).is_empty());
    }

    #[test]
    fn a_stroke_across_two_lines_gives_the_candidate_the_dip_nearest_it() {
        // 12 mm at 0.01 mm a sample, the surface at 500 counts on every channel, two dips of
        // 200 counts in P 5 mm apart (a crack and a print beside it).
        let along: Vec<f64> = (0..1200).map(|i| f64::from(i) * 0.01).collect();
        let samples: Vec<[f64; 4]> = along
            .iter()
            .map(|&x| {
                let p = if (3.0..4.0).contains(&x) || (8.0..9.0).contains(&x) {
                    300.0
                } else {
                    500.0
                };
                [500.0, 500.0, 500.0, p]
            })
            .collect();
        let config = LocaliseConfig::default();
        let extent = localise(&samples, &along, &config)
            .expect("a pass")
            .expect("a dip");
        let dips = SeparateDips::default();
        // The localiser's one dip spans both lines: wider than a 1 mm candidate by far.
        assert!(extent.width_mm > 1.0 + dips.excess_mm, "{extent:?}");
        let (range, own) =
            own_dip(&samples, &along, &extent, 1.0, 8.5, &config, &dips).expect("its own dip");
        assert!(
            along[range.start] > 4.0 && along[range.end - 1] >= 9.0,
            "{range:?}"
        );
        assert!(own.centre_mm > 7.0 && own.centre_mm < 10.0, "{own:?}");
        assert!(own.width_mm < extent.width_mm);
        // A candidate as wide as the dip, or lengths that differ: the stroke's dip is its own.
        assert!(own_dip(&samples, &along, &extent, 20.0, 8.5, &config, &dips).is_none());
        assert!(own_dip(&samples[1..], &along, &extent, 1.0, 8.5, &config, &dips).is_none());
    }
}
