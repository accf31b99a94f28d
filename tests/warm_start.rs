//! `optimization.warm_start`: the final design of an earlier run as the starting point, checked
//! when the study is loaded (a missing file names the command that makes it; another
//! parametrization or a design outside the bounds is refused with the reason).

use gustkit::study::Study;
use std::path::Path;

fn flagship() -> serde_json::Value {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/agard445_dlm.json");
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

/// A results.json and its final design.
fn reference_results(file: &Path) -> (serde_json::Value, Vec<f64>) {
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap();
    let want = r["final"]["design_variables"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d.as_f64().unwrap())
        .collect();
    (r, want)
}

/// A results.json like `r` with three design variables (another parametrization), in a scratch
/// folder named after `tag`: the folder and the file.
fn three_variable_results(
    r: &serde_json::Value,
    tag: &str,
) -> (std::path::PathBuf, std::path::PathBuf) {
    let dir = std::env::temp_dir().join(format!("gustkit-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let other = dir.join("results.json");
    let mut small = r.clone();
    small["design_variable_names"] = serde_json::json!(["t[0]", "t[1]", "span"]);
    small["final"]["design_variables"] = serde_json::json!([0.001, 0.001, 0.7]);
    std::fs::write(&other, small.to_string()).unwrap();
    (dir, other)
}

fn load(v: &serde_json::Value) -> Result<Study, gustkit::study::StudyError> {
    Study::from_str(Path::new("warm.json"), &v.to_string())
}

/// The reference DLM optimum (reports/reference/agard445_dlm, same plate and planform
/// parametrization) is taken as the starting design, to the bit; a missing file names the run
/// that writes it; another design-vector length and a design outside the bounds are refused.
#[test]
fn warm_start_reads_checks_and_refuses() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let reference = root.join("reports/reference/agard445_dlm/results.json");
    let mut v = flagship();
    v["optimization"]["warm_start"] = serde_json::json!({ "from": reference });
    let s = load(&v).unwrap();
    let x = s.warm_start_design().unwrap().unwrap();
    let (r, want) = reference_results(&reference);
    assert_eq!(x, want);
    // the study as a checkpoint records it: the new optional fields left out when unset (a
    // checkpoint of an earlier run keeps resuming)
    let spec = serde_json::to_value(&s.spec).unwrap();
    assert_eq!(
        spec["optimization"]["warm_start"],
        serde_json::json!({ "from": reference })
    );
    assert!(spec["aero"].get("compare_with").is_none());
    // missing: the path and the command that writes it
    v["optimization"]["warm_start"] =
        serde_json::json!({ "from": "no/such/agard445_dlm/results.json" });
    let e = load(&v).unwrap_err();
    assert_eq!(e.path, "optimization.warm_start.from", "{e}");
    assert!(
        e.reason
            .contains("no/such/agard445_dlm/results.json: cannot read the file")
            && e.reason.contains("gustkit run")
            && e.reason.contains("agard445_dlm"),
        "{e}"
    );
    // another parametrization: a results.json with three design variables
    let (dir, other) = three_variable_results(&r, "warm");
    v["optimization"]["warm_start"] = serde_json::json!({ "from": other });
    let e = load(&v).unwrap_err();
    assert!(
        e.reason.contains("has 3 design variables, this study 104"),
        "{e}"
    );
    // outside the bounds: the span far beyond its upper bound
    let mut far = r.clone();
    let n = want.len();
    far["final"]["design_variables"][n - 4] = serde_json::json!(10.0);
    std::fs::write(&other, far.to_string()).unwrap();
    let e = load(&v).unwrap_err();
    assert!(
        e.reason.contains("span = 10") && e.reason.contains("outside"),
        "{e}"
    );
    // not a results.json of an optimization
    std::fs::write(&other, "{\"kind\": \"wing\"}").unwrap();
    let e = load(&v).unwrap_err();
    assert!(e.reason.contains("holds no finished optimization"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `warm_start.hessian`: the final BFGS approximation of the run that wrote the results.json
/// (its checkpoint.json beside it) starts this run's, carried to this study's variable scaling:
/// with the same bounds it is taken as it is, with narrower thickness ranges each entry is
/// scaled by the ratios of the ranges; a missing checkpoint names the file.
#[test]
fn warm_start_hessian_is_carried_to_this_studys_scaling() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = std::env::temp_dir().join(format!("gustkit-warm-hessian-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let results = dir.join("results.json");
    std::fs::copy(
        root.join("reports/reference/agard445_dlm/results.json"),
        &results,
    )
    .unwrap();
    let mut v = flagship();
    v["optimization"]["warm_start"] = serde_json::json!({ "from": results, "hessian": true });
    let e = load(&v).unwrap_err();
    assert_eq!(e.path, "optimization.warm_start.hessian", "{e}");
    assert!(e.reason.contains("checkpoint.json"), "{e}");
    // a checkpoint with a known symmetric Hessian
    let n: usize = 104;
    let h: Vec<Vec<f64>> = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| match i.abs_diff(j) {
                    0 => 2.0 + i as f64,
                    1 => 0.5,
                    _ => 0.0,
                })
                .collect()
        })
        .collect();
    let cp = gustkit::optim::Checkpoint {
        problem_id: "agard445_dlm:0".into(),
        params: gustkit::optim::SqpParams::default(),
        iteration: 50,
        evaluations: 108,
        z: vec![0.5; n],
        hessian: h.clone(),
        penalty: 0.0,
        history: Vec::new(),
        elapsed_s: 0.0,
        problem_state: serde_json::Value::Null,
        stopped: None,
        point: None,
    };
    std::fs::write(
        dir.join("checkpoint.json"),
        serde_json::to_string(&cp).unwrap(),
    )
    .unwrap();
    let same = load(&v).unwrap().warm_start_hessian().unwrap().unwrap();
    assert_eq!(same, h);
    // wider relative thickness bounds: the ranges grow, H scales by their ratios
    v["optimization"]["thickness_relative"] = serde_json::json!([0.4, 2.5]);
    let s = load(&v).unwrap();
    let scaled = s.warm_start_hessian().unwrap().unwrap();
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&results).unwrap()).unwrap();
    let (lower, upper) = s.design_bounds().unwrap();
    let ratio = |i: usize| {
        (upper[i] - lower[i]) / (r["upper"][i].as_f64().unwrap() - r["lower"][i].as_f64().unwrap())
    };
    assert!(
        ratio(0) > 1.01,
        "the thickness range did grow: {}",
        ratio(0)
    );
    for (i, j) in [(0, 0), (0, 1), (57, 58), (103, 103)] {
        let want = ratio(i) * ratio(j) * h[i][j];
        assert!((scaled[i][j] - want).abs() <= 1e-15 * want.abs(), "{i},{j}");
    }
    // a variable fixed by equal bounds (the span at 30 in, that run's final span set to it): the
    // optimizer scales it by max(|x|, 1) = 1 m, so its entries scale by 1 / (that run's range)
    let mut r2 = r.clone();
    r2["final"]["design_variables"][100] = serde_json::json!(30.0 * 0.0254);
    std::fs::write(&results, r2.to_string()).unwrap();
    v["optimization"]["thickness_relative"] = serde_json::json!([0.5, 2.0]);
    v["optimization"]["span"] = serde_json::json!([30.0, 30.0]);
    let fixed = load(&v).unwrap().warm_start_hessian().unwrap().unwrap();
    let old_range = r["upper"][100].as_f64().unwrap() - r["lower"][100].as_f64().unwrap();
    for (i, j, want) in [
        (100, 100, h[100][100] / (old_range * old_range)),
        (99, 100, h[99][100] / old_range),
        (0, 0, h[0][0]),
    ] {
        assert!(
            (fixed[i][j] - want).abs() <= 1e-14 * want.abs(),
            "{i},{j}: {} against {want}",
            fixed[i][j]
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `gustkit flutter --design`: a run's final design becomes the analysed wing. Read back in SI
/// from the study written in inches and degrees, it is the recorded design to rounding (the
/// unit conversion's 1e-15, asked 1e-13 relative); the report name says whose design it is; a
/// design from another parametrization or with a thickness ≤ 0 is refused naming the results
/// file and its field.
#[test]
fn a_runs_final_design_becomes_the_analysed_wing() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let reference = root.join("reports/reference/agard445_dlm/results.json");
    let s = load(&flagship()).unwrap();
    let at = s.at_final_design(&reference).unwrap();
    assert_eq!(at.spec.name, "agard445_dlm_at_agard445_dlm");
    let (r, want) = reference_results(&reference);
    let got = at.initial_design().unwrap().to_vec();
    assert_eq!(got.len(), want.len());
    for (i, (g, w)) in got.iter().zip(&want).enumerate() {
        assert!((g - w).abs() <= 1e-13 * w.abs(), "{i}: {g} against {w}");
    }
    // the initial design differs from the optimum: the wing was replaced
    let initial = s.initial_design().unwrap().to_vec();
    assert!(initial.iter().zip(&want).any(|(a, b)| (a - b).abs() > 1e-6));
    let (dir, other) = three_variable_results(&r, "at-design");
    let e = s.at_final_design(&other).unwrap_err();
    assert_eq!(e.file, other);
    assert_eq!(e.path, "final.design_variables", "{e}");
    assert!(
        e.reason.contains("has 3 design variables, this study 104"),
        "{e}"
    );
    let mut negative = r.clone();
    negative["final"]["design_variables"][7] = serde_json::json!(-0.001);
    std::fs::write(&other, negative.to_string()).unwrap();
    let e = s.at_final_design(&other).unwrap_err();
    assert_eq!(e.path, "final.design_variables", "{e}");
    assert!(
        e.reason.contains("structure.thickness[7]") && e.reason.contains("positive"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
