//! One camera frame from wherever the robot's camera is: an image file, a live V4L2 device
//! (`/dev/video0`, a webcam), or a video file or stream URL (`rtsp://…`, a recorded `.mkv`).
//!
//! Image files are read directly. Devices and streams go through an `ffmpeg` process (the
//! well-kept tool for every camera format and codec; V4L2 capture included), which writes one
//! lossless PNG frame to a pipe: nothing is linked in, and a camera that hangs is killed after a
//! deadline. `ffmpeg` is found at `$CRACKBOT_FFMPEG`, on `PATH`, or in the `imageio-ffmpeg`
//! wheel that `scripts/setup.sh` installs under `~/.cache/crackbot/ffmpeg-venv`.
//!
//! [`CaptureOptions`] ask a device for a mode (size, pixel format, frame rate), set its exposure
//! and gain through V4L2 controls (`v4l2-ctl`, Debian's `v4l-utils`), and drop the first frames
//! while auto-exposure settles; a frame of another size than asked is refused, naming both (a
//! driver silently falls back to a mode it offers).

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use image::RgbImage;

/// What went wrong getting a frame; each names the source.
#[derive(Debug, thiserror::Error)]
pub enum CameraError {
    /// No ffmpeg to read a device or stream with.
    #[error(
        "{source_name}: reading a camera device or stream needs ffmpeg, and none was found \
         ($CRACKBOT_FFMPEG, PATH, or ~/.cache/crackbot/ffmpeg-venv from `bash scripts/setup.sh`)"
    )]
    NoFfmpeg {
        /// The camera source.
        source_name: String,
    },
    /// ffmpeg could not be started.
    #[error("{source_name}: could not start {ffmpeg}: {error}")]
    Spawn {
        /// The camera source.
        source_name: String,
        /// The ffmpeg binary.
        ffmpeg: PathBuf,
        /// Why.
        error: std::io::Error,
    },
    /// ffmpeg ran and failed, or gave no frame.
    #[error("{source_name}: no frame ({message})")]
    NoFrame {
        /// The camera source.
        source_name: String,
        /// ffmpeg's own words, or what was missing.
        message: String,
    },
    /// No frame within the deadline.
    #[error("{source_name}: no frame within {seconds:.0} s (the camera does not answer)")]
    Timeout {
        /// The camera source.
        source_name: String,
        /// The deadline, s.
        seconds: f64,
    },
    /// The device gave another frame size than asked (it does not offer that mode).
    #[error(
        "{source_name}: asked for {}×{} px frames but got {}×{} (the device does not offer that \
         mode: `v4l2-ctl -d DEVICE --list-formats-ext` lists the ones it does)",
        asked[0], asked[1], got[0], got[1]
    )]
    Mode {
        /// The camera source.
        source_name: String,
        /// The size asked for.
        asked: [u32; 2],
        /// The size given.
        got: [u32; 2],
    },
    /// The exposure or gain could not be set.
    #[error("{source_name}: setting {controls}: {message}")]
    Control {
        /// The camera source.
        source_name: String,
        /// The controls, as v4l2-ctl takes them.
        controls: String,
        /// v4l2-ctl's words, or why it could not run.
        message: String,
    },
    /// The image file or the frame could not be decoded.
    #[error("{source_name}: {message}")]
    Decode {
        /// The camera source.
        source_name: String,
        /// The decoder's words.
        message: String,
    },
}

/// How a frame is asked for: the device's mode, its exposure and gain, frames dropped first.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaptureOptions {
    /// Frame size `[width, height]`, pixels: asked of a device; checked on every source.
    #[serde(default)]
    pub size: Option<[u32; 2]>,
    /// A device's pixel format as ffmpeg names it (`mjpeg`, `yuyv422`, …).
    #[serde(default)]
    pub pixel_format: Option<String>,
    /// A device's frame rate, frames per second.
    #[serde(default)]
    pub framerate: Option<f64>,
    /// A device's exposure time in its own units (V4L2 `exposure_time_absolute`, usually
    /// 100 µs); turns auto-exposure off.
    #[serde(default)]
    pub exposure: Option<u32>,
    /// A device's analogue gain in its own units (V4L2 `gain`).
    #[serde(default)]
    pub gain: Option<u32>,
    /// Frames dropped before the one kept (auto-exposure and white balance settling); left out:
    /// [`DEVICE_DISCARD`] for a device, none for a file or stream.
    #[serde(default)]
    pub discard: Option<u32>,
}

/// Frames a device drops by default before the one kept: about a third of a second at 15 fps,
/// what webcams' auto-exposure takes to settle after the stream starts.
pub const DEVICE_DISCARD: u32 = 5;

impl CaptureOptions {
    /// ffmpeg's input options for `source`: the mode for a device (`-f v4l2` first), nothing
    /// else for files and streams (their size is only checked).
    pub fn input_args(&self, source: &CameraSource) -> Vec<String> {
        let mut a: Vec<String> = Vec::new();
        match source {
            CameraSource::Device(path) => {
                a.extend(["-f".into(), "v4l2".into()]);
                if let Some([w, h]) = self.size {
                    a.extend(["-video_size".into(), format!("{w}x{h}")]);
                }
                if let Some(f) = &self.pixel_format {
                    a.extend(["-input_format".into(), f.clone()]);
                }
                if let Some(r) = self.framerate {
                    a.extend(["-framerate".into(), format!("{r}")]);
                }
                a.extend(["-i".into(), path.display().to_string()]);
            }
            CameraSource::Stream(s) => a.extend(["-i".into(), s.clone()]),
            CameraSource::ImageFile(p) => a.extend(["-i".into(), p.display().to_string()]),
        }
        a
    }

    /// Frames dropped from `source` before the one kept.
    pub fn discard_for(&self, source: &CameraSource) -> u32 {
        match (self.discard, source) {
            (Some(n), _) => n,
            (None, CameraSource::Device(_)) => DEVICE_DISCARD,
            (None, _) => 0,
        }
    }

    /// ffmpeg's output options for `source`: the frame after the dropped ones, as one PNG on
    /// stdout.
    pub fn output_args(&self, source: &CameraSource) -> Vec<String> {
        let mut a: Vec<String> = Vec::new();
        let discard = self.discard_for(source);
        if discard > 0 {
            a.extend(["-vf".into(), format!("select=gte(n\\,{discard})")]);
        }
        a.extend(
            ["-frames:v", "1", "-f", "image2pipe", "-c:v", "png", "-"]
                .iter()
                .map(|s| (*s).to_string()),
        );
        a
    }

    /// The `v4l2-ctl` controls for the exposure and gain asked (empty: none asked).
    pub fn controls(&self) -> Vec<String> {
        let mut c = Vec::new();
        if let Some(e) = self.exposure {
            // 1: manual exposure (V4L2_EXPOSURE_MANUAL).
            c.push("auto_exposure=1".to_string());
            c.push(format!("exposure_time_absolute={e}"));
        }
        if let Some(g) = self.gain {
            c.push(format!("gain={g}"));
        }
        c
    }

    /// Refuses a frame of another size than asked.
    pub fn check_size(&self, source: &CameraSource, got: [u32; 2]) -> Result<(), CameraError> {
        match self.size {
            Some(asked) if asked != got => Err(CameraError::Mode {
                source_name: source.name(),
                asked,
                got,
            }),
            _ => Ok(()),
        }
    }
}

/// Where the frame comes from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CameraSource {
    /// An image file (PNG, JPEG, BMP, TIFF), read directly.
    ImageFile(PathBuf),
    /// A V4L2 capture device, e.g. `/dev/video0`.
    Device(PathBuf),
    /// Anything else ffmpeg opens: a video file or a stream URL.
    Stream(String),
}

const IMAGE_EXTENSIONS: [&str; 6] = ["png", "jpg", "jpeg", "bmp", "tif", "tiff"];

impl CameraSource {
    /// Reads a `--camera` argument: `/dev/…` is a device, a path with an image extension an
    /// image file, anything else a stream.
    pub fn parse(s: &str) -> Self {
        let path = Path::new(s);
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        if s.starts_with("/dev/") {
            CameraSource::Device(path.to_path_buf())
        } else if ext.is_some_and(|e| IMAGE_EXTENSIONS.contains(&e.as_str())) {
            CameraSource::ImageFile(path.to_path_buf())
        } else {
            CameraSource::Stream(s.to_string())
        }
    }

    /// The source as the user wrote it, for messages.
    pub fn name(&self) -> String {
        match self {
            CameraSource::ImageFile(p) | CameraSource::Device(p) => p.display().to_string(),
            CameraSource::Stream(s) => s.clone(),
        }
    }
}

/// The ffmpeg binary used for devices and streams.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Ffmpeg(pub PathBuf);

impl Ffmpeg {
    /// `$CRACKBOT_FFMPEG`, else `ffmpeg` on `PATH`, else the binary of the `imageio-ffmpeg` wheel
    /// in `$CRACKBOT_CACHE_DIR` (default `~/.cache/crackbot`)`/ffmpeg-venv`; `None` if none.
    pub fn locate() -> Option<Ffmpeg> {
        if let Some(p) = std::env::var_os("CRACKBOT_FFMPEG") {
            return Some(Ffmpeg(PathBuf::from(p)));
        }
        if let Some(paths) = std::env::var_os("PATH") {
            for dir in std::env::split_paths(&paths) {
                let candidate = dir.join("ffmpeg");
                if candidate.is_file() {
                    return Some(Ffmpeg(candidate));
                }
            }
        }
        let cache = std::env::var_os("CRACKBOT_CACHE_DIR")
            .map(PathBuf::from)
            .or_else(|| {
                std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache/crackbot"))
            })?;
        let lib = cache.join("ffmpeg-venv/lib");
        for python in std::fs::read_dir(&lib).ok()?.filter_map(Result::ok) {
            let binaries = python.path().join("site-packages/imageio_ffmpeg/binaries");
            let Ok(entries) = std::fs::read_dir(&binaries) else {
                continue;
            };
            for e in entries.filter_map(Result::ok) {
                if e.file_name().to_string_lossy().starts_with("ffmpeg-") {
                    return Some(Ffmpeg(e.path()));
                }
            }
        }
        None
    }
}

/// How long a device or stream may take to give its first frame.
pub const DEFAULT_TIMEOUT: Duration = Duration::from_secs(15);

/// One RGB frame from `source` as it comes: [`grab`] with default [`CaptureOptions`].
pub fn grab_frame(
    source: &CameraSource,
    ffmpeg: Option<&Ffmpeg>,
    timeout: Duration,
) -> Result<RgbImage, CameraError> {
    grab(source, ffmpeg, &CaptureOptions::default(), timeout)
}

/// One RGB frame from `source` as `options` ask: image files are decoded directly; devices and
/// streams need `ffmpeg` ([`Ffmpeg::locate`] when `None`) and must give a frame within
/// `timeout`. A frame of another size than asked is refused.
pub fn grab(
    source: &CameraSource,
    ffmpeg: Option<&Ffmpeg>,
    options: &CaptureOptions,
    timeout: Duration,
) -> Result<RgbImage, CameraError> {
    let frame = grab_unchecked(source, ffmpeg, options, timeout)?;
    options.check_size(source, [frame.width(), frame.height()])?;
    Ok(frame)
}

/// Sets a device's exposure and gain through `v4l2-ctl` (nothing when none are asked).
fn set_controls(path: &Path, options: &CaptureOptions, name: &str) -> Result<(), CameraError> {
    let controls = options.controls();
    if controls.is_empty() {
        return Ok(());
    }
    let joined = controls.join(",");
    let fail = |message: String| CameraError::Control {
        source_name: name.to_string(),
        controls: joined.clone(),
        message,
    };
    let out = Command::new("v4l2-ctl")
        .arg("-d")
        .arg(path)
        .arg(format!("--set-ctrl={joined}"))
        .output()
        .map_err(|e| fail(format!("v4l2-ctl (Debian's v4l-utils) could not run: {e}")))?;
    if out.status.success() {
        Ok(())
    } else {
        Err(fail(
            String::from_utf8_lossy(&out.stderr).trim().to_string(),
        ))
    }
}

fn grab_unchecked(
    source: &CameraSource,
    ffmpeg: Option<&Ffmpeg>,
    options: &CaptureOptions,
    timeout: Duration,
) -> Result<RgbImage, CameraError> {
    let name = source.name();
    match source {
        CameraSource::ImageFile(path) => {
            return image::open(path)
                .map(|i| i.to_rgb8())
                .map_err(|e| CameraError::Decode {
                    source_name: name,
                    message: e.to_string(),
                });
        }
        CameraSource::Device(path) => {
            if !path.exists() {
                return Err(CameraError::NoFrame {
                    source_name: name,
                    message: "no such device".into(),
                });
            }
            set_controls(path, options, &name)?;
        }
        CameraSource::Stream(_) => {}
    }
    let input = options.input_args(source);
    let located;
    let ffmpeg = match ffmpeg {
        Some(f) => f,
        None => {
            located = Ffmpeg::locate().ok_or_else(|| CameraError::NoFfmpeg {
                source_name: name.clone(),
            })?;
            &located
        }
    };
    let mut child = Command::new(&ffmpeg.0)
        .args(["-nostdin", "-hide_banner", "-loglevel", "error"])
        .args(&input)
        .args(options.output_args(source))
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|error| CameraError::Spawn {
            source_name: name.clone(),
            ffmpeg: ffmpeg.0.clone(),
            error,
        })?;
    // Read both pipes on threads so a chatty ffmpeg never blocks on a full pipe.
    let mut stdout = child.stdout.take();
    let mut stderr = child.stderr.take();
    let out = std::thread::spawn(move || {
        let mut v = Vec::new();
        if let Some(s) = stdout.as_mut() {
            let _ = s.read_to_end(&mut v);
        }
        v
    });
    let err = std::thread::spawn(move || {
        let mut v = Vec::new();
        if let Some(s) = stderr.as_mut() {
            let _ = s.read_to_end(&mut v);
        }
        v
    });
    let deadline = Instant::now() + timeout;
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) if Instant::now() >= deadline => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(CameraError::Timeout {
                    source_name: name,
                    seconds: timeout.as_secs_f64(),
                });
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(10)),
            Err(e) => {
                return Err(CameraError::NoFrame {
                    source_name: name,
                    message: format!("waiting for ffmpeg: {e}"),
                })
            }
        }
    };
    let png = out.join().unwrap_or_default();
    let stderr = String::from_utf8_lossy(&err.join().unwrap_or_default())
        .trim()
        .to_string();
    if !status.success() || png.is_empty() {
        let message = if stderr.is_empty() {
            format!("ffmpeg exited with {status} and wrote no frame")
        } else {
            stderr
        };
        return Err(CameraError::NoFrame {
            source_name: name,
            message,
        });
    }
    image::load_from_memory_with_format(&png, image::ImageFormat::Png)
        .map(|i| i.to_rgb8())
        .map_err(|e| CameraError::Decode {
            source_name: name,
            message: format!("ffmpeg's frame: {e}"),
        })
}
