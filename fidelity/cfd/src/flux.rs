//! Roe's approximate Riemann flux, written over a generic scalar so that its exact Jacobian (dual
//! numbers) and complex-step derivatives come from this one function.
//!
//! F(q_L, q_R) = ½ [F(q_L) + F(q_R)] − ½ Σ_k |λ̃_k| α_k r̃_k with Roe-averaged eigenvalues
//! λ̃ = (ũ_n − ã, ũ_n, ũ_n, ũ_n + ã) (relative to the face speed on moving grids), wave strengths
//! α and eigenvectors r̃ of the Roe matrix. |λ| is replaced by the smooth √(λ² + (ε ã)²) so that the
//! flux is differentiable everywhere (ε = 0 gives the classical flux).

use crate::gas::{physical_flux, primitive, NVAR};
use gustkit_core::scalar::Scalar;

/// The Roe flux with a smooth entropy fix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Roe {
    /// ε of the smooth absolute value √(λ² + (ε ã)²); 0 for the classical flux.
    pub entropy_eps: f64,
}

impl Default for Roe {
    fn default() -> Self {
        Self { entropy_eps: 0.05 }
    }
}

impl Roe {
    /// Smooth |λ| scaled by the Roe-averaged sound speed `a`.
    fn abs<S: Scalar>(&self, lambda: S, a: S) -> S {
        if self.entropy_eps == 0.0 {
            lambda.abs()
        } else {
            let d = a * self.entropy_eps;
            (lambda * lambda + d * d).sqrt()
        }
    }

    /// Flux through a face with area vector `nv` (|nv| = area, from left to right) moving with
    /// the normal volume flux `vg` = ẋ_face · nv.
    pub fn flux<S: Scalar>(&self, ql: &[S; NVAR], qr: &[S; NVAR], nv: [S; 3], vg: S) -> [S; NVAR] {
        let area = (nv[0] * nv[0] + nv[1] * nv[1] + nv[2] * nv[2]).sqrt();
        let n = [nv[0] / area, nv[1] / area, nv[2] / area];
        let (wl, wr) = (primitive(ql), primitive(qr));
        // Roe averages
        let (sl, sr) = (wl.rho.sqrt(), wr.rho.sqrt());
        let inv = S::one() / (sl + sr);
        let u: [S; 3] = std::array::from_fn(|i| (wl.vel[i] * sl + wr.vel[i] * sr) * inv);
        let h = (wl.h * sl + wr.h * sr) * inv;
        let rho = sl * sr;
        let q2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
        let a2 = (h - q2 * 0.5) * (crate::gas::GAMMA - 1.0);
        let a = a2.sqrt();
        let un = u[0] * n[0] + u[1] * n[1] + u[2] * n[2];
        let vgn = vg / area;
        // jumps
        let d_rho = wr.rho - wl.rho;
        let d_p = wr.p - wl.p;
        let du: [S; 3] = std::array::from_fn(|i| wr.vel[i] - wl.vel[i]);
        let d_un = du[0] * n[0] + du[1] * n[1] + du[2] * n[2];
        // wave strengths and smooth |λ| (eigenvalues relative to the moving face)
        let a1 = (d_p - rho * a * d_un) / (a2 * 2.0);
        let a3 = (d_p + rho * a * d_un) / (a2 * 2.0);
        let a2w = d_rho - d_p / a2;
        let l1 = self.abs(un - a - vgn, a);
        let l2 = self.abs(un - vgn, a);
        let l3 = self.abs(un + a - vgn, a);
        // Σ |λ_k| α_k r_k
        let mut diss = [S::zero(); NVAR];
        let (c1, c2, c3) = (l1 * a1, l2 * a2w, l3 * a3);
        diss[0] = c1 + c2 + c3;
        for i in 0..3 {
            // shear waves: ρ̃ (Δu − Δu_n n) with |λ2|
            let shear = rho * (du[i] - d_un * n[i]);
            diss[1 + i] = c1 * (u[i] - a * n[i]) + c2 * u[i] + c3 * (u[i] + a * n[i]) + l2 * shear;
        }
        let u_du = u[0] * du[0] + u[1] * du[1] + u[2] * du[2];
        diss[4] =
            c1 * (h - un * a) + c2 * (q2 * 0.5) + c3 * (h + un * a) + l2 * rho * (u_du - un * d_un);
        let fl = physical_flux(ql, nv, vg);
        let fr = physical_flux(qr, nv, vg);
        std::array::from_fn(|k| (fl[k] + fr[k]) * 0.5 - diss[k] * area * 0.5)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gas::conservative;
    use gustkit_core::scalar::Dual;
    use gustkit_testkit::{fd_check, rand_vec};

    fn state(rho: f64, u: [f64; 3], p: f64) -> [f64; NVAR] {
        conservative(rho, u, p)
    }

    /// F(q, q) is the physical flux (consistency), and F(q_L, q_R, n) = −F(q_R, q_L, −n)
    /// (conservation), to round-off.
    #[test]
    fn consistent_and_conservative() {
        let roe = Roe::default();
        let nv = [0.3, -0.7, 0.2];
        let q = state(1.1, [80.0, 10.0, -5.0], 9.0e4);
        let f = roe.flux(&q, &q, nv, 0.0);
        let p = physical_flux(&q, nv, 0.0);
        for k in 0..NVAR {
            assert!((f[k] - p[k]).abs() <= 1e-12 * p[k].abs().max(1.0), "{k}");
        }
        let qr = state(0.9, [60.0, -20.0, 15.0], 8.0e4);
        let a = roe.flux(&q, &qr, nv, 3.0);
        let b = roe.flux(&qr, &q, [-nv[0], -nv[1], -nv[2]], -3.0);
        for k in 0..NVAR {
            assert!((a[k] + b[k]).abs() <= 1e-12 * a[k].abs().max(1.0), "{k}");
        }
    }

    /// With the classical |λ|, the Roe flux of a supersonic flow across the face is the upwind
    /// physical flux: this holds only because the Roe matrix maps jumps of q to jumps of F
    /// exactly, so it checks the averages, wave strengths and eigenvectors together.
    #[test]
    fn supersonic_flux_is_upwind() {
        let roe = Roe { entropy_eps: 0.0 };
        let nv = [0.6, 0.8, 0.0];
        let ql = state(1.0, [600.0, 500.0, 30.0], 1.0e5);
        let qr = state(1.3, [550.0, 560.0, -20.0], 1.4e5);
        for (vg, upwind) in [(0.0, &ql), (-2000.0, &ql)] {
            let f = roe.flux(&ql, &qr, nv, vg);
            let p = physical_flux(upwind, nv, vg);
            for k in 0..NVAR {
                assert!(
                    (f[k] - p[k]).abs() <= 1e-10 * p[k].abs().max(1.0),
                    "{k}: {f:?} {p:?}"
                );
            }
        }
        // and backwards: flow from right to left across the face
        let ql = state(1.0, [-600.0, -500.0, 0.0], 1.0e5);
        let qr = state(1.2, [-650.0, -480.0, 0.0], 1.1e5);
        let f = roe.flux(&ql, &qr, nv, 0.0);
        let p = physical_flux(&qr, nv, 0.0);
        for k in 0..NVAR {
            assert!((f[k] - p[k]).abs() <= 1e-10 * p[k].abs().max(1.0), "{k}");
        }
    }

    /// Rotating the velocities and the face normal together rotates the momentum flux and leaves
    /// mass and energy fluxes unchanged.
    #[test]
    fn rotation_invariance() {
        let roe = Roe::default();
        let (c, s) = (0.6f64, 0.8f64);
        let rot = |v: [f64; 3]| [c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]];
        let (ul, ur) = ([70.0, 20.0, 3.0], [50.0, -10.0, 8.0]);
        let nv = [0.2, 0.9, -0.1];
        let f = roe.flux(&state(1.0, ul, 9e4), &state(1.2, ur, 1e5), nv, 1.5);
        let g = roe.flux(
            &state(1.0, rot(ul), 9e4),
            &state(1.2, rot(ur), 1e5),
            rot(nv),
            1.5,
        );
        let fm = rot([f[1], f[2], f[3]]);
        for (a, b) in [
            (f[0], g[0]),
            (f[4], g[4]),
            (fm[0], g[1]),
            (fm[1], g[2]),
            (fm[2], g[3]),
        ] {
            assert!((a - b).abs() <= 1e-11 * a.abs().max(1.0), "{a} {b}");
        }
    }

    /// The flux differentiated by dual numbers along random directions of (q_L, q_R, n, v_g)
    /// agrees with central differences (Richardson) to 1e-8 relative: the exact Jacobian that the
    /// Newton solver and the LFD operators will use.
    #[test]
    fn dual_derivative_matches_finite_differences() {
        let roe = Roe::default();
        let base = [
            state(1.1, [80.0, 10.0, -5.0], 9.0e4),
            state(0.9, [60.0, -20.0, 15.0], 8.0e4),
        ];
        let nv0 = [0.3, -0.7, 0.2];
        for trial in 0..4 {
            let r = rand_vec(2 * NVAR + 4, 100 + trial);
            // directions scaled to each variable's size
            let scale_q = |q: &[f64; NVAR], k: usize| q[k].abs().max(1.0) * 1e-2;
            let dl: [f64; NVAR] = std::array::from_fn(|k| r[k] * scale_q(&base[0], k));
            let dr: [f64; NVAR] = std::array::from_fn(|k| r[NVAR + k] * scale_q(&base[1], k));
            let dn = [r[10] * 0.1, r[11] * 0.1, r[12] * 0.1];
            let dvg = r[13] * 2.0;
            let at = |t: f64| -> ([f64; NVAR], [f64; NVAR], [f64; 3], f64) {
                (
                    std::array::from_fn(|k| base[0][k] + t * dl[k]),
                    std::array::from_fn(|k| base[1][k] + t * dr[k]),
                    std::array::from_fn(|i| nv0[i] + t * dn[i]),
                    1.0 + t * dvg,
                )
            };
            let dual = |v: f64, d: f64| Dual::<1>::new(v, [d]);
            let (ql, qr, nv, vg) = at(0.0);
            let fd: [Dual<1>; NVAR] = roe.flux(
                &std::array::from_fn(|k| dual(ql[k], dl[k])),
                &std::array::from_fn(|k| dual(qr[k], dr[k])),
                std::array::from_fn(|i| dual(nv[i], dn[i])),
                dual(vg, dvg),
            );
            for k in 0..NVAR {
                let f = |x: &[f64]| {
                    let (ql, qr, nv, vg) = at(x[0]);
                    roe.flux(&ql, &qr, nv, vg)[k]
                };
                let exact = fd[k].d[0];
                let rep = fd_check(&f, &[0.0], 0, exact, exact.abs().max(1e-6 * fd[k].v.abs()));
                assert!(
                    rep.best_rel_error < 1e-8,
                    "trial {trial} component {k}: {rep:?}"
                );
            }
        }
    }
}
