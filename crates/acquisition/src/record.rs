//! Recording live samples to CSV.

use std::path::Path;
use std::time::{Duration, Instant};

use crackbot_recording::{CsvRecorder, Extra, Row};

use crate::{AcquisitionError, Sample};

/// What the sensor itself can't know, written into every row: the label of the surface and the
/// repetition number, and the manipulator's state when no manipulator feeds it in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecordMeta {
    /// Column 8: class label (type experiment) or crack width in mm.
    pub label: f64,
    /// Column 9: repetition number.
    pub repetition: u32,
    /// Column 1: tip position, mm (0 without a manipulator).
    pub x_mm: f64,
    /// Column 6: sliding direction, 1 = left to right.
    pub direction: u8,
    /// Column 7: sliding movement number.
    pub slide: u32,
}

impl Default for RecordMeta {
    fn default() -> Self {
        RecordMeta {
            label: 0.0,
            repetition: 1,
            x_mm: 0.0,
            direction: 1,
            slide: 1,
        }
    }
}

/// Writes samples to a recording in the authors' nine columns plus the link's own columns
/// (`device_time_us`, `seq`, `flags`), flushing to the OS at least every `flush_every`, and on
/// [`Self::finish`] and on drop, so a port that vanishes or a Ctrl-C loses nothing received.
#[derive(Debug)]
pub struct SampleRecorder {
    csv: CsvRecorder,
    flush_every: Duration,
    last_flush: Instant,
}

impl SampleRecorder {
    /// Creates (truncates) the CSV file at `path`.
    pub fn create(path: &Path) -> Result<Self, AcquisitionError> {
        Ok(SampleRecorder {
            csv: CsvRecorder::create(path, true)?,
            flush_every: Duration::from_millis(100),
            last_flush: Instant::now(),
        })
    }

    /// Appends one sample.
    pub fn record(&mut self, sample: &Sample, meta: &RecordMeta) -> Result<(), AcquisitionError> {
        let [d1, d2, d3, p] = sample.raw.map(f64::from);
        let row = Row {
            x_mm: meta.x_mm,
            d1,
            d2,
            d3,
            p,
            direction: meta.direction,
            slide: meta.slide,
            label: meta.label,
            repetition: meta.repetition,
        };
        let extra = Extra {
            device_time_us: sample.device_time_us,
            seq: sample.seq,
            flags: sample.flags.0,
        };
        self.csv.append(&row, Some(&extra))?;
        if self.last_flush.elapsed() >= self.flush_every {
            self.flush()?;
        }
        Ok(())
    }

    /// Pushes buffered rows to the OS.
    pub fn flush(&mut self) -> Result<(), AcquisitionError> {
        self.last_flush = Instant::now();
        Ok(self.csv.flush()?)
    }

    /// Rows written so far.
    pub fn rows(&self) -> u64 {
        self.csv.rows_written()
    }

    /// Flushes, syncs and closes the file; returns the number of rows.
    pub fn finish(self) -> Result<u64, AcquisitionError> {
        Ok(self.csv.finish()?)
    }
}
