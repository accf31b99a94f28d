//! Restarted GMRES with right preconditioning (modified Gram–Schmidt Arnoldi, Givens rotations),
//! generic over the field: real for Newton–Krylov, complex for the LFD equations.

use num_complex::Complex64;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// The field GMRES works in (f64 or Complex64).
pub trait Field:
    Copy
    + Send
    + Sync
    + std::fmt::Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Mul<f64, Output = Self>
{
    fn zero() -> Self;
    fn from_re(v: f64) -> Self;
    fn conj(self) -> Self;
    /// |x|², real.
    fn norm_sqr(self) -> f64;
}

impl Field for f64 {
    fn zero() -> Self {
        0.0
    }
    fn from_re(v: f64) -> Self {
        v
    }
    fn conj(self) -> Self {
        self
    }
    fn norm_sqr(self) -> f64 {
        self * self
    }
}

impl Field for Complex64 {
    fn zero() -> Self {
        Complex64::new(0.0, 0.0)
    }
    fn from_re(v: f64) -> Self {
        Complex64::new(v, 0.0)
    }
    fn conj(self) -> Self {
        Complex64::conj(&self)
    }
    fn norm_sqr(self) -> f64 {
        Complex64::norm_sqr(&self)
    }
}

/// How a GMRES solve went: iterations and the relative residual after each.
#[derive(Clone, Debug)]
pub struct GmresInfo {
    pub iterations: usize,
    pub history: Vec<f64>,
}

/// GMRES did not reach its tolerance; the residual history says how it went.
#[derive(Clone, Debug, thiserror::Error)]
#[error("GMRES stalled at relative residual {reached:.3e} (wanted {wanted:.1e}) after {iterations} iterations; history {history:?}")]
pub struct GmresError {
    pub reached: f64,
    pub wanted: f64,
    pub iterations: usize,
    pub history: Vec<f64>,
}

/// The inner product bᴴ a, in four interleaved partial sums (independent additions the
/// processor can overlap; the vectors are long, so the order changes only round-off).
fn dot<T: Field>(a: &[T], b: &[T]) -> T {
    let mut acc = [T::zero(); 4];
    let (a4, b4) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail = a4
        .remainder()
        .iter()
        .zip(b4.remainder())
        .fold(T::zero(), |s, (x, y)| s + y.conj() * *x);
    for (x, y) in a4.zip(b4) {
        for k in 0..4 {
            acc[k] = acc[k] + y[k].conj() * x[k];
        }
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

fn norm<T: Field>(a: &[T]) -> f64 {
    let mut acc = [0.0; 4];
    let a4 = a.chunks_exact(4);
    let tail: f64 = a4.remainder().iter().map(|x| x.norm_sqr()).sum();
    for x in a4 {
        for k in 0..4 {
            acc[k] += x[k].norm_sqr();
        }
    }
    ((acc[0] + acc[1]) + (acc[2] + acc[3]) + tail).sqrt()
}

/// Solves A x = b to ‖b − A x‖ ≤ `tol` ‖b‖ from x = 0, with `op` = A and `prec` ≈ A⁻¹ applied on
/// the right, restarting every `restart` iterations, at most `max_iter` iterations.
pub fn gmres<T: Field>(
    op: &dyn Fn(&[T]) -> Vec<T>,
    prec: &dyn Fn(&[T]) -> Vec<T>,
    b: &[T],
    tol: f64,
    restart: usize,
    max_iter: usize,
) -> Result<(Vec<T>, GmresInfo), GmresError> {
    gmres_from(op, prec, b, None, tol, restart, max_iter)
}

/// [`gmres`] from the initial guess `x0` (none: from 0). The tolerance stays relative to ‖b‖,
/// so a guess changes the path, not the accuracy asked for.
pub fn gmres_from<T: Field>(
    op: &dyn Fn(&[T]) -> Vec<T>,
    prec: &dyn Fn(&[T]) -> Vec<T>,
    b: &[T],
    x0: Option<&[T]>,
    tol: f64,
    restart: usize,
    max_iter: usize,
) -> Result<(Vec<T>, GmresInfo), GmresError> {
    let op_many = |vs: &[&[T]]| -> Vec<Vec<T>> { vs.iter().map(|v| op(v)).collect() };
    let prec_many = |vs: &[&[T]]| -> Vec<Vec<T>> { vs.iter().map(|v| prec(v)).collect() };
    gmres_batch(&op_many, &prec_many, &[b], &[x0], tol, restart, max_iter)
        .pop()
        .expect("one right-hand side gives one result")
}

/// A product with several vectors at once (an operator or a preconditioner): one pass over a
/// matrix serves them all.
pub type ManyOp<'a, T> = dyn Fn(&[&[T]]) -> Vec<Vec<T>> + 'a;

/// [`gmres_from`] on several right-hand sides of one operator in lockstep: each keeps its own
/// Arnoldi basis, rotations and convergence, but every step applies `op` and `prec` to all the
/// columns still iterating at once, so a matrix-bound product reads its matrix once per step
/// instead of once per column. With products that treat each column as the one-column product
/// does, each result is bit for bit that of [`gmres_from`] on its column. Memory: one basis per
/// column in the batch.
pub fn gmres_batch<T: Field>(
    op: &ManyOp<T>,
    prec: &ManyOp<T>,
    bs: &[&[T]],
    x0s: &[Option<&[T]>],
    tol: f64,
    restart: usize,
    max_iter: usize,
) -> Vec<Result<(Vec<T>, GmresInfo), GmresError>> {
    // products of no vectors are none (the operators need not take an empty batch)
    let op = |vs: &[&[T]]| if vs.is_empty() { Vec::new() } else { op(vs) };
    let prec = |vs: &[&[T]]| if vs.is_empty() { Vec::new() } else { prec(vs) };
    let mut cols: Vec<Column<T>> = bs
        .iter()
        .enumerate()
        .map(|(i, b)| Column::new(b, x0s.get(i).copied().flatten(), (tol, max_iter)))
        .collect();
    loop {
        // r = b − A x for the columns that start a cycle from a non-zero x
        let running: Vec<usize> = (0..cols.len()).filter(|&i| cols[i].running()).collect();
        if running.is_empty() {
            break;
        }
        let need: Vec<usize> = running
            .iter()
            .copied()
            .filter(|&i| cols[i].needs_product())
            .collect();
        let mut products: Vec<Option<Vec<T>>> = vec![None; cols.len()];
        let xs: Vec<&[T]> = need.iter().map(|&i| cols[i].x.as_slice()).collect();
        for (&i, ax) in need.iter().zip(op(&xs)) {
            products[i] = Some(ax);
        }
        let mut cycling = Vec::with_capacity(running.len());
        for &i in &running {
            let ax = products[i].take();
            if cols[i].start_cycle(bs[i], ax.as_deref()) {
                cycling.push(i);
            }
        }
        // the Arnoldi steps, all columns of the cycle at once until each ends its cycle
        let mut stepping = cycling.clone();
        for _ in 0..restart {
            if stepping.is_empty() {
                break;
            }
            let z = prec(
                &stepping
                    .iter()
                    .map(|&i| cols[i].last_basis_vector())
                    .collect::<Vec<_>>(),
            );
            let w = op(&z.iter().map(Vec::as_slice).collect::<Vec<_>>());
            let mut still = Vec::with_capacity(stepping.len());
            for (&i, w) in stepping.iter().zip(w) {
                if cols[i].arnoldi_step(w) {
                    still.push(i);
                }
            }
            stepping = still;
        }
        // x += M⁻¹ (V y) for every column that ran a cycle
        let vys: Vec<Vec<T>> = cycling
            .iter()
            .map(|&i| cols[i].basis_combination())
            .collect();
        let steps = prec(&vys.iter().map(Vec::as_slice).collect::<Vec<_>>());
        for (&i, d) in cycling.iter().zip(steps) {
            cols[i].end_cycle(&d);
        }
    }
    cols.into_iter().map(Column::result).collect()
}

/// One right-hand side's GMRES state: its iterate, the current cycle's Arnoldi basis, Hessenberg
/// columns (already rotated) and rotations, and how it ended.
struct Column<T: Field> {
    x: Vec<T>,
    /// The tolerance relative to ‖b‖ and the iteration limit.
    tol: f64,
    max_iter: usize,
    bnorm: f64,
    guessed: bool,
    total: usize,
    history: Vec<f64>,
    /// The Arnoldi basis of the cycle.
    v: Vec<Vec<T>>,
    /// h[j] is column j of the rotated Hessenberg matrix (length j + 2).
    h: Vec<Vec<T>>,
    /// Complex Givens rotations [[c, s], [−s̄, c]] with c real.
    cs: Vec<f64>,
    sn: Vec<T>,
    g: Vec<T>,
    /// The cycle ended on the tolerance (or a lucky breakdown).
    converged: bool,
    done: Option<Result<(), ()>>,
}

impl<T: Field> Column<T> {
    fn new(b: &[T], x0: Option<&[T]>, (tol, max_iter): (f64, usize)) -> Self {
        let n = b.len();
        let bnorm = norm(b);
        let mut x = match x0 {
            Some(g) if g.len() == n => g.to_vec(),
            _ => vec![T::zero(); n],
        };
        let guessed = x.iter().any(|v| v.norm_sqr() > 0.0);
        let mut done = None;
        if bnorm == 0.0 {
            x.iter_mut().for_each(|v| *v = T::zero());
            done = Some(Ok(()));
        }
        Self {
            x,
            tol,
            max_iter,
            bnorm,
            guessed,
            total: 0,
            history: Vec::new(),
            v: Vec::new(),
            h: Vec::new(),
            cs: Vec::new(),
            sn: Vec::new(),
            g: Vec::new(),
            converged: false,
            done,
        }
    }

    fn running(&self) -> bool {
        self.done.is_none()
    }

    /// A cycle's residual needs A x (a first cycle from x = 0 has r = b).
    fn needs_product(&self) -> bool {
        self.total > 0 || self.guessed
    }

    /// Starts a cycle from r = b − `ax` (`ax` none: r = b); false if the column is already
    /// within the tolerance (then it is done).
    fn start_cycle(&mut self, b: &[T], ax: Option<&[T]>) -> bool {
        let r: Vec<T> = match ax {
            Some(ax) => b.iter().zip(ax).map(|(a, c)| *a - *c).collect(),
            None => b.to_vec(),
        };
        let beta = norm(&r);
        if beta <= self.tol * self.bnorm {
            self.history.push(beta / self.bnorm);
            self.done = Some(Ok(()));
            return false;
        }
        // the Arnoldi basis only: the preconditioner is the same at every step, so x moves by
        // M⁻¹ (V y) at the end of a cycle and the preconditioned vectors M⁻¹ vⱼ are not kept
        // (half the memory of flexible GMRES, one more preconditioner application a cycle)
        self.v = vec![r.iter().map(|a| *a * (1.0 / beta)).collect()];
        self.h.clear();
        self.cs.clear();
        self.sn.clear();
        self.g = vec![T::from_re(beta)];
        self.converged = false;
        true
    }

    fn last_basis_vector(&self) -> &[T] {
        self.v.last().expect("a cycle has a basis vector")
    }

    /// One Arnoldi step with w = A M⁻¹ vⱼ: orthogonalizes w (modified Gram–Schmidt), rotates the
    /// new Hessenberg column and records the residual; true while the cycle goes on.
    fn arnoldi_step(&mut self, mut w: Vec<T>) -> bool {
        let j = self.h.len();
        let mut col = vec![T::zero(); j + 2];
        for i in 0..=j {
            col[i] = dot(&w, &self.v[i]);
            for (wk, vk) in w.iter_mut().zip(&self.v[i]) {
                *wk = *wk - col[i] * *vk;
            }
        }
        let next_norm = norm(&w);
        col[j + 1] = T::from_re(next_norm);
        // apply the earlier rotations, then a new one to zero col[j + 1]
        let (cs, sn) = (&self.cs, &self.sn);
        for i in 0..j {
            let t = col[i] * cs[i] + sn[i] * col[i + 1];
            col[i + 1] = -(sn[i].conj() * col[i]) + col[i + 1] * cs[i];
            col[i] = t;
        }
        let (a, bb) = (col[j], col[j + 1]);
        let (an, bn) = (a.norm_sqr().sqrt(), bb.norm_sqr().sqrt());
        let d = an.hypot(bn);
        let (c, s, r) = if d == 0.0 {
            (1.0, T::zero(), T::zero())
        } else if an == 0.0 {
            (0.0, bb.conj() * (1.0 / bn), T::from_re(bn))
        } else {
            let phase = a * (1.0 / an);
            (an / d, phase * bb.conj() * (1.0 / d), phase * d)
        };
        col[j] = r;
        col[j + 1] = T::zero();
        self.cs.push(c);
        self.sn.push(s);
        let gj = self.g[j];
        self.g.push(-(s.conj() * gj));
        self.g[j] = gj * c;
        self.h.push(col);
        self.total += 1;
        let rel = self.g[j + 1].norm_sqr().sqrt() / self.bnorm;
        self.history.push(rel);
        if next_norm > 0.0 {
            w.iter_mut().for_each(|a| *a = *a * (1.0 / next_norm));
            self.v.push(w);
        }
        self.converged = rel <= self.tol || next_norm == 0.0;
        !(self.converged || self.total >= self.max_iter)
    }

    /// V y with y from the cycle's triangular system: the step before the preconditioner.
    fn basis_combination(&self) -> Vec<T> {
        let m = self.h.len();
        let mut y = vec![T::zero(); m];
        for i in (0..m).rev() {
            let mut s = self.g[i];
            for k in i + 1..m {
                s = s - self.h[k][i] * y[k];
            }
            y[i] = s / self.h[i][i];
        }
        let mut vy = vec![T::zero(); self.x.len()];
        for (yk, vk) in y.iter().zip(&self.v) {
            for (a, vi) in vy.iter_mut().zip(vk) {
                *a = *a + *yk * *vi;
            }
        }
        vy
    }

    /// x += M⁻¹ (V y); the column is done if its cycle converged or its iterations ran out.
    fn end_cycle(&mut self, step: &[T]) {
        for (xi, d) in self.x.iter_mut().zip(step) {
            *xi = *xi + *d;
        }
        // the basis is not needed until the next cycle starts a new one
        self.v = Vec::new();
        if self.converged {
            self.done = Some(Ok(()));
        } else if self.total >= self.max_iter {
            self.done = Some(Err(()));
        }
    }

    fn result(self) -> Result<(Vec<T>, GmresInfo), GmresError> {
        match self.done {
            Some(Ok(())) => Ok((
                self.x,
                GmresInfo {
                    iterations: self.total,
                    history: self.history,
                },
            )),
            _ => Err(GmresError {
                reached: self.history.last().copied().unwrap_or(1.0),
                wanted: self.tol,
                iterations: self.total,
                history: self.history,
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A non-symmetric, diagonally dominant system: GMRES reaches 1e-12 with and without a
    /// (Jacobi) preconditioner, restarts included, and matches a direct solve.
    #[test]
    fn solves_nonsymmetric_systems() {
        let n = 60;
        let a = |i: usize, j: usize| -> f64 {
            if i == j {
                4.0 + (i as f64) * 0.1
            } else if j == i + 1 {
                -1.3
            } else if i == j + 1 {
                -0.7
            } else if j == (i + 7) % n {
                0.2
            } else {
                0.0
            }
        };
        let op = |x: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|i| (0..n).map(|j| a(i, j) * x[j]).sum())
                .collect()
        };
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let jacobi = |x: &[f64]| -> Vec<f64> { (0..n).map(|i| x[i] / a(i, i)).collect() };
        let none = |x: &[f64]| x.to_vec();
        for (prec, restart) in [
            (&jacobi as &dyn Fn(&[f64]) -> Vec<f64>, 10),
            (&none, 60),
            (&none, 7),
        ] {
            let (x, info) = gmres(&op, prec, &b, 1e-12, restart, 500).unwrap();
            let r: Vec<f64> = op(&x).iter().zip(&b).map(|(p, q)| p - q).collect();
            assert!(norm(&r) <= 1e-11 * norm(&b), "{info:?}");
        }
        // the same system shifted by i·2 (complex, non-Hermitian) against its real 2n × 2n form
        let shift = Complex64::new(0.0, 2.0);
        let opc = |x: &[Complex64]| -> Vec<Complex64> {
            (0..n)
                .map(|i| (0..n).map(|j| x[j] * a(i, j)).sum::<Complex64>() + shift * x[i])
                .collect()
        };
        let bc: Vec<Complex64> = (0..n)
            .map(|i| Complex64::new((i as f64 * 0.37).sin(), (i as f64 * 0.11).cos()))
            .collect();
        let jc = |x: &[Complex64]| -> Vec<Complex64> {
            (0..n).map(|i| x[i] / (shift + a(i, i))).collect()
        };
        let (xc, cold) = gmres(&opc, &jc, &bc, 1e-13, 9, 500).unwrap();
        let rc: Vec<Complex64> = opc(&xc).iter().zip(&bc).map(|(p, q)| p - q).collect();
        assert!(norm(&rc) <= 1e-12 * norm(&bc));
        // from a guess near the answer (1 % off): the same accuracy relative to ‖b‖ in fewer
        // iterations; from the answer itself, none
        let near: Vec<Complex64> = xc
            .iter()
            .enumerate()
            .map(|(i, x)| x * (1.0 + 0.01 * (i as f64 * 0.7).sin()))
            .collect();
        let (xw, warm) = gmres_from(&opc, &jc, &bc, Some(&near), 1e-13, 9, 500).unwrap();
        let rw: Vec<Complex64> = opc(&xw).iter().zip(&bc).map(|(p, q)| p - q).collect();
        assert!(norm(&rw) <= 1e-12 * norm(&bc));
        assert!(warm.iterations < cold.iterations, "{warm:?} {cold:?}");
        let (_, exact) = gmres_from(&opc, &jc, &bc, Some(&xc), 1e-12, 9, 500).unwrap();
        assert_eq!(exact.iterations, 0);
        // the real form [[A, −2I], [2I, A]] [x; y] = [Re b; Im b]
        let opr = |v: &[f64]| -> Vec<f64> {
            let (x, y) = v.split_at(n);
            let (ax, ay) = (op(x), op(y));
            (0..2 * n)
                .map(|i| {
                    if i < n {
                        ax[i] - 2.0 * y[i]
                    } else {
                        ay[i - n] + 2.0 * x[i - n]
                    }
                })
                .collect()
        };
        let br: Vec<f64> = bc
            .iter()
            .map(|c| c.re)
            .chain(bc.iter().map(|c| c.im))
            .collect();
        let (xr, _) = gmres(&opr, &none, &br, 1e-14, 120, 1000).unwrap();
        for i in 0..n {
            assert!((xr[i] - xc[i].re).abs() < 1e-11 && (xr[n + i] - xc[i].im).abs() < 1e-11);
        }
        // a stall is an error with its history
        let e = gmres(&op, &none, &b, 1e-14, 2, 4).unwrap_err();
        assert_eq!(e.iterations, 4);
        assert_eq!(e.history.len(), 4);
    }
}
