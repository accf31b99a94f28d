//! Reverse-mode automatic differentiation by an operation tape: a kernel written over
//! [`Scalar`] and run on [`Rev`] values records every elementary operation with its local
//! partial derivatives; one backward sweep of the tape then gives the vector-Jacobian product
//! wᵀ ∂f/∂x for any seed w on the outputs, real or complex (the Jacobian is real, so a complex
//! seed is swept as one; the product is the transpose, not the conjugate transpose).
//!
//! The adjoints of the CFD fidelity (Jᵀ ψ of the residual, the transposes of the motion and
//! force linearizations) are such products over kernels of a few million operations, swept many
//! times (every adjoint GMRES iteration, every seed), which is what a tape is for: record once,
//! sweep often. Hand-written because the reverse-mode crates tie their variables to a tape's
//! lifetime, and [`Scalar`] needs `'static` values.
//!
//! The tape lives in a thread-local while [`Tape::record`] runs, so the recorded kernel must run
//! on the recording thread (no rayon inside it); a [`Rev`] used outside a recording is a
//! programming error and panics.

use crate::scalar::Scalar;
use std::cell::RefCell;
use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// No tape entry: a constant.
const NONE: u32 = u32::MAX;

/// One recorded operation: up to two parents with their partial derivatives.
#[derive(Clone, Copy, Debug)]
struct Entry {
    a: u32,
    b: u32,
    da: f64,
    db: f64,
}

/// Bytes per recorded operation (for memory estimates).
pub const BYTES_PER_ENTRY: usize = std::mem::size_of::<Entry>();

thread_local! {
    static TAPE: RefCell<Option<Vec<Entry>>> = const { RefCell::new(None) };
}

fn push(e: Entry) -> u32 {
    TAPE.with(|t| {
        let mut t = t.borrow_mut();
        let tape = t
            .as_mut()
            .expect("a Rev variable was used outside Tape::record (or on another thread)");
        let i = tape.len();
        assert!(i < NONE as usize, "the tape is full (2^32 operations)");
        tape.push(e);
        i as u32
    })
}

/// A real value that records its operations on the current thread's tape.
#[derive(Clone, Copy, Debug)]
pub struct Rev {
    pub v: f64,
    i: u32,
}

impl Rev {
    /// A new independent variable (only inside [`Tape::record`]).
    pub fn input(v: f64) -> Self {
        let i = push(Entry {
            a: NONE,
            b: NONE,
            da: 0.0,
            db: 0.0,
        });
        Self { v, i }
    }

    #[inline]
    fn unary(self, v: f64, d: f64) -> Self {
        if self.i == NONE {
            return Self { v, i: NONE };
        }
        let i = push(Entry {
            a: self.i,
            b: NONE,
            da: d,
            db: 0.0,
        });
        Self { v, i }
    }

    #[inline]
    fn binary(self, o: Self, v: f64, da: f64, db: f64) -> Self {
        match (self.i == NONE, o.i == NONE) {
            (true, true) => Self { v, i: NONE },
            (false, true) => self.unary(v, da),
            (true, false) => o.unary(v, db),
            (false, false) => {
                let i = push(Entry {
                    a: self.i,
                    b: o.i,
                    da,
                    db,
                });
                Self { v, i }
            }
        }
    }
}

/// A recorded tape.
pub struct Tape {
    entries: Vec<Entry>,
}

/// What an adjoint accumulates: f64 or a complex number.
pub trait Adjoint: Copy + Add<Output = Self> + Mul<f64, Output = Self> + Send + Sync {
    fn zero() -> Self;
    fn is_zero(&self) -> bool;
}

impl Adjoint for f64 {
    fn zero() -> Self {
        0.0
    }
    fn is_zero(&self) -> bool {
        *self == 0.0
    }
}

impl Adjoint for num_complex::Complex64 {
    fn zero() -> Self {
        Self::new(0.0, 0.0)
    }
    fn is_zero(&self) -> bool {
        self.re == 0.0 && self.im == 0.0
    }
}

/// The adjoints of every recorded value after a sweep.
pub struct Adjoints<T> {
    adj: Vec<T>,
}

impl<T: Adjoint> Adjoints<T> {
    /// ∂(seeded output)/∂x for a recorded value x (zero for a constant).
    pub fn of(&self, x: Rev) -> T {
        if x.i == NONE {
            T::zero()
        } else {
            self.adj[x.i as usize]
        }
    }
}

impl Tape {
    /// Runs `f` with a fresh tape on this thread and returns its result with the tape.
    pub fn record<R>(f: impl FnOnce() -> R) -> (R, Tape) {
        TAPE.with(|t| {
            let mut t = t.borrow_mut();
            assert!(t.is_none(), "Tape::record does not nest");
            *t = Some(Vec::new());
        });
        // take the tape back even if `f` panics, so the thread stays usable
        struct Reset;
        impl Drop for Reset {
            fn drop(&mut self) {
                TAPE.with(|t| {
                    let _ = t.try_borrow_mut().map(|mut t| t.take());
                });
            }
        }
        let guard = Reset;
        let out = f();
        let entries = TAPE.with(|t| t.borrow_mut().take()).expect("the tape");
        drop(guard);
        (out, Tape { entries })
    }

    /// Number of recorded operations.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Memory held by the tape, bytes.
    pub fn bytes(&self) -> usize {
        self.entries.capacity() * BYTES_PER_ENTRY
    }

    /// The backward sweep for seeds (output, weight): the adjoint of every recorded value,
    /// wᵀ ∂(outputs)/∂(value). Seeds on constants are ignored; repeated outputs add.
    pub fn sweep<T: Adjoint>(&self, seeds: impl IntoIterator<Item = (Rev, T)>) -> Adjoints<T> {
        let mut adj = vec![T::zero(); self.entries.len()];
        for (x, w) in seeds {
            if x.i != NONE {
                adj[x.i as usize] = adj[x.i as usize] + w;
            }
        }
        for i in (0..self.entries.len()).rev() {
            let g = adj[i];
            if g.is_zero() {
                continue;
            }
            let e = self.entries[i];
            if e.a != NONE {
                adj[e.a as usize] = adj[e.a as usize] + g * e.da;
            }
            if e.b != NONE {
                adj[e.b as usize] = adj[e.b as usize] + g * e.db;
            }
        }
        Adjoints { adj }
    }
}

impl PartialEq for Rev {
    fn eq(&self, other: &Self) -> bool {
        self.v == other.v
    }
}

impl PartialOrd for Rev {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        self.v.partial_cmp(&other.v)
    }
}

impl Add for Rev {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        self.binary(o, self.v + o.v, 1.0, 1.0)
    }
}
impl Sub for Rev {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        self.binary(o, self.v - o.v, 1.0, -1.0)
    }
}
impl Mul for Rev {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        self.binary(o, self.v * o.v, o.v, self.v)
    }
}
impl Div for Rev {
    type Output = Self;
    #[inline]
    fn div(self, o: Self) -> Self {
        let inv = 1.0 / o.v;
        let q = self.v * inv;
        self.binary(o, q, inv, -q * inv)
    }
}
impl Neg for Rev {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        self.unary(-self.v, -1.0)
    }
}
impl AddAssign for Rev {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}
impl SubAssign for Rev {
    #[inline]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}
impl MulAssign for Rev {
    #[inline]
    fn mul_assign(&mut self, o: Self) {
        *self = *self * o;
    }
}
impl Add<f64> for Rev {
    type Output = Self;
    #[inline]
    fn add(self, o: f64) -> Self {
        self.unary(self.v + o, 1.0)
    }
}
impl Sub<f64> for Rev {
    type Output = Self;
    #[inline]
    fn sub(self, o: f64) -> Self {
        self.unary(self.v - o, 1.0)
    }
}
impl Mul<f64> for Rev {
    type Output = Self;
    #[inline]
    fn mul(self, o: f64) -> Self {
        self.unary(self.v * o, o)
    }
}
impl Div<f64> for Rev {
    type Output = Self;
    #[inline]
    fn div(self, o: f64) -> Self {
        self.unary(self.v / o, 1.0 / o)
    }
}

impl Scalar for Rev {
    #[inline]
    fn cst(v: f64) -> Self {
        Self { v, i: NONE }
    }
    #[inline]
    fn re(self) -> f64 {
        self.v
    }
    fn sqrt(self) -> Self {
        let s = self.v.sqrt();
        self.unary(s, 0.5 / s)
    }
    fn sin(self) -> Self {
        self.unary(self.v.sin(), self.v.cos())
    }
    fn cos(self) -> Self {
        self.unary(self.v.cos(), -self.v.sin())
    }
    fn tan(self) -> Self {
        let t = self.v.tan();
        self.unary(t, 1.0 + t * t)
    }
    fn atan2(self, x: Self) -> Self {
        let r2 = self.v * self.v + x.v * x.v;
        self.binary(x, self.v.atan2(x.v), x.v / r2, -self.v / r2)
    }
    fn powi(self, n: i32) -> Self {
        let dp = if n == 0 {
            0.0
        } else {
            n as f64 * self.v.powi(n - 1)
        };
        self.unary(self.v.powi(n), dp)
    }
    fn exp(self) -> Self {
        let e = self.v.exp();
        self.unary(e, e)
    }
    fn ln(self) -> Self {
        self.unary(self.v.ln(), 1.0 / self.v)
    }
    fn atan(self) -> Self {
        self.unary(self.v.atan(), 1.0 / (1.0 + self.v * self.v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scalar::Dual;

    /// A kernel with every operation of [`Scalar`].
    fn kernel<S: Scalar>(x: &[S; 3]) -> [S; 2] {
        let a = x[0] * x[1] + x[2].sin() * x[0].cos() - x[1] / (x[2] + 3.0);
        let b = (x[0] * x[0] + x[1] * x[1]).sqrt().ln() * x[2].exp()
            + x[1].atan2(x[0])
            + x[2].tan()
            + x[0].powi(3)
            - x[1].atan() * 2.0;
        let mut c = a;
        c += b;
        c *= x[0] - 0.5;
        c -= x[2] / 4.0;
        [-c, (a * b).abs()]
    }

    /// The tape's wᵀ J equals the dual-number J v paired with w (real and complex seeds), to
    /// round-off; constants record nothing.
    #[test]
    fn sweep_is_the_transpose_of_forward_mode() {
        let x0 = [0.7, -1.3, 0.4];
        let (out, tape) = Tape::record(|| {
            let x: [Rev; 3] = std::array::from_fn(|i| Rev::input(x0[i]));
            (x, kernel(&x))
        });
        let (x, y) = out;
        let w = [0.3, -1.7];
        let adj = tape.sweep(y.iter().zip(w).map(|(r, w)| (*r, w)));
        for dir in 0..3 {
            let xd: [Dual<1>; 3] =
                std::array::from_fn(|i| Dual::new(x0[i], [(i == dir) as u8 as f64]));
            let yd = kernel(&xd);
            let forward = w[0] * yd[0].d[0] + w[1] * yd[1].d[0];
            let reverse = adj.of(x[dir]);
            assert!(
                (forward - reverse).abs() < 1e-14 * forward.abs().max(1.0),
                "{forward} {reverse}"
            );
        }
        let wc = [
            num_complex::Complex64::new(0.3, 2.0),
            num_complex::Complex64::new(-1.0, 0.5),
        ];
        let adj_c = tape.sweep(y.iter().zip(wc).map(|(r, w)| (*r, w)));
        let adj_re = tape.sweep(y.iter().zip(wc).map(|(r, w)| (*r, w.re)));
        let adj_im = tape.sweep(y.iter().zip(wc).map(|(r, w)| (*r, w.im)));
        for xi in x {
            let c = adj_c.of(xi);
            assert!((c.re - adj_re.of(xi)).abs() < 1e-15 && (c.im - adj_im.of(xi)).abs() < 1e-15);
        }
        let (_, empty) = Tape::record(|| kernel(&[Rev::cst(1.0), Rev::cst(2.0), Rev::cst(0.5)]));
        assert!(empty.is_empty());
    }
}
