//! The cross-evaluation of an optimization's designs with `aero.compare_with`'s fidelity: RMS,
//! p-k flutter point, PSD and GAFs of each design with both fidelities.

use super::*;

/// One design analysed with one fidelity, for the cross-evaluation: the flutter point and GAFs
/// of its aeroelastic model, and its gust response or the reason there is none (the model is
/// unstable at the flight condition).
pub(super) fn fidelity_evaluation(
    model: (
        &crate::aero::AeroModel,
        &crate::structure::Modes,
        &gustkit_core::GafTable,
    ),
    response: std::result::Result<&crate::pipeline::Evaluation, String>,
    output: usize,
    unit_scale: f64,
    v_max: f64,
) -> Result<FidelityEvaluation> {
    let (aero, modes, table) = model;
    let (rms, psd, unstable) = match response {
        Ok(ev) => (Some(ev.rms_m.clone()), Some(psd_series(ev, output)), None),
        Err(reason) => (None, None, Some(reason)),
    };
    Ok(FidelityEvaluation {
        fidelity: aero.name.to_string(),
        model: None,
        rms_display: rms.as_ref().map(|r| r[output] * unit_scale),
        rms,
        unstable,
        flutter: flutter_point(modes, table, &aero.flight, v_max)?,
        psd,
        gafs: table.clone(),
        time_s: 0.0,
    })
}

/// A design to cross-evaluate: its name, design vector, and its evaluation with the study's own
/// fidelity with the time it took, when the run already has it.
pub(super) type CrossPoint<'e> = (
    &'static str,
    Vec<f64>,
    Option<(&'e crate::pipeline::Evaluation, f64)>,
);

/// The designs analysed with the study's fidelity and with `other` (the study with the
/// cross-evaluation fidelity): RMS, p-k flutter point, PSD and GAFs of each. A design that one
/// fidelity finds unstable at the flight condition gets its flutter point and GAFs from it, and
/// the reason in place of an RMS.
pub(super) fn cross_evaluate(
    study: &Study,
    other: &Study,
    settings: &crate::gust::GustSettings,
    designs: &[CrossPoint<'_>],
    output: usize,
    unit_scale: f64,
    unit: &str,
) -> Result<CrossEvaluation> {
    let flight = study.flight_condition()?;
    let v_max = FLUTTER_CHECK_FACTOR * flight.velocity;
    let analyse = |s: &Study, x: &[f64], what: &str| -> Result<FidelityEvaluation> {
        let context = || format!("cross-evaluation of the {what} design");
        let t = Instant::now();
        let model = crate::pipeline::aeroelastic(&s.resolve()?, x).with_context(context)?;
        // an unstable model has no gust response: its flutter point and GAFs, and the reason
        let analysis = crate::pipeline::analyse(model, settings).with_context(context)?;
        let mut e = fidelity_evaluation(
            analysis.parts(),
            analysis.response().map_err(str::to_string),
            output,
            unit_scale,
            v_max,
        )?;
        e.time_s = t.elapsed().as_secs_f64();
        e.model = s.aero_model_words();
        Ok(e)
    };
    let designs = designs
        .iter()
        .map(|(name, x, own)| -> Result<CrossDesign> {
            let own_eval = match own {
                Some((ev, t)) => FidelityEvaluation {
                    time_s: *t,
                    model: study.aero_model_words(),
                    ..fidelity_evaluation(
                        (&ev.aero, &ev.modes, &ev.table),
                        Ok(ev),
                        output,
                        unit_scale,
                        v_max,
                    )?
                },
                None => analyse(study, x, name)?,
            };
            let mass_kg = study
                .model_at(crate::wing::DesignVector::from_slice(x))?
                .mass();
            Ok(CrossDesign {
                design: name.to_string(),
                mass_kg,
                design_variables: x.clone(),
                evaluations: vec![own_eval, analyse(other, x, name)?],
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(CrossEvaluation {
        output: settings.outputs[output].name.clone(),
        unit: unit.to_string(),
        flight_speed_m_s: flight.velocity,
        searched_up_to_m_s: v_max,
        designs,
    })
}
