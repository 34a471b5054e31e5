//! The reference set: which plates, their geometry (the simulator's surfaces, so a simulated
//! commissioning slides over exactly what is printed) and the labels each one's slides carry.

use crackbot_surface::{Feature, Surface};

/// Size of every plate, mm (the simulator's plates: 200 × 100).
pub const PLATE_SIZE_MM: [f64; 2] = [200.0, 100.0];
/// Thickness of the plates under the sound surface, mm.
pub const THICKNESS_MM: f64 = 6.0;
/// Depth of every crack, mm (the simulator's fit of the authors' printed cross-section).
pub const CRACK_DEPTH_MM: f64 = 2.53;
/// The cracks' walls, degrees from the plate (vertical: nothing to support when printing).
pub const CRACK_WALL_ANGLE_DEG: f64 = 90.0;
/// Radius of the cracks' rounded edges, mm.
pub const CRACK_EDGE_RADIUS_MM: f64 = 0.5;
/// The widths of the papers' width experiment, mm (0: the flat plate).
pub const WIDTHS_MM: [f64; 6] = [0.0, 1.0, 2.0, 5.0, 8.0, 10.0];
/// The width of the surface-type experiment's crack plate, mm (one of [`WIDTHS_MM`]).
pub const RECOGNITION_CRACK_MM: f64 = 5.0;
/// The bump: base radius and height, mm (its footprint, 10 mm across, is the widest crack's:
/// the papers' 16 mm stroke from 5–10 mm before it reaches over its top; the simulator's
/// calibrated 8 mm bump was only ever climbed and read as the wavy plate's rising flank).
pub const BUMP_MM: [f64; 2] = [5.0, 1.5];
/// The wavy pattern: amplitude and period, mm (the paper: "sine waves of 1 mm amplitude and
/// 5 mm" period), over x = 40–160 mm.
pub const WAVE_MM: [f64; 2] = [1.0, 5.0];
/// Where each plate's feature lies, mm along x (it runs across the plate, along y).
pub const FEATURE_X_MM: f64 = 100.0;
/// Where a crack's slot runs, mm along y (its ends rounded): 10 mm of sound plate beyond each
/// end keep the plate in one piece and inside the simulator's plate.
pub const CRACK_Y_MM: [f64; 2] = [10.0, 90.0];

/// The surface-type experiment's classes, in label order.
pub const RECOGNITION_CLASSES: [&str; 4] = ["no crack", "crack", "bump", "wavy"];

/// One plate of the set.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferencePlate {
    /// File stem: `flat`, `crack-1mm` … `crack-10mm`, `bump`, `wavy`.
    pub name: String,
    /// What it is, for people.
    pub title: String,
    /// Its class in the surface-type experiment ([`RECOGNITION_CLASSES`]).
    pub recognition_label: u8,
    /// Its label in the width experiment, mm (`None`: not one of its plates).
    pub width_label_mm: Option<f64>,
    /// Its top surface (heights relative to the sound surface, which is at 0).
    pub surface: Surface,
}

impl ReferencePlate {
    /// The x range (mm) where the surface departs from flat: the feature and its edges.
    pub fn feature_span_mm(&self) -> Option<[f64; 2]> {
        self.footprint_mm().map(|f| [f[0], f[1]])
    }

    /// The feature's footprint, mm: `[x_min, x_max, y_min, y_max]`.
    pub fn footprint_mm(&self) -> Option<[f64; 4]> {
        self.surface.features.iter().fold(None, |acc, f| {
            let (lo, hi) = f.footprint();
            Some(match acc {
                None => [lo[0], hi[0], lo[1], hi[1]],
                Some([a, b, c, d]) => [a.min(lo[0]), b.max(hi[0]), c.min(lo[1]), d.max(hi[1])],
            })
        })
    }
}

/// A crack of width `w` mm across the plate at [`FEATURE_X_MM`].
fn crack(w: f64) -> Feature {
    Feature::Crack {
        path: vec![[FEATURE_X_MM, CRACK_Y_MM[0]], [FEATURE_X_MM, CRACK_Y_MM[1]]],
        width_mm: w,
        depth_mm: CRACK_DEPTH_MM,
        edge_radius_mm: CRACK_EDGE_RADIUS_MM,
        wall_angle_deg: CRACK_WALL_ANGLE_DEG,
    }
}

fn plate(features: Vec<Feature>) -> Surface {
    Surface {
        size_mm: PLATE_SIZE_MM,
        features,
    }
}

fn width_name(w: f64) -> String {
    if w.fract() == 0.0 {
        format!("{w:.0}")
    } else {
        format!("{w}").replace('.', "p")
    }
}

/// The papers' set: the flat plate (no crack, 0 mm), the cracks of 1, 2, 5, 8 and 10 mm (the
/// 5 mm one is also the surface-type experiment's crack), the bump and the wavy pattern.
pub fn reference_set() -> Vec<ReferencePlate> {
    let mut set = vec![ReferencePlate {
        name: "flat".into(),
        title: "flat plate (no crack; the 0 mm width)".into(),
        recognition_label: 0,
        width_label_mm: Some(0.0),
        surface: plate(Vec::new()),
    }];
    for &w in WIDTHS_MM.iter().filter(|&&w| w > 0.0) {
        let also = if w == RECOGNITION_CRACK_MM {
            " (also the surface-type experiment's crack)"
        } else {
            ""
        };
        set.push(ReferencePlate {
            name: format!("crack-{}mm", width_name(w)),
            title: format!("crack {w} mm wide, {CRACK_DEPTH_MM} mm deep{also}"),
            recognition_label: 1,
            width_label_mm: Some(w),
            surface: plate(vec![crack(w)]),
        });
    }
    set.push(ReferencePlate {
        name: "bump".into(),
        title: format!("bump {} mm in radius, {} mm high", BUMP_MM[0], BUMP_MM[1]),
        recognition_label: 2,
        width_label_mm: None,
        surface: plate(vec![Feature::Bump {
            centre: [FEATURE_X_MM, PLATE_SIZE_MM[1] / 2.0],
            radius_mm: BUMP_MM[0],
            height_mm: BUMP_MM[1],
        }]),
    });
    set.push(ReferencePlate {
        name: "wavy".into(),
        title: format!(
            "wavy pattern, {} mm amplitude, {} mm period",
            WAVE_MM[0], WAVE_MM[1]
        ),
        recognition_label: 3,
        width_label_mm: None,
        surface: plate(vec![Feature::Wavy {
            min: [40.0, 0.0],
            max: [160.0, PLATE_SIZE_MM[1]],
            amplitude_mm: WAVE_MM[0],
            period_mm: WAVE_MM[1],
            direction_deg: 0.0,
        }]),
    });
    set
}

/// The plate of the set named `name`.
pub fn by_name(name: &str) -> Option<ReferencePlate> {
    reference_set().into_iter().find(|p| p.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_set_has_every_class_and_width_once() {
        let set = reference_set();
        assert_eq!(set.len(), 8);
        for class in 0..4 {
            assert!(set.iter().any(|p| p.recognition_label == class), "{class}");
        }
        let mut widths: Vec<f64> = set.iter().filter_map(|p| p.width_label_mm).collect();
        widths.sort_by(f64::total_cmp);
        assert_eq!(widths, WIDTHS_MM);
        // The crack's walls: 2.53 mm below the sound surface inside, 0 outside.
        let c10 = by_name("crack-10mm").unwrap();
        assert!((c10.surface.height_mm([100.0, 50.0]) + CRACK_DEPTH_MM).abs() < 1e-9);
        assert_eq!(c10.surface.height_mm([80.0, 50.0]), 0.0);
        let span = c10.feature_span_mm().unwrap();
        assert!(span[0] < 95.0 && span[1] > 105.0, "{span:?}");
        assert!(by_name("flat").unwrap().feature_span_mm().is_none());
    }

    #[test]
    fn every_plate_is_a_valid_simulated_scene() {
        for plate in reference_set() {
            let mut scene = crackbot_sim::Scene::builtin_default();
            scene.plate.size_mm = plate.surface.size_mm;
            scene.features.clone_from(&plate.surface.features);
            scene.camera = None;
            scene
                .validate()
                .unwrap_or_else(|e| panic!("{}: {e}", plate.name));
        }
    }
}
