//! The oscillatory part of Landahl's subsonic kernel and its integrals.
//!
//! Following Rodden, Giesing & Kálmán (1971) and Rodden, Taylor & McIntosh (1998): with
//! x0, ȳ0, z̄0 the offsets of the receiving point from a point of the doublet line,
//! r1 = √(ȳ0² + z̄0²), β² = 1 − M², R = √(x0² + β² r1²), u1 = (M R − x0)/(β² r1), k1 = ω r1 / U,
//!   K1 = −I1 − M r1 e^{−i k1 u1} / (R √(1+u1²)),
//!   K2 = 3 I2 + i k1 M² r1² e^{−i k1 u1} / (R² √(1+u1²))
//!        + M r1 e^{−i k1 u1} [(1+u1²) β² r1²/R² + 2 + M r1 u1 / R] / (R (1+u1²)^{3/2}),
//! with I1 = ∫_{u1}^∞ e^{−i k1 u} (1+u²)^{−3/2} du and I2 = ∫_{u1}^∞ e^{−i k1 u} (1+u²)^{−5/2} du,
//! and their steady values K10 = −1 − x0/R, K20 = 2 + x0 (2 + β² r1²/R²)/R. The numerators of the
//! incremental kernel are P1 = −(K1 e^{−i ω x0/U} − K10) T1 and P2 = −(K2 e^{−i ω x0/U} − K20) T2*,
//! T1 = cos(γr − γs), T2* = z̄0 (z̄0 cos(γr − γs) − ȳ0 sin(γr − γs)); the steady part is left to the
//! vortex lattice.
//!
//! The integrals use the 12-term exponential approximation of 1 − u/√(1+u²) by Desmarais
//! (Σ a_n e^{−2ⁿ b u}), extended to u1 < 0 by I(u1) = 2 Re I(0) − Re I(−u1) + i Im I(−u1).

use crate::cplx::Cplx;
use gustkit_core::scalar::{Dual, Scalar};

/// The scalars the kernel runs on: values (`f64`) and forward-mode duals. Beyond [`Scalar`] they
/// can take a derivative chained by hand, so that the hot Desmarais sums run on plain numbers
/// with their two partial derivatives instead of through every dual operation.
pub trait KernelScalar: Scalar {
    /// Whether the type carries derivatives (when not, the partials need not be formed).
    const DERIVATIVES: bool;
    /// f(a, b) from its value `v` and partial derivatives `da`, `db` at (a, b).
    fn lift2(a: Self, b: Self, v: f64, da: f64, db: f64) -> Self;
}

impl KernelScalar for f64 {
    const DERIVATIVES: bool = false;
    #[inline]
    fn lift2(_: f64, _: f64, v: f64, _: f64, _: f64) -> f64 {
        v
    }
}

impl<const N: usize> KernelScalar for Dual<N> {
    const DERIVATIVES: bool = true;
    #[inline]
    fn lift2(a: Self, b: Self, v: f64, da: f64, db: f64) -> Self {
        Dual::new(v, std::array::from_fn(|i| da * a.d[i] + db * b.d[i]))
    }
}

/// Desmarais coefficients a_n (n = 1 … 12) and exponent base b (p_n = 2ⁿ b).
const DESMARAIS_A: [f64; 12] = [
    0.000319759140,
    -0.000055461471,
    0.002726074362,
    0.005749551566,
    0.031455895072,
    0.106031126212,
    0.406838011567,
    0.798112357155,
    -0.417749229098,
    0.077480713894,
    -0.012677284771,
    0.001787032960,
];
const DESMARAIS_B: f64 = 0.009054814793;

/// The exponentials e^{−pₙ u} (n = 1 … 12) of the Desmarais terms at u ≥ 0 (values), by repeated
/// squaring of e^{−2 b u}: they depend on the point only, so a table of frequencies computes them
/// once. Their derivatives are −pₙ e^{−pₙ u}, chained where they are used.
fn desmarais_exponentials(u: f64) -> [f64; 12] {
    let mut q = [0.0; 12];
    q[0] = (u * (-2.0 * DESMARAIS_B)).exp();
    for n in 1..12 {
        q[n] = q[n - 1] * q[n - 1];
    }
    q
}

/// The exponentials as scalars of type S (their derivatives −pₙ qₙ du), for the generic sums.
fn exponentials_as<S: KernelScalar>(u: S, q: &[f64; 12]) -> [S; 12] {
    let mut p = 2.0 * DESMARAIS_B;
    std::array::from_fn(|n| {
        let v = S::lift2(u, u, q[n], -p * q[n], 0.0);
        p *= 2.0;
        v
    })
}

/// i0 = Σ aₙ qₙ (pₙ − i k1)/(pₙ² + k1²) at u ≥ 0 and, if asked, z0, the same at u = 0: the sums
/// of [`desmarais_sums`] without the second moments, on plain numbers with the partial
/// derivatives with respect to u (∂qₙ/∂u = −pₙ qₙ) and k1 chained by hand (a third of the work of
/// dual arithmetic through every term). The values are those of `desmarais_sums` bit for bit.
fn desmarais_i0<S: KernelScalar>(u: S, k1: S, q: &[f64; 12], with_zero: bool) -> [Cplx<S>; 2] {
    let k = k1.re();
    let k2 = k * k;
    // values and ∂/∂u, ∂/∂k1 of Re i0, Im i0, Re z0, Im z0
    let (mut re, mut im, mut zre, mut zim) = (0.0, 0.0, 0.0, 0.0);
    let (mut re_u, mut re_k, mut im_u, mut im_k) = (0.0, 0.0, 0.0, 0.0);
    let (mut zre_k, mut zim_k) = (0.0, 0.0);
    let mut p = 2.0 * DESMARAIS_B;
    for (&a, &qn) in DESMARAIS_A.iter().zip(q) {
        let den = k2 + p * p;
        let inv = 1.0 / den;
        let ainv = inv * a;
        let w = qn * ainv;
        re += w * p;
        im += -(w * k);
        if S::DERIVATIVES {
            let w_u = -p * w;
            let w_k = -2.0 * k * inv * w;
            re_u += w_u * p;
            re_k += w_k * p;
            im_u += -(w_u * k);
            im_k += -(w_k * k + w);
        }
        if with_zero {
            zre += ainv * p;
            zim += -(ainv * k);
            if S::DERIVATIVES {
                let ainv_k = -2.0 * k * inv * ainv;
                zre_k += ainv_k * p;
                zim_k += -(ainv_k * k + ainv);
            }
        }
        p *= 2.0;
    }
    [
        Cplx::new(
            S::lift2(u, k1, re, re_u, re_k),
            S::lift2(u, k1, im, im_u, im_k),
        ),
        Cplx::new(
            S::lift2(u, k1, zre, 0.0, zre_k),
            S::lift2(u, k1, zim, 0.0, zim_k),
        ),
    ]
}

/// The Desmarais sums i0 = Σ aₙ e^{−pₙu}/(pₙ + i k1) and its second moment j0 (for I2) at
/// u ≥ 0 from the exponentials `q` of [`desmarais_exponentials`], and, if asked, the same at u = 0
/// (the terms 1/(pₙ² + k1²) are shared: upstream points need both). A planar pair, which needs no
/// second moments, uses [`desmarais_i0`] instead.
fn desmarais_sums<S: Scalar>(u: S, k1: S, q: &[S; 12], with_zero: bool) -> [(Cplx<S>, Cplx<S>); 2] {
    let k2 = k1 * k1;
    let (mut i0, mut j0) = (Cplx::<S>::zero(), Cplx::<S>::zero());
    let (mut z0, mut zj) = (Cplx::<S>::zero(), Cplx::<S>::zero());
    let mut p = 2.0 * DESMARAIS_B;
    for (&a, &qn) in DESMARAIS_A.iter().zip(q) {
        let den = k2 + p * p;
        let inv = S::one() / den;
        let ainv = inv * a;
        let w = qn * ainv;
        // ∫ e^{−(p + i k1) u} = e^{−(p+ik1)u}/(p + i k1): (p − i k1)/(p² + k1²)
        i0 = i0 + Cplx::new(w * p, -(w * k1));
        let wd = w * inv;
        j0 = j0
            + Cplx::new(
                wd * (S::cst(p * p) - k2 + u * den * p),
                -(wd * k1 * (S::cst(2.0 * p) + u * den)),
            );
        if with_zero {
            z0 = z0 + Cplx::new(ainv * p, -(ainv * k1));
            let wz = ainv * inv;
            zj = zj + Cplx::new(wz * (S::cst(p * p) - k2), -(wz * k1 * (2.0 * p)));
        }
        p *= 2.0;
    }
    [(i0, j0), (z0, zj)]
}

/// The Desmarais sums at u ≥ 0 ((i0, j0) and, with `with_zero`, (z0, zj) at u = 0) from the
/// exponentials' values `q`: the second moments only when `P2`.
fn sums<S: KernelScalar, const P2: bool>(
    u: S,
    k1: S,
    q: &[f64; 12],
    with_zero: bool,
) -> [(Cplx<S>, Cplx<S>); 2] {
    if P2 {
        desmarais_sums(u, k1, &exponentials_as(u, q), with_zero)
    } else {
        let [i0, z0] = desmarais_i0(u, k1, q, with_zero);
        [(i0, Cplx::zero()), (z0, Cplx::zero())]
    }
}

/// I1 and (when `P2`) I2 at u ≥ 0 from the Desmarais sums, without their common phase:
/// I = e^{−i k1 u} × bracket, so that the caller can merge that phase with another one.
fn brackets<S: Scalar, const P2: bool>(
    u: S,
    k1: S,
    i0: Cplx<S>,
    j0: Cplx<S>,
) -> (Cplx<S>, Cplx<S>) {
    let s = (u * u + 1.0).sqrt();
    let g = S::one() - u / s;
    let ik1 = Cplx::new(S::zero(), k1);
    let b1 = Cplx::real(g) - ik1 * i0;
    let b2 = if P2 {
        let two_plus = Cplx::new(S::cst(2.0), k1 * u);
        (two_plus * Cplx::real(g) - Cplx::real(u / (s * s * s)) - ik1 * i0 + j0.scale(k1 * k1))
            .scale_f(1.0 / 3.0)
    } else {
        Cplx::zero()
    };
    (b1, b2)
}

/// I1(u1, k1) and I2(u1, k1) for any u1.
pub fn integrals<S: KernelScalar>(u1: S, k1: S) -> (Cplx<S>, Cplx<S>) {
    let q = desmarais_exponentials(u1.abs().re());
    let (i1, i2, _) = integrals_and_phase::<S, true>(u1, k1, &q);
    (i1, i2)
}

/// I1(u1, k1), I2(u1, k1) (zero unless `P2`) and the phase e^{−i k1 u1} the kernel needs with
/// them; `q` are the Desmarais exponentials at |u1|.
fn integrals_and_phase<S: KernelScalar, const P2: bool>(
    u1: S,
    k1: S,
    q: &[f64; 12],
) -> (Cplx<S>, Cplx<S>, Cplx<S>) {
    if u1.re() >= 0.0 {
        let [(i0, j0), _] = sums::<S, P2>(u1, k1, q, false);
        let (b1, b2) = brackets::<S, P2>(u1, k1, i0, j0);
        let e = Cplx::expi_neg(k1 * u1);
        (e * b1, e * b2, e)
    } else {
        // u1 < 0: Re I(u1) = 2 Re I(0) − Re I(−u1), Im I(u1) = Im I(−u1)
        let neg = -u1;
        let [(i0, j0), (z0, zj)] = sums::<S, P2>(neg, k1, q, true);
        let (b1, b2) = brackets::<S, P2>(neg, k1, i0, j0);
        let e_neg = Cplx::expi_neg(k1 * neg);
        let (b1, b2) = (e_neg * b1, e_neg * b2);
        // at u1 = 0: e = 1, g = 1, u1/s³ = 0
        let ik1 = Cplx::new(S::zero(), k1);
        let a1 = Cplx::real(S::one()) - ik1 * z0;
        let i2 = if P2 {
            let a2 = (Cplx::real(S::cst(2.0)) - ik1 * z0 + zj.scale(k1 * k1)).scale_f(1.0 / 3.0);
            Cplx::new(a2.re * 2.0 - b2.re, b2.im)
        } else {
            Cplx::zero()
        };
        (
            Cplx::new(a1.re * 2.0 - b1.re, b1.im),
            i2,
            // e^{−i k1 u1} = conj(e^{−i k1 (−u1)})
            Cplx::new(e_neg.re, -e_neg.im),
        )
    }
}

/// The frequency-independent part of the incremental kernel at one point of a doublet line, so
/// that a table of frequencies reuses the geometry (square roots, u1, the steady kernels, the
/// Desmarais exponentials).
#[derive(Clone, Copy, Debug)]
pub struct KernelPoint<S> {
    x0: S,
    cos_rs: S,
    t2: S,
    kind: PointKind<S>,
}

#[derive(Clone, Copy, Debug)]
enum PointKind<S> {
    /// On the line's own streamwise axis (r1 → 0): downstream (K1, K2 → −2, 4) or upstream (0).
    Axis { downstream: bool },
    General {
        r1: S,
        u1: S,
        su: S,
        mr_r: S,
        br: S,
        k10: S,
        k20: S,
        /// x0 + r1 u1: e^{−i ω x0/U} e^{−i k1 u1} = e^{−i (ω/U) (x0 + r1 u1)}.
        xi: S,
        /// e^{−pₙ |u1|} (values).
        q: [f64; 12],
    },
}

impl<S: KernelScalar> KernelPoint<S> {
    /// `x0`, `y0`, `z0`: receiving point minus line point in the sending box's frame; `cos_rs`,
    /// `sin_rs`: of γr − γs.
    pub fn new(x0: S, y0: S, z0: S, cos_rs: S, sin_rs: S, mach: f64) -> Self {
        let r1sq = y0 * y0 + z0 * z0;
        let t2 = z0 * (z0 * cos_rs - y0 * sin_rs);
        let scale = x0.abs().re().max(1e-300);
        let kind = if r1sq.re() <= (1e-12 * scale).powi(2) {
            PointKind::Axis {
                downstream: x0.re() >= 0.0,
            }
        } else {
            let beta2 = 1.0 - mach * mach;
            let r1 = r1sq.sqrt();
            let big_r = (x0 * x0 + r1sq * beta2).sqrt();
            let u1 = (big_r * mach - x0) / (r1 * beta2);
            let xr = x0 / big_r;
            let br = r1sq * beta2 / (big_r * big_r);
            PointKind::General {
                r1,
                u1,
                su: (u1 * u1 + 1.0).sqrt(),
                mr_r: r1 * mach / big_r,
                br,
                k10: -xr - 1.0,
                k20: xr * (br + 2.0) + 2.0,
                xi: x0 + r1 * u1,
                q: desmarais_exponentials(u1.abs().re()),
            }
        };
        Self {
            x0,
            cos_rs,
            t2,
            kind,
        }
    }

    /// Numerators (P1, P2) at ω/U = `kd`.
    pub fn numerators(&self, kd: f64) -> (Cplx<S>, Cplx<S>) {
        self.numerators_with::<true>(kd)
    }

    /// P1 alone at ω/U = `kd` (P2 returned as zero), for a planar pair: the quartic integrals
    /// of a planar pair never use P2, so neither I2 nor K2 is formed.
    pub fn numerator_p1(&self, kd: f64) -> Cplx<S> {
        self.numerators_with::<false>(kd).0
    }

    fn numerators_with<const P2: bool>(&self, kd: f64) -> (Cplx<S>, Cplx<S>) {
        let (k1v_e, k2v_e, k10, k20) = match self.kind {
            PointKind::Axis { downstream: true } => {
                let e = Cplx::expi_neg(self.x0 * kd);
                (e.scale_f(-2.0), e.scale_f(4.0), S::cst(-2.0), S::cst(4.0))
            }
            PointKind::Axis { downstream: false } => {
                (Cplx::zero(), Cplx::zero(), S::zero(), S::zero())
            }
            PointKind::General {
                r1,
                u1,
                su,
                mr_r,
                br,
                k10,
                k20,
                xi,
                ref q,
            } => {
                let k1 = r1 * kd;
                // K2's own terms over the common phase e^{−i k1 u1}
                let k2_rest = || {
                    Cplx::new(S::zero(), k1).scale(mr_r * mr_r / su)
                        + Cplx::real(
                            mr_r * ((u1 * u1 + 1.0) * br + 2.0 + mr_r * u1) / (su * su * su),
                        )
                };
                if u1.re() >= 0.0 {
                    // every term carries e^{−i k1 u1}: one phase with e^{−i ω x0/U}
                    let [(i0, j0), _] = sums::<S, P2>(u1, k1, q, false);
                    let (b1, b2) = brackets::<S, P2>(u1, k1, i0, j0);
                    let phase = Cplx::expi_neg(xi * kd);
                    let k1v = phase * (-b1 - Cplx::real(mr_r / su));
                    let k2v = if P2 {
                        phase * (b2.scale_f(3.0) + k2_rest())
                    } else {
                        Cplx::zero()
                    };
                    (k1v, k2v, k10, k20)
                } else {
                    let e = Cplx::expi_neg(self.x0 * kd);
                    let (i1, i2, ek) = integrals_and_phase::<S, P2>(u1, k1, q);
                    let k1v = (-i1 - ek.scale(mr_r / su)) * e;
                    let k2v = if P2 {
                        (i2.scale_f(3.0) + ek * k2_rest()) * e
                    } else {
                        Cplx::zero()
                    };
                    (k1v, k2v, k10, k20)
                }
            }
        };
        let p1 = -(k1v_e - Cplx::real(k10)).scale(self.cos_rs);
        let p2 = if P2 {
            -(k2v_e - Cplx::real(k20)).scale(self.t2)
        } else {
            Cplx::zero()
        };
        (p1, p2)
    }
}

/// Numerators (P1, P2) of the incremental kernel at one point of a doublet line.
///
/// `x0`, `y0`, `z0`: receiving point minus line point, in the sending box's local frame (z̄ along
/// its normal); `cos_rs`, `sin_rs`: cos and sin of γr − γs; `kd` = ω/U (1/m).
pub fn incremental_numerators<S: KernelScalar>(
    x0: S,
    y0: S,
    z0: S,
    cos_rs: S,
    sin_rs: S,
    kd: f64,
    mach: f64,
) -> (Cplx<S>, Cplx<S>) {
    KernelPoint::new(x0, y0, z0, cos_rs, sin_rs, mach).numerators(kd)
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_complex::Complex64;

    /// Composite Simpson quadrature of e^{−i k u}(1+u²)^{−p} from u1 to a large bound (the tail
    /// beyond decays like u^{1−2p}).
    fn quad(u1: f64, k: f64, p: f64) -> Complex64 {
        let upper = 2000.0;
        let n = 2_000_000;
        let h = (upper - u1) / n as f64;
        let f = |u: f64| Complex64::new(0.0, -k * u).exp() * (1.0 + u * u).powf(-p);
        let mut s = f(u1) + f(upper);
        for i in 1..n {
            let w = if i % 2 == 1 { 4.0 } else { 2.0 };
            s += f(u1 + i as f64 * h) * w;
        }
        // tail ∫_U^∞ e^{-iku} u^{-2p} du ≈ e^{-ikU} U^{-2p} / (ik) (leading term)
        let tail =
            Complex64::new(0.0, -k * upper).exp() * upper.powf(-2.0 * p) / Complex64::new(0.0, k);
        s * h / 3.0 + tail
    }

    /// The Desmarais approximations of I1 and I2 against direct quadrature, for u1 of both signs
    /// and k1 from 0.1 to 3: the approximation is good to about 1e-4 absolute.
    #[test]
    fn integrals_match_quadrature() {
        for &u1 in &[-3.0, -0.5, 0.0, 0.4, 2.5] {
            for &k1 in &[0.1, 0.8, 3.0] {
                let (i1, i2) = integrals::<f64>(u1, k1);
                let (q1, q2) = (quad(u1, k1, 1.5), quad(u1, k1, 2.5));
                assert!(
                    (i1.value() - q1).norm() < 2e-4,
                    "I1 u1={u1} k1={k1}: {:?} vs {q1}",
                    i1.value()
                );
                assert!(
                    (i2.value() - q2).norm() < 2e-4,
                    "I2 u1={u1} k1={k1}: {:?} vs {q2}",
                    i2.value()
                );
            }
        }
    }

    /// The Desmarais sums on plain numbers with hand-chained partials (desmarais_i0) give the
    /// values of the dual-number sums bit for bit and their derivatives with respect to u and
    /// k1 to 1e-13 of their size (both are exact; only the order of the roundings differs).
    #[test]
    fn lifted_sums_match_dual_sums() {
        for &u in &[0.0, 0.03, 0.7, 4.0, 40.0] {
            for &k in &[0.05, 0.9, 6.0] {
                let ud = Dual::<2>::new(u, [1.0, 0.0]);
                let kd = Dual::<2>::new(k, [0.0, 1.0]);
                let q = desmarais_exponentials(u);
                let [i0, z0] = desmarais_i0(ud, kd, &q, true);
                let qd: [Dual<2>; 12] = {
                    let mut qd = [Dual::<2>::cst(0.0); 12];
                    qd[0] = (ud * (-2.0 * DESMARAIS_B)).exp();
                    for n in 1..12 {
                        qd[n] = qd[n - 1] * qd[n - 1];
                    }
                    qd
                };
                let [(j0, _), (zz, _)] = desmarais_sums::<Dual<2>>(ud, kd, &qd, true);
                for (a, b) in [
                    (i0.re, j0.re),
                    (i0.im, j0.im),
                    (z0.re, zz.re),
                    (z0.im, zz.im),
                ] {
                    assert_eq!(a.v, b.v, "u {u} k {k}");
                    let scale = b.d[0].abs().max(b.d[1].abs()).max(1e-300);
                    for d in 0..2 {
                        assert!(
                            (a.d[d] - b.d[d]).abs() <= 1e-13 * scale,
                            "u {u} k {k} direction {d}: {} vs {}",
                            a.d[d],
                            b.d[d]
                        );
                    }
                }
            }
        }
    }

    /// P1 alone (the planar path) equals the P1 of the full numerators, for points upstream,
    /// downstream and on the axis, in values and in dual derivatives.
    #[test]
    fn p1_alone_matches_full_numerators() {
        for (x0, y0) in [
            (0.3, 0.2),
            (-0.5, 0.1),
            (0.7, 0.0),
            (-0.2, 0.0),
            (2.0, -0.4),
        ] {
            let p = KernelPoint::new(
                Dual::<1>::new(x0, [1.0]),
                Dual::<1>::new(y0, [0.5]),
                Dual::<1>::cst(0.0),
                Dual::<1>::cst(1.0),
                Dual::<1>::cst(0.0),
                0.5,
            );
            for kd in [0.1, 1.3, 7.0] {
                let a = p.numerator_p1(kd);
                let (b, _) = p.numerators(kd);
                for (x, y) in [(a.re, b.re), (a.im, b.im)] {
                    assert!((x.v - y.v).abs() <= 1e-14 * y.v.abs().max(1e-3));
                    assert!((x.d[0] - y.d[0]).abs() <= 1e-12 * y.d[0].abs().max(1e-3));
                }
            }
        }
    }

    /// The incremental kernel vanishes at ω = 0 (the steady part belongs to the vortex lattice).
    #[test]
    fn increment_vanishes_when_steady() {
        for (x0, y0, z0) in [(0.3, 0.2, 0.0), (-0.5, 0.1, 0.05), (0.7, 0.0, 0.0)] {
            let (p1, p2) = incremental_numerators::<f64>(x0, y0, z0, 1.0, 0.0, 0.0, 0.5);
            assert!(p1.value().norm() < 1e-12 && p2.value().norm() < 1e-12);
        }
    }
}
