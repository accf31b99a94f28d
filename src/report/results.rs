//! The typed results of a wing study run (results.json): what `gustkit run` computed and what
//! `gustkit report` renders again, with nothing else needed.

use crate::flutter::FlutterResult;
use crate::gust::Turbulence;
use crate::kind::StudyKind;
use crate::structure::model::{Field, NODAL};
use crate::structure::{Modes, PlateModel};
use crate::units::LengthUnit;
use serde::{Deserialize, Serialize};

/// One mode in the modal summary.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ModeRow {
    pub mode: usize,
    pub frequency_hz: f64,
    /// "bending" or "membrane": the plate field the mode lives in.
    pub field: String,
    /// What the mode looks like: "1st bending", "1st torsion", … ([`mode_names`]).
    #[serde(default)]
    pub shape: String,
    /// Vertical displacement of the wing-tip trailing edge in the mass-normalized mode, m/√kg.
    pub tip_te_w: f64,
}

/// RMS and zero-crossing rate of one gust output.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct OutputRow {
    pub name: String,
    /// RMS in `unit` (SI).
    pub rms: f64,
    pub unit: String,
    pub n0_hz: f64,
}

/// The stochastic gust response at the study's design.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GustResults {
    pub mach: f64,
    pub velocity_m_s: f64,
    pub density_kg_m3: f64,
    pub q_inf_pa: f64,
    pub turbulence: Turbulence,
    /// Number of circular frequencies of the response grid and the largest, rad/s.
    pub n_omega: usize,
    pub omega_max_rad_s: f64,
    /// Outputs by the mode-acceleration method (residual flexibility of the modes left out).
    #[serde(default)]
    pub mode_acceleration: bool,
    pub outputs: Vec<OutputRow>,
    /// The response PSD of every output (SI).
    pub psd: Vec<PsdSeries>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub calibration: Option<Calibration>,
}

/// The σ_w calibration recorded in the study, checked at the initial design.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Calibration {
    pub output: String,
    /// Target and computed RMS in `unit` (the study's length unit for displacements).
    pub target_rms: f64,
    pub rms: f64,
    pub unit: String,
    pub sigma_w_m_s: f64,
    /// σ_w that meets the target exactly.
    pub sigma_w_for_target_m_s: f64,
    pub source: String,
}

/// A p-k sweep and its flutter point.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FlutterSummary {
    pub mach: f64,
    pub density_kg_m3: f64,
    /// The flight speed the verdict's speeds are relative to (absent in older results).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flight_speed_m_s: Option<f64>,
    #[serde(flatten)]
    pub result: FlutterResult,
}

/// A design as the report shows it.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct DesignSnapshot {
    pub mass_kg: f64,
    pub area_m2: f64,
    /// RMS of the constrained output in the report unit ([`OptimizationResults::unit`]: the
    /// study's length unit for displacements, N m for moments). Written as `rms_tip_in` before
    /// results schema 2, which holds the same value when the study's unit is inches.
    #[serde(alias = "rms_tip_in")]
    pub rms_display: f64,
    /// The same RMS in SI.
    pub rms: f64,
    pub frequencies_hz: Vec<f64>,
    pub design_variables: Vec<f64>,
    /// Element corner polygons (x, y) in the study's length unit, and element thickness in it.
    pub elements: Vec<Vec<(f64, f64)>>,
    pub thickness: Vec<f64>,
    /// Response PSD of the constrained output (SI).
    pub psd: PsdSeries,
}

/// One SQP iteration in physical units.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct HistoryRow {
    pub iteration: usize,
    pub mass_kg: f64,
    /// RMS of the constrained output in the report unit (`rms_tip_in` before results schema 2).
    #[serde(alias = "rms_tip_in")]
    pub rms_display: f64,
    pub area_m2: f64,
    /// KS aggregate of the p-k dampings up to the margin speed (with a flutter-margin
    /// constraint): the constrained value, above the largest damping by up to ln(n)/ρ.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flutter_damping: Option<f64>,
    /// The largest of those p-k dampings itself (what the margin means).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flutter_damping_peak: Option<f64>,
    pub violation: f64,
    pub kkt: f64,
    pub evaluations: usize,
    /// The optimization pass this iteration belongs to: 1, then 2, … for each resolution
    /// correction (absent for the first).
    #[serde(default = "first_pass", skip_serializing_if = "is_first_pass")]
    pub pass: usize,
}

fn first_pass() -> usize {
    1
}
fn is_first_pass(p: &usize) -> bool {
    *p == 1
}

/// One resolution correction: the optimization continued from the previous pass's optimum with
/// the RMS limit scaled by the constrained / refined RMS ratio that the check measured there.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ResolutionCorrection {
    /// 2 for the first correction.
    pub pass: usize,
    /// The constrained and the refined RMS of the previous pass's optimum (report unit).
    pub rms_display: f64,
    pub refined_rms_display: f64,
    /// The limit this pass constrained the study's model to (report unit): the study's limit ×
    /// rms_display / refined_rms_display.
    pub rms_limit_display: f64,
    /// With a discrete gust peak limit corrected too: the factor on it (constrained / refined
    /// peak of the previous optimum).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_factor: Option<f64>,
    pub iterations: usize,
    pub evaluations: usize,
    pub converged: bool,
    pub message: String,
    pub mass_kg: f64,
    pub wall_time_s: f64,
}

/// The optimization: the keys the issue asks for at the top level of results.json.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct OptimizationResults {
    pub converged: bool,
    pub message: String,
    pub iterations: usize,
    pub evaluations: usize,
    pub wall_time_s: f64,
    pub output: String,
    /// RMS limit in report units.
    pub rms_limit: f64,
    pub unit: String,
    pub fix_area: bool,
    /// The flutter-margin constraint: speed factor and largest damping, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flutter_margin: Option<(f64, f64)>,
    /// Sharpness ρ of the KS aggregate of the p-k dampings the margin constraint used (200
    /// before it was recorded).
    #[serde(default = "default_ks_rho")]
    pub ks_rho: f64,
    /// Damping change that made one unit of the normalized margin constraint (0.1 before it
    /// was recorded).
    #[serde(default = "default_damping_scale")]
    pub damping_scale: f64,
    /// Published results to compare with.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<crate::study::ReferenceSpec>,
    pub design_variable_names: Vec<String>,
    pub lower: Vec<f64>,
    pub upper: Vec<f64>,
    pub initial: DesignSnapshot,
    #[serde(rename = "final")]
    pub final_: DesignSnapshot,
    pub history: Vec<HistoryRow>,
    /// Flutter speeds of the initial and final designs (absent in results before this field;
    /// not `flutter`, which is the study's own p-k sweep beside it at the top level).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flutter_check: Option<FlutterCheck>,
    /// The results.json whose final design started this run (`optimization.warm_start.from`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub warm_start: Option<String>,
    /// Wall times of the functions and gradients this run evaluated (absent before this field).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub timing: Option<Timing>,
    /// The initial, starting and final designs analysed with this run's fidelity and the one of
    /// `aero.compare_with` (absent without it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cross_evaluation: Option<CrossEvaluation>,
    /// The resolution corrections after the first pass (`optimization.resolution_corrections`);
    /// `iterations`, `evaluations`, `wall_time_s` and `history` count every pass, `timing` is the
    /// first pass's.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub corrections: Vec<ResolutionCorrection>,
    /// The discrete gust peak limit, when the optimization has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_limit: Option<PeakLimitResult>,
}

/// A discrete gust peak limit at the initial and final designs: the KS aggregate (the
/// constrained value, ≤ 1 when met) and the largest sampled |y| over the limit, and the limit in
/// the report's unit.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct PeakLimitResult {
    pub output: String,
    pub limit: f64,
    pub unit: String,
    pub gusts: usize,
    pub ks_rho: f64,
    pub initial_ks: f64,
    pub initial_peak: f64,
    pub final_ks: f64,
    pub final_peak: f64,
}

/// Wall times of repeated measurements, seconds: median, minimum and maximum.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Stats {
    pub repetitions: usize,
    pub median_s: f64,
    pub min_s: f64,
    pub max_s: f64,
}

impl Stats {
    /// The statistics of `samples` (at least one).
    pub fn of(mut samples: Vec<f64>) -> Self {
        samples.sort_by(f64::total_cmp);
        let n = samples.len();
        Self {
            repetitions: n,
            median_s: if n % 2 == 1 {
                samples[n / 2]
            } else {
                0.5 * (samples[n / 2 - 1] + samples[n / 2])
            },
            min_s: samples[0],
            max_s: samples[n - 1],
        }
    }

    /// One report line: `label  median ms (min … max, N reps)`.
    pub fn line(&self, label: &str) -> String {
        format!(
            "  {label:<42}{:9.2} ms  (min {:.2}, max {:.2}, {} reps)",
            1e3 * self.median_s,
            1e3 * self.min_s,
            1e3 * self.max_s,
            self.repetitions
        )
    }

    /// The same line in seconds, for stages that take seconds to minutes.
    pub fn line_s(&self, label: &str) -> String {
        format!(
            "  {label:<42}{:9.2} s   (min {:.2}, max {:.2}, {} reps)",
            self.median_s, self.min_s, self.max_s, self.repetitions
        )
    }
}

/// How long the optimization's evaluations took in this run (a resumed run: since the resume).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Timing {
    /// One function: model at the design (modes, aerodynamic model, GAFs), gust response and
    /// constraints.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub function: Option<Stats>,
    /// One gradient of the objective and every constraint with respect to every variable.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gradient: Option<Stats>,
    /// Threads of the process's thread pool.
    pub threads: usize,
    /// An LFD model's GMRES iterations a right-hand side, every function's GAF table in the
    /// order evaluated (they fall as the warm start takes hold; a resumed run: every session's).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub function_gmres_per_rhs: Vec<f64>,
    /// The same for every gradient's adjoint solves.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub gradient_gmres_per_rhs: Vec<f64>,
}

/// One design analysed with one fidelity.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FidelityEvaluation {
    /// `dlm` or `lfd`.
    pub fidelity: String,
    /// The fidelity's model in words (lattice, mesh or strips; absent in results before this
    /// field).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<String>,
    /// RMS of each gust output (SI), in the study's output order; absent where this fidelity
    /// finds the design unstable at the flight condition (see `unstable`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rms: Option<Vec<f64>>,
    /// RMS of the constrained output in the report unit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rms_display: Option<f64>,
    /// Why there is no gust response: the unstable root at the flight condition.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unstable: Option<String>,
    /// The p-k flutter point at the flight Mach number and density (searched up to
    /// [`CrossEvaluation::searched_up_to_m_s`]).
    pub flutter: FlutterPoint,
    /// PSD of the constrained output (absent where unstable).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub psd: Option<PsdSeries>,
    /// The GAF table of the design's modes.
    pub gafs: gustkit_core::GafTable,
    /// Wall time of the evaluation, s.
    pub time_s: f64,
}

/// One design (`initial`, `start` of a warm start, `final`) and its analyses with both
/// fidelities, this run's first.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CrossDesign {
    pub design: String,
    pub mass_kg: f64,
    pub design_variables: Vec<f64>,
    pub evaluations: Vec<FidelityEvaluation>,
}

/// The optimization's designs analysed with both fidelities (`aero.compare_with`):
/// RMS, flutter and GAFs of each design from each, for the comparison report.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CrossEvaluation {
    pub output: String,
    pub unit: String,
    pub flight_speed_m_s: f64,
    pub searched_up_to_m_s: f64,
    pub designs: Vec<CrossDesign>,
}

/// Where a design flutters: the p-k crossing, if any, below `searched_up_to_m_s`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct FlutterPoint {
    pub speed_m_s: Option<f64>,
    pub frequency_hz: Option<f64>,
    pub mode: Option<usize>,
}

/// The flutter speeds of an optimization's initial and final designs at the flight Mach number
/// and density, and of the final design with more modes than the study retains (the margin
/// constraint sees only the retained ones).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct FlutterCheck {
    pub flight_speed_m_s: f64,
    pub searched_up_to_m_s: f64,
    pub initial: FlutterPoint,
    #[serde(rename = "final")]
    pub final_: FlutterPoint,
    pub modes: usize,
    /// The final design with `more_modes` modes, where the plate has that many.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub more_modes: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub final_more_modes: Option<FlutterPoint>,
    /// The final design's p-k sweep (the V-g and V-f figure of the final design).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub final_sweep: Option<crate::flutter::FlutterResult>,
}

fn default_ks_rho() -> f64 {
    200.0
}
fn default_damping_scale() -> f64 {
    0.1
}

/// Everything `gustkit run` computed; results.json.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunResults {
    /// Always `wing`.
    pub kind: StudyKind,
    pub study: String,
    pub description: String,
    /// The study's length unit: figures and tables show lengths in it ("in", "m", "ft").
    pub length_unit: LengthUnit,
    pub mass_kg: f64,
    pub area_m2: f64,
    pub n_design_variables: usize,
    pub frequencies_hz: Vec<f64>,
    pub modes: Vec<ModeRow>,
    pub mode_shapes: ModeShapes,
    /// The aerodynamic fidelity of the run (`dlm`, `lfd`; absent in results before this field).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fidelity: Option<String>,
    /// Its model in words (lattice, mesh or strips; absent in results before this field), so
    /// that a comparison knows whether two runs of one fidelity share a model.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aero_model: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gust: Option<GustResults>,
    /// The discrete gust analysis at the study's design (absent without the section).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub discrete_gust: Option<crate::report::discrete::DiscreteGustResults>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flutter: Option<FlutterSummary>,
    #[serde(default, skip_serializing_if = "Option::is_none", flatten)]
    pub optimization: Option<OptimizationResults>,
    /// The analysis repeated with `aero.compare_with` (absent without it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub comparison: Option<FidelityComparison>,
    /// The resolution check of the final design (the initial one without an optimization).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub resolution_check: Option<ResolutionCheck>,
    /// The DLM lattice against 0.08 V/f at the highest frequency it must resolve.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lattice_rule: Option<crate::aero::dlm::LatticeRule>,
    pub run_time_s: f64,
}

/// The resolution check of a design (`runner::wing::resolution`): its flutter point and RMS at
/// the study's resolution and at a refined one (twice the modes, the DLM lattice refined by two),
/// and whether the refined model still meets the requirement (SI).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ResolutionCheck {
    /// The study's model ("DLM 8 × 12 boxes, 11 modes") and the refined one (absent when the
    /// refined analysis could not run: `not_run` says why).
    pub model: String,
    pub refined_model: Option<String>,
    pub flight_speed_m_s: f64,
    /// The speed up to which the design must not flutter (the margin speed, or the flight speed).
    pub stable_to_m_s: f64,
    /// The stability verdicts in words, and the lowest speed each found unstable.
    pub flutter: String,
    pub flutter_speed_m_s: Option<f64>,
    pub refined_flutter: Option<String>,
    pub refined_flutter_speed_m_s: Option<f64>,
    /// RMS of every gust output at both resolutions (empty without a gust analysis), m or N m.
    pub rms_m: Vec<f64>,
    pub refined_rms_m: Vec<f64>,
    /// Why the refined model gives no gust response (unstable at the flight speed).
    pub refined_unstable: Option<String>,
    /// The constrained output's index and RMS limit, when there is one.
    pub rms_limit: Option<(usize, f64)>,
    pub flutter_tolerance: f64,
    pub rms_tolerance: f64,
    pub passed: bool,
    pub not_run: Option<String>,
    pub time_s: f64,
    /// The unit the words show the RMS of the constrained (or first) output in, and the factor
    /// from SI to it (the study's length unit for a displacement; SI before this field).
    #[serde(default = "si_unit")]
    pub rms_unit: String,
    #[serde(default = "unit_factor")]
    pub rms_unit_scale: f64,
    /// With a discrete gust peak limit: the largest sampled |y| over the limit at both
    /// resolutions (held to the limit within the RMS tolerance at the refined one).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refined_peak: Option<f64>,
}

fn si_unit() -> String {
    "SI".into()
}
fn unit_factor() -> f64 {
    1.0
}

/// The study's analysis at its initial design with its own fidelity and with the one of
/// `aero.compare_with`: GAF tables, gust response and p-k sweep of the second beside the first.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FidelityComparison {
    /// The study's own fidelity and the second one.
    pub fidelity: String,
    pub other: String,
    pub gafs: gustkit_core::GafTable,
    pub gafs_other: gustkit_core::GafTable,
    /// Per reduced frequency: the largest difference of a Q_ss entry over the largest |Q_ss|
    /// of the own table, and the same for Q_gs.
    pub gaf_difference_ss: Vec<f64>,
    pub gaf_difference_gs: Vec<f64>,
    /// The second fidelity's RMS of every gust output (SI), or why there is none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rms_other: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub psd_other: Vec<PsdSeries>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unstable_other: Option<String>,
    /// The second fidelity's p-k sweep over the study's flutter speeds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flutter_other: Option<FlutterResult>,
}

impl FidelityComparison {
    /// Per k, the largest entry difference of two tables over the largest entry of `own` (Q_ss
    /// and Q_gs apart).
    pub fn differences(
        own: &gustkit_core::GafTable,
        other: &gustkit_core::GafTable,
    ) -> (Vec<f64>, Vec<f64>) {
        let rel =
            |a: &mut dyn Iterator<Item = (num_complex::Complex64, num_complex::Complex64)>| {
                let (d, m) = a.fold((0.0f64, 0.0f64), |(d, m), (x, y)| {
                    (d.max((x - y).norm()), m.max(x.norm()))
                });
                d / m.max(f64::MIN_POSITIVE)
            };
        (0..own.k.len())
            .map(|i| {
                let ss = rel(&mut own.q_ss[i]
                    .iter()
                    .flatten()
                    .copied()
                    .zip(other.q_ss[i].iter().flatten().copied()));
                let gs = rel(&mut own.q_gs[i]
                    .iter()
                    .copied()
                    .zip(other.q_gs[i].iter().copied()));
                (ss, gs)
            })
            .unzip()
    }
}

/// Mode shapes on the planform: one panel a mode, each element coloured by its mean deflection
/// (membrane modes by in-plane displacement magnitude), scaled to the mode's maximum.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ModeShapes {
    /// Element corner polygons in display units.
    pub(crate) polygons: Vec<Vec<(f64, f64)>>,
    /// Per mode: title and per-element value in [-1, 1].
    pub(crate) panels: Vec<(String, Vec<f64>)>,
    pub(crate) unit: String,
}

/// The corner polygons (x, y) of every plate element, in units of `to_m` metres.
pub fn element_polygons(model: &PlateModel, to_m: f64) -> Vec<Vec<(f64, f64)>> {
    let xy = model.node_xy();
    model
        .mesh
        .elements
        .iter()
        .map(|e| {
            e.iter()
                .map(|&n| (xy[n][0] / to_m, xy[n][1] / to_m))
                .collect()
        })
        .collect()
}

pub use crate::structure::shape_name::mode_names;

impl ModeShapes {
    /// Builds the figure data; lengths are shown in `unit` (`to_m` metres each).
    pub fn new(model: &PlateModel, modes: &Modes, unit: &str, to_m: f64) -> Self {
        let polygons = element_polygons(model, to_m);
        let names = mode_names(model, modes);
        let panels = modes
            .modes
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let value = |n: usize| {
                    let c = &m.shape[NODAL * n..NODAL * (n + 1)];
                    match m.field {
                        Field::Bending => c[0],
                        Field::Membrane => c[3].hypot(c[4]),
                    }
                };
                let vals: Vec<f64> = model
                    .mesh
                    .elements
                    .iter()
                    .map(|e| e.iter().map(|&n| value(n)).sum::<f64>() / 4.0)
                    .collect();
                let peak = vals
                    .iter()
                    .fold(0.0f64, |a, v| a.max(v.abs()))
                    .max(f64::MIN_POSITIVE);
                (
                    format!("Mode {}: {:.2} Hz ({})", i + 1, m.freq_hz(), names[i]),
                    vals.iter().map(|v| v / peak).collect(),
                )
            })
            .collect();
        Self {
            polygons,
            panels,
            unit: unit.to_string(),
        }
    }
}

/// The response PSD of one output (SI, one-sided in ω).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PsdSeries {
    pub label: String,
    pub unit: String,
    pub omega_rad_s: Vec<f64>,
    pub psd: Vec<f64>,
}
