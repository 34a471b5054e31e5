//! The CSV form of a recording: reading (with errors naming file, line and column), writing a whole
//! recording, and [`CsvRecorder`], the row-at-a-time writer of the live recorder. The format is described in
//! the [crate documentation](crate).

use std::fs::File;
use std::io::{BufWriter, Read, Write};
use std::path::{Path, PathBuf};

use crate::{Extra, Recording, RecordingError, Row, COLUMNS, EXTRA_COLUMNS};

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

    let mut csv_reader = ::csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(::csv::Trim::All)
        .from_reader(data);
    let mut records = csv_reader.records();

    let header = match records.next() {
        None => {
            return Err(RecordingError::Empty {
                path: path.to_path_buf(),
            })
        }
        Some(result) => result.map_err(|e| csv_error(path, &e))?,
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
        let record = result.map_err(|e| csv_error(path, &e))?;
        let line = record.position().map_or(0, csv::Position::line);
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

fn csv_error(path: &Path, error: &::csv::Error) -> RecordingError {
    let line = error.position().map(csv::Position::line);
    let message = match error.kind() {
        ::csv::ErrorKind::Utf8 { err, .. } => format!("invalid UTF-8 in field {}", err.field() + 1),
        _ => error.to_string(),
    };
    RecordingError::Csv {
        path: path.to_path_buf(),
        line,
        message,
    }
}

/// Checks the header; returns whether it has the extra columns.
fn check_header(header: &::csv::StringRecord, path: &Path) -> Result<bool, RecordingError> {
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
        match self.writer.as_mut().map(std::io::Write::flush) {
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
