//! The one place where a study's `FidelitySpec` becomes a `Box<dyn Aerodynamics>`, and the GAF
//! driver that couples it to the plate: modes → transfer → GAFs, and the reverse sweep back to the
//! nodal mode shapes and the planform variables.

use super::schema::FidelitySpec;
use super::{Study, StudyError};
use crate::structure::{Modes, PlateModel};
use crate::transfer::ModeTransfer;
use crate::wing::{planform_point, Planform, N_PLANFORM};
use gustkit_core::scalar::Dual;
use gustkit_core::{AeroError, Aerodynamics, FlightCondition, GafTable, ModalSurface};
use gustkit_dlm::{Dlm, SurfaceSpec};

/// Seeds on the nodal mode shapes (one vector a mode) and the direct planform gradient.
pub type ShapeSeeds = (Vec<Vec<f64>>, [f64; N_PLANFORM]);

/// An aerodynamic model bound to a planform and a plate.
pub struct AeroModel {
    pub fidelity: Box<dyn Aerodynamics>,
    pub transfer: ModeTransfer,
    pub flight: FlightCondition,
    pub k: Vec<f64>,
    /// ∂(geometry parameter)/∂(planform variable) of the fidelity's geometry parameters.
    geometry_jacobian: Vec<[f64; N_PLANFORM]>,
}

/// The DLM lifting surface of a planform (a CAERO1 from root LE (0, 0, 0) to tip LE) and the
/// derivatives of its 8 parameters with respect to the planform variables.
pub fn dlm_surface(
    planform: &Planform,
    spec: &super::schema::DlmSpec,
) -> (SurfaceSpec, Vec<[f64; N_PLANFORM]>) {
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

impl AeroModel {
    /// Builds the study's fidelity on the plate's current planform.
    pub fn new(study: &Study, plate: &PlateModel) -> Result<Self, StudyError> {
        let aero = study.spec.aero.as_ref().ok_or_else(|| {
            study.err(
                "aero",
                "the study has no aerodynamic model (add an \"aero\" section)",
            )
        })?;
        let flight = study.flight_condition()?;
        let planform = plate.planform();
        let (fidelity, points, geometry_jacobian): (Box<dyn Aerodynamics>, Vec<[f64; 2]>, _) =
            match &aero.fidelity {
                FidelitySpec::Dlm(spec) => {
                    let (surface, jac) = dlm_surface(planform, spec);
                    let mut dlm = Dlm::new(vec![surface], spec.symmetry)
                        .map_err(|e| study.err("aero.fidelity.dlm", e.to_string()))?;
                    // only the parameters the planform moves need reverse-mode work
                    let active: Vec<usize> = (0..jac.len())
                        .filter(|&i| jac[i].iter().any(|v| *v != 0.0))
                        .collect();
                    dlm.set_active_geometry(0, &active);
                    let pts = dlm
                        .parametric_points()
                        .into_iter()
                        .map(|(_, p)| p)
                        .collect();
                    (Box::new(dlm), pts, jac)
                }
            };
        Ok(Self {
            fidelity,
            transfer: ModeTransfer::new(plate, &points),
            flight,
            k: aero.reduced_frequencies.clone(),
            geometry_jacobian,
        })
    }

    /// Mode shapes on the aerodynamic surface.
    pub fn modal_surface(&self, plate: &PlateModel, modes: &Modes) -> ModalSurface {
        self.transfer.modes_on_surface(plate, modes)
    }

    /// GAFs of the plate's modes at the study's reduced frequencies.
    pub fn gafs(&self, plate: &PlateModel, modes: &Modes) -> Result<GafTable, AeroError> {
        self.fidelity
            .gafs(&self.flight, &self.modal_surface(plate, modes), &self.k)
    }

    /// Reverse mode: for seeds on the GAF table, the seeds on the nodal mode shapes (feed them to
    /// `structure::modes_vjp`) and the direct gradient with respect to the planform variables
    /// (aerodynamic geometry and transfer).
    pub fn gafs_vjp(
        &self,
        plate: &PlateModel,
        modes: &Modes,
        seed: &GafTable,
    ) -> Result<ShapeSeeds, AeroError> {
        let mut out = self.gafs_vjp_many(plate, modes, std::slice::from_ref(seed))?;
        Ok(out.pop().expect("one seed, one gradient"))
    }

    /// [`AeroModel::gafs_vjp`] for several seeds, sharing the aerodynamic model's work.
    pub fn gafs_vjp_many(
        &self,
        plate: &PlateModel,
        modes: &Modes,
        seeds: &[GafTable],
    ) -> Result<Vec<ShapeSeeds>, AeroError> {
        let surface = self.modal_surface(plate, modes);
        let gs = self
            .fidelity
            .gafs_vjp_many(&self.flight, &surface, &self.k, seeds)?;
        Ok(gs
            .iter()
            .map(|g| {
                let (shapes, mut p_bar) =
                    self.transfer.modes_on_surface_vjp(plate, modes, &g.modes);
                for (gq, row) in g.geometry.iter().zip(&self.geometry_jacobian) {
                    for k in 0..N_PLANFORM {
                        p_bar[k] += gq * row[k];
                    }
                }
                (shapes, p_bar)
            })
            .collect())
    }
}
