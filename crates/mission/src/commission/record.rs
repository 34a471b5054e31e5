//! The papers' protocol on one mounted plate: for each repetition, slides of the stroke's
//! length across the feature, forth and back alternately, each pair from a start 5–10 mm
//! before the feature's near edge (the papers: "the initial position … was not controlled and
//! varied … ~5–10 mm from the crack edge"), recorded as one recording in the authors' layout.
//! A start drawn per pair, not per repetition: with one start per repetition a model trained
//! on two repetitions had seen two starts, and read 86–96 % of a third one's windows (one
//! simulated commissioning, 12 slides a repetition).

use crackbot_plates::set::FEATURE_X_MM;
use crackbot_plates::ReferencePlate;
use crackbot_recording::{Recording, Row};
use rand::{Rng, SeedableRng};

use super::settings::CommissionSettings;
use crate::inspect::rig::context::Rig;
use crate::inspect::rig::feel::Feel;
use crate::MissionError;

/// Where a repetition's slides start, mm before the feature's near edge.
pub const START_BEFORE_EDGE_MM: [f64; 2] = [5.0, 10.0];
/// How far from the plate's middle line (y = 50 mm) a repetition's slides may run, mm.
const LINE_SPREAD_MM: f64 = 2.0;

/// One slide: from, to (mm, the plate frame) and the authors' direction column (1: +x).
pub type SlideLine = ([f64; 2], [f64; 2], u8);

/// The slides of repetition `rep` (1-based) on `plate`: pure, seeded by the settings' seed,
/// the plate and the repetition.
pub fn slide_lines(plate: &ReferencePlate, rep: u32, s: &CommissionSettings) -> Vec<SlideLine> {
    let seed = s.seed
        ^ (u64::from(rep) << 32)
        ^ plate
            .name
            .bytes()
            .fold(0u64, |h, b| h.wrapping_mul(31).wrapping_add(u64::from(b)));
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    // A crack's or a bump's near edge; the flat plate and the waves from their middle.
    let edge = match plate.feature_span_mm() {
        Some([lo, _]) if plate.recognition_label != 3 => lo,
        _ => FEATURE_X_MM,
    };
    let mut lines = Vec::new();
    for k in 0..s.slides {
        if k % 2 == 0 {
            let x0 = edge - rng.random_range(START_BEFORE_EDGE_MM[0]..=START_BEFORE_EDGE_MM[1]);
            let y =
                plate.surface.size_mm[1] / 2.0 + rng.random_range(-LINE_SPREAD_MM..=LINE_SPREAD_MM);
            lines.push(([x0, y], [x0 + s.stroke_mm, y], 1));
        } else if let Some(&(a, b, _)) = lines.last() {
            lines.push((b, a, 0));
        }
    }
    lines
}

/// Slides repetition `rep` over the mounted `plate`; its recording, labelled `label`.
/// `done` is told after each slide.
pub(crate) fn record_repetition(
    rig: &mut Rig<'_>,
    (plate, rep, label): (&ReferencePlate, u32, f64),
    s: &CommissionSettings,
    feel: &mut Feel<'_>,
    done: &mut dyn FnMut(),
) -> Result<Recording, MissionError> {
    let mut rows = Vec::new();
    for (k, (a, b, dir)) in slide_lines(plate, rep, s).into_iter().enumerate() {
        let id = k as u32 + 1;
        let ((samples, along), _) = rig.slide_and_record(id, (a, b), s.speed_mm_s, dir, feel)?;
        let sign = if dir == 1 { 1.0 } else { -1.0 };
        rows.extend(samples.iter().zip(&along).map(|(v, &x)| Row {
            x_mm: a[0] + sign * x,
            d1: v[0],
            d2: v[1],
            d3: v[2],
            p: v[3],
            direction: dir,
            slide: id,
            label,
            repetition: rep,
        }));
        done();
    }
    Ok(Recording { rows, extra: None })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crackbot_plates::by_name;

    #[test]
    fn slides_cross_the_feature_forth_and_back_from_a_seeded_start() {
        let s = CommissionSettings::default();
        let crack = by_name("crack-10mm").unwrap();
        let lines = slide_lines(&crack, 1, &s);
        assert_eq!(lines.len(), 6);
        let (a, b, dir) = lines[0];
        assert_eq!(dir, 1);
        assert_eq!(lines[1], (b, a, 0));
        // 5–10 mm before the near edge (95 mm, less the rounded edge), 16 mm long.
        assert!((84.4..=90.0).contains(&a[0]), "{a:?}");
        assert!((b[0] - a[0] - 16.0).abs() < 1e-9 && (a[1] - 50.0).abs() <= 2.0);
        assert_eq!(slide_lines(&crack, 1, &s), lines, "seeded");
        assert_ne!(
            slide_lines(&crack, 2, &s),
            lines,
            "each repetition starts elsewhere"
        );
        // The bump's: before its foot (x = 92), ending over it.
        let (a, b, _) = slide_lines(&by_name("bump").unwrap(), 1, &s)[0];
        assert!(a[0] <= 87.0 && b[0] >= 98.0, "{a:?} {b:?}");
    }
}
