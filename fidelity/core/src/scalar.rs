//! A small real scalar abstraction for forward-mode automatic differentiation.
//!
//! Geometry-dependent kernels (plate elements, box geometry) are written once over [`Scalar`], so
//! the same code gives values (`f64`) and exact directional derivatives ([`Dual`]), which the
//! reverse-mode products then contract. `num-dual` is not used because later solvers need the same
//! trait over complex values too.

use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// A real field element as far as the kernels need one.
pub trait Scalar:
    Copy
    + std::fmt::Debug
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + Add<f64, Output = Self>
    + Sub<f64, Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
    + Send
    + Sync
    + 'static
{
    /// A constant (zero derivative part).
    fn cst(v: f64) -> Self;
    /// The value part.
    fn re(self) -> f64;
    fn sqrt(self) -> Self;
    fn sin(self) -> Self;
    fn cos(self) -> Self;
    /// (sin, cos) in one call.
    #[inline]
    fn sin_cos(self) -> (Self, Self) {
        (self.sin(), self.cos())
    }
    fn tan(self) -> Self;
    fn atan2(self, x: Self) -> Self;
    fn powi(self, n: i32) -> Self;
    fn exp(self) -> Self;
    fn ln(self) -> Self;
    fn atan(self) -> Self;
    #[inline]
    fn abs(self) -> Self {
        if self.re() < 0.0 {
            -self
        } else {
            self
        }
    }
    #[inline]
    fn zero() -> Self {
        Self::cst(0.0)
    }
    #[inline]
    fn one() -> Self {
        Self::cst(1.0)
    }
}

impl Scalar for f64 {
    #[inline]
    fn cst(v: f64) -> Self {
        v
    }
    #[inline]
    fn re(self) -> f64 {
        self
    }
    #[inline]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline]
    fn sin(self) -> Self {
        f64::sin(self)
    }
    #[inline]
    fn cos(self) -> Self {
        f64::cos(self)
    }
    #[inline]
    fn tan(self) -> Self {
        f64::tan(self)
    }
    #[inline]
    fn sin_cos(self) -> (Self, Self) {
        f64::sin_cos(self)
    }
    #[inline]
    fn atan2(self, x: Self) -> Self {
        f64::atan2(self, x)
    }
    #[inline]
    fn powi(self, n: i32) -> Self {
        f64::powi(self, n)
    }
    #[inline]
    fn exp(self) -> Self {
        f64::exp(self)
    }
    #[inline]
    fn ln(self) -> Self {
        f64::ln(self)
    }
    #[inline]
    fn atan(self) -> Self {
        f64::atan(self)
    }
}

/// A forward-mode dual number with `N` simultaneous directional derivatives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dual<const N: usize> {
    pub v: f64,
    pub d: [f64; N],
}

impl<const N: usize> Dual<N> {
    /// A variable with value `v` and unit derivative in direction `dir`.
    pub fn var(v: f64, dir: usize) -> Self {
        let mut d = [0.0; N];
        d[dir] = 1.0;
        Self { v, d }
    }
    /// A value with a given derivative vector.
    pub fn new(v: f64, d: [f64; N]) -> Self {
        Self { v, d }
    }
    #[inline]
    fn chain(self, f: f64, df: f64) -> Self {
        let mut d = self.d;
        for x in d.iter_mut() {
            *x *= df;
        }
        Self { v: f, d }
    }
}

impl<const N: usize> PartialOrd for Dual<N> {
    #[inline]
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        self.v.partial_cmp(&other.v)
    }
}

impl<const N: usize> Add for Dual<N> {
    type Output = Self;
    #[inline]
    fn add(mut self, o: Self) -> Self {
        self.v += o.v;
        for (a, b) in self.d.iter_mut().zip(o.d) {
            *a += b;
        }
        self
    }
}
impl<const N: usize> Sub for Dual<N> {
    type Output = Self;
    #[inline]
    fn sub(mut self, o: Self) -> Self {
        self.v -= o.v;
        for (a, b) in self.d.iter_mut().zip(o.d) {
            *a -= b;
        }
        self
    }
}
impl<const N: usize> Mul for Dual<N> {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        let mut d = [0.0; N];
        for i in 0..N {
            d[i] = self.d[i] * o.v + self.v * o.d[i];
        }
        Self { v: self.v * o.v, d }
    }
}
impl<const N: usize> Div for Dual<N> {
    type Output = Self;
    #[inline]
    fn div(self, o: Self) -> Self {
        let inv = 1.0 / o.v;
        let q = self.v * inv;
        let mut d = [0.0; N];
        for i in 0..N {
            d[i] = (self.d[i] - q * o.d[i]) * inv;
        }
        Self { v: q, d }
    }
}
impl<const N: usize> Neg for Dual<N> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        self.chain(-self.v, -1.0)
    }
}
impl<const N: usize> AddAssign for Dual<N> {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}
impl<const N: usize> SubAssign for Dual<N> {
    #[inline]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}
impl<const N: usize> MulAssign for Dual<N> {
    #[inline]
    fn mul_assign(&mut self, o: Self) {
        *self = *self * o;
    }
}
impl<const N: usize> Add<f64> for Dual<N> {
    type Output = Self;
    #[inline]
    fn add(mut self, o: f64) -> Self {
        self.v += o;
        self
    }
}
impl<const N: usize> Sub<f64> for Dual<N> {
    type Output = Self;
    #[inline]
    fn sub(mut self, o: f64) -> Self {
        self.v -= o;
        self
    }
}
impl<const N: usize> Mul<f64> for Dual<N> {
    type Output = Self;
    #[inline]
    fn mul(self, o: f64) -> Self {
        self.chain(self.v * o, o)
    }
}
impl<const N: usize> Div<f64> for Dual<N> {
    type Output = Self;
    #[inline]
    fn div(self, o: f64) -> Self {
        self.chain(self.v / o, 1.0 / o)
    }
}

impl<const N: usize> Scalar for Dual<N> {
    #[inline]
    fn cst(v: f64) -> Self {
        Self { v, d: [0.0; N] }
    }
    #[inline]
    fn re(self) -> f64 {
        self.v
    }
    #[inline]
    fn sqrt(self) -> Self {
        let s = self.v.sqrt();
        self.chain(s, 0.5 / s)
    }
    #[inline]
    fn sin(self) -> Self {
        self.chain(self.v.sin(), self.v.cos())
    }
    #[inline]
    fn cos(self) -> Self {
        self.chain(self.v.cos(), -self.v.sin())
    }
    #[inline]
    fn tan(self) -> Self {
        let t = self.v.tan();
        self.chain(t, 1.0 + t * t)
    }
    #[inline]
    fn atan2(self, x: Self) -> Self {
        let r2 = self.v * self.v + x.v * x.v;
        let mut d = [0.0; N];
        for i in 0..N {
            d[i] = (x.v * self.d[i] - self.v * x.d[i]) / r2;
        }
        Self {
            v: self.v.atan2(x.v),
            d,
        }
    }
    #[inline]
    fn powi(self, n: i32) -> Self {
        let p = self.v.powi(n);
        let dp = if n == 0 {
            0.0
        } else {
            n as f64 * self.v.powi(n - 1)
        };
        self.chain(p, dp)
    }
    #[inline]
    fn exp(self) -> Self {
        let e = self.v.exp();
        self.chain(e, e)
    }
    #[inline]
    fn ln(self) -> Self {
        self.chain(self.v.ln(), 1.0 / self.v)
    }
    #[inline]
    fn atan(self) -> Self {
        self.chain(self.v.atan(), 1.0 / (1.0 + self.v * self.v))
    }
}

/// A complex number used for complex-step differentiation: f(x + i h) = f(x) + i h f'(x) + O(h²),
/// so Im f / h is the derivative without subtractive cancellation (h = 1e-30 in paper Eq. 20).
/// Comparisons and the non-analytic functions (abs, atan2) follow the real part, as complex-step
/// codes do: the imaginary part must stay infinitesimal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CStep(pub num_complex::Complex64);

impl CStep {
    /// The value x + i h.
    pub fn new(x: f64, h: f64) -> Self {
        Self(num_complex::Complex64::new(x, h))
    }
    /// The imaginary part (h times the derivative).
    pub fn im(self) -> f64 {
        self.0.im
    }
}

impl PartialOrd for CStep {
    #[inline]
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        self.0.re.partial_cmp(&other.0.re)
    }
}

macro_rules! cstep_ops {
    ($($tr:ident $f:ident $atr:ident $af:ident),*) => {$(
        impl $tr for CStep {
            type Output = Self;
            #[inline]
            fn $f(self, o: Self) -> Self {
                Self(self.0.$f(o.0))
            }
        }
        impl $tr<f64> for CStep {
            type Output = Self;
            #[inline]
            fn $f(self, o: f64) -> Self {
                Self(self.0.$f(o))
            }
        }
        impl $atr for CStep {
            #[inline]
            fn $af(&mut self, o: Self) {
                *self = self.$f(o);
            }
        }
    )*};
}
cstep_ops!(Add add AddAssign add_assign, Sub sub SubAssign sub_assign, Mul mul MulAssign mul_assign);

impl Div for CStep {
    type Output = Self;
    #[inline]
    fn div(self, o: Self) -> Self {
        Self(self.0 / o.0)
    }
}
impl Div<f64> for CStep {
    type Output = Self;
    #[inline]
    fn div(self, o: f64) -> Self {
        Self(self.0 / o)
    }
}
impl Neg for CStep {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self(-self.0)
    }
}

impl Scalar for CStep {
    #[inline]
    fn cst(v: f64) -> Self {
        Self::new(v, 0.0)
    }
    #[inline]
    fn re(self) -> f64 {
        self.0.re
    }
    #[inline]
    fn sqrt(self) -> Self {
        Self(self.0.sqrt())
    }
    #[inline]
    fn sin(self) -> Self {
        Self(self.0.sin())
    }
    #[inline]
    fn cos(self) -> Self {
        Self(self.0.cos())
    }
    #[inline]
    fn tan(self) -> Self {
        Self(self.0.tan())
    }
    #[inline]
    fn atan2(self, x: Self) -> Self {
        // value from the real parts, first-order imaginary part from the derivative
        let (y, x) = (self.0, x.0);
        let r2 = y.re * y.re + x.re * x.re;
        Self::new(y.re.atan2(x.re), (x.re * y.im - y.re * x.im) / r2)
    }
    #[inline]
    fn powi(self, n: i32) -> Self {
        Self(self.0.powi(n))
    }
    #[inline]
    fn exp(self) -> Self {
        Self(self.0.exp())
    }
    #[inline]
    fn ln(self) -> Self {
        Self(self.0.ln())
    }
    #[inline]
    fn atan(self) -> Self {
        // num-complex's atan goes through ln(1 ± i z), which loses an imaginary part of 1e-30
        Self::new(self.0.re.atan(), self.0.im / (1.0 + self.0.re * self.0.re))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Complex step (h = 1e-30) and dual numbers give the same derivative of a composite function
    /// to round-off (1e-14 relative): neither has a truncation or cancellation error.
    #[test]
    #[inline]
    fn complex_step_matches_dual() {
        fn f<S: Scalar>(x: S, y: S) -> S {
            (x * y).sin() / (x.powi(3) + y.sqrt()) - x.atan2(y) * x.tan()
                + (x * y).exp().ln() * y.atan()
                - (x - 2.0).abs() * y.cos()
        }
        let (x0, y0) = (0.7, 1.3);
        let d = f(Dual::<2>::var(x0, 0), Dual::var(y0, 1));
        let h = 1e-30;
        let cx = f(CStep::new(x0, h), CStep::cst(y0));
        let cy = f(CStep::cst(x0), CStep::new(y0, h));
        assert!((cx.re() - d.v).abs() < 1e-15);
        assert!(
            (cx.im() / h - d.d[0]).abs() < 1e-14 * d.d[0].abs(),
            "{} {}",
            cx.im() / h,
            d.d[0]
        );
        assert!(
            (cy.im() / h - d.d[1]).abs() < 1e-14 * d.d[1].abs(),
            "{} {}",
            cy.im() / h,
            d.d[1]
        );
    }

    /// The dual derivative of a composite function equals its analytic derivative.
    #[test]
    #[inline]
    fn dual_matches_analytic_derivative() {
        let f = |x: Dual<2>, y: Dual<2>| {
            (x * y).sin() / (x.powi(3) + y.sqrt()) - x.atan2(y) * x.tan()
                + (x * y).exp().ln() * y.atan()
        };
        let (x0, y0) = (0.7, 1.3);
        let r = f(Dual::var(x0, 0), Dual::var(y0, 1));
        let h = 1e-6;
        let g = |x: f64, y: f64| {
            (x * y).sin() / (x.powi(3) + y.sqrt()) - x.atan2(y) * x.tan()
                + (x * y).exp().ln() * y.atan()
        };
        let fdx = (g(x0 + h, y0) - g(x0 - h, y0)) / (2.0 * h);
        let fdy = (g(x0, y0 + h) - g(x0, y0 - h)) / (2.0 * h);
        // central differences with h = 1e-6 are good to ~1e-9 relative here
        assert!(
            (r.d[0] - fdx).abs() < 1e-8 * fdx.abs().max(1.0),
            "{} {fdx}",
            r.d[0]
        );
        assert!((r.d[1] - fdy).abs() < 1e-8 * fdy.abs().max(1.0));
    }
}
