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
//!   [`collect_recordings`] loads every recording named by a list of files and folders.
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

use std::fs::File;
use std::io::{BufWriter, Read, Write};
use std::ops::Range;
use std::path::{Path, PathBuf};

mod mat;

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
    fn check(&self, index: usize) -> Result<(), RecordingError> {
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

    /// The label ([`Row::label`]) when every row has the same one; `None` when it varies or there are no rows.
    pub fn label(&self) -> Option<f64> {
        let first = self.rows.first()?.label;
        self.rows
            .iter()
            .all(|r| r.label.to_bits() == first.to_bits())
            .then_some(first)
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

/// Everything that can go wrong reading, writing or checking a recording.
///
/// Every variant about a file names it; line numbers are 1-based and count the header as line 1.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// The file could not be opened, read, created or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying I/O error.
        source: std::io::Error,
    },
    /// The file holds nothing at all, not even a header line.
    #[error("{}: empty file, expected a header line", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// The header line is not the nine column names, optionally followed by the three extra ones.
    #[error("{}: line 1: wrong header: column {column} should be `{expected}`, found `{found}`", path.display())]
    Header {
        /// The file.
        path: PathBuf,
        /// 1-based position of the first wrong column.
        column: usize,
        /// The name expected there (or `<end of header>` when the header is too long).
        expected: String,
        /// The name found there (or `<missing>` when the header is too short).
        found: String,
    },
    /// A data line has the wrong number of fields.
    #[error("{}: line {line}: wrong number of fields: expected {expected}, found {found}", path.display())]
    FieldCount {
        /// The file.
        path: PathBuf,
        /// The line.
        line: u64,
        /// The number of columns in the header.
        expected: usize,
        /// The number of fields on the line.
        found: usize,
    },
    /// A value does not parse as the column's type.
    #[error("{}: line {line}, column `{column}`: cannot parse `{text}` as {expected}", path.display())]
    InvalidValue {
        /// The file.
        path: PathBuf,
        /// The line.
        line: u64,
        /// The column name.
        column: &'static str,
        /// The text of the field.
        text: String,
        /// What was expected, e.g. "a number".
        expected: &'static str,
    },
    /// A value is NaN or infinite.
    #[error("{}: line {line}, column `{column}`: non-finite value `{text}`", path.display())]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// The line.
        line: u64,
        /// The column name.
        column: &'static str,
        /// The text of the field.
        text: String,
    },
    /// The direction is a number other than 0 or 1.
    #[error("{}: line {line}, column `direction`: direction must be 0 or 1, found `{text}`", path.display())]
    InvalidDirection {
        /// The file.
        path: PathBuf,
        /// The line.
        line: u64,
        /// The text of the field.
        text: String,
    },
    /// An integer column (slide, repetition, extras) holds a negative, fractional or too large number.
    #[error(
        "{}: line {line}, column `{column}`: expected an integer in 0..={max}, found `{text}`",
        path.display()
    )]
    InvalidInteger {
        /// The file.
        path: PathBuf,
        /// The line.
        line: u64,
        /// The column name.
        column: &'static str,
        /// The text of the field.
        text: String,
        /// The largest value the column can hold.
        max: u64,
    },
    /// The last line does not end in `'\n'`: the file was cut off while being written.
    #[error("{}: file ends mid-line at line {line}: recording truncated?", path.display())]
    Truncated {
        /// The file.
        path: PathBuf,
        /// The unterminated last line.
        line: u64,
    },
    /// The CSV syntax itself is broken (e.g. invalid UTF-8, an unclosed quote).
    #[error("{}: {}malformed CSV: {message}", path.display(), match line { Some(l) => format!("line {l}: "), None => String::new() })]
    Csv {
        /// The file.
        path: PathBuf,
        /// The line, when known.
        line: Option<u64>,
        /// The CSV parser's description.
        message: String,
    },
    /// A row of an in-memory recording is invalid (see [`Recording::validate`]).
    #[error("row {index} (0-based), column `{column}`: {reason}")]
    InvalidRow {
        /// 0-based index of the row.
        index: usize,
        /// The column name.
        column: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// The extra columns of an in-memory recording do not have one entry per row.
    #[error("extra columns have {extra} entries but the recording has {rows} rows")]
    ExtraLength {
        /// Number of rows.
        rows: usize,
        /// Number of extra entries.
        extra: usize,
    },
    /// A recorder created with extra columns was given a row without them.
    #[error("{}: row {row} (0-based) has no extra columns but the recorder writes them", path.display())]
    MissingExtra {
        /// The file being written.
        path: PathBuf,
        /// 0-based index of the row.
        row: u64,
    },
    /// Writing was refused because the data is invalid; nothing (more) was written.
    #[error("{}: refusing to write invalid data: {source}", path.display())]
    InvalidData {
        /// The file that would have been written.
        path: PathBuf,
        /// What is wrong with the data.
        source: Box<RecordingError>,
    },
    /// The file does not start like a MAT-file (level 5): no `MATLAB` header text, a bad endian indicator or an
    /// unknown version.
    #[error("{}: not a MAT-file: {reason}", path.display())]
    NotMat {
        /// The file.
        path: PathBuf,
        /// What is wrong with its header.
        reason: String,
    },
    /// The file is a MAT-file version 7.3, an HDF5 file, which is not supported.
    #[error(
        "{}: MAT-file version 7.3 (HDF5) is not supported: save it as version 7 or older \
         (MATLAB `save(file, '-v7')`, or `scipy.io.savemat`)",
        path.display()
    )]
    MatV73 {
        /// The file.
        path: PathBuf,
    },
    /// The MAT-file ends too early: a data element runs past the end of the file, or a zlib stream ends before
    /// its end.
    #[error("{}: truncated MAT-file: {what}", path.display())]
    MatTruncated {
        /// The file.
        path: PathBuf,
        /// Which element, and how much is missing.
        what: String,
    },
    /// The MAT-file is malformed: corrupt zlib data, or elements inconsistent with the format.
    #[error("{}: corrupt MAT-file: {what}", path.display())]
    MatCorrupt {
        /// The file.
        path: PathBuf,
        /// Where, and what is wrong.
        what: String,
    },
    /// The MAT-file does not hold the variable wanted.
    #[error(
        "{}: no variable `{name}` in the MAT-file; variables found: {}",
        path.display(),
        if found.is_empty() { "none".to_string() } else { found.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ") }
    )]
    MatMissingVariable {
        /// The file.
        path: PathBuf,
        /// The variable wanted.
        name: &'static str,
        /// The names of the variables in the file, in file order.
        found: Vec<String>,
    },
    /// The variable is not a 2-D matrix with one column per recording column.
    #[error(
        "{}: variable `{name}` has shape {}, expected N×9 (2-D, one column per recording column)",
        path.display(),
        dims.iter().map(i64::to_string).collect::<Vec<_>>().join("×")
    )]
    MatShape {
        /// The file.
        path: PathBuf,
        /// The variable.
        name: &'static str,
        /// Its dimensions.
        dims: Vec<i64>,
    },
    /// The variable is not a real double (or single) matrix.
    #[error("{}: variable `{name}` is of class {class}, expected a real double (or single) matrix", path.display())]
    MatClass {
        /// The file.
        path: PathBuf,
        /// The variable.
        name: &'static str,
        /// Its class, e.g. `char`, `int16`, `complex double`.
        class: String,
    },
    /// A value of the variable is invalid for its column.
    #[error("{}: variable `{name}`, row {row}, column {column} (`{column_name}`): {reason}", path.display())]
    MatValue {
        /// The file.
        path: PathBuf,
        /// The variable.
        name: &'static str,
        /// 1-based row (as in MATLAB).
        row: usize,
        /// 1-based column (as in MATLAB).
        column: usize,
        /// The column's name in [`COLUMNS`].
        column_name: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// A recording cannot be written as a MAT-file.
    #[error("{}: cannot write the recording as a MAT-file: {reason}", path.display())]
    MatUnsupported {
        /// The file that would have been written.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// The file's extension is neither `.csv` nor `.mat`.
    #[error(
        "{}: unsupported extension {}: expected .csv or .mat",
        path.display(),
        path.extension().map_or_else(|| "(none)".to_string(), |e| format!("`.{}`", e.to_string_lossy()))
    )]
    UnsupportedExtension {
        /// The file.
        path: PathBuf,
    },
    /// A path given to [`collect_recordings`] does not exist.
    #[error("{}: no such file or folder", path.display())]
    NotFound {
        /// The path.
        path: PathBuf,
    },
    /// A folder given to [`collect_recordings`] holds no `.csv` or `.mat` file.
    #[error("{}: the folder holds no recording (.csv or .mat file)", path.display())]
    NoRecordings {
        /// The folder.
        path: PathBuf,
    },
}

/// Reads a recording from a CSV file. See the [crate documentation](crate) for the format.
pub fn read_csv(path: &Path) -> Result<Recording, RecordingError> {
    let file = File::open(path).map_err(|source| RecordingError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    read_impl(file, path)
}

/// Reads a recording in CSV form from any reader; `source_name` names it in error messages.
pub fn read_csv_from<R: Read>(reader: R, source_name: &str) -> Result<Recording, RecordingError> {
    read_impl(reader, Path::new(source_name))
}

fn read_impl<R: Read>(mut reader: R, path: &Path) -> Result<Recording, RecordingError> {
    let mut bytes = Vec::new();
    reader
        .read_to_end(&mut bytes)
        .map_err(|source| RecordingError::Io {
            path: path.to_path_buf(),
            source,
        })?;
    let data = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&bytes);
    if data.is_empty() {
        return Err(RecordingError::Empty {
            path: path.to_path_buf(),
        });
    }
    if data.last() != Some(&b'\n') {
        let line = data.iter().filter(|&&b| b == b'\n').count() as u64 + 1;
        return Err(RecordingError::Truncated {
            path: path.to_path_buf(),
            line,
        });
    }

    let mut csv_reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(data);
    let mut records = csv_reader.records();

    let header = match records.next() {
        None => {
            return Err(RecordingError::Empty {
                path: path.to_path_buf(),
            })
        }
        Some(result) => result.map_err(|e| csv_error(path, e))?,
    };
    let extended = check_header(&header, path)?;
    let expected_fields = if extended {
        COLUMNS.len() + EXTRA_COLUMNS.len()
    } else {
        COLUMNS.len()
    };

    let mut rows = Vec::new();
    let mut extras = Vec::new();
    for result in records {
        let record = result.map_err(|e| csv_error(path, e))?;
        let line = record.position().map_or(0, |p| p.line());
        if record.len() != expected_fields {
            return Err(RecordingError::FieldCount {
                path: path.to_path_buf(),
                line,
                expected: expected_fields,
                found: record.len(),
            });
        }
        let ctx = LineContext { path, line };
        let field = |i: usize| record.get(i).unwrap_or("");
        let row = Row {
            x_mm: ctx.float(field(0), "x_mm")?,
            d1: ctx.float(field(1), "d1")?,
            d2: ctx.float(field(2), "d2")?,
            d3: ctx.float(field(3), "d3")?,
            p: ctx.float(field(4), "p")?,
            direction: ctx.direction(field(5))?,
            slide: ctx.uint(field(6), "slide", u64::from(u32::MAX))? as u32,
            label: ctx.float(field(7), "label")?,
            repetition: ctx.uint(field(8), "repetition", u64::from(u32::MAX))? as u32,
        };
        rows.push(row);
        if extended {
            extras.push(Extra {
                device_time_us: ctx.uint(field(9), "device_time_us", u64::MAX)?,
                seq: ctx.uint(field(10), "seq", u64::from(u16::MAX))? as u16,
                flags: ctx.uint(field(11), "flags", u64::from(u8::MAX))? as u8,
            });
        }
    }
    Ok(Recording {
        rows,
        extra: extended.then_some(extras),
    })
}

fn csv_error(path: &Path, error: csv::Error) -> RecordingError {
    let line = error.position().map(|p| p.line());
    let message = match error.kind() {
        csv::ErrorKind::Utf8 { err, .. } => format!("invalid UTF-8 in field {}", err.field() + 1),
        _ => error.to_string(),
    };
    RecordingError::Csv {
        path: path.to_path_buf(),
        line,
        message,
    }
}

/// Checks the header; returns whether it has the extra columns.
fn check_header(header: &csv::StringRecord, path: &Path) -> Result<bool, RecordingError> {
    let all: Vec<&str> = COLUMNS
        .iter()
        .chain(EXTRA_COLUMNS.iter())
        .copied()
        .collect();
    let found: Vec<&str> = header.iter().collect();
    let wrong = |column: usize, expected: &str, found: &str| RecordingError::Header {
        path: path.to_path_buf(),
        column: column + 1,
        expected: expected.to_string(),
        found: found.to_string(),
    };
    for (i, name) in all.iter().enumerate() {
        match found.get(i) {
            Some(f) if f == name => {}
            Some(f) => return Err(wrong(i, name, f)),
            // Nine names exactly: the basic layout. Fewer, or between nine and twelve: a column is missing.
            None if i == COLUMNS.len() => return Ok(false),
            None => return Err(wrong(i, name, "<missing>")),
        }
    }
    if let Some(extra) = found.get(all.len()) {
        return Err(wrong(all.len(), "<end of header>", extra));
    }
    Ok(true)
}

struct LineContext<'a> {
    path: &'a Path,
    line: u64,
}

impl LineContext<'_> {
    fn invalid(&self, text: &str, column: &'static str, expected: &'static str) -> RecordingError {
        RecordingError::InvalidValue {
            path: self.path.to_path_buf(),
            line: self.line,
            column,
            text: text.to_string(),
            expected,
        }
    }

    fn non_finite(&self, text: &str, column: &'static str) -> RecordingError {
        RecordingError::NonFinite {
            path: self.path.to_path_buf(),
            line: self.line,
            column,
            text: text.to_string(),
        }
    }

    fn float(&self, text: &str, column: &'static str) -> Result<f64, RecordingError> {
        let value: f64 = text
            .parse()
            .map_err(|_| self.invalid(text, column, "a number"))?;
        if value.is_finite() {
            Ok(value)
        } else {
            Err(self.non_finite(text, column))
        }
    }

    fn direction(&self, text: &str) -> Result<u8, RecordingError> {
        let value = self.float(text, "direction")?;
        if value == 0.0 {
            Ok(0)
        } else if value == 1.0 {
            Ok(1)
        } else {
            Err(RecordingError::InvalidDirection {
                path: self.path.to_path_buf(),
                line: self.line,
                text: text.to_string(),
            })
        }
    }

    /// Parses an unsigned integer no larger than `max`. Integral floats ("3.0", as exported from MATLAB's float64
    /// matrices) are accepted up to 2^53, where floats stop representing every integer.
    fn uint(&self, text: &str, column: &'static str, max: u64) -> Result<u64, RecordingError> {
        let out_of_range = || RecordingError::InvalidInteger {
            path: self.path.to_path_buf(),
            line: self.line,
            column,
            text: text.to_string(),
            max,
        };
        if let Ok(value) = text.parse::<u64>() {
            return if value <= max {
                Ok(value)
            } else {
                Err(out_of_range())
            };
        }
        let value: f64 = text
            .parse()
            .map_err(|_| self.invalid(text, column, "an integer"))?;
        if !value.is_finite() {
            return Err(self.non_finite(text, column));
        }
        const EXACT_LIMIT: f64 = 9_007_199_254_740_992.0; // 2^53
        if value >= 0.0 && value.fract() == 0.0 && value <= EXACT_LIMIT && value as u64 <= max {
            Ok(value as u64)
        } else {
            Err(out_of_range())
        }
    }
}

fn header_line(extended: bool) -> String {
    let mut names: Vec<&str> = COLUMNS.to_vec();
    if extended {
        names.extend_from_slice(&EXTRA_COLUMNS);
    }
    let mut line = names.join(",");
    line.push('\n');
    line
}

fn write_row<W: Write>(w: &mut W, row: &Row, extra: Option<&Extra>) -> std::io::Result<()> {
    write!(
        w,
        "{},{},{},{},{},{},{},{},{}",
        row.x_mm,
        row.d1,
        row.d2,
        row.d3,
        row.p,
        row.direction,
        row.slide,
        row.label,
        row.repetition
    )?;
    if let Some(e) = extra {
        write!(w, ",{},{},{}", e.device_time_us, e.seq, e.flags)?;
    }
    w.write_all(b"\n")
}

/// Writes a whole recording to a CSV file (created or truncated), with the extra columns iff `rec.extra` is
/// present. The recording is validated first ([`Recording::validate`]); an invalid one is refused with
/// [`RecordingError::InvalidData`] and no file is touched. The data is flushed and synced to disk before returning.
pub fn write_csv(path: &Path, rec: &Recording) -> Result<(), RecordingError> {
    rec.validate()
        .map_err(|source| RecordingError::InvalidData {
            path: path.to_path_buf(),
            source: Box::new(source),
        })?;
    let io = |source| RecordingError::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = File::create(path).map_err(io)?;
    let mut w = BufWriter::new(file);
    w.write_all(header_line(rec.extra.is_some()).as_bytes())
        .map_err(io)?;
    for (i, row) in rec.rows.iter().enumerate() {
        let extra = rec.extra.as_ref().and_then(|e| e.get(i));
        write_row(&mut w, row, extra).map_err(io)?;
    }
    let file = w.into_inner().map_err(|e| io(e.into_error()))?;
    file.sync_all().map_err(io)
}

/// Streaming CSV writer used by the live recorder.
///
/// The header is written on creation; rows are appended through a buffer; [`flush`](Self::flush) pushes them to
/// the operating system, [`finish`](Self::finish) also syncs them to disk. Dropping the recorder without `finish`
/// flushes too (best effort: errors are ignored), so every appended row reaches the file. The extra columns are
/// written iff the recorder was created with `extended = true`.
#[derive(Debug)]
pub struct CsvRecorder {
    path: PathBuf,
    writer: Option<BufWriter<File>>,
    extended: bool,
    rows: u64,
}

impl CsvRecorder {
    /// Creates (or truncates) the file at `path` and writes the header line, with the extra columns iff `extended`.
    pub fn create(path: &Path, extended: bool) -> Result<Self, RecordingError> {
        let io = |source| RecordingError::Io {
            path: path.to_path_buf(),
            source,
        };
        let file = File::create(path).map_err(io)?;
        let mut writer = BufWriter::new(file);
        writer
            .write_all(header_line(extended).as_bytes())
            .map_err(io)?;
        Ok(Self {
            path: path.to_path_buf(),
            writer: Some(writer),
            extended,
            rows: 0,
        })
    }

    fn io_error(&self, source: std::io::Error) -> RecordingError {
        RecordingError::Io {
            path: self.path.clone(),
            source,
        }
    }

    /// Appends one row. `extra` is required when the recorder writes the extra columns and ignored otherwise.
    ///
    /// A row with a non-finite value or a direction other than 0/1 is refused ([`RecordingError::InvalidData`])
    /// and nothing is written, so the file always reads back.
    pub fn append(&mut self, row: &Row, extra: Option<&Extra>) -> Result<(), RecordingError> {
        let index = usize::try_from(self.rows).unwrap_or(usize::MAX);
        row.check(index)
            .map_err(|source| RecordingError::InvalidData {
                path: self.path.clone(),
                source: Box::new(source),
            })?;
        let extra = if self.extended {
            Some(extra.ok_or_else(|| RecordingError::MissingExtra {
                path: self.path.clone(),
                row: self.rows,
            })?)
        } else {
            None
        };
        let Some(writer) = self.writer.as_mut() else {
            return Err(self.io_error(std::io::Error::other("recorder already finished")));
        };
        if let Err(e) = write_row(writer, row, extra) {
            return Err(self.io_error(e));
        }
        self.rows += 1;
        Ok(())
    }

    /// Pushes the buffered rows to the operating system.
    pub fn flush(&mut self) -> Result<(), RecordingError> {
        match self.writer.as_mut().map(|w| w.flush()) {
            Some(Err(e)) => Err(self.io_error(e)),
            _ => Ok(()),
        }
    }

    /// Number of rows appended so far.
    pub fn rows_written(&self) -> u64 {
        self.rows
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Flushes, syncs the file to disk and closes it; returns the number of rows written.
    pub fn finish(mut self) -> Result<u64, RecordingError> {
        if let Some(writer) = self.writer.take() {
            let file = writer.into_inner().map_err(|e| RecordingError::Io {
                path: self.path.clone(),
                source: e.into_error(),
            })?;
            file.sync_all().map_err(|e| self.io_error(e))?;
        }
        Ok(self.rows)
    }
}

impl Drop for CsvRecorder {
    fn drop(&mut self) {
        if let Some(writer) = self.writer.as_mut() {
            let _ = writer.flush();
        }
    }
}
