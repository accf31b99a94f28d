//! The DLM's builder: a CAERO1-like lifting surface on the wing planform (root LE at the origin),
//! boxes laid on the plate's own (ξ, η) parametrization, and the derivatives of the surface's
//! eight geometry parameters with respect to the planform variables (dual numbers through the
//! planform map).

use super::registry::{
    BuildError, Capabilities, SurfaceBinding, WingBuilder, WingContext, WingFidelity,
};
use crate::wing::{planform_point, Planform, N_PLANFORM};
use gustkit_core::scalar::Dual;
use gustkit_dlm::{Dlm, SurfaceSpec};
use serde::{Deserialize, Serialize};

/// Box layout of the DLM on the planform.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DlmSpec {
    pub n_chord: usize,
    pub n_span: usize,
    #[serde(default)]
    pub chord_spacing: gustkit_dlm::Spacing,
    #[serde(default)]
    pub span_spacing: gustkit_dlm::Spacing,
    /// `"symmetric"` (a wall-mounted half wing, the default), `"antisymmetric"` or `"none"`.
    #[serde(default = "default_symmetry")]
    pub symmetry: gustkit_dlm::Symmetry,
}

fn default_symmetry() -> gustkit_dlm::Symmetry {
    gustkit_dlm::Symmetry::Symmetric
}

/// The DLM lifting surface of a planform (a CAERO1 from root LE (0, 0, 0) to tip LE) and the
/// derivatives of its 8 parameters with respect to the planform variables.
pub fn dlm_surface(planform: &Planform, spec: &DlmSpec) -> (SurfaceSpec, Vec<[f64; N_PLANFORM]>) {
    let p = planform.to_array();
    let pd: [Dual<N_PLANFORM>; N_PLANFORM] = std::array::from_fn(|k| Dual::var(p[k], k));
    let tip = planform_point(pd, 0.0, 1.0);
    let zero = [0.0; N_PLANFORM];
    let unit = |k: usize| {
        let mut v = zero;
        v[k] = 1.0;
        v
    };
    let jac = vec![
        zero,     // p1.x
        zero,     // p1.y
        zero,     // p1.z
        unit(2),  // c1 = root chord
        tip[0].d, // p4.x = tip LE x
        tip[1].d, // p4.y = span
        zero,     // p4.z
        unit(3),  // c4 = tip chord
    ];
    let surface = SurfaceSpec {
        name: "wing".into(),
        p1: [0.0, 0.0, 0.0],
        c1: planform.root_chord,
        p4: [tip[0].v, tip[1].v, 0.0],
        c4: planform.tip_chord,
        n_chord: spec.n_chord,
        n_span: spec.n_span,
        chord_spacing: spec.chord_spacing,
        span_spacing: spec.span_spacing,
    };
    (surface, jac)
}

impl DlmSpec {
    /// The lattice on a planform (boxes only; influence matrices come with the first GAFs).
    pub fn lattice(&self, planform: &Planform) -> Result<Dlm, BuildError> {
        let (surface, _) = dlm_surface(planform, self);
        Dlm::new(vec![surface], self.symmetry).map_err(|e| BuildError {
            path: String::new(),
            reason: e.to_string(),
        })
    }
}

impl WingBuilder for DlmSpec {
    fn name(&self) -> &'static str {
        "dlm"
    }

    fn capabilities(&self) -> Capabilities {
        Capabilities {
            reverse: true,
            reverse_planform: true,
        }
    }

    fn validate(&self, wing: &WingContext) -> Result<(), BuildError> {
        let (surface, _) = dlm_surface(wing.planform, self);
        surface.validate(0).map_err(|e| BuildError {
            path: String::new(),
            reason: e.to_string(),
        })
    }

    fn build(&self, wing: &WingContext) -> Result<WingFidelity, BuildError> {
        let planform = wing.planform;
        let (_, jac) = dlm_surface(planform, self);
        let mut dlm = self.lattice(planform)?;
        // only the parameters the planform moves need reverse-mode work
        let active: Vec<usize> = (0..jac.len())
            .filter(|&i| jac[i].iter().any(|v| *v != 0.0))
            .collect();
        dlm.set_active_geometry(0, &active);
        let points = dlm
            .parametric_points()
            .into_iter()
            .map(|(_, p)| p)
            .collect();
        Ok(WingFidelity {
            model: Box::new(dlm),
            binding: SurfaceBinding {
                points,
                geometry_jacobian: jac,
            },
        })
    }
}
