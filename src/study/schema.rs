//! Serde types of the study file (schema version 1).

pub use crate::units::LengthUnit;
use serde::{Deserialize, Serialize};

/// Top level of a study file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct StudyFile {
    /// Must equal [`super::SCHEMA_VERSION`].
    pub schema_version: u32,
    /// Study name; also the report folder name.
    pub name: String,
    #[serde(default)]
    pub description: String,
    /// Unit of every length in the file (span, chords, thicknesses).
    #[serde(default)]
    pub length_unit: LengthUnit,
    pub wing: WingSpec,
    pub material: MaterialSpec,
    pub structure: StructureSpec,
    /// Aerodynamic model and the reduced frequencies of the GAFs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aero: Option<AeroSpec>,
    /// Flight condition.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flight: Option<FlightSpec>,
    /// Continuous-turbulence response settings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gust: Option<GustSpec>,
    /// Discrete gust response (tuned 1-cos gusts or a tabulated profile) of the gust outputs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub discrete_gust: Option<DiscreteGustSpec>,
    /// p-k flutter sweep at the flight Mach number and density.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flutter: Option<FlutterSpec>,
    /// Gust-constrained mass minimization.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub optimization: Option<OptimizationSpec>,
    /// Parameter study run by `gustkit sweep`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sweep: Option<SweepSpec>,
}

/// A parameter study: the study's analysis (or optimization) at every combination of parameter
/// values, each parameter named by its path in this file (e.g. "flight.mach").
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SweepSpec {
    pub parameters: Vec<SweepParameter>,
    /// "grid": every combination (the first parameter varies fastest); "zip": the i-th values of
    /// every parameter together (equal lengths).
    #[serde(default)]
    pub combine: SweepCombine,
    /// Run the `optimization` section at every case instead of the analysis.
    #[serde(default)]
    pub optimize: bool,
    /// Run every combination with each of these aerodynamic fidelities in place of the study's
    /// own (e.g. `[{"dlm": {...}}, {"lfd": {...}}]`): one curve per fidelity in the figure.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub fidelities: Vec<crate::aero::FidelitySpec>,
}

/// One swept parameter.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SweepParameter {
    /// Dotted path of a number in the study file, e.g. "gust.turbulence.sigma_w_m_s".
    pub path: String,
    pub values: Vec<f64>,
}

/// How the parameter values combine into cases.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(rename_all = "snake_case")]
pub enum SweepCombine {
    #[default]
    Grid,
    Zip,
}

/// Minimum mass subject to RMS(output) ≤ limit and (optionally) the initial planform area.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct OptimizationSpec {
    /// Name of the constrained gust output.
    pub output: String,
    /// Largest RMS of that output (length unit for displacements, N·m for moments).
    pub rms_max: f64,
    /// Keep the planform area equal to the initial one.
    #[serde(default = "default_true")]
    pub fix_area: bool,
    /// Thickness bounds (length unit).
    pub thickness_min: f64,
    pub thickness_max: f64,
    /// Optional bounds relative to each element's initial thickness, [lower, upper] factors: the
    /// element's bounds are then [max(thickness_min, lower·t₀), min(thickness_max, upper·t₀)].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thickness_relative: Option<[f64; 2]>,
    /// [lower, upper] of the planform variables (length unit, degrees for the sweep).
    pub span: [f64; 2],
    pub sweep_c4_deg: [f64; 2],
    pub root_chord: [f64; 2],
    pub tip_chord: [f64; 2],
    /// Published results to compare with in the report (side by side).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<ReferenceSpec>,
    /// Optional flutter margin: every p-k root at `speed_factor` × the flight speed has damping
    /// g ≤ `damping_max`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flutter_margin: Option<FlutterMarginSpec>,
    /// Start from the final design of an earlier run (e.g. the DLM optimum before an LFD
    /// refinement); the mass change and the area constraint stay relative to this study's own
    /// initial design.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub warm_start: Option<WarmStartSpec>,
    #[serde(default = "default_max_iterations")]
    pub max_iterations: usize,
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    /// The SQP line search's memory: a trial point is accepted below the largest ℓ1 merit of the
    /// last this many accepted points (1: monotone). Left out of the serialized study at 1, so
    /// checkpoints of runs from before this field still resume.
    #[serde(
        default = "default_nonmonotone_memory",
        skip_serializing_if = "is_default_nonmonotone_memory"
    )]
    pub nonmonotone_memory: usize,
    /// How many times the optimization continues, from its optimum, with the RMS limit scaled by
    /// the constrained / refined RMS ratio of the resolution check when the refined RMS exceeds
    /// the limit beyond its tolerance (0: never; the run then exits 3 on such a design).
    #[serde(
        default = "default_resolution_corrections",
        skip_serializing_if = "is_default_resolution_corrections"
    )]
    pub resolution_corrections: usize,
    /// Minimize through a cheaper fidelity corrected to this study's at every accepted point
    /// (first-order model management): `{"low_fidelity": {"dlm": {…}}}`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model_management: Option<ModelManagementSpec>,
    /// A discrete gust peak limit: `{"output", "max"}` — the largest |value| of a `gust` output
    /// (or its acceleration, `<name>_acceleration`) over the `discrete_gust` section's gusts stays
    /// within `max` (length unit for displacements, N m, m/s²).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_constraint: Option<PeakConstraintSpec>,
}

/// `optimization.model_management`: the low fidelity and the trust region of
/// [`crate::optim::minimize_managed`].
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ModelManagementSpec {
    /// The cheap fidelity the corrected problems use (`{"dlm": {…}}`).
    pub low_fidelity: crate::aero::FidelitySpec,
    /// Initial trust-region half width, a fraction of each design variable's bound range.
    #[serde(default = "default_initial_radius")]
    pub initial_radius: f64,
    /// Outer iterations at most (each one high-fidelity function, and a gradient when its
    /// point is accepted).
    #[serde(default = "default_outer_iterations")]
    pub max_iterations: usize,
}

fn default_initial_radius() -> f64 {
    0.1
}
fn default_outer_iterations() -> usize {
    30
}

/// `optimization.peak_constraint`.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PeakConstraintSpec {
    pub output: String,
    pub max: f64,
}

/// `optimization.warm_start`: where the starting design comes from.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct WarmStartSpec {
    /// The results.json of a finished optimization, relative to the working directory (where
    /// `gustkit run` writes its run folders), e.g. "reports/agard445_dlm/results.json".
    pub from: std::path::PathBuf,
    /// Also start the BFGS approximation from that run's final one (its `checkpoint.json`
    /// beside results.json) instead of the identity. Left out of the serialized study when
    /// false, so checkpoints of runs from before this field still resume.
    #[serde(default, skip_serializing_if = "is_false")]
    pub hessian: bool,
}

fn is_false(b: &bool) -> bool {
    !*b
}

fn default_true() -> bool {
    true
}
fn default_max_iterations() -> usize {
    100
}
/// One correction: the refined RMS ratio moves little between neighbouring designs, so a second
/// correction is seldom needed (the flagship's needs one).
pub const DEFAULT_RESOLUTION_CORRECTIONS: usize = 1;
/// The largest `resolution_corrections` accepted (each is a whole warm-started optimization).
pub const MAX_RESOLUTION_CORRECTIONS: usize = 3;
fn default_resolution_corrections() -> usize {
    DEFAULT_RESOLUTION_CORRECTIONS
}
fn is_default_resolution_corrections(n: &usize) -> bool {
    *n == DEFAULT_RESOLUTION_CORRECTIONS
}
fn default_tolerance() -> f64 {
    1e-4
}
pub(crate) fn default_nonmonotone_memory() -> usize {
    1
}
fn is_default_nonmonotone_memory(n: &usize) -> bool {
    *n == default_nonmonotone_memory()
}

/// Published results of the same optimization, for the report's side-by-side table.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ReferenceSpec {
    /// Where the numbers come from.
    pub source: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub iterations: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass_change_percent: Option<f64>,
    /// RMS of the constrained output at the initial design (report units).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_rms: Option<f64>,
    /// What the reference's optimum looks like (free text).
    #[serde(default)]
    pub design: String,
}

/// The flutter-margin constraint of an optimization.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FlutterMarginSpec {
    /// Speed of the check relative to the flight speed (1.15: the customary 15 % margin).
    #[serde(default = "default_speed_factor")]
    pub speed_factor: f64,
    /// Largest damping g allowed for any root there (0: neutrally stable).
    #[serde(default)]
    pub damping_max: f64,
}

fn default_speed_factor() -> f64 {
    1.15
}

/// Velocity range of a p-k sweep (SI).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FlutterSpec {
    pub velocity_min_m_s: f64,
    pub velocity_max_m_s: f64,
    #[serde(default = "default_flutter_points")]
    pub points: usize,
}

fn default_flutter_points() -> usize {
    60
}

/// Stochastic gust analysis (paper Eqs. 16–18).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct GustSpec {
    /// `{"model": "dryden" | "von_karman", "sigma_w_m_s", "scale_length_m"}` (MIL-F-8785C L_w).
    pub turbulence: crate::gust::Turbulence,
    /// Lowest non-zero frequency of the log-spaced grid (the grid also holds ω = 0), rad/s.
    #[serde(default = "default_omega_min")]
    pub omega_min_rad_s: f64,
    /// Points of the log-spaced grid up to the highest reduced frequency of the GAF table.
    #[serde(default = "default_points")]
    pub points: usize,
    /// Largest fraction of an output's variance the grid may leave out above its last frequency
    /// (see `gust::response::TAIL_BEYOND` for the bound used).
    #[serde(default = "default_max_tail")]
    pub max_tail: f64,
    /// The mode-acceleration method (Nastran's MODACC): each output adds the quasi-static
    /// response of the modes left out through its residual flexibility, so the RMS converges
    /// with far fewer modes; `false` (the default) is the mode-displacement method.
    #[serde(default)]
    pub mode_acceleration: bool,
    /// Response outputs: vertical displacement at plate points (ξ chord fraction, η span fraction).
    pub outputs: Vec<OutputSpec>,
    /// How σ_w was chosen, if by calibration: `gustkit run` reports the RMS it gives against the
    /// target and the σ_w that would meet the target exactly (the RMS is linear in σ_w).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub calibration: Option<CalibrationSpec>,
}

/// Discrete gust analysis: the response of the gust section's outputs to vertical gusts that
/// convect over the wing at the flight speed, by the frequency response and an inverse FFT.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DiscreteGustSpec {
    /// `"one_minus_cosine"` (the default: the tuned gust search of CS-25.341(a)) or
    /// `"tabulated"` (the profile of `table`).
    #[serde(default)]
    pub profile: DiscreteProfileName,
    /// [H_min, H_max] of the tuned search, ft (CS-25: 30 to 350 ft).
    #[serde(default = "default_gradient_ft")]
    pub gradient_ft: [f64; 2],
    /// Points of the search grid in H (equally spaced; the critical H of each output is then
    /// refined).
    #[serde(default = "default_gradient_points")]
    pub gradient_points: usize,
    /// Admits gradients outside CS-25's 30–350 ft.
    #[serde(default)]
    pub allow_any_gradient: bool,
    /// The gust amplitude U_ds of the 1-cos: `{"u_ds_m_s": U}` (true airspeed, the same at every
    /// H) or `{"cs25": {"altitude_m", "f_g", "speed": "vc" | "vd"}}` (U_ref F_g (H/350 ft)^{1/6},
    /// EAS converted to TAS at the flight density).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub amplitude: Option<AmplitudeSpec>,
    /// The tabulated profile: `{"time_s": [...], "velocity_m_s": [...]}` (the gust velocity at
    /// `aero.gust_x_ref`, linear between points, zero outside).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub table: Option<GustTableSpec>,
    /// The time span of the response, s; default chosen so that every response decays in it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_span_s: Option<f64>,
    /// Adds the vertical acceleration of every displacement output (m/s²).
    #[serde(default)]
    pub accelerations: bool,
}

/// The shape of a discrete gust.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum DiscreteProfileName {
    #[default]
    OneMinusCosine,
    Tabulated,
}

/// The amplitude of the 1-cos gust.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum AmplitudeSpec {
    /// U_ds, m/s true airspeed, the same at every gradient.
    UDsMS(f64),
    /// CS-25.341(a)(4)–(6).
    Cs25(Cs25Spec),
}

/// The CS-25 design gust velocity's inputs.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Cs25Spec {
    /// Altitude of the flight condition, m (U_ref by altitude).
    pub altitude_m: f64,
    /// The flight profile alleviation factor F_g (0, 1].
    pub f_g: f64,
    /// `"vc"` (design cruising speed, the default) or `"vd"` (design dive speed: half U_ref).
    #[serde(default)]
    pub speed: DesignSpeed,
}

/// The design speed of a CS-25 gust.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum DesignSpeed {
    #[default]
    Vc,
    Vd,
}

/// A tabulated gust profile.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GustTableSpec {
    pub time_s: Vec<f64>,
    pub velocity_m_s: Vec<f64>,
}

fn default_gradient_ft() -> [f64; 2] {
    [30.0, 350.0]
}
fn default_gradient_points() -> usize {
    20
}

/// σ_w calibrated so that the initial RMS of `output` equals `target_rms` (length unit for
/// displacements, N·m for moments).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrationSpec {
    pub output: String,
    pub target_rms: f64,
    /// Free text: where the target comes from.
    #[serde(default)]
    pub source: String,
}

pub(crate) fn default_omega_min() -> f64 {
    1e-3
}
pub(crate) fn default_points() -> usize {
    2000
}
pub(crate) fn default_max_tail() -> f64 {
    1e-3
}

/// A response output: `{"name", "point": [ξ, η]}` for a vertical displacement (the default
/// quantity), or `{"name", "quantity": "root_bending_moment"}`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    pub name: String,
    /// `"vertical_displacement"` (default) or `"root_bending_moment"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quantity: Option<crate::gust::QuantityName>,
    /// (ξ, η) in [0, 1]² of a displacement output: [1, 1] is the wing-tip trailing edge.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point: Option<[f64; 2]>,
}

/// The aerodynamic model of a study.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct AeroSpec {
    /// Which fidelity and its settings, e.g. `{"dlm": {...}}`.
    pub fidelity: crate::aero::FidelitySpec,
    /// Reduced frequencies k = ω b_ref / U of the GAF table.
    pub reduced_frequencies: Vec<f64>,
    /// Reference semichord b_ref (length unit); default half the root chord.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_semichord: Option<f64>,
    /// Streamwise station of zero gust phase (length unit); default the root leading edge.
    #[serde(default)]
    pub gust_x_ref: f64,
    /// A second fidelity beside the study's own, e.g. `{"dlm": {...}}`: `gustkit run` repeats
    /// the analysis with it (GAFs, gust response, flutter) and analyses an optimization's
    /// initial, starting and final designs with it; it never drives the optimization.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub compare_with: Option<crate::aero::FidelitySpec>,
}

/// Free-stream condition (SI).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FlightSpec {
    pub mach: f64,
    pub velocity_m_s: f64,
    pub density_kg_m3: f64,
}

/// Planform and section.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct WingSpec {
    /// Semispan, length unit.
    pub span: f64,
    /// Quarter-chord sweep, degrees.
    pub sweep_c4_deg: f64,
    /// Streamwise root chord, length unit.
    pub root_chord: f64,
    /// Streamwise tip chord, length unit.
    pub tip_chord: f64,
    /// A built-in section name or a half-thickness table.
    pub airfoil: AirfoilSpec,
}

/// `"naca65a004"` or `{"name": …, "x_c": […], "z_c": […]}` (half-thickness over chord).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(untagged)]
pub enum AirfoilSpec {
    Builtin(String),
    Table {
        name: String,
        x_c: Vec<f64>,
        z_c: Vec<f64>,
    },
}

impl AirfoilSpec {
    /// The section this names, or why it names none.
    pub fn airfoil(&self) -> Result<crate::wing::Airfoil, String> {
        match self {
            AirfoilSpec::Builtin(name) => match name.to_ascii_lowercase().as_str() {
                "naca65a004" | "naca 65a004" => Ok(crate::wing::Airfoil::naca65a004()),
                other => Err(format!("unknown built-in airfoil '{other}' (built in: naca65a004; or give {{\"name\", \"x_c\", \"z_c\"}})")),
            },
            AirfoilSpec::Table { name, x_c, z_c } => {
                crate::wing::Airfoil::from_table(name, x_c.clone(), z_c.clone())
                    .map_err(|e| e.to_string())
            }
        }
    }
}

/// Orthotropic plate material (SI).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    pub e1_pa: f64,
    pub e2_pa: f64,
    pub g12_pa: f64,
    pub nu12: f64,
    pub density_kg_m3: f64,
    /// Grain (axis 1) angle from the spanwise axis toward the trailing edge, degrees.
    #[serde(default)]
    pub grain_angle_deg: f64,
}

/// Structural model and modal analysis settings.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct StructureSpec {
    #[serde(default)]
    pub mesh: MeshSpec,
    #[serde(default)]
    pub clamp: ClampSpec,
    /// The retained modes: a fixed count, or every mode below a cutoff frequency.
    #[serde(default = "default_modes")]
    pub modes: ModesSpec,
    /// Modal damping ratio ζ of every mode.
    #[serde(default)]
    pub damping_ratio: f64,
    /// Also retain in-plane (membrane) modes. Off by default: a flat plate's in-plane modes are
    /// uncoupled from its deflection and carry no aerodynamic force.
    #[serde(default)]
    pub in_plane_modes: bool,
    /// Thickness of each design patch (length unit), chordwise fastest from the root; defaults to
    /// the airfoil thickness.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thickness: Option<Vec<f64>>,
    /// Factor on every initial thickness (a sweep parameter: 1 leaves the wing as it is).
    #[serde(default = "default_one", skip_serializing_if = "is_one")]
    pub thickness_scale: f64,
}

fn default_one() -> f64 {
    1.0
}
fn is_one(v: &f64) -> bool {
    *v == 1.0
}

fn default_modes() -> ModesSpec {
    ModesSpec::Count(6)
}

/// `structure.modes`: a count (`6`), or every mode below a cutoff frequency with a floor and a
/// ceiling (`{"min": 6, "max": 40}`: the cutoff by the aerodynamic-table rule, or `cutoff_hz`).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(untagged)]
pub enum ModesSpec {
    Count(usize),
    Cutoff(ModeCutoffSpec),
}

/// Every mode below a cutoff frequency, at least `min` and at most `max` of them. Without
/// `cutoff_hz` the cutoff is `factor` × k_max V_top / (2π b_ref): the highest frequency whose
/// reduced frequency at the highest speed the study examines (the flight speed, the flutter
/// margin's speed, the flutter sweep's last) lies inside the GAF table.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ModeCutoffSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cutoff_hz: Option<f64>,
    #[serde(default = "default_one", skip_serializing_if = "is_one")]
    pub factor: f64,
    #[serde(default = "default_min_modes")]
    pub min: usize,
    #[serde(default = "default_max_modes")]
    pub max: usize,
}

fn default_min_modes() -> usize {
    6
}
fn default_max_modes() -> usize {
    40
}

/// Design patches chordwise × spanwise, each split into refine × refine elements.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSpec {
    pub chordwise: usize,
    pub spanwise: usize,
    #[serde(default = "default_refine")]
    pub refine: usize,
}

fn default_refine() -> usize {
    1
}

impl Default for MeshSpec {
    fn default() -> Self {
        Self {
            chordwise: 10,
            spanwise: 10,
            refine: 1,
        }
    }
}

/// `"all"`, `"interior"` or `{"root_nodes": [i, …]}` (chordwise node indices of the root row).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(untagged)]
pub enum ClampSpec {
    Named(String),
    RootNodes { root_nodes: Vec<usize> },
}

impl Default for ClampSpec {
    fn default() -> Self {
        ClampSpec::Named("all".into())
    }
}
