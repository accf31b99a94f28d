//! Exact reverse- and forward-mode sensitivities of the structural outputs with respect to the
//! design vector x = [t (patch thicknesses), span, sweep_c4, root_chord, tip_chord].
//!
//! Eigen-derivatives use the complete modal expansion, exact for distinct eigenvalues, evaluated
//! without the complete spectrum by Nelson's method ([`super::modal::FieldEigen::expansion`]):
//!   dλ_i = φ_iᵀ (dK − λ_i dM) φ_i,
//!   dφ_i = Σ_{j≠i} φ_j φ_jᵀ (dK − λ_i dM) φ_i / (λ_i − λ_j) − ½ φ_i (φ_iᵀ dM φ_i),
//! the second term keeping φᵀ M φ = 1. In reverse, the seeds (λ̄_i, φ̄_i) collapse to
//!   x̄ = Σ_i u_iᵀ (∂K/∂x) φ_i − v_iᵀ (∂M/∂x) φ_i,
//!   a_i = Σ_{j≠i} φ_j (φ_jᵀ φ̄_i)/(λ_i − λ_j),  u_i = a_i + λ̄_i φ_i,  v_i = λ_i u_i + ½ (φ̄_iᵀ φ_i) φ_i,
//! so one sweep over the elements gives all 104 derivatives. Element matrix derivatives with
//! respect to the planform come from dual numbers through the same element code.

use super::element;
use super::modal::{field_dofs, nodal_shape, Modes, Sampler, SAMPLED};
use super::model::{Field, PlateModel, NODAL};
use crate::wing::N_PLANFORM;
use faer::Mat;
use gustkit_core::scalar::{Dual, Scalar};

/// Seeds on the modal outputs: one entry a retained mode.
#[derive(Clone, Debug, Default)]
pub struct ModalSeed {
    /// Seed on λ_i = ω_i² (an empty vector means zero).
    pub lambda: Vec<f64>,
    /// Seed on the nodal mode shape of mode i ([`NODAL`] a node; an empty inner vector means zero).
    pub shape: Vec<Vec<f64>>,
}

impl ModalSeed {
    pub fn zeros(modes: &Modes) -> Self {
        Self {
            lambda: vec![0.0; modes.len()],
            shape: vec![Vec::new(); modes.len()],
        }
    }
}

/// Planform variables as duals seeded with the unit directions.
fn planform_duals(model: &PlateModel) -> [Dual<N_PLANFORM>; N_PLANFORM] {
    let p = model.planform().to_array();
    std::array::from_fn(|k| Dual::var(p[k], k))
}

/// Exponent of the thickness in the element stiffness of a field (t³ bending, t membrane).
fn stiffness_power(field: Field) -> f64 {
    match field {
        Field::Bending => 3.0,
        Field::Membrane => 1.0,
    }
}

/// Gathers an element's local values from a free-DOF vector.
fn gather(dofs: &[Option<usize>], v: &[f64]) -> Vec<f64> {
    dofs.iter().map(|d| d.map_or(0.0, |g| v[g])).collect()
}

/// Reverse mode of the modal analysis: x̄ (length n_dv + 4) for seeds on λ and mode shapes.
pub fn modes_vjp(model: &PlateModel, modes: &Modes, seed: &ModalSeed) -> Vec<f64> {
    let n_dv = model.mesh.n_dv();
    let mut grad = vec![0.0; n_dv + N_PLANFORM];
    for field in Field::ALL {
        let Some(fe) = modes.field(field) else {
            continue;
        };
        // Nelson's factorizations of the seeded shapes, in parallel, before they are used
        let seeded: Vec<usize> = modes
            .modes
            .iter()
            .enumerate()
            .filter(|(i, m)| m.field == field && seed.shape.get(*i).is_some_and(|s| !s.is_empty()))
            .map(|(_, m)| m.column)
            .collect();
        fe.prepare(&seeded);
        // (u_i, −v_i, φ_i) over the free DOFs of this field
        let mut triples: Vec<(Vec<f64>, Vec<f64>, Vec<f64>)> = Vec::new();
        for (i, mode) in modes.modes.iter().enumerate() {
            if mode.field != field {
                continue;
            }
            let c = mode.column;
            let phi = fe.mode_vector(c);
            let lam_bar = seed.lambda.get(i).copied().unwrap_or(0.0);
            let mut u: Vec<f64> = phi.iter().map(|p| lam_bar * p).collect();
            let mut cmix = 0.0;
            if let Some(s) = seed.shape.get(i).filter(|s| !s.is_empty()) {
                let phibar = field_dofs(model, field, s);
                cmix = dot(&phibar, &phi);
                for (ur, ar) in u.iter_mut().zip(fe.expansion(c, &phibar)) {
                    *ur += ar;
                }
            }
            let neg_v: Vec<f64> = u
                .iter()
                .zip(&phi)
                .map(|(ui, pi)| -(mode.lambda * ui + 0.5 * cmix * pi))
                .collect();
            triples.push((u, neg_v, phi));
        }
        let k_pairs: Vec<(&[f64], &[f64])> = triples
            .iter()
            .map(|(u, _, phi)| (u.as_slice(), phi.as_slice()))
            .collect();
        let m_pairs: Vec<(&[f64], &[f64])> = triples
            .iter()
            .map(|(_, neg_v, phi)| (neg_v.as_slice(), phi.as_slice()))
            .collect();
        for (g, d) in grad
            .iter_mut()
            .zip(matrix_pairs_vjp(model, field, &k_pairs, &m_pairs))
        {
            *g += d;
        }
    }
    grad
}

/// Σ aᵀ (∂K/∂x) b + Σ cᵀ (∂M/∂x) d over pairs of a field's free-DOF vectors, for every design
/// variable, in one sweep over the elements (the stiffness grows with t^p, the mass with t; the
/// planform derivatives come from the element matrices' dual numbers).
pub(crate) fn matrix_pairs_vjp(
    model: &PlateModel,
    field: Field,
    k_pairs: &[(&[f64], &[f64])],
    m_pairs: &[(&[f64], &[f64])],
) -> Vec<f64> {
    let n_dv = model.mesh.n_dv();
    let mut grad = vec![0.0; n_dv + N_PLANFORM];
    if k_pairs.is_empty() && m_pairs.is_empty() {
        return grad;
    }
    let pow = stiffness_power(field);
    for e in 0..model.mesh.elements.len() {
        let dofs = model.element_dofs(field, e);
        let nl = dofs.len();
        // Σ a bᵀ and Σ c dᵀ on the element
        let outer = |pairs: &[(&[f64], &[f64])]| {
            let mut acc = vec![0.0; nl * nl];
            for (a, b) in pairs {
                let (al, bl) = (gather(&dofs, a), gather(&dofs, b));
                for i in 0..nl {
                    for j in 0..nl {
                        acc[i * nl + j] += al[i] * bl[j];
                    }
                }
            }
            acc
        };
        let (ab, cd) = (outer(k_pairs), outer(m_pairs));
        let t = model.element_thickness(e);
        let (ke, me) = &model.element_duals(field)[e];
        let mut gk = Dual::<N_PLANFORM>::cst(0.0);
        let mut gm = Dual::<N_PLANFORM>::cst(0.0);
        for q in 0..nl * nl {
            gk += ke[q] * ab[q];
            gm += me[q] * cd[q];
        }
        grad[model.mesh.element_dv[e]] += (pow * gk.v + gm.v) / t;
        for k in 0..N_PLANFORM {
            grad[n_dv + k] += gk.d[k] + gm.d[k];
        }
    }
    grad
}

/// Forward mode of the modal analysis along dx: (dλ_i, dφ_i nodal) for each retained mode.
pub fn modes_jvp(model: &PlateModel, modes: &Modes, dx: &[f64]) -> (Vec<f64>, Vec<Vec<f64>>) {
    let n_dv = model.mesh.n_dv();
    let dp = &dx[n_dv..];
    let mut dlam = vec![0.0; modes.len()];
    let mut dphi = vec![Vec::new(); modes.len()];
    for field in Field::ALL {
        let Some(fe) = modes.field(field) else {
            continue;
        };
        let n = fe.n_dofs();
        let pow = stiffness_power(field);
        let mut dk = Mat::<f64>::zeros(n, n);
        let mut dm = Mat::<f64>::zeros(n, n);
        for (e, (ke, me)) in model.element_duals(field).iter().enumerate() {
            let dv = model.mesh.element_dv[e];
            let rel = dx[dv] / model.design.thickness[dv];
            // d(t^pow K) = pow (dt/t) K + Σ_k ∂K/∂p_k dp_k; the mass is linear in t
            let dir = |v: &Dual<N_PLANFORM>, pw: f64| {
                pw * rel * v.v + (0..N_PLANFORM).map(|k| v.d[k] * dp[k]).sum::<f64>()
            };
            let dofs = model.element_dofs(field, e);
            let nl = dofs.len();
            for (a, ga) in dofs.iter().enumerate() {
                let Some(ga) = *ga else { continue };
                for (b, gb) in dofs.iter().enumerate() {
                    let Some(gb) = *gb else { continue };
                    dk[(ga, gb)] += dir(&ke[a * nl + b], pow);
                    dm[(ga, gb)] += dir(&me[a * nl + b], 1.0);
                }
            }
        }
        for (i, mode) in modes.modes.iter().enumerate() {
            if mode.field != field {
                continue;
            }
            let c = mode.column;
            let phi = fe.mode_vector(c);
            let kphi = matvec(&dk, &phi);
            let mphi = matvec(&dm, &phi);
            let r: Vec<f64> = kphi
                .iter()
                .zip(&mphi)
                .map(|(a, b)| a - mode.lambda * b)
                .collect();
            dlam[i] = dot(&phi, &r);
            let half_m = 0.5 * dot(&phi, &mphi);
            let d: Vec<f64> = fe
                .expansion(c, &r)
                .iter()
                .zip(&phi)
                .map(|(a, p)| a - half_m * p)
                .collect();
            dphi[i] = nodal_shape(model, field, d.into_iter());
        }
    }
    (dlam, dphi)
}

/// Gradient of the structural mass with respect to x.
pub fn mass_grad(model: &PlateModel) -> Vec<f64> {
    let n_dv = model.mesh.n_dv();
    let mut g = vec![0.0; n_dv + N_PLANFORM];
    let pd = planform_duals(model);
    let rho = model.material.density;
    for e in 0..model.mesh.elements.len() {
        let a = element::area(&model.element_xy(pd, e));
        let t = model.element_thickness(e);
        g[model.mesh.element_dv[e]] += rho * a.v;
        for k in 0..N_PLANFORM {
            g[n_dv + k] += rho * t * a.d[k];
        }
    }
    g
}

impl Sampler {
    /// Reverse mode of [`Sampler::sample`]: for seeds on the sampled values, the seed on the nodal
    /// field and the gradient with respect to the planform variables (slopes move with the geometry).
    pub fn sample_vjp(
        &self,
        model: &PlateModel,
        nodal: &[f64],
        seed: &[[f64; SAMPLED]],
    ) -> (Vec<f64>, [f64; N_PLANFORM]) {
        let pd = planform_duals(model);
        let mut nodal_bar = vec![0.0; nodal.len()];
        let mut p_bar = [0.0; N_PLANFORM];
        for (q, s) in seed.iter().enumerate() {
            if s.iter().all(|v| *v == 0.0) {
                continue;
            }
            let w = self.weights(model, pd, q);
            for (r, wr) in w.iter().enumerate() {
                for &(node, slot, c) in wr {
                    let idx = NODAL * node + slot;
                    nodal_bar[idx] += c.v * s[r];
                    for k in 0..N_PLANFORM {
                        p_bar[k] += c.d[k] * nodal[idx] * s[r];
                    }
                }
            }
        }
        (nodal_bar, p_bar)
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn matvec(m: &Mat<f64>, v: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; m.nrows()];
    for (j, vj) in v.iter().enumerate() {
        if *vj != 0.0 {
            for (i, o) in out.iter_mut().enumerate() {
                *o += m[(i, j)] * vj;
            }
        }
    }
    out
}

/// Root bending moment per unit modal displacement, by the mode-displacement method: the moment
/// about the root line (the x axis) of the elastic forces K φ_m = ω_m² M φ_m over the free DOFs,
/// S_m = ω_m² rᵀ M φ_m with r the rigid rotation about the x axis (w = y, ∂w/∂y = 1). Positive when
/// the loads bend the wing up. N·m per unit η.
pub fn root_bending_moment(model: &PlateModel, modes: &Modes) -> Vec<f64> {
    // the element mass matrices' values alone, each built once for every mode: the function
    // path does not build the planform-derivative cache that only the reverse mode needs
    let p = model.planform().to_array();
    let mut b = vec![0.0; modes.len()];
    for e in 0..model.mesh.elements.len() {
        let (_, me) = model.element_matrices(Field::Bending, p, e, model.element_thickness(e));
        let (r, _) = root_rotation(model, e);
        // rᵀ Mₑ, then its product with each mode
        let rm: [f64; 12] = std::array::from_fn(|c| (0..12).map(|a| r[a] * me[a * 12 + c]).sum());
        for (bi, m) in b.iter_mut().zip(&modes.modes) {
            if m.field == Field::Bending {
                let phi = element_nodal(model, e, &m.shape);
                *bi += rm.iter().zip(&phi).map(|(x, y)| x * y).sum::<f64>();
            }
        }
    }
    b.iter()
        .zip(&modes.modes)
        .map(|(bi, m)| m.lambda * bi)
        .collect()
}

/// Reverse mode of [`root_bending_moment`]: for seeds `s_bar` (one per mode), the seeds on λ and on
/// the nodal shapes, and the direct gradient with respect to x (mass matrix and root-line geometry).
pub fn root_bending_moment_vjp(
    model: &PlateModel,
    modes: &Modes,
    s_bar: &[f64],
) -> (ModalSeed, Vec<f64>) {
    let n_dv = model.mesh.n_dv();
    let mut seed = ModalSeed::zeros(modes);
    let mut g = vec![0.0; n_dv + N_PLANFORM];
    for (i, m) in modes.modes.iter().enumerate() {
        if m.field != Field::Bending || s_bar[i] == 0.0 {
            continue;
        }
        let mut shape_bar = vec![0.0; m.shape.len()];
        let mut b = 0.0;
        let w = s_bar[i] * m.lambda;
        for (e, (_, me)) in model.element_duals(Field::Bending).iter().enumerate() {
            let (r, dr_dspan) = root_rotation(model, e);
            let phi = element_nodal(model, e, &m.shape);
            let nodes = model.mesh.elements[e];
            let (mut rmphi, mut drmphi) = (0.0, 0.0);
            let mut dmk = [0.0; N_PLANFORM];
            for a in 0..12 {
                for c in 0..12 {
                    let mv = me[a * 12 + c];
                    rmphi += r[a] * mv.v * phi[c];
                    drmphi += dr_dspan[a] * mv.v * phi[c];
                    for k in 0..N_PLANFORM {
                        dmk[k] += r[a] * mv.d[k] * phi[c];
                    }
                    // φ̄ = M r (free DOFs only: clamped entries of φ are fixed at zero)
                    let node = nodes[c / 3];
                    if !model.mesh.clamped[node] {
                        shape_bar[NODAL * node + c % 3] += w * mv.v * r[a];
                    }
                }
            }
            b += rmphi;
            // M_e ∝ t: ∂/∂t = M_e / t
            g[model.mesh.element_dv[e]] += w * rmphi / model.element_thickness(e);
            for k in 0..N_PLANFORM {
                g[n_dv + k] += w * dmk[k];
            }
            // r's w entries are η s: ∂r/∂span
            g[n_dv] += w * drmphi;
        }
        seed.lambda[i] = s_bar[i] * b;
        seed.shape[i] = shape_bar;
    }
    (seed, g)
}

/// The rigid rotation r about the x axis on element e's bending DOFs (w = y, ∂w/∂x = 0,
/// ∂w/∂y = 1), zero at clamped nodes, and its derivative with respect to the span (y = η s).
fn root_rotation(model: &PlateModel, e: usize) -> ([f64; 12], [f64; 12]) {
    let span = model.planform().span;
    let mut r = [0.0; 12];
    let mut d = [0.0; 12];
    for (a, &n) in model.mesh.elements[e].iter().enumerate() {
        if model.mesh.clamped[n] {
            continue;
        }
        let eta = model.mesh.nodes[n][1];
        r[3 * a] = eta * span;
        r[3 * a + 2] = 1.0;
        d[3 * a] = eta;
    }
    (r, d)
}

/// Element e's bending DOF values from a nodal field.
fn element_nodal(model: &PlateModel, e: usize, nodal: &[f64]) -> [f64; 12] {
    let mut v = [0.0; 12];
    for (a, &n) in model.mesh.elements[e].iter().enumerate() {
        for d in 0..3 {
            v[3 * a + d] = nodal[NODAL * n + d];
        }
    }
    v
}
