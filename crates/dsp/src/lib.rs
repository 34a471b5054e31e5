//! Signal processing of crackbot's tactile finger: segmentation of sliding movements and windowed features.
//!
//! The fibre-optic finger gives four channels at 400 Hz, in raw 10-bit ADC counts (0–1023): D1, D2, D3
//! (deformation: left, right, back/normal) and P (proximity). A sample is `[f64; 4]` in that order
//! ([`Channel`]). This crate turns samples into the inputs of the classifiers of Palermo et al., "Automatic
//! Fracture Characterization Using Tactile and Proximity Optical Sensing" (Frontiers in Robotics and AI, 2020):
//!
//! * **Segmentation** of one sliding movement (trial) — which samples show the explored mechanical feature —
//!   the paper's ([`segment_paper`], [`PaperSegmentation`]) and a robust one ([`segment_robust`],
//!   [`RobustSegmentation`]), returning a [`Segment`]; [`measure_segmentation`] compares methods over slides.
//! * **Features** of sliding windows ([`WindowConfig`], default 10 samples = 25 ms, step 2 = 5 ms): RAW, MAV, RMS
//!   ([`Feature`]) of the channel sets of the paper's tables ([`FeatureSet`]), in batch ([`extract_features`],
//!   [`extract_segment_features`] → [`FeatureMatrix`]) and streaming ([`StreamingFeatures`]) form, the two equal
//!   bit for bit.
//!
//! All values are ADC counts (features too: MAV and RMS of counts are counts). Inputs must be finite and within the
//! `f32` range (the features are stored as `f32`, as the classifiers use them); anything else is rejected with a
//! [`DspError`] naming the sample index and channel. Nothing here panics on bad input.
//!
//! # Example
//!
//! ```
//! use crackbot_dsp::{
//!     extract_features, segment_robust, Feature, FeatureSet, FeatureSpec, StreamingFeatures, WindowConfig,
//! };
//! // A short slide over a crack: the proximity drops from 520 to 270 counts for 20 samples.
//! let samples: Vec<[f64; 4]> = (0..100)
//!     .map(|i| [650.0, 430.0, 710.0, if (40..60).contains(&i) { 270.0 } else { 520.0 }])
//!     .collect();
//! let spec = FeatureSpec { features: vec![Feature::Mav, Feature::Rms], set: FeatureSet::D1D2P };
//! let batch = extract_features(&samples, &spec, WindowConfig::default())?;
//! assert_eq!((batch.n_rows(), batch.n_features, batch.window_ends[0]), (46, 6, 9));
//! let mut stream = StreamingFeatures::new(spec, WindowConfig::default())?;
//! let mut k = 0;
//! for s in &samples {
//!     if let Some(row) = stream.push(*s)? {
//!         assert_eq!(Some(row), batch.row(k)); // bit for bit
//!         k += 1;
//!     }
//! }
//! let p: Vec<f64> = samples.iter().map(|s| s[3]).collect();
//! let segment = segment_robust(&p)?;
//! assert!(segment.contains(50) && !segment.contains(5));
//! # Ok::<(), crackbot_dsp::DspError>(())
//! ```
//!
//! # Reading of the paper
//!
//! **Pre-processing (section 3.1, eq. 2).** For one trial with proximity `p` of `m` samples:
//! `Δp_i = (p_{i+n} − p_i) / n`, `Δp̄ = 1/(m−n) Σ Δp_i`, and "the data points of all measurement signals for which
//! `Δp_i > |Δp̄|` are extracted", then "additional 10 % of the original measurement data is added before and after
//! the extracted points". The text leaves open, and [`PaperSegmentation`] makes parameters of:
//!
//! * *signed or magnitude test* — we keep the printed `Δp_i > |Δp̄|` (only rising proximity passes) by default;
//!   `magnitude: true` gives `|Δp_i| > |Δp̄|`;
//! * *mask or span* — "before and after the extracted points" treats the extracted points as one block, so the
//!   default ([`Extent::Span`]) keeps the span from the first to the last passing point; [`Extent::Points`] keeps
//!   only the passing runs, each with margins;
//! * *10 % of what, where* — "of the original measurement data": 10 % of the trial length `m`, added on **each** side
//!   ([`MarginBase::Trial`], `margin_fraction = 0.1`), clamped to the trial; [`MarginBase::Extracted`] takes it of the
//!   extracted part instead (set `margin_fraction = 0.05` for a 10 % total split over both sides);
//! * *which sample a derivative belongs to* — `Δp_i` is attributed to sample `i` (its first sample);
//! * `n = 10` (25 ms), the value the paper settles on; the paper's 1-based sum over `i = 1..m−n` is our
//!   `i = 0..m−n` (0-based); `m ≤ n` is an error, and when no point passes the segment is empty (no margins).
//!
//! On the authors' recordings this faithful reading keeps about a third of the points, but the points are spread
//! over the whole slide (the flat surface's ±10-count texture makes `Δp_i` exceed the near-zero `|Δp̄|` everywhere),
//! so the span with its margins covers essentially every slide entirely. [`RobustSegmentation`] instead measures
//! how far the smoothed proximity departs from the slide's flat-surface baseline (median and MAD of its first and
//! last 10 %), with hysteresis, merging and a minimum length: it keeps the crack/bump crossings (two per out-and-back
//! slide), most of a wavy slide, and next to nothing of a flat one (measured: `tests/real_data.rs`).
//!
//! **Features (section 3.2).** Windows of 10 samples with a shift of 2; MAV = `mean(|x|)`, RMS = `sqrt(mean(x²))`.
//! The paper also classifies "raw data"; with windows we define RAW as the window's **last** sample, so every
//! feature row is aligned to one sample — its window's end index ([`FeatureMatrix::window_ends`],
//! [`StreamingFeatures::last_window_end`]) — which is what labels and per-slide aggregation use. The channel sets are
//! those of the paper's tables: P, D1D2D3, D1D2D3+P and D1D2+P.
//!
//! # Numerics
//!
//! MAV and RMS of a window are computed on the window divided by its largest magnitude `M` and multiplied back
//! ([`mav`], [`rms`]): no overflow (1e300) nor underflow (1e-300) in the squares, results never above `M`, and a
//! constant window gives exactly its value. Each row is computed from the window's samples, summed in sample
//! order, by the same function in the batch and the streaming forms — no running sums, so no drift over long
//! streams and bit-for-bit equal rows.

mod error;
mod features;
mod median;
mod segment;
mod streaming;

pub use error::{check_sample, DspError};
pub use features::{
    extract_features, extract_segment_features, mav, rms, Feature, FeatureExtractor, FeatureMatrix,
    FeatureSet, FeatureSpec, WindowConfig,
};
pub use median::median;
pub use segment::{
    measure_segmentation, segment_paper, segment_robust, Extent, MarginBase, PaperSegmentation,
    RobustSegmentation, Segment, SegmentationMethod, SegmentationReport, SegmentationSummary,
    Segmenter, SlideStats,
};
pub use streaming::StreamingFeatures;

/// One of the finger's four channels; a sample is `[D1, D2, D3, P]` ([`Channel::index`]). Defined once, in
/// `crackbot-protocol` (the wire format's channel order), and re-exported here.
pub use crackbot_protocol::Channel;

#[cfg(test)]
mod tests {
    use super::Channel;

    #[test]
    fn channels_serialise_by_name_and_index_samples() {
        for (i, c) in Channel::ALL.into_iter().enumerate() {
            assert_eq!(c.index(), i);
            let json = serde_json::to_string(&c).expect("serialise");
            assert_eq!(json, format!("\"{c}\""));
            assert_eq!(
                serde_json::from_str::<Channel>(&json).expect("deserialise"),
                c
            );
        }
        assert_eq!(serde_json::to_string(&Channel::D1).expect("json"), "\"D1\"");
        assert_eq!(Channel::P.to_string(), "P");
    }

    #[test]
    fn checked_configurations_give_the_rows_and_segments_of_the_free_functions() {
        use super::*;
        let samples: Vec<[f64; 4]> = (0..300)
            .map(|i| {
                let p = if (100..140).contains(&i) {
                    270.0
                } else {
                    520.0
                };
                [650.0 + f64::from(i % 7), 430.0, 710.0, p]
            })
            .collect();
        let p: Vec<f64> = samples.iter().map(|s| s[Channel::P.index()]).collect();
        let spec = FeatureSpec::new(Feature::Rms, FeatureSet::D1D2D3P);
        let window = WindowConfig { len: 8, step: 3 };
        let extractor = FeatureExtractor::new(spec.clone(), window).expect("valid");
        assert_eq!(
            extractor.extract(&samples),
            extract_features(&samples, &spec, window)
        );
        for method in [
            SegmentationMethod::Paper(PaperSegmentation::default()),
            SegmentationMethod::Robust(RobustSegmentation::default()),
        ] {
            let segmenter = method.check().expect("valid");
            let segment = segmenter.segment(&p).expect("segment");
            assert_eq!(Ok(&segment), method.segment(&p).as_ref());
            assert_eq!(
                extractor.extract_segment(&samples, &segment),
                extract_segment_features(&samples, &segment, &spec, window)
            );
        }
        assert!(FeatureExtractor::new(spec, WindowConfig { len: 0, step: 1 }).is_err());
        let bad = PaperSegmentation {
            n: 0,
            ..PaperSegmentation::default()
        };
        assert!(SegmentationMethod::Paper(bad).check().is_err());
    }
}
