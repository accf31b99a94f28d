//! The design vector: element-patch thicknesses followed by the four planform variables.

use super::Planform;

/// Number of planform design variables.
pub const N_PLANFORM: usize = 4;
/// Names of the planform variables in design-vector order.
pub const PLANFORM_NAMES: [&str; N_PLANFORM] = ["span", "sweep_c4", "root_chord", "tip_chord"];

/// x = [t_0 … t_{n-1}, span, sweep_c4, root_chord, tip_chord] in SI units (m, rad).
///
/// Thickness variable `i` belongs to the design patch at chordwise index `i % nx`, spanwise index
/// `i / nx` (chordwise fastest, root strip first).
#[derive(Clone, Debug, PartialEq)]
pub struct DesignVector {
    pub thickness: Vec<f64>,
    pub planform: Planform,
}

impl DesignVector {
    pub fn len(&self) -> usize {
        self.thickness.len() + N_PLANFORM
    }

    pub fn is_empty(&self) -> bool {
        false
    }

    /// Flat vector in design-vector order.
    pub fn to_vec(&self) -> Vec<f64> {
        let mut v = self.thickness.clone();
        v.extend_from_slice(&self.planform.to_array());
        v
    }

    /// Inverse of [`DesignVector::to_vec`]; `x.len()` must be at least [`N_PLANFORM`].
    pub fn from_slice(x: &[f64]) -> Self {
        let n = x.len() - N_PLANFORM;
        Self {
            thickness: x[..n].to_vec(),
            planform: Planform::from_array([x[n], x[n + 1], x[n + 2], x[n + 3]]),
        }
    }

    /// Human-readable name of variable `i` (e.g. `t[12]`, `sweep_c4`).
    pub fn name(&self, i: usize) -> String {
        let n = self.thickness.len();
        if i < n {
            format!("t[{i}]")
        } else {
            PLANFORM_NAMES[i - n].to_string()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flat_round_trip_and_names() {
        let d = DesignVector {
            thickness: vec![1.0, 2.0, 3.0],
            planform: Planform::from_array([4.0, 0.5, 6.0, 7.0]),
        };
        let v = d.to_vec();
        assert_eq!(v, vec![1.0, 2.0, 3.0, 4.0, 0.5, 6.0, 7.0]);
        assert_eq!(DesignVector::from_slice(&v), d);
        assert_eq!(d.name(1), "t[1]");
        assert_eq!(d.name(4), "sweep_c4");
    }
}
