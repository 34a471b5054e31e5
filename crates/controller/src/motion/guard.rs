//! What keeps a Cartesian arm safe, as pure checks: every target is checked before it is
//! published ([`TargetGuard`]: inside the box, under the speed and acceleration limits), and
//! every pose the arm reports is checked as it arrives ([`check_report`]: finite, in the
//! expected frame); a stream gone quiet, a pose drifting from its target, a flood of reports or
//! a contact force over the limit are faults ([`ArmFault`]) that stop the arm.

use crate::motion::path::distance;

/// The box and limits no published target may leave.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Envelope {
    /// Lower corner, mm in the surface frame `[x, y, z]`.
    pub min_mm: [f64; 3],
    /// Upper corner, mm.
    pub max_mm: [f64; 3],
    /// Fastest a target may move, mm/s.
    pub max_speed_mm_s: f64,
    /// Fastest a target's speed may change, mm/s².
    pub max_accel_mm_s2: f64,
}

/// Why the arm stopped on its own.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ArmFault {
    /// A target would have left the box (never published).
    #[error("target ({x:.2}, {y:.2}, {z:.2}) mm is outside the arm's box: not published")]
    OutsideBox {
        /// mm.
        x: f64,
        /// mm.
        y: f64,
        /// mm.
        z: f64,
    },
    /// A target would have moved too fast (never published).
    #[error("target step of {speed:.1} mm/s is over the limit {limit:.1} mm/s: not published")]
    OverSpeed {
        /// mm/s.
        speed: f64,
        /// mm/s.
        limit: f64,
    },
    /// A target would have changed speed too fast (never published).
    #[error(
        "target acceleration {accel:.0} mm/s² is over the limit {limit:.0} mm/s²: not published"
    )]
    OverAccel {
        /// mm/s².
        accel: f64,
        /// mm/s².
        limit: f64,
    },
    /// A target was not finite (never published).
    #[error("a target is not finite: not published")]
    TargetNotFinite,
    /// No pose from the arm for too long.
    #[error("no pose from the arm for {ms:.0} ms (limit {limit_ms:.0} ms)")]
    Stale {
        /// How long, ms.
        ms: f64,
        /// The limit, ms.
        limit_ms: f64,
    },
    /// The arm's pose is far from where it was sent.
    #[error("the arm is {mm:.1} mm from its target (limit {limit_mm:.1} mm)")]
    Diverged {
        /// mm.
        mm: f64,
        /// mm.
        limit_mm: f64,
    },
    /// The arm reported a pose that is not finite.
    #[error("the arm reported a pose that is not finite")]
    PoseNotFinite,
    /// The arm reported its pose in another frame.
    #[error("the arm reported its pose in frame {got:?}, expected {want:?}")]
    WrongFrame {
        /// The frame it named.
        got: String,
        /// The frame configured.
        want: String,
    },
    /// More pose reports than any arm sends.
    #[error("{count} pose reports in {ms:.0} ms: a flood (limit {limit} per period)")]
    Flood {
        /// Reports in one period.
        count: usize,
        /// The period, ms.
        ms: f64,
        /// The limit.
        limit: usize,
    },
    /// The measured contact force is over the limit.
    #[error("contact force {n:.2} N over the limit {limit_n:.2} N")]
    OverForce {
        /// N.
        n: f64,
        /// N.
        limit_n: f64,
    },
    /// The DDS side failed.
    #[error("DDS: {0}")]
    Dds(String),
}

impl ArmFault {
    /// The code the link's `Mode::Fault { code }` carries (the spec's table,
    /// `crates/controller/docs/ros2.md`).
    pub fn code(&self) -> u16 {
        match self {
            ArmFault::OutsideBox { .. }
            | ArmFault::OverSpeed { .. }
            | ArmFault::OverAccel { .. }
            | ArmFault::TargetNotFinite => 10,
            ArmFault::Stale { .. } => 11,
            ArmFault::Diverged { .. } => 12,
            ArmFault::PoseNotFinite | ArmFault::WrongFrame { .. } => 13,
            ArmFault::Flood { .. } => 14,
            ArmFault::OverForce { .. } => 15,
            ArmFault::Dds(_) => 16,
        }
    }
}

/// Checks each target against the envelope and the one before it.
#[derive(Debug, Clone)]
pub struct TargetGuard {
    envelope: Envelope,
    /// The last published target: time (s), point (mm), mean speed since the one before
    /// (mm/s) and that interval (s).
    last: Option<(f64, [f64; 3], f64, f64)>,
}

/// Slack on the speed limit for the timer's jitter (targets are sampled where the path is at
/// the moment of publishing, so a late tick takes a longer step in a longer time).
const SPEED_SLACK: f64 = 1.05;
/// Slack on the acceleration limit: finite differences of a jittery clock.
const ACCEL_SLACK: f64 = 2.0;

impl TargetGuard {
    /// A guard with nothing published yet.
    pub fn new(envelope: Envelope) -> Self {
        TargetGuard {
            envelope,
            last: None,
        }
    }

    /// The stream ended (a stop): the next target starts from rest.
    pub fn reset(&mut self) {
        self.last = None;
    }

    /// Admits the target `p` (mm) to be published at `t` s, or says why not.
    pub fn admit(&mut self, t: f64, p: [f64; 3]) -> Result<(), ArmFault> {
        let e = &self.envelope;
        if !p.iter().all(|v| v.is_finite()) || !t.is_finite() {
            return Err(ArmFault::TargetNotFinite);
        }
        if (0..3).any(|k| p[k] < e.min_mm[k] - 1e-9 || p[k] > e.max_mm[k] + 1e-9) {
            return Err(ArmFault::OutsideBox {
                x: p[0],
                y: p[1],
                z: p[2],
            });
        }
        let (mut v, mut dt_kept) = (0.0, 0.0);
        if let Some((t0, p0, v0, dt0)) = self.last {
            let dt = t - t0;
            dt_kept = dt;
            if dt > 0.0 {
                let step = distance(p, p0);
                v = step / dt;
                let limit = e.max_speed_mm_s * SPEED_SLACK;
                if v > limit {
                    return Err(ArmFault::OverSpeed {
                        speed: v,
                        limit: e.max_speed_mm_s,
                    });
                }
                // Mean speeds over two adjacent intervals differ by at most the acceleration
                // times half their summed length (a late tick and a quick one after it are
                // both fine).
                // (Right after the first target there is one interval only: no acceleration yet.)
                let accel = if dt0 > 0.0 {
                    (v - v0).abs() / ((dt + dt0) / 2.0)
                } else {
                    0.0
                };
                if accel > e.max_accel_mm_s2 * ACCEL_SLACK {
                    return Err(ArmFault::OverAccel {
                        accel,
                        limit: e.max_accel_mm_s2,
                    });
                }
            } else {
                (v, dt_kept) = (v0, dt0);
            }
        }
        self.last = Some((t, p, v, dt_kept));
        Ok(())
    }
}

/// Checks a pose the arm reported: finite, and in the frame configured.
pub fn check_report(frame: &str, want_frame: &str, p_mm: [f64; 3]) -> Result<(), ArmFault> {
    if frame != want_frame {
        return Err(ArmFault::WrongFrame {
            got: frame.chars().take(64).collect(),
            want: want_frame.to_string(),
        });
    }
    if !p_mm.iter().all(|v| v.is_finite()) {
        return Err(ArmFault::PoseNotFinite);
    }
    Ok(())
}

/// A fault when the arm's pose is further than `limit_mm` from its target.
pub fn divergence(measured: [f64; 3], target: [f64; 3], limit_mm: f64) -> Option<ArmFault> {
    let mm = distance(measured, target);
    (mm > limit_mm).then_some(ArmFault::Diverged { mm, limit_mm })
}

/// A fault when the last pose arrived more than `limit_s` ago.
pub fn staleness(since_last_s: f64, limit_s: f64) -> Option<ArmFault> {
    (since_last_s > limit_s).then_some(ArmFault::Stale {
        ms: since_last_s * 1e3,
        limit_ms: limit_s * 1e3,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn guard() -> TargetGuard {
        TargetGuard::new(Envelope {
            min_mm: [0.0, 0.0, -3.0],
            max_mm: [200.0, 100.0, 50.0],
            max_speed_mm_s: 100.0,
            max_accel_mm_s2: 500.0,
        })
    }

    #[test]
    fn targets_outside_the_box_or_too_fast_are_refused_and_named() {
        let mut g = guard();
        assert!(g.admit(0.0, [10.0, 10.0, 5.0]).is_ok());
        let e = g.admit(0.01, [10.0, 10.0, -3.5]).unwrap_err();
        assert!(matches!(e, ArmFault::OutsideBox { .. }), "{e}");
        assert!(e.to_string().contains("-3.50"), "{e}");
        assert_eq!(
            g.admit(0.01, [f64::NAN, 10.0, 5.0]),
            Err(ArmFault::TargetNotFinite)
        );
        // 5 mm in 10 ms: 500 mm/s.
        let e = g.admit(0.01, [15.0, 10.0, 5.0]).unwrap_err();
        assert!(matches!(e, ArmFault::OverSpeed { .. }), "{e}");
        // 20 mm/s over 10 ms, then 90 mm/s over the next 10 ms: 7000 mm/s².
        assert!(g.admit(0.01, [10.2, 10.0, 5.0]).is_ok());
        let e = g.admit(0.02, [11.1, 10.0, 5.0]).unwrap_err();
        assert!(matches!(e, ArmFault::OverAccel { .. }), "{e}");
        // A late tick (50 ms) then a quick one (1 ms) on a path at 500 mm/s²: fine.
        let mut late = guard();
        let at = |t: f64| [10.0 + 250.0 * t * t, 10.0, 5.0];
        for t in [0.0, 0.008, 0.016, 0.066, 0.067, 0.075] {
            assert_eq!(late.admit(t, at(t)), Ok(()), "at {t} s");
        }
        // A gentle step passes; after a reset the stream starts from rest again.
        assert!(g.admit(0.02, [10.45, 10.0, 5.0]).is_ok());
        g.reset();
        assert!(g.admit(5.0, [150.0, 90.0, 5.0]).is_ok());
    }

    proptest::proptest! {
        /// A path within the limits, published at ticks a busy host makes irregular (1 to
        /// 60 ms apart, late ones followed by quick catch-ups), is never refused.
        #[test]
        fn a_lawful_path_passes_at_any_tick_spacing(
            gaps in proptest::collection::vec(0.001f64..0.06, 50..400),
            speed in 1.0f64..100.0,
        ) {
            use crate::motion::path::{Leg, LegKind, Path};
            let legs = [
                Leg { to: [10.0, 10.0, 20.0], speed: 5.0, kind: LegKind::Vertical },
                Leg { to: [190.0, 90.0, 20.0], speed, kind: LegKind::Travel },
            ];
            let path = Path::new([10.0, 10.0, 5.0], &legs, 500.0);
            let mut g = guard();
            let mut t = 0.0;
            for dt in gaps {
                t += dt;
                proptest::prop_assert_eq!(g.admit(t, path.at(t).point), Ok(()), "at {} s", t);
            }
        }
    }

    #[test]
    fn reports_in_another_frame_or_not_finite_and_quiet_or_drifting_arms_are_faults() {
        assert!(check_report("base_link", "base_link", [1.0, 2.0, 3.0]).is_ok());
        let e = check_report("world", "base_link", [1.0, 2.0, 3.0]).unwrap_err();
        assert!(e.to_string().contains("\"world\""), "{e}");
        assert_eq!(
            check_report("base_link", "base_link", [1.0, f64::INFINITY, 3.0]),
            Err(ArmFault::PoseNotFinite)
        );
        assert!(staleness(0.1, 0.2).is_none());
        assert_eq!(staleness(0.3, 0.2).map(|f| f.code()), Some(11));
        assert!(divergence([0.0; 3], [3.0, 4.0, 0.0], 5.5).is_none());
        let f = divergence([0.0; 3], [3.0, 4.0, 0.0], 4.5).expect("diverged");
        assert!(f.to_string().contains("5.0 mm"), "{f}");
    }
}
