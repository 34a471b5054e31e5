//! The tag36h11 family's codes, read once from the AprilTag library that detects them, and each
//! tag's pattern as a grid of cells.
//!
//! A tag36h11 tag is 10 × 10 cells: a white ring one cell wide outside, a black ring one cell
//! wide inside it, and 6 × 6 data cells in the middle. Bit `i` of a code (the most significant
//! first) sets the data cell at (`bit_x[i]`, `bit_y[i]`) white; `x` runs right and `y` down the
//! tag as printed. This is how the library itself draws a tag (`apriltag_to_image`).

use std::sync::OnceLock;

/// Cells across a tag36h11 tag, white ring included.
pub const TOTAL_CELLS: usize = 10;
/// Cells across the black square (the detected corners are its corners).
pub const BORDER_CELLS: usize = 8;

/// The family as plain data.
struct Family {
    codes: Vec<u64>,
    bit_x: Vec<u32>,
    bit_y: Vec<u32>,
}

fn family() -> &'static Family {
    static FAMILY: OnceLock<Family> = OnceLock::new();
    FAMILY.get_or_init(read_family)
}

#[expect(
    unsafe_code,
    reason = "the codes are read from the AprilTag C library's own family table, the one its \
              detector decodes against; the struct is created, copied out and destroyed here"
)]
fn read_family() -> Family {
    // SAFETY: `tag36h11_create` returns a valid, fully initialised family (static arrays of
    // `ncodes` codes and `nbits` bit positions); it is only read, then destroyed once.
    unsafe {
        let f = apriltag_sys::tag36h11_create();
        let fam = &*f;
        let codes = std::slice::from_raw_parts(fam.codes, fam.ncodes as usize).to_vec();
        let bit_x = std::slice::from_raw_parts(fam.bit_x, fam.nbits as usize).to_vec();
        let bit_y = std::slice::from_raw_parts(fam.bit_y, fam.nbits as usize).to_vec();
        apriltag_sys::tag36h11_destroy(f);
        Family {
            codes,
            bit_x,
            bit_y,
        }
    }
}

/// How many distinct tags the family has.
pub fn tag_count() -> usize {
    family().codes.len()
}

/// The pattern of tag `id` as printed: `cells[y][x]` is `true` where the cell is white, `x`
/// right and `y` down, white ring included. `None` past the family's last tag.
pub fn pattern(id: usize) -> Option<[[bool; TOTAL_CELLS]; TOTAL_CELLS]> {
    let fam = family();
    let code = *fam.codes.get(id)?;
    let mut cells = [[false; TOTAL_CELLS]; TOTAL_CELLS];
    for (i, row) in cells.iter_mut().enumerate() {
        for (j, cell) in row.iter_mut().enumerate() {
            *cell = i == 0 || j == 0 || i == TOTAL_CELLS - 1 || j == TOTAL_CELLS - 1;
        }
    }
    let nbits = fam.bit_x.len();
    // The bit positions count from the black square's corner.
    let border_start = (TOTAL_CELLS - BORDER_CELLS) / 2;
    for i in 0..nbits {
        if code & (1u64 << (nbits - i - 1)) != 0 {
            cells[fam.bit_y[i] as usize + border_start][fam.bit_x[i] as usize + border_start] =
                true;
        }
    }
    Some(cells)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_family_has_its_587_codes_and_36_bits() {
        assert_eq!(tag_count(), 587);
        assert_eq!(family().bit_x.len(), 36);
        assert!(pattern(587).is_none());
    }

    #[test]
    fn every_pattern_has_a_black_ring_inside_a_white_one_and_differs_from_the_others() {
        let mut seen = std::collections::HashSet::new();
        for id in 0..tag_count() {
            let p = pattern(id).unwrap();
            let edge = |i: usize, k: usize| [p[i][k], p[k][i], p[9 - i][k], p[k][9 - i]];
            let ring = |i: usize| {
                (i..TOTAL_CELLS - i)
                    .flat_map(|k| edge(i, k))
                    .collect::<Vec<_>>()
            };
            assert!(ring(0).iter().all(|&w| w), "white ring of {id}");
            assert!(ring(1).iter().all(|&w| !w), "black ring of {id}");
            assert!(seen.insert(p), "tag {id} repeats another's pattern");
        }
    }
}
