//! Recording sessions: read a stream into a recording until a time limit, a stop request (Ctrl-C)
//! or the port going away, losing nothing that was received; and playing recordings back.

use std::future::Future;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use crate::calibration::Calibration;
use crate::summary::{StreamReport, StreamSummary};
use crate::{
    AcquisitionError, LinkStats, PortConfig, RecordMeta, Replay, Sample, SampleRecorder,
    SensorStream,
};

/// How long the reader's last samples are waited for after the loop stops.
const DRAIN_WAIT: Duration = Duration::from_millis(200);

/// Why a recording loop ended.
#[derive(Debug)]
#[non_exhaustive]
pub enum RecordEnd {
    /// The time limit was reached.
    TimeLimit,
    /// The stop future completed (Ctrl-C in the CLI).
    Stopped,
    /// The stream ended by itself.
    StreamEnded,
    /// The port failed (unplugged, closed by the other side); everything received before is
    /// recorded.
    Disconnected(AcquisitionError),
}

/// What [`record_stream`] did: the statistics of every sample it recorded and why it ended.
#[derive(Debug)]
pub struct RecordOutcome {
    /// Statistics of the samples recorded.
    pub summary: StreamSummary,
    /// Why the loop ended.
    pub ended_by: RecordEnd,
}

/// Reads `stream` into `recorder` until `limit` has passed, `stop` completes, the stream ends or
/// the port fails. Then stops the reader and records whatever it had already received (waiting
/// up to 200 ms for it). `on_sample` sees every recorded sample (a progress bar, a live plot).
///
/// A recording error (disk full) ends the loop with that error; a disconnect is not an error of
/// this function but [`RecordEnd::Disconnected`], since everything received was saved.
pub async fn record_stream(
    stream: &mut SensorStream,
    recorder: &mut SampleRecorder,
    meta: &RecordMeta,
    limit: Option<Duration>,
    stop: impl Future<Output = ()>,
    mut on_sample: impl FnMut(&Sample),
) -> Result<RecordOutcome, AcquisitionError> {
    let mut summary = StreamSummary::new();
    let started = Instant::now();
    tokio::pin!(stop);
    let ended_by = loop {
        let remaining = limit.map(|l| l.saturating_sub(started.elapsed()));
        if remaining == Some(Duration::ZERO) {
            break RecordEnd::TimeLimit;
        }
        let timeout = tokio::time::sleep(remaining.unwrap_or(Duration::from_secs(3600)));
        tokio::select! {
            item = stream.next() => match item {
                Some(Ok(sample)) => {
                    recorder.record(&sample, meta)?;
                    summary.add(&sample);
                    on_sample(&sample);
                }
                Some(Err(e)) => break RecordEnd::Disconnected(e),
                None => break RecordEnd::StreamEnded,
            },
            _ = &mut stop => break RecordEnd::Stopped,
            _ = timeout => {}
        }
    };
    // Whatever the reader thread already received is recorded too.
    stream.stop();
    while let Ok(Some(Ok(sample))) = tokio::time::timeout(DRAIN_WAIT, stream.next()).await {
        recorder.record(&sample, meta)?;
        summary.add(&sample);
        on_sample(&sample);
    }
    Ok(RecordOutcome { summary, ended_by })
}

/// A recording session of `crackbot record`: which port, where to, and for how long.
#[derive(Debug, Clone)]
pub struct RecordSession {
    /// The sensor's serial port.
    pub port: PortConfig,
    /// The CSV file to write.
    pub out: PathBuf,
    /// Label, repetition and manipulator columns of every row.
    pub meta: RecordMeta,
    /// Stop after this long (`None`: until stopped or disconnected).
    pub limit: Option<Duration>,
}

/// The result of a [`RecordSession`].
#[derive(Debug)]
pub struct RecordReport {
    /// The samples recorded and the link's health.
    pub stream: StreamReport,
    /// Rows written to the file.
    pub rows: u64,
    /// The file written.
    pub out: PathBuf,
    /// Why it ended; a disconnect carries its error (every row received was saved).
    pub ended_by: RecordEnd,
}

impl RecordSession {
    /// Opens the port, records until the limit, `stop` or a disconnect, flushes the file and
    /// reports. The file is flushed before any error of the loop is returned.
    pub async fn run(
        &self,
        stop: impl Future<Output = ()>,
        on_sample: impl FnMut(&Sample),
    ) -> Result<RecordReport, AcquisitionError> {
        let mut stream = SensorStream::open(&self.port)?;
        create_parent(&self.out)?;
        let mut recorder = SampleRecorder::create(&self.out)?;
        let outcome = record_stream(
            &mut stream,
            &mut recorder,
            &self.meta,
            self.limit,
            stop,
            on_sample,
        )
        .await;
        let link = stream.stats();
        // Flush before anything else can fail.
        let rows = recorder.finish()?;
        let outcome = outcome?;
        Ok(RecordReport {
            stream: outcome.summary.report(&link, None),
            rows,
            out: self.out.clone(),
            ended_by: outcome.ended_by,
        })
    }
}

/// Plays `replay` to its end and summarises it (no link: the counters stay zero). `on_sample`
/// sees every sample.
pub async fn summarise_replay(
    mut replay: Replay,
    calibration: Option<&Calibration>,
    mut on_sample: impl FnMut(&Sample),
) -> StreamReport {
    let mut summary = StreamSummary::new();
    while let Some(sample) = replay.next().await {
        summary.add(&sample);
        on_sample(&sample);
    }
    summary.report(&LinkStats::default(), calibration)
}

/// Creates the folder `path` will be written into.
pub fn create_parent(path: &Path) -> Result<(), AcquisitionError> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|source| AcquisitionError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
    }
    Ok(())
}
