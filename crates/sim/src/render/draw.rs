//! The renderer: one camera frame of a scene, drawn in named steps (plate and texture, relief
//! shading, screw cover, cracks and decoys, screws, then lighting and sensor noise).

use image::{GrayImage, RgbImage};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

use super::assets::{pick_strip, CrackAssets, CrackStrip};
use super::frame::{BoxAcc, BoxKind, Frame, GroundTruthBox};
use super::geometry::{mm_per_px, pixel_region, plate_points, Path2, Region};
use super::texture::{lambert, material_texture, mix64, NoiseGen};
use crate::camera::Camera;
use crate::scene::Scene;
use crate::surface::{Feature, Point};
use crate::SimError;

/// Base colour of a screw head (before shading and lighting), sRGB.
pub const SCREW_GREY: [u8; 3] = [150, 152, 158];

/// Knobs of the renderer beyond the scene.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderOptions {
    /// Overrides the camera's `noise_sigma` (grey levels).
    pub noise_sigma: Option<f64>,
    /// Overrides the camera's `lighting_variation`.
    pub lighting_variation: Option<f64>,
    /// Fixes the plate's texture and the crack photos used for each feature across frames (the
    /// same physical plate seen several times); `None`: drawn from the frame's seed too.
    pub appearance_seed: Option<u64>,
    /// Colour of whatever is around the plate, sRGB.
    pub background: [u8; 3],
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            noise_sigma: None,
            lighting_variation: None,
            appearance_seed: None,
            background: [28, 28, 32],
        }
    }
}

/// The frame's light, drawn from its seed: the direction that shades relief, cracks and screws,
/// and the lighting of the whole image (gain, a linear gradient, a vignette).
struct Light {
    /// Unit vector towards the light, z up.
    dir: [f64; 3],
    /// Elevation of the light above the plate, radians.
    elevation: f64,
    gain: f64,
    grad_strength: f64,
    grad_angle: f64,
    vignette: f64,
}

impl Light {
    /// Draws the light from `rng` for a lighting variation `lighting` (the order of the draws
    /// is part of the frame's determinism).
    fn draw(rng: &mut ChaCha8Rng, lighting: f64) -> Light {
        let az: f64 = rng.random_range(0.0..std::f64::consts::TAU);
        let el: f64 = rng.random_range(40f64..65.0).to_radians();
        let dir = [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()];
        let z: f64 = rng.sample(StandardNormal);
        let gain = (1.0 + 0.5 * lighting * z).clamp(0.4, 1.6);
        let grad_strength = lighting * rng.random::<f64>();
        let grad_angle: f64 = rng.random_range(0.0..std::f64::consts::TAU);
        let vignette = 0.8 * lighting * rng.random::<f64>();
        Light {
            dir,
            elevation: el,
            gain,
            grad_strength,
            grad_angle,
            vignette,
        }
    }
}

/// The image being drawn, in linear floating-point colour, and which pixels show the plate.
struct Canvas {
    w: usize,
    h: usize,
    px: Vec<[f32; 3]>,
    plate_mask: Vec<bool>,
    /// 255 where a crack's pixel counts in its ground-truth box, else 0.
    crack_mask: Vec<u8>,
}

/// Everything the drawing steps share.
struct Ctx<'a> {
    scene: &'a Scene,
    cam: Camera,
    /// Image → plate homography (pixels → mm on z = 0).
    /// The plate point seen through each pixel's centre (row-major), through the lens.
    plate: Vec<Option<Point>>,
    light: Light,
    /// Seed of the plate's appearance (texture, crack photos, screw slots).
    appearance: u64,
}

impl Ctx<'_> {
    /// The random stream of feature `i`'s appearance.
    fn feature_rng(&self, i: usize) -> ChaCha8Rng {
        ChaCha8Rng::seed_from_u64(mix64(self.appearance ^ mix64(i as u64 + 1)))
    }
}

/// Renders one camera frame of `scene` with its ground truth, deterministic from `seed`.
///
/// Fails when the scene is invalid, has no camera, or has cracks/decoys and `assets` holds no
/// crack strip.
pub fn render(
    scene: &Scene,
    assets: &CrackAssets,
    opts: &RenderOptions,
    seed: u64,
) -> Result<Frame, SimError> {
    scene.validate()?;
    let spec = scene.camera.as_ref().ok_or_else(|| SimError::NoCamera {
        scene: scene.name.clone(),
    })?;
    let cam = Camera::from_spec(spec)?;
    let has_lines = scene
        .features
        .iter()
        .any(|f| matches!(f, Feature::Crack { .. } | Feature::Decoy { .. }));
    if has_lines && assets.strips().is_empty() {
        return Err(SimError::NoCrackPhotos);
    }
    let noise_sigma = opts.noise_sigma.unwrap_or(spec.noise_sigma);
    let lighting = opts.lighting_variation.unwrap_or(spec.lighting_variation);
    // Named as the option that set it, or the scene's camera field.
    if !(noise_sigma.is_finite() && noise_sigma >= 0.0) {
        let field = if opts.noise_sigma.is_some() {
            "noise_sigma"
        } else {
            "camera.noise_sigma"
        };
        return Err(SimError::setting(field, noise_sigma, "≥ 0"));
    }
    if !(lighting.is_finite() && lighting >= 0.0) {
        let field = if opts.lighting_variation.is_some() {
            "lighting_variation"
        } else {
            "camera.lighting_variation"
        };
        return Err(SimError::setting(field, lighting, "≥ 0"));
    }
    let appearance = opts.appearance_seed.unwrap_or(seed);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let light = Light::draw(&mut rng, lighting);
    let mut noise_gen = NoiseGen {
        state: rng.random(),
    };
    let ctx = Ctx {
        scene,
        plate: plate_points(&cam),
        cam,
        light,
        appearance,
    };

    let mut canvas = paint_plate(&ctx, opts.background);
    shade_relief(&ctx, &mut canvas);
    let cover = ScrewCover::find(&ctx);
    let mut boxes = draw_lines(&ctx, assets, &cover, &mut canvas);
    boxes.extend(draw_screws(&ctx, &cover, &mut canvas));
    boxes.sort_by_key(|b| b.feature_index);
    let crack_mask = GrayImage::from_raw(
        ctx.cam.width(),
        ctx.cam.height(),
        std::mem::take(&mut canvas.crack_mask),
    )
    .ok_or(SimError::Buffer { what: "crack mask" })?;
    let image = develop(&ctx, &canvas, noise_sigma, &mut noise_gen)?;
    Ok(Frame {
        image,
        boxes,
        crack_mask,
        plate_to_image: ctx.cam.plate_to_image(),
        seed,
    })
}

/// Step 1: the background, and the plate in its material's colour modulated by the texture.
fn paint_plate(ctx: &Ctx<'_>, background: [u8; 3]) -> Canvas {
    let (w, h) = (ctx.cam.width() as usize, ctx.cam.height() as usize);
    let [sx, sy] = ctx.scene.plate.size_mm;
    let on_plate = |p: Point| p[0] >= 0.0 && p[1] >= 0.0 && p[0] <= sx && p[1] <= sy;
    let bg = background.map(f32::from);
    let mat = ctx.scene.plate.material.colour.map(f32::from);
    let tex_seed = mix64(ctx.appearance ^ 0x7e57_u64);
    let mut px: Vec<[f32; 3]> = vec![bg; w * h];
    let mut plate_mask = vec![false; w * h];
    for r in 0..h {
        for c in 0..w {
            if let Some(p) = ctx.plate[r * w + c].filter(|&p| on_plate(p)) {
                let t = 1.0 + material_texture(p, tex_seed);
                px[r * w + c] = [mat[0] * t, mat[1] * t, mat[2] * t];
                plate_mask[r * w + c] = true;
            }
        }
    }
    Canvas {
        w,
        h,
        px,
        plate_mask,
        crack_mask: vec![0; w * h],
    }
}

/// Step 2: shading of bumps and wavy patches from the height field's gradient.
fn shade_relief(ctx: &Ctx<'_>, canvas: &mut Canvas) {
    let w = canvas.w;
    for f in &ctx.scene.features {
        if !matches!(f, Feature::Bump { .. } | Feature::Wavy { .. }) {
            continue;
        }
        let (lo, hi) = f.footprint();
        let Some((c0, c1, r0, r1)) = pixel_region(&ctx.cam, lo, hi, &[0.0]) else {
            continue;
        };
        for r in r0..r1 {
            for c in c0..c1 {
                if !canvas.plate_mask[r * w + c] {
                    continue;
                }
                let Some(p) = ctx.plate[r * w + c] else {
                    continue;
                };
                if !(p[0] >= lo[0] && p[0] <= hi[0] && p[1] >= lo[1] && p[1] <= hi[1]) {
                    continue;
                }
                let e = 0.05;
                let gx =
                    (f.height_mm([p[0] + e, p[1]]) - f.height_mm([p[0] - e, p[1]])) / (2.0 * e);
                let gy =
                    (f.height_mm([p[0], p[1] + e]) - f.height_mm([p[0], p[1] - e])) / (2.0 * e);
                if gx == 0.0 && gy == 0.0 {
                    continue;
                }
                let shade = lambert(gx, gy, ctx.light.dir, 0.45);
                for ch in &mut canvas.px[r * w + c] {
                    *ch *= shade;
                }
            }
        }
    }
}

/// Step 3: which pixels the screw heads cover (the ray meets the head's top at its height).
struct ScrewCover {
    /// Per pixel: 0, or the covering screw's feature index + 1.
    at: Vec<u32>,
    /// The pixel region of each screw in view, by feature index.
    regions: Vec<(usize, Region)>,
}

impl ScrewCover {
    fn find(ctx: &Ctx<'_>) -> ScrewCover {
        let cam = &ctx.cam;
        let (w, h) = (cam.width() as usize, cam.height() as usize);
        let mut at: Vec<u32> = vec![0; w * h];
        let mut regions = Vec::new();
        for (i, f) in ctx.scene.features.iter().enumerate() {
            let Feature::Screw {
                centre,
                head_diameter_mm,
                height_mm,
            } = f
            else {
                continue;
            };
            let rad = head_diameter_mm / 2.0;
            let lo = [centre[0] - rad, centre[1] - rad];
            let hi = [centre[0] + rad, centre[1] + rad];
            let Some(region) = pixel_region(cam, lo, hi, &[0.0, *height_mm]) else {
                continue;
            };
            let (c0, c1, r0, r1) = region;
            for r in r0..r1 {
                for c in c0..c1 {
                    let Some(p) = cam.pixel_to_plane([c as f64 + 0.5, r as f64 + 0.5], *height_mm)
                    else {
                        continue;
                    };
                    if (p[0] - centre[0]).hypot(p[1] - centre[1]) < rad {
                        at[r * w + c] = i as u32 + 1;
                    }
                }
            }
            regions.push((i, region));
        }
        ScrewCover { at, regions }
    }
}

/// Step 4: cracks and decoys, warped from the real crack strips; their ground-truth boxes.
fn draw_lines(
    ctx: &Ctx<'_>,
    assets: &CrackAssets,
    cover: &ScrewCover,
    canvas: &mut Canvas,
) -> Vec<GroundTruthBox> {
    let mut boxes = Vec::new();
    for (i, f) in ctx.scene.features.iter().enumerate() {
        let line = match f {
            Feature::Crack {
                path,
                width_mm,
                depth_mm,
                ..
            } => Line {
                path,
                width: *width_mm,
                depth: *depth_mm,
                ink: None,
            },
            Feature::Decoy {
                path,
                width_mm,
                reflectivity,
            } => Line {
                path,
                width: *width_mm,
                depth: 0.0,
                ink: Some(*reflectivity),
            },
            _ => continue,
        };
        boxes.extend(draw_line(ctx, assets, cover, canvas, i, f, &line));
    }
    boxes
}

/// A crack (`ink: None`) or a printed decoy (`ink`: its reflectivity) to draw.
struct Line<'a> {
    path: &'a [Point],
    width: f64,
    depth: f64,
    ink: Option<f64>,
}

/// How a line's real crack strip is laid along its path in this frame: the strip picked for its
/// width in pixels, its direction and starting point (drawn from the feature's seed), its scale
/// and taper.
struct Warp<'a> {
    geo: Path2,
    strip: &'a CrackStrip,
    /// Millimetres per pixel at the line's middle.
    px_mm: f64,
    /// Half the drawn width (at least one pixel), mm.
    half_w: f64,
    /// How much of a pixel a thinner line covers.
    coverage: f32,
    flip_v: f64,
    dir_u: f64,
    mm_per_src: f64,
    u0: f64,
    /// The length over which the line narrows at each end, mm.
    taper_len: f64,
    /// The farthest from the path a pixel can be touched, mm.
    d_max: f64,
}

/// Where a plate point falls in a line's warped strip.
struct StripPoint {
    /// Signed distance from the path, mm.
    d: f64,
    /// The path's segment nearest the point.
    seg: usize,
    /// The end taper there (1 in the middle).
    taper: f64,
    u: f64,
    v: f64,
    /// The strip's scale across at `u`.
    g: f64,
    /// The strip's mask there.
    m: f32,
}

impl<'a> Warp<'a> {
    /// The warp of `line` (feature `i`); `None` for a path of no length.
    fn new(ctx: &Ctx<'_>, assets: &'a CrackAssets, i: usize, line: &Line<'_>) -> Option<Self> {
        let geo = Path2::new(line.path);
        if geo.a.is_empty() {
            return None;
        }
        let px_mm = mm_per_px(&ctx.cam, geo.point_at(geo.total / 2.0));
        // Draw at least one pixel wide; thinner cracks are fainter (their pixel coverage).
        let w_eff = line.width.max(px_mm);
        let coverage = (line.width.max(0.35 * px_mm) / w_eff).min(1.0) as f32;
        let half_w = w_eff / 2.0;
        let mut frng = ctx.feature_rng(i);
        let strip = pick_strip(assets.strips(), w_eff / px_mm, &mut frng);
        let flip_v = if frng.random::<bool>() { -1.0 } else { 1.0 };
        let dir_u = if frng.random::<bool>() { -1.0 } else { 1.0 };
        // Isotropic warp: one source pixel is as long along the crack as across it.
        let mm_per_src = half_w / f64::from(strip.mean_half_width_px);
        let needed = geo.total / mm_per_src;
        let last = (strip.len - 1) as f64;
        let u0 = if needed < last {
            let start = frng.random_range(0.0..=(last - needed));
            if dir_u > 0.0 {
                start
            } else {
                start + needed
            }
        } else {
            frng.random_range(0.0..=last)
        };
        // The crack narrows over its last few widths at each end.
        let taper_len = (3.0 * w_eff).min(0.2 * geo.total).max(1e-9);
        let d_max = 2.5 * half_w + 2.0 * px_mm;
        Some(Warp {
            geo,
            strip,
            px_mm,
            half_w,
            coverage,
            flip_v,
            dir_u,
            mm_per_src,
            u0,
            taper_len,
            d_max,
        })
    }

    /// The strip at plate point `p`, or `None` beyond the path's ends, too far across it, or
    /// where the strip's mask is empty.
    fn at(&self, p: Point) -> Option<StripPoint> {
        let geo = &self.geo;
        let (s, d, seg) = geo.locate(p)?;
        if s < 0.0 || s > geo.total || d.abs() > self.d_max {
            return None;
        }
        let taper = ((s.min(geo.total - s) / self.taper_len).clamp(0.0, 1.0))
            .powf(0.6)
            .max(0.2);
        let u = self.strip.fold(self.u0 + self.dir_u * s / self.mm_per_src);
        let g = self.strip.across_scale(u);
        let v = self.flip_v * d * g / (self.half_w * taper);
        let m = self.strip.mask_at(u, v);
        (m > 0.0).then_some(StripPoint {
            d,
            seg,
            taper,
            u,
            v,
            g,
            m,
        })
    }

    /// How opaque the line is at `q`: the mask's edge sharpened to about one rendered pixel,
    /// times the line's pixel coverage.
    fn alpha(&self, q: &StripPoint) -> f32 {
        // Rendered pixels per source pixel across.
        let sigma = (self.half_w * q.taper / q.g / self.px_mm) as f32;
        let a = if sigma > 1.0 {
            (0.5 + (q.m - 0.5) * sigma).clamp(0.0, 1.0)
        } else {
            q.m
        };
        a * self.coverage
    }
}

/// How a crack darkens the plate: deeper is darker, and the wall on the light's side shades the
/// floor next to it.
struct CrackShade {
    depth_factor: f32,
    light_h: [f64; 2],
    shadow_per_n: f64,
    width: f64,
}

impl CrackShade {
    fn new(ctx: &Ctx<'_>, line: &Line<'_>) -> Self {
        CrackShade {
            depth_factor: (0.6 + 0.4 * (1.0 - (-line.depth / 2.0).exp())) as f32,
            light_h: [ctx.light.dir[0], ctx.light.dir[1]],
            shadow_per_n: line.depth / ctx.light.elevation.tan(),
            width: line.width,
        }
    }

    /// Darkens `pix` at `q` of `warp` with opacity `alpha`.
    fn apply(&self, pix: &mut [f32; 3], warp: &Warp<'_>, q: &StripPoint, alpha: f32) {
        let ratio = warp.strip.ratio_at(q.u, q.v);
        let mut dark = alpha * self.depth_factor * (0.25 + 0.9 * (1.0 - ratio)).clamp(0.2, 0.9);
        let dir = warp.geo.dir[q.seg];
        let nrm = [-dir[1], dir[0]];
        let towards = nrm[0] * self.light_h[0] + nrm[1] * self.light_h[1];
        let shadow_len = self.shadow_per_n * towards.abs();
        if self.width > 0.0 && q.d * towards.signum() > warp.half_w * q.taper - shadow_len {
            dark += 0.3 * alpha * (1.0 - dark);
        }
        for ch in pix.iter_mut() {
            *ch *= 1.0 - dark.min(0.95);
        }
    }
}

/// Darkens `pix` by a decoy's ink of reflectivity `refl` with opacity `alpha`.
fn apply_ink(pix: &mut [f32; 3], refl: f64, alpha: f32) {
    let ink = [refl as f32, refl as f32, (refl as f32 * 1.08).min(1.0)];
    for (ch, t) in pix.iter_mut().zip(ink) {
        *ch *= 1.0 - alpha * (1.0 - t);
    }
}

/// Draws feature `i` (a crack or decoy) and returns its box, if any of it is visible.
fn draw_line(
    ctx: &Ctx<'_>,
    assets: &CrackAssets,
    cover: &ScrewCover,
    canvas: &mut Canvas,
    i: usize,
    f: &Feature,
    line: &Line<'_>,
) -> Option<GroundTruthBox> {
    let warp = Warp::new(ctx, assets, i, line)?;
    let shade = CrackShade::new(ctx, line);
    let (mut lo, mut hi) = f.footprint();
    lo = [lo[0] - warp.d_max, lo[1] - warp.d_max];
    hi = [hi[0] + warp.d_max, hi[1] + warp.d_max];
    let mut acc = BoxAcc::new();
    let (c0, c1, r0, r1) = pixel_region(&ctx.cam, lo, hi, &[0.0])?;
    let w = canvas.w;
    for r in r0..r1 {
        for c in c0..c1 {
            let k = r * w + c;
            if !canvas.plate_mask[k] {
                continue;
            }
            let Some(q) = ctx.plate[k].and_then(|p| warp.at(p)) else {
                continue;
            };
            if q.m > 0.5 && cover.at[k] == 0 {
                acc.add(c, r);
                if line.ink.is_none() {
                    canvas.crack_mask[k] = 255;
                }
            }
            let alpha = warp.alpha(&q);
            match line.ink {
                Some(refl) => apply_ink(&mut canvas.px[k], refl, alpha),
                None => shade.apply(&mut canvas.px[k], &warp, &q, alpha),
            }
        }
    }
    let kind = if line.ink.is_some() {
        BoxKind::Decoy
    } else {
        BoxKind::Crack
    };
    acc.finish(kind, i, Some(line.width))
}

/// Step 5: the screws on top, as domed metal discs with a slot; their boxes.
fn draw_screws(ctx: &Ctx<'_>, cover: &ScrewCover, canvas: &mut Canvas) -> Vec<GroundTruthBox> {
    let cam = &ctx.cam;
    let w = canvas.w;
    let grey = SCREW_GREY.map(f32::from);
    let mut boxes = Vec::new();
    for &(i, (c0, c1, r0, r1)) in &cover.regions {
        let Feature::Screw {
            centre,
            head_diameter_mm,
            height_mm,
        } = &ctx.scene.features[i]
        else {
            continue;
        };
        let rad = head_diameter_mm / 2.0;
        let mut frng = ctx.feature_rng(i);
        let slot: f64 = frng.random_range(0.0..std::f64::consts::PI);
        let (ss, sc) = slot.sin_cos();
        let mut acc = BoxAcc::new();
        for r in r0..r1 {
            for c in c0..c1 {
                let k = r * w + c;
                if cover.at[k] != i as u32 + 1 {
                    continue;
                }
                let Some(p) = cam.pixel_to_plane([c as f64 + 0.5, r as f64 + 0.5], *height_mm)
                else {
                    continue;
                };
                let (dx, dy) = (p[0] - centre[0], p[1] - centre[1]);
                // Domed head h (1 − 0.4 r²/R²): gradient −0.8 h (dx, dy)/R².
                let k_dome = 0.8 * height_mm / (rad * rad);
                let mut shade = lambert(-k_dome * dx, -k_dome * dy, ctx.light.dir, 0.45);
                let along = dx * sc + dy * ss;
                let across = -dx * ss + dy * sc;
                if across.abs() < 0.09 * head_diameter_mm && along.abs() < 0.38 * head_diameter_mm {
                    shade *= 0.35;
                }
                if dx.hypot(dy) > 0.9 * rad {
                    shade *= 0.8;
                }
                canvas.px[k] = [grey[0] * shade, grey[1] * shade, grey[2] * shade];
                acc.add(c, r);
            }
        }
        boxes.extend(acc.finish(BoxKind::Screw, i, None));
    }
    boxes
}

/// Step 6: the frame's lighting, sensor noise, and quantisation to 8-bit sRGB.
fn develop(
    ctx: &Ctx<'_>,
    canvas: &Canvas,
    noise_sigma: f64,
    noise_gen: &mut NoiseGen,
) -> Result<RgbImage, SimError> {
    let (w, h) = (canvas.w, canvas.h);
    let light = &ctx.light;
    let (cx, cy) = (w as f64 / 2.0, h as f64 / 2.0);
    let diag = (cx * cx + cy * cy).sqrt();
    let (gs, gc) = light.grad_angle.sin_cos();
    let sigma = noise_sigma as f32;
    let mut raw = vec![0u8; w * h * 3];
    for (r, (row_out, row_in)) in raw
        .chunks_exact_mut(3 * w)
        .zip(canvas.px.chunks_exact(w))
        .enumerate()
    {
        let dy = (r as f64 + 0.5 - cy) / diag;
        for (c, (out, p)) in row_out.chunks_exact_mut(3).zip(row_in).enumerate() {
            let dx = (c as f64 + 0.5 - cx) / diag;
            let light_factor = (light.gain
                * (1.0 + light.grad_strength * (dx * gc + dy * gs))
                * (1.0 - 2.0 * light.vignette * (dx * dx + dy * dy)))
                .max(0.0) as f32;
            for (o, &v) in out.iter_mut().zip(p) {
                let mut v = v * light_factor;
                if sigma > 0.0 {
                    v += sigma * noise_gen.gaussian();
                }
                // Round to nearest (the cast truncates a value already in [0.5, 255.5]).
                *o = (v.clamp(0.0, 255.0) + 0.5) as u8;
            }
        }
    }
    RgbImage::from_raw(ctx.cam.width(), ctx.cam.height(), raw)
        .ok_or(SimError::Buffer { what: "image" })
}
