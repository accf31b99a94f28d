//! Shared aerodynamic contract of gustkit: the [`aero::Aerodynamics`] trait with its types and
//! conventions, and a small forward-mode AD scalar. No solver code lives here.

pub mod aero;
pub mod hyperdual;
pub mod scalar;
pub mod strip;
pub mod tape;
pub mod theory;

pub use aero::{
    check_reduced_frequencies, AeroError, AeroSurface, Aerodynamics, AerodynamicsReverse,
    FlightCondition, GafGradient, GafTable, LinearizationCheck, ModalSurface, SolverFailure,
};
