//! `aero.compare_with` and `gustkit compare`: a run's designs analysed with a second
//! fidelity, and one report across runs rendered from their results.json files alone.

use std::path::{Path, PathBuf};
use std::process::Output;

mod common;
use common::gustkit;

fn scratch(name: &str) -> common::Scratch {
    common::scratch("compare", name)
}

fn flagship() -> serde_json::Value {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/agard445_dlm.json");
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

/// Runs a study written to `dir/<name>.json` with its report folder in `dir`; a run that wrote
/// its results (converged or not) is expected.
fn run(dir: &Path, v: &serde_json::Value) -> serde_json::Value {
    let name = v["name"].as_str().unwrap();
    let file = dir.join(format!("{name}.json"));
    std::fs::write(&file, v.to_string()).unwrap();
    let o = gustkit()
        .args(["run", file.to_str().unwrap(), "--reports"])
        .arg(dir)
        .output()
        .unwrap();
    assert!(
        matches!(o.status.code(), Some(0) | Some(3)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(dir.join(name).join("results.json")).unwrap())
        .unwrap()
}

fn compare(dirs: &[PathBuf], out: &Path) -> Output {
    gustkit()
        .arg("compare")
        .args(dirs)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

/// A small DLM optimization (A) and a second run (B) warm-started from A's optimum with the
/// same fidelity, cross-evaluated with a finer DLM lattice. B's analysis of its starting design
/// with its own fidelity is A's analysis of A's optimum: the same RMS to the bit, which the
/// report's consistency table shows. The cross-evaluation's own-fidelity RMS of the initial and
/// final designs equal the run's snapshots, the timing block is recorded, and the report holds
/// its tables and figures.
#[test]
fn cross_evaluation_and_compare_report() {
    let dir = scratch("runs");
    let mut a = flagship();
    a["name"] = "cmp_a".into();
    a["aero"]["fidelity"]["dlm"]["n_chord"] = 3.into();
    a["aero"]["fidelity"]["dlm"]["n_span"] = 4.into();
    a["structure"]["modes"] = 4.into();
    a["structure"]["damping_ratio"] = 0.01.into();
    a["gust"]["points"] = 300.into();
    a["optimization"]["max_iterations"] = 3.into();
    a.as_object_mut().unwrap().remove("flutter");
    let ra = run(&dir, &a);
    assert_eq!(ra["fidelity"], "dlm");
    let timing = &ra["timing"];
    assert!(timing["function"]["median_s"].as_f64().unwrap() > 0.0);
    assert!(timing["gradient"]["repetitions"].as_u64().unwrap() >= 3);
    assert!(timing["threads"].as_u64().unwrap() >= 1);

    let mut b = a.clone();
    b["name"] = "cmp_b".into();
    b["optimization"]["max_iterations"] = 2.into();
    b["optimization"]["warm_start"] = serde_json::json!({ "from": dir.join("cmp_a/results.json") });
    b["aero"]["compare_with"] = serde_json::json!({ "dlm": { "n_chord": 5, "n_span": 7 } });
    let rb = run(&dir, &b);
    let c = &rb["cross_evaluation"];
    let designs = c["designs"].as_array().unwrap();
    let names: Vec<&str> = designs
        .iter()
        .map(|d| d["design"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["initial", "start", "final"]);
    assert_eq!(
        designs[1]["design_variables"],
        ra["final"]["design_variables"]
    );
    for (d, snapshot) in [(&designs[0], &rb["initial"]), (&designs[2], &rb["final"])] {
        let own = &d["evaluations"][0];
        assert_eq!(
            own["rms_display"], snapshot["rms_display"],
            "{}",
            d["design"]
        );
        let other = &d["evaluations"][1];
        // another lattice: another RMS, both finite and positive, and a GAF table each
        let (p, q) = (
            own["rms_display"].as_f64().unwrap(),
            other["rms_display"].as_f64().unwrap(),
        );
        assert!(p > 0.0 && q > 0.0 && p != q, "{p} {q}");
        assert_eq!(other["gafs"]["k"], own["gafs"]["k"]);
    }
    assert_eq!(
        designs[1]["evaluations"][0]["rms_display"],
        ra["final"]["rms_display"]
    );

    let out = dir.join("cmp");
    let o = compare(&[dir.join("cmp_a"), dir.join("cmp_b")], &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "compare.md",
        "compare.json",
        "convergence.png",
        "thickness.svg",
        "psd.png",
        "gafs.png",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("compare.json")).unwrap()).unwrap();
    assert_eq!(doc["runs"].as_array().unwrap().len(), 2);
    assert_eq!(doc["cross_evaluation"].as_array().unwrap().len(), 6);
    let cons = doc["consistency"].as_array().unwrap();
    assert_eq!(cons.len(), 1, "{cons:?}");
    assert_eq!(cons[0]["relative_difference"].as_f64().unwrap(), 0.0);
    assert_eq!(ra["aero_model"], "DLM 3 × 4 boxes");
    assert_eq!(cons[0]["model_here"], ra["aero_model"]);
    assert_eq!(cons[0]["model_there"], ra["aero_model"]);
    let md = std::fs::read_to_string(out.join("compare.md")).unwrap();
    assert!(!md.contains("Where the two models differ"), "{md}");
    assert!(
        md.contains("## Cross-evaluation") && md.contains("cmp_b (dlm)"),
        "{md}"
    );
    // written whole: no staging folder left beside it
    assert!(!dir.join(".cmp.partial").exists());

    // a run C on another lattice from A's optimum, cross-evaluated with a third: no evaluation
    // of C's has A's model, so its row compares two models, and the report says so
    let mut c = b.clone();
    c["name"] = "cmp_c".into();
    c["optimization"]["max_iterations"] = 1.into();
    c["aero"]["fidelity"]["dlm"]["n_chord"] = 4.into();
    c["aero"]["fidelity"]["dlm"]["n_span"] = 5.into();
    run(&dir, &c);
    let out = dir.join("cmp_ac");
    let o = compare(&[dir.join("cmp_a"), dir.join("cmp_c")], &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("compare.json")).unwrap()).unwrap();
    let cons = doc["consistency"].as_array().unwrap();
    assert_eq!(cons.len(), 1, "{cons:?}");
    assert_eq!(cons[0]["model_here"], "DLM 4 × 5 boxes");
    assert_eq!(cons[0]["model_there"], "DLM 3 × 4 boxes");
    assert!(cons[0]["relative_difference"].as_f64().unwrap() > 0.0);
    let md = std::fs::read_to_string(out.join("compare.md")).unwrap();
    assert!(md.contains("Where the two models differ"), "{md}");
}

/// The reference DLM optimum, cross-evaluated with a DLM lattice far below the box rule (3 × 4
/// boxes, against the 10 × 15 it was designed on), flutters below the flight speed there (mode 6
/// at 106 Hz, 126 m/s against 172.8 m/s): the cross-evaluation records the flutter point, the GAFs
/// and the reason in place of an RMS, and the report says "unstable".
#[test]
fn unstable_cross_evaluation_is_recorded() {
    let dir = scratch("unstable");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut v = flagship();
    v["name"] = "cmp_unstable".into();
    v["gust"]["points"] = 300.into();
    v["optimization"]["max_iterations"] = 1.into();
    v["optimization"]["warm_start"] = serde_json::json!({
        "from": root.join("reports/reference/agard445_dlm/results.json")
    });
    v["aero"]["compare_with"] = serde_json::json!({ "dlm": { "n_chord": 3, "n_span": 4 } });
    v.as_object_mut().unwrap().remove("flutter");
    let r = run(&dir, &v);
    let start = &r["cross_evaluation"]["designs"][1];
    assert_eq!(start["design"], "start");
    let coarse = &start["evaluations"][1];
    assert!(coarse["rms_display"].is_null());
    assert!(
        coarse["unstable"].as_str().unwrap().contains("flutters"),
        "{coarse}"
    );
    let flight = r["cross_evaluation"]["flight_speed_m_s"].as_f64().unwrap();
    assert!(coarse["flutter"]["speed_m_s"].as_f64().unwrap() < flight);
    // the study's own lattice finds the same design stable, with an RMS
    assert!(start["evaluations"][0]["rms_display"].as_f64().unwrap() > 0.0);
    let out = dir.join("cmp");
    let o = compare(&[dir.join("cmp_unstable")], &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let md = std::fs::read_to_string(out.join("compare.md")).unwrap();
    assert!(md.contains("unstable at the flight condition"), "{md}");
}

/// Runs that cannot be compared are refused with the file and the reason, and nothing is
/// written: another study kind, a run without an optimization, results schema 1 (no kind), a
/// results.json from before the fidelity was recorded, a folder without results.
#[test]
fn compare_refuses_what_it_cannot_compare() {
    let dir = scratch("refuse");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = dir.join("cmp");
    let check = |run: PathBuf, words: &[&str]| {
        let o = compare(std::slice::from_ref(&run), &out);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{stderr}");
        assert!(stderr.contains("results.json"), "{stderr}");
        for w in words {
            assert!(stderr.contains(w), "{w}: {stderr}");
        }
        assert!(!stderr.contains("backtrace"), "{stderr}");
        assert!(!out.exists() && !dir.join(".cmp.partial").exists());
    };
    check(
        root.join("reports/reference/verify_naca64a010_lfd_gust"),
        &["cfd_verification", "wing optimizations"],
    );
    let write = |name: &str, text: &str| -> PathBuf {
        let d = dir.join(name);
        std::fs::create_dir_all(&d).unwrap();
        std::fs::write(d.join("results.json"), text).unwrap();
        d
    };
    check(
        write("analysis", r#"{"kind": "wing", "study": "x"}"#),
        &["holds no optimization"],
    );
    check(
        write("schema1", r#"{"study": "x", "rms_tip_in": 1.0}"#),
        &["kind: missing", "results schema 1"],
    );
    check(dir.join("nothing"), &["cannot read"]);
}

/// `aero.compare_with` in an analysis run: the initial design's GAFs, gust response and p-k
/// sweep with the second fidelity sit beside the study's own in results.json, and are those of
/// the same study run with that fidelity as its own (to the bit); the GAF differences per k are
/// those of the two tables; the figures are written; a bad field of the second fidelity is
/// named by its path.
#[test]
fn analysis_with_a_second_fidelity() {
    let dir = scratch("analysis");
    let mut v = flagship();
    v["name"] = "cmp_analysis".into();
    v.as_object_mut().unwrap().remove("optimization");
    v["aero"]["fidelity"]["dlm"]["n_chord"] = 3.into();
    v["aero"]["fidelity"]["dlm"]["n_span"] = 4.into();
    v["structure"]["modes"] = 4.into();
    v["gust"]["points"] = 300.into();
    v["flutter"] =
        serde_json::json!({"velocity_min_m_s": 100.0, "velocity_max_m_s": 400.0, "points": 20});
    let second = serde_json::json!({ "dlm": { "n_chord": 5, "n_span": 7 } });
    v["aero"]["compare_with"] = second.clone();
    let r = run(&dir, &v);
    let c = &r["comparison"];
    assert_eq!(
        (c["fidelity"].as_str(), c["other"].as_str()),
        (Some("dlm"), Some("dlm"))
    );
    // the same study with the second fidelity as its own
    let mut w = v.clone();
    w["name"] = "cmp_analysis_second".into();
    w["aero"]["fidelity"] = second;
    w["aero"].as_object_mut().unwrap().remove("compare_with");
    let r2 = run(&dir, &w);
    for (i, o) in r2["gust"]["outputs"].as_array().unwrap().iter().enumerate() {
        assert_eq!(c["rms_other"][i], o["rms"], "{}", o["name"]);
    }
    assert_eq!(
        c["flutter_other"]["flutter_speed_m_s"],
        r2["flutter"]["flutter_speed_m_s"]
    );
    // the stated differences are those of the two tables
    let entry = |t: &serde_json::Value, i: usize, m: usize, n: usize| {
        let e = &t["q_ss"][i][m][n];
        num_complex::Complex64::new(e[0].as_f64().unwrap(), e[1].as_f64().unwrap())
    };
    for i in [0, 5, 10] {
        let (mut d, mut big) = (0.0f64, 0.0f64);
        for m in 0..4 {
            for n in 0..4 {
                let a = entry(&c["gafs"], i, m, n);
                d = d.max((a - entry(&c["gafs_other"], i, m, n)).norm());
                big = big.max(a.norm());
            }
        }
        let stated = c["gaf_difference_ss"][i].as_f64().unwrap();
        assert!(
            (stated - d / big).abs() <= 1e-14,
            "k[{i}]: {stated} against {}",
            d / big
        );
        assert!(stated > 0.0);
    }
    let folder = dir.join("cmp_analysis");
    for f in [
        "gafs_fidelities.png",
        "psd_fidelities.svg",
        "flutter_vg_dlm.png",
    ] {
        assert!(folder.join(f).is_file(), "{f}");
    }
    let md = std::fs::read_to_string(folder.join("summary.md")).unwrap();
    assert!(
        md.contains("(aero.compare_with)") && md.contains("| k | Q_ss | Q_gs |"),
        "{md}"
    );
    // a bad field of the second fidelity
    v["aero"]["compare_with"] = serde_json::json!({ "dlm": { "n_chord": 0, "n_span": 7 } });
    let file = dir.join("bad.json");
    std::fs::write(&file, v.to_string()).unwrap();
    let o = gustkit()
        .args(["run", file.to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("aero.compare_with.dlm") && stderr.contains("n_chord"),
        "{stderr}"
    );
}
