//! The discrete gust analysis of a wing study at an evaluated design: the tuned 1-cos search or
//! the tabulated profile, on the gust section's outputs (and their accelerations), with its
//! results, CSV files and console lines.

use crate::gust::discrete::{tuned_search, TransientSettings};
use crate::gust::{Quantity, ResidualGafs};
use crate::report::discrete::{
    decimate, envelope_csv, CriticalRow, DiscreteGustResults, DiscreteOutput, EnvelopeRow,
    HistoryRow,
};
use crate::report::write_atomic;
use crate::study::discrete::DiscreteCase;
use crate::study::Study;
use anyhow::{Context, Result};
use std::path::Path;
use std::time::Instant;

/// Memory the grid and histories may take, bytes (the time grid is small beside the models:
/// 2 GB is far above any span the decay rule picks).
const MAX_BYTES: f64 = 2e9;

/// The residual rows of the outputs, each displacement output's repeated for its acceleration.
fn with_rows(r: &ResidualGafs, extra: &[usize]) -> ResidualGafs {
    let mut out = r.clone();
    for (i, row) in out.q_ws.iter_mut().enumerate() {
        for &y in extra {
            row.push(r.q_ws[i][y].clone());
        }
    }
    for (i, row) in out.q_wg.iter_mut().enumerate() {
        for &y in extra {
            row.push(r.q_wg[i][y]);
        }
    }
    out
}

/// A labelled CSV column of a history.
type Column = (String, Vec<f64>);

/// Runs the study's discrete gust analysis on evaluation `ev` (none without the section) and
/// writes its CSV files into `dir`.
pub(crate) fn discrete_results(
    study: &Study,
    ev: &crate::pipeline::Evaluation,
    dir: &Path,
) -> Result<Option<DiscreteGustResults>> {
    let Some(settings) = study.discrete_gust_settings()? else {
        return Ok(None);
    };
    let t0 = Instant::now();
    let file = study.file.display();
    let gust = ev.settings();
    let mut p = ev.problem();
    let mut outputs: Vec<DiscreteOutput> = gust
        .outputs
        .iter()
        .map(|o| DiscreteOutput {
            name: o.name.clone(),
            unit: o.quantity.unit().to_string(),
        })
        .collect();
    let mut derivative = vec![0u32; outputs.len()];
    let extra: Vec<usize> = if settings.accelerations {
        gust.outputs
            .iter()
            .enumerate()
            .filter(|(_, o)| matches!(o.quantity, Quantity::Displacement { .. }))
            .map(|(i, _)| i)
            .collect()
    } else {
        Vec::new()
    };
    for &y in &extra {
        p.outputs.push(p.outputs[y].clone());
        outputs.push(DiscreteOutput {
            name: format!("{}_acceleration", gust.outputs[y].name),
            unit: "m/s²".into(),
        });
        derivative.push(2);
    }
    let rows = p.residual.map(|r| with_rows(r, &extra));
    p.residual = rows.as_ref();
    let velocity = p.velocity;
    let omega_max = p.table_omega_max();
    let s = TransientSettings {
        span: settings.span,
        omega_max,
        derivative,
        keep_histories: true,
        max_bytes: MAX_BYTES,
    };
    let what = || format!("{file}: discrete gust analysis");
    let mut results = DiscreteGustResults {
        profile: String::new(),
        amplitude: String::new(),
        velocity_m_s: velocity,
        span_s: 0.0,
        span_chosen: settings.span.is_none(),
        d_omega_rad_s: 0.0,
        omega_max_rad_s: 0.0,
        n_time: 0,
        wrap_max: 0.0,
        truncated_max: 0.0,
        outputs: outputs.clone(),
        envelope: Vec::new(),
        critical: Vec::new(),
        histories: Vec::new(),
        time_s: 0.0,
    };
    let mut full: Vec<(String, Vec<Column>)> = Vec::new();
    let time = match &settings.case {
        DiscreteCase::Tuned {
            range_m,
            points,
            amplitude,
        } => {
            let amp = |h: f64| amplitude.at(h);
            let r = tuned_search(&p, &s, *range_m, *points, &amp, velocity).with_context(what)?;
            results.amplitude = amplitude.words();
            tuned_results(r, &outputs, &mut results, &mut full)
        }
        DiscreteCase::Tabulated(profile) => {
            let (r, _) = crate::gust::discrete::transient(&p, std::slice::from_ref(profile), &s)
                .with_context(what)?;
            let (ts, te) = profile.support();
            results.amplitude = format!(
                "tabulated w_g(t) from {ts} s to {te} s, peak {:.4} m/s",
                profile.peak()
            );
            tabulated_results(r, &outputs, &mut results, &mut full)
        }
    };
    results.span_s = time.span;
    results.d_omega_rad_s = time.d_omega;
    results.omega_max_rad_s = time.omega.last().copied().unwrap_or(0.0);
    results.n_time = time.time.len();
    // CSV files: lengths in the study's unit, every other quantity in SI
    let unit = study.spec.length_unit;
    write_csv_files(dir, &results, &full, &time, unit)?;
    results.time_s = t0.elapsed().as_secs_f64();
    print_critical(&results, unit);
    Ok(Some(results))
}

/// The tuned 1-cos search's results: the envelope over H, each output's critical gusts and
/// their histories (decimated for the report, whole in `full` for the CSV files); its grid.
fn tuned_results(
    r: crate::gust::discrete::TunedResult,
    outputs: &[DiscreteOutput],
    results: &mut DiscreteGustResults,
    full: &mut Vec<(String, Vec<Column>)>,
) -> crate::gust::discrete::TimeGrid {
    results.profile = "one_minus_cosine".into();
    results.wrap_max = r.wrap_max;
    results.truncated_max = r.truncated_max;
    results.envelope = r
        .envelope
        .iter()
        .map(|e| EnvelopeRow {
            gradient_m: e.gradient,
            gradient_ft: e.gradient / crate::gust::discrete::profile::FOOT,
            amplitude_m_s: e.amplitude,
            refined: e.refined,
            max: e.peaks.iter().map(|p| p.0.value).collect(),
            t_max_s: e.peaks.iter().map(|p| p.0.time).collect(),
            min: e.peaks.iter().map(|p| p.1.value).collect(),
            t_min_s: e.peaks.iter().map(|p| p.1.time).collect(),
        })
        .collect();
    let ft = |h: f64| h / crate::gust::discrete::profile::FOOT;
    for (y, (hi, lo)) in r.critical.iter().enumerate() {
        let o = &outputs[y];
        results.critical.push(CriticalRow {
            output: o.name.clone(),
            unit: o.unit.clone(),
            max: hi.peak.value,
            t_max_s: hi.peak.time,
            gradient_max_ft: Some(ft(hi.gradient)),
            min: lo.peak.value,
            t_min_s: lo.peak.time,
            gradient_min_ft: Some(ft(lo.gradient)),
        });
        let (hmax, hmin) = &r.histories[y];
        full.push((
            o.name.clone(),
            vec![
                (
                    format!("at H = {:.1} ft (max)", ft(hi.gradient)),
                    hmax.clone(),
                ),
                (
                    format!("at H = {:.1} ft (min)", ft(lo.gradient)),
                    hmin.clone(),
                ),
            ],
        ));
        for (gust_name, g, h) in [("max", hi.gradient, hmax), ("min", lo.gradient, hmin)] {
            let (t, v) = decimate(&r.response.grid.time, h);
            results.histories.push(HistoryRow {
                output: o.name.clone(),
                unit: o.unit.clone(),
                gust: gust_name.into(),
                gradient_ft: Some(ft(g)),
                time_s: t,
                value: v,
            });
        }
    }
    r.response.grid
}

/// A tabulated profile's results: each output's extremes and history; its grid.
fn tabulated_results(
    r: crate::gust::discrete::TransientResponse,
    outputs: &[DiscreteOutput],
    results: &mut DiscreteGustResults,
    full: &mut Vec<(String, Vec<Column>)>,
) -> crate::gust::discrete::TimeGrid {
    results.profile = "tabulated".into();
    let pr = &r.profiles[0];
    results.wrap_max = pr.wrap.iter().copied().fold(0.0, f64::max);
    results.truncated_max = pr.truncated;
    for (y, o) in outputs.iter().enumerate() {
        let (hi, lo) = pr.peaks[y];
        results.critical.push(CriticalRow {
            output: o.name.clone(),
            unit: o.unit.clone(),
            max: hi.value,
            t_max_s: hi.time,
            gradient_max_ft: None,
            min: lo.value,
            t_min_s: lo.time,
            gradient_min_ft: None,
        });
        let (t, v) = decimate(&r.grid.time, &pr.histories[y]);
        results.histories.push(HistoryRow {
            output: o.name.clone(),
            unit: o.unit.clone(),
            gust: "profile".into(),
            gradient_ft: None,
            time_s: t,
            value: v,
        });
        full.push((
            o.name.clone(),
            vec![("profile".into(), pr.histories[y].clone())],
        ));
    }
    r.grid
}

/// Writes each output's whole histories (`discrete_gust_<output>.csv`, lengths in the study's
/// unit) and, for a tuned search, the envelope over H.
fn write_csv_files(
    dir: &Path,
    results: &DiscreteGustResults,
    full: &[(String, Vec<Column>)],
    time: &crate::gust::discrete::TimeGrid,
    unit: crate::units::LengthUnit,
) -> Result<()> {
    for (name, columns) in full {
        let si = &results
            .outputs
            .iter()
            .find(|o| &o.name == name)
            .expect("own output")
            .unit;
        let (scale, u) = unit.display(1.0, si, 1);
        let mut csv = String::from("time [s]");
        for (label, _) in columns {
            csv += &format!(",{name} {label} [{u}]");
        }
        csv += "\n";
        for (i, t) in time.time.iter().enumerate() {
            csv += &format!("{t}");
            for (_, v) in columns {
                csv += &format!(",{}", v[i] * scale);
            }
            csv += "\n";
        }
        write_atomic(
            &dir.join(format!("discrete_gust_{name}.csv")),
            csv.as_bytes(),
        )?;
    }
    if results.profile != "tabulated" {
        write_atomic(
            &dir.join("discrete_gust_envelope.csv"),
            envelope_csv(results, unit).as_bytes(),
        )?;
    }
    Ok(())
}

/// One console line an output: its extremes, when and (a tuned search) at which H.
fn print_critical(results: &DiscreteGustResults, unit: crate::units::LengthUnit) {
    for c in &results.critical {
        let (mx, u) = unit.display(c.max, &c.unit, 1);
        let (mn, _) = unit.display(c.min, &c.unit, 1);
        let at = |g: Option<f64>| g.map_or(String::new(), |g| format!(", H = {g:.1} ft"));
        println!(
            "discrete gust {}: max {} {u} (t = {:.4} s{}), min {} {u} (t = {:.4} s{})",
            c.output,
            crate::report::style::tick(&mx),
            c.t_max_s,
            at(c.gradient_max_ft),
            crate::report::style::tick(&mn),
            c.t_min_s,
            at(c.gradient_min_ft)
        );
    }
}
