//! From recordings to labelled feature windows: experiment detection, per-slide segmentation,
//! windowed features, and the bookkeeping that lets window predictions be aggregated per slide.

use std::ops::Range;
use std::path::{Path, PathBuf};

use crackbot_dsp::{
    FeatureExtractor, FeatureMatrix, FeatureSpec, Segment, SegmentationMethod, Segmenter,
    WindowConfig,
};
use crackbot_recording::Recording;
use serde::{Deserialize, Serialize};

use crate::context::{context_row, ContextConfig, WindowPlace};
use crate::stream::StreamingContext;
use crate::TactileError;

/// Which of the paper's two experiments a set of recordings belongs to: defined with the label column it
/// gives a meaning to, in `crackbot-recording`.
pub use crackbot_recording::{Experiment, ExperimentError};

/// How slides are cut before windowing.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Segmentation {
    /// Keep the whole slide.
    None,
    /// A [`SegmentationMethod`] from `crackbot-dsp` (the paper's eq. 2, or the robust one).
    Method(SegmentationMethod),
}

impl Segmentation {
    /// Short name for tables.
    pub fn name(&self) -> &'static str {
        match self {
            Segmentation::None => "none",
            Segmentation::Method(m) => m.name(),
        }
    }
}

/// Per-recording correction of the slow offsets that the fibres' position and twist put on the
/// signals (the paper found them to change between recordings).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Normalisation {
    /// Raw ADC counts, as the paper.
    None,
    /// Subtract each channel's median over the recording (its resting level).
    RecordingMedian,
}

/// How recordings become feature windows.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PipelineConfig {
    /// Slide segmentation.
    pub segmentation: Segmentation,
    /// Window length and step (10 and 2 samples in the paper).
    pub window: WindowConfig,
    /// Features and channel set.
    pub spec: FeatureSpec,
    /// Offset correction.
    pub normalisation: Normalisation,
    /// Slides shorter than this many samples are skipped (the authors' files end with a one-sample
    /// "slide 13").
    pub min_slide_len: usize,
    /// Context features of each window (per-slide baseline, multi-scale causal spans, slide so
    /// far, direction); `None` for the paper's window features only.
    pub context: Option<ContextConfig>,
}

impl Default for PipelineConfig {
    /// The paper's pipeline: eq. 2 segmentation, 10-sample windows every 2 samples, MAV of D1, D2
    /// and P, raw counts, no context; slides shorter than 100 samples skipped.
    fn default() -> Self {
        PipelineConfig {
            segmentation: Segmentation::Method(crackbot_dsp::SegmentationMethod::Paper(
                crackbot_dsp::PaperSegmentation::default(),
            )),
            window: WindowConfig::default(),
            spec: FeatureSpec::new(crackbot_dsp::Feature::Mav, crackbot_dsp::FeatureSet::D1D2P),
            normalisation: Normalisation::None,
            min_slide_len: 100,
            context: None,
        }
    }
}

impl PipelineConfig {
    /// Checks every parameter once (segmentation, windows, features, context) into a [`Pipeline`] that
    /// builds windows without checking them again: the checked-parameters pattern of linfa's
    /// `ParamGuard`.
    pub fn check(&self) -> Result<Pipeline, TactileError> {
        if let Some(c) = &self.context {
            c.validate()?;
        }
        let segmenter = match &self.segmentation {
            Segmentation::None => None,
            Segmentation::Method(m) => Some(m.check().map_err(TactileError::Pipeline)?),
        };
        let extractor = FeatureExtractor::new(self.spec.clone(), self.window)
            .map_err(TactileError::Pipeline)?;
        Ok(Pipeline {
            segmenter,
            extractor,
            normalisation: self.normalisation,
            min_slide_len: self.min_slide_len,
            context: self.context.clone(),
            reference_context: false,
        })
    }

    /// Values per feature row.
    pub fn n_features(&self) -> usize {
        n_features(&self.spec, self.context.as_ref())
    }
}

/// Values per feature row of `spec`, with `context` features when given.
fn n_features(spec: &FeatureSpec, context: Option<&ContextConfig>) -> usize {
    match context {
        None => spec.n_features(),
        Some(c) => c.n_features(spec.n_features(), spec.set.channels().len()),
    }
}

/// One sliding movement in a [`WindowSet`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SlideRef {
    /// Index of the recording in the input list.
    pub recording: usize,
    /// Slide number in the recording (column 7).
    pub slide: u32,
    /// Class index.
    pub class: u32,
    /// Label value (class id or width in mm).
    pub label: f64,
    /// Rows of this slide's windows in the set.
    pub windows: Range<usize>,
}

/// Labelled feature windows of a set of recordings.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WindowSet {
    /// Experiment of the labels.
    pub experiment: Experiment,
    /// Row-major features, `n_rows × n_features`.
    pub x: Vec<f32>,
    /// Values per row.
    pub n_features: usize,
    /// Class index of each row.
    pub y: Vec<u32>,
    /// Label value of each row (class id, or crack width in mm).
    pub label: Vec<f64>,
    /// The slides, in order; their window ranges tile the rows.
    pub slides: Vec<SlideRef>,
    /// The recordings' paths, indexed by [`SlideRef::recording`].
    pub sources: Vec<PathBuf>,
}

impl WindowSet {
    /// Number of windows.
    pub fn n_rows(&self) -> usize {
        self.y.len()
    }

    /// Features of row `i`.
    pub fn row(&self, i: usize) -> &[f32] {
        &self.x[i * self.n_features..(i + 1) * self.n_features]
    }
}

/// The label shared by every row of a recording, or an error naming the file.
pub fn recording_label(path: &Path, rec: &Recording) -> Result<f64, TactileError> {
    rec.label().ok_or_else(|| TactileError::MixedLabels {
        path: path.to_path_buf(),
    })
}

/// The experiment: `given`, or detected from the labels of `train` and `test` together.
pub fn choose_experiment(
    given: Option<Experiment>,
    train: &[(PathBuf, Recording)],
    test: &[(PathBuf, Recording)],
) -> Result<Experiment, TactileError> {
    match given {
        Some(e) => Ok(e),
        None => detect_experiment(train.iter().chain(test)),
    }
}

/// Detects the experiment from the labels of all recordings.
pub fn detect_experiment<'a>(
    recordings: impl IntoIterator<Item = &'a (PathBuf, Recording)>,
) -> Result<Experiment, TactileError> {
    let mut labels = Vec::new();
    for (path, rec) in recordings {
        let l = recording_label(path, rec)?;
        if !labels.contains(&l) {
            labels.push(l);
        }
    }
    labels.sort_by(f64::total_cmp);
    Ok(Experiment::detect(&labels)?)
}

fn channel_medians(rec: &Recording) -> [f64; 4] {
    let mut out = [0.0; 4];
    for (c, slot) in out.iter_mut().enumerate() {
        let mut v: Vec<f64> = rec.rows.iter().map(|r| r.channels()[c]).collect();
        if v.is_empty() {
            continue;
        }
        v.sort_by(f64::total_cmp);
        *slot = v[v.len() / 2];
    }
    out
}

/// Builds the labelled windows of `recordings` under `experiment` ([`PipelineConfig::check`], then
/// [`Pipeline::build_windows`]).
pub fn build_windows(
    recordings: &[(PathBuf, Recording)],
    experiment: Experiment,
    config: &PipelineConfig,
) -> Result<WindowSet, TactileError> {
    config.check()?.build_windows(recordings, experiment)
}

/// A [`PipelineConfig`] whose parameters were checked ([`PipelineConfig::check`]).
#[derive(Debug, Clone)]
pub struct Pipeline {
    segmenter: Option<Segmenter>,
    extractor: FeatureExtractor,
    normalisation: Normalisation,
    min_slide_len: usize,
    context: Option<ContextConfig>,
    /// Computes the context rows window by window with [`context_row`] (the reference) instead
    /// of streaming them ([`ContextRows`]).
    reference_context: bool,
}

impl Pipeline {
    /// The same pipeline without context features: the paper's windows of the same slides.
    pub fn without_context(&self) -> Pipeline {
        Pipeline {
            context: None,
            ..self.clone()
        }
    }

    /// The same pipeline computing every context row from scratch with [`context_row`], O(span)
    /// per window, instead of streaming the recording through [`StreamingContext`] (O(1) per
    /// sample). The rows are equal bit for bit; this is the reference the tests hold the fast
    /// path to.
    #[doc(hidden)]
    pub fn with_reference_context(&self) -> Pipeline {
        Pipeline {
            reference_context: true,
            ..self.clone()
        }
    }

    /// Builds the labelled windows of `recordings` under `experiment`.
    pub fn build_windows(
        &self,
        recordings: &[(PathBuf, Recording)],
        experiment: Experiment,
    ) -> Result<WindowSet, TactileError> {
        let (spec, context) = (self.extractor.spec(), self.context.as_ref());
        let mut set = WindowSet {
            experiment,
            x: Vec::new(),
            n_features: n_features(spec, context),
            y: Vec::new(),
            label: Vec::new(),
            slides: Vec::new(),
            sources: recordings.iter().map(|(p, _)| p.clone()).collect(),
        };
        for (index, (path, rec)) in recordings.iter().enumerate() {
            let label = recording_label(path, rec)?;
            let class = experiment
                .class_of(label)
                .ok_or_else(|| TactileError::UnknownLabel {
                    path: path.clone(),
                    label,
                    experiment,
                })?;
            let offset = match self.normalisation {
                Normalisation::None => [0.0; 4],
                Normalisation::RecordingMedian => channel_medians(rec),
            };
            let corrected = |r: &crackbot_recording::Row| -> [f64; 4] {
                let c = r.channels();
                std::array::from_fn(|i| c[i] - offset[i])
            };
            // The whole recording, offset-corrected, and its directions: what context spans see.
            let (all_samples, all_directions) = if context.is_some() {
                whole_recording(path, rec, offset)?
            } else {
                (Vec::new(), Vec::new())
            };
            // The fast path streams the recording once; the shape values have no streaming form.
            let mut streamed = match context {
                Some(c) if !c.shape && !self.reference_context => Some(ContextRows::new(
                    c,
                    spec.set.channels(),
                    self.extractor.window().len,
                )?),
                _ => None,
            };
            for range in rec.slides() {
                if range.len() < self.min_slide_len.max(1) {
                    continue;
                }
                let rows = &rec.rows[range.clone()];
                let samples: Vec<[f64; 4]> = rows.iter().map(corrected).collect();
                let segment = self.segment(path, rows, samples.len())?;
                let m = self
                    .extractor
                    .extract_segment(&samples, &segment)
                    .map_err(|source| TactileError::Features {
                        path: path.clone(),
                        slide: rows[0].slide,
                        source,
                    })?;
                let start = set.y.len();
                let n = m.n_rows();
                match context {
                    None => set.x.extend_from_slice(&m.data),
                    Some(c) => {
                        let whole = (&all_samples[..], &all_directions[..]);
                        let rows_of = (&m, range.start);
                        self.context_rows(c, whole, rows_of, streamed.as_mut(), &mut set.x)?;
                    }
                }
                set.y.extend(std::iter::repeat_n(class, n));
                set.label.extend(std::iter::repeat_n(label, n));
                set.slides.push(SlideRef {
                    recording: index,
                    slide: rows[0].slide,
                    class,
                    label,
                    windows: start..start + n,
                });
            }
        }
        if set.y.is_empty() {
            return Err(TactileError::NoWindows);
        }
        Ok(set)
    }

    /// The segment of a slide's `rows` (`n` samples) the windows are cut from: the whole slide,
    /// or where the segmenter finds the stroke.
    fn segment(
        &self,
        path: &Path,
        rows: &[crackbot_recording::Row],
        n: usize,
    ) -> Result<Segment, TactileError> {
        match &self.segmenter {
            None => Ok(Segment {
                ranges: std::iter::once(0..n).collect(),
                trial_len: n,
            }),
            Some(segmenter) => {
                let p: Vec<f64> = rows.iter().map(|r| r.p).collect();
                segmenter
                    .segment(&p)
                    .map_err(|source| TactileError::Segmentation {
                        path: path.to_path_buf(),
                        slide: rows[0].slide,
                        source,
                    })
            }
        }
    }

    /// Each window's row of `m` (a slide starting at `slide_start` of its recording) with its
    /// context features (`c`, over the `whole` recording's samples and directions), streamed
    /// where `streamed` can, into `out`.
    fn context_rows(
        &self,
        c: &ContextConfig,
        whole: (&[[f64; 4]], &[u8]),
        (m, slide_start): (&FeatureMatrix, usize),
        mut streamed: Option<&mut ContextRows>,
        out: &mut Vec<f32>,
    ) -> Result<(), TactileError> {
        let spec = self.extractor.spec();
        for (k, &end) in m.window_ends.iter().enumerate() {
            if c.keep_window {
                out.extend_from_slice(m.row(k).unwrap_or(&[]));
            }
            let place = WindowPlace {
                samples: whole.0,
                directions: whole.1,
                slide_start,
                end: slide_start + end,
            };
            let done = match streamed.as_mut() {
                Some(streamed) => streamed.extend(place, out)?,
                None => false,
            };
            if !done {
                context_row(
                    c,
                    place,
                    spec.set.channels(),
                    self.extractor.window().len,
                    out,
                );
            }
        }
        Ok(())
    }
}

/// The whole recording at `path`, offset-corrected (`offset` per channel), and its directions:
/// what context spans see. Context spans reach outside the windows (and across slides): every
/// sample they may see must be finite, as the streaming form refuses such samples.
fn whole_recording(
    path: &Path,
    rec: &Recording,
    offset: [f64; 4],
) -> Result<(Vec<[f64; 4]>, Vec<u8>), TactileError> {
    let (samples, directions): (Vec<[f64; 4]>, Vec<u8>) = rec
        .rows
        .iter()
        .map(|r| {
            let c = r.channels();
            (std::array::from_fn(|i| c[i] - offset[i]), r.direction)
        })
        .unzip();
    for (i, s) in samples.iter().enumerate() {
        crackbot_dsp::check_sample(i, s).map_err(|source| TactileError::Features {
            path: path.to_path_buf(),
            slide: rec.rows.get(i).map_or(0, |r| r.slide),
            source,
        })?;
    }
    Ok((samples, directions))
}

/// The context rows of one recording's windows, from a [`StreamingContext`] that the recording's
/// samples stream through in order (each pushed once): O(1) per sample where [`context_row`] is
/// O(span) per window, and equal to it bit for bit (`tests/streaming_context.rs`).
struct ContextRows {
    stream: StreamingContext,
    /// Samples of the recording pushed so far.
    pushed: usize,
    /// Start of the slide the stream is in.
    slide_start: usize,
}

impl ContextRows {
    fn new(
        config: &ContextConfig,
        channels: &[usize],
        window_len: usize,
    ) -> Result<Self, TactileError> {
        let stream = StreamingContext::new(config, channels, window_len)?;
        Ok(ContextRows {
            stream,
            pushed: 0,
            slide_start: 0,
        })
    }

    /// Appends the context row of the window at `place` (`place.samples` must be the whole
    /// recording, the same on every call) to `out` and returns `true`; returns `false` with
    /// nothing appended for a window the stream has already passed (ending before the samples
    /// pushed, or in a slide it did not begin), which never happens for windows in slide order:
    /// the caller then computes it with [`context_row`].
    fn extend(&mut self, place: WindowPlace<'_>, out: &mut Vec<f32>) -> Result<bool, TactileError> {
        let end = place.end.min(place.samples.len().saturating_sub(1));
        let behind = end + 1 < self.pushed;
        let elsewhere = self.pushed > place.slide_start && self.slide_start != place.slide_start;
        if place.samples.is_empty() || behind || elsewhere {
            return Ok(false);
        }
        while self.pushed <= end {
            let i = self.pushed;
            if i == place.slide_start {
                self.stream.begin_slide();
                self.slide_start = i;
            }
            let direction = place.directions.get(i).copied().unwrap_or(0);
            self.stream.push(place.samples[i], direction)?;
            self.pushed += 1;
        }
        let start = out.len();
        out.resize(start + self.stream.n_values(), 0.0);
        self.stream.row_into(&mut out[start..])?;
        Ok(true)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn experiments_are_recognised_from_labels() {
        // `Experiment` lives in crackbot-recording (tested there); this path keeps working.
        assert_eq!(
            Experiment::detect(&[0.0, 1.0, 2.0, 3.0]).unwrap(),
            Experiment::Recognition
        );
        let both = Experiment::detect(&[0.0, 1.0]).unwrap_err().to_string();
        assert!(both.contains("both"), "{both}");
    }

    fn synthetic(label: f64) -> Recording {
        // Two slides of 200 samples; slide 1 has a dip of P at samples 50..70, slide 2 is flat.
        let rows = (0..400)
            .map(|i| crackbot_recording::Row {
                x_mm: 10.0,
                d1: 650.0,
                d2: 430.0,
                d3: 700.0,
                p: if (50..70).contains(&i) { 300.0 } else { 520.0 },
                direction: u8::from(i % 200 >= 100),
                slide: 1 + (i / 200) as u32,
                label,
                repetition: 1,
            })
            .collect();
        Recording { rows, extra: None }
    }

    #[test]
    fn errors_keep_their_source_and_name_the_slide() {
        let mut rec = synthetic(1.0);
        rec.rows[250].d2 = f64::NAN;
        let recs = vec![(PathBuf::from("bad.csv"), rec)];
        let config = PipelineConfig {
            segmentation: Segmentation::None,
            ..PipelineConfig::default()
        };
        let err = build_windows(&recs, Experiment::Recognition, &config).unwrap_err();
        assert!(
            matches!(
                &err,
                TactileError::Features {
                    slide: 2,
                    source: crackbot_dsp::DspError::NonFinite { .. },
                    ..
                }
            ),
            "{err:?}"
        );
        let text = err.to_string();
        assert!(
            text.starts_with("bad.csv: slide 2: sample 50, channel D2"),
            "{text}"
        );
        assert!(std::error::Error::source(&err).is_some());
        let wavy = vec![(PathBuf::from("wavy.csv"), synthetic(3.0))];
        let err = build_windows(&wavy, Experiment::Width, &config).unwrap_err();
        assert!(matches!(err, TactileError::UnknownLabel { .. }), "{err:?}");
        let mixed = detect_experiment(&[(PathBuf::from("x"), synthetic(4.0))]).unwrap_err();
        assert!(
            matches!(
                mixed,
                TactileError::Experiment(ExperimentError::Unknown { .. })
            ),
            "{mixed:?}"
        );
    }

    #[test]
    fn context_features_are_appended_per_window_and_may_cross_slides() {
        let recs = vec![(PathBuf::from("a"), synthetic(1.0))];
        let mut config = PipelineConfig {
            segmentation: Segmentation::None,
            window: WindowConfig::default(),
            spec: FeatureSpec::new(crackbot_dsp::Feature::Mav, crackbot_dsp::FeatureSet::P),
            normalisation: Normalisation::None,
            min_slide_len: 100,
            context: None,
        };
        let plain = build_windows(&recs, Experiment::Recognition, &config).unwrap();
        assert_eq!(plain.n_features, 1);
        let ctx = ContextConfig {
            scales: vec![300],
            baseline_len: 10,
            prefix: false,
            direction: true,
            keep_window: true,
            across_slides: false,
            shape: false,
        };
        config.context = Some(ctx.clone());
        let within = build_windows(&recs, Experiment::Recognition, &config).unwrap();
        assert_eq!(within.n_features, 1 + ctx.n_context(1));
        assert_eq!(within.n_features, config.n_features());
        assert_eq!(within.n_rows(), plain.n_rows());
        // Column 0 is the window's own MAV; then level, mean, std, min − baseline, ...
        assert_eq!(within.row(0)[0], plain.row(0)[0]);
        let last = within.slides[1].windows.end - 1;
        assert_eq!(within.row(last)[4], 0.0, "slide 2 alone never dips");
        assert_eq!(*within.row(last).last().unwrap(), 1.0, "direction");
        config.context = Some(ContextConfig {
            across_slides: true,
            ..ctx
        });
        let across = build_windows(&recs, Experiment::Recognition, &config).unwrap();
        let first2 = across.slides[1].windows.start;
        assert_eq!(across.row(first2)[4], -220.0, "slide 1's dip is remembered");
        config.context = Some(ContextConfig {
            scales: vec![0],
            ..ContextConfig::default()
        });
        assert!(build_windows(&recs, Experiment::Recognition, &config).is_err());
    }
}
