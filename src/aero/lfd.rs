//! The CFD fidelity's settings and builders: the scheme (order, limiter), the built-in airfoil
//! O-mesh and mesh files with their boundary markers, and the LFD model of a 2-D section (steady
//! Euler flow converged on the built-in mesh about a scaled NACA 64A0xx). Every closed set of
//! strings in a CFD spec is a serde enum, so a typo is refused with its JSON path at load.

use super::registry::BuildError;
use anyhow::{Context, Result};
use gustkit_cfd::airfoil::AirfoilShape;
use gustkit_cfd::gafs::Lfd;
use gustkit_cfd::lfd::LfdOperator;
use gustkit_cfd::mesh::{Boundary, Mesh};
use gustkit_cfd::residual::{free_stream, Euler, Limiter, Order};
use gustkit_cfd::steady::SteadyParams;
use serde::{Deserialize, Serialize};
use std::path::Path;

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
