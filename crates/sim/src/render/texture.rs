//! Procedural appearance: the plate's value-noise texture, the hash and the cheap Gaussian noise
//! behind it and the sensor noise, and Lambertian shading.

use crate::surface::Point;

pub(super) fn mix64(mut h: u64) -> u64 {
    h ^= h >> 33;
    h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
    h ^= h >> 33;
    h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    h ^ (h >> 33)
}

fn hash2(ix: i64, iy: i64, seed: u64) -> f32 {
    let h = mix64(
        seed ^ (ix as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (iy as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F),
    );
    (h >> 40) as f32 / (1u64 << 24) as f32
}

/// `x.floor()` as an integer without a libm call (for |x| < 2⁶³).
#[inline]
fn fast_floor(x: f64) -> i64 {
    let i = x as i64;
    if (i as f64) > x {
        i - 1
    } else {
        i
    }
}

/// Smooth value noise in [0, 1] at `(x, y)` lattice units.
fn value_noise(x: f64, y: f64, seed: u64) -> f32 {
    let (ix, iy) = (fast_floor(x), fast_floor(y));
    let (fx, fy) = (ix as f64, iy as f64);
    let (tx, ty) = ((x - fx) as f32, (y - fy) as f32);
    let (sx, sy) = (tx * tx * (3.0 - 2.0 * tx), ty * ty * (3.0 - 2.0 * ty));
    let a = hash2(ix, iy, seed);
    let b = hash2(ix + 1, iy, seed);
    let c = hash2(ix, iy + 1, seed);
    let d = hash2(ix + 1, iy + 1, seed);
    let top = a + (b - a) * sx;
    let bottom = c + (d - c) * sx;
    top + (bottom - top) * sy
}

/// The plate's material texture: a relative brightness change at plate point `p` (mm).
pub(super) fn material_texture(p: Point, seed: u64) -> f32 {
    const OCTAVES: [(f64, f32); 3] = [(14.0, 0.045), (3.0, 0.035), (0.8, 0.025)];
    let mut t = 0.0;
    for (k, (scale, amp)) in OCTAVES.iter().enumerate() {
        let n = value_noise(
            p[0] / scale,
            p[1] / scale,
            seed.wrapping_add(k as u64 * 7919),
        );
        t += amp * (2.0 * n - 1.0);
    }
    t
}

/// A small fast generator for the per-pixel sensor noise (seeded from the frame's ChaCha
/// stream): SplitMix64, and a standard normal approximated by the sum of four uniforms
/// (Irwin–Hall, bounded at ±3.46 σ), plenty for camera noise and cheap.
pub(super) struct NoiseGen {
    pub(super) state: u64,
}

impl NoiseGen {
    fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        mix64(self.state)
    }

    pub(super) fn gaussian(&mut self) -> f32 {
        let x = self.next_u64();
        let sum = (x & 0xffff) + ((x >> 16) & 0xffff) + ((x >> 32) & 0xffff) + (x >> 48);
        // Four uniforms on [0, 1): mean 2, variance 1/3.
        (sum as f32 / 65536.0 - 2.0) * 3f32.sqrt()
    }
}

/// Lambertian shading of a surface of gradient `(gx, gy)` under `light` (unit vector, z up),
/// relative to the flat plate, with some ambient light.
pub(super) fn lambert(gx: f64, gy: f64, light: [f64; 3], ambient: f64) -> f32 {
    let norm = (gx * gx + gy * gy + 1.0).sqrt();
    let ndotl = (-gx * light[0] - gy * light[1] + light[2]) / norm;
    (ambient + (1.0 - ambient) * (ndotl / light[2]).max(0.0)).clamp(0.05, 2.0) as f32
}
