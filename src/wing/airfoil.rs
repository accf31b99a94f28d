//! Airfoil half-thickness tables z/c(x/c), used to size the plate elements.

use thiserror::Error;

/// A symmetric airfoil given by its half-thickness distribution.
#[derive(Clone, Debug, PartialEq)]
pub struct Airfoil {
    /// Name for reports.
    pub name: String,
    /// Chordwise stations x/c, strictly increasing from 0 to 1.
    pub x_c: Vec<f64>,
    /// Half-thickness z/c at each station, non-negative.
    pub z_c: Vec<f64>,
}

/// Why a thickness table is unusable.
#[derive(Debug, Error, PartialEq)]
pub enum AirfoilError {
    #[error("x_c and z_c must have the same length (got {0} and {1})")]
    Length(usize, usize),
    #[error("x_c must increase strictly from 0 to 1 (problem at index {0})")]
    Stations(usize),
    #[error("z_c must be finite and non-negative (problem at index {0})")]
    Thickness(usize),
}

/// NACA 65A004 half-thickness ordinates (shared/reference/agard445.md).
const NACA65A004_X: [f64; 24] = [
    0.0, 0.005, 0.0125, 0.025, 0.05, 0.10, 0.15, 0.20, 0.25, 0.30, 0.35, 0.40, 0.45, 0.50, 0.55,
    0.60, 0.65, 0.70, 0.75, 0.80, 0.85, 0.90, 0.95, 1.00,
];
const NACA65A004_Z: [f64; 24] = [
    0.0, 0.00304, 0.00469, 0.00647, 0.00875, 0.01213, 0.01459, 0.01645, 0.01788, 0.01892, 0.01962,
    0.01997, 0.01996, 0.01954, 0.01868, 0.01743, 0.01586, 0.01402, 0.01195, 0.00967, 0.00729,
    0.00490, 0.00250, 0.00009,
];

impl Airfoil {
    /// The built-in NACA 65A004 section of the AGARD 445.6 wing.
    pub fn naca65a004() -> Self {
        Self {
            name: "NACA 65A004".into(),
            x_c: NACA65A004_X.to_vec(),
            z_c: NACA65A004_Z.to_vec(),
        }
    }

    /// A user table, checked.
    pub fn from_table(name: &str, x_c: Vec<f64>, z_c: Vec<f64>) -> Result<Self, AirfoilError> {
        if x_c.len() != z_c.len() || x_c.len() < 2 {
            return Err(AirfoilError::Length(x_c.len(), z_c.len()));
        }
        if x_c[0] != 0.0 {
            return Err(AirfoilError::Stations(0));
        }
        for i in 1..x_c.len() {
            if !(x_c[i] > x_c[i - 1]) || !x_c[i].is_finite() {
                return Err(AirfoilError::Stations(i));
            }
        }
        if x_c[x_c.len() - 1] != 1.0 {
            return Err(AirfoilError::Stations(x_c.len() - 1));
        }
        if let Some(i) = z_c.iter().position(|z| !(z.is_finite() && *z >= 0.0)) {
            return Err(AirfoilError::Thickness(i));
        }
        Ok(Self {
            name: name.into(),
            x_c,
            z_c,
        })
    }

    /// Half-thickness z/c at x/c by linear interpolation (clamped to [0, 1]).
    pub fn half_thickness(&self, x_c: f64) -> f64 {
        let x = x_c.clamp(0.0, 1.0);
        let i = self
            .x_c
            .partition_point(|&s| s <= x)
            .clamp(1, self.x_c.len() - 1);
        let (x0, x1) = (self.x_c[i - 1], self.x_c[i]);
        let w = (x - x0) / (x1 - x0);
        self.z_c[i - 1] * (1.0 - w) + self.z_c[i] * w
    }

    /// Plate thickness factor t/c of a chordwise strip [xa, xb]: z(xa) + z(xb), i.e. the mean full
    /// thickness of the section over its edges (the public AGARD plate models do this).
    pub fn strip_thickness_ratio(&self, xa: f64, xb: f64) -> f64 {
        self.half_thickness(xa) + self.half_thickness(xb)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_reproduces_table_and_midpoints() {
        let a = Airfoil::naca65a004();
        for (x, z) in a.x_c.iter().zip(&a.z_c) {
            assert!((a.half_thickness(*x) - z).abs() < 1e-15);
        }
        let mid = a.half_thickness(0.375);
        assert!((mid - 0.5 * (0.01962 + 0.01997)).abs() < 1e-15);
        // maximum thickness 4 % of chord near 40 %
        assert!((2.0 * a.half_thickness(0.40) - 0.04).abs() < 1e-4);
    }

    #[test]
    fn bad_tables_are_rejected() {
        assert_eq!(
            Airfoil::from_table("a", vec![0.0, 1.0], vec![0.0]),
            Err(AirfoilError::Length(2, 1))
        );
        assert_eq!(
            Airfoil::from_table("a", vec![0.0, 0.5, 0.5, 1.0], vec![0.0; 4]),
            Err(AirfoilError::Stations(2))
        );
        assert_eq!(
            Airfoil::from_table("a", vec![0.0, 1.0], vec![0.0, -1.0]),
            Err(AirfoilError::Thickness(1))
        );
    }
}
