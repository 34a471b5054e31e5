//! What the front ends and the mission log see of the streams as they arrive: each sensor
//! sample with the finger's position along the stroke under way, and each arm state as a pose
//! on the host's clock. Shown and logged only; the passes' verdicts use their own positions,
//! interpolated when a stroke ends (`slide.rs`).
//!
//! Times never go back within a stream: each is mapped through the clock fit as it is then,
//! and a fit that moves (drift re-estimated under load) could put a later state before an
//! earlier one; such a time is held at the last one shown (`floor`).

use crackbot_link::Mode;

use super::arm::{newest_mapped, pose, position_at, Arm};
use super::sensor::Sensor;
use crate::inspect::geometry::{along, unit};
use crate::inspect::progress::{ArmPose, LiveSample};

/// Arm states (100 Hz) looked at to place a batch of samples: the last 0.3 s.
const RECENT_STATES: usize = 30;

/// The line the finger is moving along: a slide (finger down) or a raised pass of the print
/// check (no slide id).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Stroke {
    /// The slide's id on the link; `None` for a raised pass.
    pub(crate) slide: Option<u32>,
    /// Where the line starts, mm.
    pub(crate) start: [f64; 2],
    /// Its unit direction.
    pub(crate) dir: [f64; 2],
}

impl Stroke {
    /// The line from `a` towards `b`.
    pub(crate) fn new(slide: Option<u32>, a: [f64; 2], b: [f64; 2]) -> Self {
        Stroke {
            slide,
            start: a,
            dir: unit(a, b),
        }
    }

    /// Where a finger at `p` in `mode` is along this line, mm; `None` while a slide's finger is
    /// not yet (or no longer) in it.
    fn along(&self, p: [f64; 3], mode: Mode) -> Option<f64> {
        match self.slide {
            Some(id) if mode != (Mode::Sliding { id }) => None,
            _ => Some(along(self.start, self.dir, p)),
        }
    }
}

/// The sensor's samples from index `from` on, as shown, each placed on `stroke`.
pub(crate) fn live_samples(
    arm: &mut Arm,
    sensor: &mut Sensor,
    from: usize,
    stroke: Option<&Stroke>,
    floor: &mut f64,
) -> Vec<LiveSample> {
    let states = stroke
        .map(|_| newest_mapped(arm, RECENT_STATES))
        .unwrap_or_default();
    let (samples, sync) = (&sensor.samples, &mut sensor.sync);
    samples[from.min(samples.len())..]
        .iter()
        .map(|s| {
            let host_us = sync.to_host(s.device_us).unwrap_or(s.host_us);
            let along_mm = stroke.and_then(|st| {
                let (p, mode) = position_at(&states, host_us)?;
                st.along(p, mode)
            });
            *floor = floor.max(host_us / 1e6);
            LiveSample {
                t_s: *floor,
                raw: s.raw,
                slide: stroke
                    .and_then(|st| st.slide)
                    .filter(|_| along_mm.is_some()),
                along_mm,
            }
        })
        .collect()
}

/// The arm's states newer than controller time `after_us`, as poses on the host's clock.
pub(crate) fn new_poses(
    arm: &mut Arm,
    after_us: Option<u64>,
    stroke: Option<&Stroke>,
    floor: &mut f64,
) -> Vec<ArmPose> {
    let (states, sync) = (&arm.states, &mut arm.sync);
    let newer = states
        .iter()
        .rev()
        .take_while(|s| after_us.is_none_or(|a| s.state.controller_time_us > a))
        .collect::<Vec<_>>();
    newer
        .into_iter()
        .rev()
        .filter_map(|s| {
            let host = sync.to_host(s.state.controller_time_us as f64)?;
            let p = pose(&s.state);
            let along_mm = stroke.and_then(|st| st.along(p, s.state.mode));
            *floor = floor.max(host / 1e6);
            Some(ArmPose {
                t_s: *floor,
                controller_us: s.state.controller_time_us,
                pose_mm: p,
                slide: match s.state.mode {
                    Mode::Sliding { id } => Some(id),
                    _ => None,
                },
                along_mm,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_slide_places_the_finger_only_while_it_slides() {
        let s = Stroke::new(Some(7), [10.0, 0.0], [20.0, 0.0]);
        assert_eq!(
            s.along([12.5, 0.0, 0.0], Mode::Sliding { id: 7 }),
            Some(2.5)
        );
        assert_eq!(s.along([12.5, 0.0, 0.0], Mode::Sliding { id: 8 }), None);
        assert_eq!(s.along([9.0, 0.0, 5.0], Mode::Moving), None);
        let raised = Stroke::new(None, [0.0, 0.0], [0.0, -10.0]);
        assert_eq!(raised.along([0.0, -4.0, 2.0], Mode::Moving), Some(4.0));
    }
}
