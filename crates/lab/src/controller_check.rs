//! `crackbot-lab controller-check`: the link's conformance suite (`crackbot-conformance`) against
//! a running controller, crackbot's or anyone's: it prints a pass/fail table and exits non-zero
//! when a case fails. The arm moves: run it on a clear workspace.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, Result};
use crackbot_conformance::{run, table, Expect, Host};
use crackbot_link::{Key, Security};
use crackbot_mission::inspect::Site;

/// Arguments of `controller-check`.
#[derive(Debug, clap::Args)]
pub struct ControllerCheckArgs {
    /// The controller's UDP address.
    #[arg(long)]
    controller: SocketAddr,
    /// The link's pre-shared key file (the controller's).
    #[arg(long)]
    key: PathBuf,
    /// The UDP address to talk from (the controller's `--peer`).
    #[arg(long, default_value = "127.0.0.1:7701")]
    bind: SocketAddr,
    /// The link's id.
    #[arg(long, default_value_t = 1)]
    link_id: u16,
    /// The site file whose [arm] the controller enforces (default: the default site, 200 × 100
    /// mm); accepted speeds are twice its travel and four times its slide speed.
    #[arg(long)]
    site: Option<PathBuf>,
    /// The controller's watchdog, s.
    #[arg(long, default_value_t = 1.0)]
    watchdog_s: f64,
    /// Folder of this host's epoch counter.
    #[arg(long, default_value = "out/controller-check")]
    state_dir: PathBuf,
    /// Also write the results as JSON here.
    #[arg(long)]
    json: Option<PathBuf>,
}

/// What the controller should accept, from the site file.
fn expect(args: &ControllerCheckArgs) -> Result<Expect> {
    let site = match &args.site {
        Some(p) => Site::load(p)?,
        None => Site::default(),
    };
    anyhow::ensure!(
        args.watchdog_s.is_finite() && (0.05..=30.0).contains(&args.watchdog_s),
        "--watchdog-s {} is not in [0.05, 30] s",
        args.watchdog_s
    );
    let a = site.arm;
    Ok(Expect {
        min_mm: a.workspace_min_mm,
        max_mm: a.workspace_max_mm,
        max_travel_mm_s: 2.0 * a.travel_speed_mm_s,
        max_slide_mm_s: 4.0 * a.slide_speed_mm_s,
        watchdog: Duration::from_secs_f64(args.watchdog_s),
    })
}

/// Runs the suite.
pub fn run_check(args: ControllerCheckArgs) -> Result<()> {
    let expect = expect(&args)?;
    let key = Key::from_file(&args.key).context("the link key")?;
    std::fs::create_dir_all(&args.state_dir)
        .with_context(|| format!("creating {}", args.state_dir.display()))?;
    let link = Host::link_config(
        Security::Signed(key),
        args.state_dir.join("host.epoch"),
        args.link_id,
    );
    let mut host = Host::connect(args.bind, args.controller, link)
        .with_context(|| format!("talking from {} to {}", args.bind, args.controller))?;
    eprintln!(
        "controller-check: {} cases against {} (the arm moves)",
        crackbot_conformance::CASES.len(),
        args.controller
    );
    let results = run(&mut host, &expect, |r| {
        eprintln!(
            "  {:<30} {}  {}",
            r.name,
            if r.passed { "pass" } else { "FAIL" },
            r.detail
        );
    })?;
    print!("{}", table(&results));
    if let Some(path) = &args.json {
        std::fs::write(path, serde_json::to_string_pretty(&results)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    let failed = results.iter().filter(|r| !r.passed).count();
    anyhow::ensure!(failed == 0, "{failed} of {} cases failed", results.len());
    Ok(())
}
