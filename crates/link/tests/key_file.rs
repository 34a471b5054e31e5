//! The key file: hex text, owner-only permissions, never printed.

mod common;

use common::*;
use crackbot_link::{Key, KeyFileError, LinkConfig, LinkEndpoint, LinkError, Security};

const HEX: &str = "00112233445566778899aabbccddeeff00112233445566778899aabbccddeeff";

fn write(dir: &Dir, name: &str, text: &str, mode: u32) -> std::path::PathBuf {
    let p = dir.path(name);
    std::fs::write(&p, text).expect("write");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&p, std::fs::Permissions::from_mode(mode)).expect("chmod");
    }
    #[cfg(not(unix))]
    let _ = mode;
    p
}

#[test]
fn a_private_hex_key_file_is_read() {
    let dir = Dir::new();
    let k = Key::from_file(write(&dir, "k", &format!("{HEX}\n"), 0o600)).expect("key");
    assert_eq!(k.len(), 32);
    let k = Key::from_file(write(
        &dir,
        "k2",
        &format!("  {}\r\n", HEX.repeat(2)),
        0o400,
    ))
    .expect("64-byte key");
    assert_eq!(k.len(), 64);
    let upper = Key::from_file(write(&dir, "k3", &HEX.to_uppercase(), 0o600)).expect("upper");
    assert_eq!(upper.len(), 32);
}

#[cfg(unix)]
#[test]
fn a_key_file_others_may_read_is_refused() {
    let dir = Dir::new();
    for mode in [
        0o644,
        0o640,
        0o604,
        0o620,
        0o602,
        0o660,
        0o666,
        0o700 | 0o004,
    ] {
        let p = write(&dir, &format!("k{mode:o}"), HEX, mode);
        match Key::from_file(&p) {
            Err(KeyFileError::Permissions { mode: m, .. }) => assert_eq!(m, mode),
            other => panic!("mode {mode:o}: {other:?}"),
        }
    }
    // A directory is not a key file.
    assert!(matches!(
        Key::from_file(dir.0.path()),
        Err(KeyFileError::NotAFile { .. } | KeyFileError::Permissions { .. })
    ));
}

#[test]
fn malformed_short_and_zero_keys_are_refused() {
    let dir = Dir::new();
    let cases = [
        ("empty", String::new()),
        ("whitespace", "  \n".into()),
        ("short", HEX[..62].into()),
        ("odd", HEX[..63].into()),
        ("not hex", HEX.replace('a', "g")),
        ("two lines", format!("{}\n{}", &HEX[..32], &HEX[32..])),
        ("too long", HEX.repeat(3)),
        ("all zero", "0".repeat(64)),
        ("raw bytes", "k".repeat(32)),
    ];
    for (name, text) in cases {
        let p = write(&dir, name, &text, 0o600);
        let err = Key::from_file(&p).expect_err(name);
        let shown = err.to_string();
        assert!(
            !shown.contains(&HEX[..16]),
            "{name}: error shows key material: {shown}"
        );
    }
    assert!(matches!(
        Key::from_file(dir.path("absent")),
        Err(KeyFileError::Io { .. })
    ));
}

#[test]
fn the_key_is_never_printed() {
    let dir = Dir::new();
    let k = Key::from_file(write(&dir, "k", HEX, 0o600)).expect("key");
    let cfg = LinkConfig::host(Security::Signed(k.clone()), dir.epoch("e"));
    for shown in [format!("{k:?}"), format!("{k:#?}"), format!("{cfg:?}")] {
        assert!(!shown.contains("0011223344"), "{shown}");
        assert!(!shown.contains("[0, 17, 34"), "{shown}");
        assert!(shown.contains("redacted"), "{shown}");
    }
    let ep = LinkEndpoint::bind(
        LOCALHOST.parse().expect("addr"),
        socket().local_addr().expect("addr"),
        cfg,
    )
    .expect("endpoint");
    let shown = format!("{ep:?}");
    assert!(
        !shown.contains("0011223344") && !shown.contains("[0, 17, 34"),
        "{shown}"
    );
}

#[cfg(unix)]
#[test]
fn a_new_key_file_is_private_and_reads_back() {
    use std::os::unix::fs::PermissionsExt;
    let dir = Dir::new();
    let p = dir.path("new.key");
    let k = Key::write_new_file(&p).expect("new key");
    let mode = std::fs::metadata(&p).expect("meta").permissions().mode() & 0o777;
    assert_eq!(mode, 0o600);
    assert_eq!(Key::from_file(&p).expect("reads back").len(), k.len());
    // Never overwrites.
    assert!(Key::write_new_file(&p).is_err());
}

/// A key file error surfaces as `LinkError::KeyFile` through `?` in an application.
#[test]
fn key_file_errors_convert_to_link_errors() {
    fn open(dir: &Dir) -> Result<Key, LinkError> {
        Ok(Key::from_file(dir.path("absent"))?)
    }
    let e = open(&Dir::new()).expect_err("absent");
    assert!(matches!(e, LinkError::KeyFile(_)));
    assert!(e.to_string().contains("absent"));
}
