//! Modal analysis: K φ = λ M φ, mass-normalized modes, generalized matrices, sampling.
//!
//! Each uncoupled field (bending, membrane) is solved for its lowest modes only: K = L Lᵀ, and
//! Lanczos with full reorthogonalization on the bounded operator L⁻¹ M L⁻ᵀ (eigenvalues
//! μ = 1/λ, the lowest structural modes at the top of its spectrum, where Lanczos converges
//! first), run until every wanted Ritz pair's residual is at round-off. The exact eigenvector
//! derivatives then need no complete spectrum: Nelson's method solves (K − λ_i M) a = r with
//! the row and column of φ_i's largest entry removed (one factorization per retained mode, made
//! when the reverse mode first asks for it). The complete dense decomposition is kept
//! ([`solve_field_complete`]) as the reference the tests hold the partial one to.
//!
//! Conventions: φᵀ M φ = 1; the sign of each mode makes its largest-magnitude translational nodal
//! value (w for bending, u or v for membrane) positive.

use super::band::BandLu;
use super::element;
use super::model::{Field, PlateModel, NODAL};
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::{Mat, Par, Side};
use gustkit_core::scalar::Scalar;
use rayon::prelude::*;
use std::sync::OnceLock;

/// Why a modal analysis failed.
#[derive(Debug, thiserror::Error)]
pub enum ModalError {
    #[error("the mass matrix of the {0:?} field is not positive definite (check densities and thicknesses)")]
    MassNotPositive(Field),
    #[error("the eigensolver did not converge for the {0:?} field")]
    Eigen(Field),
    #[error("asked for {asked} modes but the model has only {available} degrees of freedom")]
    TooManyModes { asked: usize, available: usize },
    #[error("the stiffness of the {0:?} field is not positive definite (a rigid-body mode: clamp the root)")]
    Unconstrained(Field),
}

/// Nelson's factorization for one mode: K − λ M without the row and column `pivot` (φ's
/// largest entry), banded LU with partial pivoting (the matrix is indefinite; the plate's
/// stiffness and mass couple only the DOFs of neighbouring nodes).
#[derive(Debug)]
struct Nelson {
    pivot: usize,
    lu: BandLu,
    /// M φ of the mode (every expansion projects with it).
    m_phi: Vec<f64>,
}

impl Nelson {
    /// The full index of a reduced one (the pivot's row and column dropped).
    fn full(&self, i: usize) -> usize {
        full_index(self.pivot, i)
    }
}

/// The full index of reduced index `i` when row and column `pivot` are dropped.
fn full_index(pivot: usize, i: usize) -> usize {
    if i < pivot {
        i
    } else {
        i + 1
    }
}

/// The lowest modes of one field and what their exact derivatives need.
#[derive(Debug)]
pub struct FieldEigen {
    pub field: Field,
    /// Stiffness and mass over the field's free DOFs.
    k: Mat<f64>,
    m: Mat<f64>,
    /// Cholesky factor L of K = L Lᵀ (the modal analysis makes it; static solves reuse it).
    chol: Mat<f64>,
    /// The lowest eigenvalues λ_j, ascending.
    pub lambda: Vec<f64>,
    /// Mass-normalized eigenvectors φ_j (columns, in the order of `lambda`).
    pub phi: Mat<f64>,
    /// Half-bandwidth of K and M (largest |i − j| of a nonzero entry).
    bandwidth: usize,
    /// Per column: Nelson's factorization, made at first use.
    nelson: Vec<OnceLock<Nelson>>,
}

impl Clone for FieldEigen {
    fn clone(&self) -> Self {
        Self {
            field: self.field,
            k: self.k.clone(),
            m: self.m.clone(),
            chol: self.chol.clone(),
            lambda: self.lambda.clone(),
            phi: self.phi.clone(),
            bandwidth: self.bandwidth,
            // factorizations are made again where a clone needs them
            nelson: (0..self.lambda.len()).map(|_| OnceLock::new()).collect(),
        }
    }
}

impl FieldEigen {
    /// Column of the j-th lowest structural mode.
    pub fn column_of_mode(&self, j: usize) -> usize {
        j
    }

    /// Free DOFs of the field.
    pub fn n_dofs(&self) -> usize {
        self.k.nrows()
    }

    /// Mass-normalized mode of column c.
    pub fn mode_vector(&self, c: usize) -> Vec<f64> {
        self.phi.col(c).iter().copied().collect()
    }

    /// K⁻¹ r over the field's free DOFs (the static deflection under loads r), by the Cholesky
    /// factor the modal analysis made.
    pub fn static_solve(&self, r: &[f64]) -> Vec<f64> {
        let mut x = Mat::<f64>::from_fn(r.len(), 1, |i, _| r[i]);
        solve_lower_triangular_in_place(self.chol.as_ref(), x.as_mut(), Par::Seq);
        solve_upper_triangular_in_place(self.chol.transpose(), x.as_mut(), Par::Seq);
        x.col(0).iter().copied().collect()
    }

    /// M v over the field's free DOFs.
    pub fn mass_times(&self, v: &[f64]) -> Vec<f64> {
        let x = Mat::<f64>::from_fn(v.len(), 1, |i, _| v[i]);
        (&self.m * &x).col(0).iter().copied().collect()
    }

    /// Makes Nelson's factorizations of the given columns (in parallel) before they are used.
    pub fn prepare(&self, columns: &[usize]) {
        columns.par_iter().for_each(|&c| {
            self.nelson(c);
        });
    }

    fn nelson(&self, c: usize) -> &Nelson {
        self.nelson[c].get_or_init(|| {
            let n = self.n_dofs();
            let phi = self.phi.col(c);
            let pivot = (0..n)
                .max_by(|&a, &b| phi[a].abs().total_cmp(&phi[b].abs()))
                .expect("a field has DOFs");
            let lam = self.lambda[c];
            let lu = BandLu::factor(n - 1, self.bandwidth, self.bandwidth, |i, j| {
                let (i, j) = (full_index(pivot, i), full_index(pivot, j));
                self.k[(i, j)] - lam * self.m[(i, j)]
            })
            .expect("K − λM without the pivot's row and column is regular for a simple λ");
            Nelson {
                pivot,
                lu,
                m_phi: (&self.m * phi).iter().copied().collect(),
            }
        })
    }

    /// Σ_{j≠c} φ_j (φ_jᵀ r) / (λ_c − λ_j), the complete modal expansion applied to r, without the
    /// complete spectrum: it is the a with (K − λ_c M) a = −(r − M φ_c φ_cᵀ r) and φ_cᵀ M a = 0.
    /// Nelson's method: the right-hand side is orthogonal to φ_c, so solving with φ_c's largest
    /// entry's row and column removed (that entry of the solution zero) satisfies the removed
    /// row too; adding −(φ_cᵀ M v) φ_c makes the solution M-orthogonal to φ_c.
    pub fn expansion(&self, c: usize, r: &[f64]) -> Vec<f64> {
        let n = r.len();
        let phi = self.phi.col(c);
        let phi_r: f64 = phi.iter().zip(r).map(|(a, b)| a * b).sum();
        let nel = self.nelson(c);
        let m_phi = &nel.m_phi;
        let mut v_red: Vec<f64> = (0..n - 1)
            .map(|i| {
                let i = nel.full(i);
                -(r[i] - m_phi[i] * phi_r)
            })
            .collect();
        nel.lu.solve_in_place(&mut v_red);
        let mut v = vec![0.0; n];
        for (i, x) in v_red.into_iter().enumerate() {
            v[nel.full(i)] = x;
        }
        let shift: f64 = m_phi.iter().zip(&v).map(|(a, b)| a * b).sum();
        v.iter()
            .zip(phi.iter())
            .map(|(a, p)| a - shift * p)
            .collect()
    }
}

/// The largest |i − j| over the nonzero entries of two symmetric matrices.
fn half_bandwidth(k: &Mat<f64>, m: &Mat<f64>) -> usize {
    let n = k.nrows();
    (0..n)
        .map(|j| {
            (0..j)
                .find(|&i| k[(i, j)] != 0.0 || m[(i, j)] != 0.0)
                .map_or(0, |i| j - i)
        })
        .max()
        .unwrap_or(0)
}

/// Solves one field for its `n_want` lowest modes (all of them when `n_want` is at least the
/// DOF count, or when the field is so small that the complete decomposition is as cheap).
pub fn solve_field(
    model: &PlateModel,
    field: Field,
    n_want: usize,
) -> Result<FieldEigen, ModalError> {
    solve_field_with(model, field, n_want, false)
}

/// The complete decomposition of one field (every mode, ascending), by the dense
/// self-adjoint eigensolver: the reference for the partial solve.
pub fn solve_field_complete(model: &PlateModel, field: Field) -> Result<FieldEigen, ModalError> {
    solve_field_with(model, field, model.n_dofs(field), true)
}

/// The `n_want` lowest modes of a field, by the complete dense decomposition when `complete_only`
/// or when the field is small, else by Lanczos.
fn solve_field_with(
    model: &PlateModel,
    field: Field,
    n_want: usize,
    complete_only: bool,
) -> Result<FieldEigen, ModalError> {
    let (k, m) = model.assemble(field);
    let n = k.nrows();
    let n_want = n_want.min(n);
    let chol = k
        .llt(Side::Lower)
        .map_err(|_| ModalError::Unconstrained(field))?
        .L()
        .to_owned();
    let (mu, y) = if complete_only || n <= 4 * n_want + 40 {
        complete(field, &chol, &m, n_want)?
    } else {
        lanczos(field, &chol, &m, n_want)?
    };
    // φ = L⁻ᵀ y / √μ, λ = 1/μ (μ descending: λ ascending)
    let mut phi = y;
    solve_upper_triangular_in_place(chol.transpose(), phi.as_mut(), Par::Seq);
    for (j, &mu_j) in mu.iter().enumerate() {
        let s = 1.0 / mu_j.sqrt();
        phi.col_mut(j).iter_mut().for_each(|v| *v *= s);
    }
    Ok(FieldEigen {
        field,
        bandwidth: half_bandwidth(&k, &m),
        k,
        m,
        chol,
        lambda: mu.iter().map(|v| 1.0 / v).collect(),
        phi,
        nelson: (0..n_want).map(|_| OnceLock::new()).collect(),
    })
}

/// The complete decomposition of L⁻¹ M L⁻ᵀ: its `n_want` largest eigenvalues (descending) and
/// their orthonormal eigenvectors.
fn complete(
    field: Field,
    chol: &Mat<f64>,
    m: &Mat<f64>,
    n_want: usize,
) -> Result<(Vec<f64>, Mat<f64>), ModalError> {
    let n = m.nrows();
    let mut b = m.clone();
    solve_lower_triangular_in_place(chol.as_ref(), b.as_mut(), Par::Seq);
    let mut bt = b.transpose().to_owned();
    solve_lower_triangular_in_place(chol.as_ref(), bt.as_mut(), Par::Seq);
    let b = Mat::from_fn(n, n, |i, j| 0.5 * (bt[(i, j)] + bt[(j, i)]));
    let eig = b
        .self_adjoint_eigen(Side::Lower)
        .map_err(|_| ModalError::Eigen(field))?;
    if eig.S()[n - 1] <= 0.0 {
        return Err(ModalError::MassNotPositive(field));
    }
    let cols: Vec<usize> = (0..n_want).map(|j| n - 1 - j).collect();
    let mu = cols.iter().map(|&c| eig.S()[c]).collect();
    let y = Mat::from_fn(n, n_want, |i, j| eig.U()[(i, cols[j])]);
    Ok((mu, y))
}

/// Relative residual ‖C y − μ y‖ / μ_max at which a wanted Ritz pair counts as converged.
const LANCZOS_TOLERANCE: f64 = 1e-14;

/// Lanczos with full reorthogonalization on C = L⁻¹ M L⁻ᵀ for its `n_want` largest eigenpairs
/// (descending). Converged when every wanted Ritz pair's residual bound |β_m s_mi| is below
/// [`LANCZOS_TOLERANCE`] of the largest Ritz value (the Krylov space is then refined no further);
/// at a breakdown (an invariant subspace) a fresh start vector orthogonal to the basis continues
/// the run, so no eigenvalue is missed for want of a component in the start vector.
fn lanczos(
    field: Field,
    chol: &Mat<f64>,
    m: &Mat<f64>,
    n_want: usize,
) -> Result<(Vec<f64>, Mat<f64>), ModalError> {
    let n = m.nrows();
    let apply = |v: &[f64], out: &mut Mat<f64>| {
        for (i, x) in v.iter().enumerate() {
            out[(i, 0)] = *x;
        }
        solve_upper_triangular_in_place(chol.transpose(), out.as_mut(), Par::Seq);
        let mv = m * &*out;
        out.copy_from(&mv);
        solve_lower_triangular_in_place(chol.as_ref(), out.as_mut(), Par::Seq);
    };
    // a deterministic start vector with every component present
    let start = |seed: usize| -> Vec<f64> {
        (0..n)
            .map(|i| 1.0 + 0.5 * ((i * (2 * seed + 7) + 3) as f64 * 0.618_033_988_75).sin())
            .collect()
    };
    let max_steps = n;
    let mut basis: Vec<Vec<f64>> = Vec::with_capacity(max_steps.min(200));
    let (mut alpha, mut beta): (Vec<f64>, Vec<f64>) = (Vec::new(), Vec::new());
    let mut w = Mat::<f64>::zeros(n, 1);
    let orthogonalize = |v: &mut Vec<f64>, basis: &[Vec<f64>]| {
        // classical Gram–Schmidt twice ("twice is enough")
        for _ in 0..2 {
            for b in basis {
                let d: f64 = b.iter().zip(v.iter()).map(|(x, y)| x * y).sum();
                v.iter_mut().zip(b).for_each(|(x, y)| *x -= d * y);
            }
        }
    };
    let normalize = |v: &mut Vec<f64>| -> f64 {
        let nrm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        v.iter_mut().for_each(|x| *x /= nrm);
        nrm
    };
    let mut q = start(0);
    normalize(&mut q);
    let mut restarts = 0;
    loop {
        basis.push(q.clone());
        let j = basis.len();
        apply(&q, &mut w);
        let mut r: Vec<f64> = (0..n).map(|i| w[(i, 0)]).collect();
        let a: f64 = r.iter().zip(&q).map(|(x, y)| x * y).sum();
        alpha.push(a);
        orthogonalize(&mut r, &basis);
        let b = r.iter().map(|x| x * x).sum::<f64>().sqrt();
        // the wanted Ritz pairs of T_j and their residual bounds |b s_ji|
        let check = j >= n_want && (j % 4 == 0 || j == max_steps || b <= 0.0);
        if check || j == max_steps {
            let t = Mat::from_fn(j, j, |i, k| {
                if i == k {
                    alpha[i]
                } else if i + 1 == k || k + 1 == i {
                    beta[i.min(k)]
                } else {
                    0.0
                }
            });
            let eig = t
                .self_adjoint_eigen(Side::Lower)
                .map_err(|_| ModalError::Eigen(field))?;
            let top = eig.S()[j - 1];
            if top <= 0.0 {
                return Err(ModalError::MassNotPositive(field));
            }
            let done = j == max_steps
                || (0..n_want).all(|i| {
                    let c = j - 1 - i;
                    (b * eig.U()[(j - 1, c)]).abs() <= LANCZOS_TOLERANCE * top
                });
            if done {
                let mu: Vec<f64> = (0..n_want).map(|i| eig.S()[j - 1 - i]).collect();
                let mut y = Mat::<f64>::zeros(n, n_want);
                for i in 0..n_want {
                    let c = j - 1 - i;
                    for (k, v) in basis.iter().enumerate() {
                        let s = eig.U()[(k, c)];
                        for (row, x) in v.iter().enumerate() {
                            y[(row, i)] += s * x;
                        }
                    }
                    let nrm = y.col(i).iter().map(|x| x * x).sum::<f64>().sqrt();
                    y.col_mut(i).iter_mut().for_each(|x| *x /= nrm);
                }
                if mu.iter().any(|v| !(*v > 0.0 && v.is_finite())) {
                    return Err(ModalError::MassNotPositive(field));
                }
                return Ok((mu, y));
            }
        }
        let tiny = 1e-10 * alpha.iter().fold(0.0f64, |acc, v| acc.max(v.abs()));
        if b > tiny {
            beta.push(b);
            r.iter_mut().for_each(|x| *x /= b);
            q = r;
        } else {
            // an invariant subspace: continue from a fresh direction (T splits there)
            restarts += 1;
            let mut fresh = start(restarts);
            orthogonalize(&mut fresh, &basis);
            if normalize(&mut fresh) <= 1e-8 * (n as f64).sqrt() {
                return Err(ModalError::Eigen(field));
            }
            beta.push(0.0);
            q = fresh;
        }
    }
}

/// One retained mode.
#[derive(Clone, Debug)]
pub struct Mode {
    pub field: Field,
    /// Column in the field's eigen-decomposition.
    pub column: usize,
    /// λ = ω², rad²/s².
    pub lambda: f64,
    /// Nodal field, [`NODAL`] values a node (w, w_x, w_y, u, v), zeros at clamped nodes.
    pub shape: Vec<f64>,
}

impl Mode {
    pub fn omega(&self) -> f64 {
        self.lambda.sqrt()
    }
    pub fn freq_hz(&self) -> f64 {
        self.omega() / (2.0 * std::f64::consts::PI)
    }
}

/// The N lowest modes of a plate model and what their sensitivities need.
#[derive(Clone, Debug)]
pub struct Modes {
    pub modes: Vec<Mode>,
    /// Modal damping ratio ζ (the same for every mode).
    pub damping_ratio: f64,
    pub(crate) fields: Vec<FieldEigen>,
}

impl Modes {
    pub fn len(&self) -> usize {
        self.modes.len()
    }
    pub fn is_empty(&self) -> bool {
        self.modes.is_empty()
    }
    pub fn freq_hz(&self) -> Vec<f64> {
        self.modes.iter().map(Mode::freq_hz).collect()
    }
    pub fn omega(&self) -> Vec<f64> {
        self.modes.iter().map(Mode::omega).collect()
    }
    /// Generalized mass M̄ = Φᵀ M Φ = I (mass-normalized modes).
    pub fn generalized_mass(&self) -> Mat<f64> {
        Mat::identity(self.len(), self.len())
    }
    /// Generalized stiffness K̄ = diag(ω²).
    pub fn generalized_stiffness(&self) -> Mat<f64> {
        Mat::from_fn(self.len(), self.len(), |i, j| {
            if i == j {
                self.modes[i].lambda
            } else {
                0.0
            }
        })
    }
    /// Generalized damping C̄ = diag(2 ζ ω).
    pub fn generalized_damping(&self) -> Mat<f64> {
        Mat::from_fn(self.len(), self.len(), |i, j| {
            if i == j {
                2.0 * self.damping_ratio * self.modes[i].omega()
            } else {
                0.0
            }
        })
    }
    /// The complete decomposition of a field, if that field was solved.
    pub(crate) fn field(&self, f: Field) -> Option<&FieldEigen> {
        self.fields.iter().find(|e| e.field == f)
    }
}

/// The `n_modes` lowest modes over the given fields with modal damping ratio `damping_ratio`.
///
/// Aeroelastic studies retain bending modes only: for a flat plate the in-plane (membrane) field is
/// uncoupled from the deflection, so its modes carry no aerodynamic force.
pub fn solve(
    model: &PlateModel,
    n_modes: usize,
    damping_ratio: f64,
    fields: &[Field],
) -> Result<Modes, ModalError> {
    let available: usize = fields.iter().map(|&f| model.n_dofs(f)).sum();
    if n_modes > available {
        return Err(ModalError::TooManyModes {
            asked: n_modes,
            available,
        });
    }
    let fields: Vec<FieldEigen> = fields
        .iter()
        .map(|&f| solve_field(model, f, n_modes))
        .collect::<Result<_, _>>()?;
    // merge the two ascending spectra
    let mut picks: Vec<(f64, usize, usize)> = fields
        .iter()
        .enumerate()
        .flat_map(|(fi, fe)| {
            (0..n_modes.min(fe.lambda.len())).map(move |j| {
                let c = fe.column_of_mode(j);
                (fe.lambda[c], fi, c)
            })
        })
        .collect();
    picks.sort_by(|a, b| a.0.total_cmp(&b.0));
    picks.truncate(n_modes);
    let mut fields = fields;
    let modes = picks
        .into_iter()
        .map(|(lambda, fi, column)| {
            let fe = &mut fields[fi];
            let mut shape = nodal_shape(model, fe.field, fe.mode_vector(column).into_iter());
            // sign convention
            let off = fe.field.nodal_offset();
            let trans: Vec<usize> = match fe.field {
                Field::Bending => vec![off],
                Field::Membrane => vec![off, off + 1],
            };
            let big = shape
                .chunks(NODAL)
                .flat_map(|c| trans.iter().map(move |&t| c[t]))
                .fold(0.0f64, |a, v| if v.abs() > a.abs() { v } else { a });
            if big < 0.0 {
                shape.iter_mut().for_each(|v| *v = -*v);
                fe.phi.col_mut(column).iter_mut().for_each(|v| *v = -*v);
            }
            Mode {
                field: fe.field,
                column,
                lambda,
                shape,
            }
        })
        .collect();
    Ok(Modes {
        modes,
        damping_ratio,
        fields,
    })
}

/// Every mode with ω ≤ `omega_cut` over the given fields, at least `min` and at most `max` of
/// them (each capped at the degrees of freedom): the `max` lowest are solved, those above the
/// cutoff dropped. A (near-)repeated pair is never split at the cut: a mode within 1e-6 of the
/// last retained one's frequency is retained with it.
pub fn solve_below(
    model: &PlateModel,
    omega_cut: f64,
    min: usize,
    max: usize,
    damping_ratio: f64,
    fields: &[Field],
) -> Result<Modes, ModalError> {
    let available: usize = fields.iter().map(|&f| model.n_dofs(f)).sum();
    let max = max.min(available);
    let mut modes = solve(model, max, damping_ratio, fields)?;
    let lambda_cut = omega_cut * omega_cut;
    let mut keep = modes
        .modes
        .iter()
        .take_while(|m| m.lambda <= lambda_cut)
        .count()
        .max(min.min(max));
    // λ = ω²: a relative gap of 2e-6 in λ is 1e-6 in frequency
    while keep > 0
        && keep < modes.modes.len()
        && modes.modes[keep].lambda <= modes.modes[keep - 1].lambda * (1.0 + 2e-6)
    {
        keep += 1;
    }
    modes.modes.truncate(keep);
    Ok(modes)
}

/// Scatters a field's free-DOF vector into a nodal [`NODAL`]-vector.
pub fn nodal_shape(model: &PlateModel, field: Field, dofs: impl Iterator<Item = f64>) -> Vec<f64> {
    let dofs: Vec<f64> = dofs.collect();
    let mut out = vec![0.0; NODAL * model.mesh.nodes.len()];
    let off = field.nodal_offset();
    for (n, start) in model.dof_start[field as usize].iter().enumerate() {
        if let Some(s) = start {
            for d in 0..field.dofs() {
                out[NODAL * n + off + d] = dofs[s + d];
            }
        }
    }
    out
}

/// Gathers a field's free-DOF vector from a nodal [`NODAL`]-vector (transpose of [`nodal_shape`]).
pub fn field_dofs(model: &PlateModel, field: Field, nodal: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; model.n_dofs(field)];
    let off = field.nodal_offset();
    for (n, start) in model.dof_start[field as usize].iter().enumerate() {
        if let Some(s) = start {
            for d in 0..field.dofs() {
                out[s + d] = nodal[NODAL * n + off + d];
            }
        }
    }
    out
}

/// Values sampled at a point of the plate.
pub const SAMPLED: usize = 5;

/// Points of the plate, given in parametric coordinates (ξ, η) so they follow the planform, at which
/// mode shapes are sampled as (w, ∂w/∂x, ∂w/∂y, u, v).
#[derive(Clone, Debug)]
pub struct Sampler {
    /// (element, natural coordinates) of each point.
    pub located: Vec<(usize, [f64; 2])>,
}

impl Sampler {
    pub fn new(model: &PlateModel, points: &[[f64; 2]]) -> Self {
        Self {
            located: points
                .iter()
                .map(|p| model.mesh.locate(p[0], p[1]))
                .collect(),
        }
    }

    /// Interpolation weights of point `q`: for each of the [`SAMPLED`] outputs, (node, nodal slot,
    /// weight) triples, for planform variables p.
    pub fn weights<S: Scalar>(
        &self,
        model: &PlateModel,
        p: [S; 4],
        q: usize,
    ) -> [Vec<(usize, usize, S)>; SAMPLED] {
        let (e, [xi, eta]) = self.located[q];
        let xy = model.element_xy(p, e);
        let f = element::deflection_functions(&xy, xi, eta);
        let nm = element::membrane_functions(xi, eta);
        let nodes = model.mesh.elements[e];
        let mut out: [Vec<(usize, usize, S)>; SAMPLED] = Default::default();
        for (r, out_r) in out.iter_mut().enumerate().take(3) {
            for (a, &node) in nodes.iter().enumerate() {
                for d in 0..3 {
                    out_r.push((node, d, f[r][3 * a + d]));
                }
            }
        }
        for (a, &node) in nodes.iter().enumerate() {
            out[3].push((node, 3, S::cst(nm[a])));
            out[4].push((node, 4, S::cst(nm[a])));
        }
        out
    }

    /// Samples a nodal field: one [`SAMPLED`]-array a point.
    pub fn sample(&self, model: &PlateModel, nodal: &[f64]) -> Vec<[f64; SAMPLED]> {
        let p = model.planform().to_array();
        (0..self.located.len())
            .map(|q| {
                let w = self.weights(model, p, q);
                std::array::from_fn(|r| {
                    w[r].iter().map(|&(n, s, c)| c * nodal[NODAL * n + s]).sum()
                })
            })
            .collect()
    }
}
