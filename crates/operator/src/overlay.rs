//! Overlay geometry: surface millimetres → pixels of the frame → points of the screen rectangle
//! the frame is drawn in.

use crackbot_telemetry::wire::CameraFrame;

/// Where surface point `mm` lands on the screen when the frame is drawn scaled into the
/// rectangle `[min, max]` (`None`: behind the camera).
pub fn mm_to_screen(
    frame: &CameraFrame,
    mm: [f64; 2],
    min: [f32; 2],
    max: [f32; 2],
) -> Option<[f32; 2]> {
    let px = frame.to_pixel(mm)?;
    if frame.width == 0 || frame.height == 0 {
        return None;
    }
    let sx = (max[0] - min[0]) as f64 / frame.width as f64;
    let sy = (max[1] - min[1]) as f64 / frame.height as f64;
    let p = [min[0] + (px[0] * sx) as f32, min[1] + (px[1] * sy) as f32];
    p.iter().all(|v| v.is_finite()).then_some(p)
}

/// The largest size with the frame's aspect ratio that fits in `avail`.
pub fn fit(width: u32, height: u32, avail: [f32; 2]) -> [f32; 2] {
    if width == 0 || height == 0 {
        return [0.0, 0.0];
    }
    let s = (avail[0] / width as f32)
        .min(avail[1] / height as f32)
        .max(0.0);
    [width as f32 * s, height as f32 * s]
}

/// A homography that maps the workspace rectangle onto the whole frame (replays of reports
/// that do not carry the camera's own homography).
pub fn workspace_to_frame(ws: [f64; 4], width: u32, height: u32) -> [[f64; 3]; 3] {
    let [x0, x1, y0, y1] = ws;
    let sx = width as f64 / (x1 - x0).max(1e-9);
    let sy = height as f64 / (y1 - y0).max(1e-9);
    [[sx, 0.0, -x0 * sx], [0.0, sy, -y0 * sy], [0.0, 0.0, 1.0]]
}

/// The two ends of a segment of `length_mm` through `centre_mm` at `axis_deg` from +x.
pub fn segment(centre_mm: [f64; 2], axis_deg: f64, length_mm: f64) -> [[f64; 2]; 2] {
    let (s, c) = axis_deg.to_radians().sin_cos();
    let h = length_mm / 2.0;
    [
        [centre_mm[0] - c * h, centre_mm[1] - s * h],
        [centre_mm[0] + c * h, centre_mm[1] + s * h],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(h: [[f64; 3]; 3]) -> CameraFrame {
        CameraFrame {
            width: 400,
            height: 200,
            surface_to_image: h,
            png: Vec::new(),
        }
    }

    #[test]
    fn the_workspace_corners_land_on_the_drawn_frames_corners() {
        let f = frame(workspace_to_frame([0.0, 200.0, 0.0, 100.0], 400, 200));
        let p = mm_to_screen(&f, [200.0, 100.0], [10.0, 20.0], [210.0, 120.0]);
        assert_eq!(p, Some([210.0, 120.0]));
        let p = mm_to_screen(&f, [0.0, 0.0], [10.0, 20.0], [210.0, 120.0]);
        assert_eq!(p, Some([10.0, 20.0]));
        let p = mm_to_screen(&f, [100.0, 50.0], [10.0, 20.0], [210.0, 120.0]);
        assert_eq!(p, Some([110.0, 70.0]));
    }

    #[test]
    fn a_point_behind_the_camera_is_not_drawn() {
        let f = frame([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]]);
        assert_eq!(mm_to_screen(&f, [1.0, 1.0], [0.0, 0.0], [1.0, 1.0]), None);
    }

    #[test]
    fn fit_keeps_the_aspect_ratio() {
        assert_eq!(fit(640, 480, [320.0, 1000.0]), [320.0, 240.0]);
        assert_eq!(fit(640, 480, [1000.0, 240.0]), [320.0, 240.0]);
        assert_eq!(fit(0, 480, [10.0, 10.0]), [0.0, 0.0]);
    }

    #[test]
    fn a_segment_is_centred_on_its_axis() {
        let [a, b] = segment([10.0, 10.0], 90.0, 4.0);
        assert!((a[0] - 10.0).abs() < 1e-9 && (a[1] - 8.0).abs() < 1e-9);
        assert!((b[0] - 10.0).abs() < 1e-9 && (b[1] - 12.0).abs() < 1e-9);
    }
}
