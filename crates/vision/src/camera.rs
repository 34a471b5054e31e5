//! One camera frame from wherever the robot's camera is: an image file, a live V4L2 device
//! (`/dev/video0`, a webcam), or a video file or stream URL (`rtsp://…`, a recorded `.mkv`).
//!
//! Image files are read directly. Devices and streams go through an `ffmpeg` process (the
//! well-kept tool for every camera format and codec; V4L2 capture included), which writes one
//! lossless PNG frame to a pipe: nothing is linked in, and a camera that hangs is killed after a
//! deadline. `ffmpeg` is found at `$CRACKBOT_FFMPEG`, on `PATH`, or in the `imageio-ffmpeg`
//! wheel that `scripts/setup.sh` installs under `~/.cache/crackbot/ffmpeg-venv`.

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
    /// The image file or the frame could not be decoded.
    #[error("{source_name}: {message}")]
    Decode {
        /// The camera source.
        source_name: String,
        /// The decoder's words.
        message: String,
    },
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

/// One RGB frame from `source`: image files are decoded directly; devices and streams need
/// `ffmpeg` ([`Ffmpeg::locate`] when `None`) and must give a frame within `timeout`.
pub fn grab_frame(
    source: &CameraSource,
    ffmpeg: Option<&Ffmpeg>,
    timeout: Duration,
) -> Result<RgbImage, CameraError> {
    let name = source.name();
    let input: Vec<String> = match source {
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
            vec!["-f".into(), "v4l2".into(), "-i".into(), name.clone()]
        }
        CameraSource::Stream(s) => vec!["-i".into(), s.clone()],
    };
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
        .args(["-frames:v", "1", "-f", "image2pipe", "-c:v", "png", "-"])
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
