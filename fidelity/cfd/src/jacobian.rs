//! The exact Jacobian of the residual at the scheme's order, assembled by graph colouring: the
//! residual of cell i depends on the states within two face-neighbour steps (face states of second
//! order use the least-squares gradients of both sides), so cells more than four steps apart can be
//! seeded together. One residual evaluation in `Dual<5>` per colour gives the five columns of
//! every cell of that colour. With it the sparse LU solves Newton and LFD systems directly.

use crate::gas::NVAR;
use crate::krylov::Field;
use crate::mesh::Side;
use crate::residual::{Euler, Order, State};
use gustkit_core::scalar::Dual;
use rayon::prelude::*;

/// The colouring and dependency sets of a mesh for Jacobian assembly.
#[derive(Clone, Debug)]
pub struct Coloring {
    /// Colour of every cell.
    pub color: Vec<usize>,
    pub n_colors: usize,
    /// Per cell: the cells its residual depends on (itself included), at the given order.
    deps: Vec<Vec<usize>>,
}

/// Face neighbours of every cell.
fn neighbours(e: &Euler) -> Vec<Vec<usize>> {
    let mut nb = vec![Vec::new(); e.mesh.n_cells];
    for f in &e.mesh.faces {
        if let Side::Cell(r) = f.right {
            nb[f.left].push(r);
            nb[r].push(f.left);
        }
    }
    nb
}

/// The cells within `depth` face-neighbour steps of `c` (breadth first, `c` first).
fn ball(nb: &[Vec<usize>], c: usize, depth: usize, mark: &mut [usize], stamp: usize) -> Vec<usize> {
    let mut out = vec![c];
    mark[c] = stamp;
    let mut frontier = vec![c];
    for _ in 0..depth {
        let mut next = Vec::new();
        for &a in &frontier {
            for &b in &nb[a] {
                if mark[b] != stamp {
                    mark[b] = stamp;
                    out.push(b);
                    next.push(b);
                }
            }
        }
        frontier = next;
    }
    out
}

impl Coloring {
    /// Greedy colouring of the cells such that no residual depends on two cells of one colour.
    pub fn new(e: &Euler, order: Order) -> Self {
        let nb = neighbours(e);
        let n = e.mesh.n_cells;
        let reach = match order {
            Order::First => 1,
            Order::Second => 2,
        };
        let mut mark = vec![usize::MAX; n];
        let deps: Vec<Vec<usize>> = (0..n).map(|c| ball(&nb, c, reach, &mut mark, c)).collect();
        let mut mark = vec![usize::MAX; n];
        let mut color = vec![usize::MAX; n];
        let mut used = Vec::new();
        for c in 0..n {
            // colours of the cells sharing a dependent residual with c (within 2 × reach)
            used.clear();
            for d in ball(&nb, c, 2 * reach, &mut mark, c) {
                if color[d] != usize::MAX {
                    used.push(color[d]);
                }
            }
            color[c] = (0..).find(|k| !used.contains(k)).expect("a free colour");
        }
        let n_colors = color.iter().max().map_or(0, |m| m + 1);
        Self {
            color,
            n_colors,
            deps,
        }
    }
}

/// The Jacobian ∂R/∂q as 5 × 5 blocks: (row cell, column cell, block).
pub type Blocks = Vec<(usize, usize, [[f64; NVAR]; NVAR])>;

/// A block-sparse matrix in compressed rows: fast products with the assembled Jacobian and its
/// transpose (a product is a few flops per stored entry, where a dual-number residual pass costs
/// the whole scheme).
#[derive(Clone, Debug)]
pub struct BlockRows {
    start: Vec<usize>,
    cols: Vec<usize>,
    vals: Vec<[[f64; NVAR]; NVAR]>,
}

/// Cell i's five unknowns of a flattened field, copied.
pub(crate) fn cell<T: Copy>(v: &[T], i: usize) -> [T; NVAR] {
    v[i * NVAR..(i + 1) * NVAR]
        .try_into()
        .expect("a cell has NVAR unknowns")
}

/// Cell i's five unknowns of a flattened field, in place.
pub(crate) fn cell_mut<T>(v: &mut [T], i: usize) -> &mut [T; NVAR] {
    (&mut v[i * NVAR..(i + 1) * NVAR])
        .try_into()
        .expect("a cell has NVAR unknowns")
}

impl BlockRows {
    /// The matrix of `blocks` over `n` block rows (repeated positions add).
    pub fn new(n: usize, blocks: &Blocks) -> Self {
        let mut count = vec![0usize; n + 1];
        for (r, _, _) in blocks {
            count[r + 1] += 1;
        }
        for i in 0..n {
            count[i + 1] += count[i];
        }
        let start = count.clone();
        let mut next = count;
        let mut cols = vec![0; blocks.len()];
        let mut vals = vec![[[0.0; NVAR]; NVAR]; blocks.len()];
        for (r, c, b) in blocks {
            let at = next[*r];
            next[*r] += 1;
            cols[at] = *c;
            vals[at] = *b;
        }
        Self { start, cols, vals }
    }

    /// Memory held, bytes.
    pub fn bytes(&self) -> usize {
        self.vals.len() * (NVAR * NVAR * 8 + 8) + self.start.len() * 8
    }

    /// y = A x.
    pub fn mul<T: Field>(&self, x: &[T]) -> Vec<T> {
        self.mul_many(&[x]).pop().expect("one vector in, one out")
    }

    /// y = Aᵀ x (transposed, not conjugated).
    pub fn mul_transpose<T: Field>(&self, x: &[T]) -> Vec<T> {
        self.mul_transpose_many(&[x])
            .pop()
            .expect("one vector in, one out")
    }

    /// A x for several x in one pass over the blocks (each read once for all of them); each
    /// product is that of [`BlockRows::mul`], bit for bit.
    pub fn mul_many<T: Field>(&self, xs: &[&[T]]) -> Vec<Vec<T>> {
        let n = self.start.len() - 1;
        let mut ys = vec![vec![T::zero(); n * NVAR]; xs.len()];
        let mut acc = vec![[T::zero(); NVAR]; xs.len()];
        for r in 0..n {
            acc.iter_mut().for_each(|a| *a = [T::zero(); NVAR]);
            for p in self.start[r]..self.start[r + 1] {
                let (c, b) = (self.cols[p], &self.vals[p]);
                for (a, x) in acc.iter_mut().zip(xs) {
                    let xc = cell(x, c);
                    for i in 0..NVAR {
                        for j in 0..NVAR {
                            a[i] = a[i] + xc[j] * b[i][j];
                        }
                    }
                }
            }
            for (y, a) in ys.iter_mut().zip(&acc) {
                y[r * NVAR..(r + 1) * NVAR].copy_from_slice(a);
            }
        }
        ys
    }

    /// Aᵀ x for several x in one pass over the blocks.
    pub fn mul_transpose_many<T: Field>(&self, xs: &[&[T]]) -> Vec<Vec<T>> {
        let n = self.start.len() - 1;
        let mut ys = vec![vec![T::zero(); n * NVAR]; xs.len()];
        for r in 0..n {
            for p in self.start[r]..self.start[r + 1] {
                let (c, b) = (self.cols[p], &self.vals[p]);
                for (y, x) in ys.iter_mut().zip(xs) {
                    let xr = cell(x, r);
                    let yc = cell_mut(y, c);
                    for j in 0..NVAR {
                        let mut acc = T::zero();
                        for i in 0..NVAR {
                            acc = acc + xr[i] * b[i][j];
                        }
                        yc[j] = yc[j] + acc;
                    }
                }
            }
        }
        ys
    }
}

impl Euler {
    /// The exact Jacobian of the first-order residual (whatever the scheme's order: it is the
    /// second-order scheme's preconditioner), face by face: the face flux in dual numbers along
    /// the ten components of its two states.
    pub fn jacobian(&self, q: &[State<f64>]) -> Blocks {
        let mut blocks: Blocks = Vec::with_capacity(4 * self.mesh.faces.len());
        for (fi, f) in self.mesh.faces.iter().enumerate() {
            let l = f.left;
            let ql: State<Dual<10>> = std::array::from_fn(|k| Dual::var(q[l][k], k));
            let (flux, right) = match f.right {
                Side::Cell(r) => {
                    let qr: State<Dual<10>> = std::array::from_fn(|k| Dual::var(q[r][k], NVAR + k));
                    (self.face_flux(fi, &ql, Some(&qr)), Some(r))
                }
                Side::Boundary(_) => (self.face_flux(fi, &ql, None), None),
            };
            let block = |off: usize, sign: f64| -> [[f64; NVAR]; NVAR] {
                std::array::from_fn(|i| std::array::from_fn(|j| sign * flux[i].d[off + j]))
            };
            blocks.push((l, l, block(0, 1.0)));
            if let Some(r) = right {
                blocks.push((l, r, block(NVAR, 1.0)));
                blocks.push((r, l, block(0, -1.0)));
                blocks.push((r, r, block(NVAR, -1.0)));
            }
        }
        blocks
    }
}

impl Euler {
    /// The exact Jacobian ∂R/∂q at order `order` as 5 × 5 blocks, by colouring (the first-order
    /// one equals [`Euler::jacobian`]).
    pub fn jacobian_colored(&self, q: &[State<f64>], coloring: &Coloring, order: Order) -> Blocks {
        let n = self.mesh.n_cells;
        let geom = self.geometry::<Dual<NVAR>>(order);
        let mut blocks: Blocks = Vec::with_capacity(coloring.deps.iter().map(Vec::len).sum());
        // the cells of every colour, and where each cell's column blocks go
        let mut members = vec![Vec::new(); coloring.n_colors];
        for (j, &col) in coloring.color.iter().enumerate() {
            members[col].push(j);
        }
        let mut cells_of: Vec<Vec<(usize, usize)>> = vec![Vec::new(); n];
        for (i, deps) in coloring.deps.iter().enumerate() {
            for &j in deps {
                cells_of[j].push((i, blocks.len()));
                blocks.push((i, j, [[0.0; NVAR]; NVAR]));
            }
        }
        // per colour: the derivative of every residual along the seeds of that colour, read
        // into its blocks as each round of colours (one a thread) ends: no more than a round's
        // dual-number residuals are held at once
        let colors: Vec<usize> = (0..coloring.n_colors).collect();
        for round in colors.chunks(rayon::current_num_threads().max(1)) {
            let columns: Vec<Vec<State<Dual<NVAR>>>> = round
                .par_iter()
                .map(|&col| {
                    let qd: Vec<State<Dual<NVAR>>> = (0..n)
                        .map(|c| {
                            std::array::from_fn(|k| {
                                if coloring.color[c] == col {
                                    Dual::var(q[c][k], k)
                                } else {
                                    Dual::new(q[c][k], [0.0; NVAR])
                                }
                            })
                        })
                        .collect();
                    self.residual_in(&qd, &geom).0
                })
                .collect();
            for (&col, r) in round.iter().zip(&columns) {
                for &j in &members[col] {
                    for &(i, at) in &cells_of[j] {
                        let ri = &r[i];
                        blocks[at].2 = std::array::from_fn(|a| std::array::from_fn(|b| ri[a].d[b]));
                    }
                }
            }
        }
        blocks
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::airfoil::AirfoilShape;
    use crate::residual::free_stream;

    /// The coloured Jacobian times a random vector equals the dual-number Jacobian product of the
    /// residual to round-off, at both orders, and so does the face-by-face first-order assembly
    /// (with a far-field and a wall boundary and symmetry planes).
    #[test]
    fn colored_jacobian_equals_jacobian_products() {
        let mesh = AirfoilShape::naca64a010().o_mesh(24, 8, 20.0, 0.004 / 20.0, 1.0);
        let q_inf = free_stream(0.4, 0.02);
        let e = Euler::new(mesh, q_inf);
        let r = gustkit_testkit::rand_vec(e.mesh.n_cells * NVAR, 4);
        let q: Vec<State<f64>> = (0..e.mesh.n_cells)
            .map(|c| std::array::from_fn(|k| q_inf[k] * (1.0 + 0.05 * r[c * NVAR + k])))
            .collect();
        let v = gustkit_testkit::rand_vec(e.mesh.n_cells * NVAR, 8);
        let qd: Vec<State<Dual<1>>> = (0..e.mesh.n_cells)
            .map(|c| std::array::from_fn(|k| Dual::new(q[c][k], [v[c * NVAR + k]])))
            .collect();
        let face_by_face = (Order::First, e.jacobian(&q));
        for (order, blocks) in [Order::First, Order::Second]
            .map(|o| (o, e.jacobian_colored(&q, &Coloring::new(&e, o), o)))
            .into_iter()
            .chain([face_by_face])
        {
            let jv = e.residual_and_fluxes(&qd, order).0;
            let mut av = vec![[0.0; NVAR]; e.mesh.n_cells];
            for (row, col, b) in blocks {
                for i in 0..NVAR {
                    for j in 0..NVAR {
                        av[row][i] += b[i][j] * v[col * NVAR + j];
                    }
                }
            }
            let scale = jv.iter().flatten().fold(0.0f64, |a, x| a.max(x.d[0].abs()));
            for c in 0..e.mesh.n_cells {
                for k in 0..NVAR {
                    assert!(
                        (av[c][k] - jv[c][k].d[0]).abs() <= 1e-13 * scale,
                        "{order:?} cell {c} var {k}: {} vs {}",
                        av[c][k],
                        jv[c][k].d[0]
                    );
                }
            }
        }
    }

    /// The compressed rows multiply like the block list, and their transpose is the transpose:
    /// yᵀ (A x) = (Aᵀ y)ᵀ x to round-off (complex vectors, the second-order Jacobian).
    #[test]
    fn block_rows_products() {
        use num_complex::Complex64 as C64;
        let mesh = AirfoilShape::naca64a010().o_mesh(24, 8, 20.0, 0.004 / 20.0, 1.0);
        let q_inf = free_stream(0.4, 0.02);
        let e = Euler::new(mesh, q_inf);
        let q = vec![q_inf; e.mesh.n_cells];
        let blocks = e.jacobian_colored(&q, &Coloring::new(&e, Order::Second), Order::Second);
        let a = BlockRows::new(e.mesh.n_cells, &blocks);
        let n = e.mesh.n_cells * NVAR;
        let r = gustkit_testkit::rand_vec(4 * n, 6);
        let x: Vec<C64> = (0..n).map(|i| C64::new(r[i], r[n + i])).collect();
        let y: Vec<C64> = (0..n)
            .map(|i| C64::new(r[2 * n + i], r[3 * n + i]))
            .collect();
        let mut ax = vec![C64::new(0.0, 0.0); n];
        for (row, col, b) in &blocks {
            for i in 0..NVAR {
                for j in 0..NVAR {
                    ax[row * NVAR + i] += x[col * NVAR + j] * b[i][j];
                }
            }
        }
        let mx = a.mul(&x);
        let scale = ax.iter().fold(0.0f64, |m, v| m.max(v.norm()));
        for (p, q) in ax.iter().zip(&mx) {
            assert!((p - q).norm() < 1e-14 * scale);
        }
        let dot = |u: &[C64], v: &[C64]| u.iter().zip(v).map(|(p, q)| p * q).sum::<C64>();
        let (l, rr) = (dot(&y, &mx), dot(&a.mul_transpose(&y), &x));
        assert!((l - rr).norm() < 1e-13 * l.norm(), "{l} vs {rr}");
    }

    /// A structured-like 2-D mesh (4 neighbours): no more colours than the balls of radius 2 and
    /// 4 hold cells (13 and 41); measured 7 and about 20.
    #[test]
    fn colour_counts() {
        let mesh = AirfoilShape::naca64a010().o_mesh(24, 8, 20.0, 0.004 / 20.0, 1.0);
        let e = Euler::new(mesh, free_stream(0.4, 0.02));
        for (order, expect) in [(Order::First, 5..=13), (Order::Second, 13..=41)] {
            let n = Coloring::new(&e, order).n_colors;
            assert!(expect.contains(&n), "{order:?}: {n} colours");
        }
    }
}
