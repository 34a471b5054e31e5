//! Windowed time-domain features (RAW, MAV, RMS) and their batch extraction.

use std::ops::Range;

use serde::{Deserialize, Serialize};

use crate::error::{check_sample, DspError};
use crate::segment::Segment;
use crate::Channel;

/// Sliding-window configuration, in samples.
///
/// Window `k` covers the samples `k·step .. k·step + len` of the signal it is applied to; its *end index* is the
/// index of its last sample, `k·step + len − 1`. The default is the paper's: 10 samples (25 ms at 400 Hz) with a
/// step of 2 samples (5 ms).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct WindowConfig {
    /// Window length in samples (≥ 1).
    pub len: usize,
    /// Step between successive windows in samples (≥ 1).
    pub step: usize,
}

impl Default for WindowConfig {
    fn default() -> Self {
        WindowConfig { len: 10, step: 2 }
    }
}

impl WindowConfig {
    /// Checks `len ≥ 1` and `step ≥ 1`.
    pub fn validate(&self) -> Result<(), DspError> {
        if self.len == 0 {
            return Err(DspError::config("WindowConfig::len", "must be at least 1"));
        }
        if self.step == 0 {
            return Err(DspError::config("WindowConfig::step", "must be at least 1"));
        }
        Ok(())
    }

    /// Number of whole windows in a signal of `n` samples.
    pub fn n_windows(&self, n: usize) -> usize {
        if self.len == 0 || self.step == 0 || n < self.len {
            0
        } else {
            (n - self.len) / self.step + 1
        }
    }
}

/// A per-channel feature of a window.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Feature {
    /// The raw value: the window's **last** sample (the sample its end index points at). The paper classifies the
    /// raw data one observation at a time; taking the last sample of each window gives one raw observation per
    /// feature row, aligned like the MAV/RMS rows and available causally in the streaming form.
    Raw,
    /// Mean absolute value, `mean(|x|)` over the window.
    Mav,
    /// Root mean square, `sqrt(mean(x²))` over the window.
    Rms,
}

impl Feature {
    /// All features, in the order RAW, MAV, RMS.
    pub const ALL: [Feature; 3] = [Feature::Raw, Feature::Mav, Feature::Rms];

    /// The name used in the paper's tables: `"RAW"`, `"MAV"`, `"RMS"`.
    pub fn name(self) -> &'static str {
        match self {
            Feature::Raw => "RAW",
            Feature::Mav => "MAV",
            Feature::Rms => "RMS",
        }
    }
}

/// The channel subsets of the paper's tables.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum FeatureSet {
    /// Proximity only.
    P,
    /// The three deformation channels.
    D1D2D3,
    /// Deformation and proximity.
    D1D2D3P,
    /// Left and right deformation and proximity (the paper's best set).
    D1D2P,
}

impl FeatureSet {
    /// All sets, in the paper's order.
    pub const ALL: [FeatureSet; 4] = [
        FeatureSet::P,
        FeatureSet::D1D2D3,
        FeatureSet::D1D2D3P,
        FeatureSet::D1D2P,
    ];

    /// Indices of the set's channels into a sample `[D1, D2, D3, P]`, ascending.
    pub fn channels(self) -> &'static [usize] {
        match self {
            FeatureSet::P => &[3],
            FeatureSet::D1D2D3 => &[0, 1, 2],
            FeatureSet::D1D2D3P => &[0, 1, 2, 3],
            FeatureSet::D1D2P => &[0, 1, 3],
        }
    }

    /// Name: `"P"`, `"D1D2D3"`, `"D1D2D3+P"`, `"D1D2+P"`.
    pub fn name(self) -> &'static str {
        match self {
            FeatureSet::P => "P",
            FeatureSet::D1D2D3 => "D1D2D3",
            FeatureSet::D1D2D3P => "D1D2D3+P",
            FeatureSet::D1D2P => "D1D2+P",
        }
    }
}

/// Which features of which channels make a feature row.
///
/// A row holds, feature-major, `features.len() × set.channels().len()` values: for each feature in `features`
/// order, that feature of each channel of `set` in channel order. E.g. `{ features: [Mav, Rms], set: D1D2P }` gives
/// `[MAV D1, MAV D2, MAV P, RMS D1, RMS D2, RMS P]` (see [`FeatureSpec::column_names`]).
#[derive(Debug, Clone, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct FeatureSpec {
    /// The features, in column order (at least one; repeats are allowed and repeat the columns).
    pub features: Vec<Feature>,
    /// The channels.
    pub set: FeatureSet,
}

impl FeatureSpec {
    /// One feature of one set, the form of the paper's tables (e.g. MAV of D1, D2, P).
    pub fn new(feature: Feature, set: FeatureSet) -> Self {
        FeatureSpec {
            features: vec![feature],
            set,
        }
    }

    /// Checks that there is at least one feature.
    pub fn validate(&self) -> Result<(), DspError> {
        if self.features.is_empty() {
            return Err(DspError::config(
                "FeatureSpec::features",
                "needs at least one feature",
            ));
        }
        Ok(())
    }

    /// Number of values in a row.
    pub fn n_features(&self) -> usize {
        self.features.len() * self.set.channels().len()
    }

    /// The features' names joined with `+`, e.g. `"MAV"` or `"MAV+RMS"`.
    pub fn feature_name(&self) -> String {
        self.features
            .iter()
            .map(|f| f.name())
            .collect::<Vec<_>>()
            .join("+")
    }

    /// Column names, e.g. `"MAV_D1"`, in row order.
    pub fn column_names(&self) -> Vec<String> {
        let mut names = Vec::with_capacity(self.n_features());
        for feature in &self.features {
            for &c in self.set.channels() {
                names.push(format!("{}_{}", feature.name(), channel_name(c)));
            }
        }
        names
    }
}

/// Feature rows of a signal, row-major `f32`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct FeatureMatrix {
    /// `n_rows × n_features` values, row-major.
    pub data: Vec<f32>,
    /// Values per row.
    pub n_features: usize,
    /// For each row, the index of the window's last sample in the input samples: the sample the row is aligned
    /// to (for labels and per-slide aggregation).
    pub window_ends: Vec<usize>,
}

impl FeatureMatrix {
    /// Number of rows.
    pub fn n_rows(&self) -> usize {
        self.window_ends.len()
    }

    /// Whether there are no rows.
    pub fn is_empty(&self) -> bool {
        self.window_ends.is_empty()
    }

    /// Row `i`, if there is one.
    pub fn row(&self, i: usize) -> Option<&[f32]> {
        let start = i.checked_mul(self.n_features)?;
        self.data.get(start..start.checked_add(self.n_features)?)
    }

    /// The rows, in order (none when `n_features` is 0).
    pub fn rows(&self) -> impl Iterator<Item = &[f32]> + '_ {
        (0..self.n_rows()).filter_map(move |i| self.row(i))
    }
}

/// MAV and RMS of one window, in `f64`: the single arithmetic used by the batch and the streaming forms.
///
/// Both are computed on the window scaled by its largest magnitude `M`: `y_i = |x_i| / M ∈ [0, 1]`,
/// `MAV = M · (Σ y_i / len)`, `RMS = M · sqrt(Σ y_i² / len)`, sums taken in sample order. So squares never overflow
/// (1e300) or underflow (1e-300), results never exceed `M`, and a constant window gives exactly `|value|` for both
/// (`y_i = 1`). An all-zero or empty window gives 0. Inputs are assumed finite (checked upstream).
#[inline]
pub(crate) fn mav_rms(x: &[f64]) -> (f64, f64) {
    let mut max = 0.0f64;
    for &v in x {
        let a = v.abs();
        if a > max {
            max = a;
        }
    }
    if max == 0.0 {
        return (0.0, 0.0);
    }
    let mut s1 = 0.0f64;
    let mut s2 = 0.0f64;
    // The quotients first, a block at a time (independent divisions, in packed instructions), then
    // the sums in order: the same operations as one loop, so the same bits.
    let mut ys = [0.0f64; 16];
    for block in x.chunks(16) {
        for (y, &v) in ys.iter_mut().zip(block) {
            *y = v.abs() / max;
        }
        for &y in &ys[..block.len()] {
            s1 += y;
            s2 += y * y;
        }
    }
    let n = x.len() as f64;
    ((s1 / n) * max, (s2 / n).sqrt() * max)
}

/// Mean absolute value of a window (ADC counts in, ADC counts out), computed as the features are; 0 for an
/// empty window. Exact for constant windows; no overflow or underflow for any finite input.
pub fn mav(x: &[f64]) -> f64 {
    mav_rms(x).0
}

/// Root mean square of a window (ADC counts in, ADC counts out), computed as the features are; 0 for an empty
/// window. Exact for constant windows; no overflow (1e300) or underflow (1e-300) for any finite input.
pub fn rms(x: &[f64]) -> f64 {
    mav_rms(x).1
}

/// Writes the features of one channel window into `out` (a whole row), at the channel's columns.
///
/// `ci` is the channel's position in the set, `nc` the number of channels of the set.
#[inline]
pub(crate) fn channel_features(
    window: &[f64],
    features: &[Feature],
    ci: usize,
    nc: usize,
    out: &mut [f32],
) {
    let (mav, rms) = mav_rms(window);
    let raw = window.last().copied().unwrap_or(0.0);
    for (fi, feature) in features.iter().enumerate() {
        let v = match feature {
            Feature::Raw => raw,
            Feature::Mav => mav,
            Feature::Rms => rms,
        };
        if let Some(slot) = out.get_mut(fi * nc + ci) {
            *slot = v as f32;
        }
    }
}

/// Computes the feature rows of a signal (batch form).
///
/// `samples` are `[D1, D2, D3, P]` in raw ADC counts (any finite value with `|x| ≤ f32::MAX` is accepted). Every
/// sample is checked first; the first one holding NaN/±∞ or a value beyond the `f32` range is reported with its
/// index and channel. Windows follow `window` (see [`WindowConfig`]); a signal shorter than one window gives an empty
/// matrix. Row `k` is aligned to sample `window_ends[k] = k·step + len − 1`. Features are in ADC counts, stored as
/// `f32`, bit-for-bit equal to what [`StreamingFeatures`](crate::StreamingFeatures) emits for the same samples.
///
/// Checks `spec` and `window` on every call; to extract many signals with one configuration, check it once
/// with [`FeatureExtractor::new`].
pub fn extract_features(
    samples: &[[f64; 4]],
    spec: &FeatureSpec,
    window: WindowConfig,
) -> Result<FeatureMatrix, DspError> {
    FeatureExtractor::new(spec.clone(), window)?.extract(samples)
}

/// Computes the feature rows of the parts of a trial a segmentation kept: windows are taken inside each of the
/// segment's ranges (never across a gap between two ranges), and `window_ends` index into `samples` (the whole
/// trial). The samples inside the ranges are checked as in [`extract_features`].
///
/// Checks `spec` and `window` on every call; to extract many trials with one configuration (one call per slide),
/// check it once with [`FeatureExtractor::new`].
pub fn extract_segment_features(
    samples: &[[f64; 4]],
    segment: &Segment,
    spec: &FeatureSpec,
    window: WindowConfig,
) -> Result<FeatureMatrix, DspError> {
    FeatureExtractor::new(spec.clone(), window)?.extract_segment(samples, segment)
}

/// A [`FeatureSpec`] and a [`WindowConfig`] checked once ([`FeatureSpec::validate`],
/// [`WindowConfig::validate`]), so that extracting the features of many signals (one per slide) does not check
/// them again: the checked-parameters pattern of linfa's `ParamGuard`. Gives exactly the rows of
/// [`extract_features`] and [`extract_segment_features`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FeatureExtractor {
    spec: FeatureSpec,
    window: WindowConfig,
}

impl FeatureExtractor {
    /// Checks `spec` and `window`.
    pub fn new(spec: FeatureSpec, window: WindowConfig) -> Result<Self, DspError> {
        spec.validate()?;
        window.validate()?;
        Ok(FeatureExtractor { spec, window })
    }

    /// The features and channels.
    pub fn spec(&self) -> &FeatureSpec {
        &self.spec
    }

    /// The windows.
    pub fn window(&self) -> WindowConfig {
        self.window
    }

    /// [`extract_features`] with the checked configuration.
    pub fn extract(&self, samples: &[[f64; 4]]) -> Result<FeatureMatrix, DspError> {
        for (index, sample) in samples.iter().enumerate() {
            check_sample(index, sample)?;
        }
        let mut m = FeatureMatrix {
            n_features: self.spec.n_features(),
            ..FeatureMatrix::default()
        };
        append_rows(samples, 0, &self.spec, self.window, &mut m);
        Ok(m)
    }

    /// [`extract_segment_features`] with the checked configuration.
    pub fn extract_segment(
        &self,
        samples: &[[f64; 4]],
        segment: &Segment,
    ) -> Result<FeatureMatrix, DspError> {
        if segment.trial_len != samples.len() {
            return Err(DspError::LengthMismatch {
                segment_len: segment.trial_len,
                len: samples.len(),
            });
        }
        let mut m = FeatureMatrix {
            n_features: self.spec.n_features(),
            ..FeatureMatrix::default()
        };
        for range in &segment.ranges {
            let part = sub(samples, range)?;
            for (k, sample) in part.iter().enumerate() {
                check_sample(range.start + k, sample)?;
            }
            append_rows(part, range.start, &self.spec, self.window, &mut m);
        }
        Ok(m)
    }
}

fn sub<'a>(samples: &'a [[f64; 4]], range: &Range<usize>) -> Result<&'a [[f64; 4]], DspError> {
    samples.get(range.clone()).ok_or_else(|| {
        DspError::config(
            "Segment::ranges",
            format!(
                "range {range:?} is not within the trial's 0..{}",
                samples.len()
            ),
        )
    })
}

/// Appends the rows of `samples` (already checked) to `m`, with window ends offset by `offset`.
fn append_rows(
    samples: &[[f64; 4]],
    offset: usize,
    spec: &FeatureSpec,
    window: WindowConfig,
    m: &mut FeatureMatrix,
) {
    let n_windows = window.n_windows(samples.len());
    if n_windows == 0 {
        return;
    }
    let channels = spec.set.channels();
    let nc = channels.len();
    let nf = spec.n_features();
    let row0 = m.data.len();
    m.data.resize(row0 + n_windows * nf, 0.0);
    m.window_ends.reserve(n_windows);
    for k in 0..n_windows {
        m.window_ends
            .push(offset + k * window.step + window.len - 1);
    }
    // One channel at a time, on a contiguous copy, so each window is a plain slice summed in sample order.
    let mut column = Vec::with_capacity(samples.len());
    for (ci, &c) in channels.iter().enumerate() {
        column.clear();
        column.extend(samples.iter().map(|s| s[c]));
        for (k, row) in m.data[row0..].chunks_exact_mut(nf).enumerate() {
            let start = k * window.step;
            if let Some(w) = column.get(start..start + window.len) {
                channel_features(w, &spec.features, ci, nc, row);
            }
        }
    }
}

/// The name of channel `c` (index into `[D1, D2, D3, P]`).
pub(crate) fn channel_name(c: usize) -> &'static str {
    Channel::ALL.get(c).map_or("?", |ch| ch.name())
}
