//! The discrete gust part of a run's results: the envelope of peaks against the gust gradient,
//! the critical gust of every output and sign, the time histories at the critical gradients, and
//! their table, figures and CSV files (lengths in the study's unit, everything else in SI).

use crate::units::LengthUnit;
use serde::{Deserialize, Serialize};

/// Samples of a history kept in results.json for the figures (the CSV files hold them all).
pub const HISTORY_SAMPLES: usize = 1500;

/// One output of the discrete gust analysis.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct DiscreteOutput {
    pub name: String,
    /// SI unit ("m", "N m", "m/s²").
    pub unit: String,
}

/// The peaks of every output at one gust gradient (SI; the 1-cos search only).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct EnvelopeRow {
    pub gradient_m: f64,
    pub gradient_ft: f64,
    pub amplitude_m_s: f64,
    /// Added by the refinement about a critical gradient.
    pub refined: bool,
    /// Per output.
    pub max: Vec<f64>,
    pub t_max_s: Vec<f64>,
    pub min: Vec<f64>,
    pub t_min_s: Vec<f64>,
}

/// The critical gust of one output: its largest and smallest value and where they occur.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CriticalRow {
    pub output: String,
    pub unit: String,
    pub max: f64,
    pub t_max_s: f64,
    pub gradient_max_ft: Option<f64>,
    pub min: f64,
    pub t_min_s: f64,
    pub gradient_min_ft: Option<f64>,
}

/// A time history at an output's critical gust (decimated to [`HISTORY_SAMPLES`]).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct HistoryRow {
    pub output: String,
    pub unit: String,
    /// Which gust: "max" (the gradient of the largest value) or "min", or "profile".
    pub gust: String,
    pub gradient_ft: Option<f64>,
    pub time_s: Vec<f64>,
    pub value: Vec<f64>,
}

/// Everything the discrete gust analysis reports.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct DiscreteGustResults {
    /// "one_minus_cosine" or "tabulated".
    pub profile: String,
    /// The amplitude rule in words (1-cos) or the table's extent.
    pub amplitude: String,
    pub velocity_m_s: f64,
    /// The frequency grid and time window: span T (s), Δω = 2π/T, the last frequency, samples.
    pub span_s: f64,
    pub span_chosen: bool,
    pub d_omega_rad_s: f64,
    pub omega_max_rad_s: f64,
    pub n_time: usize,
    /// The largest fraction of a peak left in the window's last tenth (wrap-around bound) and of
    /// a gust's energy beyond the last frequency, over every gust analysed.
    pub wrap_max: f64,
    pub truncated_max: f64,
    pub outputs: Vec<DiscreteOutput>,
    pub envelope: Vec<EnvelopeRow>,
    pub critical: Vec<CriticalRow>,
    pub histories: Vec<HistoryRow>,
    pub time_s: f64,
}

/// The part of a history a reader looks at, decimated: from the start up to 20 % past the last
/// sample above 1e-3 of the peak |y| (the rest is the decayed tail the window needs against
/// wrap-around), every n-th sample and the last of that part, at most [`HISTORY_SAMPLES`]. The
/// CSV files keep every sample of the window.
pub fn decimate(time: &[f64], value: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let peak = value.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let last = value
        .iter()
        .rposition(|v| v.abs() > 1e-3 * peak)
        .unwrap_or(time.len() - 1);
    let end = (last + last / 5 + 1).min(time.len());
    let stride = end.div_ceil(HISTORY_SAMPLES).max(1);
    let keep: Vec<usize> = (0..end)
        .filter(|i| i % stride == 0 || *i == end - 1)
        .collect();
    (
        keep.iter().map(|&i| time[i]).collect(),
        keep.iter().map(|&i| value[i]).collect(),
    )
}

pub(crate) fn shown(unit: LengthUnit, v: f64, si: &str) -> (f64, String) {
    let (x, u) = unit.display(v, si, 1);
    (x, u.to_string())
}

/// The summary.md section.
pub fn summary_text(d: &DiscreteGustResults, unit: LengthUnit) -> String {
    let tick = crate::report::style::tick;
    let mut md = format!(
        "\n## Discrete gust\n\n{} gust at V = {} m/s; {}. Response by the frequency response and an inverse FFT: span {:.3} s ({}), Δω = {:.4} rad/s up to {:.1} rad/s (the GAF table's last k), {} time samples; at most {:.1e} of a peak left at the window's end (limit 1e-3) and {:.1e} of a gust's energy beyond the last frequency (limit 1e-4).\n\n| output | max | at t [s] | H [ft] | min | at t [s] | H [ft] | unit |\n|---|---:|---:|---:|---:|---:|---:|---|\n",
        if d.profile == "tabulated" { "Tabulated" } else { "Tuned 1-cos" },
        d.velocity_m_s,
        d.amplitude,
        d.span_s,
        if d.span_chosen { "chosen so that every response decays" } else { "given" },
        d.d_omega_rad_s,
        d.omega_max_rad_s,
        d.n_time,
        d.wrap_max,
        d.truncated_max,
    );
    let h = |g: Option<f64>| g.map_or("–".to_string(), |g| format!("{g:.1}"));
    for c in &d.critical {
        let (mx, u) = shown(unit, c.max, &c.unit);
        let (mn, _) = shown(unit, c.min, &c.unit);
        md += &format!(
            "| {} | {} | {:.4} | {} | {} | {:.4} | {} | {u} |\n",
            c.output,
            tick(&mx),
            c.t_max_s,
            h(c.gradient_max_ft),
            tick(&mn),
            c.t_min_s,
            h(c.gradient_min_ft)
        );
    }
    if d.profile != "tabulated" {
        md += &format!(
            "\nThe critical gradient of each output and sign is refined about the worst of the {} equally spaced gradients by golden section. Envelope: `discrete_gust_envelope.csv`; histories at the critical gradients: `discrete_gust_<output>.csv`.\n\n![peaks against the gust gradient](discrete_gust_envelope.png)\n",
            d.envelope.iter().filter(|e| !e.refined).count()
        );
    } else {
        md += "\nHistories: `discrete_gust_<output>.csv`.\n";
    }
    md += "\n![time histories](discrete_gust_histories.png)\n";
    md
}

/// The envelope CSV: one row a gradient (grid and refinement), max and min of every output.
pub fn envelope_csv(d: &DiscreteGustResults, unit: LengthUnit) -> String {
    let mut s = String::from("gradient_ft,gradient_m,amplitude_m_s,refined");
    for o in &d.outputs {
        let (_, u) = shown(unit, 1.0, &o.unit);
        s += &format!(
            ",{0} max [{u}],{0} t_max [s],{0} min [{u}],{0} t_min [s]",
            o.name
        );
    }
    s += "\n";
    for e in &d.envelope {
        s += &format!(
            "{},{},{},{}",
            e.gradient_ft, e.gradient_m, e.amplitude_m_s, e.refined
        );
        for (i, o) in d.outputs.iter().enumerate() {
            let (mx, _) = shown(unit, e.max[i], &o.unit);
            let (mn, _) = shown(unit, e.min[i], &o.unit);
            s += &format!(",{mx},{},{mn},{}", e.t_max_s[i], e.t_min_s[i]);
        }
        s += "\n";
    }
    s
}
