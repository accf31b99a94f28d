//! Gust response against closed forms, grid convergence, and its reverse mode.

use super::*;
use gustkit_testkit::rand_vec;
use num_complex::Complex64 as C;

fn constant_table(k: &[f64], q_ss: Vec<Vec<C>>, q_gs: Vec<C>) -> GafTable {
    GafTable {
        mach: 0.5,
        b_ref: 0.01,
        x_ref: 0.0,
        k: k.to_vec(),
        q_ss: vec![q_ss; k.len()],
        q_gs: vec![q_gs; k.len()],
    }
}

/// One mode, no motion-dependent aerodynamics, nearly white forcing (Dryden with V/L ≫ ω_n):
/// σ² = π S0 / (4 ζ ω_n³) with one-sided S0 = σ_w² L/(πV) (q Q_gs / U = 1 so H = 1/A). The
/// log grid reproduces it to 1e-4 and the RMS converges as the grid is refined.
#[test]
fn single_mode_white_noise_closed_form() {
    let (wn, zeta, v, l, sigma): (f64, f64, f64, f64, f64) = (10.0, 0.02, 100.0, 0.01, 2.0);
    let q_inf = 1.0;
    let k: Vec<f64> = (0..6).map(|i| 400.0 * i as f64).collect();
    let table = constant_table(&k, vec![vec![C::new(0.0, 0.0)]], vec![C::new(v, 0.0)]);
    let turb = Turbulence::Dryden {
        sigma_w_m_s: sigma,
        scale_length_m: l,
    };
    let s0 = sigma * sigma * l / (std::f64::consts::PI * v);
    let exact = (std::f64::consts::PI * s0 / (4.0 * zeta * wn.powi(3))).sqrt();
    let mut prev = f64::INFINITY;
    for n in [2000, 8000, 32000] {
        let p = GustProblem {
            omega_n: vec![wn],
            damping_ratio: zeta,
            table: &table,
            q_inf,
            velocity: v,
            turbulence: turb,
            grid: FrequencyGrid::log(1e-3, 1e7, n).unwrap(),
            outputs: vec![vec![1.0]],
            max_tail: 1e-3,
            residual: None,
        };
        let r = solve(&p).unwrap();
        let err = (r.rms[0] - exact).abs() / exact;
        println!("n {n}: rms {} exact {exact} rel err {err:.2e}", r.rms[0]);
        assert!(err < prev);
        prev = err;
        // zero-crossing rate of a lightly damped mode: close to ω_n / 2π
        assert!((r.n0[0] - wn / (2.0 * std::f64::consts::PI)).abs() < 0.05 * wn);
    }
    assert!(prev < 1e-4, "{prev}");
}

fn problem_parts() -> (GafTable, Vec<f64>) {
    let k = [0.0, 0.05, 0.15, 0.3, 0.6, 1.0, 2.0];
    let r = rand_vec(2 * k.len() * 12, 3);
    let mut it = r.chunks(2).map(|c| C::new(c[0], c[1]));
    let mut t = constant_table(
        &k,
        vec![vec![C::new(0.0, 0.0); 3]; 3],
        vec![C::new(0.0, 0.0); 3],
    );
    for ik in 0..k.len() {
        for m in 0..3 {
            for n in 0..3 {
                t.q_ss[ik][m][n] = it.next().unwrap() * 0.3;
            }
            t.q_gs[ik][m] = it.next().unwrap();
        }
    }
    t.b_ref = 0.3;
    (t, vec![20.0, 60.0, 110.0])
}

/// The three-mode test problem on a log grid of `points` frequencies up to 999 rad/s.
fn problem<'a>(
    table: &'a GafTable,
    wn: &[f64],
    points: usize,
    outputs: Vec<Vec<f64>>,
) -> GustProblem<'a> {
    GustProblem {
        omega_n: wn.to_vec(),
        damping_ratio: 0.03,
        table,
        q_inf: 2000.0,
        velocity: 150.0,
        turbulence: Turbulence::Dryden {
            sigma_w_m_s: 1.0,
            scale_length_m: 200.0,
        },
        grid: FrequencyGrid::log(0.01, 999.0, points).unwrap(),
        outputs,
        max_tail: 1e-2,
        residual: None,
    }
}

/// The three-mode table and natural frequencies moved by s along (dt, dλ): Q + s dQ and
/// ω_n = √(ω_n² + s dλ).
fn moved(table: &GafTable, wn: &[f64], dt: &GafTable, dl: &[f64], s: f64) -> (GafTable, Vec<f64>) {
    let mut t = table.clone();
    for ik in 0..t.k.len() {
        for m in 0..3 {
            for n in 0..3 {
                t.q_ss[ik][m][n] += dt.q_ss[ik][m][n] * s;
            }
            t.q_gs[ik][m] += dt.q_gs[ik][m] * s;
        }
    }
    let omega_n = wn
        .iter()
        .zip(dl)
        .map(|(w, d)| (w * w + s * d).sqrt())
        .collect();
    (t, omega_n)
}

/// Dot-product test of the RMS reverse mode against its forward mode, in all inputs at once
/// (GAF table, ω_n², S vectors).
#[test]
fn rms_vjp_dot_product_test() {
    let (table, wn) = problem_parts();
    let p = problem(
        &table,
        &wn,
        400,
        vec![vec![1.0, -0.5, 0.3], vec![0.2, 0.9, -0.4]],
    );
    let r = solve(&p).unwrap();
    let rms_bar = [0.7, -1.3];
    let g = rms_vjp(&p, &r, &rms_bar).unwrap();
    let mut dt = table.clone();
    let rv = rand_vec(2 * table.k.len() * 12, 11);
    let mut it = rv.chunks(2).map(|c| C::new(c[0], c[1]));
    let mut pairing = 0.0;
    for ik in 0..table.k.len() {
        for m in 0..3 {
            for n in 0..3 {
                dt.q_ss[ik][m][n] = it.next().unwrap();
                pairing += (g.table.q_ss[ik][m][n].conj() * dt.q_ss[ik][m][n]).re;
            }
            dt.q_gs[ik][m] = it.next().unwrap();
            pairing += (g.table.q_gs[ik][m].conj() * dt.q_gs[ik][m]).re;
        }
    }
    let dl = rand_vec(3, 12);
    let ds = vec![rand_vec(3, 13), rand_vec(3, 14)];
    pairing += g.lambda.iter().zip(&dl).map(|(a, b)| a * b).sum::<f64>();
    for y in 0..2 {
        pairing += g.outputs[y]
            .iter()
            .zip(&ds[y])
            .map(|(a, b)| a * b)
            .sum::<f64>();
    }
    let d = rms_jvp(&p, &r, &dt, &dl, &ds, None).unwrap();
    let forward = rms_bar[0] * d[0] + rms_bar[1] * d[1];
    println!("forward {forward:.15e} reverse {pairing:.15e}");
    assert!((forward - pairing).abs() < 1e-11 * forward.abs());
    // and the forward mode against a finite difference of the RMS along the same direction
    let h = 1e-6;
    let shifted = |s: f64| {
        let (t, wn2) = moved(&table, &wn, &dt, &dl, s);
        let outs: Vec<Vec<f64>> = p
            .outputs
            .iter()
            .zip(&ds)
            .map(|(o, d)| o.iter().zip(d).map(|(a, b)| a + s * b).collect())
            .collect();
        let pp = GustProblem {
            table: &t,
            omega_n: wn2,
            outputs: outs,
            ..p.clone()
        };
        let rr = solve(&pp).unwrap();
        rms_bar[0] * rr.rms[0] + rms_bar[1] * rr.rms[1]
    };
    let fd = (shifted(h) - shifted(-h)) / (2.0 * h);
    assert!(
        (fd - forward).abs() < 1e-6 * forward.abs(),
        "{fd} vs {forward}"
    );
}

/// Random residual rows for the three-mode problem's table and two outputs.
fn random_rows(table: &GafTable, seed: u64) -> ResidualGafs {
    let nk = table.k.len();
    let v = rand_vec(2 * nk * 2 * 4, seed);
    let mut it = v.chunks(2).map(|c| C::new(c[0], c[1]) * 1e-4);
    let mut r = ResidualGafs::zeros(nk, 2, 3);
    for i in 0..nk {
        for y in 0..2 {
            for m in 0..3 {
                r.q_ws[i][y][m] = it.next().unwrap();
            }
            r.q_wg[i][y] = it.next().unwrap();
        }
    }
    r
}

/// With residual rows (mode acceleration) the reverse mode still pairs with the forward mode in
/// every input, the rows included, and the forward mode with a central difference; rows of zeros
/// give the mode-displacement response bit for bit.
#[test]
fn residual_rows_dot_product_test() {
    let (table, wn) = problem_parts();
    let outs = vec![vec![1.0, -0.5, 0.3], vec![0.2, 0.9, -0.4]];
    let rows = random_rows(&table, 21);
    let mut p = problem(&table, &wn, 400, outs.clone());
    let plain = solve(&p).unwrap();
    let zeros = ResidualGafs::zeros(table.k.len(), 2, 3);
    p.residual = Some(&zeros);
    assert_eq!(solve(&p).unwrap().rms, plain.rms);
    p.residual = Some(&rows);
    let r = solve(&p).unwrap();
    // the rows change the answer by a fair amount (the test would not see a dropped term)
    assert!(
        (r.rms[1] - plain.rms[1]).abs() > 0.05 * plain.rms[1],
        "{:?} {:?}",
        r.rms,
        plain.rms
    );
    let rms_bar = [0.7, -1.3];
    let g = rms_vjp(&p, &r, &rms_bar).unwrap();
    let g_rows = g.residual.as_ref().expect("seeds on the rows");
    let mut dt = table.clone();
    let rv = rand_vec(2 * table.k.len() * 12, 31);
    let mut it = rv.chunks(2).map(|c| C::new(c[0], c[1]));
    let mut pairing = 0.0;
    for ik in 0..table.k.len() {
        for m in 0..3 {
            for n in 0..3 {
                dt.q_ss[ik][m][n] = it.next().unwrap();
                pairing += (g.table.q_ss[ik][m][n].conj() * dt.q_ss[ik][m][n]).re;
            }
            dt.q_gs[ik][m] = it.next().unwrap();
            pairing += (g.table.q_gs[ik][m].conj() * dt.q_gs[ik][m]).re;
        }
    }
    let dr = random_rows(&table, 32);
    for ik in 0..table.k.len() {
        for y in 0..2 {
            for m in 0..3 {
                pairing += (g_rows.q_ws[ik][y][m].conj() * dr.q_ws[ik][y][m]).re;
            }
            pairing += (g_rows.q_wg[ik][y].conj() * dr.q_wg[ik][y]).re;
        }
    }
    let dl = rand_vec(3, 33);
    let ds = vec![rand_vec(3, 34), rand_vec(3, 35)];
    pairing += g.lambda.iter().zip(&dl).map(|(a, b)| a * b).sum::<f64>();
    for y in 0..2 {
        pairing += g.outputs[y]
            .iter()
            .zip(&ds[y])
            .map(|(a, b)| a * b)
            .sum::<f64>();
    }
    let d = rms_jvp(&p, &r, &dt, &dl, &ds, Some(&dr)).unwrap();
    let forward = rms_bar[0] * d[0] + rms_bar[1] * d[1];
    println!("forward {forward:.15e} reverse {pairing:.15e}");
    assert!((forward - pairing).abs() < 1e-11 * forward.abs());
    // the rows' part of the forward mode against a central difference along the rows alone
    let h = 1e-5;
    let shifted = |s: f64| {
        let mut rr = rows.clone();
        for ik in 0..table.k.len() {
            for y in 0..2 {
                for m in 0..3 {
                    rr.q_ws[ik][y][m] += dr.q_ws[ik][y][m] * s;
                }
                rr.q_wg[ik][y] += dr.q_wg[ik][y] * s;
            }
        }
        let pp = GustProblem {
            residual: Some(&rr),
            ..p.clone()
        };
        let out = solve(&pp).unwrap();
        rms_bar[0] * out.rms[0] + rms_bar[1] * out.rms[1]
    };
    let fd = (shifted(h) - shifted(-h)) / (2.0 * h);
    let zero_t = GafTable {
        q_ss: vec![vec![vec![C::new(0.0, 0.0); 3]; 3]; table.k.len()],
        q_gs: vec![vec![C::new(0.0, 0.0); 3]; table.k.len()],
        ..table.clone()
    };
    let d_rows = rms_jvp(
        &p,
        &r,
        &zero_t,
        &[0.0; 3],
        &[vec![0.0; 3], vec![0.0; 3]],
        Some(&dr),
    )
    .unwrap();
    let forward_rows = rms_bar[0] * d_rows[0] + rms_bar[1] * d_rows[1];
    assert!(
        (fd - forward_rows).abs() < 1e-6 * forward_rows.abs(),
        "{fd} vs {forward_rows}"
    );
}

/// Splitting a table of modes and residual shapes and joining the pieces gives the table back
/// where the residual shapes' own columns are zero.
#[test]
fn residual_split_and_join_are_inverse() {
    let (table, _) = problem_parts();
    let (modal, rows) = ResidualGafs::split(&table, 2);
    assert_eq!(modal.n_modes(), 2);
    assert_eq!(rows.q_wg[3][0], table.q_gs[3][2]);
    assert_eq!(rows.q_ws[3][0][1], table.q_ss[3][2][1]);
    let back = ResidualGafs::join(&modal, &rows);
    for ik in 0..table.k.len() {
        for a in 0..3 {
            for b in 0..3 {
                let want = if b == 2 {
                    C::new(0.0, 0.0)
                } else {
                    table.q_ss[ik][a][b]
                };
                assert_eq!(back.q_ss[ik][a][b], want);
            }
        }
        assert_eq!(back.q_gs[ik], table.q_gs[ik]);
    }
}

#[test]
fn bad_input_is_rejected() {
    let (table, wn) = problem_parts();
    let base = problem(&table, &wn, 100, vec![vec![1.0, 0.0, 0.0]]);
    let mut p = base.clone();
    p.damping_ratio = -0.1;
    assert!(solve(&p).unwrap_err().to_string().contains("damping_ratio"));
    let mut p = base.clone();
    p.turbulence = Turbulence::Dryden {
        sigma_w_m_s: -1.0,
        scale_length_m: 200.0,
    };
    assert!(solve(&p).unwrap_err().to_string().contains("sigma_w_m_s"));
    let mut p = base.clone();
    p.grid = FrequencyGrid::log(0.01, 1.0, 100).unwrap();
    let e = solve(&p).unwrap_err();
    assert!(
        e.to_string().contains("gust.max_tail") && e.to_string().contains("k ≈"),
        "{e}"
    );
    // the k the error names is the one that passes: the tail beyond it is the limit (to the
    // bisection's 1e-12), beyond 0.99 of it more than the limit
    let GustError::GridTooShort { k_needed, .. } = e else {
        panic!("{e}")
    };
    let omega = k_needed * p.velocity / p.table.b_ref;
    let tail = |w: f64| p.turbulence.tail_fraction(w, p.velocity);
    assert!(
        (tail(omega) / p.max_tail - 1.0).abs() < 1e-9,
        "{}",
        tail(omega)
    );
    assert!(tail(0.99 * omega) > p.max_tail);
    let mut p = base.clone();
    p.grid = FrequencyGrid::log(0.01, 2000.0, 100).unwrap();
    assert!(solve(&p)
        .unwrap_err()
        .to_string()
        .contains("outside the GAF table"));
    assert!(FrequencyGrid::log(0.0, 1.0, 10).is_err());
}

/// Von Kármán turbulence beyond the grid: with the grid ending at 250 rad/s (2.3 × the highest
/// natural frequency) the gust spectrum still holds more than the 1e-3 limit of σ_w² beyond it,
/// but the response, falling with the inertia, does not. The bound |H_y(ω_max)|² ∫_{ω_max}^∞ Φ_w
/// must lie above the variance that the grid to 1000 rad/s finds between 250 and 1000 rad/s
/// (plus that grid's own bounded tail), for every output, and under the limit; a grid ending
/// below 1.5 × the highest natural frequency falls back to the gust spectrum's own tail.
#[test]
fn response_tail_bound_holds_beyond_the_grid() {
    let (table, wn) = problem_parts();
    let outputs = vec![vec![1.0, -0.5, 0.3], vec![0.2, 0.9, -0.4]];
    let mut p = problem(&table, &wn, 4000, outputs.clone());
    p.turbulence = Turbulence::VonKarman {
        sigma_w_m_s: 1.0,
        scale_length_m: 762.0,
    };
    p.max_tail = 1e-3;
    let short_end = 250.0;
    let gust_tail = p.turbulence.tail_fraction(short_end, p.velocity);
    assert!(gust_tail > p.max_tail, "{gust_tail}");
    let mut short = p.clone();
    short.grid = FrequencyGrid::log(0.01, short_end, 3000).unwrap();
    let rs = solve(&short).unwrap();
    let mut long = p.clone();
    long.grid = FrequencyGrid::log(0.01, 999.0, 4000).unwrap();
    let rl = solve(&long).unwrap();
    for y in 0..outputs.len() {
        let total: f64 = rl.psd[y]
            .iter()
            .zip(&long.grid.weights)
            .map(|(a, b)| a * b)
            .sum();
        let beyond: f64 = rl.psd[y]
            .iter()
            .zip(&long.grid.weights)
            .zip(&long.grid.omega)
            .filter(|(_, &w)| w >= short_end)
            .map(|((a, b), _)| a * b)
            .sum();
        let found = (beyond + rl.tail[y] * total) / total;
        println!(
            "output {y}: gust tail {gust_tail:.2e}, bound {:.2e}, found {found:.2e}",
            rs.tail[y]
        );
        assert!(found <= rs.tail[y] && rs.tail[y] <= p.max_tail);
    }
    // below 1.5 × the highest natural frequency (110 rad/s): the gust spectrum's tail decides
    let mut close = p.clone();
    close.grid = FrequencyGrid::log(0.01, 150.0, 2000).unwrap();
    let e = solve(&close).unwrap_err();
    assert!(e.to_string().contains("the gust variance"), "{e}");
}

/// The forward mode of η (`FrequencyResponse::eta_jvp`) along a random direction of the GAF
/// table and of ω_n² against central differences of η itself (step 1e-6, each perturbed
/// problem solved anew) at every grid frequency: largest error below 1e-7 of the largest |dη|
/// (measured 2.3e-10; truncation ≈ 1e-12 relative, round-off ≈ 1e-16 / 1e-6).
#[test]
fn eta_jvp_matches_differences() {
    let (table, wn) = problem_parts();
    let p = problem(&table, &wn, 120, vec![vec![1.0, 0.0, 0.0]]);
    let fr = frequency_response(&p).unwrap();
    let mut dt = table.clone();
    let rv = rand_vec(2 * table.k.len() * 12, 21);
    let mut it = rv.chunks(2).map(|c| C::new(c[0], c[1]));
    for ik in 0..table.k.len() {
        for m in 0..3 {
            for n in 0..3 {
                dt.q_ss[ik][m][n] = it.next().unwrap() * 0.3;
            }
            dt.q_gs[ik][m] = it.next().unwrap();
        }
    }
    let dl: Vec<f64> = rand_vec(3, 22).iter().map(|v| v * 400.0).collect();
    let d_eta = fr.eta_jvp(&p, &dt, &dl).unwrap();
    let eta_at = |s: f64| {
        let (t, omega_n) = moved(&table, &wn, &dt, &dl, s);
        let pp = GustProblem {
            table: &t,
            omega_n,
            ..p.clone()
        };
        frequency_response(&pp).unwrap().eta
    };
    let h = 1e-6;
    let (up, down) = (eta_at(h), eta_at(-h));
    let scale = d_eta.iter().flatten().fold(0.0f64, |m, v| m.max(v.norm()));
    let mut worst = 0.0f64;
    for j in 0..d_eta.len() {
        for m in 0..3 {
            let fd = (up[j][m] - down[j][m]) / (2.0 * h);
            worst = worst.max((d_eta[j][m] - fd).norm() / scale);
        }
    }
    println!("eta_jvp: largest error {worst:.2e} of max |dη| {scale:.3e}");
    assert!(worst < 1e-7, "{worst}");
    // the wrong sizes are refused
    assert!(fr.eta_jvp(&p, &dt, &dl[..2]).is_err());
}
