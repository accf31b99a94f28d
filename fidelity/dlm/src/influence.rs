//! Normalwash influence of a box's pressure jump: D = D0 (steady horseshoe vortex) + D1 + D2
//! (oscillatory increment, quartic approximation of Rodden, Taylor & McIntosh 1998).
//!
//! Convention: w_r / U = D_rs ΔCp_s, with w the normalwash along the receiving box's normal
//! (positive with the normal) and ΔCp = (p_lower − p_upper)/q, positive for a force along the
//! sending box's normal. A lifting box therefore has D < 0 behind it (downwash).

use crate::cplx::Cplx;
use crate::geometry::AeroBox;
use crate::kernel::{KernelPoint, KernelScalar};
use gustkit_core::scalar::Scalar;
use std::f64::consts::PI;

/// Induced velocity per unit circulation of a horseshoe vortex: bound segment a → b, trailing legs
/// from b to +∞ and from +∞ to a along +x (Biot–Savart). Written in the forms
/// (r1 × r2)(|r1| + |r2|) / (|r1||r2| (|r1||r2| + r1·r2)) for the segment and
/// (x̂ × r) / (|r| (|r| − x̂·r)) for a leg, which vanish without 0/0 on the lines' extensions and
/// are singular only on the vortex lines themselves (cut off there).
fn horseshoe<S: Scalar>(p: [S; 3], a: [S; 3], b: [S; 3], tiny: f64) -> [S; 3] {
    let sub = |u: [S; 3], v: [S; 3]| [u[0] - v[0], u[1] - v[1], u[2] - v[2]];
    let dot = |u: [S; 3], v: [S; 3]| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
    let r1 = sub(p, a);
    let r2 = sub(p, b);
    let (n1, n2) = (dot(r1, r1).sqrt(), dot(r2, r2).sqrt());
    let mut v = [S::zero(); 3];
    let den = n1 * n2 * (n1 * n2 + dot(r1, r2));
    if n1.re() > tiny && n2.re() > tiny && den.re() > tiny * tiny * (n1 * n2).re() {
        let c = [
            r1[1] * r2[2] - r1[2] * r2[1],
            r1[2] * r2[0] - r1[0] * r2[2],
            r1[0] * r2[1] - r1[1] * r2[0],
        ];
        let f = (n1 + n2) / (den * (4.0 * PI));
        for i in 0..3 {
            v[i] += c[i] * f;
        }
    }
    // leg from q to +∞ (s = +1) or from +∞ to q (s = −1); x̂ × r = (0, −r_z, r_y)
    let mut leg = |r: [S; 3], n: S, s: f64| {
        // |r| − r_x without cancellation downstream: (r_y² + r_z²) / (|r| + r_x)
        let gap = if r[0].re() > 0.0 {
            (r[1] * r[1] + r[2] * r[2]) / (n + r[0])
        } else {
            n - r[0]
        };
        let den = n * gap;
        if n.re() > tiny && den.re() > tiny * tiny {
            let f = S::cst(s) / (den * (4.0 * PI));
            v[1] += -r[2] * f;
            v[2] += r[1] * f;
        }
    };
    leg(r2, n2, 1.0);
    leg(r1, n1, -1.0);
    v
}

/// Steady influence D0 of sending box `s` at the control point of receiving box `r`: the
/// incompressible horseshoe on the Prandtl–Glauert stretched geometry (x / β), times chord/2.
pub fn steady_influence<S: Scalar>(r: &AeroBox<S>, s: &AeroBox<S>, mach: f64) -> S {
    let beta = (1.0 - mach * mach).sqrt();
    let st = |p: [S; 3]| [p[0] / beta, p[1], p[2]];
    let tiny = 1e-10 * s.e.re().max(1e-300);
    let v = horseshoe(st(r.cp), st(s.line_a), st(s.line_b), tiny);
    let n = r.normal();
    (v[0] * n[0] + v[1] * n[1] + v[2] * n[2]) * s.chord * 0.5
}

/// P1 at one end of a doublet line, handed from one box pair to the next: spanwise neighbours in
/// a chordwise row of one surface share a line end (the same point, computed the same way), so
/// its kernel is evaluated once for both.
pub struct SharedEnd<'a, S> {
    /// P1 at every kd: read at `given` (when set) and overwritten with this pair's P1 at `kept`.
    pub p1: &'a mut [Cplx<S>],
    /// The point (0: η = −e, 4: η = +e) whose P1 the previous pair left, if any.
    pub given: Option<usize>,
    /// The point whose P1 this pair leaves for the next.
    pub kept: usize,
}

/// Oscillatory increments of `s` at the control point of `r` for several kd = ω/U at once (the
/// geometry, the kernel's frequency-independent parts and the quartic integrals' weights are
/// computed once); kd = 0 gives zero.
pub fn oscillatory_influences<S: KernelScalar>(
    r: &AeroBox<S>,
    s: &AeroBox<S>,
    mach: f64,
    kds: &[f64],
    out: &mut [Cplx<S>],
) {
    oscillatory_influences_shared(r, s, mach, kds, out, None);
}

/// [`oscillatory_influences`] with one line end's P1 taken from the previous pair and another's
/// left for the next (see [`SharedEnd`]; a planar pair takes it, any pair leaves it).
pub fn oscillatory_influences_shared<S: KernelScalar>(
    r: &AeroBox<S>,
    s: &AeroBox<S>,
    mach: f64,
    kds: &[f64],
    out: &mut [Cplx<S>],
    mut shared: Option<SharedEnd<'_, S>>,
) {
    // receiving point relative to the doublet line's mid-point, in the sending box's frame
    let mid = [
        (s.line_a[0] + s.line_b[0]) * 0.5,
        (s.line_a[1] + s.line_b[1]) * 0.5,
        (s.line_a[2] + s.line_b[2]) * 0.5,
    ];
    let frame = |p: [S; 3]| {
        let (xs, ys, zs) = (r.cp[0] - p[0], r.cp[1] - p[1], r.cp[2] - p[2]);
        (xs, ys * s.cos_g + zs * s.sin_g, zs * s.cos_g - ys * s.sin_g)
    };
    let (xs, yb, zb) = frame(mid);
    // relative dihedral γr − γs
    let cos_rs = r.cos_g * s.cos_g + r.sin_g * s.sin_g;
    let sin_rs = r.sin_g * s.cos_g - r.cos_g * s.sin_g;
    let e = s.e;
    let weights = QuarticWeights::new(yb, zb, e);
    let given = shared
        .as_ref()
        .and_then(|sh| sh.given)
        .filter(|_| weights.planar);
    let etas = [-1.0, -0.5, 0.0, 0.5, 1.0];
    let points: [Option<KernelPoint<S>>; 5] = std::array::from_fn(|i| {
        if given == Some(i) {
            return None;
        }
        // the ends from the line's end points themselves, so that neighbours sharing an end
        // see the same numbers
        let (x0, y0, z0) = match i {
            0 => frame(s.line_a),
            4 => frame(s.line_b),
            _ => {
                let eta = e * etas[i];
                (xs - eta * s.tan_sweep, yb - eta, zb)
            }
        };
        Some(KernelPoint::new(x0, y0, z0, cos_rs, sin_rs, mach))
    });
    for (ik, (o, &kd)) in out.iter_mut().zip(kds).enumerate() {
        if kd == 0.0 {
            *o = Cplx::zero();
            if let Some(sh) = shared.as_mut() {
                sh.p1[ik] = Cplx::zero();
            }
            continue;
        }
        if weights.planar {
            // a planar pair's integral has no P2 term: neither I2 nor K2 is formed
            let p1: [Cplx<S>; 5] = std::array::from_fn(|i| match &points[i] {
                Some(pt) => pt.numerator_p1(kd),
                None => shared.as_ref().expect("a given end is shared").p1[ik],
            });
            if let Some(sh) = shared.as_mut() {
                sh.p1[ik] = p1[sh.kept];
            }
            *o = weights
                .integrate_planar(&quartic_fit(&p1, e), yb, zb, e)
                .scale(s.chord);
        } else {
            let mut p1 = [Cplx::<S>::zero(); 5];
            let mut p2 = [Cplx::<S>::zero(); 5];
            for (i, pt) in points.iter().enumerate() {
                let (a, b) = pt
                    .as_ref()
                    .expect("every point of a non-planar pair")
                    .numerators(kd);
                p1[i] = a;
                p2[i] = b;
            }
            if let Some(sh) = shared.as_mut() {
                sh.p1[ik] = p1[sh.kept];
            }
            *o = weights
                .integrate(&quartic_fit(&p1, e), &quartic_fit(&p2, e), yb, zb, e)
                .scale(s.chord);
        }
    }
}

/// Coefficients (A, B, C, D, E) of P(η) ≈ A η² + B η + C + D η³ + E η⁴ through the values at
/// η = −e, −e/2, 0, e/2, e.
pub type Quartic<S> = (Cplx<S>, Cplx<S>, Cplx<S>, Cplx<S>, Cplx<S>);

/// The quartic through five equally spaced values on [−e, e].
pub fn quartic_fit<S: Scalar>(p: &[Cplx<S>; 5], e: S) -> Quartic<S> {
    let [pm, pmh, p0, pph, pp] = *p;
    let e2 = e * e;
    let a = (pm - pmh.scale_f(16.0) + p0.scale_f(30.0) - pph.scale_f(16.0) + pp)
        .scale(-S::one() / (e2 * 6.0));
    let b = (pm - pmh.scale_f(8.0) + pph.scale_f(8.0) - pp).scale(S::one() / (e * 6.0));
    let d = (pm - pmh.scale_f(2.0) + pph.scale_f(2.0) - pp).scale(S::cst(-2.0) / (e2 * e * 3.0));
    let ee = (pm - pmh.scale_f(4.0) + p0.scale_f(6.0) - pph.scale_f(4.0) + pp)
        .scale(S::cst(2.0) / (e2 * e2 * 3.0));
    (a, b, p0, d, ee)
}

/// (1/8π) [∫ P1(η)/r1² dη + ∫ P2(η)/r1⁴ dη] over [−e, e] in closed form for quartic numerators,
/// r1² = (ȳ − η)² + z̄² (the planar finite part when |z̄| ≤ 0.001 e, where P2 vanishes).
pub fn integrate_quartics<S: Scalar>(
    q1: &Quartic<S>,
    q2: &Quartic<S>,
    yb: S,
    zb: S,
    e: S,
) -> Cplx<S> {
    QuarticWeights::new(yb, zb, e).integrate(q1, q2, yb, zb, e)
}

/// The frequency-independent transcendental parts of the quartic integrals of one pair:
/// L = ln(((ȳ−e)² + z̄²)/((ȳ+e)² + z̄²)) and F = ∫ dη / ((ȳ−η)² + z̄²) (the finite part when
/// planar, |z̄| ≤ 0.001 e).
pub struct QuarticWeights<S> {
    f: S,
    lg: S,
    planar: bool,
}

impl<S: Scalar> QuarticWeights<S> {
    pub fn new(yb: S, zb: S, e: S) -> Self {
        let (y2, z2, e2) = (yb * yb, zb * zb, e * e);
        let planar = zb.abs().re() <= 1e-3 * e.re();
        let lg = (((yb - e) * (yb - e) + z2) / ((yb + e) * (yb + e) + z2)).ln();
        let f = if planar {
            e * 2.0 / (y2 - e2)
        } else {
            let za = zb.abs();
            (za * e * 2.0).atan2(y2 + z2 - e2) / za
        };
        Self { f, lg, planar }
    }

    /// The integrals of [`integrate_quartics`] with these weights.
    pub fn integrate(&self, q1: &Quartic<S>, q2: &Quartic<S>, yb: S, zb: S, e: S) -> Cplx<S> {
        let total = self.integrate_planar(q1, yb, zb, e);
        if self.planar {
            total
        } else {
            total + nonplanar_part(q2, yb, zb, e, self.f, self.lg)
        }
    }

    /// The P1 part of [`Self::integrate`] alone: the whole integral of a planar pair.
    pub fn integrate_planar(&self, q1: &Quartic<S>, yb: S, zb: S, e: S) -> Cplx<S> {
        let y2 = yb * yb;
        let z2 = zb * zb;
        let e2 = e * e;
        let (f, lg) = (self.f, self.lg);
        let (a1, b1, c1, d1, e1) = *q1;
        let y4 = y2 * y2;
        let z4 = z2 * z2;
        let planar_part = (a1.scale(y2 - z2)
            + b1.scale(yb)
            + c1
            + d1.scale(yb * (y2 - z2 * 3.0))
            + e1.scale(y4 - y2 * z2 * 6.0 + z4))
        .scale(f)
            + (b1.scale_f(0.5)
                + a1.scale(yb)
                + d1.scale((y2 * 3.0 - z2) * 0.5)
                + e1.scale(yb * (y2 - z2) * 2.0))
            .scale(lg)
            + (a1 + d1.scale(yb * 2.0) + e1.scale(y2 * 3.0 - z2 + e2 / 3.0)).scale(e * 2.0);
        planar_part.scale_f(1.0 / (8.0 * PI))
    }
}

/// Non-planar part D2 / chord: ∫ P2(η)/r1⁴ dη / (8π) for the quartic P2 (Rodden et al. 1998,
/// Eqs. 33–34, switching on |2 e z̄ / (ȳ² + z̄² − e²)| for numerical accuracy).
fn nonplanar_part<S: Scalar>(coef: &Quartic<S>, yb: S, zb: S, e: S, f: S, lg: S) -> Cplx<S> {
    let (a2, b2, c2, d2, e2c) = *coef;
    let (y2, z2, e2) = (yb * yb, zb * zb, e * e);
    let (y4, z4, e4) = (y2 * y2, z2 * z2, e2 * e2);
    let sum = y2 + z2 - e2;
    let ratio = (e * zb.abs() * 2.0) / sum;
    let inv_ratio_small = sum.abs().re() <= 0.1 * (e * zb.abs() * 2.0).re();
    let poly = a2.scale(y2 + z2)
        + b2.scale(yb)
        + c2
        + d2.scale(yb * (y2 + z2 * 3.0))
        + e2c.scale(y4 + y2 * z2 * 6.0 - z4 * 3.0);
    if inv_ratio_small {
        let rp = (yb + e) * (yb + e) + z2;
        let rm = (yb - e) * (yb - e) + z2;
        let plus = a2.scale((y2 + z2) * yb + (y2 - z2) * e)
            + b2.scale(y2 + z2 + yb * e)
            + c2.scale(yb + e)
            + d2.scale(y4 - z4 + (y2 - z2 * 3.0) * yb * e)
            + e2c.scale((y4 - y2 * z2 * 2.0 - z4 * 3.0) * yb + (y4 - y2 * z2 * 6.0 + z4) * e);
        let minus = a2.scale((y2 + z2) * yb - (y2 - z2) * e)
            + b2.scale(y2 + z2 - yb * e)
            + c2.scale(yb - e)
            + d2.scale(y4 - z4 - (y2 - z2 * 3.0) * yb * e)
            + e2c.scale((y4 - y2 * z2 * 2.0 - z4 * 3.0) * yb - (y4 - y2 * z2 * 6.0 + z4) * e);
        (poly.scale(f) + plus.scale(S::one() / rp) - minus.scale(S::one() / rm)
            + d2.scale(z2 * lg)
            + e2c.scale((e + yb * lg) * z2 * 4.0))
        .scale(S::one() / (z2 * (16.0 * PI)))
    } else {
        // ε of Rodden 1998 Eqs. 24–25: e²/z̄² (1 − atan(r)/r), r = 2e|z̄|/(ȳ²+z̄²−e²), by its
        // series where |r| is small (the closed form cancels there)
        let _ = f;
        let d2f = if sum.re() < 0.0 { PI } else { 0.0 };
        let eps = if ratio.abs().re() <= 0.3 {
            let r2 = ratio * ratio;
            let mut series = S::zero();
            let mut rp = S::one();
            for n in 2..8 {
                let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
                series += rp * (sign / (2.0 * n as f64 - 1.0));
                rp *= r2;
            }
            e4 * 4.0 / (sum * sum) * series
        } else {
            e2 / z2 * (S::one() - ratio.atan() / ratio)
        };
        let rp = (yb + e) * (yb + e) + z2;
        let rm = (yb - e) * (yb - e) + z2;
        let big = (a2.scale(e2) + c2).scale((y2 + z2 + e2) * 2.0)
            + b2.scale(yb * e2 * 4.0)
            + d2.scale(
                yb * (y4 - e2 * y2 * 2.0 + y2 * z2 * 2.0 + e4 * 3.0 + e2 * z2 * 2.0 + z4) * 2.0,
            )
            + e2c.scale(
                (y4 * y2 * 3.0 - e2 * y4 * 7.0
                    + y4 * z2 * 5.0
                    + e4 * y2 * 6.0
                    + e2 * y2 * z2 * 6.0
                    - e2 * z4 * 3.0
                    - z4 * z2
                    + y2 * z4
                    - e4 * z2 * 2.0)
                    * 2.0,
            );
        let corr = (eps + e2 / z2 * (-S::cst(d2f) / ratio)) / e2;
        (big.scale(S::one() / (rp * rm)) - poly.scale(corr)).scale(e / (sum * (8.0 * PI)))
            + (d2.scale(lg * 0.5) + e2c.scale((e + yb * lg) * 2.0)).scale(S::cst(1.0 / (8.0 * PI)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A lone horseshoe against the closed form for the downwash on its own mid-span far behind
    /// (2-D vortex pair): far downstream the two trailing legs of span 2e give w = −Γ/(π e)... and
    /// directly at a point 1 chord behind, Biot–Savart summed by hand.
    #[test]
    fn horseshoe_midspan_downwash() {
        let a = [0.0, -0.5, 0.0];
        let b = [0.0, 0.5, 0.0];
        // far downstream: two semi-infinite... becomes two infinite lines: w = −2 Γ/(2π e) = −Γ/(π e)
        let v = horseshoe([1e6, 0.0, 0.0], a, b, 1e-12);
        assert!((v[2] + 1.0 / (PI * 0.5)).abs() < 1e-6, "{v:?}");
        // at x = 1 on the centreline: bound segment −(1/4π)(2·0.5/√1.25)/1 ... closed form
        let v = horseshoe([1.0, 0.0, 0.0], a, b, 1e-12);
        let bound = -1.0 / (4.0 * PI) * (2.0 * 0.5 / 1.25f64.sqrt());
        let legs = -2.0 / (4.0 * PI * 0.5) * (1.0 + 1.0 / 1.25f64.sqrt());
        assert!((v[2] - (bound + legs)).abs() < 1e-12, "{v:?}");
    }

    /// The closed-form integrals of quartic numerators against Simpson quadrature, planar and
    /// non-planar, in both regimes of the non-planar formula (|r| small and large), to 1e-7.
    #[test]
    fn quartic_integrals_match_quadrature() {
        use num_complex::Complex64;
        let c = |re: f64, im: f64| Cplx::new(re, im);
        let q1 = (
            c(0.3, -0.2),
            c(-0.1, 0.4),
            c(0.7, 0.1),
            c(0.05, -0.3),
            c(-0.2, 0.15),
        );
        let q2 = (
            c(-0.4, 0.1),
            c(0.2, 0.3),
            c(0.5, -0.6),
            c(0.1, 0.2),
            c(0.3, -0.1),
        );
        let eval = |q: &Quartic<f64>, eta: f64| {
            let (a, b, cc, d, e) = *q;
            a.value() * eta * eta
                + b.value() * eta
                + cc.value()
                + d.value() * eta.powi(3)
                + e.value() * eta.powi(4)
        };
        let e = 0.5;
        for (yb, zb) in [
            (1.3, 0.4),
            (0.2, 0.3),
            (0.45, 0.05),
            (2.5, 1.5),
            (0.6, 0.002),
            (-0.9, 0.7),
        ] {
            let got = integrate_quartics(&q1, &q2, yb, zb, e).value();
            let n = 200_000;
            let h = 2.0 * e / n as f64;
            let mut acc = Complex64::new(0.0, 0.0);
            for i in 0..=n {
                let eta = -e + i as f64 * h;
                let r2 = (yb - eta).powi(2) + zb * zb;
                let w = if i == 0 || i == n {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                acc += (eval(&q1, eta) / r2 + eval(&q2, eta) / (r2 * r2)) * w;
            }
            let expect = acc * h / 3.0 / (8.0 * PI);
            assert!(
                (got - expect).norm() < 1e-7 * expect.norm().max(1.0),
                "ȳ={yb} z̄={zb}: {got} vs {expect}"
            );
        }
    }
}
