//! Tests of the MAT-file reader and writer on the authors' 30 recordings, on files built by hand, and on damaged
//! files; and of the extension-based loaders.

#![expect(
    clippy::unwrap_used,
    reason = "a test stops at the first thing it did not expect, and says where"
)]

use std::io::Write;
use std::path::PathBuf;

use crackbot_recording::{
    collect_recordings, read_csv, read_mat, read_mat_from, read_recording, write_csv, write_mat,
    write_recording, Extra, Recording, RecordingError, Row,
};
use crackbot_testkit::assert_bits_equal;
use proptest::prelude::*;

/// A file of the authors' recordings (`../shared/data/tactile/...`); the test stops with one clear message
/// when the shared data is missing.
fn data(rel: &str) -> PathBuf {
    crackbot_datasets::require(crackbot_datasets::TACTILE).join(rel)
}

/// Every real file: (path relative to the tactile data folder, label, repetition).
fn real_files() -> Vec<(String, f64, u32)> {
    let mut out = Vec::new();
    for (name, label) in [
        ("nocrack", 0.0),
        ("crack", 1.0),
        ("bump", 2.0),
        ("pattern", 3.0),
    ] {
        for rep in 1..=3 {
            out.push((format!("type/crack_{name}_complete_{rep}.mat"), label, rep));
        }
    }
    for mm in [0u32, 1, 2, 5, 8, 10] {
        for rep in 1..=3 {
            out.push((
                format!("width/crack_mm{mm}_complete_{rep}.mat"),
                f64::from(mm),
                rep,
            ));
        }
    }
    out
}

/// Output of `python3 crates/recording/tests/mat_reference.py` (an independent reader using only `zlib` and
/// `struct`), run once on the files of ../shared/data/tactile (the authors' files at commit 7b17783): file, rows,
/// columns, then the left-to-right sum of each column.
const REFERENCE: &str = "\
crack_bump_complete_1.mat 33678 9 674432.2672999928 22266328.0 14739889.0 24038794.0 18365030.0 16760.0 218328.0 67356.0 33678.0
crack_bump_complete_2.mat 33640 9 681382.6934999997 22223114.0 14725171.0 23994599.0 18418244.0 16639.0 218312.0 67280.0 67280.0
crack_bump_complete_3.mat 33554 9 683653.139599991 22150948.0 14685555.0 23937685.0 18309923.0 16621.0 218626.0 67108.0 100662.0
crack_crack_complete_1.mat 33944 9 652409.6332999944 22288545.0 14759037.0 24207743.0 15478033.0 16781.0 220419.0 33944.0 33944.0
crack_crack_complete_2.mat 33648 9 650156.3293000467 22128021.0 14694301.0 24034481.0 15316375.0 16681.0 219155.0 33648.0 67296.0
crack_crack_complete_3.mat 33516 9 650639.7864999967 21989228.0 14617210.0 23965876.0 15188283.0 16700.0 217583.0 33516.0 100548.0
crack_nocrack_complete_1.mat 33400 9 641595.1391999878 21905632.0 14350390.0 23582376.0 17308538.0 16600.0 216931.0 0.0 33400.0
crack_nocrack_complete_2.mat 33087 9 589051.4430699981 21692487.0 14248815.0 23437796.0 17206080.0 16493.0 213788.0 0.0 66174.0
crack_nocrack_complete_3.mat 33176 9 598498.7465000029 21761914.0 14319190.0 23531035.0 17262407.0 16471.0 215400.0 0.0 99528.0
crack_pattern_complete_1.mat 34060 9 587802.675799993 22389692.0 14887915.0 24293993.0 22506600.0 16753.0 222210.0 102180.0 34060.0
crack_pattern_complete_2.mat 33835 9 587333.1443300074 22212836.0 14773243.0 24125644.0 22336197.0 16593.0 219537.0 101505.0 67670.0
crack_pattern_complete_3.mat 34017 9 592436.7920399744 22316032.0 14839722.0 24248981.0 22598796.0 16638.0 220932.0 102051.0 102051.0
crack_mm0_complete_1.mat 33379 9 589219.5447200034 22241327.0 14751964.0 23946346.0 17433802.0 16613.0 216912.0 0.0 33379.0
crack_mm0_complete_2.mat 33684 9 666314.9468999911 22456104.0 14902028.0 24176311.0 17625093.0 16832.0 218737.0 0.0 67368.0
crack_mm0_complete_3.mat 33474 9 676299.2160000151 22338943.0 14824418.0 24042883.0 17545853.0 16616.0 217650.0 0.0 100422.0
crack_mm10_complete_1.mat 33398 9 524740.1179799844 22212643.0 14788790.0 24000155.0 16118445.0 16719.0 216582.0 333980.0 33398.0
crack_mm10_complete_2.mat 33309 9 540647.2631299954 22155407.0 14737303.0 23929774.0 16288319.0 16688.0 216528.0 333090.0 66618.0
crack_mm10_complete_3.mat 33378 9 547489.3281799793 22180878.0 14761664.0 23993655.0 16343809.0 16708.0 217080.0 333780.0 100134.0
crack_mm1_complete_1.mat 33296 9 632438.992800006 22199944.0 14762261.0 23899557.0 16451906.0 16576.0 216458.0 33296.0 33296.0
crack_mm1_complete_2.mat 33380 9 641010.359100036 22253734.0 14794706.0 23957401.0 16557236.0 16666.0 216882.0 33380.0 66760.0
crack_mm1_complete_3.mat 33362 9 651144.753199986 22235719.0 14792937.0 23961401.0 16585446.0 16607.0 216911.0 33362.0 100086.0
crack_mm2_complete_1.mat 33449 9 715326.4500999787 22281042.0 14620751.0 23835029.0 16327114.0 16658.0 217756.0 66898.0 33449.0
crack_mm2_complete_2.mat 33364 9 698476.4235000147 22222754.0 14661050.0 23908241.0 16471950.0 16504.0 217379.0 66728.0 66728.0
crack_mm2_complete_3.mat 33154 9 700382.8453000062 22075884.0 14584714.0 23775527.0 16406445.0 16397.0 215082.0 66308.0 99462.0
crack_mm5_complete_1.mat 33300 9 576562.0089199964 22169564.0 14761381.0 23931713.0 15219561.0 16592.0 215895.0 166500.0 33300.0
crack_mm5_complete_2.mat 33394 9 589841.3201499956 22250016.0 14804427.0 24086244.0 15320076.0 16641.0 217560.0 166970.0 66788.0
crack_mm5_complete_3.mat 33107 9 569557.827239978 22035412.0 14673088.0 23891123.0 15124718.0 16464.0 215489.0 165535.0 99321.0
crack_mm8_complete_1.mat 33367 9 560921.4601000313 22173810.0 14772381.0 24021300.0 15825563.0 16618.0 217079.0 266936.0 33367.0
crack_mm8_complete_2.mat 33617 9 578683.0402900113 22331467.0 14872248.0 24190690.0 16049210.0 16721.0 218522.0 268936.0 67234.0
crack_mm8_complete_3.mat 33428 9 544017.0237300098 22247564.0 14811068.0 24088854.0 15842151.0 16534.0 217044.0 267424.0 100284.0
";

/// The nine values of a row, in file order.
fn values(r: &Row) -> [f64; 9] {
    [
        r.x_mm,
        r.d1,
        r.d2,
        r.d3,
        r.p,
        f64::from(r.direction),
        f64::from(r.slide),
        r.label,
        f64::from(r.repetition),
    ]
}

#[test]
fn every_authors_file_loads_with_its_label_repetition_and_slides() {
    let mut with_trailing_13 = 0;
    for (rel, label, repetition) in real_files() {
        let rec = read_mat(&data(&rel)).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            (33_000..=34_100).contains(&rec.len()),
            "{rel}: {} rows",
            rec.len()
        );
        assert!(rec.extra.is_none());
        assert_eq!(rec.label(), Some(label), "{rel}");
        assert_eq!(rec.repetition(), Some(repetition), "{rel}");

        let slides = rec.slides();
        let numbers: Vec<u32> = slides.iter().map(|s| rec.rows[s.start].slide).collect();
        let expected: Vec<u32> = (1..=12).collect();
        match numbers.len() {
            12 => assert_eq!(numbers, expected, "{rel}"),
            13 => {
                assert_eq!(numbers[..12], expected[..], "{rel}");
                assert_eq!(numbers[12], 13, "{rel}");
                assert_eq!(
                    slides[12].len(),
                    1,
                    "{rel}: trailing slide 13 is one sample"
                );
                assert_eq!(slides[12].end, rec.len(), "{rel}");
                with_trailing_13 += 1;
            }
            n => panic!("{rel}: {n} slide ranges: {numbers:?}"),
        }
        // The ranges tile the recording.
        assert_eq!(slides[0].start, 0);
        for w in slides.windows(2) {
            assert_eq!(w[0].end, w[1].start);
        }
        // Real slides are a few thousand samples each.
        for s in &slides[..12] {
            assert!(
                (1_500..4_000).contains(&s.len()),
                "{rel}: slide of {} rows",
                s.len()
            );
        }

        for (i, r) in rec.rows.iter().enumerate() {
            let ctx = || format!("{rel} row {i}: {r:?}");
            assert!((7.0..30.0).contains(&r.x_mm), "{}", ctx());
            assert!((633.0..=688.0).contains(&r.d1), "{}", ctx());
            assert!((410.0..=472.0).contains(&r.d2), "{}", ctx());
            assert!((676.0..=767.0).contains(&r.d3), "{}", ctx());
            assert!((242.0..=787.0).contains(&r.p), "{}", ctx());
            for v in r.channels() {
                assert_eq!(v.fract(), 0.0, "raw ADC counts: {}", ctx());
            }
        }
        // Each slide is one stroke there and back: direction 0 (right to left), then 1, one change.
        for s in &slides[..12] {
            let rows = &rec.rows[s.clone()];
            let changes = rows
                .windows(2)
                .filter(|w| w[0].direction != w[1].direction)
                .count();
            assert_eq!((rows[0].direction, changes), (0, 1), "{rel}");
        }
    }
    // The data README says 22 files end with a slide-13 sample; of the 30 distributed here, 14 do
    // (checked with mat_reference.py too).
    assert_eq!(with_trailing_13, 14);
}

#[test]
fn column_sums_match_the_independent_python_reader() {
    let mut checked = 0;
    for line in REFERENCE.lines() {
        let mut fields = line.split_whitespace();
        let name = fields.next().unwrap();
        let rows: usize = fields.next().unwrap().parse().unwrap();
        let cols: usize = fields.next().unwrap().parse().unwrap();
        let sums: Vec<f64> = fields.map(|f| f.parse().unwrap()).collect();
        assert_eq!(cols, 9);
        let sub = if name.contains("_mm") {
            "width"
        } else {
            "type"
        };
        let rec = read_mat(&data(&format!("{sub}/{name}"))).unwrap();
        assert_eq!(rec.len(), rows, "{name}");
        for (c, expected) in sums.iter().enumerate() {
            // Left to right, as the Python reference does: the sums must agree bit for bit.
            let sum = rec.rows.iter().fold(0.0, |acc, r| acc + values(r)[c]);
            assert_eq!(
                sum.to_bits(),
                expected.to_bits(),
                "{name} column {}: {sum} vs {expected}",
                c + 1
            );
        }
        checked += 1;
    }
    assert_eq!(checked, 30);
}

#[test]
fn first_and_last_rows_match_the_independent_python_reader() {
    // `python3 crates/recording/tests/mat_reference.py --rows FILE`.
    let cases = [
        (
            "type/crack_bump_complete_1.mat",
            [12.0468, 666.0, 443.0, 710.0, 520.0, 0.0, 1.0, 2.0, 1.0],
            [12.0791, 652.0, 437.0, 721.0, 525.0, 0.0, 13.0, 2.0, 1.0],
        ),
        (
            "width/crack_mm10_complete_3.mat",
            [8.46171, 665.0, 444.0, 721.0, 495.0, 0.0, 1.0, 10.0, 3.0],
            [8.48687, 648.0, 444.0, 728.0, 512.0, 0.0, 13.0, 10.0, 3.0],
        ),
    ];
    for (rel, first, last) in cases {
        let rec = read_mat(&data(rel)).unwrap();
        assert_eq!(values(&rec.rows[0]), first, "{rel}");
        assert_eq!(values(rec.rows.last().unwrap()), last, "{rel}");
    }
}

#[test]
fn mat_round_trips_through_csv_and_mat_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let original = read_mat(&data("width/crack_mm5_complete_2.mat")).unwrap();
    let csv = dir.path().join("a.csv");
    write_recording(&csv, &original).unwrap();
    assert_bits_equal(&read_csv(&csv).unwrap(), &original, "mat");
    let mat = dir.path().join("b.MAT");
    write_recording(&mat, &original).unwrap();
    assert_bits_equal(&read_recording(&mat).unwrap(), &original, "mat");
    // Compressed like the authors' files.
    let size = std::fs::metadata(&mat).unwrap().len();
    assert!(size < 400_000, "{size} bytes");
    // An empty recording round-trips too.
    let empty = dir.path().join("empty.mat");
    write_mat(&empty, &Recording::default()).unwrap();
    assert_eq!(read_mat(&empty).unwrap(), Recording::default());
}

#[test]
fn writing_a_mat_refuses_extra_columns_and_invalid_rows() {
    let dir = tempfile::tempdir().unwrap();
    let mut rec = small_recording(3);
    rec.extra = Some(vec![Extra::default(); 3]);
    let path = dir.path().join("extra.mat");
    let msg = write_mat(&path, &rec).unwrap_err().to_string();
    assert!(
        msg.contains("extra.mat") && msg.contains("extra columns"),
        "{msg}"
    );
    assert!(!path.exists());
    rec.extra = None;
    rec.rows[1].d2 = f64::NAN;
    let msg = write_mat(&path, &rec).unwrap_err().to_string();
    assert!(
        msg.contains("extra.mat") && msg.contains("non-finite"),
        "{msg}"
    );
    assert!(!path.exists());
}

#[test]
fn extensions_pick_the_reader_and_writer() {
    let dir = tempfile::tempdir().unwrap();
    let rec = small_recording(5);
    let upper = dir.path().join("r.CSV");
    write_recording(&upper, &rec).unwrap();
    assert_bits_equal(&read_recording(&upper).unwrap(), &rec, "mat");
    for name in ["r.txt", "r", "r.mat.gz"] {
        let path = dir.path().join(name);
        std::fs::write(&path, "x").unwrap();
        let msg = read_recording(&path).unwrap_err().to_string();
        assert!(
            msg.contains(&path.display().to_string()) && msg.contains("unsupported extension"),
            "{msg}"
        );
        let err = write_recording(&dir.path().join(format!("out-{name}")), &rec).unwrap_err();
        assert!(
            matches!(err, RecordingError::UnsupportedExtension { .. }),
            "{err}"
        );
    }
    let msg = read_recording(&dir.path().join("r.txt"))
        .unwrap_err()
        .to_string();
    assert!(msg.contains("`.txt`"), "{msg}");
}

#[test]
fn collect_recordings_reads_files_and_folders_in_name_order() {
    let type_dir = data("type");
    let one = data("width/crack_mm1_complete_2.mat");
    let all = collect_recordings(&[one.clone(), type_dir]).unwrap();
    assert_eq!(all.len(), 13);
    assert_eq!(all[0].0, one);
    let names: Vec<String> = all[1..]
        .iter()
        .map(|(p, _)| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    let mut sorted = names.clone();
    sorted.sort();
    assert_eq!(names, sorted);
    assert_eq!(names[0], "crack_bump_complete_1.mat");
    assert_eq!(all[1].1.label(), Some(2.0));

    // A folder mixing forms and other files; sub-folders are not searched.
    let dir = tempfile::tempdir().unwrap();
    write_csv(&dir.path().join("b.csv"), &small_recording(2)).unwrap();
    write_mat(&dir.path().join("a.Mat"), &small_recording(3)).unwrap();
    std::fs::write(dir.path().join("notes.txt"), "not a recording").unwrap();
    std::fs::create_dir(dir.path().join("sub")).unwrap();
    write_csv(&dir.path().join("sub/c.csv"), &small_recording(4)).unwrap();
    let got = collect_recordings(&[dir.path().to_path_buf()]).unwrap();
    let lens: Vec<usize> = got.iter().map(|(_, r)| r.len()).collect();
    assert_eq!(lens, [3, 2]);

    // Errors name the path.
    let missing = dir.path().join("nope");
    let msg = collect_recordings(std::slice::from_ref(&missing))
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains(&missing.display().to_string()) && msg.contains("no such file"),
        "{msg}"
    );
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    std::fs::write(empty.join("readme.md"), "").unwrap();
    let msg = collect_recordings(std::slice::from_ref(&empty))
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains(&empty.display().to_string()) && msg.contains("no recording"),
        "{msg}"
    );
    // A bad file inside a folder is named.
    std::fs::write(dir.path().join("c.mat"), "x_mm,d1\n").unwrap();
    let msg = collect_recordings(&[dir.path().to_path_buf()])
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("c.mat") && msg.contains("not a MAT-file"),
        "{msg}"
    );
}

#[test]
fn slides_label_and_repetition_of_small_recordings() {
    assert!(Recording::default().slides().is_empty());
    assert_eq!(Recording::default().label(), None);
    assert_eq!(Recording::default().repetition(), None);
    let mut rec = small_recording(7);
    for (i, s) in [1, 1, 2, 2, 2, 1, 3].iter().enumerate() {
        rec.rows[i].slide = *s;
    }
    assert_eq!(rec.slides(), vec![0..2, 2..5, 5..6, 6..7]);
    assert_eq!(rec.label(), Some(2.0));
    assert_eq!(rec.repetition(), Some(3));
    rec.rows[4].label = 2.5;
    rec.rows[6].repetition = 4;
    assert_eq!(rec.label(), None);
    assert_eq!(rec.repetition(), None);
}

// ---- Files built by hand ----------------------------------------------------------------------------------------

fn small_recording(n: u32) -> Recording {
    Recording {
        rows: (0..n)
            .map(|i| Row {
                x_mm: 7.8 + f64::from(i) * 0.013,
                d1: 660.0,
                d2: 441.0 + f64::from(i % 3),
                d3: 720.0,
                p: 250.0 + f64::from(i),
                direction: (i / 4 % 2) as u8,
                slide: 1 + i / 4,
                label: 2.0,
                repetition: 3,
            })
            .collect(),
        extra: None,
    }
}

/// A level-5 MAT-file written by hand, independently of the crate's writer.
struct Mat {
    big_endian: bool,
}

impl Mat {
    fn u16(&self, v: u16) -> [u8; 2] {
        if self.big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    }

    fn u32(&self, v: u32) -> [u8; 4] {
        if self.big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    }

    fn header(&self) -> Vec<u8> {
        let mut h = b"MATLAB 5.0 MAT-file, written by hand for a test".to_vec();
        h.resize(116, b' ');
        h.extend_from_slice(&[0; 8]);
        h.extend_from_slice(&self.u16(0x0100));
        h.extend_from_slice(if self.big_endian { b"MI" } else { b"IM" });
        h
    }

    fn element(&self, ty: u32, data: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        out.extend_from_slice(&self.u32(ty));
        out.extend_from_slice(&self.u32(data.len() as u32));
        out.extend_from_slice(data);
        while out.len() % 8 != 0 {
            out.push(0);
        }
        out
    }

    /// A miMATRIX element: class, dimensions, name (as a small element when it fits), real part.
    fn matrix(&self, class: u32, dims: &[i32], name: &str, data_type: u32, data: &[u8]) -> Vec<u8> {
        let mut body = Vec::new();
        let flags: Vec<u8> = [self.u32(class), self.u32(0)].concat();
        body.extend(self.element(6, &flags));
        let dims: Vec<u8> = dims.iter().flat_map(|&d| self.u32(d as u32)).collect();
        body.extend(self.element(5, &dims));
        if name.len() <= 4 {
            body.extend_from_slice(&self.u32(((name.len() as u32) << 16) | 1));
            let mut n = name.as_bytes().to_vec();
            n.resize(4, 0);
            body.extend(n);
        } else {
            body.extend(self.element(1, name.as_bytes()));
        }
        body.extend(self.element(data_type, data));
        self.element(14, &body)
    }

    fn doubles(&self, values: &[f64]) -> Vec<u8> {
        values
            .iter()
            .flat_map(|v| {
                if self.big_endian {
                    v.to_be_bytes()
                } else {
                    v.to_le_bytes()
                }
            })
            .collect()
    }

    fn compressed(&self, element: &[u8]) -> Vec<u8> {
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
        z.write_all(element).unwrap();
        let data = z.finish().unwrap();
        let mut out = Vec::new();
        out.extend_from_slice(&self.u32(15));
        out.extend_from_slice(&self.u32(data.len() as u32));
        out.extend(data);
        out
    }

    fn file(&self, elements: &[Vec<u8>]) -> Vec<u8> {
        let mut out = self.header();
        for e in elements {
            out.extend_from_slice(e);
        }
        out
    }
}

const LE: Mat = Mat { big_endian: false };

/// Column-major values of the first `n` rows of a real file, with `cols` of its columns.
fn real_values(n: usize, cols: usize) -> Vec<f64> {
    static REC: std::sync::OnceLock<Recording> = std::sync::OnceLock::new();
    let rec = REC.get_or_init(|| read_mat(&data("type/crack_crack_complete_2.mat")).unwrap());
    (0..cols)
        .flat_map(|c| rec.rows[..n].iter().map(move |r| values(r)[c]))
        .collect()
}

fn write_temp(name: &str, bytes: &[u8]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).unwrap();
    (dir, path)
}

/// Reads `bytes` as a MAT-file named `name`, expecting an error whose message names the file and contains every
/// one of `facts`.
fn mat_err(name: &str, bytes: &[u8], facts: &[&str]) -> RecordingError {
    let (_dir, path) = write_temp(name, bytes);
    let err = read_mat(&path).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains(&path.display().to_string()),
        "does not name the file: {msg}"
    );
    for fact in facts {
        assert!(msg.contains(fact), "{name}: `{fact}` missing from: {msg}");
    }
    err
}

fn real_bytes() -> Vec<u8> {
    std::fs::read(data("type/crack_crack_complete_1.mat")).unwrap()
}

#[test]
fn hand_written_files_read_uncompressed_compressed_and_big_endian() {
    let values = real_values(50, 9);
    let expected = read_mat(&data("type/crack_crack_complete_2.mat")).unwrap();
    let expected = Recording {
        rows: expected.rows[..50].to_vec(),
        extra: None,
    };
    for mat in [LE, Mat { big_endian: true }] {
        let m = mat.matrix(6, &[50, 9], "synchronized_data", 9, &mat.doubles(&values));
        // Another variable before it, uncompressed, with a short name (small element).
        let other = mat.matrix(6, &[1, 1], "t", 9, &mat.doubles(&[1.0]));
        for bytes in [
            mat.file(&[other.clone(), m.clone()]),
            mat.file(&[mat.compressed(&other), mat.compressed(&m)]),
        ] {
            let rec = read_mat_from(&bytes, "hand.mat").unwrap();
            assert_bits_equal(&rec, &expected, "mat");
        }
    }
    // Integer storage of a double matrix (as MATLAB does when the values allow it), and class single.
    let ints: Vec<f64> = (0..18).map(|i| f64::from(i % 2)).collect();
    let as_u8: Vec<u8> = ints.iter().map(|&v| v as u8).collect();
    let rec = read_mat_from(
        &LE.file(&[LE.matrix(6, &[2, 9], "synchronized_data", 2, &as_u8)]),
        "u8.mat",
    )
    .unwrap();
    assert_eq!(rec.rows[0].direction, 0);
    assert_eq!(rec.rows[1].slide, 1);
    let singles: Vec<u8> = ints
        .iter()
        .flat_map(|&v| (v as f32).to_le_bytes())
        .collect();
    let rec2 = read_mat_from(
        &LE.file(&[LE.matrix(7, &[2, 9], "synchronized_data", 7, &singles)]),
        "s.mat",
    )
    .unwrap();
    assert_eq!(rec, rec2);
}

#[test]
fn not_a_mat_file_is_refused() {
    let csv = "x_mm,d1,d2,d3,p,direction,slide,label,repetition\n7.8,660,440,720,250,1,1,0,1\n";
    mat_err(
        "renamed.mat",
        csv.as_bytes(),
        &["not a MAT-file", "MATLAB", "x_mm,d1"],
    );
    let random: Vec<u8> = (0..4096u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .collect();
    mat_err("random.mat", &random, &["not a MAT-file"]);
    mat_err("empty.mat", b"", &["not a MAT-file", "empty"]);
    // A MATLAB text but a bad endian indicator.
    let mut bytes = real_bytes();
    bytes[126..128].copy_from_slice(b"XX");
    mat_err(
        "endian.mat",
        &bytes,
        &["not a MAT-file", "endian indicator"],
    );
    let mut bytes = real_bytes();
    bytes[124] = 7;
    mat_err("version.mat", &bytes, &["not a MAT-file", "version"]);
}

#[test]
fn mat_v73_hdf5_is_refused_by_name() {
    let mut h = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Sep  9 10:54:32 2019 HDF5 schema 1.00 .".to_vec();
    h.resize(116, b' ');
    h.extend_from_slice(&[0; 8]);
    h.extend_from_slice(&0x0200u16.to_le_bytes());
    h.extend_from_slice(b"IM");
    h.resize(512, 0);
    h.extend_from_slice(b"\x89HDF\r\n\x1a\n");
    h.resize(2048, 0);
    mat_err("v73.mat", &h, &["7.3", "HDF5", "not supported"]);
    // The version field alone is enough.
    let mut bytes = real_bytes();
    bytes[124..126].copy_from_slice(&0x0200u16.to_le_bytes());
    mat_err("v73b.mat", &bytes, &["7.3"]);
}

#[test]
fn truncated_files_say_truncated() {
    let bytes = real_bytes();
    // In the header, in the tag of the compressed element, and in its data.
    for cut in [3, 64, 127, 131, 2_000, bytes.len() / 2, bytes.len() - 1] {
        let err = mat_err(&format!("cut{cut}.mat"), &bytes[..cut], &["truncated"]);
        assert!(
            matches!(err, RecordingError::MatTruncated { .. }),
            "{cut}: {err}"
        );
    }
    // The element fits the file but its zlib stream ends early (the size field rewritten to match the cut).
    for keep in [100, 50_000, bytes.len() - 136 - 2] {
        let mut short = bytes[..136 + keep].to_vec();
        short[132..136].copy_from_slice(&(keep as u32).to_le_bytes());
        mat_err(
            &format!("zcut{keep}.mat"),
            &short,
            &["truncated", "zlib stream", "ends early", "byte 128"],
        );
    }
    // Header only: a MAT-file without variables.
    mat_err(
        "header.mat",
        &bytes[..128],
        &["no variable `synchronized_data`", "variables found: none"],
    );
}

#[test]
fn corrupt_zlib_data_is_reported() {
    let bytes = real_bytes();
    for at in [138, 1_000, 80_000, bytes.len() - 2] {
        let mut bad = bytes.clone();
        for b in &mut bad[at..at + 2] {
            *b ^= 0x5A;
        }
        let err = mat_err(&format!("flip{at}.mat"), &bad, &["corrupt"]);
        assert!(
            matches!(err, RecordingError::MatCorrupt { .. }),
            "{at}: {err}"
        );
    }
}

#[test]
fn wrong_variable_name_lists_the_names_found() {
    let v = real_values(10, 9);
    let bytes = LE.file(&[
        LE.matrix(6, &[10, 9], "sync_data", 9, &LE.doubles(&v)),
        LE.matrix(6, &[1, 1], "t", 9, &LE.doubles(&[0.5])),
    ]);
    mat_err(
        "names.mat",
        &bytes,
        &["no variable `synchronized_data`", "`sync_data`, `t`"],
    );
}

#[test]
fn wrong_shape_class_and_values_are_reported() {
    let v8 = real_values(10, 8);
    let bytes = LE.file(&[LE.compressed(&LE.matrix(
        6,
        &[10, 8],
        "synchronized_data",
        9,
        &LE.doubles(&v8),
    ))]);
    mat_err("eight.mat", &bytes, &["shape 10×8", "expected N×9"]);
    let v = real_values(10, 9);
    let bytes = LE.file(&[LE.matrix(6, &[10, 9, 1, 1], "synchronized_data", 9, &LE.doubles(&v))]);
    mat_err("fourd.mat", &bytes, &["shape 10×9×1×1"]);
    let bytes = LE.file(&[LE.matrix(
        4,
        &[1, 9],
        "synchronized_data",
        4,
        &[
            0x41, 0, 0x42, 0, 0x43, 0, 0x44, 0, 0x45, 0, 0x46, 0, 0x47, 0, 0x48, 0, 0x49, 0,
        ],
    )]);
    mat_err(
        "char.mat",
        &bytes,
        &["class char", "expected a real double"],
    );
    let bytes = LE.file(&[LE.matrix(10, &[1, 9], "synchronized_data", 3, &[0; 18])]);
    mat_err("int16.mat", &bytes, &["class int16"]);
    // The data does not fill the shape.
    let bytes = LE.file(&[LE.matrix(6, &[11, 9], "synchronized_data", 9, &LE.doubles(&v))]);
    mat_err(
        "short.mat",
        &bytes,
        &["corrupt", "holds 90 values", "11×9 needs 99"],
    );

    // Row 4 (1-based), column 3 (d2) NaN; row 7 direction 2; row 2 slide -1; row 9 repetition 1.5.
    let cases: [(usize, usize, f64, &[&str]); 5] = [
        (
            3,
            2,
            f64::NAN,
            &["row 4, column 3 (`d2`)", "non-finite value NaN"],
        ),
        (
            0,
            0,
            f64::INFINITY,
            &["row 1, column 1 (`x_mm`)", "non-finite value inf"],
        ),
        (
            6,
            5,
            2.0,
            &[
                "row 7, column 6 (`direction`)",
                "direction must be 0 or 1, found 2",
            ],
        ),
        (
            1,
            6,
            -1.0,
            &[
                "row 2, column 7 (`slide`)",
                "expected an integer",
                "found -1",
            ],
        ),
        (8, 8, 1.5, &["row 9, column 9 (`repetition`)", "found 1.5"]),
    ];
    for (row, col, value, facts) in cases {
        let mut v = real_values(10, 9);
        v[col * 10 + row] = value;
        let bytes = LE.file(&[LE.compressed(&LE.matrix(
            6,
            &[10, 9],
            "synchronized_data",
            9,
            &LE.doubles(&v),
        ))]);
        mat_err(&format!("value{row}_{col}.mat"), &bytes, facts);
    }
}

#[test]
fn malformed_elements_are_corrupt_not_panics() {
    let v = real_values(4, 9);
    let good = LE.matrix(6, &[4, 9], "synchronized_data", 9, &LE.doubles(&v));
    // A sub-element size running past the matrix.
    let mut bad = good.clone();
    bad[8 + 4..8 + 8].copy_from_slice(&1_000_000u32.to_le_bytes());
    mat_err("flags.mat", &LE.file(&[bad]), &["corrupt", "array flags"]);
    // The matrix element declaring gigabytes: truncated, and nothing of that size is allocated.
    let mut bad = good.clone();
    bad[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
    mat_err(
        "huge.mat",
        &LE.file(&[bad.clone()]),
        &["truncated", "4294967295"],
    );
    // The same inside a compressed element: the inflated element is inconsistent.
    mat_err(
        "hugez.mat",
        &LE.file(&[LE.compressed(&bad)]),
        &["corrupt", "4294967295"],
    );
    // Negative dimension.
    let bad = LE.matrix(6, &[-4, 9], "synchronized_data", 9, &LE.doubles(&v));
    mat_err(
        "neg.mat",
        &LE.file(&[bad]),
        &["corrupt", "negative dimension -4"],
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Arbitrary damage to a small compressed file and to an uncompressed one never panics: it reads, or fails
    /// with an error naming the file.
    #[test]
    fn damaged_files_never_panic(
        flips in proptest::collection::vec((0usize..4096, any::<u8>()), 0..6),
        cut in 0usize..4096,
        compressed in any::<bool>(),
    ) {
        let v = real_values(20, 9);
        let m = LE.matrix(6, &[20, 9], "synchronized_data", 9, &LE.doubles(&v));
        let mut bytes = LE.file(&[if compressed { LE.compressed(&m) } else { m }]);
        for (at, x) in flips {
            let n = bytes.len();
            bytes[at % n] ^= x;
        }
        bytes.truncate(cut.max(1));
        if let Err(e) = read_mat_from(&bytes, "fuzz.mat") {
            prop_assert!(e.to_string().contains("fuzz.mat"));
        }
    }
}
