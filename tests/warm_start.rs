//! `optimization.warm_start`: the final design of an earlier run as the starting point, checked
//! when the study is loaded (a missing file names the command that makes it; another
//! parametrization or a design outside the bounds is refused with the reason).

use gustkit::study::Study;
use std::path::Path;

fn flagship() -> serde_json::Value {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/agard445_dlm.json");
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
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
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&reference).unwrap()).unwrap();
    let want: Vec<f64> = r["final"]["design_variables"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d.as_f64().unwrap())
        .collect();
    assert_eq!(x, want);
    // missing: the path and the command that writes it
    v["optimization"]["warm_start"] =
        serde_json::json!({ "from": "no/such/agard445_dlm/results.json" });
    let e = load(&v).unwrap_err();
    assert_eq!(e.path, "optimization.warm_start.from", "{e}");
    assert!(
        e.reason
            .contains("cannot read no/such/agard445_dlm/results.json")
            && e.reason.contains("gustkit run")
            && e.reason.contains("agard445_dlm"),
        "{e}"
    );
    // another parametrization: a results.json with three design variables
    let dir = std::env::temp_dir().join(format!("gustkit-warm-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let other = dir.join("results.json");
    let mut small = r.clone();
    small["design_variable_names"] = serde_json::json!(["t[0]", "t[1]", "span"]);
    small["final"]["design_variables"] = serde_json::json!([0.001, 0.001, 0.7]);
    std::fs::write(&other, small.to_string()).unwrap();
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
