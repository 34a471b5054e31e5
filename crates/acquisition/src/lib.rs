//! Host side of the sensor link: opens the microcontroller's serial port, decodes its 400 Hz
//! frames into typed [`Sample`]s with host receive times, tracks link health ([`LinkStats`]:
//! CRC errors, resyncs, sequence gaps), converts raw counts to physical units
//! ([`calibration::Calibration`]), records samples to the nine-column CSV of the authors' data
//! ([`SampleRecorder`]; whole sessions that end on a time limit, Ctrl-C or a disconnect without
//! losing a sample: [`RecordSession`]), summarises streams ([`StreamSummary`] → [`StreamReport`])
//! and replays recordings as a stream ([`Replay`]).
//!
//! ```no_run
//! # async fn demo() -> Result<(), crackbot_acquisition::AcquisitionError> {
//! use crackbot_acquisition::{PortConfig, SensorStream};
//! let mut stream = SensorStream::open(&PortConfig::new("/dev/ttyACM0"))?;
//! while let Some(sample) = stream.next().await {
//!     let sample = sample?; // a Disconnected error ends the stream
//!     println!("{} {:?}", sample.seq, sample.raw);
//! }
//! # Ok(()) }
//! ```

pub mod calibration;
mod record;
mod replay;
pub mod session;
mod stream;
pub mod summary;

pub use record::{RecordMeta, SampleRecorder};
pub use replay::{samples_of, Replay, ReplaySpeed};
pub use session::{record_stream, RecordEnd, RecordOutcome, RecordReport, RecordSession};
pub use stream::{LinkStats, PortConfig, Sample, SensorStream, SequenceTracker, TryNext};
pub use summary::{StreamReport, StreamSummary};

/// Errors of the acquisition library.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum AcquisitionError {
    /// The serial device path does not exist.
    #[error("serial port {path} does not exist (is the sensor plugged in? list ports with `ls /dev/tty*`)")]
    PortNotFound {
        /// The path asked for.
        path: String,
    },
    /// The device exists but could not be opened or configured.
    #[error("cannot open serial port {path}: {source}")]
    Open {
        /// The path asked for.
        path: String,
        /// What the OS said.
        #[source]
        source: serialport::Error,
    },
    /// The port failed while streaming (unplugged, closed by the other side).
    #[error("serial port {path} disconnected: {reason}")]
    Disconnected {
        /// The port.
        path: String,
        /// What the OS said.
        reason: String,
    },
    /// A setting is out of range.
    #[error("invalid acquisition setting: {0}")]
    InvalidConfig(String),
    /// The reader thread could not be started.
    #[error("cannot start the serial reader thread: {source}")]
    Thread {
        /// What the OS said.
        #[source]
        source: std::io::Error,
    },
    /// A folder or file could not be created.
    #[error("{path}: {source}")]
    Io {
        /// The folder or file.
        path: std::path::PathBuf,
        /// What the OS said.
        #[source]
        source: std::io::Error,
    },
    /// Writing or reading a recording failed.
    #[error(transparent)]
    Recording(#[from] crackbot_recording::RecordingError),
}
