//! The frame as the pinhole would see it: every pixel of the undistorted image looks up where
//! the lens puts that ray in the camera's frame (a map made once per lens and size, then a
//! bilinear lookup per frame), and the pixel → plate homography of that pinhole.
//!
//! Why undistort the frame rather than map detections through the lens: the crack detector was
//! trained on pinhole-like images (straight cracks look straight), its map is turned into pieces
//! and paths in pixel space, and everything downstream (planner, log, operator's drawing) works
//! with one homography; undistorting once per frame keeps all of that exact, for about a
//! millisecond per VGA frame.

use image::RgbImage;
use nalgebra::{Matrix3, Vector2};

use crate::lens::Lens;
use crate::pose::Pose;

/// The undistortion of one lens at one image size.
#[derive(Debug, Clone)]
pub struct Undistorter {
    width: u32,
    height: u32,
    /// For each output pixel, row by row: the source pixel's coordinates (crackbot's
    /// convention), or NaN where the ray falls outside the lens model.
    map: Vec<[f32; 2]>,
}

impl Undistorter {
    /// The map of `lens` for `size` images: output and input share the camera matrix.
    pub fn new(lens: &Lens, size: [u32; 2]) -> Undistorter {
        let [width, height] = size;
        let k = &lens.intrinsics;
        let mut map = Vec::with_capacity(width as usize * height as usize);
        for r in 0..height {
            for c in 0..width {
                let n = Vector2::new(
                    (f64::from(c) + 0.5 - k.cx) / k.fx,
                    (f64::from(r) + 0.5 - k.cy) / k.fy,
                );
                let d = lens.distortion.apply(n);
                let src = [k.fx * d.x + k.cx, k.fy * d.y + k.cy];
                map.push(if src[0].is_finite() && src[1].is_finite() {
                    [src[0] as f32, src[1] as f32]
                } else {
                    [f32::NAN; 2]
                });
            }
        }
        Undistorter { width, height, map }
    }

    /// The image size this map is for.
    pub fn size(&self) -> [u32; 2] {
        [self.width, self.height]
    }

    /// The undistorted frame (black where no pixel of `frame` is seen). `frame` must be of
    /// [`size`](Self::size); otherwise `None`.
    pub fn apply(&self, frame: &RgbImage) -> Option<RgbImage> {
        (frame.dimensions() == (self.width, self.height)).then(|| self.remap(frame))
    }

    /// [`apply`](Self::apply) for a frame whose size the caller checked.
    pub(crate) fn remap(&self, frame: &RgbImage) -> RgbImage {
        let (w, h) = (self.width as usize, self.height as usize);
        let src = frame.as_raw();
        let mut image = RgbImage::new(self.width, self.height);
        let out: &mut [u8] = &mut image;
        for (k, &[x, y]) in self.map.iter().enumerate() {
            // Pixel centres are at +0.5.
            let (fx, fy) = (x - 0.5, y - 0.5);
            if !(fx >= 0.0 && fy >= 0.0 && fx <= (w - 1) as f32 && fy <= (h - 1) as f32) {
                continue;
            }
            let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
            let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
            let (ax, ay) = (fx - x0 as f32, fy - y0 as f32);
            for ch in 0..3 {
                let at = |xx: usize, yy: usize| f32::from(src[(yy * w + xx) * 3 + ch]);
                let top = at(x0, y0) * (1.0 - ax) + at(x1, y0) * ax;
                let bottom = at(x0, y1) * (1.0 - ax) + at(x1, y1) * ax;
                out[k * 3 + ch] = (top * (1.0 - ay) + bottom * ay).round() as u8;
            }
        }
        image
    }
}

/// The homography from plate millimetres (z = 0 of the frame `pose` maps into the camera) to
/// pixels of the undistorted image of `lens`: `K [r1 r2 t]`.
pub fn plate_to_undistorted(lens: &Lens, pose: &Pose) -> Matrix3<f64> {
    let k = &lens.intrinsics;
    let km = Matrix3::new(k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0);
    let r = pose.rotation().into_inner();
    let t = pose.translation();
    km * Matrix3::from_columns(&[r.column(0).into_owned(), r.column(1).into_owned(), t])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lens::{Distortion, Intrinsics};
    use nalgebra::{Rotation3, Vector3};

    fn lens() -> Lens {
        Lens {
            intrinsics: Intrinsics {
                fx: 500.0,
                fy: 505.0,
                cx: 160.0,
                cy: 120.0,
            },
            distortion: Distortion {
                k1: -0.3,
                k2: 0.09,
                p1: 0.001,
                p2: -0.0005,
                k3: 0.0,
            },
        }
    }

    #[test]
    fn a_point_seen_through_the_lens_lands_where_the_pinhole_puts_it() {
        let lens = lens();
        // A frame with one bright blob where the lens sees the camera-frame point p.
        let p = Vector3::new(40.0, -25.0, 200.0);
        let seen = lens.project(p).unwrap();
        let frame = RgbImage::from_fn(320, 240, |c, r| {
            let d = (f64::from(c) + 0.5 - seen[0]).hypot(f64::from(r) + 0.5 - seen[1]);
            let v = (255.0 * (-d * d / 8.0).exp()) as u8;
            image::Rgb([v, v, v])
        });
        let out = Undistorter::new(&lens, [320, 240]).apply(&frame).unwrap();
        let k = &lens.intrinsics;
        let ideal = [k.fx * p.x / p.z + k.cx, k.fy * p.y / p.z + k.cy];
        // The centroid of the blob in the undistorted frame.
        let (mut sx, mut sy, mut s) = (0.0, 0.0, 0.0);
        for (c, r, px) in out.enumerate_pixels() {
            let v = f64::from(px[0]);
            sx += v * (f64::from(c) + 0.5);
            sy += v * (f64::from(r) + 0.5);
            s += v;
        }
        let (cx, cy) = (sx / s, sy / s);
        assert!(
            (cx - ideal[0]).hypot(cy - ideal[1]) < 0.15,
            "{cx},{cy} vs {ideal:?}"
        );
        assert!(Undistorter::new(&lens, [320, 240])
            .apply(&RgbImage::new(10, 10))
            .is_none());
    }

    #[test]
    fn the_plate_homography_is_the_pinhole_projection_of_the_plate() {
        let lens = lens();
        let pose = Pose::new(
            &Rotation3::from_euler_angles(3.0, 0.1, 0.2),
            Vector3::new(-50.0, 30.0, 300.0),
        );
        let h = plate_to_undistorted(&lens, &pose);
        for q in [[0.0, 0.0], [80.0, -40.0], [-30.0, 60.0]] {
            let pc = pose.apply(Vector3::new(q[0], q[1], 0.0));
            let k = &lens.intrinsics;
            let want = [k.fx * pc.x / pc.z + k.cx, k.fy * pc.y / pc.z + k.cy];
            let v = h * Vector3::new(q[0], q[1], 1.0);
            assert!((v.x / v.z - want[0]).abs() < 1e-9 && (v.y / v.z - want[1]).abs() < 1e-9);
        }
    }
}
