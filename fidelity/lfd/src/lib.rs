//! The CFD fidelity of gustkit (work in progress): a finite-volume Euler solver whose residual is
//! written once over a generic scalar ([`gustkit_core::scalar::Scalar`]), so that exact Jacobians
//! and the linearized frequency-domain (LFD) operators come from the same code.
//!
//! So far: the perfect-gas state ([`gas`]), the differentiable Roe flux ([`flux`]), the
//! finite-volume mesh with its built-in O-mesh ([`mesh`]), the NACA 64A010 section from its
//! published ordinates ([`airfoil`]) and the first-order residual with wall, symmetry and
//! far-field boundaries ([`residual`]). Still to come (the CFD issues): second-order
//! reconstruction, the Newton–Krylov steady solver, ALE and the Field Velocity Method, the time
//! domain, mesh readers, the LFD operators and the `Aerodynamics` implementation.

pub mod airfoil;
pub mod flux;
pub mod gas;
pub mod mesh;
pub mod residual;
pub mod steady;
