//! Exact structural sensitivities: dot-product tests (reverse against forward) and central finite
//! differences, for frequencies, sampled mode shapes and mass, on the AGARD 445.6 plate model.

mod common;

use gustkit::structure::{
    airfoil_thickness, mass_grad, modal, modes_jvp, modes_vjp, Clamp, Field, ModalSeed, Modes,
    Orthotropic, PlateMesh, PlateModel, Sampler,
};
use gustkit::wing::{Airfoil, DesignVector};
use gustkit_testkit::{dot_product_mismatch, fd_check, rand_vec};

const N_MODES: usize = 6;

fn base_design(mesh: &PlateMesh) -> DesignVector {
    let planform = common::agard_planform();
    let thickness = airfoil_thickness(mesh, &planform, &Airfoil::naca65a004());
    DesignVector {
        thickness,
        planform,
    }
}

fn material() -> Orthotropic {
    common::mahogany()
}

fn model_at(x: &[f64]) -> PlateModel {
    let mesh = PlateMesh::new(10, 10, 1, &Clamp::Interior).unwrap();
    PlateModel::new(mesh, material(), DesignVector::from_slice(x)).unwrap()
}

/// Sample points (ξ, η): tip trailing edge, tip leading edge, mid-wing, an interior point.
const POINTS: [[f64; 2]; 4] = [[1.0, 1.0], [0.0, 1.0], [0.5, 0.5], [0.37, 0.83]];

/// Scalar test function J(x) = Σ λ̄_i λ_i + Σ s̄ · samples(φ_i): every structural output at once.
struct Probe {
    lam_bar: Vec<f64>,
    sample_bar: Vec<Vec<[f64; 5]>>,
}

impl Probe {
    fn new() -> Self {
        let r = rand_vec(N_MODES + N_MODES * POINTS.len() * 5, 7);
        // λ ~ 1e3..1e6: scale its seed so that both parts of J matter
        let lam_bar = r[..N_MODES].iter().map(|v| v * 1e-4).collect();
        let sample_bar = (0..N_MODES)
            .map(|i| {
                (0..POINTS.len())
                    .map(|q| std::array::from_fn(|c| r[N_MODES + (i * POINTS.len() + q) * 5 + c]))
                    .collect()
            })
            .collect();
        Self {
            lam_bar,
            sample_bar,
        }
    }

    fn value(&self, x: &[f64]) -> f64 {
        let model = model_at(x);
        let modes = modal::solve(&model, N_MODES, 0.0, &Field::ALL).unwrap();
        let sampler = Sampler::new(&model, &POINTS);
        let mut j = 0.0;
        for (i, m) in modes.modes.iter().enumerate() {
            j += self.lam_bar[i] * m.lambda;
            let s = sampler.sample(&model, &m.shape);
            for (q, sq) in s.iter().enumerate() {
                for c in 0..5 {
                    j += self.sample_bar[i][q][c] * sq[c];
                }
            }
        }
        j
    }

    fn gradient(&self, x: &[f64]) -> Vec<f64> {
        let model = model_at(x);
        let modes = modal::solve(&model, N_MODES, 0.0, &Field::ALL).unwrap();
        let sampler = Sampler::new(&model, &POINTS);
        let mut seed = ModalSeed::zeros(&modes);
        seed.lambda = self.lam_bar.clone();
        let mut p_bar = [0.0; 4];
        for (i, m) in modes.modes.iter().enumerate() {
            let (nodal_bar, pb) = sampler.sample_vjp(&model, &m.shape, &self.sample_bar[i]);
            seed.shape[i] = nodal_bar;
            for k in 0..4 {
                p_bar[k] += pb[k];
            }
        }
        let mut g = modes_vjp(&model, &modes, &seed);
        let n = g.len() - 4;
        for k in 0..4 {
            g[n + k] += p_bar[k];
        }
        g
    }
}

fn x0() -> Vec<f64> {
    let mesh = PlateMesh::new(10, 10, 1, &Clamp::Interior).unwrap();
    base_design(&mesh).to_vec()
}

/// Best agreement of `exact` with central differences (and their Richardson extrapolation) over
/// the testkit's steps, relative to `scale`. The eigenvalues themselves carry round-off noise of
/// about 1e-12 relative, which bounds what any finite difference can confirm.
fn best_rel_error(f: &dyn Fn(&[f64]) -> f64, x: &[f64], k: usize, exact: f64, scale: f64) -> f64 {
    fd_check(f, x, k, exact, scale).best_rel_error
}

/// The reverse sweep (sampler VJP + modal VJP) against central finite differences of all structural
/// outputs at once: at least 6 significant digits, for thicknesses at root, mid and tip, leading and
/// trailing edge, and for every planform variable.
#[test]
fn modal_gradient_matches_finite_differences() {
    let probe = Probe::new();
    let x = x0();
    let g = probe.gradient(&x);
    let f = |x: &[f64]| probe.value(x);
    let n = x.len() - 4;
    let gnorm = g.iter().map(|v| v * v).sum::<f64>().sqrt();
    for k in [0, 9, 45, 90, 99, n, n + 1, n + 2, n + 3] {
        // relative to the component itself, floored at 1e-3 of the gradient norm for tiny components
        let scale = g[k].abs().max(1e-3 * gnorm);
        let err = best_rel_error(&f, &x, k, g[k], scale);
        println!("dv {k:>3}: adjoint {:+.10e}  rel err {err:.1e}", g[k]);
        assert!(err < 1e-6, "dv {k}: adjoint {} rel error {err}", g[k]);
    }
}

/// Dot-product test of the modal linearization: ⟨seed, J δx⟩ = ⟨Jᵀ seed, δx⟩ to round-off.
#[test]
fn modal_vjp_dot_product_test() {
    let x = x0();
    let model = model_at(&x);
    let modes: Modes = modal::solve(&model, N_MODES, 0.0, &Field::ALL).unwrap();
    let dx: Vec<f64> = rand_vec(x.len(), 3)
        .iter()
        .zip(&x)
        .map(|(r, xi)| r * xi.abs())
        .collect();
    let (dlam, dphi) = modes_jvp(&model, &modes, &dx);
    let nodal_len = modes.modes[0].shape.len();
    let seed = ModalSeed {
        lambda: rand_vec(N_MODES, 11),
        shape: (0..N_MODES)
            .map(|i| rand_vec(nodal_len, 100 + i as u64))
            .collect(),
    };
    // stack the outputs (λ, then every nodal shape) into one vector on both sides
    let mut w = seed.lambda.clone();
    let mut jv = dlam.clone();
    for i in 0..N_MODES {
        w.extend_from_slice(&seed.shape[i]);
        jv.extend_from_slice(&dphi[i]);
    }
    let g = modes_vjp(&model, &modes, &seed);
    let mismatch = dot_product_mismatch(&w, &jv, &g, &dx);
    println!("dot-product mismatch {mismatch:.1e}");
    assert!(mismatch < 1e-11);
}

/// Frequencies: dω_i/dx from the λ seed, ω = √λ, against finite differences of each frequency.
#[test]
fn frequency_gradients_match_finite_differences() {
    let x = x0();
    let model = model_at(&x);
    let modes = modal::solve(&model, N_MODES, 0.0, &Field::ALL).unwrap();
    let n = x.len() - 4;
    for i in 0..N_MODES {
        let mut seed = ModalSeed::zeros(&modes);
        seed.lambda[i] = 0.5 / modes.modes[i].omega(); // dω = dλ / (2ω)
        let g = modes_vjp(&model, &modes, &seed);
        let f = |x: &[f64]| {
            modal::solve(&model_at(x), N_MODES, 0.0, &Field::ALL)
                .unwrap()
                .modes[i]
                .omega()
        };
        for k in [12, 77, n + 1, n + 3] {
            let err = best_rel_error(&f, &x, k, g[k], g[k].abs());
            assert!(err < 1e-6, "mode {i} dv {k}: rel error {err}");
        }
    }
}

/// Mass gradient against finite differences (mass is linear in t, smooth in the planform).
#[test]
fn mass_gradient_matches_finite_differences() {
    let x = x0();
    let g = mass_grad(&model_at(&x));
    let f = |x: &[f64]| model_at(x).mass();
    let n = x.len() - 4;
    let gnorm = g.iter().map(|v| v * v).sum::<f64>().sqrt();
    for k in [0, 55, n, n + 1, n + 2, n + 3] {
        // dm/dsweep vanishes in exact arithmetic (shearing keeps each element's area): errors are
        // measured against 1e-3 of the gradient norm for such components
        let err = best_rel_error(&f, &x, k, g[k], g[k].abs().max(1e-3 * gnorm));
        assert!(err < 1e-7, "dv {k}: rel error {err}");
    }
    // mass is homogeneous of degree one in the thicknesses
    let m = model_at(&x).mass();
    let euler: f64 = (0..n).map(|k| g[k] * x[k]).sum();
    assert!((euler - m).abs() < 1e-12 * m);
}
