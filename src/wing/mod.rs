//! Parametric wing: trapezoidal planform, airfoil thickness table and the design vector.
//!
//! Coordinates: x streamwise (aft positive), y spanwise from the root (wall), z up. The root
//! leading edge sits at the origin. A point of the wing is addressed by parametric coordinates
//! `xi` (fraction of the local chord, 0 at the leading edge) and `eta` (fraction of the span);
//! the map `(xi, eta) -> (x, y)` is bilinear, so plate elements laid on a `(xi, eta)` grid map it
//! exactly and points given in `(xi, eta)` follow the planform when it changes.

mod airfoil;
mod design;

pub use airfoil::Airfoil;
pub use design::{DesignVector, N_PLANFORM, PLANFORM_NAMES};

use gustkit_core::scalar::Scalar;
use thiserror::Error;

/// Why a planform is not a wing.
#[derive(Debug, Error, PartialEq)]
pub enum PlanformError {
    #[error("{field}: must be positive and finite (got {value})")]
    NotPositive { field: &'static str, value: f64 },
    #[error("sweep_c4: must lie strictly between -80 and 80 degrees (got {deg} deg)")]
    Sweep { deg: f64 },
}

/// Trapezoidal half-wing planform (SI: metres, radians).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Planform {
    /// Semispan s (root to tip), m.
    pub span: f64,
    /// Quarter-chord sweep angle, rad.
    pub sweep_c4: f64,
    /// Streamwise root chord c_r, m.
    pub root_chord: f64,
    /// Streamwise tip chord c_t, m.
    pub tip_chord: f64,
}

impl Planform {
    /// Checks that the planform is a proper trapezoid: positive span and chords (a chord ≤ 0
    /// anywhere would make the leading- and trailing-edge lines cross) and a sane sweep.
    pub fn validate(&self) -> Result<(), PlanformError> {
        for (field, value) in [
            ("span", self.span),
            ("root_chord", self.root_chord),
            ("tip_chord", self.tip_chord),
        ] {
            if !(value > 0.0 && value.is_finite()) {
                return Err(PlanformError::NotPositive { field, value });
            }
        }
        if !(self.sweep_c4.abs() < 80f64.to_radians()) {
            return Err(PlanformError::Sweep {
                deg: self.sweep_c4.to_degrees(),
            });
        }
        Ok(())
    }

    /// The four planform variables in design-vector order: span, sweep, root chord, tip chord.
    pub fn to_array(&self) -> [f64; 4] {
        [self.span, self.sweep_c4, self.root_chord, self.tip_chord]
    }

    pub fn from_array(p: [f64; 4]) -> Self {
        Self {
            span: p[0],
            sweep_c4: p[1],
            root_chord: p[2],
            tip_chord: p[3],
        }
    }

    /// Planform area S = s (c_r + c_t) / 2.
    pub fn area(&self) -> f64 {
        self.span * (self.root_chord + self.tip_chord) / 2.0
    }

    /// Gradient of [`Planform::area`] with respect to (span, sweep, root chord, tip chord).
    pub fn area_grad(&self) -> [f64; 4] {
        [
            (self.root_chord + self.tip_chord) / 2.0,
            0.0,
            self.span / 2.0,
            self.span / 2.0,
        ]
    }

    /// Mean aerodynamic chord of the trapezoid.
    pub fn mean_aero_chord(&self) -> f64 {
        let (cr, lam) = (self.root_chord, self.tip_chord / self.root_chord);
        2.0 / 3.0 * cr * (1.0 + lam + lam * lam) / (1.0 + lam)
    }

    /// Point (x, y) of parametric coordinates (xi, eta); see [`planform_point`].
    pub fn point(&self, xi: f64, eta: f64) -> [f64; 2] {
        planform_point(self.to_array(), xi, eta)
    }

    /// Local chord at spanwise fraction eta.
    pub fn chord(&self, eta: f64) -> f64 {
        self.root_chord + eta * (self.tip_chord - self.root_chord)
    }
}

/// Point (x, y) of parametric coordinates (xi, eta) for planform variables
/// `p = [span, sweep_c4, root_chord, tip_chord]`, generic over the scalar so that derivatives with
/// respect to the planform come from the same code.
///
/// tan Λ_LE = tan Λ_c/4 + (c_r − c_t) / (4 s); x = η s tan Λ_LE + ξ c(η); y = η s.
pub fn planform_point<S: Scalar>(p: [S; 4], xi: f64, eta: f64) -> [S; 2] {
    let [s, sweep, cr, ct] = p;
    let tan_le = sweep.tan() + (cr - ct) / (s * 4.0);
    let chord = cr + (ct - cr) * eta;
    [s * tan_le * eta + chord * xi, s * eta]
}

#[cfg(test)]
mod tests {
    use super::*;
    use gustkit_core::scalar::Dual;

    fn agard() -> Planform {
        Planform {
            span: 0.762,
            sweep_c4: 45f64.to_radians(),
            root_chord: 0.5587,
            tip_chord: 0.3682,
        }
    }

    /// Reference geometry from shared/reference/agard445.md: tip LE at x = 31.866 in, area 0.3531 m²,
    /// MAC 0.470 m.
    #[test]
    fn agard_planform_matches_reference() {
        let p = agard();
        let tip_le = p.point(0.0, 1.0);
        assert!((tip_le[0] / 0.0254 - 31.866).abs() < 0.01, "{tip_le:?}");
        assert!((p.area() - 0.3531).abs() < 2e-4);
        assert!((p.mean_aero_chord() - 0.470).abs() < 1e-3);
        // the quarter-chord line is swept at exactly 45 degrees
        let a = p.point(0.25, 0.0);
        let b = p.point(0.25, 1.0);
        assert!(((b[0] - a[0]) / (b[1] - a[1]) - 1.0).abs() < 1e-12);
    }

    /// Area gradient against central finite differences (the area is bilinear: exact to round-off).
    #[test]
    fn area_gradient_matches_fd() {
        let p = agard();
        let g = p.area_grad();
        for (k, gk) in g.iter().enumerate() {
            let h = 1e-6;
            let mut a = p.to_array();
            let mut b = p.to_array();
            a[k] += h;
            b[k] -= h;
            let fd = (Planform::from_array(a).area() - Planform::from_array(b).area()) / (2.0 * h);
            assert!((fd - gk).abs() < 1e-9, "var {k}: fd {fd} vs {gk}");
        }
    }

    /// The dual-number point derivative equals finite differences of the point map.
    #[test]
    fn point_derivative_matches_fd() {
        let p = agard().to_array();
        let pd: [Dual<4>; 4] = std::array::from_fn(|k| Dual::var(p[k], k));
        let (xi, eta) = (0.7, 0.6);
        let xd = planform_point(pd, xi, eta);
        for k in 0..4 {
            let h = 1e-6;
            let mut a = p;
            let mut b = p;
            a[k] += h;
            b[k] -= h;
            let pa = planform_point(a, xi, eta);
            let pb = planform_point(b, xi, eta);
            for c in 0..2 {
                let fd = (pa[c] - pb[c]) / (2.0 * h);
                assert!((fd - xd[c].d[k]).abs() < 1e-8, "var {k} comp {c}");
            }
        }
    }

    #[test]
    fn degenerate_planforms_are_rejected() {
        let mut p = agard();
        p.tip_chord = 0.0;
        assert_eq!(
            p.validate(),
            Err(PlanformError::NotPositive {
                field: "tip_chord",
                value: 0.0
            })
        );
        let mut p = agard();
        p.span = f64::NAN;
        assert!(p.validate().is_err());
        let mut p = agard();
        p.sweep_c4 = 85f64.to_radians();
        assert!(matches!(p.validate(), Err(PlanformError::Sweep { .. })));
    }
}
