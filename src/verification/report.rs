//! The results of a CFD verification run (results.json) and the report rendered from them alone.

use super::schema::CfdSpec;
use crate::kind::StudyKind;
use crate::report::figures::{LinePlot, Series};
use crate::report::save_figure;
use anyhow::Result;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One row of Table 1: force coefficients in body axes (x along the chord, z up), normalized by
/// the dynamic pressure of the total speed and the chord.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct ForceRow {
    pub case: String,
    pub cx: f64,
    pub cz: f64,
    pub newton_iterations: usize,
    pub residual_history: Vec<f64>,
}

/// Wall pressure coefficients, (x/c, C_p), upper and lower surface.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct PressureDistribution {
    pub label: String,
    pub upper: Vec<(f64, f64)>,
    pub lower: Vec<(f64, f64)>,
}

/// Results of the steady-gust verification.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct SteadyGustResults {
    pub alpha_deg: f64,
    pub gust_mach: f64,
    pub reduced_mach: f64,
    pub table1: Vec<ForceRow>,
    pub digits_cx: f64,
    pub digits_cz: f64,
    pub pressure: Vec<PressureDistribution>,
}

/// Results of the time-domain gust run.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct TimeGustResults {
    pub amplitude_mach: f64,
    pub reduced_frequency: f64,
    pub dt: f64,
    /// (t, C_L) at every time level, t in units of chord / a∞.
    pub lift_history: Vec<(f64, f64)>,
    /// C_L amplitude fitted over each period.
    pub amplitudes: Vec<f64>,
    /// Sears's incompressible amplitude with the Prandtl–Glauert factor.
    pub sears_pg_amplitude: f64,
    pub max_newton_iterations: usize,
    pub pressure_final: PressureDistribution,
}

/// Everything a CFD verification run writes to results.json.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct CfdResults {
    /// Always `cfd_verification`.
    pub kind: StudyKind,
    pub study: String,
    pub description: String,
    pub cfd: CfdSpec,
    pub cells: usize,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steady_gust: Option<SteadyGustResults>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_gust: Option<TimeGustResults>,
    /// Paper Table 2 (with `digits_fourier` and `digits_bdf2`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub table2: Option<super::table2::Table2>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_motion: Option<super::motion::TimeMotionResults>,
    pub run_time_s: f64,
}

/// The markdown summary of a CFD verification run.
pub fn summary(r: &CfdResults) -> String {
    let mesh = match (&r.cfd.mesh, &r.cfd.mesh_file) {
        (Some(m), _) => format!(
            "NACA 64A010 (NACA Report 903 ordinates), O-mesh {} × {} = {} cells, far field at {} chords, first cell {} chords",
            m.n_around, m.n_radial, r.cells, m.far_field_chords, m.first_spacing_chords
        ),
        (None, Some(f)) => format!("mesh file {} ({} cells)", f.path, r.cells),
        (None, None) => String::new(),
    };
    let mut md = format!(
        "# {}\n\n{}\n\n{mesh}; {} order, Roe flux; M = {}.\n",
        r.study, r.description, r.cfd.order, r.cfd.mach
    );
    if let Some(s) = &r.steady_gust {
        md += &format!(
            "\n## Table 1: angle of attack vs uniform gust\n\nα = {}°; gust w = {:.6} (Mach) with the free stream reduced to M = {:.6} (same total speed). Body-axis coefficients.\n\n| case | C_x | C_z | Newton iterations |\n|---|---:|---:|---:|\n",
            s.alpha_deg, s.gust_mach, s.reduced_mach
        );
        for row in &s.table1 {
            md += &format!(
                "| {} | {:.15e} | {:.15e} | {} |\n",
                row.case, row.cx, row.cz, row.newton_iterations
            );
        }
        md += &format!(
            "\nAgreeing significant digits: C_x {:.1}, C_z {:.1} (the paper: 12 and 11).\n\n![residuals](residuals.png)\n\n![pressure](pressure.png)\n\nFlow fields for ParaView: `flow_aoa.vtk`, `flow_gust.vtk`.\n",
            s.digits_cx, s.digits_cz
        );
    }
    if let Some(t) = &r.time_gust {
        md += &format!(
            "\n## Fig. 1: sinusoidal gust in the time domain\n\nAmplitude {} (Mach), k = {}; BDF2 with Δt = {:.4} (chord/a∞), dual-time Newton–Krylov (at most {} iterations a step).\n\n| period | C_L amplitude |\n|---:|---:|\n",
            t.amplitude_mach, t.reduced_frequency, t.dt, t.max_newton_iterations
        );
        for (i, a) in t.amplitudes.iter().enumerate() {
            md += &format!("| {} | {:.5} |\n", i + 1, a);
        }
        md += &format!(
            "\nSears's incompressible amplitude with the Prandtl–Glauert factor: {:.5} (last period / Sears-PG = {:.3}).\n\n![lift](lift_history.png)\n\n![pressure](pressure_final.png)\n\nFlow field at the last step for ParaView: `flow_final.vtk`.\n",
            t.sears_pg_amplitude,
            t.amplitudes.last().copied().unwrap_or(f64::NAN) / t.sears_pg_amplitude
        );
    }
    if let Some(t) = &r.table2 {
        md += &format!(
            "\n## Table 2: LFD gust response against the time domain\n\nk = {}; probe cell {} at ({:.4}, {:.4}) chords from the leading edge; amplitudes per unit gust velocity (in a∞). LFD (s = iω) against the least-squares Fourier fit of a nonlinear BDF2 run with gust amplitude {:e}; LFD with the BDF2 symbol against the linearized BDF2 march.\n\n| quantity | LFD | Fourier fit | digits | LFD (BDF2 symbol) | linearized BDF2 | digits |\n|---|---|---|---:|---|---|---:|\n",
            t.reduced_frequency, t.probe_cell, t.probe_center[0], t.probe_center[1], t.amplitude_mach
        );
        let z = |v: [f64; 2]| format!("{:.9} {:+.9}i", v[0], v[1]);
        for row in &t.rows {
            md += &format!(
                "| {} | {} | {} | {:.1} | {} | {} | {:.1} |\n",
                row.variable,
                z(row.lfd),
                z(row.fourier),
                row.digits_fourier,
                z(row.lfd_bdf2),
                z(row.linear_bdf2),
                row.digits_bdf2
            );
        }
        md += &format!(
            "\nAgreeing digits (smallest over the rows): Fourier fit {:.1} (the paper: 3–5), BDF2 symbol {:.1}.\n\nOne LFD frequency (factorization and solve, {} GMRES iterations): {:.2} s; the nonlinear time-domain run: {:.1} s ({:.0}× the LFD); the linearized march: {:.1} s.\n\n![lift](table2_lift.png)\n",
            t.digits_fourier,
            t.digits_bdf2,
            t.gmres_iterations,
            t.lfd_time_s,
            t.time_domain_time_s,
            t.time_domain_time_s / t.lfd_time_s,
            t.linear_march_time_s
        );
    }
    if let Some(m) = &r.time_motion {
        let z = |v: [f64; 2]| {
            let c = num_complex::Complex64::new(v[0], v[1]);
            format!("{:.5} ({:+.2}°)", c.norm(), c.arg().to_degrees())
        };
        md += &format!(
            "\n## Prescribed {} in the time domain\n\nk = {}, BDF2 with Δt = {:.4} (chord/a∞), at most {} Newton iterations a step; the whole mesh moves rigidly.\n\n| C_L harmonic (amplitude, phase to the motion's e^{{iωt}}) | |\n|---|---:|\n| time domain, last period | {} |\n| LFD, s = iω | {} |\n| LFD, BDF2 symbol | {} |\n| Theodorsen, Prandtl–Glauert | {} |\n\nTime domain against the BDF2-symbol LFD: {:.1} digits (the motion's amplitude and the transient make the difference: the LFD is the linearization).\n\n![lift](motion_lift.png)\n",
            m.motion,
            m.reduced_frequency,
            m.dt,
            m.max_newton_iterations,
            z(m.time_domain),
            z(m.lfd),
            z(m.lfd_bdf2),
            z(m.theodorsen_pg),
            m.digits_lfd_bdf2
        );
    }
    md += &format!("\nRun time {:.1} s.\n", r.run_time_s);
    md
}

fn cp_plot(title: &str, ps: &[&PressureDistribution]) -> LinePlot {
    let mut series: Vec<Series> = Vec::new();
    for p in ps {
        series.push((format!("{} (upper)", p.label), p.upper.clone()));
        series.push((format!("{} (lower)", p.label), p.lower.clone()));
    }
    LinePlot {
        title: title.into(),
        x_label: "x/c".into(),
        y_label: "C_p (up: negative)".into(),
        series,
        log_y: false,
        flip_y: true,
        dotted: Vec::new(),
    }
}

/// Writes results.json, summary.md and the figures of a CFD run into `dir`.
pub fn render(dir: &Path, r: &CfdResults) -> Result<()> {
    if let Some(s) = &r.steady_gust {
        let series = s
            .table1
            .iter()
            .map(|row| {
                (
                    row.case.clone(),
                    row.residual_history
                        .iter()
                        .enumerate()
                        .map(|(i, v)| (i as f64, *v))
                        .collect(),
                )
            })
            .collect();
        save_figure(
            dir,
            "residuals",
            &LinePlot {
                title: format!("{}: Newton residual", r.study),
                x_label: "Newton iteration".into(),
                y_label: "||R||".into(),
                series,
                log_y: true,
                flip_y: false,
                dotted: Vec::new(),
            },
        )?;
        let ps: Vec<&PressureDistribution> = s.pressure.iter().collect();
        save_figure(
            dir,
            "pressure",
            &cp_plot(&format!("{}: wall pressure", r.study), &ps),
        )?;
    }
    if let Some(t) = &r.time_gust {
        save_figure(
            dir,
            "lift_history",
            &LinePlot {
                title: format!("{}: lift in the sinusoidal gust", r.study),
                x_label: "t a∞ / c".into(),
                y_label: "C_L".into(),
                series: vec![("C_L".into(), t.lift_history.clone())],
                log_y: false,
                flip_y: false,
                dotted: Vec::new(),
            },
        )?;
        save_figure(
            dir,
            "pressure_final",
            &cp_plot(
                &format!("{}: wall pressure at the last step", r.study),
                &[&t.pressure_final],
            ),
        )?;
    }
    if let Some(m) = &r.time_motion {
        save_figure(
            dir,
            "motion_lift",
            &LinePlot {
                title: format!("{}: lift in prescribed {}", r.study, m.motion),
                x_label: "t a∞ / c".into(),
                y_label: "C_L".into(),
                series: vec![("C_L".into(), m.lift_history.clone())],
                log_y: false,
                flip_y: false,
                dotted: Vec::new(),
            },
        )?;
    }
    if let Some(t) = &r.table2 {
        save_figure(
            dir,
            "table2_lift",
            &LinePlot {
                title: format!("{}: lift per unit gust, time domain vs LFD", r.study),
                x_label: "t a∞ / c".into(),
                y_label: "C_L / (w_g / a∞)".into(),
                series: vec![
                    (
                        "time domain (mean removed)".into(),
                        t.lift_time_domain.clone(),
                    ),
                    ("LFD Re(−i L̂ e^{iωt})".into(), t.lift_lfd.clone()),
                ],
                log_y: false,
                flip_y: false,
                dotted: Vec::new(),
            },
        )?;
    }
    crate::report::write_results(dir, r, &summary(r))
}
