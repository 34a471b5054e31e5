//! Segmentation of one sliding movement: which samples show the explored mechanical feature.

use std::ops::Range;

use serde::{Deserialize, Serialize};

use crate::error::{check_signal, DspError};
use crate::median::median;
use crate::Channel;

/// The samples of one trial a segmentation kept.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Segment {
    /// Kept sample ranges (half-open indices into the trial), sorted, disjoint, non-adjacent, non-empty. The paper's
    /// span reading gives at most one.
    pub ranges: Vec<Range<usize>>,
    /// Number of samples of the trial.
    pub trial_len: usize,
}

impl Segment {
    /// Whether nothing was kept.
    pub fn is_empty(&self) -> bool {
        self.ranges.is_empty()
    }

    /// Number of kept samples.
    pub fn kept(&self) -> usize {
        self.ranges
            .iter()
            .map(|r| r.end.saturating_sub(r.start))
            .sum()
    }

    /// Fraction of the trial kept (0 for an empty trial).
    pub fn fraction_kept(&self) -> f64 {
        if self.trial_len == 0 {
            0.0
        } else {
            self.kept() as f64 / self.trial_len as f64
        }
    }

    /// From the first kept sample to the last (`0..0` when empty).
    pub fn span(&self) -> Range<usize> {
        match (self.ranges.first(), self.ranges.last()) {
            (Some(a), Some(b)) => a.start..b.end.max(a.start),
            _ => 0..0,
        }
    }

    /// Whether sample `i` was kept.
    pub fn contains(&self, i: usize) -> bool {
        self.ranges.iter().any(|r| r.contains(&i))
    }

    /// Builds a segment from ranges in increasing start order: widens each by `pad` on both sides, clamps to the
    /// trial, merges overlapping or touching ranges and drops empty ones.
    fn from_ranges(
        ranges: impl IntoIterator<Item = Range<usize>>,
        pad: usize,
        trial_len: usize,
    ) -> Segment {
        let mut out: Vec<Range<usize>> = Vec::new();
        for r in ranges {
            let start = r.start.saturating_sub(pad);
            let end = r.end.saturating_add(pad).min(trial_len);
            if start >= end {
                continue;
            }
            match out.last_mut() {
                Some(last) if start <= last.end => last.end = last.end.max(end),
                _ => out.push(start..end),
            }
        }
        Segment {
            ranges: out,
            trial_len,
        }
    }
}

/// What the paper's threshold test keeps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Extent {
    /// One range from the first to the last point passing the test (the faithful reading: "the data points … are
    /// extracted" and margins are added "before and after the extracted points", i.e. around one block).
    Span,
    /// Only the points passing the test, as runs; each run gets the margins, overlapping runs merge.
    Points,
}

/// What the paper's "additional 10 % of the original measurement data" is 10 % of.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum MarginBase {
    /// Of the trial's length `m` (faithful: "of the original measurement data").
    Trial,
    /// Of the extracted part: the span length ([`Extent::Span`]) or the number of kept points ([`Extent::Points`]).
    Extracted,
}

/// The paper's segmentation (Palermo et al. 2020, section 3.1, eq. 2), with its ambiguous choices as parameters.
///
/// For a trial's proximity `p[0..m)`: `Δp_i = (p[i+n] − p[i]) / n` for `i ∈ 0..m−n`, `Δp̄ = mean(Δp_i)`; point `i`
/// passes when `Δp_i > |Δp̄|` (or `|Δp_i| > |Δp̄|` with `magnitude`); a forward difference is attributed to its
/// first sample `i`. The kept part ([`Extent`]) is widened on **each** side by `round(margin_fraction × base)`
/// samples ([`MarginBase`]) and clamped to the trial. The default is the faithful reading: `n = 10`, signed test,
/// [`Extent::Span`], 10 % of the trial length on each side. No point passing gives an empty segment (no margins).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PaperSegmentation {
    /// Derivative lag `n` in samples (the paper: 10, i.e. 25 ms). At least 1.
    pub n: usize,
    /// `false`: `Δp_i > |Δp̄|` (as printed: rising proximity only); `true`: `|Δp_i| > |Δp̄|`.
    pub magnitude: bool,
    /// Span from first to last passing point, or the passing points themselves.
    pub extent: Extent,
    /// Margin added on each side, as a fraction of [`MarginBase`] (the paper: 0.1). Finite, ≥ 0.
    pub margin_fraction: f64,
    /// What the margin is a fraction of.
    pub margin_base: MarginBase,
}

impl Default for PaperSegmentation {
    fn default() -> Self {
        PaperSegmentation {
            n: 10,
            magnitude: false,
            extent: Extent::Span,
            margin_fraction: 0.1,
            margin_base: MarginBase::Trial,
        }
    }
}

impl PaperSegmentation {
    /// Checks `n ≥ 1` and a finite, non-negative `margin_fraction`.
    pub fn validate(&self) -> Result<(), DspError> {
        if self.n == 0 {
            return Err(DspError::config(
                "PaperSegmentation::n",
                "must be at least 1",
            ));
        }
        if !(self.margin_fraction.is_finite() && self.margin_fraction >= 0.0) {
            return Err(DspError::config(
                "PaperSegmentation::margin_fraction",
                format!(
                    "must be finite and non-negative, got {}",
                    self.margin_fraction
                ),
            ));
        }
        Ok(())
    }

    /// Segments one trial given its proximity `p` (ADC counts). Needs `m > n` samples (eq. 2 averages over `m − n`
    /// derivatives); values must be finite and within the `f32` range.
    pub fn segment(&self, p: &[f64]) -> Result<Segment, DspError> {
        self.validate()?;
        self.segment_checked(p)
    }

    /// [`segment`](Self::segment) with parameters already validated.
    fn segment_checked(&self, p: &[f64]) -> Result<Segment, DspError> {
        check_signal(p, Channel::P)?;
        let m = p.len();
        let n = self.n;
        if m <= n {
            return Err(DspError::TooShort { len: m, min: n + 1 });
        }
        let nf = n as f64;
        let deriv = |i: usize| (p[i + n] - p[i]) / nf;
        let count = m - n;
        let mut sum = 0.0;
        for i in 0..count {
            sum += deriv(i);
        }
        let threshold = (sum / count as f64).abs();
        let passes = |i: usize| {
            let d = deriv(i);
            (if self.magnitude { d.abs() } else { d }) > threshold
        };
        let margin = |base: usize| (self.margin_fraction * base as f64).round() as usize;
        match self.extent {
            Extent::Span => {
                let first = (0..count).find(|&i| passes(i));
                let last = (0..count).rev().find(|&i| passes(i));
                let (Some(first), Some(last)) = (first, last) else {
                    return Ok(Segment {
                        ranges: Vec::new(),
                        trial_len: m,
                    });
                };
                let pad = match self.margin_base {
                    MarginBase::Trial => margin(m),
                    MarginBase::Extracted => margin(last + 1 - first),
                };
                Ok(Segment::from_ranges(
                    std::iter::once(first..last + 1),
                    pad,
                    m,
                ))
            }
            Extent::Points => {
                let mut runs = Vec::new();
                let mut start = None;
                for i in 0..count {
                    match (passes(i), start) {
                        (true, None) => start = Some(i),
                        (false, Some(s)) => {
                            runs.push(s..i);
                            start = None;
                        }
                        _ => {}
                    }
                }
                if let Some(s) = start {
                    runs.push(s..count);
                }
                let pad = match self.margin_base {
                    MarginBase::Trial => margin(m),
                    MarginBase::Extracted => margin(runs.iter().map(|r| r.end - r.start).sum()),
                };
                Ok(Segment::from_ranges(runs, pad, m))
            }
        }
    }
}

/// The paper's segmentation in its faithful reading ([`PaperSegmentation::default`]) with derivative lag `n`:
/// one span from the first to the last point with `Δp_i > |Δp̄|`, widened by 10 % of the trial length on each side.
pub fn segment_paper(p: &[f64], n: usize) -> Result<Segment, DspError> {
    PaperSegmentation {
        n,
        ..PaperSegmentation::default()
    }
    .segment(p)
}

/// A robust segmentation: deviation of the smoothed proximity from the slide's flat-surface baseline, with
/// hysteresis.
///
/// 1. Smooth `p` with a centred moving average of `smooth` samples (shortened at the ends).
/// 2. Baseline `b` = median, spread `σ` = 1.4826 × median absolute deviation, both of the smoothed signal over the
///    first and last `edge_fraction` of the trial (at least `smooth` samples each), where the finger is on the flat
///    surface around the feature.
/// 3. A sample is *active* while `|s_i − b| > max(k_exit·σ, min_exit)`; an active run is kept when somewhere in it
///    `|s_i − b| > max(k_enter·σ, min_enter)` (hysteresis).
/// 4. Kept runs closer than `min_gap` samples merge; runs shorter than `min_span` are dropped; each is widened by
///    `pad` samples on each side and clamped.
///
/// A crack, a bump or the wavy pattern moves the proximity by 100–250 counts from the flat level, while the flat
/// 3D-printed surface wanders by about ±10 counts; the floors `min_enter`/`min_exit` (in ADC counts) stop a very
/// quiet baseline from turning that texture into detections. A slide over a flat surface mostly gives an empty segment,
/// and a slide that crosses the feature twice (out and back) gives two ranges. It uses future samples (centred
/// smoothing, whole-slide baseline): it is an offline pre-processing step, like the paper's.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RobustSegmentation {
    /// Moving-average length in samples (default 20 = 50 ms). At least 1.
    pub smooth: usize,
    /// Fraction of the trial at each end used for the baseline (default 0.1). In `(0, 0.5]`.
    pub edge_fraction: f64,
    /// Entry threshold in units of `σ` (default 6).
    pub k_enter: f64,
    /// Exit threshold in units of `σ` (default 3), ≤ `k_enter`.
    pub k_exit: f64,
    /// Entry threshold floor in ADC counts (default 30).
    pub min_enter: f64,
    /// Exit threshold floor in ADC counts (default 15), ≤ `min_enter`.
    pub min_exit: f64,
    /// Runs separated by fewer samples merge (default 40 = 100 ms).
    pub min_gap: usize,
    /// Shorter runs are dropped (default 20 = 50 ms).
    pub min_span: usize,
    /// Samples added on each side of a kept run (default 20 = 50 ms).
    pub pad: usize,
}

impl Default for RobustSegmentation {
    fn default() -> Self {
        RobustSegmentation {
            smooth: 20,
            edge_fraction: 0.1,
            k_enter: 6.0,
            k_exit: 3.0,
            min_enter: 30.0,
            min_exit: 15.0,
            min_gap: 40,
            min_span: 20,
            pad: 20,
        }
    }
}

impl RobustSegmentation {
    /// Checks the parameters (see the field docs).
    pub fn validate(&self) -> Result<(), DspError> {
        if self.smooth == 0 {
            return Err(DspError::config(
                "RobustSegmentation::smooth",
                "must be at least 1",
            ));
        }
        if !(self.edge_fraction > 0.0 && self.edge_fraction <= 0.5) {
            return Err(DspError::config(
                "RobustSegmentation::edge_fraction",
                format!("must be in (0, 0.5], got {}", self.edge_fraction),
            ));
        }
        let finite_nonneg = |v: f64| v.is_finite() && v >= 0.0;
        if !(finite_nonneg(self.k_exit)
            && finite_nonneg(self.k_enter)
            && self.k_exit <= self.k_enter)
        {
            return Err(DspError::config(
                "RobustSegmentation::k_exit",
                format!(
                    "need 0 ≤ k_exit ≤ k_enter, finite; got {} and {}",
                    self.k_exit, self.k_enter
                ),
            ));
        }
        if !(finite_nonneg(self.min_exit)
            && finite_nonneg(self.min_enter)
            && self.min_exit <= self.min_enter)
        {
            return Err(DspError::config(
                "RobustSegmentation::min_exit",
                format!(
                    "need 0 ≤ min_exit ≤ min_enter, finite; got {} and {}",
                    self.min_exit, self.min_enter
                ),
            ));
        }
        Ok(())
    }

    /// Segments one trial given its proximity `p` (ADC counts, finite, within the `f32` range, at least 1 sample).
    pub fn segment(&self, p: &[f64]) -> Result<Segment, DspError> {
        self.validate()?;
        self.segment_checked(p)
    }

    /// [`segment`](Self::segment) with parameters already validated.
    fn segment_checked(&self, p: &[f64]) -> Result<Segment, DspError> {
        check_signal(p, Channel::P)?;
        let m = p.len();
        if m == 0 {
            return Err(DspError::TooShort { len: 0, min: 1 });
        }
        let s = moving_average(p, self.smooth);
        let e = ((self.edge_fraction * m as f64).round() as usize)
            .max(self.smooth)
            .min(m);
        let mut edges: Vec<f64> = s[..e].to_vec();
        // The last e samples, not counting those already in the first e.
        edges.extend_from_slice(&s[e.max(m - e)..]);
        let baseline = median(&mut edges);
        let mut dev: Vec<f64> = edges.iter().map(|v| (v - baseline).abs()).collect();
        let sigma = 1.4826 * median(&mut dev);
        let enter = (self.k_enter * sigma).max(self.min_enter);
        let exit = (self.k_exit * sigma).max(self.min_exit);

        // Active runs (|s − b| > exit) that reach the entry threshold somewhere.
        let mut runs: Vec<Range<usize>> = Vec::new();
        let mut i = 0;
        while i < m {
            if (s[i] - baseline).abs() > exit {
                let start = i;
                let mut entered = false;
                while i < m && (s[i] - baseline).abs() > exit {
                    entered |= (s[i] - baseline).abs() > enter;
                    i += 1;
                }
                if entered {
                    match runs.last_mut() {
                        Some(last) if start - last.end < self.min_gap => last.end = i,
                        _ => runs.push(start..i),
                    }
                }
            } else {
                i += 1;
            }
        }
        let kept = runs
            .into_iter()
            .filter(|r| r.end - r.start >= self.min_span);
        Ok(Segment::from_ranges(kept, self.pad, m))
    }
}

/// The robust segmentation with its default parameters ([`RobustSegmentation::default`]).
pub fn segment_robust(p: &[f64]) -> Result<Segment, DspError> {
    RobustSegmentation::default().segment(p)
}

/// Centred moving average of `w` samples, the window shifted inside the signal at the ends.
fn moving_average(p: &[f64], w: usize) -> Vec<f64> {
    let m = p.len();
    let w = w.min(m).max(1);
    let half = w / 2;
    (0..m)
        .map(|i| {
            let start = i.saturating_sub(half).min(m - w);
            let win = &p[start..start + w];
            win.iter().sum::<f64>() / w as f64
        })
        .collect()
}

/// A segmentation method, for comparing them with [`measure_segmentation`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum SegmentationMethod {
    /// [`PaperSegmentation`].
    Paper(PaperSegmentation),
    /// [`RobustSegmentation`].
    Robust(RobustSegmentation),
}

impl SegmentationMethod {
    /// Segments one trial given its proximity. Checks the parameters on every call; to segment many trials
    /// (one call per slide), check them once with [`check`](Self::check).
    pub fn segment(&self, p: &[f64]) -> Result<Segment, DspError> {
        self.check()?.segment(p)
    }

    /// Checks the parameters once ([`PaperSegmentation::validate`], [`RobustSegmentation::validate`]) into a
    /// [`Segmenter`] that segments without checking them again.
    pub fn check(self) -> Result<Segmenter, DspError> {
        match &self {
            SegmentationMethod::Paper(c) => c.validate()?,
            SegmentationMethod::Robust(c) => c.validate()?,
        }
        Ok(Segmenter { method: self })
    }

    /// `"paper"` or `"robust"`.
    pub fn name(&self) -> &'static str {
        match self {
            SegmentationMethod::Paper(_) => "paper",
            SegmentationMethod::Robust(_) => "robust",
        }
    }
}

/// A [`SegmentationMethod`] whose parameters were checked once ([`SegmentationMethod::check`]): the
/// checked-parameters pattern of linfa's `ParamGuard`. Segments exactly as the method does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segmenter {
    method: SegmentationMethod,
}

impl Segmenter {
    /// Segments one trial given its proximity (values checked, parameters not again).
    pub fn segment(&self, p: &[f64]) -> Result<Segment, DspError> {
        match &self.method {
            SegmentationMethod::Paper(c) => c.segment_checked(p),
            SegmentationMethod::Robust(c) => c.segment_checked(p),
        }
    }
}

/// The outcome of a segmentation on one slide.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SlideStats {
    /// Number of samples of the slide.
    pub len: usize,
    /// The segment, or `None` when the method failed (see `error`).
    pub segment: Option<Segment>,
    /// Number of kept samples.
    pub kept: usize,
    /// `kept / len`.
    pub fraction_kept: f64,
    /// First to last kept sample (`0..0` when empty).
    pub span: Range<usize>,
    /// Length of `span`.
    pub span_len: usize,
    /// Whether nothing was kept (also true on failure).
    pub empty: bool,
    /// The error message when the method failed (e.g. a slide shorter than the derivative lag).
    pub error: Option<String>,
}

/// Summary of a segmentation over slides (failed slides count in `n_failed` only).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SegmentationSummary {
    /// Slides given.
    pub n_slides: usize,
    /// Slides on which the method failed.
    pub n_failed: usize,
    /// Slides (not failed) with an empty segment.
    pub n_empty: usize,
    /// Mean of the per-slide kept fractions (0 when no slide succeeded).
    pub mean_fraction_kept: f64,
    /// Smallest per-slide kept fraction.
    pub min_fraction_kept: f64,
    /// Largest per-slide kept fraction.
    pub max_fraction_kept: f64,
    /// Kept samples over all samples of the successful slides.
    pub overall_fraction_kept: f64,
    /// Mean span length in samples.
    pub mean_span_len: f64,
    /// Mean number of kept ranges per slide.
    pub mean_ranges: f64,
}

/// Per-slide results and summary of one segmentation method.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SegmentationReport {
    /// The method's name ([`SegmentationMethod::name`]).
    pub method: String,
    /// One entry per slide, in input order.
    pub slides: Vec<SlideStats>,
    /// The summary.
    pub summary: SegmentationSummary,
}

/// Runs `method` on every slide (each given as its proximity signal) and summarises what it kept, so that
/// segmentations can be compared. A slide the method rejects is recorded with its error, not propagated.
pub fn measure_segmentation<'a>(
    method: &SegmentationMethod,
    slides: impl IntoIterator<Item = &'a [f64]>,
) -> SegmentationReport {
    let mut stats = Vec::new();
    for p in slides {
        let len = p.len();
        let s = match method.segment(p) {
            Ok(segment) => {
                let span = segment.span();
                SlideStats {
                    len,
                    kept: segment.kept(),
                    fraction_kept: segment.fraction_kept(),
                    span_len: span.end - span.start,
                    span,
                    empty: segment.is_empty(),
                    segment: Some(segment),
                    error: None,
                }
            }
            Err(e) => SlideStats {
                len,
                segment: None,
                kept: 0,
                fraction_kept: 0.0,
                span: 0..0,
                span_len: 0,
                empty: true,
                error: Some(e.to_string()),
            },
        };
        stats.push(s);
    }
    let ok: Vec<&SlideStats> = stats.iter().filter(|s| s.error.is_none()).collect();
    let n_ok = ok.len();
    let mean = |f: &dyn Fn(&SlideStats) -> f64| {
        if n_ok == 0 {
            0.0
        } else {
            ok.iter().map(|s| f(s)).sum::<f64>() / n_ok as f64
        }
    };
    let total_len: usize = ok.iter().map(|s| s.len).sum();
    let total_kept: usize = ok.iter().map(|s| s.kept).sum();
    let summary = SegmentationSummary {
        n_slides: stats.len(),
        n_failed: stats.len() - n_ok,
        n_empty: ok.iter().filter(|s| s.empty).count(),
        mean_fraction_kept: mean(&|s| s.fraction_kept),
        min_fraction_kept: if n_ok == 0 {
            0.0
        } else {
            ok.iter()
                .map(|s| s.fraction_kept)
                .fold(f64::INFINITY, f64::min)
        },
        max_fraction_kept: ok.iter().map(|s| s.fraction_kept).fold(0.0, f64::max),
        overall_fraction_kept: if total_len == 0 {
            0.0
        } else {
            total_kept as f64 / total_len as f64
        },
        mean_span_len: mean(&|s| s.span_len as f64),
        mean_ranges: mean(&|s| s.segment.as_ref().map_or(0.0, |g| g.ranges.len() as f64)),
    };
    SegmentationReport {
        method: method.name().to_string(),
        slides: stats,
        summary,
    }
}
