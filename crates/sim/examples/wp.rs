//! Work-precision table (development aid; the CLI has `crackbot sim work-precision`).
#![allow(clippy::unwrap_used, missing_docs)]
fn main() {
    let rows = crackbot_sim::work_precision::work_precision(
        &crackbot_sim::work_precision::default_methods(),
        |_, _| {},
    )
    .unwrap();
    for r in rows {
        println!(
            "{:28} rms {:>10.4?} max {:>10.4?} ms/s {:8.3} x{:8.0} rhs/s {:8.0} {:?}",
            r.method,
            r.rms_error_counts,
            r.max_error_counts,
            r.ms_per_sim_second,
            r.real_time_factor,
            r.rhs_per_sim_second,
            r.failure
        );
    }
}
