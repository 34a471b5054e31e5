//! Finding the target in a camera image with the AprilTag library (tag36h11, full resolution,
//! edge refinement) and turning what it finds into a [`View`] for `crackbot-calib`.
//!
//! Pixels follow crackbot's convention, the library's too: the top-left corner of the image is
//! `(0, 0)` and a pixel's centre is at `+0.5`.

use apriltag::{Detector, DetectorBuilder, Family, Image};
use crackbot_calib::View;
use image::GrayImage;

use crate::error::TargetError;
use crate::spec::TargetSpec;

/// The tag coordinates of AprilTag's four detected corners, in its order.
const CORNERS: [[f64; 2]; 4] = [[-1.0, 1.0], [1.0, 1.0], [1.0, -1.0], [-1.0, -1.0]];

/// A tag of the target found in an image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FoundTag {
    /// Its id.
    pub id: u32,
    /// Its black square's corners, pixels (AprilTag's order).
    pub corners_px: [[f64; 2]; 4],
    /// The same corners in the target's frame, mm.
    pub corners_mm: [[f64; 2]; 4],
    /// The library's decision margin (higher: clearer).
    pub margin: f32,
}

/// What was found in one image.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Found {
    /// The target's tags that were found, by id.
    pub tags: Vec<FoundTag>,
    /// Ids of tag36h11 tags seen that are not on this target (another target, a stray tag).
    pub strangers: Vec<u32>,
    /// Ids of the target's tags left out because their white ring is cut by the frame's edge
    /// (their corners are then found off by pixels).
    pub clipped: Vec<u32>,
}

impl Found {
    /// The tags' corners as a view of the target (four points a tag).
    pub fn view(&self) -> View {
        let mut view = View::default();
        for t in &self.tags {
            view.target.extend_from_slice(&t.corners_mm);
            view.image.extend_from_slice(&t.corners_px);
        }
        view
    }
}

/// The AprilTag detector, set up for calibration.
pub struct TagFinder {
    detector: Detector,
}

impl TagFinder {
    /// A detector for tag36h11 with no bit errors corrected (a calibration wants no doubtful
    /// tags), no decimation and refined edges.
    pub fn new() -> Result<TagFinder, TargetError> {
        let mut detector = DetectorBuilder::new()
            .add_family_bits(Family::tag_36h11(), 0)
            .build()
            .map_err(|e| TargetError::Detector {
                message: e.to_string(),
            })?;
        detector.set_decimation(1.0);
        detector.set_sigma(0.0);
        detector.set_refine_edges(true);
        detector.set_thread_number(1);
        Ok(TagFinder { detector })
    }

    /// The tags of `spec` in `image`.
    pub fn find(&mut self, image: &GrayImage, spec: &TargetSpec) -> Result<Found, TargetError> {
        let (w, h) = (image.width() as usize, image.height() as usize);
        let mut img = Image::zeros_with_alignment(w, h, 96).map_err(|e| TargetError::Detector {
            message: e.to_string(),
        })?;
        let stride = img.stride();
        let buf = img.as_slice_mut();
        for (r, row) in image.as_raw().chunks_exact(w).enumerate() {
            buf[r * stride..r * stride + w].copy_from_slice(row);
        }
        let mut found = Found::default();
        for d in self.detector.detect(&img) {
            let id = d.id() as u32;
            let Some(place) = spec.tag(id) else {
                found.strangers.push(id);
                continue;
            };
            if clipped(&d.corners(), w as f64, h as f64) {
                found.clipped.push(id);
                continue;
            }
            found.tags.push(FoundTag {
                id,
                corners_px: d.corners(),
                corners_mm: CORNERS.map(|t| spec.tag_point(&place, t)),
                margin: d.decision_margin(),
            });
        }
        found.tags.sort_by_key(|t| t.id);
        found.strangers.sort_unstable();
        found.clipped.sort_unstable();
        Ok(found)
    }
}

/// Whether a tag with these corners comes closer to the frame's edge than its white ring's
/// width and a half (a cell is an eighth of its side) plus two pixels.
fn clipped(corners: &[[f64; 2]; 4], w: f64, h: f64) -> bool {
    let side = (0..4)
        .map(|k| {
            let (a, b) = (corners[k], corners[(k + 1) % 4]);
            (a[0] - b[0]).hypot(a[1] - b[1])
        })
        .sum::<f64>()
        / 4.0;
    let keep_out = 1.5 * side / 8.0 + 2.0;
    corners
        .iter()
        .any(|c| c[0] < keep_out || c[1] < keep_out || c[0] > w - keep_out || c[1] > h - keep_out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::print::draw;

    #[test]
    fn every_tag_of_the_printed_sheet_is_found_at_its_corners() {
        let spec = TargetSpec::default();
        let ppm = 4.0;
        let img = draw(&spec, ppm);
        let found = TagFinder::new().unwrap().find(&img, &spec).unwrap();
        assert_eq!(found.tags.len(), 32, "{found:?}");
        assert!(found.strangers.is_empty() && found.clipped.is_empty());
        let (lo, hi) = spec.sheet_mm();
        let mut worst: f64 = 0.0;
        for t in &found.tags {
            for (px, mm) in t.corners_px.iter().zip(&t.corners_mm) {
                // The sheet is drawn black or white by each pixel's centre: an edge lands on
                // the nearest pixel boundary.
                let truth = [
                    ((mm[0] - lo[0]) * ppm).round(),
                    ((hi[1] - mm[1]) * ppm).round(),
                ];
                worst = worst.max((px[0] - truth[0]).hypot(px[1] - truth[1]));
            }
        }
        assert!(
            worst < 0.3,
            "corners {worst:.3} px from where they are printed"
        );
        assert_eq!(found.view().target.len(), 128);
    }

    #[test]
    fn tags_cut_by_the_frame_are_left_out() {
        let spec = TargetSpec::default();
        let img = draw(&spec, 4.0);
        // Crop into the left column's tags' white rings.
        let (lo, _) = spec.sheet_mm();
        let x0 = ((0.5 * spec.cell_mm() - lo[0]) * 4.0) as u32;
        let cropped =
            image::imageops::crop_imm(&img, x0, 0, img.width() - x0, img.height()).to_image();
        let found = TagFinder::new().unwrap().find(&cropped, &spec).unwrap();
        assert_eq!(found.tags.len(), 28, "{found:?}");
        assert!(found.tags.iter().all(|t| t.id % 8 != 0), "{found:?}");
    }
}
