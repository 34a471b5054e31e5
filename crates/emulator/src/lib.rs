//! The sensor emulator: runs the real sampling firmware (`crackbot-firmware`) on the host and
//! writes its frames, paced at 400 Hz and at the UART's baud rate, to a serial device or to a
//! pseudo-terminal, optionally corrupting the line on the way.
//!
//! It exists so that everything downstream of the microcontroller (acquisition, recording, the
//! robot) can be run and tested over a real serial path without the hardware:
//!
//! ```text
//! signal source ──ADC──▶ firmware Sampler ──UART bytes──▶ LineCorruptor ──▶ serial port / PTY
//! ```
//!
//! * [`SignalSource`]s stand in for the analog front end: a synthetic finger sliding over a crack
//!   ([`SyntheticSlide`]), the raw channels of a recording ([`RecordingSource`]), or the physics
//!   simulator `crackbot-sim` ([`SimSource`]: the simulated finger's mechanics and optics on a
//!   plate, one 1/400 s simulation step per tick), so that
//!   simulator → firmware frames → PTY → acquisition runs over the real serial path.
//! * [`PacedUart`] is the host implementation of the firmware's UART: it accepts bytes at the
//!   configured baud rate (8N1, 10 bits per byte) and never faster, so the firmware's ring buffer
//!   and overrun logic behave as on the board.
//! * [`Pty`] and [`PtyEmulator`] put the emulator on a new pseudo-terminal, which a reader opens
//!   like any serial port (the emulator binary's `--pty`, the acquisition demo, simulated runs).
//! * [`LineCorruptor`] flips bytes, drops bytes and inserts garbage bursts at given rates, and logs
//!   which frames it damaged, so tests can check the host's decoder frame by frame.

use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use crackbot_firmware::{SampleAdc, Sampler};
use crackbot_protocol::{Decoder, WIRE_LEN};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

mod pty;
mod signal;
mod sim_source;
pub mod trace;

pub use pty::{Pty, PtyEmulator};
pub use signal::{to_counts, RecordingSource, SignalSource, SyntheticSlide};
pub use sim_source::{SimSource, CRACK_LEAD_IN_MM, PAPER_SPEED_MM_S, PAPER_STROKE_MM};

/// Bytes of the firmware's UART ring buffer in the emulator (as on the board: 8 frames).
pub const TX_RING_BYTES: usize = 8 * WIRE_LEN;

/// Errors of the emulator library.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum EmulatorError {
    /// Writing to the serial device failed (e.g. the reader closed a pseudo-terminal).
    #[error("writing to the serial device failed after {frames_sent} frames: {source}")]
    Write {
        /// Frames fully written before the failure.
        frames_sent: u64,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A configuration value is out of range.
    #[error("invalid emulator setting: {0}")]
    Config(String),
    /// A pseudo-terminal pair could not be created.
    #[error("creating a pseudo-terminal pair: {0}")]
    Pty(#[source] serialport::Error),
    /// The emulator thread could not be started.
    #[error("cannot start the emulator thread: {0}")]
    Thread(#[source] std::io::Error),
    /// The emulator thread panicked.
    #[error("the emulator thread panicked")]
    Panicked,
    /// Reading a recording for replay failed.
    #[error(transparent)]
    Recording(#[from] crackbot_recording::RecordingError),
}

/// Rates of the line faults injected by [`LineCorruptor`].
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct Corruption {
    /// Probability that a byte is flipped (XOR with a random non-zero mask).
    pub flip_rate: f64,
    /// Probability that a byte is dropped.
    pub drop_rate: f64,
    /// Probability, per frame, of a burst of 1–64 random bytes inserted before the frame.
    pub garbage_rate: f64,
}

impl Corruption {
    /// Checks that every rate is a probability.
    pub fn validate(&self) -> Result<(), EmulatorError> {
        for (name, v) in [
            ("flip rate", self.flip_rate),
            ("drop rate", self.drop_rate),
            ("garbage rate", self.garbage_rate),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return Err(EmulatorError::Config(format!(
                    "{name} {v} is not a probability in [0, 1]"
                )));
            }
        }
        Ok(())
    }

    /// Whether any fault is injected.
    pub fn is_clean(&self) -> bool {
        self.flip_rate == 0.0 && self.drop_rate == 0.0 && self.garbage_rate == 0.0
    }
}

/// Counters of the faults actually injected.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct CorruptionLog {
    /// Frames passed through the corruptor.
    pub frames: u64,
    /// Sequence numbers of the frames the line damaged (see [`LineCorruptor`]), in order: the
    /// frames a correct decoder must reject; every other frame must come through.
    pub damaged_seqs: Vec<u16>,
    /// Bytes flipped.
    pub flipped_bytes: u64,
    /// Bytes dropped.
    pub dropped_bytes: u64,
    /// Garbage bursts inserted.
    pub garbage_bursts: u64,
    /// Garbage bytes inserted.
    pub garbage_bytes: u64,
}

/// Applies [`Corruption`] to the clean byte stream of whole frames and logs which frames it
/// damaged.
///
/// The log is an oracle worked out from the bytes put on the line, not from a decoder: a frame
/// is damaged when one of its 21 COBS bytes was flipped or dropped, or when it is no longer
/// delimited, i.e. the bytes on the line between its COBS bytes and its neighbours' (its own
/// delimiters, any garbage, the neighbours' delimiters, all as sent) do not start (after it)
/// and end (before it) with a `0x00`. A dropped delimiter is harmless when the neighbour's
/// delimiter still separates the two frames, which is what the double delimiter is for.
#[derive(Debug)]
pub struct LineCorruptor {
    rates: Corruption,
    rng: ChaCha8Rng,
    pending: Vec<u8>,
    /// The last frame's sequence number, whether its COBS bytes arrived intact and whether its
    /// start was delimited; its end is known once the next frame's start is on the line.
    open_frame: Option<(u16, bool)>,
    /// Bytes put on the line since the last COBS byte of a frame (or since the start).
    separator: Vec<u8>,
    at_start: bool,
    log: CorruptionLog,
}

impl LineCorruptor {
    /// A corruptor with the given rates and RNG seed.
    pub fn new(rates: Corruption, seed: u64) -> Self {
        LineCorruptor {
            rates,
            rng: ChaCha8Rng::seed_from_u64(seed),
            pending: Vec::new(),
            open_frame: None,
            separator: Vec::new(),
            at_start: true,
            log: CorruptionLog::default(),
        }
    }

    /// Takes clean UART bytes; appends the bytes to put on the line to `out`. Bytes of a frame
    /// not yet complete are held until the rest arrives, so faults are attributed per frame.
    pub fn process(&mut self, clean: &[u8], out: &mut Vec<u8>) {
        self.pending.extend_from_slice(clean);
        let whole = self.pending.len() / WIRE_LEN * WIRE_LEN;
        let pending = std::mem::take(&mut self.pending);
        for frame in pending[..whole].chunks_exact(WIRE_LEN) {
            self.frame(frame, out);
        }
        self.pending = pending[whole..].to_vec();
    }

    /// Ends the stream: settles the fate of the last frame.
    pub fn finish(&mut self) {
        self.close_open_frame();
    }

    /// Sends one byte through the faults; returns whether it was changed or dropped.
    fn send(&mut self, byte: u8, out: &mut Vec<u8>, separator: bool) -> bool {
        let r = self.rates;
        if r.drop_rate > 0.0 && self.rng.random_bool(r.drop_rate) {
            self.log.dropped_bytes += 1;
            return true;
        }
        let sent = if r.flip_rate > 0.0 && self.rng.random_bool(r.flip_rate) {
            self.log.flipped_bytes += 1;
            byte ^ self.rng.random_range(1..=255u8)
        } else {
            byte
        };
        out.push(sent);
        if separator {
            self.separator.push(sent);
        }
        sent != byte
    }

    fn close_open_frame(&mut self) {
        if let Some((seq, ok)) = self.open_frame.take() {
            if !(ok && self.separator.first() == Some(&0)) {
                self.log.damaged_seqs.push(seq);
            }
        }
    }

    fn frame(&mut self, frame: &[u8], out: &mut Vec<u8>) {
        self.log.frames += 1;
        let mut seq = u16::MAX;
        Decoder::new().feed(frame, |r| seq = r.map_or(u16::MAX, |f| f.seq));
        if self.rates.garbage_rate > 0.0 && self.rng.random_bool(self.rates.garbage_rate) {
            let n = self.rng.random_range(1..=64);
            self.log.garbage_bursts += 1;
            self.log.garbage_bytes += n as u64;
            for _ in 0..n {
                let b = self.rng.random::<u8>();
                out.push(b);
                self.separator.push(b);
            }
        }
        let (lead, inner, trail) = (frame[0], &frame[1..WIRE_LEN - 1], frame[WIRE_LEN - 1]);
        self.send(lead, out, true);
        self.close_open_frame();
        let start_ok = if self.at_start && self.separator.is_empty() {
            true
        } else {
            self.separator.last() == Some(&0)
        };
        self.at_start = false;
        let mut inner_ok = true;
        for &b in inner {
            inner_ok &= !self.send(b, out, false);
        }
        self.separator.clear();
        self.send(trail, out, true);
        self.open_frame = Some((seq, inner_ok && start_ok));
    }

    /// What was injected so far.
    pub fn log(&self) -> &CorruptionLog {
        &self.log
    }
}

/// The host's UART for the firmware: accepts bytes no faster than `baud` allows (8N1).
#[derive(Debug)]
pub struct PacedUart {
    baud: u32,
    now_us: u64,
    accepted: u64,
    bytes: Vec<u8>,
}

impl PacedUart {
    /// A UART at `baud` bits per second.
    pub fn new(baud: u32) -> Self {
        PacedUart {
            baud,
            now_us: 0,
            accepted: 0,
            bytes: Vec::new(),
        }
    }
    /// Advances the UART's clock (device time since start, µs).
    pub fn set_time_us(&mut self, now_us: u64) {
        self.now_us = now_us;
    }
    /// Takes the bytes shifted out since the last call.
    pub fn take(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.bytes)
    }
    fn budget(&self) -> u64 {
        self.now_us * u64::from(self.baud) / 10 / 1_000_000
    }
}

impl embedded_hal_nb::serial::ErrorType for PacedUart {
    type Error = core::convert::Infallible;
}

impl embedded_hal_nb::serial::Write<u8> for PacedUart {
    fn write(&mut self, word: u8) -> nb::Result<(), Self::Error> {
        if self.accepted >= self.budget() {
            return Err(nb::Error::WouldBlock);
        }
        self.accepted += 1;
        self.bytes.push(word);
        Ok(())
    }
    fn flush(&mut self) -> nb::Result<(), Self::Error> {
        Ok(())
    }
}

/// Adapts a [`SignalSource`] to the firmware's ADC trait: quantises to 10 bits and clamps to
/// the rails (values beyond the rails are what the saturation flags report).
#[derive(Debug)]
pub struct SourceAdc<S> {
    source: S,
    tick: u64,
    rate_hz: f64,
}

impl<S: SignalSource> SampleAdc for SourceAdc<S> {
    type Error = core::convert::Infallible;
    fn read_all(&mut self) -> Result<[u16; 4], Self::Error> {
        let t = self.tick as f64 / self.rate_hz;
        self.tick += 1;
        Ok(signal::to_counts(self.source.sample(t)))
    }
}

/// Settings of an emulator run.
#[derive(Debug, Clone)]
pub struct EmulatorConfig {
    /// Sample rate, Hz (the firmware's tick rate).
    pub rate_hz: f64,
    /// UART baud rate used for pacing.
    pub baud: u32,
    /// Stop after this many ticks (None: until stopped).
    pub ticks: Option<u64>,
    /// Line faults to inject.
    pub corruption: Corruption,
    /// RNG seed of the corruptor.
    pub seed: u64,
}

impl Default for EmulatorConfig {
    fn default() -> Self {
        EmulatorConfig {
            rate_hz: f64::from(crackbot_protocol::SAMPLE_RATE_HZ),
            baud: 115_200,
            ticks: None,
            corruption: Corruption::default(),
            seed: 1,
        }
    }
}

/// What an emulator run did.
#[derive(Debug, Clone, Default, Serialize)]
pub struct EmulatorReport {
    /// Ticks of the 400 Hz timer.
    pub ticks: u64,
    /// Frames the firmware queued.
    pub frames_queued: u64,
    /// Frames the firmware dropped because the UART could not keep up.
    pub frames_dropped: u64,
    /// Bytes written to the device.
    pub bytes_written: u64,
    /// Wall-clock duration, s.
    pub seconds: f64,
    /// Faults injected.
    pub corruption: CorruptionLog,
}

/// Runs the firmware in real time, writing to `port`, until `config.ticks` ticks have run or
/// `stop` is set. Ticks are scheduled on absolute deadlines, so the average rate is exact.
pub fn run<S: SignalSource, W: Write>(
    config: &EmulatorConfig,
    source: S,
    port: &mut W,
    stop: &AtomicBool,
) -> Result<EmulatorReport, EmulatorError> {
    config.corruption.validate()?;
    if !(config.rate_hz.is_finite() && config.rate_hz > 0.0 && config.rate_hz <= 100_000.0) {
        return Err(EmulatorError::Config(format!(
            "rate {} Hz is not in (0, 100000]",
            config.rate_hz
        )));
    }
    if config.baud == 0 {
        return Err(EmulatorError::Config("baud rate 0".into()));
    }
    let period = Duration::from_secs_f64(1.0 / config.rate_hz);
    let adc = SourceAdc {
        source,
        tick: 0,
        rate_hz: config.rate_hz,
    };
    let mut sampler: Sampler<_, _, TX_RING_BYTES> = Sampler::new(adc, PacedUart::new(config.baud));
    let mut corruptor = LineCorruptor::new(config.corruption, config.seed);
    let mut line = Vec::with_capacity(4 * WIRE_LEN);
    let mut report = EmulatorReport::default();
    let start = Instant::now();
    let mut tick: u64 = 0;
    while config.ticks.is_none_or(|n| tick < n) && !stop.load(Ordering::Relaxed) {
        let deadline = start + period.mul_f64(tick as f64);
        if let Some(wait) = deadline.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        let device_us = (tick as f64 * 1e6 / config.rate_hz).round() as u64;
        sampler.uart_mut().set_time_us(device_us);
        sampler.tick(device_us as u32);
        let clean = sampler.uart_mut().take();
        line.clear();
        corruptor.process(&clean, &mut line);
        write_line(port, &line, &mut report)?;
        tick += 1;
    }
    // Shift out what is still in the firmware's ring buffer, at the UART's pace.
    let mut device_us = (tick as f64 * 1e6 / config.rate_hz).round() as u64;
    while sampler.queued_bytes() > 0 && !stop.load(Ordering::Relaxed) {
        device_us += 1_000;
        std::thread::sleep(Duration::from_millis(1));
        sampler.uart_mut().set_time_us(device_us);
        sampler.pump();
        let clean = sampler.uart_mut().take();
        line.clear();
        corruptor.process(&clean, &mut line);
        write_line(port, &line, &mut report)?;
    }
    corruptor.finish();
    let stats = sampler.stats();
    report.ticks = tick;
    report.frames_queued = u64::from(stats.frames_queued);
    report.frames_dropped = u64::from(stats.frames_dropped);
    report.seconds = start.elapsed().as_secs_f64();
    report.corruption = corruptor.log().clone();
    Ok(report)
}

fn write_line<W: Write>(
    port: &mut W,
    line: &[u8],
    report: &mut EmulatorReport,
) -> Result<(), EmulatorError> {
    if line.is_empty() {
        return Ok(());
    }
    port.write_all(line)
        .and_then(|()| port.flush())
        .map_err(|source| EmulatorError::Write {
            frames_sent: report.bytes_written / WIRE_LEN as u64,
            source,
        })?;
    report.bytes_written += line.len() as u64;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crackbot_protocol::Frame;

    fn frames(n: u16) -> Vec<u8> {
        (0..n)
            .flat_map(|seq| {
                Frame {
                    seq,
                    ..Frame::default()
                }
                .to_wire()
            })
            .collect()
    }

    #[test]
    fn clean_corruptor_passes_bytes_through_even_when_split() {
        let clean = frames(10);
        let mut c = LineCorruptor::new(Corruption::default(), 3);
        let mut out = Vec::new();
        for piece in clean.chunks(7) {
            c.process(piece, &mut out);
        }
        c.finish();
        assert_eq!(out, clean);
        assert_eq!(c.log().frames, 10);
        assert!(c.log().damaged_seqs.is_empty());
    }

    #[test]
    fn corruptor_logs_exactly_the_frames_it_changed() {
        let clean = frames(200);
        let rates = Corruption {
            flip_rate: 0.02,
            drop_rate: 0.02,
            garbage_rate: 0.1,
        };
        let mut c = LineCorruptor::new(rates, 7);
        let mut out = Vec::new();
        c.process(&clean, &mut out);
        c.finish();
        let touched = &c.log().damaged_seqs;
        assert!(!touched.is_empty());
        let mut decoded = Vec::new();
        Decoder::new().feed(&out, |r| {
            if let Ok(f) = r {
                decoded.push(f.seq);
            }
        });
        for seq in 0..200u16 {
            assert_eq!(decoded.contains(&seq), !touched.contains(&seq), "seq {seq}");
        }
    }

    #[test]
    fn paced_uart_respects_the_baud_rate() {
        use embedded_hal_nb::serial::Write as _;
        let mut uart = PacedUart::new(115_200);
        uart.set_time_us(1_000_000);
        let mut n = 0;
        while uart.write(0xAA).is_ok() {
            n += 1;
        }
        assert_eq!(n, 11_520);
    }

    #[test]
    fn bad_rates_are_rejected() {
        let c = Corruption {
            flip_rate: 1.5,
            ..Corruption::default()
        };
        assert!(c.validate().unwrap_err().to_string().contains("flip rate"));
    }
}
