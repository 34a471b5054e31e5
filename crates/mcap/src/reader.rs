//! Reading a mission log back, every message decoded as its channel's schema says.

use std::path::{Path, PathBuf};

use foxglove::messages::{
    CompressedImage, FrameTransform, ImageAnnotations, Log as FoxgloveLog, SceneUpdate,
};
use foxglove::Decode;
use serde_json::Value;

use crate::topics::{JsonTopic, Topic};
use crate::LogError;

/// A message, decoded.
#[derive(Debug, Clone, PartialEq)]
pub enum Payload {
    /// The camera frame (`foxglove.CompressedImage`).
    Image {
        /// Its format ("png").
        format: String,
        /// The encoded image.
        data: Vec<u8>,
    },
    /// A log line (`foxglove.Log`).
    Log {
        /// Its level (`foxglove.Log.Level`).
        level: i32,
        /// The text.
        message: String,
    },
    /// A JSON message ([`JsonTopic`]).
    Json(Value),
    /// A Foxglove message a replay does not need (annotations, scene, transform), decoded.
    Decoded,
    /// A channel this crate does not write (another tool's), left as it is.
    Unknown,
}

/// One message of the log.
#[derive(Debug, Clone, PartialEq)]
pub struct LoggedMessage {
    /// Its channel's topic.
    pub topic: String,
    /// When it was logged, Unix ns (the host's synchronised clock).
    pub log_time_ns: u64,
    /// What it says.
    pub payload: Payload,
}

/// A mission's log as read back.
#[derive(Debug, Clone, PartialEq)]
pub struct MissionLog {
    /// The file.
    pub path: PathBuf,
    /// Every message, in the file's order.
    pub messages: Vec<LoggedMessage>,
}

impl MissionLog {
    /// The JSON messages of `topic` with their log times, in order.
    pub fn json(&self, topic: JsonTopic) -> impl Iterator<Item = (u64, &Value)> + '_ {
        self.messages.iter().filter_map(move |m| match &m.payload {
            Payload::Json(v) if m.topic == topic.topic() => Some((m.log_time_ns, v)),
            _ => None,
        })
    }

    /// The first camera frame: its format and bytes.
    pub fn frame(&self) -> Option<(&str, &[u8])> {
        self.messages.iter().find_map(|m| match &m.payload {
            Payload::Image { format, data } => Some((format.as_str(), data.as_slice())),
            _ => None,
        })
    }

    /// The earliest log time, Unix ns.
    pub fn start_ns(&self) -> Option<u64> {
        self.messages.iter().map(|m| m.log_time_ns).min()
    }
}

fn corrupt(path: &Path, detail: impl std::fmt::Display) -> LogError {
    LogError::Corrupt {
        path: path.to_path_buf(),
        detail: detail.to_string(),
    }
}

/// Reads the whole log at `path`. A file cut short (no summary or footer), one that is not
/// MCAP, or a message that does not decode as its schema is an error naming which.
pub fn read_log(path: &Path) -> Result<MissionLog, LogError> {
    let buf = std::fs::read(path).map_err(|source| LogError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let summary = match mcap::Summary::read(&buf) {
        Ok(Some(s)) => s,
        Ok(None) => return Err(corrupt(path, "no summary: the writer did not finish it")),
        Err(e) => return Err(corrupt(path, e)),
    };
    let mut raw = Vec::new();
    for record in mcap::read::LinearReader::new(&buf).map_err(|e| corrupt(path, e))? {
        match record.map_err(|e| corrupt(path, e))? {
            mcap::records::Record::Chunk { header, data } => {
                let inner = unchunk(&header, &data).map_err(|d| corrupt(path, d))?;
                for r in mcap::read::LinearReader::sans_magic(&inner) {
                    if let mcap::records::Record::Message { header, data } =
                        r.map_err(|e| corrupt(path, e))?
                    {
                        raw.push((header, data.into_owned()));
                    }
                }
            }
            mcap::records::Record::Message { header, data } => {
                raw.push((header, data.into_owned()));
            }
            _ => {}
        }
    }
    let mut messages = Vec::with_capacity(raw.len());
    for (index, (header, data)) in raw.into_iter().enumerate() {
        let Some(channel) = summary.channels.get(&header.channel_id) else {
            return Err(corrupt(
                path,
                format!(
                    "message {index} is on channel {}, which the summary does not list",
                    header.channel_id
                ),
            ));
        };
        let topic = channel.topic.clone();
        let payload = decode(&topic, &data).map_err(|detail| LogError::BadMessage {
            path: path.to_path_buf(),
            topic: topic.clone(),
            index,
            detail,
        })?;
        messages.push(LoggedMessage {
            topic,
            log_time_ns: header.log_time,
            payload,
        });
    }
    Ok(MissionLog {
        path: path.to_path_buf(),
        messages,
    })
}

/// Largest chunk a log may hold uncompressed (this crate writes 256 KiB ones): a corrupt size
/// field must be an error, not an allocation the reader cannot make.
const MAX_CHUNK_BYTES: u64 = 1 << 30;

/// A chunk's records, decompressed and checked against its CRC, within its stated size. (The
/// `mcap` crate's own stream trusts the record lengths inside a chunk: one corrupt length
/// aborts the process on an allocation of exabytes.)
fn unchunk(header: &mcap::records::ChunkHeader, data: &[u8]) -> Result<Vec<u8>, String> {
    if header.uncompressed_size > MAX_CHUNK_BYTES {
        return Err(format!(
            "a chunk says it holds {} bytes uncompressed (at most {MAX_CHUNK_BYTES})",
            header.uncompressed_size
        ));
    }
    let size = header.uncompressed_size as usize;
    let inner = match header.compression.as_str() {
        "" => data.to_vec(),
        "zstd" => zstd::bulk::decompress(data, size).map_err(|e| format!("a zstd chunk: {e}"))?,
        other => {
            return Err(format!(
                "a chunk compressed with {other:?}, which this reader does not read"
            ))
        }
    };
    if inner.len() != size {
        return Err(format!(
            "a chunk holds {} bytes, its header says {size}",
            inner.len()
        ));
    }
    if header.uncompressed_crc != 0 && crc32fast::hash(&inner) != header.uncompressed_crc {
        return Err("a chunk's CRC does not match its content".into());
    }
    Ok(inner)
}

/// Decodes one message of `topic`.
fn decode(topic: &str, data: &[u8]) -> Result<Payload, String> {
    let text = |e: &dyn std::fmt::Display| e.to_string();
    if JsonTopic::of_topic(topic).is_some() {
        return serde_json::from_slice(data)
            .map(Payload::Json)
            .map_err(|e| text(&e));
    }
    let Some(t) = Topic::ALL.into_iter().find(|t| t.topic() == topic) else {
        return Ok(Payload::Unknown);
    };
    Ok(match t {
        Topic::Image => {
            let m = CompressedImage::decode(data).map_err(|e| text(&e))?;
            Payload::Image {
                format: m.format,
                data: m.data.to_vec(),
            }
        }
        Topic::Log => {
            let m = FoxgloveLog::decode(data).map_err(|e| text(&e))?;
            Payload::Log {
                level: m.level,
                message: m.message,
            }
        }
        Topic::Detections => {
            ImageAnnotations::decode(data).map_err(|e| text(&e))?;
            Payload::Decoded
        }
        Topic::Scene => {
            SceneUpdate::decode(data).map_err(|e| text(&e))?;
            Payload::Decoded
        }
        Topic::Transform => {
            FrameTransform::decode(data).map_err(|e| text(&e))?;
            Payload::Decoded
        }
    })
}

/// One sample of the `/tactile` channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TactileRow {
    /// Mission (or recording) time, s.
    pub t_s: f64,
    /// When it was logged, Unix ns.
    pub log_time_ns: u64,
    /// D1, D2, D3, P, counts.
    pub raw: [u16; 4],
    /// The slide the finger was down in.
    pub slide: Option<u32>,
    /// Where it was along the stroke, mm.
    pub along_mm: Option<f64>,
}

/// The `/tactile` channel's samples, in order; a sample missing a field, or with a count
/// outside 0–65535, is an error naming it.
pub fn tactile_rows(log: &MissionLog) -> Result<Vec<TactileRow>, LogError> {
    let bad = |index: usize, detail: String| LogError::BadMessage {
        path: log.path.clone(),
        topic: JsonTopic::Tactile.topic().into(),
        index,
        detail,
    };
    log.json(JsonTopic::Tactile)
        .enumerate()
        .map(|(i, (log_time_ns, v))| {
            let count = |k: &str| {
                v.get(k)
                    .and_then(Value::as_u64)
                    .and_then(|c| u16::try_from(c).ok())
                    .ok_or_else(|| bad(i, format!("{k} is not a count (0–65535): {}", v[k])))
            };
            Ok(TactileRow {
                t_s: v["t_s"].as_f64().ok_or_else(|| bad(i, "no t_s".into()))?,
                log_time_ns,
                raw: [count("d1")?, count("d2")?, count("d3")?, count("p")?],
                slide: v
                    .get("slide")
                    .and_then(Value::as_u64)
                    .and_then(|s| u32::try_from(s).ok()),
                along_mm: v.get("along_mm").and_then(Value::as_f64),
            })
        })
        .collect()
}
