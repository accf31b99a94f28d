//! Modal analysis: K φ = λ M φ, mass-normalized modes, generalized matrices, sampling.
//!
//! Each uncoupled field (bending, membrane) is solved densely and completely: M = L Lᵀ, the standard
//! problem L⁻¹ K L⁻ᵀ y = λ y with faer's self-adjoint eigensolver, φ = L⁻ᵀ y. The full spectrum is
//! kept because the exact eigenvector derivatives use the complete modal expansion.
//!
//! Conventions: φᵀ M φ = 1; the sign of each mode makes its largest-magnitude translational nodal
//! value (w for bending, u or v for membrane) positive.

use super::element;
use super::model::{Field, PlateModel, NODAL};
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::{Mat, Par, Side};
use gustkit_core::scalar::Scalar;

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

/// Complete eigen-decomposition of one field, in the well-conditioned inverse form:
/// K = L Lᵀ, L⁻¹ M L⁻ᵀ y_j = μ_j y_j with μ_j = 1/λ_j, φ_j = L⁻ᵀ y_j / √μ_j.
///
/// Reducing with the stiffness (not the mass) puts the lowest modes at the top of the spectrum of
/// a bounded operator, so they carry full relative precision, and the modal expansion can be
/// written without ever dividing by the tiny μ_j of the highest modes.
#[derive(Clone, Debug)]
pub struct FieldEigen {
    pub field: Field,
    /// Cholesky factor L of the field stiffness.
    pub chol: Mat<f64>,
    /// Orthonormal eigenvectors y_j (columns).
    pub y: Mat<f64>,
    /// Eigenvalues μ_j = 1/λ_j, ascending (lowest structural modes last).
    pub mu: Vec<f64>,
}

impl FieldEigen {
    /// Column of the j-th lowest structural mode.
    pub fn column_of_mode(&self, j: usize) -> usize {
        self.mu.len() - 1 - j
    }

    /// Mass-normalized mode of column c: φ = L⁻ᵀ y_c / √μ_c.
    pub fn mode_vector(&self, c: usize) -> Vec<f64> {
        let mut v = self.y.col(c).to_owned();
        solve_upper_triangular_in_place(self.chol.transpose(), v.as_mat_mut(), Par::Seq);
        let s = 1.0 / self.mu[c].sqrt();
        v.iter().map(|x| x * s).collect()
    }

    /// Σ_{j≠c} φ_j (φ_jᵀ r) / (λ_c − λ_j), the complete modal expansion applied to r, evaluated as
    /// L⁻ᵀ Σ_{j≠c} y_j (y_jᵀ L⁻¹ r) μ_c / (μ_j − μ_c).
    pub fn expansion(&self, c: usize, r: &[f64]) -> Vec<f64> {
        let n = r.len();
        let mut z = Mat::from_fn(n, 1, |i, _| r[i]);
        solve_lower_triangular_in_place(self.chol.as_ref(), z.as_mut(), Par::Seq);
        let mut coef = self.y.transpose() * &z;
        let mu_c = self.mu[c];
        for j in 0..n {
            coef[(j, 0)] = if j == c {
                0.0
            } else {
                coef[(j, 0)] * mu_c / (self.mu[j] - mu_c)
            };
        }
        let mut out = &self.y * &coef;
        solve_upper_triangular_in_place(self.chol.transpose(), out.as_mut(), Par::Seq);
        out.col(0).iter().copied().collect()
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

/// Solves one field completely.
pub fn solve_field(model: &PlateModel, field: Field) -> Result<FieldEigen, ModalError> {
    let (k, m) = model.assemble(field);
    let n = k.nrows();
    let llt = k
        .llt(Side::Lower)
        .map_err(|_| ModalError::Unconstrained(field))?;
    let chol = llt.L().to_owned();
    // B = L⁻¹ M L⁻ᵀ
    let mut b = m;
    solve_lower_triangular_in_place(chol.as_ref(), b.as_mut(), Par::Seq);
    let mut bt = b.transpose().to_owned();
    solve_lower_triangular_in_place(chol.as_ref(), bt.as_mut(), Par::Seq);
    let b = Mat::from_fn(n, n, |i, j| 0.5 * (bt[(i, j)] + bt[(j, i)]));
    let eig = b
        .self_adjoint_eigen(Side::Lower)
        .map_err(|_| ModalError::Eigen(field))?;
    let mu: Vec<f64> = (0..n).map(|i| eig.S()[i]).collect();
    if mu.last().is_some_and(|&top| top <= 0.0) {
        return Err(ModalError::MassNotPositive(field));
    }
    Ok(FieldEigen {
        field,
        chol,
        y: eig.U().to_owned(),
        mu,
    })
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
        .map(|&f| solve_field(model, f))
        .collect::<Result<_, _>>()?;
    // merge the two ascending spectra
    let mut picks: Vec<(f64, usize, usize)> = fields
        .iter()
        .enumerate()
        .flat_map(|(fi, fe)| {
            (0..n_modes.min(fe.mu.len())).map(move |j| {
                let c = fe.column_of_mode(j);
                (1.0 / fe.mu[c], fi, c)
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
                fe.y.col_mut(column).iter_mut().for_each(|v| *v = -*v);
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
