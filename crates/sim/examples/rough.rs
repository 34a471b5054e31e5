//! Roughness fit (development aid).
#![allow(clippy::unwrap_used, missing_docs)]
fn main() {
    let p = std::path::PathBuf::from(std::env::args().nth(1).unwrap());
    let r = crackbot_recording::read_recording(&p).unwrap();
    let o = crackbot_sim::calibrate::calibrated_sensor().optics;
    println!("{}", crackbot_sim::calibrate::fit_roughness(&o, &[r]));
}
