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
use crate::krylov::{gmres_from, GmresError, GmresInfo};
use crate::residual::{Euler, State};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::Lu;
use faer::Mat;
use gustkit_core::scalar::{Dual, Scalar};
use num_complex::Complex64 as C64;
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
        if self.restart == 0 || self.max_iterations == 0 {
            return Err("restart and max_iterations must be at least 1".into());
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
}

enum Factors {
    Lu(Box<Lu<usize, C64>>),
    Ilu(BlockIlu<C64>),
}

/// A complex field of cell states, flattened (cell-major, 5 per cell).
pub type Field = Vec<C64>;

/// GMRES on every right-hand side (in parallel; `negate`: for A x = −b) from its guess where
/// given ([`scaled_guess`]), to the tolerance of `params` relative to the right-hand side.
pub(crate) fn solve_each(
    op: &(dyn Fn(&[C64]) -> Field + Sync),
    prec: &(dyn Fn(&[C64]) -> Field + Sync),
    rhs: &[Field],
    guesses: &[Option<&Field>],
    (params, omega): (&LfdParams, f64),
    negate: bool,
) -> Result<Vec<(Field, GmresInfo)>, LfdError> {
    params.validate().map_err(LfdError::Input)?;
    rhs.par_iter()
        .enumerate()
        .map(|(index, b)| {
            let b: std::borrow::Cow<[C64]> = if negate {
                b.iter().map(|x| -x).collect::<Field>().into()
            } else {
                b.as_slice().into()
            };
            let x0 = guesses
                .get(index)
                .copied()
                .flatten()
                .filter(|g| g.len() == b.len())
                .map(|g| scaled_guess(op, g, &b));
            gmres_from(
                op,
                prec,
                &b,
                x0.as_deref(),
                params.tolerance,
                params.restart,
                params.max_iterations,
            )
            .map_err(|source| LfdError::Gmres {
                omega,
                rhs: index,
                source,
            })
        })
        .collect()
}

/// The initial guess α g for A x = b with α minimizing ‖b − α A g‖ (one product with A): a
/// guess of the wrong sign or size starts no worse than zero.
pub fn scaled_guess(op: &dyn Fn(&[C64]) -> Field, g: &[C64], b: &[C64]) -> Field {
    let ag = op(g);
    let (num, den) = ag
        .iter()
        .zip(b)
        .fold((C64::new(0.0, 0.0), 0.0), |(n, d), (a, r)| {
            (n + a.conj() * r, d + a.norm_sqr())
        });
    let alpha = if den > 0.0 {
        num / den
    } else {
        C64::new(0.0, 0.0)
    };
    g.iter().map(|v| v * alpha).collect()
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
        let vol = &self.euler.volumes;
        let mut out = self.exact.mul(v);
        for (i, o) in out.iter_mut().enumerate() {
            *o += s * vol[i / NVAR] * v[i];
        }
        out
    }

    /// The transposed operator (s V + ∂R/∂q)ᵀ v (not conjugated), for the adjoint.
    pub fn apply_transpose(&self, s: C64, v: &[C64]) -> Field {
        let vol = &self.euler.volumes;
        let mut out = self.exact.mul_transpose(v);
        for (i, o) in out.iter_mut().enumerate() {
            *o += s * vol[i / NVAR] * v[i];
        }
        out
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

    /// [`LfdOperator::solve`] with initial guesses (`guesses[i]` for right-hand side i, where
    /// given): each scaled by the complex factor that minimizes its residual (one product
    /// with the operator), so that a guess of the wrong sign or size — a mode shape that
    /// flipped between designs — starts no worse than zero. The tolerance stays relative to
    /// the right-hand side: the same accuracy as from zero.
    pub fn solve_from(
        &self,
        f: &Factored,
        rhs: &[Field],
        guesses: &[Option<&Field>],
    ) -> Result<Vec<(Field, GmresInfo)>, LfdError> {
        let prec = |v: &[C64]| self.precondition(f, v);
        let op = |v: &[C64]| self.apply(f.s, v);
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

    /// The preconditioner applied to v: M⁻¹ v.
    pub(crate) fn precondition(&self, f: &Factored, v: &[C64]) -> Field {
        match &f.factors {
            Factors::Lu(lu) => {
                let m = lu.solve(Mat::<C64>::from_fn(v.len(), 1, |i, _| v[i]));
                (0..v.len()).map(|i| m[(i, 0)]).collect()
            }
            Factors::Ilu(ilu) => ilu.apply(v),
        }
    }

    /// The transposed preconditioner applied to v: M⁻ᵀ v (not conjugated), for the adjoint.
    pub(crate) fn precondition_transpose(&self, f: &Factored, v: &[C64]) -> Field {
        match &f.factors {
            Factors::Lu(lu) => {
                let m = lu.solve_transpose(Mat::<C64>::from_fn(v.len(), 1, |i, _| v[i]));
                (0..v.len()).map(|i| m[(i, 0)]).collect()
            }
            Factors::Ilu(ilu) => ilu.apply_transpose(v),
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
}
