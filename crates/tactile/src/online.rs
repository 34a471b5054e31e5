//! Online classification with a deployed [`TactileModel`]: samples in, verdicts out.
//!
//! [`OnlineClassifier::push`] takes one sample (and the arm's position along the slide) at a time:
//! it updates the context features ([`StreamingContext`]) and, where the window forest votes, the
//! paper's window features ([`StreamingFeatures`]), keeps the rows of every sample of the slide in buffers reused from
//! slide to slide (nothing is allocated per window once the longest slide has been seen), and
//! every `step` samples classifies the newest window with the voting forests (the context forest,
//! and the window forest where the model's [`SlideVote`] is `Both`) into a **running verdict**.
//! [`OnlineClassifier::end_slide`] segments the slide (the paper's eq. 2 on P, as offline), takes
//! the windows of the segment — the very windows `crackbot tactile eval` takes — and returns the
//! **slide verdict**: the class of the largest summed slide mean of the voting forests (the offline
//! arithmetic, so the verdict and its probabilities equal the offline ones bit for bit; a test
//! checks it on real recordings), its confidence, the width (the vote's posterior mean and
//! standard deviation over the classes' widths, and the regressor's median with a robust spread) and, when the surface or the signals are unlike training, a [`Doubt`].

use crackbot_dsp::{median, Segmenter, StreamingFeatures, WindowConfig};
use crackbot_forest::Classifier;
use crackbot_recording::Recording;
use serde::Serialize;

use crate::dataset::Segmentation;
use crate::model::{Doubt, SlideVote, TactileModel};
use crate::stream::StreamingContext;
use crate::vote::slide_means;
use crate::TactileError;

/// The verdict so far during a slide.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunningVerdict {
    /// Class index of the largest mean vote so far.
    pub class: u32,
    /// Its vote (the mean over the voting forests of their mean probabilities), 0–1.
    pub confidence: f64,
    /// Windows classified so far in this slide.
    pub windows: usize,
}

/// A width in mm with its uncertainty.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WidthEstimate {
    /// The width: the winning class's width (the vote's mode), mm.
    pub mm: f64,
    /// The posterior mean width: the classes' widths weighted by the slide vote (both forests'
    /// slide means, normalised), mm.
    pub posterior_mean_mm: f64,
    /// The root-mean-square distance of the vote's widths from [`Self::mm`] under the same
    /// weights (the posterior spread around the estimate), mm.
    pub std_mm: f64,
    /// The vote's 10–90 % range, mm: the narrowest and widest class widths between which the
    /// middle 80 % of the slide vote lies (its 10 % and 90 % quantiles over the classes' widths,
    /// [`vote_range_mm`]); never below 0.
    pub range_mm: [f64; 2],
    /// The width regressor's estimate: median of its window estimates, mm.
    pub regressor_mm: f64,
    /// 1.4826 × the median absolute deviation of the regressor's window estimates (a robust
    /// standard deviation), mm.
    pub regressor_spread_mm: f64,
}

/// The `q` and `1 − q` quantiles of a vote over classes whose widths are `labels` (mm): sorted
/// by width, the first class at which the vote's cumulative share reaches `q`, and the first at
/// which it reaches `1 − q`. Both clamped at 0; `[0, 0]` for an empty or zero vote.
pub fn vote_range_mm(votes: &[f64], labels: &[f64], q: f64) -> [f64; 2] {
    let mut by_width: Vec<(f64, f64)> = labels
        .iter()
        .zip(votes)
        .filter(|(w, v)| w.is_finite() && v.is_finite() && **v > 0.0)
        .map(|(w, v)| (*w, *v))
        .collect();
    let total: f64 = by_width.iter().map(|p| p.1).sum();
    if by_width.is_empty() || total <= 0.0 {
        return [0.0, 0.0];
    }
    by_width.sort_by(|a, b| a.0.total_cmp(&b.0));
    let quantile = |share: f64| {
        let mut cum = 0.0;
        for &(w, v) in &by_width {
            cum += v / total;
            if cum >= share - 1e-12 {
                return w;
            }
        }
        by_width[by_width.len() - 1].0
    };
    [quantile(q).max(0.0), quantile(1.0 - q).max(0.0)]
}

/// The verdict at the end of a slide.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SlideVerdict {
    /// Class index.
    pub class: u32,
    /// Class name.
    pub name: String,
    /// Class label (class id, or crack width in mm).
    pub label: f64,
    /// The winning class's vote: the mean of the voting forests' slide means, 0–1.
    pub confidence: f64,
    /// Summed slide means of the voting forests, per class (0–1 with the context forest alone,
    /// 0–2 with both), as offline.
    pub votes: Vec<f64>,
    /// Width experiment: the regressor's estimate.
    pub width: Option<WidthEstimate>,
    /// Windows that made the verdict.
    pub windows: usize,
    /// Whether they are the segment's (`false`: the segmentation found nothing, every window of the
    /// slide was used).
    pub segmented: bool,
    /// First and last sample of the segment in the slide (half-open).
    pub segment: (usize, usize),
    /// Fraction of the windows unlike any training window.
    pub novel_fraction: f64,
    /// Why not to trust it, if anything.
    pub doubt: Option<Doubt>,
    /// Samples of the slide.
    pub samples: usize,
}

impl SlideVerdict {
    /// Whether the surface came out as unknown (dead or saturated channel, novel surface).
    pub fn is_unknown(&self) -> bool {
        self.doubt.as_ref().is_some_and(Doubt::is_unknown)
    }
}

/// Online classification with a deployed model (see the [module docs](self)).
#[derive(Debug)]
pub struct OnlineClassifier<'m> {
    model: &'m TactileModel,
    segmenter: Option<Segmenter>,
    channels: Vec<usize>,
    context: StreamingContext,
    window: StreamingFeatures,
    window_cfg: WindowConfig,
    n_ctx: usize,
    n_win: usize,
    k: usize,
    /// Whether the window forest votes ([`SlideVote::Both`]).
    window_votes: bool,
    min_slide_len: usize,
    samples: Vec<[f64; 4]>,
    positions: Vec<f64>,
    p: Vec<f64>,
    ctx_rows: Vec<f32>,
    win_rows: Vec<f32>,
    proba: Vec<f32>,
    running: Vec<f64>,
    running_windows: usize,
    ends: Vec<usize>,
    slide_proba: Vec<f32>,
    estimates: Vec<f64>,
}

impl<'m> OnlineClassifier<'m> {
    /// A classifier for `model`'s slides.
    pub fn new(model: &'m TactileModel) -> Result<Self, TactileError> {
        let pipeline = &model.header.pipeline;
        let segmenter = match &pipeline.segmentation {
            Segmentation::None => None,
            Segmentation::Method(m) => Some(m.check().map_err(TactileError::Pipeline)?),
        };
        let channels = pipeline.spec.set.channels().to_vec();
        let context = StreamingContext::new(model.context(), &channels, pipeline.window.len)?;
        let window_cfg = pipeline.window;
        let window = StreamingFeatures::new(
            pipeline.spec.clone(),
            WindowConfig {
                len: window_cfg.len,
                step: 1,
            },
        )
        .map_err(TactileError::Pipeline)?;
        let k = model.experiment().n_classes();
        Ok(OnlineClassifier {
            n_ctx: context.n_values(),
            n_win: window.n_features(),
            model,
            segmenter,
            channels,
            context,
            window,
            window_cfg,
            k,
            window_votes: model.header.slide_vote == SlideVote::Both,
            min_slide_len: pipeline.min_slide_len.max(1),
            samples: Vec::new(),
            positions: Vec::new(),
            p: Vec::new(),
            ctx_rows: Vec::new(),
            win_rows: Vec::new(),
            proba: vec![0.0; k],
            running: vec![0.0; k],
            running_windows: 0,
            ends: Vec::new(),
            slide_proba: Vec::new(),
            estimates: Vec::new(),
        })
    }

    /// The model.
    pub fn model(&self) -> &TactileModel {
        self.model
    }

    /// Forests whose slide means are summed into a vote (1 or 2).
    fn voters(&self) -> f64 {
        if self.window_votes {
            2.0
        } else {
            1.0
        }
    }

    /// Forgets every earlier slide (the context spans stop reaching back).
    pub fn reset(&mut self) {
        self.context.reset();
        self.begin_slide();
    }

    /// The next sample starts a new slide.
    pub fn begin_slide(&mut self) {
        self.context.begin_slide();
        self.window.reset();
        self.samples.clear();
        self.positions.clear();
        self.p.clear();
        self.ctx_rows.clear();
        self.win_rows.clear();
        self.running.fill(0.0);
        self.running_windows = 0;
    }

    /// Adds one sample `[D1, D2, D3, P]` (ADC counts), its sliding direction (column 6) and the
    /// finger's position along the slide (mm). Every `step` samples once a window is complete,
    /// returns the running verdict. A non-finite sample is refused with an error and changes
    /// nothing.
    pub fn push(
        &mut self,
        sample: [f64; 4],
        direction: u8,
        position_mm: f64,
    ) -> Result<Option<RunningVerdict>, TactileError> {
        self.context.push(sample, direction)?;
        // The paper's window features, only where the window forest votes.
        if self.window_votes {
            match self.window.push(sample).map_err(TactileError::Pipeline)? {
                Some(row) => self.win_rows.extend_from_slice(row),
                None => self.win_rows.extend(std::iter::repeat_n(0.0, self.n_win)),
            }
        }
        let i = self.samples.len();
        self.samples.push(sample);
        self.positions.push(position_mm);
        self.p.push(sample[3]);
        let len = self.window_cfg.len;
        let at = self.ctx_rows.len();
        self.ctx_rows.resize(at + self.n_ctx, 0.0);
        self.context.row_into(&mut self.ctx_rows[at..])?;
        if i + 1 < len || !(i + 1 - len).is_multiple_of(self.window_cfg.step) {
            return Ok(None);
        }
        // The running verdict: the voting forests on the newest window.
        let k = self.k;
        let ctx = &self.ctx_rows[at..at + self.n_ctx];
        self.model
            .context_forest
            .predict_proba_into(ctx, &mut self.proba);
        for (r, &p) in self.running.iter_mut().zip(&self.proba[..k]) {
            *r += f64::from(p);
        }
        if self.window_votes {
            let win = &self.win_rows[i * self.n_win..(i + 1) * self.n_win];
            self.model
                .window_forest
                .predict_proba_into(win, &mut self.proba);
            for (r, &p) in self.running.iter_mut().zip(&self.proba[..k]) {
                *r += f64::from(p);
            }
        }
        self.running_windows += 1;
        let n = self.running_windows as f64;
        let (class, best) =
            self.running
                .iter()
                .enumerate()
                .fold(
                    (0, f64::NEG_INFINITY),
                    |(c, b), (j, &v)| {
                        if v > b {
                            (j, v)
                        } else {
                            (c, b)
                        }
                    },
                );
        Ok(Some(RunningVerdict {
            class: class as u32,
            confidence: best / (self.voters() * n),
            windows: self.running_windows,
        }))
    }

    /// Samples of the current slide.
    pub fn slide_samples(&self) -> &[[f64; 4]] {
        &self.samples
    }

    /// Positions (mm) of the current slide's samples.
    pub fn slide_positions(&self) -> &[f64] {
        &self.positions
    }

    /// Ends the slide: its verdict, or `None` when it is shorter than the pipeline's minimum slide
    /// (as offline, such slides are not classified) or has no complete window.
    pub fn end_slide(&mut self) -> Result<Option<SlideVerdict>, TactileError> {
        let n = self.samples.len();
        if n < self.min_slide_len {
            return Ok(None);
        }
        let (segment, segmented) = self.window_ends()?;
        if self.ends.is_empty() {
            return Ok(None);
        }
        // Window probabilities of both forests, then the slide means in the offline order.
        let k = self.k;
        let m = self.ends.len();
        self.slide_proba.clear();
        self.slide_proba.resize(2 * m * k, 0.0);
        let (ctx_part, win_part) = self.slide_proba.split_at_mut(m * k);
        let mut novel = 0usize;
        for (j, &e) in self.ends.iter().enumerate() {
            let ctx = &self.ctx_rows[e * self.n_ctx..(e + 1) * self.n_ctx];
            self.model
                .context_forest
                .predict_proba_into(ctx, &mut ctx_part[j * k..(j + 1) * k]);
            if self.window_votes {
                let win = &self.win_rows[e * self.n_win..(e + 1) * self.n_win];
                self.model
                    .window_forest
                    .predict_proba_into(win, &mut win_part[j * k..(j + 1) * k]);
            }
            novel += usize::from(self.model.header.gate.is_novel(ctx));
        }
        let votes = if self.window_votes {
            slide_means(&[ctx_part, win_part], m, k)
        } else {
            slide_means(&[ctx_part], m, k)
        };
        let votes32: Vec<f32> = votes.iter().map(|&v| v as f32).collect();
        let class = crackbot_forest::argmax(&votes32);
        let confidence = votes.get(class as usize).copied().unwrap_or(0.0) / self.voters();
        let width = self.width_estimate(&votes, class);
        let novel_fraction = novel as f64 / m as f64;
        let doubt =
            self.model
                .header
                .gate
                .judge(&self.samples, &self.channels, novel_fraction, confidence);
        let h = &self.model.header;
        Ok(Some(SlideVerdict {
            class,
            name: h.classes.get(class as usize).cloned().unwrap_or_default(),
            label: h.labels.get(class as usize).copied().unwrap_or(f64::NAN),
            confidence,
            votes,
            width,
            windows: m,
            segmented,
            segment,
            novel_fraction,
            doubt,
            samples: n,
        }))
    }

    /// The ends of the slide's windows into `self.ends`: over the segment the segmenter finds,
    /// or the whole slide where it finds none. The segment, and whether it was found.
    fn window_ends(&mut self) -> Result<((usize, usize), bool), TactileError> {
        let n = self.samples.len();
        let w = self.window_cfg;
        self.ends.clear();
        let mut segment = (0, 0);
        if let Some(segmenter) = &self.segmenter {
            let seg = segmenter.segment(&self.p).map_err(TactileError::Pipeline)?;
            for r in &seg.ranges {
                for k in 0..w.n_windows(r.len()) {
                    self.ends.push(r.start + k * w.step + w.len - 1);
                }
            }
            let span = seg.span();
            segment = (span.start, span.end);
        }
        let segmented = !self.ends.is_empty();
        if !segmented {
            for k in 0..w.n_windows(n) {
                self.ends.push(k * w.step + w.len - 1);
            }
            segment = (0, n);
        }
        Ok((segment, segmented))
    }

    /// The slide's width from the `votes` that chose `class` (`None` for a model without a
    /// width regressor).
    fn width_estimate(&mut self, votes: &[f64], class: u32) -> Option<WidthEstimate> {
        let reg = self.model.width.as_ref()?;
        self.estimates.clear();
        for &e in &self.ends {
            let ctx = &self.ctx_rows[e * self.n_ctx..(e + 1) * self.n_ctx];
            self.estimates.push(f64::from(reg.predict(ctx)));
        }
        let mm = median(&mut self.estimates);
        for v in &mut self.estimates {
            *v = (*v - mm).abs();
        }
        let mad = median(&mut self.estimates);
        let total: f64 = votes.iter().sum();
        let labels = &self.model.header.labels;
        let mean = votes
            .iter()
            .zip(labels)
            .map(|(v, w)| v / total * w)
            .sum::<f64>();
        // The estimate is the winning class's width (chosen over the posterior mean and
        // the regressor by leave-one-repetition-out on repetitions 1–3: slide MAE
        // 0.00–0.03 mm against 1.28–1.41 and 0.07–1.42 mm, models/tactile/MODEL_CARD.md);
        // its uncertainty is the vote's spread around it.
        let mode = labels.get(class as usize).copied().unwrap_or(mean);
        let var = votes
            .iter()
            .zip(labels)
            .map(|(v, w)| v / total * (w - mode).powi(2))
            .sum::<f64>();
        Some(WidthEstimate {
            mm: mode,
            posterior_mean_mm: mean,
            std_mm: var.sqrt(),
            range_mm: vote_range_mm(votes, labels, 0.1),
            regressor_mm: mm,
            regressor_spread_mm: 1.4826 * mad,
        })
    }
}

/// Classifies every slide of a recording online, sample by sample (positions from column 1).
/// One entry per slide of the recording, `None` where the slide is not classified.
pub fn classify_recording(
    model: &TactileModel,
    recording: &Recording,
) -> Result<Vec<Option<SlideVerdict>>, TactileError> {
    let mut online = OnlineClassifier::new(model)?;
    online.reset();
    let mut out = Vec::new();
    for range in recording.slides() {
        online.begin_slide();
        for r in &recording.rows[range] {
            online.push(r.channels(), r.direction, r.x_mm)?;
        }
        out.push(online.end_slide()?);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::vote_range_mm;

    #[test]
    fn the_vote_range_spans_the_middle_eighty_percent_and_never_goes_below_zero() {
        let labels = [0.5, 1.0, 2.0, 4.0];
        // All of it on one class: a point.
        assert_eq!(
            vote_range_mm(&[0.0, 1.0, 0.0, 0.0], &labels, 0.1),
            [1.0, 1.0]
        );
        // 5 % on 0.5 mm, 90 % on 1 mm, 5 % on 4 mm: the tails are left out.
        assert_eq!(
            vote_range_mm(&[0.05, 0.9, 0.0, 0.05], &labels, 0.1),
            [1.0, 1.0]
        );
        // Split between 1 and 4 mm: the range spans both; classes need not be in order.
        assert_eq!(vote_range_mm(&[0.5, 0.5], &[4.0, 1.0], 0.1), [1.0, 4.0]);
        // Unnormalised votes give the same range.
        assert_eq!(
            vote_range_mm(&[2.0, 6.0, 2.0, 0.0], &labels, 0.1),
            [0.5, 2.0]
        );
        // A negative width (a class of a corrupt model) is clamped; no vote gives nothing.
        assert_eq!(vote_range_mm(&[1.0, 1.0], &[-1.0, 2.0], 0.1), [0.0, 2.0]);
        assert_eq!(vote_range_mm(&[0.0, 0.0], &[1.0, 2.0], 0.1), [0.0, 0.0]);
        assert_eq!(vote_range_mm(&[f64::NAN], &[1.0], 0.1), [0.0, 0.0]);
    }
}
