//! Length units of the user's files: SI inside, a study's own unit at the edges (its input and
//! everything a person reads). A leaf module: the study schema, the resolved case and the reports
//! all use it.

use serde::{Deserialize, Serialize};

/// Length unit of a study file.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(rename_all = "lowercase")]
pub enum LengthUnit {
    #[default]
    M,
    In,
    Ft,
}

impl LengthUnit {
    /// The unit's name as written in study files and reports.
    pub fn name(self) -> &'static str {
        match self {
            LengthUnit::M => "m",
            LengthUnit::In => "in",
            LengthUnit::Ft => "ft",
        }
    }

    /// Metres per unit.
    pub fn to_m(self) -> f64 {
        match self {
            LengthUnit::M => 1.0,
            LengthUnit::In => 0.0254,
            LengthUnit::Ft => 0.3048,
        }
    }

    /// The unit rule of everything a person reads (summary, console, figures, CSV): a length in
    /// the study's unit, every other quantity in SI. `value` in `si_unit` ("m" is converted, any
    /// other unit kept) raised to `power` (2 for a PSD of the quantity); the value and unit to show.
    pub fn display(self, value: f64, si_unit: &str, power: i32) -> (f64, &str) {
        if si_unit == "m" {
            (value / self.to_m().powi(power), self.name())
        } else {
            (value, si_unit)
        }
    }
}

/// A number as a message shows it: short, and never 309 digits long.
pub fn show(v: f64) -> String {
    if v != 0.0 && (v.abs() >= 1e6 || v.abs() < 1e-3) {
        format!("{v:.4e}")
    } else {
        format!("{}", (v * 1e6).round() / 1e6)
    }
}
