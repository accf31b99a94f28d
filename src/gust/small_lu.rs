//! LU with partial pivoting of the small complex modal systems of the gust response (a few
//! modes, two thousand frequencies): plain loops over one row-major array, where a general dense
//! solver's dispatch and allocations cost more than the arithmetic at this size.

use faer::c64;

/// P A = L U of an n × n complex matrix (rows swapped in place; `perm[i]` is the original row
/// of row i).
#[derive(Clone, Debug)]
pub struct SmallLu {
    n: usize,
    lu: Vec<c64>,
    perm: Vec<usize>,
}

impl SmallLu {
    /// Factors the row-major matrix `a`; `None` when a pivot is zero or not finite.
    pub fn factor(n: usize, mut a: Vec<c64>) -> Option<Self> {
        debug_assert_eq!(a.len(), n * n);
        let mut perm: Vec<usize> = (0..n).collect();
        for k in 0..n {
            let p = (k..n)
                .max_by(|&x, &y| a[x * n + k].norm().total_cmp(&a[y * n + k].norm()))
                .expect("k < n");
            if p != k {
                for j in 0..n {
                    a.swap(k * n + j, p * n + j);
                }
                perm.swap(k, p);
            }
            let d = a[k * n + k];
            if d.norm() == 0.0 || !(d.re.is_finite() && d.im.is_finite()) {
                return None;
            }
            let inv = d.inv();
            for i in k + 1..n {
                let l = a[i * n + k] * inv;
                a[i * n + k] = l;
                for j in k + 1..n {
                    let u = a[k * n + j];
                    a[i * n + j] -= l * u;
                }
            }
        }
        Some(Self { n, lu: a, perm })
    }

    /// A x = b: returns x.
    pub fn solve(&self, b: &[c64]) -> Vec<c64> {
        let n = self.n;
        let mut x: Vec<c64> = self.perm.iter().map(|&p| b[p]).collect();
        for i in 0..n {
            let mut s = x[i];
            for j in 0..i {
                s -= self.lu[i * n + j] * x[j];
            }
            x[i] = s;
        }
        for i in (0..n).rev() {
            let mut s = x[i];
            for j in i + 1..n {
                s -= self.lu[i * n + j] * x[j];
            }
            x[i] = s / self.lu[i * n + i];
        }
        x
    }

    /// Aᴴ x = b (A = Pᵀ L U, so Uᴴ Lᴴ P x = b): returns x.
    pub fn solve_adjoint(&self, b: &[c64]) -> Vec<c64> {
        let n = self.n;
        let mut w = b.to_vec();
        // Uᴴ (lower triangular) z = b
        for i in 0..n {
            let mut s = w[i];
            for j in 0..i {
                s -= self.lu[j * n + i].conj() * w[j];
            }
            w[i] = s / self.lu[i * n + i].conj();
        }
        // Lᴴ (unit upper triangular) v = z
        for i in (0..n).rev() {
            let mut s = w[i];
            for j in i + 1..n {
                s -= self.lu[j * n + i].conj() * w[j];
            }
            w[i] = s;
        }
        let mut x = vec![c64::new(0.0, 0.0); n];
        for (i, &p) in self.perm.iter().enumerate() {
            x[p] = w[i];
        }
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 6 × 6 complex matrix that needs pivoting (a zero leading entry): A x = b and Aᴴ y = c
    /// recovered to 1e-13, and a singular matrix refused.
    #[test]
    fn small_lu_solves_and_adjoint_solves() {
        let n = 6;
        let a: Vec<c64> = (0..n * n)
            .map(|q| {
                // well conditioned (a dominant diagonal) but for the zero leading entry
                let dominant = if q % (n + 1) == 0 { 4.0 } else { 0.0 };
                if q == 0 {
                    c64::new(0.0, 0.0)
                } else {
                    c64::new((q as f64 * 0.71).sin() + dominant, (q as f64 * 0.37).cos())
                }
            })
            .collect();
        let x: Vec<c64> = (0..n)
            .map(|i| c64::new(1.0 + i as f64, -0.5 * i as f64))
            .collect();
        let mul = |adjoint: bool, v: &[c64]| -> Vec<c64> {
            (0..n)
                .map(|i| {
                    (0..n)
                        .map(|j| {
                            if adjoint {
                                a[j * n + i].conj() * v[j]
                            } else {
                                a[i * n + j] * v[j]
                            }
                        })
                        .sum()
                })
                .collect()
        };
        let lu = SmallLu::factor(n, a.clone()).unwrap();
        for adjoint in [false, true] {
            let b = mul(adjoint, &x);
            let got = if adjoint {
                lu.solve_adjoint(&b)
            } else {
                lu.solve(&b)
            };
            let worst = got
                .iter()
                .zip(&x)
                .fold(0.0f64, |m, (g, e)| m.max((g - e).norm()));
            assert!(worst < 1e-13, "adjoint {adjoint}: {worst:e}");
        }
        assert!(SmallLu::factor(n, vec![c64::new(0.0, 0.0); n * n]).is_none());
    }
}
