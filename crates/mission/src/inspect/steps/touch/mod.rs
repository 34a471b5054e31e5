//! The touch step: each planned slide stroked (forth and back where the plan says), each
//! stroke recorded and saved, a stroke whose ends read unlike each other made again beside its
//! candidate, every classification unit classified and localised, and what was felt kept per
//! candidate ([`Felt`]). What the strokes read goes on to the print check ([`Touched`]).

use std::sync::atomic::Ordering;

use crackbot_planner::{Candidate, Planner, Slide, Workspace};
use crackbot_tactile::localise::{localise, CrackExtent, LocaliseConfig};
use crackbot_tactile::model::TactileModel;
use crackbot_tactile::online::OnlineClassifier;
use crackbot_tactile::stroke::{end_levels, ends_agree, own_dip, split_by_travel};

mod settings;
mod strokes;

pub use settings::{
    TouchConfig, MIN_DIP_COUNTS, RESTROKE_ALONG_MM, RESTROKE_KEEP_MM, UNEVEN_ENDS_SHARE,
};
pub(crate) use strokes::{Strokes, Touched};

use super::felt::{Crossing, Felt, PassReading};
use super::rules::Rules;
use crate::inspect::doubts::PassDoubt;
use crate::inspect::report::{InspectReport, PassRecord};
use crate::inspect::rig::context::Rig;
use crate::inspect::rig::feel::Feel;
use crate::inspect::rig::recording::save_pass;
use crate::MissionError;
use strokes::{classify, keep_pass, pass_record, Axis, Stroke, Unit};

/// What one slide's strokes came to.
enum Stroked {
    /// Judged: the strokes, for the print check.
    Judged(Strokes),
    /// Its first stroke began or ended off the sound surface: made again here, beside it.
    Again(Slide),
}

/// The touch step's state over a mission: the models fed pass by pass, the next link id, and
/// what was felt so far.
pub(crate) struct Touch<'m, 'c> {
    config: &'c TouchConfig,
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
    pub(crate) felt: Vec<(u64, Felt)>,
}

impl<'m, 'c> Touch<'m, 'c> {
    /// Ready to touch `candidates` along the plan of `planner`.
    pub(crate) fn new(
        config: &'c TouchConfig,
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

    /// Slide `si` of `of`: stroked, and made again beside its candidate where its first
    /// stroke's ends read unlike each other. What it left for the print check.
    pub(crate) fn slide(
        &mut self,
        rig: &mut Rig<'_>,
        report: &mut InspectReport,
        (si, of): (usize, usize),
        planned: &Slide,
    ) -> Result<Touched, MissionError> {
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
        let slide = again.unwrap_or_else(|| planned.clone());
        Ok(Touched {
            candidate: slide.candidates.first().copied(),
            slide,
            strokes,
        })
    }

    /// What was felt over `candidate`, where it reads as a crack by the contact strokes (the
    /// print check's turn).
    pub(crate) fn reads_as_crack(&mut self, candidate: u64) -> Option<&mut Felt> {
        let rules = self.rules;
        self.felt
            .iter_mut()
            .find(|(k, _)| *k == candidate)
            .map(|(_, f)| f)
            .filter(|f| f.reads_as_crack(&rules))
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
                let dark = rig.config.site.fibre.dark_counts;
                if let Some((beside, ends)) = self.beside_if_uneven(slide, id, &strokes, dark) {
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
            let recording = rig.out_dir.join(format!("slide-{id:03}.csv"));
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
    /// ([`TouchConfig::uneven_ends_share`], over the fibre's `dark` level) is made once more
    /// beside it ([`TouchConfig::restroke_along_mm`]), where the candidate reaches that far
    /// ([`TouchConfig::restroke_keep_mm`]): that slide, and what the uneven stroke's ends read
    /// (counts).
    fn beside_if_uneven(
        &self,
        slide: &Slide,
        id: u64,
        strokes: &Strokes,
        dark: f64,
    ) -> Option<(Slide, [f64; 2])> {
        let share = self.config.uneven_ends_share;
        let (uneven, _) = strokes
            .profiles
            .iter()
            .find(|(p, _)| !ends_agree(p, dark, share))?;
        let (c, _) = self.candidates.iter().find(|(c, _)| c.id == id)?;
        let beside = crackbot_planner::slide_along(
            slide,
            c,
            self.workspace,
            self.config.restroke_along_mm,
            self.config.restroke_keep_mm,
        )?;
        Some((beside, end_levels(uneven).unwrap_or_default()))
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
    #[expect(
        clippy::too_many_arguments,
        reason = "the unit, where it lies and what it adds to are all this step's; a struct would only rename them"
    )]
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
            split_by_travel(&unit.along, rig.config.site.arm.stroke_mm)
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
    /// ([`own_dip`], whose samples go into `strokes` for the print check).
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
                    let dips = &self.config.separate_dips;
                    own_dip(samples, along, &extent, w, near, &config, dips)
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
