//! Camera frames through a real ffmpeg process (the one `scripts/setup.sh` installs): a video
//! file gives back exactly the frame encoded into it, image files are read without ffmpeg, and
//! every failure (no device, a corrupt stream, no ffmpeg, a camera that never answers) is an
//! error naming the source. A V4L2 device goes through the same process with `-f v4l2`; there
//! is none on this machine.

use std::process::Command;
use std::time::{Duration, Instant};

use crackbot_vision::camera::{grab_frame, CameraError, CameraSource, Ffmpeg, DEFAULT_TIMEOUT};
use image::RgbImage;

fn ffmpeg() -> Ffmpeg {
    Ffmpeg::locate().expect("ffmpeg: run `bash scripts/setup.sh` (installs imageio-ffmpeg)")
}

/// Encodes `input` (with ffmpeg's input options `before` and output options `after`) losslessly
/// (PNG frames) into the video `out`.
fn encode(before: &[&str], input: &std::path::Path, after: &[&str], out: &std::path::Path) {
    let status = Command::new(&ffmpeg().0)
        .args(["-nostdin", "-hide_banner", "-loglevel", "error"])
        .args(before)
        .arg("-i")
        .arg(input)
        .args(after)
        .args(["-c:v", "png"])
        .arg(out)
        .status()
        .expect("ffmpeg");
    assert!(
        status.success(),
        "ffmpeg could not encode {}",
        input.display()
    );
}

/// A frame no codec could guess: pseudo-random pixels.
fn pattern(w: u32, h: u32) -> RgbImage {
    let mut s: u32 = 12345;
    RgbImage::from_fn(w, h, |_, _| {
        let mut px = [0u8; 3];
        for c in &mut px {
            s = s.wrapping_mul(1_103_515_245).wrapping_add(12345);
            *c = (s >> 16) as u8;
        }
        image::Rgb(px)
    })
}

#[test]
fn sources_are_told_apart() {
    assert_eq!(
        CameraSource::parse("/dev/video0"),
        CameraSource::Device("/dev/video0".into())
    );
    assert_eq!(
        CameraSource::parse("frames/a.PNG"),
        CameraSource::ImageFile("frames/a.PNG".into())
    );
    assert_eq!(
        CameraSource::parse("rtsp://10.0.0.5/cam"),
        CameraSource::Stream("rtsp://10.0.0.5/cam".into())
    );
    assert_eq!(
        CameraSource::parse("run.mkv"),
        CameraSource::Stream("run.mkv".into())
    );
}

#[test]
fn a_video_file_gives_back_exactly_the_frame_encoded_into_it() {
    let dir = tempfile::tempdir().unwrap();
    let frame = pattern(96, 64);
    let png = dir.path().join("frame.png");
    frame.save(&png).unwrap();
    let video = dir.path().join("camera.mkv");
    encode(&["-loop", "1"], &png, &["-frames:v", "5"], &video);
    let source = CameraSource::parse(video.to_str().unwrap());
    let got = grab_frame(&source, None, DEFAULT_TIMEOUT).unwrap();
    assert_eq!(got.dimensions(), frame.dimensions());
    assert!(got == frame, "the frame came back changed");
}

#[test]
fn image_files_need_no_ffmpeg() {
    let dir = tempfile::tempdir().unwrap();
    let frame = pattern(20, 10);
    let png = dir.path().join("frame.png");
    frame.save(&png).unwrap();
    let nowhere = Ffmpeg("/nonexistent/ffmpeg".into());
    let got = grab_frame(
        &CameraSource::parse(png.to_str().unwrap()),
        Some(&nowhere),
        DEFAULT_TIMEOUT,
    )
    .unwrap();
    assert!(got == frame);
    // A broken image file is named.
    let bad = dir.path().join("bad.png");
    std::fs::write(&bad, b"not a png").unwrap();
    let err = grab_frame(
        &CameraSource::parse(bad.to_str().unwrap()),
        None,
        DEFAULT_TIMEOUT,
    )
    .unwrap_err();
    assert!(matches!(err, CameraError::Decode { .. }), "{err}");
    assert!(err.to_string().contains("bad.png"), "{err}");
}

#[test]
fn failures_name_the_source() {
    let dir = tempfile::tempdir().unwrap();
    let f = ffmpeg();
    // No such device.
    let err = grab_frame(
        &CameraSource::parse("/dev/video-crackbot-absent"),
        Some(&f),
        DEFAULT_TIMEOUT,
    )
    .unwrap_err();
    assert!(
        err.to_string().contains("/dev/video-crackbot-absent")
            && err.to_string().contains("no such device"),
        "{err}"
    );
    // A corrupt stream: ffmpeg's own words come back.
    let junk = dir.path().join("junk.mkv");
    std::fs::write(&junk, vec![0x5au8; 4096]).unwrap();
    let err = grab_frame(
        &CameraSource::parse(junk.to_str().unwrap()),
        Some(&f),
        DEFAULT_TIMEOUT,
    )
    .unwrap_err();
    assert!(matches!(err, CameraError::NoFrame { .. }), "{err}");
    assert!(err.to_string().contains("junk.mkv"), "{err}");
    // No ffmpeg where it was said to be.
    let err = grab_frame(
        &CameraSource::parse(junk.to_str().unwrap()),
        Some(&Ffmpeg("/nonexistent/ffmpeg".into())),
        DEFAULT_TIMEOUT,
    )
    .unwrap_err();
    assert!(matches!(err, CameraError::Spawn { .. }), "{err}");
    assert!(err.to_string().contains("/nonexistent/ffmpeg"), "{err}");
}

#[test]
fn a_camera_that_never_answers_times_out() {
    let dir = tempfile::tempdir().unwrap();
    // A named pipe nobody writes to: ffmpeg waits on it for ever.
    let fifo = dir.path().join("silent.mkv");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let t = Instant::now();
    let err = grab_frame(
        &CameraSource::parse(fifo.to_str().unwrap()),
        Some(&ffmpeg()),
        Duration::from_millis(800),
    )
    .unwrap_err();
    assert!(matches!(err, CameraError::Timeout { .. }), "{err}");
    assert!(t.elapsed() < Duration::from_secs(5), "{:?}", t.elapsed());
    assert!(err.to_string().contains("silent.mkv"), "{err}");
}

/// A video of `frames` frames whose grey level is 10 × the frame's index.
fn ramp_video(dir: &std::path::Path, frames: u32) -> std::path::PathBuf {
    for n in 0..frames {
        let v = (10 * n) as u8;
        RgbImage::from_pixel(32, 24, image::Rgb([v, v, v]))
            .save(dir.join(format!("f{n:03}.png")))
            .expect("a frame");
    }
    let video = dir.join("ramp.mkv");
    encode(&["-framerate", "10"], &dir.join("f%03d.png"), &[], &video);
    video
}

#[test]
fn frames_are_dropped_while_the_camera_settles_and_a_mode_not_given_is_refused() {
    use crackbot_vision::camera::{grab, CaptureOptions};
    let dir = tempfile::tempdir().unwrap();
    let source = CameraSource::parse(ramp_video(dir.path(), 12).to_str().unwrap());
    let first = grab(&source, None, &CaptureOptions::default(), DEFAULT_TIMEOUT).unwrap();
    assert_eq!(first.get_pixel(0, 0)[0], 0);
    let settled = CaptureOptions {
        discard: Some(5),
        size: Some([32, 24]),
        ..CaptureOptions::default()
    };
    let got = grab(&source, None, &settled, DEFAULT_TIMEOUT).unwrap();
    assert_eq!(got.get_pixel(0, 0)[0], 50, "the sixth frame");
    let hd = CaptureOptions {
        size: Some([1280, 720]),
        ..CaptureOptions::default()
    };
    match grab(&source, None, &hd, DEFAULT_TIMEOUT) {
        Err(e @ CameraError::Mode { .. }) => {
            let m = e.to_string();
            assert!(m.contains("1280×720") && m.contains("32×24"), "{m}");
        }
        other => panic!("expected a mode error, got {other:?}"),
    }
}

#[test]
fn a_device_is_asked_for_its_mode_exposure_and_gain() {
    use crackbot_vision::camera::CaptureOptions;
    let o = CaptureOptions {
        size: Some([1280, 720]),
        pixel_format: Some("mjpeg".into()),
        framerate: Some(30.0),
        exposure: Some(150),
        gain: Some(20),
        discard: None,
    };
    let dev = CameraSource::parse("/dev/video0");
    assert_eq!(
        o.input_args(&dev).join(" "),
        "-f v4l2 -video_size 1280x720 -input_format mjpeg -framerate 30 -i /dev/video0"
    );
    // A file or stream is not asked for a mode: its size is only checked.
    assert_eq!(
        o.input_args(&CameraSource::parse("run.mkv")).join(" "),
        "-i run.mkv"
    );
    assert_eq!(
        o.controls(),
        ["auto_exposure=1", "exposure_time_absolute=150", "gain=20"]
    );
    // A device drops its first frames unless told otherwise; a file keeps its first.
    assert!(o
        .output_args(&dev)
        .join(" ")
        .starts_with("-vf select=gte(n\\,5) -frames:v 1"));
    let file = CameraSource::parse("run.mkv");
    assert!(o.output_args(&file).join(" ").starts_with("-frames:v 1"));
    assert!(CaptureOptions::default().controls().is_empty());
}
