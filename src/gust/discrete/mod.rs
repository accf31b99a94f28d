//! Discrete gusts: gust profiles (the CS-25 tuned 1-cos gust, any tabulated w_g(t)), response
//! time histories through the frequency response and an inverse FFT, and their peaks.

pub mod analysis;
pub mod peak;
pub mod profile;
pub mod transient;
pub mod tuned;

pub use analysis::{
    transient, ProfileResponse, TransientModel, TransientResponse, TransientSettings,
};
pub use peak::{PeakKs, PEAK_KS_GAP};
pub use profile::{cs25_amplitude, reference_gust_velocity, GustProfile};
pub use transient::{extremes, truncated_energy, wrap_fraction, Peak, Synthesizer, TimeGrid};
pub use tuned::{gradient_grid, tuned_search, CriticalGust, EnvelopePoint, TunedResult};
