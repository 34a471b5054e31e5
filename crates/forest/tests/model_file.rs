//! Model file: round trips and every kind of corruption.

#![expect(
    clippy::unwrap_used,
    reason = "a test stops at the first thing it did not expect, and says where"
)]

use std::path::Path;

use crackbot_forest::format::{FORMAT_VERSION, MAGIC};
use crackbot_forest::{
    synthetic, Classifier, ForestError, ForestParams, FormatError, RandomForest,
    RandomForestRegressor,
};
use proptest::prelude::*;

const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

fn small_forest() -> RandomForest {
    let data = synthetic::blobs(400, 3, 4, 60.0, 77).unwrap();
    RandomForest::fit(
        &data,
        &ForestParams::classifier().n_trees(4).seed(1).quiet(true),
    )
    .unwrap()
    .with_class_labels(vec![0.0, 1.0, 2.5, 10.0])
    .unwrap()
}

/// Byte offset of the node array in a classifier file (header, labels, importances, tree offsets).
fn nodes_offset(f: &RandomForest) -> usize {
    40 + 8 * f.n_classes() + 8 * f.n_features() + 4 * (f.n_trees() + 1)
}

/// Rewrites the trailing CRC so that only the structural validation can reject the file.
fn fix_crc(bytes: &mut [u8]) {
    let n = bytes.len() - 4;
    let crc = CRC.checksum(&bytes[..n]);
    bytes[n..].copy_from_slice(&crc.to_le_bytes());
}

fn put_u32(bytes: &mut [u8], at: usize, v: u32) {
    bytes[at..at + 4].copy_from_slice(&v.to_le_bytes());
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// Loads `bytes` from a file and returns the format error, checking that the message names the file.
fn load_err(dir: &Path, name: &str, bytes: &[u8]) -> FormatError {
    let path = write(dir, name, bytes);
    let err = RandomForest::load(&path).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains(name), "error should name the file: {msg}");
    match err {
        ForestError::ModelFile { source, .. } => source,
        other => panic!("unexpected error {other}"),
    }
}

#[test]
fn round_trip_predicts_identically() {
    let dir = tempfile::tempdir().unwrap();
    let f = small_forest();
    let path = dir.path().join("forest.crkf");
    f.save(&path).unwrap();
    let g = RandomForest::load(&path).unwrap();
    assert_eq!(f, g);
    assert_eq!(g.class_labels(), &[0.0, 1.0, 2.5, 10.0]);
    assert_eq!(f.feature_importances(), g.feature_importances());
    let test = synthetic::blobs(500, 3, 4, 60.0, 78).unwrap();
    for i in 0..test.n_rows() {
        let row = test.row(i).unwrap();
        assert_eq!(f.predict(row), g.predict(row));
        assert_eq!(f.predict_proba(row), g.predict_proba(row));
    }
    // Saving again gives the same bytes.
    assert_eq!(std::fs::read(&path).unwrap(), g.to_bytes());
    assert_eq!(&f.to_bytes()[..8], &MAGIC);
}

#[test]
fn regressor_round_trip_and_kind_check() {
    let dir = tempfile::tempdir().unwrap();
    let data = synthetic::width_regression(500, 0.2, 3).unwrap();
    let r = RandomForestRegressor::fit(&data, &ForestParams::regressor().n_trees(3).quiet(true))
        .unwrap();
    let path = dir.path().join("width.crkf");
    r.save(&path).unwrap();
    let s = RandomForestRegressor::load(&path).unwrap();
    assert_eq!(r, s);
    for i in 0..50 {
        let row = data.row(i).unwrap();
        assert_eq!(r.predict(row), s.predict(row));
    }
    // A regressor file is not a classifier, and vice versa.
    let err = RandomForest::load(&path).unwrap_err();
    assert!(
        matches!(
            err,
            ForestError::ModelFile {
                source: FormatError::WrongKind { .. },
                ..
            }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("regressor"), "{err}");
    let cpath = dir.path().join("c.crkf");
    small_forest().save(&cpath).unwrap();
    assert!(RandomForestRegressor::load(&cpath).is_err());
}

#[test]
fn wrong_magic() {
    let dir = tempfile::tempdir().unwrap();
    let mut b = small_forest().to_bytes();
    b[0] = b'X';
    let e = load_err(dir.path(), "magic.crkf", &b);
    assert!(matches!(e, FormatError::BadMagic { .. }), "{e}");
    let e = load_err(dir.path(), "text.crkf", b"hello world, not a model");
    assert!(matches!(e, FormatError::BadMagic { .. }), "{e}");
    let e = load_err(dir.path(), "empty.crkf", b"");
    assert!(matches!(e, FormatError::BadMagic { .. }), "{e}");
}

#[test]
fn unsupported_version() {
    let dir = tempfile::tempdir().unwrap();
    let mut b = small_forest().to_bytes();
    put_u32(&mut b, 8, 9);
    fix_crc(&mut b);
    let e = load_err(dir.path(), "v9.crkf", &b);
    assert!(
        matches!(e, FormatError::UnsupportedVersion { found: 9, .. }),
        "{e}"
    );
    let msg = e.to_string();
    assert!(
        msg.contains('9') && msg.contains(&FORMAT_VERSION.to_string()),
        "{msg}"
    );
}

#[test]
fn truncated_and_trailing() {
    let dir = tempfile::tempdir().unwrap();
    let b = small_forest().to_bytes();
    for cut in [12, 39, 40, 100, b.len() / 2, b.len() - 4, b.len() - 1] {
        let e = load_err(dir.path(), "cut.crkf", &b[..cut]);
        assert!(
            matches!(e, FormatError::Truncated { .. }),
            "cut at {cut}: {e}"
        );
    }
    // Huge counts in the header (leaf width × leaf count near 2^64 bytes): a length error, no overflow.
    let mut huge = b.clone();
    put_u32(&mut huge, 20, u32::MAX);
    put_u32(&mut huge, 28, u32::MAX);
    put_u32(&mut huge, 32, u32::MAX);
    let e = load_err(dir.path(), "huge.crkf", &huge);
    assert!(matches!(e, FormatError::Truncated { .. }), "{e}");
    let mut longer = b.clone();
    longer.extend_from_slice(&[0, 0, 0]);
    let e = load_err(dir.path(), "long.crkf", &longer);
    assert!(matches!(e, FormatError::TrailingBytes { extra: 3 }), "{e}");
}

#[test]
fn checksum_mismatch() {
    let dir = tempfile::tempdir().unwrap();
    let f = small_forest();
    let b = f.to_bytes();
    for at in [nodes_offset(&f) + 5, b.len() - 10, 45, b.len() - 2] {
        let mut c = b.clone();
        c[at] ^= 0x10;
        let e = load_err(dir.path(), "crc.crkf", &c);
        assert!(
            matches!(e, FormatError::ChecksumMismatch { .. }),
            "flip at {at}: {e}"
        );
    }
}

#[test]
fn inconsistent_indices_are_rejected_even_with_a_valid_crc() {
    let dir = tempfile::tempdir().unwrap();
    let f = small_forest();
    let base = nodes_offset(&f);
    // Node 0 is the root of tree 0 (internal). Node fields: feature @0, threshold @4, right @8.
    assert!(!f.nodes()[0].is_leaf());
    let tree0_end = f.tree_offsets()[1];
    let first_leaf = f
        .nodes()
        .iter()
        .position(crackbot_forest::Node::is_leaf)
        .unwrap();
    let n_leaves = (f.leaf_values().len() / f.n_classes()) as u32;
    let cases: Vec<(&str, usize, u32)> = vec![
        ("right child out of range", base + 8, f.n_nodes() as u32 + 7),
        ("right child in the next tree", base + 8, tree0_end),
        ("right child pointing back (cycle)", base + 8, 0),
        ("right child equal to the left child", base + 8, 1),
        ("feature index too large", base, 3),
        ("leaf id out of range", base + 12 * first_leaf + 8, n_leaves),
    ];
    for (what, at, v) in cases {
        let mut b = f.to_bytes();
        put_u32(&mut b, at, v);
        fix_crc(&mut b);
        let e = load_err(dir.path(), "bad.crkf", &b);
        assert!(matches!(e, FormatError::Inconsistent(_)), "{what}: {e}");
    }
    // Tree offsets that do not end at the node count.
    let mut b = f.to_bytes();
    let offsets_at = base - 4 * (f.n_trees() + 1);
    put_u32(&mut b, offsets_at + 4 * f.n_trees(), f.n_nodes() as u32 - 1);
    fix_crc(&mut b);
    assert!(matches!(
        load_err(dir.path(), "offs.crkf", &b),
        FormatError::Inconsistent(_)
    ));
    // A middle tree offset past the node count (found by the proptest below: it used to index
    // out of bounds instead of being rejected).
    let mut b = f.to_bytes();
    put_u32(&mut b, offsets_at + 4, f.n_nodes() as u32 + 64);
    fix_crc(&mut b);
    assert!(matches!(
        load_err(dir.path(), "offs-past.crkf", &b),
        FormatError::Inconsistent(_)
    ));
    // A NaN class label.
    let mut b = f.to_bytes();
    b[40..48].copy_from_slice(&f64::NAN.to_le_bytes());
    fix_crc(&mut b);
    assert!(matches!(
        load_err(dir.path(), "nan.crkf", &b),
        FormatError::Inconsistent(_)
    ));
}

#[test]
fn missing_file_names_the_path() {
    let err = RandomForest::load("/nonexistent/dir/model.crkf").unwrap_err();
    assert!(
        err.to_string().contains("/nonexistent/dir/model.crkf"),
        "{err}"
    );
    assert!(matches!(
        err,
        ForestError::ModelFile {
            source: FormatError::Io(_),
            ..
        }
    ));
    let err = small_forest()
        .save("/nonexistent/dir/model.crkf")
        .unwrap_err();
    assert!(
        err.to_string().contains("/nonexistent/dir/model.crkf"),
        "{err}"
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Any corruption (a changed byte, a cut, or a CRC-fixed changed byte that only the validation can
    /// catch) gives an error or a valid model, never a panic; a valid model must predict without panicking.
    #[test]
    fn corrupt_bytes_never_panic(at in 0usize..4096, val in any::<u8>(), cut in 0usize..4096, fix in any::<bool>()) {
        let f = small_forest();
        let mut b = f.to_bytes();
        let at = at % b.len();
        b[at] = val;
        if fix {
            fix_crc(&mut b);
        }
        if let Ok(g) = RandomForest::from_bytes(&b) {
            let _ = g.predict(&[500.0, 600.0, 700.0]);
            let _ = g.predict(&[]);
        }
        let cut = cut % b.len();
        prop_assert!(RandomForest::from_bytes(&b[..cut]).is_err());
    }
}
