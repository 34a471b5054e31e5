//! The recordings a mission leaves: one CSV per pass in the acquisition's columns plus the
//! position along the pass.

use std::path::Path;

use crate::error::io_err;
use crate::MissionError;

/// A pass's samples (D1, D2, D3, P counts) and positions (mm along the pass).
pub(crate) type Recorded = (Vec<[f64; 4]>, Vec<f64>);

/// Writes one pass in the recordings' CSV layout (the acquisition's columns plus the position).
pub(crate) fn save_pass(
    path: &Path,
    samples: &[[f64; 4]],
    positions: &[f64],
    dir: u8,
) -> Result<(), MissionError> {
    use std::io::Write;
    let f = std::fs::File::create(path).map_err(|e| io_err(path, e))?;
    let mut w = std::io::BufWriter::new(f);
    let mut put = || -> std::io::Result<()> {
        writeln!(w, "d1,d2,d3,p,direction,x_mm")?;
        for (s, x) in samples.iter().zip(positions) {
            writeln!(w, "{},{},{},{},{dir},{x:.4}", s[0], s[1], s[2], s[3])?;
        }
        w.flush()
    };
    put().map_err(|e| io_err(path, e))
}
