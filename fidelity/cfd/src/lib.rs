//! The CFD fidelity of gustkit: a finite-volume Euler solver whose residual is written once over
//! a generic scalar ([`gustkit_core::scalar::Scalar`]: f64, dual numbers, the complex step), so
//! that exact Jacobians and the linearized frequency-domain (LFD) operators come from the same
//! code.
//!
//! The perfect-gas state ([`gas`]), the differentiable Roe flux ([`flux`]), unstructured meshes
//! with the built-in O-mesh ([`mesh`]), readers and VTK output ([`readers`], [`vtk`]), the NACA
//! 64A010 from its published ordinates ([`airfoil`]), first- and second-order residuals with
//! grid-motion and Field-Velocity-Method gust fluxes ([`residual`], [`reconstruct`]), the exact
//! Jacobian by colouring ([`jacobian`]), GMRES over real and complex fields ([`krylov`]), the
//! steady Newton solver ([`steady`]), the BDF2 time domain on moving meshes ([`unsteady`]), the
//! LFD equations for gusts and mode motion ([`lfd`]), mesh deformation for mode shapes
//! ([`deform`]), the `Aerodynamics` implementation ([`lfd_model`]) and the transposed linearizations of
//! its reverse mode ([`adjoint`]), from the right-hand sides' and forces' Jacobians assembled by
//! colouring ([`lfd_jacobians`]).

pub mod adjoint;
pub mod airfoil;
pub mod deform;
pub mod flux;
pub mod forward_store;
pub mod gas;
pub mod ilu;
pub mod jacobian;
pub mod krylov;
pub mod lfd;
pub mod lfd_jacobians;
pub mod lfd_model;
pub mod mesh;
pub mod mesh_sensitivity;
pub mod readers;
pub mod reconstruct;
pub mod residual;
pub mod steady;
pub mod unsteady;
pub mod vtk;
pub mod wing_mesh;
