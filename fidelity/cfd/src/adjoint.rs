//! The transposes of the LFD's linearizations (paper Sec. III), for the adjoint of the GAFs with
//! respect to the mode shapes.
//!
//! Method: the residual and the wall forces are written once over [`Scalar`]; recorded on an
//! operation tape ([`gustkit_core::tape`]) at the steady state q₀ on the static mesh, one backward
//! sweep gives the transposed product of each linearization for any (complex) seed:
//! - ∂R/∂qᵀ ψ (the adjoint LFD operator (s V + ∂R/∂q)ᵀ; from the exact Jacobian blocks when the
//!   preconditioner holds them, else from a tape of the residual over q);
//! - Bᵀ ψ of the mode-motion right-hand side B x̂ = ∂R/∂x x̂ + s ∂R/∂v_G L x̂ + s V̂(x̂) q₀ (node
//!   positions, face volume fluxes through the swept-volume linearization L, cell volumes): one
//!   tape of the residual and the volumes over the nodes and the face volume fluxes;
//! - F_qᵀ u and F_xᵀ u of the linearized wall forces f̂ = F_q q̂ + F_x x̂: one tape of the wall
//!   forces over q and the nodes.
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
use crate::krylov::{gmres, GmresInfo};
use crate::lfd::{Factored, Field, LfdError, LfdOperator};
use crate::mesh::{Boundary, Side};
use crate::residual::State;
use gustkit_core::scalar::{Dual, Scalar};
use gustkit_core::tape::{Rev, Tape, BYTES_PER_ENTRY};
use num_complex::Complex64 as C64;
use rayon::prelude::*;

/// A recorded kernel: its tape, its inputs and its outputs, in fixed orders.
struct Recorded {
    tape: Tape,
    inputs: Vec<Rev>,
    outputs: Vec<Rev>,
}

impl Recorded {
    /// wᵀ ∂(outputs)/∂(inputs) for seeds w aligned with the outputs.
    fn vjp(&self, w: &[C64]) -> Vec<C64> {
        debug_assert_eq!(w.len(), self.outputs.len());
        let adj = self
            .tape
            .sweep(self.outputs.iter().zip(w).map(|(r, w)| (*r, *w)));
        self.inputs.iter().map(|x| adj.of(*x)).collect()
    }

    /// Memory of the tape and of one sweep's adjoints, bytes.
    fn bytes(&self) -> usize {
        self.tape.bytes() + self.tape.len() * std::mem::size_of::<C64>()
    }
}

/// The transposed linearizations of an [`LfdOperator`] about its steady state.
pub struct LfdReverse {
    /// The residual over q (geometry fixed), when the preconditioner's blocks are not exact.
    state: Option<Recorded>,
    /// The residual and the cell volumes over the node positions and the face volume fluxes.
    geometry: Recorded,
    /// The wall forces over q and the node positions.
    forces: Recorded,
    /// The wall faces of the forces, in the order of [`LfdOperator::wall_face_forces`].
    pub wall_faces: Vec<usize>,
    /// Per face, per face node: ∂(swept volume)/∂(node displacement), the linearization L.
    swept: Vec<Vec<[f64; 3]>>,
    n_nodes: usize,
    n_faces: usize,
}

/// Estimated operations recorded per cell for the residual tape (used to refuse a recording that
/// would not fit; measured: see the module's tests).
pub const TAPE_ENTRIES_PER_CELL: usize = 4000;

impl LfdReverse {
    /// Records the tapes of `lfd` at its steady state.
    pub fn new(lfd: &LfdOperator) -> Self {
        let e = &lfd.euler;
        let order = e.order;
        let mesh = &e.mesh;
        let (n_nodes, n_faces) = (mesh.nodes.len(), mesh.faces.len());
        let state = (!lfd.blocks_are_exact()).then(|| {
            let ((inputs, outputs), tape) = Tape::record(|| {
                let q: Vec<State<Rev>> =
                    lfd.q0.iter().map(|s| s.map(Rev::input)).collect::<Vec<_>>();
                let geom = e.geometry::<Rev>(order);
                let r = e.residual_in(&q, &geom).0;
                (
                    q.into_iter().flatten().collect::<Vec<_>>(),
                    r.into_iter().flatten().collect::<Vec<_>>(),
                )
            });
            Recorded {
                tape,
                inputs,
                outputs,
            }
        });
        let ((inputs, outputs), tape) = Tape::record(|| {
            let nodes: Vec<[Rev; 3]> = mesh.nodes.iter().map(|p| p.map(Rev::input)).collect();
            let vg: Vec<Rev> = e.face_vg.iter().map(|v| Rev::input(*v)).collect();
            let q: Vec<State<Rev>> = lfd.q0.iter().map(|s| s.map(Rev::cst)).collect();
            let geom = e.geometry_at(&nodes, vg.clone(), order);
            let r = e.residual_in(&q, &geom).0;
            let v = mesh.volumes_at(&nodes);
            let mut inputs: Vec<Rev> = nodes.into_iter().flatten().collect();
            inputs.extend(vg);
            let mut outputs: Vec<Rev> = r.into_iter().flatten().collect();
            outputs.extend(v);
            (inputs, outputs)
        });
        let geometry = Recorded {
            tape,
            inputs,
            outputs,
        };
        // the wall forces depend on the wall cells' states and reconstruction only: the states
        // of the wall cells and their face neighbours, the nodes of those cells; everything else
        // enters as a constant and is not recorded
        let mut near = vec![false; mesh.n_cells];
        for f in &mesh.faces {
            if f.right == Side::Boundary(Boundary::Wall) {
                near[f.left] = true;
            }
        }
        let wall_cells = near.clone();
        for f in &mesh.faces {
            if let Side::Cell(r) = f.right {
                if wall_cells[f.left] || wall_cells[r] {
                    near[f.left] = true;
                    near[r] = true;
                }
            }
        }
        let mut node_near = vec![false; n_nodes];
        for f in &mesh.faces {
            let touches = near[f.left] || matches!(f.right, Side::Cell(r) if near[r]);
            if touches {
                for &n in &f.nodes {
                    node_near[n] = true;
                }
            }
        }
        let ((inputs, outputs, wall_faces), tape) = Tape::record(|| {
            let q: Vec<State<Rev>> = lfd
                .q0
                .iter()
                .zip(&near)
                .map(|(s, &v)| s.map(|x| if v { Rev::input(x) } else { Rev::cst(x) }))
                .collect();
            let nodes: Vec<[Rev; 3]> = mesh
                .nodes
                .iter()
                .zip(&node_near)
                .map(|(p, &v)| p.map(|x| if v { Rev::input(x) } else { Rev::cst(x) }))
                .collect();
            let geom = e.geometry_at(&nodes, vec![Rev::cst(0.0); n_faces], order);
            let f = e.wall_face_forces(&q, &geom);
            let mut inputs: Vec<Rev> = q.into_iter().flatten().collect();
            inputs.extend(nodes.into_iter().flatten());
            let wall_faces = f.iter().map(|(fi, _)| *fi).collect();
            let outputs = f.into_iter().flat_map(|(_, v)| v).collect();
            (inputs, outputs, wall_faces)
        });
        let forces = Recorded {
            tape,
            inputs,
            outputs,
        };
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
            state,
            geometry,
            forces,
            wall_faces,
            swept,
            n_nodes,
            n_faces,
        }
    }

    /// Memory held by the tapes and one sweep of each, bytes.
    pub fn bytes(&self) -> usize {
        self.state.as_ref().map_or(0, Recorded::bytes) + self.geometry.bytes() + self.forces.bytes()
    }

    /// Estimated memory of [`LfdReverse::new`] for a mesh of `n_cells` cells, bytes.
    pub fn estimate_bytes(n_cells: usize) -> usize {
        n_cells * TAPE_ENTRIES_PER_CELL * (BYTES_PER_ENTRY + std::mem::size_of::<C64>())
    }

    /// The adjoint LFD operator (s V + ∂R/∂q)ᵀ v.
    pub fn apply_transpose(&self, lfd: &LfdOperator, s: C64, v: &[C64]) -> Field {
        let vol = &lfd.euler.volumes;
        let mut out: Field = match &self.state {
            Some(rec) => rec.vjp(v),
            None => {
                let mut out = vec![C64::new(0.0, 0.0); v.len()];
                for (row, col, b) in lfd.blocks() {
                    for j in 0..NVAR {
                        let mut acc = C64::new(0.0, 0.0);
                        for i in 0..NVAR {
                            acc += v[row * NVAR + i] * b[i][j];
                        }
                        out[col * NVAR + j] += acc;
                    }
                }
                out
            }
        };
        for (i, o) in out.iter_mut().enumerate() {
            *o += s * vol[i / NVAR] * v[i];
        }
        out
    }

    /// Bᵀ w: the transpose of [`LfdOperator::motion_rhs`] at s, a seed per node (mesh frame).
    pub fn motion_rhs_transpose(&self, lfd: &LfdOperator, s: C64, w: &[C64]) -> Vec<[C64; 3]> {
        let n_cells = lfd.euler.mesh.n_cells;
        let mut seeds = w.to_vec();
        // the s V̂ q₀ term: seed s Σ_k w_ck q₀_ck on each cell's volume
        seeds.extend((0..n_cells).map(|c| {
            s * (0..NVAR)
                .map(|k| w[c * NVAR + k] * lfd.q0[c][k])
                .sum::<C64>()
        }));
        let adj = self.geometry.vjp(&seeds);
        let mut nodes: Vec<[C64; 3]> = (0..self.n_nodes)
            .map(|n| std::array::from_fn(|k| adj[3 * n + k]))
            .collect();
        // the grid-velocity term s ∂R/∂v_G L x̂: Lᵀ (s ∂R/∂v_Gᵀ w)
        let vg = &adj[3 * self.n_nodes..3 * self.n_nodes + self.n_faces];
        for (fi, f) in lfd.euler.mesh.faces.iter().enumerate() {
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
        let w: Vec<C64> = u.iter().flatten().copied().collect();
        let adj = self.forces.vjp(&w);
        let n_q = adj.len() - 3 * self.n_nodes;
        let nodes = (0..self.n_nodes)
            .map(|n| std::array::from_fn(|k| adj[n_q + 3 * n + k]))
            .collect();
        (adj[..n_q].to_vec(), nodes)
    }

    /// Solves the adjoint LFD systems (s V + ∂R/∂q)ᵀ λ = r for every r with the factorization of
    /// the forward solves (its transpose preconditions GMRES), the right-hand sides in parallel.
    pub fn solve_transpose(
        &self,
        lfd: &LfdOperator,
        f: &Factored,
        rhs: &[Field],
    ) -> Result<Vec<(Field, GmresInfo)>, LfdError> {
        lfd.params.validate().map_err(LfdError::Input)?;
        let prec = |v: &[C64]| lfd.precondition_transpose(f, v);
        let op = |v: &[C64]| self.apply_transpose(lfd, f.s, v);
        rhs.par_iter()
            .enumerate()
            .map(|(index, b)| {
                let p = &lfd.params;
                gmres(&op, &prec, b, p.tolerance, p.restart, p.max_iterations).map_err(|source| {
                    LfdError::Gmres {
                        omega: f.omega,
                        rhs: index,
                        source,
                    }
                })
            })
            .collect()
    }
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

    /// Dot-product tests (paper Eq. 21) of every transposed product against its forward product,
    /// with complex vectors, at s = 0 and s = 0.8i: ∂R/∂q (from the exact blocks and from the
    /// tape), the motion right-hand side B, the wall-force linearizations F_q and F_x, and the
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
                let a = dot(&w, &lfd.apply(s, &v));
                let b = dot(&rev.apply_transpose(&lfd, s, &w), &v);
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
                "tape entries per cell: state {:?}, geometry {}, forces {}",
                rev.state
                    .as_ref()
                    .map(|r| r.tape.len() / lfd.euler.mesh.n_cells),
                rev.geometry.tape.len() / lfd.euler.mesh.n_cells,
                rev.forces.tape.len() / lfd.euler.mesh.n_cells
            );
            eprintln!(
                "{preconditioner:?}: adjoint GMRES {} iterations (forward {}); tapes {:.1} MB for {} cells",
                y[0].1.iterations,
                x[0].1.iterations,
                rev.bytes() as f64 / 1e6,
                lfd.euler.mesh.n_cells
            );
        }
    }
}
