//! A commanded motion as straight legs in the surface frame, each from rest to rest at its
//! speed with a trapezoidal speed profile (accelerate, cruise, decelerate at the acceleration
//! limit), sampled at any time: what a Cartesian arm is sent, target by target.

/// What a leg is for (the link's mode and progress follow it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LegKind {
    /// Up or down to a height, in place.
    Vertical,
    /// Level travel with the finger lifted.
    Travel,
    /// The finger pressed on the plate, along a slide.
    Stroke,
}

/// One straight leg.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Leg {
    /// Where it ends, mm in the surface frame.
    pub to: [f64; 3],
    /// Cruise speed, mm/s (> 0).
    pub speed: f64,
    /// What it is for.
    pub kind: LegKind,
}

/// Where a path is at a time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathSample {
    /// The point, mm.
    pub point: [f64; 3],
    /// Its velocity, mm/s.
    pub velocity: [f64; 3],
    /// The leg it is on (the last one once done).
    pub leg: usize,
    /// Fraction of that leg's length done, 0–1.
    pub fraction: f64,
    /// Whether the whole path is done.
    pub done: bool,
}

#[derive(Debug, Clone, Copy)]
struct Timed {
    from: [f64; 3],
    leg: Leg,
    length: f64,
    /// Time spent accelerating (and decelerating), s.
    ramp: f64,
    /// Peak speed reached, mm/s (below the cruise speed on a short leg).
    peak: f64,
    duration: f64,
}

impl Timed {
    fn new(from: [f64; 3], leg: Leg, accel: f64) -> Timed {
        let length = distance(from, leg.to);
        // Reaching the cruise speed takes `speed / accel` s and `speed² / (2 accel)` mm each way;
        // a shorter leg peaks at `sqrt(length · accel)`.
        let peak = leg.speed.min((length * accel).sqrt());
        let ramp = if accel > 0.0 { peak / accel } else { 0.0 };
        let cruise = if peak > 0.0 {
            (length - peak * ramp) / peak
        } else {
            0.0
        };
        Timed {
            from,
            leg,
            length,
            ramp,
            peak,
            duration: 2.0 * ramp + cruise.max(0.0),
        }
    }

    /// Distance along the leg and speed at `t` s into it.
    fn along(&self, t: f64) -> (f64, f64) {
        let (a, r, d) = (self.peak / self.ramp.max(1e-12), self.ramp, self.duration);
        if self.length <= 0.0 || t >= d {
            return (self.length, 0.0);
        }
        if t < r {
            (0.5 * a * t * t, a * t)
        } else if t <= d - r {
            (0.5 * a * r * r + self.peak * (t - r), self.peak)
        } else {
            let left = d - t;
            (self.length - 0.5 * a * left * left, a * left)
        }
    }
}

/// The distance between two points, mm.
pub fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)).sqrt()
}

/// A path of legs from a start point, timed at an acceleration limit.
#[derive(Debug, Clone)]
pub struct Path {
    start: [f64; 3],
    legs: Vec<Timed>,
}

impl Path {
    /// The legs from `start`, each from rest to rest at acceleration `accel_mm_s2` (> 0).
    pub fn new(start: [f64; 3], legs: &[Leg], accel_mm_s2: f64) -> Path {
        let mut from = start;
        let mut timed = Vec::with_capacity(legs.len());
        for leg in legs {
            timed.push(Timed::new(from, *leg, accel_mm_s2));
            from = leg.to;
        }
        Path { start, legs: timed }
    }

    /// How long the whole path takes, s.
    pub fn duration(&self) -> f64 {
        self.legs.iter().map(|l| l.duration).sum()
    }

    /// The legs' kinds, in order.
    pub fn kinds(&self) -> impl Iterator<Item = LegKind> + '_ {
        self.legs.iter().map(|l| l.leg.kind)
    }

    /// Where the path ends.
    pub fn end(&self) -> [f64; 3] {
        self.legs.last().map_or(self.start, |l| l.leg.to)
    }

    /// Where the path is `t` s after it started.
    pub fn at(&self, t: f64) -> PathSample {
        let mut left = t.max(0.0);
        for (i, l) in self.legs.iter().enumerate() {
            if left < l.duration {
                let (s, v) = l.along(left);
                let u = if l.length > 0.0 { s / l.length } else { 1.0 };
                let dir = if l.length > 0.0 {
                    [0, 1, 2].map(|k| (l.leg.to[k] - l.from[k]) / l.length)
                } else {
                    [0.0; 3]
                };
                return PathSample {
                    point: [0, 1, 2].map(|k| l.from[k] + u * (l.leg.to[k] - l.from[k])),
                    velocity: dir.map(|d| d * v),
                    leg: i,
                    fraction: u,
                    done: false,
                };
            }
            left -= l.duration;
        }
        PathSample {
            point: self.end(),
            velocity: [0.0; 3],
            leg: self.legs.len().saturating_sub(1),
            fraction: 1.0,
            done: true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn leg(to: [f64; 3], speed: f64) -> Leg {
        Leg {
            to,
            speed,
            kind: LegKind::Travel,
        }
    }

    #[test]
    fn a_long_leg_cruises_at_its_speed_and_takes_the_time_it_should() {
        let p = Path::new([0.0; 3], &[leg([100.0, 0.0, 0.0], 50.0)], 500.0);
        // 0.1 s up, 0.1 s down (2.5 mm each), 95 mm at 50 mm/s.
        assert!(
            (p.duration() - (0.2 + 1.9)).abs() < 1e-12,
            "{}",
            p.duration()
        );
        let mid = p.at(1.0);
        assert!((mid.velocity[0] - 50.0).abs() < 1e-9 && (mid.point[0] - 47.5).abs() < 1e-9);
        let end = p.at(5.0);
        assert!(end.done && end.point == [100.0, 0.0, 0.0] && end.velocity == [0.0; 3]);
    }

    proptest! {
        /// Sampled at 125 Hz, no step is faster than the leg's speed or changes speed faster
        /// than the acceleration limit allows, and the path is continuous across its legs.
        #[test]
        fn sampled_targets_keep_the_speed_and_acceleration_limits(
            legs in prop::collection::vec(
                (prop::array::uniform3(-50.0f64..50.0), 0.5f64..60.0), 1..5),
            accel in 50.0f64..2000.0,
        ) {
            let legs: Vec<Leg> = legs.into_iter().map(|(to, s)| leg(to, s)).collect();
            let top = legs.iter().map(|l| l.speed).fold(0.0, f64::max);
            let p = Path::new([0.0; 3], &legs, accel);
            let dt = 1.0 / 125.0;
            let (mut last, mut last_v) = (p.at(0.0).point, 0.0);
            let mut t = dt;
            while t < p.duration() + 2.0 * dt {
                let s = p.at(t);
                let v = distance(last, s.point) / dt;
                prop_assert!(v <= top + 1e-6, "{} mm/s at {} s", v, t);
                // Two samples' mean speeds differ by at most accel·dt (plus rounding).
                prop_assert!((v - last_v).abs() <= accel * dt * 1.0001 + 1e-6, "{} → {} at {}", last_v, v, t);
                last = s.point;
                last_v = v;
                t += dt;
            }
            prop_assert_eq!(last, p.end());
        }
    }
}
