//! Crack-level recall of a crack map against a crack mask: each crack of the mask (an
//! 8-connected piece) is thinned to its centre line, and counts as found when the map, at the
//! detector's own threshold, lies within a small tolerance of most of that line. Unlike box
//! metrics this hangs on no box convention, and unlike pixel F1 a long crack and a short one
//! count the same: it says how many cracks the robot would be sent to touch.

use serde::Serialize;

use crate::VisionError;

/// The map's threshold: the detector's own (its pieces are cut there).
pub const MAP_THRESHOLD: f32 = 0.5;
/// How far from the centre line the map may lie and still cover it, pixels.
pub const TOLERANCE_PX: f64 = 2.0;
/// A crack is found when more than this share of its centre line is covered.
pub const COVERED_SHARE: f64 = 0.5;
/// Pieces of the mask with a centre line shorter than this are specks of annotation, not
/// cracks, pixels.
pub const MIN_LINE_PX: usize = 10;

/// Crack-level recall over a dataset.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CrackRecall {
    /// Images with a mask.
    pub images: usize,
    /// Cracks in the masks (pieces with a centre line of at least [`MIN_LINE_PX`]).
    pub cracks: usize,
    /// Of them, found.
    pub found: usize,
    /// `found / cracks` (1 when there are none).
    pub recall: f64,
    /// Pieces of the masks too short to count.
    pub specks: usize,
}

/// Accumulates images into a [`CrackRecall`].
#[derive(Debug, Clone, Default)]
pub struct CrackRecallEvaluator {
    images: usize,
    cracks: usize,
    found: usize,
    specks: usize,
}

/// Whether the map reaches [`MAP_THRESHOLD`] within [`TOLERANCE_PX`] of each pixel: the
/// thresholded map dilated by that disk (the crack map's own dilation).
fn covered(prob: &[f32], width: usize, height: usize) -> Vec<bool> {
    let hot: Vec<bool> = prob.iter().map(|p| *p >= MAP_THRESHOLD).collect();
    crate::crack_map::dilate(&hot, height, width, TOLERANCE_PX.floor() as usize)
}

impl CrackRecallEvaluator {
    /// Adds one image: `prob` (crack probabilities) and `truth` (crack mask), both `width ×
    /// height`, row-major. Errors when the sizes disagree.
    pub fn add(
        &mut self,
        prob: &[f32],
        truth: &[bool],
        width: usize,
        height: usize,
    ) -> Result<(), VisionError> {
        crate::error::check_sizes(prob.len(), truth.len(), width, height)?;
        let label = crate::crack_map::label_components(truth, height, width);
        let n = label.iter().copied().max().unwrap_or(0);
        let mut line = truth.to_vec();
        crackbot_imaging::thinning::thin(&mut line, width);
        let near = covered(prob, width, height);
        // Per piece: centre-line pixels, and those covered.
        let mut count = vec![[0usize; 2]; n as usize + 1];
        for i in (0..line.len()).filter(|&i| line[i]) {
            let c = &mut count[label[i] as usize];
            c[0] += 1;
            c[1] += usize::from(near[i]);
        }
        for &[len, hit] in &count[1..] {
            if len < MIN_LINE_PX {
                self.specks += 1;
                continue;
            }
            self.cracks += 1;
            self.found += usize::from(hit as f64 > COVERED_SHARE * len as f64);
        }
        self.images += 1;
        Ok(())
    }

    /// The recall of the images added so far (`None` before the first).
    pub fn finish(&self) -> Option<CrackRecall> {
        (self.images > 0).then(|| CrackRecall {
            images: self.images,
            cracks: self.cracks,
            found: self.found,
            recall: if self.cracks == 0 {
                1.0
            } else {
                self.found as f64 / self.cracks as f64
            },
            specks: self.specks,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const W: usize = 60;
    const H: usize = 40;

    /// A mask with two cracks (a horizontal band at rows 9–11 from x = 5 to 54, a vertical one at
    /// columns 39–41 from y = 20 to 37) and a speck at (2, 35).
    fn mask() -> Vec<bool> {
        let mut m = vec![false; W * H];
        for y in 9..=11 {
            for x in 5..=54 {
                m[y * W + x] = true;
            }
        }
        for y in 20..=37 {
            for x in 39..=41 {
                m[y * W + x] = true;
            }
        }
        m[35 * W + 2] = true;
        m
    }

    #[test]
    fn a_crack_is_found_when_the_map_covers_most_of_its_centre_line() {
        let truth = mask();
        // The map covers the horizontal crack from x = 5 to 40, shifted two rows up: found
        // (36 of ~50 line pixels within 2 px); the vertical one only from y = 20 to 25: missed.
        let mut prob = vec![0.1f32; W * H];
        for x in 5..=40 {
            prob[8 * W + x] = 0.9;
        }
        for y in 20..=25 {
            prob[y * W + 40] = 0.9;
        }
        let mut e = CrackRecallEvaluator::default();
        e.add(&prob, &truth, W, H).unwrap();
        let r = e.finish().unwrap();
        assert_eq!(
            (r.images, r.cracks, r.found, r.specks),
            (1, 2, 1, 1),
            "{r:?}"
        );
        assert!((r.recall - 0.5).abs() < 1e-12);
        // Under the threshold nothing is found; the whole map over it finds both.
        let mut e = CrackRecallEvaluator::default();
        e.add(&vec![0.49; W * H], &truth, W, H).unwrap();
        e.add(&vec![0.5; W * H], &truth, W, H).unwrap();
        let r = e.finish().unwrap();
        assert_eq!((r.cracks, r.found), (4, 2));
    }

    #[test]
    fn sizes_that_disagree_are_named_and_no_image_gives_nothing() {
        let mut e = CrackRecallEvaluator::default();
        assert!(e.finish().is_none());
        let err = e.add(&[0.0; 10], &[false; 12], 4, 3).unwrap_err();
        assert!(err.to_string().contains("crack map"), "{err}");
    }
}
