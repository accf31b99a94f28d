//! Block ILU(k) with 5 × 5 blocks, real or complex: the incomplete LU factors of a block-sparse
//! matrix kept to the pattern of fill level ≤ k (k = 0: the matrix's own block pattern), after an
//! optional bandwidth-reducing reordering of the block rows (reverse Cuthill–McKee). The
//! preconditioner for meshes whose complete sparse LU would not fit in memory; its cost is
//! linear in the number of blocks of the pattern.

use crate::gas::NVAR;
use crate::jacobian::{cell, cell_mut, Blocks};
use crate::krylov::Field;
use num_complex::{Complex32 as C32, Complex64 as C64};

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

/// The precision the factors are stored in (they are computed in the working precision, f64
/// or complex f64, one row at a time).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum IluPrecision {
    /// f32 (complex f32) factors: half the memory. A preconditioner's factors need only a few
    /// digits — the Krylov solver converges on the exact operator to its own tolerance — so the
    /// default.
    #[default]
    Single,
    /// f64 (complex f64) factors: the factors exactly as computed.
    Double,
}

/// Settings of the incomplete factorization (defaults: ILU(0), natural order, single-precision
/// factors).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct IluParams {
    /// The largest level of fill kept (0: no fill).
    pub fill: usize,
    pub ordering: IluOrdering,
    pub precision: IluPrecision,
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

/// A scalar the factors of a `T` factorization can be kept in: `T` itself or a narrower type.
pub trait Stored<T>: Copy + Send + Sync + std::fmt::Debug {
    fn store(v: T) -> Self;
    fn load(self) -> T;
}

impl<T: Field> Stored<T> for T {
    fn store(v: T) -> Self {
        v
    }
    fn load(self) -> T {
        self
    }
}

impl Stored<f64> for f32 {
    fn store(v: f64) -> Self {
        v as f32
    }
    fn load(self) -> f64 {
        self as f64
    }
}

impl Stored<C64> for C32 {
    fn store(v: C64) -> Self {
        C32::new(v.re as f32, v.im as f32)
    }
    fn load(self) -> C64 {
        C64::new(self.re as f64, self.im as f64)
    }
}

/// Cell j of every field r less Bᵀ x of its own x: one block of a transposed substitution
/// applied to a whole batch.
fn subtract_transposed<T: Field>(b: &Block<T>, xs: &[[T; NVAR]], rs: &mut [Vec<T>], j: usize) {
    for (x, r) in xs.iter().zip(rs.iter_mut()) {
        let rj = cell_mut(r, j);
        for c in 0..NVAR {
            let s = (0..NVAR).fold(T::zero(), |s, a| s + b[a][c] * x[a]);
            rj[c] = rj[c] - s;
        }
    }
}

/// A field whose ILU factors may be stored in single precision.
pub trait IluField: Field {
    type Single: Stored<Self>;
}

impl IluField for f64 {
    type Single = f32;
}

impl IluField for C64 {
    type Single = C32;
}

/// The factors' numbers: the off-diagonal blocks of L and U in the order of
/// [`BlockIlu::cols`], and the inverted diagonal blocks of U.
type Numbers<S> = (Vec<Block<S>>, Vec<Block<S>>);

/// The factors' numbers in the precision they are stored in.
#[derive(Clone, Debug)]
enum Factors<T: IluField> {
    Double(Numbers<T>),
    Single(Numbers<T::Single>),
}

/// Incomplete block LU factors in compressed rows: per block row the strictly lower blocks (L,
/// unit diagonal) then the strictly upper blocks of U, and the inverted diagonal block of U.
#[derive(Clone, Debug)]
pub struct BlockIlu<T: IluField> {
    /// New block-row index → the matrix's own (None: natural order).
    perm: Option<Vec<usize>>,
    /// Row i's off-diagonal blocks are `row_start[i]..row_start[i + 1]`: L up to `upper[i]`,
    /// then U.
    row_start: Vec<usize>,
    upper: Vec<usize>,
    /// The column of each off-diagonal block, increasing within a row.
    cols: Vec<u32>,
    factors: Factors<T>,
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

/// The blocks of A by row of the factorization's order: row i's are
/// `blocks[index[start[i]..start[i + 1]]]`, their columns mapped by `new_index`.
struct ARows<'a> {
    start: &'a [usize],
    index: &'a [usize],
    blocks: &'a Blocks,
    new_index: &'a dyn Fn(usize) -> usize,
}

/// The position of column `j` in row `i`'s working copy (its L blocks, the diagonal, its U
/// blocks), if the pattern holds it; `lower` and `upper_cols` are the row's off-diagonal columns.
fn slot(i: usize, j: usize, lower: &[u32], upper_cols: &[u32]) -> Option<usize> {
    use std::cmp::Ordering::*;
    match j.cmp(&i) {
        Less => lower.binary_search(&(j as u32)).ok(),
        Equal => Some(lower.len()),
        Greater => upper_cols
            .binary_search(&(j as u32))
            .ok()
            .map(|p| lower.len() + 1 + p),
    }
}

impl<T: IluField> BlockIlu<T> {
    /// Factors diag(shift) + A for the real blocks of A over `n` block rows with ILU(0) in the
    /// natural order; fails naming the block row whose pivot block is singular.
    pub fn new(n: usize, blocks: &Blocks, shift: &dyn Fn(usize) -> T) -> Result<Self, String> {
        Self::with_params(n, blocks, shift, &IluParams::default())
    }

    /// Number of stored blocks (L, U and diagonal): the factors take 25 scalars each.
    pub fn n_blocks(&self) -> usize {
        self.cols.len() + self.row_start.len() - 1
    }

    /// Memory held by the factors, bytes.
    pub fn bytes(&self) -> usize {
        let n = self.row_start.len() - 1;
        let numbers = match &self.factors {
            Factors::Double(..) => std::mem::size_of::<Block<T>>(),
            Factors::Single(..) => std::mem::size_of::<Block<T::Single>>(),
        } * (self.cols.len() + n);
        numbers
            + self.cols.len() * 4
            + (2 * n + 1) * 8
            + self.perm.as_ref().map_or(0, |p| p.len() * 8)
    }

    /// Factors diag(shift) + A with the given fill level, ordering and precision (shift indexed
    /// by the matrix's own rows). Each row is eliminated in the working precision against the
    /// stored rows above it, then stored: the working copy is one row.
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
        let mut row_start = Vec::with_capacity(n + 1);
        let mut upper = Vec::with_capacity(n);
        let mut cols = Vec::with_capacity(pattern.iter().map(|r| r.len() - 1).sum());
        for (i, row) in pattern.into_iter().enumerate() {
            row_start.push(cols.len());
            cols.extend(row.iter().filter(|&&c| c < i).map(|&c| c as u32));
            upper.push(cols.len());
            cols.extend(row.iter().filter(|&&c| c > i).map(|&c| c as u32));
        }
        row_start.push(cols.len());
        // the blocks of A by (new) row
        let mut a_start = vec![0usize; n + 1];
        for (r, _, _) in blocks {
            a_start[new_index(*r) + 1] += 1;
        }
        for i in 0..n {
            a_start[i + 1] += a_start[i];
        }
        let mut a_index = vec![0usize; blocks.len()];
        let mut next = a_start.clone();
        for (b, (r, _, _)) in blocks.iter().enumerate() {
            let r = new_index(*r);
            a_index[next[r]] = b;
            next[r] += 1;
        }
        drop(next);
        let mut ilu = Self {
            perm,
            row_start,
            upper,
            cols,
            factors: Factors::Double((Vec::new(), Vec::new())),
        };
        let a = ARows {
            start: &a_start,
            index: &a_index,
            blocks,
            new_index: &new_index,
        };
        ilu.factors = match params.precision {
            IluPrecision::Double => Factors::Double(ilu.factor::<T>(a, shift, params.fill)?),
            IluPrecision::Single => {
                Factors::Single(ilu.factor::<T::Single>(a, shift, params.fill)?)
            }
        };
        Ok(ilu)
    }

    /// The IKJ elimination over the structure of `self`, storing in `S`: (off-diagonal blocks,
    /// inverted diagonal blocks).
    fn factor<S: Stored<T>>(
        &self,
        a: ARows,
        shift: &dyn Fn(usize) -> T,
        fill: usize,
    ) -> Result<Numbers<S>, String> {
        let n = self.row_start.len() - 1;
        let load = |b: &Block<S>| -> Block<T> { b.map(|r| r.map(S::load)) };
        let store = |b: &Block<T>| -> Block<S> { b.map(|r| r.map(S::store)) };
        let mut off: Vec<Block<S>> = Vec::with_capacity(self.cols.len());
        let mut inv_diag: Vec<Block<S>> = Vec::with_capacity(n);
        let mut work: Vec<Block<T>> = Vec::new();
        for i in 0..n {
            let (lo, up, hi) = (self.row_start[i], self.upper[i], self.row_start[i + 1]);
            let (lower, upper_cols) = (&self.cols[lo..up], &self.cols[up..hi]);
            let d = up - lo;
            work.clear();
            work.resize(hi - lo + 1, zero());
            for &b in &a.index[a.start[i]..a.start[i + 1]] {
                let (_, c, blk) = &a.blocks[b];
                let p = slot(i, (a.new_index)(*c), lower, upper_cols)
                    .expect("the pattern holds every block of A");
                for r in 0..NVAR {
                    for q in 0..NVAR {
                        work[p][r][q] = work[p][r][q] + T::from_re(blk[r][q]);
                    }
                }
            }
            let s = shift(self.perm.as_ref().map_or(i, |p| p[i]));
            for k in 0..NVAR {
                work[d][k][k] = work[d][k][k] + s;
            }
            // eliminate the lower blocks of row i in column order against the stored rows
            for p in 0..d {
                let k = lower[p] as usize;
                let l_ik = mul(&work[p], &load(&inv_diag[k]));
                work[p] = l_ik;
                for q in self.upper[k]..self.row_start[k + 1] {
                    let j = self.cols[q] as usize;
                    if let Some(pos) = slot(i, j, lower, upper_cols) {
                        let upd = mul(&l_ik, &load(&off[q]));
                        for a in 0..NVAR {
                            for b in 0..NVAR {
                                work[pos][a][b] = work[pos][a][b] - upd[a][b];
                            }
                        }
                    }
                }
            }
            let inv = invert(&work[d]).ok_or_else(|| {
                let row = self.perm.as_ref().map_or(i, |p| p[i]);
                format!("block ILU({fill}): singular pivot block in row {row}")
            })?;
            off.extend(work[..d].iter().chain(&work[d + 1..]).map(store));
            inv_diag.push(store(&inv));
        }
        Ok((off, inv_diag))
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
        self.apply_many(&[b]).pop().expect("one vector in, one out")
    }

    /// x = (LU)⁻ᵀ b (transposed, not conjugated).
    pub fn apply_transpose(&self, b: &[T]) -> Vec<T> {
        self.apply_transpose_many(&[b])
            .pop()
            .expect("one vector in, one out")
    }

    /// [`BlockIlu::apply`] on several vectors in one sweep over the factors (each block is read
    /// once for all of them); each result is that of `apply` on its vector, bit for bit.
    pub fn apply_many(&self, bs: &[&[T]]) -> Vec<Vec<T>> {
        self.sweep_many(bs, false)
    }

    /// [`BlockIlu::apply_transpose`] on several vectors in one sweep over the factors.
    pub fn apply_transpose_many(&self, bs: &[&[T]]) -> Vec<Vec<T>> {
        self.sweep_many(bs, true)
    }

    /// The forward (`transpose` false) or transposed substitutions on several vectors, in the
    /// factorization's order and back.
    fn sweep_many(&self, bs: &[&[T]], transpose: bool) -> Vec<Vec<T>> {
        let mut ys: Vec<Vec<T>> = bs.iter().map(|b| self.to_new(b)).collect();
        match (&self.factors, transpose) {
            (Factors::Double((off, inv)), false) => self.substitute(off, inv, &mut ys),
            (Factors::Single((off, inv)), false) => self.substitute(off, inv, &mut ys),
            (Factors::Double((off, inv)), true) => self.substitute_transpose(off, inv, &mut ys),
            (Factors::Single((off, inv)), true) => self.substitute_transpose(off, inv, &mut ys),
        }
        ys.into_iter().map(|x| self.to_old(x)).collect()
    }

    /// L U x = y in the factorization's order, in place, for every y.
    fn substitute<S: Stored<T>>(&self, off: &[Block<S>], inv: &[Block<S>], ys: &mut [Vec<T>]) {
        let n = inv.len();
        let load = |b: &Block<S>| -> Block<T> { b.map(|r| r.map(S::load)) };
        for i in 0..n {
            for p in self.row_start[i]..self.upper[i] {
                let (k, l) = (self.cols[p] as usize, load(&off[p]));
                for y in ys.iter_mut() {
                    let yk = cell(y, k);
                    let yi = cell_mut(y, i);
                    for a in 0..NVAR {
                        let s = (0..NVAR).fold(T::zero(), |s, c| s + l[a][c] * yk[c]);
                        yi[a] = yi[a] - s;
                    }
                }
            }
        }
        let mut rs: Vec<[T; NVAR]> = vec![[T::zero(); NVAR]; ys.len()];
        for i in (0..n).rev() {
            for (r, y) in rs.iter_mut().zip(ys.iter()) {
                *r = cell(y, i);
            }
            for q in self.upper[i]..self.row_start[i + 1] {
                let (j, u) = (self.cols[q] as usize, load(&off[q]));
                for (r, y) in rs.iter_mut().zip(ys.iter()) {
                    let yj = cell(y, j);
                    for a in 0..NVAR {
                        r[a] = r[a] - (0..NVAR).fold(T::zero(), |s, c| s + u[a][c] * yj[c]);
                    }
                }
            }
            let d = load(&inv[i]);
            for (r, y) in rs.iter().zip(ys.iter_mut()) {
                let yi = cell_mut(y, i);
                for a in 0..NVAR {
                    yi[a] = (0..NVAR).fold(T::zero(), |s, c| s + d[a][c] * r[c]);
                }
            }
        }
    }

    /// (L U)ᵀ x = r in the factorization's order, in place, for every r: Uᵀ y = r forward, then
    /// Lᵀ x = y backward, both column by column over the stored rows.
    fn substitute_transpose<S: Stored<T>>(
        &self,
        off: &[Block<S>],
        inv: &[Block<S>],
        rs: &mut [Vec<T>],
    ) {
        let n = inv.len();
        let load = |b: &Block<S>| -> Block<T> { b.map(|r| r.map(S::load)) };
        let mut ys: Vec<[T; NVAR]> = vec![[T::zero(); NVAR]; rs.len()];
        for i in 0..n {
            let d = load(&inv[i]);
            for (y, r) in ys.iter_mut().zip(rs.iter_mut()) {
                let ri = cell_mut(r, i);
                *y = std::array::from_fn(|a| (0..NVAR).fold(T::zero(), |s, c| s + d[c][a] * ri[c]));
                *ri = *y;
            }
            for q in self.upper[i]..self.row_start[i + 1] {
                subtract_transposed(&load(&off[q]), &ys, rs, self.cols[q] as usize);
            }
        }
        for i in (0..n).rev() {
            for (x, r) in ys.iter_mut().zip(rs.iter()) {
                *x = cell(r, i);
            }
            for p in self.row_start[i]..self.upper[i] {
                subtract_transposed(&load(&off[p]), &ys, rs, self.cols[p] as usize);
            }
        }
    }
    /// Row r's stored columns, the diagonal included (for tests of the pattern).
    #[cfg(test)]
    fn row_columns(&self, r: usize) -> Vec<usize> {
        let mut c: Vec<usize> = self.cols[self.row_start[r]..self.row_start[r + 1]]
            .iter()
            .map(|&c| c as usize)
            .collect();
        c.push(r);
        c.sort_unstable();
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let double = IluParams {
            precision: IluPrecision::Double,
            ..IluParams::default()
        };
        let ilu = BlockIlu::with_params(n, &blocks, &|_| shift, &double).unwrap();
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
        // the same factors stored in single precision (f32 unit round-off 6e-8; the diagonally
        // weighted blocks are well conditioned): the solution to about single precision, not
        // better (they really are rounded), in half the bytes of the numbers
        let single = BlockIlu::with_params(n, &blocks, &|_| shift, &IluParams::default()).unwrap();
        let err32 = single
            .apply(&b)
            .iter()
            .zip(&x)
            .map(|(p, q)| (p - q).norm())
            .fold(0.0, f64::max);
        assert!(err32 > 1e-10 && err32 < 1e-5, "{err32:e}");
        let numbers = |ilu: &BlockIlu<C64>| ilu.bytes() - ilu.cols.len() * 4 - (2 * n + 1) * 8;
        assert_eq!(2 * numbers(&single), numbers(&ilu));
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
            let params = |fill| IluParams {
                fill,
                ordering,
                precision: IluPrecision::Double,
            };
            let full = params(3);
            let ilu = BlockIlu::with_params(n, &blocks, &|_| shift, &full).unwrap();
            let e3 = residual_error(n, &blocks, shift, &ilu);
            let e0 = residual_error(
                n,
                &blocks,
                shift,
                &BlockIlu::with_params(n, &blocks, &|_| shift, &params(0)).unwrap(),
            );
            let e1 = residual_error(
                n,
                &blocks,
                shift,
                &BlockIlu::with_params(n, &blocks, &|_| shift, &params(1)).unwrap(),
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
            precision: IluPrecision::Double,
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
                ..IluParams::default()
            },
        )
        .unwrap();
        for r in 0..n {
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
            assert_eq!(ilu.row_columns(r), expect, "row {r}");
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
                ..IluParams::default()
            },
        )
        .unwrap();
        assert_transpose_consistent(&ilu, n);
    }
}
