//! Hyper-dual numbers for exact mixed second derivatives: x = v + Σ a_i ε_i + Σ b_m δ_m +
//! Σ ab_mi ε_i δ_m with every product of two ε or two δ zero (ε_i ε_j = δ_m δ_n = 0). A kernel written over [`Scalar`] and run on them gives, in the
//! `ab` parts, the derivative along δ of its directional derivatives along the ε_i, without
//! truncation error. The LFD's planform sensitivities use them: the ε parts carry the (real and
//! imaginary) LFD perturbation, δ the planform direction, so `ab` is the planform derivative of
//! the linearized residual and forces (paper Eq. 19's second-derivative terms); with M second
//! directions one evaluation gives the derivatives along M planform variables at once.

use crate::scalar::Scalar;
use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// A hyper-dual number with `N` first directions ε and `M` second directions δ (`ab[m][i]`:
/// the ε_i δ_m part).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HyperDual<const N: usize, const M: usize = 1> {
    pub v: f64,
    pub a: [f64; N],
    pub b: [f64; M],
    pub ab: [[f64; N]; M],
}

impl<const N: usize, const M: usize> HyperDual<N, M> {
    pub fn new(v: f64, a: [f64; N], b: [f64; M], ab: [[f64; N]; M]) -> Self {
        Self { v, a, b, ab }
    }

    /// f(x) from f(v), f'(v), f''(v).
    #[inline]
    fn chain(self, f: f64, f1: f64, f2: f64) -> Self {
        Self {
            v: f,
            a: self.a.map(|x| f1 * x),
            b: self.b.map(|x| f1 * x),
            ab: std::array::from_fn(|m| {
                std::array::from_fn(|i| f1 * self.ab[m][i] + f2 * self.a[i] * self.b[m])
            }),
        }
    }

    fn recip(self) -> Self {
        let r = 1.0 / self.v;
        self.chain(r, -r * r, 2.0 * r * r * r)
    }
}

impl<const N: usize, const M: usize> PartialOrd for HyperDual<N, M> {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        self.v.partial_cmp(&other.v)
    }
}

impl<const N: usize, const M: usize> Add for HyperDual<N, M> {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        Self {
            v: self.v + o.v,
            a: std::array::from_fn(|i| self.a[i] + o.a[i]),
            b: std::array::from_fn(|m| self.b[m] + o.b[m]),
            ab: std::array::from_fn(|m| std::array::from_fn(|i| self.ab[m][i] + o.ab[m][i])),
        }
    }
}
impl<const N: usize, const M: usize> Sub for HyperDual<N, M> {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        self + (-o)
    }
}
impl<const N: usize, const M: usize> Mul for HyperDual<N, M> {
    type Output = Self;
    #[inline]
    #[allow(clippy::suspicious_arithmetic_impl)] // the product rule sums its parts
    fn mul(self, o: Self) -> Self {
        Self {
            v: self.v * o.v,
            a: std::array::from_fn(|i| self.a[i] * o.v + self.v * o.a[i]),
            b: std::array::from_fn(|m| self.b[m] * o.v + self.v * o.b[m]),
            ab: std::array::from_fn(|m| {
                std::array::from_fn(|i| {
                    self.ab[m][i] * o.v
                        + self.a[i] * o.b[m]
                        + self.b[m] * o.a[i]
                        + self.v * o.ab[m][i]
                })
            }),
        }
    }
}
impl<const N: usize, const M: usize> Div for HyperDual<N, M> {
    type Output = Self;
    #[inline]
    #[allow(clippy::suspicious_arithmetic_impl)]
    fn div(self, o: Self) -> Self {
        // x / y = x · (1/y), the reciprocal with its own second derivative
        self * o.recip()
    }
}
impl<const N: usize, const M: usize> Neg for HyperDual<N, M> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self {
            v: -self.v,
            a: self.a.map(|x| -x),
            b: self.b.map(|x| -x),
            ab: self.ab.map(|r| r.map(|x| -x)),
        }
    }
}
impl<const N: usize, const M: usize> AddAssign for HyperDual<N, M> {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}
impl<const N: usize, const M: usize> SubAssign for HyperDual<N, M> {
    #[inline]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}
impl<const N: usize, const M: usize> MulAssign for HyperDual<N, M> {
    #[inline]
    fn mul_assign(&mut self, o: Self) {
        *self = *self * o;
    }
}
impl<const N: usize, const M: usize> Add<f64> for HyperDual<N, M> {
    type Output = Self;
    #[inline]
    fn add(mut self, o: f64) -> Self {
        self.v += o;
        self
    }
}
impl<const N: usize, const M: usize> Sub<f64> for HyperDual<N, M> {
    type Output = Self;
    #[inline]
    fn sub(mut self, o: f64) -> Self {
        self.v -= o;
        self
    }
}
impl<const N: usize, const M: usize> Mul<f64> for HyperDual<N, M> {
    type Output = Self;
    #[inline]
    fn mul(self, o: f64) -> Self {
        Self {
            v: self.v * o,
            a: self.a.map(|x| x * o),
            b: self.b.map(|x| x * o),
            ab: self.ab.map(|r| r.map(|x| x * o)),
        }
    }
}
impl<const N: usize, const M: usize> Div<f64> for HyperDual<N, M> {
    type Output = Self;
    #[inline]
    fn div(self, o: f64) -> Self {
        self * (1.0 / o)
    }
}

impl<const N: usize, const M: usize> Scalar for HyperDual<N, M> {
    #[inline]
    fn cst(v: f64) -> Self {
        Self {
            v,
            a: [0.0; N],
            b: [0.0; M],
            ab: [[0.0; N]; M],
        }
    }
    #[inline]
    fn re(self) -> f64 {
        self.v
    }
    fn sqrt(self) -> Self {
        let s = self.v.sqrt();
        self.chain(s, 0.5 / s, -0.25 / (s * self.v))
    }
    fn sin(self) -> Self {
        let (s, c) = self.v.sin_cos();
        self.chain(s, c, -s)
    }
    fn cos(self) -> Self {
        let (s, c) = self.v.sin_cos();
        self.chain(c, -s, -c)
    }
    fn tan(self) -> Self {
        let t = self.v.tan();
        let d = 1.0 + t * t;
        self.chain(t, d, 2.0 * t * d)
    }
    fn atan2(self, x: Self) -> Self {
        // atan(y/x) or π/2 − atan(x/y): the same derivatives as atan2, the value from atan2
        let value = self.v.atan2(x.v);
        let t = if x.v.abs() >= self.v.abs() {
            (self / x).atan()
        } else {
            -(x / self).atan()
        };
        Self { v: value, ..t }
    }
    fn powi(self, n: i32) -> Self {
        let f1 = if n == 0 {
            0.0
        } else {
            n as f64 * self.v.powi(n - 1)
        };
        let f2 = if n == 0 || n == 1 {
            0.0
        } else {
            (n * (n - 1)) as f64 * self.v.powi(n - 2)
        };
        self.chain(self.v.powi(n), f1, f2)
    }
    fn exp(self) -> Self {
        let e = self.v.exp();
        self.chain(e, e, e)
    }
    fn ln(self) -> Self {
        let r = 1.0 / self.v;
        self.chain(self.v.ln(), r, -r * r)
    }
    fn atan(self) -> Self {
        let d = 1.0 / (1.0 + self.v * self.v);
        self.chain(self.v.atan(), d, -2.0 * self.v * d * d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scalar::Dual;

    fn kernel<S: Scalar>(x: &[S; 2]) -> S {
        let a = x[0] * x[1] + x[1].sin() * x[0].cos() - x[1] / (x[0] + 3.0);
        let b = (x[0] * x[0] + x[1] * x[1]).sqrt().ln() * x[1].exp()
            + x[1].atan2(x[0])
            + x[0].atan2(x[1] * 0.1)
            + x[1].tan()
            + x[0].powi(3)
            - x[1].atan() * 2.0;
        a * b + (a - b).abs()
    }

    /// The ab part is the δ-derivative of the ε-derivative: against central differences (step
    /// 1e-5) of dual-number directional derivatives, to 1e-8; the a and b parts equal the dual
    /// numbers' to round-off.
    #[test]
    fn mixed_second_derivatives() {
        let x0 = [0.7, -1.3];
        let (e, d) = ([0.4, -0.9], [1.1, 0.3]);
        let hd: [HyperDual<1>; 2] =
            std::array::from_fn(|i| HyperDual::new(x0[i], [e[i]], [d[i]], [[0.0]]));
        let y = kernel(&hd);
        let dual_at = |t: f64, dir: [f64; 2]| {
            let x: [Dual<1>; 2] = std::array::from_fn(|i| Dual::new(x0[i] + t * d[i], [dir[i]]));
            kernel(&x).d[0]
        };
        assert!((y.a[0] - dual_at(0.0, e)).abs() < 1e-13);
        assert!((y.b[0] - dual_at(0.0, d)).abs() < 1e-13);
        let h = 1e-5;
        let fd = (dual_at(h, e) - dual_at(-h, e)) / (2.0 * h);
        assert!(
            (y.ab[0][0] - fd).abs() < 1e-8 * fd.abs().max(1.0),
            "{} vs {fd}",
            y.ab[0][0]
        );
    }

    /// Three second directions at once give, part by part, the three one-direction numbers
    /// (the same operations on each δ, no cross terms) to round-off.
    #[test]
    fn several_second_directions_are_independent() {
        let x0 = [0.7, -1.3];
        let e = [[0.4, -0.9], [0.2, 0.5]];
        let d = [[1.1, 0.3], [-0.6, 0.8], [0.0, 2.0]];
        let ab0 = [
            [[0.1, 0.0], [0.0, -0.2]],
            [[0.3, 0.1], [0.0, 0.0]],
            [[0.0, 0.0], [0.05, 0.0]],
        ];
        let many: [HyperDual<2, 3>; 2] = std::array::from_fn(|k| {
            HyperDual::new(
                x0[k],
                [e[0][k], e[1][k]],
                std::array::from_fn(|m| d[m][k]),
                std::array::from_fn(|m| ab0[m][k]),
            )
        });
        let y = kernel(&many);
        for m in 0..3 {
            let one: [HyperDual<2>; 2] = std::array::from_fn(|k| {
                HyperDual::new(x0[k], [e[0][k], e[1][k]], [d[m][k]], [ab0[m][k]])
            });
            let z = kernel(&one);
            assert_eq!((y.v, y.a), (z.v, z.a));
            assert!((y.b[m] - z.b[0]).abs() <= 1e-15 * z.b[0].abs().max(1.0));
            for i in 0..2 {
                assert!((y.ab[m][i] - z.ab[0][i]).abs() <= 1e-14 * z.ab[0][i].abs().max(1.0));
            }
        }
    }
}
