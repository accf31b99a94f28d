//! The LFD model of a 2-D section (the typical-section study): steady Euler flow converged on the
//! built-in O-mesh about a scaled NACA 64A0xx.

use super::*;

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

pub(super) fn default_thickness() -> f64 {
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
