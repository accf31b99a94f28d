//! Structure → aerodynamics transfer of mode shapes, and its transpose for loads.
//!
//! The aerodynamic points are given in the plate's own parametric coordinates (ξ, η) (the DLM
//! boxes are laid on the same bilinear planform map), so the transfer is the plate's own
//! interpolation evaluated at those points ([`Sampler`]): deflection w and streamwise slope ∂w/∂x from
//! the DKQ/ACM fields, in-plane u, v bilinear. No spline is fitted, so nothing is smoothed or
//! extrapolated, the transfer is exact for the structural model, and its derivative with respect to
//! the planform (the slopes move with the element geometry) comes from the same element code.
//! In-plane slopes are not transferred: flat-plate aerodynamics uses only the normal component.

use crate::structure::modal::SAMPLED;
use crate::structure::{Modes, PlateModel, Sampler};
use crate::wing::N_PLANFORM;
use gustkit_core::ModalSurface;

/// The nodal shapes of the retained modes.
pub fn mode_shapes(modes: &Modes) -> Vec<&[f64]> {
    modes.modes.iter().map(|m| m.shape.as_slice()).collect()
}

/// Mode-shape transfer onto a fixed list of aerodynamic points.
#[derive(Clone, Debug)]
pub struct ModeTransfer {
    sampler: Sampler,
}

impl ModeTransfer {
    /// Points in the plate's parametric coordinates (ξ, η).
    pub fn new(model: &PlateModel, points: &[[f64; 2]]) -> Self {
        Self {
            sampler: Sampler::new(model, points),
        }
    }

    pub fn n_points(&self) -> usize {
        self.sampler.located.len()
    }

    /// Mode shapes at the points: displacement (u, v, w) and streamwise slope (0, 0, ∂w/∂x).
    pub fn modes_on_surface(&self, model: &PlateModel, modes: &Modes) -> ModalSurface {
        self.shapes_on_surface(model, &mode_shapes(modes))
    }

    /// Any nodal shapes (modes, residual shapes) at the points, as [`Self::modes_on_surface`].
    pub fn shapes_on_surface(&self, model: &PlateModel, shapes: &[&[f64]]) -> ModalSurface {
        let mut out = ModalSurface::zeros(shapes.len(), self.n_points());
        for (m, shape) in shapes.iter().enumerate() {
            for (p, s) in self.sampler.sample(model, shape).iter().enumerate() {
                out.disp[m][p] = [s[3], s[4], s[0]];
                out.disp_x[m][p] = [0.0, 0.0, s[1]];
            }
        }
        out
    }

    /// Reverse mode of [`ModeTransfer::modes_on_surface`]: the seed on each mode's nodal shape and
    /// the gradient with respect to the planform variables.
    pub fn modes_on_surface_vjp(
        &self,
        model: &PlateModel,
        modes: &Modes,
        seed: &ModalSurface,
    ) -> (Vec<Vec<f64>>, [f64; N_PLANFORM]) {
        self.shapes_on_surface_vjp(model, &mode_shapes(modes), seed)
    }

    /// Reverse mode of [`ModeTransfer::shapes_on_surface`].
    pub fn shapes_on_surface_vjp(
        &self,
        model: &PlateModel,
        shapes: &[&[f64]],
        seed: &ModalSurface,
    ) -> (Vec<Vec<f64>>, [f64; N_PLANFORM]) {
        let mut p_bar = [0.0; N_PLANFORM];
        let shapes = shapes
            .iter()
            .enumerate()
            .map(|(m, shape)| {
                let s: Vec<[f64; SAMPLED]> = (0..self.n_points())
                    .map(|p| {
                        let (d, dx) = (seed.disp[m][p], seed.disp_x[m][p]);
                        [d[2], dx[2], 0.0, d[0], d[1]]
                    })
                    .collect();
                let (nodal, pb) = self.sampler.sample_vjp(model, shape, &s);
                for k in 0..N_PLANFORM {
                    p_bar[k] += pb[k];
                }
                nodal
            })
            .collect();
        (shapes, p_bar)
    }

    /// Transpose for loads: forces (x, y, z components) at the points → nodal forces conjugate to
    /// the nodal field (w, w_x, w_y, u, v); by construction Σ f·u(points) = Σ F·(nodal field).
    pub fn loads_to_nodes(&self, model: &PlateModel, forces: &[[f64; 3]]) -> Vec<f64> {
        let seed: Vec<[f64; SAMPLED]> = forces
            .iter()
            .map(|f| [f[2], 0.0, 0.0, f[0], f[1]])
            .collect();
        let zero = vec![0.0; crate::structure::model::NODAL * model.mesh.nodes.len()];
        self.sampler.sample_vjp(model, &zero, &seed).0
    }
}

#[cfg(test)]
mod tests;
