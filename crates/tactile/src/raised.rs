//! The print check over raised passes: one raised pass's ratios against the contact strokes
//! over a candidate ([`raised_ratio`]), and the ratio several passes decide by
//! ([`judged_ratio`]). The single-profile measures are [`crate::print_check`]'s.

use crate::print_check;
use crate::TactileError;

/// The print check's ratio of one raised pass (`raised`: proximity counts and positions on
/// the strokes' axis), the mean over the candidate's strokes (each a proximity channel and its
/// positions on the same axis) of [`print_check::print_ratio`]; a stroke the check cannot use
/// adds its error to `unusable`. `None` when no stroke gave a ratio.
pub fn raised_ratio(
    strokes: &[(Vec<f64>, Vec<f64>)],
    raised: (&[f64], &[f64]),
    dark: f64,
    unusable: &mut Vec<TactileError>,
) -> Option<RaisedRatio> {
    let (mut ratios, mut floors, mut levels) = (Vec::new(), Vec::new(), Vec::new());
    for (p, x) in strokes {
        match print_check::print_ratios((p, x), raised, dark) {
            Ok(r) => {
                ratios.extend(r.print);
                floors.extend(r.floor);
                levels.push(r.levels);
            }
            Err(e) => unusable.push(e),
        }
    }
    let level = |k: usize| mean(&levels.iter().map(|l| l[k]).collect::<Vec<_>>());
    Some(RaisedRatio {
        print: mean(&ratios)?,
        floor: mean(&floors),
        levels: [level(0)?, level(1)?],
    })
}

/// What one raised pass measured against the candidate's strokes (means over the strokes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RaisedRatio {
    /// [`print_check::print_ratio`].
    pub print: f64,
    /// [`print_check::floor_ratio`], the second estimate (`None` where no stroke gave one).
    pub floor: Option<f64>,
    /// [`print_check::PrintRatios::levels`]: the sound surface's level beside the line in
    /// contact and on the raised pass, counts.
    pub levels: [f64; 2],
}

/// The ratio raised passes decide by: the mean of their print ratios, or where the first was in
/// doubt, of each one's [`RaisedRatio::in_doubt`]; `None` without a pass.
pub fn judged_ratio(measured: &[RaisedRatio], in_doubt: bool) -> Option<f64> {
    let judged = |m: &RaisedRatio| if in_doubt { m.in_doubt() } else { m.print };
    mean(&measured.iter().map(judged).collect::<Vec<_>>())
}

/// The mean of `v`; `None` when it is empty.
fn mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

impl RaisedRatio {
    /// The estimate a ratio in doubt is judged by: the mean of the two, or the print ratio
    /// alone where there is no floor ratio.
    pub fn in_doubt(&self) -> f64 {
        self.floor.map_or(self.print, |f| 0.5 * (self.print + f))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passes_in_doubt_are_judged_by_both_estimates_and_others_by_the_print_ratio() {
        let pass = |print: f64, floor: Option<f64>| RaisedRatio {
            print,
            floor,
            levels: [450.0, 270.0],
        };
        let passes = [pass(0.86, Some(1.0)), pass(0.84, None)];
        // Not in doubt: the print ratios' mean.
        assert!((judged_ratio(&passes, false).unwrap() - 0.85).abs() < 1e-12);
        // In doubt: each pass's mean of the two (the print ratio where there is no floor ratio).
        assert!((judged_ratio(&passes, true).unwrap() - (0.93 + 0.84) / 2.0).abs() < 1e-12);
        assert_eq!(judged_ratio(&[], true), None);
    }
}
