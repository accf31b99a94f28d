//! The DLM on the AGARD 445.6 wing: box convergence of the GAFs and consistency of rigid motions.

mod common;

use gustkit::structure::modal;
use gustkit::study::Study;
use gustkit_core::ModalSurface;
use num_complex::Complex64 as C;

fn study_with(n_chord: usize, n_span: usize, k: &[f64]) -> Study {
    common::agard_study(|v| {
        common::set_boxes(v, n_chord, n_span);
        v["aero"]["reduced_frequencies"] = serde_json::json!(k);
        v["structure"]["modes"] = 4.into();
        v.as_object_mut().unwrap().remove("gust");
        v.as_object_mut().unwrap().remove("optimization");
    })
}

/// GAFs of the first four modes at k = 0.5 and the gust GAFs converge as the box layout is doubled
/// twice (6×8 → 12×16 → 24×32): the changes shrink by more than 2.5 (observed 3.5, close to the
/// O(h²) of the lattice) and the finest two layouts agree within 5 % of the largest entry, which
/// puts the 24×32 layout within about 1.5 % of the extrapolated limit.
#[test]
fn agard_gafs_converge_with_boxes() {
    let mut tables = Vec::new();
    for (nc, ns) in [(6, 8), (12, 16), (24, 32)] {
        let study = study_with(nc, ns, &[0.5]);
        let plate = study.build_model().unwrap();
        let modes = modal::solve(&plate, 4, 0.0, &study.mode_fields()).unwrap();
        let aero = study.aero_model(&plate).unwrap();
        tables.push(aero.gafs(&plate, &modes).unwrap());
    }
    let entries = |t: &gustkit_core::GafTable| -> Vec<C> {
        let mut v: Vec<C> = t.q_ss[0].iter().flatten().copied().collect();
        v.extend(t.q_gs[0].iter().copied());
        v
    };
    let (a, b, c) = (
        entries(&tables[0]),
        entries(&tables[1]),
        entries(&tables[2]),
    );
    let scale = c.iter().map(|v| v.norm()).fold(0.0, f64::max);
    let d1 = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0, f64::max)
        / scale;
    let d2 = b
        .iter()
        .zip(&c)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0, f64::max)
        / scale;
    println!("max change 6x8→12x16 {d1:.4}, 12x16→24x32 {d2:.4}");
    assert!(d1 / d2 > 2.5, "{d1} {d2}");
    assert!(d2 < 0.05, "{d2}");
}

/// Rigid motions of the AGARD planform: at k = 0 the lift of a unit pitch (slope −1) equals the
/// lift of a unit steady gust (both are α = 1), to round-off; at small k the plunge lift is
/// −i (k / b_ref) times the gust lift to first order in k.
#[test]
fn rigid_heave_and_pitch_consistency() {
    let study = study_with(8, 10, &[0.0, 1e-4]);
    let plate = study.build_model().unwrap();
    let aero = study.aero_model(&plate).unwrap();
    let surf = aero.fidelity.surface();
    let mut m = ModalSurface::zeros(2, surf.points.len());
    for (p, pt) in surf.points.iter().enumerate() {
        m.disp[0][p] = [0.0, 0.0, 1.0]; // heave
        m.disp[1][p] = [0.0, 0.0, -pt[0]]; // pitch about the root leading edge
        m.disp_x[1][p] = [0.0, 0.0, -1.0];
    }
    let t = aero.fidelity.gafs(&aero.flight, &m, &aero.k).unwrap();
    let lift_pitch = t.q_ss[0][0][1];
    let lift_gust = t.q_gs[0][0];
    assert!(lift_pitch.re > 0.0);
    assert!(
        (lift_pitch - lift_gust).norm() < 1e-12 * lift_gust.norm(),
        "{lift_pitch} {lift_gust}"
    );
    let kd = 1e-4 / aero.flight.b_ref;
    let plunge = t.q_ss[1][0][0];
    let expect = C::new(0.0, -kd) * t.q_gs[1][0];
    assert!(
        (plunge - expect).norm() < 1e-3 * expect.norm(),
        "{plunge} {expect}"
    );
}
