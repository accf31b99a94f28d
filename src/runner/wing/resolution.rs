//! The resolution check at the end of `run`, `flutter` and every optimization: the design
//! re-analysed with twice the modes (as many as the plate has, if fewer) and the DLM lattice
//! refined by two in each direction or the LFD on the next mesh level (2× finer in each
//! direction; not run, with the reason, when it does not fit in memory), so that a result that
//! depends on what the model leaves out shows it. A design that fails its flutter margin or RMS
//! limit at the refined resolution beyond the tolerances below does not pass.

use crate::flutter::{PkProblem, Verdict};
use crate::gust::GustSettings;
use crate::report::results::ResolutionCheck;
use crate::study::{ModesSpec, Study};
use anyhow::{Context, Result};
use std::time::Instant;

/// A refined flutter speed may fall this fraction below the margin speed before the check fails
/// (the p-k crossing is refined to 1e-10; one percent is the spread of the flutter speeds of the
/// converged lattices of the AGARD wing's study in the README).
pub const FLUTTER_TOLERANCE: f64 = 0.01;

/// A refined RMS may exceed its limit by this fraction before the check fails (the 400-box
/// lattice moves the flagship's RMS by 2.1 %).
pub const RMS_TOLERANCE: f64 = 0.02;

/// What the design must meet: a flutter-free speed (the margin speed, or the flight speed) and,
/// when constrained, an RMS limit on one output (SI).
#[derive(Clone, Copy, Debug)]
pub struct Requirement {
    pub stable_to_m_s: f64,
    pub rms: Option<(usize, f64)>,
}

/// Why a study's model cannot be refined (before anything is evaluated), if it cannot.
fn not_refinable(study: &Study) -> Option<String> {
    match study.spec.aero.as_ref().map(|a| &a.fidelity) {
        None => Some("the study has no aerodynamic model".into()),
        Some(f) => f.refined().err(),
    }
}

/// The study at the refined resolution and its words, or why there is none.
/// The refined modes reach higher frequencies than the study's table may cover: the table is
/// extended (steps of [`K_STEP`] in k) until the highest refined mode lies inside it at the flight
/// speed, so that no verdict at or above the flight speed rests on GAFs extrapolated beyond the
/// table (on the AGARD wing's initial design, 40 modes up to 667 Hz on 48 × 72 boxes "flutter" at
/// 1.28 × the flight speed by mode 34 with the table ending at k = 2, and do not up to 1.30 × with
/// it extended to k = 6).
const K_STEP: f64 = 1.25;

fn refined_study(
    study: &Study,
    x: &[f64],
    modes_used: usize,
    dofs: usize,
) -> Result<(Study, String), String> {
    let mut s = study.clone();
    let refined_modes = (2 * modes_used).min(dofs);
    s.spec.structure.modes = ModesSpec::Count(refined_modes);
    if let Some(why) = not_refinable(study) {
        return Err(why);
    }
    // the refined modes' highest frequency (a modal analysis is milliseconds beside the DLM)
    let plate = s
        .model_at(crate::wing::DesignVector::from_slice(x))
        .map_err(|e| e.reason)?;
    let omega_top = s
        .solve_modes(&plate)
        .map_err(|e| format!("the refined modal analysis: {e:#}"))?
        .omega()
        .last()
        .copied()
        .unwrap_or(0.0);
    let flight = s.flight_condition().map_err(|e| e.reason)?;
    let k_top = omega_top * flight.b_ref / flight.velocity;
    let aero = s.spec.aero.as_mut().expect("refinable: it has one");
    let k_max = aero.reduced_frequencies.last().copied().unwrap_or(0.0);
    let mut extended = String::new();
    if k_max > 0.0 && k_top > k_max {
        let mut k = k_max;
        while k < k_top {
            k = (k * K_STEP).min(k_top * 1.0001);
            aero.reduced_frequencies.push(k);
        }
        extended = format!(", reduced frequencies to {k:.2}");
    }
    let original = aero.fidelity.clone();
    let (refined, words) = aero.fidelity.refined()?;
    aero.fidelity = refined;
    let model = words + &extended;
    // the second fidelity is not part of the check
    aero.compare_with = None;
    // the refined model leaves nothing in the run folder (the LFD would write its steady state
    // and C_p sections there, which the report takes for the study's own)
    s.cache_dir = None;
    let fits = |s: &Study| s.check_memory(1).and_then(|()| s.validate_fidelity());
    if let Err(e) = fits(&s) {
        // the next lattice or mesh does not fit (an LFD on the medium mesh: the fine one needs
        // about 14.5 GB by the estimate; 19.5 GB was measured before the single-precision ILU):
        // the modes alone are doubled, and the words say what was not refined
        let aero = s.spec.aero.as_mut().expect("refinable: it has one");
        aero.fidelity = original;
        let same = format!(
            "{}{extended} (modes only: the next resolution, {}, cannot run here: {})",
            aero.fidelity.words(),
            model,
            e.reason
        );
        fits(&s).map_err(|e| {
            format!(
                "the refined model ({model}, {refined_modes} modes) cannot run here, nor twice the modes on the study's own model: {}",
                e.reason
            )
        })?;
        return Ok((s, format!("{same}, {refined_modes} modes")));
    }
    Ok((s, format!("{model}, {refined_modes} modes")))
}

/// The words of a study's aerodynamic model and mode count.
fn model_words(study: &Study, modes: usize) -> String {
    match study.spec.aero.as_ref().map(|a| &a.fidelity) {
        Some(f) => format!("{}, {modes} modes", f.words()),
        None => format!("{modes} modes"),
    }
}

/// The flutter verdict of one design's model from a fifth of the flight speed up to the flutter
/// check's factor of it (the optimization report's sweep), and the flight speed.
fn flutter_of(a: &crate::pipeline::Aeroelastic) -> Result<(Verdict, f64)> {
    let f = &a.aero.flight;
    let v_max = super::optimize::FLUTTER_CHECK_FACTOR * f.velocity;
    let r = super::optimize::flutter_sweep(&a.modes, &a.table, f, v_max)?;
    Ok((Verdict::of(&r), f.velocity))
}

/// The RMS of every output and the discrete gust peak over its limit (with a peak limit), or why
/// there are none (the model is unstable at the flight speed).
type Responses = std::result::Result<(Vec<f64>, Option<f64>), String>;

fn rms_of(
    a: crate::pipeline::Aeroelastic,
    settings: Option<&GustSettings>,
    peak: Option<&crate::study::discrete::PeakConstraint>,
) -> Result<Responses> {
    let Some(settings) = settings else {
        return Ok(Ok((Vec::new(), None)));
    };
    let analysis = crate::pipeline::analyse(a, settings)?;
    let ev = match analysis.response() {
        Ok(ev) => ev,
        Err(reason) => return Ok(Err(reason.to_string())),
    };
    let peak = match peak {
        Some(pc) => Some(peak_of(ev, pc)?),
        None => None,
    };
    Ok(Ok((ev.rms_m.clone(), peak)))
}

/// The largest sampled |y| of a peak limit's output over its gusts, over the limit, on the grid
/// the decay rule picks for this model (its own modes and GAF table).
fn peak_of(
    ev: &crate::pipeline::Evaluation,
    pc: &crate::study::discrete::PeakConstraint,
) -> Result<f64> {
    let r = crate::problem::peak_response(ev, pc, None)?;
    Ok(r.largest_abs(pc.output) / pc.limit)
}

/// The resolution check of design `x`: its flutter point and RMS at the study's resolution and at
/// the refined one, and whether the refined model still meets `req`.
pub fn check(
    study: &Study,
    x: &[f64],
    settings: Option<&GustSettings>,
    req: Requirement,
) -> Result<ResolutionCheck> {
    let t0 = Instant::now();
    // the words show the constrained (or first) output's RMS in the study's unit
    let shown = req.rms.map_or(0, |(i, _)| i);
    let (unit_scale, unit) = match settings.and_then(|s| s.outputs.get(shown)) {
        Some(o) => study.spec.length_unit.display(1.0, o.quantity.unit(), 1),
        None => (1.0, "SI"),
    };
    if let Some(why) = not_refinable(study) {
        // nothing to compare with: the design is not analysed again (an LFD analysis is minutes)
        return Ok(ResolutionCheck {
            model: model_words(study, study.max_modes()),
            refined_model: None,
            flight_speed_m_s: study.flight_condition()?.velocity,
            stable_to_m_s: req.stable_to_m_s,
            flutter: "is not analysed again".into(),
            flutter_speed_m_s: None,
            refined_flutter: None,
            refined_flutter_speed_m_s: None,
            rms_m: Vec::new(),
            refined_rms_m: Vec::new(),
            refined_unstable: None,
            rms_limit: req.rms,
            flutter_tolerance: FLUTTER_TOLERANCE,
            rms_tolerance: RMS_TOLERANCE,
            passed: true,
            not_run: Some(why),
            time_s: t0.elapsed().as_secs_f64(),
            rms_unit: unit.into(),
            rms_unit_scale: unit_scale,
            peak: None,
            refined_peak: None,
        });
    }
    let base = crate::pipeline::aeroelastic(&study.resolve()?, x).context("resolution check")?;
    let modes = base.modes.len();
    let dofs = study.retained_dofs(&base.plate);
    let (verdict, flight_speed) = flutter_of(&base)?;
    // an optimization's peak limit is checked beside its RMS limit
    let peak = match req.rms {
        Some(_) => study.peak_constraint()?,
        None => None,
    };
    let rms = rms_of(base, settings, peak.as_ref())?;
    let mut out = ResolutionCheck {
        model: model_words(study, modes),
        refined_model: None,
        flight_speed_m_s: flight_speed,
        stable_to_m_s: req.stable_to_m_s,
        flutter: verdict.words(flight_speed),
        flutter_speed_m_s: verdict.unstable_from(),
        refined_flutter: None,
        refined_flutter_speed_m_s: None,
        rms_m: rms.as_ref().ok().map(|r| r.0.clone()).unwrap_or_default(),
        refined_rms_m: Vec::new(),
        refined_unstable: None,
        rms_limit: req.rms,
        flutter_tolerance: FLUTTER_TOLERANCE,
        rms_tolerance: RMS_TOLERANCE,
        passed: false,
        not_run: None,
        time_s: 0.0,
        rms_unit: unit.into(),
        rms_unit_scale: unit_scale,
        peak: rms.as_ref().ok().and_then(|r| r.1),
        refined_peak: None,
    };
    let (refined, words) = match refined_study(study, x, modes, dofs) {
        Ok(r) => r,
        Err(why) => {
            out.not_run = Some(why);
            out.passed = true;
            out.time_s = t0.elapsed().as_secs_f64();
            return Ok(out);
        }
    };
    let fine = crate::pipeline::aeroelastic(&refined.resolve()?, x)
        .context("resolution check, refined")?;
    let (fine_verdict, _) = flutter_of(&fine)?;
    let fine_rms = rms_of(fine, settings, peak.as_ref())?;
    out.refined_model = Some(words);
    out.refined_flutter = Some(fine_verdict.words(flight_speed));
    out.refined_flutter_speed_m_s = fine_verdict.unstable_from();
    match fine_rms {
        Ok((r, p)) => {
            out.refined_rms_m = r;
            out.refined_peak = p;
        }
        Err(why) => out.refined_unstable = Some(why),
    }
    let flutter_ok = fine_verdict.stable_up_to(req.stable_to_m_s * (1.0 - FLUTTER_TOLERANCE));
    let rms_ok = match req.rms {
        Some((i, limit)) => out
            .refined_rms_m
            .get(i)
            .is_some_and(|r| *r <= limit * (1.0 + RMS_TOLERANCE)),
        None => true,
    };
    // the peak limit with the RMS limit's tolerance
    let peak_ok = out.refined_peak.is_none_or(|p| p <= 1.0 + RMS_TOLERANCE);
    out.passed = flutter_ok && rms_ok && peak_ok && out.refined_unstable.is_none();
    out.time_s = t0.elapsed().as_secs_f64();
    Ok(out)
}

/// The resolution check of `gustkit flutter`: the study's p-k sweep over `velocities` again at the
/// refined resolution. The flutter speeds at both, their difference and the verdicts' words, for
/// flutter.json and the console (a sweep has no margin to fail: it reports).
pub fn flutter_sweep(
    study: &Study,
    velocities: &[f64],
    base: &crate::flutter::FlutterResult,
    dofs: usize,
) -> Result<serde_json::Value> {
    let t0 = Instant::now();
    let modes = base.curves.len();
    let flight = study.flight_condition()?.velocity;
    let verdict = Verdict::of(base);
    let mut doc = serde_json::json!({
        "model": model_words(study, modes),
        "flutter": verdict.words(flight),
        "flutter_speed_m_s": verdict.unstable_from(),
    });
    let x = study.initial_design()?.to_vec();
    match refined_study(study, &x, modes, dofs) {
        Err(why) => doc["not_run"] = why.into(),
        Ok((refined, words)) => {
            let fine = crate::pipeline::aeroelastic(&refined.resolve()?, &x)
                .context("resolution check, refined")?;
            let r = PkProblem::new(&fine.modes, &fine.table, fine.aero.flight.density)
                .sweep(velocities)
                .map_err(|e| anyhow::anyhow!("resolution check, refined: flutter: {e}"))?;
            let v = Verdict::of(&r);
            doc["refined_model"] = words.into();
            doc["refined_flutter"] = v.words(flight).into();
            doc["refined_flutter_speed_m_s"] = v.unstable_from().into();
            if let (Some(a), Some(b)) = (verdict.unstable_from(), v.unstable_from()) {
                doc["change_percent"] = (100.0 * (b / a - 1.0)).into();
            }
        }
    }
    doc["time_s"] = t0.elapsed().as_secs_f64().into();
    Ok(doc)
}
