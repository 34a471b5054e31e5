//! Thinning binary images to one-pixel centre lines, shared by the planner (the paper's eq. 1 on
//! the crack masks) and the vision crate (where along a detected crack the finger should touch).
//!
//! [`thin`] is Zhang–Suen's two alternating sub-iterations, with each pixel removed only while it
//! is *simple* (Yokoi's 8-connectivity number is 1) and not a line end, so a crack never breaks
//! or vanishes (plain Zhang–Suen erases 2 × 2 squares and two-pixel diagonals).

/// The offsets `(dx, dy)` of the 8 neighbours, counter-clockwise from east: E, NE, N, NW, W,
/// SW, S, SE (y grows downwards); the order of [`neighbours`].
pub const NEIGHBOUR_OFFSETS: [(isize, isize); 8] = [
    (1, 0),
    (1, -1),
    (0, -1),
    (-1, -1),
    (-1, 0),
    (-1, 1),
    (0, 1),
    (1, 1),
];

/// Pixel `(x, y)` of a row-major `width`-wide image; `false` outside the image.
pub fn pixel(pixels: &[bool], width: usize, x: isize, y: isize) -> bool {
    let height = pixels.len() / width.max(1);
    x >= 0
        && y >= 0
        && (x as usize) < width
        && (y as usize) < height
        && pixels[y as usize * width + x as usize]
}

/// The 8 neighbours of pixel `(x, y)` of a row-major `width`-wide image, in the order of
/// [`NEIGHBOUR_OFFSETS`]. Pixels outside the image are `false`.
pub fn neighbours(pixels: &[bool], width: usize, x: isize, y: isize) -> [bool; 8] {
    NEIGHBOUR_OFFSETS.map(|(dx, dy)| pixel(pixels, width, x + dx, y + dy))
}

/// Yokoi's 8-connectivity number: 1 exactly when removing the pixel keeps the foreground's
/// 8-connected pieces and the background's 4-connected pieces as they were (a *simple* pixel).
pub fn connectivity8(n: &[bool; 8]) -> u32 {
    let b = |k: usize| u32::from(!n[k % 8]);
    [0, 2, 4, 6]
        .iter()
        .map(|&k| b(k) - b(k) * b(k + 1) * b(k + 2))
        .sum()
}

/// Thins the row-major `width`-wide image `pixels` in place to one-pixel centre lines (see the
/// module docs). Each sub-iteration marks its boundary pixels on a snapshot, as Zhang–Suen do
/// (so both sides are peeled evenly and nothing cascades along a row), then removes the marked
/// pixels one at a time, each only if it is still simple and not a line end.
pub fn thin(pixels: &mut [bool], width: usize) {
    if width == 0 {
        return;
    }
    let (w, h) = (width as isize, (pixels.len() / width) as isize);
    let removable = |n: &[bool; 8]| {
        let count = n.iter().filter(|&&v| v).count();
        (2..=6).contains(&count) && connectivity8(n) == 1
    };
    let mut marked = Vec::new();
    loop {
        let mut changed = false;
        for sub in 0..2 {
            marked.clear();
            for y in 0..h {
                for x in 0..w {
                    if !pixels[(y * w + x) as usize] {
                        continue;
                    }
                    let n = neighbours(pixels, width, x, y);
                    if !removable(&n) {
                        continue;
                    }
                    // Zhang–Suen's sides: the first sub-iteration peels the east/south
                    // boundary, the second the west/north one (E = n[0], N = n[2], W = n[4],
                    // S = n[6]).
                    let (east, north, west, south) = (n[0], n[2], n[4], n[6]);
                    let peel = if sub == 0 {
                        !(east && south && (north || west))
                    } else {
                        !(north && west && (east || south))
                    };
                    if peel {
                        marked.push((x, y));
                    }
                }
            }
            for &(x, y) in &marked {
                if removable(&neighbours(pixels, width, x, y)) {
                    pixels[(y * w + x) as usize] = false;
                    changed = true;
                }
            }
        }
        if !changed {
            return;
        }
    }
}
