#![allow(clippy::unwrap_used, missing_docs)]
use crackbot_sim::finger::*;
use crackbot_sim::surface::*;
fn main() {
    let s = Surface {
        size_mm: [200.0, 100.0],
        features: vec![Feature::Crack {
            path: vec![[100.0, 0.0], [100.0, 100.0]],
            width_mm: 5.0,
            depth_mm: 3.0,
            edge_radius_mm: 0.2,
            wall_angle_deg: 90.0,
        }],
    };
    let params = FingerParams {
        tip_radius_mm: 1.0,
        ..FingerParams::default()
    };
    let profile = s.profile([80.0, 50.0], [120.0, 50.0], 0.01);
    let model = FingerModel::new(&params, Envelope::new(&profile, 1.0));
    let slope = |x: f64| model.envelope().at(x).1.abs();
    let x = (1000..3000)
        .map(|k| f64::from(k) * 1e-5)
        .max_by(|a, b| slope(*a).total_cmp(&slope(*b)))
        .unwrap();
    println!("x {x} env {:?}", model.envelope().at(x));
    for k in -5..=5 {
        let xx = x + k as f64 * 2e-6;
        println!("  {xx:.7} {:?}", model.envelope().at(xx));
    }
    let mut y = model.rest_state(x);
    y[1] += 1e-4;
    y[2] = 0.01;
    y[3] = -0.02;
    y[5] = 0.005;
    let mut st = Stepper::new(Integrator::BackwardEuler { substeps: 1 });
    let arm = Still(x);
    for k in 0..20 {
        let prev = y;
        if let Err(e) = st.advance(&model, &arm, k as f64 * 0.0025, 0.0025, &mut y) {
            println!("{e}\nprev {prev:?}\nrhs {:?}", model.rhs(0.0, &prev, &arm));
            break;
        }
        println!("{k} {y:?}");
    }
}
