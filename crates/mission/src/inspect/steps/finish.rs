//! The report step: the report begun from what perception gave, a vision mission's cracks, and
//! the report's times and clock fits at the end. The cracks a fused or tactile mission
//! confirms come from the judge step and the pieces step.

use std::path::Path;
use std::time::Instant;

use crackbot_planner::Candidate;

use super::perceive::Perceived;
use super::trace::CrackTrace;
use crate::inspect::progress::Progress;
use crate::inspect::report::{
    Evidence, InspectMode, InspectReport, LinkCounters, ReportedCrack, StageTimes,
};
use crate::inspect::rig::context::Rig;

/// What perception gave, shown to the front end: the candidates with their scores, the crack
/// map seen from the plate, and the report begun.
pub(crate) fn perceived(
    rig: &mut Rig<'_>,
    (mode, out_dir): (InspectMode, &Path),
    seen: Option<Perceived>,
) -> (Vec<(Candidate, f64)>, Option<CrackTrace>, InspectReport) {
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
        mode,
        scene: rig.config.site.name.clone(),
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
        out_dir: out_dir.display().to_string(),
    };
    (candidates, trace, report)
}

/// A vision mission's report: every candidate, as the detector scored it.
pub(crate) fn vision_cracks(candidates: &[(Candidate, f64)]) -> Vec<ReportedCrack> {
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

/// The report's times and clock fits.
pub(crate) fn finish(
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
