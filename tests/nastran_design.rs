//! Design variables on a Nastran model's properties (issue 29): DVPREL1-like relations,
//! the structural mass, and the exact derivatives of mass and random gust response with
//! respect to every design variable (`nastran::design`), against closed forms and central
//! differences at several steps.

mod common;

use gustkit::nastran::bulk::BulkData;
use gustkit::nastran::design::{parse_output, DesignModel, PropertyRelation};
use gustkit::nastran::random::KInterpolation;
use gustkit::nastran::structure::subcase_modes;
use gustkit::nastran::Input;
use std::path::{Path, PathBuf};

/// The shipped bar wing of `studies/nastran_bar_wing.json`.
fn bar_wing() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/nastran/bar_wing_gust.bdf")
}

/// A cantilever plate wing of 2 × 4 CQUAD4 (two PSHELLs, root and tip halves) with a tip mass,
/// one CAERO1 of 4 × 4 boxes on an infinite-plate SPLINE1, the bar wing's gust cards
/// (`common::plate_wing_gust_deck`: 6 modes, no symmetry, X0 at the panel's leading edge).
fn plate_wing_deck() -> String {
    common::plate_wing_gust_deck(0.0, 6, false, 0.0)
}

/// One DVPREL1-like relation: card, property id, field, C0, (variable, coefficient) terms.
type Relation<'a> = (&'a str, u32, &'a str, f64, Vec<(usize, f64)>);

/// A design model of `file` with `relations` (card, id, field, c0, terms), the outputs
/// `labels`, the DLM on 41 k to `k_max` (above the FREQ list's last frequency).
fn model(
    file: &Path,
    k_max: f64,
    relations: &[Relation],
    n_variables: usize,
    labels: &[&str],
) -> DesignModel {
    let input = Input::read(file).unwrap();
    let base = BulkData::from_cards(&input.deck.bulk).unwrap();
    let sub = input.case_control.subcase(1).unwrap();
    let relations = relations
        .iter()
        .map(|(card, id, field, c0, terms)| {
            PropertyRelation::new(&base, card, *id, field, *c0, terms.clone()).unwrap()
        })
        .collect();
    let (_, modes) = subcase_modes(&base, &sub).unwrap();
    DesignModel {
        n_modes: modes.lambda.len(),
        base,
        sub,
        relations,
        requests: labels.iter().map(|l| parse_output(l).unwrap()).collect(),
        interpolation: KInterpolation::Dense((0..=40).map(|i| k_max * i as f64 / 40.0).collect()),
        n_variables,
        lfd: None,
    }
}

/// The derivatives of every output's RMS and N0 and of the mass against central differences
/// at relative steps 1e-3, 1e-4 and 1e-5: the error, relative to the value and per unit
/// relative change of the variable, falls as h² to the differences' round-off; the best step
/// must agree to 1e-7 (≥ 7 digits). Returns the best errors.
fn check_against_differences(m: &DesignModel, x0: &[f64]) -> f64 {
    let p = m.analyse(x0).unwrap();
    let g = m.gradients(&p).unwrap();
    let mut worst = 0.0f64;
    for v in 0..m.n_variables {
        let mut best = vec![f64::INFINITY; 2 * p.rows.len() + 1];
        for rel in [1e-3, 1e-4, 1e-5] {
            let h = rel * x0[v];
            let at = |s: f64| {
                let mut x = x0.to_vec();
                x[v] += s * h;
                m.analyse(&x).unwrap()
            };
            let (up, down) = (at(1.0), at(-1.0));
            let fd_mass = (up.mass - down.mass) / (2.0 * h);
            let e = x0[v] * (g.mass[v] - fd_mass).abs() / p.mass;
            best[0] = best[0].min(e);
            for (y, d) in g.outputs[v].iter().enumerate() {
                let fd_rms = (up.rows[y].rms - down.rows[y].rms) / (2.0 * h);
                let fd_n0 = (up.rows[y].n0_hz - down.rows[y].n0_hz) / (2.0 * h);
                let e_rms = x0[v] * (d.d_rms - fd_rms).abs() / d.rms;
                let e_n0 = x0[v] * (d.d_n0_hz - fd_n0).abs() / d.n0_hz;
                eprintln!(
                    "x{v} h {rel:.0e} {}: x dRMS/dx / RMS {:.8e} (err {e_rms:.1e}), x dN0/dx / N0 {:.8e} (err {e_n0:.1e})",
                    d.label,
                    x0[v] * d.d_rms / d.rms,
                    x0[v] * d.d_n0_hz / d.n0_hz
                );
                best[1 + 2 * y] = best[1 + 2 * y].min(e_rms);
                best[2 + 2 * y] = best[2 + 2 * y].min(e_n0);
            }
        }
        for (i, e) in best.iter().enumerate() {
            assert!(*e < 1e-7, "variable {v}, quantity {i}: best error {e:.1e}");
            worst = worst.max(*e);
        }
    }
    worst
}

/// The reverse mode against the forward mode (the dot-product test): for two functionals of
/// every output's RMS and N0 with fixed pseudo-random weights, the reverse gradient of each
/// variable equals the forward derivatives paired with the weights to 1e-10 of the pairing's
/// magnitude (both exact: they differ by round-off in different solves); the mass's to 1e-14.
/// Returns the largest relative difference.
fn check_reverse_against_forward(m: &DesignModel, x0: &[f64]) -> f64 {
    let p = m.analyse(x0).unwrap();
    let fwd = m.gradients(&p).unwrap();
    let n_out = p.rows.len();
    let weight = |f: usize, y: usize, which: usize| {
        // a fixed, sign-changing sequence in [-1, 1]
        (((7 * f + 3 * y + 5 * which + 1) as f64) * 0.618_033_988_75).fract() * 2.0 - 1.0
    };
    let functionals: Vec<Vec<(f64, f64)>> = (0..2)
        .map(|f| {
            (0..n_out)
                .map(|y| {
                    // per unit value, so that every output weighs alike
                    (
                        weight(f, y, 0) / p.rows[y].rms,
                        weight(f, y, 1) / p.rows[y].n0_hz,
                    )
                })
                .collect()
        })
        .collect();
    let rev = m.gradients_reverse(&p, &functionals).unwrap();
    let mut worst = 0.0f64;
    for v in 0..m.n_variables {
        assert!((rev.mass[v] - fwd.mass[v]).abs() <= 1e-14 * fwd.mass[v].abs());
        for (f, seeds) in functionals.iter().enumerate() {
            let (mut pairing, mut size) = (0.0, 0.0);
            for (y, &(rb, nb)) in seeds.iter().enumerate() {
                let d = &fwd.outputs[v][y];
                pairing += rb * d.d_rms + nb * d.d_n0_hz;
                size += (rb * d.d_rms).abs() + (nb * d.d_n0_hz).abs();
            }
            let diff = (rev.functionals[f][v] - pairing).abs() / size;
            eprintln!(
                "x{v} functional {f}: reverse {:.12e}, forward {pairing:.12e}, difference {diff:.1e}",
                rev.functionals[f][v]
            );
            assert!(diff < 1e-10, "x{v} functional {f}: {diff:.1e}");
            worst = worst.max(diff);
        }
    }
    worst
}

/// The reverse mode of the bar wing's and the plate wing's responses (every output kind:
/// displacement, acceleration, constraint force and moment, modal coordinate) against the
/// forward mode, on the DLM's dense k and on MKAERO's k with linear interpolation.
#[test]
fn reverse_mode_matches_forward_mode() {
    let relations: Vec<Relation> = vec![
        ("PBAR", 1, "A", 0.0, vec![(0, 1.6e-3)]),
        ("PBAR", 1, "I1", 0.0, vec![(0, 5.6e-7)]),
        ("PBAR", 2, "I2", 0.0, vec![(1, 6.0e-8)]),
        ("PBAR", 2, "J", 0.0, vec![(1, 4.5e-8), (2, 4.5e-8)]),
        ("PBAR", 3, "A", 0.0, vec![(2, 0.8e-3)]),
    ];
    let labels = ["9T3", "9R2", "ACCE 9T3", "SPCF 1R1", "SPCF 1T3", "MODE 2"];
    let dense = model(&bar_wing(), 0.2, &relations, 3, &labels);
    let mut worst = check_reverse_against_forward(&dense, &[1.0, 1.0, 1.0]);
    let k: Vec<f64> = (0..=40).map(|i| 0.2 * i as f64 / 40.0).collect();
    let mkaero = DesignModel {
        interpolation: KInterpolation::LinearOnMkaero(k),
        ..dense
    };
    worst = worst.max(check_reverse_against_forward(&mkaero, &[0.9, 1.2, 1.1]));
    let dir = common::scratch("nastran", "design-reverse");
    let file = dir.join("plate_wing.bdf");
    std::fs::write(&file, plate_wing_deck()).unwrap();
    let plate = model(
        &file,
        0.35,
        &[
            ("PSHELL", 1, "T", 0.0, vec![(0, 1.0)]),
            ("PSHELL", 2, "T", 0.002, vec![(1, 1.0)]),
        ],
        2,
        &["15T3", "13R1", "SPCF 2T3", "SPCF 1R1"],
    );
    worst = worst.max(check_reverse_against_forward(&plate, &[0.012, 0.006]));
    eprintln!("largest difference {worst:.1e}");
}

/// The bar wing sized by three skin-thickness-like variables (each scales its PBAR's A, I1,
/// I2 and J; PBAR 2's J shared between two variables, as a DVPREL1 with two terms): the mass
/// derivative is ρ A₀ L of the section (lumped bars: ρAL + NSM·L, NSM and CONM2s fixed) to 1e-12, and every
/// derivative of the tip's displacement, acceleration and the root's constraint moment
/// matches central differences to 1e-7.
#[test]
fn bar_wing_design_derivatives() {
    let sections = [
        (1, [1.6e-3, 5.6e-7, 8.4e-8, 1.26e-7], 0.75),
        (2, [1.2e-3, 4.0e-7, 6.0e-8, 9.0e-8], 0.75),
        (3, [0.8e-3, 2.4e-7, 3.6e-8, 5.4e-8], 0.5),
    ];
    let mut relations = Vec::new();
    for (v, (pid, dims, _)) in sections.iter().enumerate() {
        for (field, d) in ["A", "I1", "I2", "J"].iter().zip(dims) {
            let terms = if *pid == 2 && *field == "J" {
                vec![(1, 0.5 * d), (2, 0.5 * d)]
            } else {
                vec![(v, *d)]
            };
            relations.push(("PBAR", *pid, *field, 0.0, terms));
        }
    }
    let m = model(
        &bar_wing(),
        0.2,
        &relations,
        3,
        &["9T3", "ACCE 9T3", "SPCF 1R1"],
    );
    let x0 = [1.0, 1.0, 1.0];
    let p = m.analyse(&x0).unwrap();
    // the bars' ρAL, their NSM of 0.6 kg/m over 2 m, eight 0.2 kg CONM2s
    let mass = 2700.0 * (1.6e-3 * 0.75 + 1.2e-3 * 0.75 + 0.8e-3 * 0.5) + 0.6 * 2.0 + 8.0 * 0.2;
    assert!((p.mass - mass).abs() < 1e-12 * mass, "{} {mass}", p.mass);
    let g = m.gradients(&p).unwrap();
    for (v, (_, dims, length)) in sections.iter().enumerate() {
        let exact = 2700.0 * dims[0] * length;
        assert!(
            (g.mass[v] - exact).abs() < 1e-12 * exact,
            "{} {exact}",
            g.mass[v]
        );
    }
    // the labels the response gives are the labels the model was asked for
    let labels: Vec<&str> = p.rows.iter().map(|r| r.label.as_str()).collect();
    assert_eq!(labels, ["9T3", "ACCE 9T3", "SPCF 1R1"]);
    let worst = check_against_differences(&m, &x0);
    eprintln!("bar wing: largest best error {worst:.1e}");
}

/// The plate wing sized by its two PSHELL thicknesses: the mass derivative is ρ × area of the
/// PSHELL's elements (0.5 m² each; the tip CONM2 fixed) to 1e-12, and the derivatives of the
/// tip's displacement and the root's constraint force match central differences to 1e-7.
#[test]
fn plate_wing_design_derivatives() {
    let dir = common::scratch("nastran", "design-plate");
    let file = dir.join("plate_wing.bdf");
    std::fs::write(&file, plate_wing_deck()).unwrap();
    let m = model(
        &file,
        0.35,
        &[
            ("PSHELL", 1, "T", 0.0, vec![(0, 1.0)]),
            ("PSHELL", 2, "T", 0.002, vec![(1, 1.0)]),
        ],
        2,
        &["15T3", "SPCF 2T3", "SPCF 1R1"],
    );
    let x0 = [0.012, 0.006];
    let p = m.analyse(&x0).unwrap();
    let mass = 2700.0 * (0.012 + 0.008) * 0.5 + 0.5;
    assert!((p.mass - mass).abs() < 1e-12 * mass, "{} {mass}", p.mass);
    let g = m.gradients(&p).unwrap();
    for v in 0..2 {
        assert!((g.mass[v] - 1350.0).abs() < 1e-12 * 1350.0, "{}", g.mass[v]);
    }
    let worst = check_against_differences(&m, &x0);
    eprintln!("plate wing: largest best error {worst:.1e}");
}

/// The shipped study as JSON, with its model path made absolute (so a copy can live anywhere).
fn bar_wing_study() -> serde_json::Value {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/nastran_bar_wing.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap();
    v["model"]["nastran"] = bar_wing().display().to_string().into();
    v
}

/// Writes `study` to `dir/name.json` and runs it there; returns the output.
fn run_study(
    dir: &Path,
    name: &str,
    study: &serde_json::Value,
    extra: &[&str],
) -> std::process::Output {
    let file = dir.join(format!("{name}.json"));
    std::fs::write(&file, serde_json::to_string_pretty(study).unwrap()).unwrap();
    common::gustkit()
        .arg("run")
        .arg(&file)
        .arg("--reports")
        .arg(dir.join("reports"))
        .args(extra)
        .env("RAYON_NUM_THREADS", "1")
        .output()
        .unwrap()
}

/// One variable scaling all three sections of the bar wing, one limit on the tip's RMS
/// displacement: the tip RMS falls as the wing stiffens, so the lightest design meets the limit
/// exactly. The optimizer's answer against the root of RMS(t) = limit found by bisection on
/// the analysis alone (no gradient, no optimizer): t to 1e-6, the RMS at the limit to 1e-6.
/// The run also re-analyses the optimum with twice the modes and reduced frequencies and
/// writes what that moved.
#[test]
fn one_variable_optimum_matches_bisection() {
    let dir = common::scratch("nastran", "design-bisection");
    let mut v = bar_wing_study();
    let dims = [
        [1.6e-3, 5.6e-7, 8.4e-8, 1.26e-7],
        [1.2e-3, 4.0e-7, 6.0e-8, 9.0e-8],
        [0.8e-3, 2.4e-7, 3.6e-8, 5.4e-8],
    ];
    let mut relations = Vec::new();
    for (pid, d) in dims.iter().enumerate() {
        for (field, c) in ["A", "I1", "I2", "J"].iter().zip(d) {
            relations.push(serde_json::json!({"card": "PBAR", "id": pid + 1, "field": field, "terms": {"t": c}}));
        }
    }
    v["design_variables"] =
        serde_json::json!([{"name": "t", "initial": 1.0, "lower": 0.3, "upper": 3.0}]);
    v["properties"] = relations.clone().into();
    v["constraints"] = serde_json::json!([{"output": "9T3", "rms_max": 0.26}]);
    let out = run_study(&dir, "one", &v, &[]);
    common::assert_success(&out);
    let r: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("reports/nastran_bar_wing/results.json")).unwrap(),
    )
    .unwrap();
    let t_opt = r["design_variables"][0]["final"].as_f64().unwrap();
    // bisection on the analysis alone
    let rel: Vec<Relation> = dims
        .iter()
        .enumerate()
        .flat_map(|(pid, d)| {
            ["A", "I1", "I2", "J"]
                .into_iter()
                .zip(d)
                .map(move |(f, c)| ("PBAR", pid as u32 + 1, f, 0.0, vec![(0, *c)]))
        })
        .collect();
    let m = model(&bar_wing(), 0.0, &rel, 1, &["9T3"]);
    // the study's own k range (dense_k: 5 % beyond the last frequency)
    let m = DesignModel {
        interpolation: KInterpolation::Dense({
            let k_max = 1.05 * 2.0 * std::f64::consts::PI * 19.85 * 0.25 / 170.0;
            (0..=40).map(|i| k_max * i as f64 / 40.0).collect()
        }),
        ..m
    };
    let rms = |t: f64| m.analyse(&[t]).unwrap().rows[0].rms;
    let (mut lo, mut hi) = (0.3, 3.0);
    assert!(rms(lo) > 0.26 && rms(hi) < 0.26);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if rms(mid) > 0.26 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let t_root = 0.5 * (lo + hi);
    eprintln!("optimizer t = {t_opt:.10}, bisection {t_root:.10}");
    assert!((t_opt - t_root).abs() < 1e-6 * t_root, "{t_opt} {t_root}");
    let c = &r["constraints"][0];
    assert!((c["final"].as_f64().unwrap() / 0.26 - 1.0).abs() < 1e-6);
    // the mass is linear in t: m(t) = m_fixed + t (m(1) − m_fixed)
    let bars = 2700.0 * (1.6e-3 * 0.75 + 1.2e-3 * 0.75 + 0.8e-3 * 0.5);
    let mass = 9.55 - bars + t_root * bars;
    assert!((r["mass_final"].as_f64().unwrap() - mass).abs() < 1e-6 * mass);
    assert_eq!(r["kind"], "nastran_design");
    assert!(r["resolution"]["refined_modes"].as_u64().unwrap() == 16);
    assert!(c["refined"].as_f64().unwrap() > 0.0);
}

/// The shipped study: converged (exit 0), both limits met, results.json, summary.md and
/// figures written; `gustkit report` re-renders the summary from results.json to the same
/// bytes; `--resume` of the finished run continues from its checkpoint to the same design.
#[test]
fn shipped_study_runs_reports_and_resumes() {
    let dir = common::scratch("nastran", "design-shipped");
    let v = bar_wing_study();
    let out = run_study(&dir, "shipped", &v, &[]);
    common::assert_success(&out);
    let run = dir.join("reports/nastran_bar_wing");
    for f in [
        "results.json",
        "summary.md",
        "history.svg",
        "psd_final.svg",
        "checkpoint.json",
    ] {
        assert!(run.join(f).is_file(), "{f}");
    }
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("results.json")).unwrap()).unwrap();
    assert_eq!(r["converged"], true);
    for c in r["constraints"].as_array().unwrap() {
        let (value, limit) = (c["final"].as_f64().unwrap(), c["limit"].as_f64().unwrap());
        assert!(value <= limit * (1.0 + 1e-5), "{c}");
    }
    assert!(r["mass_final"].as_f64().unwrap() > 0.0);
    let summary = std::fs::read_to_string(run.join("summary.md")).unwrap();
    std::fs::remove_file(run.join("summary.md")).unwrap();
    let out = common::gustkit().arg("report").arg(&run).output().unwrap();
    common::assert_success(&out);
    assert_eq!(
        std::fs::read_to_string(run.join("summary.md")).unwrap(),
        summary
    );
    let out = run_study(&dir, "shipped", &v, &["--resume"]);
    common::assert_success(&out);
    let again: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("results.json")).unwrap()).unwrap();
    assert_eq!(again["design_variables"], r["design_variables"]);
    // a changed limit is a different problem: --resume refuses, naming the field
    let mut changed = v.clone();
    changed["constraints"][0]["rms_max"] = 0.2.into();
    let out = run_study(&dir, "shipped", &changed, &["--resume"]);
    common::assert_refused(&out, "constraints");
}

/// Limits no design within the bounds meets: the run writes everything (results.json with the
/// reason, summary) and exits 3.
#[test]
fn infeasible_limits_exit_3_with_results() {
    let dir = common::scratch("nastran", "design-infeasible");
    let mut v = bar_wing_study();
    v["constraints"] = serde_json::json!([{"output": "SPCF 1R1", "rms_max": 200.0}]);
    v["optimization"]["max_iterations"] = 15.into();
    let out = run_study(&dir, "infeasible", &v, &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{err}");
    let run = dir.join("reports/nastran_bar_wing");
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("results.json")).unwrap()).unwrap();
    assert_eq!(r["converged"], false);
    assert!(run.join("summary.md").is_file());
    assert!(std::fs::read_to_string(run.join("summary.md"))
        .unwrap()
        .contains("Not converged"));
}

/// Bad input: each a clear error (exit 1) naming the file's JSON path and the reason, and no
/// run folder.
#[test]
fn bad_nastran_studies_are_refused() {
    let dir = common::scratch("nastran", "design-bad");
    type Edit = Box<dyn Fn(&mut serde_json::Value)>;
    let cases: Vec<(&str, Edit, &str)> = vec![
        (
            "missing property",
            Box::new(|v| v["properties"][0]["id"] = 7.into()),
            "properties[0]: model: PBAR 7: is not a property of the model",
        ),
        (
            "wrong field",
            Box::new(|v| v["properties"][0]["field"] = "T".into()),
            "field T cannot be a design variable",
        ),
        (
            "unknown variable",
            Box::new(|v| v["properties"][0]["terms"] = serde_json::json!({"t_rot": 1.6e-3})),
            "properties[0].terms.t_rot: is not a design variable",
        ),
        (
            "unknown grid",
            Box::new(|v| v["constraints"][0]["output"] = "99T3".into()),
            "constraints[0].output: names grid 99",
        ),
        (
            "bad label",
            Box::new(|v| v["constraints"][0]["output"] = "tip".into()),
            "constraints[0].output: \"tip\" is not an output label",
        ),
        (
            "unknown monitor",
            Box::new(|v| v["constraints"][0]["output"] = "ROOT CMX".into()),
            "constraints[0].output: \"ROOT CMX\" is no output of the model (its monitor components: none",
        ),
        (
            "no limit",
            Box::new(|v| v["constraints"][0] = serde_json::json!({"output": "9T3"})),
            "constraints[0].rms_max: missing",
        ),
        (
            "initial outside bounds",
            Box::new(|v| v["design_variables"][0]["initial"] = 5.0.into()),
            "design_variables[0].initial: 5 lies outside the bounds",
        ),
        (
            "missing subcase",
            Box::new(|v| v["model"]["subcase"] = 4.into()),
            "model.subcase: the model has no subcase 4",
        ),
        (
            "flutter subcase",
            Box::new(|v| v["model"]["flutter_subcase"] = 7.into()),
            "model.flutter_subcase: the model has no subcase 7 with FMETHOD",
        ),
        (
            "missing model",
            Box::new(|v| v["model"]["nastran"] = "nowhere.bdf".into()),
            "model.nastran",
        ),
        (
            "unknown key",
            Box::new(|v| v["constraints"][0]["rms_maximum"] = 1.0.into()),
            "unknown field `rms_maximum`",
        ),
        (
            "objective",
            Box::new(|v| v["objective"] = "cost".into()),
            "objective: \"cost\" is not an objective",
        ),
        (
            "idle variable",
            Box::new(|v| {
                v["design_variables"].as_array_mut().unwrap().push(
                    serde_json::json!({"name": "spare", "initial": 1.0, "lower": 0.5, "upper": 2.0}),
                )
            }),
            "design_variables[3]: \"spare\" moves no property",
        ),
    ];
    for (name, edit, needle) in cases {
        let mut v = bar_wing_study();
        edit(&mut v);
        let out = run_study(&dir, "bad", &v, &[]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{name}: {err}");
        assert!(err.contains(needle), "{name}: {err}");
        assert!(err.contains("bad.json"), "{name}: {err}");
        assert!(!err.contains("panicked"), "{name}: {err}");
        assert!(!dir.join("reports/nastran_bar_wing").exists(), "{name}");
    }
}

/// The bar wing with a monitor point at the mid-span station (y = 0.75 m) summing the loads of
/// the outboard grids 4–9: shear CZ, bending CMX and torsion CMY.
fn bar_wing_with_monitor(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(bar_wing()).unwrap();
    let cards = "MONPNT1 MID     OUTBOARD LOADS                                          +MON1\n\
                 +MON1   345     WING    0       0.      0.75    0.                      \n\
                 AECOMP  WING    SET1    78                                              \n\
                 SET1    78      4       5       6       7       8       9               \n\
                 ENDDATA\n";
    let file = dir.join("bar_wing_monitor.bdf");
    std::fs::write(&file, text.replace("ENDDATA\n", cards)).unwrap();
    file
}

/// Monitor loads as design outputs: the mid-span station's shear, bending and torsion (their
/// aerodynamic part through the box forces' tangent and reverse mode, their inertial part
/// through ∂M and ∂φ) against central differences (best step to 1e-7) and the reverse mode
/// against the forward mode (1e-10), on the dense k and on MKAERO's.
#[test]
fn monitor_load_derivatives() {
    let dir = common::scratch("nastran", "design-monitor");
    let file = bar_wing_with_monitor(&dir);
    let relations: Vec<Relation> = vec![
        ("PBAR", 1, "A", 0.0, vec![(0, 1.6e-3)]),
        ("PBAR", 1, "I1", 0.0, vec![(0, 5.6e-7)]),
        ("PBAR", 2, "I1", 0.0, vec![(1, 4.0e-7)]),
        ("PBAR", 3, "A", 0.0, vec![(1, 0.4e-3), (2, 0.4e-3)]),
        ("PBAR", 3, "J", 0.0, vec![(2, 5.4e-8)]),
    ];
    let m = model(&file, 0.2, &relations, 3, &["9T3"]);
    let p = m.analyse(&[1.0, 1.0, 1.0]).unwrap();
    let labels: Vec<&str> = p.rows.iter().map(|r| r.label.as_str()).collect();
    assert_eq!(labels, ["9T3", "MID CZ", "MID CMX", "MID CMY"]);
    let worst = check_against_differences(&m, &[1.0, 1.0, 1.0]);
    let mut rev = check_reverse_against_forward(&m, &[1.0, 1.0, 1.0]);
    let k: Vec<f64> = (0..=40).map(|i| 0.2 * i as f64 / 40.0).collect();
    let mkaero = DesignModel {
        interpolation: KInterpolation::LinearOnMkaero(k),
        ..m
    };
    rev = rev.max(check_reverse_against_forward(&mkaero, &[1.1, 0.9, 1.2]));
    eprintln!("monitor: differences {worst:.1e}, reverse against forward {rev:.1e}");
}

/// A free-flying bar wing: the root's plunge (T3) and pitch (R2) free through SUPORT (the
/// other root components constrained, as a symmetric half model), the masses ahead of the
/// aerodynamic centre (a stable weathercock). Two rigid-body modes (a repeated zero root) and
/// six elastic ones: the rigid modes' shapes have no derivative of their own, but the response
/// depends on them only through the space they span, which sizing does not move — the
/// derivatives of mass, RMS and N0 (tip displacement, acceleration, the SUPORT's pitch
/// moment) match central differences to 1e-7 and the reverse mode matches the forward mode to
/// 1e-10.
#[test]
fn free_flying_design_derivatives() {
    let dir = common::scratch("nastran", "design-free");
    let text = std::fs::read_to_string(bar_wing()).unwrap();
    assert!(text.contains("SPC1,1,123456,1\n") && text.contains(",,0.2,0.05,0.,0.,"));
    let free = text
        .replace("SPC1,1,123456,1\n", "SPC1,1,1246,1\nSUPORT,1,35\n")
        .replace(",,0.2,0.05,0.,0.,", ",,0.2,-1.0,0.,0.,")
        .replace("SPCFORCES = 51\n", "");
    let file = dir.join("free.bdf");
    std::fs::write(&file, free).unwrap();
    let relations: Vec<Relation> = vec![
        ("PBAR", 1, "A", 0.0, vec![(0, 1.6e-3)]),
        ("PBAR", 1, "I1", 0.0, vec![(0, 5.6e-7)]),
        ("PBAR", 2, "A", 0.0, vec![(1, 1.2e-3)]),
        ("PBAR", 2, "I1", 0.0, vec![(1, 4.0e-7)]),
        ("PBAR", 3, "J", 0.0, vec![(1, 2.7e-8), (2, 2.7e-8)]),
    ];
    let m = model(&file, 0.2, &relations, 3, &["9T3", "ACCE 9T3", "9R2"]);
    let p = m.analyse(&[1.0, 1.0, 1.0]).unwrap();
    let f = p.modes.freq_hz();
    eprintln!("frequencies {f:?}");
    assert!(f[0] < 1e-3 && f[1] < 1e-3 && f[2] > 1.0, "{f:?}");
    let worst = check_against_differences(&m, &[1.0, 1.0, 1.0]);
    let rev = check_reverse_against_forward(&m, &[1.0, 1.0, 1.0]);
    eprintln!("free flying: differences {worst:.1e}, reverse against forward {rev:.1e}");
}

/// A run stopped by its iteration limit (exit 3, results written, checkpoint kept) and resumed
/// with a higher limit ends at the uninterrupted run's optimum (the same iterates: the
/// checkpoint holds the BFGS matrix and the merit penalty), to 1e-12.
#[test]
fn stopped_run_resumes_to_the_same_optimum() {
    let dir = common::scratch("nastran", "design-resume");
    let v = bar_wing_study();
    let out = run_study(&dir, "whole", &v, &[]);
    common::assert_success(&out);
    let read = || -> serde_json::Value {
        serde_json::from_str(
            &std::fs::read_to_string(dir.join("reports/nastran_bar_wing/results.json")).unwrap(),
        )
        .unwrap()
    };
    let whole = read();
    let mut short = v.clone();
    short["optimization"]["max_iterations"] = 2.into();
    let out = run_study(&dir, "whole", &short, &[]);
    assert_eq!(
        out.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(read()["converged"], false);
    let out = run_study(&dir, "whole", &v, &["--resume"]);
    common::assert_success(&out);
    assert!(String::from_utf8_lossy(&out.stdout).contains("resuming from iteration"));
    let resumed = read();
    assert_eq!(resumed["iterations"], whole["iterations"]);
    for (a, b) in resumed["design_variables"]
        .as_array()
        .unwrap()
        .iter()
        .zip(whole["design_variables"].as_array().unwrap())
    {
        let (x, y) = (a["final"].as_f64().unwrap(), b["final"].as_f64().unwrap());
        assert!((x - y).abs() <= 1e-12 * y.abs(), "{x} {y}");
    }
}

/// The flutter check of a design study (`model.flutter_subcase`): the model's FLUTTER 30 (p-k)
/// at the initial and final designs. With its velocities to 1.15 × the flight speed (the
/// shipped deck) neither design flutters and the run ends with exit 0; with the velocities to
/// 400 m/s the initial design's flutter speed is the one `gustkit run` finds for the same deck
/// as SOL 145 (the same p-k), the final design flutters within the list, and the run ends
/// with exit 3 saying where. The in-plane modes, which the lattice does not see, have a
/// damping of round-off size (±1e-15) and are not flutter.
#[test]
fn flutter_check_of_the_final_design() {
    let dir = common::scratch("nastran", "design-flutter");
    let v = bar_wing_study();
    let out = run_study(&dir, "flutter", &v, &[]);
    common::assert_success(&out);
    let read = |name: &str| -> serde_json::Value {
        serde_json::from_str(
            &std::fs::read_to_string(dir.join(format!("reports/{name}/results.json"))).unwrap(),
        )
        .unwrap()
    };
    let r = read("nastran_bar_wing");
    let row = &r["flutter_check"][0];
    assert_eq!(row["velocity_max"], 195.5);
    assert!(row.get("final_speed").is_none() || row["final_speed"].is_null());
    // velocities to 400 m/s
    let deck = std::fs::read_to_string(bar_wing()).unwrap();
    assert!(deck.contains("FLFACT,4,100.,THRU,195.5,20"));
    let wide = deck.replace("FLFACT,4,100.,THRU,195.5,20", "FLFACT,4,50.,THRU,400.,36");
    std::fs::write(dir.join("wide.bdf"), &wide).unwrap();
    let mut w = v.clone();
    w["model"]["nastran"] = dir.join("wide.bdf").display().to_string().into();
    let out = run_study(&dir, "flutter", &w, &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(err.contains("the final design flutters at V = "), "{err}");
    let r = read("nastran_bar_wing");
    let row = &r["flutter_check"][0];
    let (initial, last) = (
        row["initial_speed"].as_f64().unwrap(),
        row["final_speed"].as_f64().unwrap(),
    );
    // the same deck as a SOL 145 analysis: its flutter point
    let cc_end = wide.find("BEGIN BULK").unwrap();
    let sol145 = format!(
        "SOL 145\nCEND\nSPC = 1\nMETHOD = 1\nFMETHOD = 30\n{}",
        &wide[cc_end..]
    );
    std::fs::write(dir.join("f145.bdf"), sol145).unwrap();
    let out = common::gustkit()
        .arg("run")
        .arg(dir.join("f145.bdf"))
        .arg("--reports")
        .arg(dir.join("reports"))
        .output()
        .unwrap();
    common::assert_success(&out);
    let f = read("f145");
    let point = &f["subcases"][0]["flutter"][0];
    assert_eq!(point["flutter_speed"].as_f64().unwrap(), initial);
    eprintln!("flutter: initial {initial:.3} m/s (SOL 145 the same), final {last:.3} m/s");
    // a coupled bending–torsion mode, not an in-plane one
    assert!(initial > 150.0 && last > 150.0, "{initial} {last}");
}
