//! Sequential quadratic programming in the spirit of SLSQP for
//!   min f(x)  s.t.  h(x) = 0,  c(x) ≤ 0,  lb ≤ x ≤ ub,
//! with a damped-BFGS Hessian of the Lagrangian, elastic QP subproblems solved by clarabel (so an
//! inconsistent linearization never stops the run), an L1 exact-penalty merit function with a
//! backtracking Armijo line search, design-variable scaling by the bound ranges, and a KKT-based
//! stopping test. Every iteration can be observed and checkpointed; a run resumes from its
//! checkpoint to the same result.

pub mod qp;

use serde::{Deserialize, Serialize};

/// Function values at a point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Values {
    pub f: f64,
    pub eq: Vec<f64>,
    /// Inequalities, feasible when ≤ 0.
    pub ineq: Vec<f64>,
}

/// Gradients at a point (rows: constraints).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Gradients {
    pub f: Vec<f64>,
    pub eq: Vec<Vec<f64>>,
    pub ineq: Vec<Vec<f64>>,
}

/// Why a problem could not be evaluated at a point: the evaluator's own error, kept whole to the
/// edge (its cause chain, and a fidelity's solver failure with its residual history, reach the
/// runner, which words it for the user; the SQP records it in words only in its history).
pub type EvalError = anyhow::Error;

/// An optimization problem. Evaluations may fail (e.g. an unstable design): the line search then
/// backtracks.
pub trait Problem {
    fn lower(&self) -> Vec<f64>;
    fn upper(&self) -> Vec<f64>;
    fn values(&mut self, x: &[f64]) -> Result<Values, EvalError>;
    /// Gradients at the point of the last successful `values` call with the same x.
    fn gradients(&mut self, x: &[f64]) -> Result<Gradients, EvalError>;
    /// What the problem keeps with every checkpoint (its own records, e.g. evaluation times),
    /// handed back by [`Problem::restore`] when a run resumes; nothing by default.
    fn state(&self) -> serde_json::Value {
        serde_json::Value::Null
    }
    /// Takes back the [`Problem::state`] of a checkpoint when a run resumes.
    fn restore(&mut self, _state: &serde_json::Value) -> Result<(), EvalError> {
        Ok(())
    }
}

/// Settings of the SQP.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SqpParams {
    pub max_iterations: usize,
    /// KKT tolerance (scaled variables): |∇f·d| + Σ|λ_i c_i| and the constraint violation.
    pub tolerance: f64,
    /// Elastic penalty of the QP subproblem.
    pub elastic_penalty: f64,
    /// Smallest line-search step before the iteration is declared stalled.
    pub min_step: f64,
    /// How many accepted points the line search compares a trial point's merit with: the trial
    /// is accepted below the largest of their merits (Grippo–Lampariello–Lucidi; NLPQLP's
    /// MAXNM), which takes the full step where the constraints' curvature raises the merit by
    /// a second-order amount (the Maratos effect) instead of paying a second-order correction's
    /// evaluation. 1: the monotone search. Absent in checkpoints from before it: 1.
    #[serde(default = "monotone")]
    pub nonmonotone_memory: usize,
}

/// The largest `nonmonotone_memory` accepted (NLPQLP suggests about 10).
pub const MAX_NONMONOTONE_MEMORY: usize = 20;

fn monotone() -> usize {
    1
}

/// Why a line-search memory cannot be used (the settings' and the study files' one check).
pub fn check_nonmonotone_memory(memory: usize) -> Result<(), String> {
    if (1..=MAX_NONMONOTONE_MEMORY).contains(&memory) {
        Ok(())
    } else {
        Err(format!(
            "must lie between 1 (the monotone line search) and {MAX_NONMONOTONE_MEMORY} (got {memory})"
        ))
    }
}

impl SqpParams {
    /// Checks the settings (as clarabel's settings are checked before a solve).
    pub fn validate(&self) -> Result<(), SqpError> {
        let bad = |m: String| Err(SqpError::Params(m));
        if self.max_iterations == 0 {
            return bad("max_iterations must be at least 1".into());
        }
        for (name, v) in [
            ("tolerance", self.tolerance),
            ("elastic_penalty", self.elastic_penalty),
            ("min_step", self.min_step),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return bad(format!("{name} must be positive and finite (got {v})"));
            }
        }
        if let Err(reason) = check_nonmonotone_memory(self.nonmonotone_memory) {
            return bad(format!("nonmonotone_memory {reason}"));
        }
        if self.min_step >= 1.0 {
            return bad(format!(
                "min_step must lie below 1, the full step (got {})",
                self.min_step
            ));
        }
        Ok(())
    }
}

impl Default for SqpParams {
    fn default() -> Self {
        Self {
            max_iterations: 100,
            tolerance: 1e-4,
            elastic_penalty: 1e4,
            min_step: 1e-8,
            nonmonotone_memory: 1,
        }
    }
}

/// One iteration as recorded in the history and shown to observers.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Iterate {
    pub iteration: usize,
    pub x: Vec<f64>,
    pub values: Values,
    /// Largest constraint violation.
    pub violation: f64,
    /// KKT measure of the step taken from this point.
    pub kkt: f64,
    pub step: f64,
    pub evaluations: usize,
    /// Step length the line search accepted from this point (0 until it has run).
    #[serde(default)]
    pub alpha: f64,
    /// Trial points of that line search that could not be evaluated.
    #[serde(default)]
    pub failed_trials: usize,
    /// Why the last of them could not be (e.g. the design flutters at the flight condition).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trial_failure: Option<String>,
    /// The recovery that solved this iteration's subproblem when clarabel could not as posed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub recovery: Option<String>,
}

/// How an SQP iteration ended: the executor goes on after [`SqpStatus::StepTaken`] only, and a
/// run's [`SqpInfo`] says which of the others ended it (as Clarabel's solver status does).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SqpStatus {
    /// A step was accepted and the BFGS matrix updated: the next iteration follows.
    #[default]
    StepTaken,
    /// The KKT conditions hold to the tolerance at the current point.
    Converged,
    /// The iteration limit was reached.
    IterationLimit,
    /// The line search found no acceptable point along the step (`converged` where the point
    /// met the looser test: violation below the tolerance, KKT below ten times it).
    LineSearchStalled { converged: bool },
    /// The subproblem failed as posed and with every recovery: the run ends at its best
    /// feasible iterate, and its checkpoint says why.
    SubproblemFailed,
    /// The gradients at the accepted point could not be evaluated: the run ends at its best
    /// feasible iterate.
    GradientsFailed,
    /// An observer asked to stop.
    Stopped,
}

/// How a run ended.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SqpInfo {
    pub converged: bool,
    /// What ended the run.
    #[serde(default)]
    pub status: SqpStatus,
    pub iterations: usize,
    pub evaluations: usize,
    pub message: String,
    pub x: Vec<f64>,
    pub values: Values,
    pub history: Vec<Iterate>,
    /// Wall time of the run, s, over every session that worked on it (a resumed run adds the
    /// time its checkpoint had recorded).
    #[serde(default)]
    pub elapsed_s: f64,
}

/// Why the SQP could not run.
#[derive(Debug, thiserror::Error)]
pub enum SqpError {
    #[error("bounds: lower bound {lower} exceeds upper bound {upper} for variable {index}")]
    InfeasibleBounds {
        index: usize,
        lower: f64,
        upper: f64,
    },
    #[error("the starting point cannot be evaluated: {0:#}")]
    Start(#[source] EvalError),
    #[error("checkpoint: {0}")]
    Checkpoint(String),
    #[error("bounds: {lower} lower and {upper} upper bounds for {n} design variables")]
    BoundsLength {
        n: usize,
        lower: usize,
        upper: usize,
    },
    #[error("settings: {0}")]
    Params(String),
    #[error("initial Hessian: {0}")]
    InitialHessian(String),
    #[error("an observer failed: {0}")]
    Observer(String),
    #[error("gradients failed at iteration {iteration}: {source:#}")]
    Gradient {
        iteration: usize,
        #[source]
        source: EvalError,
    },
}

/// Everything needed to continue a run: written after every iteration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    /// Identifies the problem the checkpoint belongs to (checked on resume).
    pub problem_id: String,
    pub params: SqpParams,
    pub iteration: usize,
    pub evaluations: usize,
    /// Scaled iterate.
    pub z: Vec<f64>,
    pub hessian: Vec<Vec<f64>>,
    pub penalty: f64,
    pub history: Vec<Iterate>,
    /// Wall time of the run up to this checkpoint, s, over every session that worked on it.
    #[serde(default)]
    pub elapsed_s: f64,
    /// The problem's own records ([`Problem::state`]).
    #[serde(default)]
    pub problem_state: serde_json::Value,
    /// Why the run ended here when it could not go on (a subproblem that no recovery solved):
    /// `--resume` then says so at once instead of failing the same way.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped: Option<String>,
    /// The values and gradients at `z`, so that a resumed run goes on from them as the run that
    /// wrote the checkpoint would have, without evaluating the point again (one function and one
    /// gradient: minutes with the LFD). A checkpoint without them (an earlier gustkit's) has its
    /// point evaluated again on resume.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point: Option<PointEvaluation>,
}

/// The values and gradients at a checkpoint's point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointEvaluation {
    pub values: Values,
    pub gradients: Gradients,
}

mod managed;
mod sqp;
pub use managed::{
    minimize_managed, ManagedCheckpoint, ManagedInfo, ManagedIterate, ManagedObserver,
    ManagedParams,
};
pub use sqp::{
    minimize, Checkpointing, Clarabel, Control, Executor, Observer, Scaling, SubproblemSolver,
};

#[cfg(test)]
mod tests;
