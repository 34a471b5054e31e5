//! The touch step's pieces: a slide's axis, the strokes of a classification unit as recorded,
//! both models over a unit ([`classify`]), and each stroke's record in the report
//! ([`pass_record`], [`keep_pass`]).

use std::ops::Range;
use std::path::PathBuf;

use crackbot_planner::Slide;
use crackbot_tactile::localise::CrackExtent;
use crackbot_tactile::online::{OnlineClassifier, SlideVerdict};

use crate::inspect::doubts::{PassDoubt, NOT_JUDGED};
use crate::inspect::progress::Progress;
use crate::inspect::report::{Dip, InspectReport, PassRecord};
use crate::MissionError;

/// The contact strokes over one candidate, as the print check compares raised passes with
/// them.
#[derive(Debug, Clone, Default)]
pub(crate) struct Strokes {
    /// Each stroke's proximity channel and positions on the slide's axis (mm from its start).
    pub(crate) profiles: Vec<(Vec<f64>, Vec<f64>)>,
    /// Where the one stroke also crossed a second line: the samples around the candidate's
    /// own dip ([`crackbot_tactile::stroke::own_dip`]).
    pub(crate) own_dip: Option<Range<usize>>,
    /// Where the finger ended.
    pub(crate) finger_at: [f64; 2],
}

/// What one slide's touch leaves for the print check: the slide stroked (the planned one, or
/// the one made again beside it), its candidate and its contact strokes.
pub(crate) struct Touched {
    /// The slide stroked.
    pub(crate) slide: Slide,
    /// Its candidate (`None`: a tactile row).
    pub(crate) candidate: Option<u64>,
    /// Its strokes.
    pub(crate) strokes: Strokes,
}

/// One stroke of a classification unit, as recorded.
#[derive(Debug, Clone)]
pub(crate) struct Stroke {
    /// Its link id.
    pub(crate) id: u32,
    /// Where it started and ended, mm.
    pub(crate) from: [f64; 2],
    pub(crate) to: [f64; 2],
    /// Samples recorded.
    pub(crate) samples: usize,
    /// Its recording.
    pub(crate) recording: PathBuf,
    /// Attempts needed.
    pub(crate) attempts: u32,
}

/// A classification unit: a stroke forth and back (or one), its samples, positions along the
/// slide's axis and direction column.
#[derive(Debug, Default)]
pub(crate) struct Unit {
    pub(crate) samples: Vec<[f64; 4]>,
    pub(crate) along: Vec<f64>,
    pub(crate) dirs: Vec<u8>,
    pub(crate) strokes: Vec<Stroke>,
}

/// A slide's axis: its start, unit direction and length.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Axis {
    pub(crate) start: [f64; 2],
    pub(crate) u: [f64; 2],
    pub(crate) len: f64,
}

impl Axis {
    pub(crate) fn of(slide: &Slide) -> Axis {
        let d = [
            slide.end_mm[0] - slide.start_mm[0],
            slide.end_mm[1] - slide.start_mm[1],
        ];
        let len = d[0].hypot(d[1]).max(1e-9);
        Axis {
            start: slide.start_mm,
            u: [d[0] / len, d[1] / len],
            len,
        }
    }

    /// The point `s` mm along the axis.
    pub(crate) fn at(&self, s: f64) -> [f64; 2] {
        [self.start[0] + s * self.u[0], self.start[1] + s * self.u[1]]
    }

    /// How far `p` lies along the axis, mm.
    pub(crate) fn along(&self, p: [f64; 2]) -> f64 {
        (p[0] - self.start[0]) * self.u[0] + (p[1] - self.start[1]) * self.u[1]
    }
}

/// Both models over one pass: the recognition verdict and the width verdict.
pub(crate) fn classify(
    online: &mut OnlineClassifier<'_>,
    online_width: &mut OnlineClassifier<'_>,
    samples: &[[f64; 4]],
    positions: &[f64],
    dirs: &[u8],
    fresh: bool,
) -> Result<(Option<SlideVerdict>, Option<SlideVerdict>), MissionError> {
    if fresh {
        online.reset();
        online_width.reset();
    }
    online.begin_slide();
    online_width.begin_slide();
    for ((s, x), d) in samples.iter().zip(positions).zip(dirs) {
        online.push(*s, *d, *x)?;
        online_width.push(*s, *d, *x)?;
    }
    Ok((online.end_slide()?, online_width.end_slide()?))
}

/// Announces a finished pass to front ends (`done` of `of` slides) and keeps it in the report.
/// Its class is shown as "not judged" where its stroke was left unjudged, "–" where it has none.
pub(crate) fn keep_pass(
    progress: &mut dyn FnMut(&Progress),
    report: &mut InspectReport,
    done: usize,
    of: usize,
    rec: PassRecord,
) {
    let class = match (&rec.class, &rec.doubt) {
        (Some(c), _) => c.clone(),
        (None, Some(PassDoubt::NotJudged { .. })) => NOT_JUDGED.into(),
        (None, _) => "–".into(),
    };
    progress(&Progress::Slid {
        done,
        of,
        class,
        pass: Box::new(rec.clone()),
    });
    report.passes.push(rec);
}

/// The report's record of one stroke of a judged unit.
pub(crate) fn pass_record(
    s: &Stroke,
    candidate: Option<u64>,
    samples: usize,
    verdict: Option<&SlideVerdict>,
    width: Option<&SlideVerdict>,
    extent: &Option<CrackExtent>,
) -> PassRecord {
    PassRecord {
        id: s.id,
        candidate,
        start_mm: s.from,
        end_mm: s.to,
        samples,
        class: verdict.map(|v| v.name.clone()),
        confidence: verdict.map_or(0.0, |v| v.confidence),
        width_mm: width.map(|w| w.label),
        doubt: verdict.and_then(|v| v.doubt.as_ref()).map(PassDoubt::from),
        dip: extent.as_ref().map(|e| Dip {
            centre_mm: e.centre_mm,
            width_mm: e.width_mm,
            confidence: e.confidence,
        }),
        recording: s.recording.display().to_string(),
        attempts: s.attempts,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_slides_axis_places_points_along_it_both_ways() {
        let slide = Slide {
            candidates: vec![3],
            row: None,
            start_mm: [10.0, 20.0],
            end_mm: [13.0, 24.0],
            stroke_mm: 5.0,
            passes: 2,
            speed_mm_s: 4.6,
            duration_s: 2.2,
            sound_run_mm: None,
            shifted_mm: 0.0,
            clipped: false,
            moved_along_mm: 0.0,
        };
        let axis = Axis::of(&slide);
        assert!((axis.len - 5.0).abs() < 1e-12);
        assert_eq!(axis.u, [0.6, 0.8]);
        let p = axis.at(2.5);
        assert!((p[0] - 11.5).abs() < 1e-12 && (p[1] - 22.0).abs() < 1e-12);
        assert!((axis.along(p) - 2.5).abs() < 1e-12);
        // A point beside the axis is placed by its projection; one behind the start is negative.
        assert!((axis.along([11.5 + 0.8, 22.0 - 0.6]) - 2.5).abs() < 1e-12);
        assert!(axis.along([7.0, 16.0]) < 0.0);
        // A slide of no length still has an axis (its length is kept above zero).
        let still = Axis::of(&Slide {
            end_mm: slide.start_mm,
            ..slide
        });
        assert!(still.len > 0.0 && still.along([10.0, 20.0]) == 0.0);
    }
}
