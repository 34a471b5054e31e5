//! The touch step: each planned slide stroked (forth and back where the plan says), each
//! stroke recorded and saved, a stroke whose ends read unlike each other made again beside its
//! candidate, every classification unit classified and localised, what was felt kept per
//! candidate ([`Felt`]), and the print check run over what reads as a crack.

use std::path::PathBuf;
use std::sync::atomic::Ordering;

use crackbot_planner::{Candidate, Planner, Slide, Workspace};
use crackbot_tactile::localise::{localise, CrackExtent, LocaliseConfig};
use crackbot_tactile::model::TactileModel;
use crackbot_tactile::online::{OnlineClassifier, SlideVerdict};

use super::config::InspectConfig;
use super::feel::Feel;
use super::judge::{Felt, PassReading, Rules};
use super::passes::{self, classify, save_pass, split_by_travel, Crossing, Rig};
use super::raised::{print_check, Strokes};
use super::report::{keep_pass, Dip, InspectReport, PassDoubt, PassRecord};
use crate::MissionError;

/// A candidate's stroke is made once more beside it when its two ends read this unlike each
/// other: the darker end's signal above the fibre's dark level is less than this share of the
/// brighter end's (`passes::ends_agree`). A stroke is planned to start and end on sound surface;
/// on the simulated trial scenes 9000–9119 and 9180–9299, 30 of 839 candidate strokes did not
/// (another crack or a print beside the candidate, a bump's flank, a screw head, a crack wider
/// than its stroke), and half of those candidates ended as errors.
pub const UNEVEN_ENDS_SHARE: f64 = 0.6;
/// How far along the candidate the stroke is made again, mm: past a screw head's radius.
pub const RESTROKE_ALONG_MM: f64 = 5.0;
/// Least of the candidate left beyond the moved stroke, mm: it still crosses the candidate.
pub const RESTROKE_KEEP_MM: f64 = 1.0;

/// One stroke of a classification unit, as recorded.
#[derive(Debug, Clone)]
struct Stroke {
    /// Its link id.
    id: u32,
    /// Where it started and ended, mm.
    from: [f64; 2],
    to: [f64; 2],
    /// Samples recorded.
    samples: usize,
    /// Its recording.
    recording: PathBuf,
    /// Attempts needed.
    attempts: u32,
}

/// A classification unit: a stroke forth and back (or one), its samples, positions along the
/// slide's axis and direction column.
#[derive(Debug, Default)]
struct Unit {
    samples: Vec<[f64; 4]>,
    along: Vec<f64>,
    dirs: Vec<u8>,
    strokes: Vec<Stroke>,
}

/// A slide's axis: its start, unit direction and length.
#[derive(Debug, Clone, Copy)]
struct Axis {
    start: [f64; 2],
    u: [f64; 2],
    len: f64,
}

impl Axis {
    fn of(slide: &Slide) -> Axis {
        let d = [
            slide.end_mm[0] - slide.start_mm[0],
            slide.end_mm[1] - slide.start_mm[1],
        ];
        let len = d[0].hypot(d[1]).max(1e-9);
        Axis {
            start: slide.start_mm,
            u: [d[0] / len, d[1] / len],
            len,
        }
    }

    /// The point `s` mm along the axis.
    fn at(&self, s: f64) -> [f64; 2] {
        [self.start[0] + s * self.u[0], self.start[1] + s * self.u[1]]
    }

    /// How far `p` lies along the axis, mm.
    fn along(&self, p: [f64; 2]) -> f64 {
        (p[0] - self.start[0]) * self.u[0] + (p[1] - self.start[1]) * self.u[1]
    }
}

/// What one slide's strokes came to.
enum Stroked {
    /// Judged: the strokes, for the print check.
    Judged(Strokes),
    /// Its first stroke began or ended off the sound surface: made again here, beside it.
    Again(Slide),
}

/// The touch step's state over a mission: the models fed pass by pass, the next link id, and
/// what was felt so far.
pub(super) struct Touch<'m, 'c> {
    config: &'c InspectConfig,
    candidates: &'c [(Candidate, f64)],
    planner: &'c Planner,
    workspace: &'c Workspace,
    rules: Rules,
    online: OnlineClassifier<'m>,
    online_width: OnlineClassifier<'m>,
    feel: Feel<'m>,
    classes: usize,
    next_id: u32,
    /// Per candidate (or stroke-long piece of a tactile row), in the order first felt.
    pub(super) felt: Vec<(u64, Felt)>,
}

impl<'m, 'c> Touch<'m, 'c> {
    /// Ready to touch `candidates` along the plan of `planner`.
    pub(super) fn new(
        config: &'c InspectConfig,
        (recognition, width): (&'m TactileModel, &'m TactileModel),
        candidates: &'c [(Candidate, f64)],
        (planner, workspace): (&'c Planner, &'c Workspace),
        rules: Rules,
    ) -> Result<Self, MissionError> {
        Ok(Touch {
            config,
            candidates,
            planner,
            workspace,
            rules,
            online: OnlineClassifier::new(recognition)?,
            online_width: OnlineClassifier::new(width)?,
            feel: Feel::new(recognition, width)?,
            classes: recognition.header.classes.len(),
            next_id: 1,
            felt: Vec::new(),
        })
    }

    /// Slide `si` of `of`: stroked, made again beside its candidate where its first stroke's
    /// ends read unlike each other, then the print check over its candidate.
    pub(super) fn slide(
        &mut self,
        rig: &mut Rig<'_>,
        report: &mut InspectReport,
        (si, of): (usize, usize),
        planned: &Slide,
    ) -> Result<(), MissionError> {
        let mut again: Option<Slide> = None;
        let strokes = loop {
            let slide = again.as_ref().unwrap_or(planned);
            if rig.stop.load(Ordering::Relaxed) {
                return Err(MissionError::Interrupted);
            }
            match self.stroke_slide(rig, report, (si, of), slide, again.is_some())? {
                Stroked::Again(beside) => again = Some(beside),
                Stroked::Judged(strokes) => break strokes,
            }
        };
        let slide = again.as_ref().unwrap_or(planned);
        let cand = slide.candidates.first().copied();
        if let (Some(c), Some(h)) = (cand, self.config.print_check_mm) {
            let rules = self.rules;
            let felt = self.felt.iter_mut().find(|(k, _)| *k == c).map(|(_, f)| f);
            if let Some(f) = felt.filter(|f| f.reads_as_crack(&rules)) {
                print_check(rig, self.planner, self.workspace, slide, c, h, &strokes, f)?;
            }
        }
        Ok(())
    }

    /// The slide's passes, unit by unit, each judged; or the slide beside it, where its first
    /// stroke's ends read unlike each other (`again`: this is already that one).
    fn stroke_slide(
        &mut self,
        rig: &mut Rig<'_>,
        report: &mut InspectReport,
        (si, of): (usize, usize),
        slide: &Slide,
        again: bool,
    ) -> Result<Stroked, MissionError> {
        let cand = slide.candidates.first().copied();
        let axis = Axis::of(slide);
        let n_passes = slide.passes.max(1) as usize;
        let mut strokes = Strokes {
            finger_at: slide.start_mm,
            ..Strokes::default()
        };
        let mut p = 0;
        while p < n_passes {
            // One classification unit: a stroke forth and back, as the authors' slides are
            // (direction 0 then 1); a single stroke when the plan has no way back.
            let n = if cand.is_some() && p + 1 < n_passes {
                2
            } else {
                1
            };
            let unit = self.stroke_unit(rig, slide, &axis, p..p + n, &mut strokes)?;
            // A candidate's first stroke that began or ended off the sound surface is made once
            // more beside it.
            if let (Some(id), false, 0) = (cand, again, p) {
                if let Some((beside, ends)) = self.beside_if_uneven(slide, id, &strokes) {
                    let moved = (beside.moved_along_mm - slide.moved_along_mm).abs();
                    Self::not_judged(rig, report, (si, of), (cand, moved), ends, &unit);
                    return Ok(Stroked::Again(beside));
                }
            }
            self.judge_unit(
                rig,
                report,
                (si + 1, of),
                slide,
                &axis,
                &unit,
                p == 0,
                &mut strokes,
            )?;
            p += n;
        }
        Ok(Stroked::Judged(strokes))
    }

    /// Strokes `passes` of `slide` (even: forth, odd: back), each recorded and saved as
    /// `slide-NNN.csv`; their proximity profiles go into `strokes`.
    fn stroke_unit(
        &mut self,
        rig: &mut Rig<'_>,
        slide: &Slide,
        axis: &Axis,
        passes: std::ops::Range<usize>,
        strokes: &mut Strokes,
    ) -> Result<Unit, MissionError> {
        let mut unit = Unit::default();
        for q in passes {
            let forth = q % 2 == 0;
            let (a, b) = if forth {
                (slide.start_mm, slide.end_mm)
            } else {
                (slide.end_mm, slide.start_mm)
            };
            let id = self.next_id;
            self.next_id += 1;
            let dir = u8::from(!forth);
            let ((s, x), attempts) =
                rig.slide_and_record(id, (a, b), slide.speed_mm_s, dir, &mut self.feel)?;
            let recording = self.config.out_dir.join(format!("slide-{id:03}.csv"));
            save_pass(&recording, &s, &x, dir)?;
            // Positions along the slide's axis, from its start.
            let on_axis: Vec<f64> = x
                .iter()
                .map(|&v| if forth { v } else { axis.len - v })
                .collect();
            strokes
                .profiles
                .push((s.iter().map(|v| v[3]).collect(), on_axis.clone()));
            strokes.finger_at = b;
            unit.strokes.push(Stroke {
                id,
                from: a,
                to: b,
                samples: s.len(),
                recording,
                attempts,
            });
            unit.along.extend(on_axis);
            unit.dirs.extend(std::iter::repeat_n(dir, s.len()));
            unit.samples.extend(s);
        }
        Ok(unit)
    }

    /// A candidate's first stroke that began or ended off the sound surface
    /// ([`UNEVEN_ENDS_SHARE`]) is made once more beside it ([`RESTROKE_ALONG_MM`]), where the
    /// candidate reaches that far ([`RESTROKE_KEEP_MM`]): that slide, and what the uneven
    /// stroke's ends read (counts).
    fn beside_if_uneven(
        &self,
        slide: &Slide,
        id: u64,
        strokes: &Strokes,
    ) -> Option<(Slide, [f64; 2])> {
        let dark = self.config.site.fibre.dark_counts;
        let (uneven, _) = strokes
            .profiles
            .iter()
            .find(|(p, _)| !passes::ends_agree(p, dark, UNEVEN_ENDS_SHARE))?;
        let (c, _) = self.candidates.iter().find(|(c, _)| c.id == id)?;
        let beside = passes::slide_along(
            slide,
            c,
            self.workspace,
            RESTROKE_ALONG_MM,
            RESTROKE_KEEP_MM,
        )?;
        Some((beside, passes::end_levels(uneven).unwrap_or_default()))
    }

    /// The strokes of a unit made again beside: kept (a front end lists every stroke), their
    /// recordings stay, their doubt (the ends' levels `[e0, e1]`, how far along it moved)
    /// says why they were not judged.
    fn not_judged(
        rig: &mut Rig<'_>,
        report: &mut InspectReport,
        (si, of): (usize, usize),
        (cand, moved_mm): (Option<u64>, f64),
        [e0, e1]: [f64; 2],
        unit: &Unit,
    ) {
        for s in &unit.strokes {
            let rec = PassRecord {
                id: s.id,
                candidate: cand,
                start_mm: s.from,
                end_mm: s.to,
                samples: s.samples,
                class: None,
                confidence: 0.0,
                width_mm: None,
                doubt: Some(PassDoubt::NotJudged {
                    end_counts: [e0, e1],
                    moved_mm,
                }),
                dip: None,
                recording: s.recording.display().to_string(),
                attempts: s.attempts,
            };
            keep_pass(rig.progress, report, si, of, rec);
        }
    }

    /// Judges a unit: the whole unit over a candidate, stroke-long pieces of a tactile row
    /// ([`split_by_travel`]), each classified (the context reaches back over the candidate's
    /// earlier strokes, as over the authors' back-and-forth strokes; a new candidate or row
    /// starts afresh), localised, kept in the report and added to what was felt.
    #[allow(clippy::too_many_arguments)]
    fn judge_unit(
        &mut self,
        rig: &mut Rig<'_>,
        report: &mut InspectReport,
        (done, of): (usize, usize),
        slide: &Slide,
        axis: &Axis,
        unit: &Unit,
        fresh: bool,
        strokes: &mut Strokes,
    ) -> Result<(), MissionError> {
        let cand = slide.candidates.first().copied();
        let pieces: Vec<(usize, usize)> = if cand.is_none() {
            split_by_travel(&unit.along, self.config.site.arm.stroke_mm)
        } else {
            vec![(0, unit.samples.len())]
        };
        for (p0, p1) in pieces {
            let (verdict, wv) = classify(
                &mut self.online,
                &mut self.online_width,
                &unit.samples[p0..p1],
                &unit.along[p0..p1],
                &unit.dirs[p0..p1],
                fresh && p0 == 0,
            )?;
            let extent = self.locate(slide, axis, unit, (p0, p1), strokes);
            let mid = unit
                .along
                .get((p0 + p1) / 2)
                .copied()
                .unwrap_or(axis.len / 2.0);
            let crossing: Crossing = extent.as_ref().map_or((axis.at(mid), None), |e| {
                (
                    axis.at(e.centre_mm),
                    Some([axis.at(e.start_mm), axis.at(e.end_mm)]),
                )
            });
            for s in &unit.strokes {
                let samples = if cand.is_some() { s.samples } else { p1 - p0 };
                let rec = pass_record(s, cand, samples, verdict.as_ref(), wv.as_ref(), &extent);
                keep_pass(rig.progress, report, done, of, rec);
            }
            let key = cand.unwrap_or(u64::from(unit.strokes[0].id) << 32 | p0 as u64);
            let slides: Vec<u32> = unit.strokes.iter().map(|s| s.id).collect();
            let reading = PassReading {
                verdict: verdict.as_ref(),
                width: wv.as_ref().map(|w| {
                    (
                        w.label,
                        w.width.as_ref().map_or([w.label; 2], |e| e.range_mm),
                    )
                }),
                dip_confidence: extent.as_ref().map(|e| e.confidence),
                crossing,
                on_candidate: cand.is_some(),
                slide: slides[0],
            };
            let rules = self.rules;
            self.felt_mut(key).add_pass(&slides, &reading, &rules);
        }
        Ok(())
    }

    /// Where the unit's piece `p0..p1` crossed a crack: the localiser with the mission's
    /// shallowest dip; where the one stroke also crossed a second crack or a print beside its
    /// candidate, the localiser spans both dips, and the one nearest the candidate is its
    /// ([`passes::own_dip`], whose samples go into `strokes` for the print check).
    fn locate(
        &self,
        slide: &Slide,
        axis: &Axis,
        unit: &Unit,
        (p0, p1): (usize, usize),
        strokes: &mut Strokes,
    ) -> Option<CrackExtent> {
        let config = LocaliseConfig {
            min_depth_counts: self.config.min_dip_counts,
            ..Default::default()
        };
        let (samples, along) = (&unit.samples[p0..p1], &unit.along[p0..p1]);
        let extent = localise(samples, along, &config).ok().flatten()?;
        let cand = slide.candidates.first().copied();
        let own = match cand {
            Some(id) if strokes.profiles.len() == 1 => self
                .candidates
                .iter()
                .find(|(c, _)| c.id == id)
                .and_then(|(c, _)| {
                    let w = c
                        .width_mm
                        .unwrap_or(self.planner.settings().assumed_width_mm);
                    let near = axis.along(c.centre_mm);
                    passes::own_dip(samples, along, &extent, w, near, &config)
                }),
            _ => None,
        };
        match own {
            Some((r, e)) => {
                strokes.own_dip = Some(p0 + r.start..p0 + r.end);
                Some(e)
            }
            None => Some(extent),
        }
    }

    /// What was felt over `key`, new if nothing was yet.
    fn felt_mut(&mut self, key: u64) -> &mut Felt {
        let i = match self.felt.iter().position(|(c, _)| *c == key) {
            Some(i) => i,
            None => {
                self.felt.push((key, Felt::new(self.classes)));
                self.felt.len() - 1
            }
        };
        &mut self.felt[i].1
    }
}

/// The report's record of one stroke of a judged unit.
fn pass_record(
    s: &Stroke,
    candidate: Option<u64>,
    samples: usize,
    verdict: Option<&SlideVerdict>,
    width: Option<&SlideVerdict>,
    extent: &Option<CrackExtent>,
) -> PassRecord {
    PassRecord {
        id: s.id,
        candidate,
        start_mm: s.from,
        end_mm: s.to,
        samples,
        class: verdict.map(|v| v.name.clone()),
        confidence: verdict.map_or(0.0, |v| v.confidence),
        width_mm: width.map(|w| w.label),
        doubt: verdict.and_then(|v| v.doubt.as_ref()).map(PassDoubt::from),
        dip: extent.as_ref().map(|e| Dip {
            centre_mm: e.centre_mm,
            width_mm: e.width_mm,
            confidence: e.confidence,
        }),
        recording: s.recording.display().to_string(),
        attempts: s.attempts,
    }
}
