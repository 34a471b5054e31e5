//! Guarded touches by the ROS 2 arm, for registering the plate: from a point above the plate,
//! the finger moves along the approach direction at the approach speed until the arm meets the
//! plate (the contact force over 1 N when the arm reports a wrench, else the arm held back 1 mm
//! behind its target), records where it stopped, and goes back up.
//!
//! Everything here is in the arm's base frame (mm inside, m at the edges): the plate's frame is
//! what is being found.

use std::time::{Duration, Instant};

use super::config::Ros2Config;
use super::dds::{endpoints, publish_target, take_force, take_poses, Endpoints, Ros2Error};
use crate::motion::frame::SurfaceFrame;
use crate::motion::path::{distance, Leg, LegKind, Path};

/// The arm held back this far behind its target along the approach is a contact, mm.
const CONTACT_LAG_MM: f64 = 1.0;
/// A contact force over this is a contact, N.
const CONTACT_FORCE_N: f64 = 1.0;
/// No contact within this far of the start is an error, mm.
const MAX_TRAVEL_MM: f64 = 100.0;
/// How long to wait for the arm's first pose.
const FIRST_POSE: Duration = Duration::from_secs(10);

/// One tick's view of the arm.
struct Link<'a> {
    e: &'a Endpoints,
    config: &'a Ros2Config,
    base: SurfaceFrame,
    pose: Option<[f64; 3]>,
    last_heard: Instant,
}

impl Link<'_> {
    /// Takes what arrived; `Err` on a broken pose or a silent arm.
    fn listen(&mut self) -> Result<Option<f64>, Ros2Error> {
        let (_, newest) = take_poses(self.e, self.config, &self.base);
        match newest {
            Some(Ok(p)) => {
                self.pose = Some(p);
                self.last_heard = Instant::now();
            }
            Some(Err(f)) => return Err(Ros2Error::Arm(f)),
            None => {}
        }
        let limit = self.config.safety.stale_after_ms / 1e3;
        if self.pose.is_some() && self.last_heard.elapsed().as_secs_f64() > limit {
            return Err(Ros2Error::Arm(crate::motion::guard::ArmFault::Stale {
                ms: self.last_heard.elapsed().as_secs_f64() * 1e3,
                limit_ms: limit * 1e3,
            }));
        }
        Ok(take_force(self.e))
    }

    fn period(&self) -> Duration {
        Duration::from_secs_f64(1.0 / self.config.target.rate_hz)
    }

    /// Streams `path` until it is done and the arm is within 0.5 mm of its end.
    fn follow(&mut self, path: &Path) -> Result<(), Ros2Error> {
        let start = Instant::now();
        let end = path.end();
        loop {
            self.listen()?;
            let s = path.at(start.elapsed().as_secs_f64());
            publish_target(self.e, self.config, &self.base, s.point)?;
            let close = self.pose.is_some_and(|p| distance(p, end) < 0.5);
            if s.done && close {
                return Ok(());
            }
            if start.elapsed().as_secs_f64() > path.duration() + 5.0 {
                return Err(Ros2Error::Touch(format!(
                    "the arm did not reach ({:.1}, {:.1}, {:.1}) mm",
                    end[0], end[1], end[2]
                )));
            }
            std::thread::sleep(self.period());
        }
    }

    /// Moves along `dir` from `from` until the arm meets something; returns where it stopped.
    fn descend(&mut self, from: [f64; 3], dir: [f64; 3]) -> Result<[f64; 3], Ros2Error> {
        let speed = self.config.motion.approach_speed_mm_s;
        let start = Instant::now();
        loop {
            let force = self.listen()?;
            let travelled = speed * start.elapsed().as_secs_f64();
            let target = [0, 1, 2].map(|k| from[k] + dir[k] * travelled);
            if let Some(p) = self.pose {
                let lag: f64 = (0..3).map(|k| (target[k] - p[k]) * dir[k]).sum();
                // With a wrench, its force says contact; without, the arm held back behind its
                // target (a starved arm driver lags in free air too, so lag is the fallback).
                let touched = if self.config.wrench.topic.is_empty() {
                    lag > CONTACT_LAG_MM
                } else {
                    force.is_some_and(|f| f > CONTACT_FORCE_N)
                };
                if touched {
                    return self.settle(p);
                }
            }
            if travelled > MAX_TRAVEL_MM {
                return Err(Ros2Error::Touch(format!(
                    "no contact within {MAX_TRAVEL_MM} mm of ({:.1}, {:.1}, {:.1}) mm",
                    from[0], from[1], from[2]
                )));
            }
            publish_target(self.e, self.config, &self.base, target)?;
            std::thread::sleep(self.period());
        }
    }
}

impl Link<'_> {
    /// Holds the arm where it met the plate for 100 ms and returns where it then is (the pose
    /// that arrived at the contact may be a period old).
    fn settle(&mut self, at: [f64; 3]) -> Result<[f64; 3], Ros2Error> {
        let until = Instant::now() + Duration::from_millis(100);
        while Instant::now() < until {
            publish_target(self.e, self.config, &self.base, at)?;
            std::thread::sleep(self.period());
            self.listen()?;
        }
        Ok(self.pose.unwrap_or(at))
    }
}

fn travel(config: &Ros2Config, from: [f64; 3], to: [f64; 3]) -> Path {
    let leg = Leg {
        to,
        speed: config.motion.travel_speed_mm_s,
        kind: LegKind::Travel,
    };
    Path::new(from, &[leg], config.motion.max_accel_mm_s2)
}

/// Touches the plate from each of `starts` (m, base frame) moving along `approach`; returns
/// the points where the arm met it (m, base frame).
pub fn guarded_touches(
    config: &Ros2Config,
    starts: &[[f64; 3]],
    approach: [f64; 3],
) -> Result<Vec<[f64; 3]>, Ros2Error> {
    let norm = approach.iter().map(|v| v * v).sum::<f64>().sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        return Err(Ros2Error::Touch(
            "the approach direction has no length".into(),
        ));
    }
    let dir = approach.map(|v| v / norm);
    let e = endpoints(config)?;
    let mut link = Link {
        e: &e,
        config,
        base: SurfaceFrame::default(),
        pose: None,
        last_heard: Instant::now(),
    };
    let waiting = Instant::now();
    while link.pose.is_none() {
        link.listen()?;
        if waiting.elapsed() > FIRST_POSE {
            return Err(Ros2Error::Touch(format!(
                "no pose from the arm in {} s: is it publishing on {}?",
                FIRST_POSE.as_secs(),
                config.pose.topic
            )));
        }
        std::thread::sleep(link.period());
    }
    let mut found = Vec::with_capacity(starts.len());
    for (i, s) in starts.iter().enumerate() {
        let above = s.map(|v| v * 1e3);
        let here = link.pose.unwrap_or(above);
        link.follow(&travel(config, here, above))?;
        let hit = link.descend(above, dir)?;
        tracing::info!(
            "touch {}: the plate at ({:.2}, {:.2}, {:.2}) mm",
            i + 1,
            hit[0],
            hit[1],
            hit[2]
        );
        found.push(hit.map(|v| v * 1e-3));
        link.follow(&travel(config, hit, above))?;
    }
    Ok(found)
}
