//! The results of `gustkit sweep` (sweep_results.json) and the table, CSV and figure rendered from
//! them alone.

use super::style::{legend_right, series_color, tick, LegendEntry};
use super::{save_figure, write_atomic, Figure};
use anyhow::{anyhow, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One named result of a case.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Metric {
    pub name: String,
    pub unit: String,
    pub value: f64,
}

/// The outcome of one case.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CaseResult {
    pub index: usize,
    /// Parameter values, in the order of `SweepResults::parameters`.
    pub values: Vec<f64>,
    /// The case's fidelity when the sweep runs several (`sweep.fidelities`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fidelity: Option<String>,
    /// Hash of the case's study, so that `--resume` reuses a result only for the same case.
    pub study_hash: String,
    /// Mass, RMS of each output, flutter speed, optimum … (empty when the case failed).
    pub metrics: Vec<Metric>,
    /// Why the case failed (e.g. the flight condition flutters), if it did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// How the case's optimization ended (with `optimize`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub message: Option<String>,
    pub wall_time_s: f64,
}

/// All cases of a sweep.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SweepResults {
    pub study: String,
    pub parameters: Vec<String>,
    /// How the parameter values combined: with "zip" the curves join every case of a fidelity
    /// (the other parameters move with the first), with "grid" the cases that share the others.
    #[serde(default)]
    pub combine: crate::study::SweepCombine,
    pub optimize: bool,
    pub cases: Vec<CaseResult>,
    pub wall_time_s: f64,
}

impl SweepResults {
    /// Names (with units) of every metric any case reported, in first-seen order.
    fn metric_names(&self) -> Vec<(String, String)> {
        let mut names: Vec<(String, String)> = Vec::new();
        for c in &self.cases {
            for m in &c.metrics {
                if !names.iter().any(|(n, _)| *n == m.name) {
                    names.push((m.name.clone(), m.unit.clone()));
                }
            }
        }
        names
    }

    /// The metrics worth a panel of the figure: those that vary between cases (a Mach sweep
    /// does not change the mass); all of them when none varies.
    fn plotted_metrics(&self) -> Vec<(String, String)> {
        let names = self.metric_names();
        let varies = |n: &str| {
            let v: Vec<f64> = self
                .cases
                .iter()
                .filter_map(|c| Self::value(c, n))
                .collect();
            let (lo, hi) = v
                .iter()
                .fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(*x), b.max(*x)));
            hi - lo > 1e-12 * hi.abs().max(lo.abs())
        };
        let varying: Vec<(String, String)> =
            names.iter().filter(|(n, _)| varies(n)).cloned().collect();
        if varying.is_empty() {
            names
        } else {
            varying
        }
    }

    fn value(c: &CaseResult, name: &str) -> Option<f64> {
        c.metrics.iter().find(|m| m.name == name).map(|m| m.value)
    }

    /// Whether the cases run with several fidelities (a fidelity column and curve labels).
    fn has_fidelities(&self) -> bool {
        self.cases.iter().any(|c| c.fidelity.is_some())
    }
}

/// The table as CSV (failed cases have empty metrics and their error in the last column).
pub fn csv(r: &SweepResults) -> String {
    let names = r.metric_names();
    let mut out = String::from("case");
    if r.has_fidelities() {
        out += ",fidelity";
    }
    for p in &r.parameters {
        out += &format!(",{p}");
    }
    for (n, u) in &names {
        out += &format!(",{n} [{u}]");
    }
    out += ",error\n";
    for c in &r.cases {
        out += &c.index.to_string();
        if r.has_fidelities() {
            out += &format!(",{}", c.fidelity.as_deref().unwrap_or(""));
        }
        for v in &c.values {
            out += &format!(",{v}");
        }
        for (n, _) in &names {
            out += &match SweepResults::value(c, n) {
                Some(v) => format!(",{v:.10e}"),
                None => ",".into(),
            };
        }
        let err = c.error.as_deref().unwrap_or("").replace(['"', '\n'], "'");
        out += &format!(",\"{err}\"\n");
    }
    out
}

/// The markdown summary with the table.
pub fn summary(r: &SweepResults) -> String {
    let names = r.metric_names();
    let failed = r.cases.iter().filter(|c| c.error.is_some()).count();
    let mut md = format!(
        "# {}: sweep\n\n{} cases of {} over {} ({} failed), {:.1} s in all.\n\n| case |",
        r.study,
        r.cases.len(),
        if r.optimize {
            "the optimization"
        } else {
            "the analysis"
        },
        r.parameters.join(", "),
        failed,
        r.wall_time_s
    );
    let fidelity_column = r.has_fidelities();
    if fidelity_column {
        md += " fidelity |";
    }
    for p in &r.parameters {
        md += &format!(" {p} |");
    }
    for (n, u) in &names {
        md += &format!(" {n} [{u}] |");
    }
    md += "\n|---:|";
    if fidelity_column {
        md += "---|";
    }
    md += &"---:|".repeat(r.parameters.len() + names.len());
    md += "\n";
    for c in &r.cases {
        md += &format!("| {} |", c.index);
        if fidelity_column {
            md += &format!(" {} |", c.fidelity.as_deref().unwrap_or(""));
        }
        for v in &c.values {
            md += &format!(" {v} |");
        }
        for (n, _) in &names {
            md += &match SweepResults::value(c, n) {
                Some(v) if v.fract() == 0.0 && v.abs() < 1e9 => format!(" {v:.0} |"),
                Some(v) => format!(" {v:.5} |"),
                None => " – |".into(),
            };
        }
        md += "\n";
    }
    for c in r.cases.iter().filter(|c| c.message.is_some()) {
        md += &format!(
            "\nCase {} (optimization): {}\n",
            c.index,
            c.message.as_deref().unwrap_or("")
        );
    }
    for c in r.cases.iter().filter(|c| c.error.is_some()) {
        md += &format!("\nCase {}: {}\n", c.index, c.error.as_deref().unwrap_or(""));
    }
    md += "\n![sweep](sweep.png)\n\nThe figure leaves out the results that are the same in every case. Table: `sweep.csv`.\n";
    md
}

/// Every metric against the first parameter, one line for each combination of the others.
pub struct SweepPlot<'a> {
    pub results: &'a SweepResults,
}

impl Figure for SweepPlot<'_> {
    fn size(&self) -> (u32, u32) {
        let n = self.results.plotted_metrics().len().max(1) as u32;
        (1000, 340 * n)
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing sweep: {e}");
        area.fill(&WHITE).map_err(err)?;
        let r = self.results;
        let names = r.plotted_metrics();
        // groups: cases sharing the fidelity and the values of every parameter but the first
        type Key = (Option<String>, Vec<f64>);
        let mut groups: Vec<(Key, Vec<&CaseResult>)> = Vec::new();
        let zip = r.combine == crate::study::SweepCombine::Zip;
        for c in &r.cases {
            let others = if zip {
                Vec::new()
            } else {
                c.values[1..].to_vec()
            };
            let key = (c.fidelity.clone(), others);
            match groups.iter_mut().find(|g| g.0 == key) {
                Some(g) => g.1.push(c),
                None => groups.push((key, vec![c])),
            }
        }
        let labels: Vec<String> = groups
            .iter()
            .map(|(key, _)| {
                let label = key
                    .0
                    .iter()
                    .cloned()
                    .chain(
                        r.parameters[1..]
                            .iter()
                            .zip(&key.1)
                            .map(|(p, v)| format!("{p} = {v}")),
                    )
                    .collect::<Vec<_>>()
                    .join(", ");
                if label.is_empty() && zip && r.parameters.len() > 1 {
                    format!("{} with {}", r.parameters[0], r.parameters[1..].join(", "))
                } else {
                    label
                }
            })
            .collect();
        let any_failed = names.iter().any(|(name, _)| {
            r.cases
                .iter()
                .any(|c| SweepResults::value(c, name).is_none())
        });
        let mut entries: Vec<LegendEntry> = Vec::new();
        if groups.len() > 1 || any_failed {
            entries.extend(
                labels
                    .iter()
                    .enumerate()
                    .filter(|(_, l)| !l.is_empty())
                    .map(|(gi, l)| LegendEntry::line(l.clone(), series_color(gi))),
            );
            if any_failed {
                entries.push(LegendEntry::marker("failed case (×)", RED.to_rgba()));
            }
        }
        let plot = legend_right(area, &entries, 10)?;
        let panels = plot.split_evenly((names.len().max(1), 1));
        let xs = || r.cases.iter().map(|c| c.values[0]);
        let (x0, x1) = (xs().fold(f64::MAX, f64::min), xs().fold(f64::MIN, f64::max));
        let (x0, x1) = if x1 > x0 {
            (x0, x1)
        } else {
            (x0 - 0.5, x1 + 0.5)
        };
        for (panel, (name, unit)) in panels.iter().zip(&names) {
            let ys: Vec<f64> = r
                .cases
                .iter()
                .filter_map(|c| SweepResults::value(c, name))
                .collect();
            if ys.is_empty() {
                continue;
            }
            let (y0, y1) = (
                ys.iter().copied().fold(f64::MAX, f64::min),
                ys.iter().copied().fold(f64::MIN, f64::max),
            );
            let pad = 0.08 * (y1 - y0).max(1e-9 * y1.abs().max(1e-30));
            // decimals enough to tell ticks a tenth of the range apart, no more
            let digits = (-(0.1 * (y1 - y0 + 2.0 * pad)).log10())
                .ceil()
                .clamp(0.0, 8.0) as usize;
            let mut chart = ChartBuilder::on(panel)
                .margin(10)
                .margin_right(30)
                .x_label_area_size(35)
                .y_label_area_size(75)
                .build_cartesian_2d(x0..x1, (y0 - pad)..(y1 + pad))
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc(r.parameters[0].as_str())
                .y_desc(format!("{name} [{unit}]"))
                .x_label_formatter(&tick)
                .y_label_formatter(&|v| tick(&format!("{v:.digits$}").parse().unwrap_or(*v)))
                .label_style(("sans-serif", 14))
                .axis_desc_style(("sans-serif", 14))
                .draw()
                .map_err(err)?;
            for (gi, (_, cases)) in groups.iter().enumerate() {
                let color = series_color(gi);
                let mut pts: Vec<(f64, f64)> = cases
                    .iter()
                    .filter_map(|c| SweepResults::value(c, name).map(|y| (c.values[0], y)))
                    .collect();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                chart
                    .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
                    .map_err(err)?;
                chart
                    .draw_series(pts.iter().map(|p| Circle::new(*p, 4, color.filled())))
                    .map_err(err)?;
            }
            // cases that failed (or lack this result) get a red cross on the lower edge
            let failed: Vec<f64> = r
                .cases
                .iter()
                .filter(|c| SweepResults::value(c, name).is_none())
                .map(|c| c.values[0])
                .collect();
            if !failed.is_empty() {
                chart
                    .draw_series(
                        failed
                            .iter()
                            .map(|x| Cross::new((*x, y0 - 0.5 * pad), 6, RED.stroke_width(2))),
                    )
                    .map_err(err)?;
            }
        }
        Ok(())
    }
}

/// Writes sweep_results.json, sweep.csv, sweep.md and the figure into `dir`.
pub fn render(dir: &Path, r: &SweepResults) -> Result<()> {
    save_figure(dir, "sweep", &SweepPlot { results: r })?;
    write_atomic(&dir.join("sweep.csv"), csv(r).as_bytes())?;
    write_atomic(&dir.join("sweep.md"), summary(r).as_bytes())?;
    write_atomic(
        &dir.join("sweep_results.json"),
        serde_json::to_string_pretty(r)?.as_bytes(),
    )
}

/// Reads `dir/sweep_results.json` and renders the sweep report again.
pub fn rerender(dir: &Path) -> Result<SweepResults> {
    let path = dir.join("sweep_results.json");
    let r: SweepResults = super::from_json(&path, &super::read_json(&path)?)?;
    render(dir, &r)?;
    Ok(r)
}
