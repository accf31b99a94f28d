//! The CFD fidelity of gustkit (work in progress): a finite-volume Euler solver whose residual is
//! written once over a generic scalar ([`gustkit_core::scalar::Scalar`]), so that exact Jacobians
//! and the linearized frequency-domain (LFD) operators come from the same code.
//!
//! So far: the perfect-gas state ([`gas`]), the differentiable Roe flux ([`flux`]) and the
//! finite-volume mesh with its built-in O-mesh ([`mesh`]).

pub mod flux;
pub mod gas;
pub mod mesh;
