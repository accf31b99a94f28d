//! Plate finite-element model of the wing: elements, mesh, assembly, modal analysis and exact
//! sensitivities.

pub mod band;
pub mod element;
mod material;
pub mod mesh;
pub mod modal;
pub mod model;
pub mod residual;
pub mod sensitivity;
pub mod shape_name;
pub mod triangle;

pub use material::{MaterialError, Orthotropic};
pub use mesh::{Clamp, PlateMesh};
pub use modal::{Mode, Modes, Sampler};
pub use model::{airfoil_thickness, Field, PlateModel};
pub use sensitivity::{
    mass_grad, modes_jvp, modes_vjp, root_bending_moment, root_bending_moment_vjp, ModalSeed,
};
