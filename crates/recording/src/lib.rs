//! Tactile recordings in the authors' nine-column layout.
//!
//! The fibre-optic finger's recordings published by Palermo et al. (2020) hold one sample per row and nine
//! columns: the x position of the haptic-device tip (mm), the four raw 10-bit ADC channels D1, D2, D3 (deformation)
//! and P (proximity), the sliding direction, the number of the slide within the recording, the label (surface class
//! or crack width in mm) and the repetition number. crackbot's own recorder may add three more columns
//! ([`EXTRA_COLUMNS`]: the device timestamp, the frame sequence number and the status flags).
//!
//! This crate holds the one in-memory type for such a recording, [`Recording`], its CSV form and the authors' own
//! MAT-file form:
//!
//! * [`read_csv`] / [`read_csv_from`] read a CSV file (header line + one row per line), with errors that name the
//!   file, the line and the column of the problem;
//! * [`write_csv`] writes a whole recording;
//! * [`CsvRecorder`] writes one row at a time, for the live recorder;
//! * [`read_mat`] / [`read_mat_from`] read the authors' MAT-files (level 5, compressed or not; the variable
//!   `synchronized_data`), [`write_mat`] writes one;
//! * [`read_recording`] / [`write_recording`] pick the form by the file's extension (`.csv` or `.mat`), and
//!   [`collect_recordings`] loads every recording named by a list of files and folders;
//!   [`conversion_targets`] names the files a conversion writes (one file, or one per input in a folder).
//!
//! [`Experiment`] says what the label column means: the paper's two experiments, their label values and class
//! names.
//!
//! [`Recording::slides`], [`Recording::label`] and [`Recording::repetition`] give a recording's structure.
//!
//! # CSV format
//!
//! The first line is the header: exactly the nine names of [`COLUMNS`], or those followed by the three names of
//! [`EXTRA_COLUMNS`], comma separated. Every following line is one row. Every line, the last one included, ends with
//! `'\n'`; a file whose last line does not is reported as truncated ([`RecordingError::Truncated`]), because the
//! recorder never leaves a line unterminated unless it was interrupted. Floating-point values are written with Rust's
//! shortest round-trip formatting, so they read back bit for bit.

use std::ops::Range;
use std::path::{Path, PathBuf};

mod csv;
mod error;
mod experiment;
mod mat;

pub use crate::csv::{read_csv, read_csv_from, write_csv, CsvRecorder};
pub use error::RecordingError;
pub use experiment::{Experiment, ExperimentError};
pub use mat::{read_mat, read_mat_from, write_mat, MAT_VARIABLE, MAX_INFLATED};

/// The nine columns of a recording, in file order.
pub const COLUMNS: [&str; 9] = [
    "x_mm",
    "d1",
    "d2",
    "d3",
    "p",
    "direction",
    "slide",
    "label",
    "repetition",
];

/// The optional extra columns written by crackbot's own recorder, after [`COLUMNS`].
pub const EXTRA_COLUMNS: [&str; 3] = ["device_time_us", "seq", "flags"];

/// One sample of a recording: the nine columns of the authors' layout.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Row {
    /// x position of the haptic-device tip along the sliding direction (mm).
    pub x_mm: f64,
    /// D1, left deformation channel (raw 10-bit ADC counts, or a processed value).
    pub d1: f64,
    /// D2, right deformation channel (raw ADC counts).
    pub d2: f64,
    /// D3, back/normal deformation channel (raw ADC counts).
    pub d3: f64,
    /// P, proximity channel (raw ADC counts).
    pub p: f64,
    /// Sliding direction: 1 = left to right, 0 = right to left.
    pub direction: u8,
    /// Number of the sliding movement within the recording (1-based in the authors' data).
    pub slide: u32,
    /// Label: class id (surface-type experiment, 0..=3) or crack width in mm (width experiment).
    pub label: f64,
    /// Repetition number of the recording (1..=5 in the authors' data).
    pub repetition: u32,
}

impl Row {
    /// The four channel values `[D1, D2, D3, P]`, the sample layout of `crackbot-dsp` (index with
    /// `Channel::index`).
    pub fn channels(&self) -> [f64; 4] {
        [self.d1, self.d2, self.d3, self.p]
    }

    /// The floating-point fields with their column names, in file order.
    fn float_fields(&self) -> [(&'static str, f64); 6] {
        [
            ("x_mm", self.x_mm),
            ("d1", self.d1),
            ("d2", self.d2),
            ("d3", self.d3),
            ("p", self.p),
            ("label", self.label),
        ]
    }

    /// Checks one row: every float finite, direction 0 or 1. `index` is the 0-based row index, for the message.
    pub(crate) fn check(&self, index: usize) -> Result<(), RecordingError> {
        for (column, value) in self.float_fields() {
            if !value.is_finite() {
                return Err(RecordingError::InvalidRow {
                    index,
                    column,
                    reason: format!("non-finite value {value}"),
                });
            }
        }
        if self.direction > 1 {
            return Err(RecordingError::InvalidRow {
                index,
                column: "direction",
                reason: format!("direction must be 0 or 1, found {}", self.direction),
            });
        }
        Ok(())
    }
}

/// The extra columns of crackbot's own recorder ([`EXTRA_COLUMNS`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub struct Extra {
    /// Device timestamp of the sample (microseconds since the device started).
    pub device_time_us: u64,
    /// Frame sequence number (wraps around).
    pub seq: u16,
    /// Status flags of the frame.
    pub flags: u8,
}

/// A tactile recording held in memory.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Recording {
    /// The samples, in time order.
    pub rows: Vec<Row>,
    /// The extra columns, one per row, when the recording has them.
    pub extra: Option<Vec<Extra>>,
}

impl Recording {
    /// Number of rows.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// Whether the recording has no rows.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// Checks that every floating-point value is finite, every direction is 0 or 1 and, when the extra columns are
    /// present, that there is exactly one [`Extra`] per row.
    pub fn validate(&self) -> Result<(), RecordingError> {
        if let Some(extra) = &self.extra {
            if extra.len() != self.rows.len() {
                return Err(RecordingError::ExtraLength {
                    rows: self.rows.len(),
                    extra: extra.len(),
                });
            }
        }
        for (index, row) in self.rows.iter().enumerate() {
            row.check(index)?;
        }
        Ok(())
    }

    /// The slides of the recording: maximal runs of consecutive rows with the same [`Row::slide`] number, as row
    /// index ranges, in order. Every row is in exactly one range.
    ///
    /// In the authors' files a slide is one stroke there and back (direction 0, then 1), about 2,800 samples;
    /// each file holds slides 1 to 12, and some (14 of the 30 files of repetitions 1–3) end with one trailing
    /// sample labelled slide 13, which is kept here as its own one-row range (callers that want whole slides only
    /// can drop short ranges). A slide number that comes back later starts a new range.
    pub fn slides(&self) -> Vec<Range<usize>> {
        let mut out = Vec::new();
        let mut start = 0;
        for i in 1..=self.rows.len() {
            let boundary = match (self.rows.get(i - 1), self.rows.get(i)) {
                (Some(a), Some(b)) => a.slide != b.slide,
                _ => true,
            };
            if boundary {
                out.push(start..i);
                start = i;
            }
        }
        out
    }

    /// Adds `by` to D1, D2 and D3 of every row, as a remounted fibre shifts its offsets (P is left alone).
    pub fn shift_deformation(&mut self, by: [f64; 3]) {
        for r in &mut self.rows {
            r.d1 += by[0];
            r.d2 += by[1];
            r.d3 += by[2];
        }
    }

    /// The label ([`Row::label`]) when every row has the same one; `None` when it varies or there are no rows.
    pub fn label(&self) -> Option<f64> {
        let first = self.rows.first()?.label;
        self.rows
            .iter()
            .all(|r| r.label.to_bits() == first.to_bits())
            .then_some(first)
    }

    /// The recording of the width experiment relabelled for the surface-type one
    /// ([`Experiment::recognition_label_of_width`]): 0 mm as flat, any other width as a crack.
    /// A label that is no width of the experiment is an error naming its row.
    pub fn width_as_recognition(&self) -> Result<Recording, RecordingError> {
        let mut out = self.clone();
        for (index, row) in out.rows.iter_mut().enumerate() {
            row.label = Experiment::recognition_label_of_width(row.label).ok_or_else(|| {
                RecordingError::InvalidRow {
                    index,
                    column: "label",
                    reason: format!(
                        "{} is no width of the width experiment (0, 1, 2, 5, 8, 10 mm)",
                        row.label
                    ),
                }
            })?;
        }
        Ok(out)
    }

    /// The repetition number ([`Row::repetition`]) when every row has the same one; `None` when it varies or there
    /// are no rows.
    pub fn repetition(&self) -> Option<u32> {
        let first = self.rows.first()?.repetition;
        self.rows
            .iter()
            .all(|r| r.repetition == first)
            .then_some(first)
    }
}

/// The file forms of a recording, chosen by extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// `.csv`: see the [crate documentation](crate).
    Csv,
    /// `.mat`: a MAT-file, level 5 (see [`read_mat`]).
    Mat,
}

impl Format {
    /// The form of `path` by its extension (`.csv` or `.mat`, any case);
    /// [`RecordingError::UnsupportedExtension`] otherwise.
    pub fn of_path(path: &Path) -> Result<Format, RecordingError> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("csv") => Ok(Format::Csv),
            Some("mat") => Ok(Format::Mat),
            _ => Err(RecordingError::UnsupportedExtension {
                path: path.to_path_buf(),
            }),
        }
    }

    /// The extension of the form, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Csv => "csv",
            Format::Mat => "mat",
        }
    }
}

/// Reads a recording, as CSV ([`read_csv`]) or as a MAT-file ([`read_mat`]) by the file's extension (`.csv` or
/// `.mat`, any case). Any other extension is refused with [`RecordingError::UnsupportedExtension`].
pub fn read_recording(path: &Path) -> Result<Recording, RecordingError> {
    match Format::of_path(path)? {
        Format::Csv => read_csv(path),
        Format::Mat => read_mat(path),
    }
}

/// Writes a recording, as CSV ([`write_csv`]) or as a MAT-file ([`write_mat`]) by the file's extension (`.csv` or
/// `.mat`, any case). Any other extension is refused with [`RecordingError::UnsupportedExtension`] before the file
/// is touched.
pub fn write_recording(path: &Path, rec: &Recording) -> Result<(), RecordingError> {
    match Format::of_path(path)? {
        Format::Csv => write_csv(path, rec),
        Format::Mat => write_mat(path, rec),
    }
}

/// Loads every recording named by `paths`, in order: each path is a recording file (read with
/// [`read_recording`], so `.csv` or `.mat`) or a folder, of which every `.csv`/`.mat` file directly inside
/// (not in sub-folders; any case of the extension) is read, sorted by file name; other files are ignored.
///
/// Errors: [`RecordingError::NotFound`] for a path that does not exist, [`RecordingError::NoRecordings`] for a
/// folder without any recording, and the first error reading a file (which names it).
pub fn collect_recordings(paths: &[PathBuf]) -> Result<Vec<(PathBuf, Recording)>, RecordingError> {
    let mut out = Vec::new();
    for path in paths {
        let io = |source: std::io::Error| {
            if source.kind() == std::io::ErrorKind::NotFound {
                RecordingError::NotFound { path: path.clone() }
            } else {
                RecordingError::Io {
                    path: path.clone(),
                    source,
                }
            }
        };
        let meta = std::fs::metadata(path).map_err(io)?;
        if !meta.is_dir() {
            out.push((path.clone(), read_recording(path)?));
            continue;
        }
        let mut files = Vec::new();
        for entry in std::fs::read_dir(path).map_err(io)? {
            let file = entry.map_err(io)?.path();
            if Format::of_path(&file).is_ok() && file.is_file() {
                files.push(file);
            }
        }
        if files.is_empty() {
            return Err(RecordingError::NoRecordings { path: path.clone() });
        }
        files.sort_by(|a, b| a.file_name().cmp(&b.file_name()));
        for file in files {
            let rec = read_recording(&file)?;
            out.push((file, rec));
        }
    }
    Ok(out)
}

/// Whether `out` names one output file: an extension of a recording form, and not an existing folder.
fn is_file_target(out: &Path) -> bool {
    Format::of_path(out).is_ok() && !out.is_dir()
}

/// The files a conversion of the recordings read from `inputs` (in order) writes, creating the folders they go
/// in:
///
/// * `out` ending in `.csv` or `.mat` (and not an existing folder) is that one file, for
///   exactly one input ([`RecordingError::OneFileManyRecordings`] otherwise); its parent folder is created;
/// * otherwise `out` is a folder (created if needed; it must exist already or have no extension) and each input
///   becomes `<stem>.<format>` there. Two inputs with the same stem are refused
///   ([`RecordingError::TargetClash`]) before anything is written.
pub fn conversion_targets(
    inputs: &[PathBuf],
    out: &Path,
    format: Format,
) -> Result<Vec<PathBuf>, RecordingError> {
    if is_file_target(out) {
        if inputs.len() != 1 {
            return Err(RecordingError::OneFileManyRecordings {
                out: out.to_path_buf(),
                recordings: inputs.len(),
            });
        }
        if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
            create_folder(dir)?;
        }
        return Ok(vec![out.to_path_buf()]);
    }
    if out.extension().is_some() && !out.is_dir() {
        return Err(RecordingError::BadOutputName {
            out: out.to_path_buf(),
        });
    }
    if out.exists() && !out.is_dir() {
        return Err(RecordingError::OutputNotFolder {
            out: out.to_path_buf(),
        });
    }
    create_folder(out)?;
    let ext = format.extension();
    let mut targets: Vec<PathBuf> = Vec::with_capacity(inputs.len());
    for (k, input) in inputs.iter().enumerate() {
        let stem = input
            .file_stem()
            .ok_or_else(|| RecordingError::NoFileName {
                path: input.clone(),
            })?;
        let target = out.join(stem).with_extension(ext);
        if let Some(j) = targets.iter().position(|t| *t == target) {
            return Err(RecordingError::TargetClash {
                first: inputs[j].clone(),
                second: inputs[k].clone(),
                target,
            });
        }
        targets.push(target);
    }
    Ok(targets)
}

fn create_folder(dir: &Path) -> Result<(), RecordingError> {
    std::fs::create_dir_all(dir).map_err(|source| RecordingError::CreateFolder {
        path: dir.to_path_buf(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shifting_the_deformation_moves_d1_to_d3_and_nothing_else() {
        let row = Row {
            x_mm: 3.0,
            d1: 1.0,
            d2: 2.0,
            d3: 3.0,
            p: 4.0,
            direction: 1,
            slide: 2,
            label: 5.0,
            repetition: 1,
        };
        let mut r = Recording {
            rows: vec![row; 3],
            extra: None,
        };
        r.shift_deformation([10.0, -5.0, 0.5]);
        for got in &r.rows {
            assert_eq!((got.d1, got.d2, got.d3), (11.0, -3.0, 3.5));
            assert_eq!(
                (got.x_mm, got.p, got.direction, got.slide, got.label),
                (3.0, 4.0, 1, 2, 5.0)
            );
        }
    }

    #[test]
    fn width_recordings_read_as_surface_types_and_bad_widths_are_named() {
        let row = |label| Row {
            x_mm: 0.0,
            d1: 1.0,
            d2: 1.0,
            d3: 1.0,
            p: 1.0,
            direction: 0,
            slide: 1,
            label,
            repetition: 1,
        };
        let rec = Recording {
            rows: vec![row(0.0), row(2.0), row(10.0)],
            extra: None,
        };
        let labels: Vec<f64> = rec
            .width_as_recognition()
            .unwrap()
            .rows
            .iter()
            .map(|r| r.label)
            .collect();
        assert_eq!(labels, [0.0, 1.0, 1.0]);
        let bad = Recording {
            rows: vec![row(5.0), row(3.0)],
            extra: None,
        };
        let err = bad.width_as_recognition().unwrap_err().to_string();
        assert!(
            err.contains("row 1") && err.contains("3 is no width"),
            "{err}"
        );
    }

    #[test]
    fn row_channels_are_the_sample_layout() {
        let row = Row {
            x_mm: 1.0,
            d1: 2.0,
            d2: 3.0,
            d3: 4.0,
            p: 5.0,
            direction: 0,
            slide: 1,
            label: 0.0,
            repetition: 1,
        };
        assert_eq!(row.channels(), [2.0, 3.0, 4.0, 5.0]);
    }

    #[test]
    fn conversion_targets_name_files_and_refuse_clashes() {
        let dir = tempfile::tempdir().expect("temp dir");
        let inputs = [PathBuf::from("a/x.mat"), PathBuf::from("b/y.csv")];
        let out = dir.path().join("out");
        let targets = conversion_targets(&inputs, &out, Format::Mat).expect("targets");
        assert_eq!(targets, [out.join("x.mat"), out.join("y.mat")]);
        assert!(out.is_dir());
        let one = dir.path().join("sub/one.csv");
        assert_eq!(
            conversion_targets(&inputs[..1], &one, Format::Csv).expect("one file"),
            std::slice::from_ref(&one)
        );
        let err = conversion_targets(&inputs, &one, Format::Csv).unwrap_err();
        assert!(err.to_string().contains("names one file"), "{err}");
        let clash = [PathBuf::from("a/x.mat"), PathBuf::from("b/x.csv")];
        let err = conversion_targets(&clash, &out, Format::Csv).unwrap_err();
        assert!(
            err.to_string().contains("would both be written to"),
            "{err}"
        );
        let err = conversion_targets(&inputs, &dir.path().join("t.txt"), Format::Csv).unwrap_err();
        assert!(err.to_string().contains(".csv or .mat"), "{err}");
    }
}
