//! `aero.compare_with` in an analysis run: the study's initial design analysed again with the
//! second fidelity (GAF table, gust response, p-k sweep), beside the study's own results.

use super::gust::psd_series;
use crate::pipeline::{aeroelastic, analyse, Evaluation};
use crate::report::results::FidelityComparison;
use crate::study::Study;
use anyhow::{Context, Result};

/// The analysis with `other` (the study with its second fidelity) at the initial design, and
/// the GAF table of the study's own fidelity (`own`, when the gust analysis already has it).
pub(crate) fn compare_fidelities(
    study: &Study,
    other: &Study,
    own: Option<&Evaluation>,
) -> Result<FidelityComparison> {
    let (case, case_other) = (study.resolve()?, other.resolve()?);
    let x = case.initial.to_vec();
    let context = |what: &str| format!("{}: aero.compare_with: {what}", study.file.display());
    let own_model;
    let (fidelity, gafs) = match own {
        Some(ev) => (ev.aero.name, ev.table.clone()),
        None => {
            own_model = aeroelastic(&case, &x).with_context(|| context("own fidelity"))?;
            (own_model.aero.name, own_model.table.clone())
        }
    };
    let model = aeroelastic(&case_other, &x).with_context(|| context("the second fidelity"))?;
    let other_name = model.aero.name;
    let gafs_other = model.table.clone();
    let flutter_other = match study.spec.flutter {
        Some(_) => Some(
            crate::flutter::PkProblem::new(&model.modes, &model.table, model.aero.flight.density)
                .sweep(&study.flutter_velocities()?)
                .with_context(|| context("p-k sweep"))?,
        ),
        None => None,
    };
    let (mut rms_other, mut psd_other, mut unstable_other) = (None, Vec::new(), None);
    if study.spec.gust.is_some() {
        let settings = study.gust_settings()?;
        let analysis = analyse(model, &settings).with_context(|| context("gust response"))?;
        match analysis.response() {
            Err(reason) => unstable_other = Some(reason.to_string()),
            Ok(ev) => {
                psd_other = (0..ev.rms_m.len()).map(|i| psd_series(ev, i)).collect();
                rms_other = Some(ev.rms_m.clone());
            }
        }
    }
    let (gaf_difference_ss, gaf_difference_gs) =
        FidelityComparison::differences(&gafs, &gafs_other);
    Ok(FidelityComparison {
        fidelity: fidelity.to_string(),
        other: other_name.to_string(),
        gafs,
        gafs_other,
        gaf_difference_ss,
        gaf_difference_gs,
        rms_other,
        psd_other,
        unstable_other,
        flutter_other,
    })
}
