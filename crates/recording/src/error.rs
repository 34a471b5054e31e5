//! The crate's error type.

use std::path::PathBuf;

/// Everything that can go wrong reading, writing or checking a recording.
///
/// Every variant about a file names it; line numbers are 1-based and count the header as line 1.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
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
    /// A row of an in-memory recording is invalid (see [`Recording::validate`](crate::Recording::validate)).
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
        /// The column's name in [`COLUMNS`](crate::COLUMNS).
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
    /// A path given to [`collect_recordings`](crate::collect_recordings) does not exist.
    #[error("{}: no such file or folder", path.display())]
    NotFound {
        /// The path.
        path: PathBuf,
    },
    /// A folder given to [`collect_recordings`](crate::collect_recordings) holds no `.csv` or `.mat` file.
    #[error("{}: the folder holds no recording (.csv or .mat file)", path.display())]
    NoRecordings {
        /// The folder.
        path: PathBuf,
    },
    /// A conversion's output names one file but there are several recordings to write.
    #[error(
        "--out {} names one file but the inputs hold {recordings} recordings; give a folder",
        out.display()
    )]
    OneFileManyRecordings {
        /// The output file.
        out: PathBuf,
        /// The number of recordings.
        recordings: usize,
    },
    /// A conversion's output has an extension that is not a recording form, and is not an existing folder.
    #[error(
        "--out {}: a single output file must end in .csv or .mat; an output folder must exist \
         already or have no extension",
        out.display()
    )]
    BadOutputName {
        /// The output path.
        out: PathBuf,
    },
    /// A conversion's output folder exists as something else.
    #[error(
        "--out {} exists and is not a folder (a single output file must end in .csv or .mat)",
        out.display()
    )]
    OutputNotFolder {
        /// The output path.
        out: PathBuf,
    },
    /// A folder could not be created.
    #[error("creating folder {}", path.display())]
    CreateFolder {
        /// The folder.
        path: PathBuf,
        /// The underlying I/O error.
        source: std::io::Error,
    },
    /// An input path has no file name to name its output after.
    #[error("{}: no file name", path.display())]
    NoFileName {
        /// The input.
        path: PathBuf,
    },
    /// Two inputs would be converted to the same output file.
    #[error(
        "{} and {} would both be written to {}",
        first.display(),
        second.display(),
        target.display()
    )]
    TargetClash {
        /// The first input.
        first: PathBuf,
        /// The second input.
        second: PathBuf,
        /// The output both would be written to.
        target: PathBuf,
    },
}
