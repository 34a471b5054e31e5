//! Streaming form of the windowed features.

use crate::error::{check_sample, DspError};
use crate::features::{channel_features, FeatureSpec, WindowConfig};

/// Computes feature rows one sample at a time, bit-for-bit equal to [`extract_features`](crate::extract_features).
///
/// Each [`push`](StreamingFeatures::push) stores the sample in a ring buffer (O(channels), no allocation); once `len`
/// samples are in, every `step`-th push also computes and returns a row, from the window's exact values summed in
/// sample order, the very arithmetic of the batch form (O(len · channels) per row, no running sums that would drift).
/// The row returned after the sample of stream index `t` (0-based, counting accepted samples) is batch row
/// `(t + 1 − len) / step`, aligned to sample `t`.
///
/// A sample holding NaN/±∞ or a value beyond the `f32` range is rejected with an error naming its stream index and
/// channel; it is **not** stored and the stream is otherwise unchanged, so the next push continues as if the bad
/// sample never arrived (stream indices count accepted samples only). Call [`reset`](Self::reset) to start over
/// instead, e.g. at the start of a new slide.
#[derive(Debug, Clone)]
pub struct StreamingFeatures {
    spec: FeatureSpec,
    window: WindowConfig,
    /// Per set channel, `2·len` values: each sample is written at `pos` and `pos + len`, so the last `len` samples
    /// are always the contiguous slice `ring[pos..pos + len]`, oldest first.
    ring: Vec<f64>,
    pos: usize,
    /// Accepted samples since the start or the last reset.
    seen: usize,
    /// Pushes left before the next row.
    countdown: usize,
    row: Vec<f32>,
}

impl StreamingFeatures {
    /// A stream computing `spec` over windows `window`.
    pub fn new(spec: FeatureSpec, window: WindowConfig) -> Result<Self, DspError> {
        spec.validate()?;
        window.validate()?;
        let nc = spec.set.channels().len();
        let ring_len = window
            .len
            .checked_mul(2 * nc)
            .ok_or_else(|| DspError::config("WindowConfig::len", "too large"))?;
        Ok(StreamingFeatures {
            ring: vec![0.0; ring_len],
            pos: 0,
            seen: 0,
            countdown: window.len,
            row: vec![0.0; spec.n_features()],
            spec,
            window,
        })
    }

    /// Adds one sample `[D1, D2, D3, P]` (ADC counts); returns a feature row when a window ends at this sample.
    pub fn push(&mut self, sample: [f64; 4]) -> Result<Option<&[f32]>, DspError> {
        check_sample(self.seen, &sample)?;
        let len = self.window.len;
        let channels = self.spec.set.channels();
        for (ci, &c) in channels.iter().enumerate() {
            let base = ci * 2 * len;
            if let Some(slot) = self.ring.get_mut(base + self.pos) {
                *slot = sample[c];
            }
            if let Some(slot) = self.ring.get_mut(base + self.pos + len) {
                *slot = sample[c];
            }
        }
        self.pos += 1;
        if self.pos == len {
            self.pos = 0;
        }
        self.seen += 1;
        self.countdown -= 1;
        if self.countdown > 0 {
            return Ok(None);
        }
        self.countdown = self.window.step;
        let nc = channels.len();
        for ci in 0..nc {
            let start = ci * 2 * len + self.pos;
            if let Some(w) = self.ring.get(start..start + len) {
                channel_features(w, &self.spec.features, ci, nc, &mut self.row);
            }
        }
        Ok(Some(&self.row))
    }

    /// Forgets all samples: the next push is stream index 0.
    pub fn reset(&mut self) {
        self.pos = 0;
        self.seen = 0;
        self.countdown = self.window.len;
    }

    /// Number of samples accepted since the start or the last reset.
    pub fn samples_seen(&self) -> usize {
        self.seen
    }

    /// Stream index of the last sample of the most recent row's window (the sample that row is aligned to).
    pub fn last_window_end(&self) -> Option<usize> {
        if self.seen < self.window.len {
            return None;
        }
        // Rows end at len−1, len−1+step, …; the latest is at or before seen−1.
        let since = self.seen - self.window.len;
        Some(self.window.len - 1 + since - since % self.window.step)
    }

    /// Values per row.
    pub fn n_features(&self) -> usize {
        self.row.len()
    }

    /// The feature specification.
    pub fn spec(&self) -> &FeatureSpec {
        &self.spec
    }

    /// The window configuration.
    pub fn window(&self) -> WindowConfig {
        self.window
    }
}
