//! The first-hour bad-input cases of the reliability issue, by category, through the command line:
//! each is refused at load with exit status 1 and one line `error: FILE: JSON.PATH: reason` that
//! names the field and, for lengths, speaks the file's unit — never a panic (101), an abort (134)
//! or a kill (137), never a backtrace (even with RUST_BACKTRACE=1), and nothing is written.

use std::path::Path;
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};

fn flagship() -> serde_json::Value {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/agard445_dlm.json");
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

mod common;

/// A fresh scratch folder per call (the tests run in parallel), removed when it drops.
fn scratch() -> common::Scratch {
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    common::scratch(
        "bad-input",
        &NEXT.fetch_add(1, Ordering::Relaxed).to_string(),
    )
}

/// Sets the value at a dotted path (object keys or array indices).
fn set(v: &mut serde_json::Value, path: &str, value: serde_json::Value) {
    let mut node = v;
    let keys: Vec<&str> = path.split('.').collect();
    for key in &keys[..keys.len() - 1] {
        node = match key.parse::<usize>() {
            Ok(i) => &mut node[i],
            Err(_) => &mut node[*key],
        };
    }
    let last = keys[keys.len() - 1];
    match last.parse::<usize>() {
        Ok(i) => node[i] = value,
        Err(_) => node[last] = value,
    }
}

/// Runs `gustkit <command> FILE` on the flagship edited at `path` and checks the refusal.
fn refused(command: &str, path: &str, value: serde_json::Value, want_path: &str, want: &[&str]) {
    let dir = scratch();
    let mut v = flagship();
    set(&mut v, path, value);
    let name = format!("case_{}", want_path.replace(['.', '[', ']'], "_"));
    v["name"] = name.clone().into();
    let file = dir.join(format!("{name}.json"));
    std::fs::write(&file, v.to_string()).unwrap();
    let reports = dir.join("reports");
    let o = Command::new(env!("CARGO_BIN_EXE_gustkit"))
        .env("RUST_BACKTRACE", "1")
        .args([command, file.to_str().unwrap(), "--reports"])
        .arg(&reports)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{path}: {err}");
    let line = err.trim();
    assert_eq!(
        line.lines().count(),
        1,
        "{path}: one line, no backtrace: {err}"
    );
    let head = format!("error: {}: {want_path}: ", file.display());
    assert!(
        line.starts_with(&head),
        "{path}: want '{head}…', got {line}"
    );
    for w in want {
        assert!(line.contains(w), "{path}: want '{w}' in {line}");
    }
    assert!(
        !reports.join(&name).exists(),
        "{path}: a refused study writes nothing"
    );
}

/// Sizes that would exhaust the machine: refused before allocating, with the estimate.
#[test]
fn sizes_beyond_the_machine() {
    refused(
        "run",
        "structure.mesh.refine",
        50.into(),
        "structure.mesh.refine",
        &["251001 nodes", "GB", "limit of 12 GB"],
    );
    refused(
        "run",
        "aero.fidelity.dlm.n_chord",
        100000.into(),
        "aero.fidelity.dlm.n_chord",
        &["1500000 boxes", "GB"],
    );
    refused(
        "run",
        "aero.fidelity",
        serde_json::json!({"strip": {"n_strips": 100000}}),
        "aero.fidelity.strip.n_strips",
        &["[1, 10000]"],
    );
    refused(
        "run",
        "gust.points",
        10_000_000.into(),
        "gust.points",
        &["at most 1000000"],
    );
    refused(
        "flutter",
        "flutter",
        serde_json::json!({"velocity_min_m_s": 10.0, "velocity_max_m_s": 300.0, "points": 1_000_000}),
        "flutter.points",
        &["10000"],
    );
    refused(
        "run",
        "structure.modes",
        100000.into(),
        "structure.modes",
        &["degrees of freedom"],
    );
}

/// Garbage that used to be accepted: a 1e-6 in wing, Mach 0.999 with the DLM, a 1e308 grain
/// angle, sweep bounds beyond the wing's own 80°; values in the file's unit (inches).
#[test]
fn garbage_is_refused_in_the_files_units() {
    // the mode-acceleration switch takes a boolean
    refused(
        "run",
        "gust.mode_acceleration",
        "yes".into(),
        "gust.mode_acceleration",
        &["expected a boolean"],
    );
    refused(
        "modes",
        "wing.span",
        1e-6.into(),
        "wing.span",
        &["in (got 1.0000e-6 in)"],
    );
    refused(
        "modes",
        "wing.span",
        (-30.0).into(),
        "wing.span",
        &["positive", "-30 in"],
    );
    refused(
        "modes",
        "wing.span",
        1e308.into(),
        "wing.span",
        &["1.0000e308 in"],
    );
    refused(
        "run",
        "flight.mach",
        0.999.into(),
        "flight.mach",
        &["0.97", "lfd"],
    );
    refused(
        "modes",
        "material.grain_angle_deg",
        1e308.into(),
        "material.grain_angle_deg",
        &["-360 and 360"],
    );
    refused(
        "run",
        "optimization.sweep_c4_deg",
        serde_json::json!([0.0, 89.0]),
        "optimization.sweep_c4_deg[1]",
        &["80 degrees", "89 deg"],
    );
    refused(
        "run",
        "flight.velocity_m_s",
        1e300.into(),
        "flight.velocity_m_s",
        &["1.0000e300 m/s"],
    );
}

/// Errors that used to mislead: a huge thickness (was "rigid-body mode"), the iteration limit
/// (was reported against the tolerance), frequencies unsorted or too few (were caught late,
/// without the path), repeated prefixes, a 3-component point ("trailing characters").
#[test]
fn errors_say_what_is_wrong() {
    refused(
        "modes",
        "structure.thickness",
        serde_json::json!(vec![1e308; 100]),
        "structure.thickness[0]",
        &["at most 0.5", "in (got 1.0000e308 in)"],
    );
    refused(
        "run",
        "optimization.max_iterations",
        0.into(),
        "optimization.max_iterations",
        &["at least 1"],
    );
    refused(
        "run",
        "optimization.resolution_corrections",
        9.into(),
        "optimization.resolution_corrections",
        &["between 0 and 3", "got 9"],
    );
    refused(
        "run",
        "optimization.model_management",
        serde_json::json!({"low_fidelity": {"dlm": {"n_chord": 5, "n_span": 8}}, "initial_radius": 2.0}),
        "optimization.model_management.initial_radius",
        &["(0, 1]", "got 2"],
    );
    // a warm-start BFGS matrix that a managed run would silently drop
    let mut o = flagship()["optimization"].clone();
    o["model_management"] =
        serde_json::json!({"low_fidelity": {"dlm": {"n_chord": 5, "n_span": 8}}});
    o["warm_start"] = serde_json::json!({"from": "elsewhere/results.json", "hessian": true});
    refused(
        "run",
        "optimization",
        o,
        "optimization.warm_start.hessian",
        &["model_management", "set it to false"],
    );
    refused(
        "run",
        "optimization.nonmonotone_memory",
        0.into(),
        "optimization.nonmonotone_memory",
        &["between 1 (the monotone line search) and 20", "got 0"],
    );
    refused(
        "modes",
        "aero.reduced_frequencies",
        serde_json::json!([0.0, 0.5, 0.2, 1.0, 2.0]),
        "aero.reduced_frequencies[2]",
        &["increase", "0.2 after 0.5"],
    );
    refused(
        "modes",
        "aero.reduced_frequencies",
        serde_json::json!([0.0, 1.0, 2.0]),
        "aero.reduced_frequencies",
        &["at least 4"],
    );
    refused(
        "modes",
        "structure.clamp",
        serde_json::json!({"root_nodes": [50]}),
        "structure.clamp",
        &["root node index 50"],
    );
    refused(
        "modes",
        "gust.outputs.0.point",
        serde_json::json!([0.5, 0.5, 0.5]),
        "gust.outputs[0].point",
        &["more entries than this field takes"],
    );
}

/// The discrete gust section (issue 30): a gradient outside CS-25's 30–350 ft without the option
/// that allows it, a tabulated profile whose times do not increase, a 1-cos gust without its
/// amplitude, an alleviation factor above 1: each refused at load naming the field and the fix.
#[test]
fn discrete_gust_errors_name_the_field() {
    let cs25 = serde_json::json!({"cs25": {"altitude_m": 0.0, "f_g": 1.0}});
    refused(
        "modes",
        "discrete_gust",
        serde_json::json!({"gradient_ft": [20.0, 350.0], "amplitude": cs25}),
        "discrete_gust.gradient_ft",
        &["outside CS-25's 30–350 ft", "allow_any_gradient"],
    );
    refused(
        "modes",
        "discrete_gust",
        serde_json::json!({"profile": "tabulated", "table": {"time_s": [0.0, 0.2, 0.1], "velocity_m_s": [0.0, 5.0, 0.0]}}),
        "discrete_gust.table.time_s[2]",
        &["increase strictly", "0.1 s after 0.2 s"],
    );
    refused(
        "modes",
        "discrete_gust",
        serde_json::json!({"gradient_ft": [30.0, 350.0]}),
        "discrete_gust.amplitude",
        &["u_ds_m_s", "cs25"],
    );
    refused(
        "modes",
        "discrete_gust",
        serde_json::json!({"amplitude": {"cs25": {"altitude_m": 0.0, "f_g": 1.5}}}),
        "discrete_gust.amplitude.cs25.f_g",
        &["(0, 1]", "got 1.5"],
    );
    refused(
        "run",
        "optimization.peak_constraint",
        serde_json::json!({"output": "tip_te_w", "max": 1.0}),
        "optimization.peak_constraint",
        &["needs a discrete_gust section"],
    );
}

/// A prefix is never repeated: the JSON path names the field once.
#[test]
fn no_repeated_prefixes() {
    let dir = scratch();
    for (path, value) in [
        ("structure.clamp", serde_json::json!({"root_nodes": [50]})),
        ("structure.thickness", serde_json::json!(vec![-0.1; 100])),
    ] {
        let mut v = flagship();
        set(&mut v, path, value);
        let file = dir.join("prefix.json");
        std::fs::write(&file, v.to_string()).unwrap();
        let o = Command::new(env!("CARGO_BIN_EXE_gustkit"))
            .args(["modes", file.to_str().unwrap(), "--json"])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        for twice in ["clamp: clamp:", "]: thickness"] {
            assert!(!err.contains(twice), "{err}");
        }
    }
}

/// A UTF-8 byte-order mark (as Windows editors write) is accepted.
#[test]
fn byte_order_mark_is_accepted() {
    let dir = scratch();
    let mut v = flagship();
    v.as_object_mut().unwrap().remove("optimization");
    let file = dir.join("bom.json");
    std::fs::write(&file, format!("\u{feff}{v}")).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_gustkit"))
        .args(["modes", file.to_str().unwrap(), "--json", "--reports"])
        .arg(dir.join("reports"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// Command-line values: a negative reduced frequency is a value (and refused as one), a zero
/// repeat count (an LFD study's first calls only) is refused for a DLM study, several design variables follow one `--dv`, and an `--out` that is
/// a folder is refused without leaving a temporary file in it.
#[test]
fn command_line_values() {
    let dir = scratch();
    let study = Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/agard445_dlm.json");
    let g = || Command::new(env!("CARGO_BIN_EXE_gustkit"));
    let o = g()
        .args([
            "aic",
            study.to_str().unwrap(),
            "--mach",
            "0.5",
            "--k",
            "-0.5",
            "--out",
        ])
        .arg(dir.join("aic.json"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("--k: k[0]") && err.contains("-0.5"), "{err}");
    let o = g()
        .args(["bench", study.to_str().unwrap(), "--repeat", "0"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("--repeat 0") && err.contains("LFD study"),
        "{err}"
    );
    let o = g()
        .args(["bench", study.to_str().unwrap(), "--repeat", "-1"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let o = g()
        .args([
            "check-gradient",
            study.to_str().unwrap(),
            "--json",
            "--dv",
            "t[0]",
            "t[55]",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let names: Vec<&str> = rows["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["dv"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["t[0]", "t[55]"]);
    let out = dir.join("outdir");
    std::fs::create_dir_all(&out).unwrap();
    let o = g()
        .args([
            "aic",
            study.to_str().unwrap(),
            "--mach",
            "0.5",
            "--k",
            "0.1",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("is a folder"));
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 0, "no stray file");
}

/// `gustkit flutter` on a study without a `flutter` section: one line naming the field, the keys
/// to add and a range from the study's flight speed (the minimal wing flies at 170 m/s: 34 to
/// 340 m/s), and no report folder.
#[test]
fn flutter_without_a_flutter_section_names_what_to_add() {
    let base = scratch();
    let dir = base.join("no_flutter");
    let study = Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/minimal_wing.json");
    let o = Command::new(env!("CARGO_BIN_EXE_gustkit"))
        .args(["flutter", study.to_str().unwrap(), "--reports"])
        .arg(&dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    for w in [
        "minimal_wing.json: flutter: missing",
        "\"velocity_min_m_s\": 34",
        "\"velocity_max_m_s\": 340",
        "\"points\": 60",
    ] {
        assert!(err.contains(w), "want {w}: {err}");
    }
    assert!(!dir.join("minimal_wing").exists());
}

/// `gustkit mesh-study` refuses, with exit status 1 and nothing written: a study that is not an
/// LFD one, an unknown level, a level whose memory estimate is above the study's
/// `memory_limit_gb` (named with the estimate and the limit, before anything runs), and a
/// `--design` file that is not there.
#[test]
fn mesh_study_refuses_what_it_cannot_run() {
    let base = scratch();
    let dir = base.join("mesh-study");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let g = |study: &Path, levels: &str| {
        Command::new(env!("CARGO_BIN_EXE_gustkit"))
            .arg("mesh-study")
            .arg(study)
            .args(["--levels", levels, "--reports"])
            .arg(&dir)
            .output()
            .unwrap()
    };
    let o = g(&root.join("studies/agard445_dlm.json"), "coarse");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("needs the LFD fidelity"), "{err}");
    let lfd = root.join("studies/agard445_lfd_mesh_study.json");
    let o = g(&lfd, "coarse,finest");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("unknown mesh level \"finest\""), "{err}");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&lfd).unwrap()).unwrap();
    set(&mut v, "aero.fidelity.lfd.memory_limit_gb", 4.0.into());
    let small = base.join("mesh_study_4gb.json");
    std::fs::write(&small, v.to_string()).unwrap();
    let o = g(&small, "coarse,fine");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("level fine")
            && err.contains("458752 cells")
            && err.contains("memory_limit_gb = 4"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
    // `--design` of a results.json that is not there: the file named, nothing run
    let missing = base.join("no_run").join("results.json");
    let o = Command::new(env!("CARGO_BIN_EXE_gustkit"))
        .arg("mesh-study")
        .arg(&lfd)
        .args(["--levels", "coarse", "--reports"])
        .arg(&dir)
        .arg("--design")
        .arg(&missing)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("no_run") && err.contains("cannot read the file"),
        "{err}"
    );
    assert!(!dir.exists(), "nothing written");
}
