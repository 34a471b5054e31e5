//! The target's geometry: a grid of tag36h11 tags on a sheet, as a TOML table, checked once.
//!
//! The target's frame (millimetres, on the printed face): the origin is the outer corner of the
//! black square of the bottom-left tag, `x` runs right along the bottom row and `y` up the sheet,
//! `z` out of the printed face. Laid face up on the plate with its bottom edge along the plate's
//! `x` axis, the target's axes are the plate's. Tag `first_id + row · cols + col` has its black
//! square at `[col · pitch, col · pitch + tag] × [row · pitch, row · pitch + tag]`, `pitch = tag +
//! gap`, row 0 at the bottom.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::TargetError;
use crate::family::{pattern, tag_count, BORDER_CELLS, TOTAL_CELLS};

/// A grid of AprilTags as written in `target.toml` (see `docs/target.md`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TargetSpec {
    /// The tag family; only `"tag36h11"`.
    pub family: String,
    /// Tags across (along `x`).
    pub cols: u32,
    /// Tags up (along `y`).
    pub rows: u32,
    /// Side of each tag's black square, mm (the corners detected are its corners).
    pub tag_mm: f64,
    /// White space between neighbouring black squares, mm (at least a quarter of `tag_mm`, so
    /// each tag keeps its white ring).
    pub gap_mm: f64,
    /// The id of the bottom-left tag; the others follow row by row.
    pub first_id: u32,
    /// White paper around the grid, mm (at least a quarter of `tag_mm`).
    pub margin_mm: f64,
}

impl Default for TargetSpec {
    /// 8 × 4 tags of 18 mm with 5.4 mm gaps: 181.8 × 88.2 mm, which fits the papers' 200 × 100 mm
    /// plate (and an A4 sheet) with a margin.
    fn default() -> Self {
        TargetSpec {
            family: "tag36h11".to_string(),
            cols: 8,
            rows: 4,
            tag_mm: 18.0,
            gap_mm: 5.4,
            first_id: 0,
            margin_mm: 5.0,
        }
    }
}

/// One printed tag: its id and its black square's corners in the target's frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TagPlace {
    /// The tag's id in the family.
    pub id: u32,
    /// Column (0 at the left).
    pub col: u32,
    /// Row (0 at the bottom).
    pub row: u32,
    /// The black square's bottom-left corner, mm.
    pub origin_mm: [f64; 2],
}

impl TargetSpec {
    /// Checks every field, naming the first that is wrong.
    pub fn check(&self) -> Result<(), TargetError> {
        let bad = |field: &'static str, value: String, expected: &str| {
            Err(TargetError::Invalid {
                field,
                value,
                expected: expected.to_string(),
            })
        };
        if self.family != "tag36h11" {
            return bad("family", format!("{:?}", self.family), "\"tag36h11\"");
        }
        if self.cols == 0 || self.rows == 0 {
            return bad(
                "cols × rows",
                format!("{} × {}", self.cols, self.rows),
                "at least one tag",
            );
        }
        if !(self.tag_mm.is_finite() && self.tag_mm > 0.0) {
            return bad("tag_mm", self.tag_mm.to_string(), "a positive length");
        }
        let ring = self.cell_mm() * (TOTAL_CELLS - BORDER_CELLS) as f64;
        if !(self.gap_mm.is_finite() && self.gap_mm >= ring - 1e-9) {
            return bad(
                "gap_mm",
                self.gap_mm.to_string(),
                &format!("at least tag_mm / 4 = {ring} (each tag's white ring)"),
            );
        }
        if !(self.margin_mm.is_finite() && self.margin_mm >= ring / 2.0 - 1e-9) {
            return bad(
                "margin_mm",
                self.margin_mm.to_string(),
                &format!("at least tag_mm / 8 = {} (the white ring)", ring / 2.0),
            );
        }
        let last = u64::from(self.first_id) + u64::from(self.cols) * u64::from(self.rows);
        if last > tag_count() as u64 {
            return bad(
                "first_id, cols × rows",
                format!("ids {} to {}", self.first_id, last - 1),
                &format!("ids below {} (the tag36h11 family's size)", tag_count()),
            );
        }
        Ok(())
    }

    /// Reads and checks a target file.
    pub fn load(path: &Path) -> Result<TargetSpec, TargetError> {
        let text = std::fs::read_to_string(path).map_err(|source| TargetError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let spec: TargetSpec = toml::from_str(&text).map_err(|e| TargetError::Parse {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        spec.check()?;
        Ok(spec)
    }

    /// Writes the target file (TOML).
    pub fn save(&self, path: &Path) -> Result<(), TargetError> {
        let text = toml::to_string(self).map_err(|e| TargetError::Parse {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        let text = format!(
            "# crackbot calibration target: tag36h11 AprilTags; see crates/calib-target/docs/target.md\n{text}"
        );
        std::fs::write(path, text).map_err(|source| TargetError::Io {
            path: path.to_path_buf(),
            source,
        })
    }

    /// Side of one cell of a tag's pattern, mm.
    pub fn cell_mm(&self) -> f64 {
        self.tag_mm / BORDER_CELLS as f64
    }

    /// Distance between neighbouring tags' origins, mm.
    pub fn pitch_mm(&self) -> f64 {
        self.tag_mm + self.gap_mm
    }

    /// The grid's extent (black squares only), mm `[width, height]`.
    pub fn grid_mm(&self) -> [f64; 2] {
        let side =
            |n: u32| f64::from(n) * self.tag_mm + f64::from(n.saturating_sub(1)) * self.gap_mm;
        [side(self.cols), side(self.rows)]
    }

    /// The sheet's extent, margins included, as `(min, max)` corners in the target's frame.
    pub fn sheet_mm(&self) -> ([f64; 2], [f64; 2]) {
        let [w, h] = self.grid_mm();
        let m = self.margin_mm;
        ([-m, -m], [w + m, h + m])
    }

    /// Every tag of the target, row by row from the bottom.
    pub fn tags(&self) -> impl Iterator<Item = TagPlace> + '_ {
        (0..self.rows).flat_map(move |row| {
            (0..self.cols).map(move |col| TagPlace {
                id: self.first_id + row * self.cols + col,
                col,
                row,
                origin_mm: [
                    f64::from(col) * self.pitch_mm(),
                    f64::from(row) * self.pitch_mm(),
                ],
            })
        })
    }

    /// The tag with `id`, if it is on this target.
    pub fn tag(&self, id: u32) -> Option<TagPlace> {
        let k = id.checked_sub(self.first_id)?;
        (k < self.cols * self.rows).then(|| {
            let (row, col) = (k / self.cols, k % self.cols);
            TagPlace {
                id,
                col,
                row,
                origin_mm: [
                    f64::from(col) * self.pitch_mm(),
                    f64::from(row) * self.pitch_mm(),
                ],
            }
        })
    }

    /// The point of the target's frame at tag coordinates `(tx, ty)` of `tag` (AprilTag's: `-1`
    /// to `1` across the black square, `x` right and `y` down the tag as printed).
    pub fn tag_point(&self, tag: &TagPlace, t: [f64; 2]) -> [f64; 2] {
        let s = self.tag_mm;
        [
            tag.origin_mm[0] + s * (t[0] + 1.0) / 2.0,
            tag.origin_mm[1] + s * (1.0 - t[1]) / 2.0,
        ]
    }

    /// What is printed at `p` (target frame, mm): `Some(true)` white paper, `Some(false)` black
    /// ink, `None` off the sheet.
    pub fn is_white(&self, p: [f64; 2]) -> Option<bool> {
        let (lo, hi) = self.sheet_mm();
        if !(p[0] >= lo[0] && p[0] < hi[0] && p[1] >= lo[1] && p[1] < hi[1]) {
            return None;
        }
        let pitch = self.pitch_mm();
        let c = self.cell_mm();
        // The tag whose square (white ring included) could hold p.
        let col = ((p[0] + c) / pitch).floor();
        let row = ((p[1] + c) / pitch).floor();
        if col < 0.0 || row < 0.0 || col >= f64::from(self.cols) || row >= f64::from(self.rows) {
            return Some(true);
        }
        let (col, row) = (col as u32, row as u32);
        let x0 = f64::from(col) * pitch - c;
        let y_top = f64::from(row) * pitch + self.tag_mm + c;
        let i = ((p[0] - x0) / c).floor();
        let j = ((y_top - p[1]) / c).floor();
        if !(0.0..TOTAL_CELLS as f64).contains(&i) || !(0.0..TOTAL_CELLS as f64).contains(&j) {
            return Some(true);
        }
        let id = self.first_id + row * self.cols + col;
        Some(pattern(id as usize).is_none_or(|cells| cells[j as usize][i as usize]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_fits_the_papers_plate_and_is_valid() {
        let s = TargetSpec::default();
        s.check().unwrap();
        let (lo, hi) = s.sheet_mm();
        assert!(hi[0] - lo[0] <= 200.0 && hi[1] - lo[1] <= 100.0);
        assert_eq!(s.tags().count(), 32);
    }

    #[test]
    fn tags_are_found_by_id_and_their_corners_sit_on_the_grid() {
        let s = TargetSpec::default();
        for t in s.tags() {
            assert_eq!(s.tag(t.id), Some(t));
            let bl = s.tag_point(&t, [-1.0, 1.0]);
            assert!(
                (bl[0] - t.origin_mm[0]).abs() < 1e-12 && (bl[1] - t.origin_mm[1]).abs() < 1e-12
            );
            let tr = s.tag_point(&t, [1.0, -1.0]);
            assert!((tr[0] - t.origin_mm[0] - s.tag_mm).abs() < 1e-12);
        }
        assert_eq!(s.tag(32), None);
    }

    #[test]
    fn the_black_ring_and_white_paper_are_where_the_frame_says() {
        let s = TargetSpec::default();
        let c = s.cell_mm();
        // Inside the black ring of tag 0, just in from its corners.
        for p in [[0.5 * c, 0.5 * c], [s.tag_mm - 0.5 * c, s.tag_mm - 0.5 * c]] {
            assert_eq!(s.is_white(p), Some(false), "{p:?}");
        }
        // The white ring, the gap and the margin.
        assert_eq!(s.is_white([-0.5 * c, 5.0]), Some(true));
        assert_eq!(s.is_white([s.tag_mm + 0.5 * s.gap_mm, 5.0]), Some(true));
        assert_eq!(
            s.is_white([-s.margin_mm + 0.1, -s.margin_mm + 0.1]),
            Some(true)
        );
        assert_eq!(s.is_white([-s.margin_mm - 0.1, 0.0]), None);
    }

    #[test]
    fn bad_fields_are_named() {
        type Spoil = fn(&mut TargetSpec);
        let cases: [(&str, Spoil); 5] = [
            ("family", |s| s.family = "tag16h5".into()),
            ("cols × rows", |s| s.rows = 0),
            ("tag_mm", |s| s.tag_mm = f64::NAN),
            ("gap_mm", |s| s.gap_mm = 1.0),
            ("first_id, cols × rows", |s| s.first_id = 580),
        ];
        for (field, spoil) in cases {
            let mut s = TargetSpec::default();
            spoil(&mut s);
            match s.check() {
                Err(TargetError::Invalid { field: f, .. }) => assert_eq!(f, field),
                other => panic!("{field}: {other:?}"),
            }
        }
    }
}
