//! The print check step: a candidate the contact strokes read as a crack is passed over again
//! with the finger raised, and the share of its proximity dip kept there tells a print (ink
//! darkens the fibre alike at every height) from a crack ([`print_check`]). One guarded raised
//! pass; made again higher where the surface at the line stands above the plate; more passes,
//! back and forth, where the first ratio lies near the threshold.

use std::path::Path;

use crackbot_planner::{Planner, RaisedPass, Workspace};
use crackbot_tactile::raised::{judged_ratio, raised_ratio, RaisedRatio};

mod settings;

pub use settings::{
    print_check_height, PrintCheckConfig, MAX_SURFACE_RISE_MM, PRINT_CHECK_HEIGHT_MM,
    PRINT_CHECK_OVERRUN_MM, PRINT_CHECK_PASSES_IN_DOUBT, PRINT_CHECK_SPEED_MM_S, PRINT_RATIO_DOUBT,
    PRINT_RATIO_SETTLED, RAISED_PASS_CLEAR_MM, RAISED_PASS_GUARD_COUNTS, SURFACE_RISE_TOLERANCE_MM,
};

use super::felt::Felt;
use super::touch::{Strokes, Touched};
use crate::inspect::doubts::CrackDoubt;
use crate::inspect::geometry::unit;
use crate::inspect::rig::context::Rig;
use crate::inspect::rig::hover::Obstruction;
use crate::inspect::rig::recording::{save_pass, Recorded};
use crate::MissionError;

/// How far the surface at the line stands above the plane a raised pass was held over, mm
/// (negative where it lies below), from the sound surface's level beside the line in contact
/// and on the raised pass (`levels`, counts, [`crackbot_tactile::print_check::PrintRatios::levels`]):
/// in contact the fibre is `d₀` from the surface wherever it is, so the ratio of the two levels
/// above `dark`, `f(g)/f(d₀)`, gives the raised fibre's distance `g` to the surface there
/// (beyond the curve's peak), and the rise is `d₀ + height_mm − g`. The surface's reflectivity
/// cancels. `None` where the contact level is within a count of `dark` or the raised one is not
/// above it. The raised fibre closer to the surface than the curve's peak reads as that close.
pub fn surface_rise_mm(
    fibre: &crackbot_fibre::ProximityFibre,
    levels: [f64; 2],
    dark: f64,
    height_mm: f64,
) -> Option<f64> {
    let [contact, raised] = levels.map(|l| l - dark);
    if !(contact > 1.0 && raised > 0.0) {
        return None;
    }
    let peak = fibre.peak_mm;
    let d0 = fibre.height_mm;
    // f(g) = 2u²/(1 + u⁴), u = g / peak: on its falling side u² = (1 + √(1 − t²)) / t.
    let t = (raised / contact * crackbot_fibre::intensity(d0, peak)).min(1.0);
    let u2 = (1.0 + (1.0 - t * t).max(0.0).sqrt()) / t;
    let g = peak * u2.sqrt();
    Some(d0 + height_mm - g)
}

/// One candidate's print check: its slide's axis, its strokes, where its raised passes go.
struct Check<'c> {
    settings: &'c PrintCheckConfig,
    fibre: &'c crackbot_fibre::ProximityFibre,
    out_dir: &'c Path,
    candidate: u64,
    /// The slide's start and unit direction: positions on its axis.
    origin: [f64; 2],
    u: [f64; 2],
    strokes: &'c Strokes,
    /// The candidate's own dip's samples, where the stroke crossed a second line.
    own: Option<Vec<(Vec<f64>, Vec<f64>)>>,
    raised: RaisedPass,
    dark: f64,
}

/// Runs the print check (`settings`) over the candidate a slide touched (`touched`), where the
/// contact strokes read it as a crack (`felt`, `None` where they did not), the check is on and
/// the planner gives it a raised pass; the ratios, and whether something stood in the way, go
/// into `felt`.
pub(crate) fn print_check(
    rig: &mut Rig<'_>,
    settings: &PrintCheckConfig,
    (planner, workspace): (&Planner, &Workspace),
    touched: &Touched,
    felt: Option<&mut Felt>,
) -> Result<(), MissionError> {
    let (Some(candidate), Some(height_mm), Some(felt)) =
        (touched.candidate, settings.height_mm, felt)
    else {
        return Ok(());
    };
    let (slide, strokes) = (&touched.slide, &touched.strokes);
    let pass = crackbot_planner::raised_pass(slide, planner.settings(), workspace)
        .zip(planner.settings().raised_pass);
    let Some(([from, to], raised)) = pass else {
        return Ok(());
    };
    let own = match (&strokes.own_dip, strokes.profiles.as_slice()) {
        (Some(r), [(p, x)]) if r.end <= p.len() => {
            Some(vec![(p[r.clone()].to_vec(), x[r.clone()].to_vec())])
        }
        _ => None,
    };
    let check = Check {
        settings,
        fibre: &rig.config.site.fibre,
        out_dir: rig.out_dir,
        candidate,
        origin: slide.start_mm,
        u: unit(slide.start_mm, slide.end_mm),
        strokes,
        own,
        raised,
        dark: rig.config.site.fibre.dark_counts,
    };
    check.run(rig, [from, to], height_mm, felt)
}

impl Check<'_> {
    /// The first raised pass, the pass made again higher, the passes in doubt; the verdict's
    /// ratios into `f`.
    fn run(
        &self,
        rig: &mut Rig<'_>,
        [from, to]: [[f64; 2]; 2],
        h: f64,
        f: &mut Felt,
    ) -> Result<(), MissionError> {
        let (mut first, obstruction) = self.first_pass(rig, [from, to], h, f)?;
        // Where the arm is, and where the next raised pass goes.
        let (mut a, mut b) = (to, from);
        let mut height = h;
        if obstruction.is_none() {
            if let Some((again, raised_to)) =
                self.again_if_surface_rises(rig, [a, b], h, first, f)?
            {
                first = Some(again);
                height = raised_to;
                std::mem::swap(&mut a, &mut b);
            }
        }
        let mut ratios: Vec<RaisedRatio> = first.into_iter().collect();
        let in_doubt = match (first, obstruction) {
            (Some(first), None) => {
                self.passes_in_doubt(rig, [a, b], height, first.print, &mut ratios, f)?
            }
            _ => false,
        };
        f.height_ratio = judged_ratio(&ratios, in_doubt);
        // Stopped before the crossing, or past it with no ratio from what it read: nothing
        // rules out what stands there.
        let passed = obstruction.map(|o| self.passed_every_crossing(from, to, o, f));
        f.stands = passed.is_some_and(|p| !p || ratios.is_empty());
        f.print_ratios = ratios.iter().map(|m| m.print).collect();
        if in_doubt {
            f.floor_ratios = ratios.iter().map(|m| m.floor).collect();
        }
        Ok(())
    }

    /// The finger rises and backs off behind where the strokes left it, then passes raised to
    /// as far past the other end (the planner's raised pass): both ends of the raised pass are
    /// sound surface, whatever the state stream's spacing. Guarded: stopped over what stands
    /// under the line. Its ratio, and what stopped it.
    fn first_pass(
        &self,
        rig: &mut Rig<'_>,
        [from, to]: [[f64; 2]; 2],
        h: f64,
        f: &mut Felt,
    ) -> Result<(Option<RaisedRatio>, Option<Obstruction>), MissionError> {
        let speed = self.raised.speed_mm_s;
        rig.hover_and_record(self.strokes.finger_at, from, h, speed, None)?;
        let ((hs, hx), obstruction) =
            rig.hover_and_record(from, to, h, speed, Some(self.settings.guard_counts))?;
        if let Some(o) = obstruction {
            f.doubts.push(CrackDoubt::RaisedPassStopped {
                at_mm: o.at_mm,
                length_mm: (to[0] - from[0]).hypot(to[1] - from[1]),
                rise_counts: o.rise_counts,
            });
        }
        let d = unit(from, to);
        let path = self
            .out_dir
            .join(format!("raised-{:03}.csv", self.candidate));
        save_pass(&path, &hs, &hx, u8::from(self.backwards(d)))?;
        Ok((self.ratio(&hs, &hx, from, d, &mut f.doubts), obstruction))
    }

    /// Where the first pass reads a print and the surface at the line stands above the plate
    /// it was held over ([`surface_rise_mm`] beyond [`SURFACE_RISE_TOLERANCE_MM`]: a bump's
    /// flank, a curved part), the pass is made again from `a` back to `b`, that much higher
    /// (at most [`MAX_SURFACE_RISE_MM`]). Only a first pass that reads a print: nearer the
    /// surface a crack keeps more of its dip, so at the check's height one that reads a crack
    /// would read one all the more. The pass made again's ratio and height, where it gave one.
    fn again_if_surface_rises(
        &self,
        rig: &mut Rig<'_>,
        [a, b]: [[f64; 2]; 2],
        h: f64,
        first: Option<RaisedRatio>,
        f: &mut Felt,
    ) -> Result<Option<(RaisedRatio, f64)>, MissionError> {
        let s = self.settings;
        let rise = first
            .filter(|r| r.print > s.print_ratio)
            .and_then(|r| surface_rise_mm(self.fibre, r.levels, self.dark, h))
            .filter(|r| *r > s.surface_rise_tolerance_mm);
        let Some(rise) = rise else {
            return Ok(None);
        };
        let height = h + rise.min(s.max_surface_rise_mm);
        f.doubts.push(CrackDoubt::SurfaceRise {
            rise_mm: rise,
            height_mm: height,
        });
        let ((rs, rx), stopped, dk) = self.pass(rig, [a, b], height, "again")?;
        if let Some(o) = stopped {
            f.doubts.push(CrackDoubt::RaisedAgainStopped {
                at_mm: o.at_mm,
                rise_counts: o.rise_counts,
            });
            return Ok(None);
        }
        Ok(self
            .ratio(&rs, &rx, a, dk, &mut f.doubts)
            .map(|again| (again, height)))
    }

    /// Near the print threshold ([`PRINT_RATIO_DOUBT`] of the first ratio `first`): more
    /// raised passes, back and forth from `a`, up to [`PRINT_CHECK_PASSES_IN_DOUBT`] in all
    /// (two where they settle, [`PRINT_RATIO_SETTLED`]), each one's ratios added to `ratios`.
    /// Whether the first was in doubt.
    fn passes_in_doubt(
        &self,
        rig: &mut Rig<'_>,
        [mut a, mut b]: [[f64; 2]; 2],
        height: f64,
        first: f64,
        ratios: &mut Vec<RaisedRatio>,
        f: &mut Felt,
    ) -> Result<bool, MissionError> {
        let s = self.settings;
        if (first - s.print_ratio).abs() >= s.ratio_doubt {
            return Ok(false);
        }
        for k in 2..=s.passes_in_doubt {
            let ((rs, rx), stopped, dk) = self.pass(rig, [a, b], height, &k.to_string())?;
            if let Some(o) = stopped {
                f.doubts.push(CrackDoubt::RaisedInDoubtStopped {
                    pass: k,
                    at_mm: o.at_mm,
                    rise_counts: o.rise_counts,
                    passes: ratios.len(),
                });
                break;
            }
            ratios.extend(self.ratio(&rs, &rx, a, dk, &mut f.doubts));
            std::mem::swap(&mut a, &mut b);
            if k % 2 == 0 && ratios.len() == k && settled(ratios, s) {
                break;
            }
        }
        f.doubts.push(CrackDoubt::RatioInDoubt {
            first,
            threshold: s.print_ratio,
            within: s.ratio_doubt,
            passes: ratios.len(),
        });
        Ok(true)
    }

    /// One more guarded raised pass from `a` to `b` at `height`, saved as
    /// `raised-NNN-{name}.csv`; with what stopped it and its direction.
    fn pass(
        &self,
        rig: &mut Rig<'_>,
        [a, b]: [[f64; 2]; 2],
        height: f64,
        name: &str,
    ) -> Result<(Recorded, Option<Obstruction>, [f64; 2]), MissionError> {
        let (pass, stopped) = rig.hover_and_record(
            a,
            b,
            height,
            self.raised.speed_mm_s,
            Some(self.settings.guard_counts),
        )?;
        let dk = unit(a, b);
        let path = self
            .out_dir
            .join(format!("raised-{:03}-{name}.csv", self.candidate));
        save_pass(&path, &pass.0, &pass.1, u8::from(self.backwards(dk)))?;
        Ok((pass, stopped, dk))
    }

    /// A raised pass from `start` in direction `dir`: its ratio against the candidate's own
    /// dip, or against the strokes where that gives none (the contact dip a stroke's deepest
    /// point may be the other line it crossed).
    fn ratio(
        &self,
        samples: &[[f64; 4]],
        xs: &[f64],
        start: [f64; 2],
        dir: [f64; 2],
        doubts: &mut Vec<CrackDoubt>,
    ) -> Option<RaisedRatio> {
        let p: Vec<f64> = samples.iter().map(|v| v[3]).collect();
        let x: Vec<f64> = xs.iter().map(|&v| self.on_axis(start, dir, v)).collect();
        let mut unusable = Vec::new();
        let r = self
            .own
            .as_ref()
            .and_then(|own| raised_ratio(own, (&p, &x), self.dark, &mut Vec::new()))
            .or_else(|| raised_ratio(&self.strokes.profiles, (&p, &x), self.dark, &mut unusable));
        doubts.extend(unusable.into_iter().map(|e| CrackDoubt::UnusableStroke {
            reason: e.to_string(),
        }));
        r
    }

    /// A point `v` mm along a raised pass from `a` in direction `dir`, on the slide's axis as
    /// the strokes' positions.
    fn on_axis(&self, a: [f64; 2], dir: [f64; 2], v: f64) -> f64 {
        let p = [a[0] + v * dir[0], a[1] + v * dir[1]];
        (p[0] - self.origin[0]) * self.u[0] + (p[1] - self.origin[1]) * self.u[1]
    }

    /// A raised pass in direction `d` runs against the slide's axis.
    fn backwards(&self, d: [f64; 2]) -> bool {
        d[0] * self.u[0] + d[1] * self.u[1] < 0.0
    }

    /// Stopped by something standing: had the pass from `from` to `to` gone
    /// [`PrintCheckConfig::clear_mm`] past every crossing?
    fn passed_every_crossing(
        &self,
        from: [f64; 2],
        to: [f64; 2],
        o: Obstruction,
        f: &Felt,
    ) -> bool {
        let d = unit(from, to);
        let sign = if self.backwards(d) { -1.0 } else { 1.0 };
        f.crossings.iter().all(|c| {
            let crossing =
                (c.0[0] - self.origin[0]) * self.u[0] + (c.0[1] - self.origin[1]) * self.u[1];
            sign * (self.on_axis(from, d, o.at_mm) - crossing) > self.settings.clear_mm
        })
    }
}

/// One pass each way and settled: the rest would not move the mean across the threshold.
fn settled(ratios: &[RaisedRatio], s: &PrintCheckConfig) -> bool {
    judged_ratio(ratios, true).is_some_and(|m| (m - s.print_ratio).abs() >= s.ratio_settled)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_surface_rise_is_read_from_the_two_levels_whatever_the_reflectivity() {
        let o = crackbot_fibre::ProximityFibre::default();
        let (d0, dark) = (o.height_mm, o.dark_counts);
        let f = |d: f64| o.intensity(d);
        // The calibrated fibre's peak signal above dark for reflectivity 1, counts
        // (`crackbot_sim::optics::OpticsParams::proximity_peak_counts`).
        let peak_counts = 772.15;
        // Levels of a surface of reflectivity `r` with the raised fibre `g` mm from it.
        let levels = |r: f64, g: f64| {
            [
                dark + r * peak_counts * f(d0),
                dark + r * peak_counts * f(g),
            ]
        };
        for r in [0.3, 0.8, 1.0] {
            for rise in [-1.0, 0.0, 0.4, 1.2] {
                let got = surface_rise_mm(&o, levels(r, d0 + 2.0 - rise), dark, 2.0).unwrap();
                assert!((got - rise).abs() < 1e-9, "r {r} rise {rise}: {got}");
            }
        }
        // The levels measured over flat trial plates (the contact stroke's about 452 counts,
        // the raised pass's 215 + 0.117 of the contact signal) read as no rise, well within
        // the tolerance.
        let flat = surface_rise_mm(&o, [452.0, 215.0 + 0.117 * 237.0], 215.0, 2.0).unwrap();
        assert!(flat.abs() < SURFACE_RISE_TOLERANCE_MM, "{flat}");
        // Brighter than the curve's peak allows reads as the peak; no signal gives nothing.
        let touching = surface_rise_mm(&o, [dark + 100.0, dark + 300.0], dark, 2.0).unwrap();
        assert!(
            (touching - (d0 + 2.0 - o.peak_mm)).abs() < 1e-9,
            "{touching}"
        );
        assert_eq!(
            surface_rise_mm(&o, [dark + 0.5, dark + 10.0], dark, 2.0),
            None
        );
        assert_eq!(
            surface_rise_mm(&o, [dark + 200.0, dark - 1.0], dark, 2.0),
            None
        );
        assert_eq!(
            surface_rise_mm(&o, [f64::NAN, dark + 10.0], dark, 2.0),
            None
        );
    }
}
