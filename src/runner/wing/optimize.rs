//! The gust-constrained mass minimization of a wing study: the SQP run with its progress
//! observer, the atomic checkpoint of every iteration, `--resume`, and the results it reports.

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

/// Shows each SQP iteration on a progress bar (and as a line on stdout).
struct RunObserver {
    mass0: f64,
    rms_scale: f64,
    rms_unit: &'static str,
    rms_limit: f64,
    /// Damping limit of the flutter-margin constraint, when there is one.
    damping_max: Option<f64>,
    /// Whether the last inequality is a discrete gust peak limit.
    peak: bool,
    quiet: bool,
    bar: indicatif::ProgressBar,
    /// When the previous iteration ended (the run's start before the first).
    last: Instant,
    /// The iteration limit, for the bound on the remaining time.
    max_iterations: usize,
}

/// A wall time for a progress line: seconds below two minutes, then minutes, then hours.
fn duration(s: f64) -> String {
    if s < 120.0 {
        format!("{s:.1} s")
    } else if s < 7200.0 {
        format!("{:.1} min", s / 60.0)
    } else {
        format!("{:.1} h", s / 3600.0)
    }
}

/// Keeps every iteration's checkpoint in `checkpoint.json` of the run folder, written
/// atomically (a kill never leaves half a checkpoint).
struct FileCheckpoint {
    path: std::path::PathBuf,
}

impl Checkpointing for FileCheckpoint {
    fn save(&mut self, cp: &crate::optim::Checkpoint) -> Result<(), String> {
        serde_json::to_vec(cp)
            .map_err(anyhow::Error::from)
            .and_then(|b| write_atomic(&self.path, &b))
            .map_err(|e| format!("{e:#}"))
    }
}

impl crate::optim::Observer for RunObserver {
    fn iteration(
        &mut self,
        it: &crate::optim::Iterate,
        cp: &crate::optim::Checkpoint,
    ) -> Result<Control, String> {
        let rms = (it.values.ineq[0] + 1.0) * self.rms_limit;
        let flutter = match (it.values.ineq.get(1), self.damping_max) {
            (Some(c), Some(g_max)) => format!(", g_KS {:+.4}", g_max + c * DAMPING_SCALE),
            _ => String::new(),
        };
        let flutter = match (self.peak, it.values.ineq.last()) {
            (true, Some(c)) => format!("{flutter}, peak KS {:.4} × limit", c + 1.0),
            _ => flutter,
        };
        let line = format!(
            "iteration {:>3}: mass {:.5} kg ({:+.2} %), RMS {:.4} {} (limit {:.4}){flutter}, violation {:.2e}, KKT {:.2e}, step {:.3}{}",
            it.iteration,
            it.values.f * self.mass0,
            100.0 * (it.values.f - 1.0),
            rms * self.rms_scale,
            self.rms_unit,
            self.rms_limit * self.rms_scale,
            it.violation,
            it.kkt,
            it.alpha,
            if it.failed_trials > 0 {
                // the reason whole (never cut mid-word), its lines joined: one progress line
                let reason = it
                    .trial_failure
                    .as_deref()
                    .unwrap_or("")
                    .lines()
                    .collect::<Vec<_>>()
                    .join("; ");
                format!(" ({} trial points failed; the last: {reason})", it.failed_trials)
            } else {
                String::new()
            }
        );
        // wall time of this iteration, and the remaining time if every iteration up to the
        // limit took as long (a bound: the run stops earlier when it converges)
        let took = self.last.elapsed().as_secs_f64();
        self.last = Instant::now();
        let left = self.max_iterations.saturating_sub(cp.iteration) as f64 * took;
        let line = format!(
            "{line}; {} this iteration, at most {} to the iteration limit",
            duration(took),
            duration(left)
        );
        if !self.quiet {
            self.bar.suspend(|| println!("{line}"));
        }
        self.bar.set_position(cp.iteration as u64);
        self.bar.set_message(format!(
            "mass {:+.1} %, RMS {:.3} {}, KKT {:.1e}",
            100.0 * (it.values.f - 1.0),
            rms * self.rms_scale,
            self.rms_unit,
            it.kkt
        ));
        Ok(Control::Continue)
    }
}

/// FNV-1a hash of a string, to tie a checkpoint to the study that wrote it.
pub(crate) fn fnv(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The part of a study that defines its optimization problem: everything but what only labels
/// the run (description, reference), decides when it stops (max_iterations, tolerance) or belongs
/// to other analyses (the flutter sweep, the sweep section). A checkpoint resumes only when this
/// is unchanged.
fn defining_spec(study: &Study) -> Result<serde_json::Value> {
    let mut v = serde_json::to_value(&study.spec)?;
    if let Some(m) = v.as_object_mut() {
        for key in ["description", "flutter", "sweep"] {
            m.remove(key);
        }
        // the second fidelity only analyses the designs the optimization reaches
        if let Some(a) = m.get_mut("aero").and_then(|a| a.as_object_mut()) {
            a.remove("compare_with");
        }
        if let Some(o) = m.get_mut("optimization").and_then(|o| o.as_object_mut()) {
            for key in [
                "max_iterations",
                "tolerance",
                "reference",
                "resolution_corrections",
            ] {
                o.remove(key);
            }
        }
    }
    Ok(v)
}

/// The JSON paths at which `a` and `b` differ (below `at`).
fn json_differences(a: &serde_json::Value, b: &serde_json::Value, at: &str) -> Vec<String> {
    use serde_json::Value;
    let join = |k: &str| {
        if at.is_empty() {
            k.to_string()
        } else {
            format!("{at}.{k}")
        }
    };
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            let mut keys: Vec<&String> = x.keys().chain(y.keys()).collect();
            keys.sort();
            keys.dedup();
            keys.into_iter()
                .flat_map(|k| match (x.get(k), y.get(k)) {
                    (Some(p), Some(q)) => json_differences(p, q, &join(k)),
                    _ => vec![join(k)],
                })
                .collect()
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => x
            .iter()
            .zip(y)
            .enumerate()
            .flat_map(|(i, (p, q))| json_differences(p, q, &format!("{at}[{i}]")))
            .collect(),
        _ if a == b => Vec::new(),
        _ => vec![if at.is_empty() {
            ".".into()
        } else {
            at.to_string()
        }],
    }
}

/// A design as the report shows it: values, planform, thickness map and the PSD of `output`.
fn snapshot(
    study: &Study,
    ev: &crate::pipeline::Evaluation,
    output: usize,
    unit_scale: f64,
) -> DesignSnapshot {
    let to_m = study.spec.length_unit.to_m();
    let mesh = &ev.plate.mesh;
    DesignSnapshot {
        mass_kg: ev.mass_kg,
        area_m2: ev.area_m2,
        rms_display: ev.rms_m[output] * unit_scale,
        rms: ev.rms_m[output],
        frequencies_hz: ev.freq_hz.clone(),
        design_variables: ev.x.clone(),
        elements: element_polygons(&ev.plate, to_m),
        thickness: (0..mesh.elements.len())
            .map(|e| ev.plate.element_thickness(e) / to_m)
            .collect(),
        psd: psd_series(ev, output),
    }
}

/// The design problem of the study's `optimization` section (which the caller has checked):
/// bounds `lower`/`upper`, the constrained output and its limit in SI, the flutter margin, and
/// the initial design's evaluation `ev0` as the reference of mass and area.
pub(crate) fn design_spec(
    study: &Study,
    settings: &crate::gust::GustSettings,
    ev0: &crate::pipeline::Evaluation,
    lower: Vec<f64>,
    upper: Vec<f64>,
) -> crate::problem::DesignSpec {
    let o = study.spec.optimization.as_ref().expect("caller checked");
    let (output, rms_limit) = rms_constraint(study, settings).expect("checked");
    crate::problem::DesignSpec {
        lower,
        upper,
        output,
        rms_limit,
        mass0: ev0.mass_kg,
        area0: ev0.area_m2,
        fix_area: o.fix_area,
        flutter: o
            .flutter_margin
            .as_ref()
            .map(|m| crate::flutter::margin::FlutterMargin {
                speed_factor: m.speed_factor,
                damping_max: m.damping_max,
            }),
        mode_floor: None,
        peak: None,
    }
}

/// The discrete gust peak limit of the study's optimization (none without one): its grid is the
/// one the decay rule chooses at the initial design, with twice the span (or the study's span).
pub(crate) fn peak_limit(
    study: &Study,
    ev0: &crate::pipeline::Evaluation,
) -> Result<Option<crate::problem::PeakLimit>> {
    let Some(constraint) = study.peak_constraint()? else {
        return Ok(None);
    };
    let settings = study
        .discrete_gust_settings()?
        .expect("checked with the constraint");
    let r = crate::problem::peak_response(ev0, &constraint, settings.span).with_context(|| {
        format!(
            "{}: discrete gust peak limit at the initial design",
            study.file.display()
        )
    })?;
    let span = if settings.span.is_some() {
        r.grid.span
    } else {
        2.0 * r.grid.span
    };
    let grid = crate::gust::discrete::TimeGrid::new(span, ev0.problem().table_omega_max())
        .map_err(anyhow::Error::msg)?;
    Ok(Some(crate::problem::PeakLimit { constraint, grid }))
}

/// The constrained gust output of the study's `optimization` section: its index among the
/// settings' outputs and its RMS limit in SI (a displacement limit is in the study's length unit).
/// None without an optimization or when the output is not among `settings`.
pub(crate) fn rms_constraint(
    study: &Study,
    settings: &crate::gust::GustSettings,
) -> Option<(usize, f64)> {
    let o = study.spec.optimization.as_ref()?;
    let output = settings
        .outputs
        .iter()
        .position(|out| out.name == o.output)?;
    let is_disp = matches!(
        settings.outputs[output].quantity,
        crate::gust::Quantity::Displacement { .. }
    );
    let to_m = study.spec.length_unit.to_m();
    Some((output, if is_disp { o.rms_max * to_m } else { o.rms_max }))
}

/// The study as its optimization sees it: with a basis chosen by the cutoff rule, the count of
/// modes below the cutoff at the initial design, kept whole by a floor on the first mode left out
/// ([`crate::problem::ModeFloor`]); otherwise the study itself and no floor. The final design is
/// reported and checked with the same basis.
pub(crate) fn design_basis(study: &Study) -> Result<(Study, Option<crate::problem::ModeFloor>)> {
    let crate::study::ModeRule::Cutoff { omega_cut, .. } = study.mode_rule()? else {
        return Ok((study.clone(), None));
    };
    let plate = study
        .model_at(crate::wing::DesignVector::from_slice(
            &study.initial_design()?.to_vec(),
        ))
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let retained = study.solve_modes(&plate).context("initial design")?.len();
    let mut fixed = study.clone();
    fixed.spec.structure.modes = crate::study::schema::ModesSpec::Count(retained);
    Ok((
        fixed,
        Some(crate::problem::ModeFloor {
            retained,
            omega_cut,
        }),
    ))
}

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

/// The checkpoint file of a pass in the run folder (`checkpoint.json` for the first, which warm
/// starts of later runs read).
pub fn checkpoint_file(dir: &Path, pass: usize) -> std::path::PathBuf {
    match pass {
        1 => dir.join("checkpoint.json"),
        n => dir.join(format!("checkpoint_pass{n}.json")),
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
    let o = study.spec.optimization.as_ref().expect("caller checked");
    let settings = study.gust_settings()?;
    let (lower, upper) = study.design_bounds()?;
    let case = study.resolve()?;
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
    let mut spec = design_spec(study, &settings, &ev0, lower, upper);
    spec.rms_limit *= pass.rms_factor;
    let (fixed_basis, floor) = design_basis(study)?;
    let fixed_basis = fixed_basis.resolve()?;
    spec.mode_floor = floor;
    spec.peak = peak_limit(study, &ev0)?;
    if let Some(pl) = spec.peak.as_mut() {
        pl.constraint.limit *= pass.peak_factor;
    }
    if let (Some(pl), false) = (&spec.peak, quiet) {
        let (limit, limit_unit) =
            study
                .spec
                .length_unit
                .display(pl.constraint.limit, &pl.constraint.unit, 1);
        println!(
            "discrete gust peak limit: |{}| ≤ {} {} over {} gusts (KS, ρ = ln(n)/{}), on a fixed grid of {:.3} s, {} samples",
            pl.constraint.name,
            crate::report::style::tick(&limit),
            limit_unit,
            pl.constraint.gusts.len(),
            crate::gust::discrete::PEAK_KS_GAP,
            pl.grid.span,
            pl.grid.time.len()
        );
    }
    if let (Some(f), false) = (floor, quiet) {
        println!(
            "modal basis: the {} modes below {:.1} Hz at the initial design; the first mode left out must stay above it",
            f.retained,
            f.omega_cut / (2.0 * std::f64::consts::PI)
        );
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
        ..Default::default()
    };
    let defining = defining_spec(study)?;
    let mut problem_id = format!(
        "{}:{:016x}",
        study.spec.name,
        fnv(&serde_json::to_string(&defining)?)
    );
    if pass.number > 1 {
        problem_id += &format!(":pass{}", pass.number);
    }
    let study_copy = dir.join("checkpoint_study.json");
    let checkpoint_path = checkpoint_file(dir, pass.number);
    // a correction pass that had not begun when the run stopped begins now
    let resume = resume && (pass.number == 1 || checkpoint_path.exists());
    let checkpoint = if resume {
        let path = checkpoint_path.clone();
        let text = std::fs::read_to_string(&path).with_context(|| {
            format!(
                "--resume: cannot read {} (no interrupted run to continue: run without --resume)",
                path.display()
            )
        })?;
        let cp: crate::optim::Checkpoint = serde_json::from_str(&text).with_context(|| {
            format!(
                "--resume: {} is not a gustkit checkpoint (corrupted?)",
                path.display()
            )
        })?;
        if cp.problem_id != problem_id {
            let changed = std::fs::read_to_string(&study_copy)
                .ok()
                .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
                .map(|old| json_differences(&old, &defining, ""))
                .filter(|d| !d.is_empty());
            let what = match changed {
                Some(d) => format!(
                    "the study changed since the checkpoint was written: {}",
                    d.iter().take(6).cloned().collect::<Vec<_>>().join(", ")
                ),
                None => "the checkpoint belongs to another problem".to_string(),
            };
            anyhow::bail!(
                "{}: --resume: {what}; only the description, the reference, max_iterations, tolerance, aero.compare_with, the flutter sweep and the sweep section may change between a run and its resumption. Run without --resume to start over",
                study.file.display()
            );
        }
        if !quiet {
            println!("resuming from iteration {}", cp.iteration);
        }
        Some(cp)
    } else {
        if pass.number == 1 {
            write_atomic(
                &study_copy,
                serde_json::to_string_pretty(&defining)?.as_bytes(),
            )?;
        }
        None
    };
    let bar = if quiet {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(o.max_iterations as u64)
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} SQP [{elapsed_precise}] {bar:30} {pos}/{len} iterations  {msg}",
        )
        .expect("valid template"),
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    let mut observer = RunObserver {
        mass0: ev0.mass_kg,
        rms_scale: unit_scale,
        rms_unit: unit,
        rms_limit,
        damping_max: spec.flutter.map(|m| m.damping_max),
        peak: spec.peak.is_some(),
        quiet,
        bar,
        last: Instant::now(),
        max_iterations: o.max_iterations,
    };
    let mut store = FileCheckpoint {
        path: checkpoint_path,
    };
    let mut problem = DesignProblem::new(&fixed_basis, settings.clone(), spec.clone());
    let info = Executor::new(params, &problem_id)
        .resume(checkpoint)
        .initial_hessian(hessian)
        .observe(&mut observer)
        .checkpoint(&mut store)
        .run(&mut problem, x_start.as_deref().unwrap_or(&x0));
    observer.bar.finish_and_clear();
    let info = info.map_err(|e| anyhow::anyhow!("optimization: {e}"))?;
    // over every session of a resumed run
    let wall_time_s = info.elapsed_s;
    let timing = Timing {
        function: (!problem.function_times.is_empty())
            .then(|| Stats::of(std::mem::take(&mut problem.function_times))),
        gradient: (!problem.gradient_times.is_empty())
            .then(|| Stats::of(std::mem::take(&mut problem.gradient_times))),
        threads: rayon::current_num_threads(),
    };
    let t_ev = Instant::now();
    let ev = crate::pipeline::evaluate(&fixed_basis, &settings, &info.x).context("final design")?;
    let t_ev = t_ev.elapsed().as_secs_f64();
    // the largest p-k damping of each iterate (re-evaluated for iterates of an earlier session)
    let mut peaks = std::mem::take(&mut problem.damping_peaks);
    let mut peak_at = |x: &[f64]| -> Result<Option<f64>> {
        let Some(m) = &spec.flutter else {
            return Ok(None);
        };
        if let Some((_, g)) = peaks.iter().rev().find(|(px, _)| px.as_slice() == x) {
            return Ok(Some(*g));
        }
        let e = crate::pipeline::evaluate(&fixed_basis, &settings, x)?;
        let g = e.flutter_damping(m)?.2.peak();
        peaks.push((x.to_vec(), g));
        Ok(Some(g))
    };
    let history = info
        .history
        .iter()
        .map(|it| -> Result<HistoryRow> {
            Ok(HistoryRow {
                iteration: it.iteration,
                mass_kg: it.values.f * ev0.mass_kg,
                rms_display: (it.values.ineq[0] + 1.0) * rms_limit * unit_scale,
                area_m2: it
                    .values
                    .eq
                    .first()
                    .map_or(ev0.area_m2, |h| (h + 1.0) * ev0.area_m2),
                flutter_damping: match (it.values.ineq.get(1), &spec.flutter) {
                    (Some(c), Some(m)) => Some(m.damping_max + c * DAMPING_SCALE),
                    _ => None,
                },
                flutter_damping_peak: peak_at(&it.x)?,
                violation: it.violation,
                kkt: it.kkt,
                evaluations: it.evaluations,
                pass: pass.number,
            })
        })
        .collect::<Result<Vec<_>>>()?;
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
        "{} after {} iterations ({} evaluations, {:.1} s): mass {:.4} → {:.4} kg ({:+.1} %), RMS {:.4} → {:.4} {unit}",
        info.message,
        info.iterations,
        info.evaluations,
        wall_time_s,
        ev0.mass_kg,
        ev.mass_kg,
        100.0 * (ev.mass_kg / ev0.mass_kg - 1.0),
        ev0.rms_m[output] * unit_scale,
        ev.rms_m[output] * unit_scale
    );
    }
    let cross_evaluation = match study.compare_study()? {
        Some(other) => {
            let mut designs = vec![("initial", x0.clone(), Some((&ev0, t_ev0)))];
            if let Some(x) = &x_start {
                designs.push(("start", x.clone(), None));
            }
            designs.push(("final", info.x.clone(), Some((&ev, t_ev))));
            let c = cross_evaluate(study, &other, &settings, &designs, output, unit_scale, unit)?;
            if !quiet {
                for d in &c.designs {
                    let row: Vec<String> = d
                        .evaluations
                        .iter()
                        .map(|e| match e.rms_display {
                            Some(v) => format!("{} {v:.4} {unit}", e.fidelity),
                            None => format!("{} unstable", e.fidelity),
                        })
                        .collect();
                    println!(
                        "cross-evaluation, {} design: RMS {}",
                        d.design,
                        row.join(", ")
                    );
                }
            }
            Some(c)
        }
        None => None,
    };
    let peak_limit = match &spec.peak {
        Some(pl) => {
            let (_, k0) = pl.evaluate(&ev0).map_err(anyhow::Error::msg)?;
            let (_, k1) = pl.evaluate(&ev).map_err(anyhow::Error::msg)?;
            let (limit, unit) =
                study
                    .spec
                    .length_unit
                    .display(pl.constraint.limit, &pl.constraint.unit, 1);
            if !quiet {
                println!(
                    "discrete gust peak |{}|: {:.4} → {:.4} × the limit {} {unit} (KS {:.4} → {:.4})",
                    pl.constraint.name,
                    k0.peak,
                    k1.peak,
                    crate::report::style::tick(&limit),
                    k0.ks,
                    k1.ks
                );
            }
            Some(crate::report::results::PeakLimitResult {
                output: pl.constraint.name.clone(),
                limit,
                unit: unit.to_string(),
                gusts: pl.constraint.gusts.len(),
                ks_rho: k1.rho,
                initial_ks: k0.ks,
                initial_peak: k0.peak,
                final_ks: k1.ks,
                final_peak: k1.peak,
            })
        }
        None => None,
    };
    let design = study.initial_design()?;
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

/// One design analysed with one fidelity, for the cross-evaluation: the flutter point and GAFs
/// of its aeroelastic model, and its gust response or the reason there is none (the model is
/// unstable at the flight condition).
fn fidelity_evaluation(
    model: (
        &crate::aero::AeroModel,
        &crate::structure::Modes,
        &gustkit_core::GafTable,
    ),
    response: std::result::Result<&crate::pipeline::Evaluation, String>,
    output: usize,
    unit_scale: f64,
    v_max: f64,
) -> Result<FidelityEvaluation> {
    let (aero, modes, table) = model;
    let (rms, psd, unstable) = match response {
        Ok(ev) => (Some(ev.rms_m.clone()), Some(psd_series(ev, output)), None),
        Err(reason) => (None, None, Some(reason)),
    };
    Ok(FidelityEvaluation {
        fidelity: aero.name.to_string(),
        rms_display: rms.as_ref().map(|r| r[output] * unit_scale),
        rms,
        unstable,
        flutter: flutter_point(modes, table, &aero.flight, v_max)?,
        psd,
        gafs: table.clone(),
        time_s: 0.0,
    })
}

/// A design to cross-evaluate: its name, design vector, and its evaluation with the study's own
/// fidelity with the time it took, when the run already has it.
type CrossPoint<'e> = (
    &'static str,
    Vec<f64>,
    Option<(&'e crate::pipeline::Evaluation, f64)>,
);

/// The designs analysed with the study's fidelity and with `other` (the study with the
/// cross-evaluation fidelity): RMS, p-k flutter point, PSD and GAFs of each. A design that one
/// fidelity finds unstable at the flight condition gets its flutter point and GAFs from it, and
/// the reason in place of an RMS.
fn cross_evaluate(
    study: &Study,
    other: &Study,
    settings: &crate::gust::GustSettings,
    designs: &[CrossPoint<'_>],
    output: usize,
    unit_scale: f64,
    unit: &str,
) -> Result<CrossEvaluation> {
    let flight = study.flight_condition()?;
    let v_max = FLUTTER_CHECK_FACTOR * flight.velocity;
    let analyse = |s: &Study, x: &[f64], what: &str| -> Result<FidelityEvaluation> {
        let context = || format!("cross-evaluation of the {what} design");
        let t = Instant::now();
        let model = crate::pipeline::aeroelastic(&s.resolve()?, x).with_context(context)?;
        // an unstable model has no gust response: its flutter point and GAFs, and the reason
        let analysis = crate::pipeline::analyse(model, settings).with_context(context)?;
        let mut e = fidelity_evaluation(
            analysis.parts(),
            analysis.response().map_err(str::to_string),
            output,
            unit_scale,
            v_max,
        )?;
        e.time_s = t.elapsed().as_secs_f64();
        Ok(e)
    };
    let designs = designs
        .iter()
        .map(|(name, x, own)| -> Result<CrossDesign> {
            let own_eval = match own {
                Some((ev, t)) => FidelityEvaluation {
                    time_s: *t,
                    ..fidelity_evaluation(
                        (&ev.aero, &ev.modes, &ev.table),
                        Ok(ev),
                        output,
                        unit_scale,
                        v_max,
                    )?
                },
                None => analyse(study, x, name)?,
            };
            let mass_kg = study
                .model_at(crate::wing::DesignVector::from_slice(x))?
                .mass();
            Ok(CrossDesign {
                design: name.to_string(),
                mass_kg,
                design_variables: x.clone(),
                evaluations: vec![own_eval, analyse(other, x, name)?],
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(CrossEvaluation {
        output: settings.outputs[output].name.clone(),
        unit: unit.to_string(),
        flight_speed_m_s: flight.velocity,
        searched_up_to_m_s: v_max,
        designs,
    })
}

/// Speeds of the flutter check: from a fifth of the flight speed up to this factor of it.
pub(crate) const FLUTTER_CHECK_FACTOR: f64 = 2.0;

/// The p-k sweep of a modal model with its GAF table at 91 speeds from a fifth of the flight
/// speed up to `v_max`.
pub(crate) fn flutter_sweep(
    modes: &crate::structure::Modes,
    table: &gustkit_core::GafTable,
    flight: &gustkit_core::FlightCondition,
    v_max: f64,
) -> Result<crate::flutter::FlutterResult> {
    let v = flight.velocity;
    let speeds: Vec<f64> = (0..=90)
        .map(|i| v * 0.2 + (v_max - 0.2 * v) * i as f64 / 90.0)
        .collect();
    crate::flutter::PkProblem::new(modes, table, flight.density)
        .sweep(&speeds)
        .map_err(|e| anyhow::anyhow!("flutter check: {e}"))
}

/// Where the p-k sweep of a modal model with its GAF table crosses zero damping, from a fifth of
/// the flight speed up to `v_max`.
fn flutter_point(
    modes: &crate::structure::Modes,
    table: &gustkit_core::GafTable,
    flight: &gustkit_core::FlightCondition,
    v_max: f64,
) -> Result<FlutterPoint> {
    let r = flutter_sweep(modes, table, flight, v_max)?;
    Ok(FlutterPoint {
        speed_m_s: r.flutter_speed_m_s,
        frequency_hz: r.flutter_frequency_hz,
        mode: r.flutter_mode,
    })
}

/// The flutter speeds of the initial and final designs (the resolution check of the run adds the
/// final design's at the refined resolution).
fn flutter_check(
    ev0: &crate::pipeline::Evaluation,
    ev: &crate::pipeline::Evaluation,
) -> Result<FlutterCheck> {
    let flight = &ev.aero.flight;
    let v_max = FLUTTER_CHECK_FACTOR * flight.velocity;
    let final_sweep = flutter_sweep(&ev.modes, &ev.table, flight, v_max)?;
    Ok(FlutterCheck {
        flight_speed_m_s: flight.velocity,
        searched_up_to_m_s: v_max,
        initial: flutter_point(&ev0.modes, &ev0.table, &ev0.aero.flight, v_max)?,
        final_: FlutterPoint {
            speed_m_s: final_sweep.flutter_speed_m_s,
            frequency_hz: final_sweep.flutter_frequency_hz,
            mode: final_sweep.flutter_mode,
        },
        modes: ev.modes.len(),
        more_modes: None,
        final_more_modes: None,
        final_sweep: Some(final_sweep),
    })
}
