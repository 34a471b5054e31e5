//! What the finger feels while a stroke is still under way: the deployed models' running
//! verdict, for the front ends ([`Progress::Feeling`](crate::inspect::Progress::Feeling)). The pass's verdict is still taken when
//! the stroke ends, from positions interpolated at every sample
//! (the touch step's `classify`); this one uses the arm's latest state, is only shown, and
//! never decides anything.

use std::time::{Duration, Instant};

use crackbot_tactile::model::TactileModel;
use crackbot_tactile::online::OnlineClassifier;

use crackbot_tactile::online::RunningVerdict;

use super::arm::pose;
use super::sensor::TimedSample;
use crate::inspect::geometry::{along, unit};
use crate::inspect::progress::Feeling;
use crate::MissionError;

/// How often a running verdict is shown.
const SHOW_FEELING_EVERY: Duration = Duration::from_millis(100);

/// Both deployed models fed sample by sample during a stroke.
pub(crate) struct Feel<'m> {
    recognition: OnlineClassifier<'m>,
    width: OnlineClassifier<'m>,
    /// The stroke under way: its id, start, unit direction and direction column.
    stroke: Option<(u32, [f64; 2], [f64; 2], u8)>,
    /// Sensor samples (index into the mission's) looked at so far.
    seen: usize,
    last: (Option<RunningVerdict>, Option<RunningVerdict>),
    shown_at: Instant,
}

impl<'m> Feel<'m> {
    pub(crate) fn new(
        recognition: &'m TactileModel,
        width: &'m TactileModel,
    ) -> Result<Self, MissionError> {
        Ok(Feel {
            recognition: OnlineClassifier::new(recognition)?,
            width: OnlineClassifier::new(width)?,
            stroke: None,
            seen: 0,
            last: (None, None),
            shown_at: Instant::now(),
        })
    }

    /// A stroke `id` from `a` to `b` (direction column `dir`) starts; sensor samples from index
    /// `first_sample` on are its candidates.
    pub(crate) fn begin(&mut self, id: u32, (a, b): ([f64; 2], [f64; 2]), dir: u8, first: usize) {
        self.recognition.reset();
        self.width.reset();
        self.stroke = Some((id, a, unit(a, b), dir));
        self.seen = first;
        self.last = (None, None);
    }

    /// Feeds the samples that arrived since the last call while the arm, by its latest state,
    /// was down in the stroke; returns the feeling to show every [`SHOW_FEELING_EVERY`].
    pub(crate) fn update(
        &mut self,
        samples: &[TimedSample],
        latest: Option<&crackbot_link::State>,
    ) -> Result<Option<Feeling>, MissionError> {
        let Some((id, a, u, dir)) = self.stroke else {
            return Ok(None);
        };
        let new = samples.get(self.seen..).unwrap_or_default();
        self.seen = samples.len();
        let down = latest.filter(|s| {
            s.mode == crackbot_link::Mode::Sliding { id } && f64::from(s.pose.z_mm) < 0.5
        });
        let Some(state) = down else {
            return Ok(None);
        };
        let along_mm = along(a, u, pose(state));
        for s in new {
            let raw = s.raw.map(f64::from);
            if let Some(v) = self.recognition.push(raw, dir, along_mm)? {
                self.last.0 = Some(v);
            }
            if let Some(v) = self.width.push(raw, dir, along_mm)? {
                self.last.1 = Some(v);
            }
        }
        let Some(r) = self.last.0.as_ref() else {
            return Ok(None);
        };
        if self.shown_at.elapsed() < SHOW_FEELING_EVERY {
            return Ok(None);
        }
        self.shown_at = Instant::now();
        let name = |m: &TactileModel, c: u32| m.header.classes.get(c as usize).cloned();
        Ok(Some(Feeling {
            slide: id,
            class: name(self.recognition.model(), r.class).unwrap_or_else(|| r.class.to_string()),
            confidence: r.confidence,
            width_mm: self.last.1.as_ref().and_then(|w| {
                let labels = &self.width.model().header.labels;
                labels.get(w.class as usize).copied()
            }),
            windows: r.windows,
            along_mm,
        }))
    }
}
