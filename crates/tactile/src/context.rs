//! Context features: what a decision at one window may know beyond the window's own 25 ms.
//!
//! The paper classifies each 10-sample window on its own. Most windows of a slide over a crack
//! lie on the flat part of the surface and look exactly like the windows of a flat surface, so a
//! window-level classifier can only separate them through the absolute ADC levels, which drift
//! between recordings. [`ContextConfig`] adds, for each window, features of the signal **up to the
//! window's last sample** (causal: a streaming classifier could compute them as it goes):
//!
//! * **per-slide baseline**: every level is taken relative to the median of the slide's first
//!   `baseline_len` samples (the slide's own resting level), which removes the offsets that the
//!   fibres' position and twist put on each recording without the recording-wide median (which
//!   depends on how much of the recording the feature occupies);
//! * **multi-scale windows**: for each length `L` of `scales`, over the last `L` samples (fewer at
//!   the start of a slide): mean, standard deviation, minimum, maximum (all but the standard
//!   deviation relative to the baseline) and the slope (last sample − first sample of the span);
//! * **slide so far** (`prefix`): minimum, maximum and range of the slide from its first sample;
//! * **direction** (`direction`): the sliding direction of the window's last sample (column 6),
//!   which the robot knows.
//!
//! Not used, on purpose: the x position (column 1) and the time since the slide started. The
//! surfaces were printed with their feature at one place and the device slides over the same
//! range every time, so either would let a classifier learn *where* each surface's feature lies
//! in the authors' set-up rather than what it looks like; neither carries over to a new surface.
//!
//! Measured on the authors' repetitions 1–3 only (never tested on a repetition it trained on; 100
//! trees, seed 1; [`ContextConfig::default`]: spans of 200, 1200 and 2000 samples reaching back
//! across slides; `crackbot tactile eval --context`):
//!
//! | protocol | recognition: windows | recognition: slides | width: windows | width: slides |
//! |---|---|---|---|---|
//! | paper's features, train 1 repetition, test another (6 pairs) | 85.6 % | 100 % | 55.4 % | 99.5 % |
//! | context, 6 pairs, context forest alone | 95.5 % | 97.6 % | 77.1 % | 82.6 % |
//! | context, 6 pairs, slide vote with the paper forest | 95.5 % | **100 %** | 77.1 % | 92.6 % |
//! | context, leave one repetition out (3 folds), slide vote with the paper forest | 96.8 % | **100 %** | **91.5 %** | **100 %** |
//!
//! Per pair: `cargo run --release -p crackbot-research --example context_protocols -- DIR`. One caveat:
//! for width trained on a single repetition, the paper forest's slide means alone (99.5 %) still
//! beat the joint vote (92.6 %); with two training repetitions every vote is right.
//!
//! With context, the windows of a slide share the same few crossings, so their errors are
//! correlated and the slide mean of the context forest alone is *less* accurate than the paper
//! forest's. The paper's windows are wrong more often but independently. The slide verdict of
//! `crackbot tactile eval --context` therefore sums both forests' slide means
//! ([`crate::eval::test_classifier_with_slide_voters`]). Spans confined to the slide
//! (`across_slides: false`) were worse than the paper's features at the window level (the start of
//! a slide has not met the crack yet).

use serde::{Deserialize, Serialize};

use crate::TactileError;

/// Which context features are appended to (or replace) the window's own features.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ContextConfig {
    /// Causal context lengths in samples (each ≥ 1); default `[200, 1200, 2000]` (0.5 s, 3 s, 5 s).
    pub scales: Vec<usize>,
    /// Samples at the start of each slide whose per-channel median is the slide's baseline
    /// (≥ 1; clamped to the slide length).
    pub baseline_len: usize,
    /// Adds minimum, maximum and range of the slide so far.
    pub prefix: bool,
    /// Adds the sliding direction.
    pub direction: bool,
    /// Keeps the window's own features (absolute ADC counts) in front of the context features.
    pub keep_window: bool,
    /// Lets the spans reach back into the previous slides of the same recording (the finger's
    /// memory of the last seconds of a continuous exploration); otherwise they stop at the slide's
    /// first sample.
    pub across_slides: bool,
    /// Adds, per channel and scale, the longest runs (in samples) below / above half the span's
    /// departure from the baseline (how long one crossing of a dip or bump lasts, wherever it
    /// lies) and the span's absolute minimum and maximum (ADC counts: the depth a crack lets the
    /// proximity reach, which the baseline-relative values lose).
    pub shape: bool,
}

/// The best configuration measured on repetitions 1–3 (see the module docs).
impl Default for ContextConfig {
    fn default() -> Self {
        ContextConfig {
            scales: vec![200, 1200, 2000],
            baseline_len: 40,
            prefix: true,
            direction: true,
            keep_window: false,
            across_slides: true,
            shape: false,
        }
    }
}

/// Values per channel and scale.
const PER_SCALE: usize = 7;
/// Extra values per channel and scale with [`ContextConfig::shape`].
const PER_SHAPE: usize = 4;
/// Values per channel of the slide-so-far block.
const PER_PREFIX: usize = 3;

/// Smallest sample value the context features see: samples are rounded to whole ADC counts and
/// clamped to `[SAMPLE_MIN, SAMPLE_MAX]` (a 12-bit converter's range with room for offset-corrected
/// values), so every statistic is an exact integer and the streaming form equals this one bit for bit.
pub const SAMPLE_MIN: i32 = -4096;
/// Largest sample value the context features see (see [`SAMPLE_MIN`]).
pub const SAMPLE_MAX: i32 = 8191;
/// Longest context span (and baseline) in samples.
pub const MAX_SCALE: usize = 60_000;

impl ContextConfig {
    /// Checks that every scale and the baseline length are between 1 and [`MAX_SCALE`].
    pub fn validate(&self) -> Result<(), TactileError> {
        if self.scales.contains(&0) {
            return Err(TactileError::Context {
                reason: "context scales must be at least 1 sample",
            });
        }
        if self.scales.iter().any(|&s| s > MAX_SCALE) {
            return Err(TactileError::Context {
                reason: "context scales must be at most 60000 samples (150 s at 400 Hz)",
            });
        }
        if self.baseline_len == 0 {
            return Err(TactileError::Context {
                reason: "the baseline length must be at least 1 sample",
            });
        }
        if self.baseline_len > MAX_SCALE {
            return Err(TactileError::Context {
                reason: "the baseline length must be at most 60000 samples",
            });
        }
        Ok(())
    }

    /// Number of context values (not counting the window's own features) for `n_channels`
    /// channels: one "current level" per channel, [`PER_SCALE`] per channel and scale,
    /// [`PER_PREFIX`] per channel for the prefix, 1 for the direction.
    pub fn n_context(&self, n_channels: usize) -> usize {
        let per_scale = PER_SCALE + if self.shape { PER_SHAPE } else { 0 };
        n_channels * (1 + per_scale * self.scales.len())
            + if self.prefix {
                PER_PREFIX * n_channels
            } else {
                0
            }
            + usize::from(self.direction)
    }

    /// Number of values of a whole row, given the window's own features and channels.
    pub fn n_features(&self, window_features: usize, n_channels: usize) -> usize {
        self.n_context(n_channels) + if self.keep_window { window_features } else { 0 }
    }
}

/// A sample value as the context features see it: rounded to whole counts, clamped to
/// [`SAMPLE_MIN`]`..=`[`SAMPLE_MAX`]. Callers reject non-finite samples first (NaN maps to 0).
#[inline]
pub fn quantise(x: f64) -> i32 {
    if x.is_nan() {
        return 0;
    }
    x.round()
        .clamp(f64::from(SAMPLE_MIN), f64::from(SAMPLE_MAX)) as i32
}

/// Twice the median of `sorted` (ascending): the median in half counts, exact for an even count.
pub(crate) fn twice_median(sorted: &[i32]) -> i64 {
    let n = sorted.len();
    match n {
        0 => 0,
        _ if n % 2 == 1 => 2 * i64::from(sorted[n / 2]),
        _ => i64::from(sorted[n / 2 - 1]) + i64::from(sorted[n / 2]),
    }
}

/// Median of the first `len` values of each channel, in counts (quantised, see [`quantise`]):
/// the baseline of a window whose slide has seen these samples so far.
pub fn slide_baseline(samples: &[[f64; 4]], len: usize) -> [f64; 4] {
    let n = len.min(samples.len());
    let mut out = [0.0; 4];
    let mut v = Vec::with_capacity(n);
    for (c, slot) in out.iter_mut().enumerate() {
        v.clear();
        v.extend(samples[..n].iter().map(|s| quantise(s[c])));
        v.sort_unstable();
        *slot = twice_median(&v) as f64 / 2.0;
    }
    out
}

/// Largest value counted "below" a span (`x < (b + lo) / 2`, `b2 = 2b`, `lo2 = 2·lo`).
#[inline]
pub(crate) fn below_limit(b2: i64, lo2: i64) -> i64 {
    (b2 + lo2 - 1).div_euclid(4)
}

/// Smallest value counted "above" a span (`x > (b + hi) / 2`).
#[inline]
pub(crate) fn above_limit(b2: i64, hi2: i64) -> i64 {
    (b2 + hi2).div_euclid(4) + 1
}

/// Exact integer statistics of one span of one channel: what both the offline and the streaming
/// computation produce, and [`SpanStats::push_values`] turns into features.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct SpanStats {
    pub n: i64,
    pub sum: i64,
    pub sum_sq: i64,
    pub min: i32,
    pub max: i32,
    pub first: i32,
    pub last: i32,
    /// Samples with `x ≤ below_limit(b2, lo2)`.
    pub below: i64,
    /// Samples with `x ≥ above_limit(b2, hi2)`.
    pub above: i64,
}

impl SpanStats {
    /// `(lo2, hi2)`: twice the span's minimum and maximum, the baseline included.
    #[inline]
    pub fn extremes2(&self, b2: i64) -> (i64, i64) {
        (
            b2.min(2 * i64::from(self.min)),
            b2.max(2 * i64::from(self.max)),
        )
    }

    /// The seven values of a span: mean, standard deviation, minimum, maximum (relative to the
    /// baseline `b2 / 2`), slope, fraction below and fraction above.
    #[inline]
    pub fn values(&self, b2: i64) -> [f32; PER_SCALE] {
        let n = self.n.max(1);
        let nf = n as f64;
        let b = b2 as f64 / 2.0;
        let (lo2, hi2) = self.extremes2(b2);
        // Exact in i64: |x| ≤ 8192 and n ≤ MAX_SCALE (60 000) bound n·Σx² and (Σx)² by 2.5e17.
        let num = n * self.sum_sq - self.sum * self.sum;
        let var = num.max(0) as f64 / (nf * nf);
        [
            (self.sum as f64 / nf - b) as f32,
            var.sqrt() as f32,
            ((lo2 - b2) as f64 / 2.0) as f32,
            ((hi2 - b2) as f64 / 2.0) as f32,
            (i64::from(self.last) - i64::from(self.first)) as f32,
            (self.below as f64 / nf) as f32,
            (self.above as f64 / nf) as f32,
        ]
    }
}

/// The slide-so-far values: minimum, maximum (relative to the baseline) and range.
#[inline]
pub(crate) fn prefix_values(min: i32, max: i32, b2: i64) -> [f32; PER_PREFIX] {
    let lo2 = b2.min(2 * i64::from(min));
    let hi2 = b2.max(2 * i64::from(max));
    [
        ((lo2 - b2) as f64 / 2.0) as f32,
        ((hi2 - b2) as f64 / 2.0) as f32,
        ((hi2 - lo2) as f64 / 2.0) as f32,
    ]
}

/// The "current level": the window's mean relative to the baseline.
#[inline]
pub(crate) fn level_value(sum: i64, n: i64, b2: i64) -> f32 {
    (sum as f64 / n.max(1) as f64 - b2 as f64 / 2.0) as f32
}

/// Length of the longest run of `true`.
fn longest_run(flags: impl Iterator<Item = bool>) -> usize {
    let (mut best, mut run) = (0, 0);
    for f in flags {
        run = if f { run + 1 } else { 0 };
        best = best.max(run);
    }
    best
}

/// Where a window is: the recording's samples, its slide's first sample, its last sample.
#[derive(Debug, Clone, Copy)]
pub struct WindowPlace<'a> {
    /// Every sample of the recording (`[D1, D2, D3, P]`, after any normalisation; finite).
    pub samples: &'a [[f64; 4]],
    /// Column 6 of every sample.
    pub directions: &'a [u8],
    /// Index of the first sample of the window's slide.
    pub slide_start: usize,
    /// Index of the window's last sample (≥ `slide_start`).
    pub end: usize,
}

/// Exact statistics of channel `c` over `span`, "below" and "above" counted against the
/// baseline `b2` (half counts).
fn span_stats(span: &[[f64; 4]], c: usize, b2: i64) -> SpanStats {
    let mut s = SpanStats {
        min: i32::MAX,
        max: i32::MIN,
        ..SpanStats::default()
    };
    for x in span {
        let q = quantise(x[c]);
        s.n += 1;
        s.sum += i64::from(q);
        s.sum_sq += i64::from(q) * i64::from(q);
        s.min = s.min.min(q);
        s.max = s.max.max(q);
    }
    if let (Some(a), Some(z)) = (span.first(), span.last()) {
        s.first = quantise(a[c]);
        s.last = quantise(z[c]);
    }
    let (lo2, hi2) = s.extremes2(b2);
    let (below, above) = (below_limit(b2, lo2), above_limit(b2, hi2));
    for x in span {
        let q = i64::from(quantise(x[c]));
        s.below += i64::from(q <= below);
        s.above += i64::from(q >= above);
    }
    s
}

/// The context values of the window at `place`, appended to `out` (the offline computation; the
/// streaming one is [`crate::stream::StreamingContext`], equal bit for bit).
///
/// `channels` are the indices of the channels to describe, `window_len` the length of the window
/// itself (its mean relative to the baseline is the "current level"). The baseline is the median
/// of the slide's first [`ContextConfig::baseline_len`] samples **up to the window's end**
/// (causal: a window before the baseline is complete sees the samples so far). Spans end at
/// `place.end` and start no earlier than the slide's first sample, or than the recording's first
/// sample with [`ContextConfig::across_slides`]. Samples are seen as whole counts ([`quantise`]).
/// Appends exactly [`ContextConfig::n_context`]`(channels.len())` values.
pub fn context_row(
    config: &ContextConfig,
    place: WindowPlace<'_>,
    channels: &[usize],
    window_len: usize,
    out: &mut Vec<f32>,
) {
    let samples = place.samples;
    let end = place.end.min(samples.len().saturating_sub(1));
    let slide_start = place.slide_start.min(end);
    let floor = if config.across_slides { 0 } else { slide_start };
    let span = |len: usize| -> &[[f64; 4]] {
        let start = (end + 1).saturating_sub(len.max(1)).max(floor);
        samples.get(start..=end).unwrap_or(&[])
    };
    let base_end = (slide_start + config.baseline_len).min(end + 1);
    let slide_head = samples.get(slide_start..base_end).unwrap_or(&[]);
    let mut sorted = Vec::with_capacity(slide_head.len());
    for &c in channels {
        sorted.clear();
        sorted.extend(slide_head.iter().map(|s| quantise(s[c])));
        sorted.sort_unstable();
        let b2 = twice_median(&sorted);
        let w = span_stats(span(window_len), c, b2);
        out.push(level_value(w.sum, w.n, b2));
        for &len in &config.scales {
            let s = span(len);
            let stats = span_stats(s, c, b2);
            if config.shape {
                let (lo2, hi2) = stats.extremes2(b2);
                let (below, above) = (below_limit(b2, lo2), above_limit(b2, hi2));
                out.extend_from_slice(&[
                    longest_run(s.iter().map(|x| i64::from(quantise(x[c])) <= below)) as f32,
                    longest_run(s.iter().map(|x| i64::from(quantise(x[c])) >= above)) as f32,
                    (lo2 as f64 / 2.0) as f32,
                    (hi2 as f64 / 2.0) as f32,
                ]);
            }
            out.extend_from_slice(&stats.values(b2));
        }
        if config.prefix {
            let s = span_stats(samples.get(slide_start..=end).unwrap_or(&[]), c, b2);
            out.extend_from_slice(&prefix_values(s.min, s.max, b2));
        }
    }
    if config.direction {
        out.push(f32::from(place.directions.get(end).copied().unwrap_or(0)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn baseline_is_the_median_of_the_first_samples() {
        let s: Vec<[f64; 4]> = (0..10).map(|i| [i as f64, 5.0, 0.0, 100.0]).collect();
        assert_eq!(slide_baseline(&s, 3), [1.0, 5.0, 0.0, 100.0]);
        assert_eq!(slide_baseline(&s, 4), [1.5, 5.0, 0.0, 100.0]);
        assert_eq!(slide_baseline(&s, 100), [4.5, 5.0, 0.0, 100.0]);
        assert_eq!(slide_baseline(&[], 5), [0.0; 4]);
    }

    #[test]
    fn context_values_are_causal_relative_and_counted() {
        // P steps from 500 to 300 at sample 50; D1 is a ramp.
        let s: Vec<[f64; 4]> = (0..100)
            .map(|i| [i as f64, 0.0, 0.0, if i < 50 { 500.0 } else { 300.0 }])
            .collect();
        let dir: Vec<u8> = (0..100).map(|i| u8::from(i >= 60)).collect();
        let config = ContextConfig {
            scales: vec![20],
            baseline_len: 10,
            prefix: true,
            direction: true,
            keep_window: false,
            across_slides: false,
            shape: false,
        };
        assert!(config.validate().is_ok());
        let b = slide_baseline(&s, config.baseline_len);
        assert_eq!(b[3], 500.0);
        let place = |end| WindowPlace {
            samples: &s,
            directions: &dir,
            slide_start: 0,
            end,
        };
        let mut row = Vec::new();
        context_row(&config, place(69), &[0, 3], 10, &mut row);
        assert_eq!(row.len(), config.n_context(2));
        assert_eq!(row.len(), 2 * (1 + 7 + 3) + 1);
        // D1 (baseline 4.5): level = mean(60..=69) − 4.5 = 60; over 50..=69: mean 59.5 − 4.5,
        // std, min 50 − 4.5, max 69 − 4.5, slope 19, nothing below the baseline, above the
        // midpoint 36.75 everything; prefix min 0 − 4.5, max 69 − 4.5, range 69.
        assert_eq!(
            &row[..11],
            &[60.0, 55.0, row[2], 0.0, 64.5, 19.0, 0.0, 1.0, -4.5, 64.5, 69.0]
        );
        assert!((row[2] - (133.0f32 / 4.0).sqrt()).abs() < 1e-4);
        // P: a step down of 200 from the baseline, seen in the 20-sample span and the prefix.
        assert_eq!(
            &row[11..22],
            &[-200.0, -200.0, 0.0, -200.0, 0.0, 0.0, 1.0, 0.0, -200.0, 0.0, 200.0]
        );
        assert_eq!(row[22], 1.0);
        // The future (the step) is not seen by a window that ends before it.
        let mut early = Vec::new();
        context_row(&config, place(49), &[3], 10, &mut early);
        assert_eq!(early, vec![0.0; 12]);
        // Half of a span that straddles the step lies below the midpoint (400).
        let mut straddle = Vec::new();
        context_row(&config, place(59), &[3], 10, &mut straddle);
        assert_eq!(straddle[6], 0.5);
        // Spans are clamped at the slide's start...
        let mut first = Vec::new();
        context_row(&config, place(0), &[0], 10, &mut first);
        assert_eq!(first.len(), config.n_context(1));
        assert_eq!(
            first[0], 0.0,
            "the baseline so far is the first sample itself"
        );
        // ...unless they may reach into earlier slides of the recording.
        let later = WindowPlace {
            slide_start: 55,
            ..place(59)
        };
        let mut within = Vec::new();
        context_row(&config, later, &[3], 10, &mut within);
        // The slide's baseline is its own first samples (300): flat within the slide...
        assert_eq!(
            within[1], 0.0,
            "the span stops at the slide's start, after the step"
        );
        let across = ContextConfig {
            across_slides: true,
            ..config.clone()
        };
        let mut reach = Vec::new();
        context_row(&across, later, &[3], 10, &mut reach);
        assert_eq!(
            reach[1], 100.0,
            "the span sees 10 samples of 500 before the step"
        );
    }

    #[test]
    fn shape_values_measure_runs_and_absolute_extremes() {
        assert_eq!(
            longest_run([true, true, false, true, true, true, false].into_iter()),
            3
        );
        assert_eq!(longest_run(std::iter::empty()), 0);
        // Two dips of P below the baseline 500: 5 samples to 300, then 8 samples to 200.
        let s: Vec<[f64; 4]> = (0..60)
            .map(|i| {
                let p = match i {
                    20..=24 => 300.0,
                    40..=47 => 200.0,
                    _ => 500.0,
                };
                [0.0, 0.0, 0.0, p]
            })
            .collect();
        let dir = vec![0u8; 60];
        let config = ContextConfig {
            scales: vec![60],
            baseline_len: 10,
            prefix: false,
            direction: false,
            keep_window: false,
            across_slides: false,
            shape: true,
        };
        let mut row = Vec::new();
        let place = WindowPlace {
            samples: &s,
            directions: &dir,
            slide_start: 0,
            end: 59,
        };
        context_row(&config, place, &[3], 10, &mut row);
        assert_eq!(row.len(), config.n_context(1));
        assert_eq!(row.len(), 1 + 7 + 4);
        // Midpoint below: (500 + 200) / 2 = 350, so both dips count; the longest lasts 8.
        assert_eq!(&row[1..5], &[8.0, 0.0, 200.0, 500.0]);
        assert_eq!(row[5 + 5], 13.0 / 60.0);
    }

    #[test]
    fn invalid_configs_are_refused_and_counts_follow_the_options() {
        let mut c = ContextConfig::default();
        assert_eq!(c.n_context(3), 3 * (1 + 21 + 3) + 1);
        assert_eq!(c.n_features(3, 3), c.n_context(3));
        c.keep_window = true;
        assert_eq!(c.n_features(3, 3), c.n_context(3) + 3);
        c.prefix = false;
        c.direction = false;
        assert_eq!(c.n_context(1), 22);
        c.shape = true;
        assert_eq!(c.n_context(1), 34);
        c.scales = vec![0];
        assert!(c.validate().is_err());
        c.scales = vec![5];
        c.baseline_len = 0;
        assert!(c.validate().is_err());
    }
}
