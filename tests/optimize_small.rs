//! A small gust-constrained mass minimization end to end (coarse DLM, 4 modes): the SQP reaches a
//! KKT point with the RMS constraint active, the area kept, and the mass reduced.

use gustkit::optim::{minimize, SqpParams};
use gustkit::problem::{DesignProblem, DesignSpec};
use gustkit::study::Study;
use std::path::Path;

#[test]
fn small_mass_minimization() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/studies/agard445_dlm_analysis.json"
    ))
    .unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["aero"]["fidelity"]["dlm"]["n_chord"] = 3.into();
    v["aero"]["fidelity"]["dlm"]["n_span"] = 4.into();
    v["structure"]["modes"] = 4.into();
    v["structure"]["damping_ratio"] = 0.01.into();
    v["gust"]["points"] = 400.into();
    v["gust"]["outputs"] = serde_json::json!([{"name": "tip_te_w", "point": [1.0, 1.0]}]);
    let study = Study::from_str(Path::new("small.json"), &v.to_string()).unwrap();
    let settings = study.gust_settings().unwrap();
    let case = study.resolve().unwrap();
    let x0 = study.initial_design().unwrap().to_vec();
    let ev0 = gustkit::pipeline::evaluate(&case, &settings, &x0).unwrap();
    let n = x0.len() - 4;
    // thickness between 0.7 and 1.5 times the initial, planform ±10 % (sweep ±5°): a region that
    // stays clear of flutter at the flight condition of this coarse model
    let mut lower: Vec<f64> = x0[..n].iter().map(|t| 0.7 * t).collect();
    let mut upper: Vec<f64> = x0[..n].iter().map(|t| 1.5 * t).collect();
    for k in 0..4 {
        let p = x0[n + k];
        let (lo, hi) = if k == 1 {
            (p - 5f64.to_radians(), p + 5f64.to_radians())
        } else {
            (0.9 * p, 1.1 * p)
        };
        lower.push(lo);
        upper.push(hi);
    }
    let spec = DesignSpec {
        lower,
        upper,
        output: 0,
        rms_limit: 0.9 * ev0.rms_m[0],
        mass0: ev0.mass_kg,
        area0: ev0.area_m2,
        fix_area: true,
        flutter: None,
        mode_floor: None,
        peak: None,
    };
    let mut problem = DesignProblem::new(&case, settings, spec.clone());
    let params = SqpParams {
        max_iterations: 60,
        ..Default::default()
    };
    let r = minimize(&mut problem, &x0, &params, "small", None, &mut ()).unwrap();
    let last = problem.last().unwrap();
    println!(
        "{} after {} iterations ({} evaluations): mass {:.4} → {:.4} kg, RMS {:.4e} → {:.4e} (limit {:.4e}), area {:.6} → {:.6}",
        r.message, r.iterations, r.evaluations, ev0.mass_kg, r.values.f * spec.mass0, ev0.rms_m[0], last.rms_m[0], spec.rms_limit, ev0.area_m2, last.area_m2
    );
    for it in &r.history {
        println!(
            "it {:>3}: f {:.6} h {:+.2e} c {:+.2e} kkt {:.2e} step {:.2e} evals {}",
            it.iteration,
            it.values.f,
            it.values.eq[0],
            it.values.ineq[0],
            it.kkt,
            it.step,
            it.evaluations
        );
    }
    assert!(r.converged, "{}", r.message);
    assert!(
        r.values.ineq[0] <= 1e-4 && r.values.ineq[0] > -1e-2,
        "RMS constraint active: {}",
        r.values.ineq[0]
    );
    assert!(r.values.eq[0].abs() <= 1e-4);
}
