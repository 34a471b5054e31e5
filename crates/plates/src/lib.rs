//! The reference plates a finger is commissioned on: the papers' set (a flat plate, cracks of
//! 1, 2, 5, 8 and 10 mm, a bump, a wavy pattern) as files a user prints.
//!
//! * [`set`]: which plates, their geometry (the simulator's [`Surface`](crackbot_surface::Surface)s,
//!   so a simulated commissioning slides over what is printed) and each plate's labels;
//! * [`mesh`]: each plate as a closed, consistently wound STL mesh (mm);
//! * [`drawing`]: each plate's sheet, an A4 PNG at true scale with its dimensions and mounting.
//!
//! [`write_set`] writes them all with a manifest (`plates.toml`); `crackbot commission plates`
//! calls it. The format is in `crates/plates/docs/plates.md`.

pub mod drawing;
pub mod error;
pub mod mesh;
pub mod set;

use std::path::{Path, PathBuf};

pub use error::PlateError;
pub use set::{by_name, reference_set, ReferencePlate};

/// What [`write_set`] wrote for one plate.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Written {
    /// The plate's name.
    pub name: String,
    /// What it is.
    pub title: String,
    /// Its class in the surface-type experiment (0 no crack, 1 crack, 2 bump, 3 wavy).
    pub recognition_label: u8,
    /// Its label in the width experiment, mm (absent: not one of its plates).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub width_label_mm: Option<f64>,
    /// The mesh, relative to the manifest.
    pub stl: PathBuf,
    /// Triangles in it.
    pub triangles: usize,
    /// The drawing, relative to the manifest.
    pub drawing: PathBuf,
}

/// The manifest.
#[derive(serde::Serialize)]
struct Manifest<'a> {
    /// Thickness under the sound surface, mm.
    thickness_mm: f64,
    /// The drawings' scale.
    drawing_px_per_mm: f64,
    plate: &'a [Written],
}

/// Writes every plate's STL and drawing (at `px_per_mm`) into `dir` (created) and the manifest
/// `plates.toml`; what was written, plate by plate.
pub fn write_set(dir: &Path, px_per_mm: f64) -> Result<Vec<Written>, PlateError> {
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| PlateError::Io { path, source }
    };
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let mut written = Vec::new();
    for plate in reference_set() {
        let stl = PathBuf::from(format!("{}.stl", plate.name));
        let png = PathBuf::from(format!("{}.png", plate.name));
        let triangles = mesh::write_stl(&plate, &dir.join(&stl))?;
        drawing::write_png(&plate, px_per_mm, &dir.join(&png))?;
        written.push(Written {
            name: plate.name,
            title: plate.title,
            recognition_label: plate.recognition_label,
            width_label_mm: plate.width_label_mm,
            stl,
            triangles,
            drawing: png,
        });
    }
    let manifest = Manifest {
        thickness_mm: set::THICKNESS_MM,
        drawing_px_per_mm: px_per_mm,
        plate: &written,
    };
    let text = toml::to_string_pretty(&manifest).expect("the manifest serialises");
    let path = dir.join("plates.toml");
    std::fs::write(&path, text).map_err(io(&path))?;
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_set_is_written_with_its_manifest_and_drawings_at_true_scale() {
        let dir = tempfile::tempdir().unwrap();
        let written = write_set(dir.path(), 4.0).unwrap();
        assert_eq!(written.len(), 8);
        let manifest = std::fs::read_to_string(dir.path().join("plates.toml")).unwrap();
        assert_eq!(manifest.matches("[[plate]]").count(), 8, "{manifest}");
        // The 10 mm crack's drawing: A4 at 4 px/mm, stated in the file; the plan's row through
        // the plate's middle is dark exactly across the crack (x = 95–105 mm).
        let path = dir.path().join("crack-10mm.png");
        let decoder =
            png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
        let reader = decoder.read_info().unwrap();
        let dims = reader.info().pixel_dims.unwrap();
        assert_eq!((dims.xppu, dims.unit), (4000, png::Unit::Meter));
        let img = image::open(&path).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (840, 1188));
        // A row of the plan 20 mm below its top edge (y = 80 mm on the plate).
        let row = ((drawing_plan_top() + 20.0) * 4.0) as u32;
        // (Inside the outline, drawn 0.3 mm wide.)
        let dark: Vec<u32> = ((7 * 4)..(203 * 4))
            .filter(|&x| img.get_pixel(x, row)[0] < 180)
            .collect();
        let (first, last) = (
            dark[0] as f64 / 4.0 - 5.0,
            *dark.last().unwrap() as f64 / 4.0 - 5.0,
        );
        assert!(
            (first - 95.0).abs() < 0.6 && (last - 105.0).abs() < 0.6,
            "{first}–{last} mm"
        );
    }

    fn drawing_plan_top() -> f64 {
        48.0
    }
}
