//! Reading frames from a serial port: the reader thread, gap tracking and link statistics.

use std::io::{ErrorKind, Read};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crackbot_protocol::{Decoder, DecoderStats, Flags, Frame, SAMPLE_PERIOD_US};
use serde::Serialize;
use tokio::sync::mpsc;

use crate::AcquisitionError;

/// One decoded sensor sample, as the host saw it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Sample {
    /// Sequence number sent by the firmware (wraps at 65 536).
    pub seq: u16,
    /// Device clock, µs since the first sample of this stream (unwrapped, monotonic).
    pub device_time_us: u64,
    /// Host clock when the bytes of this sample were read, since the stream was opened.
    pub host_time: Duration,
    /// Raw ADC counts of D1, D2, D3, P.
    pub raw: [u16; 4],
    /// Status flags (saturation per channel, overrun).
    pub flags: Flags,
    /// Frames missing immediately before this one (sequence jump), 0 when contiguous and after
    /// a restart (how many went unsent while the device rebooted is unknown).
    pub missing_before: u32,
    /// The device restarted just before this frame ([`SequenceTracker::observe`]).
    pub restarted: bool,
}

/// Counters of a link: the decoder's counters plus what the host learns from sequence numbers.
/// Serialised flat (`{"bytes": …, "frames": …, "crc_errors": …, "resyncs": …, "gaps": …}`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct LinkStats {
    /// Bytes, valid frames and the rejected chunks by cause.
    #[serde(flatten)]
    pub decoder: DecoderStats,
    /// Times the decoder dropped bytes and resynchronised ([`DecoderStats::resyncs`]).
    pub resyncs: u64,
    /// Sequence jumps seen (each one a run of lost frames).
    pub gaps: u64,
    /// Frames lost in those jumps.
    pub missing_frames: u64,
    /// Frames that carried the firmware's overrun flag.
    pub overrun_flags: u64,
    /// Frames with at least one saturated channel.
    pub saturated_frames: u64,
    /// Restarts of the device (reset, watchdog, power): its clock went back.
    pub restarts: u64,
}

impl LinkStats {
    /// Fraction of the frames sent (delivered + missing) that were delivered.
    pub fn delivery_ratio(&self) -> f64 {
        let sent = self.decoder.frames + self.missing_frames;
        if sent == 0 {
            1.0
        } else {
            self.decoder.frames as f64 / sent as f64
        }
    }
}

/// Turns frames into [`Sample`]s: unwraps the device clock, detects sequence gaps.
#[derive(Debug, Clone, Default)]
pub struct SequenceTracker {
    last: Option<(u16, u32)>,
    device_time_us: u64,
}

impl SequenceTracker {
    /// A tracker that has seen nothing yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Accounts `frame` (received at `host_time`) and returns its sample.
    ///
    /// A gap is the number of sequence numbers skipped. Sequence numbers wrap every 65 536
    /// frames (164 s at 400 Hz); when the device clock says more time passed than the sequence
    /// jump explains, the clock wins, so an outage longer than a wrap is still counted right.
    ///
    /// A device clock that goes back (by the wrapping difference read as signed: back by less
    /// than 2³¹ µs, 36 min) is a restart of the device, which starts again at sequence 0 and
    /// time 0: the sample is marked [`Sample::restarted`], no frames are counted missing, and
    /// the unwrapped device time goes on from where it was, one period later.
    pub fn observe(&mut self, frame: &Frame, host_time: Duration) -> Sample {
        let mut restarted = false;
        let missing_before = match self.last {
            None => 0,
            Some((_, ts)) if (frame.timestamp_us.wrapping_sub(ts) as i32) < 0 => {
                restarted = true;
                self.device_time_us += u64::from(SAMPLE_PERIOD_US) + u64::from(frame.timestamp_us);
                0
            }
            Some((seq, ts)) => {
                let dt = u64::from(frame.timestamp_us.wrapping_sub(ts));
                self.device_time_us += dt;
                let by_seq = u64::from(frame.seq.wrapping_sub(seq).wrapping_sub(1));
                let by_clock = (dt + u64::from(SAMPLE_PERIOD_US) / 2) / u64::from(SAMPLE_PERIOD_US);
                let by_clock = by_clock.saturating_sub(1);
                // Within one wrap of the sequence number the two agree; beyond it, add wraps.
                let wraps = by_clock.saturating_sub(by_seq) / 65_536;
                (by_seq + wraps * 65_536).min(u64::from(u32::MAX)) as u32
            }
        };
        self.last = Some((frame.seq, frame.timestamp_us));
        Sample {
            seq: frame.seq,
            device_time_us: self.device_time_us,
            host_time,
            raw: frame.channels,
            flags: frame.flags,
            missing_before,
            restarted,
        }
    }
}

/// Settings of a serial sensor port.
#[derive(Debug, Clone)]
pub struct PortConfig {
    /// Device path, e.g. `/dev/ttyACM0` or a pseudo-terminal `/dev/pts/3`.
    pub path: String,
    /// Baud rate (ignored by pseudo-terminals).
    pub baud: u32,
    /// How long one read waits for bytes before checking whether to stop.
    pub poll_interval: Duration,
}

impl PortConfig {
    /// The sensor's defaults: 115 200 baud, 50 ms poll interval.
    pub fn new(path: impl Into<String>) -> Self {
        PortConfig {
            path: path.into(),
            baud: 115_200,
            poll_interval: Duration::from_millis(50),
        }
    }
}

/// What [`SensorStream::try_next`] found.
#[derive(Debug)]
pub enum TryNext {
    /// A sample (or the error that ends the stream).
    Ready(Result<Sample, AcquisitionError>),
    /// Nothing waiting now.
    Empty,
    /// The stream has ended.
    Ended,
}

/// A live stream of samples from a serial port, read by a background thread.
///
/// The thread decodes everything it reads and hands the samples over in order; when the port
/// fails (unplugged, PTY closed) it first delivers every sample already received, then one
/// [`AcquisitionError::Disconnected`], then the stream ends.
#[derive(Debug)]
pub struct SensorStream {
    rx: mpsc::Receiver<Result<Sample, AcquisitionError>>,
    stats: Arc<Mutex<LinkStats>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    path: String,
    opened_at: Instant,
}

impl SensorStream {
    /// Opens the port and starts reading.
    pub fn open(config: &PortConfig) -> Result<Self, AcquisitionError> {
        if config.path.is_empty() {
            return Err(AcquisitionError::PortNotFound {
                path: config.path.clone(),
            });
        }
        if !Path::new(&config.path).exists() {
            return Err(AcquisitionError::PortNotFound {
                path: config.path.clone(),
            });
        }
        if config.baud == 0 {
            return Err(AcquisitionError::InvalidConfig(format!(
                "baud rate 0 for {}",
                config.path
            )));
        }
        let port = serialport::new(&config.path, config.baud)
            .timeout(config.poll_interval)
            .open()
            .map_err(|source| AcquisitionError::Open {
                path: config.path.clone(),
                source,
            })?;
        let (tx, rx) = mpsc::channel(8192);
        let stats = Arc::new(Mutex::new(LinkStats::default()));
        let stop = Arc::new(AtomicBool::new(false));
        let opened_at = Instant::now();
        let reader = Reader {
            start: opened_at,
            port,
            path: config.path.clone(),
            tx,
            stats: stats.clone(),
            stop: stop.clone(),
        };
        let thread = std::thread::Builder::new()
            .name(format!("sensor-reader {}", config.path))
            .spawn(move || reader.run())
            .map_err(|source| AcquisitionError::Thread { source })?;
        Ok(SensorStream {
            rx,
            stats,
            stop,
            thread: Some(thread),
            path: config.path.clone(),
            opened_at,
        })
    }

    /// The host instant [`Sample::host_time`] counts from (to put the samples on the same
    /// clock as other streams, e.g. the arm's positions).
    pub fn opened_at(&self) -> Instant {
        self.opened_at
    }

    /// The device path.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// Next sample; `None` once the stream has ended (after an error or [`Self::stop`]).
    pub async fn next(&mut self) -> Option<Result<Sample, AcquisitionError>> {
        self.rx.recv().await
    }

    /// The next sample if one has arrived, without waiting.
    pub fn try_next(&mut self) -> TryNext {
        match self.rx.try_recv() {
            Ok(s) => TryNext::Ready(s),
            Err(mpsc::error::TryRecvError::Empty) => TryNext::Empty,
            Err(mpsc::error::TryRecvError::Disconnected) => TryNext::Ended,
        }
    }

    /// Next sample, blocking the calling (non-async) thread.
    pub fn blocking_next(&mut self) -> Option<Result<Sample, AcquisitionError>> {
        self.rx.blocking_recv()
    }

    /// Link counters so far.
    pub fn stats(&self) -> LinkStats {
        *self.stats.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Asks the reader thread to stop. Samples already read stay available through
    /// [`Self::next`] until it returns `None`.
    pub fn stop(&self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

impl Drop for SensorStream {
    fn drop(&mut self) {
        self.stop();
        self.rx.close();
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

struct Reader {
    start: Instant,
    port: Box<dyn serialport::SerialPort>,
    path: String,
    tx: mpsc::Sender<Result<Sample, AcquisitionError>>,
    stats: Arc<Mutex<LinkStats>>,
    stop: Arc<AtomicBool>,
}

impl Reader {
    fn run(mut self) {
        let start = self.start;
        let mut decoder = Decoder::new();
        let mut tracker = SequenceTracker::new();
        let mut buf = [0u8; 4096];
        let mut batch = Vec::with_capacity(256);
        let mut link = LinkStats::default();
        while !self.stop.load(Ordering::Relaxed) {
            let n = match self.port.read(&mut buf) {
                Ok(0) => {
                    let _ = self
                        .tx
                        .blocking_send(Err(self.disconnected("end of file".into())));
                    return;
                }
                Ok(n) => n,
                Err(e)
                    if matches!(
                        e.kind(),
                        ErrorKind::TimedOut | ErrorKind::WouldBlock | ErrorKind::Interrupted
                    ) =>
                {
                    continue
                }
                Err(e) => {
                    let _ = self.tx.blocking_send(Err(self.disconnected(e.to_string())));
                    return;
                }
            };
            let host_time = start.elapsed();
            decoder.feed(&buf[..n], |r| match r {
                Ok(frame) => batch.push(tracker.observe(&frame, host_time)),
                Err(e) => tracing::debug!(port = %self.path, "dropped bytes: {e}"),
            });
            for s in &batch {
                link.gaps += u64::from(s.missing_before > 0);
                link.missing_frames += u64::from(s.missing_before);
                link.overrun_flags += u64::from(s.flags.overrun());
                link.restarts += u64::from(s.restarted);
                link.saturated_frames += u64::from(s.flags.any_saturated());
            }
            self.publish(&mut link, decoder.stats());
            for s in batch.drain(..) {
                if self.tx.blocking_send(Ok(s)).is_err() {
                    return; // the consumer is gone
                }
            }
        }
    }

    fn publish(&self, link: &mut LinkStats, d: &DecoderStats) {
        link.decoder = *d;
        link.resyncs = d.resyncs();
        *self.stats.lock().unwrap_or_else(PoisonError::into_inner) = *link;
    }

    fn disconnected(&self, reason: String) -> AcquisitionError {
        AcquisitionError::Disconnected {
            path: self.path.clone(),
            reason,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(seq: u16, ts: u32) -> Frame {
        Frame {
            seq,
            timestamp_us: ts,
            ..Frame::default()
        }
    }

    #[test]
    fn contiguous_frames_have_no_gap_and_monotonic_time() {
        let mut t = SequenceTracker::new();
        let s: Vec<Sample> = (0..5u16)
            .map(|k| t.observe(&frame(k, u32::from(k) * 2500), Duration::ZERO))
            .collect();
        assert!(s.iter().all(|s| s.missing_before == 0));
        assert_eq!(
            s.iter().map(|s| s.device_time_us).collect::<Vec<_>>(),
            vec![0, 2500, 5000, 7500, 10000]
        );
    }

    #[test]
    fn a_clock_that_goes_back_is_a_restart_not_a_gap() {
        let mut t = SequenceTracker::new();
        t.observe(&frame(799, 799 * 2500), Duration::ZERO);
        let s = t.observe(&frame(0, 0), Duration::ZERO);
        assert!(s.restarted);
        assert_eq!(s.missing_before, 0);
        assert_eq!(s.device_time_us, 2500, "one period after the last frame");
        // The first frame after the reset lost too: still a restart, still monotonic.
        let mut t = SequenceTracker::new();
        t.observe(&frame(799, 799 * 2500), Duration::ZERO);
        let s = t.observe(&frame(1, 2500), Duration::ZERO);
        assert!(s.restarted && s.missing_before == 0);
        assert_eq!(s.device_time_us, 2500 + 2500);
        let s = t.observe(&frame(2, 5000), Duration::ZERO);
        assert!(!s.restarted && s.missing_before == 0);
        // A wrap of the device clock is not a restart.
        let mut t = SequenceTracker::new();
        t.observe(&frame(10, u32::MAX - 1000), Duration::ZERO);
        assert!(!t.observe(&frame(11, 1500), Duration::ZERO).restarted);
    }

    #[test]
    fn gaps_and_wraps_are_counted() {
        let mut t = SequenceTracker::new();
        t.observe(&frame(65_534, u32::MAX - 2499), Duration::ZERO);
        // Sequence and clock both wrap; 3 frames lost.
        let s = t.observe(&frame(3, 10_000), Duration::ZERO);
        assert_eq!(s.missing_before, 4);
        assert_eq!(s.device_time_us, 12_500);
    }

    #[test]
    fn an_outage_longer_than_a_sequence_wrap_is_counted_from_the_clock() {
        let mut t = SequenceTracker::new();
        t.observe(&frame(10, 0), Duration::ZERO);
        // 70 000 periods later the sequence number has wrapped once.
        let seq = (10u32 + 70_000) as u16;
        let s = t.observe(&frame(seq, 70_000 * 2500), Duration::ZERO);
        assert_eq!(s.missing_before, 69_999);
    }
}
