//! The runner of wing studies: modal analysis, gust response with its σ_w calibration, p-k
//! flutter, the gust-constrained optimization and the gradient check, each in its own module;
//! [`run`] does every analysis a study defines and writes its report.

mod correction;
mod discrete;
mod fidelities;
pub mod flutter;
pub mod gradient;
pub mod gust;
pub mod mesh_study;
pub mod optimize;
pub mod resolution;

use crate::kind::StudyKind;
use crate::report::figures::ModeShapes;
use crate::report::results::{FlutterSummary, ModeRow, RunResults};
use crate::report::run::frequency_table;
use crate::report::{self, save_figure, write_atomic};
use crate::structure::model::Field;
use crate::structure::{Modes, PlateModel, Sampler};
use crate::study::Study;
use anyhow::{Context, Result};
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// The modal analysis of a study as written to JSON.
#[derive(Serialize)]
pub struct ModalSummary {
    pub study: String,
    pub mass_kg: f64,
    pub area_m2: f64,
    pub frequencies_hz: Vec<f64>,
    pub modes: Vec<ModeRow>,
}

fn field_name(f: Field) -> &'static str {
    match f {
        Field::Bending => "bending",
        Field::Membrane => "membrane",
    }
}

/// Builds the model of a study and solves its modes.
pub fn analyze(study: &Study) -> Result<(PlateModel, Modes, ModalSummary)> {
    let model = study.build_model()?;
    let modes = study
        .solve_modes(&model)
        .with_context(|| format!("{}: modal analysis", study.file.display()))?;
    let tip = Sampler::new(&model, &[[1.0, 1.0]]);
    let names = crate::report::results::mode_names(&model, &modes);
    let summary = ModalSummary {
        study: study.spec.name.clone(),
        mass_kg: model.mass(),
        area_m2: model.planform().area(),
        frequencies_hz: modes.freq_hz(),
        modes: modes
            .modes
            .iter()
            .enumerate()
            .map(|(i, m)| ModeRow {
                mode: i + 1,
                frequency_hz: m.freq_hz(),
                field: field_name(m.field).to_string(),
                shape: names[i].clone(),
                tip_te_w: tip.sample(&model, &m.shape)[0][0],
            })
            .collect(),
    };
    Ok((model, modes, summary))
}

/// The mode-shape figure data of a model.
fn mode_shapes(study: &Study, model: &PlateModel, modes: &Modes) -> ModeShapes {
    ModeShapes::new(
        model,
        modes,
        study.spec.length_unit.name(),
        study.spec.length_unit.to_m(),
    )
}

/// Writes the modal figures and the VTK file into `dir`.
fn write_modal_files(study: &Study, model: &PlateModel, modes: &Modes, dir: &Path) -> Result<()> {
    save_figure(dir, "modes", &mode_shapes(study, model, modes))?;
    let vtk = report::vtk::plate_modes(model, modes, &format!("gustkit {} modes", study.spec.name));
    write_atomic(&dir.join("modes.vtk"), vtk.as_bytes())
}

/// Writes what the aerodynamic model reports about its own state (the LFD's steady flow field
/// and C_p sections) into the run folder `dir`; a model writes no file itself.
pub(crate) fn write_artifacts(
    dir: &Path,
    aero: &crate::aero::AeroModel,
    study: &Study,
) -> Result<()> {
    for (name, text) in aero
        .fidelity
        .artifacts(&format!("gustkit {}", study.spec.name))
    {
        write_atomic(&dir.join(name), text.as_bytes())?;
    }
    Ok(())
}

/// `gustkit modes`.
pub fn modes(study: &Study, json: bool, reports: &Path) -> Result<()> {
    let study = study.clone();
    let (model, modes, summary) = analyze(&study)?;
    let dir = study.report_dir(reports);
    write_modal_files(&study, &model, &modes, &dir)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
        eprintln!("figures and VTK written to {}", dir.display());
    } else {
        println!(
            "{}: mass {:.4} kg, planform area {:.4} m²",
            summary.study, summary.mass_kg, summary.area_m2
        );
        print!("{}", frequency_table(&summary.modes));
        println!("figures and VTK written to {}", dir.display());
    }
    Ok(())
}

/// `gustkit run`: every analysis the study defines, with its report.
pub fn run(study: &Study, reports: &Path, resume: bool) -> Result<crate::runner::Outcome> {
    let study = study.clone();
    let t0 = Instant::now();
    let (model, modes, summary) = analyze(&study)?;
    let final_dir = study.report_dir(reports);
    // fail early, before any long computation, when the run folder cannot be written
    let folder = crate::report::folder::RunFolder::begin(&final_dir, resume)?;
    let dir = folder.path().to_path_buf();
    // fidelities keep reusable state (the LFD's steady solution) in the run folder
    let mut study = study;
    study.cache_dir = Some(dir.clone());
    let vtk = report::vtk::plate_modes(
        &model,
        &modes,
        &format!("gustkit {} modes", study.spec.name),
    );
    write_atomic(&dir.join("modes.vtk"), vtk.as_bytes())?;
    println!("{}", frequency_table(&summary.modes));
    let lattice_rule = lattice_rule(&study, &model, &modes)?;
    if let Some(l) = &lattice_rule {
        println!("{}", report::run::lattice_words(l, study.spec.length_unit));
    }
    let (gust, gust_evaluation) = match study.spec.gust {
        Some(_) => {
            let (g, ev) = gust::gust_results(&study)?;
            (Some(g), Some(ev))
        }
        None => (None, None),
    };
    // the flutter analysis below writes the same design's artifacts from its own model
    if let (Some(ev), None) = (&gust_evaluation, &study.spec.flutter) {
        write_artifacts(&dir, &ev.aero, &study)?;
    }
    let discrete_gust = match &gust_evaluation {
        Some(ev) => discrete::discrete_results(&study, ev, &dir)?,
        None => None,
    };
    let flutter = match study.spec.flutter {
        Some(_) => {
            let (doc, r, velocities) = flutter::flutter_analysis(&study, &dir, false)?;
            flutter::print_flutter(&study, &r, &velocities, &doc);
            Some(FlutterSummary {
                mach: doc["mach"].as_f64().unwrap_or(f64::NAN),
                density_kg_m3: doc["density_kg_m3"].as_f64().unwrap_or(f64::NAN),
                flight_speed_m_s: doc["flight_speed_m_s"].as_f64(),
                result: r,
            })
        }
        None => None,
    };
    if let Some(k) = study.amplitude_fields_k() {
        let title = format!("gustkit {}", study.spec.name);
        let fields = match &gust_evaluation {
            Some(ev) => ev.aero.fidelity.amplitude_fields(k, &title),
            None => {
                let case = study.resolve()?;
                crate::pipeline::aeroelastic(&case, &case.initial.to_vec())?
                    .aero
                    .fidelity
                    .amplitude_fields(k, &title)
            }
        };
        for (stem, text) in &fields {
            write_atomic(&dir.join(format!("{stem}.vtk")), text.as_bytes())?;
        }
        println!(
            "LFD amplitude fields at k = {k}: {} VTK files (every mode and the gust)",
            fields.len()
        );
    }
    let comparison = match study.compare_study()? {
        Some(other) => {
            let c = fidelities::compare_fidelities(&study, &other, gust_evaluation.as_ref())?;
            print!(
                "{}",
                report::run::comparison_text(
                    &c,
                    gust.as_ref(),
                    flutter.as_ref(),
                    study.spec.length_unit,
                )
            );
            Some(c)
        }
        None => None,
    };
    drop(gust_evaluation);
    let optimization = match study.spec.optimization {
        Some(_) => Some(optimize::optimize(&study, &dir, resume, false)?),
        None => None,
    };
    let first_check = resolution_check(&study, optimization.as_ref())?;
    if let Some(c) = &first_check {
        println!("{}", report::run::resolution_words(c));
    }
    // an optimum whose refined RMS exceeds the limit is optimized again with the limit corrected
    let (optimization, resolution_check) = match (optimization, first_check) {
        (Some(o), Some(c)) => {
            let (o, c) = correction::correct(&study, &dir, resume, o, c, |o| {
                resolution_check(&study, Some(o))?
                    .ok_or_else(|| anyhow::anyhow!("the resolution check of a corrected design"))
            })?;
            (Some(o), Some(c))
        }
        other => other,
    };
    let results = RunResults {
        kind: StudyKind::Wing,
        study: study.spec.name.clone(),
        description: study.spec.description.clone(),
        length_unit: study.spec.length_unit,
        mass_kg: summary.mass_kg,
        area_m2: summary.area_m2,
        n_design_variables: model.design.len(),
        frequencies_hz: summary.frequencies_hz,
        modes: summary.modes,
        mode_shapes: mode_shapes(&study, &model, &modes),
        fidelity: study
            .spec
            .aero
            .as_ref()
            .map(|a| a.fidelity.builder().name().to_string()),
        aero_model: study.aero_model_words(),
        gust,
        discrete_gust,
        flutter,
        optimization,
        comparison,
        resolution_check,
        lattice_rule,
        run_time_s: t0.elapsed().as_secs_f64(),
    };
    report::run::render(&dir, &results)?;
    // the C_p sections of the (latest) steady LFD state, when the fidelity wrote them
    let cp = dir.join(format!("{}.csv", crate::aero::lfd::CP_SECTIONS_STEM));
    if let Ok(text) = std::fs::read_to_string(&cp) {
        let figure = report::figures::cp_sections(&text)
            .with_context(|| format!("reading {}", cp.display()))?;
        save_figure(&dir, crate::aero::lfd::CP_SECTIONS_STEM, &figure)?;
    }
    folder.commit()?;
    println!("report written to {}", final_dir.display());
    Ok(match (&results.optimization, &results.resolution_check) {
        (Some(o), _) if !o.converged => crate::runner::Outcome::GoalNotReached(format!(
            "the optimization did not converge: {} after {} iterations",
            o.message, o.iterations
        )),
        (_, Some(c)) if !c.passed => crate::runner::Outcome::GoalNotReached(format!(
            "the design fails the resolution check: with {} it {}{}",
            c.refined_model.as_deref().unwrap_or(""),
            c.refined_flutter.as_deref().unwrap_or(""),
            match c.refined_peak {
                Some(p) if p > 1.0 + c.rms_tolerance => {
                    format!("; its discrete gust peak is {p:.4} × its limit")
                }
                _ => String::new(),
            }
        )),
        _ => crate::runner::Outcome::Done,
    })
}

/// The DLM lattice of the study's initial design against 0.08 V/f (MSC's rule), f the mode
/// cutoff (or, with a fixed count, the highest retained mode) and V the flight speed; none for
/// another fidelity or without a flight condition.
fn lattice_rule(
    study: &Study,
    model: &PlateModel,
    modes: &Modes,
) -> Result<Option<crate::aero::dlm::LatticeRule>> {
    let Some(crate::aero::FidelitySpec::Dlm(spec)) = study.spec.aero.as_ref().map(|a| &a.fidelity)
    else {
        return Ok(None);
    };
    if study.spec.flight.is_none() {
        return Ok(None);
    }
    let velocity = study.flight_condition()?.velocity;
    let (f, what) = match study.mode_rule()? {
        crate::study::ModeRule::Cutoff { omega_cut, .. } => {
            (omega_cut / (2.0 * std::f64::consts::PI), "the mode cutoff")
        }
        crate::study::ModeRule::Count(_) => (
            modes.freq_hz().last().copied().unwrap_or(0.0),
            "the highest retained mode",
        ),
    };
    if !(f > 0.0) {
        return Ok(None);
    }
    Ok(Some(crate::aero::dlm::lattice_rule(
        spec,
        model.planform(),
        velocity,
        f,
        what,
    )))
}

/// The resolution check of a run: the optimization's final design against its margin speed and
/// RMS limit, or (without an optimization) the initial design against the flight speed. None for
/// a study with neither a gust nor a flutter analysis.
fn resolution_check(
    study: &Study,
    optimization: Option<&crate::report::results::OptimizationResults>,
) -> Result<Option<crate::report::results::ResolutionCheck>> {
    let s = &study.spec;
    if s.aero.is_none() || (s.gust.is_none() && s.flutter.is_none() && s.optimization.is_none()) {
        return Ok(None);
    }
    let settings = match s.gust {
        Some(_) => Some(study.gust_settings()?),
        None => None,
    };
    let flight = study.flight_condition()?.velocity;
    let (x, req) = match (optimization, &s.optimization) {
        (Some(o), Some(spec)) => {
            let limit = settings
                .as_ref()
                .and_then(|g| optimize::rms_constraint(study, g));
            let margin = spec
                .flutter_margin
                .as_ref()
                .map_or(flight, |m| m.speed_factor * flight);
            (
                o.final_.design_variables.clone(),
                resolution::Requirement {
                    stable_to_m_s: margin,
                    rms: limit,
                },
            )
        }
        _ => (
            study.initial_design()?.to_vec(),
            resolution::Requirement {
                stable_to_m_s: flight,
                rms: None,
            },
        ),
    };
    // an optimization's design is checked with the basis its constraints saw
    let basis = match optimization {
        Some(_) => optimize::design_basis(study)?.0,
        None => study.clone(),
    };
    Ok(Some(resolution::check(&basis, &x, settings.as_ref(), req)?))
}
