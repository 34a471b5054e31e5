//! The configuration file as `crackbot run --print-config` writes it: every key of a
//! configuration, each with a comment saying what it is and where its default comes from (the
//! constant that holds it, and the measurement behind that, in `crates/research/EXPERIMENTS.md`
//! by section title). A test checks that every key written has its comment.

/// `section.key` → what it is, and the source of its default.
pub(crate) const COMMENTS: &[(&str, &str)] = &[
    ("mode", "fused (the camera proposes, the finger confirms), vision (camera only) or tactile (scan rows, no camera)"),
    ("rig", "What the mission runs on. Without [rig.hardware], the simulated rig over --scene (the built-in scene by default)."),
    ("rig.speedup", "Simulation speed-up (1: real time, as hardware runs; the figures in EXPERIMENTS.md are at 1)."),
    ("rig.seed", "Seed of the simulated sensor and camera."),
    ("rig.camera_calibration", "The camera's lens and the plate's pose (crackbot calibrate camera, then surface): frames are undistorted and mapped to the plate through it."),
    ("rig.hardware", "Real hardware: the sensor's serial port, the controller's UDP address, the link key, the camera."),
    ("rig.hardware.serial", "The sensor's serial device (or a pseudo-terminal)."),
    ("rig.hardware.controller", "The manipulator controller's UDP address, e.g. \"192.168.1.20:7700\"."),
    ("rig.hardware.bind", "This host's UDP address for the link (the controller sends to it)."),
    ("rig.hardware.key_file", "The link's pre-shared key file (64-128 hex digits, mode 0600)."),
    ("rig.hardware.camera", "A V4L2 device (/dev/video0), a video file or stream URL, or an image file."),
    ("rig.hardware.homography", "The camera's pixel -> surface calibration (crackbot homography fit); or rig.camera_calibration in its place."),
    ("rig.hardware.capture", "How frames are asked of the camera (crackbot_vision::camera::CaptureOptions); each key may be left out."),
    ("rig.hardware.capture.size", "Frame size [width, height], px: asked of a device, checked on every source (another size is refused)."),
    ("rig.hardware.capture.pixel_format", "A device's pixel format as ffmpeg names it (mjpeg, yuyv422, ...)."),
    ("rig.hardware.capture.framerate", "A device's frame rate, fps."),
    ("rig.hardware.capture.exposure", "A device's exposure (V4L2 exposure_time_absolute, its units); turns auto-exposure off (v4l2-ctl)."),
    ("rig.hardware.capture.gain", "A device's gain (V4L2 gain, its units)."),
    ("rig.hardware.capture.discard", "Frames dropped before the one kept (left out: DEVICE_DISCARD = 5 from a device, none from a file or stream)."),
    ("rig.site", "The place (a site file's contents; crackbot_mission::inspect::Site): on the simulator, the scene's."),
    ("rig.site.name", "The site's name, for the report."),
    ("rig.site.arm", "The arm's reachable box on the surface and its speeds."),
    ("rig.site.arm.workspace_min_mm", "Lower corner of the reachable box, mm [x, y]."),
    ("rig.site.arm.workspace_max_mm", "Upper corner, mm [x, y]."),
    ("rig.site.arm.slide_speed_mm_s", "Speed of a tactile slide, mm/s (the paper: about 3.89)."),
    ("rig.site.arm.travel_speed_mm_s", "Speed of moves between slides, finger lifted, mm/s."),
    ("rig.site.arm.stroke_mm", "Longest slide stroke, mm (the paper: about 16)."),
    ("rig.site.fibre", "The finger's proximity fibre (crackbot_fibre::ProximityFibre), fitted to the authors' recordings (crates/sim/docs/calibration.md)."),
    ("rig.site.fibre.peak_mm", "Distance of the proximity curve's peak, mm."),
    ("rig.site.fibre.height_mm", "The fibre's distance from the surface in contact, mm."),
    ("rig.site.fibre.dark_counts", "The proximity channel's dark level, counts."),
    ("rig.site.fibre.offset_mm", "How far ahead of the tip the fibre looks, mm."),
    ("rig.site.fibre.spot_mm", "The fibre's spot on the surface, mm."),
    ("perceive", "The camera and the detector."),
    ("perceive.detector_model", "The ONNX detector (left out: models/detector/crackseg-tiles/crack-detector-320.onnx)."),
    ("perceive.min_score", "Vision missions: detections below this score are not reported."),
    ("perceive.proposal_min_score", "Fused missions: detections below this score are not touched (the finger confirms or rejects the rest)."),
    ("perceive.candidates", "cracks: every crack a detection holds, on its centre line; detections: each detection once across its main axis."),
    ("plan", "The plan (crackbot-planner)."),
    ("plan.gamma", "gamma of the tactile-only scan (the paper's eq. 2), in (0, 1)."),
    ("plan.mean_crack_length_mm", "Mean crack length of the tactile-only scan, mm (the paper's eq. 1 on real masks: paper_mean_length_mm(148.06, 480, 100))."),
    ("plan.planner", "The planner's settings (crackbot_planner::Settings); the mission's defaults differ from the planner's: EXPERIMENTS.md, \"Strokes as long as the finger's reach\"."),
    ("plan.planner.slide_speed_mm_s", "Sliding speed, mm/s: the simulator's fit to the authors' recordings, which the tactile models learned (SIM_SLIDE_SPEED_MM_S)."),
    ("plan.planner.travel_speed_mm_s", "Speed of moves with the finger lifted, mm/s (the site's)."),
    ("plan.planner.travel_accel_mm_s2", "Acceleration of moves, mm/s^2 (left out: constant speed)."),
    ("plan.planner.settle_s", "Per slide: lowering, settling, lifting the finger, s (an assumption)."),
    ("plan.planner.reversal_s", "Length of each start/stop ramp of a stroke, s (the simulator's arm: 0.05)."),
    ("plan.planner.passes", "Strokes across each candidate: one was as accurate as four on the trials at a third of the time (EXPERIMENTS.md, \"Error against run time before the print check: strokes, stroke length, margin\")."),
    ("plan.planner.scan_passes", "One-way passes per row of the tactile-only scan."),
    ("plan.planner.margin_mm", "Sound surface beyond a candidate's edge and the finger's reach, mm (TOUCH_MARGIN_MM)."),
    ("plan.planner.min_margin_mm", "The least margin accepted where the workspace cuts a slide short, mm."),
    ("plan.planner.reach_mm", "How far beyond a crack's edge the finger still feels it, mm: the proximity fibre's reach (offset + spot/2)."),
    ("plan.planner.min_stroke_mm", "Shortest stroke, mm (TOUCH_MIN_STROKE_MM, or the site's stroke if shorter; the paper's 16)."),
    ("plan.planner.assumed_width_mm", "Width assumed for a candidate that gives none, mm."),
    ("plan.planner.along_spacing_mm", "Spacing of slides along a crack, mm (left out: one slide across its centre)."),
    ("plan.planner.overlap", "Overlapping candidates: slide each, or merge."),
    ("plan.planner.order", "How candidates are ordered."),
    ("plan.planner.on_unreachable", "Candidates no slide can reach: report or refuse."),
    ("plan.planner.start_mm", "Where the finger starts, mm (left out: the workspace's lower corner)."),
    ("plan.planner.return_to_start", "Whether the plan ends back at the start."),
    ("plan.planner.raised_pass", "The print check's raised pass (left out: [print_check]'s overrun_mm and speed_mm_s)."),
    ("touch", "The contact strokes: the deployed tactile models, what counts as a dip, strokes made again."),
    ("touch.recognition_model", "The deployed recognition model (models/tactile/recognition.ctm)."),
    ("touch.width_model", "The deployed width model (models/tactile/width.ctm)."),
    ("touch.min_dip_counts", "Shallowest proximity dip a confirmed crack needs, counts (MIN_DIP_COUNTS; EXPERIMENTS.md, \"Prints told by two heights\"); 100 suits missions without the print check."),
    ("touch.uneven_ends_share", "A candidate's stroke is made again beside it when its darker end keeps less than this share of the brighter end's signal (UNEVEN_ENDS_SHARE; trial scenes 9000-9119, 9180-9299)."),
    ("touch.restroke_along_mm", "How far along the candidate the stroke is made again, mm: past a screw head (RESTROKE_ALONG_MM)."),
    ("touch.restroke_keep_mm", "Least of the candidate left beyond the moved stroke, mm (RESTROKE_KEEP_MM)."),
    ("touch.separate_dips", "A stroke's dip wider than its candidate is looked at for several dips (crackbot_tactile::stroke; trial scenes 9540-9659)."),
    ("touch.separate_dips.excess_mm", "Wider than the candidate by more than this, mm (SEPARATE_DIPS_EXCESS_MM)."),
    ("touch.separate_dips.back_share", "Dips are apart where the smoothed P comes back within this share of the dip's depth (SEPARATE_DIPS_BACK_SHARE) ..."),
    ("touch.separate_dips.gap_mm", "... for at least this much travel, mm (SEPARATE_DIPS_GAP_MM)."),
    ("print_check", "Fused missions: a candidate read as a crack is passed over again with the finger raised; a print's dip keeps its share of the signal, a crack's does not."),
    ("print_check.height_mm", "Height of the raised pass, mm above the plate, 0.5-20; 0: no print check (PRINT_CHECK_HEIGHT_MM; EXPERIMENTS.md, \"Prints told by two heights\")."),
    ("print_check.print_ratio", "Above this print ratio, a print (crackbot_tactile::print_check::PRINT_RATIO)."),
    ("print_check.ratio_doubt", "A first ratio within this of the threshold is measured again (PRINT_RATIO_DOUBT; EXPERIMENTS.md, \"Two estimates of a ratio in doubt\")."),
    ("print_check.passes_in_doubt", "Most raised passes over a candidate in doubt, as many each way (PRINT_CHECK_PASSES_IN_DOUBT)."),
    ("print_check.ratio_settled", "Passes in doubt stop where their mean lies this far from the threshold (PRINT_RATIO_SETTLED; EXPERIMENTS.md, \"Two estimates of a ratio in doubt\")."),
    ("print_check.guard_counts", "A raised pass is stopped when P rises this far above its start, counts: something stands under the line (RAISED_PASS_GUARD_COUNTS; EXPERIMENTS.md, \"Raised passes stop over what stands under them\")."),
    ("print_check.clear_mm", "A stopped pass judges its candidate only if it went this far past the crossing, mm (RAISED_PASS_CLEAR_MM)."),
    ("print_check.surface_rise_tolerance_mm", "The pass is made again higher where the surface stands more than this above the plate, mm (SURFACE_RISE_TOLERANCE_MM; EXPERIMENTS.md, \"The raised pass as high above the surface as the check needs\")."),
    ("print_check.max_surface_rise_mm", "The most a pass made again is raised, mm (MAX_SURFACE_RISE_MM)."),
    ("print_check.overrun_mm", "How far the raised pass runs past each end of the stroke, mm (PRINT_CHECK_OVERRUN_MM)."),
    ("print_check.speed_mm_s", "Speed of the raised pass, mm/s, or the arm's travel limit if lower (PRINT_CHECK_SPEED_MM_S)."),
    ("judge", "From what the finger felt to a verdict."),
    ("judge.require_dip", "A confirmed crack must show the proximity dip every real crack makes (the authors' plates: 72 of 72 to 73 of 76 passes per plate)."),
    ("judge.doubted_dip_confidence", r#"A doubted "no crack" over a dip at least this confident goes to the print check; 0: off (DOUBTED_DIP_CONFIDENCE; EXPERIMENTS.md, 'A doubted "no crack" over a deep dip goes to the print check')."#),
    ("judge.weak_no_crack_confidence", "A \"no crack\" vote weaker than this counts as doubted (WEAK_NO_CRACK_CONFIDENCE; EXPERIMENTS.md, \"The recognition model that knows the simulated finger\")."),
    ("judge.implausible_ratio_share", "A print ratio below this share of the shallowest crack's is neither crack nor print (IMPLAUSIBLE_RATIO_SHARE; trials 9000-9419)."),
    ("pieces", "Fused missions: confirmed pieces of one crack reported as one."),
    ("pieces.gap_mm", "Pieces whose detections continue each other across at most this gap are one crack, mm; 0: off (PIECE_GAP_MM; trial seeds 1000-1029, 2000-2029, 3000-3029)."),
    ("pieces.trace_gap_mm", "Pieces whose crossings the crack map joins, off it for at most this much, are one crack, mm; negative: off (PIECE_TRACE_GAP_MM; EXPERIMENTS.md, \"Pieces joined where the crack map runs between their crossings\")."),
    ("output", "Where the report, the recordings and the log go."),
    ("output.out_dir", "The mission's folder: report.json, frame.png, one CSV per pass, mission.mcap."),
    ("output.mcap", "Write mission.mcap, the log Foxglove opens."),
    ("output.foxglove", "Serve the log live over the Foxglove WebSocket protocol on this address (feature foxglove)."),
    ("output.ros2_domain", "Publish the log's messages live on ROS 2 topics over DDS on this domain (feature ros2)."),
];

/// The top-level sections in the order a mission uses them.
const SECTION_ORDER: &[&str] = &[
    "rig",
    "perceive",
    "plan",
    "touch",
    "print_check",
    "judge",
    "pieces",
    "output",
];

/// The comment of `key`, if it has one.
fn comment(key: &str) -> Option<&'static str> {
    COMMENTS.iter().find(|(k, _)| *k == key).map(|(_, c)| *c)
}

/// `table` as TOML with each key's comment above it: a table's plain keys first, then its
/// sub-tables under their own `[headers]`.
pub(crate) fn commented(table: &toml::Table) -> String {
    let mut out = String::from(
        "# A crackbot mission (crackbot run --config FILE). Every key may be left out: it then\n\
         # keeps its default. Flags given with --config override the file.\n",
    );
    write_table(&mut out, "", table);
    out
}

/// Writes the keys of `table` (at `path`, "" for the root), then its sub-tables.
fn write_table(out: &mut String, path: &str, table: &toml::Table) {
    let full = |k: &str| {
        if path.is_empty() {
            k.to_string()
        } else {
            format!("{path}.{k}")
        }
    };
    for (k, v) in table.iter().filter(|(_, v)| !v.is_table()) {
        if let Some(c) = comment(&full(k)) {
            out.push_str(&format!("# {c}\n"));
        }
        out.push_str(&format!("{} = {v}\n", toml_key(k)));
    }
    // Sections in the order the mission uses them, then any other.
    let mut sections: Vec<(&String, &toml::Value)> = table.iter().collect();
    sections.sort_by_key(|(k, _)| {
        SECTION_ORDER
            .iter()
            .position(|s| s == k)
            .unwrap_or(usize::MAX)
    });
    for (k, v) in sections {
        if let toml::Value::Table(t) = v {
            let p = full(k);
            out.push('\n');
            if let Some(c) = comment(&p) {
                out.push_str(&format!("# {c}\n"));
            }
            out.push_str(&format!("[{p}]\n"));
            write_table(out, &p, t);
        }
    }
}

/// A key as TOML writes it (bare where it can be).
fn toml_key(k: &str) -> String {
    if !k.is_empty()
        && k.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        k.to_string()
    } else {
        toml::Value::String(k.to_string()).to_string()
    }
}

#[cfg(all(test, feature = "sim"))]
mod tests {
    use super::*;
    use crate::inspect::InspectConfig;

    /// Every key path of `table`.
    fn keys(table: &toml::Table, path: &str, out: &mut Vec<String>) {
        for (k, v) in table {
            let p = if path.is_empty() {
                k.clone()
            } else {
                format!("{path}.{k}")
            };
            if let toml::Value::Table(t) = v {
                keys(t, &p, out);
            }
            out.push(p);
        }
    }

    #[test]
    fn every_key_written_says_what_it_is() {
        let mut c = InspectConfig::new(crackbot_sim::Scene::builtin_default(), "out/mission");
        // The optional keys too.
        c.perceive.detector_model = Some("models/detector/crack-detector-320.onnx".into());
        c.rig.camera_calibration = Some("out/camera.toml".into());
        let table = toml::Table::try_from(&c).unwrap();
        let mut all = Vec::new();
        keys(&table, "", &mut all);
        let missing: Vec<&String> = all.iter().filter(|k| comment(k).is_none()).collect();
        assert!(missing.is_empty(), "keys without a comment: {missing:?}");
        // And no comment for a key that is not there (a renamed key leaves its comment behind),
        // but for the optional ones.
        let optional = [
            "rig.hardware",
            "plan.planner.travel_accel_mm_s2",
            "plan.planner.along_spacing_mm",
            "plan.planner.start_mm",
            "plan.planner.raised_pass",
            "output.foxglove",
            "output.ros2_domain",
        ];
        let stale: Vec<&str> = COMMENTS
            .iter()
            .map(|(k, _)| *k)
            .filter(|k| !all.iter().any(|a| a == k))
            .filter(|k| !optional.iter().any(|o| k.starts_with(o)))
            .collect();
        assert!(stale.is_empty(), "comments of no key: {stale:?}");
        assert_eq!(toml_key("speedup"), "speedup");
        assert_eq!(toml_key("a b"), "\"a b\"");
    }
}
