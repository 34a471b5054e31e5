//! The camera calibration file: TOML, written by `crackbot calibrate camera` (the lens) and
//! `crackbot calibrate surface` (the plate's pose), read by the mission. The format is specified
//! in `crates/calib/docs/calibration-file.md`, so that any tool can read or write it.

use std::path::{Path, PathBuf};

use image::RgbImage;
use serde::{Deserialize, Serialize};

use crate::lens::{Distortion, Intrinsics, Lens};
use crate::pose::Pose;
use crate::undistort::Undistorter;

/// The value of `format` this version reads and writes.
pub const FORMAT: &str = "crackbot-camera-calibration/1";
/// The one lens model: OpenCV's pinhole with k1, k2, p1, p2, k3.
pub const MODEL: &str = "opencv-pinhole-k1k2p1p2k3";

/// Why a calibration file cannot be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FileError {
    /// The file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// Not TOML, or a key missing, unknown or of the wrong type.
    #[error("{}: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// The parser's words (with line and column).
        message: String,
    },
    /// A value out of its range.
    #[error("{}: {field} = {value}: {expected}", path.display())]
    Field {
        /// The file.
        path: PathBuf,
        /// The key, with its table.
        field: &'static str,
        /// The value found.
        value: String,
        /// What it must be.
        expected: &'static str,
    },
    /// A frame of another size than the calibration's.
    #[error(
        "{}: calibrated for {}×{} px images, but the camera gives {}×{} px; calibrate this mode \
         (crackbot calibrate camera) or ask the camera for {}×{}",
        path.display(), calibrated[0], calibrated[1], frame[0], frame[1], calibrated[0], calibrated[1]
    )]
    ImageSize {
        /// The file.
        path: PathBuf,
        /// Its image size.
        calibrated: [u32; 2],
        /// The frame's.
        frame: [u32; 2],
    },
    /// A calibration without the plate's pose used where the pose is needed.
    #[error("{}: no [surface] table: run `crackbot calibrate surface` with the target on the plate", path.display())]
    NoSurface {
        /// The file.
        path: PathBuf,
    },
}

/// `[image]`: the size the lens was calibrated at.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImageSize {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
}

/// `[lens]`: the model, its parameters and how well they fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LensTable {
    /// [`MODEL`].
    pub model: String,
    /// `[[fx, 0, cx], [0, fy, cy], [0, 0, 1]]`, pixels (OpenCV's camera matrix).
    pub camera_matrix: [[f64; 3]; 3],
    /// `[k1, k2, p1, p2, k3]` (OpenCV's order).
    pub distortion: [f64; 5],
    /// RMS reprojection error of the calibration, pixels.
    pub rms_px: f64,
    /// Views it was fitted from.
    pub views: u32,
}

/// `[surface]`: the plate's pose in the camera frame (plate → camera).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceTable {
    /// Rotation vector, radians (OpenCV's `rvec`).
    pub rotation: [f64; 3],
    /// The plate's origin in the camera frame, mm (OpenCV's `tvec`).
    pub translation_mm: [f64; 3],
    /// RMS reprojection error of the target on the plate, pixels.
    pub rms_px: f64,
}

/// A whole calibration file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraFile {
    /// [`FORMAT`].
    pub format: String,
    /// When it was made (RFC 3339, UTC).
    pub date: String,
    /// Pixel coordinates' origin: `"corner"` (crackbot's: (0, 0) is the top-left corner of the
    /// top-left pixel) or `"centre"` (OpenCV's: its centre). The matrix is in this convention.
    pub pixel_origin: String,
    /// The image size.
    pub image: ImageSize,
    /// The lens.
    pub lens: LensTable,
    /// The plate's pose, once `calibrate surface` ran.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface: Option<SurfaceTable>,
}

impl CameraFile {
    /// A file for `lens` calibrated at `size` from `views` views with `rms_px`, dated `date`.
    pub fn new(lens: &Lens, size: [u32; 2], views: u32, rms_px: f64, date: String) -> Self {
        let k = &lens.intrinsics;
        CameraFile {
            format: FORMAT.into(),
            date,
            pixel_origin: "corner".into(),
            image: ImageSize {
                width: size[0],
                height: size[1],
            },
            lens: LensTable {
                model: MODEL.into(),
                camera_matrix: [[k.fx, 0.0, k.cx], [0.0, k.fy, k.cy], [0.0, 0.0, 1.0]],
                distortion: lens.distortion.to_array(),
                rms_px,
                views,
            },
            surface: None,
        }
    }

    /// The lens.
    pub fn lens(&self) -> Lens {
        let m = &self.lens.camera_matrix;
        Lens {
            intrinsics: Intrinsics {
                fx: m[0][0],
                fy: m[1][1],
                cx: m[0][2],
                cy: m[1][2],
            },
            distortion: Distortion::from_array(self.lens.distortion),
        }
    }

    /// The plate's pose (plate → camera), if the surface was calibrated.
    pub fn surface_pose(&self) -> Option<Pose> {
        self.surface.as_ref().map(|s| Pose {
            rotation: s.rotation,
            translation: s.translation_mm,
        })
    }

    /// Reads and checks a file.
    pub fn load(path: &Path) -> Result<CameraFile, FileError> {
        let text = std::fs::read_to_string(path).map_err(|source| FileError::Io {
            path: path.into(),
            source,
        })?;
        let file: CameraFile = toml::from_str(&text).map_err(|e| FileError::Parse {
            path: path.into(),
            message: e.to_string(),
        })?;
        file.check(path)?;
        Ok(file)
    }

    /// Writes the file (with a comment naming its specification).
    pub fn save(&self, path: &Path) -> Result<(), FileError> {
        let body = toml::to_string(self).map_err(|e| FileError::Parse {
            path: path.into(),
            message: e.to_string(),
        })?;
        let text = format!(
            "# crackbot camera calibration; the format: crates/calib/docs/calibration-file.md\n{body}"
        );
        std::fs::write(path, text).map_err(|source| FileError::Io {
            path: path.into(),
            source,
        })
    }

    /// Every value in its range.
    pub fn check(&self, path: &Path) -> Result<(), FileError> {
        let bad = |field, value: String, expected| FileError::Field {
            path: path.into(),
            field,
            value,
            expected,
        };
        if self.format != FORMAT {
            return Err(bad(
                "format",
                format!("{:?}", self.format),
                "\"crackbot-camera-calibration/1\"",
            ));
        }
        if self.lens.model != MODEL {
            return Err(bad(
                "lens.model",
                format!("{:?}", self.lens.model),
                "\"opencv-pinhole-k1k2p1p2k3\" (the only model this version reads)",
            ));
        }
        if !matches!(self.pixel_origin.as_str(), "corner" | "centre") {
            return Err(bad(
                "pixel_origin",
                format!("{:?}", self.pixel_origin),
                "\"corner\" or \"centre\"",
            ));
        }
        if self.image.width == 0 || self.image.height == 0 {
            let size = format!("{}×{}", self.image.width, self.image.height);
            return Err(bad("image", size, "width and height > 0"));
        }
        let m = &self.lens.camera_matrix;
        let finite = m.iter().flatten().all(|v| v.is_finite());
        let shape = m[0][1] == 0.0 && m[1][0] == 0.0 && m[2] == [0.0, 0.0, 1.0];
        if !(finite && shape && m[0][0] > 0.0 && m[1][1] > 0.0) {
            return Err(bad(
                "lens.camera_matrix",
                format!("{m:?}"),
                "[[fx, 0, cx], [0, fy, cy], [0, 0, 1]] with fx, fy > 0, all finite",
            ));
        }
        if !self.lens.distortion.iter().all(|v| v.is_finite()) {
            return Err(bad(
                "lens.distortion",
                format!("{:?}", self.lens.distortion),
                "finite",
            ));
        }
        if !(self.lens.rms_px.is_finite() && self.lens.rms_px >= 0.0) {
            return Err(bad("lens.rms_px", self.lens.rms_px.to_string(), "≥ 0"));
        }
        if let Some(s) = &self.surface {
            let finite = s
                .rotation
                .iter()
                .chain(&s.translation_mm)
                .all(|v| v.is_finite());
            if !finite || s.translation_mm[2] <= 0.0 {
                return Err(bad(
                    "surface",
                    format!(
                        "rotation {:?}, translation_mm {:?}",
                        s.rotation, s.translation_mm
                    ),
                    "finite, the plate in front of the camera (translation_mm z > 0)",
                ));
            }
        }
        Ok(())
    }

    /// `frame` as the lens's pinhole sees it ([`crate::Undistorter`]); a frame of another size
    /// than the calibration's is refused (`path` named).
    pub fn undistort(&self, path: &Path, frame: &RgbImage) -> Result<RgbImage, FileError> {
        self.check_frame(path, frame.width(), frame.height())?;
        let size = [self.image.width, self.image.height];
        Ok(Undistorter::new(&self.lens(), size).remap(frame))
    }

    /// Refuses a frame of another size than the calibration's.
    pub fn check_frame(&self, path: &Path, width: u32, height: u32) -> Result<(), FileError> {
        if [width, height] == [self.image.width, self.image.height] {
            Ok(())
        } else {
            Err(FileError::ImageSize {
                path: path.into(),
                calibrated: [self.image.width, self.image.height],
                frame: [width, height],
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> CameraFile {
        let lens = Lens {
            intrinsics: Intrinsics {
                fx: 920.0,
                fy: 915.0,
                cx: 652.0,
                cy: 351.0,
            },
            distortion: Distortion::from_array([-0.3, 0.09, 0.001, -0.0008, 0.0]),
        };
        let mut f = CameraFile::new(&lens, [1280, 720], 20, 0.14, "2026-12-07T19:10:00Z".into());
        f.surface = Some(SurfaceTable {
            rotation: [3.0, 0.1, 0.2],
            translation_mm: [-90.0, -60.0, 400.0],
            rms_px: 0.12,
        });
        f
    }

    #[test]
    fn a_file_round_trips_and_gives_its_lens_back() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("camera.toml");
        let f = sample();
        f.save(&path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.starts_with("# crackbot camera calibration"), "{text}");
        let back = CameraFile::load(&path).unwrap();
        assert_eq!(back, f);
        assert_eq!(back.lens().distortion.k1, -0.3);
        assert_eq!(back.surface_pose().unwrap().translation[2], 400.0);
    }

    #[test]
    fn a_frame_of_another_size_is_refused_naming_both() {
        let err = sample()
            .check_frame(Path::new("camera.toml"), 1920, 1080)
            .unwrap_err();
        let text = err.to_string();
        assert!(
            text.contains("1280×720") && text.contains("1920×1080"),
            "{text}"
        );
        sample()
            .check_frame(Path::new("camera.toml"), 1280, 720)
            .unwrap();
    }

    #[test]
    fn bad_files_name_what_is_wrong() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("camera.toml");
        type Spoil<'a> = &'a dyn Fn(&mut CameraFile);
        let cases: [(Spoil, &str); 5] = [
            (&|f| f.lens.model = "fisheye".into(), "lens.model"),
            (&|f| f.format = "v0".into(), "format"),
            (&|f| f.image.width = 0, "image"),
            (&|f| f.lens.camera_matrix[0][0] = -1.0, "lens.camera_matrix"),
            (&|f| f.lens.distortion[1] = f64::NAN, "lens.distortion"),
        ];
        for (spoil, field) in cases {
            let mut f = sample();
            spoil(&mut f);
            // NaN cannot be written as TOML by every writer: check the value directly too.
            let err = f.check(&path).unwrap_err().to_string();
            assert!(err.contains(field), "{err}");
        }
        std::fs::write(&path, "format = 3\n[lens\n").unwrap();
        assert!(matches!(
            CameraFile::load(&path),
            Err(FileError::Parse { .. })
        ));
        std::fs::write(&path, "this is not a calibration").unwrap();
        let err = CameraFile::load(&path).unwrap_err().to_string();
        assert!(err.contains("camera.toml"), "{err}");
        let missing = CameraFile::load(&dir.path().join("none.toml")).unwrap_err();
        assert!(matches!(missing, FileError::Io { .. }));
    }
}
