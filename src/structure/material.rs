//! Orthotropic plane-stress material with a grain angle.

use thiserror::Error;

/// Why a material is not admissible.
#[derive(Debug, Error, PartialEq)]
pub enum MaterialError {
    #[error("{field}: must be positive and finite (got {value})")]
    NotPositive { field: &'static str, value: f64 },
    #[error(
        "nu12: the compliance is not positive definite (need nu12^2 < E1/E2 = {limit:.4}, got nu12 = {nu12})"
    )]
    NotPositiveDefinite { nu12: f64, limit: f64 },
}

/// Orthotropic lamina (SI). The grain (axis 1) lies at `grain_angle` from the spanwise axis +y,
/// positive toward the trailing edge (+x); 45° is the quarter-chord line of a wing swept 45°.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orthotropic {
    pub e1: f64,
    pub e2: f64,
    pub g12: f64,
    pub nu12: f64,
    pub density: f64,
    pub grain_angle: f64,
}

impl Orthotropic {
    /// Isotropic material as a special case.
    pub fn isotropic(e: f64, nu: f64, density: f64) -> Self {
        Self {
            e1: e,
            e2: e,
            g12: e / (2.0 * (1.0 + nu)),
            nu12: nu,
            density,
            grain_angle: 0.0,
        }
    }

    /// Checks positivity of the moduli and density and positive definiteness of the stiffness.
    pub fn validate(&self) -> Result<(), MaterialError> {
        for (field, value) in [
            ("e1", self.e1),
            ("e2", self.e2),
            ("g12", self.g12),
            ("density", self.density),
        ] {
            if !(value > 0.0 && value.is_finite()) {
                return Err(MaterialError::NotPositive { field, value });
            }
        }
        let limit = self.e1 / self.e2;
        if !(self.nu12 * self.nu12 < limit) || !self.nu12.is_finite() {
            return Err(MaterialError::NotPositiveDefinite {
                nu12: self.nu12,
                limit,
            });
        }
        Ok(())
    }

    /// Plane-stress stiffness Q̄ in the (x, y) frame, engineering shear strain:
    /// σ = Q̄ [ε_x, ε_y, γ_xy]. Obtained as Q̄ = Rᵀ Q R with R the strain rotation into the grain
    /// frame, so that the strain energy is frame independent.
    pub fn qbar(&self) -> [[f64; 3]; 3] {
        let nu21 = self.nu12 * self.e2 / self.e1;
        let den = 1.0 - self.nu12 * nu21;
        let q = [
            [self.e1 / den, self.nu12 * self.e2 / den, 0.0],
            [self.nu12 * self.e2 / den, self.e2 / den, 0.0],
            [0.0, 0.0, self.g12],
        ];
        // axis 1 direction in (x, y): angle from +y toward +x
        let (s, c) = self.grain_angle.sin_cos();
        let (l1, m1) = (s, c); // unit vector of axis 1
        let (l2, m2) = (-c, s); // axis 2, perpendicular
                                // ε_11 = l1² εx + m1² εy + l1 m1 γ; ε_22 likewise; γ_12 = 2 l1 l2 εx + 2 m1 m2 εy + (l1 m2 + l2 m1) γ
        let r = [
            [l1 * l1, m1 * m1, l1 * m1],
            [l2 * l2, m2 * m2, l2 * m2],
            [2.0 * l1 * l2, 2.0 * m1 * m2, l1 * m2 + l2 * m1],
        ];
        let mut out = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                let mut acc = 0.0;
                for a in 0..3 {
                    for b in 0..3 {
                        acc += r[a][i] * q[a][b] * r[b][j];
                    }
                }
                out[i][j] = acc;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An isotropic material is invariant under rotation and gives the classical plane-stress matrix.
    #[test]
    fn isotropic_is_rotation_invariant() {
        let mut m = Orthotropic::isotropic(70e9, 0.3, 2700.0);
        let q0 = m.qbar();
        m.grain_angle = 0.37;
        let q1 = m.qbar();
        let d = 70e9 / (1.0 - 0.09);
        let expect = [[d, 0.3 * d, 0.0], [0.3 * d, d, 0.0], [0.0, 0.0, 0.35 * d]];
        for i in 0..3 {
            for j in 0..3 {
                assert!((q0[i][j] - expect[i][j]).abs() < 1e-6 * d);
                assert!((q1[i][j] - expect[i][j]).abs() < 1e-6 * d);
            }
        }
    }

    /// Grain along +y gives E1 in the yy entry; grain along +x puts it in xx; the uniaxial modulus
    /// along the grain recovered from the compliance is E1 at any angle.
    #[test]
    fn orthotropic_rotation() {
        let mut m = Orthotropic {
            e1: 3.151e9,
            e2: 0.4162e9,
            g12: 0.4392e9,
            nu12: 0.31,
            density: 381.98,
            grain_angle: 0.0,
        };
        let q = m.qbar();
        assert!(q[1][1] > q[0][0]);
        m.grain_angle = std::f64::consts::FRAC_PI_2;
        let q = m.qbar();
        assert!(q[0][0] > q[1][1]);
        // uniaxial stress along the grain at 45°: strain direction (s, c)
        m.grain_angle = 45f64.to_radians();
        let q = m.qbar();
        // invert q (3x3) and evaluate the compliance along the grain
        let inv = invert3(q);
        let (s, c) = m.grain_angle.sin_cos();
        // σ = σ0 [s², c², s c]; ε_11 = [s², c², s c]·ε
        let t = [s * s, c * c, s * c];
        let mut compliance = 0.0;
        for i in 0..3 {
            for j in 0..3 {
                compliance += t[i] * inv[i][j] * t[j];
            }
        }
        assert!((1.0 / compliance / m.e1 - 1.0).abs() < 1e-12);
    }

    fn invert3(a: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
        let det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
            - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
        let mut out = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                let (r0, r1) = ((j + 1) % 3, (j + 2) % 3);
                let (c0, c1) = ((i + 1) % 3, (i + 2) % 3);
                out[i][j] = (a[r0][c0] * a[r1][c1] - a[r0][c1] * a[r1][c0]) / det;
            }
        }
        out
    }

    #[test]
    fn bad_materials_are_rejected() {
        let mut m = Orthotropic::isotropic(1.0, 0.3, 1.0);
        m.g12 = -1.0;
        assert!(matches!(
            m.validate(),
            Err(MaterialError::NotPositive { field: "g12", .. })
        ));
        let mut m = Orthotropic::isotropic(1.0, 0.3, 1.0);
        m.nu12 = 1.2;
        assert!(matches!(
            m.validate(),
            Err(MaterialError::NotPositiveDefinite { .. })
        ));
    }
}
