//! Stochastic gust response: turbulence spectra, GAF interpolation in k, the modal frequency
//! response of paper Eq. 16, PSD (Eq. 17), RMS and zero-crossing rate (Eq. 18), and their adjoint.

pub mod discrete;
pub mod interp;
pub mod psd;
pub mod response;
pub mod settings;
pub mod small_lu;

pub use psd::Turbulence;
pub use response::{
    frequency_response, rms_vjp, solve, FrequencyGrid, FrequencyResponse, GustError, GustGradient,
    GustProblem, GustResponse, ResidualGafs,
};
pub use settings::{GustSettings, Output, Quantity, QuantityName};
