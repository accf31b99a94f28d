//! The results of `gustkit run` as one typed document (results.json), and the report rendered from
//! it alone: `gustkit run` and `gustkit report RUN_DIR` call the same [`render`], so a report can
//! be re-drawn without re-running anything.

use super::figures::{gaf_panels, Convergence, PsdPlot, ThicknessMaps, VgVf};
use super::results::{
    FidelityComparison, FlutterSummary, GustResults, ModeRow, PsdSeries, RunResults,
};
use super::{from_json, FigureFiles, FigureSink};
use crate::flutter::FlutterResult;
use anyhow::Result;
use std::path::Path;

/// Markdown frequency table.
pub fn frequency_table(modes: &[ModeRow]) -> String {
    let mut t = String::from("| mode | shape | frequency [Hz] |\n|---:|---|---:|\n");
    for r in modes {
        let shape = if r.shape.is_empty() {
            &r.field
        } else {
            &r.shape
        };
        t += &format!("| {} | {shape} | {:.3} |\n", r.mode, r.frequency_hz);
    }
    t
}

/// One design's flutter point in words: the verdict's, speed as a multiple of the flight speed.
fn flutter_point_words(
    p: &crate::report::results::FlutterPoint,
    fc: &crate::report::results::FlutterCheck,
) -> String {
    crate::flutter::verdict::point_words(
        p.speed_m_s,
        p.frequency_hz,
        p.mode,
        fc.flight_speed_m_s,
        fc.searched_up_to_m_s,
    )
}

/// The flutter speeds of an optimization's initial and final designs (and of the final design
/// with more modes), with a warning when the extra modes flutter below the margin.
fn flutter_check_text(
    fc: &crate::report::results::FlutterCheck,
    margin: Option<(f64, f64)>,
) -> String {
    let mut md = format!(
        "\nFlutter (p-k at the flight Mach number and density, {} modes): initial design {}; final design {}.",
        fc.modes,
        flutter_point_words(&fc.initial, fc),
        flutter_point_words(&fc.final_, fc)
    );
    if let (Some(n), Some(p)) = (fc.more_modes, &fc.final_more_modes) {
        md += &format!(
            " With {n} modes the final design flutters at {}.",
            flutter_point_words(p, fc)
        );
        if let (Some((factor, _)), Some(v)) = (margin, p.speed_m_s) {
            if v < factor * fc.flight_speed_m_s {
                md += &format!(
                    " **That is below the margin of {factor} × the flight speed**: the margin constraint sees only the {} retained modes; retain more modes (structure.modes) and run again.",
                    fc.modes
                );
            }
        }
    }
    md + "\n"
}

/// One sentence on the flutter point of a sweep: the [`Verdict`](crate::flutter::Verdict)'s words,
/// relative to the flight speed when the results record it (older results do not).
pub fn flutter_point(r: &FlutterResult, flight_speed_m_s: Option<f64>) -> String {
    let verdict = crate::flutter::Verdict::of(r);
    match flight_speed_m_s {
        Some(v) => verdict.words(v),
        None => match verdict.unstable_from() {
            Some(v) => format!("unstable from V = {v:.2} m/s ({:.1} ft/s)", v / 0.3048),
            None => "no flutter over the speeds examined".to_string(),
        },
    }
}

/// The DLM lattice rule in one sentence, lengths in the study's unit; in bold when it is not met.
pub fn lattice_words(r: &crate::aero::dlm::LatticeRule, unit: crate::units::LengthUnit) -> String {
    let (b, u) = unit.display(r.box_length_m, "m", 1);
    let (l, _) = unit.display(r.limit_m, "m", 1);
    let head = format!(
        "DLM lattice: the longest box is {b:.4} {u} ({} chordwise), {} 0.08 V/f = {l:.4} {u} at f = {:.1} Hz ({}) and V = {:.1} m/s (MSC's rule: about 12.5 boxes a wavelength)",
        r.n_chord,
        if r.met() { "within" } else { "longer than" },
        r.frequency_hz,
        r.frequency_is,
        r.velocity_m_s,
    );
    if r.met() {
        head
    } else {
        format!(
            "**{head}: the highest retained modes are not resolved; raise aero.fidelity.dlm.n_chord to {} or more**",
            r.n_chord_needed
        )
    }
}

/// The markdown summary.
pub fn summary(r: &RunResults) -> String {
    let mut md = format!(
        "# {}\n\n{}\n\n## Structure\n\nMass {:.4} kg, planform area {:.4} m², {} design variables.\n\n{}\n![modes](modes.png)\n\nVTK: `modes.vtk`.\n",
        r.study,
        r.description,
        r.mass_kg,
        r.area_m2,
        r.n_design_variables,
        frequency_table(&r.modes),
    );
    if let Some(l) = &r.lattice_rule {
        md += &format!("\n{}.\n", lattice_words(l, r.length_unit));
    }
    if let Some(g) = &r.gust {
        md += &format!(
            "\n## Gust response\n\nM = {}, V = {} m/s, ρ = {} kg/m³, q = {:.1} Pa; {}; {} frequencies on a log grid up to {:.1} rad/s; outputs by the {}.\n\n| output | RMS | unit | N0 [Hz] |\n|---|---:|---|---:|\n",
            g.mach, g.velocity_m_s, g.density_kg_m3, g.q_inf_pa, g.turbulence, g.n_omega, g.omega_max_rad_s,
            if g.mode_acceleration {
                "mode-acceleration method (each adds the residual flexibility of the modes left out)"
            } else {
                "mode-displacement method"
            }
        );
        for o in &g.outputs {
            let (rms, unit) = r.length_unit.display(o.rms, &o.unit, 1);
            md += &format!(
                "| {} | {} | {unit} | {:.3} |\n",
                o.name,
                crate::report::style::tick(&rms),
                o.n0_hz
            );
        }
        if let Some(c) = &g.calibration {
            md += &format!(
                "\nσ_w calibration: σ_w = {} m/s gives RMS({}) = {:.4} {} at the initial design against the target {} {} ({:+.3} %); the target alone would give σ_w = {:.4} m/s. {}\n",
                c.sigma_w_m_s, c.output, c.rms, c.unit, c.target_rms, c.unit,
                100.0 * (c.rms / c.target_rms - 1.0), c.sigma_w_for_target_m_s, c.source
            );
        }
        md += "\n![PSD](psd.png)\n";
    }
    if let Some(d) = &r.discrete_gust {
        md += &crate::report::discrete::summary_text(d, r.length_unit);
    }
    if let Some(f) = &r.flutter {
        md += &format!(
            "\n## Flutter (p-k)\n\nM = {}, ρ = {} kg/m³: {}.\n\n![V-g, V-f](flutter_vg.png)\n",
            f.mach,
            f.density_kg_m3,
            flutter_point(&f.result, f.flight_speed_m_s)
        );
    }
    if let Some(o) = &r.optimization {
        let (i, f) = (&o.initial, &o.final_);
        md += &format!(
            "\n## Optimization\n\nMinimum mass subject to RMS({}) ≤ {:.4} {}{}; {} design variables. {} after {} iterations ({} evaluations, {:.1} s).\n\n| | initial | final | change |\n|---|---:|---:|---:|\n| mass [kg] | {:.4} | {:.4} | {:+.1} % |\n| RMS {} [{}] | {:.4} | {:.4} | {:+.1} % |\n| area [m²] | {:.5} | {:.5} | {:+.2} % |\n",
            o.output,
            o.rms_limit,
            o.unit,
            match o.flutter_margin {
                Some((f, g)) => format!(", every p-k root damped (g ≤ {g}) at {f} × the flight speed (KS aggregate, ρ = {:.0})", o.ks_rho),
                None => String::new(),
            } + if o.fix_area { ", planform area fixed" } else { "" },
            o.design_variable_names.len(),
            o.message,
            o.iterations,
            o.evaluations,
            o.wall_time_s,
            i.mass_kg,
            f.mass_kg,
            100.0 * (f.mass_kg / i.mass_kg - 1.0),
            o.output,
            o.unit,
            i.rms_display,
            f.rms_display,
            100.0 * (f.rms_display / i.rms_display - 1.0),
            i.area_m2,
            f.area_m2,
            100.0 * (f.area_m2 / i.area_m2 - 1.0),
        );
        md += &corrections_text(o);
        if let Some(pl) = &o.peak_limit {
            md += &format!(
                "\nDiscrete gust peak limit |{}| ≤ {} {} over {} gusts, as the KS aggregate over every time sample and gust (ρ = {:.0}, at most 0.005 above the largest sampled value): initial {:.4}, final {:.4} × the limit (KS {:.4} → {:.4}).\n",
                pl.output,
                crate::report::style::tick(&pl.limit),
                pl.unit,
                pl.gusts,
                pl.ks_rho,
                pl.initial_peak,
                pl.final_peak,
                pl.initial_ks,
                pl.final_ks
            );
        }
        if let Some(fc) = &o.flutter_check {
            md += &flutter_check_text(fc, o.flutter_margin);
        }
        if let Some(refr) = &o.reference {
            let opt = |v: Option<String>| v.unwrap_or_else(|| "–".into());
            md += &format!(
                "\nSide by side with {}:\n\n| | reference | gustkit |\n|---|---:|---:|\n| iterations | {} | {} |\n| mass change | {} | {:+.1} % |\n| initial RMS [{}] | {} | {:.3} |\n| optimum | {} | see the planform table and figure below |\n",
                refr.source,
                opt(refr.iterations.map(|v| v.to_string())),
                o.iterations,
                opt(refr.mass_change_percent.map(|v| format!("{v:+.1} %"))),
                100.0 * (f.mass_kg / i.mass_kg - 1.0),
                o.unit,
                opt(refr.initial_rms.map(|v| format!("{v:.3}"))),
                i.rms_display,
                if refr.design.is_empty() { "–" } else { &refr.design },
            );
        }
        // planform variables in the study's units: lengths in its length unit, sweep in degrees
        let to_unit = 1.0 / r.length_unit.to_m();
        md += "\n| planform variable | lower | initial | final | upper | unit |\n|---|---:|---:|---:|---:|---|\n";
        let n = o.design_variable_names.len();
        for k in n.saturating_sub(4)..n {
            let (scale, unit) = if o.design_variable_names[k].starts_with("sweep") {
                (180.0 / std::f64::consts::PI, "deg")
            } else {
                (to_unit, r.length_unit.name())
            };
            md += &format!(
                "| {} | {:.3} | {:.3} | {:.3} | {:.3} | {unit} |\n",
                o.design_variable_names[k],
                scale * o.lower[k],
                scale * i.design_variables[k],
                scale * f.design_variables[k],
                scale * o.upper[k]
            );
        }
        let at_bound = |x: &[f64]| {
            (0..n)
                .filter(|&k| {
                    let tol = 1e-6 * (o.upper[k] - o.lower[k]).abs().max(1e-12);
                    (x[k] - o.lower[k]).abs() < tol || (x[k] - o.upper[k]).abs() < tol
                })
                .count()
        };
        md += &format!(
            "\n{} of {} design variables end at a bound.\n\n![convergence](convergence.png)\n\n![PSD initial and final](psd_optimization.png)\n\n![thickness](thickness.png)\n",
            at_bound(&f.design_variables),
            n
        );
    }
    if let Some(c) = &r.resolution_check {
        md += &format!("\n## Resolution check\n\n{}\n", resolution_words(c));
    }
    if let Some(c) = &r.comparison {
        md += &comparison_text(c, r.gust.as_ref(), r.flutter.as_ref(), r.length_unit);
        md += "\n![GAFs of both fidelities](gafs_fidelities.png)\n";
        if !c.psd_other.is_empty() {
            md += "\n![PSD with both fidelities](psd_fidelities.png)\n";
        }
        if c.flutter_other.is_some() {
            md += &format!(
                "\n![V-g, V-f with the {}](flutter_vg_{}.png)\n",
                c.other, c.other
            );
        }
    }
    md += &format!("\nRun time {:.2} s.\n", r.run_time_s);
    md
}

/// The markdown section of `aero.compare_with`: gust RMS and flutter speed of both fidelities,
/// and how far apart their GAF tables are at each reduced frequency.
pub fn comparison_text(
    c: &FidelityComparison,
    gust: Option<&GustResults>,
    flutter: Option<&FlutterSummary>,
    length_unit: crate::units::LengthUnit,
) -> String {
    let (a, b) = (&c.fidelity, &c.other);
    let mut md = format!("\n## The {a} beside the {b} (aero.compare_with)\n\nThe initial design analysed with both fidelities.\n");
    if let Some(g) = gust {
        match &c.rms_other {
            Some(rms) => {
                md += &format!(
                    "\n| output | RMS, {a} | RMS, {b} | {a} / {b} − 1 | unit |\n|---|---:|---:|---:|---|\n"
                );
                for (o, other) in g.outputs.iter().zip(rms) {
                    let (own, unit) = length_unit.display(o.rms, &o.unit, 1);
                    let (other_shown, _) = length_unit.display(*other, &o.unit, 1);
                    md += &format!(
                        "| {} | {} | {} | {:+.1} % | {unit} |\n",
                        o.name,
                        crate::report::style::tick(&own),
                        crate::report::style::tick(&other_shown),
                        100.0 * (o.rms / other - 1.0),
                    );
                }
            }
            None => {
                md += &format!(
                    "\nThe {b} gives no gust response: {}\n",
                    c.unstable_other.as_deref().unwrap_or("")
                )
            }
        }
    }
    if let (Some(f), Some(other)) = (flutter, &c.flutter_other) {
        md += &format!(
            "\nFlutter (p-k, M = {}, ρ = {} kg/m³): {a} {}; {b} {}.\n",
            f.mach,
            f.density_kg_m3,
            flutter_point(&f.result, f.flight_speed_m_s),
            flutter_point(other, f.flight_speed_m_s)
        );
    }
    md += &format!(
        "\nGAF tables: the largest difference of an entry over the largest entry of the {a} table, per reduced frequency.\n\n| k | Q_ss | Q_gs |\n|---:|---:|---:|\n"
    );
    for (i, k) in c.gafs.k.iter().enumerate() {
        md += &format!(
            "| {k} | {:.1} % | {:.1} % |\n",
            100.0 * c.gaf_difference_ss[i],
            100.0 * c.gaf_difference_gs[i]
        );
    }
    md
}

/// A PSD series as a person reads it: a displacement's PSD in the study's length unit squared
/// ([`crate::units::LengthUnit::display`]); results.json keeps SI.
pub(crate) fn shown(s: &PsdSeries, unit: crate::units::LengthUnit) -> PsdSeries {
    let (scale, shown_unit) = unit.display(1.0, &s.unit, 2);
    PsdSeries {
        label: s.label.clone(),
        unit: shown_unit.to_string(),
        omega_rad_s: s.omega_rad_s.clone(),
        psd: s.psd.iter().map(|v| v * scale).collect(),
    }
}

/// Every figure of a wing run, into `sink` (files, or a test's check of what they draw).
pub fn figures(r: &RunResults, sink: &mut impl FigureSink) -> Result<()> {
    sink.figure("modes", &r.mode_shapes)?;
    if let Some(g) = &r.gust {
        let panels = g
            .psd
            .iter()
            .map(|s| vec![shown(s, r.length_unit)])
            .collect();
        sink.figure(
            "psd",
            &PsdPlot {
                title: format!("{}: gust response PSD", r.study),
                panels,
            },
        )?;
    }
    if let Some(d) = &r.discrete_gust {
        crate::report::discrete_plots::figures(d, &r.study, r.length_unit, sink)?;
    }
    if let Some(f) = &r.flutter {
        sink.figure(
            "flutter_vg",
            &VgVf {
                result: &f.result,
                title: format!(
                    "{}: p-k, M = {}, rho = {} kg/m3",
                    r.study, f.mach, f.density_kg_m3
                ),
            },
        )?;
    }
    if let Some(o) = &r.optimization {
        sink.figure("convergence", &Convergence::new(&r.study, o))?;
        if let Some(sweep) = o
            .flutter_check
            .as_ref()
            .and_then(|c| c.final_sweep.as_ref())
        {
            sink.figure(
                "flutter_vg_final",
                &VgVf {
                    result: sweep,
                    title: format!(
                        "{}: p-k of the final design at the flight Mach number and density",
                        r.study
                    ),
                },
            )?;
        }
        let mut initial = shown(&o.initial.psd, r.length_unit);
        initial.label = format!("{} initial", initial.label);
        let mut fin = shown(&o.final_.psd, r.length_unit);
        fin.label = format!("{} final", fin.label);
        sink.figure(
            "psd_optimization",
            &PsdPlot {
                title: format!("{}: PSD at the initial and final designs", r.study),
                panels: vec![vec![initial, fin]],
            },
        )?;
        sink.figure(
            "thickness",
            &ThicknessMaps {
                title: format!("{}: planform and thickness", r.study),
                unit: r.length_unit.name().to_string(),
                panels: vec![
                    (
                        "initial".into(),
                        o.initial.elements.clone(),
                        o.initial.thickness.clone(),
                    ),
                    (
                        "final".into(),
                        o.final_.elements.clone(),
                        o.final_.thickness.clone(),
                    ),
                ],
            },
        )?;
    }
    if let Some(c) = &r.comparison {
        sink.figure(
            "gafs_fidelities",
            &gaf_panels(
                format!(
                    "{}: GAFs of the {} and the {}",
                    r.study, c.fidelity, c.other
                ),
                &[
                    (c.fidelity.clone(), &c.gafs),
                    (c.other.clone(), &c.gafs_other),
                ],
            ),
        )?;
        if let Some(g) = r.gust.as_ref().filter(|_| !c.psd_other.is_empty()) {
            let panels = g
                .psd
                .iter()
                .zip(&c.psd_other)
                .map(|(own, other)| {
                    let (mut own, mut other) =
                        (shown(own, r.length_unit), shown(other, r.length_unit));
                    own.label = format!("{}, {}", own.label, c.fidelity);
                    other.label = format!("{}, {}", other.label, c.other);
                    vec![own, other]
                })
                .collect();
            sink.figure(
                "psd_fidelities",
                &PsdPlot {
                    title: format!("{}: gust response PSD with both fidelities", r.study),
                    panels,
                },
            )?;
        }
        if let (Some(f), Some(other)) = (&r.flutter, &c.flutter_other) {
            sink.figure(
                &format!("flutter_vg_{}", c.other),
                &VgVf {
                    result: other,
                    title: format!(
                        "{}: p-k with the {}, M = {}, rho = {} kg/m3",
                        r.study, c.other, f.mach, f.density_kg_m3
                    ),
                },
            )?;
        }
    }
    Ok(())
}

/// Writes results.json, summary.md and every figure of `r` into `dir` (each file atomically).
pub fn render(dir: &Path, r: &RunResults) -> Result<()> {
    figures(r, &mut FigureFiles(dir))?;
    crate::report::write_results(dir, r, &summary(r))
}

/// `gustkit report RUN_DIR`: re-renders the report from `value`, the results.json at `path`.
pub fn rerender(
    dir: &Path,
    path: &Path,
    value: &serde_json::Value,
    r: RunResults,
) -> Result<RunResults> {
    let r = with_optimization(path, value, r)?;
    render(dir, &r)?;
    Ok(r)
}

/// A wing run's results read from `value`, the results.json at `path`.
pub fn read(path: &Path, value: &serde_json::Value) -> Result<RunResults> {
    with_optimization(path, value, from_json(path, value)?)
}

/// `r` with its optimization read on its own: a flattened Option swallows errors in its fields.
fn with_optimization(
    path: &Path,
    value: &serde_json::Value,
    mut r: RunResults,
) -> Result<RunResults> {
    if value.get("converged").is_some() {
        r.optimization = Some(from_json(path, value)?);
    }
    Ok(r)
}

/// The resolution corrections of an optimization, a table with a line of explanation (empty
/// without any).
fn corrections_text(o: &crate::report::results::OptimizationResults) -> String {
    if o.corrections.is_empty() {
        return String::new();
    }
    let mut md = format!(
        "\nResolution corrections: the refined model found the optimum's RMS above the limit, so the optimization continued from it with the limit scaled by the constrained / refined RMS ratio (`optimization.resolution_corrections`):\n\n| pass | RMS before [{u}] | refined [{u}] | corrected limit [{u}] | iterations | evaluations | mass [kg] | time [s] | result |\n|---:|---:|---:|---:|---:|---:|---:|---:|---|\n",
        u = o.unit
    );
    for c in &o.corrections {
        md += &format!(
            "| {} | {:.4} | {:.4} | {:.4} | {} | {} | {:.4} | {:.1} | {} |\n",
            c.pass,
            c.rms_display,
            c.refined_rms_display,
            c.rms_limit_display,
            c.iterations,
            c.evaluations,
            c.mass_kg,
            c.wall_time_s,
            c.message
        );
    }
    md
}

/// The resolution check in one paragraph: both models, their verdicts and RMS, and whether the
/// refined one meets the requirement.
pub fn resolution_words(c: &crate::report::results::ResolutionCheck) -> String {
    let Some(refined) = &c.refined_model else {
        return format!(
            "Resolution check ({}): {}; the refined analysis did not run: {}.",
            c.model,
            c.flutter,
            c.not_run.as_deref().unwrap_or("")
        );
    };
    let (u, sc) = (&c.rms_unit, c.rms_unit_scale);
    // six significant digits, no trailing zeros (the figures' tick form)
    let sig = |v: f64| crate::report::style::tick(&v);
    let rms = match (c.rms_limit, c.rms_m.first()) {
        (Some((i, limit)), _) => match (c.rms_m.get(i), c.refined_rms_m.get(i)) {
            (Some(a), Some(b)) => format!(
                " RMS of the constrained output {} → {} {u} ({:+.2} %; limit {} {u}, tolerance {:.0} %).",
                sig(a * sc),
                sig(b * sc),
                100.0 * (b / a - 1.0),
                sig(limit * sc),
                100.0 * c.rms_tolerance
            ),
            _ => String::new(),
        },
        (None, Some(a)) => match c.refined_rms_m.first() {
            Some(b) => format!(
                " RMS of the first output {} → {} {u} ({:+.2} %).",
                sig(a * sc),
                sig(b * sc),
                100.0 * (b / a - 1.0)
            ),
            None => String::new(),
        },
        _ => String::new(),
    };
    let rms = match (c.peak, c.refined_peak) {
        (Some(a), Some(b)) => format!(
            "{rms} Discrete gust peak {} → {} × its limit (tolerance {:.0} %).",
            sig(a),
            sig(b),
            100.0 * c.rms_tolerance
        ),
        _ => rms,
    };
    let unstable = c
        .refined_unstable
        .as_deref()
        .map(|u| format!(" The refined model gives no gust response: {u}."))
        .unwrap_or_default();
    let verdict = if c.passed {
        format!(
            "The design holds at the refined resolution (no flutter below {:.1} m/s within {:.0} %).",
            c.stable_to_m_s,
            100.0 * c.flutter_tolerance
        )
    } else {
        format!(
            "**The design fails at the refined resolution** (it must not flutter below {:.1} m/s, {:.2} × the flight speed, within {:.0} %, and meet its RMS limit{} within {:.0} %).",
            c.stable_to_m_s,
            c.stable_to_m_s / c.flight_speed_m_s,
            100.0 * c.flutter_tolerance,
            if c.refined_peak.is_some() { " and its discrete gust peak limit" } else { "" },
            100.0 * c.rms_tolerance
        )
    };
    format!(
        "Resolution check: with {} the design {}; with {refined} it {}.{rms}{unstable} {verdict} ({:.1} s)",
        c.model,
        c.flutter,
        c.refined_flutter.as_deref().unwrap_or(""),
        c.time_s
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lattice sentence: within the rule plainly, beyond it in bold with the n_chord that
    /// would meet it, lengths in the study's unit.
    #[test]
    fn lattice_words_name_the_fix() {
        let planform = crate::wing::Planform {
            span: 15.0,
            sweep_c4: 28f64.to_radians(),
            root_chord: 5.0,
            tip_chord: 1.6,
        };
        let spec = crate::aero::dlm::DlmSpec {
            n_chord: 8,
            n_span: 16,
            chord_spacing: Default::default(),
            span_spacing: Default::default(),
            symmetry: gustkit_dlm::Symmetry::Symmetric,
        };
        let r = crate::aero::dlm::lattice_rule(&spec, &planform, 233.0, 58.0, "the mode cutoff");
        let w = lattice_words(&r, crate::units::LengthUnit::M);
        assert!(
            w.starts_with("**DLM lattice: the longest box is 0.6250 m"),
            "{w}"
        );
        assert!(
            w.contains("raise aero.fidelity.dlm.n_chord to 16 or more**"),
            "{w}"
        );
        let inch = lattice_words(&r, crate::units::LengthUnit::In);
        assert!(inch.contains("24.6063 in"), "{inch}");
    }
}
