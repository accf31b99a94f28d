//! Study loading: the shipped study parses, and bad input names the file, field and reason.

use super::*;

fn agard_text() -> String {
    std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/studies/agard445_dlm_analysis.json"
    ))
    .unwrap()
}

fn load_modified(edit: impl FnOnce(&mut serde_json::Value)) -> Result<Study, StudyError> {
    let mut v: serde_json::Value = serde_json::from_str(&agard_text()).unwrap();
    edit(&mut v);
    Study::from_str(Path::new("case.json"), &v.to_string())
}

#[test]
fn shipped_study_loads_in_si() {
    let s = load_modified(|_| {}).unwrap();
    let p = s.planform().unwrap();
    assert!((p.span - 0.762).abs() < 1e-12);
    assert!((p.root_chord - 0.5587).abs() < 1e-4);
    let d = s.initial_design().unwrap();
    assert_eq!(d.thickness.len(), 100);
    // root leading-edge patch: chord at 5 % span × (z(0) + z(0.1))
    let expect = p.chord(0.05) * (0.0 + 0.01213);
    assert!((d.thickness[0] - expect).abs() < 1e-12);
}

fn expect_error(edit: impl FnOnce(&mut serde_json::Value), path: &str, reason_part: &str) {
    let e = load_modified(edit).unwrap_err();
    assert_eq!(e.path, path, "{e}");
    assert!(e.reason.contains(reason_part), "{e}");
    assert!(e.to_string().starts_with("case.json: "), "{e}");
}

#[test]
fn unknown_and_missing_fields_name_their_path() {
    expect_error(
        |v| v["wing"]["spam"] = 1.0.into(),
        "wing.spam",
        "unknown field `spam`",
    );
    expect_error(
        |v| {
            v["wing"].as_object_mut().unwrap().remove("span");
        },
        "wing",
        "missing field `span`",
    );
    expect_error(
        |v| v["structure"]["mesh"]["chordwise"] = "ten".into(),
        "structure.mesh.chordwise",
        "invalid type",
    );
    expect_error(
        |v| v["schema_version"] = 7.into(),
        "schema_version",
        "schema version 1",
    );
}

#[test]
fn bad_values_name_their_field() {
    expect_error(
        |v| v["wing"]["span"] = (-1.0).into(),
        "wing.span",
        "positive",
    );
    expect_error(
        |v| v["wing"]["tip_chord"] = 0.0.into(),
        "wing.tip_chord",
        "positive",
    );
    expect_error(
        |v| v["wing"]["sweep_c4_deg"] = 89.0.into(),
        "wing.sweep_c4_deg",
        "80",
    );
    expect_error(
        |v| v["material"]["g12_pa"] = 0.0.into(),
        "material.g12_pa",
        "positive",
    );
    expect_error(
        |v| v["material"]["nu12"] = 3.0.into(),
        "material.nu12",
        "positive definite",
    );
    expect_error(
        |v| v["material"]["density_kg_m3"] = (-3.0).into(),
        "material.density_kg_m3",
        "positive",
    );
    expect_error(
        |v| v["structure"]["damping_ratio"] = 1.5.into(),
        "structure.damping_ratio",
        "[0, 1)",
    );
    expect_error(
        |v| v["structure"]["modes"] = 0.into(),
        "structure.modes",
        "at least 1",
    );
    expect_error(
        |v| v["structure"]["clamp"] = "none".into(),
        "structure.clamp",
        "unknown clamp",
    );
    expect_error(
        |v| v["structure"]["clamp"] = serde_json::json!({"root_nodes": [99]}),
        "structure.clamp",
        "outside",
    );
    expect_error(
        |v| v["wing"]["airfoil"] = "naca0012".into(),
        "wing.airfoil",
        "unknown built-in",
    );
    let mut t = vec![0.1; 100];
    t[17] = -0.01;
    expect_error(
        |v| v["structure"]["thickness"] = t.into(),
        "structure.thickness[17]",
        "positive",
    );
    expect_error(
        |v| v["structure"]["thickness"] = vec![0.1; 3].into(),
        "structure.thickness",
        "expected 100",
    );
    expect_error(|v| v["name"] = "a/b".into(), "name", "file-name-safe");
}

#[test]
fn unreadable_file_and_syntax_errors() {
    let e = Study::load(Path::new("/nonexistent/study.json")).unwrap_err();
    assert!(e.reason.contains("cannot read"), "{e}");
    let e = Study::from_str(Path::new("x.json"), "{\"schema_version\": 1,").unwrap_err();
    assert!(e.reason.contains("EOF"), "{e}");
}

fn flagship_error(edit: impl FnOnce(&mut serde_json::Value), path: &str, reason_part: &str) {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/studies/agard445_dlm.json"
    ))
    .unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    edit(&mut v);
    let e = Study::from_str(Path::new("case.json"), &v.to_string()).unwrap_err();
    assert_eq!(e.path, path, "{e}");
    assert!(e.reason.contains(reason_part), "{e}");
}

/// The flagship's optimization section: bounds that cannot hold, an initial design outside them,
/// bad relative bounds, flutter margin, calibration and sweep entries name their field.
#[test]
fn optimization_and_sweep_errors_name_their_field() {
    flagship_error(
        |v| v["optimization"]["span"] = serde_json::json!([33.0, 27.0]),
        "optimization.span",
        "exceeds",
    );
    flagship_error(
        |v| v["optimization"]["sweep_c4_deg"] = serde_json::json!([46.0, 50.0]),
        "optimization.sweep_c4_deg",
        "outside the bounds",
    );
    flagship_error(
        |v| v["optimization"]["thickness_relative"] = serde_json::json!([1.2, 2.0]),
        "optimization.thickness_relative",
        "lower <= 1 <= upper",
    );
    flagship_error(
        |v| v["optimization"]["flutter_margin"]["speed_factor"] = (-1.0).into(),
        "optimization.flutter_margin.speed_factor",
        "(0, 3]",
    );
    flagship_error(
        |v| v["optimization"]["flutter_margin"]["damping"] = 0.0.into(),
        "optimization.flutter_margin.damping",
        "unknown field",
    );
    flagship_error(
        |v| v["structure"]["thickness_scale"] = 0.0.into(),
        "structure.thickness_scale",
        "positive",
    );
    flagship_error(
        |v| v["gust"]["calibration"]["target"] = 1.0.into(),
        "gust.calibration.target",
        "unknown field",
    );
    flagship_error(
        |v| v["sweep"] = serde_json::json!({"parameters": [{"path": "flight.mach"}]}),
        "sweep.parameters[0]",
        "missing field `values`",
    );
}

/// Sweep cases: grid order (first parameter fastest), zip, and the errors of bad sweeps.
#[test]
fn sweep_cases_grid_zip_and_errors() {
    let mut v: serde_json::Value = serde_json::from_str(&agard_text()).unwrap();
    v["sweep"] = serde_json::json!({"parameters": [
        {"path": "flight.mach", "values": [0.3, 0.4, 0.5]},
        {"path": "gust.turbulence.sigma_w_m_s", "values": [1.0, 2.0]}
    ]});
    let s = Study::from_str(Path::new("s.json"), &v.to_string()).unwrap();
    let cases = s.sweep_cases().unwrap();
    assert_eq!(cases.len(), 6);
    assert_eq!(cases[4].values, vec![0.4, 2.0]);
    let f = cases[4].study.flight_condition().unwrap();
    assert_eq!(f.mach, 0.4);
    assert_eq!(
        cases[4].study.gust_settings().unwrap().turbulence.sigma(),
        2.0
    );
    assert!(cases[4].study.spec.sweep.is_none());
    v["sweep"]["combine"] = "zip".into();
    let s = Study::from_str(Path::new("s.json"), &v.to_string()).unwrap();
    let e = s.sweep_cases().unwrap_err();
    assert_eq!(e.path, "sweep.combine");
    v["sweep"]["parameters"][0]["values"] = serde_json::json!([0.3, 0.6]);
    let s = Study::from_str(Path::new("s.json"), &v.to_string()).unwrap();
    let cases = s.sweep_cases().unwrap();
    assert_eq!(cases.len(), 2);
    assert_eq!(cases[1].values, vec![0.6, 2.0]);
    // a Mach number the DLM refuses is named with its case
    v["sweep"]["parameters"][0]["values"] = serde_json::json!([0.3, 1.2]);
    let s = Study::from_str(Path::new("s.json"), &v.to_string()).unwrap();
    let e = s.sweep_cases().unwrap_err();
    assert!(
        e.reason.contains("case 1") && e.reason.contains("flight.mach = 1.2"),
        "{e}"
    );
    // a string field is not a parameter; optimize without an optimization section
    v["sweep"]["parameters"][0]["path"] = "wing.airfoil".into();
    let s = Study::from_str(Path::new("s.json"), &v.to_string()).unwrap();
    let e = s.sweep_cases().unwrap_err();
    assert_eq!(e.path, "sweep.parameters[0].path");
    v["sweep"]["parameters"][0]["path"] = "flight.mach".into();
    v["sweep"]["optimize"] = true.into();
    let s = Study::from_str(Path::new("s.json"), &v.to_string()).unwrap();
    assert_eq!(s.sweep_cases().unwrap_err().path, "sweep.optimize");
}

/// `structure.modes` as a cutoff rule: its fields are checked by name, and the rule retains
/// exactly the modes of the complete spectrum below the cutoff k_max V_top / (2π b_ref), at least
/// `min`, at most `max`.
#[test]
fn mode_cutoff_rule() {
    expect_error(
        |v| v["structure"]["modes"] = serde_json::json!({"min": 0}),
        "structure.modes.min",
        "at least 1",
    );
    expect_error(
        |v| v["structure"]["modes"] = serde_json::json!({"min": 8, "max": 4}),
        "structure.modes.max",
        "at least min",
    );
    expect_error(
        |v| v["structure"]["modes"] = serde_json::json!({"cutoff_hz": -5.0}),
        "structure.modes.cutoff_hz",
        "positive",
    );
    expect_error(
        |v| v["structure"]["modes"] = serde_json::json!({"min": 100000, "max": 100000}),
        "structure.modes.min",
        "degrees of freedom",
    );
    let study =
        load_modified(|v| v["structure"]["modes"] = serde_json::json!({"max": 40})).unwrap();
    let crate::study::ModeRule::Cutoff {
        omega_cut,
        min,
        max,
    } = study.mode_rule().unwrap()
    else {
        panic!("a cutoff rule");
    };
    let f = study.flight_condition().unwrap();
    let k_max = *study
        .spec
        .aero
        .as_ref()
        .unwrap()
        .reduced_frequencies
        .last()
        .unwrap();
    assert!((omega_cut - k_max * study.top_speed().unwrap() / f.b_ref).abs() < 1e-9 * omega_cut);
    assert_eq!((min, max), (6, 40));
    let plate = study.build_model().unwrap();
    let modes = study.solve_modes(&plate).unwrap();
    let all = crate::structure::modal::solve(&plate, 40, 0.0, &study.mode_fields()).unwrap();
    let below = all
        .omega()
        .iter()
        .filter(|w| **w <= omega_cut)
        .count()
        .max(6);
    assert_eq!(modes.len(), below);
    for (a, b) in modes.omega().iter().zip(all.omega()) {
        assert!((a - b).abs() <= 1e-12 * b);
    }
    // a cutoff below the first mode keeps the floor; one above every mode the ceiling
    let low = load_modified(|v| {
        v["structure"]["modes"] = serde_json::json!({"cutoff_hz": 0.1, "min": 3})
    })
    .unwrap();
    assert_eq!(low.solve_modes(&plate).unwrap().len(), 3);
    let high = load_modified(|v| {
        v["structure"]["modes"] = serde_json::json!({"cutoff_hz": 1e6, "min": 3, "max": 9})
    })
    .unwrap();
    assert_eq!(high.solve_modes(&plate).unwrap().len(), 9);
}
