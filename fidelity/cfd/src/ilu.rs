//! Block ILU(0) with 5 × 5 blocks, real or complex: the incomplete LU factors of a block-sparse
//! matrix kept to the matrix's own block pattern (no fill). The preconditioner for meshes whose
//! complete sparse LU would not fit in memory; its cost is linear in the number of blocks.

use crate::gas::NVAR;
use crate::jacobian::Blocks;
use crate::krylov::Field;

type Block<T> = [[T; NVAR]; NVAR];

/// Incomplete block LU factors: per block row, the strictly lower blocks (L, unit diagonal), the
/// inverted diagonal block of U and the strictly upper blocks of U.
#[derive(Clone, Debug)]
pub struct BlockIlu<T> {
    /// Per row: (column, block) sorted by column, diagonal included.
    rows: Vec<Vec<(usize, Block<T>)>>,
    /// Position of the diagonal in each row.
    diag: Vec<usize>,
    /// Inverse of each row's diagonal block of U.
    inv_diag: Vec<Block<T>>,
}

fn zero<T: Field>() -> Block<T> {
    [[T::zero(); NVAR]; NVAR]
}

fn mul<T: Field>(a: &Block<T>, b: &Block<T>) -> Block<T> {
    std::array::from_fn(|i| {
        std::array::from_fn(|j| (0..NVAR).fold(T::zero(), |s, k| s + a[i][k] * b[k][j]))
    })
}

/// The inverse of a block by Gauss–Jordan elimination with partial pivoting; None when singular.
fn invert<T: Field>(a: &Block<T>) -> Option<Block<T>> {
    let mut m = *a;
    let mut inv: Block<T> = std::array::from_fn(|i| {
        std::array::from_fn(|j| T::from_re(if i == j { 1.0 } else { 0.0 }))
    });
    for c in 0..NVAR {
        let p = (c..NVAR).max_by(|&x, &y| m[x][c].norm_sqr().total_cmp(&m[y][c].norm_sqr()))?;
        if m[p][c].norm_sqr() == 0.0 {
            return None;
        }
        m.swap(c, p);
        inv.swap(c, p);
        let d = m[c][c];
        for j in 0..NVAR {
            m[c][j] = m[c][j] / d;
            inv[c][j] = inv[c][j] / d;
        }
        for r in 0..NVAR {
            if r != c {
                let f = m[r][c];
                for j in 0..NVAR {
                    m[r][j] = m[r][j] - f * m[c][j];
                    inv[r][j] = inv[r][j] - f * inv[c][j];
                }
            }
        }
    }
    Some(inv)
}

impl<T: Field> BlockIlu<T> {
    /// Factors diag(shift) + A for the real blocks of A over `n` block rows; fails naming the
    /// block row whose pivot block is singular.
    pub fn new(n: usize, blocks: &Blocks, shift: &dyn Fn(usize) -> T) -> Result<Self, String> {
        let mut rows: Vec<Vec<(usize, Block<T>)>> = vec![Vec::new(); n];
        for (r, c, b) in blocks {
            let row = &mut rows[*r];
            let pos = match row.iter().position(|(col, _)| col == c) {
                Some(p) => p,
                None => {
                    row.push((*c, zero()));
                    row.len() - 1
                }
            };
            for i in 0..NVAR {
                for j in 0..NVAR {
                    row[pos].1[i][j] = row[pos].1[i][j] + T::from_re(b[i][j]);
                }
            }
        }
        let mut diag = vec![0; n];
        for (i, row) in rows.iter_mut().enumerate() {
            if !row.iter().any(|(c, _)| *c == i) {
                row.push((i, zero()));
            }
            row.sort_by_key(|(c, _)| *c);
            let d = row
                .iter()
                .position(|(c, _)| *c == i)
                .expect("diagonal present");
            let s = shift(i);
            for k in 0..NVAR {
                row[d].1[k][k] = row[d].1[k][k] + s;
            }
            diag[i] = d;
        }
        let mut inv_diag: Vec<Block<T>> = Vec::with_capacity(n);
        for i in 0..n {
            // eliminate the lower blocks of row i in column order (IKJ ILU(0))
            for p in 0..diag[i] {
                let k = rows[i][p].0;
                let l_ik = mul(&rows[i][p].1, &inv_diag[k]);
                rows[i][p].1 = l_ik;
                for q in diag[k] + 1..rows[k].len() {
                    let (j, u_kj) = rows[k][q];
                    if let Ok(pos) = rows[i].binary_search_by_key(&j, |(c, _)| *c) {
                        let upd = mul(&l_ik, &u_kj);
                        for a in 0..NVAR {
                            for b in 0..NVAR {
                                rows[i][pos].1[a][b] = rows[i][pos].1[a][b] - upd[a][b];
                            }
                        }
                    }
                }
            }
            let inv = invert(&rows[i][diag[i]].1)
                .ok_or_else(|| format!("block ILU(0): singular pivot block in row {i}"))?;
            inv_diag.push(inv);
        }
        Ok(Self {
            rows,
            diag,
            inv_diag,
        })
    }

    /// x = (LU)⁻¹ b by forward and backward block substitution.
    pub fn apply(&self, b: &[T]) -> Vec<T> {
        let n = self.rows.len();
        let mut y = b.to_vec();
        for i in 0..n {
            for p in 0..self.diag[i] {
                let (k, l) = &self.rows[i][p];
                for a in 0..NVAR {
                    let s = (0..NVAR).fold(T::zero(), |s, c| s + l[a][c] * y[k * NVAR + c]);
                    y[i * NVAR + a] = y[i * NVAR + a] - s;
                }
            }
        }
        let mut x = y;
        for i in (0..n).rev() {
            let mut r: [T; NVAR] = std::array::from_fn(|a| x[i * NVAR + a]);
            for (j, u) in &self.rows[i][self.diag[i] + 1..] {
                for a in 0..NVAR {
                    r[a] = r[a] - (0..NVAR).fold(T::zero(), |s, c| s + u[a][c] * x[j * NVAR + c]);
                }
            }
            let d = &self.inv_diag[i];
            for a in 0..NVAR {
                x[i * NVAR + a] = (0..NVAR).fold(T::zero(), |s, c| s + d[a][c] * r[c]);
            }
        }
        x
    }

    /// x = (LU)⁻ᵀ b (transposed, not conjugated): Uᵀ y = b forward, then Lᵀ x = y backward, both
    /// column by column over the stored rows.
    pub fn apply_transpose(&self, b: &[T]) -> Vec<T> {
        let n = self.rows.len();
        let mut r = b.to_vec();
        for i in 0..n {
            let d = &self.inv_diag[i];
            let y: [T; NVAR] = std::array::from_fn(|a| {
                (0..NVAR).fold(T::zero(), |s, c| s + d[c][a] * r[i * NVAR + c])
            });
            for a in 0..NVAR {
                r[i * NVAR + a] = y[a];
            }
            for (j, u) in &self.rows[i][self.diag[i] + 1..] {
                for c in 0..NVAR {
                    let s = (0..NVAR).fold(T::zero(), |s, a| s + u[a][c] * y[a]);
                    r[j * NVAR + c] = r[j * NVAR + c] - s;
                }
            }
        }
        for i in (0..n).rev() {
            let x: [T; NVAR] = std::array::from_fn(|a| r[i * NVAR + a]);
            for p in 0..self.diag[i] {
                let (k, l) = &self.rows[i][p];
                for c in 0..NVAR {
                    let s = (0..NVAR).fold(T::zero(), |s, a| s + l[a][c] * x[a]);
                    r[k * NVAR + c] = r[k * NVAR + c] - s;
                }
            }
        }
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_complex::Complex64 as C64;

    /// On a block-tridiagonal matrix ILU(0) has no fill to drop: it is the exact LU, and applying
    /// it solves the system to round-off (complex shift included).
    #[test]
    fn exact_on_block_tridiagonal() {
        let n = 30;
        let r = gustkit_testkit::rand_vec(3 * n * NVAR * NVAR, 3);
        let mut blocks: Blocks = Vec::new();
        for i in 0..n {
            let b = |o: usize, diag: f64| -> [[f64; NVAR]; NVAR] {
                std::array::from_fn(|a| {
                    std::array::from_fn(|c| {
                        r[((3 * i + o) * NVAR + a) * NVAR + c] + if a == c { diag } else { 0.0 }
                    })
                })
            };
            blocks.push((i, i, b(0, 6.0)));
            if i > 0 {
                blocks.push((i, i - 1, b(1, 0.0)));
            }
            if i + 1 < n {
                blocks.push((i, i + 1, b(2, 0.0)));
            }
        }
        let shift = C64::new(0.3, 1.7);
        let ilu = BlockIlu::new(n, &blocks, &|_| shift).unwrap();
        let x: Vec<C64> = (0..n * NVAR)
            .map(|i| C64::new((i as f64 * 0.7).sin(), (i as f64 * 0.3).cos()))
            .collect();
        // b = (shift I + A) x
        let mut b: Vec<C64> = x.iter().map(|v| v * shift).collect();
        for (row, col, blk) in &blocks {
            for a in 0..NVAR {
                for c in 0..NVAR {
                    b[row * NVAR + a] += x[col * NVAR + c] * blk[a][c];
                }
            }
        }
        let y = ilu.apply(&b);
        let err = y
            .iter()
            .zip(&x)
            .map(|(p, q)| (p - q).norm())
            .fold(0.0, f64::max);
        assert!(err < 1e-12, "{err:e}");
    }

    /// The transposed application is the transpose of the application: yᵀ (M⁻¹ x) = (M⁻ᵀ y)ᵀ x
    /// to round-off, on a block pattern with fill dropped (a 2-D five-point stencil).
    #[test]
    fn transpose_is_the_adjoint_of_apply() {
        let (nx, ny) = (6, 5);
        let n = nx * ny;
        let r = gustkit_testkit::rand_vec(5 * n * NVAR * NVAR, 11);
        let mut blocks: Blocks = Vec::new();
        let mut next = 0;
        for j in 0..ny {
            for i in 0..nx {
                let row = j * nx + i;
                let mut add = |col: usize, diag: f64| {
                    let o = next;
                    next += 1;
                    blocks.push((
                        row,
                        col,
                        std::array::from_fn(|a| {
                            std::array::from_fn(|c| {
                                r[(o * NVAR + a) * NVAR + c] + if a == c { diag } else { 0.0 }
                            })
                        }),
                    ));
                };
                add(row, 8.0);
                if i > 0 {
                    add(row - 1, 0.0);
                }
                if i + 1 < nx {
                    add(row + 1, 0.0);
                }
                if j > 0 {
                    add(row - nx, 0.0);
                }
                if j + 1 < ny {
                    add(row + nx, 0.0);
                }
            }
        }
        let ilu = BlockIlu::new(n, &blocks, &|_| C64::new(0.5, 2.0)).unwrap();
        let x: Vec<C64> = (0..n * NVAR)
            .map(|i| C64::new((i as f64 * 0.7).sin(), (i as f64 * 0.3).cos()))
            .collect();
        let y: Vec<C64> = (0..n * NVAR)
            .map(|i| C64::new((i as f64 * 1.1).cos(), (i as f64 * 0.9).sin()))
            .collect();
        let dot = |a: &[C64], b: &[C64]| a.iter().zip(b).map(|(p, q)| p * q).sum::<C64>();
        let lhs = dot(&y, &ilu.apply(&x));
        let rhs = dot(&ilu.apply_transpose(&y), &x);
        assert!((lhs - rhs).norm() < 1e-13 * lhs.norm(), "{lhs} vs {rhs}");
    }
}
