//! The link's conformance suite for any manipulator controller.
//!
//! It runs the wire format's cases (`crates/link/docs/wire-format.md`) against a running
//! controller over the signed UDP link, as a host would: the state stream's rate and clock, a
//! legitimate move and slide, every refusal by field (§11), an expired deadline, a stop in every
//! state and the watchdog. Each case drives the arm and says what it saw; [`run`] gives one
//! [`CaseResult`] per case, [`table`] prints them. `crackbot-lab controller-check` is its command.
//!
//! The arm moves: run it on a clear workspace. The suite parks the arm between cases inside the
//! workspace it is told ([`Expect`]), lifted 8–10 mm above the plate, and slides 12–15 mm.
//!
//! * [`host`]: the suite's end of the link.
//! * [`cases`]: the cases.

pub mod cases;
pub mod host;

use std::time::{Duration, Instant};

use serde::Serialize;

pub use host::{Host, HostError};

/// What the controller should accept: its workspace and limits (the site file's, for
/// crackbot's controller: travel up to twice and slides up to four times the site's speeds).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Expect {
    /// Lower corner of the workspace, mm.
    pub min_mm: [f64; 2],
    /// Upper corner, mm.
    pub max_mm: [f64; 2],
    /// Fastest travel accepted, mm/s.
    pub max_travel_mm_s: f64,
    /// Fastest slide accepted, mm/s.
    pub max_slide_mm_s: f64,
    /// The controller's watchdog.
    pub watchdog: Duration,
}

impl Default for Expect {
    /// crackbot's default site: 200 × 100 mm, travel to 100 mm/s, slides to 15.56 mm/s, 1 s.
    fn default() -> Self {
        Expect {
            min_mm: [0.0, 0.0],
            max_mm: [200.0, 100.0],
            max_travel_mm_s: 100.0,
            max_slide_mm_s: 4.0 * 3.89,
            watchdog: Duration::from_secs(1),
        }
    }
}

impl Expect {
    /// A point at fractions `fx`, `fy` of the workspace, `z` mm up.
    pub fn spot(&self, fx: f64, fy: f64, z: f64) -> [f64; 3] {
        [
            self.min_mm[0] + fx * (self.max_mm[0] - self.min_mm[0]),
            self.min_mm[1] + fy * (self.max_mm[1] - self.min_mm[1]),
            z,
        ]
    }

    /// The suite's travel speed, mm/s.
    pub fn travel_speed(&self) -> f64 {
        (self.max_travel_mm_s / 2.0).min(50.0)
    }

    /// The suite's slide speed, mm/s.
    pub fn slide_speed(&self) -> f64 {
        (self.max_slide_mm_s / 2.0).min(4.0)
    }

    /// About how long a move from `a` to `b` takes, s.
    pub fn travel_time(&self, a: [f64; 3], b: [f64; 3]) -> f64 {
        let d = (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt();
        if d.is_finite() {
            d / self.travel_speed() + 3.0
        } else {
            30.0
        }
    }
}

/// A case: its name and its function.
pub type Case = (&'static str, fn(&mut Host, &Expect) -> cases::Verdict);

/// Every case, in the order they run.
pub const CASES: &[Case] = &[
    ("state stream: rate and clock", cases::state_stream),
    ("a move inside the workspace", cases::legitimate_move),
    ("a slide", cases::legitimate_slide),
    ("refusals by field", cases::refusals),
    ("an expired deadline", cases::expired),
    ("a stop in every state", cases::stop_in_every_state),
    ("the watchdog", cases::watchdog),
];

/// One case's outcome.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CaseResult {
    /// The case.
    pub name: &'static str,
    /// Whether it passed.
    pub passed: bool,
    /// What it saw, or what went wrong.
    pub detail: String,
    /// How long it took, s.
    pub seconds: f64,
}

/// Runs every case against the controller `host` talks to; `progress` hears each result as it
/// comes. A controller that sends no state at all fails before any case.
pub fn run(
    host: &mut Host,
    expect: &Expect,
    progress: impl FnMut(&CaseResult),
) -> Result<Vec<CaseResult>, HostError> {
    run_cases(host, expect, CASES, progress)
}

/// Runs `cases` (some of [`CASES`]) as [`run`] runs them all.
pub fn run_cases(
    host: &mut Host,
    expect: &Expect,
    cases: &[Case],
    mut progress: impl FnMut(&CaseResult),
) -> Result<Vec<CaseResult>, HostError> {
    host.wait_for_state(Duration::from_secs(10))?;
    let mut out = Vec::with_capacity(cases.len());
    for (name, case) in cases {
        let t = Instant::now();
        let verdict = case(host, expect);
        let r = CaseResult {
            name,
            passed: verdict.is_ok(),
            detail: verdict.unwrap_or_else(|e| e),
            seconds: t.elapsed().as_secs_f64(),
        };
        progress(&r);
        out.push(r);
        if !matches!(host.mode(), crackbot_link::Mode::Idle) {
            // Leave the next case a stopped arm, not a moving one.
            let _ = host.send(&crackbot_link::Message::Stop);
            let _ = host.pump(Duration::from_millis(300));
        }
    }
    Ok(out)
}

/// The results as a Markdown table.
pub fn table(results: &[CaseResult]) -> String {
    let mut s = String::from("| case | result | what it saw | s |\n|---|---|---|---|\n");
    for r in results {
        s.push_str(&format!(
            "| {} | {} | {} | {:.1} |\n",
            r.name,
            if r.passed { "pass" } else { "FAIL" },
            r.detail.replace('|', "/"),
            r.seconds
        ));
    }
    let passed = results.iter().filter(|r| r.passed).count();
    s.push_str(&format!("\n{passed} of {} cases passed\n", results.len()));
    s
}
