//! `crackbot-robot`: the headless robot. With no arguments it runs a fused inspection mission on
//! the built-in default scene, starting the simulated controller and sensor itself; `crackbot run`
//! takes the same flags.

#![expect(
    clippy::needless_pass_by_value,
    reason = "each command's handler takes the arguments clap parsed for it, as its owner"
)]

use anyhow::Result;
use clap::Parser;

mod finger;
mod run;

/// The headless crack-inspection robot.
#[derive(Debug, Parser)]
#[command(name = "crackbot-robot", version, about)]
struct Cli {
    #[command(flatten)]
    args: run::RunArgs,
}

fn main() -> Result<()> {
    tracing_subscriber::fmt()
        .with_writer(std::io::stderr)
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "warn".into()),
        )
        .init();
    run::run(Cli::parse().args)
}
