//! First-order model management (Alexandrov, Dennis, Lewis & Torczon 1998, "A trust-region
//! framework for managing the use of approximation models"): minimize an expensive problem
//! (the high fidelity, e.g. the Euler LFD) through a cheap one (the low fidelity, e.g. the DLM)
//! corrected at the current point x_k to agree with it in values and gradients,
//!   c̃(x) = c_low(x) + [c_high(x_k) − c_low(x_k)] + [∇c_high(x_k) − ∇c_low(x_k)]·(x − x_k),
//! for the objective and every constraint. The corrected problem is solved by the SQP inside a
//! trust-region box around x_k; its optimum is evaluated with the high fidelity and accepted when
//! the ℓ1 merit falls by at least a tenth of what the corrected problem predicted. Each outer
//! iteration costs one high-fidelity function (and one gradient when accepted); the first-order
//! agreement makes the limit a KKT point of the high fidelity, not of the low one. Where the low
//! fidelity cannot serve (it fails at x_k, or its corrected problem stops short without
//! converging because its trial points fail, as a coarse lattice that flutters where the fine
//! one does not), the outer iteration is one SQP iteration of the high fidelity in the box.

use super::{
    sqp::{dot, infeasibility_sum, violation, Scaling},
    Checkpoint, Control, EvalError, Executor, Gradients, Observer, PointEvaluation, Problem,
    SqpError, SqpParams, Values,
};
use serde::{Deserialize, Serialize};

/// Settings of the model management (outer loop); `inner` are the corrected problem's SQP
/// settings (its tolerance is replaced by `tolerance`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ManagedParams {
    /// Outer iterations: high-fidelity functions at most.
    pub max_iterations: usize,
    /// KKT tolerance, as the SQP's, for the high fidelity at the current point.
    pub tolerance: f64,
    /// Initial trust-region half width in the scaled variables (bound range = 1).
    pub initial_radius: f64,
    /// Below this half width the run stops (the corrections cannot predict the high fidelity
    /// on any smaller step).
    pub min_radius: f64,
    pub inner: SqpParams,
}

impl Default for ManagedParams {
    fn default() -> Self {
        Self {
            max_iterations: 50,
            tolerance: 1e-4,
            initial_radius: 0.1,
            min_radius: 1e-6,
            inner: SqpParams::default(),
        }
    }
}

impl ManagedParams {
    /// Checks the settings before anything is evaluated.
    pub fn validate(&self) -> Result<(), SqpError> {
        let bad = |m: String| Err(SqpError::Params(m));
        if self.max_iterations == 0 {
            return bad("the model management's max_iterations must be at least 1".into());
        }
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return bad(format!(
                "the model management's tolerance must lie in (0, 1) (got {})",
                self.tolerance
            ));
        }
        if !(self.initial_radius > 0.0 && self.initial_radius <= 1.0) {
            return bad(format!(
                "the trust region's initial radius must lie in (0, 1] of the bound ranges (got {})",
                self.initial_radius
            ));
        }
        if !(self.min_radius > 0.0 && self.min_radius < self.initial_radius) {
            return bad(format!(
                "the trust region's min_radius must be positive and below the initial radius {} (got {})",
                self.initial_radius, self.min_radius
            ));
        }
        self.inner.validate()
    }
}

/// One outer iteration: the point it started from (high-fidelity values), the trust region and
/// what became of the corrected problem's optimum.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ManagedIterate {
    pub iteration: usize,
    pub x: Vec<f64>,
    pub values: Values,
    pub violation: f64,
    /// The KKT measure at `x`: the corrected problem's first, which is the high fidelity's
    /// (values and gradients agree there).
    pub kkt: f64,
    /// How the corrected problem's SQP ended (its message).
    #[serde(default)]
    pub inner_outcome: String,
    /// Trust-region half width (scaled variables) of the corrected problem's solve.
    pub radius: f64,
    /// Actual over predicted merit decrease at the corrected optimum (none: not evaluated).
    pub ratio: Option<f64>,
    pub accepted: bool,
    /// Largest scaled component of the step to the corrected optimum.
    pub step: f64,
    /// SQP iterations on the corrected problem (low-fidelity gradients).
    pub inner_iterations: usize,
    /// High-fidelity functions and gradients so far, this iteration's included.
    pub high_functions: usize,
    pub high_gradients: usize,
}

/// Everything needed to continue a managed run after its last outer iteration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ManagedCheckpoint {
    pub problem_id: String,
    pub params: ManagedParams,
    pub x: Vec<f64>,
    /// The high fidelity's values and gradients at `x`.
    pub values: Values,
    pub gradients: Gradients,
    pub radius: f64,
    pub penalty: f64,
    /// The last corrected problem's BFGS matrix (scaled by the bounds, as the SQP's).
    pub hessian: Option<Vec<Vec<f64>>>,
    pub history: Vec<ManagedIterate>,
    pub high_functions: usize,
    pub high_gradients: usize,
    /// Wall time over every session of the run so far, in seconds (absent in older files).
    #[serde(default)]
    pub elapsed_s: f64,
}

/// How a managed run ended.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ManagedInfo {
    pub converged: bool,
    pub message: String,
    pub x: Vec<f64>,
    /// High-fidelity values at `x`.
    pub values: Values,
    pub iterations: usize,
    pub high_functions: usize,
    pub high_gradients: usize,
    pub history: Vec<ManagedIterate>,
    /// Wall time over every session of the run, in seconds.
    pub elapsed_s: f64,
}

/// Sees the start point's evaluation and every outer iteration with its checkpoint (saved by
/// the observer, as it wishes).
pub trait ManagedObserver {
    /// The start point's high-fidelity function and gradient are done (a fresh run only; a
    /// resumed run has them in its checkpoint): its cost is then not counted in the first
    /// outer iteration's.
    fn start(&mut self, _values: &Values) {}
    fn iteration(
        &mut self,
        record: &ManagedIterate,
        checkpoint: &ManagedCheckpoint,
    ) -> Result<Control, String>;
}

impl ManagedObserver for () {
    fn iteration(&mut self, _: &ManagedIterate, _: &ManagedCheckpoint) -> Result<Control, String> {
        Ok(Control::Continue)
    }
}

/// The low fidelity corrected to agree with the high one at `xk` in values and gradients,
/// bounded by the trust-region box.
struct Corrected<'a> {
    low: &'a mut dyn Problem,
    xk: Vec<f64>,
    dv: Values,
    dg: Gradients,
    lower: Vec<f64>,
    upper: Vec<f64>,
}

impl Problem for Corrected<'_> {
    fn lower(&self) -> Vec<f64> {
        self.lower.clone()
    }
    fn upper(&self) -> Vec<f64> {
        self.upper.clone()
    }
    fn values(&mut self, x: &[f64]) -> Result<Values, EvalError> {
        let v = self.low.values(x)?;
        let s: Vec<f64> = x.iter().zip(&self.xk).map(|(a, b)| a - b).collect();
        let shift = |low: f64, d: f64, g: &[f64]| low + d + dot(g, &s);
        Ok(Values {
            f: shift(v.f, self.dv.f, &self.dg.f),
            eq: (0..v.eq.len())
                .map(|i| shift(v.eq[i], self.dv.eq[i], &self.dg.eq[i]))
                .collect(),
            ineq: (0..v.ineq.len())
                .map(|i| shift(v.ineq[i], self.dv.ineq[i], &self.dg.ineq[i]))
                .collect(),
        })
    }
    fn gradients(&mut self, x: &[f64]) -> Result<Gradients, EvalError> {
        let g = self.low.gradients(x)?;
        let add = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(a, b)| a + b).collect::<Vec<_>>();
        let rows = |a: &[Vec<f64>], b: &[Vec<f64>]| {
            a.iter().zip(b).map(|(a, b)| add(a, b)).collect::<Vec<_>>()
        };
        Ok(Gradients {
            f: add(&g.f, &self.dg.f),
            eq: rows(&g.eq, &self.dg.eq),
            ineq: rows(&g.ineq, &self.dg.ineq),
        })
    }
}

/// The high fidelity bounded by the trust-region box: where the low fidelity cannot serve, an
/// outer iteration is one SQP iteration of the high fidelity itself in the box.
struct Boxed<'a> {
    high: &'a mut dyn Problem,
    lower: Vec<f64>,
    upper: Vec<f64>,
}

impl Problem for Boxed<'_> {
    fn lower(&self) -> Vec<f64> {
        self.lower.clone()
    }
    fn upper(&self) -> Vec<f64> {
        self.upper.clone()
    }
    fn values(&mut self, x: &[f64]) -> Result<Values, EvalError> {
        self.high.values(x)
    }
    fn gradients(&mut self, x: &[f64]) -> Result<Gradients, EvalError> {
        self.high.gradients(x)
    }
}

/// `high − low`, refusing values of different shapes (the two fidelities must pose the same
/// constraints).
fn differences(
    (hv, hg): (&Values, &Gradients),
    (lv, lg): (&Values, &Gradients),
) -> Result<(Values, Gradients), SqpError> {
    if hv.eq.len() != lv.eq.len() || hv.ineq.len() != lv.ineq.len() {
        return Err(SqpError::Params(format!(
            "the two fidelities pose different constraints ({} and {} equalities, {} and {} inequalities)",
            hv.eq.len(),
            lv.eq.len(),
            hv.ineq.len(),
            lv.ineq.len()
        )));
    }
    let sub = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(a, b)| a - b).collect::<Vec<_>>();
    let rows = |a: &[Vec<f64>], b: &[Vec<f64>]| {
        a.iter().zip(b).map(|(a, b)| sub(a, b)).collect::<Vec<_>>()
    };
    Ok((
        Values {
            f: hv.f - lv.f,
            eq: sub(&hv.eq, &lv.eq),
            ineq: sub(&hv.ineq, &lv.ineq),
        },
        Gradients {
            f: sub(&hg.f, &lg.f),
            eq: rows(&hg.eq, &lg.eq),
            ineq: rows(&hg.ineq, &lg.ineq),
        },
    ))
}

/// The low fidelity's values and gradients at a point, or why it could not give them.
type LowAt = Result<(Values, Gradients), String>;

/// Keeps the last checkpoint of an inner SQP run (its merit penalty and BFGS matrix).
struct LastInner(Option<Checkpoint>);

impl Observer for LastInner {
    fn iteration(&mut self, _: &super::Iterate, c: &Checkpoint) -> Result<Control, String> {
        self.0 = Some(c.clone());
        Ok(Control::Continue)
    }
}

/// Minimizes `high` through `low` from `x0` (or from `resume`), see the module's words.
pub fn minimize_managed(
    high: &mut dyn Problem,
    low: &mut dyn Problem,
    x0: &[f64],
    params: &ManagedParams,
    problem_id: &str,
    resume: Option<ManagedCheckpoint>,
    observer: &mut dyn ManagedObserver,
) -> Result<ManagedInfo, SqpError> {
    params.validate()?;
    let (lb, ub) = (high.lower(), high.upper());
    if lb.len() != x0.len() || ub.len() != x0.len() {
        return Err(SqpError::BoundsLength {
            n: x0.len(),
            lower: lb.len(),
            upper: ub.len(),
        });
    }
    let scaling = Scaling::new(&lb, &ub, x0);
    // the clock starts before the start point's evaluation, as the SQP's does
    let started = std::time::Instant::now();
    let mut s = match resume {
        Some(c) => {
            if c.problem_id != problem_id || c.x.len() != x0.len() {
                return Err(SqpError::Checkpoint(format!(
                    "it belongs to another problem ('{}' with {} variables)",
                    c.problem_id,
                    c.x.len()
                )));
            }
            c
        }
        None => {
            let x: Vec<f64> = x0
                .iter()
                .zip(lb.iter().zip(&ub))
                .map(|(x, (l, u))| x.clamp(*l, *u))
                .collect();
            let values = high.values(&x).map_err(SqpError::Start)?;
            let gradients = high.gradients(&x).map_err(|source| SqpError::Gradient {
                iteration: 0,
                source,
            })?;
            observer.start(&values);
            ManagedCheckpoint {
                problem_id: problem_id.to_string(),
                params: params.clone(),
                x,
                values,
                gradients,
                radius: params.initial_radius,
                penalty: 0.0,
                hessian: None,
                history: Vec::new(),
                high_functions: 1,
                high_gradients: 1,
                elapsed_s: 0.0,
            }
        }
    };
    let elapsed_before = s.elapsed_s;
    s.params = params.clone();
    let inner_params = SqpParams {
        tolerance: params.tolerance,
        ..params.inner.clone()
    };
    let mut low_at: Option<(Vec<f64>, LowAt)> = None;
    loop {
        let iteration = s.history.len();
        let finish = |s: &ManagedCheckpoint, converged: bool, message: String| ManagedInfo {
            converged,
            message,
            x: s.x.clone(),
            values: s.values.clone(),
            iterations: s.history.len(),
            high_functions: s.high_functions,
            high_gradients: s.high_gradients,
            history: s.history.clone(),
            elapsed_s: elapsed_before + started.elapsed().as_secs_f64(),
        };
        if iteration >= params.max_iterations {
            return Ok(finish(
                &s,
                false,
                format!("iteration limit {} reached", params.max_iterations),
            ));
        }
        // the low fidelity at x_k, kept across rejected steps (which leave x_k where it was)
        let xk = s.x.clone();
        let at = match low_at.take() {
            Some((x, at)) if x == xk => at,
            _ => low
                .values(&xk)
                .and_then(|v| low.gradients(&xk).map(|g| (v, g)))
                .map_err(|e| format!("{e:#}")),
        };
        // the trust-region box in the scaled variables, within the bounds
        let (lower, upper): (Vec<f64>, Vec<f64>) = (0..s.x.len())
            .map(|i| {
                let w = s.radius * scaling.scale()[i];
                ((s.x[i] - w).max(lb[i]), (s.x[i] + w).min(ub[i]))
            })
            .unzip();
        // the inner runs are scaled by the bounds, not by the trust region (the KKT test and the
        // carried BFGS matrix then mean the same in every box)
        let solve = |problem: &mut dyn Problem, params, point: Option<PointEvaluation>| {
            let mut last = LastInner(None);
            let mut ex = Executor::new(params, "inner")
                .scaling(scaling.clone())
                .initial_hessian(s.hessian.clone());
            if let Some(p) = point {
                ex = ex.evaluated_at(p);
            }
            let inner = ex.observe(&mut last).run(problem, &s.x)?;
            let step = inner
                .x
                .iter()
                .zip(&s.x)
                .zip(scaling.scale())
                .fold(0.0f64, |a, ((xc, xk), sc)| a.max(((xc - xk) / sc).abs()));
            Ok::<_, SqpError>((inner, last.0, step))
        };
        let corrected_step = |low: &mut dyn Problem, (dv, dg): (Values, Gradients)| {
            let mut corrected = Corrected {
                low,
                xk: s.x.clone(),
                dv,
                dg,
                lower: lower.clone(),
                upper: upper.clone(),
            };
            solve(&mut corrected, inner_params.clone(), None)
        };
        // one SQP iteration of the high fidelity in the box, started from what x_k's
        // evaluation gave (its line search evaluates the high fidelity; its BFGS update learns
        // the high fidelity's curvature)
        let high_step = |high: &mut dyn Problem| {
            let mut boxed = Boxed {
                high,
                lower: lower.clone(),
                upper: upper.clone(),
            };
            let params = SqpParams {
                max_iterations: 1,
                ..inner_params.clone()
            };
            let point = PointEvaluation {
                values: s.values.clone(),
                gradients: s.gradients.clone(),
            };
            solve(&mut boxed, params, Some(point))
        };
        // where the low fidelity cannot be evaluated at x_k, or its corrected problem ends
        // without converging short of a tenth of the box (its trial points failing: a low
        // fidelity that flutters where the high one does not), the outer iteration is the
        // high fidelity's own SQP iteration in the box
        let (inner, last, step, fallback) = match &at {
            Ok((lv, lg)) => {
                let d = differences((&s.values, &s.gradients), (lv, lg))?;
                let (inner, last, step) = corrected_step(&mut *low, d)?;
                if !inner.converged && step < 0.1 * s.radius {
                    let why = format!("the low fidelity's problem: {}", inner.message);
                    let (inner, last, step) = high_step(&mut *high)?;
                    (inner, last, step, Some(why))
                } else {
                    (inner, last, step, None)
                }
            }
            Err(e) => {
                let why = format!("the low fidelity fails at the point: {e}");
                let (inner, last, step) = high_step(&mut *high)?;
                (inner, last, step, Some(why))
            }
        };
        low_at = Some((xk, at));
        let mut record = ManagedIterate {
            iteration,
            x: s.x.clone(),
            values: s.values.clone(),
            violation: violation(&s.values),
            kkt: inner.history.first().map_or(f64::NAN, |h| h.kkt),
            inner_outcome: match &fallback {
                Some(why) => format!(
                    "{why}; instead the high fidelity's SQP step: {}",
                    inner.message
                ),
                None => inner.message.clone(),
            },
            radius: s.radius,
            ratio: None,
            accepted: false,
            step,
            inner_iterations: inner.iterations,
            high_functions: s.high_functions,
            high_gradients: s.high_gradients,
        };
        if inner.converged && inner.iterations == 0 {
            // the corrected problem's KKT test at x_k is the high fidelity's: values and
            // gradients agree there
            s.history.push(record);
            return Ok(finish(
                &s,
                true,
                "KKT conditions of the high fidelity satisfied to the tolerance".into(),
            ));
        }
        if let Some(c) = &last {
            s.penalty = s.penalty.max(c.penalty);
            s.hessian = Some(c.hessian.clone());
        }
        if fallback.is_some() {
            // the high fidelity's own line search accepted the point (or found none)
            s.high_functions += inner.evaluations;
            record.high_functions = s.high_functions;
            match last.and_then(|c| c.point) {
                Some(p) if inner.iterations > 0 && step > 0.0 => {
                    s.high_gradients += 1;
                    record.high_gradients = s.high_gradients;
                    record.accepted = true;
                    s.x = inner.x.clone();
                    s.values = p.values;
                    s.gradients = p.gradients;
                    if step >= 0.9 * s.radius {
                        s.radius = (2.0 * s.radius).min(1.0);
                    }
                }
                _ => s.radius *= 0.5,
            }
        } else {
            // a step that restores feasibility at the objective's expense must show as a decrease
            // of the merit: the penalty then weighs the violation removed at least twice the
            // objective's rise (the predicted decrease is then at least that rise)
            let feasibility_gain = infeasibility_sum(&s.values) - infeasibility_sum(&inner.values);
            let objective_rise = inner.values.f - s.values.f;
            if feasibility_gain > 0.0 && objective_rise > 0.0 {
                s.penalty = s.penalty.max(2.0 * objective_rise / feasibility_gain);
            }
            let penalty = s.penalty;
            let phi = |v: &Values| v.f + penalty * infeasibility_sum(v);
            let predicted = phi(&s.values) - phi(&inner.values);
            let scale_phi = phi(&s.values).abs().max(1.0);
            if predicted > 1e-14 * scale_phi {
                s.high_functions += 1;
                record.high_functions = s.high_functions;
                if let Ok(vc) = high.values(&inner.x) {
                    let ratio = (phi(&s.values) - phi(&vc)) / predicted;
                    record.ratio = Some(ratio);
                    if ratio >= 0.1 {
                        let gc = high
                            .gradients(&inner.x)
                            .map_err(|source| SqpError::Gradient { iteration, source })?;
                        s.high_gradients += 1;
                        record.high_gradients = s.high_gradients;
                        record.accepted = true;
                        s.x = inner.x.clone();
                        s.values = vc;
                        s.gradients = gc;
                        if ratio > 0.75 && step >= 0.9 * s.radius {
                            s.radius = (2.0 * s.radius).min(1.0);
                        } else if ratio < 0.25 {
                            s.radius = 0.5 * step;
                        }
                    }
                }
            }
            if !record.accepted {
                // a corrected problem that made no step is tried again in a smaller box
                s.radius = 0.5
                    * if step > 0.0 {
                        step.min(s.radius)
                    } else {
                        s.radius
                    };
            }
        }
        s.history.push(record.clone());
        s.elapsed_s = elapsed_before + started.elapsed().as_secs_f64();
        if observer
            .iteration(&record, &s)
            .map_err(SqpError::Observer)?
            == Control::Stop
        {
            return Ok(finish(&s, false, "stopped by the observer".into()));
        }
        let small_step = record.accepted && step < params.tolerance;
        if small_step && violation(&s.values) < params.tolerance {
            return Ok(finish(
                &s,
                true,
                "the corrected problem's step fell below the tolerance at a feasible point".into(),
            ));
        }
        if s.radius < params.min_radius {
            let feasible = violation(&s.values) < params.tolerance;
            return Ok(finish(
                &s,
                false,
                format!(
                    "the trust region shrank below {} (the corrected low fidelity predicts no step the high fidelity confirms){}",
                    params.min_radius,
                    if feasible { "" } else { "; the point is infeasible" }
                ),
            ));
        }
    }
}
