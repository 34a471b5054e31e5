//! The context features computed as samples arrive: [`StreamingContext`], equal bit for bit to
//! the offline [`context_row`](crate::context::context_row).
//!
//! Every statistic is an exact integer (samples are whole counts, [`quantise`]), so running sums
//! give the very numbers a direct loop gives, in any order. Per sample and channel, the state
//! is updated in O(1) amortised (sums, a ring of the last samples, monotonic queues for each
//! span's minimum and maximum) plus O(log V) for the "below/above" counts (a Fenwick tree of
//! counts over the sample values of each span, V = [`SAMPLE_MAX`] − [`SAMPLE_MIN`] + 1); a row
//! costs O(channels · scales · log V). Nothing is allocated after [`StreamingContext::new`].
//!
//! Spans reach back into earlier slides ([`ContextConfig::across_slides`]) until
//! [`StreamingContext::reset`]; [`StreamingContext::begin_slide`] starts a new slide (its
//! baseline and "slide so far"). The per-span shape values ([`ContextConfig::shape`]) have no
//! streaming form and are refused.

use std::collections::VecDeque;

use crackbot_dsp::check_sample;

use crate::context::{
    above_limit, below_limit, level_value, prefix_values, quantise, twice_median, ContextConfig,
    SpanStats, SAMPLE_MAX, SAMPLE_MIN,
};
use crate::TactileError;

/// Counts of sample values over a span: a Fenwick (binary indexed) tree over
/// `SAMPLE_MIN..=SAMPLE_MAX`.
#[derive(Debug, Clone)]
struct ValueCounts {
    tree: Vec<u32>,
}

const N_VALUES: usize = (SAMPLE_MAX - SAMPLE_MIN + 1) as usize;

impl ValueCounts {
    fn new() -> Self {
        ValueCounts {
            tree: vec![0; N_VALUES + 1],
        }
    }

    fn clear(&mut self) {
        self.tree.fill(0);
    }

    #[inline]
    fn add(&mut self, q: i32, delta: i32) {
        self.add_from((q - SAMPLE_MIN) as usize + 1, delta);
    }

    /// One value `old` becomes `new`: both update paths walked together, stopping where they
    /// merge (above it, the −1 and +1 cancel), so nearby values cost a few steps.
    #[inline]
    fn replace(&mut self, old: i32, new: i32) {
        let n = self.tree.len();
        let mut i = (old - SAMPLE_MIN) as usize + 1;
        let mut j = (new - SAMPLE_MIN) as usize + 1;
        while i != j {
            if i < j {
                if let Some(slot) = self.tree.get_mut(i) {
                    *slot = slot.wrapping_sub(1);
                }
                i += i & i.wrapping_neg();
                if i >= n {
                    // The old path has left the tree; finish the new one alone.
                    self.add_from(j, 1);
                    return;
                }
            } else {
                if let Some(slot) = self.tree.get_mut(j) {
                    *slot = slot.wrapping_add(1);
                }
                j += j & j.wrapping_neg();
                if j >= n {
                    self.add_from(i, -1);
                    return;
                }
            }
        }
    }

    #[inline]
    fn add_from(&mut self, mut i: usize, delta: i32) {
        while let Some(slot) = self.tree.get_mut(i) {
            *slot = slot.wrapping_add_signed(delta);
            i += i & i.wrapping_neg();
        }
    }

    /// Number of values `≤ k`.
    #[inline]
    fn at_most(&self, k: i64) -> i64 {
        if k < i64::from(SAMPLE_MIN) {
            return 0;
        }
        let mut i = (k.min(i64::from(SAMPLE_MAX)) - i64::from(SAMPLE_MIN)) as usize + 1;
        let mut total = 0i64;
        while i > 0 {
            total += i64::from(self.tree.get(i).copied().unwrap_or(0));
            i &= i - 1;
        }
        total
    }
}

/// Sliding-window minimum (or maximum with `max`) over the last `len` samples.
#[derive(Debug, Clone)]
struct MonoQueue<const MAX: bool> {
    items: VecDeque<(u64, i32)>,
}

impl<const MAX: bool> MonoQueue<MAX> {
    fn new(len: usize) -> Self {
        MonoQueue {
            items: VecDeque::with_capacity(len + 1),
        }
    }

    #[inline]
    fn push(&mut self, t: u64, q: i32, oldest: u64) {
        while let Some(&(_, v)) = self.items.back() {
            let dominated = if MAX { v <= q } else { v >= q };
            if !dominated {
                break;
            }
            self.items.pop_back();
        }
        self.items.push_back((t, q));
        while let Some(&(i, _)) = self.items.front() {
            if i >= oldest {
                break;
            }
            self.items.pop_front();
        }
    }

    fn value(&self) -> i32 {
        self.items.front().map_or(0, |&(_, v)| v)
    }

    fn clear(&mut self) {
        self.items.clear();
    }
}

/// One span (of one channel): running sums, extremes and value counts of its samples.
#[derive(Debug, Clone)]
struct Span {
    len: usize,
    n: usize,
    sum: i64,
    sum_sq: i64,
    min: MonoQueue<false>,
    max: MonoQueue<true>,
    counts: ValueCounts,
}

impl Span {
    fn new(len: usize) -> Self {
        Span {
            len,
            n: 0,
            sum: 0,
            sum_sq: 0,
            min: MonoQueue::new(len),
            max: MonoQueue::new(len),
            counts: ValueCounts::new(),
        }
    }

    fn clear(&mut self) {
        self.n = 0;
        self.sum = 0;
        self.sum_sq = 0;
        self.min.clear();
        self.max.clear();
        self.counts.clear();
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
        let slot = (t & mask) as usize;
        for (state, &c) in self.states.iter_mut().zip(&self.channels) {
            let q = quantise(sample[c]);
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
            for span in state.spans.iter_mut() {
                let len = span.len as u64;
                match leaving(span.len) {
                    // The same value leaves and enters: the counts are unchanged.
                    Some(old) if old == q => {}
                    Some(old) => {
                        span.sum += i64::from(q) - i64::from(old);
                        span.sum_sq +=
                            i64::from(q) * i64::from(q) - i64::from(old) * i64::from(old);
                        span.counts.replace(old, q);
                    }
                    None => {
                        span.n += 1;
                        span.sum += i64::from(q);
                        span.sum_sq += i64::from(q) * i64::from(q);
                        span.counts.add(q, 1);
                    }
                }
                let oldest = (t + 1).saturating_sub(len).max(floor);
                span.min.push(t, q, oldest);
                span.max.push(t, q, oldest);
            }
            state.ring[slot] = q;
            if state.head.len() < self.config.baseline_len {
                let at = state.head.partition_point(|&v| v <= q);
                state.head.insert(at, q);
            }
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
                let mut stats = SpanStats {
                    n: span.n as i64,
                    sum: span.sum,
                    sum_sq: span.sum_sq,
                    min: span.min.value(),
                    max: span.max.value(),
                    first: state.ring[(first_t & mask) as usize],
                    last: state.ring[(last_t & mask) as usize],
                    below: 0,
                    above: 0,
                };
                let (lo2, hi2) = stats.extremes2(b2);
                stats.below = span.counts.at_most(below_limit(b2, lo2));
                stats.above = stats.n - span.counts.at_most(above_limit(b2, hi2) - 1);
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
