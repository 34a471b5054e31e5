//! Replays a saved mission (the folder `crackbot run --out DIR` writes: `mission.mcap`,
//! `report.json`, `frame.png`, `slide-NNN.csv`) as the telemetry a live robot would have sent,
//! so a replay shows in the same views.
//!
//! From the mission's log (`mission.mcap`, `crackbot-mcap`), every sample and verdict comes at
//! the time it was logged. A folder without one (written before the log existed) is read from
//! its slide recordings, which carry no clock: their samples are laid end to end at 400 Hz, with
//! half a second between slides. The report carries no camera homography: the plan's workspace is
//! drawn over the whole frame (an approximation; the app says so).

use std::path::{Path, PathBuf};

use crackbot_telemetry::wire::{
    CameraFrame, Detection, MissionStatus, PassVerdict, Phase, PlannedSlide, PlannedSlides,
    TactileSample, Telemetry,
};
use serde_json::Value;

use crate::OperatorError;

/// Sample rate of the recordings.
pub const RATE_HZ: f64 = 400.0;
/// Pause laid between two slides' recordings, s.
pub const GAP_S: f64 = 0.5;

/// A saved mission, as telemetry in the order a robot sends it.
#[derive(Debug, Clone)]
pub struct Replay {
    /// Everything, in order (the status first, the final status with the report last).
    pub telemetry: Vec<Telemetry>,
    /// Whether the overlay's homography is the workspace fitted to the frame.
    pub approximate_overlay: bool,
}

fn bad(path: &Path, detail: impl std::fmt::Display) -> OperatorError {
    OperatorError::Replay {
        path: path.to_path_buf(),
        detail: detail.to_string(),
    }
}

fn f64_at(v: &Value, key: &str) -> Option<f64> {
    v.get(key).and_then(Value::as_f64)
}

fn point(v: &Value, key: &str) -> Option<[f64; 2]> {
    let a = v.get(key)?.as_array()?;
    Some([a.first()?.as_f64()?, a.get(1)?.as_f64()?])
}

/// Reads the mission saved in `dir`: its `mission.mcap` when it has one (real timestamps), else
/// its report and slide recordings. `dir` may also be an MCAP file.
pub fn load(dir: &Path) -> Result<Replay, OperatorError> {
    if dir
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
    {
        return load_mcap(dir);
    }
    let log = dir.join(LOG_FILE);
    if log.is_file() {
        return load_mcap(&log);
    }
    load_folder(dir)
}

/// The log a mission writes in its folder.
pub const LOG_FILE: &str = "mission.mcap";

/// A mission's status message.
fn status_of(mode: &str, scene: &str, phase: Phase, report_json: Option<String>) -> Telemetry {
    Telemetry::Mission(MissionStatus {
        mission: 1,
        mode: mode.to_string(),
        scene: scene.to_string(),
        phase,
        report_json,
    })
}

/// What a replay shows before the first slide: the statuses, the frame (`png`), the candidates
/// and the plan, from the report.
struct Header {
    out: Vec<Telemetry>,
    approximate_overlay: bool,
    /// Slides planned.
    of: u32,
    mode: String,
    scene: String,
}

fn header(
    report: &Value,
    png: Option<Vec<u8>>,
    frame_path: &Path,
) -> Result<Header, OperatorError> {
    let mode = report["mode"].as_str().unwrap_or("fused").to_string();
    let scene = report["scene"].as_str().unwrap_or("?").to_string();
    let status =
        |phase: Phase, report_json: Option<String>| status_of(&mode, &scene, phase, report_json);
    let mut out = vec![status(Phase::Starting, None)];

    let workspace = report["plan"]["workspace"].as_object().map(|w| {
        let g = |k: &str| w.get(k).and_then(Value::as_f64).unwrap_or(0.0);
        [g("x_min_mm"), g("x_max_mm"), g("y_min_mm"), g("y_max_mm")]
    });
    let mut approximate_overlay = false;
    if let Some(png) = png {
        let (width, height) = image::ImageReader::new(std::io::Cursor::new(&png))
            .with_guessed_format()
            .map_err(|e| bad(frame_path, e))?
            .into_dimensions()
            .map_err(|e| bad(frame_path, e))?;
        // The mission's own homography (reports since the frame was saved in them), else the
        // workspace fitted to the frame.
        let saved = report["frame"]["surface_to_image"]
            .as_array()
            .and_then(|rows| {
                let mut m = [[0.0; 3]; 3];
                for (i, row) in rows.iter().enumerate().take(3) {
                    for (j, v) in row.as_array()?.iter().enumerate().take(3) {
                        m[i][j] = v.as_f64()?;
                    }
                }
                (rows.len() == 3).then_some(m)
            });
        approximate_overlay = saved.is_none();
        out.push(status(Phase::Perceiving, None));
        out.push(Telemetry::Camera(CameraFrame {
            width,
            height,
            surface_to_image: saved.unwrap_or_else(|| {
                crate::overlay::workspace_to_frame(
                    workspace.unwrap_or([0.0, 200.0, 0.0, 100.0]),
                    width,
                    height,
                )
            }),
            png,
        }));
    }
    let detections: Vec<Detection> = report["candidates"]
        .as_array()
        .map(|a| a.iter().filter_map(detection).collect())
        .unwrap_or_default();
    out.push(Telemetry::Detections(detections));

    let slides: Vec<PlannedSlide> = report["plan"]["slides"]
        .as_array()
        .map(|a| a.iter().filter_map(planned_slide).collect())
        .unwrap_or_default();
    let of = slides.len() as u32;
    if report["plan"].is_object() {
        out.push(status(Phase::Exploring { done: 0, of }, None));
        out.push(Telemetry::Plan(PlannedSlides {
            slides,
            estimated_s: f64_at(&report["plan"], "estimated_s").unwrap_or(0.0),
        }));
    }

    Ok(Header {
        out,
        approximate_overlay,
        of,
        mode,
        scene,
    })
}

/// Reads a mission log (`mission.mcap`): the frame, the report's candidates and plan, and the
/// samples and verdicts at the times they were logged.
fn load_mcap(path: &Path) -> Result<Replay, OperatorError> {
    use crackbot_mcap::JsonTopic;
    let log = crackbot_mcap::read_log(path).map_err(|e| bad(path, e))?;
    let report = log
        .json(JsonTopic::Report)
        .next()
        .map(|(_, v)| v.clone())
        .ok_or_else(|| {
            bad(
                path,
                "no /mission/report in the log: the mission did not finish",
            )
        })?;
    let text = report.to_string();
    let png = log.frame().map(|(_, data)| data.to_vec());
    let Header {
        mut out,
        approximate_overlay,
        of,
        mode,
        scene,
    } = header(&report, png, path)?;
    let rows = crackbot_mcap::tactile_rows(&log).map_err(|e| bad(path, e))?;
    // The samples in chunks of 25 ms, as the robot sends them, and the verdicts, by log time.
    let mut events: Vec<(u64, Telemetry)> = rows
        .chunks(10)
        .map(|c| {
            let samples = c
                .iter()
                .map(|r| TactileSample {
                    t_s: r.t_s,
                    raw: r.raw,
                })
                .collect();
            (c[0].log_time_ns, Telemetry::Tactile(samples))
        })
        .collect();
    events.extend(
        log.json(JsonTopic::Verdict)
            .filter_map(|(t, v)| Some((t, Telemetry::Verdict(verdict(v)?)))),
    );
    events.sort_by_key(|(t, _)| *t);
    let mut done = 0u32;
    for (_, e) in events {
        let judged = matches!(e, Telemetry::Verdict(_));
        out.push(e);
        if judged {
            done += 1;
            let phase = Phase::Exploring {
                done,
                of: of.max(done),
            };
            out.push(status_of(&mode, &scene, phase, None));
        }
    }
    out.push(status_of(&mode, &scene, Phase::Finished, Some(text)));
    Ok(Replay {
        telemetry: out,
        approximate_overlay,
    })
}

/// Reads the folder `crackbot run --out DIR` wrote without a log: the report, `frame.png` and
/// the slide recordings, laid end to end at 400 Hz.
fn load_folder(dir: &Path) -> Result<Replay, OperatorError> {
    let report_path = dir.join("report.json");
    let text = std::fs::read_to_string(&report_path).map_err(|e| bad(&report_path, e))?;
    let report: Value = serde_json::from_str(&text).map_err(|e| bad(&report_path, e))?;
    if !report.is_object() {
        return Err(bad(&report_path, "not a mission report (a JSON object)"));
    }
    let frame_path = dir.join("frame.png");
    let png = std::fs::read(&frame_path).ok();
    let Header {
        mut out,
        approximate_overlay,
        of,
        mode,
        scene,
    } = header(&report, png, &frame_path)?;
    let status =
        |phase: Phase, report_json: Option<String>| status_of(&mode, &scene, phase, report_json);
    let passes = report["passes"].as_array().cloned().unwrap_or_default();
    let mut t = 0.0;
    for (i, pass) in passes.iter().enumerate() {
        if let Some(rec) = pass["recording"].as_str() {
            let path = recording_path(dir, rec);
            let samples = read_slide_csv(&path, t)?;
            if let Some(last) = samples.last() {
                t = last.t_s + GAP_S;
            }
            // Chunks of 25 ms, as the robot sends them.
            for chunk in samples.chunks(10) {
                out.push(Telemetry::Tactile(chunk.to_vec()));
            }
        }
        if let Some(v) = verdict(pass) {
            out.push(Telemetry::Verdict(v));
        }
        out.push(status(
            Phase::Exploring {
                done: (i + 1) as u32,
                of: of.max((i + 1) as u32),
            },
            None,
        ));
    }
    out.push(status(Phase::Finished, Some(text)));
    Ok(Replay {
        telemetry: out,
        approximate_overlay,
    })
}

/// A recording's path: as written, or beside the report when the folder has moved.
fn recording_path(dir: &Path, rec: &str) -> PathBuf {
    let p = PathBuf::from(rec);
    if p.is_file() {
        return p;
    }
    match p.file_name() {
        Some(name) => dir.join(name),
        None => dir.join(rec),
    }
}

/// One slide's recording (`d1,d2,d3,p,direction,x_mm`), its samples from time `t0` at 400 Hz.
pub fn read_slide_csv(path: &Path, t0: f64) -> Result<Vec<TactileSample>, OperatorError> {
    let text = std::fs::read_to_string(path).map_err(|e| bad(path, e))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines
        .next()
        .ok_or_else(|| bad(path, "empty recording"))?
        .split(',')
        .map(str::trim)
        .collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .ok_or_else(|| bad(path, format!("no column {name:?} in the header")))
    };
    let cols = [col("d1")?, col("d2")?, col("d3")?, col("p")?];
    let mut out = Vec::new();
    for (n, line) in lines.enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').collect();
        let mut raw = [0u16; 4];
        for (k, &c) in cols.iter().enumerate() {
            let f = fields
                .get(c)
                .ok_or_else(|| bad(path, format!("line {}: too few fields", n + 2)))?;
            let v: f64 = f
                .trim()
                .parse()
                .map_err(|_| bad(path, format!("line {}: {f:?} is not a number", n + 2)))?;
            raw[k] = v.round().clamp(0.0, u16::MAX as f64) as u16;
        }
        out.push(TactileSample {
            t_s: t0 + out.len() as f64 / RATE_HZ,
            raw,
        });
    }
    Ok(out)
}

fn detection(c: &Value) -> Option<Detection> {
    Some(Detection {
        id: c["id"].as_u64()?,
        centre_mm: point(c, "centre_mm")?,
        axis_deg: f64_at(c, "axis_deg").unwrap_or(0.0),
        length_mm: f64_at(c, "length_mm").unwrap_or(0.0),
        width_mm: f64_at(c, "width_mm"),
        score: f64_at(c, "score").unwrap_or(0.0),
    })
}

fn planned_slide(s: &Value) -> Option<PlannedSlide> {
    Some(PlannedSlide {
        candidates: s["candidates"]
            .as_array()
            .map(|a| a.iter().filter_map(Value::as_u64).collect())
            .unwrap_or_default(),
        start_mm: point(s, "start_mm")?,
        end_mm: point(s, "end_mm")?,
        passes: s["passes"].as_u64().unwrap_or(1) as u32,
        speed_mm_s: f64_at(s, "speed_mm_s").unwrap_or(0.0),
    })
}

fn verdict(p: &Value) -> Option<PassVerdict> {
    Some(PassVerdict {
        id: p["id"].as_u64()? as u32,
        candidate: p["candidate"].as_u64(),
        start_mm: point(p, "start_mm")?,
        end_mm: point(p, "end_mm")?,
        samples: p["samples"].as_u64().unwrap_or(0),
        class: p["class"].as_str().map(str::to_string),
        confidence: f64_at(p, "confidence").unwrap_or(0.0),
        width_mm: f64_at(p, "width_mm"),
        doubt: p["doubt"].as_str().map(str::to_string),
        dip_mm: p["dip"]
            .as_object()
            .and_then(|d| Some([d.get("centre_mm")?.as_f64()?, d.get("width_mm")?.as_f64()?])),
    })
}
