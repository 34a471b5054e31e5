//! Telling a mark printed on the surface from a crack with the proximity fibre at two heights.
//!
//! # Why
//!
//! The proximity fibre returns `R · f(d)`: the surface's reflectivity `R` times a curve of the
//! distance `d` to it. A crack darkens it by moving the surface away (its floor is farther); a
//! printed crack (the paper's decoys: flat paper, dark ink) by lowering `R` at the same
//! distance. One contact slide cannot tell them apart: both dip, and the deformation channels
//! do not move over cracks under a few millimetres (the authors' own 1 and 2 mm plates leave
//! D1–D3 as still as the flat plate does), so a dark enough print of a narrow crack reads as a
//! crack. The authors trained their classifier on two printed cracks for this; we have no
//! recording of one.
//!
//! Raised by `h`, the fibre sees ink darken it by the same share `1 − R` as in contact, while a
//! crack's floor, `depth` below the plate, darkens it by less: `f(d₀ + h + depth) / f(d₀ + h)`
//! is closer to 1 than `f(d₀ + depth) / f(d₀)` where `f` falls off (`1/d²` beyond its peak).
//! The measure the robot uses is [`print_ratio`]: the least-squares factor between the raised
//! dip and the contact dip (each as a share of its signal above the fibre's dark level), at the
//! shift where they line up ([`profile_ratio`]), or the ratio of their floors where the contact
//! dip has reached the fibre's dark level. It is about 1 for ink of any darkness or width and
//! below 1 for a crack. The share of the spot a narrow mark covers cancels in the ratio of the
//! two heights.
//! Two simpler measures are kept for comparison: [`height_ratio`] (the dips' floors: biased
//! towards "print" where the raised dip is only a few counts deep, as the minimum of noisy
//! samples lies below the true floor) and [`area_ratio`] (the dips' areas: blur-proof, but in
//! contact the finger's stick-slip stretches the dip along the arm's position). Figures:
//! `crates/research/EXPERIMENTS.md`, "Prints told by two heights".
//!
//! # What it needs and does not do
//!
//! * The fibre's dark level (P with nothing in view, the sensor's calibration), to within a
//!   few counts: at 2 mm the flat surface is only about 27 counts above it.
//! * A pass at a known height above the surface at the line; the arm must not meet anything on
//!   the way (the check is meant for candidates the finger already slid over and found no bump
//!   on). Held level over a bump's flank or a curved part, the fibre is nearer the surface than
//!   that: [`PrintRatios::levels`] tells how near, and the robot makes the pass again where it
//!   was off (`crackbot_mission::inspect::surface_rise_mm`).
//! * The raised pass's dip is the one that lines up with the contact dip, not its deepest
//!   point: a raised pass may reach other dark things beside the line ([`print_ratios`]).
//! * It does not tell a crack from a groove or step of the same depth, nor see a crack filled
//!   with dark dirt as anything but ink.

use crate::TactileError;

/// Width of the moving average over position that finds the dip's floor and window, mm (the
/// same distance at any speed, so a narrow dip keeps the same depth on a slow pass in contact
/// and a fast raised one).
const SMOOTH_MM: f64 = 0.2;
/// The window extends this far beyond where the smoothed dip is back to within
/// [`EDGE_SHARE`] of its depth, mm.
const WINDOW_MARGIN_MM: f64 = 0.5;
/// The dip's edge: where the smoothed signal comes back to this share of the depth.
const EDGE_SHARE: f64 = 0.1;
/// The sound surface's level and the dip's baseline are read from the samples within this
/// distance of the dip's floor, mm. Over a whole pass they were pulled up where part of it ran
/// onto a bump's flank or towards a screw head (closer to a raised fibre, brighter), and the
/// dip's share with them: cracks beside bumps read as prints. Replayed offline on the saved
/// passes of 4852 candidates over a crack or a print (simulated trials 9000–10499, real time,
/// `examples/replay_ratios.rs`) with the robot's rule for ratios in doubt, cracks read as prints
/// 33 → 27 (17 → 11 beside a screw or bump) and prints read as cracks 38 → 37; chosen on seeds
/// 9000–9779 among 3, 4, 5, 6 and 8 mm (`crates/research/EXPERIMENTS.md`, "A local baseline
/// for the print check").
pub const LEVEL_REACH_MM: f64 = 5.0;
/// Fewest samples a pass needs.
pub const MIN_SAMPLES: usize = 20;
/// Least height of the sound surface's signal above the dark level, counts: below it the fibre
/// sees too little for a ratio.
pub const MIN_SIGNAL_COUNTS: f64 = 3.0;

/// The proximity dip of one pass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DipArea {
    /// P over the sound surface beside the dip (median outside the window, within
    /// [`LEVEL_REACH_MM`] of the floor), counts.
    pub baseline: f64,
    /// ∫ (baseline − P) dx over the window, counts · mm.
    pub area: f64,
    /// `area / (baseline − dark)`, mm: the dip's area as a share of the signal.
    pub relative_mm: f64,
    /// `(baseline − floor) / (baseline − dark)`: the dip's depth (of the signal smoothed over
    /// 0.2 mm) as a share of the signal.
    pub relative_depth: f64,
    /// The window the area is taken over, mm along the pass.
    pub window_mm: [f64; 2],
}

fn err(reason: String) -> TactileError {
    TactileError::PrintCheck { reason }
}

/// The proximity dip of one pass: `p` the proximity channel (counts) and `along` the position of
/// each sample along the line (mm; any order, any direction), `dark` the fibre's dark level
/// (counts). The dip is found around the smoothed minimum; its window runs to where the dip is
/// back within 10 % of its depth, plus 0.5 mm; the baseline is the median outside it, both
/// within [`LEVEL_REACH_MM`] of the floor.
///
/// Errors name what is wrong: lengths that differ, fewer than [`MIN_SAMPLES`] samples, a value
/// that is not finite, a pass that does not move, or a baseline less than
/// [`MIN_SIGNAL_COUNTS`] above `dark`.
pub fn dip_area(p: &[f64], along: &[f64], dark: f64) -> Result<DipArea, TactileError> {
    dip_area_within(p, along, dark, None)
}

/// A pass the dip's measures can use: as many positions as samples, enough of them, every one
/// finite, and a finite dark level.
fn check_pass(p: &[f64], along: &[f64], dark: f64) -> Result<(), TactileError> {
    if p.len() != along.len() {
        return Err(err(format!(
            "{} proximity samples but {} positions",
            p.len(),
            along.len()
        )));
    }
    if p.len() < MIN_SAMPLES {
        return Err(err(format!(
            "{} samples in the pass, at least {MIN_SAMPLES} needed",
            p.len()
        )));
    }
    if let Some(i) = (0..p.len()).find(|&i| !(p[i].is_finite() && along[i].is_finite())) {
        return Err(err(format!(
            "sample {i} is not a finite number (P {}, position {} mm)",
            p[i], along[i]
        )));
    }
    if !dark.is_finite() {
        return Err(err(format!("the dark level {dark} is not a finite number")));
    }
    Ok(())
}

/// `v` at sorted positions `x` (mm) averaged over ±`SMOOTH_MM`/2 of position (two pointers over
/// the sorted samples).
fn smooth_by_position(x: &[f64], v: &[f64]) -> Vec<f64> {
    let n = v.len();
    let (mut a, mut b, mut sum) = (0usize, 0usize, 0.0);
    (0..n)
        .map(|i| {
            while b < n && x[b] <= x[i] + SMOOTH_MM / 2.0 {
                sum += v[b];
                b += 1;
            }
            while x[a] < x[i] - SMOOTH_MM / 2.0 {
                sum -= v[a];
                a += 1;
            }
            sum / (b - a) as f64
        })
        .collect()
}

/// The area between `baseline` and `v` at sorted positions `x` inside `window` (mm), counts ×
/// mm. Trapezoid weights: each sample stands for half the gaps to its neighbours.
fn area_below(x: &[f64], v: &[f64], baseline: f64, window: [f64; 2]) -> f64 {
    let n = v.len();
    let mut area = 0.0;
    for i in 0..n {
        if x[i] < window[0] || x[i] > window[1] {
            continue;
        }
        let left = if i > 0 { x[i] - x[i - 1] } else { 0.0 };
        let right = if i + 1 < n { x[i + 1] - x[i] } else { 0.0 };
        area += (baseline - v[i]) * 0.5 * (left + right);
    }
    area
}

/// As [`dip_area`], with the dip's floor searched only among the samples within `within` (mm
/// along the pass; the whole pass when `None` or when no sample lies there): where a pass
/// also crosses something else dark, the dip of the line being judged rather than the deepest.
///
/// Errors as [`dip_area`].
pub fn dip_area_within(
    p: &[f64],
    along: &[f64],
    dark: f64,
    within: Option<[f64; 2]>,
) -> Result<DipArea, TactileError> {
    check_pass(p, along, dark)?;
    let mut order: Vec<usize> = (0..p.len()).collect();
    order.sort_by(|&a, &b| along[a].total_cmp(&along[b]));
    let x: Vec<f64> = order.iter().map(|&i| along[i]).collect();
    let v: Vec<f64> = order.iter().map(|&i| p[i]).collect();
    let n = v.len();
    if x[n - 1] - x[0] < 1.0 {
        return Err(err(format!(
            "the pass spans {:.3} mm; at least 1 mm needed",
            x[n - 1] - x[0]
        )));
    }
    let smooth = smooth_by_position(&x, &v);
    let searched = |xi: f64| within.is_none_or(|[lo, hi]| xi >= lo && xi <= hi);
    let deepest = |keep: &dyn Fn(f64) -> bool| {
        smooth
            .iter()
            .copied()
            .enumerate()
            .filter(|&(i, _)| keep(x[i]))
            .min_by(|a, b| a.1.total_cmp(&b.1))
    };
    let (m, floor) = deepest(&searched)
        .or_else(|| deepest(&|_| true))
        .unwrap_or((0, v[0]));
    // The sound surface's level (and, below, the dip's baseline) from the samples near the
    // dip only: a bump or a screw head farther along brightens a raised pass and would raise
    // both.
    let [r0, r1] = level_reach(&x, &smooth, m);
    let near = |xi: f64| xi >= r0 && xi <= r1;
    let level = level_within(&x, &smooth, [r0, r1]);
    let edge = level - EDGE_SHARE * (level - floor).max(0.0);
    let mut lo = m;
    while lo > 0 && smooth[lo] < edge {
        lo -= 1;
    }
    let mut hi = m;
    while hi + 1 < n && smooth[hi] < edge {
        hi += 1;
    }
    let window = [x[lo] - WINDOW_MARGIN_MM, x[hi] + WINDOW_MARGIN_MM];
    let inside = |xi: f64| xi >= window[0] && xi <= window[1];
    let mut outside: Vec<f64> = (0..n)
        .filter(|&i| !inside(x[i]) && near(x[i]))
        .map(|i| v[i])
        .collect();
    let baseline = if outside.len() >= MIN_SAMPLES / 2 {
        outside.sort_by(f64::total_cmp);
        outside[outside.len() / 2]
    } else {
        level
    };
    if baseline - dark < MIN_SIGNAL_COUNTS {
        return Err(err(format!(
            "the sound surface reads {baseline:.1} counts, within {MIN_SIGNAL_COUNTS} of the \
             fibre's dark level {dark:.1}: too far away to judge"
        )));
    }
    let area = area_below(&x, &v, baseline, window);
    Ok(DipArea {
        baseline,
        area,
        relative_mm: area / (baseline - dark),
        relative_depth: (baseline - floor) / (baseline - dark),
        window_mm: window,
    })
}

/// The dip's relative depth raised over its relative depth in contact (the mean of the contact
/// passes): about 1 for a print, below 1 for a crack. `None` when the contact passes show no
/// dip worth a ratio (under 5 % of the signal): nothing to tell apart. A simpler measure than
/// [`profile_ratio`]: on the simulated trials it separated deep dips as well, and called
/// shallow cracks prints (seeds 3000–3029: five cracks above 0.9). A real fibre whose spot
/// widens with distance would also make a print narrower than the raised spot look shallower
/// raised, and crack-like; its area ratio ([`area_ratio`]) would not.
pub fn height_ratio(contact: &[DipArea], raised: &DipArea) -> Option<f64> {
    ratio_of(contact, raised, |d| d.relative_depth)
}

/// `measure` of `raised` over its mean over `contact`; `None` when that mean is 0.05 or less.
fn ratio_of(contact: &[DipArea], raised: &DipArea, measure: fn(&DipArea) -> f64) -> Option<f64> {
    if contact.is_empty() {
        return None;
    }
    let c = contact.iter().map(measure).sum::<f64>() / contact.len() as f64;
    (c > 0.05).then(|| measure(raised) / c)
}

/// As [`height_ratio`], with the dip's area instead of its depth (blur-proof, noisier in
/// contact). `None` when the contact passes' relative area is under 0.05 mm.
pub fn area_ratio(contact: &[DipArea], raised: &DipArea) -> Option<f64> {
    ratio_of(contact, raised, |d| d.relative_mm)
}

/// Fewest grid cells beside the contact dip [`profile_ratio`] needs to estimate its noise.
const MIN_NOISE_BINS: usize = 6;
/// A contact dip this deep (a share of the signal above the dark level) has reached the fibre's
/// dark level: [`print_ratio`] compares its floor, not its profile.
pub const SATURATED_SHARE: f64 = 0.85;

/// Spacing of the grid the passes' dip profiles are binned onto for [`profile_ratio`], mm.
const GRID_MM: f64 = 0.05;
/// How far beyond the contact dip's window, placed where the profile fit lines the two passes
/// up, the raised dip's floor is searched for, mm ([`print_ratios`]).
pub const RAISED_DIP_SEARCH_MM: f64 = 0.5;
/// Largest shift between the contact and the raised dip [`profile_ratio`] searches, mm (the
/// fibre looks ahead along the motion, so passes in opposite directions see the dip about
/// twice its look-ahead apart).
const MAX_SHIFT_MM: f64 = 6.0;

/// A pass's dip profile `(baseline − P) / (baseline − dark)` binned every [`GRID_MM`] from
/// `x0`; empty bins between samples interpolated, `NaN` beyond the samples.
fn profile(p: &[f64], along: &[f64], dip: &DipArea, dark: f64, x0: f64, n: usize) -> Vec<f64> {
    let mut sum = vec![0.0; n];
    let mut count = vec![0u32; n];
    for (&v, &x) in p.iter().zip(along) {
        let i = ((x - x0) / GRID_MM).floor();
        if i >= 0.0 && (i as usize) < n {
            sum[i as usize] += (dip.baseline - v) / (dip.baseline - dark);
            count[i as usize] += 1;
        }
    }
    let mut out: Vec<f64> = sum
        .iter()
        .zip(&count)
        .map(|(s, &c)| if c > 0 { s / f64::from(c) } else { f64::NAN })
        .collect();
    // Bins between samples (a pass sampled more sparsely than the grid) are interpolated.
    let mut last: Option<usize> = None;
    for i in 0..n {
        if out[i].is_nan() {
            continue;
        }
        if let Some(l) = last.filter(|&l| i > l + 1) {
            for k in l + 1..i {
                let f = (k - l) as f64 / (i - l) as f64;
                out[k] = out[l] + f * (out[i] - out[l]);
            }
        }
        last = Some(i);
    }
    out
}

/// The raised pass's dip as a multiple of the contact pass's: the least-squares factor `k` in
/// `raised(x) ≈ k · contact(x + shift)`, both as shares of their signal above `dark`, at the
/// shift (within ±6 mm) where the two profiles correlate best. About 1 for a print, below 1
/// for a crack, like [`height_ratio`], but from every sample of the dip rather than its
/// floor: a shallow dip's raised floor, a few counts deep, is mostly noise, and its minimum is
/// biased deep (the least-squares factor is not). The contact profile's own noise (its mean
/// square beside the dip) is taken out of the fit's denominator: noise in the template would
/// otherwise pull the factor of a shallow print towards "crack". `None` when the contact dip
/// is under 5 % of its signal or the profiles never overlap over the dip.
///
/// Errors as [`dip_area`] for either pass.
pub fn profile_ratio(
    contact: (&[f64], &[f64]),
    raised: (&[f64], &[f64]),
    dark: f64,
) -> Result<Option<f64>, TactileError> {
    let dc = dip_area(contact.0, contact.1, dark)?;
    let dr = dip_area(raised.0, raised.1, dark)?;
    Ok(fit_profiles(contact, raised, &dc, &dr, dark).map(|fit| fit.factor))
}

/// The least-squares fit of a raised dip onto a contact dip ([`profile_ratio`]).
#[derive(Debug, Clone, Copy, PartialEq)]
struct ProfileFit {
    /// The factor `k` in `raised(x) ≈ k · contact(x + shift)`.
    factor: f64,
    /// Where the raised pass sees the contact dip, relative to the contact pass, mm.
    shift_mm: f64,
}

/// [`profile_ratio`]'s fit of two passes whose dips are already found.
fn fit_profiles(
    contact: (&[f64], &[f64]),
    raised: (&[f64], &[f64]),
    dc: &DipArea,
    dr: &DipArea,
    dark: f64,
) -> Option<ProfileFit> {
    if dc.relative_depth < 0.05 {
        return None;
    }
    let span = |x: &[f64]| {
        x.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            })
    };
    let (c0, c1) = span(contact.1);
    let (r0, r1) = span(raised.1);
    let nc = ((c1 - c0) / GRID_MM).ceil() as usize + 1;
    let nr = ((r1 - r0) / GRID_MM).ceil() as usize + 1;
    let c = profile(contact.0, contact.1, dc, dark, c0, nc);
    let r = profile(raised.0, raised.1, dr, dark, r0, nr);
    // The contact dip's window, in grid cells: the part of the profile that must overlap.
    let w0 = (((dc.window_mm[0] - c0) / GRID_MM).floor().max(0.0) as usize).min(nc - 1);
    let w1 = (((dc.window_mm[1] - c0) / GRID_MM).ceil().max(0.0) as usize).min(nc - 1);
    // The contact profile's noise: its mean square beside the dip, where it should be 0. Noise
    // in the template inflates `Σ c²` by about `n · noise` and biases the factor low (errors
    // in variables); it is taken out below, at most halving `Σ c²`.
    let (mut beside, mut nb) = (0.0, 0usize);
    for (i, &cv) in c.iter().enumerate() {
        if (i < w0 || i > w1) && !cv.is_nan() {
            beside += cv * cv;
            nb += 1;
        }
    }
    let noise = if nb >= MIN_NOISE_BINS {
        beside / nb as f64
    } else {
        0.0
    };
    let max_shift = (MAX_SHIFT_MM / GRID_MM).round() as i64;
    let offset = ((c0 - r0) / GRID_MM).round() as i64;
    let mut best: Option<(f64, ProfileFit)> = None;
    for s in -max_shift..=max_shift {
        let (mut rc, mut cc, mut rr, mut n) = (0.0, 0.0, 0.0, 0usize);
        for (i, &cv) in c.iter().enumerate().take(w1 + 1).skip(w0) {
            let j = i as i64 + offset + s;
            if j < 0 || j >= nr as i64 {
                continue;
            }
            let rv = r[j as usize];
            if cv.is_nan() || rv.is_nan() {
                continue;
            }
            rc += rv * cv;
            cc += cv * cv;
            rr += rv * rv;
            n += 1;
        }
        // Most of the contact window must be seen by the raised pass.
        if n * 4 < (w1 - w0 + 1) * 3 || cc <= 0.0 || rr <= 0.0 {
            continue;
        }
        let corr = rc / (cc * rr).sqrt();
        if best.is_none_or(|(b, _)| corr > b) {
            let fit = ProfileFit {
                factor: rc / (cc - n as f64 * noise).max(0.5 * cc),
                shift_mm: s as f64 * GRID_MM,
            };
            best = Some((corr, fit));
        }
    }
    best.map(|(_, fit)| fit)
}

/// The ratio the robot judges a candidate by: [`profile_ratio`], except where the contact dip
/// has reached the fibre's dark level ([`SATURATED_SHARE`] of its signal or more), where it is
/// [`height_ratio`], the ratio of the two dips' floors (each smoothed over 0.2 mm, as shares of
/// their signal). The raised pass's dip is the one that lines up with the contact dip
/// ([`print_ratios`]).
///
/// Why: where no light comes back in contact (a crack whose floor is beyond the fibre's range)
/// the contact dip is clipped flat at the dark level while the raised one is not, so the two
/// profiles differ in shape and the least-squares factor comes out near 1 whatever the raised
/// dip's depth (wide simulated cracks read 0.89–1.06, as prints). Both floors are then deep,
/// well above the noise, so the floor ratio is reliable; a print can only be that dark with
/// ink close to black, whose raised dip keeps its depth (ratio about 1, still a print).
///
/// Errors as [`dip_area`] for either pass.
pub fn print_ratio(
    contact: (&[f64], &[f64]),
    raised: (&[f64], &[f64]),
    dark: f64,
) -> Result<Option<f64>, TactileError> {
    Ok(print_ratios(contact, raised, dark)?.print)
}

/// Both estimates of one raised pass against one contact pass, from the same two dips.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrintRatios {
    /// [`print_ratio`].
    pub print: Option<f64>,
    /// [`floor_ratio`].
    pub floor: Option<f64>,
    /// The sound surface's level beside the contact dip and beside the raised dip (each dip's
    /// [`DipArea::baseline`]), counts: their ratio above the dark level tells how far the
    /// raised fibre was from the surface at the line (`crackbot_mission::inspect::surface_rise_mm`).
    pub levels: [f64; 2],
}

/// [`print_ratio`] and [`floor_ratio`] of the same passes, from the same two dips.
///
/// The raised pass's dip is the one the profile fit lines up with the contact dip: its floor
/// is searched within the contact dip's window, moved by the fit's shift, and
/// [`RAISED_DIP_SEARCH_MM`] either side ([`dip_area_within`]); the fit is made again against
/// that dip where it is not the pass's deepest. A raised pass overruns the stroke and its fibre
/// looks ahead, so it can reach a line or shadow beside the one judged: its deepest point
/// there set the floor ratio of a 0.77 mm crack beside a 3.5 mm print to 1.15–1.17 on two of
/// four passes, and the crack was rejected as a print (trial 11998;
/// `crates/research/EXPERIMENTS.md`, "The raised dip where the fit puts it"). Where the fit
/// finds no overlap, the deepest point stands; so it does where the contact dip has reached
/// the dark level ([`SATURATED_SHARE`]): a flat-bottomed contact dip lines up loosely with a
/// rounded raised one, and searched where the fit put it, the raised floors of wide cracks
/// read 0.52–0.66 (0.76–0.85 at the deepest point) and a 1.8 mm print's 0.47, a crack; a line
/// that dark is the deepest thing its raised pass meets.
///
/// Errors as [`dip_area`] for either pass.
pub fn print_ratios(
    contact: (&[f64], &[f64]),
    raised: (&[f64], &[f64]),
    dark: f64,
) -> Result<PrintRatios, TactileError> {
    let dc = dip_area(contact.0, contact.1, dark)?;
    let deepest = dip_area(raised.0, raised.1, dark)?;
    if dc.relative_depth >= SATURATED_SHARE {
        // At the dark level the floors decide, the raised one at the pass's deepest point.
        let floor = height_ratio(&[dc], &deepest);
        return Ok(PrintRatios {
            print: floor,
            floor,
            levels: [dc.baseline, deepest.baseline],
        });
    }
    // The raised pass may cross something darker than the line being judged (another line
    // beside it, a shadow past the stroke's end): its dip is the one the profile fit lines up
    // with the contact dip, not the deepest (`RAISED_DIP_SEARCH_MM`).
    let (dr, fit) = match fit_profiles(contact, raised, &dc, &deepest, dark) {
        Some(first) => {
            let within = [
                dc.window_mm[0] + first.shift_mm - RAISED_DIP_SEARCH_MM,
                dc.window_mm[1] + first.shift_mm + RAISED_DIP_SEARCH_MM,
            ];
            let dr = dip_area_within(raised.0, raised.1, dark, Some(within))?;
            let fit = if dr == deepest {
                Some(first)
            } else {
                fit_profiles(contact, raised, &dc, &dr, dark)
            };
            (dr, fit)
        }
        None => (deepest, None),
    };
    Ok(PrintRatios {
        print: fit.map(|fit| fit.factor),
        floor: height_ratio(&[dc], &dr),
        levels: [dc.baseline, dr.baseline],
    })
}

/// The 80th percentile of `smooth` over the samples whose position `x` lies in `[lo, hi]`
/// (the sound surface's level there); the floor sample is always among them.
fn level_within(x: &[f64], smooth: &[f64], [lo, hi]: [f64; 2]) -> f64 {
    let mut sorted: Vec<f64> = x
        .iter()
        .zip(smooth)
        .filter(|(&xi, _)| xi >= lo && xi <= hi)
        .map(|(_, &v)| v)
        .collect();
    sorted.sort_by(f64::total_cmp);
    sorted[(0.8 * (sorted.len() - 1) as f64).round() as usize]
}

/// Where the sound surface's level is read for the dip whose floor is sample `m` (positions
/// `x` sorted, `smooth` the smoothed signal): within [`LEVEL_REACH_MM`] of the floor, or where
/// the dip is so wide that those samples all lie in it, within that distance of where the
/// smoothed signal comes back halfway up to the pass's median. Over a 10 mm crack the raised
/// dip is about 9 mm of flat floor; the noise put its deepest sample anywhere on it, and from
/// its middle the 80th percentile within 5 mm read the floor itself: the crack kept 4–13 % of
/// its dip instead of 78 % and was rejected as "neither a crack nor a print" in about one
/// default-scene mission in fifteen under load. A dip whose level near the floor lies at least
/// halfway up to the median (every narrower dip) keeps the 5 mm reach.
fn level_reach(x: &[f64], smooth: &[f64], m: usize) -> [f64; 2] {
    let reach = [x[m] - LEVEL_REACH_MM, x[m] + LEVEL_REACH_MM];
    let floor = smooth[m];
    let mut sorted = smooth.to_vec();
    sorted.sort_by(f64::total_cmp);
    let half = floor + 0.5 * (sorted[sorted.len() / 2] - floor);
    if level_within(x, smooth, reach) >= half {
        return reach;
    }
    let (mut lo, mut hi) = (m, m);
    while lo > 0 && smooth[lo - 1] < half {
        lo -= 1;
    }
    while hi + 1 < smooth.len() && smooth[hi + 1] < half {
        hi += 1;
    }
    [x[lo] - LEVEL_REACH_MM, x[hi] + LEVEL_REACH_MM]
}

/// The ratio of the two dips' floors ([`height_ratio`] of one contact and one raised pass; each
/// floor smoothed over 0.2 mm, as a share of its signal above `dark`): the second estimate of
/// the same ratio as [`print_ratio`], from the dips' deepest points rather than their profiles.
/// Its errors are not the profile fit's: a raised dip only a few counts deep biases it towards
/// "print" (the least of noisy samples lies below the true floor), while a raised spot wider
/// than the contact one biases the profile fit towards "crack" for a narrow mark. The robot
/// averages the two where the print ratio is in doubt (`crackbot_mission::inspect`,
/// `PRINT_RATIO_DOUBT`). `None` when the contact dip is under 5 % of its signal.
///
/// Errors as [`dip_area`] for either pass.
pub fn floor_ratio(
    contact: (&[f64], &[f64]),
    raised: (&[f64], &[f64]),
    dark: f64,
) -> Result<Option<f64>, TactileError> {
    Ok(print_ratios(contact, raised, dark)?.floor)
}

/// Above this [`print_ratio`] a dip is a print's, not a crack's (chosen on simulated trial
/// scenes 1000–1029, where cracks came out at 0.56–0.87 but for one at 1.06 and decoys at
/// 0.90 or more but for one at 0.84; `crates/research/EXPERIMENTS.md`, "Prints told by two
/// heights").
pub const PRINT_RATIO: f64 = 0.88;

#[cfg(test)]
mod tests {
    use super::*;

    /// A pass over a dip of relative depth `share` and width `w` centred at 5 mm, the sound
    /// surface `signal` counts above a dark level of 280, blurred by a spot of `spot` mm.
    fn pass(share: f64, w: f64, signal: f64, spot: f64) -> (Vec<f64>, Vec<f64>) {
        let along: Vec<f64> = (0..400).map(|i| i as f64 * 0.025).collect();
        let p = along
            .iter()
            .map(|&x| {
                // Coverage of the spot [x - spot/2, x + spot/2] by the mark [5 - w/2, 5 + w/2].
                let (a, b) = (x - spot / 2.0, x + spot / 2.0);
                let cover = ((b.min(5.0 + w / 2.0) - a.max(5.0 - w / 2.0)).max(0.0)) / spot;
                280.0 + signal * (1.0 - share * cover)
            })
            .collect();
        (p, along)
    }

    #[test]
    fn ink_keeps_its_share_at_any_height_and_blur() {
        // Ink of reflectivity 0.4, 0.5 mm wide: contact (224 counts of signal, 1.1 mm spot)
        // against raised (27 counts, a spot twice as wide).
        let (p, x) = pass(0.6, 0.5, 224.0, 1.1);
        let c = dip_area(&p, &x, 280.0).unwrap();
        let (p, x) = pass(0.6, 0.5, 27.0, 2.2);
        let r = dip_area(&p, &x, 280.0).unwrap();
        assert!((c.area - 0.6 * 0.5 * 224.0).abs() < 1.0, "{c:?}");
        let ratio = area_ratio(&[c], &r).unwrap();
        assert!((ratio - 1.0).abs() < 0.02, "{ratio}");
        // The depth keeps its share where the spot does not widen.
        let (p, x) = pass(0.6, 0.5, 27.0, 1.1);
        let r = dip_area(&p, &x, 280.0).unwrap();
        let ratio = height_ratio(&[c], &r).unwrap();
        assert!((ratio - 1.0).abs() < 0.02, "{ratio}");
        assert!(ratio > PRINT_RATIO);
    }

    /// A pass over 0–16 mm across a 0.5 mm mark at 5 mm (a 1.1 mm spot, as [`pass`]),
    /// brighter by `rise` of its signal from 10.5 mm on (a raised pass running onto a bump's
    /// flank or towards a screw head; darker where `rise` is negative).
    fn pass_to_a_bump(share: f64, signal: f64, rise: f64) -> (Vec<f64>, Vec<f64>) {
        let along: Vec<f64> = (0..640).map(|i| i as f64 * 0.025).collect();
        let p = along
            .iter()
            .map(|&x| {
                let cover = ((x + 0.55).min(5.25) - (x - 0.55).max(4.75)).max(0.0) / 1.1;
                let bright = if x >= 10.5 { 1.0 + rise } else { 1.0 };
                280.0 + signal * (bright - share * cover)
            })
            .collect();
        (p, along)
    }

    #[test]
    fn a_bright_stretch_away_from_the_dip_does_not_move_its_ratio() {
        // Contact: ink or a crack, 60 % of the signal. Raised by a print (60 %) or a crack
        // (30 %), a third of the pass 35 % brighter, as a bump's flank reads: it must not
        // set the level or the baseline (read over the whole pass, they made the print 1.86
        // and the crack 1.09, a print).
        let contact = pass_to_a_bump(0.6, 224.0, 0.0);
        for (raised_share, want) in [(0.6, 1.0), (0.3, 0.5)] {
            let raised = pass_to_a_bump(raised_share, 27.0, 0.35);
            let r = print_ratio((&contact.0, &contact.1), (&raised.0, &raised.1), 280.0)
                .unwrap()
                .unwrap();
            assert!(
                (r - want).abs() < 0.03,
                "raised share {raised_share}: ratio {r}"
            );
            let d = dip_area(&raised.0, &raised.1, 280.0).unwrap();
            assert!((d.baseline - 307.0).abs() < 0.5, "{d:?}");
        }
    }

    #[test]
    fn a_wide_flat_dip_reads_the_sound_surface_wherever_its_deepest_sample_lies() {
        // The default scene's 10 mm crack raised 2 mm (its recorded pass): 0–20 mm, the sound
        // surface 35 counts above a dark level of 215, a flat floor 25 counts lower over
        // 3.5–12.5 mm with a count of ripple, its deepest sample put at `deepest` mm.
        let along: Vec<f64> = (0..800).map(|i| f64::from(i) * 0.025).collect();
        let raised = |deepest: f64| -> Vec<f64> {
            along
                .iter()
                .map(|&x| {
                    if !(3.5..=12.5).contains(&x) {
                        250.0
                    } else if (x - deepest).abs() < 0.15 {
                        224.0
                    } else {
                        225.0 + 0.5 * (7.0 * x).sin()
                    }
                })
                .collect()
        };
        for deepest in [4.0, 8.0, 12.0] {
            let d = dip_area(&raised(deepest), &along, 215.0).unwrap();
            assert!(
                (d.baseline - 250.0).abs() < 0.5,
                "deepest at {deepest}: {d:?}"
            );
            assert!((d.relative_depth - 26.0 / 35.0).abs() < 0.02, "{d:?}");
        }
        // A narrow dip keeps the 5 mm reach: the bright stretch 5.5 mm away stays out of it
        // (a_bright_stretch_away_from_the_dip_does_not_move_its_ratio).
    }

    #[test]
    fn a_darker_stretch_farther_along_the_raised_pass_is_not_the_dip() {
        // Contact: a 0.5 mm crack at 5 mm, 60 % of the signal where it covers the spot.
        // Raised: the same crack at 45 % (a crack: 0.75), the pass running from 10.5 mm on
        // over something darker, 60 % of its signal (the print beside trial 11998's 0.77 mm
        // crack, which its raised passes reached beyond the stroke's end). That stretch is the
        // raised pass's deepest point...
        let contact = pass_to_a_bump(0.6, 224.0, 0.0);
        let raised = pass_to_a_bump(0.45, 27.0, -0.6);
        let deepest = dip_area(&raised.0, &raised.1, 280.0).unwrap();
        assert!(deepest.window_mm[0] > 9.0, "{deepest:?}");
        // ...but both estimates judge the crack's own dip, where the fit lines the two up (its
        // floor against the stretch's read 2.2, a print).
        let r = print_ratios((&contact.0, &contact.1), (&raised.0, &raised.1), 280.0).unwrap();
        let (print, floor) = (r.print.unwrap(), r.floor.unwrap());
        assert!((print - 0.75).abs() < 0.03, "{r:?}");
        assert!((floor - 0.75).abs() < 0.03, "{r:?}");
        // Searched within a window, the dip is the one there; a window holding no sample is
        // the whole pass.
        let own = dip_area_within(&raised.0, &raised.1, 280.0, Some([4.0, 6.0])).unwrap();
        assert!(own.window_mm[0] < 5.0 && own.window_mm[1] > 5.0, "{own:?}");
        let none = dip_area_within(&raised.0, &raised.1, 280.0, Some([40.0, 41.0])).unwrap();
        assert_eq!(none, deepest);
    }

    #[test]
    fn a_crack_loses_share_when_raised() {
        // A 1 mm crack 2 mm deep under the calibrated curve (far side, 1/d²): the floor is
        // 3.03 mm away in contact and 5.03 mm raised by 2 mm.
        let share = |d0: f64, depth: f64| 1.0 - (d0 / (d0 + depth)).powi(2);
        let (p, x) = pass(share(1.026, 2.0), 1.0, 224.0, 1.1);
        let c = dip_area(&p, &x, 280.0).unwrap();
        let (p, x) = pass(share(3.026, 2.0), 1.0, 27.0, 1.1);
        let r = dip_area(&p, &x, 280.0).unwrap();
        let ratio = height_ratio(&[c], &r).unwrap();
        assert!(ratio < 0.75, "{ratio}");
        assert!(ratio < PRINT_RATIO);
        let ratio = area_ratio(&[c], &r).unwrap();
        assert!(ratio < 0.75, "{ratio}");
    }

    #[test]
    fn the_floor_ratio_tells_ink_from_a_crack_and_names_bad_passes() {
        let share = |d0: f64, depth: f64| 1.0 - (d0 / (d0 + depth)).powi(2);
        let ratio = |contact: (Vec<f64>, Vec<f64>), raised: (Vec<f64>, Vec<f64>)| {
            floor_ratio((&contact.0, &contact.1), (&raised.0, &raised.1), 280.0)
                .unwrap()
                .unwrap()
        };
        // Ink keeps its share raised; a crack's floor loses it.
        let ink = ratio(pass(0.6, 1.0, 224.0, 1.1), pass(0.6, 1.0, 27.0, 1.1));
        assert!((ink - 1.0).abs() < 0.02 && ink > PRINT_RATIO, "{ink}");
        let crack = ratio(
            pass(share(1.026, 2.0), 1.0, 224.0, 1.1),
            pass(share(3.026, 2.0), 1.0, 27.0, 1.1),
        );
        assert!(crack < 0.75, "{crack}");
        // Both ratios come with the sound surface's level beside each dip.
        let (c, cx) = pass(0.6, 1.0, 224.0, 1.1);
        let (r, rx) = pass(0.6, 1.0, 27.0, 1.1);
        let levels = print_ratios((&c, &cx), (&r, &rx), 280.0).unwrap().levels;
        assert!(
            (levels[0] - 504.0).abs() < 0.5 && (levels[1] - 307.0).abs() < 0.5,
            "{levels:?}"
        );
        // No dip in contact: nothing to compare.
        let (flat, x) = pass(0.0, 1.0, 224.0, 1.1);
        let (raised, rx) = pass(0.6, 1.0, 27.0, 1.1);
        assert_eq!(
            floor_ratio((&flat, &x), (&raised, &rx), 280.0).unwrap(),
            None
        );
        // A raised pass that reads nothing above the dark level is an error naming it.
        let dark_pass = vec![281.0; rx.len()];
        let e = floor_ratio((&flat, &x), (&dark_pass, &rx), 280.0).unwrap_err();
        assert!(e.to_string().contains("dark level"), "{e}");
    }

    /// `pass` with deterministic noise of about `sigma` counts, the positions shifted by
    /// `shift` mm and taken every `step` mm.
    fn noisy(
        share: f64,
        w: f64,
        signal: f64,
        shift: f64,
        step: f64,
        sigma: f64,
    ) -> (Vec<f64>, Vec<f64>) {
        let (p, x) = pass(share, w, signal, 1.1);
        let mut seed = 12345u64;
        let mut out = (Vec::new(), Vec::new());
        let every = (step / 0.025).round().max(1.0) as usize;
        for (i, (v, xi)) in p.iter().zip(&x).enumerate() {
            if i % every != 0 {
                continue;
            }
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let u = (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            out.0.push(v + sigma * 3.46 * u);
            out.1.push(xi + shift);
        }
        out
    }

    /// [`profile_ratio`] of two passes that both have a dip, over a dark level of 280.
    fn fitted(contact: (&[f64], &[f64]), raised: (&[f64], &[f64])) -> f64 {
        profile_ratio(contact, raised, 280.0).unwrap().unwrap()
    }

    #[test]
    fn the_profile_fit_finds_the_shifted_raised_dip_and_its_share_through_noise() {
        // A shallow print: 20 % of the signal, 0.8 mm wide. In contact (224 counts, slow) and
        // raised (27 counts, 0.1 mm a sample, 0.5 counts of noise, seen 3.6 mm later).
        let (cp, cx) = noisy(0.2, 0.8, 224.0, 0.0, 0.025, 0.5);
        let (rp, rx) = noisy(0.2, 0.8, 27.0, 3.6, 0.1, 0.5);
        let k = fitted((&cp, &cx), (&rp, &rx));
        assert!((k - 1.0).abs() < 0.08, "{k}");
        // The same dip raised at 70 % of its share: a crack.
        let (rp, rx) = noisy(0.14, 0.8, 27.0, -3.6, 0.1, 0.5);
        let k = fitted((&cp, &cx), (&rp, &rx));
        assert!((k - 0.7).abs() < 0.08, "{k}");
        // No dip in contact: nothing to compare.
        let (fp, fx) = noisy(0.0, 0.8, 224.0, 0.0, 0.025, 0.5);
        assert_eq!(profile_ratio((&fp, &fx), (&rp, &rx), 280.0).unwrap(), None);
        assert!(profile_ratio((&cp[..5], &cx[..5]), (&rp, &rx), 280.0).is_err());
    }

    #[test]
    fn a_noisy_contact_template_does_not_pull_a_print_towards_a_crack() {
        // A print of 25 % of the signal, 1 mm wide, with 20 counts of noise in contact (a
        // template this noisy biased the plain least-squares factor to about 0.8).
        let (cp, cx) = noisy(0.25, 1.0, 224.0, 0.0, 0.025, 20.0);
        let (rp, rx) = noisy(0.25, 1.0, 27.0, 2.0, 0.1, 0.3);
        let k = fitted((&cp, &cx), (&rp, &rx));
        assert!((k - 1.0).abs() < 0.1, "{k}");
    }

    #[test]
    fn a_dip_at_the_dark_level_is_judged_by_its_floors() {
        // A wide crack whose floor is beyond the fibre's range: 92 % of the signal in contact,
        // 72 % raised. Its floors say crack.
        let (cp, cx) = noisy(0.92, 4.0, 224.0, 0.0, 0.025, 0.5);
        let (rp, rx) = noisy(0.72, 4.0, 27.0, 1.0, 0.1, 0.3);
        let k = print_ratio((&cp, &cx), (&rp, &rx), 280.0).unwrap().unwrap();
        assert!((k - 0.72 / 0.92).abs() < 0.05, "{k}");
        assert!(k < PRINT_RATIO);
        // Ink as dark keeps its floor raised: a print.
        let (rp, rx) = noisy(0.92, 4.0, 27.0, 1.0, 0.1, 0.3);
        let k = print_ratio((&cp, &cx), (&rp, &rx), 280.0).unwrap().unwrap();
        assert!(k > PRINT_RATIO, "{k}");
        // Below the dark level's share it is the profile fit.
        let (cp, cx) = noisy(0.5, 1.0, 224.0, 0.0, 0.025, 0.5);
        let (rp, rx) = noisy(0.5, 1.0, 27.0, 1.0, 0.1, 0.3);
        let a = print_ratio((&cp, &cx), (&rp, &rx), 280.0).unwrap();
        let b = profile_ratio((&cp, &cx), (&rp, &rx), 280.0).unwrap();
        assert_eq!(a, b);
        assert!(print_ratio((&cp[..5], &cx[..5]), (&rp, &rx), 280.0).is_err());
    }

    #[test]
    fn bad_passes_are_named() {
        let (p, x) = pass(0.5, 1.0, 100.0, 1.0);
        let e = dip_area(&p[..10], &x[..10], 280.0).unwrap_err().to_string();
        assert!(e.contains("10 samples"), "{e}");
        let e = dip_area(&p, &x[..300], 280.0).unwrap_err().to_string();
        assert!(e.contains("400 proximity samples but 300 positions"), "{e}");
        let mut q = p.clone();
        q[7] = f64::NAN;
        let e = dip_area(&q, &x, 280.0).unwrap_err().to_string();
        assert!(e.contains("sample 7"), "{e}");
        let still = vec![3.0; 400];
        let e = dip_area(&p, &still, 280.0).unwrap_err().to_string();
        assert!(e.contains("spans 0.000 mm"), "{e}");
        let e = dip_area(&p, &x, 379.0).unwrap_err().to_string();
        assert!(e.contains("dark level"), "{e}");
        assert!(dip_area(&p, &x, f64::INFINITY).is_err());
    }

    #[test]
    fn a_pass_without_a_dip_has_no_ratio_and_noise_is_no_dip() {
        let (p, x) = pass(0.0, 1.0, 224.0, 1.1);
        let c = dip_area(&p, &x, 280.0).unwrap();
        assert!(c.area.abs() < 1e-9);
        assert_eq!(height_ratio(&[c], &c), None);
        assert_eq!(height_ratio(&[], &c), None);
        assert_eq!(area_ratio(&[c], &c), None);
    }
}
