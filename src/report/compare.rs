//! `gustkit compare RUN_DIR...`: one report across optimization runs and fidelities, rendered from
//! their results.json files alone: convergence histories overlaid (paper Fig. 6), thickness maps
//! side by side (Fig. 7), the PSD of each optimum with both fidelities, the GAFs of both
//! fidelities on the same design, and the paper's Sec. IV numbers as a table.

use super::figures::{gaf_panels, line_plot, Panels, PsdPlot, Series, ThicknessMaps};
use super::results::{CrossEvaluation, OptimizationResults, RunResults};
use super::save_figure;
use crate::kind::StudyKind;
use anyhow::{anyhow, bail, Result};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// One run of the comparison: where it came from, its results and its optimization.
pub struct ComparedRun {
    /// The run folder as given.
    pub dir: PathBuf,
    /// `study (fidelity)`: the label in tables and legends.
    pub label: String,
    pub results: RunResults,
}

impl ComparedRun {
    fn opt(&self) -> &OptimizationResults {
        self.results.optimization.as_ref().expect("checked at load")
    }
}

/// Reads a run folder's results.json for the comparison: a wing study's optimization of this
/// results schema; anything else is refused with the file and the reason.
pub fn load_run(dir: &Path) -> Result<ComparedRun> {
    let path = dir.join("results.json");
    let value = super::read_json(&path)?;
    let kind = StudyKind::of_results(&path, &value)?;
    if kind != StudyKind::Wing {
        bail!(
            "{}: holds {} results; gustkit compare puts wing optimizations side by side",
            path.display(),
            kind.name()
        );
    }
    if value.get("rms_tip_in").is_some() || value.get("history").is_none() {
        bail!(
            "{}: {}",
            path.display(),
            if value.get("history").is_none() {
                "holds no optimization (gustkit compare puts optimization runs side by side)"
                    .to_string()
            } else {
                "written with results schema 1 (rms_tip_in); run the study again with this gustkit"
                    .to_string()
            }
        );
    }
    let results = super::run::read(&path, &value)?;
    let fidelity = results.fidelity.clone().ok_or_else(|| {
        anyhow!(
            "{}: fidelity: missing — written before results files recorded their aerodynamic fidelity; run the study again with this gustkit",
            path.display()
        )
    })?;
    Ok(ComparedRun {
        dir: dir.to_path_buf(),
        label: format!("{} ({fidelity})", results.study),
        results,
    })
}

/// One row of the runs table (also written to compare.json).
#[derive(Serialize)]
struct RunRow {
    run: String,
    fidelity: String,
    converged: bool,
    iterations: usize,
    evaluations: usize,
    warm_start: Option<String>,
    mass_initial_kg: f64,
    mass_final_kg: f64,
    mass_change_percent: f64,
    unit: String,
    rms_initial: f64,
    rms_start: f64,
    rms_final: f64,
    function_median_s: Option<f64>,
    gradient_median_s: Option<f64>,
    threads: Option<usize>,
    wall_time_s: f64,
}

/// One design analysed with one fidelity (compare.json and the cross-evaluation table).
#[derive(Serialize)]
struct CrossRow {
    run: String,
    design: String,
    fidelity: String,
    mass_kg: f64,
    /// None where this fidelity finds the design unstable at the flight condition.
    rms: Option<f64>,
    flutter_speed_m_s: Option<f64>,
    flutter_speed_ratio: Option<f64>,
}

/// A start design of one run that is another run's optimum, analysed with that run's fidelity
/// by both: the two numbers must agree where the two models are the same (the same lattice or
/// mesh); where they differ the row compares the two models, not the runs' consistency.
#[derive(Serialize)]
struct Consistency {
    run: String,
    other: String,
    fidelity: String,
    rms_here: f64,
    rms_there: f64,
    relative_difference: f64,
    /// The model of each side in words (absent where a results.json predates the record).
    model_here: Option<String>,
    model_there: Option<String>,
}

impl Consistency {
    /// Whether both sides used one model: unknown where either side did not record it.
    fn same_model(&self) -> Option<bool> {
        Some(self.model_here.as_ref()? == self.model_there.as_ref()?)
    }
}

/// compare.json: the tables of the report as numbers.
#[derive(Serialize)]
struct CompareDoc {
    runs: Vec<RunRow>,
    cross_evaluation: Vec<CrossRow>,
    consistency: Vec<Consistency>,
}

fn run_row(r: &ComparedRun) -> RunRow {
    let o = r.opt();
    let timing = o.timing.as_ref();
    RunRow {
        run: r.results.study.clone(),
        fidelity: r.results.fidelity.clone().unwrap_or_default(),
        converged: o.converged,
        iterations: o.iterations,
        evaluations: o.evaluations,
        warm_start: o.warm_start.clone(),
        mass_initial_kg: o.initial.mass_kg,
        mass_final_kg: o.final_.mass_kg,
        mass_change_percent: 100.0 * (o.final_.mass_kg / o.initial.mass_kg - 1.0),
        unit: o.unit.clone(),
        rms_initial: o.initial.rms_display,
        rms_start: o.history.first().map_or(f64::NAN, |h| h.rms_display),
        rms_final: o.final_.rms_display,
        function_median_s: timing.and_then(|t| t.function.as_ref()).map(|s| s.median_s),
        gradient_median_s: timing.and_then(|t| t.gradient.as_ref()).map(|s| s.median_s),
        threads: timing.map(|t| t.threads),
        wall_time_s: o.wall_time_s,
    }
}

fn cross_rows(r: &ComparedRun, c: &CrossEvaluation) -> Vec<CrossRow> {
    c.designs
        .iter()
        .flat_map(|d| {
            d.evaluations.iter().map(move |e| CrossRow {
                run: r.results.study.clone(),
                design: d.design.clone(),
                fidelity: e.fidelity.clone(),
                mass_kg: d.mass_kg,
                rms: e.rms_display,
                flutter_speed_m_s: e.flutter.speed_m_s,
                flutter_speed_ratio: e.flutter.speed_m_s.map(|v| v / c.flight_speed_m_s),
            })
        })
        .collect()
}

/// Where a run's cross-evaluated design is another run's final design, analysed there with that
/// run's own fidelity: the pairs of RMS values of the same design and model.
fn consistency(runs: &[ComparedRun]) -> Vec<Consistency> {
    let mut out = Vec::new();
    for r in runs {
        let Some(c) = &r.opt().cross_evaluation else {
            continue;
        };
        for other in runs.iter().filter(|o| !std::ptr::eq(*o, r)) {
            let of = other.opt();
            let fidelity = other.results.fidelity.clone().unwrap_or_default();
            // the first design of this run that is the other's optimum
            let same = c
                .designs
                .iter()
                .find(|d| d.design_variables == of.final_.design_variables);
            if let Some(d) = same {
                // that run's own model where this run evaluated with it, else its fidelity
                let there_model = other.results.aero_model.as_ref();
                let here = d
                    .evaluations
                    .iter()
                    .find(|e| {
                        e.fidelity == fidelity
                            && e.model.is_some()
                            && e.model.as_ref() == there_model
                    })
                    .or_else(|| d.evaluations.iter().find(|e| e.fidelity == fidelity));
                if let Some((rms_here, e)) = here.and_then(|e| Some((e.rms_display?, e))) {
                    out.push(Consistency {
                        run: r.label.clone(),
                        other: other.label.clone(),
                        fidelity: fidelity.clone(),
                        rms_here,
                        rms_there: of.final_.rms_display,
                        relative_difference: (rms_here / of.final_.rms_display - 1.0).abs(),
                        model_here: e.model.clone(),
                        model_there: other.results.aero_model.clone(),
                    });
                }
            }
        }
    }
    out
}

/// Histories of every run overlaid: mass and RMS normalized by their references, against the
/// iteration.
fn convergence(runs: &[ComparedRun]) -> Panels {
    let curve = |r: &ComparedRun, f: &dyn Fn(&OptimizationResults, usize) -> f64| -> Series {
        let o = r.opt();
        (
            r.label.clone(),
            (0..o.history.len())
                .map(|i| (o.history[i].iteration as f64, f(o, i)))
                .collect(),
        )
    };
    let mass = runs
        .iter()
        .map(|r| curve(r, &|o, i| o.history[i].mass_kg / o.initial.mass_kg))
        .collect();
    let rms = runs
        .iter()
        .map(|r| curve(r, &|o, i| o.history[i].rms_display / o.rms_limit))
        .collect();
    Panels {
        title: "Optimization histories".into(),
        cols: 1,
        plots: vec![
            line_plot(
                "mass / mass of the study's initial design".into(),
                "iteration",
                "mass ratio",
                mass,
            ),
            line_plot(
                "RMS of the constrained output / its limit".into(),
                "iteration",
                "RMS ratio",
                rms,
            ),
        ],
    }
}

/// The first run's initial design, then every run's optimum, on one thickness scale.
fn thickness(runs: &[ComparedRun]) -> ThicknessMaps {
    let first = runs[0].opt();
    let mut panels = vec![(
        "initial design".to_string(),
        first.initial.elements.clone(),
        first.initial.thickness.clone(),
    )];
    for r in runs {
        let o = r.opt();
        panels.push((
            format!("{} optimum", r.label),
            o.final_.elements.clone(),
            o.final_.thickness.clone(),
        ));
    }
    ThicknessMaps {
        title: "Planform and thickness of the optima".into(),
        unit: runs[0].results.length_unit.name().to_string(),
        panels,
    }
}

/// The PSD of each optimum: with the run's own fidelity, and with the other where the run
/// cross-evaluated it.
/// The PSDs in the first run's length unit (the unit rule: what a person reads in the study's
/// unit, results in SI).
fn psd(runs: &[ComparedRun]) -> PsdPlot {
    let unit = runs[0].results.length_unit;
    let mut series = Vec::new();
    for r in runs {
        let o = r.opt();
        let own = r.results.fidelity.clone().unwrap_or_default();
        let mut s = super::run::shown(&o.final_.psd, unit);
        s.label = format!("{} optimum, {own}", r.results.study);
        series.push(s);
        if let Some(c) = &o.cross_evaluation {
            for d in c.designs.iter().filter(|d| d.design == "final") {
                for e in d.evaluations.iter().filter(|e| e.fidelity != own) {
                    if let Some(mut s) = e.psd.as_ref().map(|p| super::run::shown(p, unit)) {
                        s.label = format!("{} optimum, {}", r.results.study, e.fidelity);
                        series.push(s);
                    }
                }
            }
        }
    }
    PsdPlot {
        title: format!(
            "PSD of {} at each optimum with each fidelity",
            runs[0].opt().output
        ),
        panels: vec![series],
    }
}

/// The GAFs of both fidelities on one design (the first cross-evaluated run's final design).
fn gafs(r: &ComparedRun, c: &CrossEvaluation) -> Option<Panels> {
    let d = c.designs.iter().find(|d| d.design == "final")?;
    let tables: Vec<(String, &gustkit_core::GafTable)> = d
        .evaluations
        .iter()
        .map(|e| (e.fidelity.clone(), &e.gafs))
        .collect();
    Some(gaf_panels(
        format!(
            "GAFs of both fidelities on the optimum of {} (modes of that design)",
            r.label
        ),
        &tables,
    ))
}

fn opt_f(v: Option<f64>, digits: usize) -> String {
    v.map_or("–".into(), |v| format!("{v:.digits$}"))
}

fn markdown(runs: &[ComparedRun], doc: &CompareDoc, figures: &[&str]) -> String {
    let mut md = String::from("# Comparison of optimization runs\n\nRuns: ");
    md += &runs
        .iter()
        .map(|r| format!("`{}` ({})", r.dir.display(), r.label))
        .collect::<Vec<_>>()
        .join(", ");
    md += ".\n\n## Runs\n\n| run | fidelity | iterations (evaluations) | converged | mass [kg] initial → final | change | RMS initial design | RMS start | RMS final | function (median) | gradient (median) | threads | wall time |\n|---|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for r in &doc.runs {
        md += &format!(
            "| {} | {} | {} ({}) | {} | {:.4} → {:.4} | {:+.1} % | {:.4} {} | {:.4} {} | {:.4} {} | {} s | {} s | {} | {:.1} min |\n",
            r.run,
            r.fidelity,
            r.iterations,
            r.evaluations,
            if r.converged { "yes" } else { "**no**" },
            r.mass_initial_kg,
            r.mass_final_kg,
            r.mass_change_percent,
            r.rms_initial,
            r.unit,
            r.rms_start,
            r.unit,
            r.rms_final,
            r.unit,
            opt_f(r.function_median_s, 2),
            opt_f(r.gradient_median_s, 2),
            r.threads.map_or("–".into(), |t| t.to_string()),
            r.wall_time_s / 60.0
        );
    }
    let refs: Vec<_> = runs
        .iter()
        .filter_map(|r| r.opt().reference.as_ref().map(|x| (r, x)))
        .collect();
    if !refs.is_empty() {
        md += "\nPublished numbers beside the runs:\n\n| run | source | iterations | mass change | initial RMS | notes |\n|---|---|---:|---:|---:|---|\n";
        for (r, x) in refs {
            md += &format!(
                "| {} | {} | {} | {} | {} | {} |\n",
                r.label,
                x.source,
                x.iterations.map_or("–".into(), |v| v.to_string()),
                x.mass_change_percent
                    .map_or("–".into(), |v| format!("{v:+.1} %")),
                opt_f(x.initial_rms, 2),
                if x.design.is_empty() {
                    "–"
                } else {
                    &x.design
                }
            );
        }
    }
    if !doc.cross_evaluation.is_empty() {
        let unit = runs
            .iter()
            .find_map(|r| r.opt().cross_evaluation.as_ref().map(|c| c.unit.clone()))
            .unwrap_or_default();
        md += &format!("\n## Cross-evaluation\n\nEach design analysed with both fidelities at the flight condition of its study: RMS of the constrained output and the p-k flutter speed (searched up to twice the flight speed; V/V_flight in brackets).\n\n| run | design | fidelity | mass [kg] | RMS [{unit}] | flutter speed [m/s] |\n|---|---|---|---:|---:|---:|\n");
        for c in &doc.cross_evaluation {
            md += &format!(
                "| {} | {} | {} | {:.4} | {} | {} |\n",
                c.run,
                c.design,
                c.fidelity,
                c.mass_kg,
                c.rms
                    .map_or("unstable at the flight condition".into(), |v| format!(
                        "{v:.4}"
                    )),
                match (c.flutter_speed_m_s, c.flutter_speed_ratio) {
                    (Some(v), Some(q)) => format!("{v:.1} ({q:.3})"),
                    _ => "none".into(),
                }
            );
        }
    }
    if !doc.consistency.is_empty() {
        md += "\nThe same design with the same fidelity in two runs (a warm start's first design is the other run's optimum); the two numbers must agree where the models are the same:\n\n| run | other run | fidelity | model here | model there | RMS here | RMS there | relative difference |\n|---|---|---|---|---|---:|---:|---:|\n";
        let words = |m: &Option<String>| m.clone().unwrap_or_else(|| "not recorded".into());
        for c in &doc.consistency {
            md += &format!(
                "| {} | {} | {} | {} | {} | {:.6} | {:.6} | {:.1e} |\n",
                c.run,
                c.other,
                c.fidelity,
                words(&c.model_here),
                words(&c.model_there),
                c.rms_here,
                c.rms_there,
                c.relative_difference
            );
        }
        if doc
            .consistency
            .iter()
            .any(|c| c.same_model() == Some(false))
        {
            md += "\nWhere the two models differ (another lattice or mesh), the row measures the difference of the models, not the runs' consistency.\n";
        }
        if doc.consistency.iter().any(|c| c.same_model().is_none()) {
            md += "\nWhere a model is not recorded (results.json written before 2026-12-07), whether the two sides share one is unknown: the same fidelity on another lattice or mesh differs by its discretization.\n";
        }
    }
    md += "\n## Figures\n\n";
    for f in figures {
        md += &format!("![{f}]({f}.png)\n\n");
    }
    md
}

/// `gustkit compare`: the comparison report of `dirs` in `out` (written whole or not at all).
pub fn compare(dirs: &[PathBuf], out: &Path) -> Result<()> {
    if dirs.is_empty() {
        bail!("gustkit compare needs at least one run folder");
    }
    let runs = dirs
        .iter()
        .map(|d| load_run(d))
        .collect::<Result<Vec<_>>>()?;
    let folder = super::folder::RunFolder::begin(out, false)?;
    let dir = folder.path().to_path_buf();
    let mut figures = vec!["convergence", "thickness", "psd"];
    save_figure(&dir, "convergence", &convergence(&runs))?;
    save_figure(&dir, "thickness", &thickness(&runs))?;
    save_figure(&dir, "psd", &psd(&runs))?;
    let gaf_fig = runs
        .iter()
        .find_map(|r| r.opt().cross_evaluation.as_ref().and_then(|c| gafs(r, c)));
    if let Some(g) = gaf_fig {
        save_figure(&dir, "gafs", &g)?;
        figures.push("gafs");
    }
    let doc = CompareDoc {
        runs: runs.iter().map(run_row).collect(),
        cross_evaluation: runs
            .iter()
            .filter_map(|r| r.opt().cross_evaluation.as_ref().map(|c| cross_rows(r, c)))
            .flatten()
            .collect(),
        consistency: consistency(&runs),
    };
    super::write_atomic(
        &dir.join("compare.json"),
        serde_json::to_string_pretty(&doc)?.as_bytes(),
    )?;
    super::write_atomic(
        &dir.join("compare.md"),
        markdown(&runs, &doc, &figures).as_bytes(),
    )?;
    folder.commit()?;
    println!(
        "comparison of {} runs written to {}",
        runs.len(),
        out.display()
    );
    Ok(())
}
