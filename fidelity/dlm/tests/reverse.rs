//! Reverse mode of the DLM GAFs: dot-product tests against forward products (modes and geometry)
//! and finite differences of the geometry gradient.

use gustkit_core::{Aerodynamics, AerodynamicsReverse, FlightCondition, GafTable, ModalSurface};
use gustkit_dlm::{Dlm, Spacing, SurfaceSpec, Symmetry};
use gustkit_testkit::{fd_check, rand_vec};
use num_complex::Complex64 as C;

fn wing() -> SurfaceSpec {
    SurfaceSpec {
        name: "wing".into(),
        p1: [0.0, 0.0, 0.0],
        c1: 0.56,
        p4: [0.81, 0.76, 0.0],
        c4: 0.37,
        n_chord: 4,
        n_span: 5,
        chord_spacing: Spacing::Uniform,
        span_spacing: Spacing::Cosine,
    }
}

fn flight() -> FlightCondition {
    FlightCondition {
        mach: 0.5,
        velocity: 170.0,
        density: 0.2,
        b_ref: 0.235,
        x_ref: 0.1,
    }
}

const K: [f64; 3] = [0.0, 0.3, 1.1];

/// Smooth pseudo-modes on the surface points: polynomials in x, y with random coefficients.
fn modes(dlm: &Dlm, nm: usize, seed: u64) -> ModalSurface {
    let c = rand_vec(6 * nm, seed);
    let mut m = ModalSurface::zeros(nm, dlm.surface().points.len());
    for (p, pt) in dlm.surface().points.iter().enumerate() {
        let (x, y) = (pt[0], pt[1]);
        for i in 0..nm {
            let a = &c[6 * i..6 * i + 6];
            let z = a[0] + a[1] * x + a[2] * y + a[3] * y * y + a[4] * x * y + a[5] * x * x;
            let zx = a[1] + a[4] * y + 2.0 * a[5] * x;
            m.disp[i][p] = [0.0, 0.0, z];
            m.disp_x[i][p] = [0.0, 0.0, zx];
        }
    }
    m
}

fn random_seed(nm: usize, s: u64) -> GafTable {
    let mut t = GafTable::zeros(&flight(), &K, nm);
    let r = rand_vec(2 * K.len() * (nm * nm + nm), s);
    let mut it = r.chunks(2).map(|v| C::new(v[0], v[1]));
    for ik in 0..K.len() {
        for m in 0..nm {
            for n in 0..nm {
                t.q_ss[ik][m][n] = it.next().unwrap();
            }
            t.q_gs[ik][m] = it.next().unwrap();
        }
    }
    t
}

fn pair(seed: &GafTable, q: &GafTable) -> f64 {
    seed.pair(q)
}

fn flat(m: &ModalSurface) -> Vec<f64> {
    m.values().copied().collect()
}

/// Modes: the GAFs are bilinear in the sampled shapes, so the central difference (Q(m+δ) −
/// Q(m−δ))/2 is their exact forward product; ⟨Q̄, J δ⟩ = ⟨Jᵀ Q̄, δ⟩ to round-off.
#[test]
fn mode_shape_dot_product_test() {
    for sym in [Symmetry::Symmetric, Symmetry::None] {
        let dlm = Dlm::new(vec![wing()], sym).unwrap();
        let nm = 3;
        let m0 = modes(&dlm, nm, 1);
        let dm = modes(&dlm, nm, 2);
        let seed = random_seed(nm, 3);
        let shift = |s: f64| {
            let mut m = m0.clone();
            for (a, b) in m.values_mut().zip(flat(&dm)) {
                *a += s * b;
            }
            m
        };
        let qp = dlm.gafs(&flight(), &shift(1.0), &K).unwrap();
        let qm = dlm.gafs(&flight(), &shift(-1.0), &K).unwrap();
        let forward = 0.5 * (pair(&seed, &qp) - pair(&seed, &qm));
        let g = dlm.gafs_vjp(&flight(), &m0, &K, &seed).unwrap();
        let reverse: f64 = flat(&g.modes)
            .iter()
            .zip(flat(&dm))
            .map(|(a, b)| a * b)
            .sum();
        println!("{sym:?}: forward {forward:.15e} reverse {reverse:.15e}");
        assert!((forward - reverse).abs() < 1e-10 * forward.abs());
    }
}

/// Geometry: ⟨Q̄, J_q δq⟩ from the tangent equation equals ⟨J_qᵀ Q̄, δq⟩ to round-off, and each
/// component of the reverse gradient matches central finite differences (Richardson) of
/// Re⟨Q̄, Q(q)⟩ to at least 6 significant digits.
#[test]
fn geometry_dot_product_and_finite_differences() {
    let base = wing();
    let dlm = Dlm::new(vec![base.clone()], Symmetry::Symmetric).unwrap();
    let nm = 2;
    let m = modes(&dlm, nm, 5);
    let seed = random_seed(nm, 6);
    let g = dlm.gafs_vjp(&flight(), &m, &K, &seed).unwrap();
    let dq = rand_vec(8, 9);
    let jv = dlm.gafs_geometry_jvp(&flight(), &m, &K, &dq).unwrap();
    let forward = pair(&seed, &jv);
    let reverse: f64 = g.geometry.iter().zip(&dq).map(|(a, b)| a * b).sum();
    println!("forward {forward:.15e} reverse {reverse:.15e}");
    assert!((forward - reverse).abs() < 1e-10 * forward.abs());
    // finite differences: the modes stay attached to the box indices (as the transfer would
    // re-sample them, which is the pipeline's part of the chain)
    let f = |q: &[f64]| {
        let s = SurfaceSpec {
            p1: [q[0], q[1], q[2]],
            c1: q[3],
            p4: [q[4], q[5], q[6]],
            c4: q[7],
            ..base.clone()
        };
        let d = Dlm::new(vec![s], Symmetry::Symmetric).unwrap();
        pair(&seed, &d.gafs(&flight(), &m, &K).unwrap())
    };
    let q0 = base.params();
    let gnorm = g.geometry.iter().map(|v| v * v).sum::<f64>().sqrt();
    // p1.y = 0 is the symmetry plane and p1.z, p4.z move the plane off z = 0: all 8 are checked
    for p in 0..8 {
        // zero-valued parameters get absolute steps (fd_check's rule)
        let x = q0.to_vec();
        let rep = fd_check(
            &f,
            &x,
            p,
            g.geometry[p],
            g.geometry[p].abs().max(1e-6 * gnorm),
        );
        println!(
            "{}: adjoint {:+.10e} fd {:+.10e} rel err {:.1e}",
            dlm.geometry_names()[p],
            g.geometry[p],
            rep.best,
            rep.best_rel_error
        );
        assert!(rep.best_rel_error < 1e-6, "param {p}: {rep:?}");
    }
}

/// Several seeds in one reverse pass give, seed by seed, the gradients of separate passes (the
/// shared factorization and dual-number geometry pass change nothing but the cost).
#[test]
fn many_seeds_equal_separate_passes() {
    let dlm = Dlm::new(vec![wing()], Symmetry::Symmetric).unwrap();
    let m = modes(&dlm, 3, 5);
    let seeds = [random_seed(3, 21), random_seed(3, 22), random_seed(3, 23)];
    let many = dlm.gafs_vjp_many(&flight(), &m, &K, &seeds).unwrap();
    assert_eq!(many.len(), 3);
    for (s, g) in seeds.iter().zip(&many) {
        let one = dlm.gafs_vjp(&flight(), &m, &K, s).unwrap();
        let (a, b) = (flat(&one.modes), flat(&g.modes));
        let scale = a.iter().fold(0.0f64, |x, v| x.max(v.abs()));
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() <= 1e-13 * scale, "{x} {y}");
        }
        let gs = one.geometry.iter().fold(0.0f64, |x, v| x.max(v.abs()));
        for (x, y) in one.geometry.iter().zip(&g.geometry) {
            assert!((x - y).abs() <= 1e-12 * gs, "{x} {y}");
        }
    }
}

/// No seeds, no gradients: the many-seed reverse mode returns an empty list (it used to index
/// the first seed's adjoint quantities and panic).
#[test]
fn many_seeds_with_no_seed_is_empty() {
    let dlm = Dlm::new(vec![wing()], Symmetry::Symmetric).unwrap();
    let m = modes(&dlm, 3, 5);
    let many = dlm.gafs_vjp_many(&flight(), &m, &K, &[]).unwrap();
    assert!(many.is_empty());
}

/// The box forces are what the GAFs weigh: Σ_j n_j·u_m(dp_j) F_j,col = Q[m][col] for every mode
/// and the gust column at every k (1e-12 of the table's largest entry): the loads a structural
/// model takes to its grids are the ones its equations of motion saw.
#[test]
fn box_forces_weighted_by_the_modes_are_the_gafs() {
    let dlm = Dlm::new(vec![wing()], Symmetry::Symmetric).unwrap();
    let m = modes(&dlm, 3, 7);
    let t = dlm.gafs(&flight(), &m, &K).unwrap();
    let f = dlm.box_forces(&flight(), &m, &K).unwrap();
    let n = dlm.n_boxes();
    let normals = &dlm.surface().normals;
    for ik in 0..K.len() {
        let scale = t.q_ss[ik]
            .iter()
            .flatten()
            .chain(&t.q_gs[ik])
            .fold(0.0f64, |a, v| a.max(v.norm()));
        for mode in 0..3 {
            for col in 0..4 {
                let sum: C = (0..n)
                    .map(|j| {
                        let (u, nn) = (m.disp[mode][n + j], normals[n + j]);
                        f[ik][j][col] * (u[0] * nn[0] + u[1] * nn[1] + u[2] * nn[2])
                    })
                    .sum();
                let want = if col < 3 {
                    t.q_ss[ik][mode][col]
                } else {
                    t.q_gs[ik][mode]
                };
                assert!(
                    (sum - want).norm() < 1e-12 * scale,
                    "k {} m {mode} c {col}",
                    K[ik]
                );
            }
        }
    }
}

/// The box forces' reverse mode against their forward products (a dot-product test): for
/// random seeds F̄ and a random direction δu of the shapes, Re Σ conj(F̄)·(F(u + δu) − F(u)) —
/// exact, the forces being linear in the shapes — equals ⟨ū, δu⟩ to 1e-12 of the pairing's
/// size, at three k (k = 0 included).
#[test]
fn box_forces_reverse_matches_forward() {
    let dlm = Dlm::new(vec![wing()], Symmetry::Symmetric).unwrap();
    let m = modes(&dlm, 3, 7);
    let dir = modes(&dlm, 3, 11);
    let n = dlm.n_boxes();
    let r = rand_vec(2 * K.len() * n * 4, 5);
    let seeds: Vec<Vec<Vec<C>>> = (0..K.len())
        .map(|ik| {
            (0..n)
                .map(|j| {
                    (0..4)
                        .map(|c| {
                            let i = 2 * ((ik * n + j) * 4 + c);
                            C::new(r[i], r[i + 1])
                        })
                        .collect()
                })
                .collect()
        })
        .collect();
    let f0 = dlm.box_forces(&flight(), &m, &K).unwrap();
    // the forces of the direction alone (linear: F(u + δu) − F(u) = F(δu) but for the gust
    // column, which the seeds' modal part does not see)
    let f1 = dlm.box_forces(&flight(), &dir, &K).unwrap();
    let mut forward = 0.0;
    let mut size = 0.0;
    for ik in 0..K.len() {
        for j in 0..n {
            for c in 0..3 {
                let t = (seeds[ik][j][c].conj() * f1[ik][j][c]).re;
                forward += t;
                size += t.abs();
            }
        }
    }
    assert_eq!(f0.len(), K.len());
    let bar = dlm.box_forces_vjp(&flight(), &m, &K, &seeds).unwrap();
    let reverse: f64 = bar.values().zip(dir.values()).map(|(a, b)| a * b).sum();
    assert!(
        (forward - reverse).abs() < 1e-12 * size,
        "forward {forward} reverse {reverse}"
    );
}
