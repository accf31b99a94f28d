//! `gustkit run STUDY.json` for a study of a Nastran model (`"model": {"nastran": …}`): the
//! structural mass minimized over DVPREL1-like design variables under limits on the random gust
//! response (RMS, N0) of the model's subcase, by the SQP with its checkpoint and `--resume`; the
//! final design re-analysed with twice the modes and twice the reduced frequencies (the
//! resolution check); results.json, summary.md and figures in the usual run folder. Values are
//! in the model's own units.

use super::nastran::{dense_k, lmodes};
use super::wing::optimize::{fnv, json_differences, FileCheckpoint};
use super::wing::resolution::RMS_TOLERANCE;
use crate::nastran::bulk::BulkData;
use crate::nastran::design::{parse_output, DesignModel, DesignPoint, PropertyRelation};
use crate::nastran::random::KInterpolation;
use crate::nastran::structure::subcase_modes;
use crate::nastran::{Input, Subcase};
use crate::optim::{Checkpoint, Control, EvalError, Executor, Gradients, Iterate, Problem, Values};
use crate::report::write_atomic;
use crate::study::nastran::NastranStudyFile;
use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::Instant;

/// A limit on one output: which row of the response, RMS or N0, and the largest value.
#[derive(Clone, Copy, Debug)]
struct Limit {
    row: usize,
    n0: bool,
    max: f64,
}

/// The optimization problem: mass/mass₀ over the variables, value/limit − 1 ≤ 0 per limit.
struct MassProblem<'a> {
    model: &'a DesignModel,
    limits: &'a [Limit],
    lower: Vec<f64>,
    upper: Vec<f64>,
    mass0: f64,
    last: Option<DesignPoint>,
    function_times: Vec<f64>,
    gradient_times: Vec<f64>,
}

impl MassProblem<'_> {
    /// Whether the gradients come from the reverse mode (one sweep a limit) rather than the
    /// forward mode (one a design variable): whichever needs fewer.
    fn reverse(&self) -> bool {
        self.limits.len() <= self.model.n_variables
    }

    fn values_at(&self, p: &DesignPoint) -> Values {
        Values {
            f: p.mass / self.mass0,
            eq: Vec::new(),
            ineq: self
                .limits
                .iter()
                .map(|l| {
                    let r = &p.rows[l.row];
                    (if l.n0 { r.n0_hz } else { r.rms }) / l.max - 1.0
                })
                .collect(),
        }
    }
}

impl Problem for MassProblem<'_> {
    fn lower(&self) -> Vec<f64> {
        self.lower.clone()
    }

    fn upper(&self) -> Vec<f64> {
        self.upper.clone()
    }

    fn values(&mut self, x: &[f64]) -> Result<Values, EvalError> {
        let t = Instant::now();
        let p = self.model.analyse(x)?;
        let v = self.values_at(&p);
        self.last = Some(p);
        self.function_times.push(t.elapsed().as_secs_f64());
        Ok(v)
    }

    fn gradients(&mut self, x: &[f64]) -> Result<Gradients, EvalError> {
        let t = Instant::now();
        if self.last.as_ref().is_none_or(|p| p.x != x) {
            self.last = Some(self.model.analyse(x)?);
        }
        let p = self.last.as_ref().expect("analysed above");
        if self.reverse() {
            // one functional a limit: its output's RMS or N0 over the limit
            let functionals: Vec<Vec<(f64, f64)>> = self
                .limits
                .iter()
                .map(|l| {
                    let mut seeds = vec![(0.0, 0.0); p.rows.len()];
                    seeds[l.row] = if l.n0 {
                        (0.0, 1.0 / l.max)
                    } else {
                        (1.0 / l.max, 0.0)
                    };
                    seeds
                })
                .collect();
            let g = self.model.gradients_reverse(p, &functionals)?;
            self.gradient_times.push(t.elapsed().as_secs_f64());
            return Ok(Gradients {
                f: g.mass.iter().map(|d| d / self.mass0).collect(),
                eq: Vec::new(),
                ineq: g.functionals,
            });
        }
        let g = self.model.gradients(p)?;
        let grads = Gradients {
            f: g.mass.iter().map(|d| d / self.mass0).collect(),
            eq: Vec::new(),
            ineq: self
                .limits
                .iter()
                .map(|l| {
                    g.outputs
                        .iter()
                        .map(|per_output| {
                            let d = &per_output[l.row];
                            (if l.n0 { d.d_n0_hz } else { d.d_rms }) / l.max
                        })
                        .collect()
                })
                .collect(),
        };
        self.gradient_times.push(t.elapsed().as_secs_f64());
        Ok(grads)
    }
}

/// Prints one line an iteration.
struct Progress {
    mass0: f64,
    quiet: bool,
}

impl crate::optim::Observer for Progress {
    fn iteration(&mut self, it: &Iterate, _: &Checkpoint) -> Result<Control, String> {
        if !self.quiet {
            let worst = it
                .values
                .ineq
                .iter()
                .fold(f64::NEG_INFINITY, |a, &g| a.max(g));
            println!(
                "iteration {:3}: mass {:.6e} ({:+.2} %), largest constraint ratio {:.4}, KKT {:.2e}, step {:.3}",
                it.iteration,
                it.values.f * self.mass0,
                100.0 * (it.values.f - 1.0),
                worst + 1.0,
                it.kkt,
                it.step
            );
        }
        Ok(Control::Continue)
    }
}

#[derive(Serialize, Deserialize)]
struct VariableResult {
    name: String,
    lower: f64,
    upper: f64,
    initial: f64,
    #[serde(rename = "final")]
    final_value: f64,
}

#[derive(Serialize, Deserialize)]
struct PropertyResult {
    /// `PBAR 3 A`.
    label: String,
    /// The value on the model's card.
    model: f64,
    initial: f64,
    #[serde(rename = "final")]
    final_value: f64,
}

#[derive(Serialize, Deserialize)]
struct ConstraintResult {
    output: String,
    /// `rms` or `n0_hz`.
    quantity: String,
    limit: f64,
    initial: f64,
    #[serde(rename = "final")]
    final_value: f64,
    /// At the final design with twice the modes and twice the reduced frequencies.
    refined: f64,
}

/// One p-k flutter point of the flutter subcase at the initial and final designs.
#[derive(Serialize, Deserialize)]
struct FlutterCheckRow {
    flutter_id: u32,
    mach: f64,
    density_ratio: f64,
    /// The FLFACT velocities' range (the model's units).
    velocity_min: f64,
    velocity_max: f64,
    /// The flutter speed within the range, none when stable throughout.
    initial_speed: Option<f64>,
    final_speed: Option<f64>,
    final_frequency_hz: Option<f64>,
    final_mode: Option<usize>,
}

#[derive(Serialize, Deserialize)]
struct HistoryRow {
    iteration: usize,
    mass: f64,
    /// The largest value/limit over the constraints.
    largest_ratio: f64,
    kkt: f64,
    step: f64,
}

#[derive(Serialize, Deserialize)]
struct OutputPsd {
    label: String,
    rms: f64,
    n0_hz: f64,
    psd: Vec<f64>,
}

/// What the resolution check used.
#[derive(Serialize, Deserialize)]
struct Resolution {
    modes: usize,
    reduced_frequencies: usize,
    refined_modes: usize,
    refined_reduced_frequencies: usize,
    /// The largest |refined − value| / limit over the constraints.
    largest_change_of_limit: f64,
}

/// results.json of a Nastran design study.
#[derive(Serialize, Deserialize)]
struct NastranDesignResults {
    kind: String,
    study: String,
    description: String,
    input: String,
    subcase: u32,
    units: String,
    converged: bool,
    status: String,
    message: String,
    iterations: usize,
    evaluations: usize,
    wall_time_s: f64,
    mass_initial: f64,
    mass_final: f64,
    mass_change_percent: f64,
    design_variables: Vec<VariableResult>,
    properties: Vec<PropertyResult>,
    constraints: Vec<ConstraintResult>,
    /// The flutter subcase's points at the initial and final designs (`model.flutter_subcase`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    flutter_check: Vec<FlutterCheckRow>,
    resolution: Resolution,
    history: Vec<HistoryRow>,
    frequencies_hz: Vec<f64>,
    /// The constrained grid and mode outputs, then every monitor component, at the final
    /// design.
    final_response: Vec<OutputPsd>,
    function_time_median_s: f64,
    gradient_time_median_s: f64,
    /// `reverse` (one sweep a limit) or `forward` (one a design variable): whichever needs
    /// fewer.
    gradient_mode: String,
    threads: usize,
    warnings: Vec<String>,
    /// Where the GAFs come from, in words (the model's DLM, or the study's LFD).
    #[serde(default)]
    aerodynamics: String,
}

/// A study's design model, its limits, the reading's warnings and the initial design analysed
/// (which places each limit on its row of the response), every model error named by the
/// study's JSON path.
type Designed = (DesignModel, Vec<Limit>, Vec<String>, DesignPoint);

/// The model, its subcase and the design model of a study ([`Designed`]).
fn design_model(study: &NastranStudyFile) -> Result<Designed> {
    let file = study.model_path();
    let at = |path: &str| format!("{}: {path}", study.file.display());
    let input = Input::read(&file).with_context(|| at("model.nastran"))?;
    let base = BulkData::from_cards(&input.deck.bulk).with_context(|| at("model.nastran"))?;
    let mut warnings = input.warnings();
    warnings.extend(base.warnings.iter().cloned());
    let ids = input.case_control.subcase_ids();
    let id = match (study.model.subcase, ids.as_slice()) {
        (Some(id), _) if ids.contains(&id) => id,
        (Some(id), _) => bail!(
            "{}: the model has no subcase {id} (it has {ids:?})",
            at("model.subcase")
        ),
        (None, [one]) => *one,
        (None, _) => bail!(
            "{}: the model has subcases {ids:?}: name the one to design against",
            at("model.subcase")
        ),
    };
    let sub: Subcase = input.case_control.subcase(id).expect("listed subcase");
    if let Some(f) = study.model.flutter_subcase {
        let ok = input
            .case_control
            .subcase(f)
            .is_some_and(|s| s.selections.contains_key("FMETHOD"));
        if !ok {
            bail!(
                "{}: the model has no subcase {f} with FMETHOD (its subcases: {ids:?}): name the subcase of its p-k flutter analysis",
                at("model.flutter_subcase")
            );
        }
    }
    if !sub.selections.contains_key("RANDOM") {
        bail!(
            "{}: subcase {id} selects no RANDOM: the constraints are on its random gust response (GUST, FREQUENCY, RANDOM)",
            at("model.subcase")
        );
    }
    let relations = study
        .properties
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let terms = r
                .terms
                .iter()
                .map(|(name, c)| (study.variable(name).expect("checked at load"), *c))
                .collect();
            PropertyRelation::new(&base, &r.card, r.id, &r.field, r.c0, terms)
                .with_context(|| at(&format!("properties[{i}]")))
        })
        .collect::<Result<Vec<_>>>()?;
    let (s, modes) = subcase_modes(&base, &sub).with_context(|| at("model.nastran"))?;
    // the requests: the constrained grid and mode outputs (monitor points are always part of
    // the response)
    let mut labels: Vec<String> = Vec::new();
    for (i, c) in study.constraints.iter().enumerate() {
        let Some(request) = parse_output(&c.output) else {
            continue;
        };
        if request.2 != crate::nastran::random::Quantity::Mode && !s.index.contains_key(&request.0)
        {
            bail!(
                "{}: names grid {}, which the model does not define",
                at(&format!("constraints[{i}].output")),
                request.0
            );
        }
        let label = c.output.trim().to_string();
        if !labels.contains(&label) {
            labels.push(label);
        }
    }
    let requests = labels.iter().map(|l| parse_output(l).unwrap()).collect();
    let n_variables = study.design_variables.len();
    let n_modes = lmodes(&base, modes.lambda.len());
    let (interpolation, lfd) = match &study.aero {
        None => (
            dense_k(&base, &sub).with_context(|| at("model.nastran"))?,
            None,
        ),
        Some(a) => {
            let lfd = nastran_lfd(&base, &sub, &s, a).with_context(|| at("aero"))?;
            (
                KInterpolation::Dense(a.reduced_frequencies.clone()),
                Some(std::sync::Arc::new(lfd)),
            )
        }
    };
    let model = DesignModel {
        base,
        sub,
        relations,
        requests,
        interpolation,
        n_variables,
        n_modes,
        lfd,
    };
    // each limit's row of the response, by its label
    let x0: Vec<f64> = study.design_variables.iter().map(|v| v.initial).collect();
    let start = model
        .analyse(&x0)
        .with_context(|| format!("{}: the initial design", study.file.display()))?;
    let mut limits = Vec::new();
    for (i, c) in study.constraints.iter().enumerate() {
        let label = c.output.trim();
        let Some(row) = start.rows.iter().position(|r| r.label == label) else {
            let monitors: Vec<&str> = start.rows[model.requests.len()..]
                .iter()
                .map(|r| r.label.as_str())
                .collect();
            bail!(
                "{}: \"{label}\" is no output of the model (its monitor components: {})",
                at(&format!("constraints[{i}].output")),
                if monitors.is_empty() {
                    "none, it has no MONPNT1".to_string()
                } else {
                    monitors.join(", ")
                }
            );
        };
        for (n0, max) in [(false, c.rms_max), (true, c.n0_max_hz)] {
            if let Some(max) = max {
                limits.push(Limit { row, n0, max });
            }
        }
    }
    Ok((model, limits, warnings, start))
}

/// The p-k flutter points of the study's flutter subcase at the initial and final designs.
fn flutter_check(
    study: &NastranStudyFile,
    model: &DesignModel,
    (x0, x): (&[f64], &[f64]),
) -> Result<Vec<FlutterCheckRow>> {
    let Some(id) = study.model.flutter_subcase else {
        return Ok(Vec::new());
    };
    let input = Input::read(&study.model_path())?;
    let sub = input
        .case_control
        .subcase(id)
        .context("the flutter subcase was checked at load")?;
    let at = |x: &[f64]| -> Result<Vec<super::nastran::FlutterPoint>> {
        let b = crate::nastran::design::apply(&model.base, &model.relations, x)?;
        let (s, modes) = subcase_modes(&b, &sub)?;
        super::nastran::flutter(&b, &sub, &s, &modes)
    };
    let (before, after) = (
        at(x0).context("the flutter check of the initial design")?,
        at(x).context("the flutter check of the final design")?,
    );
    Ok(before
        .iter()
        .zip(&after)
        .map(|(a, b)| FlutterCheckRow {
            flutter_id: b.flutter_id,
            mach: b.mach,
            density_ratio: b.density_ratio,
            velocity_min: b.velocities.first().copied().unwrap_or(0.0),
            velocity_max: b.velocities.last().copied().unwrap_or(0.0),
            initial_speed: a.flutter_speed,
            final_speed: b.flutter_speed,
            final_frequency_hz: b.flutter_frequency_hz,
            final_mode: b.flutter_mode,
        })
        .collect())
}

/// The same model with twice the modes (the METHOD asked for 2n roots, its upper frequency
/// dropped) and twice the reduced frequencies over the same range.
fn refined(model: &DesignModel) -> Result<DesignModel> {
    let mut m = model.clone();
    let method = m
        .sub
        .selections
        .get("METHOD")
        .copied()
        .context("no METHOD")?;
    let eig = m.base.eigr.get_mut(&method).context("no EIGR/EIGRL")?;
    eig.nd = Some(2 * model.n_modes as u32);
    eig.f2 = None;
    m.base.params.remove("LMODES");
    let (_, modes) = subcase_modes(&m.base, &m.sub)?;
    m.n_modes = modes.lambda.len().min(2 * model.n_modes);
    if let KInterpolation::Dense(k) = &model.interpolation {
        let k_max = k.last().copied().unwrap_or(0.0);
        let n = 2 * (k.len() - 1);
        m.interpolation =
            KInterpolation::Dense((0..=n).map(|i| k_max * i as f64 / n as f64).collect());
    }
    Ok(m)
}

/// The LFD of the study's `aero` on the model's panel, at the subcase's Mach number, with its
/// table reaching the FREQ list's highest reduced frequency.
fn nastran_lfd(
    base: &crate::nastran::bulk::BulkData,
    sub: &Subcase,
    s: &crate::nastran::structure::Structure,
    a: &crate::study::nastran::NastranAeroSpec,
) -> Result<crate::nastran::lfd::NastranLfd> {
    let flight = crate::nastran::response::subcase_flight(base, sub)?;
    let k_needed = match dense_k(base, sub)? {
        // dense_k reaches 5 % beyond the list's last frequency
        KInterpolation::Dense(k) => k.last().copied().unwrap_or(0.0) / 1.05,
        KInterpolation::LinearOnMkaero(_) => 0.0,
    };
    let k_last = a.reduced_frequencies.last().copied().unwrap_or(0.0);
    if k_last < k_needed * (1.0 - 1e-9) {
        bail!(
            "reduced_frequencies: end at {k_last}, below the FREQ list's highest reduced frequency {k_needed:.4} (ω REFC / 2V): extend the table to it"
        );
    }
    let airfoil = a
        .airfoil
        .airfoil()
        .map_err(|e| anyhow::anyhow!("airfoil: {e}"))?;
    let surf = crate::nastran::aero::lifting_surfaces(base, s)?;
    Ok(crate::nastran::lfd::NastranLfd::build(
        base,
        s,
        &surf,
        (&a.fidelity, &airfoil),
        &flight,
        None,
    )?)
}

/// Where a design model's GAFs come from, in words.
fn aerodynamics_words(study: &NastranStudyFile, model: &DesignModel) -> String {
    let k = model.interpolation.reduced_frequencies().len();
    match (&model.lfd, &study.aero) {
        (Some(l), Some(a)) => format!(
            "the {} about the model's CAERO1 panel (semispan {}, root chord {}, tip chord {}, quarter-chord sweep {:.2}°; the study's section) at M {}, its wall points moved by the model's splines, on the study's {k} reduced frequencies (aero.reduced_frequencies)",
            a.fidelity.words(),
            l.planform.span,
            l.planform.root_chord,
            l.planform.tip_chord,
            l.planform.sweep_c4.to_degrees(),
            l.mach
        ),
        _ => format!(
            "the DLM on the model's CAERO1 boxes, as Nastran's, on {k} reduced frequencies to 5 % beyond the FREQ list's last"
        ),
    }
}

/// The median of some timings (0 when there are none), as the wing runs' `Stats` take it.
fn median(times: &[f64]) -> f64 {
    if times.is_empty() {
        return 0.0;
    }
    crate::report::results::Stats::of(times.to_vec()).median_s
}

/// Runs a Nastran design study into reports/<name>/.
pub fn run(study: &NastranStudyFile, reports: &Path, resume: bool) -> Result<super::Outcome> {
    let (model, limits, mut warnings, start) = design_model(study)?;
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    let x0: Vec<f64> = study.design_variables.iter().map(|v| v.initial).collect();
    for r in &model.relations {
        let (on_card, at_x0) = (r.current(&model.base), r.value(&x0));
        if (on_card - at_x0).abs() > 1e-9 * on_card.abs() {
            let w = format!(
                "{}: the initial design sets {at_x0:.6e} in place of the card's {on_card:.6e} (the relation overrides the card, as DVPREL1 does)",
                r.label()
            );
            eprintln!("warning: {w}");
            warnings.push(w);
        }
    }
    let final_dir = reports.join(&study.name);
    let folder = crate::report::folder::RunFolder::begin(&final_dir, resume)?;
    let dir = folder.path().to_path_buf();
    println!(
        "{}: {} design variables, {} constraints on subcase {}, {} modes, {} reduced frequencies; initial mass {:.6e}",
        study.name,
        model.n_variables,
        limits.len(),
        model.sub.id,
        model.n_modes,
        model.interpolation.reduced_frequencies().len(),
        start.mass
    );
    let problem_id = checkpoint_id(study, &model)?;
    let checkpoint = open_checkpoint(study, &dir, &problem_id, resume)?;
    let mut problem = MassProblem {
        model: &model,
        limits: &limits,
        lower: study.design_variables.iter().map(|v| v.lower).collect(),
        upper: study.design_variables.iter().map(|v| v.upper).collect(),
        mass0: start.mass,
        last: None,
        function_times: Vec::new(),
        gradient_times: Vec::new(),
    };
    let params = crate::optim::SqpParams {
        max_iterations: study.optimization.max_iterations,
        tolerance: study.optimization.tolerance,
        nonmonotone_memory: study.optimization.nonmonotone_memory,
        ..Default::default()
    };
    let mut progress = Progress {
        mass0: start.mass,
        quiet: false,
    };
    let mut store = FileCheckpoint {
        path: dir.join("checkpoint.json"),
    };
    let info = Executor::new(params, &problem_id)
        .resume(checkpoint)
        .observe(&mut progress)
        .checkpoint(&mut store)
        .run(&mut problem, &x0)
        .map_err(|e| anyhow::anyhow!("optimization: {e}"))?;
    let last = model.analyse(&info.x).context("the final design")?;
    let fine = refined(&model)?;
    let check = fine
        .analyse(&info.x)
        .context("the final design's resolution check (twice the modes and reduced frequencies)")?;
    let mut results = results(
        study,
        (&model, &fine),
        &limits,
        (&start, &last, &check),
        &info,
        &problem,
        warnings,
    );
    results.flutter_check = flutter_check(study, &model, (&x0, &info.x))?;
    write_atomic(
        &dir.join("results.json"),
        serde_json::to_string_pretty(&results)?.as_bytes(),
    )?;
    render(&results, &dir)?;
    print!("{}", summary(&results));
    let violated = results
        .constraints
        .iter()
        .filter(|c| c.final_value > c.limit * (1.0 + 10.0 * study.optimization.tolerance))
        .map(|c| {
            format!(
                "{} {} {:.6e} > {:.6e}",
                c.output, c.quantity, c.final_value, c.limit
            )
        })
        .collect::<Vec<_>>();
    let unresolved = results
        .constraints
        .iter()
        .filter(|c| c.refined > c.limit * (1.0 + RMS_TOLERANCE))
        .map(|c| {
            format!(
                "{} {} {:.6e} > {:.6e}",
                c.output, c.quantity, c.refined, c.limit
            )
        })
        .collect::<Vec<_>>();
    folder.commit()?;
    println!("results written to {}", final_dir.display());
    if !info.converged {
        return Ok(super::Outcome::GoalNotReached(format!(
            "the optimization did not converge: {}",
            info.message
        )));
    }
    if !violated.is_empty() {
        return Ok(super::Outcome::GoalNotReached(format!(
            "the final design violates its limits: {}",
            violated.join("; ")
        )));
    }
    let fluttering: Vec<String> = results
        .flutter_check
        .iter()
        .filter_map(|f| f.final_speed.map(|v| flutter_words(f, v)))
        .collect();
    if !fluttering.is_empty() {
        return Ok(super::Outcome::GoalNotReached(format!(
            "the final design {}",
            fluttering.join("; ")
        )));
    }
    if !unresolved.is_empty() {
        return Ok(super::Outcome::GoalNotReached(format!(
            "the final design exceeds its limits by more than {:.0} % with twice the modes and reduced frequencies: {}",
            100.0 * RMS_TOLERANCE,
            unresolved.join("; ")
        )));
    }
    Ok(super::Outcome::Done)
}

/// "flutters at V = … (FLUTTER 30 at Mach …, density ratio …), mode 3, 42.1 Hz".
fn flutter_words(f: &FlutterCheckRow, v: f64) -> String {
    let mut w = format!(
        "flutters at V = {v:.6} (FLUTTER {} at Mach {}, density ratio {}; velocities {}–{})",
        f.flutter_id, f.mach, f.density_ratio, f.velocity_min, f.velocity_max
    );
    if let Some(m) = f.final_mode {
        w += &format!(", mode {m}");
    }
    if let Some(hz) = f.final_frequency_hz {
        w += &format!(", {hz:.4} Hz");
    }
    w
}

/// The checkpoint's problem id: the study's defining fields and the model's data.
fn checkpoint_id(study: &NastranStudyFile, model: &DesignModel) -> Result<String> {
    let defining = defining(study)?;
    let text = format!(
        "{}{:?}",
        serde_json::to_string(&defining)?,
        (&model.base, &model.sub)
    );
    Ok(format!("{}:{:016x}", study.name, fnv(&text)))
}

/// The study without what may change between a run and its resumption.
fn defining(study: &NastranStudyFile) -> Result<serde_json::Value> {
    let mut v = serde_json::to_value(study)?;
    if let Some(m) = v.as_object_mut() {
        m.remove("description");
        m.remove("optimization");
    }
    Ok(v)
}

/// The checkpoint to resume from (with `--resume`), or none; without `--resume` the study's
/// defining fields are kept beside the checkpoint to name what changed when a resume refuses.
fn open_checkpoint(
    study: &NastranStudyFile,
    dir: &Path,
    problem_id: &str,
    resume: bool,
) -> Result<Option<Checkpoint>> {
    let study_copy = dir.join("checkpoint_study.json");
    let defining = defining(study)?;
    if !resume {
        write_atomic(
            &study_copy,
            serde_json::to_string_pretty(&defining)?.as_bytes(),
        )?;
        return Ok(None);
    }
    let path = dir.join("checkpoint.json");
    let text = std::fs::read_to_string(&path).with_context(|| {
        format!(
            "--resume: cannot read {} (no interrupted run to continue: run without --resume)",
            path.display()
        )
    })?;
    let cp: Checkpoint = serde_json::from_str(&text)
        .with_context(|| format!("--resume: {} is not a gustkit checkpoint", path.display()))?;
    if cp.problem_id != problem_id {
        let changed = std::fs::read_to_string(&study_copy)
            .ok()
            .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
            .map(|old| json_differences(&old, &defining, ""))
            .unwrap_or_default();
        let what = if changed.is_empty() {
            "the Nastran model changed since the checkpoint was written".to_string()
        } else {
            format!("the study changed: {}", changed.join(", "))
        };
        bail!(
            "{}: --resume: {what}; only the description and the optimization section may change between a run and its resumption. Run without --resume to start over",
            study.file.display()
        );
    }
    println!("resuming from iteration {}", cp.iteration);
    Ok(Some(cp))
}

/// The results of a finished run.
fn results(
    study: &NastranStudyFile,
    (model, fine): (&DesignModel, &DesignModel),
    limits: &[Limit],
    (start, last, check): (&DesignPoint, &DesignPoint, &DesignPoint),
    info: &crate::optim::SqpInfo,
    problem: &MassProblem,
    warnings: Vec<String>,
) -> NastranDesignResults {
    let value = |p: &DesignPoint, l: &Limit| {
        let r = &p.rows[l.row];
        if l.n0 {
            r.n0_hz
        } else {
            r.rms
        }
    };
    let constraints: Vec<ConstraintResult> = limits
        .iter()
        .map(|l| ConstraintResult {
            output: start.rows[l.row].label.clone(),
            quantity: if l.n0 { "n0_hz" } else { "rms" }.into(),
            limit: l.max,
            initial: value(start, l),
            final_value: value(last, l),
            refined: value(check, l),
        })
        .collect();
    let k_count = |m: &DesignModel| m.interpolation.reduced_frequencies().len();
    NastranDesignResults {
        kind: crate::kind::StudyKind::NastranDesign.name().into(),
        study: study.name.clone(),
        description: study.description.clone(),
        input: study.model.nastran.clone(),
        subcase: model.sub.id,
        units: "the model's own (gustkit converts nothing in a Nastran model)".into(),
        converged: info.converged,
        status: format!("{:?}", info.status),
        message: info.message.clone(),
        iterations: info.iterations,
        evaluations: info.evaluations,
        wall_time_s: info.elapsed_s,
        mass_initial: start.mass,
        mass_final: last.mass,
        mass_change_percent: 100.0 * (last.mass / start.mass - 1.0),
        design_variables: study
            .design_variables
            .iter()
            .zip(&info.x)
            .map(|(v, &x)| VariableResult {
                name: v.name.clone(),
                lower: v.lower,
                upper: v.upper,
                initial: v.initial,
                final_value: x,
            })
            .collect(),
        properties: model
            .relations
            .iter()
            .map(|r| PropertyResult {
                label: r.label(),
                model: r.current(&model.base),
                initial: r.value(&start.x),
                final_value: r.value(&info.x),
            })
            .collect(),
        resolution: Resolution {
            modes: model.n_modes,
            reduced_frequencies: k_count(model),
            refined_modes: fine.n_modes,
            refined_reduced_frequencies: k_count(fine),
            largest_change_of_limit: constraints
                .iter()
                .map(|c| (c.refined - c.final_value).abs() / c.limit)
                .fold(0.0, f64::max),
        },
        constraints,
        flutter_check: Vec::new(),
        history: info
            .history
            .iter()
            .map(|it| HistoryRow {
                iteration: it.iteration,
                mass: it.values.f * start.mass,
                largest_ratio: 1.0
                    + it.values
                        .ineq
                        .iter()
                        .fold(f64::NEG_INFINITY, |a, &g| a.max(g)),
                kkt: it.kkt,
                step: it.step,
            })
            .collect(),
        frequencies_hz: last
            .rows
            .first()
            .map(|r| r.frequencies_hz.clone())
            .unwrap_or_default(),
        final_response: last
            .rows
            .iter()
            .map(|r| OutputPsd {
                label: r.label.clone(),
                rms: r.rms,
                n0_hz: r.n0_hz,
                psd: r.psd.clone(),
            })
            .collect(),
        function_time_median_s: median(&problem.function_times),
        gradient_time_median_s: median(&problem.gradient_times),
        gradient_mode: if problem.reverse() {
            "reverse"
        } else {
            "forward"
        }
        .into(),
        threads: rayon::current_num_threads(),
        warnings,
        aerodynamics: aerodynamics_words(study, model),
    }
}

/// The figures: the optimization history and the final design's PSDs.
fn render(r: &NastranDesignResults, dir: &Path) -> Result<()> {
    use crate::report::figures::{line_plot, LinePlot, Panels};
    use crate::report::save_figure;
    let by_iteration = |f: &dyn Fn(&HistoryRow) -> f64| -> Vec<(f64, f64)> {
        r.history
            .iter()
            .map(|h| (h.iteration as f64, f(h)))
            .collect()
    };
    let fig = Panels {
        title: format!("{}: optimization history", r.study),
        cols: 2,
        plots: vec![
            line_plot(
                "structural mass".into(),
                "iteration",
                "mass (model units)",
                vec![("mass".into(), by_iteration(&|h| h.mass))],
            ),
            line_plot(
                "largest constraint".into(),
                "iteration",
                "value / limit",
                vec![("largest".into(), by_iteration(&|h| h.largest_ratio))],
            ),
        ],
    };
    save_figure(dir, "history", &fig)?;
    let series = r
        .final_response
        .iter()
        .filter(|o| o.psd.len() == r.frequencies_hz.len())
        .map(|o| {
            (
                o.label.clone(),
                r.frequencies_hz
                    .iter()
                    .copied()
                    .zip(o.psd.iter().copied())
                    .collect(),
            )
        })
        .collect();
    let fig = LinePlot {
        log_y: true,
        ..line_plot(
            format!(
                "{}: PSDs of the constrained outputs at the final design",
                r.study
            ),
            "frequency (Hz)",
            "PSD (model units² / Hz)",
            series,
        )
    };
    save_figure(dir, "psd_final", &fig)?;
    write_atomic(&dir.join("summary.md"), summary(r).as_bytes())
}

fn summary(r: &NastranDesignResults) -> String {
    let mut out = format!(
        "# {}\n\n{}\n\nModel `{}`, subcase {}; units: {}.\n\n",
        r.study, r.description, r.input, r.subcase, r.units
    );
    out.push_str(&format!(
        "**{}** after {} iterations ({} evaluations, {:.2} s; median evaluation {:.3} s, gradient ({} mode) {:.3} s, {} threads): {}.\n\n",
        if r.converged { "Converged" } else { "Not converged" },
        r.iterations,
        r.evaluations,
        r.wall_time_s,
        r.function_time_median_s,
        r.gradient_mode,
        r.gradient_time_median_s,
        r.threads,
        r.message
    ));
    out.push_str(&format!(
        "Structural mass {:.6e} → {:.6e} ({:+.2} %).\n\n",
        r.mass_initial, r.mass_final, r.mass_change_percent
    ));
    out.push_str(
        "| design variable | lower | upper | initial | final |\n|---|---:|---:|---:|---:|\n",
    );
    for v in &r.design_variables {
        out.push_str(&format!(
            "| {} | {} | {} | {} | {:.6} |\n",
            v.name, v.lower, v.upper, v.initial, v.final_value
        ));
    }
    out.push_str("\n| property | on the card | initial | final |\n|---|---:|---:|---:|\n");
    for p in &r.properties {
        out.push_str(&format!(
            "| {} | {:.6e} | {:.6e} | {:.6e} |\n",
            p.label, p.model, p.initial, p.final_value
        ));
    }
    let s = &r.resolution;
    out.push_str(&format!(
        "\n| constraint | limit | initial | final | refined ({} modes, {} k) |\n|---|---:|---:|---:|---:|\n",
        s.refined_modes, s.refined_reduced_frequencies
    ));
    for c in &r.constraints {
        let over = c.refined > c.limit * (1.0 + RMS_TOLERANCE);
        let refined = format!("{:.6e}", c.refined);
        out.push_str(&format!(
            "| {} {} | {:.6e} | {:.6e} | {:.6e} | {} |\n",
            c.output,
            c.quantity,
            c.limit,
            c.initial,
            c.final_value,
            if over {
                format!("**{refined}**")
            } else {
                refined
            }
        ));
    }
    out.push_str(&format!(
        "\nThe constraints see {} modes (the model's METHOD and PARAM LMODES) and {} reduced frequencies; the final design re-analysed with {} modes and {} reduced frequencies moves them by at most {:.2e} of their limits (a refined value more than {:.0} % above its limit is in bold and fails the run). Aerodynamics: {}.\n",
        s.modes, s.reduced_frequencies, s.refined_modes, s.refined_reduced_frequencies, s.largest_change_of_limit, 100.0 * RMS_TOLERANCE,
        if r.aerodynamics.is_empty() {
            "the DLM on the model's CAERO1 boxes, as Nastran's"
        } else {
            r.aerodynamics.as_str()
        }
    ));
    if !r.flutter_check.is_empty() {
        out.push_str(
            "\n| flutter (p-k) | velocities | initial design | final design |\n|---|---|---|---|\n",
        );
        for f in &r.flutter_check {
            let speed = |v: Option<f64>| v.map_or("no flutter".to_string(), |v| format!("{v:.6}"));
            let final_words = match f.final_speed {
                Some(v) => format!("**{}**", flutter_words(f, v)),
                None => "no flutter".into(),
            };
            out.push_str(&format!(
                "| FLUTTER {}, Mach {}, density ratio {} | {}–{} | {} | {} |\n",
                f.flutter_id,
                f.mach,
                f.density_ratio,
                f.velocity_min,
                f.velocity_max,
                speed(f.initial_speed),
                final_words
            ));
        }
    }
    if !r.warnings.is_empty() {
        out.push_str("\nWarnings:\n\n");
        for w in &r.warnings {
            out.push_str(&format!("- {w}\n"));
        }
    }
    out
}

/// `gustkit report` of a Nastran design run: summary and figures from results.json alone.
pub fn rerender(dir: &Path, value: &serde_json::Value) -> Result<String> {
    let path = dir.join("results.json");
    let r: NastranDesignResults = crate::report::from_json(&path, value)?;
    render(&r, dir)?;
    Ok(r.study)
}
