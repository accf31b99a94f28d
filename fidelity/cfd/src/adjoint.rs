//! The transposes of the LFD's linearizations (paper Sec. III), for the adjoint of the GAFs with
//! respect to the mode shapes.
//!
//! Method: the Jacobians of the residual, the cell volumes and the wall forces with respect to
//! the node positions, the face volume fluxes and the state are assembled once about the steady
//! state q₀ on the static mesh, by colouring ([`crate::lfd_jacobians`]); their transposed
//! products serve any (complex) seed:
//! - ∂R/∂qᵀ ψ (the adjoint LFD operator (s V + ∂R/∂q)ᵀ) from the operator's assembled exact
//!   Jacobian ([`LfdOperator::apply_transpose`]);
//! - Bᵀ ψ of the mode-motion right-hand side B x̂ = ∂R/∂x x̂ + s ∂R/∂v_G L x̂ + s V̂(x̂) q₀ (node
//!   positions, face volume fluxes through the swept-volume linearization L, cell volumes);
//! - F_qᵀ u and F_xᵀ u of the linearized wall forces f̂ = F_q q̂ + F_x x̂.
//!
//! The adjoint LFD systems (s V + ∂R/∂q)ᵀ λ = r are solved by GMRES on that transposed operator,
//! preconditioned by the transposed factors of the same frequency's preconditioner (the sparse LU's
//! transpose solve or the block ILU's), so the factorization made for the forward solves serves
//! the adjoint ones. Every product is checked against its forward product (dot-product tests).
//!
//! The thickness variables reach the GAFs only through the mode shapes, so these transposes and
//! the adjoint solves give their exact gradient. The planform variables also move the mesh and
//! so q₀ and the LFD operator (second derivatives of the residual); that part is not here.

use crate::gas::NVAR;
use crate::krylov::GmresInfo;
use crate::lfd::{Factored, Field, LfdError, LfdOperator};
use crate::lfd_jacobians::{ForceJacobian, MotionJacobian};
use crate::residual::State;
use gustkit_core::scalar::{Dual, Scalar};
use num_complex::Complex64 as C64;

/// The transposed linearizations of an [`LfdOperator`] about its steady state.
pub struct LfdReverse {
    /// ∂R/∂x, ∂V/∂x and ∂R/∂v_G: the mode-motion right-hand side's parts.
    pub motion: MotionJacobian,
    /// ∂f/∂q and ∂f/∂x of the wall forces.
    pub forces: ForceJacobian,
    /// The wall faces of the forces, in the order of [`LfdOperator::wall_face_forces`].
    pub wall_faces: Vec<usize>,
    /// Per face, per face node: ∂(swept volume)/∂(node displacement), the linearization L.
    swept: Vec<Vec<[f64; 3]>>,
    n_nodes: usize,
    n_cells: usize,
}

/// Bytes per cell a gradient holds beyond its GAF table whatever the threads (used to refuse a
/// mesh that would not fit), with a margin: [`LfdReverse`] without ∂R/∂x (recomputed by
/// colouring once a gradient, for the adjoints summed over the frequencies: kept, it took a
/// 5 × 3 block for each of the 80 cells within two face-neighbour steps of an interior node's
/// eight cells, about 10 kB a node), the sweep's per-mode fields (the modes' geometry tangents,
/// node seeds) and the mode columns' adjoints summed over the frequencies (80 B a cell a mode
/// and seed). Measured with `gustkit bench studies/agard445_lfd_coarse_warm.json` (coarse wing mesh,
/// 11 modes, the four planform tangents, one seed; single-precision ILU, forward solutions on
/// disk): the reverse sweep's peak 47.5 kB a cell on 1 thread and 70.7 on 2 against the GAF
/// table's 24.0 and 37.4, so 23.5 and 33.3 kB above it: 13.7 kB shared and 9.8 kB a thread
/// (∂R/∂x kept: 31.4 and 40.7 kB above it, 22.1 shared). The operation tapes the Jacobians
/// replaced took about 2 800 entries of 40 bytes a cell (113 kB, up to twice that in their
/// buffers). Since measured, the sweep also keeps the mode motions' swept face volumes for all
/// frequencies (80 B a face and mode a batch of four tangents: 2.7 kB a cell with 11 modes on
/// the wing meshes' 3.1 faces a cell), added here.
pub const BYTES_PER_CELL: usize = 17_500;

/// Bytes per cell and thread a gradient holds beyond its GAF table's own per-thread state:
/// the geometry tangents' hyper-dual evaluations (the mesh, its geometry and the residual over
/// numbers with four second directions, one evaluation a thread at a time), a frequency's
/// adjoints and mode-column adjoints; the frequency's factorization and GMRES basis are dropped
/// before the hyper-dual evaluations. Measured 9.8 kB (see [`BYTES_PER_CELL`]).
pub const TANGENT_BYTES_PER_CELL: usize = 10_000;

impl LfdReverse {
    /// Assembles the linearizations of `lfd` at its steady state, ∂R/∂x kept.
    pub fn new(lfd: &LfdOperator) -> Self {
        Self::assemble(lfd, MotionJacobian::new(&lfd.euler, &lfd.q0))
    }

    /// [`LfdReverse::new`] without keeping ∂R/∂x (about 10 kB a cell): each
    /// [`LfdReverse::position_transpose`] recomputes it by colouring, for all its seeds at once.
    pub fn recomputing(lfd: &LfdOperator) -> Self {
        Self::assemble(lfd, MotionJacobian::recomputing(&lfd.euler, &lfd.q0))
    }

    fn assemble(lfd: &LfdOperator, motion: MotionJacobian) -> Self {
        let e = &lfd.euler;
        let mesh = &e.mesh;
        let forces = ForceJacobian::new(e, &lfd.q0);
        // L: the swept volume of each face moving from x₀ to x₀ + ε x̂, differentiated per node
        let swept = mesh
            .faces
            .iter()
            .map(|f| {
                let a: Vec<[Dual<3>; 3]> = f
                    .nodes
                    .iter()
                    .map(|&n| mesh.nodes[n].map(Dual::cst))
                    .collect();
                (0..f.nodes.len())
                    .map(|j| {
                        let mut b = a.clone();
                        b[j] = std::array::from_fn(|k| Dual::var(a[j][k].v, k));
                        crate::mesh::swept_volume(&a, &b).d
                    })
                    .collect()
            })
            .collect();
        Self {
            wall_faces: forces.wall_faces.clone(),
            motion,
            forces,
            swept,
            n_nodes: mesh.nodes.len(),
            n_cells: mesh.n_cells,
        }
    }

    /// Memory held, bytes.
    pub fn bytes(&self) -> usize {
        self.motion.bytes()
            + self.forces.bytes()
            + self.swept.iter().map(|s| 24 + s.len() * 24).sum::<usize>()
    }

    /// Estimated memory of [`LfdReverse::new`] and of the geometry gradient's evaluations on
    /// `threads` threads for a mesh of `n_cells` cells, bytes.
    pub fn estimate_bytes(n_cells: usize, threads: usize) -> usize {
        n_cells * (BYTES_PER_CELL + threads * TANGENT_BYTES_PER_CELL)
    }

    /// Bᵀ w: the transpose of [`LfdOperator::motion_rhs`] at s, a seed per node (mesh frame):
    /// [`LfdReverse::position_transpose`] plus [`LfdReverse::motion_rhs_transpose_s_terms`].
    pub fn motion_rhs_transpose(&self, lfd: &LfdOperator, s: C64, w: &[C64]) -> Vec<[C64; 3]> {
        let mut nodes = self
            .position_transpose(lfd, &[w])
            .pop()
            .expect("one seed, one field");
        for (a, b) in nodes
            .iter_mut()
            .zip(self.motion_rhs_transpose_s_terms(lfd, s, w))
        {
            for k in 0..3 {
                a[k] += b[k];
            }
        }
        nodes
    }

    /// ∂R/∂xᵀ w for every seed w: the part of Bᵀ w that does not depend on the frequency (a
    /// reverse sweep applies it once, to the adjoints summed over the frequencies).
    pub fn position_transpose(&self, lfd: &LfdOperator, ws: &[&[C64]]) -> Vec<Vec<[C64; 3]>> {
        self.motion.node_transpose(&lfd.euler, &lfd.q0, ws)
    }

    /// The terms of Bᵀ w proportional to s: the cell volumes' s V̂ q₀ and the grid velocity's
    /// s ∂R/∂v_G L x̂ (per node, mesh frame).
    pub fn motion_rhs_transpose_s_terms(
        &self,
        lfd: &LfdOperator,
        s: C64,
        w: &[C64],
    ) -> Vec<[C64; 3]> {
        let mesh = &lfd.euler.mesh;
        // the s V̂ q₀ term: seed s Σ_k w_ck q₀_ck on each cell's volume
        let seeds: Vec<C64> = (0..mesh.n_cells)
            .map(|c| {
                s * (0..NVAR)
                    .map(|k| w[c * NVAR + k] * lfd.q0[c][k])
                    .sum::<C64>()
            })
            .collect();
        let mut nodes = self.motion.volume_transpose(&seeds);
        // the grid-velocity term s ∂R/∂v_G L x̂: Lᵀ (s ∂R/∂v_Gᵀ w)
        let vg = self.motion.face_transpose(mesh, w);
        for (fi, f) in mesh.faces.iter().enumerate() {
            let g = s * vg[fi];
            for (j, &n) in f.nodes.iter().enumerate() {
                for k in 0..3 {
                    nodes[n][k] += g * self.swept[fi][j][k];
                }
            }
        }
        nodes
    }

    /// The transpose of the linearized wall forces [`LfdOperator::wall_face_forces`]: for a
    /// seed on each wall face's force (in the order of `wall_faces`), the seeds F_qᵀ u on the
    /// state and F_xᵀ u on the node displacements.
    pub fn wall_forces_transpose(&self, u: &[[C64; 3]]) -> (Field, Vec<[C64; 3]>) {
        self.forces.transpose(u, self.n_cells, self.n_nodes)
    }

    /// Solves the adjoint LFD systems (s V + ∂R/∂q)ᵀ λ = r for every r with the factorization of
    /// the forward solves (its transpose preconditions GMRES), the right-hand sides in parallel.
    pub fn solve_transpose(
        &self,
        lfd: &LfdOperator,
        f: &Factored,
        rhs: &[Field],
    ) -> Result<Vec<(Field, GmresInfo)>, LfdError> {
        self.solve_transpose_from(lfd, f, rhs, &[])
    }

    /// [`LfdReverse::solve_transpose`] from initial guesses, combined to minimize the residual
    /// (see [`LfdOperator::solve_from`]).
    pub fn solve_transpose_from(
        &self,
        lfd: &LfdOperator,
        f: &Factored,
        rhs: &[Field],
        guesses: &[Vec<crate::lfd::Guess>],
    ) -> Result<Vec<(Field, GmresInfo)>, LfdError> {
        let prec = |vs: &[&[C64]]| lfd.precondition_transpose_many(f, vs);
        let op = |vs: &[&[C64]]| lfd.apply_transpose_many(f.s, vs);
        crate::lfd::solve_each(&op, &prec, rhs, guesses, (&lfd.params, f.omega), false)
    }
}

/// Finite-difference steps of the linearization table (the paper's Table 3: 1e-8 … 1e-13).
pub const TABLE_STEPS: [f64; 6] = [1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13];

/// wᵀ v of real vectors.
fn dot_re(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The linearization table of an LFD model about its steady state (paper Table 3): for random
/// real vectors v and w, each linearization's forward pairing wᵀ(L v), its transposed pairing
/// (Lᵀ w)ᵀ v, and real finite differences wᵀ(f(x + h v) − f(x))/h of the function it
/// linearizes. Rows: the residual's state Jacobian (the LFD operator), its node-position and
/// face-volume-flux Jacobians (the mode-motion and gust right-hand sides), the cell volumes, the
/// wall forces' state and node Jacobians, and the mesh deformation (linear: its differences are
/// exact up to round-off).
pub fn linearization_table(
    lfd: &LfdOperator,
    rev: &LfdReverse,
    deform: &crate::deform::Deformation,
    seed: u64,
) -> Vec<gustkit_core::LinearizationCheck> {
    let p = Probes::new(lfd, rev, seed);
    let mut rows = vec![
        p.state_jacobian(),
        p.motion_rhs(),
        p.volume_flux_rhs(),
        p.cell_volumes(),
    ];
    rows.extend(p.wall_forces());
    rows.push(p.deformation(deform));
    rows
}

/// The random directions of the linearization table and the state they probe about.
struct Probes<'a> {
    lfd: &'a LfdOperator,
    rev: &'a LfdReverse,
    /// State direction v and residual weight w.
    v: Vec<f64>,
    w: Vec<f64>,
    /// Node motion (3 a node): of the local spacing's size, zero on the far field.
    x: Vec<f64>,
    /// Face volume-flux direction.
    g: Vec<f64>,
    /// Cell-volume weight.
    wv: Vec<f64>,
    /// Wall-face force weight (3 a face).
    wf: Vec<f64>,
    q0: Vec<f64>,
    x0: Vec<[f64; 3]>,
}

/// One table row.
fn row(
    name: &str,
    forward: f64,
    reverse: Option<f64>,
    fd: Vec<(f64, f64)>,
) -> gustkit_core::LinearizationCheck {
    gustkit_core::LinearizationCheck {
        name: name.into(),
        forward,
        reverse,
        fd,
    }
}

/// Real finite differences (f(h) − f(0))/h at the table's steps.
fn differences(f: &dyn Fn(f64) -> f64) -> Vec<(f64, f64)> {
    let f0 = f(0.0);
    TABLE_STEPS.iter().map(|&h| (h, (f(h) - f0) / h)).collect()
}

fn complex(x: &[f64]) -> Vec<C64> {
    x.iter().map(|v| C64::new(*v, 0.0)).collect()
}

fn real(x: &[C64]) -> Vec<f64> {
    x.iter().map(|v| v.re).collect()
}

fn nodes3(x: &[f64]) -> Vec<[f64; 3]> {
    x.chunks(3).map(|c| [c[0], c[1], c[2]]).collect()
}

fn states(q: &[f64]) -> Vec<State<f64>> {
    q.chunks(NVAR)
        .map(|c| std::array::from_fn(|k| c[k]))
        .collect()
}

/// The smallest edge length at each node of a mesh.
fn node_spacing(mesh: &crate::mesh::Mesh) -> Vec<f64> {
    let mut spacing = vec![f64::MAX; mesh.nodes.len()];
    for f in &mesh.faces {
        for (i, &a) in f.nodes.iter().enumerate() {
            let b = f.nodes[(i + 1) % f.nodes.len()];
            let d = (0..3)
                .map(|k| (mesh.nodes[a][k] - mesh.nodes[b][k]).powi(2))
                .sum::<f64>()
                .sqrt();
            spacing[a] = spacing[a].min(d);
            spacing[b] = spacing[b].min(d);
        }
    }
    spacing
}

impl<'a> Probes<'a> {
    fn new(lfd: &'a LfdOperator, rev: &'a LfdReverse, seed: u64) -> Self {
        let mesh = &lfd.euler.mesh;
        let (n, nn, nf) = (lfd.n(), mesh.nodes.len(), mesh.faces.len());
        let r = lcg_vector(
            2 * n + 3 * nn + nf + mesh.n_cells + 3 * rev.wall_faces.len(),
            seed,
        );
        let mut it = r.iter().copied();
        let mut take =
            |m: usize| -> Vec<f64> { (0..m).map(|_| it.next().unwrap_or(0.0)).collect() };
        let (v, w) = (take(n), take(n));
        // node motions of the size of the local spacing (so the differences see a smooth
        // function of the step), vanishing on the far field (as the deformation's do)
        let far = mesh
            .nodes
            .iter()
            .map(|p| p[0].hypot(p[1]))
            .fold(0.0f64, f64::max);
        let spacing = node_spacing(mesh);
        let x: Vec<f64> = take(3 * nn)
            .chunks(3)
            .zip(&mesh.nodes)
            .zip(&spacing)
            .flat_map(|((c, p), &h)| {
                let on = if p[0].hypot(p[1]) < 0.5 * far {
                    0.1 * h
                } else {
                    0.0
                };
                [c[0] * on, c[1] * on, c[2] * on]
            })
            .collect();
        let g = take(nf);
        let wv = take(mesh.n_cells);
        let wf = take(3 * rev.wall_faces.len());
        Self {
            lfd,
            rev,
            v,
            w,
            x,
            g,
            wv,
            wf,
            q0: lfd.q0.iter().flatten().copied().collect(),
            x0: mesh.nodes.clone(),
        }
    }

    /// The nodes moved by h along the node direction.
    fn moved(&self, h: f64) -> Vec<[f64; 3]> {
        self.x0
            .iter()
            .zip(nodes3(&self.x))
            .map(|(p, d)| std::array::from_fn(|k| p[k] + h * d[k]))
            .collect()
    }

    /// The state moved by h along v.
    fn state_at(&self, h: f64) -> Vec<f64> {
        self.q0
            .iter()
            .zip(&self.v)
            .map(|(a, b)| a + h * b)
            .collect()
    }

    /// The node direction as complex amplitudes.
    fn x_hat(&self) -> Vec<[C64; 3]> {
        nodes3(&self.x)
            .iter()
            .map(|p| p.map(|v| C64::new(v, 0.0)))
            .collect()
    }

    /// The steady residual of state `q` on `nodes` with face volume fluxes `vg`.
    fn residual(&self, q: &[f64], nodes: &[[f64; 3]], vg: &[f64]) -> Vec<f64> {
        let e = &self.lfd.euler;
        let geom = e.geometry_at(nodes, vg.to_vec(), e.order);
        e.residual_in(&states(q), &geom)
            .0
            .into_iter()
            .flatten()
            .collect()
    }

    /// The wall-face forces of state `q` on `nodes` (a static grid).
    fn forces(&self, q: &[f64], nodes: &[[f64; 3]]) -> Vec<f64> {
        let e = &self.lfd.euler;
        let geom = e.geometry_at(nodes, vec![0.0; e.mesh.faces.len()], e.order);
        e.wall_face_forces(&states(q), &geom)
            .into_iter()
            .flat_map(|(_, f)| f)
            .collect()
    }

    /// ∂R/∂q: the LFD operator at s = 0.
    fn state_jacobian(&self) -> gustkit_core::LinearizationCheck {
        let (lfd, v, w) = (self.lfd, &self.v, &self.w);
        let zero = C64::new(0.0, 0.0);
        let face_vg = &lfd.euler.face_vg;
        row(
            "dR/dq (LFD operator, A at s = 0)",
            dot_re(w, &real(&lfd.apply_dual(zero, &complex(v)))),
            Some(dot_re(&real(&lfd.apply_transpose(zero, &complex(w))), v)),
            differences(&|h| dot_re(w, &self.residual(&self.state_at(h), &self.x0, face_vg))),
        )
    }

    /// ∂R/∂x_G: the mode-motion right-hand side at s = 0.
    fn motion_rhs(&self) -> gustkit_core::LinearizationCheck {
        let (lfd, w, x) = (self.lfd, &self.w, &self.x);
        let zero = C64::new(0.0, 0.0);
        let bt = self.rev.motion_rhs_transpose(lfd, zero, &complex(w));
        row(
            "dR/dx_G (mesh-motion right-hand side)",
            dot_re(w, &real(&lfd.motion_rhs(zero, &self.x_hat()))),
            Some(bt.iter().flatten().zip(x).map(|(a, b)| a.re * b).sum()),
            differences(&|h| {
                dot_re(
                    w,
                    &self.residual(&self.q0, &self.moved(h), &lfd.euler.face_vg),
                )
            }),
        )
    }

    /// ∂R/∂v_G: the face volume fluxes (grid velocity and gust right-hand sides).
    fn volume_flux_rhs(&self) -> gustkit_core::LinearizationCheck {
        let (lfd, w, g) = (self.lfd, &self.w, &self.g);
        let mesh = &lfd.euler.mesh;
        let adj = self.rev.motion.face_transpose(mesh, &complex(w));
        row(
            "dR/dv_G (grid-velocity and gust fluxes)",
            dot_re(w, &real(&lfd.volume_flux_rhs(&complex(g)))),
            Some(adj.iter().zip(g).map(|(a, b)| a.re * b).sum()),
            differences(&|h| {
                let vg: Vec<f64> = lfd
                    .euler
                    .face_vg
                    .iter()
                    .zip(g)
                    .map(|(a, b)| a + h * b)
                    .collect();
                dot_re(w, &self.residual(&self.q0, &self.x0, &vg))
            }),
        )
    }

    /// ∂V/∂x_G: the cell volumes (the s V̂ q₀ term).
    fn cell_volumes(&self) -> gustkit_core::LinearizationCheck {
        let mesh = &self.lfd.euler.mesh;
        let (wv, x) = (&self.wv, &self.x);
        let forward: f64 = {
            let nd: Vec<[Dual<1>; 3]> = self
                .x0
                .iter()
                .zip(nodes3(x))
                .map(|(p, d)| std::array::from_fn(|k| Dual::new(p[k], [d[k]])))
                .collect();
            mesh.volumes_at(&nd)
                .iter()
                .zip(wv)
                .map(|(a, b)| a.d[0] * b)
                .sum()
        };
        let adj = self.rev.motion.volume_transpose(&complex(wv));
        row(
            "dV/dx_G (cell volumes)",
            forward,
            Some(adj.iter().flatten().zip(x).map(|(a, b)| a.re * b).sum()),
            differences(&|h| {
                mesh.volumes_at(&self.moved(h))
                    .iter()
                    .zip(wv)
                    .map(|(a, b)| a * b)
                    .sum()
            }),
        )
    }

    /// ∂f/∂q and ∂f/∂x_G: the linearized wall forces.
    fn wall_forces(&self) -> [gustkit_core::LinearizationCheck; 2] {
        let (lfd, wf, v, x) = (self.lfd, &self.wf, &self.v, &self.x);
        let u: Vec<[C64; 3]> = wf
            .chunks(3)
            .map(|c| [c[0], c[1], c[2]].map(|v| C64::new(v, 0.0)))
            .collect();
        let (uq, ux) = self.rev.wall_forces_transpose(&u);
        let fq: Vec<f64> = lfd
            .wall_face_forces(&complex(v), None)
            .into_iter()
            .flat_map(|(_, f)| f.map(|z| z.re))
            .collect();
        let fx: Vec<f64> = lfd
            .wall_face_forces(&vec![C64::new(0.0, 0.0); lfd.n()], Some(&self.x_hat()))
            .into_iter()
            .flat_map(|(_, f)| f.map(|z| z.re))
            .collect();
        [
            row(
                "df/dq (wall forces, state)",
                dot_re(wf, &fq),
                Some(dot_re(&real(&uq), v)),
                differences(&|h| dot_re(wf, &self.forces(&self.state_at(h), &self.x0))),
            ),
            row(
                "df/dx_G (wall forces, nodes)",
                dot_re(wf, &fx),
                Some(ux.iter().flatten().zip(x).map(|(a, b)| a.re * b).sum()),
                differences(&|h| dot_re(wf, &self.forces(&self.q0, &self.moved(h)))),
            ),
        ]
    }

    /// The mesh deformation (linear): wall motion → node motion and its transpose.
    fn deformation(&self, deform: &crate::deform::Deformation) -> gustkit_core::LinearizationCheck {
        let x = &self.x;
        let nw = deform.wall_nodes.len();
        let wall: Vec<[f64; 3]> = nodes3(&x[..3 * nw.min(self.x0.len())]);
        let seed_nodes = nodes3(x);
        let pair = |a: &[[f64; 3]], b: &[[f64; 3]]| -> f64 {
            a.iter()
                .flatten()
                .zip(b.iter().flatten())
                .map(|(a, b)| a * b)
                .sum()
        };
        row(
            "mesh deformation",
            pair(&deform.apply(&wall), &seed_nodes),
            Some(pair(&deform.apply_transpose(&seed_nodes), &wall)),
            differences(&|h| {
                let moved: Vec<[f64; 3]> = wall.iter().map(|p| p.map(|v| h * v)).collect();
                pair(&deform.apply(&moved), &seed_nodes)
            }),
        )
    }
}

/// Reproducible pseudo-random numbers in [−1, 1) (a 64-bit LCG), for the table's vectors.
fn lcg_vector(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::airfoil::AirfoilShape;
    use crate::lfd::{Preconditioner, Symbol};
    use crate::residual::{free_stream, Euler, Order};
    use crate::steady::SteadyParams;

    fn rand_c(n: usize, seed: u64) -> Vec<C64> {
        let r = gustkit_testkit::rand_vec(2 * n, seed);
        (0..n).map(|i| C64::new(r[2 * i], r[2 * i + 1])).collect()
    }

    fn dot(a: &[C64], b: &[C64]) -> C64 {
        a.iter().zip(b).map(|(p, q)| p * q).sum()
    }

    /// A converged second-order flow at incidence (lift, so every term is non-trivial) on a
    /// small O-mesh with the given preconditioner.
    fn problem(preconditioner: Preconditioner) -> LfdOperator {
        let mesh = AirfoilShape::naca64a010().o_mesh(24, 8, 20.0, 0.004 / 20.0, 1.0);
        let e = Euler::new(mesh, free_stream(0.5, 0.03));
        assert_eq!(e.order, Order::Second);
        let (q0, _) = e
            .solve_steady(vec![e.q_inf; e.mesh.n_cells], &SteadyParams::default())
            .unwrap();
        let mut lfd = LfdOperator::with_preconditioner(e, q0, preconditioner);
        lfd.params.tolerance = 1e-13;
        lfd
    }

    fn agree(a: C64, b: C64) -> f64 {
        (a - b).norm() / a.norm().max(b.norm())
    }

    /// The linearization table (paper Table 3 analogue): every forward pairing equals its
    /// transposed one to 12 digits or more (measured 14.8–15.4), and the real finite differences
    /// approach it at their best step of 1e-8 … 1e-13 to 4 digits or more (measured 4.6–8.1: a
    /// one-sided difference loses to truncation above and to cancellation below; the small
    /// node-force pairing, 2.7e-5 of its terms, shows the cancellation most, as in the paper).
    #[test]
    fn linearization_table_agrees() {
        let lfd = problem(Preconditioner::Exact);
        let rev = LfdReverse::new(&lfd);
        let deform = crate::deform::Deformation::new(&lfd.euler.mesh, 10.0);
        for row in linearization_table(&lfd, &rev, &deform, 7) {
            let rev_v = row.reverse.unwrap();
            let digits = -((row.forward - rev_v).abs() / row.forward.abs()).log10();
            let best_fd = row
                .fd
                .iter()
                .map(|(_, v)| -((v - row.forward).abs() / row.forward.abs()).log10())
                .fold(f64::MIN, f64::max);
            eprintln!(
                "{:<42} forward {:+.15e} reverse {:+.15e} ({digits:.1} digits), best FD {best_fd:.1} digits",
                row.name, row.forward, rev_v
            );
            assert!(digits >= 12.0, "{}: {digits} digits", row.name);
            assert!(
                best_fd >= 4.0,
                "{}: finite differences {best_fd} digits",
                row.name
            );
        }
    }

    /// Dot-product tests (paper Eq. 21) of every transposed product against its forward product,
    /// with complex vectors, at s = 0 and s = 0.8i: ∂R/∂q (the assembled operator also against
    /// the dual-number residual pass, to 1e-13), the motion right-hand side B, the wall-force linearizations F_q and F_x, and the
    /// adjoint solve against the forward one. Agreement to 12 digits or more.
    #[test]
    fn transposes_pass_dot_product_tests() {
        for preconditioner in [Preconditioner::Exact, Preconditioner::FirstOrderIlu] {
            let lfd = problem(preconditioner);
            let rev = LfdReverse::new(&lfd);
            let n = lfd.n();
            let nn = lfd.euler.mesh.nodes.len();
            let v = rand_c(n, 1);
            let w = rand_c(n, 2);
            for s in [C64::new(0.0, 0.0), C64::new(0.0, 0.8)] {
                // ⟨w, A v⟩ = ⟨Aᵀ w, v⟩
                // the assembled operator against the dual-number residual pass
                let (av, av_dual) = (lfd.apply(s, &v), lfd.apply_dual(s, &v));
                let scale = av_dual.iter().fold(0.0f64, |m, x| m.max(x.norm()));
                for (p, q) in av.iter().zip(&av_dual) {
                    assert!((p - q).norm() < 1e-13 * scale, "{p} vs {q}");
                }
                let a = dot(&w, &av_dual);
                let b = dot(&lfd.apply_transpose(s, &w), &v);
                assert!(agree(a, b) < 1e-12, "{preconditioner:?} operator: {a} {b}");
                // ⟨w, B x̂⟩ = ⟨Bᵀ w, x̂⟩ (x̂ zero on the far-field nodes, as the deformation has)
                let xr = rand_c(3 * nn, 3);
                let x_hat: Vec<[C64; 3]> = (0..nn)
                    .map(|i| {
                        let p = lfd.euler.mesh.nodes[i];
                        let on = if p[0].hypot(p[1]) < 10.0 { 1.0 } else { 0.0 };
                        std::array::from_fn(|k| xr[3 * i + k] * on)
                    })
                    .collect();
                let a = dot(&w, &lfd.motion_rhs(s, &x_hat));
                let bt = rev.motion_rhs_transpose(&lfd, s, &w);
                let b: C64 = bt
                    .iter()
                    .zip(&x_hat)
                    .map(|(p, q)| (0..3).map(|k| p[k] * q[k]).sum::<C64>())
                    .sum();
                assert!(agree(a, b) < 1e-12, "{preconditioner:?} motion: {a} {b}");
                // ⟨u, F_q v + F_x x̂⟩ = ⟨F_qᵀ u, v⟩ + ⟨F_xᵀ u, x̂⟩
                let f = lfd.wall_face_forces(&v, Some(&x_hat));
                let u: Vec<[C64; 3]> = {
                    let r = rand_c(3 * f.len(), 4);
                    (0..f.len())
                        .map(|i| std::array::from_fn(|k| r[3 * i + k]))
                        .collect()
                };
                assert_eq!(
                    f.iter().map(|(fi, _)| *fi).collect::<Vec<_>>(),
                    rev.wall_faces
                );
                let a: C64 = f
                    .iter()
                    .zip(&u)
                    .map(|((_, p), q)| (0..3).map(|k| p[k] * q[k]).sum::<C64>())
                    .sum();
                let (uq, ux) = rev.wall_forces_transpose(&u);
                let b = dot(&uq, &v)
                    + ux.iter()
                        .zip(&x_hat)
                        .map(|(p, q)| (0..3).map(|k| p[k] * q[k]).sum::<C64>())
                        .sum::<C64>();
                assert!(agree(a, b) < 1e-12, "{preconditioner:?} forces: {a} {b}");
            }
            // ⟨w, A⁻¹ v⟩ = ⟨A⁻ᵀ w, v⟩ with the forward and adjoint GMRES (tolerance 1e-13)
            let f = lfd.factor(0.8, Symbol::Exact).unwrap();
            let x = lfd.solve(&f, &[v.iter().map(|z| -z).collect()]).unwrap();
            let y = rev
                .solve_transpose(&lfd, &f, std::slice::from_ref(&w))
                .unwrap();
            let (a, b) = (dot(&w, &x[0].0), dot(&y[0].0, &v));
            assert!(agree(a, b) < 1e-11, "{preconditioner:?} solve: {a} {b}");
            eprintln!(
                "linearizations per cell: motion {} B, forces {} B ({} + {} evaluations)",
                rev.motion.bytes() / lfd.euler.mesh.n_cells,
                rev.forces.bytes() / lfd.euler.mesh.n_cells,
                rev.motion.evaluations,
                rev.forces.evaluations
            );
            eprintln!(
                "{preconditioner:?}: adjoint GMRES {} iterations (forward {}); linearizations {:.1} MB for {} cells",
                y[0].1.iterations,
                x[0].1.iterations,
                rev.bytes() as f64 / 1e6,
                lfd.euler.mesh.n_cells
            );
        }
    }
}
