//! Frame times: a ring buffer of the intervals between frames, their median and 99th
//! percentile, and a histogram for the measurement file.

use std::collections::VecDeque;

use serde::Serialize;

/// The last frame intervals, s.
#[derive(Debug, Clone)]
pub struct FrameTimes {
    times: VecDeque<f64>,
    capacity: usize,
    total: u64,
}

/// A summary of the frame times.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameStats {
    /// Frames measured.
    pub frames: usize,
    /// Median interval, ms.
    pub median_ms: f64,
    /// 99th percentile, ms.
    pub p99_ms: f64,
    /// Longest, ms.
    pub max_ms: f64,
    /// Frames per second from the mean interval.
    pub mean_fps: f64,
    /// Histogram: (upper bound ms, count); the last bound is infinite (written as null).
    pub histogram: Vec<(Option<f64>, usize)>,
}

/// Upper bounds of the histogram's bins, ms.
pub const BINS_MS: [f64; 10] = [2.0, 4.0, 8.0, 12.0, 16.7, 20.0, 33.3, 50.0, 100.0, 250.0];

impl FrameTimes {
    /// Keeps the last `capacity` intervals.
    pub fn new(capacity: usize) -> Self {
        FrameTimes {
            times: VecDeque::with_capacity(capacity),
            capacity: capacity.max(1),
            total: 0,
        }
    }

    /// One frame took `dt_s`.
    pub fn push(&mut self, dt_s: f64) {
        if !dt_s.is_finite() || dt_s < 0.0 {
            return;
        }
        if self.times.len() == self.capacity {
            self.times.pop_front();
        }
        self.times.push_back(dt_s);
        self.total += 1;
    }

    /// Frames recorded in all.
    pub fn total(&self) -> u64 {
        self.total
    }

    /// Forgets everything (a measurement starts).
    pub fn clear(&mut self) {
        self.times.clear();
    }

    /// The summary, `None` before the first frame.
    pub fn stats(&self) -> Option<FrameStats> {
        if self.times.is_empty() {
            return None;
        }
        let mut ms: Vec<f64> = self.times.iter().map(|t| t * 1000.0).collect();
        ms.sort_by(f64::total_cmp);
        let q = |p: f64| ms[((ms.len() - 1) as f64 * p).round() as usize];
        let mean = ms.iter().sum::<f64>() / ms.len() as f64;
        let mut histogram: Vec<(Option<f64>, usize)> =
            BINS_MS.iter().map(|b| (Some(*b), 0)).collect();
        histogram.push((None, 0));
        for t in &ms {
            let i = BINS_MS.iter().position(|b| t <= b).unwrap_or(BINS_MS.len());
            histogram[i].1 += 1;
        }
        Some(FrameStats {
            frames: ms.len(),
            median_ms: q(0.5),
            p99_ms: q(0.99),
            max_ms: ms[ms.len() - 1],
            mean_fps: if mean > 0.0 { 1000.0 / mean } else { 0.0 },
            histogram,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stats_of_known_intervals() {
        let mut f = FrameTimes::new(1000);
        for i in 0..100 {
            f.push(if i == 99 { 0.1 } else { 0.010 });
        }
        let s = f.stats().unwrap();
        assert_eq!(s.frames, 100);
        assert!((s.median_ms - 10.0).abs() < 1e-9);
        assert!((s.max_ms - 100.0).abs() < 1e-9);
        assert_eq!(s.histogram.iter().map(|b| b.1).sum::<usize>(), 100);
        assert_eq!(s.histogram[3], (Some(12.0), 99));
        assert!((s.mean_fps - 1000.0 / 10.9).abs() < 1e-6);
    }

    #[test]
    fn the_ring_keeps_the_last() {
        let mut f = FrameTimes::new(3);
        for t in [1.0, 2.0, 3.0, 4.0] {
            f.push(t);
        }
        f.push(f64::NAN);
        let s = f.stats().unwrap();
        assert_eq!(s.frames, 3);
        assert_eq!(f.total(), 4);
        assert!((s.median_ms - 3000.0).abs() < 1e-9);
    }
}
