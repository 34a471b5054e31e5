//! A bag's folder as rosbag2 writes one with its MCAP storage: `<name>_0.mcap` (profile `ros2`,
//! `ros2msg` schemas, `cdr` channels with their offered QoS, a `rosbag2` metadata record) and
//! `metadata.yaml` (version 5, the oldest that every ROS 2 release since Humble reads).

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use crate::convert::BagMessage;
use crate::error::RosbagError;
use crate::msgs::MsgType;
use crate::topics::{qos_yaml, RosTopic};

/// The metadata version written.
pub const METADATA_VERSION: u32 = 5;

/// What a bag holds.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BagSummary {
    /// The bag's folder.
    pub dir: PathBuf,
    /// Its MCAP file.
    pub mcap: PathBuf,
    /// Messages per topic, for the topics it holds.
    pub per_topic: BTreeMap<&'static str, u64>,
    /// Earliest log time, Unix ns (0 for an empty bag).
    pub start_ns: u64,
    /// Latest less earliest, ns.
    pub duration_ns: u64,
}

impl BagSummary {
    /// Messages in all.
    pub fn messages(&self) -> u64 {
        self.per_topic.values().sum()
    }
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> RosbagError + '_ {
    move |source| RosbagError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Creates `dir` for a bag: refused when it exists and holds anything.
fn make_dir(dir: &Path) -> Result<(), RosbagError> {
    if dir.exists() {
        let mut entries = std::fs::read_dir(dir).map_err(io(dir))?;
        if entries.next().is_some() {
            return Err(RosbagError::Exists {
                path: dir.to_path_buf(),
            });
        }
    }
    std::fs::create_dir_all(dir).map_err(io(dir))
}

/// `metadata.yaml`'s text for `summary` (the topics in [`RosTopic::ALL`]'s order).
pub fn metadata_yaml(summary: &BagSummary) -> String {
    let file = summary
        .mcap
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let (start, duration, count) = (summary.start_ns, summary.duration_ns, summary.messages());
    let mut y = format!(
        "rosbag2_bagfile_information:\n  version: {METADATA_VERSION}\n  storage_identifier: mcap\n  duration:\n    nanoseconds: {duration}\n  starting_time:\n    nanoseconds_since_epoch: {start}\n  message_count: {count}\n  topics_with_message_count:\n"
    );
    for t in RosTopic::ALL {
        let Some(n) = summary.per_topic.get(t.name()) else {
            continue;
        };
        let qos = qos_yaml(t.qos()).replace('\n', "\\n");
        y.push_str(&format!(
            "    - topic_metadata:\n        name: {}\n        type: {}\n        serialization_format: cdr\n        offered_qos_profiles: \"{qos}\"\n      message_count: {n}\n",
            t.name(),
            t.msg_type().name(),
        ));
    }
    y.push_str(&format!(
        "  compression_format: \"\"\n  compression_mode: \"\"\n  relative_file_paths:\n    - {file}\n  files:\n    - path: {file}\n      starting_time:\n        nanoseconds_since_epoch: {start}\n      duration:\n        nanoseconds: {duration}\n      message_count: {count}\n"
    ));
    y
}

/// Writes `messages` as a bag in `dir` (created; refused when it holds anything).
pub fn write_bag(dir: &Path, messages: &[BagMessage]) -> Result<BagSummary, RosbagError> {
    make_dir(dir)?;
    let name = dir
        .file_name()
        .map_or_else(|| "bag".into(), |n| n.to_string_lossy().into_owned());
    let path = dir.join(format!("{name}_0.mcap"));
    let mcap_err = |source| RosbagError::Mcap {
        path: path.clone(),
        source,
    };
    let file = File::create(&path).map_err(io(&path))?;
    let options = mcap::WriteOptions::new()
        .profile("ros2")
        .library(concat!("crackbot-rosbag ", env!("CARGO_PKG_VERSION")))
        .compression(Some(mcap::Compression::Zstd));
    let mut w = options.create(BufWriter::new(file)).map_err(mcap_err)?;
    let mut schemas: BTreeMap<MsgType, u16> = BTreeMap::new();
    let mut channels: BTreeMap<RosTopic, (u16, u32)> = BTreeMap::new();
    let mut order: Vec<&BagMessage> = messages.iter().collect();
    order.sort_by_key(|m| m.log_time_ns);
    for t in RosTopic::ALL {
        if !messages.iter().any(|m| m.topic == t) {
            continue;
        }
        let ty = t.msg_type();
        let schema = match schemas.get(&ty) {
            Some(&id) => id,
            None => {
                let id = w
                    .add_schema(&ty.name(), "ros2msg", ty.definition().as_bytes())
                    .map_err(mcap_err)?;
                schemas.insert(ty, id);
                id
            }
        };
        let meta = BTreeMap::from([("offered_qos_profiles".to_string(), qos_yaml(t.qos()))]);
        let channel = w
            .add_channel(schema, t.name(), "cdr", &meta)
            .map_err(mcap_err)?;
        channels.insert(t, (channel, 0));
    }
    let mut per_topic = BTreeMap::new();
    for m in &order {
        let Some((channel, sequence)) = channels.get_mut(&m.topic) else {
            continue;
        };
        *sequence += 1;
        let header = mcap::records::MessageHeader {
            channel_id: *channel,
            sequence: *sequence,
            log_time: m.log_time_ns,
            publish_time: m.log_time_ns,
        };
        w.write_to_known_channel(&header, &m.data)
            .map_err(mcap_err)?;
        *per_topic.entry(m.topic.name()).or_insert(0) += 1;
    }
    let start_ns = order.first().map_or(0, |m| m.log_time_ns);
    let end_ns = order.last().map_or(0, |m| m.log_time_ns);
    let summary = BagSummary {
        dir: dir.to_path_buf(),
        mcap: path.clone(),
        per_topic,
        start_ns,
        duration_ns: end_ns - start_ns,
    };
    let yaml = metadata_yaml(&summary);
    let record = mcap::records::Metadata {
        name: "rosbag2".into(),
        metadata: BTreeMap::from([("serialized_metadata".to_string(), yaml.clone())]),
    };
    w.write_metadata(&record).map_err(mcap_err)?;
    w.finish().map_err(mcap_err)?;
    drop(w);
    let meta_path = dir.join("metadata.yaml");
    std::fs::write(&meta_path, yaml).map_err(io(&meta_path))?;
    Ok(summary)
}
