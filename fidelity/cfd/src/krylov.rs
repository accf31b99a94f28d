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

/// The inner product bᴴ a.
fn dot<T: Field>(a: &[T], b: &[T]) -> T {
    a.iter()
        .zip(b)
        .fold(T::zero(), |s, (x, y)| s + y.conj() * *x)
}

fn norm<T: Field>(a: &[T]) -> f64 {
    a.iter().map(|x| x.norm_sqr()).sum::<f64>().sqrt()
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
    let n = b.len();
    let bnorm = norm(b);
    let mut x = match x0 {
        Some(g) if g.len() == n => g.to_vec(),
        _ => vec![T::zero(); n],
    };
    let guessed = x.iter().any(|v| v.norm_sqr() > 0.0);
    let mut history = Vec::new();
    if bnorm == 0.0 {
        x.iter_mut().for_each(|v| *v = T::zero());
        return Ok((
            x,
            GmresInfo {
                iterations: 0,
                history,
            },
        ));
    }
    let mut total = 0;
    loop {
        // r = b − A x (a first cycle from x = 0 has r = b)
        let r: Vec<T> = if total == 0 && !guessed {
            b.to_vec()
        } else {
            let ax = op(&x);
            b.iter().zip(&ax).map(|(a, c)| *a - *c).collect()
        };
        let beta = norm(&r);
        if beta <= tol * bnorm {
            history.push(beta / bnorm);
            return Ok((
                x,
                GmresInfo {
                    iterations: total,
                    history,
                },
            ));
        }
        // the Arnoldi basis only: the preconditioner is the same at every step, so x moves by
        // M⁻¹ (V y) at the end of a cycle and the preconditioned vectors M⁻¹ vⱼ are not kept
        // (half the memory of flexible GMRES, one more preconditioner application a cycle)
        let mut v: Vec<Vec<T>> = vec![r.iter().map(|a| *a * (1.0 / beta)).collect()];
        let mut h: Vec<Vec<T>> = Vec::new(); // h[j] is column j (length j + 2)
                                             // complex Givens rotations [[c, s], [−s̄, c]] with c real
        let (mut cs, mut sn): (Vec<f64>, Vec<T>) = (Vec::new(), Vec::new());
        let mut g = vec![T::from_re(beta)];
        let mut converged = false;
        for j in 0..restart {
            let mut w = op(&prec(&v[j]));
            let mut col = vec![T::zero(); j + 2];
            for i in 0..=j {
                col[i] = dot(&w, &v[i]);
                for (wk, vk) in w.iter_mut().zip(&v[i]) {
                    *wk = *wk - col[i] * *vk;
                }
            }
            let next_norm = norm(&w);
            col[j + 1] = T::from_re(next_norm);
            // apply the earlier rotations, then a new one to zero col[j + 1]
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
            cs.push(c);
            sn.push(s);
            g.push(-(s.conj() * g[j]));
            g[j] = g[j] * c;
            h.push(col);
            total += 1;
            let rel = g[j + 1].norm_sqr().sqrt() / bnorm;
            history.push(rel);
            if next_norm > 0.0 {
                v.push(w.iter().map(|a| *a * (1.0 / next_norm)).collect());
            }
            if rel <= tol || next_norm == 0.0 || total >= max_iter {
                converged = rel <= tol || next_norm == 0.0;
                break;
            }
        }
        // y from the triangular system, x += M⁻¹ (V y)
        let m = h.len();
        let mut y = vec![T::zero(); m];
        for i in (0..m).rev() {
            let mut s = g[i];
            for k in i + 1..m {
                s = s - h[k][i] * y[k];
            }
            y[i] = s / h[i][i];
        }
        let mut vy = vec![T::zero(); n];
        for (yk, vk) in y.iter().zip(&v) {
            for (a, vi) in vy.iter_mut().zip(vk) {
                *a = *a + *yk * *vi;
            }
        }
        for (xi, d) in x.iter_mut().zip(prec(&vy)) {
            *xi = *xi + d;
        }
        if converged {
            return Ok((
                x,
                GmresInfo {
                    iterations: total,
                    history,
                },
            ));
        }
        if total >= max_iter {
            return Err(GmresError {
                reached: history.last().copied().unwrap_or(1.0),
                wanted: tol,
                iterations: total,
                history,
            });
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
