//! Where the CFD mesh comes from: the built-in airfoil O-mesh, a 2-D mesh file with its
//! boundary markers, or an external 3-D wing mesh (Gmsh or SU2) matched to the planform.

use super::*;

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

pub(super) fn default_far() -> f64 {
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

pub(super) fn default_span() -> f64 {
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
pub(super) const PLANFORM_TOLERANCE: f64 = 0.02;

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
    pub(super) fn content_hash(&self) -> u64 {
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
