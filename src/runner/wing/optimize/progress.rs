//! An optimization's progress on the console: a bar, and a line per SQP iteration with the
//! mass, the constrained RMS, the flutter margin, the KKT measure and the time to the limit.

use super::*;

/// Shows each SQP iteration on a progress bar (and as a line on stdout).
pub(super) struct RunObserver {
    pub(super) mass0: f64,
    pub(super) rms_scale: f64,
    pub(super) rms_unit: &'static str,
    pub(super) rms_limit: f64,
    /// Damping limit of the flutter-margin constraint, when there is one.
    pub(super) damping_max: Option<f64>,
    /// Whether the last inequality is a discrete gust peak limit.
    pub(super) peak: bool,
    pub(super) quiet: bool,
    pub(super) bar: indicatif::ProgressBar,
    /// When the previous iteration ended (the run's start before the first).
    pub(super) last: Instant,
    /// The iteration limit, for the bound on the remaining time.
    pub(super) max_iterations: usize,
}

impl RunObserver {
    /// The observer of a run from a design of mass `mass0` (kg), the constrained RMS shown as
    /// (scale to the shown unit, unit, limit in SI), the flutter margin's damping limit and
    /// whether there is a peak limit; a hidden bar when `quiet`.
    pub(super) fn new(
        mass0: f64,
        (rms_scale, rms_unit, rms_limit): (f64, &'static str, f64),
        damping_max: Option<f64>,
        peak: bool,
        quiet: bool,
        max_iterations: usize,
    ) -> Self {
        let bar = if quiet {
            indicatif::ProgressBar::hidden()
        } else {
            indicatif::ProgressBar::new(max_iterations as u64)
        };
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} SQP [{elapsed_precise}] {bar:30} {pos}/{len} iterations  {msg}",
            )
            .expect("valid template"),
        );
        bar.enable_steady_tick(std::time::Duration::from_millis(200));
        RunObserver {
            mass0,
            rms_scale,
            rms_unit,
            rms_limit,
            damping_max,
            peak,
            quiet,
            bar,
            last: Instant::now(),
            max_iterations,
        }
    }
}

/// A wall time for a progress line: seconds below two minutes, then minutes, then hours.
pub(super) fn duration(s: f64) -> String {
    if s < 120.0 {
        format!("{s:.1} s")
    } else if s < 7200.0 {
        format!("{:.1} min", s / 60.0)
    } else {
        format!("{:.1} h", s / 3600.0)
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

/// Prints the limits the optimization sets besides the study's RMS: the discrete gust peak
/// limit and the modal basis kept whole.
pub(super) fn print_limits(
    study: &Study,
    spec: &crate::problem::DesignSpec,
    floor: Option<crate::problem::ModeFloor>,
) {
    if let Some(pl) = &spec.peak {
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
    if let Some(f) = floor {
        println!(
            "modal basis: the {} modes below {:.1} Hz at the initial design; modes {}–{} must stay above it (KS, ρ = {:.0}), mode {} above {:.1} Hz",
            f.retained,
            f.omega_cut / (2.0 * std::f64::consts::PI),
            f.retained + 1,
            f.retained + f.band,
            f.rho(),
            f.retained + f.band + 1,
            crate::problem::FLOOR_GUARD * f.omega_cut / (2.0 * std::f64::consts::PI)
        );
    }
}

/// The line that ends an optimization: why, how long, the mass and the constrained RMS from
/// the initial design (`evs.0`) to the final (`evs.1`), shown as (scale, unit).
pub(super) fn outcome_words(
    info: &crate::optim::SqpInfo,
    (ev0, ev): (&crate::pipeline::Evaluation, &crate::pipeline::Evaluation),
    output: usize,
    (unit_scale, unit): (f64, &str),
) -> String {
    format!(
        "{} after {} iterations ({} evaluations, {:.1} s): mass {:.4} → {:.4} kg ({:+.1} %), RMS {:.4} → {:.4} {unit}",
        info.message,
        info.iterations,
        info.evaluations,
        info.elapsed_s,
        ev0.mass_kg,
        ev.mass_kg,
        100.0 * (ev.mass_kg / ev0.mass_kg - 1.0),
        ev0.rms_m[output] * unit_scale,
        ev.rms_m[output] * unit_scale
    )
}

/// Prints the RMS of every design of a cross-evaluation with each fidelity.
pub(super) fn print_cross_evaluation(c: &crate::report::results::CrossEvaluation, unit: &str) {
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
