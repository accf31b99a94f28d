//! The mode-acceleration method (residual flexibility of the modes left out): exact for static
//! loads whatever the modes kept, nothing added when every mode is kept, and its adjoint gradient
//! through the whole gust pipeline against finite differences.

mod common;

use gustkit::pipeline::{evaluate, gradient, OutputSeeds};
use gustkit::structure::modal::{field_dofs, Sampler};
use gustkit::structure::residual::residual_shapes;
use gustkit::structure::{modal, root_bending_moment, Clamp, Field};
use gustkit::wing::DesignVector;
use gustkit_testkit::fd_check;

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// For a static load f the method is exact with any number of modes: the tip deflection
/// Σ_i (c·φ_i)(φ_i·f)/λ_i + w·f equals c·K⁻¹f (K⁻¹f by the complete modal sum, an independent
/// route), and the root bending moment Σ_i S_i (φ_i·f)/λ_i + w·f equals the moment of the load
/// about the root line (force summation), to 1e-9 with 6 of 336 modes (measured: 12 digits; the
/// modal sums alone are 4e-4 and 1.1 % off); with every mode kept the
/// residual shapes vanish (the deflection's to 1e-9 of its 6-mode size, the moment's, whose sum
/// weighs the least accurate highest modes as much as the rest, to 1e-6).
#[test]
fn static_loads_are_exact_and_the_residual_vanishes_with_every_mode() {
    let model = common::agard_plate(1, Clamp::Interior);
    let n = model.n_dofs(Field::Bending);
    let all = modal::solve(&model, n, 0.0, &[Field::Bending]).unwrap();
    let six = modal::solve(&model, 6, 0.0, &[Field::Bending]).unwrap();
    let outputs = vec![Some(Sampler::new(&model, &[[1.0, 1.0]])), None];
    // a load: nodal forces growing toward the tip and the trailing edge, plus nodal moments
    let xy = model.node_xy();
    let mut f_nodal = vec![0.0; 5 * xy.len()];
    for (i, p) in xy.iter().enumerate() {
        if !model.mesh.clamped[i] {
            f_nodal[5 * i] = 1.0 + 3.0 * p[1] - 0.5 * p[0];
            f_nodal[5 * i + 1] = -0.1 * p[1];
            f_nodal[5 * i + 2] = 0.2 * p[0];
        }
    }
    let f = field_dofs(&model, Field::Bending, &f_nodal);
    let modal_part = |modes: &modal::Modes, s: &[f64]| -> f64 {
        modes
            .modes
            .iter()
            .zip(s)
            .map(|(m, sm)| sm * dot(&field_dofs(&model, Field::Bending, &m.shape), &f) / m.lambda)
            .sum()
    };
    let tip_samples = |modes: &modal::Modes| -> Vec<f64> {
        let s = outputs[0].as_ref().unwrap();
        modes
            .modes
            .iter()
            .map(|m| s.sample(&model, &m.shape)[0][0])
            .collect()
    };
    // exact answers
    let tip_exact = modal_part(&all, &tip_samples(&all));
    let span = model.planform().span;
    let moment_exact: f64 = xy
        .iter()
        .enumerate()
        .filter(|(i, _)| !model.mesh.clamped[*i])
        .map(|(i, _)| {
            let eta = model.mesh.nodes[i][1];
            f_nodal[5 * i] * eta * span + f_nodal[5 * i + 2]
        })
        .sum();
    let w6 = residual_shapes(&model, &six, &outputs);
    let tip6 = modal_part(&six, &tip_samples(&six));
    let tip_ma = tip6 + dot(&field_dofs(&model, Field::Bending, &w6[0]), &f);
    let moment6 = modal_part(&six, &root_bending_moment(&model, &six));
    let moment_ma = moment6 + dot(&field_dofs(&model, Field::Bending, &w6[1]), &f);
    println!("tip: exact {tip_exact:.12e}, 6 modes {tip6:.6e}, with the residual {tip_ma:.12e}");
    println!(
        "moment: exact {moment_exact:.12e}, 6 modes {moment6:.6e}, with the residual {moment_ma:.12e}"
    );
    // the test sees the residual: 6 modes alone are off by 4e-4 (tip) and 1 % (moment)
    assert!((tip6 - tip_exact).abs() > 1e-4 * tip_exact.abs());
    assert!((moment6 - moment_exact).abs() > 1e-3 * moment_exact.abs());
    assert!((tip_ma - tip_exact).abs() < 1e-9 * tip_exact.abs());
    assert!((moment_ma - moment_exact).abs() < 1e-9 * moment_exact.abs());
    // every mode kept: nothing left
    let w_all = residual_shapes(&model, &all, &outputs);
    let scale = w6[0].iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let left = w_all[0].iter().fold(0.0f64, |a, v| a.max(v.abs()));
    println!("largest residual entry: 6 modes {scale:.3e}, all modes {left:.3e}");
    assert!(left < 1e-9 * scale);
    let r_scale = w6[1].iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let r_left = w_all[1].iter().fold(0.0f64, |a, v| a.max(v.abs()));
    // r − ΦΦᵀMr weighs every mode alike, the highest (least accurate) ones too: 3e-8 measured
    assert!(r_left < 1e-6 * r_scale, "{r_left} vs {r_scale}");
}

/// The RMS of both outputs by the mode-acceleration method: adjoint (through the GAF rows of the
/// residual shapes, the static solve, the modes and the output geometry) against central
/// differences with Richardson extrapolation, to 6 significant digits (of the entry, or 1e-3 of
/// the gradient's norm where smaller) on root, mid-span and tip thicknesses and every planform
/// variable.
#[test]
fn mode_acceleration_rms_gradient_matches_finite_differences() {
    let study = common::agard_study(|v| {
        common::set_boxes(v, 4, 6);
        v["aero"]["reduced_frequencies"] =
            serde_json::json!([0.0, 0.02, 0.08, 0.18, 0.32, 0.5, 0.72, 1.0, 1.4, 2.0]);
        v["structure"]["modes"] = 4.into();
        v["structure"]["damping_ratio"] = 0.01.into();
        v["gust"]["points"] = 600.into();
        v["gust"]["mode_acceleration"] = true.into();
        v["gust"]["outputs"] = serde_json::json!([
            {"name": "tip_te_w", "point": [1.0, 1.0]},
            {"name": "root_bm", "quantity": "root_bending_moment"}
        ]);
        v.as_object_mut().unwrap().remove("optimization");
    });
    let settings = study.gust_settings().unwrap();
    let case = study.resolve().unwrap();
    assert!(settings.mode_acceleration);
    let x0 = study.initial_design().unwrap().to_vec();
    let ev = evaluate(&case, &settings, &x0).unwrap();
    let mut plain_settings = settings.clone();
    plain_settings.mode_acceleration = false;
    let plain = evaluate(&case, &plain_settings, &x0).unwrap();
    println!(
        "RMS with the residual {:.6e} m, {:.6e} N m; without {:.6e} m, {:.6e} N m",
        ev.rms_m[0], ev.rms_m[1], plain.rms_m[0], plain.rms_m[1]
    );
    // the residual matters with 4 modes (a test that did not add it would fail here)
    assert!((ev.rms_m[0] - plain.rms_m[0]).abs() > 1e-3 * plain.rms_m[0]);
    let n = x0.len() - 4;
    for (y, seeds) in [[1.0, 0.0], [0.0, 1.0]].into_iter().enumerate() {
        let g = gradient(
            &ev,
            &OutputSeeds {
                rms: seeds.to_vec(),
                ..Default::default()
            },
        )
        .unwrap();
        let f = |x: &[f64]| evaluate(&case, &settings, x).unwrap().rms_m[y];
        let gnorm = g.iter().map(|v| v * v).sum::<f64>().sqrt();
        for k in [9, 50, 95, n, n + 1, n + 2, n + 3] {
            let rep = fd_check(&f, &x0, k, g[k], g[k].abs().max(1e-3 * gnorm));
            println!(
                "output {y} {:>10}: adjoint {:+.10e} fd {:+.10e} rel err {:.1e}",
                DesignVector::from_slice(&x0).name(k),
                g[k],
                rep.best,
                rep.best_rel_error
            );
            assert!(rep.best_rel_error < 1e-6, "output {y}, dv {k}: {rep:?}");
        }
    }
}
