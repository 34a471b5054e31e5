//! The mission as named steps, each a function of its own: wait for the streams, perceive,
//! plan, touch every candidate ([`super::touch`]: strokes, retries, strokes made again, the
//! print check), judge ([`super::judge`]), and the report. The rig (arm, sensor, stop flag,
//! front end) is set up and torn down by [`super::run_inspection`].

use std::time::{Duration, Instant};

use crackbot_planner::{Candidate, Limits, Plan, Planner, RaisedPass, Settings, Workspace};
use crackbot_tactile::model::TactileModel;

use super::config::{InspectConfig, InspectMode};
use super::judge::{judge, Felt, Judgement, Rules};
use super::passes::Rig;
use super::perceive::{perceive, Perceived};
use super::pieces::{self, CrackTrace};
use super::raised::{PRINT_CHECK_OVERRUN_MM, PRINT_CHECK_SPEED_MM_S};
use super::report::{
    Evidence, InspectReport, LinkCounters, Progress, RejectedCandidate, ReportedCrack, StageTimes,
};
use super::touch::Touch;
use crate::MissionError;

/// How long the arm's state stream and the sensor have to start, s.
const STREAMS_START_S: u64 = 5;

/// Runs the steps of a mission over `rig` with the deployed models; `started` is when the
/// mission began and `setup_s` what setting up the rig took.
pub(super) fn mission(
    rig: &mut Rig<'_>,
    (recognition, width): (&TactileModel, &TactileModel),
    started: Instant,
    setup_s: f64,
) -> Result<InspectReport, MissionError> {
    let config = rig.config;
    let mut stages = StageTimes {
        setup_s,
        ..StageTimes::default()
    };
    wait_for_streams(rig)?;

    let t = Instant::now();
    let seen = match config.mode {
        InspectMode::Tactile => None,
        _ => Some(perceive(config, rig.backend)?),
    };
    stages.perceive_s = t.elapsed().as_secs_f64();
    let (candidates, trace, mut report) = perceived(rig, seen);
    if config.mode == InspectMode::Vision {
        report.cracks = vision_cracks(&candidates);
        return Ok(finish(rig, report, stages, started));
    }

    let t = Instant::now();
    let (planner, workspace, plan) = plan(config, &report.candidates)?;
    stages.plan_s = t.elapsed().as_secs_f64();
    (rig.progress)(&Progress::Planned {
        slides: plan.slides.len(),
        estimated_s: plan.estimated_s,
        plan: plan.clone(),
    });

    let explore = Instant::now();
    let rules = Rules::new(&recognition.header.classes, config)?;
    let mut touch = Touch::new(
        config,
        (recognition, width),
        &candidates,
        (&planner, &workspace),
        rules,
    )?;
    let n = plan.slides.len();
    for (si, slide) in plan.slides.iter().enumerate() {
        touch.slide(rig, &mut report, (si, n), slide)?;
    }
    stages.explore_s = explore.elapsed().as_secs_f64();

    let felt = std::mem::take(&mut touch.felt);
    let names = &recognition.header.classes;
    let (cracks, rejected) = judge_all(felt, &candidates, &rules, names);
    report.cracks = join_pieces(config, cracks, &report.candidates, trace.as_ref());
    report.rejected = rejected;
    report.plan = Some(plan);
    Ok(finish(rig, report, stages, started))
}

/// Waits for the arm's state stream and the sensor ([`STREAMS_START_S`]); an error names the
/// one that stayed silent.
fn wait_for_streams(rig: &mut Rig<'_>) -> Result<(), MissionError> {
    let deadline = Instant::now() + Duration::from_secs(STREAMS_START_S);
    while rig.arm.states.is_empty() || rig.sensor.samples.is_empty() {
        rig.pump(Duration::from_millis(5))?;
        if Instant::now() > deadline {
            return Err(if rig.arm.states.is_empty() {
                MissionError::ControllerUnreachable {
                    addr: rig.arm.ep.peer_addr().to_string(),
                }
            } else {
                MissionError::NoSamples {
                    port: rig.sensor.path.clone(),
                }
            });
        }
    }
    Ok(())
}

/// What perception gave, shown to the front end: the candidates with their scores, the crack
/// map seen from the plate, and the report begun.
fn perceived(
    rig: &mut Rig<'_>,
    seen: Option<Perceived>,
) -> (Vec<(Candidate, f64)>, Option<CrackTrace>, InspectReport) {
    let config = rig.config;
    let (candidates, trace, frame) = match seen {
        None => (Vec::new(), None, None),
        Some(s) => (s.candidates, s.trace, Some(s.frame)),
    };
    if let Some(frame) = &frame {
        (rig.progress)(&Progress::Frame(frame.clone()));
    }
    let detections: Vec<Candidate> = candidates.iter().map(|(c, _)| c.clone()).collect();
    (rig.progress)(&Progress::Perceived {
        candidates: candidates.len(),
        detections: detections.clone(),
    });
    let report = InspectReport {
        mode: config.mode,
        scene: config.site.name.clone(),
        cracks: Vec::new(),
        rejected: Vec::new(),
        candidates: detections,
        frame,
        passes: Vec::new(),
        plan: None,
        elapsed_s: 0.0,
        exploration_s: 0.0,
        stages: StageTimes::default(),
        sensor_clock: None,
        controller_clock: None,
        link: LinkCounters::default(),
        out_dir: config.out_dir.display().to_string(),
    };
    (candidates, trace, report)
}

/// A vision mission's report: every candidate, as the detector scored it.
fn vision_cracks(candidates: &[(Candidate, f64)]) -> Vec<ReportedCrack> {
    candidates
        .iter()
        .map(|(c, score)| ReportedCrack {
            candidate: Some(c.id),
            position_mm: c.centre_mm,
            extent_mm: None,
            class: "crack".into(),
            width_mm: None,
            width_range_mm: None,
            confidence: *score,
            evidence: Evidence {
                detector_score: Some(*score),
                ..Evidence::default()
            },
        })
        .collect()
}

/// The plan step: the scene's workspace and speed limits, the planner with the print check's
/// raised passes (the settings' own, or the default overrun and speed under the travel limit;
/// none without the check), and the plan: boustrophedon rows (tactile) or a slide across
/// every candidate.
fn plan(
    config: &InspectConfig,
    candidates: &[Candidate],
) -> Result<(Planner, Workspace, Plan), MissionError> {
    let m = &config.site.arm;
    let workspace = Workspace {
        x_min_mm: m.workspace_min_mm[0],
        x_max_mm: m.workspace_max_mm[0],
        y_min_mm: m.workspace_min_mm[1],
        y_max_mm: m.workspace_max_mm[1],
    };
    let limits = Limits {
        max_slide_speed_mm_s: 4.0 * m.slide_speed_mm_s,
        max_travel_speed_mm_s: 2.0 * m.travel_speed_mm_s,
    };
    let settings = Settings {
        raised_pass: config.print_check_mm.map(|_| {
            config.planner.raised_pass.unwrap_or(RaisedPass {
                overrun_mm: PRINT_CHECK_OVERRUN_MM,
                speed_mm_s: PRINT_CHECK_SPEED_MM_S.min(limits.max_travel_speed_mm_s),
            })
        }),
        ..config.planner.clone()
    };
    let planner = Planner::new(workspace, limits, settings)?;
    let plan = match config.mode {
        InspectMode::Tactile => planner.tactile_scan(config.gamma, config.mean_crack_length_mm)?,
        _ => planner.targeted(candidates)?,
    };
    Ok((planner, workspace, plan))
}

/// The judge step over every candidate (and tactile row piece) felt: confirmed cracks, and
/// the candidates rejected with what the finger felt instead (row pieces that are not cracks
/// are not listed). `names` are the recognition model's classes.
fn judge_all(
    felt: Vec<(u64, Felt)>,
    candidates: &[(Candidate, f64)],
    rules: &Rules,
    names: &[String],
) -> (Vec<ReportedCrack>, Vec<RejectedCandidate>) {
    let (mut cracks, mut rejected) = (Vec::new(), Vec::new());
    for (key, f) in felt {
        let (judgement, class, confidence) = judge(&f, rules);
        let name = names.get(class).cloned().unwrap_or_default();
        let detection = candidates.iter().find(|(c, _)| c.id == key);
        match judgement {
            Judgement::Crack {
                position_mm,
                extent_mm,
                width,
            } => cracks.push(ReportedCrack {
                candidate: detection.map(|(c, _)| c.id),
                position_mm,
                extent_mm,
                class: name,
                width_mm: width.map(|w| w.mm),
                width_range_mm: width.map(|w| w.range_mm),
                confidence,
                evidence: Evidence {
                    detector_score: detection.map(|d| d.1),
                    slides: f.slides,
                    votes: f.votes,
                    doubts: f.doubts,
                    height_ratio: f.height_ratio,
                    print_ratios: f.print_ratios,
                    floor_ratios: f.floor_ratios,
                    pieces: Vec::new(),
                },
            }),
            Judgement::Rejected(why) => {
                if let Some((c, score)) = detection {
                    rejected.push(RejectedCandidate {
                        candidate: c.id,
                        position_mm: c.centre_mm,
                        felt: why.felt(&name, rules),
                        detector_score: *score,
                        slides: f.slides,
                        height_ratio: f.height_ratio,
                        print_ratios: f.print_ratios,
                        floor_ratios: f.floor_ratios,
                        votes: f.votes,
                    });
                }
            }
        }
    }
    (cracks, rejected)
}

/// Confirmed candidates that are pieces of one crack, reported as one
/// ([`pieces::join_pieces`]), where the mission joins pieces at all.
fn join_pieces(
    config: &InspectConfig,
    cracks: Vec<ReportedCrack>,
    candidates: &[Candidate],
    trace: Option<&CrackTrace>,
) -> Vec<ReportedCrack> {
    if config.piece_gap_mm.is_none() && config.piece_trace_gap_mm.is_none() {
        return cracks;
    }
    let rule = pieces::PieceRule {
        gap_mm: config.piece_gap_mm,
        trace_gap_mm: config.piece_trace_gap_mm,
    };
    pieces::join_pieces(cracks, candidates, trace, rule)
}

/// The report's times and clock fits.
fn finish(
    rig: &mut Rig<'_>,
    mut report: InspectReport,
    stages: StageTimes,
    started: Instant,
) -> InspectReport {
    if report.mode != InspectMode::Vision {
        report.exploration_s = stages.explore_s * rig.config.speedup;
        report.sensor_clock = rig.sensor.sync.fit();
        report.controller_clock = rig.arm.sync.fit();
    }
    report.stages = stages;
    report.elapsed_s = started.elapsed().as_secs_f64();
    report
}
