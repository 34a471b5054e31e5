//! The binary model file (format version 1).
//!
//! Little-endian throughout:
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 8 | magic `b"CRKFORST"` |
//! | 8 | 4 | format version (`1`) |
//! | 12 | 4 | kind: 1 = classifier, 2 = regressor |
//! | 16 | 4 | `n_features` |
//! | 20 | 4 | leaf width `W`: `n_classes` (classifier) or 1 (regressor) |
//! | 24 | 4 | `n_trees` |
//! | 28 | 4 | `n_nodes` |
//! | 32 | 4 | `n_leaves` |
//! | 36 | 4 | flags: bit 0 = feature importances present |
//! | 40 | 8·W | class labels as `f64` (classifier only; e.g. crack widths in mm) |
//! | … | 8·n_features | feature importances as `f64` (if flag bit 0) |
//! | … | 4·(n_trees+1) | tree offsets into the node array (`u32`) |
//! | … | 12·n_nodes | nodes: feature `u32` (`u32::MAX` = leaf), threshold `f32`, right child / leaf id `u32` |
//! | … | 4·W·n_leaves | leaf values `f32` (class probabilities, or the mean for a regressor) |
//! | end−4 | 4 | CRC-32 (ISO-HDLC, as zlib) of every preceding byte |
//!
//! Loading checks, in order: magic, version, kind, length (truncated / trailing bytes), checksum, then every
//! structural invariant (see [`crate::flat`]): offsets increasing, child indices inside their tree and
//! greater than their parent's (so no cycle is possible), feature indices `< n_features`, leaf ids in range,
//! finite values.

use std::path::Path;

use crate::error::{ForestError, FormatError};
use crate::flat::{FlatTrees, Node};

/// Magic number at the start of every model file.
pub const MAGIC: [u8; 8] = *b"CRKFORST";
/// Format version written by this build.
pub const FORMAT_VERSION: u32 = 1;
/// Format versions this build reads.
pub const SUPPORTED_VERSIONS: &[u32] = &[1];
const HEADER_LEN: usize = 40;
const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// Model kind stored in the header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    Classifier = 1,
    Regressor = 2,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::Classifier => "classifier",
            Kind::Regressor => "regressor",
        }
    }
}

/// Everything a model file holds.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Parts {
    pub kind: Kind,
    pub trees: FlatTrees,
    pub labels: Vec<f64>,
    pub importances: Option<Vec<f64>>,
}

/// Checks labels and importances (the tree arrays are checked by [`FlatTrees::validate`]).
pub(crate) fn validate_parts(p: &Parts) -> Result<(), FormatError> {
    p.trees.validate()?;
    let bad = |m: String| Err(FormatError::Inconsistent(m));
    match p.kind {
        Kind::Classifier => {
            if p.labels.len() != p.trees.width {
                return bad(format!(
                    "{} class labels for {} classes",
                    p.labels.len(),
                    p.trees.width
                ));
            }
            if p.labels.iter().any(|v| !v.is_finite()) {
                return bad("non-finite class label".into());
            }
        }
        Kind::Regressor => {
            if p.trees.width != 1 || !p.labels.is_empty() {
                return bad(format!(
                    "regressor with leaf width {} and {} labels",
                    p.trees.width,
                    p.labels.len()
                ));
            }
        }
    }
    if let Some(imp) = &p.importances {
        if imp.len() != p.trees.n_features || imp.iter().any(|v| !v.is_finite()) {
            return bad("feature importances: wrong count or non-finite".into());
        }
    }
    Ok(())
}

/// Serialises a model.
pub(crate) fn encode(p: &Parts) -> Vec<u8> {
    let t = &p.trees;
    let n_leaves = t.leaf_values.len() / t.width.max(1);
    let mut b = Vec::with_capacity(
        HEADER_LEN
            + 8 * (p.labels.len() + t.n_features)
            + 4 * t.offsets.len()
            + 12 * t.nodes.len()
            + 4 * t.leaf_values.len()
            + 4,
    );
    b.extend_from_slice(&MAGIC);
    for v in [
        FORMAT_VERSION,
        p.kind as u32,
        t.n_features as u32,
        t.width as u32,
        t.n_trees() as u32,
        t.nodes.len() as u32,
        n_leaves as u32,
        p.importances.is_some() as u32,
    ] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    for v in &p.labels {
        b.extend_from_slice(&v.to_le_bytes());
    }
    if let Some(imp) = &p.importances {
        for v in imp {
            b.extend_from_slice(&v.to_le_bytes());
        }
    }
    for v in &t.offsets {
        b.extend_from_slice(&v.to_le_bytes());
    }
    for n in &t.nodes {
        b.extend_from_slice(&n.feature.to_le_bytes());
        b.extend_from_slice(&n.threshold.to_le_bytes());
        b.extend_from_slice(&n.right.to_le_bytes());
    }
    for v in &t.leaf_values {
        b.extend_from_slice(&v.to_le_bytes());
    }
    let crc = CRC.checksum(&b);
    b.extend_from_slice(&crc.to_le_bytes());
    b
}

/// Little-endian reader over a slice whose length was checked beforehand.
struct Reader<'a> {
    b: &'a [u8],
    pos: usize,
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N], FormatError> {
        let s = self.b.get(self.pos..self.pos + N).ok_or_else(|| {
            FormatError::Inconsistent(format!("unexpected end at byte {}", self.pos))
        })?;
        self.pos += N;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }
    fn u32(&mut self) -> Result<u32, FormatError> {
        Ok(u32::from_le_bytes(self.take()?))
    }
    fn f32(&mut self) -> Result<f32, FormatError> {
        Ok(f32::from_le_bytes(self.take()?))
    }
    fn f64(&mut self) -> Result<f64, FormatError> {
        Ok(f64::from_le_bytes(self.take()?))
    }
}

/// Decodes and fully validates a model of kind `want`.
pub(crate) fn decode(bytes: &[u8], want: Kind) -> Result<Parts, FormatError> {
    if bytes.len() < 8 || bytes[..8] != MAGIC {
        return Err(FormatError::BadMagic {
            found: bytes[..bytes.len().min(8)].to_vec(),
            expected: MAGIC,
        });
    }
    if bytes.len() < HEADER_LEN {
        return Err(FormatError::Truncated {
            expected: HEADER_LEN as u64,
            actual: bytes.len() as u64,
        });
    }
    let mut r = Reader { b: bytes, pos: 8 };
    let version = r.u32()?;
    if !SUPPORTED_VERSIONS.contains(&version) {
        return Err(FormatError::UnsupportedVersion {
            found: version,
            supported: SUPPORTED_VERSIONS,
        });
    }
    let kind = match r.u32()? {
        1 => Kind::Classifier,
        2 => Kind::Regressor,
        k => return Err(FormatError::Inconsistent(format!("unknown model kind {k}"))),
    };
    if kind != want {
        return Err(FormatError::WrongKind {
            found: kind.name(),
            expected: want.name(),
        });
    }
    let n_features = r.u32()? as u128;
    let width = r.u32()? as u128;
    let n_trees = r.u32()? as u128;
    let n_nodes = r.u32()? as u128;
    let n_leaves = r.u32()? as u128;
    let flags = r.u32()?;
    if flags & !1 != 0 {
        return Err(FormatError::Inconsistent(format!(
            "unknown flags {flags:#x}"
        )));
    }
    let has_imp = flags & 1 == 1;
    let n_labels = if kind == Kind::Classifier { width } else { 0 };
    // Every count is < 2^32, so this cannot overflow u128.
    let expected = HEADER_LEN as u128
        + 8 * n_labels
        + if has_imp { 8 * n_features } else { 0 }
        + 4 * (n_trees + 1)
        + 12 * n_nodes
        + 4 * width * n_leaves
        + 4;
    let actual = bytes.len() as u128;
    let clamp = |v: u128| u64::try_from(v).unwrap_or(u64::MAX);
    if actual < expected {
        return Err(FormatError::Truncated {
            expected: clamp(expected),
            actual: clamp(actual),
        });
    }
    if actual > expected {
        return Err(FormatError::TrailingBytes {
            extra: clamp(actual - expected),
        });
    }
    let body = &bytes[..bytes.len() - 4];
    let mut crc_bytes = [0u8; 4];
    crc_bytes.copy_from_slice(&bytes[bytes.len() - 4..]);
    let stored = u32::from_le_bytes(crc_bytes);
    let computed = CRC.checksum(body);
    if stored != computed {
        return Err(FormatError::ChecksumMismatch { stored, computed });
    }
    // The length check bounds every count by the file size, so these allocations are safe.
    let labels = (0..n_labels)
        .map(|_| r.f64())
        .collect::<Result<Vec<_>, _>>()?;
    let importances = if has_imp {
        Some(
            (0..n_features)
                .map(|_| r.f64())
                .collect::<Result<Vec<_>, _>>()?,
        )
    } else {
        None
    };
    let offsets = (0..=n_trees)
        .map(|_| r.u32())
        .collect::<Result<Vec<_>, _>>()?;
    let nodes = (0..n_nodes)
        .map(|_| {
            Ok(Node {
                feature: r.u32()?,
                threshold: r.f32()?,
                right: r.u32()?,
            })
        })
        .collect::<Result<Vec<_>, FormatError>>()?;
    let leaf_values = (0..width * n_leaves)
        .map(|_| r.f32())
        .collect::<Result<Vec<_>, _>>()?;
    let parts = Parts {
        kind,
        trees: FlatTrees {
            n_features: n_features as usize,
            width: width as usize,
            nodes,
            offsets,
            leaf_values,
            walk: None,
        },
        labels,
        importances,
    };
    validate_parts(&parts)?;
    Ok(Parts {
        trees: parts.trees.finish(),
        ..parts
    })
}

/// Writes a model file (to a temporary file in the same folder, then renamed into place).
pub(crate) fn save(path: &Path, p: &Parts) -> Result<(), ForestError> {
    let wrap = |e: std::io::Error| ForestError::ModelFile {
        path: path.to_path_buf(),
        source: FormatError::Io(e),
    };
    let bytes = encode(p);
    let file_name = path
        .file_name()
        .map_or_else(|| "model".into(), |s| s.to_string_lossy().into_owned());
    let tmp = path.with_file_name(format!(".{file_name}.tmp{}", std::process::id()));
    std::fs::write(&tmp, &bytes).map_err(wrap)?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        wrap(e)
    })
}

/// Reads and validates a model file of kind `want`.
pub(crate) fn load(path: &Path, want: Kind) -> Result<Parts, ForestError> {
    let wrap = |source: FormatError| ForestError::ModelFile {
        path: path.to_path_buf(),
        source,
    };
    let bytes = std::fs::read(path).map_err(|e| wrap(FormatError::Io(e)))?;
    decode(&bytes, want).map_err(wrap)
}
