//! Block ILU(k) with 5 × 5 blocks, real or complex: the incomplete LU factors of a block-sparse
//! matrix kept to the pattern of fill level ≤ k (k = 0: the matrix's own block pattern), after an
//! optional bandwidth-reducing reordering of the block rows (reverse Cuthill–McKee). The
//! preconditioner for meshes whose complete sparse LU would not fit in memory; its cost is
//! linear in the number of blocks of the pattern.

use crate::gas::NVAR;
use crate::jacobian::Blocks;
use crate::krylov::Field;

type Block<T> = [[T; NVAR]; NVAR];

/// The order in which the block rows are eliminated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum IluOrdering {
    /// The mesh's own cell order.
    #[default]
    Natural,
    /// Reverse Cuthill–McKee of the block pattern's graph (started from a pseudo-peripheral
    /// cell of each connected part): a narrow band, so that fill stays near the diagonal.
    ReverseCuthillMckee,
}

/// Settings of the incomplete factorization (defaults: ILU(0), natural order).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct IluParams {
    /// The largest level of fill kept (0: no fill).
    pub fill: usize,
    pub ordering: IluOrdering,
}

impl IluParams {
    /// Fill levels above 3 give patterns that cost more than they return on these meshes.
    pub fn validate(&self) -> Result<(), String> {
        if self.fill > 3 {
            return Err(format!(
                "the ILU fill level must be at most 3 (got {})",
                self.fill
            ));
        }
        Ok(())
    }
}

/// Incomplete block LU factors: per block row, the strictly lower blocks (L, unit diagonal), the
/// inverted diagonal block of U and the strictly upper blocks of U.
#[derive(Clone, Debug)]
pub struct BlockIlu<T> {
    /// New block-row index → the matrix's own (None: natural order).
    perm: Option<Vec<usize>>,
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

/// The reverse Cuthill–McKee order of the symmetrized block pattern: new index → old. Each
/// connected part starts at a pseudo-peripheral vertex (the last level of a breadth-first search
/// from a vertex of least degree, repeated while the depth grows); neighbours are visited by
/// increasing degree.
pub fn reverse_cuthill_mckee(n: usize, blocks: &Blocks) -> Vec<usize> {
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (r, c, _) in blocks {
        if r != c {
            adj[*r].push(*c);
            adj[*c].push(*r);
        }
    }
    for a in adj.iter_mut() {
        a.sort_unstable();
        a.dedup();
    }
    let degree = |v: usize| adj[v].len();
    // breadth-first search from `root` within the unvisited part: (order, start of the last
    // level in it, depth)
    let bfs = |root: usize, visited: &[bool]| -> (Vec<usize>, usize, usize) {
        let mut seen = visited.to_vec();
        let mut order = vec![root];
        seen[root] = true;
        let (mut start, mut last_level, mut depth) = (0, 0, 0);
        while start < order.len() {
            let end = order.len();
            for idx in start..end {
                let v = order[idx];
                let mut next: Vec<usize> = adj[v].iter().copied().filter(|&w| !seen[w]).collect();
                next.sort_by_key(|&w| (degree(w), w));
                for w in next {
                    seen[w] = true;
                    order.push(w);
                }
            }
            last_level = start;
            start = end;
            if start < order.len() {
                depth += 1;
            }
        }
        (order, last_level, depth)
    };
    let mut visited = vec![false; n];
    let mut result = Vec::with_capacity(n);
    for seed in 0..n {
        if visited[seed] {
            continue;
        }
        // least-degree vertex of this part, then pseudo-peripheral by repeated searches
        let (part, _, _) = bfs(seed, &visited);
        let root = *part.iter().min_by_key(|&&v| (degree(v), v)).expect("seed");
        let (mut order, mut last, mut depth) = bfs(root, &visited);
        for _ in 0..8 {
            let candidate = *order[last..]
                .iter()
                .min_by_key(|&&v| (degree(v), v))
                .expect("last level");
            let (o, l, d) = bfs(candidate, &visited);
            if d <= depth {
                break;
            }
            (order, last, depth) = (o, l, d);
        }
        for &v in &order {
            visited[v] = true;
        }
        result.extend(order);
    }
    result.reverse();
    result
}

/// The block pattern of fill level ≤ `fill` (symbolic ILU(k)): per row, the sorted columns.
/// Entries of A have level 0; eliminating column k of row i gives (i, j) the level
/// lev(i,k) + lev(k,j) + 1 for every j in row k's upper part.
fn fill_pattern(a_rows: &[Vec<usize>], fill: usize) -> Vec<Vec<usize>> {
    let n = a_rows.len();
    let mut upper: Vec<Vec<(usize, usize)>> = Vec::with_capacity(n);
    let mut pattern = Vec::with_capacity(n);
    let mut level = vec![usize::MAX; n];
    for (i, a_row) in a_rows.iter().enumerate() {
        let mut cols: Vec<usize> = a_row.clone();
        for &c in &cols {
            level[c] = 0;
        }
        if fill > 0 {
            let mut idx = 0;
            while idx < cols.len() && cols[idx] < i {
                let k = cols[idx];
                let l_ik = level[k];
                for &(j, l_kj) in &upper[k] {
                    let l = l_ik + l_kj + 1;
                    if l > fill {
                        continue;
                    }
                    if level[j] == usize::MAX {
                        let pos = cols.partition_point(|&c| c < j);
                        cols.insert(pos, j);
                        level[j] = l;
                    } else if l < level[j] {
                        level[j] = l;
                    }
                }
                idx += 1;
            }
        }
        upper.push(
            cols.iter()
                .filter(|&&c| c > i)
                .map(|&c| (c, level[c]))
                .collect(),
        );
        for &c in &cols {
            level[c] = usize::MAX;
        }
        pattern.push(cols);
    }
    pattern
}

impl<T: Field> BlockIlu<T> {
    /// Factors diag(shift) + A for the real blocks of A over `n` block rows with ILU(0) in the
    /// natural order; fails naming the block row whose pivot block is singular.
    pub fn new(n: usize, blocks: &Blocks, shift: &dyn Fn(usize) -> T) -> Result<Self, String> {
        Self::with_params(n, blocks, shift, &IluParams::default())
    }

    /// Number of stored blocks (L, U and diagonal): the factors take 25 scalars each.
    pub fn n_blocks(&self) -> usize {
        self.rows.iter().map(Vec::len).sum()
    }

    /// Factors diag(shift) + A with the given fill level and ordering (shift indexed by the
    /// matrix's own rows).
    pub fn with_params(
        n: usize,
        blocks: &Blocks,
        shift: &dyn Fn(usize) -> T,
        params: &IluParams,
    ) -> Result<Self, String> {
        params.validate()?;
        let perm = match params.ordering {
            IluOrdering::Natural => None,
            IluOrdering::ReverseCuthillMckee => Some(reverse_cuthill_mckee(n, blocks)),
        };
        let inverse = perm.as_ref().map(|p| {
            let mut inv = vec![0; n];
            for (new, &old) in p.iter().enumerate() {
                inv[old] = new;
            }
            inv
        });
        let new_index = |old: usize| inverse.as_ref().map_or(old, |inv| inv[old]);
        let mut a_rows: Vec<Vec<usize>> = vec![Vec::new(); n];
        for (r, c, _) in blocks {
            a_rows[new_index(*r)].push(new_index(*c));
        }
        for (i, row) in a_rows.iter_mut().enumerate() {
            row.push(i);
            row.sort_unstable();
            row.dedup();
        }
        let pattern = fill_pattern(&a_rows, params.fill);
        drop(a_rows);
        let mut rows: Vec<Vec<(usize, Block<T>)>> = pattern
            .into_iter()
            .map(|cols| cols.into_iter().map(|c| (c, zero())).collect())
            .collect();
        for (r, c, b) in blocks {
            let (r, c) = (new_index(*r), new_index(*c));
            let row = &mut rows[r];
            let pos = row
                .binary_search_by_key(&c, |(col, _)| *col)
                .expect("the pattern holds every block of A");
            for i in 0..NVAR {
                for j in 0..NVAR {
                    row[pos].1[i][j] = row[pos].1[i][j] + T::from_re(b[i][j]);
                }
            }
        }
        let mut diag = vec![0; n];
        for (i, row) in rows.iter_mut().enumerate() {
            let d = row
                .iter()
                .position(|(c, _)| *c == i)
                .expect("diagonal present");
            let s = shift(perm.as_ref().map_or(i, |p| p[i]));
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
            let inv = invert(&rows[i][diag[i]].1).ok_or_else(|| {
                let row = perm.as_ref().map_or(i, |p| p[i]);
                format!(
                    "block ILU({}): singular pivot block in row {row}",
                    params.fill
                )
            })?;
            inv_diag.push(inv);
        }
        Ok(Self {
            perm,
            rows,
            diag,
            inv_diag,
        })
    }

    /// b in the factorization's row order.
    fn to_new(&self, b: &[T]) -> Vec<T> {
        match &self.perm {
            None => b.to_vec(),
            Some(p) => p
                .iter()
                .flat_map(|&old| b[old * NVAR..(old + 1) * NVAR].iter().copied())
                .collect(),
        }
    }

    /// x from the factorization's row order back to the matrix's.
    fn to_old(&self, x: Vec<T>) -> Vec<T> {
        match &self.perm {
            None => x,
            Some(p) => {
                let mut out = x.clone();
                for (new, &old) in p.iter().enumerate() {
                    out[old * NVAR..(old + 1) * NVAR]
                        .copy_from_slice(&x[new * NVAR..(new + 1) * NVAR]);
                }
                out
            }
        }
    }

    /// x = (LU)⁻¹ b by forward and backward block substitution.
    pub fn apply(&self, b: &[T]) -> Vec<T> {
        let n = self.rows.len();
        let mut y = self.to_new(b);
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
        self.to_old(x)
    }

    /// x = (LU)⁻ᵀ b (transposed, not conjugated): Uᵀ y = b forward, then Lᵀ x = y backward, both
    /// column by column over the stored rows.
    pub fn apply_transpose(&self, b: &[T]) -> Vec<T> {
        let n = self.rows.len();
        let mut r = self.to_new(b);
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
        self.to_old(r)
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
        let blocks = five_point(nx, ny, 8.0, &|i, j| j * nx + i);
        let ilu = BlockIlu::new(nx * ny, &blocks, &|_| C64::new(0.5, 2.0)).unwrap();
        assert_transpose_consistent(&ilu, nx * ny);
    }

    /// yᵀ (M⁻¹ x) = (M⁻ᵀ y)ᵀ x to round-off for two fixed vectors.
    fn assert_transpose_consistent(ilu: &BlockIlu<C64>, n: usize) {
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

    /// The blocks of a 2-D five-point stencil on an nx × ny grid (random blocks, diagonally
    /// weighted by `diag`), rows numbered by `index(i, j)`.
    fn five_point(
        nx: usize,
        ny: usize,
        diag: f64,
        index: &dyn Fn(usize, usize) -> usize,
    ) -> Blocks {
        let r = gustkit_testkit::rand_vec(5 * nx * ny * NVAR * NVAR, 23);
        let mut blocks: Blocks = Vec::new();
        let mut next = 0;
        for j in 0..ny {
            for i in 0..nx {
                let row = index(i, j);
                let mut add = |col: usize, d: f64| {
                    let o = next;
                    next += 1;
                    blocks.push((
                        row,
                        col,
                        std::array::from_fn(|a| {
                            std::array::from_fn(|c| {
                                r[(o * NVAR + a) * NVAR + c] + if a == c { d } else { 0.0 }
                            })
                        }),
                    ));
                };
                add(row, diag);
                if i > 0 {
                    add(index(i - 1, j), 0.0);
                }
                if i + 1 < nx {
                    add(index(i + 1, j), 0.0);
                }
                if j > 0 {
                    add(index(i, j - 1), 0.0);
                }
                if j + 1 < ny {
                    add(index(i, j + 1), 0.0);
                }
            }
        }
        blocks
    }

    fn residual_error(n: usize, blocks: &Blocks, shift: C64, ilu: &BlockIlu<C64>) -> f64 {
        let x: Vec<C64> = (0..n * NVAR)
            .map(|i| C64::new((i as f64 * 0.7).sin(), (i as f64 * 0.3).cos()))
            .collect();
        let mut b: Vec<C64> = x.iter().map(|v| v * shift).collect();
        for (row, col, blk) in blocks {
            for a in 0..NVAR {
                for c in 0..NVAR {
                    b[row * NVAR + a] += x[col * NVAR + c] * blk[a][c];
                }
            }
        }
        ilu.apply(&b)
            .iter()
            .zip(&x)
            .map(|(p, q)| (p - q).norm())
            .fold(0.0, f64::max)
    }

    /// More fill, a closer inverse: on a 5 × 4 grid ILU(0), ILU(1), ILU(3) solve ever more
    /// accurately in the natural and the RCM order; where level 3 holds every block of the band
    /// (a 3-wide grid) ILU(3) is the complete LU and solves to round-off.
    #[test]
    fn full_fill_is_the_exact_lu_in_either_order() {
        let (nx, ny) = (5, 4);
        let n = nx * ny;
        let blocks = five_point(nx, ny, 8.0, &|i, j| j * nx + i);
        let shift = C64::new(0.4, 1.3);
        for ordering in [IluOrdering::Natural, IluOrdering::ReverseCuthillMckee] {
            let full = IluParams { fill: 3, ordering };
            let ilu = BlockIlu::with_params(n, &blocks, &|_| shift, &full).unwrap();
            let e3 = residual_error(n, &blocks, shift, &ilu);
            let e0 = residual_error(
                n,
                &blocks,
                shift,
                &BlockIlu::with_params(n, &blocks, &|_| shift, &IluParams { fill: 0, ordering })
                    .unwrap(),
            );
            let e1 = residual_error(
                n,
                &blocks,
                shift,
                &BlockIlu::with_params(n, &blocks, &|_| shift, &IluParams { fill: 1, ordering })
                    .unwrap(),
            );
            assert!(
                e0 > 1e-6 && e1 < e0,
                "{ordering:?}: ILU(0) {e0:e}, ILU(1) {e1:e}"
            );
            assert!(e3 < e1, "{ordering:?}: ILU(3) {e3:e}, ILU(1) {e1:e}");
        }
        // a 3-wide grid in natural order: its LU fills the band ±3, every band block within
        // level 3 (the deepest chain: (5,6) level 2 from the west neighbour's fill, then (8,6)
        // level 0 + 2 + 1), so ILU(3) is the complete LU
        let (nx, ny) = (3, 6);
        let n = nx * ny;
        let blocks = five_point(nx, ny, 8.0, &|i, j| j * nx + i);
        let exact = IluParams {
            fill: 3,
            ordering: IluOrdering::Natural,
        };
        let ilu = BlockIlu::with_params(n, &blocks, &|_| shift, &exact).unwrap();
        let e = residual_error(n, &blocks, shift, &ilu);
        assert!(e < 1e-12, "ILU(3) on a 3-wide band: {e:e}");
    }

    /// ILU(1) of the five-point stencil in natural order adds exactly the two diagonals at
    /// ±(nx − 1) (the classical result: eliminating the west neighbour fills north-west of the
    /// south neighbour's row and vice versa).
    #[test]
    fn ilu1_fill_of_the_five_point_stencil() {
        let (nx, ny) = (6, 5);
        let n = nx * ny;
        let blocks = five_point(nx, ny, 8.0, &|i, j| j * nx + i);
        let ilu = BlockIlu::with_params(
            n,
            &blocks,
            &|_| C64::new(0.0, 1.0),
            &IluParams {
                fill: 1,
                ordering: IluOrdering::Natural,
            },
        )
        .unwrap();
        for (r, row) in ilu.rows.iter().enumerate() {
            let (i, j) = (r % nx, r / nx);
            let mut expect = vec![r];
            if i > 0 {
                expect.push(r - 1);
            }
            if i + 1 < nx {
                expect.push(r + 1);
            }
            if j > 0 {
                expect.push(r - nx);
                if i + 1 < nx {
                    expect.push(r - nx + 1);
                }
            }
            if j + 1 < ny {
                expect.push(r + nx);
                if i > 0 {
                    expect.push(r + nx - 1);
                }
            }
            expect.sort_unstable();
            let cols: Vec<usize> = row.iter().map(|(c, _)| *c).collect();
            assert_eq!(cols, expect, "row {r}");
        }
    }

    /// RCM returns a permutation and brings a scrambled grid's bandwidth back to the grid's
    /// narrow width (at most the shorter side + 1), from tens of rows.
    #[test]
    fn rcm_narrows_a_scrambled_grid() {
        let (nx, ny) = (12, 5);
        let n = nx * ny;
        // a fixed scramble: multiplication by a unit modulo n
        let scramble = |i: usize, j: usize| ((j * nx + i) * 37) % n;
        let blocks = five_point(nx, ny, 8.0, &scramble);
        let band = |new_of: &dyn Fn(usize) -> usize| {
            blocks
                .iter()
                .map(|(r, c, _)| new_of(*r).abs_diff(new_of(*c)))
                .max()
                .unwrap()
        };
        let before = band(&|i| i);
        let perm = reverse_cuthill_mckee(n, &blocks);
        let mut inv = vec![usize::MAX; n];
        for (new, &old) in perm.iter().enumerate() {
            assert_eq!(inv[old], usize::MAX, "cell {old} twice");
            inv[old] = new;
        }
        let after = band(&|i| inv[i]);
        assert!(before > 30, "scrambled bandwidth {before}");
        assert!(after <= ny + 1, "RCM bandwidth {after}");
    }

    /// Fill and reordering keep the transposed application the transpose of the application.
    #[test]
    fn transpose_with_fill_and_ordering() {
        let (nx, ny) = (7, 4);
        let n = nx * ny;
        let blocks = five_point(nx, ny, 6.0, &|i, j| j * nx + i);
        let ilu = BlockIlu::with_params(
            n,
            &blocks,
            &|c| C64::new(0.5, 0.1 * c as f64),
            &IluParams {
                fill: 2,
                ordering: IluOrdering::ReverseCuthillMckee,
            },
        )
        .unwrap();
        assert_transpose_consistent(&ilu, n);
    }
}
