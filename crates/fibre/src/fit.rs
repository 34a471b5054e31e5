//! The proximity fibre's distance curve fitted to a finger's own readings: the proximity
//! channel read at rest over bare plate, in contact and held at a staircase of heights above
//! it (`crackbot commission`'s approach), and high above it for the dark level.
//!
//! Over bare plate at hover height `h` the fibre is `height_mm + h` from the surface, so the
//! channel reads `dark + gain · intensity(height_mm + h, peak_mm)`. The fit takes `dark` as
//! measured, solves `gain` linearly for each `(peak_mm, height_mm)` and searches those two on a
//! grid refined three times. A fibre that sits beyond its curve's peak in contact (every finger
//! built like the authors') sees only the falling side, where `peak_mm`, `height_mm` and `gain`
//! trade off against one another; the curve itself over the heights measured is what is pinned
//! down, and [`FittedCurve::half_height_mm`] (the hover height at which the signal above dark
//! falls to half its contact value) is read off the fitted curve: a controller that holds the
//! finger no lower than 0.5 mm (the simulated one) never reads the authors' fibre at its half,
//! about 0.45 mm above contact.

use crate::{intensity, FibreError, ProximityFibre};

/// One reading of the approach: the proximity channel (counts, a median over the samples held
/// there) with the finger `hover_mm` above contact (0: in contact).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ApproachPoint {
    /// Height of the tip's lowest point above the surface, mm (0: in contact).
    pub hover_mm: f64,
    /// The proximity channel there, counts.
    pub counts: f64,
}

/// The fitted curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FittedCurve {
    /// The fibre with the fitted `peak_mm`, `height_mm` and the measured `dark_counts` (its
    /// `offset_mm` and `spot_mm` as given: the approach does not see them).
    pub fibre: ProximityFibre,
    /// Counts above dark at the curve's peak over this surface.
    pub gain_counts: f64,
    /// Counts above dark in contact, read.
    pub contact_counts: f64,
    /// Hover height at which the signal above dark falls to half its contact value, mm, on the
    /// fitted curve ([`half_height_of`]).
    pub half_height_mm: f64,
    /// RMS of the fit's residuals, counts.
    pub rms_counts: f64,
}

/// Fewest approach points a fit needs.
pub const MIN_POINTS: usize = 6;

/// Fits the curve to `points` (any order; one at `hover_mm` 0) with the dark level `dark`
/// (counts, read far above the surface); `prior` gives the fibre's offset and spot. Errors name
/// what the readings lack: too few points, no contact point, a signal that does not fall with
/// height, or one that never falls to half within the heights read.
pub fn fit_approach(
    points: &[ApproachPoint],
    dark: f64,
    prior: ProximityFibre,
) -> Result<FittedCurve, FibreError> {
    let bad = |what: String| FibreError::Approach { what };
    if points.len() < MIN_POINTS {
        return Err(bad(format!(
            "{} readings, at least {MIN_POINTS} needed",
            points.len()
        )));
    }
    let mut pts: Vec<ApproachPoint> = points.to_vec();
    pts.sort_by(|a, b| a.hover_mm.total_cmp(&b.hover_mm));
    if pts
        .iter()
        .any(|p| !p.hover_mm.is_finite() || !p.counts.is_finite())
        || !dark.is_finite()
    {
        return Err(bad("a reading that is not a number".into()));
    }
    if pts[0].hover_mm.abs() > 1e-9 {
        return Err(bad("no reading in contact (hover 0 mm)".into()));
    }
    let contact = pts[0].counts - dark;
    if contact <= 0.0 {
        return Err(bad(format!(
            "in contact the channel reads {:.1} counts, not above the dark level {dark:.1}: the fibre sees nothing",
            pts[0].counts
        )));
    }
    let last = pts[pts.len() - 1];
    if last.counts - dark > 0.5 * contact {
        return Err(bad(format!(
            "the signal never falls to half its contact value ({contact:.1} counts above dark) \
             within {:.1} mm: the curve's fall is not seen",
            last.hover_mm
        )));
    }
    let (peak_mm, height_mm, gain, rms) = search(&pts, dark);
    let fibre = ProximityFibre {
        peak_mm,
        height_mm,
        dark_counts: dark,
        ..prior
    };
    Ok(FittedCurve {
        fibre,
        gain_counts: gain,
        contact_counts: contact,
        half_height_mm: half_height_of(&fibre),
        rms_counts: rms,
    })
}

/// The gain that fits `(peak, height)` best, and the residuals' RMS.
fn gain_for(pts: &[ApproachPoint], dark: f64, peak: f64, height: f64) -> (f64, f64) {
    let (mut yi, mut ii) = (0.0, 0.0);
    for p in pts {
        let i = intensity(height + p.hover_mm, peak);
        yi += (p.counts - dark) * i;
        ii += i * i;
    }
    let g = if ii > 0.0 { yi / ii } else { 0.0 };
    let ss: f64 = pts
        .iter()
        .map(|p| (p.counts - dark - g * intensity(height + p.hover_mm, peak)).powi(2))
        .sum();
    (g, (ss / pts.len() as f64).sqrt())
}

/// Grid search of `(peak, height)` over 0.05–5 mm each, refined three times around the best.
fn search(pts: &[ApproachPoint], dark: f64) -> (f64, f64, f64, f64) {
    let (mut lo, mut hi) = ([0.05, 0.05], [5.0, 5.0]);
    let mut best = (f64::INFINITY, 1.0, 1.0, 0.0);
    for _ in 0..4 {
        const N: usize = 40;
        for i in 0..=N {
            for j in 0..=N {
                let peak = lo[0] + (hi[0] - lo[0]) * i as f64 / N as f64;
                let height = lo[1] + (hi[1] - lo[1]) * j as f64 / N as f64;
                let (g, rms) = gain_for(pts, dark, peak, height);
                if g > 0.0 && rms < best.0 {
                    best = (rms, peak, height, g);
                }
            }
        }
        let span = [(hi[0] - lo[0]) / 8.0, (hi[1] - lo[1]) / 8.0];
        lo = [(best.1 - span[0]).max(0.01), (best.2 - span[1]).max(0.01)];
        hi = [best.1 + span[0], best.2 + span[1]];
    }
    (best.1, best.2, best.3, best.0)
}

/// The hover height at which a fibre's signal above dark falls to half its contact value, mm
/// (bisection on its curve): what [`FittedCurve::half_height_mm`] measures.
pub fn half_height_of(fibre: &ProximityFibre) -> f64 {
    let target = 0.5 * intensity(fibre.height_mm, fibre.peak_mm);
    // Beyond the peak the curve falls monotonically; in front of it, the half lies beyond the
    // peak, once the signal has risen over it and fallen again.
    let (mut a, mut b) = ((fibre.peak_mm - fibre.height_mm).max(0.0), 100.0_f64);
    for _ in 0..100 {
        let m = 0.5 * (a + b);
        if intensity(fibre.height_mm + m, fibre.peak_mm) > target {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn approach(f: &ProximityFibre, gain: f64, noise: f64) -> Vec<ApproachPoint> {
        let heights = [
            0.0, 0.1, 0.2, 0.3, 0.45, 0.6, 0.8, 1.0, 1.3, 1.6, 2.0, 2.5, 3.0, 4.0,
        ];
        heights
            .iter()
            .enumerate()
            .map(|(k, &h)| ApproachPoint {
                hover_mm: h,
                counts: f.dark_counts
                    + gain * intensity(f.height_mm + h, f.peak_mm)
                    + noise * if k % 2 == 0 { 1.0 } else { -1.0 },
            })
            .collect()
    }

    #[test]
    fn a_curve_is_recovered_where_the_readings_pin_it() {
        for (peak, height, gain) in [(0.454, 1.026, 772.0), (0.6, 1.3, 600.0), (0.35, 0.8, 900.0)] {
            let truth = ProximityFibre {
                peak_mm: peak,
                height_mm: height,
                dark_counts: 230.0,
                ..ProximityFibre::default()
            };
            let pts = approach(&truth, gain, 0.3);
            let fit = fit_approach(&pts, 230.0, ProximityFibre::default()).unwrap();
            let want = half_height_of(&truth);
            assert!(
                (fit.half_height_mm - want).abs() < 0.05,
                "{fit:?} vs {want}"
            );
            // The fitted curve reads like the true one over the heights measured.
            for p in &pts {
                let f = 230.0
                    + fit.gain_counts
                        * intensity(fit.fibre.height_mm + p.hover_mm, fit.fibre.peak_mm);
                assert!((f - p.counts).abs() < 2.0, "{p:?}: fitted {f}");
            }
            assert!(fit.rms_counts < 1.0, "{fit:?}");
        }
    }

    #[test]
    fn readings_that_cannot_give_a_curve_are_named() {
        let f = ProximityFibre::default();
        let pts = approach(&f, 700.0, 0.0);
        let err =
            |pts: &[ApproachPoint], dark: f64| fit_approach(pts, dark, f).unwrap_err().to_string();
        assert!(err(&pts[..3], 215.0).contains("at least 6"));
        assert!(err(&pts[1..], 215.0).contains("no reading in contact"));
        assert!(err(&pts, 2000.0).contains("not above the dark level"));
        // Only the first few tenths of a millimetre: never half.
        let near: Vec<ApproachPoint> = [0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3]
            .iter()
            .map(|&h| ApproachPoint {
                hover_mm: h,
                counts: 215.0 + 700.0 * intensity(f.height_mm + h, f.peak_mm),
            })
            .collect();
        assert!(
            err(&near, 215.0).contains("never falls to half"),
            "{}",
            err(&near, 215.0)
        );
    }
}
