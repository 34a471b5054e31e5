//! The context features computed as samples arrive: [`StreamingContext`], equal bit for bit to
//! the offline [`context_row`](crate::context::context_row).
//!
//! The window pipeline ([`Pipeline::build_windows`](crate::dataset::Pipeline::build_windows),
//! i.e. `tactile train` and `tactile eval`) streams each recording through it too, rather than
//! calling `context_row` per window (O(span) each, 96 % of an evaluation's time before): a
//! deployed model's evaluation on 20 simulated recordings went from 41 s to 1.3 s with the same
//! report (`tests/streaming_context.rs` holds the two to the same bits).
//!
//! Every statistic is an exact integer (samples are whole counts, [`quantise`]), so running sums
//! give the very numbers a direct loop gives, in any order. Per sample, channel and span, the
//! state is updated in O(1) (sums, a ring of the last samples, a histogram of the span's values
//! over [`SAMPLE_MIN`]`..=`[`SAMPLE_MAX`], the "below/above" counts carried against the current
//! limits), plus, when an extreme leaves the span or a limit moves, a vectorised scan of the
//! histogram between the old and the new value (mostly a few counts). A row then only turns the
//! ready statistics into values, O(channels · scales). Nothing is allocated after
//! [`StreamingContext::new`].
//!
//! Spans reach back into earlier slides ([`ContextConfig::across_slides`]) until
//! [`StreamingContext::reset`]; [`StreamingContext::begin_slide`] starts a new slide (its
//! baseline and "slide so far"). The per-span shape values ([`ContextConfig::shape`]) have no
//! streaming form and are refused.

use crackbot_dsp::check_sample;

use crate::context::{
    above_limit, below_limit, level_value, prefix_values, quantise, twice_median, ContextConfig,
    SpanStats, SAMPLE_MAX, SAMPLE_MIN,
};
use crate::TactileError;

const N_VALUES: usize = (SAMPLE_MAX - SAMPLE_MIN + 1) as usize;

/// Index of value `q` (in `SAMPLE_MIN..=SAMPLE_MAX`) in a [`Span`]'s histogram.
#[inline(always)]
fn slot(q: i32) -> usize {
    (q - SAMPLE_MIN) as usize
}

/// Sum of the counts of a histogram slice (vectorised).
#[inline]
fn count_sum(h: &[u16]) -> i64 {
    i64::from(h.iter().map(|&c| u32::from(c)).sum::<u32>())
}

/// Index of the first non-zero count of `h`, scanning 32 counts at a time.
#[inline]
fn first_nonzero(h: &[u16]) -> Option<usize> {
    let mut base = 0;
    for chunk in h.chunks(32) {
        if chunk.iter().fold(0, |a, &c| a | c) != 0 {
            return chunk.iter().position(|&c| c != 0).map(|i| base + i);
        }
        base += chunk.len();
    }
    None
}

/// Index of the last non-zero count of `h`, scanning 32 counts at a time.
#[inline]
fn last_nonzero(h: &[u16]) -> Option<usize> {
    let mut end = h.len();
    for chunk in h.rchunks(32) {
        end -= chunk.len();
        if chunk.iter().fold(0, |a, &c| a | c) != 0 {
            return chunk.iter().rposition(|&c| c != 0).map(|i| end + i);
        }
    }
    None
}

/// One span (of one channel): running sums, a histogram of its values, its extremes, and the
/// "below"/"above" counts against the limits of the baseline last seen.
///
/// The limits move only when the extremes or the baseline do, and then mostly by a few counts:
/// the counts are carried from sample to sample (±1 for the values entering and leaving) and,
/// when a limit moves, corrected by the histogram's counts between the old and new limit.
#[derive(Debug, Clone)]
struct Span {
    len: usize,
    n: usize,
    sum: i64,
    sum_sq: i64,
    /// Count of each value `SAMPLE_MIN..=SAMPLE_MAX` in the span (a span is ≤ `MAX_SCALE` <
    /// 2^16 samples).
    hist: Vec<u16>,
    min: i32,
    max: i32,
    /// `below` counts the values `≤ below_at`, `above` those `≥ above_at`; the limits are clamped
    /// to `SAMPLE_MIN − 1..=SAMPLE_MAX` and `SAMPLE_MIN..=SAMPLE_MAX + 1` (same counts).
    below_at: i32,
    below: i64,
    above_at: i32,
    above: i64,
}

impl Span {
    fn new(len: usize) -> Self {
        Span {
            len,
            n: 0,
            sum: 0,
            sum_sq: 0,
            hist: vec![0; N_VALUES],
            min: 0,
            max: 0,
            below_at: SAMPLE_MIN - 1,
            below: 0,
            above_at: SAMPLE_MAX + 1,
            above: 0,
        }
    }

    fn clear(&mut self) {
        self.n = 0;
        self.sum = 0;
        self.sum_sq = 0;
        self.hist.fill(0);
        self.min = 0;
        self.max = 0;
        self.below_at = SAMPLE_MIN - 1;
        self.below = 0;
        self.above_at = SAMPLE_MAX + 1;
        self.above = 0;
    }

    /// `q` enters the span and `old` (if any) leaves it.
    #[inline(always)]
    fn update(&mut self, q: i32, old: Option<i32>) {
        let q64 = i64::from(q);
        if let Some(c) = self.hist.get_mut(slot(q)) {
            *c = c.wrapping_add(1);
        }
        self.below += i64::from(q <= self.below_at);
        self.above += i64::from(q >= self.above_at);
        match old {
            Some(old) => {
                let o64 = i64::from(old);
                self.sum += q64 - o64;
                self.sum_sq += q64 * q64 - o64 * o64;
                self.below -= i64::from(old <= self.below_at);
                self.above -= i64::from(old >= self.above_at);
                let left = match self.hist.get_mut(slot(old)) {
                    Some(c) => {
                        *c = c.wrapping_sub(1);
                        *c == 0
                    }
                    None => false,
                };
                self.min = self.min.min(q);
                self.max = self.max.max(q);
                // The extreme left the span: the next one lies between it and `q` (exclusive of
                // `old`, inclusive of `q`, whose count is ≥ 1).
                if left && old == self.min {
                    let from = slot(old) + 1;
                    self.min = self
                        .hist
                        .get(from..=slot(q))
                        .and_then(first_nonzero)
                        .map_or(q, |i| SAMPLE_MIN + (from + i) as i32);
                }
                if left && old == self.max {
                    let from = slot(q);
                    self.max = self
                        .hist
                        .get(from..slot(old))
                        .and_then(last_nonzero)
                        .map_or(q, |i| SAMPLE_MIN + (from + i) as i32);
                }
            }
            None => {
                if self.n == 0 {
                    self.min = q;
                    self.max = q;
                } else {
                    self.min = self.min.min(q);
                    self.max = self.max.max(q);
                }
                self.n += 1;
                self.sum += q64;
                self.sum_sq += q64 * q64;
            }
        }
    }

    /// Moves the "below"/"above" limits to those of the baseline `b2` and the current extremes.
    #[inline(always)]
    fn set_limits(&mut self, b2: i64) {
        let lo2 = b2.min(2 * i64::from(self.min));
        let hi2 = b2.max(2 * i64::from(self.max));
        let below_at =
            below_limit(b2, lo2).clamp(i64::from(SAMPLE_MIN) - 1, i64::from(SAMPLE_MAX)) as i32;
        let above_at =
            above_limit(b2, hi2).clamp(i64::from(SAMPLE_MIN), i64::from(SAMPLE_MAX) + 1) as i32;
        if below_at != self.below_at {
            // Values in (low, high] of the two limits change sides.
            let (lo, hi) = (self.below_at.min(below_at), self.below_at.max(below_at));
            let moved = count_sum(self.hist.get(slot(lo + 1)..slot(hi + 1)).unwrap_or(&[]));
            self.below += if below_at > self.below_at {
                moved
            } else {
                -moved
            };
            self.below_at = below_at;
        }
        if above_at != self.above_at {
            // Values in [low, high) of the two limits change sides.
            let (lo, hi) = (self.above_at.min(above_at), self.above_at.max(above_at));
            let moved = count_sum(self.hist.get(slot(lo)..slot(hi)).unwrap_or(&[]));
            self.above += if above_at < self.above_at {
                moved
            } else {
                -moved
            };
            self.above_at = above_at;
        }
    }
}

/// The window's own span: only its sum is read (the "current level").
#[derive(Debug, Clone, Default)]
struct WindowSum {
    len: usize,
    n: usize,
    sum: i64,
}

/// One channel's state.
#[derive(Debug, Clone)]
struct ChannelState {
    /// The last `ring_len` samples (oldest overwritten), indexed by stream time modulo `ring_len`
    /// (a power of two: the index is a mask).
    ring: Vec<i32>,
    /// The window's own span (the "current level"), then one per scale.
    window: WindowSum,
    spans: Vec<Span>,
    /// The slide's first samples so far, sorted (its baseline is their median).
    head: Vec<i32>,
    slide_min: i32,
    slide_max: i32,
}

/// Context features sample by sample (see the [module docs](self)).
#[derive(Debug, Clone)]
pub struct StreamingContext {
    config: ContextConfig,
    channels: Vec<usize>,
    states: Vec<ChannelState>,
    ring_len: usize,
    /// Samples accepted since the last reset (stream time of the next sample).
    t: u64,
    /// Stream time of the first sample of the current slide.
    slide_start: u64,
    /// Samples accepted in the current slide.
    slide_len: u64,
    direction: u8,
}

impl StreamingContext {
    /// Context features `config` of `channels` (indices into `[D1, D2, D3, P]`), the window's own
    /// length being `window_len` (its mean is the "current level").
    pub fn new(
        config: &ContextConfig,
        channels: &[usize],
        window_len: usize,
    ) -> Result<Self, TactileError> {
        config.validate()?;
        if config.shape {
            return Err(TactileError::Context {
                reason: "the per-span shape values have no streaming form (offline only)",
            });
        }
        if window_len == 0 || window_len > crate::context::MAX_SCALE {
            return Err(TactileError::Context {
                reason: "the window length must be between 1 and 60000 samples",
            });
        }
        if channels.is_empty() || channels.iter().any(|&c| c > 3) {
            return Err(TactileError::Context {
                reason: "context channels must be indices 0..=3 of [D1, D2, D3, P], at least one",
            });
        }
        let ring_len = config
            .scales
            .iter()
            .copied()
            .chain([window_len])
            .max()
            .unwrap_or(window_len)
            .next_power_of_two();
        let states = channels
            .iter()
            .map(|_| ChannelState {
                ring: vec![0; ring_len],
                window: WindowSum {
                    len: window_len,
                    ..WindowSum::default()
                },
                spans: config.scales.iter().map(|&l| Span::new(l)).collect(),
                head: Vec::with_capacity(config.baseline_len),
                slide_min: 0,
                slide_max: 0,
            })
            .collect();
        Ok(StreamingContext {
            config: config.clone(),
            channels: channels.to_vec(),
            states,
            ring_len,
            t: 0,
            slide_start: 0,
            slide_len: 0,
            direction: 0,
        })
    }

    /// Values per row: [`ContextConfig::n_context`] of the channels.
    pub fn n_values(&self) -> usize {
        self.config.n_context(self.channels.len())
    }

    /// The configuration.
    pub fn config(&self) -> &ContextConfig {
        &self.config
    }

    /// Samples accepted in the current slide.
    pub fn slide_len(&self) -> u64 {
        self.slide_len
    }

    /// Forgets everything: the next sample starts a new stream and a new slide.
    pub fn reset(&mut self) {
        self.t = 0;
        self.slide_start = 0;
        self.slide_len = 0;
        for s in &mut self.states {
            s.window = WindowSum {
                len: s.window.len,
                ..WindowSum::default()
            };
            for span in &mut s.spans {
                span.clear();
            }
            s.head.clear();
        }
    }

    /// The next sample starts a new slide: a new baseline and "slide so far"; the spans go on
    /// reaching back into earlier slides unless [`ContextConfig::across_slides`] is off.
    pub fn begin_slide(&mut self) {
        self.slide_start = self.t;
        self.slide_len = 0;
        let across = self.config.across_slides;
        for s in &mut self.states {
            s.head.clear();
            if !across {
                s.window = WindowSum {
                    len: s.window.len,
                    ..WindowSum::default()
                };
                for span in &mut s.spans {
                    span.clear();
                }
            }
        }
    }

    /// Adds one sample `[D1, D2, D3, P]` and its sliding direction (column 6). A sample holding
    /// NaN/±∞ (or beyond the `f32` range) is refused with an error naming its index in the slide
    /// and its channel, and leaves the state unchanged.
    pub fn push(&mut self, sample: [f64; 4], direction: u8) -> Result<(), TactileError> {
        check_sample(self.slide_len as usize, &sample).map_err(TactileError::Pipeline)?;
        let t = self.t;
        let floor = if self.config.across_slides {
            0
        } else {
            self.slide_start
        };
        let mask = self.ring_len as u64 - 1;
        let ring_slot = (t & mask) as usize;
        for (state, &c) in self.states.iter_mut().zip(&self.channels) {
            let q = quantise(sample[c]);
            if state.head.len() < self.config.baseline_len {
                let at = state.head.partition_point(|&v| v <= q);
                state.head.insert(at, q);
            }
            let b2 = twice_median(&state.head);
            // The sample leaving each span is still in the ring (every span ≤ ring length).
            let ring = &state.ring;
            let leaving = |len: usize| {
                let len = len as u64;
                (t >= len && t - len >= floor).then(|| ring[((t - len) & mask) as usize])
            };
            let w = &mut state.window;
            if let Some(old) = leaving(w.len) {
                w.sum -= i64::from(old);
                w.n -= 1;
            }
            w.n += 1;
            w.sum += i64::from(q);
            for span in &mut state.spans {
                span.update(q, leaving(span.len));
                span.set_limits(b2);
            }
            state.ring[ring_slot] = q;
            if self.slide_len == 0 {
                state.slide_min = q;
                state.slide_max = q;
            } else {
                state.slide_min = state.slide_min.min(q);
                state.slide_max = state.slide_max.max(q);
            }
        }
        self.t += 1;
        self.slide_len += 1;
        self.direction = direction;
        Ok(())
    }

    /// The context values at the last sample pushed into `out` (exactly [`Self::n_values`]
    /// long, or an error): the offline row of a window ending at that sample.
    pub fn row_into(&self, out: &mut [f32]) -> Result<(), TactileError> {
        if out.len() != self.n_values() {
            return Err(TactileError::Context {
                reason: "the output row's length differs from the context's number of values",
            });
        }
        if self.slide_len == 0 {
            return Err(TactileError::Context {
                reason: "no sample of the current slide yet",
            });
        }
        let mut k = 0;
        let mut put = |v: &[f32]| {
            for &x in v {
                if let Some(o) = out.get_mut(k) {
                    *o = x;
                }
                k += 1;
            }
        };
        let mask = self.ring_len as u64 - 1;
        let last_t = self.t - 1;
        for state in &self.states {
            let b2 = twice_median(&state.head);
            put(&[level_value(state.window.sum, state.window.n as i64, b2)]);
            for span in &state.spans {
                let n = span.n as u64;
                let first_t = last_t + 1 - n;
                // The counts are against the limits of this baseline (set by the last push).
                let stats = SpanStats {
                    n: span.n as i64,
                    sum: span.sum,
                    sum_sq: span.sum_sq,
                    min: span.min,
                    max: span.max,
                    first: state.ring[(first_t & mask) as usize],
                    last: state.ring[(last_t & mask) as usize],
                    below: span.below,
                    above: span.above,
                };
                put(&stats.values(b2));
            }
            if self.config.prefix {
                put(&prefix_values(state.slide_min, state.slide_max, b2));
            }
        }
        if self.config.direction {
            put(&[f32::from(self.direction)]);
        }
        Ok(())
    }
}
