//! gustkit: aeroelastic gust analysis and gust-constrained wing design.
//!
//! The pipeline runs design vector → wing → plate model → modes → (aerodynamics) → gust response,
//! and back again for gradients. See README.md for the architecture.

pub mod cfd;
pub mod cli;
pub mod flutter;
pub mod gust;
pub mod optim;
pub mod pipeline;
pub mod report;
pub mod section;
pub mod structure;
pub mod study;
pub mod transfer;
pub mod wing;
