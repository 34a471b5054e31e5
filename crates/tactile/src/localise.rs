//! Localisation along the slide: where a crack starts and ends, in mm on the surface axis of the
//! position stream, from the proximity channel's dip.
//!
//! # Method
//!
//! [`localise`] takes one slide (samples `[D1, D2, D3, P]` and the position of each, mm) and cuts it at the position
//! stream's turning points into passes ([`split_passes`]; the authors' slides go there and back). In each pass
//! ([`localise_pass`]) P is smoothed by a centred 9-sample moving average; its flat level is the 75th percentile
//! (a crack only lowers P, and a 10 mm crack fills more than half a 16 mm pass), its floor the minimum. A dip
//! shallower than 100 counts or 10 × the P noise (from the sample-to-sample differences) is no feature (`None`).
//! Otherwise the dip's edges are where the smoothed P first and last crosses half depth, interpolated between
//! samples and mapped to positions; everything between them counts (a wide crack's middle comes back up, walls
//! dip twice). The positions are then corrected: `+ look_ahead_mm` (the fibre looks ahead of the position's point
//! along +x; 1.352 mm, the simulator's calibrated optics — the real plates' crack positions are not published, so
//! the real data cannot check it) and `∓ direction_lag_mm` along the motion (the dip appears late in the direction
//! of motion: the finger drags behind the device). The width is `(edge distance − 0.794) / 0.7391` (the fibre's
//! spot widens narrow dips, the walls of wide cracks narrow them), and `start_mm`, `end_mm` are the centre ∓ half
//! of it. A slide's passes are fused by a confidence-weighted mean, which cancels the direction lag. The paper's
//! segmentation (`crackbot_dsp::segment`) was not used: its derivative test passes on noise all along a pass, so
//! its span is nearly the whole pass; the deformation channels show no edge sharper than P's.
//!
//! # Measured accuracy
//!
//! `CRACKBOT_DATA_DIR=/work/shared/data cargo run --release -p crackbot-research --example localisation` (real
//! recordings `tactile/{type,width}` repetitions 1–3; simulated slides from `crackbot_sim`).
//!
//! Estimated on **repetition 1** (uncorrected reading, per crack plate): half the difference between the median
//! centres of the two directions is 0.31–0.57 mm (crack 0.50; 1, 2, 5, 8, 10 mm: 0.31, 0.35, 0.42, 0.41, 0.57),
//! the same at the near and the far edge (a shift, not a stretch): **lag 0.418 mm** (median). Dip extent against
//! width (1–10 mm plates, least squares of per-plate medians): extent = 0.794 mm + 0.7391 × width.
//!
//! Real recordings, **repetitions 2 and 3** (24 passes per recording; centre std pooled over both directions,
//! mean over the recordings; max |deviation| of a pass's centre from its recording's mean, worst recording;
//! direction bias = mean centre of the +x passes minus the −x ones, uncorrected → corrected; width MAE against the
//! label over all passes):
//!
//! | class | passes with a dip (reps 1–3) | centre std mm | max dev mm | direction bias mm | width MAE mm |
//! |---|---|---|---|---|---|
//! | crack (type) | 72/72 | 0.057 | 0.14 | +0.91 → +0.08 | – |
//! | 1 mm | 72/72 | 0.111 | 0.20 | +0.63 → −0.20 | 0.17 |
//! | 2 mm | 72/72 | 0.082 | 0.15 | +0.69 → −0.15 | 0.16 |
//! | 5 mm | 73/76 | 0.071 | 0.25 | +0.80 → −0.04 | 0.35 |
//! | 8 mm | 72/72 | 0.051 | 0.16 | +0.87 → +0.03 | 0.14 |
//! | 10 mm | 72/73 | 0.204 | 0.30 | +1.22 → +0.38 | 0.26 |
//! | flat, 0 mm | 0/72, 0/72 | – | – | – | – |
//! | bump | 22/72 | 0.478 | 0.62 | +1.76 → +0.92 | – |
//! | wavy | 72/72 | 0.266 | 0.40 | +1.33 → +0.49 | – |
//!
//! Within one direction the 12 centres of a crack recording spread by 0.02–0.09 mm (std); what remains of the
//! direction bias (−0.24 to +0.38 mm) is the plate-to-plate variation of the lag, which a slide's fused centre
//! (both directions) does not have: its std over the 12 slides is 0.02–0.05 mm. No flat slide gives a dip; the
//! wavy pattern and the bump (when deep enough) do — telling them from cracks is the classifier's job. The width
//! calibration is fitted on the same plates (repetition 1), so the width MAE is between sessions, not plates.
//!
//! Simulated slides (`crackbot_sim::experiment::simulate_recording`, the width experiment's 1–10 mm plates, 3
//! recordings × 3 slides each, 90 passes; truth: the crack spans `offset + start … + width` of the position
//! column), MAE in mm on the test set (seed 2), with the default (real-data) settings and with look-ahead, lag and
//! width offset fitted on a calibration set (seed 1: look-ahead 2.525 mm, lag −0.022 mm, offset −1.045 mm):
//!
//! | settings | passes with a dip | start | end | centre | width |
//! |---|---|---|---|---|---|
//! | default | 90/90 | 0.81 | 2.27 | 1.54 | 1.46 |
//! | sim-fitted | 90/90 | 0.09 | 1.10 | 0.51 | 1.18 |
//!
//! The simulated dip does not look like the real one: in the simulator the tip drops into wide cracks and P rises
//! there, so the dip covers only the near part of an 8 or 10 mm crack (sim-fitted centre MAE 0.01 mm at 5 mm,
//! 0.60 at 8, 1.59 at 10), and the simulated lag is about 0 where the real one is 0.42 mm. These figures are of the
//! simulator as of this commit (its dynamics were being changed at the time).

use std::ops::Range;

use serde::{Deserialize, Serialize};

use crate::TactileError;

/// Index of P in a `[D1, D2, D3, P]` sample.
const P: usize = 3;

/// Settings of the localiser. [`Default`] is what the module docs measured.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LocaliseConfig {
    /// Width of the centred moving average applied to P before the threshold, samples (odd or even; 1 = none).
    pub smooth_samples: usize,
    /// Quantile of the smoothed P taken as the pass's flat level (a crack only lowers P, and may cover more than
    /// half of a pass).
    pub baseline_quantile: f64,
    /// Smallest dip (baseline − floor of the smoothed P) reported as a feature, counts.
    pub min_depth_counts: f64,
    /// Smallest dip reported, in units of the P noise (estimated from the pass's sample-to-sample differences).
    pub min_snr: f64,
    /// Fraction of the dip's depth below the baseline at which its edges are read (0.5: half depth).
    pub level_fraction: f64,
    /// Where the proximity fibre looks, ahead of the position stream's point along +x, mm: added to every position.
    pub look_ahead_mm: f64,
    /// Direction-dependent lag of the dip behind the position stream, mm: subtracted along the motion (a pass
    /// moving towards +x sees the dip `direction_lag_mm` too far in +x, a pass moving back as far in −x).
    pub direction_lag_mm: f64,
    /// The crack's width is `(dip extent − width_offset_mm) / width_scale`: the fibre's spot widens a narrow dip,
    /// a wide crack's walls narrow it. Offset in mm.
    pub width_offset_mm: f64,
    /// Scale of the width calibration (dip extent per mm of crack), positive.
    pub width_scale: f64,
    /// A pass must travel at least this far, mm; shorter ones (turning points, a trailing sample) are skipped by
    /// [`localise`] and refused by [`localise_pass`].
    pub min_travel_mm: f64,
    /// A reversal of the position stream by more than this, mm, ends a pass ([`split_passes`]).
    pub turn_hysteresis_mm: f64,
}

impl Default for LocaliseConfig {
    fn default() -> Self {
        LocaliseConfig {
            smooth_samples: 9,
            baseline_quantile: 0.75,
            min_depth_counts: 100.0,
            min_snr: 10.0,
            level_fraction: 0.5,
            look_ahead_mm: DEFAULT_LOOK_AHEAD_MM,
            direction_lag_mm: DEFAULT_DIRECTION_LAG_MM,
            width_offset_mm: DEFAULT_WIDTH_OFFSET_MM,
            width_scale: DEFAULT_WIDTH_SCALE,
            min_travel_mm: 2.0,
            turn_hysteresis_mm: 0.5,
        }
    }
}

/// The proximity fibre's look-ahead along +x, mm: the value `crackbot sim calibrate` fitted on the authors'
/// recordings (`crackbot_sim::OpticsParams::default().proximity_offset_mm`). The real plates' crack positions are
/// not published, so the real data cannot check it.
pub const DEFAULT_LOOK_AHEAD_MM: f64 = 1.352;
/// The direction-dependent lag, mm, estimated on repetition 1 of the authors' recordings (module docs).
pub const DEFAULT_DIRECTION_LAG_MM: f64 = 0.418;
/// Offset of the width calibration, mm: least squares of the dip's extent on the crack's width over the
/// authors' width plates of 1–10 mm, repetition 1 (per-plate medians; module docs).
pub const DEFAULT_WIDTH_OFFSET_MM: f64 = 0.794;
/// Scale of the width calibration, fitted with [`DEFAULT_WIDTH_OFFSET_MM`].
pub const DEFAULT_WIDTH_SCALE: f64 = 0.7391;

impl LocaliseConfig {
    /// The raw reading: no look-ahead, lag or width correction (what the corrections are estimated from).
    pub fn uncorrected() -> Self {
        LocaliseConfig {
            look_ahead_mm: 0.0,
            direction_lag_mm: 0.0,
            width_offset_mm: 0.0,
            width_scale: 1.0,
            ..LocaliseConfig::default()
        }
    }

    /// Checks every setting.
    pub fn validate(&self) -> Result<(), TactileError> {
        let bad = |reason: String| Err(TactileError::Localisation { reason });
        if self.smooth_samples == 0 {
            return bad("smooth_samples must be at least 1".into());
        }
        if !(self.baseline_quantile > 0.0 && self.baseline_quantile <= 1.0) {
            return bad(format!(
                "baseline_quantile must be in (0, 1], got {}",
                self.baseline_quantile
            ));
        }
        if !(self.level_fraction > 0.0 && self.level_fraction < 1.0) {
            return bad(format!(
                "level_fraction must be in (0, 1), got {}",
                self.level_fraction
            ));
        }
        for (name, v) in [
            ("min_depth_counts", self.min_depth_counts),
            ("min_snr", self.min_snr),
            ("min_travel_mm", self.min_travel_mm),
            ("turn_hysteresis_mm", self.turn_hysteresis_mm),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(format!("{name} must be finite and non-negative, got {v}"));
            }
        }
        for (name, v) in [
            ("look_ahead_mm", self.look_ahead_mm),
            ("direction_lag_mm", self.direction_lag_mm),
            ("width_offset_mm", self.width_offset_mm),
        ] {
            if !v.is_finite() {
                return bad(format!("{name} must be finite, got {v}"));
            }
        }
        if !(self.width_scale.is_finite() && self.width_scale > 0.0) {
            return bad(format!(
                "width_scale must be finite and positive, got {}",
                self.width_scale
            ));
        }
        Ok(())
    }
}

/// Which way the position stream moved during the samples an extent was read from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Travel {
    /// Towards +x (the authors' direction 0).
    Increasing,
    /// Towards −x (the authors' direction 1).
    Decreasing,
    /// Passes both ways, fused ([`localise`]).
    Both,
}

/// Where a crack lies along the slide.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CrackExtent {
    /// Near end of the crack on the surface axis (the smaller x), mm: `centre_mm − width_mm / 2`.
    pub start_mm: f64,
    /// Far end (the larger x), mm: `centre_mm + width_mm / 2`.
    pub end_mm: f64,
    /// Middle of the dip, corrected for look-ahead and lag, mm.
    pub centre_mm: f64,
    /// The crack's width, from the dip's extent through the width calibration, mm (at least 0).
    pub width_mm: f64,
    /// The dip's near edge (smaller x) at the edge level, corrected for look-ahead and lag, mm.
    pub dip_start_mm: f64,
    /// The dip's far edge, mm; `dip_end_mm ≥ dip_start_mm`.
    pub dip_end_mm: f64,
    /// 0–1: how clear the dip is — `fill × (1 − min_depth / depth)`, halved when the dip runs off an end of the
    /// pass (see the fields below).
    pub confidence: f64,
    /// Flat level of P, counts.
    pub baseline_counts: f64,
    /// Baseline minus the smoothed P's minimum, counts.
    pub depth_counts: f64,
    /// Depth over the P noise.
    pub snr: f64,
    /// Fraction of the samples between the two edges whose smoothed P is below the edge level (1: one clean dip;
    /// less for a wide crack whose middle comes back up, or for several dips spanned).
    pub fill: f64,
    /// Whether the dip runs off the start or end of the samples (the extent is then cut there).
    pub truncated: bool,
    /// Which way the samples moved.
    pub travel: Travel,
    /// Passes fused (1 for [`localise_pass`]).
    pub passes: u32,
}

/// The centred moving average of `values` over `width` samples (`width` 0 or 1: the values
/// themselves), the window shortened at the ends: how the localiser smooths P before its
/// threshold ([`LocaliseConfig::smooth_samples`]).
pub fn centred_moving_average(values: impl IntoIterator<Item = f64>, width: usize) -> Vec<f64> {
    let mut prefix = vec![0.0];
    let mut acc = 0.0;
    for v in values {
        acc += v;
        prefix.push(acc);
    }
    let n = prefix.len() - 1;
    let width = width.max(1);
    let half = width / 2;
    let back = width - 1 - half;
    (0..n)
        .map(|i| {
            let a = i.saturating_sub(back);
            let b = (i + half + 1).min(n);
            (prefix[b] - prefix[a]) / (b - a) as f64
        })
        .collect()
}

fn invalid(reason: String) -> TactileError {
    TactileError::Localisation { reason }
}

/// Checks lengths and finiteness of one slide's samples and positions.
fn check_inputs(samples: &[[f64; 4]], positions: &[f64]) -> Result<(), TactileError> {
    if samples.is_empty() {
        return Err(invalid("no samples".into()));
    }
    if samples.len() != positions.len() {
        return Err(invalid(format!(
            "{} samples but {} positions",
            samples.len(),
            positions.len()
        )));
    }
    if let Some(i) = samples.iter().position(|s| !s[P].is_finite()) {
        return Err(invalid(format!("P of sample {i} is not finite")));
    }
    if let Some(i) = positions.iter().position(|x| !x.is_finite()) {
        return Err(invalid(format!("position {i} is not finite")));
    }
    Ok(())
}

/// Cuts a slide at the turning points of its position stream: each range is one pass in one direction. A turn is
/// where the position comes back more than `hysteresis_mm` from its running extreme; the cut is at that extreme.
/// The ranges cover every sample, in order.
pub fn split_passes(
    positions: &[f64],
    hysteresis_mm: f64,
) -> Result<Vec<Range<usize>>, TactileError> {
    if !(hysteresis_mm.is_finite() && hysteresis_mm >= 0.0) {
        return Err(invalid(format!(
            "hysteresis must be finite and non-negative, got {hysteresis_mm}"
        )));
    }
    if let Some(i) = positions.iter().position(|x| !x.is_finite()) {
        return Err(invalid(format!("position {i} is not finite")));
    }
    let mut out = Vec::new();
    if positions.is_empty() {
        return Ok(out);
    }
    let mut start = 0;
    // 0: direction not known yet, +1 / −1: moving that way.
    let mut dir = 0i8;
    // Before the direction is known: the pass's highest and lowest samples; after: `ext` is its running extreme.
    let (mut hi, mut lo, mut ext) = (0usize, 0usize, 0usize);
    for (i, &x) in positions.iter().enumerate() {
        match dir {
            0 => {
                if x > positions[hi] {
                    hi = i;
                }
                if x < positions[lo] {
                    lo = i;
                }
                if positions[hi] - positions[lo] > hysteresis_mm {
                    (dir, ext) = if hi > lo { (1, hi) } else { (-1, lo) };
                }
            }
            _ => {
                let d = f64::from(dir);
                if d * (x - positions[ext]) > 0.0 {
                    ext = i;
                } else if d * (positions[ext] - x) > hysteresis_mm {
                    out.push(start..ext + 1);
                    start = ext + 1;
                    dir = -dir;
                    // Every sample since the old extreme is within the hysteresis of it, so `x` is the new one.
                    ext = i;
                }
            }
        }
    }
    if start < positions.len() {
        out.push(start..positions.len());
    }
    Ok(out)
}

/// The crack's extent from one pass in one direction (positions moving one way overall), or `None` when the pass
/// shows no dip of P deep enough ([`LocaliseConfig::min_depth_counts`], [`LocaliseConfig::min_snr`]).
///
/// `samples` are `[D1, D2, D3, P]` (only P is used: the deformation channels did not sharpen the edges), one per
/// position; `positions` are the position stream's mm, interpolated to the samples or held between updates.
/// Errors: invalid settings, no samples, lengths that differ, a non-finite P or position, a pass travelling less
/// than [`LocaliseConfig::min_travel_mm`].
pub fn localise_pass(
    samples: &[[f64; 4]],
    positions: &[f64],
    config: &LocaliseConfig,
) -> Result<Option<CrackExtent>, TactileError> {
    config.validate()?;
    check_inputs(samples, positions)?;
    localise_checked(samples, positions, config)
}

/// The noise of P from the sample-to-sample differences (robust: median absolute
/// difference), at least a quantisation step's worth, counts.
fn p_noise(samples: &[[f64; 4]]) -> f64 {
    let mut diffs: Vec<f64> = samples
        .windows(2)
        .map(|w| (w[1][P] - w[0][P]).abs())
        .collect();
    if diffs.is_empty() {
        0.5
    } else {
        let mid = diffs.len() / 2;
        let (_, m, _) = diffs.select_nth_unstable_by(mid, f64::total_cmp);
        (*m / (0.6745 * std::f64::consts::SQRT_2)).max(0.5)
    }
}

/// Where the smoothed P crosses `level` at the dip's first and last samples below it
/// (`[first, last]`), interpolated between `positions`, mm; and whether either edge is the
/// pass's own end (the dip runs off it).
fn dip_edges(
    smooth: &[f64],
    positions: &[f64],
    level: f64,
    [first, last]: [usize; 2],
) -> ([f64; 2], bool) {
    let n = smooth.len();
    let at = |i: usize, f: f64| positions[i] + f * (positions[i + 1] - positions[i]);
    let mut truncated = false;
    let edge_a = if first == 0 {
        truncated = true;
        positions[0]
    } else {
        let (u, v) = (smooth[first - 1], smooth[first]);
        at(first - 1, (u - level) / (u - v))
    };
    let edge_b = if last == n - 1 {
        truncated = true;
        positions[n - 1]
    } else {
        let (u, v) = (smooth[last], smooth[last + 1]);
        at(last, (level - u) / (v - u))
    };
    ([edge_a, edge_b], truncated)
}

fn localise_checked(
    samples: &[[f64; 4]],
    positions: &[f64],
    config: &LocaliseConfig,
) -> Result<Option<CrackExtent>, TactileError> {
    let n = samples.len();
    let travel = positions[n - 1] - positions[0];
    if travel.abs() < config.min_travel_mm.max(f64::MIN_POSITIVE) {
        return Err(invalid(format!(
            "the positions travel {:.3} mm, less than the {} mm of a pass",
            travel.abs(),
            config.min_travel_mm
        )));
    }
    let sign = travel.signum();

    // Smoothed P: centred moving average, windows shrinking at the ends.
    let smooth = centred_moving_average(samples.iter().map(|s| s[P]), config.smooth_samples);

    let noise = p_noise(samples);

    let mut sorted = smooth.clone();
    sorted.sort_unstable_by(f64::total_cmp);
    let q = ((n - 1) as f64 * config.baseline_quantile).round() as usize;
    let baseline = sorted[q.min(n - 1)];
    let floor = sorted[0];
    let depth = baseline - floor;
    let snr = depth / noise;
    if depth < config.min_depth_counts || snr < config.min_snr || depth <= 0.0 {
        return Ok(None);
    }
    let level = baseline - config.level_fraction * depth;

    let below = |i: usize| smooth[i] < level;
    let (Some(first), Some(last)) = ((0..n).find(|&i| below(i)), (0..n).rev().find(|&i| below(i)))
    else {
        return Ok(None);
    };
    let ([edge_a, edge_b], truncated) = dip_edges(&smooth, positions, level, [first, last]);
    let inside = last + 1 - first;
    let fill = (first..=last).filter(|&i| below(i)).count() as f64 / inside as f64;

    let shift = config.look_ahead_mm - sign * config.direction_lag_mm;
    let (lo, hi) = if edge_a <= edge_b {
        (edge_a, edge_b)
    } else {
        (edge_b, edge_a)
    };
    let (dip_start_mm, dip_end_mm) = (lo + shift, hi + shift);
    let centre_mm = 0.5 * (dip_start_mm + dip_end_mm);
    let width_mm =
        ((dip_end_mm - dip_start_mm - config.width_offset_mm) / config.width_scale).max(0.0);
    let mut confidence = fill * (1.0 - config.min_depth_counts / depth).clamp(0.0, 1.0);
    if truncated {
        confidence *= 0.5;
    }
    Ok(Some(CrackExtent {
        start_mm: centre_mm - 0.5 * width_mm,
        end_mm: centre_mm + 0.5 * width_mm,
        centre_mm,
        width_mm,
        dip_start_mm,
        dip_end_mm,
        confidence,
        baseline_counts: baseline,
        depth_counts: depth,
        snr,
        fill,
        truncated,
        travel: if sign > 0.0 {
            Travel::Increasing
        } else {
            Travel::Decreasing
        },
        passes: 1,
    }))
}

/// One pass of a slide and what [`localise_pass`] read from it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PassExtent {
    /// The pass's samples in the slide.
    pub range: Range<usize>,
    /// Its extent, `None` when it shows no dip.
    pub extent: Option<CrackExtent>,
}

/// Every pass of a slide ([`split_passes`]; passes shorter than [`LocaliseConfig::min_travel_mm`] skipped), each
/// localised by [`localise_pass`].
pub fn localise_passes(
    samples: &[[f64; 4]],
    positions: &[f64],
    config: &LocaliseConfig,
) -> Result<Vec<PassExtent>, TactileError> {
    config.validate()?;
    check_inputs(samples, positions)?;
    let mut out = Vec::new();
    for range in split_passes(positions, config.turn_hysteresis_mm)? {
        let pos = &positions[range.clone()];
        let travel = match (pos.first(), pos.last()) {
            (Some(a), Some(b)) => (b - a).abs(),
            _ => 0.0,
        };
        if travel < config.min_travel_mm.max(f64::MIN_POSITIVE) {
            continue;
        }
        let extent = localise_checked(&samples[range.clone()], pos, config)?;
        out.push(PassExtent { range, extent });
    }
    Ok(out)
}

/// The crack's extent along one slide — one pass or several (the authors' slides go there and back) — or `None`
/// when no pass shows a dip. Passes are cut at the position stream's turning points and localised one by one
/// ([`localise_passes`]); the extents found are averaged, weighted by confidence (equally if all are 0), and the
/// fused confidence is their mean confidence times the fraction of passes that found a dip.
///
/// Errors as [`localise_pass`], and when no pass travels [`LocaliseConfig::min_travel_mm`].
pub fn localise(
    samples: &[[f64; 4]],
    positions: &[f64],
    config: &LocaliseConfig,
) -> Result<Option<CrackExtent>, TactileError> {
    let passes = localise_passes(samples, positions, config)?;
    if passes.is_empty() {
        return Err(invalid(format!(
            "no pass of the slide travels {} mm",
            config.min_travel_mm
        )));
    }
    let found: Vec<&CrackExtent> = passes.iter().filter_map(|p| p.extent.as_ref()).collect();
    Ok(fuse(&found, passes.len()))
}

/// Confidence-weighted mean of `found`, out of `total` passes.
fn fuse(found: &[&CrackExtent], total: usize) -> Option<CrackExtent> {
    let first = found.first()?;
    if found.len() == 1 {
        let mut one = **first;
        one.confidence *= 1.0 / total as f64;
        return Some(one);
    }
    let wsum: f64 = found.iter().map(|e| e.confidence).sum();
    let weight = |e: &CrackExtent| {
        if wsum > 0.0 {
            e.confidence / wsum
        } else {
            1.0 / found.len() as f64
        }
    };
    let mean = |f: fn(&CrackExtent) -> f64| found.iter().map(|e| weight(e) * f(e)).sum::<f64>();
    let centre_mm = mean(|e| e.centre_mm);
    let width_mm = mean(|e| e.width_mm);
    let plain =
        |f: fn(&CrackExtent) -> f64| found.iter().map(|e| f(e)).sum::<f64>() / found.len() as f64;
    let travel = if found.iter().all(|e| e.travel == first.travel) {
        first.travel
    } else {
        Travel::Both
    };
    Some(CrackExtent {
        start_mm: centre_mm - 0.5 * width_mm,
        end_mm: centre_mm + 0.5 * width_mm,
        centre_mm,
        width_mm,
        dip_start_mm: mean(|e| e.dip_start_mm),
        dip_end_mm: mean(|e| e.dip_end_mm),
        confidence: plain(|e| e.confidence) * found.len() as f64 / total as f64,
        baseline_counts: plain(|e| e.baseline_counts),
        depth_counts: plain(|e| e.depth_counts),
        snr: plain(|e| e.snr),
        fill: plain(|e| e.fill),
        truncated: found.iter().any(|e| e.truncated),
        travel,
        passes: found.len() as u32,
    })
}
