//! The headless robot and the simulated controller as two processes, as on hardware: the robot
//! gets `--serial` (the controller's pseudo-terminal), `--controller` (its UDP address) and
//! `--key` (the pre-shared key file), and `crackbot run` takes the same flags.

use std::io::{BufRead, BufReader};
use std::net::UdpSocket;
use std::process::{Command, Stdio};

use crackbot_testkit::DdsArm;
use crackbot_tests::{binary, confirmed, text};

/// A small plate with one 10 mm crack, so that the tactile-only scan is a few short rows.
const SCENE: &str = r#"
name = "one crack, small plate"
[plate]
size_mm = [40.0, 24.0]
[[features]]
kind = "crack"
path = [[20.0, 6.0], [20.0, 14.0]]
width_mm = 10.0
depth_mm = 4.0
[manipulator]
workspace_min_mm = [0.0, 0.0, -5.0]
workspace_max_mm = [40.0, 24.0, 150.0]
"#;

/// What the robot knows of [`SCENE`]'s place on hardware: its arm's box (the rest default).
const SITE: &str = "name = \"test plate\"\n[arm]\nworkspace_min_mm = [0.0, 0.0]\nworkspace_max_mm = [40.0, 24.0]\n";

fn free_port() -> u16 {
    UdpSocket::bind("127.0.0.1:0")
        .and_then(|s| s.local_addr())
        .map(|a| a.port())
        .expect("a free UDP port")
}

/// Writes a key file of `byte` repeated (hex), mode 0600.
fn key_file(path: &std::path::Path, byte: &str) {
    std::fs::write(path, format!("{}\n", byte.repeat(32))).expect("key");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o600)).expect("chmod");
    }
}

/// A running `crackbot-controller` over [`SCENE`].
struct Controller {
    child: std::process::Child,
    /// Its standard output, kept open (it prints more, and a closed pipe would end it).
    _stdout: BufReader<std::process::ChildStdout>,
    pty: String,
    port: u16,
    /// The port the robot must bind.
    host_port: u16,
}

/// Starts a controller process over [`SCENE`].
fn start_controller(dir: &std::path::Path, key: &std::path::Path, speedup: &str) -> Controller {
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, SCENE).expect("scene");
    std::fs::write(dir.join("site.toml"), SITE).expect("site");
    spawn_controller(dir, &scene, key, speedup)
}

/// `crackbot-controller` over `scene`, its state in `dir/ctrl`, once it has printed its PTY.
fn spawn_controller(
    dir: &std::path::Path,
    scene: &std::path::Path,
    key: &std::path::Path,
    speedup: &str,
) -> Controller {
    let scene = scene.to_str().expect("utf-8");
    spawn_controller_with(dir, key, &["--scene", scene, "--speedup", speedup])
}

/// `crackbot-controller` with `args` (its arm), talking on two free ports with `key`, its state
/// in `dir/ctrl`, once it has printed its PTY.
fn spawn_controller_with(
    dir: &std::path::Path,
    key: &std::path::Path,
    args: &[&str],
) -> Controller {
    // The robot is built first: a controller left idle while cargo builds the robot catches its
    // simulated clock up in a burst once slides come, and a mission then ends in a blink.
    binary("crackbot-robot");
    let (cport, hport) = (free_port(), free_port());
    let mut controller = Command::new(binary("crackbot-controller"))
        .args(args)
        .args(["--bind", &format!("127.0.0.1:{cport}")])
        .args(["--peer", &format!("127.0.0.1:{hport}")])
        .args(["--key", key.to_str().expect("utf-8")])
        .args(["--state-dir", dir.join("ctrl").to_str().expect("utf-8")])
        .args(["--seconds", "300"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("starting crackbot-controller");
    let mut out = BufReader::new(controller.stdout.take().expect("stdout"));
    let mut line = String::new();
    out.read_line(&mut line).expect("the PTY line");
    let pty = line
        .trim()
        .strip_prefix("PTY ")
        .expect("PTY /dev/pts/N")
        .to_string();
    Controller {
        child: controller,
        _stdout: out,
        pty,
        port: cport,
        host_port: hport,
    }
}

#[test]
fn the_robot_drives_the_controller_process_over_the_link_and_refuses_a_bad_key() {
    let dir = tempfile::tempdir().expect("tempdir");
    let site = dir.path().join("site.toml");
    let key = dir.path().join("link.key");
    key_file(&key, "5a");
    let c = start_controller(dir.path(), &key, "8");
    let (mut controller, pty, cport, hport) = (c.child, c.pty, c.port, c.host_port);
    let _stdout = c._stdout;

    let robot = |extra: &[&str], key: &std::path::Path| {
        Command::new(binary("crackbot-robot"))
            .args(["--site", site.to_str().expect("utf-8")])
            .args([
                "--mode",
                "tactile",
                "--gamma",
                "0.75",
                "--speedup",
                "8",
                "--json",
            ])
            .args(["--serial", &pty])
            .args(["--controller", &format!("127.0.0.1:{cport}")])
            .args(["--bind", &format!("127.0.0.1:{hport}")])
            .args(["--key", key.to_str().expect("utf-8")])
            .args(extra)
            .output()
            .expect("running crackbot-robot")
    };
    // A robot with another key is never heard: the mission fails clearly, nothing moves.
    let wrong = dir.path().join("wrong.key");
    key_file(&wrong, "a7");
    let o = robot(
        &["--out", dir.path().join("wrong").to_str().expect("utf-8")],
        &wrong,
    );
    assert!(!o.status.success());
    assert!(
        text(&o.stderr).contains("unreachable"),
        "{}",
        text(&o.stderr)
    );

    let o = robot(
        &["--out", dir.path().join("mission").to_str().expect("utf-8")],
        &key,
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON object");
    let passes = report["passes"].as_array().expect("passes");
    assert!(!passes.is_empty());
    for p in passes {
        assert!(p["samples"].as_u64().expect("samples") > 100, "{p}");
    }
    for k in ["cracks", "rejected", "elapsed_s"] {
        assert!(report.get(k).is_some(), "{k} missing");
    }
    // Every row stayed inside the workspace the controller enforces.
    for p in passes {
        for end in ["start_mm", "end_mm"] {
            let x = p[end][0].as_f64().expect("x");
            let y = p[end][1].as_f64().expect("y");
            assert!(
                (0.0..=40.0).contains(&x) && (0.0..=24.0).contains(&y),
                "{p}"
            );
        }
    }
    controller.kill().ok();
    controller.wait().ok();
}

#[test]
fn a_mission_file_names_the_rig_and_the_settings_and_flags_override_it() {
    let dir = tempfile::tempdir().expect("tempdir");
    let key = dir.path().join("link.key");
    key_file(&key, "5a");
    // The defaults as a file, every key explained, and read back by the robot unchanged.
    let o = Command::new(binary("crackbot-robot"))
        .arg("--print-config")
        .output()
        .expect("crackbot-robot --print-config");
    assert!(o.status.success(), "{}", text(&o.stderr));
    let printed = text(&o.stdout);
    for section in [
        "[rig]",
        "[perceive]",
        "[plan.planner]",
        "[touch]",
        "[print_check]",
        "[judge]",
        "[pieces]",
        "[output]",
    ] {
        assert!(printed.contains(section), "{section} missing:\n{printed}");
    }
    assert!(printed.contains("# Height of the raised pass"), "{printed}");
    let defaults = dir.path().join("defaults.toml");
    std::fs::write(&defaults, &printed).expect("defaults.toml");
    let again = Command::new(binary("crackbot-robot"))
        .args([
            "--config",
            defaults.to_str().expect("utf-8"),
            "--print-config",
        ])
        .output()
        .expect("crackbot-robot --config --print-config");
    assert_eq!(text(&again.stdout), printed, "{}", text(&again.stderr));

    let c = start_controller(dir.path(), &key, "8");
    let (mut controller, pty, cport, hport) = (c.child, c.pty, c.port, c.host_port);
    let _stdout = c._stdout;
    // A site's mission written down: the hardware, the site's box, the mode and a step's
    // setting; the speed-up comes from the flags.
    let file = dir.path().join("mission.toml");
    let out = dir.path().join("mission");
    std::fs::write(
        &file,
        format!(
            "mode = \"tactile\"\n\
             [rig.hardware]\nserial = \"{pty}\"\ncontroller = \"127.0.0.1:{cport}\"\n\
             bind = \"127.0.0.1:{hport}\"\nkey_file = \"{key}\"\n\
             [rig.site]\nname = \"test plate\"\n\
             [rig.site.arm]\nworkspace_min_mm = [0.0, 0.0]\nworkspace_max_mm = [40.0, 24.0]\n\
             [plan]\ngamma = 0.75\n[output]\nout_dir = \"{out}\"\n",
            key = key.display(),
            out = out.display(),
        ),
    )
    .expect("mission.toml");
    let o = Command::new(binary("crackbot-robot"))
        .args([
            "--config",
            file.to_str().expect("utf-8"),
            "--speedup",
            "8",
            "--json",
        ])
        .output()
        .expect("crackbot-robot --config");
    assert!(o.status.success(), "{}", text(&o.stderr));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON object");
    assert_eq!(report["mode"], "tactile");
    assert_eq!(report["scene"], "test plate");
    assert!(!report["passes"].as_array().expect("passes").is_empty());
    assert!(out.join("report.json").is_file());
    controller.kill().ok();
    controller.wait().ok();

    // A key the configuration does not have, and a value out of range, are named.
    let bad = dir.path().join("bad.toml");
    for (body, named) in [
        ("[print_check]\nhieght_mm = 2.0\n", "hieght_mm"),
        ("[touch]\nmin_dip_counts = -3.0\n", "touch.min_dip_counts"),
    ] {
        std::fs::write(&bad, body).expect("bad.toml");
        let o = Command::new(binary("crackbot-robot"))
            .args(["--config", bad.to_str().expect("utf-8")])
            .output()
            .expect("crackbot-robot --config bad.toml");
        assert!(!o.status.success());
        assert!(text(&o.stderr).contains(named), "{}", text(&o.stderr));
    }
}

#[test]
fn crackbot_run_takes_the_robots_flags() {
    let robot = Command::new(binary("crackbot-robot"))
        .arg("--help")
        .output()
        .expect("crackbot-robot --help");
    let run = Command::new(binary("crackbot"))
        .args(["run", "--help"])
        .output()
        .expect("crackbot run --help");
    let flags = |o: &std::process::Output| -> Vec<String> {
        text(&o.stdout)
            .split_whitespace()
            .filter(|w| w.starts_with("--"))
            .map(|w| w.trim_end_matches(',').to_string())
            .collect()
    };
    let (a, b) = (flags(&robot), flags(&run));
    for f in [
        "--scene",
        "--site",
        "--mode",
        "--json",
        "--serial",
        "--controller",
        "--camera",
        "--key",
    ] {
        assert!(a.contains(&f.to_string()), "crackbot-robot lacks {f}");
    }
    assert_eq!(a, b, "crackbot run and crackbot-robot differ");
    // Bad input is refused by name before anything starts.
    let o = Command::new(binary("crackbot-robot"))
        .args(["--mode", "sideways"])
        .output()
        .expect("crackbot-robot");
    assert!(!o.status.success());
    assert!(text(&o.stderr).contains("sideways"), "{}", text(&o.stderr));
    let o = Command::new(binary("crackbot-robot"))
        .args(["--proposal-min-score", "1.5"])
        .output()
        .expect("crackbot-robot");
    assert!(!o.status.success());
    let err = text(&o.stderr);
    assert!(
        err.contains("--proposal-min-score") && err.contains("[0, 1]"),
        "{err}"
    );
}

#[test]
fn a_controller_and_sensor_that_vanish_mid_mission_end_it_with_a_clear_error() {
    let dir = tempfile::tempdir().expect("tempdir");
    let site = dir.path().join("site.toml");
    let key = dir.path().join("link.key");
    key_file(&key, "3c");
    let c = start_controller(dir.path(), &key, "2");
    let (mut controller, pty, cport, hport) = (c.child, c.pty, c.port, c.host_port);
    let _stdout = c._stdout;
    let out_dir = dir.path().join("mission");
    let robot = Command::new(binary("crackbot-robot"))
        .args(["--site", site.to_str().expect("utf-8")])
        .args(["--mode", "tactile", "--gamma", "0.75", "--speedup", "2"])
        .args(["--serial", &pty])
        .args(["--controller", &format!("127.0.0.1:{cport}")])
        .args(["--bind", &format!("127.0.0.1:{hport}")])
        .args(["--key", key.to_str().expect("utf-8")])
        .args(["--out", out_dir.to_str().expect("utf-8")])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("starting crackbot-robot");
    // Mid-mission, once the first row is saved (about 4 s at this speed on an idle machine;
    // waited for, not assumed, so a loaded machine cannot kill it too early), the controller
    // process dies: its link and its serial port go with it.
    let slides_saved = || {
        std::fs::read_dir(&out_dir).map_or(0, |d| {
            d.filter_map(Result::ok)
                .filter(|e| e.file_name().to_string_lossy().starts_with("slide-"))
                .count()
        })
    };
    let waited = std::time::Instant::now();
    while slides_saved() == 0 {
        assert!(
            waited.elapsed() < std::time::Duration::from_secs(90),
            "no slide saved in 90 s"
        );
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    std::thread::sleep(std::time::Duration::from_millis(500));
    let killed_at = slides_saved();
    controller.kill().expect("kill");
    controller.wait().ok();
    let t = std::time::Instant::now();
    let o = robot.wait_with_output().expect("the robot ends");
    assert!(
        t.elapsed() < std::time::Duration::from_secs(15),
        "{:?}",
        t.elapsed()
    );
    assert!(
        !o.status.success(),
        "the robot ended well after its controller died (slides saved when it was killed: \
         {killed_at}); stdout: {}; stderr: {}",
        text(&o.stdout),
        text(&o.stderr)
    );
    let err = text(&o.stderr);
    assert!(
        err.contains("disconnected") || err.contains("vanished") || err.contains("unreachable"),
        "{err}"
    );
    assert!(err.contains("recordings so far"), "{err}");
    // What was recorded before is still on disk.
    assert!(slides_saved() >= 1, "no recording kept");
}

/// The fused mission on hardware with the camera given as a video file: the default scene is
/// rendered once, encoded into a lossless video by ffmpeg, calibrated with `crackbot homography
/// fit`, and the robot reads its frame through `--camera video.mkv` (the same ffmpeg path as a
/// V4L2 device), detects, and slides across every candidate on the controller process.
/// The default scene's camera on hardware: its rendered frame as a lossless video the robot
/// reads through ffmpeg, and the exact plate → image homography fitted from point pairs.
struct Camera {
    scene: std::path::PathBuf,
    frame: std::path::PathBuf,
    video: std::path::PathBuf,
    homography: std::path::PathBuf,
}

fn default_scene_camera(dir: &std::path::Path) -> Camera {
    let scene =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/sim/scenes/default.toml");
    // The frame and its exact plate → image homography.
    let render = dir.join("render");
    let o = Command::new(binary("crackbot-lab"))
        .args(["sim", "render", "--frames", "1", "--scene"])
        .arg(&scene)
        .arg("--out")
        .arg(&render)
        .output()
        .expect("crackbot-lab sim render");
    assert!(o.status.success(), "{}", text(&o.stderr));
    let coco: serde_json::Value =
        serde_json::from_slice(&std::fs::read(render.join("coco.json")).expect("coco.json"))
            .expect("COCO JSON");
    let h: Vec<Vec<f64>> = serde_json::from_value(coco["images"][0]["plate_to_image"].clone())
        .expect("plate_to_image");
    let mut pairs = String::from("u,v,x_mm,y_mm\n");
    for (x, y) in [
        (10.0, 10.0),
        (190.0, 10.0),
        (10.0, 90.0),
        (190.0, 90.0),
        (100.0, 50.0),
        (60.0, 30.0),
    ] {
        let w = h[2][0] * x + h[2][1] * y + h[2][2];
        let u = (h[0][0] * x + h[0][1] * y + h[0][2]) / w;
        let v = (h[1][0] * x + h[1][1] * y + h[1][2]) / w;
        pairs.push_str(&format!("{u},{v},{x},{y}\n"));
    }
    let pairs_csv = dir.join("pairs.csv");
    std::fs::write(&pairs_csv, pairs).expect("pairs");
    let cal = dir.join("camera.toml");
    let o = Command::new(binary("crackbot"))
        .args(["homography", "fit"])
        .arg(&pairs_csv)
        .arg("--out")
        .arg(&cal)
        .output()
        .expect("crackbot homography fit");
    assert!(o.status.success(), "{}", text(&o.stderr));
    // The camera: a lossless video of that frame.
    let frame = render.join("images/frame_0000.png");
    let video = dir.join("camera.mkv");
    let ffmpeg = crackbot_vision::camera::Ffmpeg::locate()
        .expect("ffmpeg: run `bash scripts/setup.sh` (installs imageio-ffmpeg)");
    let status = Command::new(&ffmpeg.0)
        .args(["-nostdin", "-loglevel", "error", "-loop", "1", "-i"])
        .arg(&frame)
        .args(["-frames:v", "3", "-c:v", "png"])
        .arg(&video)
        .status()
        .expect("ffmpeg");
    assert!(status.success());

    Camera {
        scene,
        frame,
        video,
        homography: cal,
    }
}

#[test]
fn a_fused_mission_reads_its_camera_through_ffmpeg() {
    let dir = tempfile::tempdir().expect("tempdir");
    let Camera {
        scene,
        frame,
        video,
        homography: cal,
    } = default_scene_camera(dir.path());
    let key = dir.path().join("link.key");
    key_file(&key, "6d");
    let c = spawn_controller(dir.path(), &scene, &key, "8");
    let (mut controller, pty, cport, hport) = (c.child, c.pty, c.port, c.host_port);
    let _stdout = c._stdout;
    let mission = dir.path().join("mission");
    // The scene's arm is the default's: the robot's default site.
    let o = Command::new(binary("crackbot-robot"))
        .args(["--mode", "fused", "--speedup", "8", "--json"])
        .args(["--serial", &pty])
        .args(["--controller", &format!("127.0.0.1:{cport}")])
        .args(["--bind", &format!("127.0.0.1:{hport}")])
        .args(["--key", key.to_str().expect("utf-8")])
        .arg("--camera")
        .arg(&video)
        .arg("--homography")
        .arg(&cal)
        .arg("--out")
        .arg(&mission)
        .output()
        .expect("running crackbot-robot");
    controller.kill().ok();
    controller.wait().ok();
    assert!(o.status.success(), "{}", text(&o.stderr));
    // The frame the robot saw is the rendered one, pixel for pixel.
    let seen = image::open(mission.join("frame.png"))
        .expect("frame.png")
        .to_rgb8();
    let rendered = image::open(&frame).expect("the rendered frame").to_rgb8();
    assert!(seen == rendered, "the camera's frame came through changed");
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON object");
    let candidates = report["candidates"].as_array().expect("candidates").len();
    assert!(
        candidates >= 4,
        "{candidates} candidates on the default scene"
    );
    // One judged stroke per candidate (a stroke whose ends read unlike each other is kept but
    // not judged, and its candidate stroked again beside it).
    let passes = report["passes"].as_array().expect("passes");
    let judged = passes
        .iter()
        .filter(|p| {
            !p["doubt"]
                .as_str()
                .is_some_and(|d| d.starts_with("not judged"))
        })
        .count();
    assert_eq!(judged, candidates, "one judged stroke per candidate");
    assert!(passes.len() <= 2 * candidates);
    // A confirmed candidate is a crack of its own or a piece of another's.
    let cracks = report["cracks"].as_array().expect("cracks");
    let pieces: usize = cracks
        .iter()
        .map(|c| c["evidence"]["pieces"].as_array().map_or(0, Vec::len))
        .sum();
    let judged = cracks.len() + pieces + report["rejected"].as_array().expect("rejected").len();
    assert_eq!(judged, candidates, "every candidate confirmed or rejected");
}

/// The states a host on link `link_id` hears from a controller process started with
/// `--link-id 9`, in half a second of listening.
fn states_heard_on_link(link_id: u16) -> usize {
    use crackbot_link::{EpochSource, Key, LinkConfig, LinkEndpoint, Message, Security};
    let dir = tempfile::tempdir().expect("tempdir");
    let key_path = dir.path().join("link.key");
    key_file(&key_path, "5a");
    let (cport, hport) = (free_port(), free_port());
    let mut controller = Command::new(binary("crackbot-controller"))
        .args(["--bind", &format!("127.0.0.1:{cport}")])
        .args(["--peer", &format!("127.0.0.1:{hport}")])
        .args(["--key", key_path.to_str().expect("utf-8")])
        .args([
            "--state-dir",
            dir.path().join("ctrl").to_str().expect("utf-8"),
        ])
        .args(["--link-id", "9", "--seconds", "20"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("starting crackbot-controller");
    let mut out = BufReader::new(controller.stdout.take().expect("stdout"));
    let mut line = String::new();
    out.read_line(&mut line).expect("the PTY line");
    let socket = UdpSocket::bind(("127.0.0.1", hport)).expect("the host's port");
    let key = Key::from_file(&key_path).expect("the key");
    let config =
        LinkConfig::host(Security::Signed(key), EpochSource::Fixed(1)).with_link_id(link_id);
    let mut ep = LinkEndpoint::from_socket(socket, ([127, 0, 0, 1], cport).into(), config)
        .expect("the host's endpoint");
    let end = std::time::Instant::now() + std::time::Duration::from_millis(500);
    let mut states = 0;
    while std::time::Instant::now() < end {
        ep.send_unreliable(&Message::Heartbeat)
            .expect("a heartbeat");
        // (One message a turn: a steady 100 Hz stream never leaves `recv` waiting 20 ms.)
        if let Ok(Some(r)) = ep.recv(std::time::Duration::from_millis(20)) {
            states += usize::from(matches!(r.message, Message::State(_)));
        }
    }
    controller.kill().ok();
    controller.wait().ok();
    states
}

#[test]
fn the_controller_takes_the_link_id_the_wire_format_names() {
    // Its own link: the 100 Hz state stream arrives. Another link's host hears nothing.
    let same = states_heard_on_link(9);
    assert!(same > 10, "{same} states on link 9");
    assert_eq!(states_heard_on_link(1), 0);
}

#[test]
fn the_conformance_suite_passes_on_the_controller_process() {
    // `crackbot-lab controller-check` against `crackbot-controller --arm sim` over the default
    // scene (the default site's box), at real time, as a third party would run it.
    let dir = tempfile::tempdir().expect("tempdir");
    let scene =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/sim/scenes/default.toml");
    let key = dir.path().join("link.key");
    key_file(&key, "5e");
    binary("crackbot-lab");
    let c = spawn_controller(dir.path(), &scene, &key, "1");
    let (mut controller, cport, hport) = (c.child, c.port, c.host_port);
    let _stdout = c._stdout;
    let json = dir.path().join("check.json");
    let o = Command::new(binary("crackbot-lab"))
        .args([
            "controller-check",
            "--controller",
            &format!("127.0.0.1:{cport}"),
        ])
        .args(["--bind", &format!("127.0.0.1:{hport}")])
        .arg("--key")
        .arg(&key)
        .arg("--state-dir")
        .arg(dir.path().join("check"))
        .arg("--json")
        .arg(&json)
        .output()
        .expect("crackbot-lab controller-check");
    controller.kill().ok();
    controller.wait().ok();
    let table = text(&o.stdout);
    eprintln!("{table}");
    assert!(o.status.success(), "{table}\n{}", text(&o.stderr));
    assert!(table.contains("7 of 7 cases passed"), "{table}");
    let results: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&json).expect("check.json")).expect("JSON");
    let passed = results
        .as_array()
        .expect("a list of cases")
        .iter()
        .filter(|r| r["passed"] == true)
        .count();
    assert_eq!(passed, 7, "{results}");
}

#[test]
fn a_fused_mission_through_a_cyclone_dds_arm_confirms_the_default_scenes_four_cracks() {
    let dir = tempfile::tempdir().expect("tempdir");
    let cam = default_scene_camera(dir.path());
    // The plate 0.4 m out, 0.1 m aside, 50 mm up, turned 30° about the base's z axis.
    let h = 15f64.to_radians();
    let (s, c) = (h.sin(), h.cos());
    let site = dir.path().join("site.toml");
    std::fs::write(
        &site,
        format!("name = \"DDS bench\"\n[surface]\norigin_m = [0.4, -0.1, 0.05]\nrotation_xyzw = [0.0, 0.0, {s}, {c}]\n"),
    )
    .expect("site");
    let domain = 150 + (std::process::id() % 60) as u16;
    let ros2 = dir.path().join("ros2.toml");
    std::fs::write(&ros2, format!("[dds]\ndomain_id = {domain}\n")).expect("ros2 config");
    // The arm starts 5 mm above the plate's origin, in its base frame.
    let arm = DdsArm::start(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")),
        domain,
        &["--start", "0.4,-0.1,0.055"],
    );
    let key = dir.path().join("link.key");
    key_file(&key, "3c");
    let utf8 = |p: &std::path::Path| p.to_str().expect("utf-8").to_string();
    let (scene, site_arg, ros2_arg) = (utf8(&cam.scene), utf8(&site), utf8(&ros2));
    let c = spawn_controller_with(
        dir.path(),
        &key,
        &[
            "--arm",
            "ros2",
            "--sim-finger",
            "--scene",
            &scene,
            "--site",
            &site_arg,
            "--ros2-config",
            &ros2_arg,
        ],
    );
    let (mut controller, pty, cport, hport) = (c.child, c.pty, c.port, c.host_port);
    let _stdout = c._stdout;
    let o = Command::new(binary("crackbot-robot"))
        .args(["--mode", "fused", "--speedup", "1", "--json"])
        .arg("--site")
        .arg(&site)
        .args(["--serial", &pty])
        .args(["--controller", &format!("127.0.0.1:{cport}")])
        .args(["--bind", &format!("127.0.0.1:{hport}")])
        .arg("--key")
        .arg(&key)
        .arg("--camera")
        .arg(&cam.video)
        .arg("--homography")
        .arg(&cam.homography)
        .arg("--out")
        .arg(dir.path().join("dds"))
        .output()
        .expect("crackbot-robot");
    controller.kill().ok();
    controller.wait().ok();
    drop(arm);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let through_dds = confirmed(&o.stdout);
    // The scene's four cracks, each confirmed once: the simulated rig's result on this scene
    // (README, "What you see"), checked against the scene's truth rather than a second run.
    let scene = crackbot_sim::Scene::load_or_default(Some(&cam.scene)).expect("the scene");
    let cracks: Vec<(&Vec<[f64; 2]>, f64)> = scene
        .features
        .iter()
        .filter_map(|f| match f {
            crackbot_sim::Feature::Crack { path, width_mm, .. } => Some((path, *width_mm)),
            _ => None,
        })
        .collect();
    assert_eq!(cracks.len(), 4);
    eprintln!("through DDS: {through_dds:?}");
    assert_eq!(through_dds.len(), cracks.len(), "{through_dds:?}");
    let mut found = vec![false; cracks.len()];
    for p in &through_dds {
        // Within the crack, or 1.5 mm beside it (the crossing of a wide crack is where the
        // finger read it, not on its centre line).
        let (k, d) = cracks
            .iter()
            .map(|(c, w)| off_path(*p, c) - w / 2.0)
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .expect("cracks");
        assert!(d < 1.5, "{p:?} is {d:.1} mm beside the nearest crack");
        assert!(!found[k], "{p:?}: crack {k} confirmed twice");
        found[k] = true;
    }
}

/// How far `p` lies from the polyline `path`, mm.
fn off_path(p: [f64; 2], path: &[[f64; 2]]) -> f64 {
    path.windows(2)
        .map(|w| {
            let (a, b) = (w[0], w[1]);
            let d = [b[0] - a[0], b[1] - a[1]];
            let t = (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / (d[0] * d[0] + d[1] * d[1]))
                .clamp(0.0, 1.0);
            (p[0] - a[0] - t * d[0]).hypot(p[1] - a[1] - t * d[1])
        })
        .fold(f64::INFINITY, f64::min)
}
