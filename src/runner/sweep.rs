//! `gustkit sweep`: every case of a study's sweep section in parallel, each case's result saved
//! as it finishes (so `--resume` redoes only the missing ones), then the table, CSV and figure.

use crate::report::write_atomic;
use crate::runner::wing::{analyze, optimize::optimize, optimize::spec_hash};
use crate::study::Study;
use anyhow::{Context, Result};
use std::path::Path;
use std::time::Instant;

/// The metrics of one sweep case, as far as they could be computed: mass and first frequency;
/// flutter speed (with a flutter section; none found in the range gives no value); RMS of every
/// gust output; the optimum (with `optimize`). A stage that fails (e.g. the flight condition
/// flutters, so there is no RMS) ends the case with its error and keeps what came before.
fn sweep_metrics(
    case: &crate::study::sweep::SweepCase,
    dir: &Path,
    optimize_case: bool,
) -> (
    Vec<crate::report::sweep::Metric>,
    Option<String>,
    Option<String>,
) {
    use crate::report::sweep::Metric;
    let metric = |name: &str, unit: &str, value: f64| Metric {
        name: name.to_string(),
        unit: unit.to_string(),
        value,
    };
    let study = &case.study;
    let mut out = Vec::new();
    let mut message = None;
    let mut stages = || -> Result<()> {
        let (plate, modes, summary) = analyze(study)?;
        out.push(metric("mass", "kg", summary.mass_kg));
        out.push(metric("f1", "Hz", summary.frequencies_hz[0]));
        if study.spec.flutter.is_some() {
            let aero = study.aero_model(&plate)?;
            let table = aero
                .gafs(&plate, &modes)
                .map_err(|e| anyhow::anyhow!("aero: {e}"))?;
            let pk = crate::flutter::PkProblem::new(&modes, &table, aero.flight.density);
            let r = pk.sweep(&study.flutter_velocities()?)?;
            if let Some(v) = r.flutter_speed_m_s {
                out.push(metric("flutter speed", "m/s", v));
                out.push(metric(
                    "flutter speed / flight speed",
                    "-",
                    v / aero.flight.velocity,
                ));
            }
        }
        if study.spec.gust.is_some() {
            let case = study.resolve()?;
            let settings = case.gust_settings()?;
            let ev = crate::pipeline::evaluate(&case, settings, &case.initial.to_vec())?;
            for (o, rms) in settings.outputs.iter().zip(&ev.rms_m) {
                let (rms, unit) = study.spec.length_unit.display(*rms, o.quantity.unit(), 1);
                out.push(metric(&format!("RMS {}", o.name), unit, rms));
            }
        }
        if optimize_case {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create {}", dir.display()))?;
            let o = optimize(study, dir, false, true)?;
            out.push(metric("optimum mass", "kg", o.final_.mass_kg));
            out.push(metric(
                &format!("optimum RMS {}", o.output),
                &o.unit,
                o.final_.rms_display,
            ));
            out.push(metric("iterations", "-", o.iterations as f64));
            out.push(metric(
                "converged",
                "-",
                if o.converged { 1.0 } else { 0.0 },
            ));
            message = Some(o.message);
        }
        Ok(())
    };
    let error = stages().err().map(|e| format!("{e:#}"));
    (out, message, error)
}

/// `gustkit sweep`: every case of the study's sweep in parallel (rayon), each case's result
/// written as it finishes so that `--resume` skips it; then the table, CSV and figure.
pub fn sweep(study: &Study, reports: &Path, resume: bool) -> Result<crate::runner::Outcome> {
    use crate::report::sweep::{CaseResult, SweepResults};
    use rayon::prelude::*;
    let cases = study.sweep_cases()?;
    let spec = study.spec.sweep.as_ref().expect("checked by sweep_cases");
    // cases run in parallel, one per thread: their memory adds up
    let at_once = rayon::current_num_threads().min(cases.len());
    for case in &cases {
        case.study.check_memory(at_once).map_err(|e| {
            anyhow::anyhow!(
                "{}: sweep case {}: {}: {}",
                study.file.display(),
                case.index,
                e.path,
                e.reason
            )
        })?;
    }
    let dir = study.report_dir(reports).join("sweep");
    std::fs::create_dir_all(dir.join("cases"))
        .with_context(|| format!("cannot create the sweep folder {}", dir.display()))?;
    println!(
        "{}: {} cases over {}{}",
        study.spec.name,
        cases.len(),
        spec.parameters
            .iter()
            .map(|p| p.path.as_str())
            .collect::<Vec<_>>()
            .join(", "),
        match spec.fidelities.len() {
            0 => String::new(),
            n => format!(", with each of {n} fidelities"),
        }
    );
    let t0 = Instant::now();
    let bar = indicatif::ProgressBar::new(cases.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} sweep [{elapsed_precise}] {bar:30} {pos}/{len} cases  {msg}",
        )
        .expect("valid template"),
    );
    let results: Vec<Result<CaseResult>> = cases
        .par_iter()
        .map(|case| {
            let hash = spec_hash(&case.study.spec)?;
            let path = dir.join(format!("cases/case_{:04}.json", case.index));
            if resume {
                if let Ok(text) = std::fs::read_to_string(&path) {
                    if let Ok(r) = serde_json::from_str::<CaseResult>(&text) {
                        if r.study_hash == hash {
                            bar.inc(1);
                            return Ok(r);
                        }
                    }
                }
            }
            let t = Instant::now();
            let case_dir = dir.join(format!("cases/case_{:04}", case.index));
            let (metrics, message, error) = sweep_metrics(case, &case_dir, spec.optimize);
            let r = CaseResult {
                index: case.index,
                values: case.values.clone(),
                fidelity: case.fidelity.clone(),
                study_hash: hash,
                metrics,
                error,
                message,
                wall_time_s: t.elapsed().as_secs_f64(),
            };
            write_atomic(&path, serde_json::to_string_pretty(&r)?.as_bytes())?;
            bar.inc(1);
            bar.set_message(format!("case {} done", case.index));
            Ok(r)
        })
        .collect();
    bar.finish_and_clear();
    let cases = results.into_iter().collect::<Result<Vec<_>>>()?;
    let r = SweepResults {
        study: study.spec.name.clone(),
        parameters: spec.parameters.iter().map(|p| p.path.clone()).collect(),
        combine: spec.combine,
        optimize: spec.optimize,
        cases,
        wall_time_s: t0.elapsed().as_secs_f64(),
    };
    crate::report::sweep::render(&dir, &r)?;
    print!("{}", crate::report::sweep::summary(&r));
    println!("sweep written to {}", dir.display());
    let short = r
        .cases
        .iter()
        .filter(|c| {
            c.error.is_some()
                || c.metrics
                    .iter()
                    .any(|m| m.name == "converged" && m.value == 0.0)
        })
        .count();
    Ok(if short == 0 {
        crate::runner::Outcome::Done
    } else {
        crate::runner::Outcome::GoalNotReached(format!(
            "{short} of {} sweep cases failed or did not converge",
            r.cases.len()
        ))
    })
}
