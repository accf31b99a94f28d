//! Residual flexibility of the retained modes: the mode-acceleration method for response outputs.
//!
//! With N retained modes the mode-displacement method gives an output y = cᵀu as cᵀΦη and leaves
//! out the quasi-static response of every mode above them. The mode-acceleration method adds it:
//!   u = Φ η + R F,   R = K⁻¹ − Φ Λ⁻¹ Φᵀ   (the flexibility of the modes left out),
//! with F the applied (aerodynamic) load on the structure, so y = cᵀΦη + wᵀF with the residual
//! shape w = R c. A response code then needs the generalized force of the load on w, i.e. one more
//! row of the GAF matrices: wᵀF = q_inf (Q_ws(ik) η + Q_wg(ik) w_g/U).
//!   - displacement at a point (c its interpolation weights): w = K⁻¹c − Σ_i φ_i (φ_iᵀc)/λ_i;
//!   - root bending moment y = rᵀK u (r the rigid rotation about the root line, see
//!     [`super::root_bending_moment`]): w = K R r = r − Σ_i φ_i (φ_iᵀ M r), the force summation.
//!
//! With every mode of the field retained, K⁻¹ = Φ Λ⁻¹ Φᵀ and w = 0. The motion of the residual
//! flexibility does not feed back into the aerodynamic loads (the method's usual approximation).
//!
//! Reverse mode, for seeds w̄ on the free DOFs (s_i = φ_iᵀc, t_i = φ_iᵀw̄, m_i = φ_iᵀMr):
//!   displacement: a = K⁻¹w̄, x̄ −= aᵀ(∂K/∂x)K⁻¹c, c̄ = a − Σ φ_i t_i/λ_i,
//!                 φ̄_i −= (s_i w̄ + t_i c)/λ_i, λ̄_i += t_i s_i/λ_i²;
//!   moment:       r̄ = w̄ − Σ t_i M φ_i, φ̄_i −= m_i w̄ + t_i M r, x̄ −= Σ t_i φ_iᵀ(∂M/∂x) r.

use super::modal::{field_dofs, nodal_shape, Modes, Sampler, SAMPLED};
use super::model::{Field, PlateModel, NODAL};
use super::sensitivity::{matrix_pairs_vjp, ModalSeed};
use crate::wing::N_PLANFORM;

/// The free-DOF vector c of an output: a point's deflection weights, or the rigid rotation r
/// about the root line (w = η s, ∂w/∂y = 1 at every free node) for the root bending moment.
fn output_vector(model: &PlateModel, output: Option<&Sampler>) -> Vec<f64> {
    let mut nodal = vec![0.0; NODAL * model.mesh.nodes.len()];
    match output {
        Some(sampler) => {
            let p = model.planform().to_array();
            for (node, slot, weight) in &sampler.weights(model, p, 0)[0] {
                nodal[NODAL * node + slot] += *weight;
            }
        }
        None => {
            let span = model.planform().span;
            for (n, node) in model.mesh.nodes.iter().enumerate() {
                if !model.mesh.clamped[n] {
                    nodal[NODAL * n] = node[1] * span;
                    nodal[NODAL * n + 2] = 1.0;
                }
            }
        }
    }
    field_dofs(model, Field::Bending, &nodal)
}

/// The retained bending modes: (index in `modes`, φ over the free DOFs, λ).
fn bending_modes(modes: &Modes) -> Vec<(usize, Vec<f64>, f64)> {
    let Some(fe) = modes.field(Field::Bending) else {
        return Vec::new();
    };
    modes
        .modes
        .iter()
        .enumerate()
        .filter(|(_, m)| m.field == Field::Bending)
        .map(|(i, m)| (i, fe.mode_vector(m.column), m.lambda))
        .collect()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn axpy(y: &mut [f64], a: f64, x: &[f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += a * xi;
    }
}

/// The residual shape of each output as a nodal field ([`NODAL`] values a node): `outputs` holds
/// a point's sampler for a displacement, `None` for the root bending moment.
pub fn residual_shapes(
    model: &PlateModel,
    modes: &Modes,
    outputs: &[Option<Sampler>],
) -> Vec<Vec<f64>> {
    let Some(fe) = modes.field(Field::Bending) else {
        return vec![vec![0.0; NODAL * model.mesh.nodes.len()]; outputs.len()];
    };
    let retained = bending_modes(modes);
    outputs
        .iter()
        .map(|o| {
            let c = output_vector(model, o.as_ref());
            let w = match o {
                Some(_) => {
                    let mut w = fe.static_solve(&c);
                    for (_, phi, lambda) in &retained {
                        axpy(&mut w, -dot(phi, &c) / lambda, phi);
                    }
                    w
                }
                None => {
                    let mr = fe.mass_times(&c);
                    let mut w = c;
                    for (_, phi, _) in &retained {
                        axpy(&mut w, -dot(phi, &mr), phi);
                    }
                    w
                }
            };
            nodal_shape(model, Field::Bending, w.into_iter())
        })
        .collect()
}

fn slices(v: &[(Vec<f64>, Vec<f64>)]) -> Vec<(&[f64], &[f64])> {
    v.iter()
        .map(|(a, b)| (a.as_slice(), b.as_slice()))
        .collect()
}

/// Reverse mode of [`residual_shapes`]: for seeds on the nodal residual shapes, the seeds on the
/// modes (feed them to `modes_vjp`) and the direct gradient with respect to x (stiffness, mass
/// and the outputs' geometry).
pub fn residual_shapes_vjp(
    model: &PlateModel,
    modes: &Modes,
    outputs: &[Option<Sampler>],
    shape_bar: &[Vec<f64>],
) -> (ModalSeed, Vec<f64>) {
    let n = model.mesh.n_dv() + N_PLANFORM;
    let mut seed = ModalSeed::zeros(modes);
    let Some(fe) = modes.field(Field::Bending) else {
        return (seed, vec![0.0; n]);
    };
    let retained = bending_modes(modes);
    let nd = fe.n_dofs();
    let mut phi_bar: Vec<Vec<f64>> = vec![vec![0.0; nd]; retained.len()];
    let mut p_bar = [0.0; N_PLANFORM];
    // (−a, K⁻¹c) stiffness pairs and (−Σ t_i φ_i, r) mass pairs, one an output
    let mut k_pairs: Vec<(Vec<f64>, Vec<f64>)> = Vec::new();
    let mut m_pairs: Vec<(Vec<f64>, Vec<f64>)> = Vec::new();
    for (o, wb) in outputs.iter().zip(shape_bar) {
        if wb.iter().all(|v| *v == 0.0) {
            continue;
        }
        let wb = field_dofs(model, Field::Bending, wb);
        let c = output_vector(model, o.as_ref());
        match o {
            Some(sampler) => {
                let a = fe.static_solve(&wb);
                let mut c_bar = a.clone();
                for (j, (i, phi, lambda)) in retained.iter().enumerate() {
                    let (s, t) = (dot(phi, &c), dot(phi, &wb));
                    axpy(&mut phi_bar[j], -s / lambda, &wb);
                    axpy(&mut phi_bar[j], -t / lambda, &c);
                    axpy(&mut c_bar, -t / lambda, phi);
                    seed.lambda[*i] += t * s / (lambda * lambda);
                }
                k_pairs.push((a.iter().map(|v| -v).collect(), fe.static_solve(&c)));
                // c̄ → the point's weights move with the planform
                let c_bar_nodal = nodal_shape(model, Field::Bending, c_bar.into_iter());
                let mut unit = [0.0; SAMPLED];
                unit[0] = 1.0;
                let (_, pb) = sampler.sample_vjp(model, &c_bar_nodal, &[unit]);
                for k in 0..N_PLANFORM {
                    p_bar[k] += pb[k];
                }
            }
            None => {
                let mr = fe.mass_times(&c);
                // v = Σ t_i φ_i carries every mode's share: r̄ −= M v, x̄ −= vᵀ(∂M/∂x) r
                let mut v = vec![0.0; nd];
                for (j, (_, phi, _)) in retained.iter().enumerate() {
                    let (m, t) = (dot(phi, &mr), dot(phi, &wb));
                    axpy(&mut phi_bar[j], -m, &wb);
                    axpy(&mut phi_bar[j], -t, &mr);
                    axpy(&mut v, t, phi);
                }
                let mut r_bar = wb.clone();
                axpy(&mut r_bar, -1.0, &fe.mass_times(&v));
                m_pairs.push((v.iter().map(|x| -x).collect(), c));
                // r's deflection entries are η s: ∂r/∂span
                let r_bar_nodal = nodal_shape(model, Field::Bending, r_bar.into_iter());
                for (nd, node) in model.mesh.nodes.iter().enumerate() {
                    p_bar[0] += r_bar_nodal[NODAL * nd] * node[1];
                }
            }
        }
    }
    for (j, (i, _, _)) in retained.iter().enumerate() {
        seed.shape[*i] = nodal_shape(model, Field::Bending, phi_bar[j].iter().copied());
    }
    let (kp, mp) = (slices(&k_pairs), slices(&m_pairs));
    let mut g = matrix_pairs_vjp(model, Field::Bending, &kp, &mp);
    let n_dv = model.mesh.n_dv();
    for k in 0..N_PLANFORM {
        g[n_dv + k] += p_bar[k];
    }
    (seed, g)
}
