//! The end-to-end adjoint gradient of the gust RMS (and mass, area) against finite differences,
//! for every class of design variable.

mod common;

use gustkit::pipeline::{evaluate, gradient, OutputSeeds};
use gustkit::study::Study;
use gustkit::wing::DesignVector;
use gustkit_testkit::fd_check;
use std::path::Path;

/// The AGARD study with a coarse box layout (the chain is the same, the test stays quick).
fn study() -> Study {
    common::agard_study(|v| {
        common::set_boxes(v, 4, 6);
        v["aero"]["reduced_frequencies"] =
            serde_json::json!([0.0, 0.02, 0.08, 0.18, 0.32, 0.5, 0.72, 1.0, 1.4, 2.0]);
        v["structure"]["modes"] = 4.into();
        v["structure"]["damping_ratio"] = 0.01.into();
        v["gust"]["points"] = 600.into();
        v["gust"]["outputs"] = serde_json::json!([
            {"name": "tip_te_w", "point": [1.0, 1.0]},
            {"name": "root_bm", "quantity": "root_bending_moment"}
        ]);
        v.as_object_mut().unwrap().remove("optimization");
    })
}

/// RMS of the tip trailing-edge deflection: adjoint against central differences (Richardson) to
/// at least 6 significant digits for thicknesses (root TE, mid, tip) and all planform variables;
/// mass and area gradients likewise.
#[test]
fn rms_gradient_matches_finite_differences() {
    let study = study();
    let settings = study.gust_settings().unwrap();
    let case = study.resolve().unwrap();
    let x0 = study.initial_design().unwrap().to_vec();
    let ev = evaluate(&case, &settings, &x0).unwrap();
    println!(
        "rms {:.6e} m, mass {:.4} kg, f {:.3?}",
        ev.rms_m[0], ev.mass_kg, ev.freq_hz
    );
    let g = gradient(
        &ev,
        &OutputSeeds {
            mass: 0.0,
            area: 0.0,
            rms: vec![1.0, 0.0],
            damping: None,
            gust: None,
        },
    )
    .unwrap();
    let n = x0.len() - 4;
    let f = |x: &[f64]| evaluate(&case, &settings, x).unwrap().rms_m[0];
    six_digits_on_every_class(&f, &x0, &g);
    // mass and area through the same entry point
    let gm = gradient(
        &ev,
        &OutputSeeds {
            mass: 1.0,
            area: 2.0,
            rms: vec![0.0, 0.0],
            damping: None,
            gust: None,
        },
    )
    .unwrap();
    let fm = |x: &[f64]| {
        let e = evaluate(&case, &settings, x).unwrap();
        e.mass_kg + 2.0 * e.area_m2
    };
    for k in [3, n + 1, n + 2] {
        let rep = fd_check(&fm, &x0, k, gm[k], gm[k].abs().max(1e-6));
        assert!(rep.best_rel_error < 1e-6, "mass/area dv {k}: {rep:?}");
    }
}

/// A flight condition beyond flutter is a clear error, never an RMS.
#[test]
fn unstable_flight_condition_is_an_error() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/studies/agard445_dlm_analysis.json"
    ))
    .unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["aero"]["fidelity"]["dlm"]["n_chord"] = 4.into();
    v["aero"]["fidelity"]["dlm"]["n_span"] = 6.into();
    v["flight"]["density_kg_m3"] = 0.8.into();
    let study = Study::from_str(Path::new("dense.json"), &v.to_string()).unwrap();
    let settings = study.gust_settings().unwrap();
    let case = study.resolve().unwrap();
    let x0 = study.initial_design().unwrap().to_vec();
    let e = evaluate(&case, &settings, &x0)
        .err()
        .expect("must fail")
        .to_string();
    assert!(e.contains("unstable") && e.contains("flutters"), "{e}");
}

/// RMS of the root bending moment (mode-displacement method): adjoint against finite differences.
#[test]
fn root_bending_moment_rms_gradient() {
    let study = study();
    let settings = study.gust_settings().unwrap();
    let case = study.resolve().unwrap();
    let x0 = study.initial_design().unwrap().to_vec();
    let ev = evaluate(&case, &settings, &x0).unwrap();
    println!("RMS root bending moment {:.6e} N m", ev.rms_m[1]);
    assert!(ev.rms_m[1] > 0.0);
    let g = gradient(
        &ev,
        &OutputSeeds {
            mass: 0.0,
            area: 0.0,
            rms: vec![0.0, 1.0],
            damping: None,
            gust: None,
        },
    )
    .unwrap();
    let n = x0.len() - 4;
    let gnorm = g.iter().map(|v| v * v).sum::<f64>().sqrt();
    let f = |x: &[f64]| evaluate(&case, &settings, x).unwrap().rms_m[1];
    for k in [0, 44, n, n + 1, n + 2, n + 3] {
        let rep = fd_check(&f, &x0, k, g[k], g[k].abs().max(1e-3 * gnorm));
        println!(
            "{:>10}: adjoint {:+.10e} rel err {:.1e}",
            DesignVector::from_slice(&x0).name(k),
            g[k],
            rep.best_rel_error
        );
        assert!(rep.best_rel_error < 1e-6, "dv {k}: {rep:?}");
    }
}

/// The flutter-margin constraint (KS aggregate of the p-k dampings up to 1.15 × the flight speed):
/// adjoint through the p-k eigen-sensitivities, the GAF reverse mode and the modal sensitivities
/// against central differences (Richardson). The damping comes out of two nested eigensolutions
/// and carries round-off of ~1e-12: derivatives that are small against the gradient norm (interior
/// thicknesses, ~1e-3 of it) are resolved by differences only to ~1e-5 of themselves, so errors
/// are measured against max(|g_k|, 1 % of the gradient norm) and must stay below 1e-5; the
/// planform variables and the tip thickness agree to 1e-7 … 1e-9.
#[test]
fn flutter_margin_gradient_matches_finite_differences() {
    check_flutter_margin_gradient(&study());
}

/// The same with 20 modes (the count the cutoff rule retains at thinned designs): the KS now
/// aggregates roots beyond the GAF table, on the high-frequency asymptote, whose weights and
/// k-slope enter the same adjoint; same measure and bound.
#[test]
fn flutter_margin_gradient_with_twenty_modes() {
    let mut v: serde_json::Value = serde_json::to_value(&study().spec).unwrap();
    v["structure"]["modes"] = 20.into();
    let s = gustkit::study::Study::from_str(std::path::Path::new("twenty.json"), &v.to_string())
        .unwrap();
    check_flutter_margin_gradient(&s);
}

fn check_flutter_margin_gradient(study: &Study) {
    use gustkit::flutter::margin::{ks_max, ks_rho, FlutterMargin, PK_STEPS};
    let settings = study.gust_settings().unwrap();
    let case = study.resolve().unwrap();
    let x0 = study.initial_design().unwrap().to_vec();
    let margin = FlutterMargin {
        speed_factor: 1.15,
        damping_max: 0.0,
    };
    let ev = evaluate(&case, &settings, &x0).unwrap();
    let (ks, weights, mut seed) = ev.flutter_damping(&margin).unwrap();
    let beyond = seed
        .roots
        .iter()
        .filter(|r| r.k > *ev.table.k.last().unwrap())
        .count();
    println!(
        "{} modes: g_KS {ks:.6} over {} roots ({beyond} beyond the table), largest g {:.6}",
        ev.modes.len(),
        seed.roots.len(),
        seed.roots.iter().map(|r| r.g).fold(f64::MIN, f64::max)
    );
    seed.g_bar = weights;
    let g = gradient(
        &ev,
        &OutputSeeds {
            mass: 0.0,
            area: 0.0,
            rms: vec![0.0, 0.0],
            damping: Some(seed),
            gust: None,
        },
    )
    .unwrap();
    let n = x0.len() - 4;
    let gnorm = g.iter().map(|v| v * v).sum::<f64>().sqrt();
    // the margin needs no gust response: a step that crosses the flight condition's stability
    // boundary (the 20-mode model has a root beyond the table near it) is still differentiated
    let f = |x: &[f64]| {
        let a = gustkit::pipeline::aeroelastic(&case, x).unwrap();
        let roots = gustkit::flutter::PkProblem::new(&a.modes, &a.table, a.aero.flight.density)
            .roots_up_to(margin.speed_factor * a.aero.flight.velocity, PK_STEPS)
            .unwrap();
        let g: Vec<f64> = roots.iter().map(|r| r.g).collect();
        ks_max(&g, ks_rho(g.len())).0
    };
    for k in [5, 50, 99, n, n + 1, n + 2, n + 3] {
        let rep = fd_check(&f, &x0, k, g[k], g[k].abs().max(1e-2 * gnorm));
        println!(
            "{:>10}: adjoint {:+.10e} fd {:+.10e} rel err {:.1e}",
            DesignVector::from_slice(&x0).name(k),
            g[k],
            rep.best,
            rep.best_rel_error
        );
        assert!(rep.best_rel_error < 1e-5, "dv {k}: {rep:?}");
    }
}

/// The modal-basis floor of an optimization by the cutoff rule (the KS aggregate of
/// 1 − ω²ⱼ/ω²_cut over the N modes above the basis): its gradient (KS weights × eigenvalue
/// derivatives φᵀ(∂K − λ∂M)φ) against central differences (Richardson) to at least 6 significant
/// digits for thicknesses at the root trailing edge, mid-span and the tip and every planform
/// variable, on the flagship's plate with N = 11 (the rule's count) and 20 and the cutoff of the
/// flagship's rule, 226 Hz.
#[test]
fn mode_floor_gradient_against_finite_differences() {
    let study =
        Study::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/agard445_dlm.json"))
            .unwrap();
    let case = study.resolve().unwrap();
    let x0 = study.initial_design().unwrap().to_vec();
    let plate0 = study.model_at(DesignVector::from_slice(&x0)).unwrap();
    for retained in [11, 20] {
        let floor = gustkit::problem::ModeFloor::new(
            retained,
            2.0 * std::f64::consts::PI * 226.0,
            case.modes.retained_dofs(&plate0),
        );
        assert_eq!(floor.band, retained);
        let value = |x: &[f64]| {
            let plate = study.model_at(DesignVector::from_slice(x)).unwrap();
            floor.evaluate(&case.modes, &plate).unwrap()
        };
        let (modes, c0) = value(&x0);
        let g = floor.gradient(&plate0, &modes);
        println!(
            "floor constraint {c0:+.6} (modes {}–{} from {:.2} Hz, rho {:.0})",
            retained + 1,
            retained + floor.band,
            modes.freq_hz()[retained],
            floor.rho()
        );
        let f = |x: &[f64]| value(x).1;
        six_digits_on_every_class(&f, &x0, &g);
    }
}

/// Where the optimum has pushed modes onto the cutoff together (the DLM optimum of the point
/// floor, tests/data: modes 12 and 13 within 0.01 Hz of each other at 226.4 Hz), the KS floor is
/// smooth and the first left-out mode alone is not. Along d = ∇(g₁₃ − g₁₂), from where g₁₃ − g₁₂
/// is −1e-3 to where it is +1e-3 (crossing the pair), the directional derivative of the first
/// mode's margin max(g₁₂, g₁₃) jumps by |d|² (within 10 %: the eigenvalues' curvature), that of
/// the KS floor by its weights' change, tanh(ρ · 1e-3 / 2) ≈ 0.06 for ρ = 120 (at most 0.15 |d|²
/// allowed: mode 14, 0.16 Hz above, shares the weight). The gradient there matches central
/// differences to 6 digits like anywhere else.
#[test]
fn mode_floor_is_smooth_where_modes_cluster() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let study = Study::load(&root.join("studies/agard445_dlm.json")).unwrap();
    let case = study.resolve().unwrap();
    let xc = common::fixture_design("agard445_dlm_optimum_2026_12_clustered.json");
    let plate_at = |x: &[f64]| study.model_at(DesignVector::from_slice(x)).unwrap();
    let omega_cut = 2.0 * std::f64::consts::PI * 226.44;
    let floor =
        gustkit::problem::ModeFloor::new(11, omega_cut, case.modes.retained_dofs(&plate_at(&xc)));
    let (modes, _) = floor.evaluate(&case.modes, &plate_at(&xc)).unwrap();
    let f = modes.freq_hz();
    println!(
        "modes 12, 13, 14 at {:.3}, {:.3}, {:.3} Hz",
        f[11], f[12], f[13]
    );
    assert!(
        f[12] - f[11] < 0.05,
        "the fixture's pair is no longer clustered"
    );
    // the single eigenvalues' gradients: floors of one mode each on the same modes
    let single = |mode: usize| gustkit::problem::ModeFloor {
        retained: mode - 1,
        omega_cut,
        band: 1,
    };
    let g12 = single(12).gradient(&plate_at(&xc), &modes);
    let g13 = single(13).gradient(&plate_at(&xc), &modes);
    let d: Vec<f64> = g13.iter().zip(&g12).map(|(a, b)| a - b).collect();
    let dd: f64 = d.iter().map(|v| v * v).sum();
    let gap = (modes.modes[12].lambda - modes.modes[11].lambda) / (omega_cut * omega_cut);
    let along = |t: f64| -> Vec<f64> { xc.iter().zip(&d).map(|(x, d)| x + t * d).collect() };
    let point = |x: &[f64]| {
        let m = case.modes.solve_count(&plate_at(x), 12).unwrap();
        1.0 - m.modes[11].lambda / (omega_cut * omega_cut)
    };
    let ks = |x: &[f64]| floor.evaluate(&case.modes, &plate_at(x)).unwrap().1;
    // the directional derivative by a central difference far inside the ±1e-3 window
    let slope = |c: &dyn Fn(&[f64]) -> f64, t: f64| {
        let h = 1e-6 / dd;
        (c(&along(t + h)) - c(&along(t - h))) / (2.0 * h)
    };
    // g13 − g12 = gap + t |d|² to first order
    let (t_minus, t_plus) = ((-1e-3 - gap) / dd, (1e-3 - gap) / dd);
    let jump_point = (slope(&point, t_plus) - slope(&point, t_minus)) / dd;
    let jump_ks = (slope(&ks, t_plus) - slope(&ks, t_minus)) / dd;
    println!("gap {gap:.2e}; derivative jumps across the pair / |d|²: first mode {jump_point:.3}, KS {jump_ks:.3} (rho {:.0})", floor.rho());
    assert!((jump_point - 1.0).abs() < 0.1, "{jump_point}");
    assert!(jump_ks.abs() < 0.15, "{jump_ks}");
    let g = floor.gradient(&plate_at(&xc), &modes);
    six_digits_on_every_class(&ks, &xc, &g);
}

/// Gradient `g` of `f` at `x0` against central differences (Richardson) to at least 6 significant
/// digits (relative to the entry, or 1e-3 of the gradient's norm where the entry is smaller) for
/// thicknesses at the root trailing edge, mid-span and the tip and every planform variable.
fn six_digits_on_every_class(f: &dyn Fn(&[f64]) -> f64, x0: &[f64], g: &[f64]) {
    let gnorm = g.iter().map(|v| v * v).sum::<f64>().sqrt();
    let n = x0.len() - 4;
    for k in [9, 50, 95, n, n + 1, n + 2, n + 3] {
        let rep = fd_check(f, x0, k, g[k], g[k].abs().max(1e-3 * gnorm));
        println!(
            "{:>10}: adjoint {:+.10e} fd {:+.10e} rel err {:.1e}",
            DesignVector::from_slice(x0).name(k),
            g[k],
            rep.best,
            rep.best_rel_error
        );
        assert!(rep.best_rel_error < 1e-6, "dv {k}: {rep:?}");
    }
}

/// The discrete gust peak limit (issue 30): the KS aggregate of the root bending moment and of
/// the tip trailing-edge acceleration over three 1-cos gusts (H = 30, 120 and 350 ft, 10 m/s)
/// on a fixed time grid, its adjoint gradient through the whole chain (inverse-FFT adjoint,
/// Eq. 16 on the uniform grid, GAF reverse mode, modes, planform) against central differences
/// (Richardson) to at least 6 significant digits for thicknesses at the root trailing edge,
/// mid-span and the tip and every planform variable.
#[test]
fn discrete_gust_peak_gradient_matches_finite_differences() {
    use gustkit::gust::discrete::{transient, GustProfile, TimeGrid, TransientSettings};
    let study = study();
    let settings = study.gust_settings().unwrap();
    let case = study.resolve().unwrap();
    let x0 = study.initial_design().unwrap().to_vec();
    let ev0 = evaluate(&case, &settings, &x0).unwrap();
    let velocity = ev0.aero.flight.velocity;
    let gusts: Vec<GustProfile> = [30.0, 120.0, 350.0]
        .iter()
        .map(|ft| GustProfile::OneMinusCosine {
            gradient: ft * 0.3048,
            amplitude: 10.0,
            velocity,
        })
        .collect();
    let p0 = ev0.problem();
    let omega_max = p0.table_omega_max();
    for (output, derivative) in [(1usize, 0u32), (0, 2)] {
        let mut der = vec![0; p0.outputs.len()];
        der[output] = derivative;
        let ts = TransientSettings {
            span: None,
            omega_max,
            derivative: der.clone(),
            keep_histories: false,
            max_bytes: 1e9,
        };
        let (r, _) = transient(&p0, &gusts, &ts).unwrap();
        let limit = r.largest_abs(output);
        let pl = gustkit::problem::PeakLimit {
            constraint: gustkit::study::discrete::PeakConstraint {
                name: "test".into(),
                output,
                derivative,
                limit,
                unit: String::new(),
                gusts: gusts.clone(),
            },
            grid: TimeGrid::new(2.0 * r.grid.span, omega_max).unwrap(),
        };
        let f = |x: &[f64]| {
            let ev = evaluate(&case, &settings, x).unwrap();
            pl.evaluate(&ev).unwrap().1.ks
        };
        let (mut model, ks) = pl.evaluate(&ev0).unwrap();
        let gg = ks.vjp(&mut model, &ev0.problem(), &gusts, 1.0).unwrap();
        let g = gradient(
            &ev0,
            &OutputSeeds {
                mass: 0.0,
                area: 0.0,
                rms: vec![0.0; 2],
                damping: None,
                gust: Some(gg),
            },
        )
        .unwrap();
        println!(
            "output {output}, d = {derivative}: KS {:.6}, peak {:.6}",
            ks.ks, ks.peak
        );
        six_digits_on_every_class(&f, &x0, &g);
    }
}

/// The strip-theory wing fidelity (`aero.fidelity: {"strip": …}`), added by the recipe of
/// ARCHITECTURE.md: its RMS gradient in the thickness variables (its reverse mode covers the
/// mode shapes; the planform variables are refused for an optimization) against central
/// differences (Richardson) to 2e-6 of the larger of |g_k| and 1e-3 ‖g‖ (six digits within the
/// differences' own scatter: for the tip thickness the best step's estimates differ from each
/// other by 1e-6), at a speed where strip theory finds the wing stable (it flutters at
/// 0.89 × the flagship's flight speed: strip theory overestimates a low-aspect-ratio wing's lift).
#[test]
fn strip_fidelity_thickness_gradient_matches_finite_differences() {
    let study = common::agard_study(|v| {
        v["aero"]["fidelity"] = serde_json::json!({"strip": {"n_strips": 12, "points": 9}});
        v["aero"].as_object_mut().unwrap().remove("compare_with");
        v["flight"]["velocity_m_s"] = 120.0.into();
        v["structure"]["modes"] = 4.into();
        v["structure"]["damping_ratio"] = 0.01.into();
        v["gust"]["points"] = 600.into();
        v.as_object_mut().unwrap().remove("optimization");
    });
    let settings = study.gust_settings().unwrap();
    let case = study.resolve().unwrap();
    let x0 = case.initial.to_vec();
    let ev = evaluate(&case, &settings, &x0).unwrap();
    let seeds = OutputSeeds {
        rms: std::iter::once(1.0)
            .chain(std::iter::repeat(0.0))
            .take(ev.rms_m.len())
            .collect(),
        ..Default::default()
    };
    let g = gradient(&ev, &seeds).unwrap();
    let f = |x: &[f64]| evaluate(&case, &settings, x).unwrap().rms_m[0];
    let gnorm = g.iter().map(|v| v * v).sum::<f64>().sqrt();
    for k in [9, 50, 95] {
        let rep = fd_check(&f, &x0, k, g[k], g[k].abs().max(1e-3 * gnorm));
        assert!(rep.best_rel_error < 2e-6, "dv {k}: {rep:?}");
    }
}
