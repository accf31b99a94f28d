//! Perfect-gas conservative state q = [ρ, ρu, ρv, ρw, ρE] and the quantities derived from it.

use gustkit_core::scalar::Scalar;

/// Ratio of specific heats of air.
pub const GAMMA: f64 = 1.4;

/// Number of conservative variables.
pub const NVAR: usize = 5;

/// Primitive variables of a state.
#[derive(Clone, Copy, Debug)]
pub struct Primitive<S> {
    pub rho: S,
    pub vel: [S; 3],
    pub p: S,
    /// Total enthalpy H = (ρE + p)/ρ.
    pub h: S,
}

/// Primitive variables of a conservative state (no positivity check: callers check states).
pub fn primitive<S: Scalar>(q: &[S; NVAR]) -> Primitive<S> {
    let rho = q[0];
    let vel = [q[1] / rho, q[2] / rho, q[3] / rho];
    let ke = (vel[0] * vel[0] + vel[1] * vel[1] + vel[2] * vel[2]) * 0.5;
    let p = (q[4] - rho * ke) * (GAMMA - 1.0);
    Primitive {
        rho,
        vel,
        p,
        h: (q[4] + p) / rho,
    }
}

/// Conservative state from density, velocity and pressure.
pub fn conservative<S: Scalar>(rho: S, vel: [S; 3], p: S) -> [S; NVAR] {
    let ke = (vel[0] * vel[0] + vel[1] * vel[1] + vel[2] * vel[2]) * 0.5;
    [
        rho,
        rho * vel[0],
        rho * vel[1],
        rho * vel[2],
        p / (GAMMA - 1.0) + rho * ke,
    ]
}

/// Speed of sound √(γ p / ρ).
pub fn sound_speed<S: Scalar>(w: &Primitive<S>) -> S {
    (w.p * GAMMA / w.rho).sqrt()
}

/// Pressure coefficient C_p = (p − p∞)/(½ ρ∞ V∞²) of a state in the solver's free-stream units
/// (ρ∞ = 1, a∞ = 1, so p∞ = 1/γ and ½ ρ∞ V∞² = ½ M²).
pub fn pressure_coefficient(q: &[f64; NVAR], mach: f64) -> f64 {
    (primitive(q).p - 1.0 / GAMMA) / (0.5 * mach * mach)
}

/// Physical (Euler) flux through a face with area vector `nv` (|nv| = area) moving with normal
/// speed `vg` (grid velocity · nv, the ALE face flux of volume): F = (u·nv − vg) q + p [0, nv, u·nv].
pub fn physical_flux<S: Scalar>(q: &[S; NVAR], nv: [S; 3], vg: S) -> [S; NVAR] {
    let w = primitive(q);
    let un = w.vel[0] * nv[0] + w.vel[1] * nv[1] + w.vel[2] * nv[2];
    let rel = un - vg;
    [
        q[0] * rel,
        q[1] * rel + w.p * nv[0],
        q[2] * rel + w.p * nv[1],
        q[3] * rel + w.p * nv[2],
        q[4] * rel + w.p * un,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_sound_speed() {
        let q = conservative(1.2, [100.0, -20.0, 5.0], 101325.0);
        let w = primitive(&q);
        assert!((w.rho - 1.2).abs() < 1e-15);
        assert!((w.vel[1] + 20.0).abs() < 1e-12);
        assert!((w.p - 101325.0).abs() < 1e-9);
        // a = √(γ p / ρ) = 343.7… m/s at these values
        let a = sound_speed(&w);
        assert!((a - (1.4f64 * 101325.0 / 1.2).sqrt()).abs() < 1e-12);
        // H = a²/(γ−1) + |u|²/2
        let h = a * a / 0.4 + 0.5 * (100.0f64.powi(2) + 400.0 + 25.0);
        assert!((w.h - h).abs() < 1e-9 * h);
    }
}
