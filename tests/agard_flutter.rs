//! p-k flutter of the AGARD 445.6 weakened wing with the DLM against the wind-tunnel flutter points
//! (Yates, AGARD R-765): M = 0.499, ρ = 0.000830 slug/ft³: V_f = 565.5 ft/s (172.4 m/s), flutter
//! frequency ratio 0.5353 of the 38.17 Hz torsion mode (20.4 Hz); M = 0.901, ρ = 0.000193 slug/ft³:
//! V_f = 973.4 ft/s (296.7 m/s), 101.1 rad/s (16.09 Hz; flutter speed index 0.3700, mass ratio
//! 143.9: V_f = 0.37 · b_s ω_α √μ with b_s = 0.9165 ft, ω_α = 239.3 rad/s gives the same speed). Linear potential flow with a plate model is expected
//! within several percent at M = 0.5 and to lie above experiment near M = 0.9 (no transonic dip).

mod common;

use std::path::Path;
use std::process::Command;

fn flutter(study: &str) -> serde_json::Value {
    let dir = std::env::temp_dir().join(format!("gustkit-flutter-{}-{study}", std::process::id()));
    let o = Command::new(env!("CARGO_BIN_EXE_gustkit"))
        .args([
            "flutter",
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("studies")
                .join(study)
                .to_str()
                .unwrap(),
            "--json",
            "--reports",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(dir
        .join(study.trim_end_matches(".json"))
        .join("flutter_vg.png")
        .exists());
    std::fs::remove_dir_all(&dir).unwrap();
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn agard_flutter_m0499_and_m0901() {
    for (study, v_exp, f_exp, tol_v, tol_f) in [
        ("agard445_flutter_m0499.json", 172.4, 20.4, 0.06, 0.15),
        ("agard445_flutter_m0901.json", 296.7, 16.09, 0.08, 0.10),
    ] {
        let r = flutter(study);
        let v = r["flutter_speed_m_s"].as_f64().expect("flutter found");
        let f = r["flutter_frequency_hz"].as_f64().unwrap();
        println!("{study}: V_f {v:.1} m/s (exp {v_exp}), f {f:.2} Hz (exp {f_exp})");
        assert!((v - v_exp).abs() < tol_v * v_exp, "{study}: {v}");
        assert!((f - f_exp).abs() < tol_f * f_exp, "{study}: {f}");
        assert_eq!(r["curves"].as_array().unwrap().len(), 6);
    }
}

/// The transonic dip, which linear potential flow cannot see: at M = 0.954, ρ = 0.000123 slug/ft³
/// (Yates: V_f = 1008.4 ft/s = 307.4 m/s, flutter speed index 0.3059, the bottom of the dip) the
/// DLM's flutter speed lies further above experiment than at M = 0.901 (measured +11.3 % against
/// +2.5 %), and within 20 % of it.
#[test]
fn dlm_misses_the_transonic_dip() {
    let over = |study: &str, v_exp: f64| {
        let v = flutter(study)["flutter_speed_m_s"]
            .as_f64()
            .expect("flutter found");
        v / v_exp - 1.0
    };
    let at_0901 = over("agard445_flutter_m0901.json", 296.7);
    let at_0954 = over("agard445_flutter_m0954.json", 307.4);
    assert!(
        at_0954 > at_0901 && at_0954 > 0.0 && at_0954 < 0.2,
        "above experiment: {at_0901:.3} at M 0.901, {at_0954:.3} at M 0.954"
    );
}

/// `gustkit run` on a flutter study includes the p-k result in results.json and summary.md.
#[test]
fn run_includes_flutter() {
    let dir = std::env::temp_dir().join(format!("gustkit-run-flutter-{}", std::process::id()));
    let o = Command::new(env!("CARGO_BIN_EXE_gustkit"))
        .args([
            "run",
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("studies/agard445_flutter_m0901.json")
                .to_str()
                .unwrap(),
            "--reports",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("agard445_flutter_m0901/results.json")).unwrap(),
    )
    .unwrap();
    assert!(r["flutter"]["flutter_speed_m_s"].as_f64().unwrap() > 250.0);
    let md = std::fs::read_to_string(dir.join("agard445_flutter_m0901/summary.md")).unwrap();
    assert!(md.contains("## Flutter (p-k)"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// On the flagship's optimum of November 2026 (tests/data: modes 4 and 5 at 71.8 and 76.7 Hz
/// settled on one root before the roots were assigned jointly), every p-k branch keeps its own
/// root at every speed: no two modes report the same damping and frequency.
#[test]
fn flagship_optimum_branches_stay_apart() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    // the flagship's model of that time: 6 modes on 8 × 12 boxes
    let mut v: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root.join("studies/agard445_dlm.json")).unwrap(),
    )
    .unwrap();
    v["structure"]["modes"] = 6.into();
    v["aero"]["fidelity"]["dlm"]["n_chord"] = 8.into();
    v["aero"]["fidelity"]["dlm"]["n_span"] = 12.into();
    let study =
        gustkit::study::Study::from_str(&root.join("flagship_2026_11.json"), &v.to_string())
            .unwrap();
    let x = common::fixture_design("agard445_dlm_optimum_2026_11.json");
    let settings = study.gust_settings().unwrap();
    let case = study.resolve().unwrap();
    let ev = gustkit::pipeline::evaluate(&case, &settings, &x).unwrap();
    let pk = gustkit::flutter::PkProblem::new(&ev.modes, &ev.table, ev.aero.flight.density);
    let v_flight = ev.aero.flight.velocity;
    let speeds: Vec<f64> = (1..=60).map(|i| v_flight * 2.0 * i as f64 / 60.0).collect();
    let r = pk.sweep(&speeds).unwrap();
    for iv in 0..speeds.len() {
        for a in 0..r.curves.len() {
            for b in a + 1..r.curves.len() {
                let (ca, cb) = (&r.curves[a], &r.curves[b]);
                let d = (ca.damping_g[iv] - cb.damping_g[iv]).abs()
                    + (ca.frequency_hz[iv] - cb.frequency_hz[iv]).abs();
                assert!(
                    d > 1e-6,
                    "V {:.1} m/s: modes {} and {} share the root g {:.5}, f {:.3} Hz",
                    speeds[iv],
                    ca.mode,
                    cb.mode,
                    ca.damping_g[iv],
                    ca.frequency_hz[iv]
                );
            }
        }
    }
    let fl = r.flutter_speed_m_s.expect("the optimum flutters below 2 V");
    println!(
        "optimum: flutter at {:.1} m/s = {:.3} V (mode {:?})",
        fl,
        fl / v_flight,
        r.flutter_mode
    );
    // the margin constraint (every root damped up to 1.15 V) is active at the optimum
    assert!(fl > 1.14 * v_flight && fl < 1.25 * v_flight, "{fl}");
}
