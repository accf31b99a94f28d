//! `gustkit flutter`: the p-k sweep of a wing study with its V-g/V-f figures and flutter.json.

use crate::report::run::flutter_point;
use crate::report::{self, save_figure, write_atomic};
use crate::study::Study;
use anyhow::Result;
use std::path::Path;

/// `gustkit flutter`: p-k sweep of a study at its flight Mach number and density, with the
/// same sweep at twice the resolution beside it when `resolution_check`.
pub fn flutter(study: &Study, json: bool, reports: &Path, resolution_check: bool) -> Result<()> {
    // a study without a usable sweep is refused before its report folder is made
    study.flutter_velocities()?;
    let dir = study.report_dir(reports);
    std::fs::create_dir_all(&dir)
        .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", dir.display()))?;
    // the report folder keeps the LFD's steady solution for the next command
    let mut study = study.clone();
    study.cache_dir = Some(dir.clone());
    let study = &study;
    let (doc, r, velocities) = flutter_analysis(study, &dir, resolution_check)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&doc)?);
        return Ok(());
    }
    print_flutter(study, &r, &velocities, &doc);
    let c = &doc["resolution_check"];
    match c["refined_model"].as_str() {
        _ if !resolution_check => println!("resolution check not run (--no-resolution-check)"),
        Some(m) => println!(
            "resolution check: with {m} the design {}{}",
            c["refined_flutter"].as_str().unwrap_or(""),
            c["change_percent"]
                .as_f64()
                .map(|p| format!(" ({p:+.2} % in flutter speed)"))
                .unwrap_or_default()
        ),
        None => println!(
            "resolution check not run: {}",
            c["not_run"].as_str().unwrap_or("")
        ),
    }
    println!(
        "V-g/V-f figures and flutter.json written to {}",
        study.report_dir(reports).display()
    );
    Ok(())
}

/// The p-k sweep of a study with its V-g/V-f figures and `flutter.json` in `dir`; with
/// `resolution_check`, the same sweep at the refined resolution beside it (`gustkit run` checks
/// its design on its own).
pub(crate) fn flutter_analysis(
    study: &Study,
    dir: &Path,
    resolution_check: bool,
) -> Result<(serde_json::Value, crate::flutter::FlutterResult, Vec<f64>)> {
    let file = &study.file;
    let velocities = study.flutter_velocities()?;
    let (plate, modes, _) = super::analyze(study)?;
    let aero = study.aero_model(&plate)?;
    super::write_artifacts(dir, &aero, study)?;
    let table = aero
        .gafs(&plate, &modes)
        .map_err(|e| anyhow::anyhow!("{}: aero: {e}", file.display()))?;
    let pk = crate::flutter::PkProblem::new(&modes, &table, aero.flight.density);
    let r = pk
        .sweep(&velocities)
        .map_err(|e| anyhow::anyhow!("{}: flutter: {e}", file.display()))?;
    save_figure(
        dir,
        "flutter_vg",
        &report::figures::VgVf {
            result: &r,
            title: format!(
                "{}: p-k, M = {}, rho = {} kg/m3",
                study.spec.name, aero.flight.mach, aero.flight.density
            ),
        },
    )?;
    let mut doc = serde_json::json!({
        "study": study.spec.name,
        "mach": aero.flight.mach,
        "density_kg_m3": aero.flight.density,
        "flight_speed_m_s": aero.flight.velocity,
        "verdict": crate::flutter::Verdict::of(&r).words(aero.flight.velocity),
        "flutter_speed_m_s": r.flutter_speed_m_s,
        "flutter_frequency_hz": r.flutter_frequency_hz,
        "flutter_mode": r.flutter_mode,
        "curves": r.curves,
    });
    if resolution_check {
        let dofs = study.retained_dofs(&plate);
        doc["resolution_check"] = super::resolution::flutter_sweep(study, &velocities, &r, dofs)?;
    }
    write_atomic(
        &dir.join("flutter.json"),
        serde_json::to_string_pretty(&doc)?.as_bytes(),
    )?;
    Ok((doc, r, velocities))
}

/// The p-k table and the flutter point on stdout.
pub(crate) fn print_flutter(
    study: &Study,
    r: &crate::flutter::FlutterResult,
    velocities: &[f64],
    doc: &serde_json::Value,
) {
    println!(
        "{}: p-k at M = {}, ρ = {} kg/m³",
        study.spec.name, doc["mach"], doc["density_kg_m3"]
    );
    print!("{:>10}", "V [m/s]");
    for c in &r.curves {
        print!("{:>22}", format!("mode {} g / f [Hz]", c.mode));
    }
    println!();
    for i in 0..velocities.len() {
        print!("{:>10.2}", velocities[i]);
        for c in &r.curves {
            print!("{:>12.4} {:>9.3}", c.damping_g[i], c.frequency_hz[i]);
        }
        println!();
    }
    println!("{}", flutter_point(r, doc["flight_speed_m_s"].as_f64()));
}
