//! The acquisition demo on a simulated scene (`crackbot demo`, the README's main job today).
//!
//! ```text
//! simulated finger ─▶ firmware (on this host) ─▶ PTY ─▶ acquisition ─▶ CSV + summary
//! ```

use std::future::Future;
use std::path::PathBuf;
use std::time::Duration;

use crackbot_acquisition::calibration::Calibration;
use crackbot_acquisition::session::create_parent;
use crackbot_acquisition::{
    record_stream, PortConfig, RecordMeta, Sample, SampleRecorder, SensorStream, StreamReport,
};
use crackbot_emulator::{Corruption, EmulatorConfig, EmulatorReport, PtyEmulator, SimSource};
use crackbot_protocol::SAMPLE_RATE_HZ;
use crackbot_sim::Scene;
use serde::Serialize;

use crate::MissionError;

/// Seed of the simulated finger's noise in the demo.
pub const DEMO_SEED: u64 = 7;
/// How long the PTY stays open after the last frame, so the reader drains it.
const LINGER: Duration = Duration::from_millis(300);
/// Slack on top of the demo's length before the reader gives up.
const READ_SLACK: Duration = Duration::from_secs(1);

/// What the simulated finger slides on.
#[derive(Debug, Clone, PartialEq)]
pub enum DemoSurface {
    /// The first crack of the built-in default scene.
    BuiltinScene,
    /// The first crack of a scene file.
    SceneFile(PathBuf),
    /// A plate with one crack of this width, mm.
    Crack {
        /// Width of the crack, mm.
        width_mm: f64,
    },
}

/// Settings of the demo.
#[derive(Debug, Clone)]
pub struct DemoConfig {
    /// Seconds of sensor data to stream.
    pub seconds: f64,
    /// The recording to write.
    pub out: PathBuf,
    /// Probability of a flipped byte on the emulated line.
    pub flip_rate: f64,
    /// What the finger slides on.
    pub surface: DemoSurface,
    /// The calibration the means are reported in physical units with.
    pub calibration: Calibration,
}

impl DemoConfig {
    /// Five seconds across the first crack of the built-in scene, recorded to `out`, clean line,
    /// the example calibration.
    pub fn new(out: impl Into<PathBuf>) -> Result<Self, MissionError> {
        Ok(DemoConfig {
            seconds: 5.0,
            out: out.into(),
            flip_rate: 0.0,
            surface: DemoSurface::BuiltinScene,
            calibration: Calibration::example()?,
        })
    }
}

/// What the demo did: the stream's summary (the keys of [`StreamReport`], flattened), where the
/// recording went, and the emulator's own account.
#[derive(Debug, Clone, Serialize)]
pub struct DemoReport {
    /// Summary of the samples the acquisition received.
    #[serde(flatten)]
    pub stream: StreamReport,
    /// The CSV file written.
    pub recording: String,
    /// Rows written to it.
    pub rows_written: u64,
    /// What the emulated sensor sent.
    pub emulator: EmulatorReport,
    /// The pseudo-terminal the samples came over.
    pub port: String,
}

/// The simulated sensor source of `surface`.
fn source_of(surface: &DemoSurface) -> Result<SimSource, MissionError> {
    Ok(match surface {
        DemoSurface::Crack { width_mm } => SimSource::over_crack(*width_mm, DEMO_SEED)?,
        DemoSurface::SceneFile(path) => {
            SimSource::across_first_crack(&Scene::load(path)?, DEMO_SEED)?
        }
        DemoSurface::BuiltinScene => {
            SimSource::across_first_crack(&Scene::builtin_default(), DEMO_SEED)?
        }
    })
}

/// Runs the demo: starts the emulated sensor on a new pseudo-terminal, reads it back over the
/// serial path into `config.out` until the sensor's samples are in (or `stop` completes), and
/// reports. `on_started` gets the device path once the reader is open; `on_sample` sees every
/// recorded sample.
pub async fn run_demo(
    config: &DemoConfig,
    stop: impl Future<Output = ()>,
    on_started: impl FnOnce(&str),
    on_sample: impl FnMut(&Sample),
) -> Result<DemoReport, MissionError> {
    if !(config.seconds.is_finite() && config.seconds > 0.0) {
        return Err(MissionError::Setting {
            field: "seconds",
            value: config.seconds,
            allowed: "a positive number of seconds",
        });
    }
    let rate = f64::from(SAMPLE_RATE_HZ);
    let emulator_config = EmulatorConfig {
        ticks: Some((config.seconds * rate).round() as u64),
        corruption: Corruption {
            flip_rate: config.flip_rate,
            ..Default::default()
        },
        ..Default::default()
    };
    emulator_config.corruption.validate()?;
    // The simulator is set up before anything streams, so a bad scene fails first.
    let source = source_of(&config.surface)?;
    let emulator = PtyEmulator::spawn(emulator_config, source, LINGER)?;
    let port = emulator.path().to_string();
    let mut stream = SensorStream::open(&PortConfig::new(&port))?;
    create_parent(&config.out)?;
    let mut recorder = SampleRecorder::create(&config.out)?;
    on_started(&port);
    let outcome = record_stream(
        &mut stream,
        &mut recorder,
        &RecordMeta::default(),
        Some(Duration::from_secs_f64(config.seconds) + READ_SLACK),
        stop,
        on_sample,
    )
    .await;
    emulator.stop();
    let emulator_report = emulator.join()?;
    let link = stream.stats();
    let rows_written = recorder.finish()?;
    let outcome = outcome?;
    if outcome.summary.samples() == 0 {
        return Err(MissionError::NoSamples { port });
    }
    Ok(DemoReport {
        stream: outcome.summary.report(&link, Some(&config.calibration)),
        recording: config.out.display().to_string(),
        rows_written,
        emulator: emulator_report,
        port,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn runtime() -> tokio::runtime::Runtime {
        tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()
            .unwrap()
    }

    #[test]
    fn the_demo_streams_the_simulated_crack_over_a_real_pty() {
        let dir = tempfile::tempdir().unwrap();
        let mut config = DemoConfig::new(dir.path().join("demo.csv")).unwrap();
        config.seconds = 1.0;
        config.surface = DemoSurface::Crack { width_mm: 5.0 };
        let mut seen = 0u64;
        let mut started = None;
        let report = runtime()
            .block_on(run_demo(
                &config,
                std::future::pending(),
                |p| started = Some(p.to_string()),
                |_| seen += 1,
            ))
            .unwrap();
        assert_eq!(started.as_deref(), Some(report.port.as_str()));
        assert_eq!(report.stream.samples, 400);
        assert_eq!(seen, 400);
        assert_eq!(report.rows_written, 400);
        assert_eq!(report.emulator.ticks, 400);
        assert_eq!(report.stream.link.decoder.crc_errors, 0);
        let json = serde_json::to_value(&report).unwrap();
        for key in ["samples", "host_rate_hz", "link", "recording", "emulator"] {
            assert!(json.get(key).is_some(), "{key} missing from {json}");
        }
    }

    #[test]
    fn bad_settings_are_refused_before_anything_streams() {
        let mut config = DemoConfig::new("/nonexistent/never-written.csv").unwrap();
        config.seconds = -1.0;
        let err = runtime()
            .block_on(run_demo(&config, std::future::pending(), |_| {}, |_| {}))
            .unwrap_err();
        assert!(
            matches!(err, MissionError::Setting { field: "seconds", value, .. } if value == -1.0),
            "{err}"
        );
        config.seconds = 1.0;
        config.surface = DemoSurface::SceneFile("/nonexistent/scene.toml".into());
        let err = runtime()
            .block_on(run_demo(&config, std::future::pending(), |_| {}, |_| {}))
            .unwrap_err();
        assert!(err.to_string().contains("scene.toml"), "{err}");
    }
}
