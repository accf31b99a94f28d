//! The transfer's transpose and reverse mode.

use super::*;
use crate::structure::{modal, Field};
use crate::study::Study;
use gustkit_testkit::{dot, rand_vec};
use std::path::Path;

fn plate() -> (PlateModel, Modes) {
    let s = Study::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/agard445_dlm_analysis.json"),
    )
    .unwrap();
    let p = s.build_model().unwrap();
    let m = modal::solve(&p, 3, 0.0, &[Field::Bending, Field::Membrane]).unwrap();
    (p, m)
}

/// Virtual work: Σ_p f_p · u(p) = Σ F_nodal · (nodal field) for any nodal field, so the loads
/// transpose is exactly the adjoint of the displacement transfer.
#[test]
fn loads_transpose_is_the_adjoint_of_the_transfer() {
    let (p, _) = plate();
    let pts: Vec<[f64; 2]> = rand_vec(40, 8)
        .chunks(2)
        .map(|c| [0.5 + 0.5 * c[0], 0.5 + 0.5 * c[1]])
        .collect();
    let t = ModeTransfer::new(&p, &pts);
    let nodal = rand_vec(crate::structure::model::NODAL * p.mesh.nodes.len(), 9);
    let forces: Vec<[f64; 3]> = rand_vec(60, 10)
        .chunks(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    let samples = t.sampler.sample(&p, &nodal);
    let work_points: f64 = samples
        .iter()
        .zip(&forces)
        .map(|(s, f)| f[0] * s[3] + f[1] * s[4] + f[2] * s[0])
        .sum();
    let work_nodes = dot(&t.loads_to_nodes(&p, &forces), &nodal);
    assert!((work_points - work_nodes).abs() < 1e-12 * work_points.abs());
}

/// Reverse mode of the modal-surface transfer against its forward product (linear in the shapes).
#[test]
fn transfer_vjp_dot_product_test() {
    let (p, modes) = plate();
    let pts: Vec<[f64; 2]> = rand_vec(30, 3)
        .chunks(2)
        .map(|c| [0.5 + 0.5 * c[0], 0.5 + 0.5 * c[1]])
        .collect();
    let t = ModeTransfer::new(&p, &pts);
    let mut seed = ModalSurface::zeros(modes.len(), pts.len());
    let r = rand_vec(modes.len() * pts.len() * 6, 4);
    for (v, ri) in seed.values_mut().zip(&r) {
        *v = *ri;
    }
    let (shape_bar, _) = t.modes_on_surface_vjp(&p, &modes, &seed);
    // perturb the nodal shapes: the transfer is linear in them
    let mut pert = modes.clone();
    let d: Vec<Vec<f64>> = (0..modes.len())
        .map(|m| rand_vec(modes.modes[m].shape.len(), 20 + m as u64))
        .collect();
    for (m, mode) in pert.modes.iter_mut().enumerate() {
        for (a, b) in mode.shape.iter_mut().zip(&d[m]) {
            *a += b;
        }
    }
    let s0 = t.modes_on_surface(&p, &modes);
    let s1 = t.modes_on_surface(&p, &pert);
    let flat = |m: &ModalSurface| -> Vec<f64> { m.values().copied().collect() };
    let jv: Vec<f64> = flat(&s1)
        .iter()
        .zip(flat(&s0))
        .map(|(a, b)| a - b)
        .collect();
    let forward = dot(&flat(&seed), &jv);
    let reverse: f64 = (0..modes.len()).map(|m| dot(&shape_bar[m], &d[m])).sum();
    assert!(
        (forward - reverse).abs() < 1e-12 * forward.abs(),
        "{forward} {reverse}"
    );
}
