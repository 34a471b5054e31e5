//! Writes the real MAV D1D2+P windows of the surface-type experiment (repetition 1 → `train.csv`,
//! repetition 2 → `test.csv`; columns `mav_d1,mav_d2,mav_p,class`) for `benches/sklearn_ort.py`, the same
//! windows `benches/tactile.rs` uses.
//!
//! `cargo run --release -p crackbot-research --example export_windows -- benches/out`

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crackbot_tactile::dataset::WindowSet;

#[path = "../../../benches/common/windows.rs"]
mod windows;

fn write(path: &Path, set: &WindowSet) -> std::io::Result<()> {
    let mut s = String::from("mav_d1,mav_d2,mav_p,class\n");
    for (i, &class) in set.y.iter().enumerate() {
        for v in set.row(i) {
            // `{}` prints the shortest decimal that reads back as the same f32.
            let _ = write!(s, "{v},");
        }
        let _ = writeln!(s, "{class}");
    }
    std::fs::write(path, s)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "benches/out".into()),
    );
    std::fs::create_dir_all(&out)?;
    let real = windows::load(&windows::data_dir());
    write(&out.join("train.csv"), &real.train)?;
    write(&out.join("test.csv"), &real.test)?;
    println!(
        "{}: {} train windows (repetition 1), {} test windows (repetition 2), {} features",
        out.display(),
        real.train.n_rows(),
        real.test.n_rows(),
        real.train.n_features
    );
    Ok(())
}
