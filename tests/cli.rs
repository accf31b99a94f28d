//! The command line as users run it: outputs, files, and errors on bad input.

use std::path::{Path, PathBuf};
use std::process::Command;

fn gustkit() -> Command {
    Command::new(env!("CARGO_BIN_EXE_gustkit"))
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gustkit-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn study() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/agard445_dlm.json")
}

/// `gustkit modes --json` prints the frequencies and mass and writes the figures and the VTK file.
#[test]
fn modes_json_and_report_files() {
    let dir = scratch("modes");
    let out = gustkit()
        .args(["modes", study().to_str().unwrap(), "--json", "--reports"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let f = v["frequencies_hz"].as_array().unwrap();
    assert_eq!(f.len(), 6);
    // first bending of the AGARD wing: Yates 9.60 Hz; the plate model is within 5 %
    let f1 = f[0].as_f64().unwrap();
    assert!((f1 - 9.60).abs() < 0.05 * 9.60, "{f1}");
    let m = v["mass_kg"].as_f64().unwrap();
    assert!((m - 1.69).abs() < 0.02, "{m}");
    for name in ["modes.png", "modes.svg", "modes.vtk"] {
        let p = dir.join("agard445_dlm").join(name);
        assert!(
            std::fs::metadata(&p)
                .map(|m| m.len() > 1000)
                .unwrap_or(false),
            "{name} missing"
        );
    }
    let vtk = std::fs::read_to_string(dir.join("agard445_dlm/modes.vtk")).unwrap();
    assert!(vtk.contains("POINTS 121 double") && vtk.contains("VECTORS mode_6 double"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `gustkit run` writes results.json and summary.md.
#[test]
fn run_writes_results_and_summary() {
    let dir = scratch("run");
    let out = gustkit()
        .args(["run", study().to_str().unwrap(), "--reports"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("agard445_dlm/results.json")).unwrap(),
    )
    .unwrap();
    assert!(r["mass_kg"].as_f64().unwrap() > 1.6);
    let md = std::fs::read_to_string(dir.join("agard445_dlm/summary.md")).unwrap();
    assert!(md.contains("| 1 | bending |"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A malformed study fails with the file, the field path and the reason, and no panic.
#[test]
fn bad_study_names_file_and_field() {
    let dir = scratch("bad");
    let text = std::fs::read_to_string(study())
        .unwrap()
        .replace("\"span\": 30.0", "\"span\": -30.0");
    let bad = dir.join("bad.json");
    std::fs::write(&bad, text).unwrap();
    let out = gustkit()
        .args(["modes", bad.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.json") && err.contains("wing.span") && err.contains("positive"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An unwritable report folder is a clear error.
#[test]
fn unwritable_report_folder_is_an_error() {
    let out = gustkit()
        .args([
            "modes",
            study().to_str().unwrap(),
            "--reports",
            "/proc/gustkit-no",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("cannot create folder"), "{err}");
}
