//! A plate as a closed triangle mesh: its top surface sampled on a grid that is fine only where
//! the feature is (the simulator's height function, so the print is what the simulator slides
//! over), the same grid flat underneath, and the four sides between them. Every edge is shared
//! by exactly two triangles: a slicer reads it as one solid.

use std::path::Path;

use crackbot_surface::Feature;

use crate::error::PlateError;
use crate::set::{ReferencePlate, THICKNESS_MM};

/// Grid spacing across a crack, mm (its rounded edges and walls).
const CRACK_STEP_MM: f64 = 0.05;
/// Grid spacing along a crack around its rounded ends, mm.
const CRACK_END_STEP_MM: f64 = 0.25;
/// Grid spacing over a bump, both ways, mm.
const BUMP_STEP_MM: f64 = 0.25;
/// Grid points per period of the wavy pattern.
const WAVE_STEPS: f64 = 24.0;
/// Half the width of a crack's wall in the mesh, mm: the heightfield's wall is this steep.
const WALL_MM: f64 = 0.002;

/// The sample positions along x and y, sorted, from 0 to the plate's size.
fn grid(plate: &ReferencePlate) -> (Vec<f64>, Vec<f64>) {
    let [w, h] = plate.surface.size_mm;
    let (mut xs, mut ys) = (vec![0.0, w], vec![0.0, h]);
    let steps = |lo: f64, hi: f64, step: f64, out: &mut Vec<f64>| {
        let n = ((hi - lo) / step).ceil() as usize;
        out.extend((0..=n).map(|i| lo + (hi - lo) * i as f64 / n as f64));
    };
    for f in &plate.surface.features {
        let (lo, hi) = f.footprint();
        match f {
            Feature::Crack { path, width_mm, .. } => {
                steps(lo[0] - 0.1, hi[0] + 0.1, CRACK_STEP_MM, &mut xs);
                // Its rounded ends.
                let r = (hi[0] - lo[0]) / 2.0 + 0.1;
                for end in [path[0][1], path[path.len() - 1][1]] {
                    steps(end - r, end + r, CRACK_END_STEP_MM, &mut ys);
                }
                // Both walls nearly vertical.
                let x = path[0][0];
                for side in [-1.0, 1.0] {
                    let wall = x + side * width_mm / 2.0;
                    xs.extend([wall - WALL_MM, wall + WALL_MM]);
                }
            }
            Feature::Bump { .. } => {
                steps(lo[0], hi[0], BUMP_STEP_MM, &mut xs);
                steps(lo[1], hi[1], BUMP_STEP_MM, &mut ys);
            }
            Feature::Wavy { period_mm, .. } => {
                steps(lo[0], hi[0], period_mm / WAVE_STEPS, &mut xs);
            }
            Feature::Decoy { .. } | Feature::Screw { .. } => {}
        }
    }
    for v in [&mut xs, &mut ys] {
        v.retain(|&a| a >= 0.0);
        v.sort_by(f64::total_cmp);
        v.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
    }
    xs.retain(|&a| a <= w);
    ys.retain(|&a| a <= h);
    (xs, ys)
}

fn triangle(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> stl_io::Triangle {
    let (u, v) = (
        [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
        [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
    );
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt().max(1e-300);
    let f = |p: [f64; 3]| stl_io::Vertex::new(p.map(|x| x as f32));
    stl_io::Triangle {
        normal: stl_io::Normal::new(n.map(|x| (x / len) as f32)),
        vertices: [f(a), f(b), f(c)],
    }
}

/// The quad `a b c d` (counter-clockwise seen from outside) as two triangles.
fn quad(out: &mut Vec<stl_io::Triangle>, [a, b, c, d]: [[f64; 3]; 4]) {
    out.push(triangle(a, b, c));
    out.push(triangle(a, c, d));
}

/// The plate's closed mesh, mm, its sound surface at [`THICKNESS_MM`] above its underside.
pub fn triangles(plate: &ReferencePlate) -> Vec<stl_io::Triangle> {
    let (xs, ys) = grid(plate);
    let top = |i: usize, j: usize| {
        let (x, y) = (xs[i], ys[j]);
        [x, y, THICKNESS_MM + plate.surface.height_mm([x, y])]
    };
    let bottom = |i: usize, j: usize| [xs[i], ys[j], 0.0];
    let (nx, ny) = (xs.len(), ys.len());
    let mut out = Vec::with_capacity(4 * nx * ny + 4 * (nx + ny));
    for i in 0..nx - 1 {
        for j in 0..ny - 1 {
            quad(
                &mut out,
                [top(i, j), top(i + 1, j), top(i + 1, j + 1), top(i, j + 1)],
            );
            quad(
                &mut out,
                [
                    bottom(i, j),
                    bottom(i, j + 1),
                    bottom(i + 1, j + 1),
                    bottom(i + 1, j),
                ],
            );
        }
    }
    // The sides: y = 0 and y = max along x, x = 0 and x = max along y.
    for i in 0..nx - 1 {
        quad(
            &mut out,
            [bottom(i, 0), bottom(i + 1, 0), top(i + 1, 0), top(i, 0)],
        );
        let j = ny - 1;
        quad(
            &mut out,
            [bottom(i + 1, j), bottom(i, j), top(i, j), top(i + 1, j)],
        );
    }
    for j in 0..ny - 1 {
        quad(
            &mut out,
            [bottom(0, j + 1), bottom(0, j), top(0, j), top(0, j + 1)],
        );
        let i = nx - 1;
        quad(
            &mut out,
            [bottom(i, j), bottom(i, j + 1), top(i, j + 1), top(i, j)],
        );
    }
    out
}

/// Writes the plate's mesh as binary STL (mm); the number of triangles.
pub fn write_stl(plate: &ReferencePlate, path: &Path) -> Result<usize, PlateError> {
    let mesh = triangles(plate);
    let io = |source| PlateError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut w = std::io::BufWriter::new(std::fs::File::create(path).map_err(io)?);
    stl_io::write_stl(&mut w, mesh.iter()).map_err(io)?;
    Ok(mesh.len())
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use super::*;
    use crate::set::{by_name, reference_set, CRACK_DEPTH_MM, CRACK_Y_MM, PLATE_SIZE_MM};

    /// Volume of a closed mesh (divergence theorem), mm³.
    fn volume(mesh: &stl_io::IndexedMesh) -> f64 {
        mesh.faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.vertices.map(|v| mesh.vertices[v].0.map(f64::from));
                (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                    + a[2] * (b[0] * c[1] - b[1] * c[0]))
                    / 6.0
            })
            .sum()
    }

    #[test]
    fn every_plate_is_one_closed_solid_of_the_simulated_shape() {
        let dir = tempfile::tempdir().unwrap();
        for plate in reference_set() {
            let path = dir.path().join(format!("{}.stl", plate.name));
            let n = write_stl(&plate, &path).unwrap();
            let mut f = std::fs::File::open(&path).unwrap();
            let mesh = stl_io::read_stl(&mut f).unwrap();
            assert_eq!(mesh.faces.len(), n);
            mesh.validate()
                .unwrap_or_else(|e| panic!("{}: {e}", plate.name));
            // Every directed edge once, and its reverse once: closed and consistently wound.
            let mut edges: HashMap<(usize, usize), usize> = HashMap::new();
            for f in &mesh.faces {
                for k in 0..3 {
                    *edges
                        .entry((f.vertices[k], f.vertices[(k + 1) % 3]))
                        .or_default() += 1;
                }
            }
            for (&(a, b), &c) in &edges {
                assert_eq!(c, 1, "{}: edge {a}-{b} used {c} times", plate.name);
                assert_eq!(edges.get(&(b, a)), Some(&1), "{}: open edge", plate.name);
            }
            // The volume: the slab less the groove, plus the bump or the waves.
            let slab = PLATE_SIZE_MM[0] * PLATE_SIZE_MM[1] * THICKNESS_MM;
            let v = volume(&mesh);
            // A crack: its slot and the half-discs of its rounded ends.
            let want = match plate.width_label_mm {
                Some(w) if w > 0.0 => {
                    let long = CRACK_Y_MM[1] - CRACK_Y_MM[0];
                    slab - (w * long + std::f64::consts::PI * w * w / 4.0) * CRACK_DEPTH_MM
                }
                _ => slab,
            };
            if plate.name == "bump" {
                // The cap's volume, the height integrated on a 0.05 mm grid: within 2 %.
                let step = 0.05;
                let mut cap = 0.0;
                for i in 0..(20.0 / step) as usize {
                    for j in 0..(20.0 / step) as usize {
                        let p = [90.0 + i as f64 * step, 40.0 + j as f64 * step];
                        cap += plate.surface.height_mm(p) * step * step;
                    }
                }
                assert!(
                    cap > 20.0 && ((v - slab) / cap - 1.0).abs() < 0.02,
                    "bump: {v} vs {cap}"
                );
                continue;
            }
            assert!(
                (v - want).abs() < 0.002 * slab,
                "{}: volume {v:.1} mm³, want {want:.1}",
                plate.name
            );
        }
        // The mesh samples the simulator's surface: the 10 mm crack's floor is its depth.
        let p = by_name("crack-10mm").unwrap();
        let mesh = triangles(&p);
        let lowest = mesh
            .iter()
            .flat_map(|t| t.vertices.iter().map(|v| v[2]))
            .filter(|&z| z > 0.0)
            .fold(f32::INFINITY, f32::min);
        assert!((f64::from(lowest) - (THICKNESS_MM - CRACK_DEPTH_MM)).abs() < 1e-4);
    }
}
