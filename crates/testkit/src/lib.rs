//! Helpers the workspace's tests share, so each is written (and fixed) once: a free TCP port on
//! loopback, golden vectors' hex, a median, and bit-for-bit comparison of recordings. A
//! dev-dependency only. The helpers panic with a message on bad input: they are for tests.

use std::net::TcpListener;

use crackbot_recording::{Recording, Row};

/// A TCP port on 127.0.0.1 that nothing listens on now (the OS picks it; a race with another
/// process binding it first is possible but rare).
pub fn free_tcp_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .and_then(|s| s.local_addr())
        .map(|a| a.port())
        .expect("a free TCP port on 127.0.0.1")
}

/// The bytes of a hex string (two digits a byte, as golden vectors write them).
///
/// # Panics
/// On an odd length or a character that is not a hex digit.
pub fn hex(s: &str) -> Vec<u8> {
    assert!(s.len().is_multiple_of(2), "odd-length hex {s:?}");
    (0..s.len())
        .step_by(2)
        .map(|i| {
            u8::from_str_radix(&s[i..i + 2], 16)
                .unwrap_or_else(|e| panic!("bad hex {:?} at {i}: {e}", &s[i..i + 2]))
        })
        .collect()
}

/// The median of `v` (the mean of the two middle values for an even count; NaN when empty).
pub fn median(v: &[f64]) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// Every field of a row as bits (floats by their bit pattern: `-0.0` and `0.0` differ, NaN
/// equals itself).
pub fn row_bits(r: &Row) -> [u64; 9] {
    [
        r.x_mm.to_bits(),
        r.d1.to_bits(),
        r.d2.to_bits(),
        r.d3.to_bits(),
        r.p.to_bits(),
        u64::from(r.direction),
        u64::from(r.slide),
        r.label.to_bits(),
        u64::from(r.repetition),
    ]
}

/// Asserts that two recordings are the same bit for bit: rows, every field's bits, and the
/// extra columns. `what` names the comparison in the failure.
pub fn assert_bits_equal(a: &Recording, b: &Recording, what: &str) {
    assert_eq!(a.rows.len(), b.rows.len(), "{what}: row count");
    assert_eq!(a.extra, b.extra, "{what}: extra columns");
    for (i, (x, y)) in a.rows.iter().zip(&b.rows).enumerate() {
        assert_eq!(row_bits(x), row_bits(y), "{what}: row {i}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hex_reads_golden_vectors_and_refuses_bad_digits() {
        assert_eq!(hex("00ff1a"), vec![0, 255, 26]);
        assert_eq!(hex(""), Vec::<u8>::new());
        assert!(std::panic::catch_unwind(|| hex("0g")).is_err());
        assert!(std::panic::catch_unwind(|| hex("abc")).is_err());
    }

    #[test]
    fn the_median_of_odd_even_and_empty_lists() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
        assert!(median(&[]).is_nan());
    }

    #[test]
    fn a_free_port_can_be_bound() {
        let port = free_tcp_port();
        TcpListener::bind(("127.0.0.1", port)).unwrap();
    }

    #[test]
    fn recordings_differing_in_one_bit_are_told_apart() {
        let row = Row {
            x_mm: 1.0,
            d1: 2.0,
            d2: 3.0,
            d3: 4.0,
            p: 5.0,
            direction: 1,
            slide: 1,
            label: 0.0,
            repetition: 1,
        };
        let a = Recording {
            rows: vec![row],
            extra: None,
        };
        assert_bits_equal(&a, &a.clone(), "same");
        let mut b = a.clone();
        b.rows[0].label = -0.0;
        assert!(std::panic::catch_unwind(|| assert_bits_equal(&a, &b, "signed zero")).is_err());
    }
}

/// A ROS 2 arm played by Eclipse Cyclone DDS's Python binding (`scripts/dds_arm.sh`, an
/// independent DDS), running until dropped.
#[derive(Debug)]
pub struct DdsArm(std::process::Child);

impl DdsArm {
    /// Starts `scripts/dds_arm.sh` of the workspace at `root` on DDS domain `domain` with `args`,
    /// once it has said `READY`.
    ///
    /// # Panics
    /// When the script cannot start or does not say `READY` (run `bash scripts/setup.sh`).
    pub fn start(root: &std::path::Path, domain: u16, args: &[&str]) -> DdsArm {
        use std::io::BufRead;
        let mut child = std::process::Command::new("bash")
            .arg(root.join("scripts/dds_arm.sh"))
            .args(["--domain", &domain.to_string()])
            .args(args)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::inherit())
            .spawn()
            .expect("starting scripts/dds_arm.sh (Python 3 with venv: bash scripts/setup.sh)");
        let mut line = String::new();
        std::io::BufReader::new(child.stdout.take().expect("stdout"))
            .read_line(&mut line)
            .expect("READY");
        assert_eq!(line.trim(), "READY", "the DDS arm did not start");
        DdsArm(child)
    }
}

impl Drop for DdsArm {
    fn drop(&mut self) {
        // SIGTERM: the arm prints its summary (targets received, rate, p99 gap) and exits.
        let _ = std::process::Command::new("kill")
            .args(["-TERM", &self.0.id().to_string()])
            .status();
        let _ = self.0.wait();
    }
}
