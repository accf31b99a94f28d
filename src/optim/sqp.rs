//! The SQP iteration (see the module documentation of `optim`).

use super::qp::{self, QpData};
use super::{
    Checkpoint, Gradients, Iterate, PointEvaluation, Problem, SqpError, SqpInfo, SqpParams,
    SqpStatus, Values,
};

/// What an observer tells the run after an iteration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Control {
    Continue,
    /// End the run here (not converged; the last checkpoint continues it).
    Stop,
}

/// Sees every iteration with the checkpoint to continue from it (progress bars, logs, a user's
/// stop). Fallible, as argmin's observers are: an error ends the run with
/// [`SqpError::Observer`].
pub trait Observer {
    fn iteration(&mut self, iterate: &Iterate, checkpoint: &Checkpoint) -> Result<Control, String>;
}

/// An observer that does nothing.
impl Observer for () {
    fn iteration(&mut self, _: &Iterate, _: &Checkpoint) -> Result<Control, String> {
        Ok(Control::Continue)
    }
}

/// Where the checkpoint of every iteration is kept: a plug-in of its own beside the observers
/// (a file written atomically, say). An error ends the run with [`SqpError::Checkpoint`].
pub trait Checkpointing {
    fn save(&mut self, checkpoint: &Checkpoint) -> Result<(), String>;
}

/// No checkpoints.
impl Checkpointing for () {
    fn save(&mut self, _: &Checkpoint) -> Result<(), String> {
        Ok(())
    }
}

/// Solves the QP subproblems: clarabel by default ([`Clarabel`]); a plug-in so that a test can
/// hand the run a subproblem that fails and watch it recover.
pub trait SubproblemSolver {
    fn solve(&mut self, data: &QpData<'_>) -> Result<qp::QpStep, qp::QpError>;
}

/// The subproblems on clarabel ([`qp::solve`]).
pub struct Clarabel;

impl SubproblemSolver for Clarabel {
    fn solve(&mut self, data: &QpData<'_>) -> Result<qp::QpStep, qp::QpError> {
        qp::solve(data)
    }
}

/// The recoveries tried, in order, when a subproblem cannot be solved, each from the original
/// data: the BFGS matrix reset to the identity (an ill-conditioned quasi-Newton matrix is the
/// usual cause), then clarabel's tolerant settings as well, then also a step no longer than
/// [`SHORT_STEP`] in every scaled variable (a trust region that keeps the subproblem bounded
/// and well scaled).
const RECOVERIES: [(&str, bool, bool, bool); 3] = [
    ("the BFGS matrix reset to the identity", true, false, false),
    (
        "the BFGS matrix reset and clarabel's tolerant settings",
        true,
        true,
        false,
    ),
    (
        "the BFGS matrix reset, tolerant settings and a step of at most 0.05 in each scaled variable",
        true,
        true,
        true,
    ),
];

/// The longest step in a scaled variable in the last recovery.
const SHORT_STEP: f64 = 0.05;

/// The SQP run: settings, the problem's identity (a checkpoint of another problem is refused),
/// an optional checkpoint to continue, observers and a checkpoint store.
pub struct Executor<'a> {
    params: SqpParams,
    problem_id: String,
    resume: Option<Checkpoint>,
    hessian: Option<Vec<Vec<f64>>>,
    observers: Vec<&'a mut dyn Observer>,
    checkpoints: Option<&'a mut dyn Checkpointing>,
    subproblems: Option<&'a mut dyn SubproblemSolver>,
    scaling: Option<Scaling>,
    point: Option<PointEvaluation>,
}

impl<'a> Executor<'a> {
    pub fn new(params: SqpParams, problem_id: &str) -> Self {
        Self {
            params,
            problem_id: problem_id.to_string(),
            resume: None,
            hessian: None,
            observers: Vec::new(),
            checkpoints: None,
            subproblems: None,
            scaling: None,
            point: None,
        }
    }

    /// Scales the variables by `scaling` instead of the problem's own bounds (the model
    /// management's corrected problems: bounded by a trust region, scaled by the bounds).
    pub(super) fn scaling(mut self, scaling: Scaling) -> Self {
        self.scaling = Some(scaling);
        self
    }

    /// Starts from the values and gradients at `x0` already evaluated (the model management's
    /// point x_k): the fresh start does not evaluate them again. Ignored when `x0` lies outside
    /// the bounds (the start is then another point) and when resuming.
    pub(super) fn evaluated_at(mut self, point: PointEvaluation) -> Self {
        self.point = Some(point);
        self
    }

    /// Solves the QP subproblems with `solver` instead of clarabel.
    pub fn subproblem_solver(mut self, solver: &'a mut dyn SubproblemSolver) -> Self {
        self.subproblems = Some(solver);
        self
    }

    /// Start the BFGS approximation from `hessian` (of the Lagrangian in the scaled variables
    /// z = (x − lower) / (upper − lower), e.g. another run's final one) instead of the identity.
    /// Ignored when resuming: the checkpoint holds its own.
    pub fn initial_hessian(mut self, hessian: Option<Vec<Vec<f64>>>) -> Self {
        self.hessian = hessian;
        self
    }

    /// Continue from `checkpoint` (when given) instead of starting afresh.
    pub fn resume(mut self, checkpoint: Option<Checkpoint>) -> Self {
        self.resume = checkpoint;
        self
    }

    /// Adds an observer (called in the order added).
    pub fn observe(mut self, observer: &'a mut dyn Observer) -> Self {
        self.observers.push(observer);
        self
    }

    /// Keeps every iteration's checkpoint in `store` (saved before the observers see it).
    pub fn checkpoint(mut self, store: &'a mut dyn Checkpointing) -> Self {
        self.checkpoints = Some(store);
        self
    }

    /// Runs the SQP on `problem` from `x0` (or from the checkpoint).
    pub fn run(self, problem: &mut dyn Problem, x0: &[f64]) -> Result<SqpInfo, SqpError> {
        run(self, problem, x0)
    }
}

/// Runs the SQP from `x0`, or continues a checkpoint, with one observer and no checkpoint store.
pub fn minimize(
    problem: &mut dyn Problem,
    x0: &[f64],
    params: &SqpParams,
    problem_id: &str,
    resume: Option<Checkpoint>,
    observer: &mut dyn Observer,
) -> Result<SqpInfo, SqpError> {
    Executor::new(params.clone(), problem_id)
        .resume(resume)
        .observe(observer)
        .run(problem, x0)
}

/// The optimizer's affine variable scaling x = offset + scale ∘ z: z ∈ [0, 1] between finite
/// bounds; a fixed variable (lb = ub) scaled by max(|lb|, 1), an unbounded one by max(|x0|, 1).
/// The one scaling of the design variables: a BFGS matrix carried from one run to another is
/// rescaled by it ([`Scaling::rescale_hessian`]).
#[derive(Clone, Debug)]
pub struct Scaling {
    offset: Vec<f64>,
    scale: Vec<f64>,
}

impl Scaling {
    /// The scaling of a problem with bounds `lb`, `ub` started at `x0`.
    pub fn new(lb: &[f64], ub: &[f64], x0: &[f64]) -> Self {
        let (mut offset, mut scale) = (Vec::new(), Vec::new());
        for i in 0..x0.len() {
            if lb[i].is_finite() && ub[i].is_finite() && ub[i] > lb[i] {
                offset.push(lb[i]);
                scale.push(ub[i] - lb[i]);
            } else if lb[i].is_finite() && lb[i] == ub[i] {
                offset.push(0.0);
                scale.push(lb[i].abs().max(1.0));
            } else {
                offset.push(0.0);
                scale.push(x0[i].abs().max(1.0));
            }
        }
        Self { offset, scale }
    }

    /// The scale of each variable (x units per z unit).
    pub fn scale(&self) -> &[f64] {
        &self.scale
    }

    /// A Hessian in the scaled variables of `from` expressed in those of `self`: with
    /// x = o + s ∘ z, H_z = S H_x S, so H_self = D H_from D with D = s_self / s_from.
    pub fn rescale_hessian(&self, h: &[Vec<f64>], from: &Scaling) -> Vec<Vec<f64>> {
        let d: Vec<f64> = self
            .scale
            .iter()
            .zip(&from.scale)
            .map(|(a, b)| a / b)
            .collect();
        h.iter()
            .enumerate()
            .map(|(i, row)| {
                row.iter()
                    .enumerate()
                    .map(|(j, v)| d[i] * d[j] * v)
                    .collect()
            })
            .collect()
    }
    fn x(&self, z: &[f64]) -> Vec<f64> {
        z.iter()
            .zip(self.offset.iter().zip(&self.scale))
            .map(|(z, (o, s))| o + s * z)
            .collect()
    }
    pub(super) fn z(&self, x: &[f64]) -> Vec<f64> {
        x.iter()
            .zip(self.offset.iter().zip(&self.scale))
            .map(|(x, (o, s))| (x - o) / s)
            .collect()
    }
    fn grad(&self, g: &[f64]) -> Vec<f64> {
        g.iter().zip(&self.scale).map(|(g, s)| g * s).collect()
    }
}

pub(super) fn violation(v: &Values) -> f64 {
    v.eq.iter()
        .map(|h| h.abs())
        .chain(v.ineq.iter().map(|c| c.max(0.0)))
        .fold(0.0, f64::max)
}

pub(super) fn infeasibility_sum(v: &Values) -> f64 {
    v.eq.iter().map(|h| h.abs()).sum::<f64>() + v.ineq.iter().map(|c| c.max(0.0)).sum::<f64>()
}

pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// ∇L in scaled variables for multipliers (λ_E, λ_I).
fn lagrangian_grad(s: &Scaling, g: &Gradients, le: &[f64], li: &[f64]) -> Vec<f64> {
    let mut out = s.grad(&g.f);
    for (row, l) in g.eq.iter().zip(le).chain(g.ineq.iter().zip(li)) {
        for (o, v) in out.iter_mut().zip(s.grad(row)) {
            *o += l * v;
        }
    }
    out
}

/// The SQP iteration of an [`Executor`].
fn run(ex: Executor<'_>, problem: &mut dyn Problem, x0: &[f64]) -> Result<SqpInfo, SqpError> {
    let Executor {
        params,
        problem_id,
        resume,
        hessian,
        mut observers,
        mut checkpoints,
        subproblems,
        scaling,
        point,
    } = ex;
    let mut clarabel = Clarabel;
    let solver: &mut dyn SubproblemSolver = match subproblems {
        Some(s) => s,
        None => &mut clarabel,
    };
    let (params, problem_id) = (&params, problem_id.as_str());
    params.validate()?;
    let (lb, ub) = (problem.lower(), problem.upper());
    check_bounds(&lb, &ub, x0.len())?;
    let scaling = scaling.unwrap_or_else(|| Scaling::new(&lb, &ub, x0));
    let started = std::time::Instant::now();
    let start = match resume {
        Some(c) => Start::resumed(c, problem, params, problem_id, x0.len())?,
        None => {
            let start = Start::fresh(x0, &scaling, (&lb, &ub), hessian)?;
            let at_x0 = start.z == scaling.z(x0);
            Start {
                point: point.filter(|p| at_x0 && fits(p, x0.len())),
                ..start
            }
        }
    };
    let elapsed_before = start.elapsed_s;
    let elapsed = || elapsed_before + started.elapsed().as_secs_f64();
    let mut state = SqpState::evaluated(start, problem, &scaling)?;
    loop {
        let (status, message) = state.iterate(problem, solver, params, &scaling, (&lb, &ub))?;
        match status {
            SqpStatus::StepTaken => {}
            SqpStatus::Converged
            | SqpStatus::IterationLimit
            | SqpStatus::LineSearchStalled { .. } => {
                let converged = matches!(
                    status,
                    SqpStatus::Converged | SqpStatus::LineSearchStalled { converged: true }
                );
                return Ok(state.finish(converged, status, message, &scaling, elapsed()));
            }
            SqpStatus::SubproblemFailed | SqpStatus::GradientsFailed => {
                // a failed subproblem stops the checkpoint too: `--resume` then says why at once
                if status == SqpStatus::SubproblemFailed {
                    let stopped = state.checkpoint(
                        problem_id,
                        params,
                        elapsed(),
                        problem.state(),
                        Some(message.clone()),
                    );
                    save(&mut checkpoints, &stopped)?;
                }
                return Ok(state.stop_at_best(status, message, elapsed(), params.tolerance));
            }
            SqpStatus::Stopped => unreachable!("only the executor stops a run"),
        }
        let checkpoint = state.checkpoint(problem_id, params, elapsed(), problem.state(), None);
        save(&mut checkpoints, &checkpoint)?;
        if observe(&mut observers, &state, &checkpoint)? == Control::Stop {
            let elapsed_s = checkpoint.elapsed_s;
            return Ok(state.finish(
                false,
                SqpStatus::Stopped,
                "stopped by the observer".into(),
                &scaling,
                elapsed_s,
            ));
        }
    }
}

/// Refuses bounds of the wrong length or with a lower bound above its upper one.
fn check_bounds(lb: &[f64], ub: &[f64], n: usize) -> Result<(), SqpError> {
    if lb.len() != n || ub.len() != n {
        return Err(SqpError::BoundsLength {
            n,
            lower: lb.len(),
            upper: ub.len(),
        });
    }
    for i in 0..n {
        if !(lb[i] <= ub[i]) {
            return Err(SqpError::InfeasibleBounds {
                index: i,
                lower: lb[i],
                upper: ub[i],
            });
        }
    }
    Ok(())
}

/// Saves a checkpoint in the store, if the run keeps one.
fn save(
    store: &mut Option<&mut dyn Checkpointing>,
    checkpoint: &Checkpoint,
) -> Result<(), SqpError> {
    match store {
        Some(store) => store
            .save(checkpoint)
            .map_err(|e| SqpError::Checkpoint(format!("cannot save it: {e}"))),
        None => Ok(()),
    }
}

/// Shows the record of the point just left to every observer (all of them, even after one asks
/// to stop); stop when any asked to.
fn observe(
    observers: &mut [&mut dyn Observer],
    state: &SqpState,
    checkpoint: &Checkpoint,
) -> Result<Control, SqpError> {
    let record = state.history.last().expect("the point left");
    let mut control = Control::Continue;
    for o in observers.iter_mut() {
        if o.iteration(record, checkpoint)
            .map_err(SqpError::Observer)?
            == Control::Stop
        {
            control = Control::Stop;
        }
    }
    Ok(control)
}

/// Where a run starts, before its point is evaluated: a fresh point or a checkpoint's.
struct Start {
    z: Vec<f64>,
    hess: Vec<Vec<f64>>,
    penalty: f64,
    history: Vec<Iterate>,
    iteration: usize,
    evaluations: usize,
    /// Wall time of the sessions before this one.
    elapsed_s: f64,
    /// The values and gradients at `z` a checkpoint kept (none: evaluate the point).
    point: Option<PointEvaluation>,
}

impl Start {
    /// A checkpoint of this problem, written with these settings (the iteration limit may be
    /// raised to continue a run that reached it) by a run that did not stop for good; the
    /// problem's own records restored from it.
    fn resumed(
        c: Checkpoint,
        problem: &mut dyn Problem,
        params: &SqpParams,
        problem_id: &str,
        n: usize,
    ) -> Result<Self, SqpError> {
        if c.problem_id != problem_id || c.z.len() != n || c.hessian.len() != n {
            return Err(SqpError::Checkpoint(format!(
                "it belongs to another problem ('{}' with {} variables, this is '{problem_id}' with {n})",
                c.problem_id,
                c.z.len()
            )));
        }
        // the settings that only decide when to stop or what to accept from here on may change
        let same_settings = SqpParams {
            max_iterations: params.max_iterations,
            tolerance: params.tolerance,
            nonmonotone_memory: params.nonmonotone_memory,
            ..c.params.clone()
        } == *params;
        if !same_settings {
            return Err(SqpError::Checkpoint(
                "it was written with other optimizer settings".into(),
            ));
        }
        if let Some(reason) = &c.stopped {
            return Err(SqpError::Checkpoint(format!(
                "the run it belongs to stopped at iteration {} because {reason}; every recovery was tried there, so resuming would stop the same way: change the study (bounds, constraints, starting point) and run without --resume",
                c.iteration
            )));
        }
        problem
            .restore(&c.problem_state)
            .map_err(|e| SqpError::Checkpoint(format!("the problem's records: {e:#}")))?;
        Ok(Self {
            z: c.z,
            hess: c.hessian,
            penalty: c.penalty,
            history: c.history,
            iteration: c.iteration,
            evaluations: c.evaluations,
            elapsed_s: c.elapsed_s,
            point: c.point.filter(|p| fits(p, n)),
        })
    }

    /// `x0` moved inside the bounds, with the given BFGS matrix (checked) or the identity.
    fn fresh(
        x0: &[f64],
        scaling: &Scaling,
        (lb, ub): (&[f64], &[f64]),
        hessian: Option<Vec<Vec<f64>>>,
    ) -> Result<Self, SqpError> {
        let z: Vec<f64> = scaling
            .z(x0)
            .iter()
            .enumerate()
            .map(|(i, v)| {
                if lb[i].is_finite() && ub[i].is_finite() {
                    v.clamp(0.0, 1.0)
                } else {
                    *v
                }
            })
            .collect();
        let n = z.len();
        let hess = match hessian {
            Some(h) => checked_hessian(h, n)?,
            None => identity(n),
        };
        Ok(Self {
            z,
            hess,
            penalty: 0.0,
            history: Vec::new(),
            iteration: 0,
            evaluations: 0,
            elapsed_s: 0.0,
            point: None,
        })
    }
}

/// A kept point evaluation that fits `n` variables: finite, a gradient row of length `n` for the
/// objective and for every constraint (else the point is evaluated again).
fn fits(p: &PointEvaluation, n: usize) -> bool {
    let (v, g) = (&p.values, &p.gradients);
    let rows_fit = |rows: &[Vec<f64>], count: usize| {
        rows.len() == count && rows.iter().all(|r| r.len() == n && finite(r))
    };
    v.f.is_finite()
        && finite(&v.eq)
        && finite(&v.ineq)
        && g.f.len() == n
        && finite(&g.f)
        && rows_fit(&g.eq, v.eq.len())
        && rows_fit(&g.ineq, v.ineq.len())
}

/// Every entry finite.
fn finite(v: &[f64]) -> bool {
    v.iter().all(|a| a.is_finite())
}

/// A given initial BFGS matrix: n × n, finite, symmetric to round-off, with a positive diagonal.
fn checked_hessian(h: Vec<Vec<f64>>, n: usize) -> Result<Vec<Vec<f64>>, SqpError> {
    let square = h.len() == n && h.iter().all(|r| r.len() == n);
    if !square {
        return Err(SqpError::InitialHessian(format!(
            "need {n} × {n} entries for {n} design variables (got {} rows)",
            h.len()
        )));
    }
    let symmetric = (0..n).all(|i| {
        (0..n).all(|j| {
            h[i][j].is_finite()
                && (h[i][j] - h[j][i]).abs() <= 1e-10 * (h[i][i].abs() + h[j][j].abs())
        })
    });
    if !symmetric || (0..n).any(|i| !(h[i][i] > 0.0)) {
        return Err(SqpError::InitialHessian(
            "must be finite and symmetric with a positive diagonal".into(),
        ));
    }
    Ok(h)
}

/// The state of an SQP run between iterations: the scaled iterate with its values and
/// gradients, the BFGS matrix, the merit penalty, the history and the counters.
struct SqpState {
    z: Vec<f64>,
    hess: Vec<Vec<f64>>,
    penalty: f64,
    history: Vec<Iterate>,
    iteration: usize,
    evaluations: usize,
    values: Values,
    grads: Gradients,
}

/// The subproblem's data at the current point, in the scaled variables: the objective's
/// gradient, the constraint Jacobians and the step bounds.
struct Linearization {
    g: Vec<f64>,
    eq_jac: Vec<Vec<f64>>,
    ineq_jac: Vec<Vec<f64>>,
    lower: Vec<f64>,
    upper: Vec<f64>,
}

impl Linearization {
    fn at(z: &[f64], grads: &Gradients, scaling: &Scaling, (lb, ub): (&[f64], &[f64])) -> Self {
        let x = scaling.x(z);
        let step_bound = |b: f64, i: usize, infinite: f64| {
            if b.is_finite() {
                (b - x[i]) / scaling.scale[i]
            } else {
                infinite
            }
        };
        Self {
            g: scaling.grad(&grads.f),
            eq_jac: grads.eq.iter().map(|r| scaling.grad(r)).collect(),
            ineq_jac: grads.ineq.iter().map(|r| scaling.grad(r)).collect(),
            lower: (0..z.len())
                .map(|i| step_bound(lb[i], i, f64::NEG_INFINITY))
                .collect(),
            upper: (0..z.len())
                .map(|i| step_bound(ub[i], i, f64::INFINITY))
                .collect(),
        }
    }

    /// The QP with this linearization, the BFGS matrix and the constraint values `eq`, `ineq`
    /// (the point's, or shifted ones for a second-order correction).
    fn qp<'a>(
        &'a self,
        hessian: &'a [Vec<f64>],
        eq: &'a [f64],
        ineq: &'a [f64],
        params: &SqpParams,
    ) -> QpData<'a> {
        QpData {
            hessian,
            grad: &self.g,
            eq,
            eq_jac: &self.eq_jac,
            ineq,
            ineq_jac: &self.ineq_jac,
            lower: &self.lower,
            upper: &self.upper,
            rho: params.elastic_penalty,
            tolerant: false,
        }
    }
}

/// The KKT measure of a QP step: |gᵀd| + Σ|λ_eq h| + Σ|λ_ineq c|.
fn kkt_measure(g: &[f64], step: &qp::QpStep, values: &Values) -> f64 {
    dot(g, &step.d).abs()
        + step
            .lambda_eq
            .iter()
            .zip(&values.eq)
            .map(|(l, h)| (l * h).abs())
            .sum::<f64>()
        + step
            .lambda_ineq
            .iter()
            .zip(&values.ineq)
            .map(|(l, c)| (l * c).abs())
            .sum::<f64>()
}

/// Where a line search ended: the accepted point and its values (none when it stalled), its
/// step length, and the trial points that could not be evaluated (their count, the last reason).
struct LineSearch {
    accepted: Option<(Vec<f64>, Values)>,
    alpha: f64,
    failed: usize,
    last_failure: Option<String>,
}

/// Powell's damped BFGS update of `hess` with the step `s` and the change `y` of the
/// Lagrangian's gradient (y is damped towards B s when sᵀy < 0.2 sᵀBs, keeping B positive).
fn damped_bfgs(hess: &mut [Vec<f64>], s: &[f64], mut y: Vec<f64>) {
    let n = s.len();
    let bs: Vec<f64> = (0..n).map(|i| dot(&hess[i], s)).collect();
    let sbs = dot(s, &bs);
    let sy = dot(s, &y);
    if sbs > 1e-300 {
        if sy < 0.2 * sbs {
            let theta = 0.8 * sbs / (sbs - sy);
            for i in 0..n {
                y[i] = theta * y[i] + (1.0 - theta) * bs[i];
            }
        }
        let sy = dot(s, &y);
        for i in 0..n {
            for j in 0..n {
                hess[i][j] += y[i] * y[j] / sy - bs[i] * bs[j] / sbs;
            }
        }
    }
}

impl SqpState {
    /// The run's state at its start, with the values and gradients of its point.
    fn evaluated(
        start: Start,
        problem: &mut dyn Problem,
        scaling: &Scaling,
    ) -> Result<Self, SqpError> {
        let (values, grads, evaluations) = match start.point {
            Some(p) => (p.values, p.gradients, start.evaluations),
            None => {
                let values = problem
                    .values(&scaling.x(&start.z))
                    .map_err(SqpError::Start)?;
                let grads = problem.gradients(&scaling.x(&start.z)).map_err(|source| {
                    SqpError::Gradient {
                        iteration: start.iteration,
                        source,
                    }
                })?;
                (values, grads, start.evaluations + 1)
            }
        };
        Ok(Self {
            z: start.z,
            hess: start.hess,
            penalty: start.penalty,
            history: start.history,
            iteration: start.iteration,
            evaluations,
            values,
            grads,
        })
    }

    /// The checkpoint of the run as it stands, with why it stopped (if it did).
    fn checkpoint(
        &self,
        problem_id: &str,
        params: &SqpParams,
        elapsed_s: f64,
        problem_state: serde_json::Value,
        stopped: Option<String>,
    ) -> Checkpoint {
        Checkpoint {
            problem_id: problem_id.to_string(),
            params: params.clone(),
            iteration: self.iteration,
            evaluations: self.evaluations,
            z: self.z.clone(),
            hessian: self.hess.clone(),
            penalty: self.penalty,
            history: self.history.clone(),
            elapsed_s,
            problem_state,
            stopped,
            point: Some(PointEvaluation {
                values: self.values.clone(),
                gradients: self.grads.clone(),
            }),
        }
    }

    /// The run's end at the current point.
    fn finish(
        self,
        converged: bool,
        status: SqpStatus,
        message: String,
        scaling: &Scaling,
        elapsed_s: f64,
    ) -> SqpInfo {
        SqpInfo {
            converged,
            status,
            iterations: self.iteration,
            evaluations: self.evaluations,
            message,
            x: scaling.x(&self.z),
            values: self.values,
            history: self.history,
            elapsed_s,
        }
    }

    /// The run's end where it cannot go on: at the best feasible iterate of its history.
    fn stop_at_best(
        self,
        status: SqpStatus,
        message: String,
        elapsed_s: f64,
        tolerance: f64,
    ) -> SqpInfo {
        let mut info = stop_at_best(
            message,
            self.history,
            self.iteration,
            self.evaluations,
            elapsed_s,
            tolerance,
        );
        info.status = status;
        info
    }

    /// The record of the current point where no subproblem could be solved (its KKT measure
    /// the previous iteration's).
    fn record_failed_subproblem(&mut self, scaling: &Scaling) {
        let kkt = self.history.last().map_or(f64::MAX, |it| it.kkt);
        self.history.push(Iterate {
            iteration: self.iteration,
            x: scaling.x(&self.z),
            values: self.values.clone(),
            violation: violation(&self.values),
            kkt,
            step: 0.0,
            evaluations: self.evaluations,
            alpha: 0.0,
            failed_trials: 0,
            trial_failure: None,
            recovery: None,
        });
    }

    /// Raises the merit penalty above every multiplier of the step, letting it relax towards
    /// that bound again (Powell's rule: a penalty stuck at early, large multipliers makes the
    /// merit reject good steps).
    fn update_penalty(&mut self, step: &qp::QpStep) -> f64 {
        let lam_max = step
            .lambda_eq
            .iter()
            .chain(&step.lambda_ineq)
            .fold(0.0f64, |a, l| a.max(l.abs()));
        let needed = 1.1 * lam_max + 1e-8;
        self.penalty = needed.max(0.5 * (self.penalty + needed));
        self.penalty
    }

    /// Backtracking on the ℓ1 merit φ = f + penalty · Σ violation along the QP step (Armijo,
    /// halving down to `min_step`), with a second-order correction of a rejected full step (the
    /// Maratos effect: the curvature of the constraints raises the violation along the QP
    /// step; the QP is solved again with its constraints shifted by the trial point's values).
    /// The Armijo test is against the largest merit of the last `nonmonotone_memory` accepted
    /// points, each with today's penalty (Panier & Tits 1991); with a memory of 1 that is φ
    /// at the current point.
    #[allow(clippy::too_many_arguments)]
    fn line_search(
        &mut self,
        problem: &mut dyn Problem,
        solver: &mut dyn SubproblemSolver,
        params: &SqpParams,
        scaling: &Scaling,
        lin: &Linearization,
        step: &qp::QpStep,
        penalty: f64,
    ) -> LineSearch {
        let phi = |v: &Values| v.f + penalty * infeasibility_sum(v);
        let phi0 = phi(&self.values);
        // the history ends with the current point's record
        let phi_ref = self
            .history
            .iter()
            .rev()
            .take(params.nonmonotone_memory)
            .map(|it| phi(&it.values))
            .fold(phi0, f64::max);
        let deriv =
            dot(&lin.g, &step.d) - penalty * (infeasibility_sum(&self.values) - step.elastic);
        let z = &self.z;
        let mut alpha = 1.0;
        let (mut failed, mut last_failure) = (0usize, None);
        let accepted = loop {
            let zt: Vec<f64> = z.iter().zip(&step.d).map(|(a, b)| a + alpha * b).collect();
            let trial = problem.values(&scaling.x(&zt));
            self.evaluations += 1;
            match trial {
                Ok(v) => {
                    if phi(&v) <= phi_ref + 1e-4 * alpha * deriv.min(0.0) {
                        break Some((zt, v));
                    }
                    if alpha == 1.0 {
                        let shift = |c: &[f64], jac: &[Vec<f64>]| -> Vec<f64> {
                            c.iter()
                                .zip(jac)
                                .map(|(c, row)| c - dot(row, &step.d))
                                .collect()
                        };
                        let (eq_soc, ineq_soc) =
                            (shift(&v.eq, &lin.eq_jac), shift(&v.ineq, &lin.ineq_jac));
                        if let Ok(soc) =
                            solver.solve(&lin.qp(&self.hess, &eq_soc, &ineq_soc, params))
                        {
                            let zc: Vec<f64> = z.iter().zip(&soc.d).map(|(a, b)| a + b).collect();
                            self.evaluations += 1;
                            match problem.values(&scaling.x(&zc)) {
                                Ok(vc) if phi(&vc) <= phi_ref + 1e-4 * deriv.min(0.0) => {
                                    break Some((zc, vc));
                                }
                                Ok(_) => {}
                                Err(reason) => {
                                    failed += 1;
                                    last_failure = Some(format!("{reason:#}"));
                                }
                            }
                        }
                    }
                }
                Err(reason) => {
                    failed += 1;
                    last_failure = Some(format!("{reason:#}"));
                }
            }
            alpha *= 0.5;
            if alpha < params.min_step {
                break None;
            }
        };
        LineSearch {
            accepted,
            alpha,
            failed,
            last_failure,
        }
    }

    /// One SQP iteration: the subproblem at the current point (recovered when it fails), the
    /// KKT test, the merit line search with its second-order correction, the gradients at the
    /// accepted point and the damped BFGS update. Returns how it ended and the words for a run
    /// that ends there; after [`SqpStatus::StepTaken`] the state is at the new point, its
    /// history ending with the record of the point left (with its line search).
    fn iterate(
        &mut self,
        problem: &mut dyn Problem,
        solver: &mut dyn SubproblemSolver,
        params: &SqpParams,
        scaling: &Scaling,
        bounds: (&[f64], &[f64]),
    ) -> Result<(SqpStatus, String), SqpError> {
        let n = self.z.len();
        let iteration = self.iteration;
        let lin = Linearization::at(&self.z, &self.grads, scaling, bounds);
        let qp = lin.qp(&self.hess, &self.values.eq, &self.values.ineq, params);
        let (step, recovery) = match solve_with_recovery(solver, &qp) {
            Ok(s) => s,
            Err(reason) => {
                self.record_failed_subproblem(scaling);
                return Ok((
                    SqpStatus::SubproblemFailed,
                    format!(
                        "the QP subproblem failed at iteration {iteration} and every recovery failed too ({reason})"
                    ),
                ));
            }
        };
        if recovery.is_some() {
            // the recovered subproblem solved with the identity: the BFGS restarts from it
            self.hess = identity(n);
        }
        let viol = violation(&self.values);
        let kkt = kkt_measure(&lin.g, &step, &self.values);
        self.history.push(Iterate {
            iteration,
            x: scaling.x(&self.z),
            values: self.values.clone(),
            violation: viol,
            kkt,
            step: step.d.iter().fold(0.0, |a, v| a.max(v.abs())),
            evaluations: self.evaluations,
            alpha: 0.0,
            failed_trials: 0,
            trial_failure: None,
            recovery,
        });
        if kkt < params.tolerance && viol < params.tolerance {
            return Ok((
                SqpStatus::Converged,
                "KKT conditions satisfied to the tolerance".into(),
            ));
        }
        // the subproblem could not meet the linearized constraints within the bounds
        let infeasible = if viol >= params.tolerance && step.elastic > 1e-8 {
            format!(
                "; the linearized constraints cannot be met within the bounds (largest violation {viol:.3e}): the problem looks infeasible"
            )
        } else {
            String::new()
        };
        if iteration >= params.max_iterations {
            return Ok((
                SqpStatus::IterationLimit,
                format!(
                    "iteration limit {} reached{infeasible}",
                    params.max_iterations
                ),
            ));
        }
        let penalty = self.update_penalty(&step);
        let search = self.line_search(problem, solver, params, scaling, &lin, &step, penalty);
        if let Some(last) = self.history.last_mut() {
            last.alpha = if search.accepted.is_some() {
                search.alpha
            } else {
                0.0
            };
            last.failed_trials = search.failed;
            last.trial_failure = search.last_failure.clone();
        }
        let Some((z_new, v_new)) = search.accepted else {
            let converged = viol < params.tolerance && kkt < 10.0 * params.tolerance;
            let message = match search.last_failure {
                Some(reason) => format!(
                    "line search stalled ({} of its trial points could not be evaluated; the last: {reason})",
                    search.failed
                ),
                None => "line search stalled (no decrease of the merit function along the step)".into(),
            } + &infeasible;
            return Ok((SqpStatus::LineSearchStalled { converged }, message));
        };
        let grads_new = match problem.gradients(&scaling.x(&z_new)) {
            Ok(g) => g,
            Err(reason) => {
                let message = format!(
                    "the gradients at the point accepted at iteration {iteration} could not be evaluated ({reason})"
                );
                return Ok((SqpStatus::GradientsFailed, message));
            }
        };
        // damped BFGS on the Lagrangian with the new multipliers
        let s: Vec<f64> = z_new.iter().zip(&self.z).map(|(a, b)| a - b).collect();
        let gl_new = lagrangian_grad(scaling, &grads_new, &step.lambda_eq, &step.lambda_ineq);
        let gl_old = lagrangian_grad(scaling, &self.grads, &step.lambda_eq, &step.lambda_ineq);
        let y: Vec<f64> = gl_new.iter().zip(&gl_old).map(|(a, b)| a - b).collect();
        damped_bfgs(&mut self.hess, &s, y);
        self.z = z_new;
        self.values = v_new;
        self.grads = grads_new;
        self.iteration += 1;
        Ok((SqpStatus::StepTaken, String::new()))
    }
}

/// The n × n identity (the BFGS start and reset).
fn identity(n: usize) -> Vec<Vec<f64>> {
    (0..n)
        .map(|i| (0..n).map(|j| if i == j { 1.0 } else { 0.0 }).collect())
        .collect()
}

/// Solves a subproblem, and when that fails, tries the [`RECOVERIES`] in order. Returns the step
/// and which recovery gave it, or every attempt's reason.
fn solve_with_recovery(
    solver: &mut dyn SubproblemSolver,
    data: &QpData<'_>,
) -> Result<(qp::QpStep, Option<String>), String> {
    let first = match solver.solve(data) {
        Ok(step) => return Ok((step, None)),
        Err(e) => e.0,
    };
    let mut reasons = vec![format!("as posed: {first}")];
    let n = data.grad.len();
    let eye = identity(n);
    for (name, reset, tolerant, short) in RECOVERIES {
        let (lower, upper): (Vec<f64>, Vec<f64>) = if short {
            (
                data.lower.iter().map(|l| l.max(-SHORT_STEP)).collect(),
                data.upper.iter().map(|u| u.min(SHORT_STEP)).collect(),
            )
        } else {
            (data.lower.to_vec(), data.upper.to_vec())
        };
        // a bound pair the trust region would cross (a variable outside it) keeps its own bounds
        let (lower, upper): (Vec<f64>, Vec<f64>) = lower
            .iter()
            .zip(&upper)
            .zip(data.lower.iter().zip(data.upper))
            .map(|((l, u), (l0, u0))| if l <= u { (*l, *u) } else { (*l0, *u0) })
            .unzip();
        let attempt = QpData {
            hessian: if reset { &eye } else { data.hessian },
            lower: &lower,
            upper: &upper,
            tolerant,
            ..*data
        };
        match solver.solve(&attempt) {
            Ok(step) => return Ok((step, Some(name.to_string()))),
            Err(e) => reasons.push(format!("{name}: {}", e.0)),
        }
    }
    Err(reasons.join("; "))
}

/// The end of a run that cannot go on: not converged, at the best feasible iterate of `history`
/// (the lowest objective among those whose violation is below `tolerance`; the last iterate when
/// none is feasible), the message saying which it is and why the run ended.
fn stop_at_best(
    why: String,
    history: Vec<Iterate>,
    iteration: usize,
    evaluations: usize,
    elapsed_s: f64,
    tolerance: f64,
) -> SqpInfo {
    let last = history.last().expect("at least the starting point");
    let best = history
        .iter()
        .filter(|it| it.violation < tolerance)
        .min_by(|a, b| a.values.f.total_cmp(&b.values.f));
    let (chosen, which) = match best {
        Some(b) => (
            b,
            format!(
                "the results are those of iteration {}, the best feasible iterate (the last, iteration {}, has objective {:.6} and violation {:.2e})",
                b.iteration, last.iteration, last.values.f, last.violation
            ),
        ),
        None => (
            last,
            format!(
                "no iterate was feasible: the results are those of the last, iteration {} (violation {:.2e})",
                last.iteration, last.violation
            ),
        ),
    };
    SqpInfo {
        converged: false,
        status: SqpStatus::SubproblemFailed,
        iterations: iteration,
        evaluations,
        message: format!("{why}; {which}"),
        x: chosen.x.clone(),
        values: chosen.values.clone(),
        history,
        elapsed_s,
    }
}
