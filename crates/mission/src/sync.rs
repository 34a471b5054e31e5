//! Passive clock synchronisation of a remote clock (the sensor board's, the arm controller's)
//! to the host's, from one-way timestamps only.
//!
//! Each message carries the remote clock's time `r` when it was sent and is stamped with the
//! host's time `l` when it arrives: `l = a·r + b + d` with an unknown, non-negative delay `d`.
//! Every point therefore lies on or above the true line `a·r + b`, and the best estimate of
//! that line under this constraint is the linear programme of Moon, Skelly and Towsley (1999),
//! the lower bound Olson's passive synchronisation (IROS 2010) also keeps: the line below all
//! points that minimises their summed distance to it. Its optimum is the edge of the points'
//! lower convex hull that spans their mean `r`. It estimates the offset and the drift (rate
//! error) together, needs no messages back, and is not pulled up by late packets: only the
//! fastest messages shape the hull.
//!
//! The estimator keeps the points of the last [`ClockSync::window_us`] of remote time (drift
//! changes slowly with temperature; a bounded window also bounds the work) and maps a remote
//! time to the host's as `a·r + b`: the arrival time of an instant message. Both of the
//! robot's streams (sensor, controller) are mapped the same way, so their common minimal
//! latency cancels when positions are interpolated at the sensor's samples.

use std::collections::VecDeque;

/// One remote clock's mapping to the host clock (see the [module docs](self)).
#[derive(Debug, Clone)]
pub struct ClockSync {
    points: VecDeque<(f64, f64)>,
    window_us: f64,
    /// The fitted line `(a, b)`, `None` until two distinct points are in.
    fit: Option<(f64, f64)>,
    dirty: bool,
}

/// The fitted relation of a remote clock to the host's.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ClockFit {
    /// Host µs per remote µs, minus one, in parts per million (the remote clock's drift seen from
    /// the host, sign flipped: a remote clock running fast gives a negative value).
    pub rate_ppm: f64,
    /// Host time at remote time zero, µs.
    pub offset_us: f64,
    /// Points in the window.
    pub points: usize,
}

impl ClockSync {
    /// An estimator keeping `window_us` of remote time (at least 1 s).
    pub fn new(window_us: f64) -> Self {
        ClockSync {
            points: VecDeque::new(),
            window_us: window_us.max(1e6),
            fit: None,
            dirty: false,
        }
    }

    /// Remote time kept, µs.
    pub fn window_us(&self) -> f64 {
        self.window_us
    }

    /// Adds a message sent at `remote_us` and received at `host_us`. Non-finite values and
    /// remote times going backwards by more than the window (a restarted remote clock) are
    /// handled: the former are ignored, the latter restart the estimate.
    pub fn add(&mut self, remote_us: f64, host_us: f64) {
        if !(remote_us.is_finite() && host_us.is_finite()) {
            return;
        }
        if let Some(&(last, _)) = self.points.back() {
            if remote_us + self.window_us < last {
                self.points.clear();
                self.fit = None;
            }
        }
        self.points.push_back((remote_us, host_us));
        while let Some(&(r, _)) = self.points.front() {
            if r + self.window_us < remote_us {
                self.points.pop_front();
            } else {
                break;
            }
        }
        self.dirty = true;
    }

    /// The host time of remote time `remote_us`, `None` before the first point.
    pub fn to_host(&mut self, remote_us: f64) -> Option<f64> {
        self.refit();
        match self.fit {
            Some((a, b)) => Some(a * remote_us + b),
            None => {
                let &(r, l) = self
                    .points
                    .iter()
                    .min_by(|x, y| (x.1 - x.0).total_cmp(&(y.1 - y.0)))?;
                Some(remote_us - r + l)
            }
        }
    }

    /// The current fit, `None` until two points with different remote times are in.
    pub fn fit(&mut self) -> Option<ClockFit> {
        self.refit();
        self.fit.map(|(a, b)| ClockFit {
            rate_ppm: (a - 1.0) * 1e6,
            offset_us: b,
            points: self.points.len(),
        })
    }

    fn refit(&mut self) {
        if !self.dirty {
            return;
        }
        self.dirty = false;
        self.fit = fit_lower_bound(&self.points);
    }
}

/// The LP optimum: the lower hull's edge spanning the mean remote time.
fn fit_lower_bound(points: &VecDeque<(f64, f64)>) -> Option<(f64, f64)> {
    if points.len() < 2 {
        return None;
    }
    // Work relative to the first point, so large absolute times keep their precision.
    let (r0, l0) = points[0];
    let mut pts: Vec<(f64, f64)> = points.iter().map(|&(r, l)| (r - r0, l - l0)).collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mean_r = pts.iter().map(|p| p.0).sum::<f64>() / pts.len() as f64;
    // Andrew's monotone chain, lower hull only.
    let mut hull: Vec<(f64, f64)> = Vec::with_capacity(pts.len());
    for p in pts {
        if let Some(&(lr, _)) = hull.last() {
            if lr == p.0 {
                // Same remote time: the earlier arrival (sorted first) is the lower point.
                continue;
            }
        }
        while hull.len() >= 2 {
            let (a, b) = (hull[hull.len() - 2], hull[hull.len() - 1]);
            let cross = (b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0);
            if cross <= 0.0 {
                hull.pop();
            } else {
                break;
            }
        }
        hull.push(p);
    }
    if hull.len() < 2 {
        return None;
    }
    let edge = hull
        .windows(2)
        .find(|w| w[0].0 <= mean_r && mean_r <= w[1].0)
        .unwrap_or(&hull[hull.len() - 2..]);
    let (p, q) = (edge[0], edge[1]);
    let a = (q.1 - p.1) / (q.0 - p.0);
    let b = p.1 - a * p.0;
    // Back to absolute times: l − l0 = a (r − r0) + b.
    Some((a, b + l0 - a * r0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A remote clock `offset` µs ahead and `drift_ppm` fast, messages every `period` µs with
    /// exponential delays of mean `mean_delay` µs above a minimum of 200 µs.
    fn run(
        offset: f64,
        drift_ppm: f64,
        period: f64,
        mean_delay: f64,
        seconds: f64,
    ) -> (ClockSync, f64) {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut sync = ClockSync::new(30e6);
        let mut host = 1.0e9;
        let end = host + seconds * 1e6;
        while host < end {
            let remote = (host - 1.0e9) * (1.0 + drift_ppm * 1e-6) + offset;
            let u: f64 = rng.random_range(1e-9..1.0);
            let delay = 200.0 - mean_delay * u.ln();
            sync.add(remote, host + delay);
            host += period;
        }
        (sync, end)
    }

    #[test]
    fn offset_and_drift_are_recovered_from_one_way_delays() {
        for (offset, drift) in [(0.0, 0.0), (3.7e6, 80.0), (-2.5e6, -150.0), (1.0e12, 40.0)] {
            let (mut sync, end) = run(offset, drift, 2500.0, 1500.0, 20.0);
            let fit = sync.fit().expect("a fit");
            // The host's rate per remote µs is 1/(1+drift): −drift ppm to first order.
            assert!(
                (fit.rate_ppm + drift).abs() < 5.0,
                "drift {drift}: fitted {fit:?}"
            );
            // Mapping error at the end: within the minimum delay plus a little.
            let remote_now = (end - 1.0e9) * (1.0 + drift * 1e-6) + offset;
            let mapped = sync.to_host(remote_now).expect("mapped");
            let err = mapped - end;
            assert!(
                err > -50.0 && err < 400.0,
                "offset {offset} drift {drift}: error {err} µs"
            );
        }
    }

    #[test]
    fn late_packets_do_not_pull_the_estimate() {
        // Heavy tail: mean delay 20 ms, yet the fastest messages keep the bound tight.
        let (mut sync, end) = run(5e5, 60.0, 10_000.0, 20_000.0, 30.0);
        let remote_now = (end - 1.0e9) * (1.0 + 60e-6) + 5e5;
        let err = sync.to_host(remote_now).expect("mapped") - end;
        assert!(err.abs() < 1500.0, "error {err} µs");
    }

    #[test]
    fn a_restarted_remote_clock_restarts_the_estimate_and_bad_values_are_ignored() {
        let mut sync = ClockSync::new(2e6);
        assert_eq!(sync.to_host(5.0), None);
        assert!(sync.fit().is_none());
        for i in 0..100 {
            sync.add(50e6 + f64::from(i) * 1e4, 1e9 + f64::from(i) * 1e4 + 300.0);
        }
        sync.add(f64::NAN, 1.0);
        sync.add(1.0, f64::INFINITY);
        let before = sync.to_host(51e6).expect("mapped");
        assert!((before - (1e9 + 1e6 + 300.0)).abs() < 1.0, "{before}");
        // The remote restarts from zero.
        for i in 0..100 {
            sync.add(f64::from(i) * 1e4, 2e9 + f64::from(i) * 1e4 + 300.0);
        }
        let after = sync.to_host(5e5).expect("mapped");
        assert!((after - (2e9 + 5e5 + 300.0)).abs() < 1.0, "{after}");
        // One point only: a pure offset.
        let mut one = ClockSync::new(1e6);
        one.add(10.0, 110.0);
        assert_eq!(one.to_host(20.0), Some(120.0));
    }
}
