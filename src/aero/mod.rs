//! Aerodynamics bound to the structure: the builder contract ([`contract`]), the fidelity registry
//! ([`registry`]: a study's fidelity spec → its builder → a model with its surface binding), the
//! builders of each fidelity
//! ([`dlm`], [`lfd`], [`strip`]) and the GAF driver [`AeroModel`] that couples a wing model to the
//! plate: modes → transfer → GAFs, and the reverse sweep back to the nodal mode shapes and the
//! planform variables. Nothing here asks which fidelity it is holding.

pub mod contract;
pub mod dlm;
pub mod lfd;
pub mod registry;
pub mod strip;

pub use contract::{
    BuildError, Capabilities, ModelFootprint, Sizing, SurfaceBinding, WingBuilder, WingContext,
    WingFidelity,
};
pub use registry::{FidelitySpec, SectionFidelitySpec};

use crate::structure::{Modes, PlateModel};
use crate::transfer::{mode_shapes, ModeTransfer};
use crate::wing::N_PLANFORM;
use gustkit_core::{AeroError, AerodynamicsReverse, FlightCondition, GafTable, ModalSurface};

/// Seeds on the nodal mode shapes (one vector a mode) and the direct planform gradient.
pub type ShapeSeeds = (Vec<Vec<f64>>, [f64; N_PLANFORM]);

/// An aerodynamic model bound to a planform and a plate.
pub struct AeroModel {
    /// The fidelity's name, for messages ("dlm", "lfd").
    pub name: &'static str,
    pub fidelity: Box<dyn gustkit_core::Aerodynamics>,
    pub transfer: ModeTransfer,
    pub flight: FlightCondition,
    pub k: Vec<f64>,
    /// ∂(geometry parameter)/∂(planform variable) of the fidelity's geometry parameters.
    geometry_jacobian: Vec<[f64; N_PLANFORM]>,
}

impl AeroModel {
    /// Builds the fidelity of `spec` on the plate's current planform and binds it to the plate
    /// through the builder's surface binding; `cache_dir` is where the fidelity may keep state
    /// between runs.
    pub fn new(
        spec: &FidelitySpec,
        flight: FlightCondition,
        k: Vec<f64>,
        plate: &PlateModel,
        airfoil: &crate::wing::Airfoil,
        cache_dir: Option<&std::path::Path>,
    ) -> Result<Self, BuildError> {
        let builder = spec.builder();
        let built = builder.build(&WingContext {
            planform: plate.planform(),
            airfoil,
            flight: &flight,
            cache_dir,
            fixed_planform: false,
        })?;
        Ok(Self::bind(builder.name(), built, flight, k, plate))
    }

    /// Binds a built wing model to the plate: the transfer samples the plate's modes at the
    /// binding's (ξ, η) points, one for each point of the model's surface.
    pub fn bind(
        name: &'static str,
        built: WingFidelity,
        flight: FlightCondition,
        k: Vec<f64>,
        plate: &PlateModel,
    ) -> Self {
        debug_assert_eq!(
            built.binding.points.len(),
            built.model.surface().points.len(),
            "a surface binding has one plate point for each surface point"
        );
        Self {
            name,
            transfer: ModeTransfer::new(plate, &built.binding.points),
            fidelity: built.model,
            flight,
            k,
            geometry_jacobian: built.binding.geometry_jacobian,
        }
    }

    /// Mode shapes on the aerodynamic surface.
    pub fn modal_surface(&self, plate: &PlateModel, modes: &Modes) -> ModalSurface {
        self.transfer.modes_on_surface(plate, modes)
    }

    /// GAFs of the plate's modes at the study's reduced frequencies.
    pub fn gafs(&self, plate: &PlateModel, modes: &Modes) -> Result<GafTable, AeroError> {
        self.gafs_of_shapes(plate, &mode_shapes(modes))
    }

    /// GAFs of any nodal shapes (the modes followed by residual shapes, say).
    pub fn gafs_of_shapes(
        &self,
        plate: &PlateModel,
        shapes: &[&[f64]],
    ) -> Result<GafTable, AeroError> {
        let surface = self.transfer.shapes_on_surface(plate, shapes);
        self.fidelity.gafs(&self.flight, &surface, &self.k)
    }

    /// The fidelity's reverse mode, or the error that says it has none.
    fn reverse(&self) -> Result<&dyn AerodynamicsReverse, AeroError> {
        self.fidelity
            .reverse()
            .ok_or_else(|| AeroError::Unsupported {
                fidelity: self.name.to_string(),
                what: "supply gradients (it has no reverse mode)".into(),
            })
    }

    /// Whether the bound model has a reverse mode.
    pub fn has_reverse(&self) -> bool {
        self.fidelity.reverse().is_some()
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
        self.gafs_vjp_many_shapes(plate, &mode_shapes(modes), seeds)
    }

    /// [`AeroModel::gafs_vjp_many`] for the GAFs of any nodal shapes ([`AeroModel::gafs_of_shapes`]).
    pub fn gafs_vjp_many_shapes(
        &self,
        plate: &PlateModel,
        shapes: &[&[f64]],
        seeds: &[GafTable],
    ) -> Result<Vec<ShapeSeeds>, AeroError> {
        let reverse = self.reverse()?;
        let surface = self.transfer.shapes_on_surface(plate, shapes);
        let gs = reverse.gafs_vjp_many(&self.flight, &surface, &self.k, seeds)?;
        Ok(gs
            .iter()
            .map(|g| {
                let (shapes, mut p_bar) =
                    self.transfer.shapes_on_surface_vjp(plate, shapes, &g.modes);
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

#[cfg(test)]
mod tests;
