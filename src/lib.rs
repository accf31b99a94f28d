//! gustkit: aeroelastic gust analysis and gust-constrained wing design.
//!
//! The pipeline runs design vector → wing → plate model → modes → (aerodynamics) → gust response,
//! and back again for gradients. See README.md for the user guide and ARCHITECTURE.md for the
//! layout.

pub mod aero;
pub mod atomic;
pub mod case;
pub mod cli;
pub mod flutter;
pub mod gust;
pub mod kind;
pub mod nastran;
pub mod optim;
pub mod pipeline;
pub mod problem;
pub mod report;
pub mod runner;
pub mod structure;
pub mod study;
pub mod transfer;
pub mod typical_section;
pub mod units;
pub mod verification;
pub mod wing;
