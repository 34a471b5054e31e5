//! Min/max decimation of a time series to a fixed number of columns: each column of the plot
//! keeps its lowest and its highest sample (in time order), so a minute of 400 Hz data draws as
//! about two points per pixel column and no spike disappears.

/// The samples of `points` (time-sorted `(t, y)`) with `t0 <= t < t1`, reduced to at most two
/// points per column of `columns` equal columns of `[t0, t1)`: the minimum and the maximum of
/// the column, in the order they occur. Columns with no sample give nothing. With fewer
/// samples than `2 * columns`, every sample in range is kept.
pub fn min_max<I>(points: I, t0: f64, t1: f64, columns: usize) -> Vec<[f64; 2]>
where
    I: IntoIterator<Item = [f64; 2]>,
{
    let mut out = Vec::with_capacity(2 * columns.max(1));
    if columns == 0 || !t0.is_finite() || !t1.is_finite() || t1 <= t0 {
        return out;
    }
    let scale = columns as f64 / (t1 - t0);
    // The column being filled: its index, first sample, min and max (with their order).
    let mut current: Option<(usize, [f64; 2], [f64; 2])> = None;
    let flush = |out: &mut Vec<[f64; 2]>, c: &(usize, [f64; 2], [f64; 2])| {
        let (_, lo, hi) = *c;
        if lo == hi {
            out.push(lo);
        } else if lo[0] <= hi[0] {
            out.push(lo);
            out.push(hi);
        } else {
            out.push(hi);
            out.push(lo);
        }
    };
    for p in points {
        if !(p[0] >= t0 && p[0] < t1) || p[1].is_nan() {
            continue;
        }
        let col = (((p[0] - t0) * scale) as usize).min(columns - 1);
        match &mut current {
            Some(c) if c.0 == col => {
                if p[1] < c.1[1] {
                    c.1 = p;
                }
                if p[1] > c.2[1] {
                    c.2 = p;
                }
            }
            _ => {
                if let Some(c) = current.take() {
                    flush(&mut out, &c);
                }
                current = Some((col, p, p));
            }
        }
    }
    if let Some(c) = current {
        flush(&mut out, &c);
    }
    out
}

/// The index range of a time-sorted series whose times fall in `[t0, t1)`, by binary search
/// (`time` reads a sample's time).
pub fn visible_range<T>(
    series: &std::collections::VecDeque<T>,
    t0: f64,
    t1: f64,
    time: impl Fn(&T) -> f64,
) -> std::ops::Range<usize> {
    let start = series.partition_point(|s| time(s) < t0);
    let end = series.partition_point(|s| time(s) < t1).max(start);
    start..end
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn brute(points: &[[f64; 2]], t0: f64, t1: f64, columns: usize) -> Vec<(f64, f64)> {
        // (min, max) per non-empty column, by brute force.
        let mut cols: Vec<Option<(f64, f64)>> = vec![None; columns];
        for p in points {
            if p[0] >= t0 && p[0] < t1 {
                let c = (((p[0] - t0) / (t1 - t0) * columns as f64) as usize).min(columns - 1);
                let e = cols[c].get_or_insert((p[1], p[1]));
                e.0 = e.0.min(p[1]);
                e.1 = e.1.max(p[1]);
            }
        }
        cols.into_iter().flatten().collect()
    }

    proptest! {
        #[test]
        fn keeps_each_columns_extremes_in_time_order(
            mut ys in proptest::collection::vec(-1000.0f64..1000.0, 0..600),
            columns in 1usize..80,
            t0 in -2.0f64..1.0,
            span in 0.1f64..3.0,
        ) {
            let points: Vec<[f64; 2]> =
                ys.drain(..).enumerate().map(|(i, y)| [i as f64 / 200.0, y]).collect();
            let t1 = t0 + span;
            let out = min_max(points.iter().copied(), t0, t1, columns);
            prop_assert!(out.len() <= 2 * columns);
            prop_assert!(out.windows(2).all(|w| w[0][0] <= w[1][0]), "time order");
            // Every point out is a point in.
            for p in &out {
                prop_assert!(points.contains(p));
            }
            // Per column: the same min and max as brute force.
            let want = brute(&points, t0, t1, columns);
            let mut got: Vec<(f64, f64)> = Vec::new();
            let mut last_col = usize::MAX;
            for p in &out {
                let c = (((p[0] - t0) / (t1 - t0) * columns as f64) as usize).min(columns - 1);
                if c != last_col {
                    got.push((p[1], p[1]));
                    last_col = c;
                } else {
                    let e = got.last_mut().unwrap();
                    e.0 = e.0.min(p[1]);
                    e.1 = e.1.max(p[1]);
                }
            }
            prop_assert_eq!(got, want);
        }
    }

    #[test]
    fn a_minute_of_400_hz_becomes_two_points_per_column() {
        let points = (0..24_000).map(|i| [i as f64 / 400.0, (i as f64 * 0.37).sin()]);
        let out = min_max(points, 0.0, 60.0, 800);
        assert_eq!(out.len(), 1600);
    }

    #[test]
    fn a_spike_survives() {
        let mut points: Vec<[f64; 2]> = (0..24_000).map(|i| [i as f64 / 400.0, 0.0]).collect();
        points[12_345][1] = 99.0;
        let out = min_max(points, 0.0, 60.0, 100);
        assert!(out.iter().any(|p| p[1] == 99.0));
    }

    #[test]
    fn empty_or_degenerate_ranges_give_nothing() {
        let points = [[0.0, 1.0], [1.0, 2.0]];
        assert!(min_max(points, 1.0, 1.0, 10).is_empty());
        assert!(min_max(points, 0.0, 2.0, 0).is_empty());
        assert!(min_max(points, f64::NAN, 2.0, 10).is_empty());
    }

    #[test]
    fn visible_range_finds_the_window() {
        let s: std::collections::VecDeque<f64> = (0..100).map(|i| i as f64).collect();
        assert_eq!(visible_range(&s, 10.0, 20.0, |x| *x), 10..20);
        assert_eq!(visible_range(&s, 200.0, 300.0, |x| *x), 100..100);
        assert_eq!(visible_range(&s, 20.0, 10.0, |x| *x), 20..20);
    }
}
