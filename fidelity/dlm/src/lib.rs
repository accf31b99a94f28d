//! Doublet-Lattice Method (DLM) fidelity: trapezoidal lifting surfaces divided into boxes, the
//! steady vortex lattice plus the oscillatory doublet-lattice increment (Albano & Rodden 1969 with
//! the quartic kernel approximation of Rodden, Taylor & McIntosh 1998), and GAFs through the shared
//! [`gustkit_core::Aerodynamics`] trait.

pub mod cplx;
pub mod geometry;
pub mod influence;
pub mod kernel;
pub mod model;

pub use geometry::{Spacing, SurfaceSpec};
pub use model::{Dlm, Symmetry};
