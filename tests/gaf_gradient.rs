//! The reverse sweep through modal analysis, transfer and DLM: the gradient of a real functional of
//! the GAF table with respect to all 104 design variables against finite differences.

mod common;

use gustkit::structure::{modal, modes_vjp, ModalSeed};
use gustkit::study::Study;
use gustkit::wing::DesignVector;
use gustkit_core::GafTable;
use gustkit_testkit::{fd_check, rand_vec};
use num_complex::Complex64 as C;

/// The AGARD study with a coarser box layout and fewer frequencies, to keep the test quick.
fn study() -> Study {
    common::agard_study(|v| {
        common::set_boxes(v, 5, 6);
        v["aero"]["reduced_frequencies"] = serde_json::json!([0.0, 0.3, 1.0]);
        v["structure"]["modes"] = 4.into();
        v.as_object_mut().unwrap().remove("gust");
        v.as_object_mut().unwrap().remove("optimization");
    })
}

fn seed(nk: usize, nm: usize) -> GafTable {
    let r = rand_vec(2 * nk * (nm * nm + nm), 17);
    let mut it = r.chunks(2).map(|v| C::new(v[0], v[1]));
    GafTable {
        mach: 0.5,
        b_ref: 1.0,
        x_ref: 0.0,
        k: vec![0.0; nk],
        q_ss: (0..nk)
            .map(|_| {
                (0..nm)
                    .map(|_| (0..nm).map(|_| it.next().unwrap()).collect())
                    .collect()
            })
            .collect(),
        q_gs: (0..nk)
            .map(|_| (0..nm).map(|_| it.next().unwrap()).collect())
            .collect(),
    }
}

fn functional(study: &Study, seed: &GafTable, x: &[f64]) -> f64 {
    let plate = study.model_at(DesignVector::from_slice(x)).unwrap();
    let modes = modal::solve(&plate, study.max_modes(), 0.0, &study.mode_fields()).unwrap();
    let aero = study.aero_model(&plate).unwrap();
    let q = aero.gafs(&plate, &modes).unwrap();
    seed.pair(&q)
}

/// Thicknesses at the root trailing edge, mid-wing and tip, and every planform variable: the
/// adjoint agrees with central differences (Richardson) to at least 6 significant digits.
#[test]
fn gaf_functional_gradient_matches_finite_differences() {
    let study = study();
    let x0 = study.initial_design().unwrap().to_vec();
    let plate = study.build_model().unwrap();
    let modes = modal::solve(&plate, 4, 0.0, &study.mode_fields()).unwrap();
    let aero = study.aero_model(&plate).unwrap();
    let sd = seed(3, 4);
    let (shapes, p_bar) = aero.gafs_vjp(&plate, &modes, &sd).unwrap();
    let mut ms = ModalSeed::zeros(&modes);
    ms.shape = shapes;
    let mut g = modes_vjp(&plate, &modes, &ms);
    let n = g.len() - 4;
    for k in 0..4 {
        g[n + k] += p_bar[k];
    }
    let gnorm = g.iter().map(|v| v * v).sum::<f64>().sqrt();
    let f = |x: &[f64]| functional(&study, &sd, x);
    for k in [9, 44, 95, n, n + 1, n + 2, n + 3] {
        let rep = fd_check(&f, &x0, k, g[k], g[k].abs().max(1e-3 * gnorm));
        println!(
            "{}: adjoint {:+.10e} fd {:+.10e} rel err {:.1e}",
            DesignVector::from_slice(&x0).name(k),
            g[k],
            rep.best,
            rep.best_rel_error
        );
        assert!(rep.best_rel_error < 1e-6, "dv {k}: {rep:?}");
    }
}
