//! p-k flutter of the classic 2-DOF typical section with Theodorsen aerodynamics.

use super::*;
use gustkit_testkit::bessel::theodorsen;
use num_complex::Complex64 as C;
use std::f64::consts::PI;

/// Hodges & Pierce's typical section: a = −1/5, x_α = 1/10, μ = 20, r_α² = 6/25, ω_h/ω_α = 2/5,
/// b = 1, ω_α = 1, ρ = 1.
struct AirfoilShape {
    m: [[f64; 2]; 2],
    k: [[f64; 2]; 2],
    a: f64,
}

fn section() -> AirfoilShape {
    let (a, xa, mu, r2, sigma): (f64, f64, f64, f64, f64) = (-0.2, 0.1, 20.0, 0.24, 0.4);
    let m = mu * PI; // ρ = b = 1
    AirfoilShape {
        m: [[m, m * xa], [m * xa, m * r2]],
        k: [[m * sigma * sigma, 0.0], [0.0, m * r2]],
        a,
    }
}

/// Theodorsen generalized forces / q for η = (h/b, α), h down, b = 1.
fn theodorsen_q(k: f64, a: f64) -> [[C; 2]; 2] {
    let (cr, ci) = if k == 0.0 { (1.0, 0.0) } else { theodorsen(k) };
    let c = C::new(cr, ci);
    let i = C::new(0.0, 1.0);
    let l1 = 2.0 * PI * (-k * k) + 4.0 * PI * c * (i * k);
    let l2 = 2.0 * PI * (i * k + a * k * k) + 4.0 * PI * c * (1.0 + i * k * (0.5 - a));
    let m1 = 2.0 * PI * (-a * k * k) + 4.0 * PI * (a + 0.5) * c * (i * k);
    let m2 = 2.0 * PI * (-(0.5 - a) * i * k + (0.125 + a * a) * k * k)
        + 4.0 * PI * (a + 0.5) * c * (1.0 + i * k * (0.5 - a));
    [[-l1, -l2], [m1, m2]]
}

/// Mass-normalized modes Φ of (K, M) (2 × 2) and their ω_n.
fn modes(s: &AirfoilShape) -> ([[f64; 2]; 2], [f64; 2]) {
    // det(K − λ M) = 0
    let (m, k) = (s.m, s.k);
    let a = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let b = -(k[0][0] * m[1][1] + k[1][1] * m[0][0] - k[0][1] * m[1][0] - k[1][0] * m[0][1]);
    let c = k[0][0] * k[1][1] - k[0][1] * k[1][0];
    let d = (b * b - 4.0 * a * c).sqrt();
    let lam = [(-b - d) / (2.0 * a), (-b + d) / (2.0 * a)];
    let mut phi = [[0.0; 2]; 2];
    for (j, l) in lam.iter().enumerate() {
        // (k00 − l m00) x0 + (k01 − l m01) x1 = 0
        let v = [-(k[0][1] - l * m[0][1]), k[0][0] - l * m[0][0]];
        let nrm = (0..2)
            .map(|r| (0..2).map(|q| v[r] * m[r][q] * v[q]).sum::<f64>())
            .sum::<f64>()
            .sqrt();
        phi[0][j] = v[0] / nrm;
        phi[1][j] = v[1] / nrm;
    }
    (phi, [lam[0].sqrt(), lam[1].sqrt()])
}

fn table(s: &AirfoilShape, ks: &[f64]) -> (GafTable, [f64; 2]) {
    let (phi, wn) = modes(s);
    let modal = |q: [[C; 2]; 2]| -> Vec<Vec<C>> {
        (0..2)
            .map(|i| {
                (0..2)
                    .map(|j| {
                        (0..2)
                            .map(|r| (0..2).map(|c| phi[r][i] * q[r][c] * phi[c][j]).sum::<C>())
                            .sum()
                    })
                    .collect()
            })
            .collect()
    };
    let t = GafTable {
        mach: 0.0,
        b_ref: 1.0,
        x_ref: 0.0,
        k: ks.to_vec(),
        q_ss: ks.iter().map(|&k| modal(theodorsen_q(k, s.a))).collect(),
        q_gs: ks.iter().map(|_| vec![C::new(0.0, 0.0); 2]).collect(),
    };
    (t, wn)
}

/// Independent reference by the k-method with exact C(k): (M + ½ρ(b/k)² Q) η = λ K η,
/// λ = (1 + i g)/ω²; flutter where g of the critical branch crosses zero (bisection in k).
fn k_method_flutter(s: &AirfoilShape) -> (f64, f64) {
    let g_of = |k: f64| -> Vec<(f64, f64)> {
        let q = theodorsen_q(k, s.a);
        let f = 0.5 * (1.0 / k).powi(2);
        let am = |r: usize, c: usize| C::new(s.m[r][c], 0.0) + q[r][c] * f;
        let (k0, k1) = (s.k[0][0], s.k[1][1]);
        let qa = k0 * k1;
        let qb = -(am(0, 0) * k1 + am(1, 1) * k0);
        let qc = am(0, 0) * am(1, 1) - am(0, 1) * am(1, 0);
        let d = (qb * qb - 4.0 * qa * qc).sqrt();
        [(-qb + d) / (2.0 * qa), (-qb - d) / (2.0 * qa)]
            .iter()
            .map(|l| (l.im / l.re, 1.0 / l.re.sqrt()))
            .collect()
    };
    // scan k downward (speed upward) for a sign change of g on either branch
    let ks: Vec<f64> = (1..400).map(|i| 2.0 - i as f64 * 0.0049).collect();
    for w in ks.windows(2) {
        for br in 0..2 {
            let (g0, g1) = (g_of(w[0])[br].0, g_of(w[1])[br].0);
            if g0 < 0.0 && g1 >= 0.0 {
                let (mut lo, mut hi) = (w[1], w[0]);
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if g_of(mid)[br].0 >= 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                let k = 0.5 * (lo + hi);
                let omega = g_of(k)[br].1;
                return (omega / k, omega);
            }
        }
    }
    panic!("no flutter found by the k-method");
}

/// The section's GAF table at 41 reduced frequencies on [0, 2] and its natural frequencies.
fn section_table(s: &AirfoilShape) -> (GafTable, [f64; 2]) {
    let ks: Vec<f64> = (0..=40).map(|i| 0.05 * i as f64).collect();
    table(s, &ks)
}

/// The section's p-k problem: no structural damping, ρ = 1.
fn section_problem(t: &GafTable, wn: [f64; 2]) -> PkProblem<'_> {
    PkProblem::from_parts(wn.to_vec(), 0.0, t, 1.0)
}

/// The p-k flutter speed and frequency equal the k-method's at the neutral point (both methods are
/// exact for harmonic motion there) to the accuracy of the GAF spline (41 frequencies on [0, 2]):
/// 1e-4. Hodges & Pierce quote U_F/(b ω_α) ≈ 2.17 for this section.
#[test]
fn typical_section_flutter_matches_k_method() {
    let s = section();
    let (t, wn) = section_table(&s);
    let pk = section_problem(&t, wn);
    let v: Vec<f64> = (1..=60).map(|i| 0.05 * i as f64).collect();
    let r = pk.sweep(&v).unwrap();
    let (vf, wf) = k_method_flutter(&s);
    let vpk = r.flutter_speed_m_s.expect("flutter in range");
    let fpk = r.flutter_frequency_hz.unwrap() * 2.0 * PI;
    println!("p-k: V_F = {vpk:.5}, ω_F = {fpk:.5}; k-method: V_F = {vf:.5}, ω_F = {wf:.5}");
    assert!((vpk - vf).abs() < 1e-4 * vf, "{vpk} vs {vf}");
    assert!((fpk - wf).abs() < 1e-4 * wf, "{fpk} vs {wf}");
    assert!((vf - 2.17).abs() < 0.05 * 2.17, "{vf}");
    // below flutter all modes are damped, above it one is not
    for c in &r.curves {
        for (vv, g) in c.velocity_m_s.iter().zip(&c.damping_g) {
            if *vv < 0.95 * vpk {
                assert!(*g < 0.0, "mode {} V {vv} g {g}", c.mode);
            }
        }
    }
}

/// Every p-k branch keeps its own root: at every speed no two modes report the same (g, f), also
/// above the coalescence of the typical section's bending and torsion (the branch merging seen
/// before the roots were assigned jointly). The bending branch turns aperiodic and its real root
/// crosses zero at the static divergence speed U_D = b ω_α √(μ r_α² / (1 + 2a)) = √8 (steady
/// thin-airfoil lift; exact at p = 0), found here by linear interpolation between speeds 0.05
/// apart: 1e-3.
#[test]
fn branches_never_share_a_root() {
    let s = section();
    let (t, wn) = section_table(&s);
    let pk = section_problem(&t, wn);
    let v: Vec<f64> = (1..=80).map(|i| 0.05 * i as f64).collect();
    let r = pk.sweep(&v).unwrap();
    for iv in 0..v.len() {
        let (a, b) = (&r.curves[0], &r.curves[1]);
        let da = (a.damping_g[iv] - b.damping_g[iv]).abs();
        let df = (a.frequency_hz[iv] - b.frequency_hz[iv]).abs();
        assert!(da + df > 1e-6, "V {}: modes 1 and 2 share a root", v[iv]);
    }
    let bend = &r.curves[0];
    let iv = (1..v.len())
        .find(|&i| bend.aperiodic[i] && bend.damping_g[i - 1] < 0.0 && bend.damping_g[i] >= 0.0)
        .expect("an aperiodic root crosses zero");
    let (g0, g1) = (bend.damping_g[iv - 1], bend.damping_g[iv]);
    let v_div = v[iv - 1] + (v[iv] - v[iv - 1]) * (-g0) / (g1 - g0);
    let u_d = (20.0f64 * 0.24 / (1.0 - 0.4)).sqrt();
    println!("divergence: p-k {v_div:.5}, theory {u_d:.5}");
    assert!((v_div - u_d).abs() < 1e-3 * u_d, "{v_div} vs {u_d}");
    assert_eq!(bend.frequency_hz[iv], 0.0);
}

/// Two roots that trade places in the all-modes assignment as k crosses 1.14: below it the root
/// of frequency ≈ 1.162 is nearer the previous speed's root, above it the one of ≈ 1.12, so
/// φ(k) jumps across the diagonal and the assigned-root iteration cycles (the failure met in the
/// LFD optimization, mode 6 cycling between k 1.12 and 1.162). After FREEZE_AFTER iterations the
/// mode keeps its branch, and the fixed point of that branch is found to round-off.
#[test]
fn a_mode_cycling_between_two_branches_settles_on_one() {
    // b = v = 1, so k = Im p. Branch A: Im p = 1.12 + 0.3 (k − 1.14), fixed point 0.778/0.7;
    // branch B: Im p = 1.162 − 0.2 (k − 1.14), fixed point 1.162 + 0.228 … (1.39 / 1.2)
    let k_a = (1.12 - 0.3 * 1.14) / 0.7;
    let k_b = (1.162 + 0.2 * 1.14) / 1.2;
    let branches = |k: f64| {
        let d = k - 1.14;
        vec![
            Complex64::new(-0.05 + 2.0 * d, 1.12 + 0.3 * d),
            Complex64::new(-0.05 - 2.0 * d, 1.162 - 0.2 * d),
        ]
    };
    let refs = [Complex64::new(0.0, 1.14)];
    // the branch assignment does jump: below 1.14 B is nearer the reference, above it A
    let nearest = |k: f64| assign_roots(&refs, &branches(k))[0];
    assert_eq!((nearest(1.12), nearest(1.16)), (1, 0));
    let mut calls = 0;
    let root = track_root(0, 1.0, 1.0, 2.0, &refs, |k| {
        calls += 1;
        Ok(branches(k))
    })
    .expect("the frozen branch converges");
    assert!(
        calls > FREEZE_AFTER,
        "the assigned-root iteration cannot converge on this φ, yet it stopped after {calls}"
    );
    // a consistent root: its own k is the k it was computed at, on one of the two branches
    let on_a = (root.k - k_a).abs();
    let on_b = (root.k - k_b).abs();
    assert!(
        on_a.min(on_b) <= 1e-12,
        "k = {} (branch fixed points {k_a}, {k_b})",
        root.k
    );
    assert!((root.p.im - root.k).abs() <= 1e-12);
    assert_eq!(root.g, 2.0 * root.p.re / root.p.im);
}

/// A mode whose assignment never changes converges before the fallback: the same φ's branch A
/// alone, as the ordinary case.
#[test]
fn a_single_branch_converges_before_the_fallback() {
    let refs = [Complex64::new(0.0, 1.14)];
    let mut calls = 0;
    let root = track_root(0, 1.0, 1.0, 2.0, &refs, |k| {
        calls += 1;
        Ok(vec![Complex64::new(-0.05, 1.12 + 0.3 * (k - 1.14))])
    })
    .unwrap();
    assert!(calls < 10, "{calls} eigenvalue solves");
    assert!((root.k - (1.12 - 0.3 * 1.14) / 0.7).abs() <= 1e-13);
}

/// Beyond the table the GAFs follow the high-frequency asymptote Q ≈ A₀ + i k A₁ − k² A₂ (real
/// A's: apparent stiffness, damping and mass, Roger's quasi-steady form): a table sampled from
/// exactly that form (which the not-a-knot spline reproduces inside it) is continued exactly, to
/// round-off, up to k = 8 times the table's last, with the slopes d/dk equal to central differences of the values (step 1e-5,
/// error O(h²) ≈ 1e-10 of the entries).
#[test]
fn gafs_beyond_the_table_follow_the_quadratic_asymptote() {
    let (a0, a1, a2) = (-1.3, 0.7, 0.45);
    let exact = |k: f64| C::new(a0 - k * k * a2, k * a1);
    let ks = [0.0, 0.1, 0.3, 0.6, 1.0, 1.5, 2.0];
    let t = GafTable {
        mach: 0.0,
        b_ref: 1.0,
        x_ref: 0.0,
        k: ks.to_vec(),
        q_ss: ks.iter().map(|&k| vec![vec![exact(k)]]).collect(),
        q_gs: ks.iter().map(|_| vec![C::new(0.0, 0.0)]).collect(),
    };
    let pk = PkProblem::from_parts(vec![10.0], 0.0, &t, 1.0);
    let value = |k: f64| {
        let w = pk.aero_weights(k).unwrap();
        let sum = |w: &[f64]| -> C { w.iter().zip(&t.q_ss).map(|(w, q)| q[0][0] * *w).sum() };
        (
            sum(&w.re).re,
            sum(&w.im).im,
            sum(&w.d_re).re,
            sum(&w.d_im).im,
        )
    };
    for k in [0.5, 1.7, 2.0, 2.5, 4.0, 9.0, 16.0] {
        let (re, im, d_re, d_im) = value(k);
        let q = exact(k);
        let scale = 1.0 + k * k;
        assert!(
            (re - q.re).abs() < 1e-12 * scale,
            "k {k}: Re {re} vs {}",
            q.re
        );
        assert!(
            (im - q.im).abs() < 1e-12 * scale,
            "k {k}: Im {im} vs {}",
            q.im
        );
        let h = 1e-5;
        let (rp, ip, _, _) = value(k + h);
        let (rm, im_m, _, _) = value(k - h);
        assert!(
            (d_re - (rp - rm) / (2.0 * h)).abs() < 1e-8 * scale,
            "k {k}: dRe"
        );
        assert!(
            (d_im - (ip - im_m) / (2.0 * h)).abs() < 1e-8 * scale,
            "k {k}: dIm"
        );
    }
}
