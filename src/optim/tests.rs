//! The SQP on standard problems with known optima, checkpoint/resume, and bad input.

use super::*;

/// A problem from closures.
struct Fns<F, G> {
    lb: Vec<f64>,
    ub: Vec<f64>,
    values: F,
    grads: G,
}

impl<F, G> Problem for Fns<F, G>
where
    F: FnMut(&[f64]) -> Result<Values, String>,
    G: FnMut(&[f64]) -> Gradients,
{
    fn lower(&self) -> Vec<f64> {
        self.lb.clone()
    }
    fn upper(&self) -> Vec<f64> {
        self.ub.clone()
    }
    fn values(&mut self, x: &[f64]) -> Result<Values, crate::optim::EvalError> {
        (self.values)(x).map_err(anyhow::Error::msg)
    }
    fn gradients(&mut self, x: &[f64]) -> Result<Gradients, crate::optim::EvalError> {
        Ok((self.grads)(x))
    }
}

/// A problem whose evaluation fails with a fidelity's solver failure under a context, as the
/// design problem's would.
struct SolverFails;

impl Problem for SolverFails {
    fn lower(&self) -> Vec<f64> {
        vec![0.0]
    }
    fn upper(&self) -> Vec<f64> {
        vec![1.0]
    }
    fn values(&mut self, _: &[f64]) -> Result<Values, crate::optim::EvalError> {
        let failure = gustkit_core::AeroError::Solver {
            k: 0.5,
            rhs: "gust".into(),
            failure: gustkit_core::SolverFailure {
                reason: "GMRES stalled".into(),
                history: vec![1.0, 0.1, 0.09],
            },
        };
        Err(anyhow::Error::new(failure).context("GAF table"))
    }
    fn gradients(&mut self, _: &[f64]) -> Result<Gradients, crate::optim::EvalError> {
        unreachable!("values fail first")
    }
}

/// An evaluation error reaches the caller typed (the solver failure with its whole residual
/// history can be taken out of the SQP's error) and worded whole (context, reason, digest).
#[test]
fn evaluation_errors_stay_typed_to_the_edge() {
    let e = minimize(
        &mut SolverFails,
        &[0.5],
        &SqpParams::default(),
        "x",
        None,
        &mut (),
    )
    .unwrap_err();
    let SqpError::Start(source) = &e else {
        panic!("not a start error: {e}")
    };
    match source.downcast_ref::<gustkit_core::AeroError>() {
        Some(gustkit_core::AeroError::Solver { failure, .. }) => {
            assert_eq!(failure.history, vec![1.0, 0.1, 0.09])
        }
        other => panic!("the solver failure is lost: {other:?}"),
    }
    let words = e.to_string();
    for part in ["GAF table", "k = 0.5 (gust)", "GMRES stalled", "3 values"] {
        assert!(words.contains(part), "{part} missing from: {words}");
    }
    // said once: the failure is in the solver error's words, not repeated as its source
    assert_eq!(words.matches("GMRES stalled").count(), 1, "{words}");
}

fn hs71() -> impl Problem {
    Fns {
        lb: vec![1.0; 4],
        ub: vec![5.0; 4],
        values: |x: &[f64]| {
            Ok(Values {
                f: x[0] * x[3] * (x[0] + x[1] + x[2]) + x[2],
                eq: vec![x.iter().map(|v| v * v).sum::<f64>() - 40.0],
                ineq: vec![25.0 - x[0] * x[1] * x[2] * x[3]],
            })
        },
        grads: |x: &[f64]| Gradients {
            f: vec![
                x[3] * (2.0 * x[0] + x[1] + x[2]),
                x[0] * x[3],
                x[0] * x[3] + 1.0,
                x[0] * (x[0] + x[1] + x[2]),
            ],
            eq: vec![x.iter().map(|v| 2.0 * v).collect()],
            ineq: vec![vec![
                -x[1] * x[2] * x[3],
                -x[0] * x[2] * x[3],
                -x[0] * x[1] * x[3],
                -x[0] * x[1] * x[2],
            ]],
        },
    }
}

/// Hock–Schittkowski 71: f* = 17.0140173 at (1, 4.7429994, 3.8211503, 1.3794082) from (1, 5, 5, 1),
/// with an equality, an inequality and bounds all active or nearly so.
#[test]
fn hock_schittkowski_71() {
    let mut p = hs71();
    let params = SqpParams {
        tolerance: 1e-8,
        ..Default::default()
    };
    let r = minimize(
        &mut p,
        &[1.0, 5.0, 5.0, 1.0],
        &params,
        "hs71",
        None,
        &mut (),
    )
    .unwrap();
    println!(
        "HS71: {} iterations, {} evaluations, f = {:.10}, x = {:.7?}",
        r.iterations, r.evaluations, r.values.f, r.x
    );
    assert!(r.converged, "{}", r.message);
    assert_eq!(r.status, SqpStatus::Converged);
    assert!((r.values.f - 17.0140173).abs() < 1e-6);
    for (a, b) in r.x.iter().zip([1.0, 4.7429994, 3.8211503, 1.3794082]) {
        assert!((a - b).abs() < 1e-5, "{:?}", r.x);
    }
    assert!(r.iterations < 30);
}

/// Rosenbrock with the bound x ≤ 0.8 active: optimum (0.8, 0.64), f = 0.04, from (−1.2, 1).
#[test]
fn bounded_rosenbrock() {
    let mut p = Fns {
        lb: vec![-1.5, -1.0],
        ub: vec![0.8, 3.0],
        values: |x: &[f64]| {
            Ok(Values {
                f: (1.0 - x[0]).powi(2) + 100.0 * (x[1] - x[0] * x[0]).powi(2),
                eq: vec![],
                ineq: vec![],
            })
        },
        grads: |x: &[f64]| Gradients {
            f: vec![
                -2.0 * (1.0 - x[0]) - 400.0 * x[0] * (x[1] - x[0] * x[0]),
                200.0 * (x[1] - x[0] * x[0]),
            ],
            eq: vec![],
            ineq: vec![],
        },
    };
    let params = SqpParams {
        tolerance: 1e-10,
        max_iterations: 200,
        ..Default::default()
    };
    let r = minimize(&mut p, &[-1.2, 1.0], &params, "rosen", None, &mut ()).unwrap();
    println!(
        "Rosenbrock: {} iterations, f = {:.3e}, x = {:?}",
        r.iterations, r.values.f, r.x
    );
    assert!(r.converged, "{}", r.message);
    assert!((r.x[0] - 0.8).abs() < 1e-7 && (r.x[1] - 0.64).abs() < 1e-6);
    assert!((r.values.f - 0.04).abs() < 1e-8);
}

/// A convex QP: min (x−1)² + (y−2.5)² s.t. three linear inequalities, x, y ≥ 0; optimum (1.4, 1.7),
/// f = 0.8, reached in a few iterations.
#[test]
fn convex_qp() {
    let mut p = Fns {
        lb: vec![0.0, 0.0],
        ub: vec![f64::INFINITY, f64::INFINITY],
        values: |x: &[f64]| {
            Ok(Values {
                f: (x[0] - 1.0).powi(2) + (x[1] - 2.5).powi(2),
                eq: vec![],
                ineq: vec![
                    -(x[0] - 2.0 * x[1] + 2.0),
                    -(-x[0] - 2.0 * x[1] + 6.0),
                    -(-x[0] + 2.0 * x[1] + 2.0),
                ],
            })
        },
        grads: |x: &[f64]| Gradients {
            f: vec![2.0 * (x[0] - 1.0), 2.0 * (x[1] - 2.5)],
            eq: vec![],
            ineq: vec![vec![-1.0, 2.0], vec![1.0, 2.0], vec![1.0, -2.0]],
        },
    };
    let params = SqpParams {
        tolerance: 1e-9,
        ..Default::default()
    };
    let r = minimize(&mut p, &[2.0, 0.0], &params, "qp", None, &mut ()).unwrap();
    println!("QP: {} iterations, x = {:?}", r.iterations, r.x);
    assert!(r.converged);
    assert!((r.x[0] - 1.4).abs() < 1e-6 && (r.x[1] - 1.7).abs() < 1e-6);
    assert!(r.iterations <= 6);
}

/// A problem that counts its evaluations.
struct Counted<P: Problem> {
    inner: P,
    values: usize,
    gradients: usize,
}

impl<P: Problem> Problem for Counted<P> {
    fn lower(&self) -> Vec<f64> {
        self.inner.lower()
    }
    fn upper(&self) -> Vec<f64> {
        self.inner.upper()
    }
    fn values(&mut self, x: &[f64]) -> Result<Values, EvalError> {
        self.values += 1;
        self.inner.values(x)
    }
    fn gradients(&mut self, x: &[f64]) -> Result<Gradients, EvalError> {
        self.gradients += 1;
        self.inner.gradients(x)
    }
}

/// Stopping after 3 iterations and resuming from the checkpoint gives the same final result as an
/// uninterrupted run, with no evaluation more: the checkpoint keeps its point's values and
/// gradients. A checkpoint without them (an earlier gustkit's) has its point evaluated again, to
/// the same end; one whose kept gradients do not fit is evaluated again too; a checkpoint of
/// another problem is refused.
#[test]
fn resume_from_checkpoint_reproduces_the_run() {
    let params = SqpParams {
        tolerance: 1e-8,
        ..Default::default()
    };
    let x0 = [1.0, 5.0, 5.0, 1.0];
    let full = minimize(&mut hs71(), &x0, &params, "hs71", None, &mut ()).unwrap();
    struct StopAt(usize, Option<Checkpoint>);
    impl Observer for StopAt {
        fn iteration(&mut self, _: &Iterate, c: &Checkpoint) -> Result<Control, String> {
            // round-trip through JSON as the CLI does
            let text = serde_json::to_string(c).unwrap();
            self.1 = Some(serde_json::from_str(&text).unwrap());
            Ok(if c.iteration < self.0 {
                Control::Continue
            } else {
                Control::Stop
            })
        }
    }
    let mut stop = StopAt(3, None);
    let part = minimize(&mut hs71(), &x0, &params, "hs71", None, &mut stop).unwrap();
    assert!(!part.converged && part.iterations == 3);
    let counted = || Counted {
        inner: hs71(),
        values: 0,
        gradients: 0,
    };
    let mut p = counted();
    let resumed = minimize(&mut p, &x0, &params, "hs71", stop.1.clone(), &mut ()).unwrap();
    assert!(resumed.converged);
    assert_eq!(resumed.iterations, full.iterations);
    assert_eq!(resumed.x, full.x);
    assert_eq!(resumed.history, full.history);
    assert_eq!(resumed.evaluations, full.evaluations);
    assert_eq!(p.values, full.evaluations - part.evaluations);
    // without the kept point (or with one that does not fit): one evaluation more, same end
    let without = stop.1.clone().map(|c| Checkpoint { point: None, ..c });
    let mut mangled = stop.1.clone().unwrap();
    mangled.point.as_mut().unwrap().gradients.f.pop();
    for c in [without, Some(mangled)] {
        let mut p = counted();
        let again = minimize(&mut p, &x0, &params, "hs71", c, &mut ()).unwrap();
        assert_eq!(again.x, full.x);
        assert_eq!(again.evaluations, full.evaluations + 1);
        assert_eq!(p.values, full.evaluations - part.evaluations + 1);
    }
    // what decides when to stop or what to accept from here on may change; the subproblem's
    // settings, which shaped the points already taken, may not
    let looser = SqpParams {
        tolerance: 1e-6,
        nonmonotone_memory: 3,
        max_iterations: 50,
        ..params.clone()
    };
    let again = minimize(&mut hs71(), &x0, &looser, "hs71", stop.1.clone(), &mut ()).unwrap();
    assert!(again.converged && again.iterations > 3, "{}", again.message);
    let other = SqpParams {
        elastic_penalty: 1e3,
        ..params.clone()
    };
    let e = minimize(&mut hs71(), &x0, &other, "hs71", stop.1.clone(), &mut ()).unwrap_err();
    assert!(matches!(e, SqpError::Checkpoint(_)), "{e}");
    let e = minimize(&mut hs71(), &x0, &params, "other", stop.1, &mut ()).unwrap_err();
    assert!(matches!(e, SqpError::Checkpoint(_)), "{e}");
}

/// Crossed bounds and an unevaluable start are errors; points that fail to evaluate during the
/// line search are backtracked over.
#[test]
fn bad_input_and_failed_evaluations() {
    let mut p = Fns {
        lb: vec![1.0, 0.0],
        ub: vec![0.0, 1.0],
        values: |_: &[f64]| {
            Ok(Values {
                f: 0.0,
                eq: vec![],
                ineq: vec![],
            })
        },
        grads: |_: &[f64]| Gradients {
            f: vec![0.0, 0.0],
            eq: vec![],
            ineq: vec![],
        },
    };
    let e = minimize(
        &mut p,
        &[0.5, 0.5],
        &SqpParams::default(),
        "x",
        None,
        &mut (),
    )
    .unwrap_err();
    assert!(matches!(e, SqpError::InfeasibleBounds { index: 0, .. }));
    // f = (x − 3)² but evaluations fail for x > 2: the optimum on the usable region is at its edge
    let mut p = Fns {
        lb: vec![0.0],
        ub: vec![10.0],
        values: |x: &[f64]| {
            if x[0] > 2.0 {
                Err("unstable".into())
            } else {
                Ok(Values {
                    f: (x[0] - 3.0).powi(2),
                    eq: vec![],
                    ineq: vec![],
                })
            }
        },
        grads: |x: &[f64]| Gradients {
            f: vec![2.0 * (x[0] - 3.0)],
            eq: vec![],
            ineq: vec![],
        },
    };
    let r = minimize(&mut p, &[0.0], &SqpParams::default(), "x", None, &mut ()).unwrap();
    assert!(r.x[0] <= 2.0 && r.x[0] > 1.9, "{:?} {}", r.x, r.message);
    let mut p = Fns {
        lb: vec![0.0],
        ub: vec![1.0],
        values: |_: &[f64]| Err("cannot evaluate".to_string()),
        grads: |_: &[f64]| Gradients {
            f: vec![0.0],
            eq: vec![],
            ineq: vec![],
        },
    };
    assert!(matches!(
        minimize(&mut p, &[0.5], &SqpParams::default(), "x", None, &mut ()),
        Err(SqpError::Start(_))
    ));
}

/// Bounds whose length does not match the starting point, and settings that cannot work, are
/// errors before anything is evaluated (they used to index out of range or run on).
#[test]
fn bounds_length_and_settings_are_checked() {
    let mut p = Fns {
        lb: vec![0.0],
        ub: vec![1.0, 1.0],
        values: |_: &[f64]| -> Result<Values, String> { panic!("must not be evaluated") },
        grads: |_: &[f64]| -> Gradients { panic!("must not be evaluated") },
    };
    let e = minimize(
        &mut p,
        &[0.5, 0.5],
        &SqpParams::default(),
        "x",
        None,
        &mut (),
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            SqpError::BoundsLength {
                n: 2,
                lower: 1,
                upper: 2
            }
        ),
        "{e}"
    );
    for bad in [
        SqpParams {
            max_iterations: 0,
            ..Default::default()
        },
        SqpParams {
            tolerance: f64::NAN,
            ..Default::default()
        },
        SqpParams {
            min_step: 2.0,
            ..Default::default()
        },
    ] {
        let e = minimize(&mut p, &[0.5, 0.5], &bad, "x", None, &mut ()).unwrap_err();
        assert!(matches!(e, SqpError::Params(_)), "{e}");
    }
    assert!(SqpParams::default().validate().is_ok());
}

/// The QP subproblem's failure carries clarabel's status: a QP with a NaN gradient cannot be
/// solved, and the error says why instead of a bare "failed".
#[test]
fn qp_failure_names_clarabel_status() {
    let hess = vec![vec![1.0]];
    let e = qp::solve(&qp::QpData {
        hessian: &hess,
        grad: &[f64::NAN],
        eq: &[],
        eq_jac: &[],
        ineq: &[],
        ineq_jac: &[],
        lower: &[-1.0],
        upper: &[1.0],
        rho: 1e4,
        tolerant: false,
    })
    .unwrap_err();
    assert!(e.to_string().starts_with("clarabel: "), "{e}");
}

/// The BFGS approximation can start from another run's final one: the identity given explicitly
/// reproduces the default run bit for bit; HS71 restarted from a perturbed point with the final
/// Hessian of a converged run reaches the same optimum in fewer iterations than from the
/// identity; a Hessian of the wrong size, asymmetric or with a non-positive diagonal is refused.
#[test]
fn initial_hessian_from_another_run() {
    let params = SqpParams {
        tolerance: 1e-8,
        ..Default::default()
    };
    let x0 = [1.0, 5.0, 5.0, 1.0];
    struct Last(Option<Checkpoint>);
    impl Observer for Last {
        fn iteration(&mut self, _: &Iterate, c: &Checkpoint) -> Result<Control, String> {
            self.0 = Some(c.clone());
            Ok(Control::Continue)
        }
    }
    let mut last = Last(None);
    let first = Executor::new(params.clone(), "hs71")
        .observe(&mut last)
        .run(&mut hs71(), &x0)
        .unwrap();
    assert!(first.converged);
    let eye: Vec<Vec<f64>> = (0..4)
        .map(|i| (0..4).map(|j| if i == j { 1.0 } else { 0.0 }).collect())
        .collect();
    let same = Executor::new(params.clone(), "hs71")
        .initial_hessian(Some(eye.clone()))
        .run(&mut hs71(), &x0)
        .unwrap();
    assert_eq!(same.x, first.x);
    assert_eq!(same.iterations, first.iterations);
    // a nearby problem's start: the optimum moved by 0.2 in every variable
    let near: Vec<f64> = first.x.iter().map(|v| (v + 0.2).min(5.0)).collect();
    let cold = Executor::new(params.clone(), "hs71")
        .run(&mut hs71(), &near)
        .unwrap();
    let warm = Executor::new(params.clone(), "hs71")
        .initial_hessian(Some(last.0.unwrap().hessian))
        .run(&mut hs71(), &near)
        .unwrap();
    println!(
        "HS71 from a nearby point: {} iterations from the identity, {} from the converged Hessian",
        cold.iterations, warm.iterations
    );
    assert!(cold.converged && warm.converged);
    assert!((warm.values.f - first.values.f).abs() < 1e-7);
    assert!(warm.iterations < cold.iterations);
    let refused = |h: Vec<Vec<f64>>| {
        let e = Executor::new(params.clone(), "hs71")
            .initial_hessian(Some(h))
            .run(&mut hs71(), &x0)
            .unwrap_err();
        assert!(matches!(e, SqpError::InitialHessian(_)), "{e}");
    };
    refused(eye[..3].to_vec());
    let mut skew = eye.clone();
    skew[0][1] = 0.5;
    refused(skew);
    let mut negative = eye;
    negative[2][2] = -1.0;
    refused(negative);
}

/// Clarabel, except that calls listed in `fail` (counted from 0) fail as clarabel's
/// `InsufficientProgress` would, and with `fail_from` every call from that one on.
/// With `fail_once`, the first call whose Hessian is not the identity (a BFGS matrix, posed as
/// is: no recovery resets it) fails once.
struct Failing {
    calls: usize,
    fail: Vec<usize>,
    fail_from: Option<usize>,
    fail_once: bool,
}

impl SubproblemSolver for Failing {
    fn solve(&mut self, d: &qp::QpData<'_>) -> Result<qp::QpStep, qp::QpError> {
        let c = self.calls;
        self.calls += 1;
        let identity = d
            .hessian
            .iter()
            .enumerate()
            .all(|(i, r)| r.iter().enumerate().all(|(j, v)| *v == f64::from(i == j)));
        if self.fail_once && !identity {
            self.fail_once = false;
            return Err(qp::QpError("status InsufficientProgress".into()));
        }
        if self.fail.contains(&c) || self.fail_from.is_some_and(|f| c >= f) {
            return Err(qp::QpError("status InsufficientProgress".into()));
        }
        Clarabel.solve(d)
    }
}

/// A subproblem that fails once is recovered (the BFGS matrix reset): HS71 still reaches its
/// optimum to 1e-6 and the iteration records which recovery solved it.
#[test]
fn a_failed_subproblem_is_recovered() {
    let params = SqpParams {
        tolerance: 1e-8,
        ..Default::default()
    };
    let x0 = [1.0, 5.0, 5.0, 1.0];
    // the first subproblem posed with a BFGS matrix fails (as clarabel's InsufficientProgress)
    let mut solver = Failing {
        calls: 0,
        fail: Vec::new(),
        fail_from: None,
        fail_once: true,
    };
    let r = Executor::new(params, "hs71")
        .subproblem_solver(&mut solver)
        .run(&mut hs71(), &x0)
        .unwrap();
    assert!(r.converged, "{}", r.message);
    assert!((r.values.f - 17.014_017_3).abs() < 1e-6, "{}", r.values.f);
    let recovered: Vec<&str> = r
        .history
        .iter()
        .filter_map(|it| it.recovery.as_deref())
        .collect();
    assert_eq!(recovered, ["the BFGS matrix reset to the identity"]);
}

/// When no recovery solves the subproblem the run ends without an error: not converged, at the
/// best feasible iterate, the reason in words naming every attempt; its checkpoint says so, and
/// resuming from it is refused at once with that reason.
#[test]
fn an_unrecoverable_subproblem_ends_the_run_at_the_best_feasible_iterate() {
    let params = SqpParams {
        tolerance: 1e-8,
        ..Default::default()
    };
    let x0 = [1.0, 5.0, 5.0, 1.0];
    struct Keep(Option<Checkpoint>);
    impl Checkpointing for Keep {
        fn save(&mut self, c: &Checkpoint) -> Result<(), String> {
            self.0 = Some(serde_json::from_str(&serde_json::to_string(c).unwrap()).unwrap());
            Ok(())
        }
    }
    let mut store = Keep(None);
    let mut solver = Failing {
        calls: 0,
        fail: Vec::new(),
        fail_from: Some(4),
        fail_once: false,
    };
    let r = Executor::new(params.clone(), "hs71")
        .subproblem_solver(&mut solver)
        .checkpoint(&mut store)
        .run(&mut hs71(), &x0)
        .unwrap();
    assert!(!r.converged);
    assert_eq!(r.status, SqpStatus::SubproblemFailed);
    assert!(
        r.message.contains("every recovery failed")
            && r.message.contains("BFGS matrix reset")
            && r.message.contains("InsufficientProgress"),
        "{}",
        r.message
    );
    // the reported design is the best feasible iterate (or the last when none is)
    let feasible: Vec<&Iterate> = r
        .history
        .iter()
        .filter(|it| it.violation < params.tolerance)
        .collect();
    match feasible
        .iter()
        .min_by(|a, b| a.values.f.total_cmp(&b.values.f))
    {
        Some(best) => {
            assert_eq!(r.x, best.x);
            assert!(r.message.contains("best feasible"), "{}", r.message);
        }
        None => {
            assert_eq!(&r.x, &r.history.last().unwrap().x);
            assert!(
                r.message.contains("no iterate was feasible"),
                "{}",
                r.message
            );
        }
    }
    let cp = store.0.expect("a checkpoint");
    assert!(cp.stopped.is_some());
    let e = minimize(&mut hs71(), &x0, &params, "hs71", Some(cp), &mut ()).unwrap_err();
    assert!(
        matches!(&e, SqpError::Checkpoint(m) if m.contains("every recovery was tried")),
        "{e}"
    );
}

/// A variable with equal bounds (a fixed planform) enters the subproblem as an equality: the
/// bounded Rosenbrock-like problem with one variable fixed solves, and the variable never moves.
#[test]
fn equal_bounds_fix_a_variable() {
    let mut p = Fns {
        lb: vec![-2.0, 0.7, -2.0],
        ub: vec![2.0, 0.7, 2.0],
        values: |x: &[f64]| {
            Ok(Values {
                f: (x[0] - 1.0).powi(2) + (x[2] - x[1]).powi(2) + x[0] * x[1],
                eq: vec![],
                ineq: vec![x[0] + x[2] - 1.0],
            })
        },
        grads: |x: &[f64]| Gradients {
            f: vec![
                2.0 * (x[0] - 1.0) + x[1],
                -2.0 * (x[2] - x[1]) + x[0],
                2.0 * (x[2] - x[1]),
            ],
            eq: vec![],
            ineq: vec![vec![1.0, 0.0, 1.0]],
        },
    };
    // clarabel's own tolerances (1e-8) bound how far the KKT measure falls
    let params = SqpParams {
        tolerance: 1e-7,
        ..Default::default()
    };
    let r = minimize(&mut p, &[0.0, 0.7, 0.0], &params, "fixed", None, &mut ()).unwrap();
    assert!(r.converged, "{}", r.message);
    assert!(r.history.iter().all(|it| it.x[1] == 0.7));
    // optimum of (x0 − 1)² + 0.7 x0 + (x2 − 0.7)² with x0 + x2 ≤ 1: x0 = 0.65, x2 = 0.7 → 1.35 > 1,
    // so the constraint is active: x0 = 0.475, x2 = 0.525 (stationarity with one multiplier)
    assert!(
        (r.x[0] - 0.475).abs() < 1e-6 && (r.x[2] - 0.525).abs() < 1e-6,
        "{:?}",
        r.x
    );
}

/// Powell's example of the Maratos effect (Nocedal & Wright, Example 15.4): min 2(x₁² + x₂² − 1)
/// − x₁ on the unit circle, optimum (1, 0) with λ = 3/2. Started on the circle at θ = 2 rad, the
/// monotone ℓ1 line search rejects full steps that raise the merit a little (the second-order
/// correction's evaluation, then halving); a memory of 4 accepted points lets some of them
/// through. Both reach the optimum to the tolerance; measured: 16 iterations and 61 evaluations
/// monotone, 15 and 55 with the memory (the saving is the point of the setting, so it is asserted).
#[test]
fn a_nonmonotone_memory_saves_line_search_evaluations() {
    let run = |memory: usize| {
        let mut p = Fns {
            lb: vec![-2.0; 2],
            ub: vec![2.0; 2],
            values: |x: &[f64]| {
                let r2 = x[0] * x[0] + x[1] * x[1];
                Ok(Values {
                    f: 2.0 * (r2 - 1.0) - x[0],
                    eq: vec![r2 - 1.0],
                    ineq: vec![],
                })
            },
            grads: |x: &[f64]| Gradients {
                f: vec![4.0 * x[0] - 1.0, 4.0 * x[1]],
                eq: vec![vec![2.0 * x[0], 2.0 * x[1]]],
                ineq: vec![],
            },
        };
        let params = SqpParams {
            tolerance: 1e-9,
            nonmonotone_memory: memory,
            ..Default::default()
        };
        let theta: f64 = 2.0;
        minimize(
            &mut p,
            &[theta.cos(), theta.sin()],
            &params,
            "powell",
            None,
            &mut (),
        )
        .unwrap()
    };
    let monotone = run(1);
    for r in [&monotone, &run(4)] {
        println!(
            "{} iterations, {} evaluations, x = {:?}",
            r.iterations, r.evaluations, r.x
        );
        assert!(r.converged, "{}", r.message);
        // the KKT tolerance 1e-9 puts x within about its square root of (1, 0)
        assert!(
            (r.x[0] - 1.0).abs() < 1e-6 && r.x[1].abs() < 1e-6,
            "{:?}",
            r.x
        );
    }
    let nonmonotone = run(4);
    assert!(
        monotone.evaluations > monotone.iterations + 1,
        "the monotone search must need second-order corrections here ({} evaluations, {} iterations and the start)",
        monotone.evaluations,
        monotone.iterations
    );
    assert!(
        nonmonotone.evaluations < monotone.evaluations,
        "memory 4: {} evaluations against the monotone search's {}",
        nonmonotone.evaluations,
        monotone.evaluations
    );
    assert!(SqpParams {
        nonmonotone_memory: 0,
        ..Default::default()
    }
    .validate()
    .is_err());
}

/// HS71 seen through a wrong cheap model: the objective, the equality and the inequality each
/// off by smooth terms of the order of their own size (a low fidelity 10–30 % off, as the DLM
/// against the LFD on a thin design).
fn hs71_low() -> impl Problem {
    Fns {
        lb: vec![1.0; 4],
        ub: vec![5.0; 4],
        values: |x: &[f64]| {
            Ok(Values {
                f: x[0] * x[3] * (x[0] + x[1] + x[2]) + x[2] + 0.3 * x[1] * x[1],
                eq: vec![x.iter().map(|v| v * v).sum::<f64>() - 40.0 + 2.0 * (x[0] - x[2])],
                ineq: vec![25.0 - 0.8 * x[0] * x[1] * x[2] * x[3] + 0.5 * x[1]],
            })
        },
        grads: |x: &[f64]| Gradients {
            f: vec![
                x[3] * (2.0 * x[0] + x[1] + x[2]),
                x[0] * x[3] + 0.6 * x[1],
                x[0] * x[3] + 1.0,
                x[0] * (x[0] + x[1] + x[2]),
            ],
            eq: vec![vec![
                2.0 * x[0] + 2.0,
                2.0 * x[1],
                2.0 * x[2] - 2.0,
                2.0 * x[3],
            ]],
            ineq: vec![vec![
                -0.8 * x[1] * x[2] * x[3],
                -0.8 * x[0] * x[2] * x[3] + 0.5,
                -0.8 * x[0] * x[1] * x[3],
                -0.8 * x[0] * x[1] * x[2],
            ]],
        },
    }
}

/// A low fidelity that cannot be evaluated where `x[var] < below` (as a coarse lattice that
/// flutters where the fine one does not).
struct FailsBelow<P> {
    low: P,
    var: usize,
    below: f64,
}

impl<P: Problem> Problem for FailsBelow<P> {
    fn lower(&self) -> Vec<f64> {
        self.low.lower()
    }
    fn upper(&self) -> Vec<f64> {
        self.low.upper()
    }
    fn values(&mut self, x: &[f64]) -> Result<Values, crate::optim::EvalError> {
        if x[self.var] < self.below {
            anyhow::bail!("unstable below x[{}] = {}", self.var, self.below);
        }
        self.low.values(x)
    }
    fn gradients(&mut self, x: &[f64]) -> Result<Gradients, crate::optim::EvalError> {
        if x[self.var] < self.below {
            anyhow::bail!("unstable below x[{}] = {}", self.var, self.below);
        }
        self.low.gradients(x)
    }
}

/// Where the low fidelity cannot be evaluated (HS71's optimum, x2 = 4.743, lies in the region
/// where it fails), the outer iterations take the high fidelity's own SQP step in the
/// trust-region box instead and still reach HS71's optimum to the KKT test's accuracy (x within
/// 1e-5, f within 1e-6).
#[test]
fn model_management_steps_on_where_the_low_fidelity_fails() {
    let params = ManagedParams {
        tolerance: 1e-8,
        max_iterations: 200,
        ..Default::default()
    };
    let x_star = [1.0, 4.7429994, 3.8211503, 1.3794082];
    let mut low = FailsBelow {
        low: hs71_low(),
        var: 1,
        below: 4.8,
    };
    let r = minimize_managed(
        &mut hs71(),
        &mut low,
        &[1.0, 5.0, 5.0, 1.0],
        &params,
        "m",
        None,
        &mut (),
    )
    .unwrap();
    let own_steps = r
        .history
        .iter()
        .filter(|h| h.inner_outcome.contains("the high fidelity's SQP step"))
        .count();
    println!(
        "{} outer iterations ({own_steps} of them the high fidelity's own SQP step), {} high functions, {} gradients, f = {:.10}, x = {:.7?}; {}",
        r.iterations, r.high_functions, r.high_gradients, r.values.f, r.x, r.message
    );
    assert!(r.converged, "{}", r.message);
    assert!(own_steps > 0);
    assert!((r.values.f - 17.0140173).abs() < 1e-6, "{}", r.values.f);
    for (a, b) in r.x.iter().zip(x_star) {
        assert!((a - b).abs() < 1e-5, "{:?}", r.x);
    }
}

/// The model management reaches the high fidelity's optimum, not the low one's: HS71 through a
/// low fidelity whose own optimum lies elsewhere (and through HS71 itself), to the tolerance the
/// KKT test allows (1e-8 on the measure: x within about 1e-5, f within 1e-6 of 17.0140173).
/// Resuming from an outer iteration's checkpoint ends at the same point.
#[test]
fn model_management_converges_to_the_high_fidelity_optimum() {
    let params = ManagedParams {
        tolerance: 1e-8,
        ..Default::default()
    };
    let x0 = [1.0, 5.0, 5.0, 1.0];
    let low_alone = minimize(
        &mut hs71_low(),
        &x0,
        &SqpParams {
            tolerance: 1e-8,
            ..Default::default()
        },
        "low",
        None,
        &mut (),
    )
    .unwrap();
    assert!(
        (low_alone.values.f - 17.0140173).abs() > 0.1,
        "the low fidelity's own optimum must differ: {:?}",
        low_alone.x
    );
    let x_star = [1.0, 4.7429994, 3.8211503, 1.3794082];
    /// The checkpoints, and how many outer iterations had been seen at each `start` call.
    struct Keep(Vec<ManagedCheckpoint>, Vec<usize>);
    impl ManagedObserver for Keep {
        fn start(&mut self, _: &Values) {
            self.1.push(self.0.len());
        }
        fn iteration(
            &mut self,
            _: &ManagedIterate,
            c: &ManagedCheckpoint,
        ) -> Result<Control, String> {
            let text = serde_json::to_string(c).unwrap();
            self.0.push(serde_json::from_str(&text).unwrap());
            Ok(Control::Continue)
        }
    }
    let mut kept = Keep(Vec::new(), Vec::new());
    let exact =
        minimize_managed(&mut hs71(), &mut hs71(), &x0, &params, "m", None, &mut ()).unwrap();
    let wrong = minimize_managed(
        &mut hs71(),
        &mut hs71_low(),
        &x0,
        &params,
        "m",
        None,
        &mut kept,
    )
    .unwrap();
    for (name, r) in [("exact", &exact), ("wrong", &wrong)] {
        println!(
            "{name} low fidelity: {} outer iterations, {} high functions, {} high gradients, f = {:.10}, x = {:.7?}; {}",
            r.iterations, r.high_functions, r.high_gradients, r.values.f, r.x, r.message
        );
        assert!(r.converged, "{name}: {}", r.message);
        assert!(
            (r.values.f - 17.0140173).abs() < 1e-6,
            "{name}: {}",
            r.values.f
        );
        for (a, b) in r.x.iter().zip(x_star) {
            assert!((a - b).abs() < 1e-5, "{name}: {:?}", r.x);
        }
    }
    // the start point's evaluation is reported once, before the first outer iteration
    assert_eq!(kept.1, vec![0]);
    // resume from the third outer iteration's checkpoint: the same end, bit for bit, and no
    // start point evaluated again
    let mut resumed = Keep(Vec::new(), Vec::new());
    let again = minimize_managed(
        &mut hs71(),
        &mut hs71_low(),
        &x0,
        &params,
        "m",
        Some(kept.0[2].clone()),
        &mut resumed,
    )
    .unwrap();
    assert_eq!(again.x, wrong.x);
    assert_eq!(again.history, wrong.history);
    assert!(resumed.1.is_empty());
    // fidelities posing different constraints are refused
    let mut other = Fns {
        lb: vec![1.0; 4],
        ub: vec![5.0; 4],
        values: |_: &[f64]| {
            Ok(Values {
                f: 0.0,
                eq: vec![],
                ineq: vec![0.0],
            })
        },
        grads: |_: &[f64]| Gradients {
            f: vec![0.0; 4],
            eq: vec![],
            ineq: vec![vec![0.0; 4]],
        },
    };
    let e =
        minimize_managed(&mut hs71(), &mut other, &x0, &params, "m", None, &mut ()).unwrap_err();
    assert!(
        matches!(e, SqpError::Params(ref m) if m.contains("different constraints")),
        "{e}"
    );
}

/// A costly fidelity: every function and gradient takes at least `delay_s`, and is counted.
struct Slow<P> {
    inner: P,
    delay_s: f64,
    calls: usize,
}

impl<P: Problem> Slow<P> {
    fn new(inner: P, delay_s: f64) -> Self {
        Slow {
            inner,
            delay_s,
            calls: 0,
        }
    }
    fn wait(&mut self) {
        self.calls += 1;
        std::thread::sleep(std::time::Duration::from_secs_f64(self.delay_s));
    }
}

impl<P: Problem> Problem for Slow<P> {
    fn lower(&self) -> Vec<f64> {
        self.inner.lower()
    }
    fn upper(&self) -> Vec<f64> {
        self.inner.upper()
    }
    fn values(&mut self, x: &[f64]) -> Result<Values, crate::optim::EvalError> {
        self.wait();
        self.inner.values(x)
    }
    fn gradients(&mut self, x: &[f64]) -> Result<Gradients, crate::optim::EvalError> {
        self.wait();
        self.inner.gradients(x)
    }
}

/// The wall time a run reports covers every evaluation of its costly fidelity, the start
/// point's included, in the SQP and in the model management alike (the managed run's clock once
/// started after its start point's function and gradient: on the medium-mesh LFD that left out
/// 17 of 64 minutes). HS71's own arithmetic takes milliseconds, so the time must be at least the
/// evaluations' count times their 50 ms delay.
#[test]
fn the_reported_time_covers_every_costly_evaluation() {
    let delay_s = 0.05;
    let x0 = [1.0, 5.0, 5.0, 1.0];
    let mut high = Slow::new(hs71(), delay_s);
    let params = ManagedParams {
        tolerance: 1e-6,
        ..Default::default()
    };
    let r = minimize_managed(&mut high, &mut hs71_low(), &x0, &params, "m", None, &mut ()).unwrap();
    assert!(r.converged, "{}", r.message);
    assert_eq!(high.calls, r.high_functions + r.high_gradients);
    let floor = high.calls as f64 * delay_s;
    assert!(
        r.elapsed_s >= floor,
        "managed: {} s < {floor} s",
        r.elapsed_s
    );
    let mut slow = Slow::new(hs71(), delay_s);
    let params = SqpParams {
        tolerance: 1e-6,
        ..Default::default()
    };
    let r = minimize(&mut slow, &x0, &params, "s", None, &mut ()).unwrap();
    let floor = slow.calls as f64 * delay_s;
    assert!(r.elapsed_s >= floor, "SQP: {} s < {floor} s", r.elapsed_s);
}
