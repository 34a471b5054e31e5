//! Calibration run (development aid).
#![allow(clippy::unwrap_used, missing_docs)]
fn main() {
    let dir = std::path::PathBuf::from(std::env::args().nth(1).unwrap());
    let rep: u32 = std::env::args()
        .nth(2)
        .unwrap_or("1".into())
        .parse()
        .unwrap();
    let mut recs = Vec::new();
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        if p.to_string_lossy().ends_with(&format!("_{rep}.mat")) {
            recs.push(crackbot_recording::read_recording(&p).unwrap());
        }
    }
    let t = std::time::Instant::now();
    let r = crackbot_sim::calibrate::calibrate_paper(&recs, 7).unwrap();
    println!(
        "{:.1} s\n{}",
        t.elapsed().as_secs_f64(),
        serde_json::to_string_pretty(&r).unwrap()
    );
    let mut cfg = crackbot_sim::experiment::ExperimentConfig::paper(
        crackbot_sim::experiment::Experiment::Recognition,
        7,
    );
    cfg.sensor.optics = r.optics.clone();
    let traces = crackbot_sim::calibrate::simulate_traces(&cfg).unwrap();
    let targets = crackbot_sim::calibrate::real_quantiles(&recs);
    for t in targets.iter().filter(|t| t.channel == 3) {
        let tr = traces.iter().find(|x| x.label == t.label).unwrap();
        let mut v: Vec<f64> = tr
            .samples
            .iter()
            .filter(|s| (s.arm_velocity_mm_s >= 0.0) as u8 == t.direction)
            .map(|s| s.analog[3])
            .collect();
        v.sort_by(f64::total_cmp);
        let q: Vec<i64> = crackbot_sim::calibrate::QUANTILES
            .iter()
            .map(|q| v[((v.len() - 1) as f64 * q) as usize] as i64)
            .collect();
        println!(
            "label {} dir {} real {:?}\n                 sim  {:?}",
            t.label,
            t.direction,
            t.values.iter().map(|x| *x as i64).collect::<Vec<_>>(),
            q
        );
    }
}
#[allow(dead_code)]
fn unused() {}
