//! Thinning binary images to one-pixel centre lines, shared by the planner (the paper's eq. 1 on
//! the crack masks) and the vision crate (where along a detected crack the finger should touch).
//!
//! [`thin`] is Zhang–Suen's two alternating sub-iterations, with each pixel removed only while it
//! is *simple* (Yokoi's 8-connectivity number is 1) and not a line end, so a crack never breaks
//! or vanishes (plain Zhang–Suen erases 2 × 2 squares and two-pixel diagonals). A pixel that
//! ends a line two pixels thick when a sub-iteration starts ([`two_thick_end`]) is not peeled in
//! it: without that, a two-pixel diagonal was eaten from its end in one sweep.

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

/// Whether a pixel with neighbours `n` ends a line two pixels thick: exactly two neighbours,
/// next to each other around it (E and NE, NE and N, …). Such an end has two neighbours, not
/// one, so the line-end rule alone does not keep it; removed, it leaves the next pixel in the
/// same state, and a two-pixel staircase (a thin crack running diagonally across the crack
/// map's cells) was eaten from its end in one raster sweep, leaving no centre line at all. So
/// [`thin`] does not mark such a pixel; a pixel that becomes one during a sub-iteration may still
/// go (the pixel beside a kept end, as the staircase thins to one pixel).
pub fn two_thick_end(n: &[bool; 8]) -> bool {
    n.iter().filter(|&&v| v).count() == 2 && (0..8).any(|k| n[k] && n[(k + 1) % 8])
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
                    if !removable(&n) || two_thick_end(&n) {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A `w × h` image with the pixels `on(x, y)` set.
    fn image(w: usize, h: usize, on: impl Fn(usize, usize) -> bool) -> Vec<bool> {
        (0..w * h).map(|i| on(i % w, i / w)).collect()
    }

    fn count(p: &[bool]) -> usize {
        p.iter().filter(|&&v| v).count()
    }

    #[test]
    fn a_two_pixel_diagonal_staircase_thins_to_a_line_along_its_whole_length() {
        // Rows of two pixels, each row one to the right: a thin crack running diagonally across
        // the crack map's cells (trial scene 10217's lost crack). It used to vanish entirely.
        for n in [3usize, 12, 40] {
            let (w, h) = (n + 4, n + 2);
            let mut p = image(w, h, |x, y| (1..=n).contains(&y) && (x == y || x == y + 1));
            thin(&mut p, w);
            let ys: Vec<usize> = (0..w * h).filter(|&i| p[i]).map(|i| i / w).collect();
            assert!(
                ys.contains(&1) && ys.contains(&n),
                "n {n}: the centre line must span rows 1..={n}, kept rows {ys:?}"
            );
            assert!(
                count(&p) <= n + 2,
                "n {n}: {} pixels left, not one per row",
                count(&p)
            );
            // One 8-connected piece, each pixel with at most two neighbours but the ends.
            let ends = (0..w * h)
                .filter(|&i| p[i])
                .filter(|&i| {
                    let k = neighbours(&p, w, (i % w) as isize, (i / w) as isize);
                    k.iter().filter(|&&v| v).count() == 1
                })
                .count();
            assert!(ends <= 2 + usize::from(n > 3), "n {n}: {ends} free ends");
        }
        // Either diagonal.
        let n = 20;
        let w = n + 4;
        let mut p = image(w, n + 2, |x, y| {
            (1..=n).contains(&y) && (x + y == n + 1 || x + y == n + 2)
        });
        thin(&mut p, w);
        assert!(
            count(&p) >= n,
            "anti-diagonal: {} pixels left of {n} rows",
            count(&p)
        );
    }

    #[test]
    fn thick_bars_and_squares_still_thin_to_one_pixel_and_one_pixel_lines_stay() {
        // A 5-pixel-thick horizontal bar thins to its centre row, with at most a short hook
        // at each end (a corner pixel that became a two-pixel end while peeling; the crack
        // map's spur rule drops hooks that short).
        let (w, h) = (30, 9);
        let mut p = image(w, h, |x, y| (2..=6).contains(&y) && (2..=27).contains(&x));
        thin(&mut p, w);
        let rows: Vec<String> = (0..h)
            .map(|y| {
                (0..w)
                    .map(|x| if p[y * w + x] { '#' } else { '.' })
                    .collect()
            })
            .collect();
        let centre = (0..w).filter(|&x| p[4 * w + x]).count();
        let off = (0..w * h)
            .filter(|&i| p[i] && i / w != 4)
            .collect::<Vec<_>>();
        assert!(
            centre >= 20 && off.len() <= 4 && off.iter().all(|&i| !(6..=23).contains(&(i % w))),
            "bar:\n{}",
            rows.join("\n")
        );
        // A 2 × 2 square does not vanish.
        let mut p = image(4, 4, |x, y| (1..=2).contains(&x) && (1..=2).contains(&y));
        thin(&mut p, 4);
        assert!(count(&p) >= 1);
        // A one-pixel diagonal is its own centre line.
        let line = image(12, 12, |x, y| x == y && (1..=10).contains(&x));
        let mut p = line.clone();
        thin(&mut p, 12);
        assert_eq!(p, line);
        assert!(two_thick_end(&[
            true, true, false, false, false, false, false, false
        ]));
        assert!(!two_thick_end(&[
            true, false, true, false, false, false, false, false
        ]));
    }
}
