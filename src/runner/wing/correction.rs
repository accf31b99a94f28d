//! Resolution corrections: when the refined model of the resolution check finds the optimum's
//! RMS above its limit beyond the tolerance, the optimization continues from that optimum with
//! the limit scaled by the ratio of the constrained to the refined RMS measured there (a
//! multiplicative, zeroth-order correction of the cheap model by the refined one, as in
//! variable-fidelity optimization), and the new optimum is checked again. The ratio moves little
//! between neighbouring designs, so the corrected optimum meets the limit at the refined resolution
//! within the check's tolerance. A flutter failure is not corrected: new modes that flutter do not
//! scale.

use super::optimize::{checkpoint_file, optimize_pass, Pass};
use super::resolution::{FLUTTER_TOLERANCE, RMS_TOLERANCE};
use crate::report::results::{
    CrossEvaluation, OptimizationResults, ResolutionCheck, ResolutionCorrection,
};
use crate::study::Study;
use anyhow::{Context, Result};
use std::path::Path;

/// The RMS factor of the next pass (constrained / refined RMS of the checked design), when the
/// check failed on the RMS alone and the refined RMS says by how much; None otherwise.
pub fn rms_factor(c: &ResolutionCheck) -> Option<f64> {
    if c.passed || c.refined_unstable.is_some() || c.not_run.is_some() {
        return None;
    }
    let flutter_ok = c
        .refined_flutter_speed_m_s
        .is_none_or(|v| v >= c.stable_to_m_s * (1.0 - FLUTTER_TOLERANCE));
    let (i, limit) = c.rms_limit?;
    let (coarse, fine) = (*c.rms_m.get(i)?, *c.refined_rms_m.get(i)?);
    let rms_failed = fine > limit * (1.0 + RMS_TOLERANCE);
    (flutter_ok && rms_failed && coarse > 0.0 && fine.is_finite()).then(|| coarse / fine)
}

/// The peak-limit factor of the next pass (constrained / refined peak of the checked design),
/// when the refined peak exceeds its limit beyond the tolerance and the design holds its flutter
/// margin; None otherwise.
pub fn peak_factor(c: &ResolutionCheck) -> Option<f64> {
    if c.passed || c.refined_unstable.is_some() || c.not_run.is_some() {
        return None;
    }
    let flutter_ok = c
        .refined_flutter_speed_m_s
        .is_none_or(|v| v >= c.stable_to_m_s * (1.0 - FLUTTER_TOLERANCE));
    let (coarse, fine) = (c.peak?, c.refined_peak?);
    (flutter_ok && fine > 1.0 + RMS_TOLERANCE && coarse > 0.0 && fine.is_finite())
        .then(|| coarse / fine)
}

/// The corrections of a finished first pass `first` whose check is `check`: up to the study's
/// `resolution_corrections` passes, each from the last optimum, re-checked by `recheck`. Returns
/// the optimization with every pass in it and the last check.
pub fn correct(
    study: &Study,
    dir: &Path,
    resume: bool,
    first: OptimizationResults,
    check: ResolutionCheck,
    recheck: impl Fn(&OptimizationResults) -> Result<ResolutionCheck>,
) -> Result<(OptimizationResults, ResolutionCheck)> {
    let allowed = study
        .spec
        .optimization
        .as_ref()
        .map_or(0, |o| o.resolution_corrections);
    let (mut all, mut check) = (first, check);
    for number in 2..=allowed + 1 {
        if !all.converged {
            break;
        }
        let (rf, pf) = (rms_factor(&check), peak_factor(&check));
        if rf.is_none() && pf.is_none() {
            break;
        }
        let factor = rf.unwrap_or(1.0);
        let (i, _) = check.rms_limit.expect("a correction needs the RMS limit");
        let scale = all.final_.rms_display / all.final_.rms;
        let (coarse, fine) = (check.rms_m[i] * scale, check.refined_rms_m[i] * scale);
        let limit = all.rms_limit * factor;
        if rf.is_some() {
            println!(
                "resolution correction {}: the refined RMS {fine:.4} {u} is {:+.2} % of the constrained {coarse:.4} {u}; the optimization continues from its optimum with the limit {limit:.4} {u}",
                number - 1,
                100.0 * (fine / coarse - 1.0),
                u = all.unit,
            );
        }
        if let (Some(f), Some(p), Some(q)) = (pf, check.peak, check.refined_peak) {
            println!(
                "resolution correction {}: the refined discrete gust peak is {q:.4} × its limit (constrained: {p:.4}); the optimization continues from its optimum with the peak limit × {f:.4}",
                number - 1,
            );
        }
        // the previous pass's BFGS matrix (same bounds, same scaling) starts this one
        let previous = checkpoint_file(dir, number - 1);
        let hessian = std::fs::read_to_string(&previous)
            .ok()
            .and_then(|t| serde_json::from_str::<crate::optim::Checkpoint>(&t).ok())
            .map(|cp| cp.hessian);
        let pass = Pass {
            number,
            rms_factor: factor,
            peak_factor: pf.unwrap_or(1.0),
            start: Some((all.final_.design_variables.clone(), hessian)),
        };
        let next = optimize_pass(study, dir, resume, false, &pass)
            .with_context(|| format!("resolution correction {}", number - 1))?;
        let record = ResolutionCorrection {
            pass: number,
            rms_display: coarse,
            refined_rms_display: fine,
            rms_limit_display: limit,
            peak_factor: pf,
            iterations: next.iterations,
            evaluations: next.evaluations,
            converged: next.converged,
            message: next.message.clone(),
            mass_kg: next.final_.mass_kg,
            wall_time_s: next.wall_time_s,
        };
        all = merge(all, next, record);
        check = recheck(&all)?;
        println!("{}", crate::report::run::resolution_words(&check));
    }
    Ok((all, check))
}

/// The optimization of every pass so far followed by pass `next`: its final design, convergence
/// and cross-evaluation; the iterations, evaluations, wall time and history of both.
fn merge(
    before: OptimizationResults,
    next: OptimizationResults,
    record: ResolutionCorrection,
) -> OptimizationResults {
    let offset = before.history.last().map_or(0, |h| h.iteration + 1);
    let mut history = before.history;
    history.extend(next.history.into_iter().map(|mut h| {
        h.iteration += offset;
        h
    }));
    let mut corrections = before.corrections;
    corrections.push(record);
    OptimizationResults {
        iterations: before.iterations + next.iterations,
        evaluations: before.evaluations + next.evaluations,
        wall_time_s: before.wall_time_s + next.wall_time_s,
        // the study's limit, what the report holds the design to
        rms_limit: before.rms_limit,
        initial: before.initial,
        timing: before.timing,
        warm_start: before.warm_start,
        history,
        corrections,
        cross_evaluation: whole_run_designs(before.cross_evaluation, next.cross_evaluation),
        ..next
    }
}

/// The cross-evaluated designs of the whole run: the first pass's initial and starting designs
/// (the starting one another run's optimum, for `gustkit compare`'s consistency table) and the
/// last pass's final design.
fn whole_run_designs(
    before: Option<CrossEvaluation>,
    next: Option<CrossEvaluation>,
) -> Option<CrossEvaluation> {
    match (before, next) {
        (Some(mut all), Some(next)) => {
            all.designs.retain(|d| d.design != "final");
            all.designs
                .extend(next.designs.into_iter().filter(|d| d.design == "final"));
            Some(all)
        }
        (_, next) => next,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A check of a design constrained to 1.0 whose refined RMS is `fine` and refined flutter
    /// speed `flutter` (margin speed 100 m/s).
    fn check(fine: f64, flutter: Option<f64>) -> ResolutionCheck {
        let flutter_ok = flutter.is_none_or(|v| v >= 99.0);
        ResolutionCheck {
            model: "coarse".into(),
            refined_model: Some("fine".into()),
            flight_speed_m_s: 87.0,
            stable_to_m_s: 100.0,
            flutter: String::new(),
            flutter_speed_m_s: None,
            refined_flutter: None,
            refined_flutter_speed_m_s: flutter,
            rms_m: vec![7.0, 1.0],
            refined_rms_m: vec![7.0, fine],
            refined_unstable: None,
            rms_limit: Some((1, 1.0)),
            flutter_tolerance: FLUTTER_TOLERANCE,
            rms_tolerance: RMS_TOLERANCE,
            passed: flutter_ok && fine <= 1.0 + RMS_TOLERANCE,
            not_run: None,
            time_s: 0.0,
            rms_unit: "m".into(),
            rms_unit_scale: 1.0,
            peak: None,
            refined_peak: None,
        }
    }

    /// A correction pass's cross-evaluation keeps the run's initial and starting designs (the
    /// pass starts at the previous optimum, already analysed as its final design) and takes the
    /// new final design.
    #[test]
    fn the_whole_run_keeps_its_first_start_and_its_last_final_design() {
        let designs = |names: &[(&str, f64)]| CrossEvaluation {
            output: "tip".into(),
            unit: "in".into(),
            flight_speed_m_s: 1.0,
            searched_up_to_m_s: 2.0,
            designs: names
                .iter()
                .map(|(d, m)| crate::report::results::CrossDesign {
                    design: d.to_string(),
                    mass_kg: *m,
                    design_variables: vec![*m],
                    evaluations: Vec::new(),
                })
                .collect(),
        };
        let first = designs(&[("initial", 3.0), ("start", 2.0), ("final", 1.5)]);
        let second = designs(&[("final", 1.4)]);
        let names = |c: Option<CrossEvaluation>| -> Option<Vec<(String, f64)>> {
            c.map(|c| {
                c.designs
                    .iter()
                    .map(|d| (d.design.clone(), d.mass_kg))
                    .collect()
            })
        };
        let owned = |v: &[(&str, f64)]| Some(v.iter().map(|(d, m)| (d.to_string(), *m)).collect());
        let all = whole_run_designs(Some(first.clone()), Some(second.clone()));
        assert_eq!(
            names(all),
            owned(&[("initial", 3.0), ("start", 2.0), ("final", 1.4)])
        );
        // without the first pass's evaluations, the last pass's stand
        assert_eq!(
            names(whole_run_designs(None, Some(second))),
            owned(&[("final", 1.4)])
        );
        assert_eq!(names(whole_run_designs(Some(first), None)), None);
    }

    #[test]
    fn only_an_rms_failure_is_corrected_by_the_ratio() {
        // 4 % above the limit at the refined resolution: the next limit is 1/1.04 of the study's
        let f = rms_factor(&check(1.04, None)).unwrap();
        assert!((f - 1.0 / 1.04).abs() < 1e-15, "{f}");
        // within the tolerance (2 %), or below the limit: nothing to correct
        assert_eq!(rms_factor(&check(1.015, None)), None);
        assert_eq!(rms_factor(&check(0.9, None)), None);
        // a refined flutter below the margin speed is not an RMS matter: no correction
        assert_eq!(rms_factor(&check(1.04, Some(90.0))), None);
        // a flutter point above the margin speed does not stop the RMS correction
        assert!(rms_factor(&check(1.04, Some(150.0))).is_some());
        // unstable at the refined resolution, or no refined model: no correction
        let mut c = check(1.04, None);
        c.refined_unstable = Some("flutters at the flight speed".into());
        assert_eq!(rms_factor(&c), None);
        let mut c = check(1.04, None);
        c.not_run = Some("LFD".into());
        assert_eq!(rms_factor(&c), None);
    }

    /// The peak limit's correction: the ratio of the constrained to the refined peak when the
    /// refined peak exceeds its limit beyond the tolerance, none within it or with flutter.
    #[test]
    fn a_peak_failure_is_corrected_by_the_ratio() {
        let with_peak = |peak: f64, fine: f64, flutter: Option<f64>| {
            let mut c = check(0.9, flutter);
            c.peak = Some(peak);
            c.refined_peak = Some(fine);
            c.passed = false;
            c
        };
        let f = peak_factor(&with_peak(1.0, 1.03, None)).unwrap();
        assert!((f - 1.0 / 1.03).abs() < 1e-15, "{f}");
        assert_eq!(peak_factor(&with_peak(1.0, 1.015, None)), None);
        assert_eq!(peak_factor(&with_peak(1.0, 1.03, Some(90.0))), None);
        // no peak limit: nothing to correct
        assert_eq!(peak_factor(&check(1.04, None)), None);
    }
}
