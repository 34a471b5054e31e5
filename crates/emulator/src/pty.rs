//! The emulator on a new pseudo-terminal: the wiring shared by the emulator binary (`--pty`), the
//! acquisition demo and simulated missions. The reader opens [`Pty::path`] like any serial port.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use serialport::{SerialPort as _, TTYPort};

use crate::{run, EmulatorConfig, EmulatorError, EmulatorReport, SignalSource};

/// A pseudo-terminal pair: the emulator writes to the master side, a reader opens the slave's
/// device path. The slave side is held open for as long as the pair lives, so its raw settings
/// stay in force and the reader never sees the device vanish early.
#[derive(Debug)]
pub struct Pty {
    master: TTYPort,
    slave: TTYPort,
    path: String,
}

impl Pty {
    /// Creates a new pair.
    pub fn open() -> Result<Pty, EmulatorError> {
        let (master, slave) = TTYPort::pair().map_err(EmulatorError::Pty)?;
        let path = slave.name().ok_or_else(|| {
            EmulatorError::Pty(serialport::Error::new(
                serialport::ErrorKind::Unknown,
                "the pseudo-terminal has no device path",
            ))
        })?;
        Ok(Pty {
            master,
            slave,
            path,
        })
    }

    /// Device path of the reader's side, e.g. `/dev/pts/3`.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// The master side (write frames here) and the slave side (keep it alive while a reader
    /// needs the device).
    pub fn into_parts(self) -> (TTYPort, TTYPort) {
        (self.master, self.slave)
    }
}

/// The emulator streaming into a new pseudo-terminal from its own thread.
///
/// Dropping it stops the emulator and waits for the thread.
#[derive(Debug)]
pub struct PtyEmulator {
    path: String,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<Result<EmulatorReport, EmulatorError>>>,
}

impl PtyEmulator {
    /// Opens a pseudo-terminal and starts `source` streaming into it under `config`. After the
    /// last frame the device stays open for `linger`, so a reader can drain it.
    pub fn spawn<S>(
        config: EmulatorConfig,
        source: S,
        linger: Duration,
    ) -> Result<PtyEmulator, EmulatorError>
    where
        S: SignalSource + Send + 'static,
    {
        config.corruption.validate()?;
        let pty = Pty::open()?;
        let path = pty.path().to_string();
        let stop = Arc::new(AtomicBool::new(false));
        let thread_stop = stop.clone();
        let thread = std::thread::Builder::new()
            .name(format!("sensor-emulator {path}"))
            .spawn(move || {
                let (mut master, slave) = pty.into_parts();
                let report = run(&config, source, &mut master, &thread_stop);
                // Keep the PTY open until the reader has drained it.
                std::thread::sleep(linger);
                drop(slave);
                report
            })
            .map_err(EmulatorError::Thread)?;
        Ok(PtyEmulator {
            path,
            stop,
            thread: Some(thread),
        })
    }

    /// Device path to open with the acquisition.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// Asks the emulator to stop after the current tick.
    pub fn stop(&self) {
        self.stop.store(true, Ordering::Relaxed);
    }

    /// Waits for the emulator to finish (its tick count, or [`Self::stop`]) and returns its
    /// report.
    pub fn join(mut self) -> Result<EmulatorReport, EmulatorError> {
        match self.thread.take() {
            Some(thread) => thread.join().map_err(|_| EmulatorError::Panicked)?,
            None => Err(EmulatorError::Panicked),
        }
    }
}

impl Drop for PtyEmulator {
    fn drop(&mut self) {
        if let Some(thread) = self.thread.take() {
            self.stop();
            let _ = thread.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use std::io::Read;

    use super::*;
    use crate::SyntheticSlide;

    #[test]
    fn frames_arrive_on_the_pty_path() {
        let config = EmulatorConfig {
            ticks: Some(40),
            ..EmulatorConfig::default()
        };
        let emulator =
            PtyEmulator::spawn(config, SyntheticSlide::new(3), Duration::from_millis(300)).unwrap();
        let mut port = serialport::new(emulator.path(), 115_200)
            .timeout(Duration::from_millis(200))
            .open()
            .unwrap();
        let mut bytes = Vec::new();
        let mut buf = [0u8; 512];
        while bytes.len() < 40 * crackbot_protocol::WIRE_LEN {
            match port.read(&mut buf) {
                Ok(n) => bytes.extend_from_slice(&buf[..n]),
                Err(e) if e.kind() == std::io::ErrorKind::TimedOut => break,
                Err(e) => panic!("{e}"),
            }
        }
        let report = emulator.join().unwrap();
        assert_eq!(report.ticks, 40);
        assert_eq!(bytes.len() as u64, report.bytes_written);
        let mut decoder = crackbot_protocol::Decoder::new();
        let mut frames = 0;
        decoder.feed(&bytes, |r| frames += u32::from(r.is_ok()));
        assert_eq!(frames, 40);
    }

    #[test]
    fn a_bad_corruption_rate_is_refused_before_the_pty_opens() {
        let config = EmulatorConfig {
            corruption: crate::Corruption {
                flip_rate: 2.0,
                ..Default::default()
            },
            ..EmulatorConfig::default()
        };
        let err = PtyEmulator::spawn(config, SyntheticSlide::new(3), Duration::ZERO).unwrap_err();
        assert!(err.to_string().contains("flip"), "{err}");
    }
}
