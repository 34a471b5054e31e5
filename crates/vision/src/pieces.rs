//! One crack, one candidate: how the pieces the robot touches ([`CrackPiece`], one stroke each)
//! fall on the true cracks of rendered frames.
//!
//! Each piece is assigned to the nearest crack or printed decoy whose centre line passes within
//! [`touch_tolerance_px`] of its touch point (or to nothing). Then each crack is one of:
//! * **one piece**: exactly one piece of its own (one stroke, one report);
//! * **in pieces**: two or more (the robot touches it twice and reports it twice);
//! * **joined**: none of its own, but a detection box holds it (by the
//!   [`crate::scene_recall`] test): its crack cells were merged into another crack's
//!   component and it lost its own touch;
//! * **missed**: neither.

use serde::Serialize;

use crate::crack_map::CrackPiece;
use crackbot_imaging::scene_truth::FrameTruth;

/// Distance from a piece's touch point to a centre line that still counts as on it, pixels
/// (the map's 2-pixel cells and the renderer's line both blur by about a pixel), plus half the
/// piece's width.
pub const TOUCH_TOLERANCE_PX: f64 = 4.0;

/// How far a piece's touch point may be from a centre line it belongs to, pixels.
pub fn touch_tolerance_px(piece: &CrackPiece) -> f64 {
    TOUCH_TOLERANCE_PX + 0.5 * f64::from(piece.width_px).max(0.0)
}

/// A crack that came out in pieces, or lost its own.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PieceCase {
    /// The image.
    pub file: String,
    /// The crack's box `[x, y, w, h]`.
    pub bbox: [f64; 4],
    /// Its width, mm.
    pub width_mm: Option<f64>,
    /// Pieces of its own.
    pub pieces: usize,
}

/// How the pieces fall on the cracks of a set of frames.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct PieceCounts {
    /// Visible cracks.
    pub cracks: usize,
    /// Cracks with exactly one piece of their own.
    pub one_piece: usize,
    /// Cracks with two or more.
    pub in_pieces: usize,
    /// Cracks with none of their own but inside a detection box (merged into another's).
    pub joined: usize,
    /// Cracks with neither.
    pub missed: usize,
    /// `one_piece / cracks`.
    pub one_piece_rate: f64,
    /// Pieces over all frames.
    pub pieces: usize,
    /// Pieces on a printed decoy.
    pub on_decoys: usize,
    /// Pieces on neither a crack nor a decoy (screws, bumps, texture).
    pub on_nothing: usize,
    /// The cracks in pieces or joined, for a look.
    pub cases: Vec<PieceCase>,
}

/// Distance from `p` to the polyline `path` (segments with an end behind the camera skipped).
fn distance_to_path(p: [f64; 2], path: &[Option<[f64; 2]>]) -> f64 {
    let mut best = f64::INFINITY;
    for seg in path.windows(2) {
        let (Some(a), Some(b)) = (seg[0], seg[1]) else {
            continue;
        };
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len2 = dx * dx + dy * dy;
        let t = if len2 > 0.0 {
            (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (qx, qy) = (a[0] + t * dx, a[1] + t * dy);
        best = best.min((p[0] - qx).hypot(p[1] - qy));
    }
    best
}

impl PieceCounts {
    /// Adds one frame: its truth, the pieces of every detection counted (at the `detect`
    /// threshold), and for each crack of `frame.boxes` whether a detection box holds it
    /// (`found`, by index into `frame.boxes`; ignored for other kinds).
    pub fn add_frame(&mut self, frame: &FrameTruth, pieces: &[CrackPiece], found: &[bool]) {
        let mut own = vec![0usize; frame.boxes.len()];
        for piece in pieces {
            self.pieces += 1;
            let touch = [f64::from(piece.touch[0]), f64::from(piece.touch[1])];
            let tol = touch_tolerance_px(piece);
            let nearest = frame
                .boxes
                .iter()
                .enumerate()
                .filter(|(_, f)| f.kind == "crack" || f.kind == "decoy")
                .filter_map(|(i, f)| {
                    let d = distance_to_path(touch, f.path_px.as_deref()?);
                    (d <= tol).then_some((i, d))
                })
                .min_by(|a, b| a.1.total_cmp(&b.1));
            match nearest {
                Some((i, _)) if frame.boxes[i].kind == "crack" => own[i] += 1,
                Some(_) => self.on_decoys += 1,
                None => self.on_nothing += 1,
            }
        }
        for (i, f) in frame.boxes.iter().enumerate() {
            if f.kind != "crack" {
                continue;
            }
            self.cracks += 1;
            let held = found.get(i).copied().unwrap_or(false);
            match (own[i], held) {
                (1, _) => self.one_piece += 1,
                (0, false) => self.missed += 1,
                (n, _) => {
                    if n == 0 {
                        self.joined += 1;
                    } else {
                        self.in_pieces += 1;
                    }
                    self.cases.push(PieceCase {
                        file: frame.file_name.clone(),
                        bbox: f.bbox,
                        width_mm: f.width_mm,
                        pieces: n,
                    });
                }
            }
        }
        if self.cracks > 0 {
            self.one_piece_rate = self.one_piece as f64 / self.cracks as f64;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene_recall::FeatureTruth;

    fn crack(kind: &str, path: &[[f64; 2]]) -> FeatureTruth {
        FeatureTruth {
            kind: kind.into(),
            feature_index: 0,
            bbox: [0.0, 0.0, 1.0, 1.0],
            pixels: 1,
            width_mm: Some(1.0),
            path_px: Some(path.iter().map(|&p| Some(p)).collect()),
            path_mm: None,
            centre_mm: None,
        }
    }

    fn piece(x: f32, y: f32) -> CrackPiece {
        CrackPiece {
            touch: [x, y],
            axis: [[x - 5.0, y], [x + 5.0, y]],
            length_px: 10.0,
            width_px: 2.0,
        }
    }

    #[test]
    fn cracks_are_one_piece_in_pieces_joined_or_missed() {
        let frame = FrameTruth {
            file_name: "a.png".into(),
            width: 200,
            height: 200,
            seed: 0,
            scene_seed: 0,
            material: "PLA".into(),
            plate_to_image: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            boxes: vec![
                crack("crack", &[[0.0, 10.0], [100.0, 10.0]]),
                crack("crack", &[[0.0, 50.0], [100.0, 50.0]]),
                crack("crack", &[[0.0, 90.0], [100.0, 90.0]]),
                crack("crack", &[[0.0, 150.0], [100.0, 150.0]]),
                crack("decoy", &[[0.0, 190.0], [100.0, 190.0]]),
            ],
        };
        let pieces = [
            piece(50.0, 12.0),  // on crack 0
            piece(20.0, 49.0),  // two on crack 1
            piece(80.0, 51.0),  //
            piece(50.0, 189.0), // on the decoy
            piece(50.0, 120.0), // on nothing
        ];
        let mut c = PieceCounts::default();
        c.add_frame(&frame, &pieces, &[true, true, true, false, true]);
        assert_eq!(
            (c.cracks, c.one_piece, c.in_pieces, c.joined, c.missed),
            (4, 1, 1, 1, 1)
        );
        assert_eq!((c.pieces, c.on_decoys, c.on_nothing), (5, 1, 1));
        assert_eq!(c.cases.len(), 2);
        assert!((c.one_piece_rate - 0.25).abs() < 1e-12);
    }

    #[test]
    fn the_distance_skips_points_behind_the_camera() {
        let path = [Some([0.0, 0.0]), None, Some([10.0, 0.0]), Some([20.0, 0.0])];
        assert!((distance_to_path([15.0, 3.0], &path) - 3.0).abs() < 1e-12);
        assert!(distance_to_path([0.0, 3.0], &[Some([0.0, 0.0]), None]).is_infinite());
    }
}
