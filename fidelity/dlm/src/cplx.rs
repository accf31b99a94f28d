//! Complex numbers over a generic real [`Scalar`], so the kernel can carry dual numbers.

use gustkit_core::scalar::Scalar;
use num_complex::Complex64;
use std::ops::{Add, Mul, Neg, Sub};

/// a + i b with a, b of scalar type S.
#[derive(Clone, Copy, Debug)]
pub struct Cplx<S> {
    pub re: S,
    pub im: S,
}

impl<S: Scalar> Cplx<S> {
    #[inline]
    pub fn new(re: S, im: S) -> Self {
        Self { re, im }
    }
    #[inline]
    pub fn real(re: S) -> Self {
        Self { re, im: S::zero() }
    }
    #[inline]
    pub fn zero() -> Self {
        Self::real(S::zero())
    }
    /// exp(-i θ) for real θ.
    #[inline]
    pub fn expi_neg(theta: S) -> Self {
        let (s, c) = theta.sin_cos();
        Self { re: c, im: -s }
    }
    #[inline]
    pub fn scale(self, s: S) -> Self {
        Self {
            re: self.re * s,
            im: self.im * s,
        }
    }
    #[inline]
    pub fn scale_f(self, s: f64) -> Self {
        Self {
            re: self.re * s,
            im: self.im * s,
        }
    }
    /// The value part as a `Complex64`.
    #[inline]
    pub fn value(self) -> Complex64 {
        Complex64::new(self.re.re(), self.im.re())
    }
}

impl<S: Scalar> Add for Cplx<S> {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        Self::new(self.re + o.re, self.im + o.im)
    }
}
impl<S: Scalar> Sub for Cplx<S> {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        Self::new(self.re - o.re, self.im - o.im)
    }
}
impl<S: Scalar> Mul for Cplx<S> {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        Self::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
}
impl<S: Scalar> Neg for Cplx<S> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self::new(-self.re, -self.im)
    }
}
