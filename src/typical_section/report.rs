//! The typical-section report: summary.md (GAF table, RMS, flutter of each model) and figures,
//! rendered from results.json alone.

use super::run::SectionResults;
use crate::report::figures::{LinePlot, PsdPlot, VgVf};
use crate::report::save_figure;
use anyhow::Result;
use gustkit_core::GafTable;
use std::path::Path;

/// The markdown summary.
pub fn summary(r: &SectionResults) -> String {
    let st = &r.spec.structure;
    let mut md = format!(
        "# {}\n\n{}\n\nTypical section: chord {} m, a = {}, x_α = {}, r_α = {}, μ = {}, ζ = {}; natural frequencies {:.3} and {:.3} Hz. Flight: M = {}, U = {:.2} m/s, ρ = {} kg/m³. LFD: NACA 64A0xx ({:.1} % thick) on a {} × {} O-mesh ({} cells), {} order.\n",
        r.study,
        r.description,
        st.chord_m,
        st.elastic_axis,
        st.x_alpha,
        st.r_alpha,
        st.mass_ratio,
        st.damping_ratio,
        r.natural_frequencies_hz[0],
        r.natural_frequencies_hz[1],
        r.spec.flight.mach,
        r.velocity_m_s,
        r.spec.flight.density_kg_m3,
        100.0 * r.spec.cfd.thickness,
        r.spec.cfd.mesh.n_around,
        r.spec.cfd.mesh.n_radial,
        r.cells,
        r.spec.cfd.order
    );
    md += "\n## Gust response and flutter\n\n| model | RMS plunge (mm) | RMS pitch (deg) | flutter speed (m/s) | flutter frequency (Hz) | time (s) |\n|---|---:|---:|---:|---:|---:|\n";
    for m in &r.models {
        let opt = |v: Option<f64>| v.map_or("—".to_string(), |x| format!("{x:.2}"));
        md += &format!(
            "| {} | {:.4} | {:.4} | {} | {} | {:.1} |\n",
            m.model,
            1e3 * m.rms_plunge_m,
            m.rms_pitch_rad.to_degrees(),
            opt(m.flutter.flutter_speed_m_s),
            opt(m.flutter.flutter_frequency_hz),
            m.time_s
        );
    }
    if let [a, b] = &r.models[..] {
        md += &format!(
            "\nLFD / strip theory: RMS plunge {:.3}, RMS pitch {:.3}. The p-k sweep keeps the GAFs of the study's Mach number at every speed (Nastran PK at fixed Mach).\n",
            a.rms_plunge_m / b.rms_plunge_m,
            a.rms_pitch_rad / b.rms_pitch_rad
        );
    }
    if let Some(c) = &r.resolution_check {
        md += &format!("\n{}\n", c.words());
    }
    md += "\n## GAFs (per unit span, divided by q∞; modes mass-normalized)\n\n| k | entry | LFD | strip theory |\n|---:|---|---|---|\n";
    if let [a, b] = &r.models[..] {
        for (i, k) in a.gafs.k.iter().enumerate() {
            for (name, x, y) in gaf_entries(&a.gafs, &b.gafs, i) {
                md += &format!(
                    "| {k} | {name} | {:.4} {:+.4}i | {:.4} {:+.4}i |\n",
                    x.re, x.im, y.re, y.im
                );
            }
        }
    }
    md += "\n![GAFs](gafs.png)\n\n![PSD](psd.png)\n\n![V-g LFD](vg_lfd.png)\n\n![V-g strip](vg_strip.png)\n";
    md += &format!("\nRun time {:.1} s.\n", r.run_time_s);
    md
}

type Entry = (String, num_complex::Complex64, num_complex::Complex64);

/// The named GAF entries of two tables at frequency index i.
fn gaf_entries(a: &GafTable, b: &GafTable, i: usize) -> Vec<Entry> {
    let n = a.n_modes();
    let mut out = Vec::new();
    for m in 0..n {
        for k in 0..n {
            out.push((
                format!("Q_ss[{}][{}]", m + 1, k + 1),
                a.q_ss[i][m][k],
                b.q_ss[i][m][k],
            ));
        }
    }
    for m in 0..n {
        out.push((format!("Q_gs[{}]", m + 1), a.q_gs[i][m], b.q_gs[i][m]));
    }
    out
}

/// Writes results.json, summary.md and the figures into `dir`.
pub fn render(dir: &Path, r: &SectionResults) -> Result<()> {
    if let [a, b] = &r.models[..] {
        let mut series = Vec::new();
        let n = a.gafs.k.len();
        for (e, name) in gaf_entries(&a.gafs, &b.gafs, 0)
            .iter()
            .map(|e| &e.0)
            .enumerate()
        {
            for (label, table) in [("LFD", &a.gafs), ("strip", &b.gafs)] {
                let pts: Vec<(f64, f64)> = (0..n)
                    .map(|i| (table.k[i], gaf_entries(table, table, i)[e].1.norm()))
                    .collect();
                series.push((format!("|{name}| {label}"), pts));
            }
        }
        save_figure(
            dir,
            "gafs",
            &LinePlot {
                title: format!("{}: GAF magnitudes against k", r.study),
                x_label: "k = ω b / U".into(),
                y_label: "|Q| (per unit span)".into(),
                series,
                log_y: true,
                flip_y: false,
                dotted: Vec::new(),
            },
        )?;
        save_figure(
            dir,
            "psd",
            &PsdPlot {
                title: format!("{}: response PSD", r.study),
                panels: vec![
                    vec![a.psd_plunge.clone(), b.psd_plunge.clone()],
                    vec![a.psd_pitch.clone(), b.psd_pitch.clone()],
                ],
            },
        )?;
        for (m, stem) in [(a, "vg_lfd"), (b, "vg_strip")] {
            save_figure(
                dir,
                stem,
                &VgVf {
                    result: &m.flutter,
                    title: format!("{}: p-k, {}", r.study, m.model),
                },
            )?;
        }
    }
    crate::report::write_results(dir, r, &summary(r))
}
