//! LU with partial pivoting of a banded matrix (LAPACK's gbtf2/gbtrs scheme), for Nelson's
//! eigenvector derivatives: the plate's K − λM is indefinite and banded (half-bandwidth 38 of 335
//! DOFs on the flagship's plate), where faer's general sparse LU spends about 1.5 ms on ordering
//! and symbolic work that a band needs none of (this factorization: about 0.4 ms).

/// Why a banded factorization failed.
#[derive(Debug, thiserror::Error)]
#[error("the banded matrix is singular (zero pivot in column {column})")]
pub struct SingularBand {
    pub column: usize,
}

/// P A = L U of an n × n matrix with `kl` sub- and `ku` super-diagonals. Row i keeps columns
/// i − kl ..= i + kl + ku (the upper band grows by kl through the row interchanges); L's
/// multipliers stay where they were computed, and the solve applies the interchanges as it goes.
#[derive(Clone, Debug)]
pub struct BandLu {
    n: usize,
    kl: usize,
    ku: usize,
    /// Row-major window of width 2 kl + ku + 1 per row.
    a: Vec<f64>,
    piv: Vec<usize>,
}

impl BandLu {
    fn width(kl: usize, ku: usize) -> usize {
        2 * kl + ku + 1
    }

    /// Index of (i, j) in the window (j within i − kl ..= i + kl + ku).
    #[inline]
    fn at(&self, i: usize, j: usize) -> usize {
        i * Self::width(self.kl, self.ku) + (j + self.kl - i)
    }

    /// Factors the matrix whose entries `entry(i, j)` are zero outside the band.
    pub fn factor(
        n: usize,
        kl: usize,
        ku: usize,
        entry: impl Fn(usize, usize) -> f64,
    ) -> Result<Self, SingularBand> {
        let w = Self::width(kl, ku);
        let mut lu = Self {
            n,
            kl,
            ku,
            a: vec![0.0; n * w],
            piv: vec![0; n],
        };
        for i in 0..n {
            for j in i.saturating_sub(kl)..=(i + ku).min(n.saturating_sub(1)) {
                let at = lu.at(i, j);
                lu.a[at] = entry(i, j);
            }
        }
        for k in 0..n {
            let last_row = (k + kl).min(n - 1);
            let last_col = (k + kl + ku).min(n - 1);
            let p = (k..=last_row)
                .max_by(|&x, &y| {
                    let (ax, ay) = (lu.a[lu.at(x, k)].abs(), lu.a[lu.at(y, k)].abs());
                    ax.total_cmp(&ay).then(y.cmp(&x))
                })
                .expect("k..=last_row is not empty");
            lu.piv[k] = p;
            if p != k {
                for j in k..=last_col {
                    let (x, y) = (lu.at(k, j), lu.at(p, j));
                    lu.a.swap(x, y);
                }
            }
            let d = lu.a[lu.at(k, k)];
            if d == 0.0 || !d.is_finite() {
                return Err(SingularBand { column: k });
            }
            for i in k + 1..=last_row {
                let ik = lu.at(i, k);
                let l = lu.a[ik] / d;
                lu.a[ik] = l;
                if l != 0.0 {
                    let (ri, rk) = (lu.at(i, k + 1), lu.at(k, k + 1));
                    for t in 0..last_col - k {
                        lu.a[ri + t] -= l * lu.a[rk + t];
                    }
                }
            }
        }
        Ok(lu)
    }

    /// Solves A x = b in place.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        let n = self.n;
        for k in 0..n {
            b.swap(k, self.piv[k]);
            let bk = b[k];
            for i in k + 1..=(k + self.kl).min(n - 1) {
                b[i] -= self.a[self.at(i, k)] * bk;
            }
        }
        for k in (0..n).rev() {
            let mut s = b[k];
            for j in k + 1..=(k + self.kl + self.ku).min(n - 1) {
                s -= self.a[self.at(k, j)] * b[j];
            }
            b[k] = s / self.a[self.at(k, k)];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A banded indefinite matrix with a zero diagonal entry (pivoting needed): the solution of
    /// A x = b is x to 1e-12, and a singular band is reported by column.
    #[test]
    fn band_lu_solves_with_pivoting() {
        let (n, kl, ku) = (40, 3, 2);
        let entry = |i: usize, j: usize| -> f64 {
            if j + kl < i || j > i + ku {
                0.0
            } else if i == j {
                if i % 5 == 0 {
                    0.0
                } else {
                    (i as f64 * 0.7).sin() - 0.2
                }
            } else {
                ((i * 7 + j * 3) as f64 * 0.37).cos()
            }
        };
        let x: Vec<f64> = (0..n).map(|i| 1.0 + (i as f64 * 0.3).cos()).collect();
        let mut b: Vec<f64> = (0..n)
            .map(|i| (0..n).map(|j| entry(i, j) * x[j]).sum())
            .collect();
        let lu = BandLu::factor(n, kl, ku, entry).unwrap();
        lu.solve_in_place(&mut b);
        let worst = b
            .iter()
            .zip(&x)
            .fold(0.0f64, |m, (a, e)| m.max((a - e).abs()));
        assert!(worst < 1e-12, "{worst:e}");
        let singular = BandLu::factor(4, 1, 1, |i, j| if i == 2 || j == 2 { 0.0 } else { 1.0 });
        assert!(singular.is_err());
    }
}
