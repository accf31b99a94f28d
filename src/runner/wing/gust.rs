//! The gust response of a wing study at its design (paper Eqs. 16–18) and the σ_w calibration
//! it records.

use crate::report::figures::PsdSeries;
use crate::report::results::{GustResults, OutputRow};
use crate::study::Study;
use anyhow::{Context, Result};

/// The response PSD of output `i` of an evaluation, for the figures: at most about 500 of the
/// log-spaced grid points (every n-th and the last), so that results.json stays small.
pub(crate) fn psd_series(ev: &crate::pipeline::Evaluation, i: usize) -> PsdSeries {
    let o = &ev.settings().outputs[i];
    let n = ev.grid.omega.len();
    let stride = n.div_ceil(500).max(1);
    let keep: Vec<usize> = (0..n).filter(|j| j % stride == 0 || *j == n - 1).collect();
    PsdSeries {
        label: o.name.clone(),
        unit: o.quantity.unit().to_string(),
        omega_rad_s: keep.iter().map(|&j| ev.grid.omega[j]).collect(),
        psd: keep.iter().map(|&j| ev.response.psd[i][j]).collect(),
    }
}

/// The gust response part of the results at the study's design, with the evaluation it came from.
pub(crate) fn gust_results(study: &Study) -> Result<(GustResults, crate::pipeline::Evaluation)> {
    let case = study.resolve()?;
    let settings = case.gust_settings()?;
    let ev = crate::pipeline::evaluate(&case, settings, &case.initial.to_vec())
        .with_context(|| format!("{}: gust analysis", study.file.display()))?;
    let f = ev.aero.flight;
    let outputs: Vec<OutputRow> = settings
        .outputs
        .iter()
        .enumerate()
        .map(|(i, o)| OutputRow {
            name: o.name.clone(),
            rms: ev.rms_m[i],
            unit: o.quantity.unit().to_string(),
            n0_hz: ev.n0_hz[i],
        })
        .collect();
    for o in &outputs {
        let (rms, unit) = study.spec.length_unit.display(o.rms, &o.unit, 1);
        println!(
            "RMS {}: {} {unit}",
            o.name,
            crate::report::style::tick(&rms)
        );
    }
    let spec = study.spec.gust.as_ref().expect("checked by gust_settings");
    let calibration = match &spec.calibration {
        Some(c) => {
            let i = settings
                .outputs
                .iter()
                .position(|o| o.name == c.output)
                .with_context(|| {
                    format!(
                        "{}: gust.calibration.output: no gust output named '{}'",
                        study.file.display(),
                        c.output
                    )
                })?;
            let (to_unit, unit) =
                study
                    .spec
                    .length_unit
                    .display(1.0, settings.outputs[i].quantity.unit(), 1);
            let rms = ev.rms_m[i] * to_unit;
            let sigma = settings.turbulence.sigma();
            println!(
                "σ_w calibration: RMS {} {rms:.5} {unit} (target {} {unit}); σ_w for the target {:.5} m/s",
                c.output,
                c.target_rms,
                sigma * c.target_rms / rms
            );
            Some(crate::report::results::Calibration {
                output: c.output.clone(),
                target_rms: c.target_rms,
                rms,
                unit: unit.to_string(),
                sigma_w_m_s: sigma,
                sigma_w_for_target_m_s: sigma * c.target_rms / rms,
                source: c.source.clone(),
            })
        }
        None => None,
    };
    let results = GustResults {
        mach: f.mach,
        velocity_m_s: f.velocity,
        density_kg_m3: f.density,
        q_inf_pa: f.q_inf(),
        turbulence: settings.turbulence,
        n_omega: ev.grid.omega.len(),
        mode_acceleration: ev.residual.is_some(),
        omega_max_rad_s: ev.grid.omega.last().copied().unwrap_or(0.0),
        psd: (0..outputs.len()).map(|i| psd_series(&ev, i)).collect(),
        outputs,
        calibration,
    };
    Ok((results, ev))
}
