//! Where a detected crack runs, in image pixels: its axis and centre line ([`CrackShape`]) and
//! the cracks it holds, where the finger should touch each ([`CrackPiece`]). Produced by the
//! crack map (`crack_map.rs`), carried by every [`crate::Detection`].

use serde::{Deserialize, Serialize};

/// Most points of a crack's centre-line polyline.
pub const MAX_POLYLINE_POINTS: usize = 9;

/// Where a detected crack runs, in image pixels.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CrackShape {
    /// The main axis: the two ends of the crack along its principal direction.
    pub axis: [[f32; 2]; 2],
    /// The centre line from one end to the other (2 to [`MAX_POLYLINE_POINTS`] points).
    pub polyline: Vec<[f32; 2]>,
    /// Length of the polyline, pixels.
    pub length_px: f32,
    /// The cracks the component holds, longest first, where the finger should touch each (see
    /// [`crate::crack_map`]); empty when none is at least [`crate::crack_map::MIN_PIECE_CELLS`] long.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub pieces: Vec<CrackPiece>,
}

/// One crack of a detection, where a stroke across it should go (image pixels).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CrackPiece {
    /// A point of its centre line near its middle, away from junctions with other cracks.
    pub touch: [f32; 2],
    /// Its direction at `touch`: the ends of a segment through `touch`, as long as the piece.
    pub axis: [[f32; 2]; 2],
    /// Length of its centre line, pixels.
    pub length_px: f32,
    /// Its width at `touch`: the run of crack cells across its direction there, pixels (a map
    /// cell's resolution).
    pub width_px: f32,
}
