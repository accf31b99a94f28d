//! The design problem of a study's `optimization` section: bounds, the constrained output and
//! its limit, the flutter margin, the modal basis kept whole, the discrete gust peak limit, and
//! the snapshot of a design that the results keep.

use super::*;

/// A design as the report shows it: values, planform, thickness map and the PSD of `output`.
pub(super) fn snapshot(
    study: &Study,
    ev: &crate::pipeline::Evaluation,
    output: usize,
    unit_scale: f64,
) -> DesignSnapshot {
    let to_m = study.spec.length_unit.to_m();
    let mesh = &ev.plate.mesh;
    DesignSnapshot {
        mass_kg: ev.mass_kg,
        area_m2: ev.area_m2,
        rms_display: ev.rms_m[output] * unit_scale,
        rms: ev.rms_m[output],
        frequencies_hz: ev.freq_hz.clone(),
        design_variables: ev.x.clone(),
        elements: element_polygons(&ev.plate, to_m),
        thickness: (0..mesh.elements.len())
            .map(|e| ev.plate.element_thickness(e) / to_m)
            .collect(),
        psd: psd_series(ev, output),
    }
}

/// The design problem of the study's `optimization` section: bounds `lower`/`upper`, the
/// constrained output and its limit in SI, the flutter margin, and the initial design's
/// evaluation `ev0` as the reference of mass and area; an error for a study without one (or
/// whose output is not among the gust outputs, which loading refuses).
pub(crate) fn design_spec(
    study: &Study,
    settings: &crate::gust::GustSettings,
    ev0: &crate::pipeline::Evaluation,
    lower: Vec<f64>,
    upper: Vec<f64>,
) -> Result<crate::problem::DesignSpec> {
    let o = optimization_section(study)?;
    let (output, rms_limit) = rms_constraint(study, settings).with_context(|| {
        format!(
            "{}: optimization.output: '{}' is not one of the gust outputs",
            study.file.display(),
            o.output
        )
    })?;
    Ok(crate::problem::DesignSpec {
        lower,
        upper,
        output,
        rms_limit,
        mass0: ev0.mass_kg,
        area0: ev0.area_m2,
        fix_area: o.fix_area,
        flutter: o
            .flutter_margin
            .as_ref()
            .map(|m| crate::flutter::margin::FlutterMargin {
                speed_factor: m.speed_factor,
                damping_max: m.damping_max,
            }),
        mode_floor: None,
        peak: None,
    })
}

/// The discrete gust peak limit of the study's optimization (none without one): its grid is the
/// one the decay rule chooses at the initial design, with twice the span (or the study's span).
pub(crate) fn peak_limit(
    study: &Study,
    ev0: &crate::pipeline::Evaluation,
) -> Result<Option<crate::problem::PeakLimit>> {
    let Some(constraint) = study.peak_constraint()? else {
        return Ok(None);
    };
    let settings = study
        .discrete_gust_settings()?
        .expect("checked with the constraint");
    let r = crate::problem::peak_response(ev0, &constraint, settings.span).with_context(|| {
        format!(
            "{}: discrete gust peak limit at the initial design",
            study.file.display()
        )
    })?;
    let span = if settings.span.is_some() {
        r.grid.span
    } else {
        2.0 * r.grid.span
    };
    let grid = crate::gust::discrete::TimeGrid::new(span, ev0.problem().table_omega_max())
        .map_err(anyhow::Error::msg)?;
    Ok(Some(crate::problem::PeakLimit { constraint, grid }))
}

/// The constrained gust output of the study's `optimization` section: its index among the
/// settings' outputs and its RMS limit in SI (a displacement limit is in the study's length unit).
/// None without an optimization or when the output is not among `settings`.
pub(crate) fn rms_constraint(
    study: &Study,
    settings: &crate::gust::GustSettings,
) -> Option<(usize, f64)> {
    let o = study.spec.optimization.as_ref()?;
    let output = settings
        .outputs
        .iter()
        .position(|out| out.name == o.output)?;
    let is_disp = matches!(
        settings.outputs[output].quantity,
        crate::gust::Quantity::Displacement { .. }
    );
    let to_m = study.spec.length_unit.to_m();
    Some((output, if is_disp { o.rms_max * to_m } else { o.rms_max }))
}

/// The study as its optimization sees it: with a basis chosen by the cutoff rule, the count of
/// modes below the cutoff at the initial design, kept whole by a floor on the modes left out
/// ([`crate::problem::ModeFloor`]); otherwise the study itself and no floor. The final design is
/// reported and checked with the same basis.
pub(crate) fn design_basis(study: &Study) -> Result<(Study, Option<crate::problem::ModeFloor>)> {
    let crate::study::ModeRule::Cutoff { omega_cut, .. } = study.mode_rule()? else {
        return Ok((study.clone(), None));
    };
    let plate = study
        .model_at(crate::wing::DesignVector::from_slice(
            &study.initial_design()?.to_vec(),
        ))
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let retained = study.solve_modes(&plate).context("initial design")?.len();
    let mut fixed = study.clone();
    fixed.spec.structure.modes = crate::study::schema::ModesSpec::Count(retained);
    Ok((
        fixed,
        Some(crate::problem::ModeFloor::new(
            retained,
            omega_cut,
            study.retained_dofs(&plate),
        )),
    ))
}

/// The study's `optimization` section, or an error naming the file (a runner asked for an
/// optimization of a study without one).
pub(crate) fn optimization_section(study: &Study) -> Result<&crate::study::OptimizationSpec> {
    study.spec.optimization.as_ref().with_context(|| {
        format!(
            "{}: the study has no optimization section",
            study.file.display()
        )
    })
}

/// The discrete gust peak limit's values at the initial and final designs (KS and largest
/// sampled |y| over the limit), with a line on the console unless `quiet`.
pub(super) fn peak_limit_result(
    study: &Study,
    pl: &crate::problem::PeakLimit,
    ev0: &crate::pipeline::Evaluation,
    ev: &crate::pipeline::Evaluation,
    quiet: bool,
) -> Result<crate::report::results::PeakLimitResult> {
    let (_, k0) = pl.evaluate(ev0)?;
    let (_, k1) = pl.evaluate(ev)?;
    let (limit, unit) = study
        .spec
        .length_unit
        .display(pl.constraint.limit, &pl.constraint.unit, 1);
    if !quiet {
        println!(
            "discrete gust peak |{}|: {:.4} → {:.4} × the limit {} {unit} (KS {:.4} → {:.4})",
            pl.constraint.name,
            k0.peak,
            k1.peak,
            crate::report::style::tick(&limit),
            k0.ks,
            k1.ks
        );
    }
    Ok(crate::report::results::PeakLimitResult {
        output: pl.constraint.name.clone(),
        limit,
        unit: unit.to_string(),
        gusts: pl.constraint.gusts.len(),
        ks_rho: k1.rho,
        initial_ks: k0.ks,
        initial_peak: k0.peak,
        final_ks: k1.ks,
        final_peak: k1.peak,
    })
}

/// The report's row of every SQP iterate: mass, constrained RMS (shown: the
/// SI limit times the unit scale, with the pass number), area, flutter damping and the largest p-k
/// damping of the iterate (from `peaks`, the problem's records, or `evaluate`d again for the
/// iterates of an earlier session).
pub(super) fn history_rows(
    info: &crate::optim::SqpInfo,
    ev0: &crate::pipeline::Evaluation,
    spec: &crate::problem::DesignSpec,
    (rms_limit, unit_scale, pass): (f64, f64, usize),
    mut peaks: Vec<(Vec<f64>, f64)>,
    evaluate: impl Fn(&[f64]) -> Result<crate::pipeline::Evaluation>,
) -> Result<Vec<HistoryRow>> {
    let mut peak_at = |x: &[f64]| -> Result<Option<f64>> {
        let Some(m) = &spec.flutter else {
            return Ok(None);
        };
        if let Some((_, g)) = peaks.iter().rev().find(|(px, _)| px.as_slice() == x) {
            return Ok(Some(*g));
        }
        let g = evaluate(x)?.flutter_damping(m)?.2.peak();
        peaks.push((x.to_vec(), g));
        Ok(Some(g))
    };
    info.history
        .iter()
        .map(|it| -> Result<HistoryRow> {
            Ok(HistoryRow {
                iteration: it.iteration,
                mass_kg: it.values.f * ev0.mass_kg,
                rms_display: (it.values.ineq[0] + 1.0) * rms_limit * unit_scale,
                area_m2: it
                    .values
                    .eq
                    .first()
                    .map_or(ev0.area_m2, |h| (h + 1.0) * ev0.area_m2),
                flutter_damping: match (it.values.ineq.get(1), &spec.flutter) {
                    (Some(c), Some(m)) => Some(m.damping_max + c * DAMPING_SCALE),
                    _ => None,
                },
                flutter_damping_peak: peak_at(&it.x)?,
                violation: it.violation,
                kkt: it.kkt,
                evaluations: it.evaluations,
                pass,
            })
        })
        .collect()
}
