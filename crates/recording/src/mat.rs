//! MAT-file level 5 reader and writer for the authors' recordings.
//!
//! A level-5 MAT-file is a 128-byte header (116 bytes of text starting with `MATLAB`, an 8-byte subsystem offset,
//! a 2-byte version 0x0100 and the endian indicator `IM` for little-endian or `MI` for big-endian files) followed by
//! data elements. Each element is an 8-byte tag (type, byte count) and its data padded to 8 bytes, or a 4-byte
//! "small element" tag with up to 4 bytes of data. A variable is a `miMATRIX` element, directly or inside a
//! `miCOMPRESSED` element (a zlib stream, not padded). A `miMATRIX` holds sub-elements: array flags (class,
//! complex/logical bits), dimensions, name, then the real part. The real part of a double array may be stored as a
//! smaller integer type; every numeric storage type is accepted and converted to `f64`.
//!
//! Safety of the reader: every read is bounds-checked against the buffer it comes from, declared sizes are checked
//! against the bytes actually present before anything is allocated from them, and inflating a compressed element
//! stops at [`MAX_INFLATED`] bytes. No input makes it panic; every failure is a [`RecordingError`] naming the file.

use std::io::Write;
use std::path::Path;

use flate2::{Decompress, FlushDecompress, Status};

use crate::{Recording, RecordingError, Row, COLUMNS};

/// Name of the variable holding the recording in the authors' MAT-files.
pub const MAT_VARIABLE: &str = "synchronized_data";

/// Largest size a compressed element may inflate to (1 GiB, about 400 times the authors' largest variable).
pub const MAX_INFLATED: usize = 1 << 30;

const HEADER_LEN: usize = 128;
const TAG_LEN: usize = 8;
const HDF5_SIGNATURE: &[u8; 8] = b"\x89HDF\r\n\x1a\n";

const MI_INT8: u32 = 1;
const MI_UINT8: u32 = 2;
const MI_INT16: u32 = 3;
const MI_UINT16: u32 = 4;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_SINGLE: u32 = 7;
const MI_DOUBLE: u32 = 9;
const MI_INT64: u32 = 12;
const MI_UINT64: u32 = 13;
const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;
const MI_UTF8: u32 = 16;

const MX_DOUBLE_CLASS: u32 = 6;
const MX_SINGLE_CLASS: u32 = 7;
const FLAG_COMPLEX: u32 = 0x0800;
const FLAG_LOGICAL: u32 = 0x0200;

/// Name of a MATLAB array class, for messages.
fn class_name(class: u32) -> String {
    let name = match class {
        1 => "cell",
        2 => "struct",
        3 => "object",
        4 => "char",
        5 => "sparse",
        6 => "double",
        7 => "single",
        8 => "int8",
        9 => "uint8",
        10 => "int16",
        11 => "uint16",
        12 => "int32",
        13 => "uint32",
        14 => "int64",
        15 => "uint64",
        16 => "function handle",
        17 => "opaque",
        _ => return format!("unknown class {class}"),
    };
    name.to_string()
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Endian {
    Little,
    Big,
}

impl Endian {
    fn u16(self, b: [u8; 2]) -> u16 {
        match self {
            Endian::Little => u16::from_le_bytes(b),
            Endian::Big => u16::from_be_bytes(b),
        }
    }

    fn u32(self, b: [u8; 4]) -> u32 {
        match self {
            Endian::Little => u32::from_le_bytes(b),
            Endian::Big => u32::from_be_bytes(b),
        }
    }
}

/// `N` bytes of `buf` at `pos`, if present.
fn array_at<const N: usize>(buf: &[u8], pos: usize) -> Option<[u8; N]> {
    buf.get(pos..pos.checked_add(N)?)?.try_into().ok()
}

/// `n` rounded up to a multiple of 8.
fn pad8(n: usize) -> usize {
    n.saturating_add(7) & !7
}

/// One data element: its type, its data and where the next element starts.
struct Element<'a> {
    ty: u32,
    data: &'a [u8],
    next: usize,
}

/// Why an element could not be read.
enum ElementError {
    /// Fewer than 8 bytes left for the tag.
    ShortTag { remaining: usize },
    /// The data runs past the end of the buffer.
    ShortData { declared: usize, remaining: usize },
    /// A small element declaring more than 4 bytes.
    BadSmall { declared: usize },
}

impl ElementError {
    fn describe(&self, what: &str) -> String {
        match self {
            ElementError::ShortTag { remaining } => {
                format!("{what}: the 8-byte tag has only {remaining} bytes")
            }
            ElementError::ShortData {
                declared,
                remaining,
            } => format!("{what} declares {declared} bytes of data but only {remaining} follow"),
            ElementError::BadSmall { declared } => {
                format!("{what} is a small element declaring {declared} bytes (at most 4)")
            }
        }
    }
}

/// Reads the element whose tag starts at `pos` of `buf`. The data of every element except `miCOMPRESSED` is padded
/// to 8 bytes; a missing final padding is tolerated.
fn element(buf: &[u8], pos: usize, endian: Endian) -> Result<Element<'_>, ElementError> {
    let remaining = buf.len().saturating_sub(pos);
    let first = array_at::<4>(buf, pos).ok_or(ElementError::ShortTag { remaining })?;
    let word = endian.u32(first);
    if word >> 16 != 0 {
        // Small data element: byte count in the upper half, type in the lower, data in the next 4 bytes.
        let declared = (word >> 16) as usize;
        if declared > 4 {
            return Err(ElementError::BadSmall { declared });
        }
        let start = pos + 4;
        let data = buf
            .get(start..start + declared)
            .ok_or(ElementError::ShortData {
                declared,
                remaining: remaining.saturating_sub(4),
            })?;
        return Ok(Element {
            ty: word & 0xFFFF,
            data,
            next: (pos + TAG_LEN).min(buf.len()),
        });
    }
    let size = array_at::<4>(buf, pos + 4).ok_or(ElementError::ShortTag { remaining })?;
    let declared = endian.u32(size) as usize;
    let start = pos + TAG_LEN;
    let data = start
        .checked_add(declared)
        .and_then(|end| buf.get(start..end))
        .ok_or(ElementError::ShortData {
            declared,
            remaining: remaining - TAG_LEN,
        })?;
    let next = if word == MI_COMPRESSED {
        start + declared
    } else {
        start.saturating_add(pad8(declared)).min(buf.len())
    };
    Ok(Element {
        ty: word,
        data,
        next,
    })
}

/// The header of a variable: what is needed to decide whether it is the one wanted.
struct ArrayHeader<'a> {
    flags: u32,
    dims: Vec<i64>,
    name: String,
    /// The sub-elements after the name (real part, imaginary part, ...).
    rest: &'a [u8],
}

/// Reads the MAT-file in memory.
struct MatReader<'a> {
    path: &'a Path,
    endian: Endian,
}

impl<'a> MatReader<'a> {
    fn truncated(&self, what: String) -> RecordingError {
        RecordingError::MatTruncated {
            path: self.path.to_path_buf(),
            what,
        }
    }

    fn corrupt(&self, what: String) -> RecordingError {
        RecordingError::MatCorrupt {
            path: self.path.to_path_buf(),
            what,
        }
    }

    /// Inflates the zlib stream of the compressed element at byte `at`.
    fn inflate(&self, input: &[u8], at: usize) -> Result<Vec<u8>, RecordingError> {
        let mut z = Decompress::new(true);
        let mut out: Vec<u8> = Vec::with_capacity(input.len().saturating_mul(8).min(MAX_INFLATED));
        loop {
            if out.len() == out.capacity() {
                if out.len() >= MAX_INFLATED {
                    return Err(self.corrupt(format!(
                        "compressed element at byte {at} inflates to more than {MAX_INFLATED} bytes"
                    )));
                }
                out.reserve(out.len().max(1 << 16).min(MAX_INFLATED - out.len()));
            }
            let consumed = usize::try_from(z.total_in()).unwrap_or(usize::MAX);
            let rest = input.get(consumed..).unwrap_or(&[]);
            let produced = out.len();
            let status = z
                .decompress_vec(rest, &mut out, FlushDecompress::None)
                .map_err(|e| {
                    self.corrupt(format!(
                        "compressed element at byte {at}: corrupt zlib data ({e})"
                    ))
                })?;
            if status == Status::StreamEnd {
                return Ok(out);
            }
            let progressed = usize::try_from(z.total_in()).unwrap_or(usize::MAX) != consumed
                || out.len() != produced;
            if !progressed && out.len() < out.capacity() {
                return Err(if consumed >= input.len() {
                    self.truncated(format!(
                        "the zlib stream of the compressed element at byte {at} ends early \
                         ({} compressed bytes inflate to {} bytes, stream unfinished)",
                        input.len(),
                        out.len()
                    ))
                } else {
                    self.corrupt(format!(
                        "compressed element at byte {at}: zlib stream stalled at compressed byte {consumed}"
                    ))
                });
            }
        }
    }

    /// Parses flags, dimensions and name of the `miMATRIX` whose data is `body`. `at` locates it, for messages.
    fn array_header<'b>(
        &self,
        body: &'b [u8],
        at: &str,
    ) -> Result<ArrayHeader<'b>, RecordingError> {
        let sub = |pos: usize, what: &str| {
            element(body, pos, self.endian)
                .map_err(|e| self.corrupt(e.describe(&format!("{at}: {what}"))))
        };
        let flags_el = sub(0, "array flags")?;
        let flags = match (flags_el.ty, array_at::<4>(flags_el.data, 0)) {
            (MI_UINT32, Some(b)) => self.endian.u32(b),
            _ => {
                return Err(self.corrupt(format!(
                "{at}: array flags should be miUINT32 with 8 bytes, found type {} with {} bytes",
                flags_el.ty,
                flags_el.data.len()
            )))
            }
        };
        let dims_el = sub(flags_el.next, "dimensions")?;
        if dims_el.ty != MI_INT32
            || !dims_el.data.chunks_exact(4).remainder().is_empty()
            || dims_el.data.len() < 8
        {
            return Err(self.corrupt(format!(
                "{at}: dimensions should be at least two miINT32 values, found type {} with {} bytes",
                dims_el.ty,
                dims_el.data.len()
            )));
        }
        let dims: Vec<i64> = dims_el
            .data
            .chunks_exact(4)
            .map(|c| {
                let b = [c[0], c[1], c[2], c[3]];
                i64::from(self.endian.u32(b) as i32)
            })
            .collect();
        if let Some(d) = dims.iter().find(|&&d| d < 0) {
            return Err(self.corrupt(format!("{at}: negative dimension {d}")));
        }
        let name_el = sub(dims_el.next, "name")?;
        if name_el.ty != MI_INT8 && name_el.ty != MI_UINT8 && name_el.ty != MI_UTF8 {
            return Err(self.corrupt(format!(
                "{at}: the name should be miINT8 text, found type {}",
                name_el.ty
            )));
        }
        let name = String::from_utf8_lossy(name_el.data).into_owned();
        Ok(ArrayHeader {
            flags,
            dims,
            name,
            rest: body.get(name_el.next..).unwrap_or(&[]),
        })
    }

    /// Decodes the numeric data element `el` to `f64`.
    fn numeric(&self, el: &Element<'_>, at: &str) -> Result<Vec<f64>, RecordingError> {
        let e = self.endian;
        let data = el.data;
        let width = match el.ty {
            MI_INT8 | MI_UINT8 => 1,
            MI_INT16 | MI_UINT16 => 2,
            MI_INT32 | MI_UINT32 | MI_SINGLE => 4,
            MI_DOUBLE | MI_INT64 | MI_UINT64 => 8,
            other => {
                return Err(self.corrupt(format!(
                    "{at}: the real part has non-numeric data type {other}"
                )))
            }
        };
        if !data.chunks_exact(width).remainder().is_empty() {
            return Err(self.corrupt(format!(
                "{at}: real part of {} bytes is not a whole number of {width}-byte values",
                data.len()
            )));
        }
        macro_rules! decode {
            ($t:ty) => {{
                const N: usize = std::mem::size_of::<$t>();
                data.chunks_exact(N)
                    .map(|c| {
                        let mut b = [0u8; N];
                        b.copy_from_slice(c);
                        let v = match e {
                            Endian::Little => <$t>::from_le_bytes(b),
                            Endian::Big => <$t>::from_be_bytes(b),
                        };
                        v as f64
                    })
                    .collect()
            }};
        }
        Ok(match el.ty {
            MI_INT8 => decode!(i8),
            MI_UINT8 => decode!(u8),
            MI_INT16 => decode!(i16),
            MI_UINT16 => decode!(u16),
            MI_INT32 => decode!(i32),
            MI_UINT32 => decode!(u32),
            MI_SINGLE => decode!(f32),
            MI_INT64 => decode!(i64),
            MI_UINT64 => decode!(u64),
            _ => decode!(f64),
        })
    }

    /// Turns the wanted variable into a recording.
    fn recording(&self, header: &ArrayHeader<'_>, at: &str) -> Result<Recording, RecordingError> {
        let class = header.flags & 0xFF;
        let complex = header.flags & FLAG_COMPLEX != 0;
        let logical = header.flags & FLAG_LOGICAL != 0;
        if !(class == MX_DOUBLE_CLASS || class == MX_SINGLE_CLASS) || complex || logical {
            let mut found = class_name(class);
            if logical {
                found = format!("logical ({found})");
            }
            if complex {
                found = format!("complex {found}");
            }
            return Err(RecordingError::MatClass {
                path: self.path.to_path_buf(),
                name: MAT_VARIABLE,
                class: found,
            });
        }
        let wrong_shape = || RecordingError::MatShape {
            path: self.path.to_path_buf(),
            name: MAT_VARIABLE,
            dims: header.dims.clone(),
        };
        let [rows, cols] = header.dims[..] else {
            return Err(wrong_shape());
        };
        if cols != COLUMNS.len() as i64 {
            return Err(wrong_shape());
        }
        let rows = usize::try_from(rows).map_err(|_| wrong_shape())?;
        let real = element(header.rest, 0, self.endian)
            .map_err(|e| self.corrupt(e.describe(&format!("{at}: real part"))))?;
        let values = self.numeric(&real, at)?;
        let needed = rows.checked_mul(COLUMNS.len());
        if needed != Some(values.len()) {
            return Err(self.corrupt(format!(
                "{at}: the real part holds {} values but the shape {rows}×{cols} needs {}",
                values.len(),
                needed.map_or_else(|| "more".to_string(), |n| n.to_string())
            )));
        }
        // Column-major: column c is values[c*rows .. (c+1)*rows].
        let columns: Vec<&[f64]> = if rows == 0 {
            vec![&[][..]; COLUMNS.len()]
        } else {
            values.chunks_exact(rows).collect()
        };
        let mut out = Vec::with_capacity(rows);
        for r in 0..rows {
            let mut v = [0.0; 9];
            for (c, value) in v.iter_mut().enumerate() {
                *value = columns
                    .get(c)
                    .and_then(|col| col.get(r))
                    .copied()
                    .unwrap_or(f64::NAN);
            }
            out.push(self.row(&v, r)?);
        }
        let rec = Recording {
            rows: out,
            extra: None,
        };
        rec.validate()
            .map_err(|source| RecordingError::InvalidData {
                path: self.path.to_path_buf(),
                source: Box::new(source),
            })?;
        Ok(rec)
    }

    /// Converts the nine values of row `r` (0-based), checking every column.
    fn row(&self, v: &[f64; 9], r: usize) -> Result<Row, RecordingError> {
        let bad = |c: usize, reason: String| RecordingError::MatValue {
            path: self.path.to_path_buf(),
            name: MAT_VARIABLE,
            row: r + 1,
            column: c + 1,
            column_name: COLUMNS[c],
            reason,
        };
        for (c, value) in v.iter().enumerate() {
            if !value.is_finite() {
                return Err(bad(c, format!("non-finite value {value}")));
            }
        }
        let direction = match v[5] {
            0.0 => 0,
            1.0 => 1,
            other => return Err(bad(5, format!("direction must be 0 or 1, found {other}"))),
        };
        let uint = |c: usize| {
            let value = v[c];
            if value >= 0.0 && value.fract() == 0.0 && value <= f64::from(u32::MAX) {
                Ok(value as u32)
            } else {
                Err(bad(
                    c,
                    format!("expected an integer in 0..={}, found {value}", u32::MAX),
                ))
            }
        };
        Ok(Row {
            x_mm: v[0],
            d1: v[1],
            d2: v[2],
            d3: v[3],
            p: v[4],
            direction,
            slide: uint(6)?,
            label: v[7],
            repetition: uint(8)?,
        })
    }

    /// Checks the header, returning the endianness.
    fn header(path: &Path, bytes: &[u8]) -> Result<Endian, RecordingError> {
        let not_mat = |reason: String| RecordingError::NotMat {
            path: path.to_path_buf(),
            reason,
        };
        if bytes.is_empty() {
            return Err(not_mat("the file is empty".to_string()));
        }
        let magic = b"MATLAB";
        let n = magic.len().min(bytes.len());
        if bytes.get(..n) != magic.get(..n) {
            let preview: String = bytes
                .iter()
                .take(16)
                .map(|&b| {
                    if b.is_ascii_graphic() || b == b' ' {
                        char::from(b)
                    } else {
                        '.'
                    }
                })
                .collect();
            return Err(not_mat(format!(
                "the header text does not start with `MATLAB` (it starts with `{preview}`)"
            )));
        }
        if bytes.starts_with(b"MATLAB 7.3") || bytes.get(512..520) == Some(&HDF5_SIGNATURE[..]) {
            return Err(RecordingError::MatV73 {
                path: path.to_path_buf(),
            });
        }
        if bytes.len() < HEADER_LEN {
            return Err(RecordingError::MatTruncated {
                path: path.to_path_buf(),
                what: format!(
                    "the file has {} bytes, less than the 128-byte header",
                    bytes.len()
                ),
            });
        }
        let endian = match array_at::<2>(bytes, 126) {
            Some([b'I', b'M']) => Endian::Little,
            Some([b'M', b'I']) => Endian::Big,
            other => {
                return Err(not_mat(format!(
                    "the endian indicator at byte 126 is {:?}, expected `IM` or `MI`",
                    other
                        .map(|b| String::from_utf8_lossy(&b).into_owned())
                        .unwrap_or_default()
                )))
            }
        };
        let version = array_at::<2>(bytes, 124).map_or(0, |b| endian.u16(b));
        match version {
            0x0100 => Ok(endian),
            0x0200 => Err(RecordingError::MatV73 {
                path: path.to_path_buf(),
            }),
            other => Err(not_mat(format!(
                "unknown MAT-file version 0x{other:04x} (level 5 files have 0x0100)"
            ))),
        }
    }
}

/// Reads the authors' recording from a MAT-file (level 5, compressed or not): the variable `synchronized_data`
/// ([`MAT_VARIABLE`]), a real double (or single) matrix of N rows × the nine [`COLUMNS`].
///
/// Errors name the file and the problem: [`RecordingError::NotMat`] (not a MAT-file),
/// [`RecordingError::MatV73`] (an HDF5-based MAT 7.3 file), [`RecordingError::MatTruncated`] (an element runs past
/// the end of the file, or a zlib stream ends early), [`RecordingError::MatCorrupt`] (corrupt zlib data or
/// malformed elements), [`RecordingError::MatMissingVariable`] (listing the variables found),
/// [`RecordingError::MatShape`], [`RecordingError::MatClass`] and [`RecordingError::MatValue`] (a NaN or infinite
/// value, a direction other than 0/1, a slide or repetition that is not a non-negative integer; with its 1-based row
/// and column).
pub fn read_mat(path: &Path) -> Result<Recording, RecordingError> {
    let bytes = std::fs::read(path).map_err(|source| RecordingError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    read_mat_impl(&bytes, path)
}

/// Reads a MAT-file held in memory; `source_name` names it in error messages. See [`read_mat`].
pub fn read_mat_from(bytes: &[u8], source_name: &str) -> Result<Recording, RecordingError> {
    read_mat_impl(bytes, Path::new(source_name))
}

fn read_mat_impl(bytes: &[u8], path: &Path) -> Result<Recording, RecordingError> {
    let endian = MatReader::header(path, bytes)?;
    let reader = MatReader { path, endian };
    let mut names = Vec::new();
    let mut pos = HEADER_LEN;
    while pos < bytes.len() {
        let el = element(bytes, pos, endian).map_err(|e| match e {
            ElementError::BadSmall { .. } => {
                reader.corrupt(e.describe(&format!("the data element at byte {pos}")))
            }
            _ => reader.truncated(e.describe(&format!("the data element at byte {pos}"))),
        })?;
        let (at, inflated);
        let body = match el.ty {
            MI_MATRIX => {
                at = format!("variable at byte {pos}");
                el.data
            }
            MI_COMPRESSED => {
                at = format!("compressed variable at byte {pos}");
                inflated = reader.inflate(el.data, pos)?;
                let inner = element(&inflated, 0, endian).map_err(|e| {
                    reader.corrupt(e.describe(&format!(
                        "the element inflated from the compressed element at byte {pos}"
                    )))
                })?;
                if inner.ty != MI_MATRIX {
                    // Not a variable: nothing to read.
                    pos = el.next;
                    continue;
                }
                inner.data
            }
            _ => {
                pos = el.next;
                continue;
            }
        };
        let header = reader.array_header(body, &at)?;
        if header.name == MAT_VARIABLE {
            return reader.recording(&header, &at);
        }
        names.push(header.name);
        pos = el.next;
    }
    Err(RecordingError::MatMissingVariable {
        path: path.to_path_buf(),
        name: MAT_VARIABLE,
        found: names,
    })
}

/// Appends one element (tag and data padded to 8 bytes) to `out`, little-endian.
fn push_element(out: &mut Vec<u8>, ty: u32, data: &[u8]) -> Result<(), String> {
    let size = u32::try_from(data.len()).map_err(|_| "the matrix exceeds 4 GiB".to_string())?;
    out.extend_from_slice(&ty.to_le_bytes());
    out.extend_from_slice(&size.to_le_bytes());
    out.extend_from_slice(data);
    out.resize(pad8(out.len()), 0);
    Ok(())
}

/// The bytes of a compressed level-5 MAT-file holding `rec` as `synchronized_data`.
fn mat_bytes(rec: &Recording) -> Result<Vec<u8>, String> {
    let rows = rec.rows.len();
    let rows_i32 =
        i32::try_from(rows).map_err(|_| format!("{rows} rows exceed a MAT dimension"))?;
    let mut matrix = Vec::new();
    let mut flags = Vec::new();
    flags.extend_from_slice(&MX_DOUBLE_CLASS.to_le_bytes());
    flags.extend_from_slice(&0u32.to_le_bytes());
    push_element(&mut matrix, MI_UINT32, &flags)?;
    let mut dims = Vec::new();
    dims.extend_from_slice(&rows_i32.to_le_bytes());
    dims.extend_from_slice(&(COLUMNS.len() as i32).to_le_bytes());
    push_element(&mut matrix, MI_INT32, &dims)?;
    push_element(&mut matrix, MI_INT8, MAT_VARIABLE.as_bytes())?;
    let mut data = Vec::with_capacity(rows * COLUMNS.len() * 8);
    let columns: [fn(&Row) -> f64; 9] = [
        |r| r.x_mm,
        |r| r.d1,
        |r| r.d2,
        |r| r.d3,
        |r| r.p,
        |r| f64::from(r.direction),
        |r| f64::from(r.slide),
        |r| r.label,
        |r| f64::from(r.repetition),
    ];
    for column in columns {
        for row in &rec.rows {
            data.extend_from_slice(&column(row).to_le_bytes());
        }
    }
    push_element(&mut matrix, MI_DOUBLE, &data)?;
    let mut element = Vec::with_capacity(matrix.len() + TAG_LEN);
    push_element(&mut element, MI_MATRIX, &matrix)?;

    let mut encoder = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
    encoder
        .write_all(&element)
        .and_then(|()| encoder.finish())
        .map_err(|e| format!("compressing: {e}"))
        .and_then(|compressed| {
            let mut out = Vec::with_capacity(HEADER_LEN + TAG_LEN + compressed.len());
            let mut text = format!(
                "MATLAB 5.0 MAT-file, Platform: {}, Created by: crackbot-recording {}",
                std::env::consts::OS,
                env!("CARGO_PKG_VERSION")
            )
            .into_bytes();
            text.resize(116, b' ');
            out.extend_from_slice(&text);
            out.extend_from_slice(&[0; 8]);
            out.extend_from_slice(&0x0100u16.to_le_bytes());
            out.extend_from_slice(b"IM");
            let size = u32::try_from(compressed.len())
                .map_err(|_| "the compressed matrix exceeds 4 GiB".to_string())?;
            out.extend_from_slice(&MI_COMPRESSED.to_le_bytes());
            out.extend_from_slice(&size.to_le_bytes());
            out.extend_from_slice(&compressed);
            Ok(out)
        })
}

/// Writes a recording as a compressed level-5 MAT-file (the authors' format: one variable `synchronized_data`, a
/// double matrix of N rows × the nine [`COLUMNS`]), readable by MATLAB, `scipy.io.loadmat` and [`read_mat`].
///
/// The recording is validated first ([`RecordingError::InvalidData`]); one with the extra columns is refused
/// ([`RecordingError::MatUnsupported`]: the MAT form holds the nine columns only, write it as CSV). No file is
/// touched when the recording is refused. The data is synced to disk before returning.
pub fn write_mat(path: &Path, rec: &Recording) -> Result<(), RecordingError> {
    rec.validate()
        .map_err(|source| RecordingError::InvalidData {
            path: path.to_path_buf(),
            source: Box::new(source),
        })?;
    let unsupported = |reason: String| RecordingError::MatUnsupported {
        path: path.to_path_buf(),
        reason,
    };
    if rec.extra.is_some() {
        return Err(unsupported(
            "the recording has the extra columns (device_time_us, seq, flags), which the nine-column MAT form \
             would lose; write it as .csv"
                .to_string(),
        ));
    }
    let bytes = mat_bytes(rec).map_err(unsupported)?;
    let io = |source| RecordingError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut file = std::fs::File::create(path).map_err(io)?;
    file.write_all(&bytes).map_err(io)?;
    file.sync_all().map_err(io)
}
