//! The Jacobians of the LFD's right-hand sides and wall forces, assembled as sparse matrices by
//! colouring (as the state Jacobian is in [`crate::jacobian`]): what the reverse mode needs of
//! them is their transposed products, and a stored sparse matrix gives those for a few flops per
//! entry, in about a tenth of the memory an operation tape of the same functions takes.
//!
//! - [`MotionJacobian`]: ∂R/∂x (node positions), ∂V/∂x (cell volumes) and ∂R/∂v_G (face volume
//!   fluxes) at the steady state: the mode-motion right-hand side B. The residual of cell c
//!   depends on node n only if c lies within two face-neighbour steps (second order; none for
//!   first order) of a cell touching n, so nodes whose such neighbourhoods are disjoint are
//!   seeded together: one residual evaluation in `Dual<3>` per colour gives the three columns of
//!   every node of that colour.
//! - [`ForceJacobian`]: ∂f/∂q and ∂f/∂x of the wall-face forces, whose dependencies reach one
//!   face-neighbour step from the wall cells.
//!
//! Every column is checked against the dual-number forward products and the operation-tape
//! transposes they replace (the tests below, to round-off).

use crate::gas::NVAR;
use crate::mesh::{Boundary, Mesh, Side};
use crate::residual::{Euler, Order, State};
use gustkit_core::scalar::{Dual, Scalar};
use num_complex::Complex64 as C64;
use rayon::prelude::*;

/// Rows of each column group in compressed form: `rows[start[g]..start[g + 1]]`.
struct Pattern {
    start: Vec<usize>,
    rows: Vec<u32>,
}

impl Pattern {
    fn of(&self, g: usize) -> &[u32] {
        &self.rows[self.start[g]..self.start[g + 1]]
    }

    fn from_lists(lists: impl Iterator<Item = Vec<u32>>) -> Self {
        let mut start = vec![0];
        let mut rows = Vec::new();
        for l in lists {
            rows.extend(l);
            start.push(rows.len());
        }
        Self { start, rows }
    }

    fn n_groups(&self) -> usize {
        self.start.len() - 1
    }

    fn bytes(&self) -> usize {
        self.start.len() * 8 + self.rows.len() * 4
    }
}

/// Greedy colouring of column groups such that no row depends on two groups of one colour:
/// (colour of every group, groups of every colour).
fn color_groups(pattern: &Pattern, n_rows: usize) -> Vec<Vec<u32>> {
    let mut claimed: Vec<Vec<u32>> = vec![Vec::new(); n_rows];
    let mut used: Vec<bool> = Vec::new();
    let mut classes: Vec<Vec<u32>> = Vec::new();
    for g in 0..pattern.n_groups() {
        used.iter_mut().for_each(|u| *u = false);
        for &r in pattern.of(g) {
            for &c in &claimed[r as usize] {
                used[c as usize] = true;
            }
        }
        let color = used.iter().position(|u| !u).unwrap_or(used.len());
        if color == used.len() {
            used.push(false);
            classes.push(Vec::new());
        }
        classes[color].push(g as u32);
        for &r in pattern.of(g) {
            claimed[r as usize].push(color as u32);
        }
    }
    classes
}

/// The cells on either side of every face holding each node.
fn cells_of_nodes(mesh: &Mesh) -> Vec<Vec<u32>> {
    let mut t: Vec<Vec<u32>> = vec![Vec::new(); mesh.nodes.len()];
    for f in &mesh.faces {
        for &n in &f.nodes {
            t[n].push(f.left as u32);
            if let Side::Cell(r) = f.right {
                t[n].push(r as u32);
            }
        }
    }
    for l in &mut t {
        l.sort_unstable();
        l.dedup();
    }
    t
}

/// The nodes of every cell (of its faces).
fn nodes_of_cells(mesh: &Mesh) -> Vec<Vec<u32>> {
    let mut c: Vec<Vec<u32>> = vec![Vec::new(); mesh.n_cells];
    for f in &mesh.faces {
        for &n in &f.nodes {
            c[f.left].push(n as u32);
            if let Side::Cell(r) = f.right {
                c[r].push(n as u32);
            }
        }
    }
    for l in &mut c {
        l.sort_unstable();
        l.dedup();
    }
    c
}

/// Face neighbours of every cell.
fn neighbours(mesh: &Mesh) -> Vec<Vec<u32>> {
    let mut nb = vec![Vec::new(); mesh.n_cells];
    for f in &mesh.faces {
        if let Side::Cell(r) = f.right {
            nb[f.left].push(r as u32);
            nb[r].push(f.left as u32);
        }
    }
    nb
}

/// The cells within `depth` face-neighbour steps of `seeds`, sorted (`mark`: scratch, all
/// different from `stamp` on entry).
fn dilate(nb: &[Vec<u32>], seeds: &[u32], depth: usize, mark: &mut [u32], stamp: u32) -> Vec<u32> {
    let mut out: Vec<u32> = Vec::new();
    for &c in seeds {
        if mark[c as usize] != stamp {
            mark[c as usize] = stamp;
            out.push(c);
        }
    }
    let mut frontier = out.clone();
    for _ in 0..depth {
        let mut next = Vec::new();
        for &a in &frontier {
            for &b in &nb[a as usize] {
                if mark[b as usize] != stamp {
                    mark[b as usize] = stamp;
                    out.push(b);
                    next.push(b);
                }
            }
        }
        frontier = next;
    }
    out.sort_unstable();
    out
}

/// The node positions in `Dual<3>`, the nodes of `seeded` along their three coordinates.
fn seeded_nodes(mesh: &Mesh, seeded: impl Iterator<Item = usize>) -> Vec<[Dual<3>; 3]> {
    let mut x: Vec<[Dual<3>; 3]> = mesh.nodes.iter().map(|p| p.map(Dual::cst)).collect();
    for n in seeded {
        x[n] = std::array::from_fn(|k| Dual::var(mesh.nodes[n][k], k));
    }
    x
}

/// Face-neighbour steps from a moved node (or a wall cell) that its effect reaches: the second
/// order's least-squares weights use the centres of the neighbours, and its face states the
/// gradients of both sides.
fn reach(order: Order) -> usize {
    match order {
        Order::First => 0,
        Order::Second => 2,
    }
}

/// One cell's ∂R_c/∂x_n block (5 rows × 3 coordinates) from its residual in `Dual<3>` with
/// node n seeded: the same for kept and recomputed ∂R/∂x, so both give the same numbers.
fn node_block(rc: &State<Dual<3>>) -> [[f64; 3]; NVAR] {
    std::array::from_fn(|i| std::array::from_fn(|k| rc[i].d[k]))
}

/// ∂R/∂x, ∂V/∂x and ∂R/∂v_G at the steady state, in compressed columns.
///
/// ∂R/∂x is the bulk of it (a 5 × 3 block for each of the about 80 cells a node moves at second
/// order: about 10 kB a node); built with [`MotionJacobian::recomputing`] it is not kept and each
/// [`MotionJacobian::node_transpose`] evaluates it again by the same colouring, contracting every
/// colour's columns with all its seeds at once and dropping them: the reverse sweep then applies
/// it once, to the adjoints summed over the frequencies (it does not depend on them).
pub struct MotionJacobian {
    /// Per node: the residual rows (cells) it moves.
    node_rows: Pattern,
    /// Nodes whose rows are disjoint, seeded together in one evaluation.
    node_classes: Vec<Vec<u32>>,
    /// ∂R_c/∂x_n for each (node, cell) of `node_rows`: 5 rows × 3 coordinates (`None`: recomputed
    /// in each transposed product).
    dr_dx: Option<Vec<[[f64; 3]; NVAR]>>,
    /// Per node: the cells whose volume it moves.
    volume_rows: Pattern,
    dv_dx: Vec<[f64; 3]>,
    /// Per face: ∂R/∂v_G on its left and right cells (zero on the right of a boundary face).
    dr_dvg: Vec<[[f64; NVAR]; 2]>,
    /// Residual evaluations of the assembly: the colours of the faces, and of the nodes when
    /// ∂R/∂x is kept (not kept, each transposed product evaluates the node colours instead).
    pub evaluations: usize,
}

impl MotionJacobian {
    /// Assembles the Jacobians of `euler`'s residual (at its order) and volumes at `q0`.
    pub fn new(euler: &Euler, q0: &[State<f64>]) -> Self {
        Self::assemble(euler, q0, true)
    }

    /// [`MotionJacobian::new`] without keeping ∂R/∂x: its transposed products recompute it.
    pub fn recomputing(euler: &Euler, q0: &[State<f64>]) -> Self {
        Self::assemble(euler, q0, false)
    }

    fn assemble(euler: &Euler, q0: &[State<f64>], keep_dr_dx: bool) -> Self {
        let mesh = &euler.mesh;
        let order = euler.order;
        let nb = neighbours(mesh);
        let touching = cells_of_nodes(mesh);
        let mut mark = vec![u32::MAX; mesh.n_cells];
        let node_rows = Pattern::from_lists(
            touching
                .iter()
                .enumerate()
                .map(|(n, t)| dilate(&nb, t, reach(order), &mut mark, n as u32)),
        );
        let volume_rows = Pattern::from_lists(touching.into_iter());
        let node_classes = color_groups(&node_rows, mesh.n_cells);
        let vg0 = &euler.face_vg;
        // the volumes: each node's cells, by the same colouring's classes (one cheap pass each)
        let mut dv_dx = vec![[0.0; 3]; volume_rows.rows.len()];
        let volume_classes = color_groups(&volume_rows, mesh.n_cells);
        for class in &volume_classes {
            let nodes = seeded_nodes(mesh, class.iter().map(|&n| n as usize));
            let v = mesh.volumes_at(&nodes);
            for &n in class {
                let n = n as usize;
                for p in volume_rows.start[n]..volume_rows.start[n + 1] {
                    dv_dx[p] = v[volume_rows.rows[p] as usize].d;
                }
            }
        }
        // the face volume fluxes enter the flux of their own face only
        let face_rows = Pattern::from_lists(mesh.faces.iter().map(|f| match f.right {
            Side::Cell(r) => vec![f.left as u32, r as u32],
            Side::Boundary(_) => vec![f.left as u32],
        }));
        let face_classes = color_groups(&face_rows, mesh.n_cells);
        let nodes: Vec<[Dual<1>; 3]> = mesh.nodes.iter().map(|p| p.map(Dual::cst)).collect();
        let q1: Vec<State<Dual<1>>> = q0.iter().map(|s| s.map(Dual::cst)).collect();
        let per_face: Vec<Vec<(usize, [[f64; NVAR]; 2])>> = face_classes
            .par_iter()
            .map(|class| {
                let mut vg: Vec<Dual<1>> = vg0.iter().map(|v| Dual::cst(*v)).collect();
                for &f in class {
                    vg[f as usize] = Dual::var(vg0[f as usize], 0);
                }
                let geom = euler.geometry_at(&nodes, vg, order);
                let r = euler.residual_in(&q1, &geom).0;
                class
                    .iter()
                    .map(|&f| {
                        let f = f as usize;
                        let face = &mesh.faces[f];
                        let left = r[face.left].map(|v| v.d[0]);
                        let right = match face.right {
                            Side::Cell(c) => r[c].map(|v| v.d[0]),
                            Side::Boundary(_) => [0.0; NVAR],
                        };
                        (f, [left, right])
                    })
                    .collect()
            })
            .collect();
        let mut dr_dvg = vec![[[0.0; NVAR]; 2]; mesh.faces.len()];
        for (f, d) in per_face.into_iter().flatten() {
            dr_dvg[f] = d;
        }
        let mut jac = Self {
            evaluations: face_classes.len() + if keep_dr_dx { node_classes.len() } else { 0 },
            node_rows,
            node_classes,
            dr_dx: None,
            volume_rows,
            dv_dx,
            dr_dvg,
        };
        if keep_dr_dx {
            let mut dr_dx = vec![[[0.0; 3]; NVAR]; jac.node_rows.rows.len()];
            let rows = &jac.node_rows;
            jac.by_node_colours(
                euler,
                q0,
                |n, r| {
                    rows.of(n)
                        .iter()
                        .map(|&c| node_block(&r[c as usize]))
                        .collect::<Vec<_>>()
                },
                |n, blocks| dr_dx[rows.start[n]..rows.start[n + 1]].copy_from_slice(&blocks),
            );
            jac.dr_dx = Some(dr_dx);
        }
        jac
    }

    /// One residual evaluation in `Dual<3>` per colour of nodes (the colours in rounds of one a
    /// thread): `per_node(n, residual)` for each node of the colour, its results handed to
    /// `sink(n, result)` in the colours' order as each round ends, so that no more than a round's
    /// evaluations and results are held at once.
    fn by_node_colours<T: Send>(
        &self,
        euler: &Euler,
        q0: &[State<f64>],
        per_node: impl Fn(usize, &[State<Dual<3>>]) -> T + Sync,
        mut sink: impl FnMut(usize, T),
    ) {
        let mesh = &euler.mesh;
        let q: Vec<State<Dual<3>>> = q0.iter().map(|s| s.map(Dual::cst)).collect();
        let vg0 = &euler.face_vg;
        for round in self
            .node_classes
            .chunks(rayon::current_num_threads().max(1))
        {
            let per_class: Vec<Vec<T>> = round
                .par_iter()
                .map(|class| {
                    let nodes = seeded_nodes(mesh, class.iter().map(|&n| n as usize));
                    let vg: Vec<Dual<3>> = vg0.iter().map(|v| Dual::cst(*v)).collect();
                    let geom = euler.geometry_at(&nodes, vg, euler.order);
                    let r = euler.residual_in(&q, &geom).0;
                    class.iter().map(|&n| per_node(n as usize, &r)).collect()
                })
                .collect();
            for (class, vals) in round.iter().zip(per_class) {
                for (&n, v) in class.iter().zip(vals) {
                    sink(n as usize, v);
                }
            }
        }
    }

    /// Whether ∂R/∂x is kept (else each transposed product recomputes it).
    pub fn keeps_dr_dx(&self) -> bool {
        self.dr_dx.is_some()
    }

    /// Memory held, bytes.
    pub fn bytes(&self) -> usize {
        self.node_rows.bytes()
            + self
                .node_classes
                .iter()
                .map(|c| 24 + c.len() * 4)
                .sum::<usize>()
            + self
                .dr_dx
                .as_ref()
                .map_or(0, |d| d.len() * std::mem::size_of::<[[f64; 3]; NVAR]>())
            + self.volume_rows.bytes()
            + self.dv_dx.len() * 24
            + self.dr_dvg.len() * std::mem::size_of::<[[f64; NVAR]; 2]>()
    }

    /// ∂R/∂xᵀ w per node for each seed `w` on the residual (5 a cell) of `euler` at `q0` (the
    /// state it was assembled at): from the kept blocks, or by one coloured evaluation pass for
    /// all the seeds together.
    pub fn node_transpose(
        &self,
        euler: &Euler,
        q0: &[State<f64>],
        ws: &[&[C64]],
    ) -> Vec<Vec<[C64; 3]>> {
        let zero = [C64::new(0.0, 0.0); 3];
        let contract = |rows: &[u32], block: &dyn Fn(usize) -> [[f64; 3]; NVAR]| {
            let mut acc = vec![zero; ws.len()];
            for (p, &c) in rows.iter().enumerate() {
                let d = block(p);
                for (a, w) in acc.iter_mut().zip(ws) {
                    let wc = &w[c as usize * NVAR..(c as usize + 1) * NVAR];
                    for i in 0..NVAR {
                        for k in 0..3 {
                            a[k] += wc[i] * d[i][k];
                        }
                    }
                }
            }
            acc
        };
        let n_nodes = self.node_rows.n_groups();
        let mut out = vec![vec![zero; n_nodes]; ws.len()];
        let mut sink = |n: usize, acc: Vec<[C64; 3]>| {
            for (o, a) in out.iter_mut().zip(acc) {
                o[n] = a;
            }
        };
        match &self.dr_dx {
            Some(dr_dx) => {
                let per_node: Vec<Vec<[C64; 3]>> = (0..n_nodes)
                    .into_par_iter()
                    .map(|n| {
                        let a = self.node_rows.start[n];
                        contract(self.node_rows.of(n), &|p| dr_dx[a + p])
                    })
                    .collect();
                for (n, acc) in per_node.into_iter().enumerate() {
                    sink(n, acc);
                }
            }
            None => self.by_node_colours(
                euler,
                q0,
                |n, r| {
                    let rows = self.node_rows.of(n);
                    contract(rows, &|p| node_block(&r[rows[p] as usize]))
                },
                &mut sink,
            ),
        }
        out
    }

    /// ∂V/∂xᵀ wv per node for a seed `wv` on the cell volumes.
    pub fn volume_transpose(&self, wv: &[C64]) -> Vec<[C64; 3]> {
        (0..self.volume_rows.n_groups())
            .into_par_iter()
            .map(|n| {
                let mut acc = [C64::new(0.0, 0.0); 3];
                let (a, b) = (self.volume_rows.start[n], self.volume_rows.start[n + 1]);
                for (&c, d) in self.volume_rows.rows[a..b].iter().zip(&self.dv_dx[a..b]) {
                    for k in 0..3 {
                        acc[k] += wv[c as usize] * d[k];
                    }
                }
                acc
            })
            .collect()
    }

    /// ∂R/∂v_Gᵀ w per face for a seed `w` on the residual.
    pub fn face_transpose(&self, mesh: &Mesh, w: &[C64]) -> Vec<C64> {
        mesh.faces
            .par_iter()
            .zip(&self.dr_dvg)
            .map(|(f, d)| {
                let mut acc = C64::new(0.0, 0.0);
                for i in 0..NVAR {
                    acc += w[f.left * NVAR + i] * d[0][i];
                }
                if let Side::Cell(r) = f.right {
                    for i in 0..NVAR {
                        acc += w[r * NVAR + i] * d[1][i];
                    }
                }
                acc
            })
            .collect()
    }
}

/// ∂f/∂q and ∂f/∂x of the wall-face forces at the steady state, in compressed columns over the
/// cells and nodes near the wall.
pub struct ForceJacobian {
    /// The wall faces, in the order of [`Euler::wall_face_forces`].
    pub wall_faces: Vec<usize>,
    /// The cells whose state moves a wall force, and per such cell the wall faces (indices
    /// into `wall_faces`) it moves.
    cells: Vec<u32>,
    cell_rows: Pattern,
    /// ∂f_w/∂q_c: 3 force components × 5 states.
    df_dq: Vec<[[f64; NVAR]; 3]>,
    /// The nodes whose position moves a wall force, and per node the faces it moves.
    nodes: Vec<u32>,
    node_rows: Pattern,
    df_dx: Vec<[[f64; 3]; 3]>,
    /// Evaluations of the wall forces in the assembly.
    pub evaluations: usize,
}

impl ForceJacobian {
    /// Assembles the wall forces' Jacobians of `euler` at `q0`.
    pub fn new(euler: &Euler, q0: &[State<f64>]) -> Self {
        let mesh = &euler.mesh;
        let order = euler.order;
        let nb = neighbours(mesh);
        let cell_nodes = nodes_of_cells(mesh);
        let wall_faces: Vec<usize> = mesh
            .faces
            .iter()
            .enumerate()
            .filter(|(_, f)| f.right == Side::Boundary(Boundary::Wall))
            .map(|(i, _)| i)
            .collect();
        // per wall face: the cells whose state reaches it (its cell and, at second order, the
        // gradient's neighbours) and the nodes of those cells (their centres, the face's area)
        let depth = reach(order) / 2;
        let mut mark = vec![u32::MAX; mesh.n_cells];
        let mut cell_lists: Vec<Vec<u32>> = vec![Vec::new(); mesh.n_cells];
        let mut node_lists: Vec<Vec<u32>> = vec![Vec::new(); mesh.nodes.len()];
        for (w, &fi) in wall_faces.iter().enumerate() {
            let cells = dilate(
                &nb,
                &[mesh.faces[fi].left as u32],
                depth,
                &mut mark,
                w as u32,
            );
            let mut nodes: Vec<u32> = cells
                .iter()
                .flat_map(|&c| cell_nodes[c as usize].iter().copied())
                .collect();
            nodes.sort_unstable();
            nodes.dedup();
            for c in cells {
                cell_lists[c as usize].push(w as u32);
            }
            for n in nodes {
                node_lists[n as usize].push(w as u32);
            }
        }
        let cells: Vec<u32> = (0..mesh.n_cells as u32)
            .filter(|&c| !cell_lists[c as usize].is_empty())
            .collect();
        let nodes: Vec<u32> = (0..mesh.nodes.len() as u32)
            .filter(|&n| !node_lists[n as usize].is_empty())
            .collect();
        let cell_rows = Pattern::from_lists(cells.iter().map(|&c| cell_lists[c as usize].clone()));
        let node_rows = Pattern::from_lists(nodes.iter().map(|&n| node_lists[n as usize].clone()));
        drop((cell_lists, node_lists));
        let n_wall = wall_faces.len();
        // the state columns: five per cell of a colour
        let cell_classes = color_groups(&cell_rows, n_wall);
        let geom5 = euler.geometry::<Dual<NVAR>>(order);
        let by_cell: Vec<Vec<[[f64; NVAR]; 3]>> = cell_classes
            .par_iter()
            .map(|class| {
                let mut q: Vec<State<Dual<NVAR>>> = q0.iter().map(|s| s.map(Dual::cst)).collect();
                for &g in class {
                    let c = cells[g as usize] as usize;
                    q[c] = std::array::from_fn(|k| Dual::var(q0[c][k], k));
                }
                let f = euler.wall_face_forces(&q, &geom5);
                let mut out = Vec::new();
                for &g in class {
                    for &w in cell_rows.of(g as usize) {
                        let fw = &f[w as usize].1;
                        out.push(std::array::from_fn(|i| fw[i].d));
                    }
                }
                out
            })
            .collect();
        let mut df_dq = vec![[[0.0; NVAR]; 3]; cell_rows.rows.len()];
        for (class, vals) in cell_classes.iter().zip(by_cell) {
            let mut it = vals.into_iter();
            for &g in class {
                let g = g as usize;
                for slot in &mut df_dq[cell_rows.start[g]..cell_rows.start[g + 1]] {
                    *slot = it.next().expect("one block per face");
                }
            }
        }
        // the node columns: three per node of a colour
        let node_classes = color_groups(&node_rows, n_wall);
        let q3: Vec<State<Dual<3>>> = q0.iter().map(|s| s.map(Dual::cst)).collect();
        let by_node: Vec<Vec<[[f64; 3]; 3]>> = node_classes
            .par_iter()
            .map(|class| {
                let x = seeded_nodes(mesh, class.iter().map(|&g| nodes[g as usize] as usize));
                let geom = euler.geometry_at(&x, vec![Dual::cst(0.0); mesh.faces.len()], order);
                let f = euler.wall_face_forces(&q3, &geom);
                let mut out = Vec::new();
                for &g in class {
                    for &w in node_rows.of(g as usize) {
                        let fw = &f[w as usize].1;
                        out.push(std::array::from_fn(|i| fw[i].d));
                    }
                }
                out
            })
            .collect();
        let mut df_dx = vec![[[0.0; 3]; 3]; node_rows.rows.len()];
        for (class, vals) in node_classes.iter().zip(by_node) {
            let mut it = vals.into_iter();
            for &g in class {
                let g = g as usize;
                for slot in &mut df_dx[node_rows.start[g]..node_rows.start[g + 1]] {
                    *slot = it.next().expect("one block per face");
                }
            }
        }
        Self {
            wall_faces,
            evaluations: cell_classes.len() + node_classes.len(),
            cells,
            cell_rows,
            df_dq,
            nodes,
            node_rows,
            df_dx,
        }
    }

    /// Memory held, bytes.
    pub fn bytes(&self) -> usize {
        self.wall_faces.len() * 8
            + (self.cells.len() + self.nodes.len()) * 4
            + self.cell_rows.bytes()
            + self.node_rows.bytes()
            + self.df_dq.len() * std::mem::size_of::<[[f64; NVAR]; 3]>()
            + self.df_dx.len() * std::mem::size_of::<[[f64; 3]; 3]>()
    }

    /// F_qᵀ u (5 a cell, `n_cells` cells) and F_xᵀ u (per node, `n_nodes` nodes) for a seed on
    /// each wall face's force.
    pub fn transpose(
        &self,
        u: &[[C64; 3]],
        n_cells: usize,
        n_nodes: usize,
    ) -> (Vec<C64>, Vec<[C64; 3]>) {
        let mut uq = vec![C64::new(0.0, 0.0); n_cells * NVAR];
        for (g, &c) in self.cells.iter().enumerate() {
            let (a, b) = (self.cell_rows.start[g], self.cell_rows.start[g + 1]);
            let out = &mut uq[c as usize * NVAR..(c as usize + 1) * NVAR];
            for (&w, d) in self.cell_rows.rows[a..b].iter().zip(&self.df_dq[a..b]) {
                let uw = &u[w as usize];
                for i in 0..3 {
                    for k in 0..NVAR {
                        out[k] += uw[i] * d[i][k];
                    }
                }
            }
        }
        let mut ux = vec![[C64::new(0.0, 0.0); 3]; n_nodes];
        for (g, &n) in self.nodes.iter().enumerate() {
            let (a, b) = (self.node_rows.start[g], self.node_rows.start[g + 1]);
            let out = &mut ux[n as usize];
            for (&w, d) in self.node_rows.rows[a..b].iter().zip(&self.df_dx[a..b]) {
                let uw = &u[w as usize];
                for i in 0..3 {
                    for k in 0..3 {
                        out[k] += uw[i] * d[i][k];
                    }
                }
            }
        }
        (uq, ux)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::airfoil::AirfoilShape;
    use crate::residual::free_stream;
    use crate::wing_mesh::{WingMesh, WingMeshSpec};
    use gustkit_core::tape::{Rev, Tape};

    fn rand_c(n: usize, seed: u64) -> Vec<C64> {
        let r = gustkit_testkit::rand_vec(2 * n, seed);
        (0..n).map(|i| C64::new(r[2 * i], r[2 * i + 1])).collect()
    }

    /// A state near the free stream (5 % perturbations): the linearizations hold about any state.
    fn perturbed(e: &Euler) -> Vec<State<f64>> {
        let r = gustkit_testkit::rand_vec(e.mesh.n_cells * NVAR, 11);
        (0..e.mesh.n_cells)
            .map(|c| std::array::from_fn(|k| e.q_inf[k] * (1.0 + 0.05 * r[c * NVAR + k])))
            .collect()
    }

    /// The reference: the same transposed products by one operation tape of the whole residual,
    /// volumes and wall forces (the reverse mode before the assembled Jacobians).
    fn taped(
        e: &Euler,
        q0: &[State<f64>],
        w: &[C64],
        wv: &[C64],
        u: &[[C64; 3]],
    ) -> (Vec<C64>, Vec<C64>, Vec<C64>) {
        let mesh = &e.mesh;
        let ((inputs, outputs), tape) = Tape::record(|| {
            let nodes: Vec<[Rev; 3]> = mesh.nodes.iter().map(|p| p.map(Rev::input)).collect();
            let vg: Vec<Rev> = e.face_vg.iter().map(|v| Rev::input(*v)).collect();
            let q: Vec<State<Rev>> = q0.iter().map(|s| s.map(Rev::cst)).collect();
            let geom = e.geometry_at(&nodes, vg.clone(), e.order);
            let r = e.residual_in(&q, &geom).0;
            let v = mesh.volumes_at(&nodes);
            let mut inputs: Vec<Rev> = nodes.into_iter().flatten().collect();
            inputs.extend(vg);
            let mut outputs: Vec<Rev> = r.into_iter().flatten().collect();
            outputs.extend(v);
            (inputs, outputs)
        });
        let adj = tape.sweep(
            outputs
                .iter()
                .zip(w.iter().chain(wv))
                .map(|(r, w)| (*r, *w)),
        );
        let motion: Vec<C64> = inputs.iter().map(|x| adj.of(*x)).collect();
        let ((inputs, outputs), tape) = Tape::record(|| {
            let q: Vec<State<Rev>> = q0.iter().map(|s| s.map(Rev::input)).collect();
            let nodes: Vec<[Rev; 3]> = mesh.nodes.iter().map(|p| p.map(Rev::input)).collect();
            let geom = e.geometry_at(&nodes, vec![Rev::cst(0.0); mesh.faces.len()], e.order);
            let f = e.wall_face_forces(&q, &geom);
            let mut inputs: Vec<Rev> = q.into_iter().flatten().collect();
            inputs.extend(nodes.into_iter().flatten());
            let outputs: Vec<Rev> = f.into_iter().flat_map(|(_, v)| v).collect();
            (inputs, outputs)
        });
        let adj = tape.sweep(
            outputs
                .iter()
                .zip(u.iter().flatten())
                .map(|(r, w)| (*r, *w)),
        );
        let all: Vec<C64> = inputs.iter().map(|x| adj.of(*x)).collect();
        let n_q = mesh.n_cells * NVAR;
        (motion, all[..n_q].to_vec(), all[n_q..].to_vec())
    }

    fn assert_close(name: &str, a: &[C64], b: &[C64]) {
        assert_eq!(a.len(), b.len(), "{name}");
        let scale = b.iter().fold(0.0f64, |m, v| m.max(v.norm()));
        let err = a
            .iter()
            .zip(b)
            .fold(0.0f64, |m, (p, q)| m.max((p - q).norm()));
        assert!(scale > 0.0, "{name}: all zero");
        assert!(err <= 1e-12 * scale, "{name}: {err:e} of {scale:e}");
    }

    /// Every transposed product of the assembled Jacobians equals the operation tape's to
    /// round-off (1e-12 of the largest entry) for random complex seeds, ∂R/∂x both kept and
    /// recomputed (two seeds in one pass, the second a complex multiple of the first): on a 2-D O-mesh at
    /// second and first order (symmetry planes, wall, far field) and on a small 3-D wing mesh
    /// whose sections close to zero thickness at the tip (degenerate faces).
    #[test]
    fn assembled_transposes_equal_the_tapes() {
        let o_mesh = AirfoilShape::naca64a010().o_mesh(24, 8, 20.0, 0.004 / 20.0, 1.0);
        let spec = WingMeshSpec {
            n_around: 16,
            n_radial: 5,
            n_span: 4,
            n_outboard: 3,
            far_field_chords: 15.0,
            first_spacing_chords: 0.02,
            tip_closure: 0.1,
        };
        let wing = WingMesh::new(
            [1.0, 0.3, 0.6, 0.4],
            &|x: f64| 0.2 * x.sqrt() * (1.0 - x),
            &spec,
        )
        .mesh;
        let cases = [
            (o_mesh.clone(), Order::Second),
            (o_mesh, Order::First),
            (wing, Order::Second),
        ];
        for (case, (mesh, order)) in cases.into_iter().enumerate() {
            let mut e = Euler::new(mesh, free_stream(0.5, 0.03));
            e.order = order;
            let q0 = perturbed(&e);
            let motion = MotionJacobian::new(&e, &q0);
            let recomputing = MotionJacobian::recomputing(&e, &q0);
            assert!(motion.keeps_dr_dx() && !recomputing.keeps_dr_dx());
            let forces = ForceJacobian::new(&e, &q0);
            let (nc, nn) = (e.mesh.n_cells, e.mesh.nodes.len());
            let w = rand_c(nc * NVAR, 1);
            let wv = rand_c(nc, 2);
            let u: Vec<[C64; 3]> = rand_c(3 * forces.wall_faces.len(), 3)
                .chunks(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect();
            let (m_ref, q_ref, x_ref) = taped(&e, &q0, &w, &wv, &u);
            // a second seed: the recomputing pass contracts several at once
            let w2: Vec<C64> = w.iter().map(|z| z * C64::new(0.3, -2.0)).collect();
            for (jac, how) in [(&motion, "kept"), (&recomputing, "recomputed")] {
                let both = jac.node_transpose(&e, &q0, &[&w, &w2]);
                let volumes = jac.volume_transpose(&wv);
                let nodes: Vec<C64> = both[0]
                    .iter()
                    .zip(&volumes)
                    .flat_map(|(a, b)| (0..3).map(move |k| a[k] + b[k]))
                    .collect();
                assert_close(
                    &format!("case {case} dR/dx {how}"),
                    &nodes,
                    &m_ref[..3 * nn],
                );
                let scaled: Vec<C64> = both[0]
                    .iter()
                    .flatten()
                    .map(|z| z * C64::new(0.3, -2.0))
                    .collect();
                let second: Vec<C64> = both[1].iter().flatten().copied().collect();
                assert_close(
                    &format!("case {case} dR/dx {how}, second seed"),
                    &second,
                    &scaled,
                );
                let faces = jac.face_transpose(&e.mesh, &w);
                assert_close(
                    &format!("case {case} dR/dv_G {how}"),
                    &faces,
                    &m_ref[3 * nn..],
                );
            }
            let (uq, ux) = forces.transpose(&u, nc, nn);
            let ux: Vec<C64> = ux.into_iter().flatten().collect();
            assert_close(&format!("case {case} df/dq"), &uq, &q_ref);
            assert_close(&format!("case {case} df/dx"), &ux, &x_ref);
            eprintln!(
                "case {case}: {nc} cells, {} + {} evaluations, {:.0} (recomputing ∂R/∂x: {:.0}) + {:.0} B a cell",
                motion.evaluations,
                forces.evaluations,
                motion.bytes() as f64 / nc as f64,
                recomputing.bytes() as f64 / nc as f64,
                forces.bytes() as f64 / nc as f64
            );
        }
    }
}
