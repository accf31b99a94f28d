//! The CFD fidelity's closed sets of settings as serde enums (scheme order, limiter, airfoil,
//! boundary markers, built-in wing mesh levels and sizes, preconditioner, ILU ordering): a typo
//! is refused with its JSON path at load.

use super::*;

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

pub(super) fn default_far_wing() -> f64 {
    15.0
}

pub(super) fn default_tip_closure() -> f64 {
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
    pub(super) fn preconditioner(self) -> Preconditioner {
        match self {
            LfdPreconditionerSpec::FirstOrderIlu => Preconditioner::FirstOrderIlu,
            LfdPreconditionerSpec::BlockIlu => Preconditioner::BlockIlu,
            LfdPreconditionerSpec::ExactLu => Preconditioner::Exact,
            LfdPreconditionerSpec::FirstOrderLu => Preconditioner::FirstOrder,
        }
    }
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

/// Where the forward LFD solutions wait for the reverse sweep.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum ForwardSolutionsSpec {
    /// Scratch files in the system's temporary folder.
    #[default]
    Disk,
    /// The process's memory.
    Memory,
}

/// The precision of the block ILU's stored factors.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum IluPrecisionSpec {
    /// f32 (complex f32) factors, half the memory.
    #[default]
    Single,
    /// f64 (complex f64) factors.
    Double,
}

/// ILU(1): on the medium wing mesh at k = 0.98 one right-hand side takes 61 GMRES iterations
/// and 6.6 s against 130 and 11.4 s with ILU(0) in the mesh's order (105 and 7.9 s in RCM
/// order; ILU(2) 50 and 7.7 s, ILU(3) 45 and 8.8 s: more fill costs more than it saves).
pub(super) fn default_ilu_fill() -> usize {
    1
}
