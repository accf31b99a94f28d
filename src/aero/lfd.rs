//! The CFD fidelity's settings and builders: the scheme (order, limiter), the built-in airfoil
//! O-mesh and mesh files with their boundary markers, and the LFD model of a 2-D section (steady
//! Euler flow converged on the built-in mesh about a scaled NACA 64A0xx). Every closed set of
//! strings in a CFD spec is a serde enum, so a typo is refused with its JSON path at load.

use super::contract::{
    BuildError, Capabilities, SurfaceBinding, WingBuilder, WingContext, WingFidelity,
};
use crate::wing::{N_PLANFORM, PLANFORM_NAMES};
use anyhow::{Context, Result};
use gustkit_cfd::airfoil::AirfoilShape;
use gustkit_cfd::ilu::{IluOrdering, IluParams};
use gustkit_cfd::lfd::{LfdOperator, LfdParams, Preconditioner};
use gustkit_cfd::lfd_model::Lfd;
use gustkit_cfd::mesh::{Boundary, Mesh};
use gustkit_cfd::mesh_sensitivity::MeshTangent;
use gustkit_cfd::residual::{free_stream, Euler, Limiter, Order};
use gustkit_cfd::steady::NewtonLinearSolver;
use gustkit_cfd::steady::SteadyParams;
use gustkit_cfd::wing_mesh::{SectionCell, WingMesh, WingMeshSpec};
use gustkit_core::scalar::Dual;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Spatial order of the finite-volume scheme.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum OrderSpec {
    First,
    #[default]
    Second,
}

impl std::fmt::Display for OrderSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            OrderSpec::First => "first",
            OrderSpec::Second => "second",
        })
    }
}

impl OrderSpec {
    pub fn order(self) -> Order {
        match self {
            OrderSpec::First => Order::First,
            OrderSpec::Second => Order::Second,
        }
    }
}

/// Limiter of the second-order reconstruction.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum LimiterSpec {
    #[default]
    None,
    /// The smooth, differentiable van Albada average (ε = 1e-3 of the free-stream scales).
    VanAlbada,
}

impl LimiterSpec {
    pub fn limiter(self) -> Limiter {
        match self {
            LimiterSpec::None => Limiter::None,
            LimiterSpec::VanAlbada => Limiter::VanAlbada { eps: 1e-3 },
        }
    }
}

/// A built-in airfoil of the CFD fidelity.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
pub enum CfdAirfoil {
    /// NACA 64A010 from its NACA Report 903 ordinates.
    #[serde(rename = "naca64a010")]
    Naca64a010,
}

impl CfdAirfoil {
    pub fn shape(self) -> AirfoilShape {
        match self {
            CfdAirfoil::Naca64a010 => AirfoilShape::naca64a010(),
        }
    }
}

/// The boundary condition a mesh-file marker stands for.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum MarkerKind {
    Wall,
    FarField,
    Symmetry,
}

impl MarkerKind {
    pub fn boundary(self) -> Boundary {
        match self {
            MarkerKind::Wall => Boundary::Wall,
            MarkerKind::FarField => Boundary::FarField,
            MarkerKind::Symmetry => Boundary::Symmetry,
        }
    }
}

/// The built-in O-mesh (chord 1, lengths in chords).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct OMeshSpec {
    pub n_around: usize,
    pub n_radial: usize,
    #[serde(default = "default_far")]
    pub far_field_chords: f64,
    /// Height of the first cell at the wall.
    pub first_spacing_chords: f64,
}

fn default_far() -> f64 {
    50.0
}

impl OMeshSpec {
    /// The mesh about a section (chord 1, mid-chord at the origin).
    pub fn mesh(&self, shape: &AirfoilShape) -> Mesh {
        shape.o_mesh(
            self.n_around,
            self.n_radial,
            self.far_field_chords,
            self.first_spacing_chords / self.far_field_chords,
            1.0,
        )
    }
}

/// A mesh file: Gmsh 4.1 (`.msh`) or SU2 (`.su2`), its markers mapped to boundary conditions;
/// 2-D meshes are extruded to `span`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MeshFileSpec {
    /// Relative to the study file.
    pub path: String,
    pub markers: std::collections::BTreeMap<String, MarkerKind>,
    #[serde(default = "default_span")]
    pub span: f64,
}

fn default_span() -> f64 {
    1.0
}

impl MeshFileSpec {
    /// Reads the mesh, `path` relative to the folder of the study file `study`.
    pub fn read(&self, study: &Path) -> Result<Mesh> {
        let path = study.parent().unwrap_or(Path::new(".")).join(&self.path);
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("cfd.mesh_file.path: cannot read {}", path.display()))?;
        let markers = self
            .markers
            .iter()
            .map(|(name, kind)| (name.clone(), kind.boundary()))
            .collect();
        let mesh = if self.path.ends_with(".su2") {
            gustkit_cfd::readers::read_su2(&text, &markers, self.span)
        } else {
            gustkit_cfd::readers::read_gmsh(&text, &markers, self.span)
        };
        mesh.map_err(|e| anyhow::anyhow!("cfd.mesh_file: {}: {e}", path.display()))
    }
}

/// The LFD model of a typical section: the NACA 64A010 ordinates scaled to `thickness` (fraction
/// of the chord) on the built-in O-mesh.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SectionLfdSpec {
    #[serde(default = "default_thickness")]
    pub thickness: f64,
    pub mesh: OMeshSpec,
    #[serde(default)]
    pub order: OrderSpec,
}

fn default_thickness() -> f64 {
    0.10
}

impl SectionLfdSpec {
    /// Converges the steady flow at `mach` and wraps it as the section's LFD model (chord
    /// `chord_m`; the mesh's unit thickness stands for one metre of span: forces per metre).
    pub fn build(&self, chord_m: f64, mach: f64) -> Result<Lfd, BuildError> {
        let fail = |path: &str, reason: String| BuildError {
            path: path.into(),
            reason,
        };
        let mesh = self
            .mesh
            .mesh(&AirfoilShape::naca64a010().scaled(self.thickness / 0.10));
        mesh.check().map_err(|e| fail("mesh", e.to_string()))?;
        let mut e = Euler::new(mesh, free_stream(mach, 0.0));
        e.order = self.order.order();
        let params = SteadyParams {
            exact_jacobian: true,
            ..SteadyParams::default()
        };
        let (q0, _) = e
            .solve_steady(vec![e.q_inf; e.mesh.n_cells], &params)
            .map_err(|err| fail("", format!("steady state: {err}")))?;
        Ok(Lfd::new(LfdOperator::new(e, q0), chord_m, chord_m, 10.0))
    }
}

/// The built-in wing mesh levels.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum WingMeshLevel {
    /// About 7 k cells: CI tests and quick looks.
    #[default]
    Coarse,
    /// About 57 k cells (2× finer in each direction).
    Medium,
    /// About 460 k cells.
    Fine,
}

impl WingMeshLevel {
    pub fn name(self) -> &'static str {
        match self {
            WingMeshLevel::Coarse => "coarse",
            WingMeshLevel::Medium => "medium",
            WingMeshLevel::Fine => "fine",
        }
    }
}

/// Explicit sizes of the built-in wing mesh (instead of a level).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct WingMeshSizes {
    pub n_around: usize,
    pub n_radial: usize,
    pub n_span: usize,
    pub n_outboard: usize,
    #[serde(default = "default_far_wing")]
    pub far_field_chords: f64,
    pub first_spacing_chords: f64,
    #[serde(default = "default_tip_closure")]
    pub tip_closure: f64,
}

fn default_far_wing() -> f64 {
    15.0
}
fn default_tip_closure() -> f64 {
    0.05
}

/// The preconditioner of the LFD solves (one factorization per reduced frequency for every
/// right-hand side).
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum LfdPreconditionerSpec {
    /// Block ILU(k) of the first-order Jacobian (`ilu_fill`, `ilu_ordering`): robust on 3-D
    /// meshes (the default: on the medium wing mesh at k = 0.98 GMRES converges in 61
    /// iterations with ILU(1) in RCM order, where the exact Jacobian's ILU(0) stalls at a
    /// relative residual of 0.995).
    #[default]
    FirstOrderIlu,
    /// Block ILU(k) of the exact second-order Jacobian: fewer iterations on coarse meshes, can
    /// stall on finer ones (ILU(0) and ILU(1) in RCM order do on the medium wing mesh).
    BlockIlu,
    /// Sparse LU of the exact Jacobian: one GMRES iteration, small meshes only.
    ExactLu,
    /// Sparse LU of the first-order Jacobian.
    FirstOrderLu,
}

impl LfdPreconditionerSpec {
    fn preconditioner(self) -> Preconditioner {
        match self {
            LfdPreconditionerSpec::FirstOrderIlu => Preconditioner::FirstOrderIlu,
            LfdPreconditionerSpec::BlockIlu => Preconditioner::BlockIlu,
            LfdPreconditionerSpec::ExactLu => Preconditioner::Exact,
            LfdPreconditionerSpec::FirstOrderLu => Preconditioner::FirstOrder,
        }
    }
}

/// Length unit of an external mesh file's coordinates.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq, Hash)]
#[serde(rename_all = "snake_case")]
pub enum MeshUnit {
    #[default]
    M,
    Mm,
    In,
    Ft,
}

impl MeshUnit {
    /// Metres per unit.
    pub fn to_m(self) -> f64 {
        match self {
            MeshUnit::M => 1.0,
            MeshUnit::Mm => 1e-3,
            MeshUnit::In => 0.0254,
            MeshUnit::Ft => 0.3048,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            MeshUnit::M => "m",
            MeshUnit::Mm => "mm",
            MeshUnit::In => "in",
            MeshUnit::Ft => "ft",
        }
    }
}

/// An external 3-D wing mesh: `aero.fidelity.lfd.mesh_file`. The wing lies as the built-in
/// mesh's does: x downstream, y up, z spanwise from the root (the symmetry plane z = 0), the
/// root's leading edge at the origin; its wall must match the study's planform.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct WingMeshFile {
    /// SU2 (`.su2`) or Gmsh 4.1 (`.msh`), relative to the study file's folder.
    pub path: String,
    /// Marker (physical group) names and their boundary conditions: every boundary face needs
    /// one; `wall` is the wing.
    pub markers: std::collections::BTreeMap<String, MarkerKind>,
    /// The unit of the file's coordinates (default m).
    #[serde(default)]
    pub length_unit: MeshUnit,
}

/// How far, as a fraction of the local chord or of the span, a wall node may lie outside the
/// structural planform: the tip cap and a rounded leading edge reach a little beyond it.
const PLANFORM_TOLERANCE: f64 = 0.02;

impl WingMeshFile {
    /// Reads the mesh in metres; the error names the file and the reason.
    pub fn read(&self) -> std::result::Result<Mesh, String> {
        let text = std::fs::read_to_string(&self.path)
            .map_err(|e| format!("cannot read {}: {e}", self.path))?;
        let markers = self
            .markers
            .iter()
            .map(|(name, kind)| (name.clone(), kind.boundary()))
            .collect();
        let mut mesh = if self.path.ends_with(".su2") {
            gustkit_cfd::readers::read_su2(&text, &markers, 1.0)
        } else if self.path.ends_with(".msh") {
            gustkit_cfd::readers::read_gmsh(&text, &markers, 1.0)
        } else {
            return Err(format!(
                "{}: the name must end in .su2 or .msh (the format)",
                self.path
            ));
        }
        .map_err(|e| format!("{}: {e}", self.path))?;
        // a 2-D file comes back extruded to one unit: z = 0 and 1 only
        let su2_2d = self.path.ends_with(".su2")
            && text
                .lines()
                .find_map(|l| l.trim().strip_prefix("NDIME"))
                .is_some_and(|rest| rest.trim_start_matches([' ', '=']).trim() == "2");
        if su2_2d || mesh.nodes.iter().all(|p| p[2] == 0.0 || p[2] == 1.0) {
            return Err(format!(
                "{}: a 2-D mesh; a wing study needs a 3-D mesh of the wing",
                self.path
            ));
        }
        let scale = self.length_unit.to_m();
        for p in mesh.nodes.iter_mut() {
            *p = p.map(|v| v * scale);
        }
        Ok(mesh)
    }

    /// A hash of the file's bytes, for the steady state's cache key.
    fn content_hash(&self) -> u64 {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        std::fs::read(&self.path).unwrap_or_default().hash(&mut h);
        self.length_unit.hash(&mut h);
        h.finish()
    }
}

/// The wall nodes' (ξ, η) on the planform, or why the wall does not match it: a node outside
/// the planform by more than [`PLANFORM_TOLERANCE`], or a wall that does not reach the root, the
/// tip, the leading or the trailing edge. Lengths in the errors are in `unit`.
pub fn planform_coordinates(
    planform: &crate::wing::Planform,
    wall: &[[f64; 3]],
    unit: MeshUnit,
) -> std::result::Result<Vec<[f64; 2]>, String> {
    let u = unit.to_m();
    let mut out = Vec::with_capacity(wall.len());
    let (mut eta_range, mut xi_range) = ([f64::MAX, f64::MIN], [f64::MAX, f64::MIN]);
    for (i, x) in wall.iter().enumerate() {
        // the CFD frame: x downstream, y up, z along the span
        let eta = x[2] / planform.span;
        let le = planform.point(0.0, eta.clamp(0.0, 1.0))[0];
        let chord = planform.chord(eta.clamp(0.0, 1.0));
        let xi = (x[0] - le) / chord;
        let outside = (-xi).max(xi - 1.0).max(-eta).max(eta - 1.0);
        if outside > PLANFORM_TOLERANCE {
            return Err(format!(
                "the wing surface does not match the structural planform: wall node {i} at (x, y, z) = ({:.4}, {:.4}, {:.4}) {} (x downstream, y up, z spanwise) lies at chord fraction {xi:.3} and span fraction {eta:.3} of the planform (span {:.4} {}, root chord {:.4} {}), beyond the {} % tolerance",
                x[0] / u,
                x[1] / u,
                x[2] / u,
                unit.name(),
                planform.span / u,
                unit.name(),
                planform.root_chord / u,
                unit.name(),
                PLANFORM_TOLERANCE * 100.0
            ));
        }
        eta_range = [eta_range[0].min(eta), eta_range[1].max(eta)];
        xi_range = [xi_range[0].min(xi), xi_range[1].max(xi)];
        out.push([xi.clamp(0.0, 1.0), eta.clamp(0.0, 1.0)]);
    }
    if wall.is_empty()
        || eta_range[0] > PLANFORM_TOLERANCE
        || eta_range[1] < 1.0 - PLANFORM_TOLERANCE
        || xi_range[0] > PLANFORM_TOLERANCE
        || xi_range[1] < 1.0 - PLANFORM_TOLERANCE
    {
        return Err(format!(
            "the wing surface does not match the structural planform: its wall covers span fractions {:.3} to {:.3} and chord fractions {:.3} to {:.3} of the planform (span {:.4} {}), where 0 to 1 are needed",
            eta_range[0],
            eta_range[1],
            xi_range[0],
            xi_range[1],
            planform.span / u,
            unit.name()
        ));
    }
    Ok(out)
}

/// The elimination order of the block ILU preconditioners.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum IluOrderingSpec {
    /// Reverse Cuthill–McKee of the Jacobian's block graph.
    #[default]
    Rcm,
    /// The mesh's own cell order.
    Natural,
}

/// ILU(1): on the medium wing mesh at k = 0.98 one right-hand side takes 61 GMRES iterations
/// and 6.6 s against 130 and 11.4 s with ILU(0) in the mesh's order (105 and 7.9 s in RCM
/// order; ILU(2) 50 and 7.7 s, ILU(3) 45 and 8.8 s: more fill costs more than it saves).
fn default_ilu_fill() -> usize {
    1
}

/// The LFD fidelity of a wing study: `aero.fidelity: {"lfd": {...}}`. Every field has a default,
/// so `{"lfd": {}}` is the coarse built-in mesh at second order with block ILU(1) of the
/// first-order Jacobian in reverse Cuthill–McKee order.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct LfdWingSpec {
    /// The built-in mesh level: "coarse" (default), "medium" or "fine".
    #[serde(default)]
    pub mesh: WingMeshLevel,
    /// Explicit mesh sizes instead of the level.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh_sizes: Option<WingMeshSizes>,
    /// An external 3-D mesh (SU2 or Gmsh) instead of the built-in one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh_file: Option<WingMeshFile>,
    #[serde(default)]
    pub order: OrderSpec,
    #[serde(default)]
    pub limiter: LimiterSpec,
    #[serde(default)]
    pub preconditioner: LfdPreconditionerSpec,
    /// Fill level k of the block ILU(k) preconditioners (0 to 3; ignored by the LU ones).
    #[serde(default = "default_ilu_fill")]
    pub ilu_fill: usize,
    /// The ILU's elimination order: "rcm" (reverse Cuthill–McKee) or "natural" (the mesh's).
    #[serde(default)]
    pub ilu_ordering: IluOrderingSpec,
    /// GMRES stops at ‖A q̂ + b‖ ≤ tolerance ‖b‖.
    #[serde(default = "default_gmres_tolerance")]
    pub gmres_tolerance: f64,
    #[serde(default = "default_gmres_restart")]
    pub gmres_restart: usize,
    #[serde(default = "default_gmres_max")]
    pub gmres_max_iterations: usize,
    /// Mode shapes reach the volume mesh by inverse-distance weighting blended to zero at this
    /// many root chords from the wall.
    #[serde(default = "default_deform_radius")]
    pub deform_radius_chords: f64,
    /// The most memory the model may take, GB (refused before anything is allocated).
    #[serde(default = "default_memory_limit")]
    pub memory_limit_gb: f64,
    /// The most Newton iterations of the steady solve (transonic cases on finer meshes need
    /// more than the default 60).
    #[serde(default = "default_steady_iterations")]
    pub steady_max_iterations: usize,
    /// `gustkit run` writes the LFD amplitudes at this reduced frequency (one of
    /// `aero.reduced_frequencies`) of every mode and the gust at the initial design for
    /// ParaView: `lfd_mode<i>_k<k>.vtk`, `lfd_gust_k<k>.vtk` (pressure, C_p and velocity, real
    /// and imaginary parts).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub amplitude_fields_k: Option<f64>,
}

fn default_gmres_tolerance() -> f64 {
    1e-8
}
fn default_gmres_restart() -> usize {
    80
}
fn default_gmres_max() -> usize {
    800
}
fn default_deform_radius() -> f64 {
    5.0
}
/// The steady state of `e` from the guess `q`, the pseudo-time step started where switched
/// evolution relaxation would have taken it by the time the residual fell from the free
/// stream's to the guess's; `None` if it does not converge.
fn steady_from_guess(
    e: &Euler,
    q: Vec<gustkit_cfd::residual::State<f64>>,
    params: &SteadyParams,
) -> Option<(
    Vec<gustkit_cfd::residual::State<f64>>,
    gustkit_cfd::steady::SteadyInfo,
)> {
    let norm = |q: &[gustkit_cfd::residual::State<f64>]| -> f64 {
        e.residual(q)
            .iter()
            .flatten()
            .map(|v| v * v)
            .sum::<f64>()
            .sqrt()
    };
    let ratio = norm(&vec![e.q_inf; e.mesh.n_cells]) / norm(&q);
    let warm_params = SteadyParams {
        cfl0: (params.cfl0 * ratio).clamp(params.cfl0, params.cfl_max),
        ..params.clone()
    };
    e.solve_steady(q, &warm_params).ok()
}

/// The build error of a steady solve that failed: one that ran out of Newton iterations points
/// at the key that raises them, with how far the residual fell (the whole history follows).
fn steady_failure(err: gustkit_cfd::steady::SteadyError, limit: usize) -> BuildError {
    match &err {
        gustkit_cfd::steady::SteadyError::NoConvergence { history, .. } => {
            let first = history.first().copied().unwrap_or(f64::NAN);
            let last = history.last().copied().unwrap_or(f64::NAN);
            BuildError {
                path: "steady_max_iterations".into(),
                reason: format!(
                    "the steady state did not converge in {limit} Newton iterations (the residual fell from {first:.3e} to {last:.3e}, {:.1} decades): raise steady_max_iterations (transonic cases on the medium mesh need about 250); {err}",
                    (first / last).log10()
                ),
            }
        }
        _ => BuildError {
            path: String::new(),
            reason: format!("steady state did not converge: {err}"),
        },
    }
}

fn default_steady_iterations() -> usize {
    60
}
fn default_memory_limit() -> f64 {
    12.0
}

/// Bytes per cell of the LFD wing model on `threads` threads (each holds a frequency's solver
/// state), from its parts: the mesh, geometry,
/// states and deformation (≈ 8 kB), the exact second-order Jacobian (≈ 12 kB), per concurrent
/// frequency its complex block ILU(0) (≈ 24 kB) and the fill blocks of ILU(k), and per
/// concurrent right-hand side the GMRES
/// basis (restart + 1 complex vectors of 5 unknowns), and the forward solutions of one GAF table
/// kept for the reverse sweep (≈ 7 kB: 11 k × 7 columns × 80 B). 88 kB a cell at restart 80;
/// measured on the medium wing mesh: 3.94 GB peak for 57 344 cells (69 kB a cell, before the
/// solutions were kept).
fn bytes_per_cell(restart: usize, ilu_fill: usize, threads: usize) -> f64 {
    let threads = threads.max(1) as f64;
    // the fill blocks beyond ILU(0)'s, per cell (measured on the medium wing mesh: 6.9, 12.7,
    // 22.1 and 33.2 blocks a row for ILU(0) to ILU(3)), 400 B a complex block and its column
    let fill_blocks = [0.0, 5.8, 15.2, 26.3][ilu_fill.min(3)];
    8e3 + 12e3 + 7e3 + threads * (24e3 + fill_blocks * 408.0 + (restart as f64 + 1.0) * 5.0 * 16.0)
}

impl LfdWingSpec {
    /// The wing mesh sizes of the spec.
    pub fn mesh_spec(&self) -> WingMeshSpec {
        match &self.mesh_sizes {
            Some(m) => WingMeshSpec {
                n_around: m.n_around,
                n_radial: m.n_radial,
                n_span: m.n_span,
                n_outboard: m.n_outboard,
                far_field_chords: m.far_field_chords,
                first_spacing_chords: m.first_spacing_chords,
                tip_closure: m.tip_closure,
            },
            None => WingMeshSpec::level(self.mesh.name()).expect("built-in level"),
        }
    }

    /// The converged steady state on the built-in mesh `spec` (the flight condition, order and
    /// limiter of the study), started from the state of the mesh with half its cells in each
    /// direction where there is one, else from the free stream; `None` if it does not converge
    /// (the caller then starts its own mesh from the free stream).
    fn sequenced_steady(
        &self,
        wing: &WingContext,
        spec: &WingMeshSpec,
        params: &SteadyParams,
    ) -> Option<Vec<gustkit_cfd::residual::State<f64>>> {
        let wm = WingMesh::new(
            wing.planform.to_array(),
            &|x| wing.airfoil.half_thickness(x),
            spec,
        );
        let mut e = Euler::new(wm.mesh, free_stream(wing.flight.mach, 0.0));
        e.order = self.order.order();
        e.limiter = self.limiter.limiter();
        let free_stream = vec![e.q_inf; e.mesh.n_cells];
        let guess = spec.halved().and_then(|coarse| {
            let q = self.sequenced_steady(wing, &coarse, params)?;
            Some(spec.prolong(&coarse, &q))
        });
        guess
            .and_then(|q| steady_from_guess(&e, q, params))
            .or_else(|| e.solve_steady(free_stream, params).ok())
            .map(|(q, _)| q)
    }

    /// The memory the model would take, GB.
    /// (on the threads of the pool it will run on: rayon's current pool).
    pub fn memory_estimate_gb(&self) -> f64 {
        self.mesh_spec().n_cells() as f64
            * bytes_per_cell(
                self.gmres_restart,
                self.ilu_fill,
                rayon::current_num_threads(),
            )
            / 1e9
    }

    fn params(&self) -> LfdParams {
        LfdParams {
            tolerance: self.gmres_tolerance,
            restart: self.gmres_restart,
            max_iterations: self.gmres_max_iterations,
            ilu: IluParams {
                fill: self.ilu_fill,
                ordering: match self.ilu_ordering {
                    IluOrderingSpec::Rcm => IluOrdering::ReverseCuthillMckee,
                    IluOrderingSpec::Natural => IluOrdering::Natural,
                },
            },
        }
    }
}

impl LfdWingSpec {
    /// The file in `dir` that holds the steady state of this mesh, wing and flight condition:
    /// named by a hash of everything the state depends on, so a changed input misses it.
    pub fn steady_file(&self, wing: &WingContext, dir: &Path) -> PathBuf {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        format!(
            "{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}",
            self.mesh_file.as_ref().map(|f| f.content_hash()),
            self.mesh_spec(),
            wing.planform.to_array().map(f64::to_bits),
            wing.airfoil,
            wing.flight.mach.to_bits(),
            self.order,
            self.limiter
        )
        .hash(&mut h);
        dir.join(format!("{STEADY_PREFIX}{:016x}.bin", h.finish()))
    }
}

/// A state read from `file` if it is one of this mesh (length) and physical (finite, positive
/// density); `None` for anything else.
fn read_state(e: &Euler, file: &Path) -> Option<Vec<gustkit_cfd::residual::State<f64>>> {
    let bytes = std::fs::read(file).ok()?;
    let n = e.mesh.n_cells;
    let nvar = gustkit_cfd::gas::NVAR;
    if bytes.len() != 8 * nvar * n {
        return None;
    }
    let vals: Vec<f64> = bytes
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")))
        .collect();
    let q: Vec<gustkit_cfd::residual::State<f64>> = vals
        .chunks_exact(nvar)
        .map(|c| std::array::from_fn(|k| c[k]))
        .collect();
    if q.iter().flatten().any(|v| !v.is_finite()) || q.iter().any(|s| !(s[0] > 0.0)) {
        return None;
    }
    Some(q)
}

/// A steady state read from `file` if it is one of this mesh, physical, and converged
/// (‖R‖ within 1e-12 of the flux scale, well above round-off and far below any truncation
/// error); anything else is ignored and the state solved again.
fn converged_state(e: &Euler, file: &Path) -> Option<Vec<gustkit_cfd::residual::State<f64>>> {
    let q = read_state(e, file)?;
    let r: f64 = e
        .residual(&q)
        .iter()
        .flatten()
        .map(|v| v * v)
        .sum::<f64>()
        .sqrt();
    (r <= 1e-12 * e.flux_scale(&q)).then_some(q)
}

/// The steady state of the folder's previous wing (another design of an optimization), when one
/// of this mesh's size is there: the initial guess of the next steady solve, which converges to
/// the same state as from the free stream in fewer Newton iterations.
fn previous_state(
    e: &Euler,
    cache: Option<&Path>,
) -> Option<Vec<gustkit_cfd::residual::State<f64>>> {
    cache.and_then(Path::parent).and_then(|dir| {
        std::fs::read_dir(dir).ok()?.flatten().find_map(|entry| {
            let name = entry.file_name();
            let name = name.to_string_lossy();
            let ours = Some(entry.path()) == cache.map(Path::to_path_buf);
            (!ours && name.starts_with(STEADY_PREFIX) && name.ends_with(".bin"))
                .then(|| read_state(e, &entry.path()))
                .flatten()
        })
    })
}

/// Writes a steady state to `file` atomically (little-endian f64, cell by cell), and removes the
/// folder's other steady states (a run folder keeps the one of its latest wing).
fn save_state(file: &Path, q: &[gustkit_cfd::residual::State<f64>]) -> std::io::Result<()> {
    let bytes: Vec<u8> = q.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    crate::atomic::write(file, &bytes)?;
    if let Some(dir) = file.parent() {
        for entry in std::fs::read_dir(dir)?.flatten() {
            let path = entry.path();
            let name = entry.file_name();
            let name = name.to_string_lossy();
            if path != file && name.starts_with(STEADY_PREFIX) && name.ends_with(".bin") {
                let _ = std::fs::remove_file(path);
            }
        }
    }
    Ok(())
}

/// Span fractions of the C_p sections: root, mid-span and tip (inboard of the tip closure).
pub const CP_SECTIONS: [f64; 3] = [0.0, 0.5, 0.9];

/// The stem of the C_p section CSV written beside the steady state (and of its figure).
pub const CP_SECTIONS_STEM: &str = "steady_cp_sections";

/// C_p of the wall cells of the chordwise sections at [`CP_SECTIONS`] (each the strip whose
/// middle lies nearest): (η of the strip's middle, [(wall cell, C_p)] around the contour).
pub fn cp_sections(
    mesh: &WingMesh,
    q: &[gustkit_cfd::residual::State<f64>],
    mach: f64,
) -> Vec<(f64, Vec<(SectionCell, f64)>)> {
    CP_SECTIONS
        .iter()
        .map(|&eta| {
            let (eta_mid, cells) = mesh.wall_section(eta);
            let cp = cells
                .iter()
                .map(|&c| (c, gustkit_cfd::gas::pressure_coefficient(&q[c.cell], mach)))
                .collect();
            (eta_mid, cp)
        })
        .collect()
}

/// Writes [`cp_sections`] into `dir` as `steady_cp_sections.csv` (eta, x_c, side, cp), which the
/// run's report draws (upper and lower surface against x/c, one panel a section).
fn write_cp_sections(
    mesh: &WingMesh,
    q: &[gustkit_cfd::residual::State<f64>],
    mach: f64,
    dir: &Path,
) -> std::io::Result<()> {
    let mut csv = String::from("eta,x_c,side,cp\n");
    for (eta, cells) in cp_sections(mesh, q, mach) {
        for (c, cp) in cells {
            let side = if c.upper { "upper" } else { "lower" };
            csv.push_str(&format!("{eta:.6},{:.6},{side},{cp:.8e}\n", c.x_c));
        }
    }
    crate::atomic::write(&dir.join(format!("{CP_SECTIONS_STEM}.csv")), csv.as_bytes())
}

/// File-name prefix of the cached steady states (`steady_lfd_<hash>.bin`).
pub const STEADY_PREFIX: &str = "steady_lfd_";

/// The VTK file of the latest steady state beside it (its prefix carries it to the next run).
pub const STEADY_VTK: &str = "steady_lfd_flow.vtk";

impl WingBuilder for LfdWingSpec {
    fn name(&self) -> &'static str {
        "lfd"
    }

    fn check_mach(&self, mach: f64) -> Result<(), String> {
        if !(mach > 0.0 && mach < 1.0) {
            return Err(format!(
                "the LFD needs a subsonic free stream, 0 < M < 1 (got {})",
                crate::units::show(mach)
            ));
        }
        Ok(())
    }

    fn capabilities(&self) -> Capabilities {
        // the mode shapes by adjoint LFD solves, the planform through the mesh tangents
        // (not for an external mesh: its nodes do not move with the planform)
        Capabilities {
            reverse: true,
            reverse_planform: self.mesh_file.is_none(),
        }
    }

    fn validate(&self, wing: &WingContext) -> Result<(), BuildError> {
        let fail = |path: &str, reason: String| BuildError {
            path: path.into(),
            reason,
        };
        let mesh = self.mesh_spec();
        mesh.validate().map_err(|(field, reason)| {
            let path = if self.mesh_sizes.is_some() {
                format!("mesh_sizes.{field}")
            } else {
                "mesh".into()
            };
            fail(&path, reason)
        })?;
        if let Some(file) = &self.mesh_file {
            if self.mesh_sizes.is_some() {
                return Err(fail(
                    "mesh_file",
                    "give mesh_file or mesh_sizes, not both".into(),
                ));
            }
            if let Err(e) = std::fs::metadata(&file.path) {
                return Err(fail(
                    "mesh_file.path",
                    format!("cannot read {}: {e}", file.path),
                ));
            }
        }
        self.params()
            .ilu
            .validate()
            .map_err(|r| fail("ilu_fill", r))?;
        self.params()
            .validate()
            .map_err(|r| fail("gmres_tolerance", r))?;
        if self.steady_max_iterations == 0 {
            return Err(fail(
                "steady_max_iterations",
                "must be at least 1 (got 0)".into(),
            ));
        }
        if !(self.deform_radius_chords > 0.0 && self.deform_radius_chords.is_finite()) {
            return Err(fail(
                "deform_radius_chords",
                format!("must be positive (got {})", self.deform_radius_chords),
            ));
        }
        self.check_mach(wing.flight.mach)
            .map_err(|reason| fail("", format!("flight.mach: {reason}")))?;
        let gb = self.memory_estimate_gb();
        // (an external mesh's size is known once it is read: checked by `build`)
        if self.mesh_file.is_none() && !(gb <= self.memory_limit_gb) {
            return Err(fail(
                if self.mesh_sizes.is_some() {
                    "mesh_sizes"
                } else {
                    "mesh"
                },
                format!(
                    "the {} mesh ({} cells) needs about {gb:.1} GB, above memory_limit_gb = {} (this machine has 24 GB shared with other jobs): choose a coarser mesh or raise the limit",
                    if self.mesh_sizes.is_some() { "given" } else { self.mesh.name() },
                    mesh.n_cells(),
                    self.memory_limit_gb
                ),
            ));
        }
        Ok(())
    }

    fn validate_gradients(&self, wing: &WingContext) -> Result<(), BuildError> {
        self.validate(wing)?;
        let cells = self.mesh_spec().n_cells();
        let gb = self.memory_estimate_gb()
            + gustkit_cfd::adjoint::LfdReverse::estimate_bytes(cells) as f64 / 1e9;
        if self.mesh_file.is_none() && !(gb <= self.memory_limit_gb) {
            return Err(BuildError {
                path: if self.mesh_sizes.is_some() {
                    "mesh_sizes".into()
                } else {
                    "mesh".into()
                },
                reason: format!(
                    "gradients on the {} mesh ({cells} cells) need about {gb:.1} GB with the reverse mode's tapes, above memory_limit_gb = {}: choose a coarser mesh or raise the limit",
                    if self.mesh_sizes.is_some() { "given" } else { self.mesh.name() },
                    self.memory_limit_gb
                ),
            });
        }
        Ok(())
    }

    fn build(&self, wing: &WingContext) -> Result<WingFidelity, BuildError> {
        self.validate(wing)?;
        // the steady state is reused from `wing.cache_dir` when the mesh, the section, the
        // planform, the Mach number and the discretization are those it was solved for
        let fail = |reason: String| BuildError {
            path: String::new(),
            reason,
        };
        let p = wing.planform.to_array();
        let file_fail = |reason: String| BuildError {
            path: "mesh_file.path".into(),
            reason,
        };
        // the built-in mesh, or the external one (no planform tangents, no C_p sections)
        let (volume, built_in) = match &self.mesh_file {
            Some(file) => {
                let m = file.read().map_err(file_fail)?;
                m.check()
                    .map_err(|e| file_fail(format!("{}: invalid mesh: {e}", file.path)))?;
                let gb = m.n_cells as f64
                    * bytes_per_cell(
                        self.gmres_restart,
                        self.ilu_fill,
                        rayon::current_num_threads(),
                    )
                    / 1e9;
                if !(gb <= self.memory_limit_gb) {
                    return Err(file_fail(format!(
                        "{} ({} cells) needs about {gb:.1} GB, above memory_limit_gb = {}: choose a coarser mesh or raise the limit",
                        file.path, m.n_cells, self.memory_limit_gb
                    )));
                }
                (m, None)
            }
            None => {
                let wm = WingMesh::new(p, &|x| wing.airfoil.half_thickness(x), &self.mesh_spec());
                wm.mesh
                    .check()
                    .map_err(|e| fail(format!("the built-in wing mesh is invalid: {e}")))?;
                (wm.mesh.clone(), Some(wm))
            }
        };
        let mut e = Euler::new(volume.clone(), free_stream(wing.flight.mach, 0.0));
        e.order = self.order.order();
        e.limiter = self.limiter.limiter();
        // the LFD's ILU settings serve the Newton steps too (medium mesh: 65 s with ILU(0) in
        // the mesh's order, 30 s with ILU(1) in RCM order, 12 Newton iterations either way)
        let params = SteadyParams {
            linear_solver: NewtonLinearSolver::BlockIlu,
            ilu: self.params().ilu,
            max_iterations: self.steady_max_iterations,
            ..SteadyParams::default()
        };
        let cache = wing.cache_dir.map(|d| self.steady_file(wing, d));
        let q0 = match cache.as_deref().and_then(|f| converged_state(&e, f)) {
            Some(q) => q,
            None => {
                let free_stream = || vec![e.q_inf; e.mesh.n_cells];
                let from_guess = |q| steady_from_guess(&e, q, &params);
                // from the previous design's state; else, on the built-in mesh, from the steady
                // state of the mesh with half the cells in each direction (itself started the
                // same way): mesh sequencing, which converges transonic cases on the finer levels
                // in a few Newton iterations where the free-stream start needs hundreds; from the
                // free stream should those fail
                let warm = previous_state(&e, cache.as_deref())
                    .and_then(from_guess)
                    .or_else(|| {
                        let spec = self.mesh_spec();
                        let coarse = spec.halved().filter(|_| built_in.is_some())?;
                        let q = self.sequenced_steady(wing, &coarse, &params)?;
                        from_guess(spec.prolong(&coarse, &q))
                    });
                let (q, _) = match warm {
                    Some(solved) => solved,
                    None => e
                        .solve_steady(free_stream(), &params)
                        .map_err(|err| steady_failure(err, self.steady_max_iterations))?,
                };
                if let Some(f) = &cache {
                    // a cache that cannot be written costs the next run a steady solve, no more
                    let _ = save_state(f, &q);
                    // and the field for ParaView beside it (ρ, p, C_p, Mach, velocity per cell)
                    let vtk = gustkit_cfd::vtk::flow_vtk(
                        &volume,
                        &q,
                        wing.flight.mach,
                        &format!(
                            "gustkit: steady Euler about the wing at M = {}",
                            wing.flight.mach
                        ),
                    );
                    let _ = crate::atomic::write(&f.with_file_name(STEADY_VTK), vtk.as_bytes());
                    // and C_p at the root, mid-span and tip sections (the report draws them)
                    if let (Some(dir), Some(mesh)) = (f.parent(), &built_in) {
                        let _ = write_cp_sections(mesh, &q, wing.flight.mach, dir);
                    }
                }
                q
            }
        };
        let mut op = LfdOperator::with_preconditioner(e, q0, self.preconditioner.preconditioner());
        op.params = self.params();
        let model = Lfd::new(
            op,
            1.0,
            1.0,
            self.deform_radius_chords * wing.planform.root_chord,
        );
        let Some(mesh) = built_in else {
            // an external mesh: its wall nodes placed on the planform, or why they do not fit
            let unit = self
                .mesh_file
                .as_ref()
                .map_or(MeshUnit::M, |f| f.length_unit);
            let wall: Vec<[f64; 3]> = model
                .wall_nodes()
                .iter()
                .map(|&n| volume.nodes[n])
                .collect();
            let points = planform_coordinates(wing.planform, &wall, unit).map_err(|r| {
                file_fail(format!(
                    "{}: {r}",
                    self.mesh_file.as_ref().map_or("", |f| f.path.as_str())
                ))
            })?;
            return Ok(WingFidelity {
                model: Box::new(model),
                binding: SurfaceBinding {
                    points,
                    geometry_jacobian: Vec::new(),
                },
            });
        };
        let points = model
            .wall_nodes()
            .iter()
            .map(|&n| mesh.parametric(n))
            .collect();
        // the planform variables move the mesh (and the deformation radius, a multiple of the
        // root chord): their tangents, for the reverse mode's geometry gradient
        let mut model = model;
        let pd: [Dual<N_PLANFORM>; N_PLANFORM] = std::array::from_fn(|k| Dual::var(p[k], k));
        let xd = mesh.nodes_at(pd);
        model.tangents = (0..N_PLANFORM)
            .map(|k| MeshTangent {
                name: PLANFORM_NAMES[k].to_string(),
                nodes: xd.iter().map(|x| x.map(|v| v.d[k])).collect(),
                radius: if k == 2 {
                    self.deform_radius_chords
                } else {
                    0.0
                },
            })
            .collect();
        let geometry_jacobian = (0..N_PLANFORM)
            .map(|k| std::array::from_fn(|j| if j == k { 1.0 } else { 0.0 }))
            .collect();
        Ok(WingFidelity {
            model: Box::new(model),
            binding: SurfaceBinding {
                points,
                geometry_jacobian,
            },
        })
    }
}
