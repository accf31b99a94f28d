//! The SQP subproblem, solved with clarabel in elastic form so that it always has a solution:
//!   min ½ dᵀB d + gᵀd + ρ Σ (t_i + u_j + v_j)
//!   s.t. J_E d + h = u − v,  J_I d + c ≤ t,  lb − x ≤ d ≤ ub − x,  t, u, v ≥ 0,
//! where (h, J_E) are the equality and (c, J_I) the inequality constraints (c ≤ 0) linearized at x.
//! With ρ large the elastic variables vanish whenever the linearization is consistent.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, ZeroConeT,
};

/// Data of one subproblem (all in the optimizer's scaled variables).
pub struct QpData<'a> {
    pub hessian: &'a [Vec<f64>],
    pub grad: &'a [f64],
    pub eq: &'a [f64],
    pub eq_jac: &'a [Vec<f64>],
    pub ineq: &'a [f64],
    pub ineq_jac: &'a [Vec<f64>],
    /// Step bounds lb − x and ub − x.
    pub lower: &'a [f64],
    pub upper: &'a [f64],
    /// Elastic penalty ρ.
    pub rho: f64,
    /// Clarabel with more iterations, looser tolerances and more regularization: a recovery
    /// setting for a subproblem the default settings could not solve.
    pub tolerant: bool,
}

/// Step bounds closer than this (scaled variables) fix the variable: it enters the subproblem as
/// an equality, since a pair of opposite inequalities with no interior between them stalls an
/// interior-point method (clarabel's `InsufficientProgress`).
const FIXED_GAP: f64 = 1e-12;

/// The step and the multipliers of the linearized constraints (equality, inequality; inequality
/// multipliers ≥ 0), and the elastic violation left in the subproblem.
#[derive(Debug)]
pub struct QpStep {
    pub d: Vec<f64>,
    pub lambda_eq: Vec<f64>,
    pub lambda_ineq: Vec<f64>,
    /// Multipliers of the lower and upper step bounds (≥ 0).
    pub bound_lower: Vec<f64>,
    pub bound_upper: Vec<f64>,
    pub elastic: f64,
}

/// Why clarabel returned no step: its status (e.g. `NumericalError`, `MaxIterations`), or the
/// reason it refused the problem data.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("clarabel: {0}")]
pub struct QpError(pub String);

/// Solves the elastic QP; an error carries clarabel's status when it did not solve it.
pub fn solve(q: &QpData) -> Result<QpStep, QpError> {
    let n = q.grad.len();
    let (me, mi) = (q.eq.len(), q.ineq.len());
    // variables: d (n), u (me), v (me), t (mi)
    let nv = n + 2 * me + mi;
    let mut pi = Vec::new();
    let mut pj = Vec::new();
    let mut pv = Vec::new();
    for j in 0..n {
        for i in 0..=j {
            let v = 0.5 * (q.hessian[i][j] + q.hessian[j][i]);
            if v != 0.0 {
                pi.push(i);
                pj.push(j);
                pv.push(v);
            }
        }
    }
    let p = CscMatrix::new_from_triplets(nv, nv, pi, pj, pv);
    let mut lin = q.grad.to_vec();
    lin.extend(std::iter::repeat_n(q.rho, 2 * me + mi));
    // rows: equalities (zero cone), then inequalities, bounds, elastic signs (nonnegative cone)
    let (mut ai, mut aj, mut av) = (Vec::new(), Vec::new(), Vec::new());
    let mut b = Vec::new();
    let mut row = 0;
    for e in 0..me {
        for j in 0..n {
            if q.eq_jac[e][j] != 0.0 {
                ai.push(row);
                aj.push(j);
                av.push(q.eq_jac[e][j]);
            }
        }
        // J d − u + v = −h
        ai.extend([row, row]);
        aj.extend([n + e, n + me + e]);
        av.extend([-1.0, 1.0]);
        b.push(-q.eq[e]);
        row += 1;
    }
    // variables with equal step bounds: d_j = the bound (zero cone)
    let fixed: Vec<usize> = (0..n)
        .filter(|&j| {
            q.lower[j].is_finite() && q.upper[j].is_finite() && q.upper[j] - q.lower[j] <= FIXED_GAP
        })
        .collect();
    let mut fixed_rows = Vec::new();
    for &j in &fixed {
        ai.push(row);
        aj.push(j);
        av.push(1.0);
        b.push(0.5 * (q.lower[j] + q.upper[j]));
        fixed_rows.push((j, row));
        row += 1;
    }
    let zero_rows = row;
    for c in 0..mi {
        for j in 0..n {
            if q.ineq_jac[c][j] != 0.0 {
                ai.push(row);
                aj.push(j);
                av.push(q.ineq_jac[c][j]);
            }
        }
        // J d − t + s = −c, s ≥ 0
        ai.push(row);
        aj.push(n + 2 * me + c);
        av.push(-1.0);
        b.push(-q.ineq[c]);
        row += 1;
    }
    // finite step bounds only (rows of infinite bounds would wreck the conditioning)
    let mut bound_rows = Vec::new();
    for j in 0..n {
        if fixed.binary_search(&j).is_ok() {
            continue;
        }
        // d ≤ ub − x
        if q.upper[j].is_finite() {
            ai.push(row);
            aj.push(j);
            av.push(1.0);
            b.push(q.upper[j]);
            bound_rows.push((j, true, row));
            row += 1;
        }
        // −d ≤ −(lb − x)
        if q.lower[j].is_finite() {
            ai.push(row);
            aj.push(j);
            av.push(-1.0);
            b.push(-q.lower[j]);
            bound_rows.push((j, false, row));
            row += 1;
        }
    }
    for k in n..nv {
        ai.push(row);
        aj.push(k);
        av.push(-1.0);
        b.push(0.0);
        row += 1;
    }
    let a = CscMatrix::new_from_triplets(row, nv, ai, aj, av);
    let cones = [ZeroConeT(zero_rows), NonnegativeConeT(row - zero_rows)];
    let settings = if q.tolerant {
        DefaultSettings {
            verbose: false,
            presolve_enable: false,
            max_iter: 1000,
            tol_gap_abs: 1e-7,
            tol_gap_rel: 1e-7,
            tol_feas: 1e-7,
            static_regularization_constant: 1e-7,
            equilibrate_max_iter: 50,
            ..DefaultSettings::default()
        }
    } else {
        DefaultSettings {
            verbose: false,
            presolve_enable: false,
            ..DefaultSettings::default()
        }
    };
    let mut solver = DefaultSolver::new(&p, &lin, &a, &b, &cones, settings)
        .map_err(|e| QpError(format!("problem data refused: {e:?}")))?;
    solver.solve();
    let s = &solver.solution;
    if !matches!(s.status, SolverStatus::Solved | SolverStatus::AlmostSolved) {
        return Err(QpError(format!("status {:?}", s.status)));
    }
    let z = &s.z;
    let elastic = s.x[n..].iter().sum();
    let mut bound_upper = vec![0.0; n];
    let mut bound_lower = vec![0.0; n];
    for &(j, upper, r) in &bound_rows {
        if upper {
            bound_upper[j] = z[r];
        } else {
            bound_lower[j] = z[r];
        }
    }
    // a fixed variable's equality multiplier: the upper bound's when positive, else the lower's
    for &(j, r) in &fixed_rows {
        bound_upper[j] = z[r].max(0.0);
        bound_lower[j] = (-z[r]).max(0.0);
    }
    Ok(QpStep {
        d: s.x[..n].to_vec(),
        lambda_eq: z[..me].to_vec(),
        lambda_ineq: z[zero_rows..zero_rows + mi].to_vec(),
        bound_upper,
        bound_lower,
        elastic,
    })
}
