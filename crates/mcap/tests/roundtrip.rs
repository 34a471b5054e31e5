//! A log written with every channel reads back message for message; files cut short, not MCAP
//! or with a message that does not decode are errors that say which.

use crackbot_mcap::{
    read_log, JsonTopic, Label, LogError, LogLevel, LogWriter, Payload, Polyline, SceneLine,
};

const ORIGIN_NS: u64 = 1_700_000_000_000_000_000;

fn png() -> Vec<u8> {
    // A 1×1 PNG (any bytes would do: the log does not decode the image).
    vec![0x89, b'P', b'N', b'G', 13, 10, 26, 10, 1, 2, 3]
}

fn write_all(path: &std::path::Path) {
    let log = LogWriter::create(path, ORIGIN_NS).expect("the log");
    log.frame(0.5, &png());
    log.detections(
        0.5,
        &[Polyline {
            points: vec![[1.0, 2.0], [30.0, 2.0], [30.0, 9.0]],
            closed: true,
            rgba: [1.0, 0.0, 0.0, 1.0],
        }],
        &[Label {
            at: [1.0, 2.0],
            text: "crack 0.91".into(),
        }],
    );
    log.scene(
        0.6,
        "plan",
        &[SceneLine {
            points_mm: vec![[0.0, 0.0, 0.0], [10.0, 5.0, 0.0]],
            thickness_mm: 1.0,
            rgba: [0.0, 1.0, 0.0, 1.0],
        }],
    );
    for i in 0..1000 {
        let t = 1.0 + f64::from(i) / 400.0;
        log.json(
            JsonTopic::Tactile,
            t,
            &serde_json::json!({"t_s": t, "d1": i, "d2": 2, "d3": 3, "p": 4, "slide": 1, "along_mm": null}),
        )
        .expect("a sample");
        if i % 4 == 0 {
            log.finger_at(t, [f64::from(i) * 0.01, 5.0, 0.0]);
        }
    }
    log.log(3.6, LogLevel::Info, "mission finished");
    log.json(JsonTopic::Report, 3.7, &serde_json::json!({"cracks": []}))
        .expect("the report");
    log.finish().expect("closing the log");
}

#[test]
fn every_message_reads_back_with_its_time() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mission.mcap");
    write_all(&path);
    let log = read_log(&path).unwrap();
    let tactile: Vec<_> = log.json(JsonTopic::Tactile).collect();
    assert_eq!(tactile.len(), 1000);
    assert_eq!(tactile[0].0, ORIGIN_NS + 1_000_000_000);
    assert!(tactile.windows(2).all(|w| w[0].0 < w[1].0));
    assert_eq!(tactile[999].1["d1"], 999);
    assert_eq!(log.frame(), Some(("png", png().as_slice())));
    let count = |topic: &str| log.messages.iter().filter(|m| m.topic == topic).count();
    assert_eq!(count("/tf"), 250);
    assert_eq!(count("/camera/detections"), 1);
    assert_eq!(count("/plan"), 1);
    assert!(log.messages.iter().any(|m| m.payload
        == Payload::Log {
            level: 2,
            message: "mission finished".into()
        }));
    assert_eq!(log.json(JsonTopic::Report).count(), 1);
    assert_eq!(log.start_ns(), Some(ORIGIN_NS + 500_000_000));
}

#[test]
fn a_file_cut_short_is_an_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mission.mcap");
    write_all(&path);
    let whole = std::fs::read(&path).unwrap();
    for keep in [
        0,
        8,
        whole.len() / 3,
        whole.len() / 2,
        whole.len() - 9,
        whole.len() - 1,
    ] {
        let cut = dir.path().join(format!("cut-{keep}.mcap"));
        std::fs::write(&cut, &whole[..keep]).unwrap();
        match read_log(&cut) {
            Err(LogError::Corrupt { path, .. }) => assert_eq!(path, cut),
            other => panic!("{keep} bytes: {other:?}"),
        }
    }
}

#[test]
fn a_file_that_is_not_mcap_or_not_there_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let text = dir.path().join("report.json");
    std::fs::write(&text, b"{\"cracks\": []}").unwrap();
    assert!(matches!(read_log(&text), Err(LogError::Corrupt { .. })));
    let missing = dir.path().join("none.mcap");
    assert!(matches!(read_log(&missing), Err(LogError::Io { .. })));
}

#[test]
fn flipped_bytes_are_an_error_or_read_back_never_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mission.mcap");
    write_all(&path);
    let whole = std::fs::read(&path).unwrap();
    let mut seen_error = false;
    for i in (0..whole.len()).step_by(97) {
        let mut bad = whole.clone();
        bad[i] ^= 0x5a;
        let p = dir.path().join("bad.mcap");
        std::fs::write(&p, &bad).unwrap();
        seen_error |= read_log(&p).is_err();
    }
    assert!(seen_error);
}

#[test]
fn a_second_log_replaces_the_first() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mission.mcap");
    write_all(&path);
    let log = LogWriter::create(&path, ORIGIN_NS).unwrap();
    log.log(0.0, LogLevel::Warning, "again");
    log.finish().unwrap();
    let read = read_log(&path).unwrap();
    assert_eq!(read.messages.len(), 1);
}
