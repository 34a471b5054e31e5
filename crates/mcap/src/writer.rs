//! Writing a mission log: one Foxglove context per log, its MCAP file as a sink (and, with the
//! feature `live`, a WebSocket server as another).

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use foxglove::messages::{
    line_primitive, log, points_annotation, Color, CompressedImage, FrameTransform,
    ImageAnnotations, LinePrimitive, Log, Point2, Point3, PointsAnnotation, Quaternion,
    SceneEntity, SceneUpdate, TextAnnotation, Timestamp, Vector3,
};
use foxglove::{
    Channel, ChannelBuilder, Context, McapCompression, McapWriteOptions, McapWriterHandle,
    PartialMetadata, RawChannel, Schema,
};
use serde::Serialize;

use crate::topics::{JsonTopic, Topic};
use crate::LogError;

/// Bytes of messages per chunk before it is compressed and indexed: about 2 s of a mission's
/// tactile samples, so a viewer seeking decompresses little.
const CHUNK_BYTES: u64 = 256 * 1024;

/// A line in image pixels (a box's outline, a centre line).
#[derive(Debug, Clone, PartialEq)]
pub struct Polyline {
    /// Its points, px.
    pub points: Vec<[f64; 2]>,
    /// Closed (a box) or open (a centre line).
    pub closed: bool,
    /// Colour, RGBA 0–1.
    pub rgba: [f64; 4],
}

/// A text drawn on the frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Label {
    /// Where, px.
    pub at: [f64; 2],
    /// What.
    pub text: String,
}

/// A line on the surface (a planned slide, a candidate's course), mm.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneLine {
    /// Its points on the surface, mm (z above the plate).
    pub points_mm: Vec<[f64; 3]>,
    /// Width drawn, mm.
    pub thickness_mm: f64,
    /// Colour, RGBA 0–1.
    pub rgba: [f64; 4],
}

/// One sensor sample as the `/tactile` and `/slide` channels carry it (their JSON Schemas).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SampleMessage {
    /// Mission (or recording) time, s.
    pub t_s: f64,
    /// D1, counts.
    pub d1: u16,
    /// D2, counts.
    pub d2: u16,
    /// D3, counts.
    pub d3: u16,
    /// P, counts.
    pub p: u16,
    /// The slide the finger was down in.
    pub slide: Option<u32>,
    /// Where it was along the stroke, mm.
    pub along_mm: Option<f64>,
}

impl SampleMessage {
    /// The sample `raw` (D1, D2, D3, P) at `t_s`.
    pub fn new(t_s: f64, raw: [u16; 4], slide: Option<u32>, along_mm: Option<f64>) -> Self {
        let [d1, d2, d3, p] = raw;
        SampleMessage {
            t_s,
            d1,
            d2,
            d3,
            p,
            slide,
            along_mm,
        }
    }
}

/// How much a log line matters (`foxglove.Log`'s levels).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LogLevel {
    /// Information.
    Info,
    /// Something to look at.
    Warning,
    /// The mission failed.
    Error,
}

impl LogLevel {
    /// Its `foxglove.Log.Level` number (2 info, 3 warning, 4 error), as [`crate::Payload::Log`]
    /// carries it.
    pub fn foxglove_level(self) -> i32 {
        let level = match self {
            LogLevel::Info => log::Level::Info,
            LogLevel::Warning => log::Level::Warning,
            LogLevel::Error => log::Level::Error,
        };
        level as i32
    }
}

/// A mission's log being written: every channel of [`Topic`] and [`JsonTopic`], stamped with
/// the host's clock.
pub struct LogWriter {
    ctx: Arc<Context>,
    path: PathBuf,
    mcap: Option<McapWriterHandle<BufWriter<File>>>,
    /// Unix nanoseconds of the mission's clock zero (its `t_s = 0`).
    origin_ns: u64,
    image: Channel<CompressedImage>,
    detections: Channel<ImageAnnotations>,
    scene: Channel<SceneUpdate>,
    transform: Channel<FrameTransform>,
    log: Channel<Log>,
    json: BTreeMap<JsonTopic, Arc<RawChannel>>,
    #[cfg(feature = "live")]
    pub(crate) server: Option<foxglove::WebSocketServerHandle>,
}

impl std::fmt::Debug for LogWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LogWriter")
            .field("path", &self.path)
            .field("origin_ns", &self.origin_ns)
            .finish_non_exhaustive()
    }
}

fn sdk(what: &'static str) -> impl FnOnce(foxglove::FoxgloveError) -> LogError {
    move |e| LogError::Sdk {
        what,
        detail: e.to_string(),
    }
}

fn color([r, g, b, a]: [f64; 4]) -> Option<Color> {
    Some(Color { r, g, b, a })
}

impl LogWriter {
    /// Creates the log at `path` (replacing a file there), its clock zero at `origin_ns` (Unix
    /// nanoseconds): a message at mission time `t_s` is stamped `origin_ns + t_s·10⁹`.
    pub fn create(path: &Path, origin_ns: u64) -> Result<Self, LogError> {
        let io = |source| LogError::Io {
            path: path.to_path_buf(),
            source,
        };
        match std::fs::remove_file(path) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(io(e)),
        }
        let file = File::create_new(path).map_err(io)?;
        let ctx = Context::new();
        let options = McapWriteOptions::new()
            .compression(Some(McapCompression::Zstd))
            .chunk_size(Some(CHUNK_BYTES));
        let mcap = ctx
            .mcap_writer_with_options(options)
            .create(BufWriter::new(file))
            .map_err(sdk("the MCAP sink"))?;
        let build = |t: Topic| ChannelBuilder::new(t.topic()).context(&ctx);
        let mut json = BTreeMap::new();
        for t in JsonTopic::ALL {
            let schema = Schema::new(t.schema(), "jsonschema", t.json_schema().into_bytes());
            let channel = ChannelBuilder::new(t.topic())
                .context(&ctx)
                .message_encoding("json")
                .schema(schema)
                .build_raw()
                .map_err(sdk("a JSON channel"))?;
            json.insert(t, channel);
        }
        Ok(LogWriter {
            image: build(Topic::Image).build(),
            detections: build(Topic::Detections).build(),
            scene: build(Topic::Scene).build(),
            transform: build(Topic::Transform).build(),
            log: build(Topic::Log).build(),
            json,
            path: path.to_path_buf(),
            mcap: Some(mcap),
            origin_ns,
            ctx,
            #[cfg(feature = "live")]
            server: None,
        })
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The Foxglove context the channels live in (for another sink).
    pub fn context(&self) -> &Arc<Context> {
        &self.ctx
    }

    /// Unix nanoseconds of mission time `t_s` (before the clock's zero too: the first samples
    /// of a stream can be older than the link; a time that is not finite is the zero).
    pub fn ns(&self, t_s: f64) -> u64 {
        let dt = if t_s.is_finite() {
            (t_s * 1e9).round() as i64
        } else {
            0
        };
        self.origin_ns.saturating_add_signed(dt)
    }

    fn stamp(&self, t_s: f64) -> (Option<Timestamp>, PartialMetadata) {
        let ns = self.ns(t_s);
        let ts = Timestamp::new(
            u32::try_from(ns / 1_000_000_000).unwrap_or(u32::MAX),
            (ns % 1_000_000_000) as u32,
        );
        (Some(ts), PartialMetadata::with_log_time(ns))
    }

    /// The camera frame, PNG bytes, at `t_s`.
    pub fn frame(&self, t_s: f64, png: &[u8]) {
        let (timestamp, meta) = self.stamp(t_s);
        let msg = CompressedImage {
            timestamp,
            frame_id: "camera".into(),
            data: png.to_vec().into(),
            format: "png".into(),
        };
        self.image.log_with_meta(&msg, meta);
    }

    /// The detections on the frame: their outlines and centre lines, and labels.
    pub fn detections(&self, t_s: f64, lines: &[Polyline], labels: &[Label]) {
        let (timestamp, meta) = self.stamp(t_s);
        let points = lines
            .iter()
            .map(|l| PointsAnnotation {
                timestamp,
                r#type: if l.closed {
                    points_annotation::Type::LineLoop
                } else {
                    points_annotation::Type::LineStrip
                } as i32,
                points: l.points.iter().map(|&[x, y]| Point2 { x, y }).collect(),
                outline_color: color(l.rgba),
                thickness: 2.0,
                ..Default::default()
            })
            .collect();
        let texts = labels
            .iter()
            .map(|l| TextAnnotation {
                timestamp,
                position: Some(Point2 {
                    x: l.at[0],
                    y: l.at[1],
                }),
                text: l.text.clone(),
                font_size: 14.0,
                text_color: color([1.0, 1.0, 1.0, 1.0]),
                background_color: color([0.0, 0.0, 0.0, 0.6]),
                ..Default::default()
            })
            .collect();
        let msg = ImageAnnotations {
            timestamp,
            points,
            texts,
            ..Default::default()
        };
        self.detections.log_with_meta(&msg, meta);
    }

    /// An entity `id` of lines on the surface (frame `surface`, drawn in metres as 3D viewers
    /// expect; the JSON channels keep mm).
    pub fn scene(&self, t_s: f64, id: &str, lines: &[SceneLine]) {
        let (timestamp, meta) = self.stamp(t_s);
        let lines = lines
            .iter()
            .map(|l| LinePrimitive {
                r#type: line_primitive::Type::LineStrip as i32,
                thickness: l.thickness_mm / 1e3,
                points: l
                    .points_mm
                    .iter()
                    .map(|&[x, y, z]| Point3 {
                        x: x / 1e3,
                        y: y / 1e3,
                        z: z / 1e3,
                    })
                    .collect(),
                color: color(l.rgba),
                ..Default::default()
            })
            .collect();
        let msg = SceneUpdate {
            entities: vec![SceneEntity {
                timestamp,
                frame_id: "surface".into(),
                id: id.into(),
                lines,
                ..Default::default()
            }],
            ..Default::default()
        };
        self.scene.log_with_meta(&msg, meta);
    }

    /// Where the finger is over the surface, mm, as the transform `surface` → `finger` (m).
    pub fn finger_at(&self, t_s: f64, [x, y, z]: [f64; 3]) {
        let (timestamp, meta) = self.stamp(t_s);
        let msg = FrameTransform {
            timestamp,
            parent_frame_id: "surface".into(),
            child_frame_id: "finger".into(),
            translation: Some(Vector3 {
                x: x / 1e3,
                y: y / 1e3,
                z: z / 1e3,
            }),
            rotation: Some(Quaternion {
                x: 0.0,
                y: 0.0,
                z: 0.0,
                w: 1.0,
            }),
        };
        self.transform.log_with_meta(&msg, meta);
    }

    /// A JSON message on `topic` at `t_s`.
    pub fn json<T: Serialize>(
        &self,
        topic: JsonTopic,
        t_s: f64,
        value: &T,
    ) -> Result<(), LogError> {
        let bytes = serde_json::to_vec(value).map_err(|source| LogError::Encode {
            topic: topic.topic(),
            source,
        })?;
        let (_, meta) = self.stamp(t_s);
        if let Some(c) = self.json.get(&topic) {
            c.log_with_meta(&bytes, meta);
        }
        Ok(())
    }

    /// A sample on `topic` (`/tactile` or `/slide`), stamped with its own time.
    pub fn sample(&self, topic: JsonTopic, s: &SampleMessage) -> Result<(), LogError> {
        self.json(topic, s.t_s, s)
    }

    /// A log line at `t_s`.
    pub fn log(&self, t_s: f64, level: LogLevel, message: &str) {
        let (timestamp, meta) = self.stamp(t_s);
        let msg = Log {
            timestamp,
            level: level.foxglove_level(),
            message: message.into(),
            name: "crackbot".into(),
            ..Default::default()
        };
        self.log.log_with_meta(&msg, meta);
    }

    /// Writes the summary and the indexes and closes the file (a live server stops too).
    pub fn finish(mut self) -> Result<PathBuf, LogError> {
        #[cfg(feature = "live")]
        if let Some(s) = self.server.take() {
            s.stop().detach_all();
        }
        if let Some(m) = self.mcap.take() {
            let mut w = m.close().map_err(sdk("closing the MCAP file"))?;
            std::io::Write::flush(&mut w).map_err(|source| LogError::Io {
                path: self.path.clone(),
                source,
            })?;
        }
        Ok(self.path.clone())
    }
}
