//! The gust-constrained mass minimization of a wing study: the SQP run with its progress
//! observer, the atomic checkpoint of every iteration, `--resume`, and the results it reports.

mod cross;
mod design;
mod flutter_check;
mod managed;
mod progress;
mod resume;

use cross::*;
pub(crate) use design::*;
pub(crate) use flutter_check::*;
use progress::*;
pub use resume::*;

use super::gust::psd_series;
use crate::flutter::margin::{ks_rho, DAMPING_SCALE, PK_STEPS};
use crate::optim::{Checkpointing, Control, Executor};
use crate::report::results::{
    element_polygons, CrossDesign, CrossEvaluation, DesignSnapshot, FidelityEvaluation,
    FlutterCheck, FlutterPoint, HistoryRow, OptimizationResults, Stats, Timing,
};
use crate::report::write_atomic;
use crate::study::Study;
use anyhow::{Context, Result};
use std::path::Path;
use std::time::Instant;

/// A BFGS matrix of the scaled variables, row by row (as checkpoints keep it).
pub type Hessian = Vec<Vec<f64>>;

/// One pass of an optimization: the first solves the study's problem; each later one (a
/// resolution correction) starts from the previous pass's optimum and BFGS matrix with the RMS
/// limit scaled.
#[derive(Clone, Debug)]
pub struct Pass {
    /// 1 for the study's own problem, then 2, 3, ….
    pub number: usize,
    /// The constrained limit is this factor × the study's limit.
    pub rms_factor: f64,
    /// The discrete gust peak limit likewise (1 without one).
    pub peak_factor: f64,
    /// Where the pass starts and its initial BFGS matrix (scaled variables), when not the
    /// study's.
    pub start: Option<(Vec<f64>, Option<Hessian>)>,
}

impl Pass {
    /// The study's own problem.
    pub fn first() -> Self {
        Self {
            number: 1,
            rms_factor: 1.0,
            peak_factor: 1.0,
            start: None,
        }
    }
}

/// A resumed LFD run starts its GMRES from the solutions kept with its checkpoint (read after
/// the initial design's evaluation, which would otherwise be the newest guess), with a line.
fn resume_warm_start(dir: &Path, quiet: bool) {
    if crate::aero::lfd::load_warm_start(dir) && !quiet {
        println!(
            "GMRES warm start: the last designs' solutions read from {}",
            dir.join(crate::aero::lfd::WARM_START_FILE).display()
        );
    }
}

/// The gust-constrained mass minimization of a study (the `optimization` section).
pub fn optimize(
    study: &Study,
    dir: &Path,
    resume: bool,
    quiet: bool,
) -> Result<OptimizationResults> {
    optimize_pass(study, dir, resume, quiet, &Pass::first())
}

/// One pass of the gust-constrained mass minimization of a study.
pub fn optimize_pass(
    study: &Study,
    dir: &Path,
    resume: bool,
    quiet: bool,
    pass: &Pass,
) -> Result<OptimizationResults> {
    use crate::problem::DesignProblem;
    let o = optimization_section(study)?;
    let (lower, upper) = study.design_bounds()?;
    let case = study.resolve()?;
    let settings = case.gust_settings()?.clone();
    let x0 = case.initial.to_vec();
    // a warm start begins at another run's final design (a correction pass at the previous
    // pass's); mass and area stay relative to x0
    let (x_start, hessian) = match &pass.start {
        Some((x, h)) => (Some(x.clone()), h.clone()),
        None => (study.warm_start_design()?, study.warm_start_hessian()?),
    };
    let t_ev0 = Instant::now();
    let ev0 = crate::pipeline::evaluate(&case, &settings, &x0).context("initial design")?;
    let t_ev0 = t_ev0.elapsed().as_secs_f64();
    let mut spec = design_spec(study, &settings, &ev0, lower, upper)?;
    spec.rms_limit *= pass.rms_factor;
    let (fixed_basis, floor) = design_basis(study)?;
    let fixed_basis = fixed_basis.resolve()?;
    spec.mode_floor = floor;
    spec.peak = peak_limit(study, &ev0)?;
    if let Some(pl) = spec.peak.as_mut() {
        pl.constraint.limit *= pass.peak_factor;
    }
    if !quiet {
        print_limits(study, &spec, floor);
    }
    let (output, rms_limit) = (spec.output, spec.rms_limit);
    // the report shows a displacement RMS in the study's own length unit (the unit rule)
    let (unit_scale, unit) =
        study
            .spec
            .length_unit
            .display(1.0, settings.outputs[output].quantity.unit(), 1);
    let params = crate::optim::SqpParams {
        max_iterations: o.max_iterations,
        tolerance: o.tolerance,
        nonmonotone_memory: o.nonmonotone_memory,
        ..Default::default()
    };
    let low_study = study.low_fidelity_study()?;
    let (problem_id, checkpoint) = match low_study {
        // the managed run keeps its own checkpoint
        Some(_) => (String::new(), None),
        None => open_checkpoint(study, dir, pass.number, resume, quiet)?,
    };
    let checkpoint_path = checkpoint_file(dir, pass.number);
    let mut observer = RunObserver::new(
        ev0.mass_kg,
        (unit_scale, unit, rms_limit),
        spec.flutter.map(|m| m.damping_max),
        spec.peak.is_some(),
        quiet,
        o.max_iterations,
    );
    let mut store = FileCheckpoint {
        path: checkpoint_path,
    };
    if checkpoint.is_some() {
        resume_warm_start(dir, quiet);
    }
    let mut problem = DesignProblem::new(&fixed_basis, settings.clone(), spec.clone());
    let info = match &low_study {
        Some(low_study) => {
            observer.bar.finish_and_clear();
            managed::run_managed(
                study,
                low_study,
                dir,
                (pass.number, resume, quiet),
                &mut problem,
                x_start.as_deref().unwrap_or(&x0),
                params,
                (ev0.mass_kg, (unit_scale, unit, rms_limit)),
            )?
        }
        None => {
            let info = Executor::new(params, &problem_id)
                .resume(checkpoint)
                .initial_hessian(hessian)
                .observe(&mut observer)
                .checkpoint(&mut store)
                .run(&mut problem, x_start.as_deref().unwrap_or(&x0));
            observer.bar.finish_and_clear();
            info.map_err(|e| anyhow::anyhow!("optimization: {e}"))?
        }
    };
    // an ended optimization resumes no more: its warm-start store is not part of the report
    crate::aero::lfd::remove_warm_start_file(dir);
    // over every session of a resumed run
    let wall_time_s = info.elapsed_s;
    let timing = Timing {
        function: (!problem.function_times.is_empty())
            .then(|| Stats::of(std::mem::take(&mut problem.function_times))),
        gradient: (!problem.gradient_times.is_empty())
            .then(|| Stats::of(std::mem::take(&mut problem.gradient_times))),
        threads: rayon::current_num_threads(),
        function_gmres_per_rhs: std::mem::take(&mut problem.function_gmres),
        gradient_gmres_per_rhs: std::mem::take(&mut problem.gradient_gmres),
    };
    let t_ev = Instant::now();
    let ev = crate::pipeline::evaluate(&fixed_basis, &settings, &info.x).context("final design")?;
    // the final design's flow (an LFD's steady field and C_p) in the run folder
    super::write_artifacts(dir, &ev.aero, study)?;
    let t_ev = t_ev.elapsed().as_secs_f64();
    let history = history_rows(
        &info,
        &ev0,
        &spec,
        (rms_limit, unit_scale, pass.number),
        std::mem::take(&mut problem.damping_peaks),
        |x| crate::pipeline::evaluate(&fixed_basis, &settings, x),
    )?;
    // the flutter check reports; it does not fail a finished optimization
    let flutter = match flutter_check(&ev0, &ev) {
        Ok(f) => Some(f),
        Err(e) => {
            eprintln!("warning: the flutter check of the initial and final designs failed: {e:#}");
            None
        }
    };
    if !quiet {
        println!(
            "{}",
            outcome_words(&info, (&ev0, &ev), output, (unit_scale, unit))
        );
    }
    let cross_evaluation = match study.compare_study()? {
        Some(other) => {
            // a correction pass analyses only its final design: the run keeps the first pass's
            // initial and starting designs, and this pass starts at the previous optimum
            let mut designs = Vec::new();
            if pass.start.is_none() {
                designs.push(("initial", x0.clone(), Some((&ev0, t_ev0))));
                if let Some(x) = &x_start {
                    designs.push(("start", x.clone(), None));
                }
            }
            designs.push(("final", info.x.clone(), Some((&ev, t_ev))));
            let c = cross_evaluate(study, &other, &settings, &designs, output, unit_scale, unit)?;
            if !quiet {
                print_cross_evaluation(&c, unit);
            }
            Some(c)
        }
        None => None,
    };
    let peak_limit = match &spec.peak {
        Some(pl) => Some(peak_limit_result(study, pl, &ev0, &ev, quiet)?),
        None => None,
    };
    let design = &case.initial;
    Ok(OptimizationResults {
        converged: info.converged,
        message: info.message.clone(),
        iterations: info.iterations,
        evaluations: info.evaluations,
        wall_time_s,
        output: o.output.clone(),
        rms_limit: rms_limit * unit_scale,
        unit: unit.to_string(),
        fix_area: o.fix_area,
        flutter_margin: spec.flutter.map(|m| (m.speed_factor, m.damping_max)),
        ks_rho: ks_rho(ev0.modes.len() * PK_STEPS),
        damping_scale: DAMPING_SCALE,
        reference: o.reference.clone(),
        design_variable_names: (0..x0.len()).map(|i| design.name(i)).collect(),
        lower: spec.lower,
        upper: spec.upper,
        initial: snapshot(study, &ev0, output, unit_scale),
        final_: snapshot(study, &ev, output, unit_scale),
        history,
        flutter_check: flutter,
        warm_start: o.warm_start.as_ref().map(|w| w.from.display().to_string()),
        timing: Some(timing),
        cross_evaluation,
        corrections: Vec::new(),
        peak_limit,
    })
}
