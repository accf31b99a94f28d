//! The linearized frequency-domain (LFD) equations about a steady state q₀ (paper Eqs. 7 and 12):
//! (s V + ∂R/∂q) q̂ = −b for harmonic perturbations e^{iωt}, with s = iω (or, to reproduce a BDF2
//! time march exactly, its symbol s = (3 − 4e^{−iωΔt} + e^{−2iωΔt})/(2Δt)). The right-hand sides
//! come from the generic residual in dual numbers: a convected gust enters the face volume fluxes
//! (Field Velocity Method, ∂R/∂u_G û_G), mode motion the node positions, the face volume fluxes of
//! the grid velocity and the cell volumes (∂R/∂x_G x̂_G + s ∂R/∂ẋ_G x̂_G + s V̂ q₀). Each
//! frequency factors the complex first-order operator s V + ∂R₁/∂q once (sparse LU) and solves
//! every right-hand side by restarted complex GMRES on the exact operator, preconditioned with it.

use crate::gas::NVAR;
use crate::ilu::{BlockIlu, IluParams};
use crate::jacobian::{BlockRows, Blocks};
use crate::krylov::{gmres_batch, GmresError, GmresInfo};
use crate::residual::{Euler, State};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::Lu;
use faer::Mat;
use gustkit_core::scalar::{Dual, Scalar};
use num_complex::{Complex32 as C32, Complex64 as C64};
use rayon::prelude::*;

/// The time derivative's symbol: what iω becomes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Symbol {
    /// s = iω: the continuous-time LFD.
    Exact,
    /// s = (3 − 4e^{−iωΔt} + e^{−2iωΔt})/(2Δt): the periodic response of the BDF2 march with
    /// step Δt, for verification against it.
    Bdf2 { dt: f64 },
}

impl Symbol {
    /// s at circular frequency ω.
    pub fn at(&self, omega: f64) -> C64 {
        match *self {
            Symbol::Exact => C64::new(0.0, omega),
            Symbol::Bdf2 { dt } => {
                let z = C64::new(0.0, -omega * dt).exp();
                (3.0 - 4.0 * z + z * z) / (2.0 * dt)
            }
        }
    }
}

/// Settings of the LFD solves.
#[derive(Clone, Debug, PartialEq)]
pub struct LfdParams {
    /// GMRES stops at ‖A q̂ + b‖ ≤ tolerance ‖b‖.
    pub tolerance: f64,
    pub restart: usize,
    pub max_iterations: usize,
    /// The right-hand sides of one frequency are solved in lockstep batches of this many
    /// (each step applies the operator and the preconditioner to the whole batch, reading their
    /// matrices once; each keeps its own GMRES basis, so memory grows with the batch).
    pub batch: usize,
    /// Fill level and ordering of the block ILU preconditioners (ignored by the LU ones).
    pub ilu: IluParams,
}

impl LfdParams {
    /// Checks the settings before a solve: a tolerance in (0, 1), a restart length and an
    /// iteration limit of at least one.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return Err(format!(
                "tolerance: must lie in (0, 1) (got {})",
                self.tolerance
            ));
        }
        if self.restart == 0 || self.max_iterations == 0 || self.batch == 0 {
            return Err("restart, max_iterations and batch must be at least 1".into());
        }
        self.ilu.validate()
    }
}

impl Default for LfdParams {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            restart: 80,
            max_iterations: 800,
            batch: 1,
            ilu: IluParams::default(),
        }
    }
}

/// Why an LFD solve failed.
#[derive(Debug, thiserror::Error)]
pub enum LfdError {
    #[error("LFD at ω = {omega}, right-hand side {rhs}: {source}")]
    Gmres {
        omega: f64,
        /// Index of the right-hand side in the list given to [`LfdOperator::solve`].
        rhs: usize,
        #[source]
        source: GmresError,
    },
    #[error("LFD at ω = {omega}: the preconditioner could not be factored: {reason}")]
    Factor { omega: f64, reason: String },
    #[error("{0}")]
    Input(String),
}

/// A harmonic vertical gust of unit velocity amplitude convected at `convection` in +x:
/// û_G = [0, e^{−iω(x − x0)/U}, 0] (the 2-D meshes are in the x-y plane, y up; paper Eq. 13).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HarmonicGust {
    pub convection: f64,
    pub x0: f64,
}

/// Which matrix the factored preconditioner s V + J holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preconditioner {
    /// The exact Jacobian of the scheme (coloured assembly): the LU solves the LFD system
    /// directly, GMRES only polishes (one or two iterations). The default where it fits in memory.
    Exact,
    /// The first-order Jacobian: a sparser LU, more GMRES iterations.
    FirstOrder,
    /// Block ILU(0) of the exact Jacobian: no fill, for meshes whose LU would not fit in memory;
    /// the most GMRES iterations.
    BlockIlu,
    /// Block ILU(0) of the first-order Jacobian: sparser and more diagonally dominant than the
    /// exact one's (the exact second-order Jacobian's ILU(0) can be unstable on fine 3-D meshes).
    FirstOrderIlu,
}

/// The LFD problem about a converged steady state.
pub struct LfdOperator {
    pub euler: Euler,
    pub q0: Vec<State<f64>>,
    /// Jacobian blocks at q₀ of the preconditioner's matrix.
    blocks: Blocks,
    /// The exact Jacobian at the scheme's order at q₀, in compressed rows: the operator's
    /// products (forward and transposed).
    exact: BlockRows,
    pub preconditioner: Preconditioner,
    pub params: LfdParams,
}

/// One frequency's factored preconditioner.
pub struct Factored {
    pub omega: f64,
    pub s: C64,
    factors: Factors,
}

impl Factored {
    /// Stored 5 × 5 blocks of an ILU's factors (0 for a sparse LU): the preconditioner's size.
    pub fn n_blocks(&self) -> usize {
        match &self.factors {
            Factors::Ilu(ilu) => ilu.n_blocks(),
            Factors::Lu(_) => 0,
        }
    }

    /// Memory held by an ILU's factors, bytes (0 for a sparse LU, which does not report it).
    pub fn bytes(&self) -> usize {
        match &self.factors {
            Factors::Ilu(ilu) => ilu.bytes(),
            Factors::Lu(_) => 0,
        }
    }
}

enum Factors {
    Lu(Box<Lu<usize, C64>>),
    Ilu(BlockIlu<C64>),
}

/// The sparse LU's solves of several vectors (`transpose`: Aᵀ x = v, not conjugated), one
/// column at a time: faer's multi-column solve rounds differently from its one-column solve, and
/// a batch must give the answers of one right-hand side at a time bit for bit.
fn lu_solve_many(lu: &Lu<usize, C64>, vs: &[&[C64]], transpose: bool) -> Vec<Field> {
    vs.iter()
        .map(|v| {
            let b = Mat::<C64>::from_fn(v.len(), 1, |i, _| v[i]);
            let x = match transpose {
                true => lu.solve_transpose(b),
                false => lu.solve(b),
            };
            (0..v.len()).map(|i| x[(i, 0)]).collect()
        })
        .collect()
}

/// A complex field of cell states, flattened (cell-major, 5 per cell).
pub type Field = Vec<C64>;

/// A GMRES initial guess kept in single precision (a previous design's solution).
pub type Guess<'a> = &'a [C32];

/// Products with several vectors at once: the LFD operator or its preconditioner.
pub(crate) type Many<'a> = dyn Fn(&[&[C64]]) -> Vec<Field> + Sync + 'a;

/// GMRES on every right-hand side (`negate`: for A x = −b) from the combination of its guesses
/// ([`combined_guess`]; `guesses[i]` for right-hand side i, none or several), to the tolerance
/// of `params` relative to the right-hand side: in lockstep batches of `params.batch` (the
/// batches in parallel).
pub(crate) fn solve_each(
    op: &Many,
    prec: &Many,
    rhs: &[Field],
    guesses: &[Vec<Guess>],
    (params, omega): (&LfdParams, f64),
    negate: bool,
) -> Result<Vec<(Field, GmresInfo)>, LfdError> {
    params.validate().map_err(LfdError::Input)?;
    let one = |v: &[C64]| -> Field { op(&[v]).pop().expect("one vector in, one out") };
    let indices: Vec<usize> = (0..rhs.len()).collect();
    let solved: Vec<Vec<(Field, GmresInfo)>> = indices
        .par_chunks(params.batch)
        .map(|batch| {
            let bs: Vec<std::borrow::Cow<[C64]>> = batch
                .iter()
                .map(|&i| {
                    if negate {
                        rhs[i].iter().map(|x| -x).collect::<Field>().into()
                    } else {
                        rhs[i].as_slice().into()
                    }
                })
                .collect();
            let x0s: Vec<Option<Field>> = batch
                .iter()
                .zip(&bs)
                .map(|(&i, b)| guesses.get(i).and_then(|g| combined_guess(&one, g, b)))
                .collect();
            let results = gmres_batch(
                op,
                prec,
                &bs.iter().map(|b| b.as_ref()).collect::<Vec<_>>(),
                &x0s.iter().map(Option::as_deref).collect::<Vec<_>>(),
                params.tolerance,
                params.restart,
                params.max_iterations,
            );
            batch
                .iter()
                .zip(results)
                .map(|(&index, r)| {
                    r.map_err(|source| LfdError::Gmres {
                        omega,
                        rhs: index,
                        source,
                    })
                })
                .collect::<Result<Vec<_>, _>>()
        })
        .collect::<Result<_, _>>()?;
    Ok(solved.into_iter().flatten().collect())
}

/// Below this fraction of its own norm, the part of A g_j outside the span of the earlier
/// guesses' products is taken for round-off of the single-precision guesses (relative 6e-8) and
/// the guess is left out, so that nearly equal guesses do not combine with huge coefficients.
const GUESS_INDEPENDENCE: f64 = 1e-6;

/// The initial guess Σ α_j g_j for A x = b with α minimizing ‖b − Σ α_j A g_j‖ (one product with
/// A a guess, modified Gram–Schmidt with reorthogonalization on the products): the guesses are
/// the solutions of previous designs, and their span follows a solution that moves with the
/// design (a line search's trial points lie on a line: two designs give its first-order change).
/// With one guess it is the complex scaling that makes a mode shape whose sign flipped start no
/// worse than from zero; in every case the guess's residual is at most ‖b‖. Guesses of another
/// length are ignored; none left (or a non-finite result) gives no guess.
pub fn combined_guess(op: &dyn Fn(&[C64]) -> Field, guesses: &[Guess], b: &[C64]) -> Option<Field> {
    let n = b.len();
    let dot = |u: &[C64], v: &[C64]| -> C64 { u.iter().zip(v).map(|(a, c)| a.conj() * c).sum() };
    let norm = |u: &[C64]| u.iter().map(|v| v.norm_sqr()).sum::<f64>().sqrt();
    // the guesses in double precision, and an orthonormal basis q_j = Σ_i c_ji A g_i of their
    // products
    let mut kept: Vec<Field> = Vec::new();
    let mut basis: Vec<(Field, Vec<C64>)> = Vec::new();
    for g in guesses.iter().filter(|g| g.len() == n) {
        let g: Field = g
            .iter()
            .map(|v| C64::new(v.re as f64, v.im as f64))
            .collect();
        let mut w = op(&g);
        let size = norm(&w);
        if !(size > 0.0 && size.is_finite()) {
            continue;
        }
        let i = kept.len();
        let mut c = vec![C64::new(0.0, 0.0); i + 1];
        c[i] = C64::new(1.0, 0.0);
        for _ in 0..2 {
            for (q, cq) in &basis {
                let h = dot(q, &w);
                w.iter_mut().zip(q).for_each(|(a, qv)| *a -= h * qv);
                c.iter_mut().zip(cq).for_each(|(a, cv)| *a -= h * cv);
            }
        }
        let rest = norm(&w);
        if rest <= GUESS_INDEPENDENCE * size {
            continue;
        }
        w.iter_mut().for_each(|a| *a /= rest);
        c.iter_mut().for_each(|a| *a /= rest);
        kept.push(g);
        basis.push((w, c));
    }
    if kept.is_empty() {
        return None;
    }
    // α = Σ_j ⟨q_j, b⟩ c_j: the projection of b on the span is Σ_j ⟨q_j, b⟩ q_j = Σ_i α_i A g_i
    let mut alpha = vec![C64::new(0.0, 0.0); kept.len()];
    for (q, c) in &basis {
        let h = dot(q, b);
        alpha.iter_mut().zip(c).for_each(|(a, cv)| *a += h * cv);
    }
    let mut x = vec![C64::new(0.0, 0.0); n];
    for (g, a) in kept.iter().zip(&alpha) {
        x.iter_mut().zip(g).for_each(|(xv, gv)| *xv += a * gv);
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

impl LfdOperator {
    /// The LFD problem of `euler` (static mesh, no gust) about its steady state `q0`, with the
    /// exact Jacobian as preconditioner.
    pub fn new(euler: Euler, q0: Vec<State<f64>>) -> Self {
        Self::with_preconditioner(euler, q0, Preconditioner::Exact)
    }

    /// The LFD problem with a chosen preconditioner.
    pub fn with_preconditioner(
        euler: Euler,
        q0: Vec<State<f64>>,
        preconditioner: Preconditioner,
    ) -> Self {
        let coloring = crate::jacobian::Coloring::new(&euler, euler.order);
        let exact_blocks = euler.jacobian_colored(&q0, &coloring, euler.order);
        let exact = BlockRows::new(euler.mesh.n_cells, &exact_blocks);
        let blocks = match preconditioner {
            Preconditioner::FirstOrder | Preconditioner::FirstOrderIlu => euler.jacobian(&q0),
            Preconditioner::Exact | Preconditioner::BlockIlu => exact_blocks,
        };
        Self {
            euler,
            q0,
            blocks,
            exact,
            preconditioner,
            params: LfdParams::default(),
        }
    }

    pub fn n(&self) -> usize {
        self.euler.mesh.n_cells * NVAR
    }

    /// The exact operator (s V + ∂R/∂q) v at the scheme's order, with the assembled Jacobian.
    pub fn apply(&self, s: C64, v: &[C64]) -> Field {
        self.apply_many(s, &[v])
            .pop()
            .expect("one vector in, one out")
    }

    /// The transposed operator (s V + ∂R/∂q)ᵀ v (not conjugated), for the adjoint.
    pub fn apply_transpose(&self, s: C64, v: &[C64]) -> Field {
        self.apply_transpose_many(s, &[v])
            .pop()
            .expect("one vector in, one out")
    }

    /// [`LfdOperator::apply`] on several vectors in one pass over the Jacobian.
    pub fn apply_many(&self, s: C64, vs: &[&[C64]]) -> Vec<Field> {
        let mut outs = self.exact.mul_many(vs);
        self.add_shift(s, vs, &mut outs);
        outs
    }

    /// [`LfdOperator::apply_transpose`] on several vectors in one pass over the Jacobian.
    pub fn apply_transpose_many(&self, s: C64, vs: &[&[C64]]) -> Vec<Field> {
        let mut outs = self.exact.mul_transpose_many(vs);
        self.add_shift(s, vs, &mut outs);
        outs
    }

    /// out += s V v for each pair.
    fn add_shift(&self, s: C64, vs: &[&[C64]], outs: &mut [Field]) {
        let vol = &self.euler.volumes;
        for (out, v) in outs.iter_mut().zip(vs) {
            for (i, o) in out.iter_mut().enumerate() {
                *o += s * vol[i / NVAR] * v[i];
            }
        }
    }

    /// [`LfdOperator::apply`] by one dual-number pass of the residual (the real and imaginary
    /// parts of v as two directions): the reference the assembled Jacobian is checked against.
    pub fn apply_dual(&self, s: C64, v: &[C64]) -> Field {
        let q: Vec<State<Dual<2>>> = self
            .q0
            .iter()
            .enumerate()
            .map(|(c, qc)| {
                std::array::from_fn(|k| {
                    let x = v[c * NVAR + k];
                    Dual::new(qc[k], [x.re, x.im])
                })
            })
            .collect();
        let jv = self.euler.residual(&q);
        (0..self.n())
            .map(|i| {
                let (c, k) = (i / NVAR, i % NVAR);
                s * v[i] * self.euler.volumes[c] + C64::new(jv[c][k].d[0], jv[c][k].d[1])
            })
            .collect()
    }

    /// Factors the preconditioner s V + ∂R₁/∂q at ω (once per frequency).
    pub fn factor(&self, omega: f64, symbol: Symbol) -> Result<Factored, LfdError> {
        let mut f = self.factor_shift(symbol.at(omega))?;
        f.omega = omega;
        Ok(f)
    }

    /// Solves (s V + ∂R/∂q) q̂ = −b for every right-hand side b with one factorization (the
    /// right-hand sides in parallel).
    pub fn solve(&self, f: &Factored, rhs: &[Field]) -> Result<Vec<(Field, GmresInfo)>, LfdError> {
        self.solve_from(f, rhs, &[])
    }

    /// [`LfdOperator::solve`] with initial guesses (`guesses[i]` for right-hand side i: none,
    /// or previous designs' solutions): their combination that minimizes the residual
    /// ([`combined_guess`]), so that a guess of the wrong sign or size — a mode shape that
    /// flipped between designs — starts no worse than zero. The tolerance stays relative to
    /// the right-hand side: the same accuracy as from zero.
    pub fn solve_from(
        &self,
        f: &Factored,
        rhs: &[Field],
        guesses: &[Vec<Guess>],
    ) -> Result<Vec<(Field, GmresInfo)>, LfdError> {
        let prec = |vs: &[&[C64]]| self.precondition_many(f, vs);
        let op = |vs: &[&[C64]]| self.apply_many(f.s, vs);
        solve_each(&op, &prec, rhs, guesses, (&self.params, f.omega), true)
    }

    /// The gust right-hand side b = ∂R/∂u_G û_G at ω: the face volume fluxes of the harmonic gust
    /// (integrated exactly over each face, as in the time domain) through the residual's dual
    /// numbers.
    pub fn gust_rhs(&self, omega: f64, gust: &HarmonicGust) -> Field {
        let dvg = self
            .euler
            .harmonic_gust_fluxes(omega, gust.convection, gust.x0);
        self.volume_flux_rhs(&dvg)
    }

    /// ∂R/∂(face volume fluxes) · δ for complex face volume fluxes δ.
    pub fn volume_flux_rhs(&self, dvg: &[C64]) -> Field {
        let vg: Vec<Dual<2>> = self
            .euler
            .face_vg
            .iter()
            .zip(dvg)
            .map(|(v, d)| Dual::new(*v, [d.re, d.im]))
            .collect();
        let nodes: Vec<[Dual<2>; 3]> = self
            .euler
            .mesh
            .nodes
            .iter()
            .map(|p| p.map(Dual::cst))
            .collect();
        let geom = self.euler.geometry_at(&nodes, vg, self.euler.order);
        self.residual_part(&geom)
    }

    /// The mode-motion right-hand side b = ∂R/∂x x̂ + s ∂R/∂ẋ x̂ + s V̂ q₀ for node displacements
    /// `x_hat`: the node positions, the face volume fluxes s L(x̂) (L the linearized swept volume,
    /// the same discrete geometric conservation law as the time domain) and the cell volumes, all
    /// in dual numbers.
    pub fn motion_rhs(&self, s: C64, x_hat: &[[C64; 3]]) -> Field {
        let mesh = &self.euler.mesh;
        let nodes: Vec<[Dual<2>; 3]> = mesh
            .nodes
            .iter()
            .zip(x_hat)
            .map(|(p, d)| std::array::from_fn(|i| Dual::new(p[i], [d[i].re, d[i].im])))
            .collect();
        // L(x̂): the swept volume of every face moving from x₀ to x₀ + ε x̂, to first order
        let vg: Vec<Dual<2>> = mesh
            .faces
            .iter()
            .enumerate()
            .map(|(fi, f)| {
                let a: Vec<[Dual<2>; 3]> = f
                    .nodes
                    .iter()
                    .map(|&n| mesh.nodes[n].map(Dual::cst))
                    .collect();
                let b: Vec<[Dual<2>; 3]> = f.nodes.iter().map(|&n| nodes[n]).collect();
                let l = crate::mesh::swept_volume(&a, &b);
                let sl = s * C64::new(l.d[0], l.d[1]);
                Dual::new(self.euler.face_vg[fi], [sl.re, sl.im])
            })
            .collect();
        let geom = self.euler.geometry_at(&nodes, vg, self.euler.order);
        let mut b = self.residual_part(&geom);
        let v_hat = mesh.volumes_at(&nodes);
        for (c, vc) in v_hat.iter().enumerate() {
            let dv = s * C64::new(vc.d[0], vc.d[1]);
            for k in 0..NVAR {
                b[c * NVAR + k] += dv * self.q0[c][k];
            }
        }
        b
    }

    /// The derivative part of R(q₀) on a dual-number geometry, as a complex field.
    fn residual_part(&self, geom: &crate::residual::Geom<Dual<2>>) -> Field {
        let q: Vec<State<Dual<2>>> = self.q0.iter().map(|s| s.map(Dual::cst)).collect();
        let r = self.euler.residual_in(&q, geom).0;
        r.iter()
            .flatten()
            .map(|v| C64::new(v.d[0], v.d[1]))
            .collect()
    }

    /// The linearized force on every wall face (paper Eqs. 8 and 14): the wall forces of
    /// [`Euler::wall_face_forces`] at q₀ + ε q̂ on the mesh moved by ε x̂, by dual numbers.
    pub fn wall_face_forces(
        &self,
        q_hat: &[C64],
        x_hat: Option<&[[C64; 3]]>,
    ) -> Vec<(usize, [C64; 3])> {
        let mesh = &self.euler.mesh;
        let order = self.euler.order;
        let q: Vec<State<Dual<2>>> = self
            .q0
            .iter()
            .enumerate()
            .map(|(c, qc)| {
                std::array::from_fn(|k| {
                    let x = q_hat[c * NVAR + k];
                    Dual::new(qc[k], [x.re, x.im])
                })
            })
            .collect();
        let geom = match x_hat {
            None => self.euler.geometry::<Dual<2>>(order),
            Some(xh) => {
                let nodes: Vec<[Dual<2>; 3]> = mesh
                    .nodes
                    .iter()
                    .zip(xh)
                    .map(|(p, d)| std::array::from_fn(|i| Dual::new(p[i], [d[i].re, d[i].im])))
                    .collect();
                self.euler
                    .geometry_at(&nodes, vec![Dual::cst(0.0); mesh.faces.len()], order)
            }
        };
        self.euler
            .wall_face_forces(&q, &geom)
            .into_iter()
            .map(|(fi, f)| (fi, f.map(|v| C64::new(v.d[0], v.d[1]))))
            .collect()
    }

    /// The linearized total wall force (non-dimensional, like [`Euler::wall_force`]).
    pub fn force(&self, q_hat: &[C64], x_hat: Option<&[[C64; 3]]>) -> [C64; 3] {
        let mut total = [C64::new(0.0, 0.0); 3];
        for (_, f) in self.wall_face_forces(q_hat, x_hat) {
            for k in 0..3 {
                total[k] += f[k];
            }
        }
        total
    }

    /// The generalized forces Σ_faces f̂_f · φ̄_f of the linearized wall forces on each shape
    /// (node displacements; φ̄_f the mean over the face's nodes): paper Eqs. 9 and 15.
    pub fn generalized_forces(
        &self,
        q_hat: &[C64],
        x_hat: Option<&[[C64; 3]]>,
        shapes: &[Vec<[f64; 3]>],
    ) -> Vec<C64> {
        let faces = self.wall_face_forces(q_hat, x_hat);
        shapes
            .iter()
            .map(|phi| {
                faces
                    .iter()
                    .map(|(fi, f)| {
                        let nodes = &self.euler.mesh.faces[*fi].nodes;
                        let w = 1.0 / nodes.len() as f64;
                        (0..3)
                            .map(|k| f[k] * nodes.iter().map(|&n| phi[n][k]).sum::<f64>() * w)
                            .sum::<C64>()
                    })
                    .sum()
            })
            .collect()
    }
}

impl LfdOperator {
    /// The linearized equations marched in time by BDF2 from rest (q = 0 at the first two levels):
    /// V (3qⁿ⁺¹ − 4qⁿ + qⁿ⁻¹)/(2Δt) + ∂R/∂q qⁿ⁺¹ = −b(tⁿ⁺¹), each step solved by GMRES on the exact
    /// operator with the factored first-order one as preconditioner; `observe(n, tⁿ, qⁿ)` sees
    /// every level. The reference the BDF2-symbol LFD must reproduce once transients have decayed.
    pub fn linear_march(
        &self,
        dt: f64,
        steps: usize,
        forcing: &dyn Fn(f64) -> Field,
        observe: &mut dyn FnMut(usize, f64, &[C64]),
    ) -> Result<(), LfdError> {
        let n = self.n();
        let f = self.factor_shift(C64::new(1.5 / dt, 0.0))?;
        let vol = &self.euler.volumes;
        let (mut q_old, mut q) = (vec![C64::new(0.0, 0.0); n], vec![C64::new(0.0, 0.0); n]);
        for step in 1..=steps {
            let t = step as f64 * dt;
            let b = forcing(t);
            // A qⁿ⁺¹ = −(b − V (4qⁿ − qⁿ⁻¹)/(2Δt)) with A = 3V/(2Δt) + ∂R/∂q
            let rhs: Field = (0..n)
                .map(|i| b[i] - (4.0 * q[i] - q_old[i]) * (vol[i / NVAR] / (2.0 * dt)))
                .collect();
            let (q_new, _) = self
                .solve(&f, std::slice::from_ref(&rhs))?
                .pop()
                .expect("one right-hand side");
            q_old = std::mem::replace(&mut q, q_new);
            observe(step, t, &q);
        }
        Ok(())
    }

    /// The preconditioner applied to each of several vectors: M⁻¹ v (one sweep over an ILU's
    /// factors for all of them).
    pub(crate) fn precondition_many(&self, f: &Factored, vs: &[&[C64]]) -> Vec<Field> {
        match &f.factors {
            Factors::Lu(lu) => lu_solve_many(lu, vs, false),
            Factors::Ilu(ilu) => ilu.apply_many(vs),
        }
    }

    /// The transposed preconditioner applied to several vectors: M⁻ᵀ v (not conjugated), for
    /// the adjoint.
    pub(crate) fn precondition_transpose_many(&self, f: &Factored, vs: &[&[C64]]) -> Vec<Field> {
        match &f.factors {
            Factors::Lu(lu) => lu_solve_many(lu, vs, true),
            Factors::Ilu(ilu) => ilu.apply_transpose_many(vs),
        }
    }

    /// The preconditioner factored for a given shift s (the frequency only labels errors).
    fn factor_shift(&self, s: C64) -> Result<Factored, LfdError> {
        let vol = &self.euler.volumes;
        let fail = |reason: String| LfdError::Factor {
            omega: s.im,
            reason,
        };
        let factors = if matches!(
            self.preconditioner,
            Preconditioner::BlockIlu | Preconditioner::FirstOrderIlu
        ) {
            Factors::Ilu(
                BlockIlu::with_params(
                    self.euler.mesh.n_cells,
                    &self.blocks,
                    &|c| s * vol[c],
                    &self.params.ilu,
                )
                .map_err(fail)?,
            )
        } else {
            let a = self
                .euler
                .shifted_matrix(&self.blocks, &|c| s * vol[c], &|v| C64::new(v, 0.0))
                .map_err(fail)?;
            Factors::Lu(Box::new(a.sp_lu().map_err(|e| fail(format!("{e:?}")))?))
        };
        Ok(Factored {
            omega: s.im,
            s,
            factors,
        })
    }
}

/// The Fourier coefficient q̂ of a sampled periodic signal q_n = Re(q̂ e^{iωt_n}) over one period
/// of `samples.len()` equal steps (exact for a pure harmonic when there are three or more).
pub fn fourier_coefficient(samples: &[(f64, f64)], omega: f64) -> C64 {
    let n = samples.len() as f64;
    samples
        .iter()
        .map(|&(t, y)| y * C64::new(0.0, -omega * t).exp())
        .sum::<C64>()
        * (2.0 / n)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::airfoil::AirfoilShape;
    use crate::deform::Deformation;
    use crate::residual::{free_stream, Gust, Order};
    use crate::steady::SteadyParams;
    use crate::unsteady::march;

    /// The combined guess on a dense random operator: where b = A (α₁ g₁ + α₂ g₂) it recovers the
    /// solution (residual at round-off, 1e-12 of ‖b‖ stated for the 24-unknown products), with
    /// one guess it is the residual-minimizing complex scaling (α = (A g)ᴴ b / ‖A g‖²), a guess
    /// repeated adds nothing (no huge coefficients from a dependent direction), a guess of
    /// another length is ignored, none gives no guess, and for an unrelated b the combination's
    /// residual never exceeds ‖b‖ (no worse than starting from zero).
    #[test]
    fn combined_guesses_minimize_the_residual_over_their_span() {
        let n = 24;
        let r = gustkit_testkit::rand_vec(2 * n * n + 8 * n, 3);
        let a: Vec<C64> = r[..2 * n * n]
            .chunks(2)
            .map(|c| C64::new(c[0], c[1]))
            .collect();
        let op = |v: &[C64]| -> Field {
            (0..n)
                .map(|i| (0..n).map(|j| a[i * n + j] * v[j]).sum())
                .collect()
        };
        let single = |off: usize| -> Vec<C32> {
            r[2 * n * n + off..2 * n * n + off + 2 * n]
                .chunks(2)
                .map(|c| C32::new(c[0] as f32, c[1] as f32))
                .collect()
        };
        let (g1, g2, g3) = (single(0), single(2 * n), single(4 * n));
        let wide = |g: &[C32]| -> Field {
            g.iter()
                .map(|v| C64::new(v.re as f64, v.im as f64))
                .collect()
        };
        let norm = |v: &[C64]| v.iter().map(|x| x.norm_sqr()).sum::<f64>().sqrt();
        let residual = |x: &[C64], b: &[C64]| {
            let ax = op(x);
            norm(&ax.iter().zip(b).map(|(p, q)| q - p).collect::<Field>())
        };
        let (a1, a2) = (C64::new(0.3, 0.0), C64::new(0.5, -0.2));
        let x: Field = wide(&g1)
            .iter()
            .zip(wide(&g2))
            .map(|(u, v)| a1 * u + a2 * v)
            .collect();
        let b = op(&x);
        let guess = combined_guess(&op, &[&g1, &g2], &b).unwrap();
        assert!(residual(&guess, &b) <= 1e-12 * norm(&b));
        // one guess: the complex scaling
        let ag = op(&wide(&g1));
        let alpha = ag.iter().zip(&b).map(|(p, q)| p.conj() * q).sum::<C64>()
            / ag.iter().map(|p| p.norm_sqr()).sum::<f64>();
        let scaled = combined_guess(&op, &[&g1], &b).unwrap();
        for (s, g) in scaled.iter().zip(wide(&g1)) {
            assert!((s - alpha * g).norm() <= 1e-13 * alpha.norm() * g.norm().max(1.0));
        }
        // a repeated guess, and one of another length, change nothing
        let repeated = combined_guess(&op, &[&g1, &g1, &g1[..n - 1]], &b).unwrap();
        for (p, q) in repeated.iter().zip(&scaled) {
            assert!((p - q).norm() <= 1e-12 * q.norm().max(1.0));
        }
        assert!(combined_guess(&op, &[], &b).is_none());
        assert!(combined_guess(&op, &[&g1[..3]], &b).is_none());
        // an unrelated right-hand side: never worse than zero
        let unrelated = op(&wide(&g3));
        let far = combined_guess(&op, &[&g1, &g2], &unrelated).unwrap();
        assert!(residual(&far, &unrelated) <= norm(&unrelated) * (1.0 + 1e-12));
    }

    /// The steady NACA 64A010 at M = 0.4 and zero incidence on a small O-mesh (far field at
    /// `far` chords) and its LFD problem.
    fn problem(n_around: usize, n_radial: usize, far: f64, order: Order) -> LfdOperator {
        let mesh = AirfoilShape::naca64a010().o_mesh(n_around, n_radial, far, 0.004 / far, 1.0);
        let mut e = Euler::new(mesh, free_stream(0.4, 0.0));
        e.order = order;
        let (q0, _) = e
            .solve_steady(vec![e.q_inf; e.mesh.n_cells], &SteadyParams::default())
            .unwrap();
        let mut lfd = LfdOperator::new(e, q0);
        lfd.params.tolerance = 1e-13;
        lfd
    }

    /// The cell whose centre is nearest to a point 0.02 chords above the leading edge (the cell
    /// at the leading edge itself straddles the symmetry line, where a vertical gust leaves ρ, u
    /// and p unperturbed).
    fn leading_edge_cell(e: &Euler) -> usize {
        let c = &e.lsq.centers;
        let d = |i: usize| (c[i][0] + 0.5).hypot(c[i][1] - 0.02);
        (0..e.mesh.n_cells)
            .min_by(|&a, &b| d(a).total_cmp(&d(b)))
            .unwrap()
    }

    fn digits(a: C64, b: C64) -> f64 {
        -((a - b).norm() / b.norm()).log10()
    }

    /// The harmonic gust's face fluxes are the complex amplitudes of the time-domain ones: the
    /// sine gust w = sin(ω(t − (x − x0)/U)) = Re(−i ŵ e^{iωt}) gives Re(−i e^{iωt} ĝ_f) = g_f(t)
    /// on every face, to round-off.
    #[test]
    fn harmonic_gust_fluxes_are_time_domain_amplitudes() {
        let mesh = AirfoilShape::naca64a010().o_mesh(24, 8, 20.0, 0.004 / 20.0, 1.0);
        let e = Euler::new(mesh, free_stream(0.4, 0.0));
        let (omega, u, x0) = (0.4, 0.4, -0.5);
        let g_hat = e.harmonic_gust_fluxes(omega, u, x0);
        for t in [0.0, 1.3, 7.9] {
            let g = e.gust_fluxes(
                &Gust::Sine {
                    amplitude: 1.0,
                    omega,
                    convection: u,
                    x0,
                },
                t,
            );
            for (a, b) in g.iter().zip(&g_hat) {
                let v = (C64::new(0.0, -1.0) * C64::new(0.0, omega * t).exp() * b).re;
                assert!((a - v).abs() < 1e-13 * (1.0 + a.abs()), "{a} vs {v}");
            }
        }
    }

    /// With the BDF2 symbol for iω the LFD gust solution is the periodic response of the
    /// linearized BDF2 march (second order, k = 0.5 at M = 0.4, 24 steps a period): after 30
    /// periods from rest (the transient decays by about 0.3 digits a period on this mesh: 10 digits
    /// at the end) the Fourier coefficients over the last period of the lift and of the state in
    /// the cell above the leading edge agree to 8 digits or more. The march's forcing uses the
    /// time-domain gust fluxes, not the harmonic ones.
    #[test]
    fn bdf2_symbol_lfd_is_the_periodic_bdf2_response() {
        let lfd = problem(32, 12, 20.0, Order::Second);
        let (u, k) = (0.4, 0.5);
        let omega = k * u / 0.5;
        let steps_per_period = 24;
        let dt = 2.0 * std::f64::consts::PI / omega / steps_per_period as f64;
        let gust = HarmonicGust {
            convection: u,
            x0: 0.0,
        };
        let f = lfd.factor(omega, Symbol::Bdf2 { dt }).unwrap();
        let b = lfd.gust_rhs(omega, &gust);
        let (q_hat, info) = lfd.solve(&f, &[b]).unwrap().pop().unwrap();
        assert!(info.iterations < 60, "{info:?}");
        let lift_hat = lfd.force(&q_hat, None)[1];
        let cell = leading_edge_cell(&lfd.euler);
        // the sine gust Re(−i ŵ e^{iωt}) through the time-domain face fluxes
        let sine = Gust::Sine {
            amplitude: 1.0,
            omega,
            convection: u,
            x0: 0.0,
        };
        let forcing = |t: f64| -> Field {
            let g: Vec<C64> = lfd
                .euler
                .gust_fluxes(&sine, t)
                .iter()
                .map(|v| C64::new(*v, 0.0))
                .collect();
            lfd.volume_flux_rhs(&g)
        };
        let periods = 30;
        let mut lift = Vec::new();
        let mut state: Vec<Vec<(f64, f64)>> = vec![Vec::new(); NVAR];
        let last = (periods - 1) * steps_per_period;
        lfd.linear_march(dt, periods * steps_per_period, &forcing, &mut |n, t, q| {
            if n > last {
                lift.push((t, lfd.force(q, None)[1].re));
                for k in 0..NVAR {
                    state[k].push((t, q[cell * NVAR + k].re));
                }
            }
        })
        .unwrap();
        // march = Re(−i q̂ e^{iωt}): q̂ = i × its Fourier coefficient
        let i = C64::new(0.0, 1.0);
        let d_lift = digits(i * fourier_coefficient(&lift, omega), lift_hat);
        eprintln!("digits: {:.2}", d_lift);
        assert!(d_lift >= 8.0, "lift: {d_lift:.1} digits");
        for k in [0, 1, 2, 4] {
            let d = digits(
                i * fourier_coefficient(&state[k], omega),
                q_hat[cell * NVAR + k],
            );
            eprintln!("digits: {:.2}", d);
            assert!(d >= 8.0, "state {k}: {d:.1} digits");
        }
    }

    /// The nonlinear BDF2 march (dual-time Newton–Krylov, preconditioner kept for the march) under
    /// a tiny gust or a tiny mode motion, its lift Fourier coefficient over the last of `periods`
    /// periods per unit amplitude, against the BDF2-symbol LFD: they differ by the nonlinearity
    /// (relative size of the amplitude) and the decayed transient only.
    pub(crate) fn nonlinear_lift(
        lfd: &LfdOperator,
        omega: f64,
        steps_per_period: usize,
        periods: usize,
        gust: Option<&Gust>,
        motion: Option<crate::unsteady::Motion<'_>>,
    ) -> Vec<(f64, f64)> {
        let params = SteadyParams {
            exact_jacobian: true,
            ..SteadyParams::small_amplitude()
        };
        let lift =
            nonlinear_lift_periods(lfd, omega, steps_per_period, periods, gust, motion, &params);
        lift.last().unwrap().clone()
    }

    /// [`nonlinear_lift`] with the dual-time settings `params`, the lift over every period (the
    /// first period first), so that a caller can watch the start-up transient decay.
    pub(crate) fn nonlinear_lift_periods(
        lfd: &LfdOperator,
        omega: f64,
        steps_per_period: usize,
        periods: usize,
        gust: Option<&Gust>,
        motion: Option<crate::unsteady::Motion<'_>>,
        params: &SteadyParams,
    ) -> Vec<Vec<(f64, f64)>> {
        let dt = 2.0 * std::f64::consts::PI / omega / steps_per_period as f64;
        let mut e = lfd.euler.clone();
        let (_, samples) = march(
            &mut e,
            lfd.q0.clone(),
            gust,
            motion,
            dt,
            periods * steps_per_period,
            params,
        )
        .unwrap();
        let lift0 = lfd.euler.wall_force(&lfd.q0)[1];
        // levels 1 ..= steps of each period (t = 0 is level 0)
        samples[1..]
            .chunks(steps_per_period)
            .map(|c| c.iter().map(|s| (s.time, s.force[1] - lift0)).collect())
            .collect()
    }

    /// The gust LFD (BDF2 symbol) against the nonlinear march with a sine gust of amplitude 1e-6:
    /// the lift agrees to 8 digits (measured 9.6: the nonlinearity at the fundamental frequency is
    /// of second order in the amplitude, the transient after 30 periods ~1e-10).
    #[test]
    fn gust_lfd_matches_small_amplitude_time_domain() {
        let lfd = problem(32, 12, 20.0, Order::Second);
        let (u, omega, n) = (0.4, 0.4, 24);
        let dt = 2.0 * std::f64::consts::PI / omega / n as f64;
        let f = lfd.factor(omega, Symbol::Bdf2 { dt }).unwrap();
        let b = lfd.gust_rhs(
            omega,
            &HarmonicGust {
                convection: u,
                x0: 0.0,
            },
        );
        let (q_hat, _) = lfd.solve(&f, &[b]).unwrap().pop().unwrap();
        let lift_hat = lfd.force(&q_hat, None)[1];
        let amp = 1e-6;
        let sine = Gust::Sine {
            amplitude: amp,
            omega,
            convection: u,
            x0: 0.0,
        };
        let lift = nonlinear_lift(&lfd, omega, n, 30, Some(&sine), None);
        // w = Re(−i amp ŵ e^{iωt})
        let c = fourier_coefficient(&lift, omega) * C64::new(0.0, 1.0 / amp);
        let d = digits(c, lift_hat);
        eprintln!("digits: {:.2}", d);
        assert!(d >= 8.0, "{d:.1} digits: {c} vs {lift_hat}");
    }

    /// Mode motion: pitch about the quarter chord spread through the mesh by inverse-distance
    /// weighting, moving the mesh by Re(1e-6 x̂ e^{iωt}) in the nonlinear ALE march (swept-volume
    /// GCL) against the BDF2-symbol LFD with the motion right-hand side (node positions, grid
    /// velocities, volumes): the lift agrees to 6 digits (measured 7.1).
    #[test]
    fn motion_lfd_matches_small_amplitude_time_domain() {
        let lfd = problem(32, 12, 20.0, Order::Second);
        let (omega, n) = (0.4, 24);
        let dt = 2.0 * std::f64::consts::PI / omega / n as f64;
        let mesh = &lfd.euler.mesh;
        let d = Deformation::new(mesh, 8.0);
        let wall: Vec<[f64; 3]> = d
            .wall_nodes
            .iter()
            .map(|&k| [mesh.nodes[k][1], -(mesh.nodes[k][0] + 0.25), 0.0])
            .collect();
        let x_hat: Vec<[f64; 3]> = d.apply(&wall);
        let x_hat_c: Vec<[C64; 3]> = x_hat.iter().map(|p| p.map(|v| C64::new(v, 0.0))).collect();
        let f = lfd.factor(omega, Symbol::Bdf2 { dt }).unwrap();
        let b = lfd.motion_rhs(f.s, &x_hat_c);
        let (q_hat, _) = lfd.solve(&f, &[b]).unwrap().pop().unwrap();
        let lift_hat = lfd.force(&q_hat, Some(&x_hat_c))[1];
        let amp = 1e-6;
        let x0 = mesh.nodes.clone();
        let motion = move |t: f64| -> Vec<[f64; 3]> {
            let c = amp * (omega * t).cos();
            x0.iter()
                .zip(&x_hat)
                .map(|(p, u)| std::array::from_fn(|k| p[k] + c * u[k]))
                .collect()
        };
        let lift = nonlinear_lift(&lfd, omega, n, 30, None, Some(&motion));
        let c = fourier_coefficient(&lift, omega) / amp;
        let dg = digits(c, lift_hat);
        eprintln!("digits: {:.2}", dg);
        assert!(dg >= 6.0, "{dg:.1} digits: {c} vs {lift_hat}");
    }

    /// k → 0: the LFD gust response at ω = 0 is the derivative of the steady lift with respect
    /// to a uniform vertical gust (central differences of two nonlinear steady solutions with
    /// w = ±1e-4, error O(w²) ≈ 1e-8; the gust is an angle-of-attack change, paper Table 1), to
    /// 6 digits; and the LFD is continuous there: ω = 1e-5 agrees with ω = 0 to 4 digits.
    #[test]
    fn zero_frequency_gust_is_the_steady_derivative() {
        let lfd = problem(32, 12, 20.0, Order::Second);
        let gust = HarmonicGust {
            convection: 0.4,
            x0: 0.0,
        };
        let lift_at = |omega: f64| {
            let f = lfd.factor(omega, Symbol::Exact).unwrap();
            let (q, _) = lfd
                .solve(&f, &[lfd.gust_rhs(omega, &gust)])
                .unwrap()
                .pop()
                .unwrap();
            lfd.force(&q, None)[1]
        };
        let l0 = lift_at(0.0);
        assert!(l0.im.abs() < 1e-12 * l0.re.abs());
        let w = 1e-4;
        let steady = |v: f64| {
            let mut e = lfd.euler.clone();
            e.set_uniform_gust([0.0, v, 0.0]);
            let (q, _) = e
                .solve_steady(lfd.q0.clone(), &SteadyParams::default())
                .unwrap();
            e.wall_force(&q)[1]
        };
        let fd = (steady(w) - steady(-w)) / (2.0 * w);
        let d = digits(l0, C64::new(fd, 0.0));
        eprintln!("digits: {:.2}", d);
        assert!(d >= 6.0, "{d:.1} digits: {l0} vs {fd}");
        let d_small = digits(lift_at(1e-5), l0);
        eprintln!("digits: {:.2}", d_small);
        assert!(d_small >= 4.0, "{d_small:.1}");
    }

    /// The three preconditioners give the same LFD gust solution (GMRES to 1e-12): the exact LU
    /// in one or two iterations, the first-order LU and the block ILU(0) of the exact Jacobian in
    /// more, all converging.
    #[test]
    fn preconditioners_agree() {
        let base = problem(32, 12, 20.0, Order::Second);
        let gust = HarmonicGust {
            convection: 0.4,
            x0: 0.0,
        };
        let mut solutions = Vec::new();
        for p in [
            Preconditioner::Exact,
            Preconditioner::FirstOrder,
            Preconditioner::BlockIlu,
        ] {
            let mut lfd = LfdOperator::with_preconditioner(base.euler.clone(), base.q0.clone(), p);
            lfd.params.tolerance = 1e-12;
            let f = lfd.factor(0.4, Symbol::Exact).unwrap();
            let (q, info) = lfd
                .solve(&f, &[lfd.gust_rhs(0.4, &gust)])
                .unwrap()
                .pop()
                .unwrap();
            eprintln!("{p:?}: {} GMRES iterations", info.iterations);
            if p == Preconditioner::Exact {
                assert!(info.iterations <= 2, "{info:?}");
            }
            solutions.push(q);
        }
        let norm = |v: &[C64]| v.iter().map(|x| x.norm_sqr()).sum::<f64>().sqrt();
        for s in &solutions[1..] {
            let d: Vec<C64> = s.iter().zip(&solutions[0]).map(|(a, b)| a - b).collect();
            assert!(
                norm(&d) < 1e-9 * norm(&solutions[0]),
                "{:e}",
                norm(&d) / norm(&solutions[0])
            );
        }
    }

    /// Right-hand sides solved in lockstep batches give the one-at-a-time solutions bit for
    /// bit, forward and transposed, with restarts at different iterations, a zero right-hand
    /// side, a warm-started column and the ILU in single precision and RCM order (the wing's
    /// defaults), and with a sparse LU preconditioner; a column that stalls is named by its
    /// index.
    #[test]
    fn batched_solves_are_those_of_one_at_a_time() {
        let base = problem(32, 12, 20.0, Order::Second);
        let mut lfd = LfdOperator::with_preconditioner(
            base.euler.clone(),
            base.q0.clone(),
            Preconditioner::FirstOrderIlu,
        );
        lfd.params.tolerance = 1e-11;
        lfd.params.restart = 7;
        lfd.params.ilu.precision = crate::ilu::IluPrecision::Single;
        lfd.params.ilu.ordering = crate::ilu::IluOrdering::ReverseCuthillMckee;
        let f = lfd.factor(0.4, Symbol::Exact).unwrap();
        let gust = |c: f64, x0: f64| lfd.gust_rhs(0.4, &HarmonicGust { convection: c, x0 });
        let n = lfd.n();
        let noise = gustkit_testkit::rand_vec(2 * n, 11);
        let random: Field = (0..n).map(|i| C64::new(noise[i], noise[n + i])).collect();
        let rhs = vec![
            gust(0.4, 0.0),
            vec![C64::new(0.0, 0.0); n],
            random,
            gust(0.3, 0.2),
        ];
        // the last column starts from a guess: the first column's solution, single precision
        let first = lfd.solve(&f, &rhs[..1]).unwrap().remove(0).0;
        let guess: Vec<C32> = first
            .iter()
            .map(|v| C32::new(v.re as f32, v.im as f32))
            .collect();
        let guesses = vec![vec![], vec![], vec![], vec![guess.as_slice()]];
        let mut runs = Vec::new();
        for batch in [1, 3, 4] {
            lfd.params.batch = batch;
            let forward = lfd.solve_from(&f, &rhs, &guesses).unwrap();
            // the adjoint's solves: the transposed operator and preconditioner
            let op = |vs: &[&[C64]]| lfd.apply_transpose_many(f.s, vs);
            let prec = |vs: &[&[C64]]| lfd.precondition_transpose_many(&f, vs);
            let transposed =
                solve_each(&op, &prec, &rhs, &guesses, (&lfd.params, f.omega), false).unwrap();
            runs.push((forward, transposed));
        }
        let its =
            |r: &[(Field, GmresInfo)]| r.iter().map(|(_, i)| i.iterations).collect::<Vec<_>>();
        eprintln!(
            "iterations forward {:?}, transposed {:?}",
            its(&runs[0].0),
            its(&runs[0].1)
        );
        // restarts (7) at different points: the columns need different iteration counts
        let counts = its(&runs[0].0);
        assert!(
            counts[1] == 0 && counts[0] > 7 && counts[0] != counts[2],
            "{counts:?}"
        );
        for (forward, transposed) in &runs[1..] {
            for (a, b) in forward
                .iter()
                .zip(&runs[0].0)
                .chain(transposed.iter().zip(&runs[0].1))
            {
                assert_eq!(a.1.iterations, b.1.iterations);
                assert_eq!(a.1.history, b.1.history);
                assert!(
                    a.0 == b.0,
                    "a batched solution differs from the one-at-a-time one"
                );
            }
        }
        // with a sparse LU preconditioner likewise
        let mut lu_lfd = LfdOperator::with_preconditioner(
            base.euler.clone(),
            base.q0.clone(),
            Preconditioner::FirstOrder,
        );
        lu_lfd.params.tolerance = 1e-11;
        let lu_f = lu_lfd.factor(0.4, Symbol::Exact).unwrap();
        let mut lu_runs = Vec::new();
        for batch in [1, 3] {
            lu_lfd.params.batch = batch;
            let forward = lu_lfd.solve_from(&lu_f, &rhs, &guesses).unwrap();
            let op = |vs: &[&[C64]]| lu_lfd.apply_transpose_many(lu_f.s, vs);
            let prec = |vs: &[&[C64]]| lu_lfd.precondition_transpose_many(&lu_f, vs);
            let transposed = solve_each(
                &op,
                &prec,
                &rhs,
                &guesses,
                (&lu_lfd.params, lu_f.omega),
                false,
            )
            .unwrap();
            lu_runs.push((forward, transposed));
        }
        for (a, b) in lu_runs[1]
            .0
            .iter()
            .zip(&lu_runs[0].0)
            .chain(lu_runs[1].1.iter().zip(&lu_runs[0].1))
        {
            assert!(a.1.iterations > 0 || a.0.iter().all(|v| v.norm() == 0.0));
            assert_eq!(a.1.history, b.1.history);
            assert!(a.0 == b.0, "a batched LU-preconditioned solution differs");
        }
        // a column that cannot reach the tolerance in the iterations allowed is named
        lfd.params.max_iterations = 3;
        lfd.params.batch = 4;
        match lfd.solve_from(&f, &rhs, &guesses) {
            Err(LfdError::Gmres { rhs, source, .. }) => {
                assert_eq!(rhs, 0);
                assert_eq!(source.iterations, 3);
            }
            other => panic!("expected a stall, got {:?}", other.map(|r| r.len())),
        }
    }
}
