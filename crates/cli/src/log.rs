//! `crackbot log`: a mission's log in other forms (today: a ROS 2 bag that `ros2 bag play`
//! plays).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::{Args, Subcommand};

/// What `crackbot log` does.
#[derive(Debug, Subcommand)]
pub enum LogCommand {
    /// Write a mission's `mission.mcap` as a ROS 2 bag (rosbag2's MCAP storage, CDR messages of
    /// `ros/crackbot_msgs` and standard ROS 2 types, `metadata.yaml`), for `ros2 bag play`.
    ToRos2(ToRos2Args),
}

/// `crackbot log to-ros2`.
#[derive(Debug, Args)]
pub struct ToRos2Args {
    /// The mission's log (`mission.mcap`), or the mission's folder holding it.
    pub log: PathBuf,
    /// The bag's folder (created; refused when it holds anything) [default: `ros2` beside the
    /// log].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print what was written as one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// The log file `given` names: itself, or `mission.mcap` in the folder it names.
fn log_file(given: &Path) -> PathBuf {
    if given.is_dir() {
        given.join("mission.mcap")
    } else {
        given.to_path_buf()
    }
}

/// Runs `crackbot log …`.
pub fn log_cmd(cmd: LogCommand) -> Result<()> {
    match cmd {
        LogCommand::ToRos2(args) => to_ros2(&args),
    }
}

fn to_ros2(args: &ToRos2Args) -> Result<()> {
    let log = log_file(&args.log);
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| log.parent().unwrap_or_else(|| Path::new(".")).join("ros2"));
    let bag = crackbot_rosbag::log_to_bag(&log, &out)
        .with_context(|| format!("writing {} as a ROS 2 bag", log.display()))?;
    if args.json {
        let v = serde_json::json!({
            "bag": bag.dir,
            "mcap": bag.mcap,
            "messages": bag.messages(),
            "topics": bag.per_topic,
            "start_ns": bag.start_ns,
            "duration_ns": bag.duration_ns,
        });
        println!("{v}");
        return Ok(());
    }
    println!(
        "{}: {} messages on {} topics, {:.1} s ({})",
        bag.dir.display(),
        bag.messages(),
        bag.per_topic.len(),
        bag.duration_ns as f64 * 1e-9,
        bag.mcap.display()
    );
    for (topic, n) in &bag.per_topic {
        println!("  {topic:<36} {n}");
    }
    println!(
        "play it: ros2 bag play {} (with crackbot_msgs built: ros/crackbot_msgs)",
        bag.dir.display()
    );
    Ok(())
}
