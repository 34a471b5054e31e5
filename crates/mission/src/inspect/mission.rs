//! The mission: each step called in order over the rig, each given its own section of the
//! checked configuration: wait for the streams, perceive, plan, touch every slide and run the
//! print check over what it read as a crack, judge, join the pieces of one crack, report. The
//! rig (arm, sensor, stop flag, front end) is set up and torn down by
//! [`super::run_inspection`].

use std::time::Instant;

use crackbot_tactile::model::TactileModel;

use super::config::CheckedConfig;
use super::progress::Progress;
use super::report::{InspectMode, InspectReport, StageTimes};
use super::rig::context::Rig;
use super::steps::finish::{finish, perceived, vision_cracks};
use super::steps::judge::judge_all;
use super::steps::perceive::perceive;
use super::steps::pieces::join_pieces;
use super::steps::plan::plan;
use super::steps::print_check::print_check;
use super::steps::rules::Rules;
use super::steps::touch::Touch;
use super::steps::wait::wait_for_streams;
use crate::MissionError;

/// Runs the steps of a mission over `rig` with the deployed models; `started` is when the
/// mission began and `setup_s` what setting up the rig took.
pub(crate) fn mission(
    config: &CheckedConfig,
    rig: &mut Rig<'_>,
    (recognition, width): (&TactileModel, &TactileModel),
    (started, setup_s): (Instant, f64),
) -> Result<InspectReport, MissionError> {
    let mode = config.mode;
    let mut stages = StageTimes {
        setup_s,
        ..StageTimes::default()
    };
    wait_for_streams(rig)?;

    let t = Instant::now();
    let seen = match mode {
        InspectMode::Tactile => None,
        _ => Some(perceive(
            (&config.perceive, mode),
            (rig.config, rig.out_dir),
            rig.backend,
        )?),
    };
    stages.perceive_s = t.elapsed().as_secs_f64();
    let out_dir = rig.out_dir;
    let (candidates, trace, mut report) = perceived(rig, (mode, out_dir), seen);
    if mode == InspectMode::Vision {
        report.cracks = vision_cracks(&candidates);
        return Ok(finish(rig, report, stages, started));
    }

    let t = Instant::now();
    let pc = &config.print_check;
    let raised = pc.height_mm.map(|_| (pc.overrun_mm, pc.speed_mm_s));
    let site = &rig.config.site;
    let (planner, workspace, plan) = plan((&config.plan, mode), site, raised, &report.candidates)?;
    stages.plan_s = t.elapsed().as_secs_f64();
    (rig.progress)(&Progress::Planned {
        slides: plan.slides.len(),
        estimated_s: plan.estimated_s,
        plan: plan.clone(),
    });

    let explore = Instant::now();
    let names = &recognition.header.classes;
    let rules = Rules::new(
        names,
        &config.judge,
        (pc.height_mm, pc.print_ratio),
        &site.fibre,
    )?;
    let mut touch = Touch::new(
        &config.touch,
        (recognition, width),
        &candidates,
        (&planner, &workspace),
        rules,
    )?;
    let n = plan.slides.len();
    for (si, slide) in plan.slides.iter().enumerate() {
        let touched = touch.slide(rig, &mut report, (si, n), slide)?;
        let felt = touched.candidate.and_then(|c| touch.reads_as_crack(c));
        print_check(rig, pc, (&planner, &workspace), &touched, felt)?;
    }
    stages.explore_s = explore.elapsed().as_secs_f64();

    let (cracks, rejected) = judge_all(std::mem::take(&mut touch.felt), &candidates, &rules, names);
    report.cracks = if config.pieces.joins() {
        join_pieces(cracks, &report.candidates, trace.as_ref(), &config.pieces)
    } else {
        cracks
    };
    report.rejected = rejected;
    report.plan = Some(plan);
    Ok(finish(rig, report, stages, started))
}
