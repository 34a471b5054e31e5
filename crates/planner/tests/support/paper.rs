//! The paper's exploration-time experiment recomputed from the planner's estimates: the tactile-
//! only scan of the 200 × 100 mm plate for γ = 0.25, 0.5, 0.75, and targeted slides across the
//! candidates of the simulator's default scene (`crates/sim/scenes/default.toml`: four cracks of
//! 1, 2 (bent), 5 and 10 mm and the printed decoy a detector also proposes), and across one and
//! two cracks (the paper's trials: 14 candidates in 10 trials, one per half of the plate).

use crackbot_planner::{
    paper_mean_length_mm, Candidate, Limits, Plan, Planner, Settings, Workspace, PAPER_EQ1,
    PAPER_TABLE_II,
};

/// The plate.
pub fn plate() -> Workspace {
    Workspace::from_size(200.0, 100.0).expect("plate")
}

/// `L̄` on the plate by the paper's own mapping (148.06 px of a 480 px frame spanning 100 mm).
pub fn paper_length_mm() -> f64 {
    paper_mean_length_mm(PAPER_EQ1.mean_length_px, PAPER_EQ1.camera_height_px, 100.0)
}

/// The default scene's cracks and decoy as a detector would give them: centre-line polylines in
/// mm with their widths.
pub fn default_scene_candidates() -> Vec<Candidate> {
    let features: [(&[[f64; 2]], f64); 5] = [
        (&[[15.0, 25.0], [60.0, 35.0]], 1.0),
        (&[[20.0, 50.0], [45.0, 62.0], [75.0, 52.0]], 2.0),
        (&[[80.0, 62.0], [135.0, 70.0]], 5.0),
        (&[[115.0, 12.0], [150.0, 40.0]], 10.0),
        (&[[20.0, 80.0], [60.0, 88.0]], 2.0), // the printed decoy
    ];
    features
        .iter()
        .enumerate()
        .map(|(i, (path, w))| {
            Candidate::from_polyline(i as u64 + 1, path, *w, 0.9).expect("candidate")
        })
        .collect()
}

/// One row of the recomputed table.
pub struct Row {
    /// "T γ = 0.25", "T+V default scene (5)", …
    pub what: String,
    /// Scan rows, for the tactile-only rows.
    pub rows: Option<usize>,
    /// The plan.
    pub plan: Plan,
    /// The paper's time for that row, s.
    pub paper_s: Option<f64>,
}

/// The table at `slide_speed_mm_s`, every other setting the default.
pub fn exploration_table(slide_speed_mm_s: f64) -> Vec<Row> {
    let settings = Settings {
        slide_speed_mm_s,
        ..Settings::default()
    };
    let p = Planner::new(plate(), Limits::default(), settings).expect("planner");
    let mut rows = Vec::new();
    for paper in &PAPER_TABLE_II[..3] {
        let g = paper.gamma.expect("gamma");
        let plan = p.tactile_scan(g, paper_length_mm()).expect("scan");
        rows.push(Row {
            what: format!("T, γ = {g}"),
            rows: Some(plan.slides.len()),
            plan,
            paper_s: Some(paper.time_s),
        });
    }
    let scene = default_scene_candidates();
    let one = vec![scene[2].clone()];
    let two = vec![scene[0].clone(), scene[2].clone()];
    for (what, cands, paper) in [
        ("T+V, 1 candidate (5 mm crack)", one, None),
        (
            "T+V, 2 candidates (1 and 5 mm cracks, one per half)",
            two,
            Some(PAPER_TABLE_II[3].time_s),
        ),
        ("T+V, default scene (4 cracks + decoy)", scene, None),
    ] {
        rows.push(Row {
            what: what.to_string(),
            rows: None,
            plan: p.targeted(&cands).expect("targeted"),
            paper_s: paper,
        });
    }
    rows
}
