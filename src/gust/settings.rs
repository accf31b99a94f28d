//! The gust analysis settings of a study in SI: the turbulence, the response frequency grid and
//! the outputs whose PSD and RMS are computed.

use super::Turbulence;
use serde::{Deserialize, Serialize};

/// What a response output measures.
#[derive(Clone, Debug, PartialEq)]
pub enum Quantity {
    /// Vertical displacement at a point of the plate given in (ξ, η), m.
    Displacement { point: [f64; 2] },
    /// Root bending moment about the root line (mode-displacement method), N·m.
    RootBendingMoment,
}

impl Quantity {
    /// SI unit of the quantity.
    pub fn unit(&self) -> &'static str {
        match self {
            Quantity::Displacement { .. } => "m",
            Quantity::RootBendingMoment => "N m",
        }
    }
}

/// A response output.
#[derive(Clone, Debug)]
pub struct Output {
    pub name: String,
    pub quantity: Quantity,
}

/// Gust settings of a study (SI).
#[derive(Clone, Debug)]
pub struct GustSettings {
    pub turbulence: Turbulence,
    pub omega_min: f64,
    pub points: usize,
    pub max_tail: f64,
    /// Outputs by the mode-acceleration method (residual flexibility of the modes left out).
    pub mode_acceleration: bool,
    pub outputs: Vec<Output>,
}

/// The quantity of a gust output as a study file names it.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum QuantityName {
    /// Vertical displacement at a plate point [ξ, η].
    #[default]
    VerticalDisplacement,
    /// Root bending moment (no point).
    RootBendingMoment,
}
