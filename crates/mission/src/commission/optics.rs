//! The finger's optics from what the approach read (pure): the proximity fibre's distance
//! curve fitted (`crackbot_fibre::fit`), the channels' levels in contact, the deformation
//! channels' response to the finger's load, and their noise; and the check that no channel
//! sits at the ends of the ADC's range.

use crackbot_fibre::fit::{fit_approach, ApproachPoint};
use crackbot_fibre::ProximityFibre;
use serde::{Deserialize, Serialize};

use super::approach::ApproachReadings;
use super::error::CommissionError;

/// The channels' names, in sample order.
pub const CHANNELS: [&str; 4] = ["D1", "D2", "D3", "P"];
/// The ADC's full scale (10 bits).
pub const ADC_FULL: u32 = 1023;
/// A channel within this many counts of either end of the range reads as saturated.
const SATURATION_MARGIN: f64 = 1.0;
/// Largest share of a pass's samples at either end of the range, %.
const SATURATED_SHARE_PCT: f64 = 1.0;

/// What commissioning measured of a finger's optics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FingerOptics {
    /// The proximity fibre as missions use it: the fitted curve (`peak_mm`, `height_mm`) and the
    /// measured dark level; where it looks and its spot as before.
    pub fibre: ProximityFibre,
    /// Counts above dark at the fitted curve's peak over the bare reference plate.
    pub proximity_gain_counts: f64,
    /// Hover height at which P above dark falls to half its contact value, mm (read).
    pub half_height_mm: f64,
    /// RMS of the curve's fit, counts.
    pub fit_rms_counts: f64,
    /// D1, D2, D3, P in contact over bare plate, counts.
    pub contact_counts: [f64; 4],
    /// D1, D2, D3 in contact less held above the plate: their response to the finger's load.
    pub load_response_counts: [f64; 3],
    /// The white noise of D1, D2, D3, P, counts.
    pub noise_counts: [f64; 4],
}

/// The optics from the approach's readings; `prior` gives the fibre's offset and spot.
pub fn fit_optics(
    r: &ApproachReadings,
    prior: ProximityFibre,
) -> Result<FingerOptics, CommissionError> {
    let mut points = vec![ApproachPoint {
        hover_mm: 0.0,
        counts: r.contact[3],
    }];
    points.extend(r.staircase.iter().map(|&(h, p)| ApproachPoint {
        hover_mm: h,
        counts: p,
    }));
    let curve = fit_approach(&points, r.dark, prior)?;
    Ok(FingerOptics {
        fibre: curve.fibre,
        proximity_gain_counts: curve.gain_counts,
        half_height_mm: curve.half_height_mm,
        fit_rms_counts: curve.rms_counts,
        contact_counts: r.contact,
        load_response_counts: std::array::from_fn(|c| r.contact[c] - r.lifted[c]),
        noise_counts: r.noise,
    })
}

/// Refuses samples of which more than 1 % sit at either end of the ADC's range on any channel
/// (`plate` names where).
pub fn check_saturation(plate: &str, samples: &[[f64; 4]]) -> Result<(), CommissionError> {
    if samples.is_empty() {
        return Ok(());
    }
    let full = f64::from(ADC_FULL);
    for (c, name) in CHANNELS.iter().enumerate() {
        for end in [0.0, full] {
            let at = samples
                .iter()
                .filter(|v| (v[c] - end).abs() <= SATURATION_MARGIN)
                .count();
            let share = 100.0 * at as f64 / samples.len() as f64;
            if share > SATURATED_SHARE_PCT {
                return Err(CommissionError::Saturated {
                    plate: plate.to_string(),
                    channel: name,
                    counts: end,
                    share,
                    full: ADC_FULL,
                });
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn readings(f: &ProximityFibre, gain: f64) -> ApproachReadings {
        let p =
            |h: f64| f.dark_counts + gain * crackbot_fibre::intensity(f.height_mm + h, f.peak_mm);
        ApproachReadings {
            contact: [650.0, 430.0, 700.0, p(0.0)],
            noise: [1.4, 2.8, 5.2, 0.4],
            lifted: [620.0, 431.0, 734.0],
            staircase: super::super::approach::HOVERS_MM
                .iter()
                .map(|&h| (h, p(h)))
                .collect(),
            dark: f.dark_counts,
            range: [[600.0, 700.0]; 4],
        }
    }

    #[test]
    fn the_optics_are_read_off_the_approach() {
        let truth = ProximityFibre {
            peak_mm: 0.5,
            height_mm: 1.2,
            dark_counts: 240.0,
            ..ProximityFibre::default()
        };
        let o = fit_optics(&readings(&truth, 700.0), ProximityFibre::default()).unwrap();
        assert_eq!(o.load_response_counts, [30.0, -1.0, -34.0]);
        assert_eq!(o.fibre.dark_counts, 240.0);
        assert_eq!(o.fibre.offset_mm, ProximityFibre::default().offset_mm);
        let want = crackbot_fibre::fit::half_height_of(&truth);
        assert!((o.half_height_mm - want).abs() < 0.05, "{o:?} vs {want}");
    }

    #[test]
    fn a_saturated_channel_is_named() {
        let mut s = vec![[650.0, 430.0, 700.0, 500.0]; 100];
        assert!(check_saturation("flat", &s).is_ok());
        for v in s.iter_mut().take(5) {
            v[3] = 1023.0;
        }
        let e = check_saturation("crack-5mm", &s).unwrap_err().to_string();
        assert!(
            e.contains("crack-5mm") && e.contains("P read 1023") && e.contains("5.0 %"),
            "{e}"
        );
    }
}
