//! `optimization.model_management`: the study's fidelity minimized through a cheaper one
//! corrected at every accepted point ([`crate::optim::minimize_managed`]), with its own atomic
//! checkpoint per outer iteration and `--resume`.

use super::*;
use crate::optim::{
    minimize_managed, Iterate, ManagedCheckpoint, ManagedInfo, ManagedIterate, ManagedObserver,
    ManagedParams, SqpInfo, SqpParams, SqpStatus,
};
use crate::problem::DesignProblem;

/// The managed run's checkpoint file of a pass.
fn managed_checkpoint_file(dir: &Path, pass: usize) -> std::path::PathBuf {
    match pass {
        1 => dir.join("checkpoint_managed.json"),
        n => dir.join(format!("checkpoint_managed_pass{n}.json")),
    }
}

/// Writes every outer iteration's checkpoint atomically (with the LFD's GMRES warm-start store
/// beside it) and prints its line.
struct ManagedFile {
    path: std::path::PathBuf,
    quiet: bool,
    mass0: f64,
    /// (scale to the display unit, unit, SI limit)
    rms: (f64, &'static str, f64),
    last: Instant,
}

impl ManagedObserver for ManagedFile {
    fn start(&mut self, values: &crate::optim::Values) {
        let took = self.last.elapsed().as_secs_f64();
        self.last = Instant::now();
        if !self.quiet {
            let (scale, unit, limit) = self.rms;
            println!(
                "start point: mass {:.5} kg ({:+.2} %), RMS {:.4} {unit}: its high-fidelity function and gradient {}",
                values.f * self.mass0,
                100.0 * (values.f - 1.0),
                (values.ineq[0] + 1.0) * limit * scale,
                progress::duration(took)
            );
        }
    }
    fn iteration(
        &mut self,
        it: &ManagedIterate,
        cp: &ManagedCheckpoint,
    ) -> Result<Control, String> {
        super::resume::save_checkpoint(&self.path, cp)?;
        let took = self.last.elapsed().as_secs_f64();
        self.last = Instant::now();
        if !self.quiet {
            let (scale, unit, limit) = self.rms;
            let ratio = it
                .ratio
                .map_or("not evaluated".into(), |r| format!("{r:.3}"));
            println!(
                "outer iteration {:>3}: from mass {:.5} kg ({:+.2} %), RMS {:.4} {unit}, violation {:.2e}, KKT {:.2e}; trust radius {:.3e}, step {:.3e}, {} corrected-problem iterations, merit ratio {ratio}: {} (corrected problem: {}); {} high-fidelity functions and {} gradients so far; {}",
                it.iteration,
                it.values.f * self.mass0,
                100.0 * (it.values.f - 1.0),
                (it.values.ineq[0] + 1.0) * limit * scale,
                it.violation,
                it.kkt,
                it.radius,
                it.step,
                it.inner_iterations,
                if it.accepted { "accepted" } else { "rejected" },
                it.inner_outcome,
                it.high_functions,
                it.high_gradients,
                progress::duration(took)
            );
        }
        Ok(Control::Continue)
    }
}

/// Runs the managed minimization of `high` (the study's fidelity) through the study's low
/// fidelity from `x`; its outcome in the SQP's words, the outer iterations as the history.
#[allow(clippy::too_many_arguments)]
pub(super) fn run_managed(
    study: &Study,
    low_study: &Study,
    dir: &Path,
    (pass, resume, quiet): (usize, bool, bool),
    high: &mut DesignProblem,
    x: &[f64],
    inner: SqpParams,
    (mass0, rms): (f64, (f64, &'static str, f64)),
) -> Result<SqpInfo> {
    let m = optimization_section(study)?
        .model_management
        .as_ref()
        .expect("called for a study with model management");
    let (low_basis, _) = design_basis(low_study)?;
    let low_basis = low_basis.resolve()?;
    let mut low = DesignProblem::new(&low_basis, high.settings.clone(), high.spec.clone());
    let (problem_id, _) = open_checkpoint(study, dir, pass, false, true)?;
    let path = managed_checkpoint_file(dir, pass);
    let checkpoint: Option<ManagedCheckpoint> = if resume && path.exists() {
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("--resume: cannot read {}", path.display()))?;
        let cp: ManagedCheckpoint = serde_json::from_str(&text).with_context(|| {
            format!(
                "--resume: {} is not a gustkit checkpoint (corrupted?)",
                path.display()
            )
        })?;
        anyhow::ensure!(
            cp.problem_id == problem_id,
            "{}: --resume: the study changed since {} was written (another problem); run without --resume to start over",
            study.file.display(),
            path.display()
        );
        if !quiet {
            println!("resuming from outer iteration {}", cp.history.len());
        }
        resume_warm_start(dir, quiet);
        Some(cp)
    } else if resume {
        anyhow::bail!(
            "--resume: cannot read {} (no interrupted run to continue: run without --resume)",
            path.display()
        );
    } else {
        None
    };
    let params = ManagedParams {
        max_iterations: m.max_iterations,
        tolerance: inner.tolerance,
        initial_radius: m.initial_radius,
        inner,
        ..Default::default()
    };
    let mut observer = ManagedFile {
        path,
        quiet,
        mass0,
        rms,
        last: Instant::now(),
    };
    let info = minimize_managed(
        high,
        &mut low,
        x,
        &params,
        &problem_id,
        checkpoint,
        &mut observer,
    )
    .map_err(|e| anyhow::anyhow!("optimization (model management): {e}"))?;
    Ok(as_sqp_info(info))
}

/// A managed run in the SQP's words: the outer iterations as the history (their KKT measure
/// the high fidelity's at the point, their evaluations its functions).
fn as_sqp_info(info: ManagedInfo) -> SqpInfo {
    let elapsed_s = info.elapsed_s;
    let history = info
        .history
        .iter()
        .map(|it| Iterate {
            iteration: it.iteration,
            x: it.x.clone(),
            values: it.values.clone(),
            violation: it.violation,
            kkt: it.kkt,
            step: it.step,
            evaluations: it.high_functions,
            alpha: if it.accepted { 1.0 } else { 0.0 },
            failed_trials: 0,
            trial_failure: None,
            recovery: None,
        })
        .collect();
    SqpInfo {
        converged: info.converged,
        status: if info.converged {
            SqpStatus::Converged
        } else {
            SqpStatus::IterationLimit
        },
        iterations: info.iterations,
        evaluations: info.high_functions,
        message: format!(
            "{} (model management: {} outer iterations, {} high-fidelity functions, {} gradients)",
            info.message, info.iterations, info.high_functions, info.high_gradients
        ),
        x: info.x,
        values: info.values,
        history,
        elapsed_s,
    }
}
