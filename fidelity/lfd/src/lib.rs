//! The CFD fidelity of gustkit (work in progress): a finite-volume Euler solver whose residual is
//! written once over a generic scalar ([`gustkit_core::scalar::Scalar`]), so that exact Jacobians
//! and the linearized frequency-domain (LFD) operators come from the same code.
//!
//! So far: the perfect-gas state ([`gas`]), the differentiable Roe flux ([`flux`]), the
//! finite-volume mesh with its built-in O-mesh ([`mesh`]), the NACA 64A010 section from its
//! published ordinates ([`airfoil`]), first- and second-order residuals (least-squares
//! reconstruction, [`reconstruct`]) with wall, symmetry and far-field boundaries and face volume
//! fluxes for grid motion and Field-Velocity-Method gusts ([`residual`]), restarted GMRES
//! ([`krylov`]), the steady Newton / Newton–Krylov solver with pseudo-transient continuation
//! ([`steady`]) and the BDF2 time domain with dual-time subiterations under prescribed gusts
//! ([`unsteady`]). Still to come (the CFD issues): moving meshes with the geometric conservation
//! law and prescribed rigid motion, 1−cos gusts, mesh readers and VTK output, the study runner,
//! the LFD operators and the `Aerodynamics` implementation.

pub mod airfoil;
pub mod deform;
pub mod flux;
pub mod gafs;
pub mod gas;
pub mod jacobian;
pub mod krylov;
pub mod lfd;
pub mod mesh;
pub mod readers;
pub mod reconstruct;
pub mod residual;
pub mod steady;
pub mod unsteady;
pub mod vtk;
