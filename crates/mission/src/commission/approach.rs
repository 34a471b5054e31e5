//! The finger's optics read on the rig over bare plate: a slow slide in contact (the channels'
//! resting levels and noise), the finger held at a staircase of heights above the plate (the
//! proximity fibre's distance curve, the deformation channels unloaded) and far above it (the
//! proximity channel's dark level).

use crackbot_dsp::median;

use crate::inspect::rig::context::Rig;
use crate::inspect::rig::feel::Feel;
use crate::MissionError;

/// Heights of the staircase above contact, mm (from the lowest a controller holds the finger
/// above the plate, `crackbot-controller`'s 0.5 mm).
pub const HOVERS_MM: [f64; 12] = [0.5, 0.6, 0.8, 1.0, 1.3, 1.6, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0];
/// Where the proximity channel reads its dark level, mm above the plate.
pub const DARK_HOVER_MM: f64 = 40.0;
/// Length of the contact slide and of each held pass, mm.
const PASS_MM: f64 = 6.0;
/// Speed of the held passes, mm/s.
const HOVER_SPEED_MM_S: f64 = 4.0;
/// Fewest samples a held pass must give.
const MIN_HELD_SAMPLES: usize = 20;

/// What the approach read, counts.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ApproachReadings {
    /// In contact, sliding slowly: the median of D1, D2, D3, P.
    pub contact: [f64; 4],
    /// The white noise of each channel in contact (the spread of sample-to-sample steps / √2).
    pub noise: [f64; 4],
    /// The medians of D1, D2, D3 held above the plate (the finger unloaded), at the highest step.
    pub lifted: [f64; 3],
    /// `(height above contact, median P)` of each step of the staircase.
    pub staircase: Vec<(f64, f64)>,
    /// The median P far above the plate.
    pub dark: f64,
    /// The lowest and highest count each channel read during the approach.
    pub range: [[f64; 2]; 4],
}

/// The white noise of `x`: the standard deviation of its steps over √2 (drift and slow
/// features cancel out of the steps).
fn step_noise(x: &[f64]) -> f64 {
    let d: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
    if d.len() < 2 {
        return f64::NAN;
    }
    let m = d.iter().sum::<f64>() / d.len() as f64;
    (d.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (d.len() - 1) as f64).sqrt()
        / std::f64::consts::SQRT_2
}

/// The lowest and highest count of each channel in `samples`.
fn range_of(samples: &[[f64; 4]]) -> [[f64; 2]; 4] {
    let mut range = [[f64::INFINITY, f64::NEG_INFINITY]; 4];
    for v in samples {
        for c in 0..4 {
            range[c] = [range[c][0].min(v[c]), range[c][1].max(v[c])];
        }
    }
    range
}

/// Reads the optics over bare plate from `at` (mm, the plate frame) along +x; the readings
/// and every sample read (for the saturation check).
pub(crate) fn approach(
    rig: &mut Rig<'_>,
    at: [f64; 2],
    speed_mm_s: f64,
    feel: &mut Feel<'_>,
) -> Result<(ApproachReadings, Vec<[f64; 4]>), MissionError> {
    let end = [at[0] + PASS_MM, at[1]];
    let ((samples, _), _) = rig.slide_and_record(1, (at, end), speed_mm_s, 1, feel)?;
    enough(&samples, "the approach's slide in contact")?;
    let channel = |s: &[[f64; 4]], c: usize| s.iter().map(|v| v[c]).collect::<Vec<f64>>();
    let contact = std::array::from_fn(|c| median(&mut channel(&samples, c)));
    let noise = std::array::from_fn(|c| step_noise(&channel(&samples, c)));
    let mut all = samples;
    let mut staircase = Vec::new();
    let mut lifted = [f64::NAN; 3];
    // The slide left the arm over `end`: each held pass runs back over the same line.
    let (mut a, mut b) = (end, at);
    for &h in &HOVERS_MM {
        let held = held_pass(rig, (a, b), h)?;
        staircase.push((h, median(&mut channel(&held, 3))));
        lifted = std::array::from_fn(|c| median(&mut channel(&held, c)));
        all.extend(held);
        std::mem::swap(&mut a, &mut b);
    }
    let far = held_pass(rig, (a, b), DARK_HOVER_MM)?;
    let dark = median(&mut channel(&far, 3));
    all.extend(far);
    let readings = ApproachReadings {
        contact,
        noise,
        lifted,
        staircase,
        dark,
        range: range_of(&all),
    };
    Ok((readings, all))
}

/// Refuses a pass of fewer than [`MIN_HELD_SAMPLES`] samples (`what` names it).
fn enough(samples: &[[f64; 4]], what: &str) -> Result<(), MissionError> {
    if samples.len() < MIN_HELD_SAMPLES {
        return Err(MissionError::Refused {
            what: what.to_string(),
            reason: format!("{} samples read, {MIN_HELD_SAMPLES} needed", samples.len()),
        });
    }
    Ok(())
}

/// The samples of a pass from `a` to `b` held `h` mm above the plate.
fn held_pass(
    rig: &mut Rig<'_>,
    (a, b): ([f64; 2], [f64; 2]),
    h: f64,
) -> Result<Vec<[f64; 4]>, MissionError> {
    let ((held, _), _) = rig.hover_and_record(a, b, h, HOVER_SPEED_MM_S, None)?;
    enough(
        &held,
        &format!("the approach's pass held {h} mm above the plate"),
    )?;
    Ok(held)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_noise_of_steps_ignores_a_slope() {
        // ±1 alternating on a ramp: steps of ±2 around the slope, σ 2 / √2 · (n/(n−1))^½.
        let x: Vec<f64> = (0..1000)
            .map(|i| 0.5 * f64::from(i) + if i % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        assert!(
            (step_noise(&x) - 2.0_f64.sqrt()).abs() < 0.01,
            "{}",
            step_noise(&x)
        );
        assert!(step_noise(&[1.0]).is_nan());
        assert_eq!(
            range_of(&[[1.0, 2.0, 3.0, 4.0], [0.0, 5.0, 3.0, 9.0]])[3],
            [4.0, 9.0]
        );
        assert!(enough(&[[0.0; 4]; 3], "a short pass").is_err());
    }
}
