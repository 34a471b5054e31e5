//! The board image on an emulated chip: `firmware/image.sh` builds the Arduino Mega 2560 image
//! (firmware/mega2560), `firmware/emulate.sh` runs it on simavr's ATmega2560 with the ADC fed
//! from a trace and USART0 on a pseudo-terminal, and the host reads that terminal exactly as a
//! real board's port: with `crackbot record`, the acquisition, or plain reads.
//!
//! Every sample is checked against the trace the ADC was fed (sample k after a reset reads
//! line k of the trace, looping), every frame's bytes against the decoder, and the faults of a
//! real desk are played: a host that stops reading, a port closed and reopened, a power-on
//! reset, a corrupted byte.

use std::io::{BufRead, BufReader, Read, Write};
use std::os::fd::AsFd;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crackbot_acquisition::{
    PortConfig, RecordEnd, RecordMeta, RecordSession, Sample, SensorStream, TryNext,
};
use crackbot_protocol::{Decoder, DecoderStats, Frame};
use nix::sys::signal::{kill, Signal};
use nix::sys::termios;
use nix::unistd::Pid;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// Builds the image (once per process; `image.sh` is quick when nothing changed) and returns the
/// ELF's path, the script's last line.
fn image() -> PathBuf {
    static ELF: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    ELF.get_or_init(|| {
        let out = Command::new("bash")
            .arg(Path::new(ROOT).join("firmware/image.sh"))
            .stderr(Stdio::inherit())
            .output()
            .expect("running firmware/image.sh");
        assert!(out.status.success(), "firmware/image.sh failed");
        let text = String::from_utf8(out.stdout).expect("UTF-8 path");
        let elf = PathBuf::from(text.lines().last().expect("a last line").trim());
        assert!(
            elf.is_file(),
            "image.sh printed {elf:?}, which is not a file"
        );
        elf
    })
    .clone()
}

/// A trace: the four channels' raw counts, one sample a line, as the emulator reads it.
fn read_trace(path: &Path) -> Vec<[u16; 4]> {
    let text = std::fs::read_to_string(path).expect("reading the trace");
    text.lines()
        .skip(1)
        .map(|line| {
            let v: Vec<u16> = line
                .split(',')
                .map(|x| x.parse().expect("a count"))
                .collect();
            [v[0], v[1], v[2], v[3]]
        })
        .collect()
}

/// The simulator's first slide on the built-in default scene, written as a trace.
fn simulator_trace(dir: &Path) -> PathBuf {
    let scene = crackbot_sim::Scene::builtin_default();
    let mut source =
        crackbot_emulator::SimSource::across_first_crack(&scene, 1).expect("the default scene");
    let path = dir.join("slide.csv");
    let file = std::fs::File::create(&path).expect("creating the trace");
    let samples = crackbot_emulator::trace::stroke_samples(&scene);
    crackbot_emulator::trace::write_trace(&mut source, samples, file).expect("writing the trace");
    assert!(source.error().is_none(), "the simulation failed");
    path
}

fn checked_in_trace() -> PathBuf {
    Path::new(ROOT).join("firmware/emulator/default-slide.csv")
}

/// A running `firmware/emulate.sh`.
struct Board {
    child: Child,
    pty: String,
    stats: PathBuf,
    _dir: tempfile::TempDir,
}

impl Board {
    fn start(trace: &Path) -> Board {
        let elf = image();
        let dir = tempfile::tempdir().expect("temp dir");
        let stats = dir.path().join("stats.json");
        let mut child = Command::new("bash")
            .arg(Path::new(ROOT).join("firmware/emulate.sh"))
            .arg("--trace")
            .arg(trace)
            .arg("--stats")
            .arg(&stats)
            .arg(&elf)
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("running firmware/emulate.sh");
        let mut line = String::new();
        BufReader::new(child.stdout.take().expect("stdout"))
            .read_line(&mut line)
            .expect("reading the terminal's path");
        let pty = line.trim().to_string();
        assert!(pty.starts_with("/dev/pts/"), "first line {line:?}");
        Board {
            child,
            pty,
            stats,
            _dir: dir,
        }
    }

    fn signal(&self, signal: Signal) {
        let pid = Pid::from_raw(i32::try_from(self.child.id()).expect("pid"));
        kill(pid, signal).expect("signalling the emulator");
    }

    /// Stops it and returns its counters.
    fn stop(mut self) -> serde_json::Value {
        self.signal(Signal::SIGTERM);
        let status = self.child.wait().expect("waiting for the emulator");
        assert!(status.success(), "the emulator failed: {status}");
        let text = std::fs::read_to_string(&self.stats).expect("the emulator's counters");
        serde_json::from_str(&text).expect("counters as JSON")
    }
}

impl Drop for Board {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The terminal opened as a raw serial port, without the acquisition.
fn open_raw(pty: &str) -> std::fs::File {
    let file = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(pty)
        .expect("opening the terminal");
    let mut t = termios::tcgetattr(file.as_fd()).expect("tcgetattr");
    termios::cfmakeraw(&mut t);
    t.control_chars[termios::SpecialCharacterIndices::VMIN as usize] = 0;
    t.control_chars[termios::SpecialCharacterIndices::VTIME as usize] = 1;
    termios::tcsetattr(file.as_fd(), termios::SetArg::TCSANOW, &t).expect("tcsetattr");
    file
}

/// Reads for `seconds` (0.1 s timeouts), appending to `bytes`.
fn read_for(port: &mut std::fs::File, seconds: f64, bytes: &mut Vec<u8>) {
    let end = Instant::now() + Duration::from_secs_f64(seconds);
    let mut buf = [0u8; 4096];
    while Instant::now() < end {
        let n = port.read(&mut buf).expect("reading the terminal");
        bytes.extend_from_slice(&buf[..n]);
    }
}

fn decode(bytes: &[u8]) -> (Vec<Frame>, DecoderStats) {
    let mut decoder = Decoder::new();
    let mut frames = Vec::new();
    decoder.feed(bytes, |r| {
        if let Ok(f) = r {
            frames.push(f);
        }
    });
    (frames, *decoder.stats())
}

fn rejected(s: &DecoderStats) -> u64 {
    s.crc_errors + s.cobs_errors + s.truncated + s.overlong + s.version_errors
}

/// Every frame carries the trace's sample for its sequence number (sample k after a reset is
/// line k of the trace).
fn assert_as_fed(frames: impl IntoIterator<Item = (u16, [u16; 4])>, trace: &[[u16; 4]]) -> usize {
    let mut n = 0;
    for (seq, raw) in frames {
        let fed = trace[usize::from(seq) % trace.len()];
        assert_eq!(raw, fed, "frame {seq} differs from the trace's sample");
        n += 1;
    }
    n
}

/// Samples of the acquisition for `seconds`.
fn collect(stream: &mut SensorStream, seconds: f64) -> Vec<Sample> {
    let end = Instant::now() + Duration::from_secs_f64(seconds);
    let mut out = Vec::new();
    while Instant::now() < end {
        match stream.try_next() {
            TryNext::Ready(Ok(s)) => out.push(s),
            TryNext::Ready(Err(e)) => panic!("acquisition error: {e}"),
            TryNext::Empty => std::thread::sleep(Duration::from_millis(5)),
            TryNext::Ended => panic!("the stream ended"),
        }
    }
    out
}

fn u(v: &serde_json::Value, key: &str) -> u64 {
    v[key].as_u64().unwrap_or_else(|| panic!("no {key} in {v}"))
}

#[test]
fn the_checked_in_trace_is_the_simulators_first_slide_on_the_default_scene() {
    let dir = tempfile::tempdir().expect("temp dir");
    let fresh = simulator_trace(dir.path());
    assert_eq!(
        std::fs::read_to_string(fresh).expect("fresh trace"),
        std::fs::read_to_string(checked_in_trace()).expect("checked-in trace"),
        "firmware/emulator/default-slide.csv is stale: rewrite it with `crackbot-sensor-emulator \
         --source sim --scene builtin --write-trace firmware/emulator/default-slide.csv`"
    );
}

/// The goal: ≥ 60 s from the emulated chip at 400 Hz ± 0.1 %, recorded as `crackbot record` does,
/// with no decode error and every sample bit-equal to what the ADC was fed; the tick's cycles
/// within 20 % of the 2.5 ms period.
#[test]
fn the_board_image_streams_a_minute_at_400_hz_every_sample_as_fed() {
    let dir = tempfile::tempdir().expect("temp dir");
    let trace_path = simulator_trace(dir.path());
    let trace = read_trace(&trace_path);
    let board = Board::start(&trace_path);
    let out = dir.path().join("minute.csv");
    // What `crackbot record --port PTY --seconds 61 --out minute.csv` runs, in this process (no
    // binary to build beside the other tests).
    let session = RecordSession {
        port: PortConfig::new(board.pty.clone()),
        out: out.clone(),
        meta: RecordMeta::default(),
        limit: Some(Duration::from_secs(61)),
    };
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .expect("tokio runtime");
    let report = runtime
        .block_on(session.run(std::future::pending(), |_| {}))
        .expect("recording the board");
    let stats = board.stop();
    assert!(
        matches!(report.ended_by, RecordEnd::TimeLimit),
        "{:?}",
        report.ended_by
    );
    let summary = serde_json::to_value(&report.stream).expect("the summary as JSON");
    eprintln!("record: {summary}\nemulator: {stats}");

    // Rate, as the host saw it and as the device stamped it.
    let host_rate = summary["host_rate_hz"].as_f64().expect("host rate");
    let device_rate = summary["device_rate_hz"].as_f64().expect("device rate");
    assert!((host_rate - 400.0).abs() <= 0.4, "host sees {host_rate} Hz");
    assert!(
        (device_rate - 400.0).abs() <= 0.4,
        "device stamps {device_rate} Hz"
    );
    let samples = u(&summary, "samples");
    assert!(samples >= 24_000, "only {samples} samples in 61 s");
    let link = &summary["link"];
    for key in [
        "crc_errors",
        "cobs_errors",
        "truncated",
        "overlong",
        "version_errors",
        "gaps",
    ] {
        assert_eq!(u(link, key), 0, "{key} in {link}");
    }
    assert_eq!(u(link, "restarts"), 0);

    // Every sample recorded is the trace's sample for its sequence number (no wrap in 61 s).
    let rec = crackbot_recording::read_csv(&out).expect("reading the recording");
    let extra = rec.extra.as_ref().expect("seq and flags columns");
    assert_eq!(rec.rows.len() as u64, samples);
    let checked = assert_as_fed(
        rec.rows.iter().zip(extra).map(|(row, x)| {
            let raw = [row.d1, row.d2, row.d3, row.p].map(|v| v as u16);
            (x.seq, raw)
        }),
        &trace,
    );
    assert_eq!(checked as u64, samples);
    assert!(extra.iter().all(|x| x.flags & 0x10 == 0), "an overrun flag");

    // Timing in the emulator: the tick's own cycles (timer + ADC handlers, the frame built and
    // queued) within 20 % of the period, and the whole CPU load under the period.
    let period = u(&stats, "period_cycles");
    let tick = u(&stats, "tick_cycles_max");
    assert!(tick * 5 <= period, "tick {tick} cycles of {period}");
    assert!(u(&stats, "period_awake_cycles_max") < period);
    assert!(u(&stats, "ticks") >= samples);
    assert_eq!(u(&stats, "bridge_dropped"), 0);
}

#[test]
fn the_board_image_encodes_the_golden_frames_bit_for_bit() {
    let golden: serde_json::Value =
        serde_json::from_str(crackbot_protocol::GOLDEN_VECTORS_JSON).expect("golden JSON");
    let valid = golden["valid"].as_array().expect("valid frames");
    let board = Board::start(&checked_in_trace());
    let mut port = open_raw(&board.pty);
    let mut bytes = Vec::new();
    // The board is up once it streams.
    read_for(&mut port, 0.2, &mut bytes);
    assert!(!decode(&bytes).0.is_empty(), "no frame from the board");
    for v in valid {
        let f = &v["frame"];
        let ch: Vec<u64> = f["channels"]
            .as_array()
            .expect("channels")
            .iter()
            .map(|c| c.as_u64().expect("a channel"))
            .collect();
        let line = format!(
            "E{:02x}{:04x}{:08x}{:04x}{:04x}{:04x}{:04x}\n",
            u(f, "flags"),
            u(f, "seq"),
            u(f, "timestamp_us"),
            ch[0],
            ch[1],
            ch[2],
            ch[3]
        );
        port.write_all(line.as_bytes())
            .expect("sending the encode command");
        // One command at a time: the answer shares the line with the 400 Hz stream.
        read_for(&mut port, 0.03, &mut bytes);
    }
    read_for(&mut port, 0.3, &mut bytes);
    board.stop();
    for v in valid {
        let wire = hex(v["wire"].as_str().expect("wire"));
        assert!(
            bytes.windows(wire.len()).any(|w| w == wire.as_slice()),
            "the board did not send golden frame {:?}",
            v["name"]
        );
    }
}

fn hex(s: &str) -> Vec<u8> {
    (0..s.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&s[i..i + 2], 16).expect("hex"))
        .collect()
}

/// The host stops reading: the terminal fills, the adapter holds CTS, the firmware's ring buffer
/// fills and it drops whole frames, flagging the overrun on the next one it sends.
#[test]
fn a_host_that_stops_reading_gets_whole_frames_and_the_overrun_flag() {
    let trace = read_trace(&checked_in_trace());
    let board = Board::start(&checked_in_trace());
    let mut port = open_raw(&board.pty);
    let mut bytes = Vec::new();
    read_for(&mut port, 1.0, &mut bytes);
    std::thread::sleep(Duration::from_secs(6));
    read_for(&mut port, 2.0, &mut bytes);
    let stats = board.stop();
    let (frames, decoder) = decode(&bytes);
    assert_eq!(rejected(&decoder), 0, "{decoder:?}");
    assert!(u(&stats, "cts_holds") >= 1, "{stats}");
    assert_eq!(u(&stats, "bridge_dropped"), 0);
    let gaps: Vec<&[Frame]> = frames
        .windows(2)
        .filter(|w| w[1].seq != w[0].seq.wrapping_add(1))
        .collect();
    assert!(
        !gaps.is_empty(),
        "no frame was dropped in 6 s without reading"
    );
    for w in &gaps {
        assert!(
            w[1].seq > w[0].seq,
            "sequence went back: {} → {}",
            w[0].seq,
            w[1].seq
        );
        assert!(
            w[1].flags.overrun(),
            "frame {} after a gap lacks the overrun flag",
            w[1].seq
        );
    }
    let missing: u32 = gaps
        .iter()
        .map(|w| u32::from(w[1].seq.wrapping_sub(w[0].seq)) - 1)
        .sum();
    eprintln!(
        "not reading for 6 s: {} frames decoded, {} gaps, {missing} frames dropped whole, \
         {decoder:?}\nemulator: {stats}",
        frames.len(),
        gaps.len()
    );
    let flagged = frames.iter().filter(|f| f.flags.overrun()).count();
    assert_eq!(flagged, gaps.len(), "overrun flags only right after gaps");
    assert_as_fed(frames.iter().map(|f| (f.seq, f.channels)), &trace);
}

/// The port closed and opened again: the stream goes on (sequence numbers forward), what was
/// lost meanwhile shows as a gap, and every sample is still as fed.
#[test]
fn a_port_closed_and_reopened_resumes_the_stream() {
    let trace = read_trace(&checked_in_trace());
    let board = Board::start(&checked_in_trace());
    let config = PortConfig::new(board.pty.clone());
    let mut first = SensorStream::open(&config).expect("opening the port");
    let before = collect(&mut first, 1.0);
    drop(first);
    std::thread::sleep(Duration::from_secs(3));
    let mut second = SensorStream::open(&config).expect("reopening the port");
    let after = collect(&mut second, 2.0);
    let link = second.stats();
    drop(second);
    let stats = board.stop();
    eprintln!("after reopening: {link:?}\nemulator: {stats}");
    let last = before.last().expect("samples before closing").seq;
    assert!(
        after.len() > 600,
        "only {} samples after reopening",
        after.len()
    );
    assert!(
        after.iter().all(|s| s.seq > last),
        "sequence went back after reopening"
    );
    assert!(
        rejected(&link.decoder) <= 1,
        "more than a cut frame: {link:?}"
    );
    assert_eq!(link.restarts, 0);
    assert!(
        link.overrun_flags >= 1,
        "the frames lost while closed are not flagged"
    );
    assert_as_fed(before.iter().chain(&after).map(|s| (s.seq, s.raw)), &trace);
}

/// A power-on reset mid-stream: the host sees the sequence start again at 0 (a restart, not a
/// gap of 65 000 frames), and the samples after it are the trace's from its start.
#[test]
fn a_reset_mid_stream_restarts_the_sequence_and_the_host_sees_it() {
    let trace = read_trace(&checked_in_trace());
    let board = Board::start(&checked_in_trace());
    let mut stream = SensorStream::open(&PortConfig::new(board.pty.clone())).expect("open");
    let mut samples = collect(&mut stream, 1.0);
    board.signal(Signal::SIGUSR1);
    samples.extend(collect(&mut stream, 1.5));
    let link = stream.stats();
    drop(stream);
    let stats = board.stop();
    eprintln!("reset mid-stream: {link:?}\nemulator: {stats}");
    assert_eq!(u(&stats, "resets"), 1);
    assert_eq!(link.restarts, 1, "{link:?}");
    assert_eq!(link.gaps, 0, "a restart counted as a gap: {link:?}");
    assert!(
        rejected(&link.decoder) <= 1,
        "more than the frame cut by the reset: {link:?}"
    );
    let at = samples
        .iter()
        .position(|s| s.restarted)
        .expect("a restarted sample");
    assert!(
        samples[at].seq <= 1,
        "the first frame after the reset is {}",
        samples[at].seq
    );
    assert!(
        at > 300 && samples.len() - at > 400,
        "{at} of {}",
        samples.len()
    );
    let times: Vec<u64> = samples.iter().map(|s| s.device_time_us).collect();
    assert!(
        times.windows(2).all(|w| w[1] > w[0]),
        "device time not monotonic"
    );
    assert_as_fed(samples.iter().map(|s| (s.seq, s.raw)), &trace);
}

/// One corrupted byte on the line: one frame rejected, the next decoded, nothing else lost.
#[test]
fn a_corrupted_byte_costs_one_frame_and_the_decoder_resynchronises() {
    let trace = read_trace(&checked_in_trace());
    let board = Board::start(&checked_in_trace());
    let mut stream = SensorStream::open(&PortConfig::new(board.pty.clone())).expect("open");
    let mut samples = collect(&mut stream, 1.0);
    board.signal(Signal::SIGUSR2);
    samples.extend(collect(&mut stream, 1.0));
    let link = stream.stats();
    drop(stream);
    let stats = board.stop();
    eprintln!("one corrupted byte: {link:?}\nemulator: {stats}");
    assert_eq!(u(&stats, "corrupted"), 1);
    assert_eq!(rejected(&link.decoder), 1, "{link:?}");
    assert_eq!((link.gaps, link.missing_frames), (1, 1), "{link:?}");
    assert_eq!(link.overrun_flags, 0);
    assert_as_fed(samples.iter().map(|s| (s.seq, s.raw)), &trace);
}

/// A trace the ADC cannot have produced is refused before the board starts, naming the line.
#[test]
fn a_bad_trace_is_refused_with_its_line() {
    let elf = image();
    let dir = tempfile::tempdir().expect("temp dir");
    for (text, expected) in [
        (
            "d1,d2,d3,p\n1,2,3,4\n1,2,3,1024\n",
            "line 3: count 1024 of channel 4 is above",
        ),
        ("d1,d2,d3,p\n1,2,3\n", "line 2: expected four raw counts"),
        ("d1,d2,d3,p\n", "holds no samples"),
    ] {
        let path = dir.path().join("bad.csv");
        std::fs::write(&path, text).expect("writing the trace");
        let out = Command::new("bash")
            .arg(Path::new(ROOT).join("firmware/emulate.sh"))
            .arg("--trace")
            .arg(&path)
            .arg(&elf)
            .output()
            .expect("running emulate.sh");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{text:?}: {stderr}");
        assert!(out.stdout.is_empty(), "a port was offered for {text:?}");
        assert!(stderr.contains(expected), "{text:?}: {stderr}");
    }
}
