use super::*;
use crate::gust::discrete::analysis::{transient, TransientSettings};
use gustkit_core::theory::strip_gafs;
use gustkit_core::GafTable;
use gustkit_testkit::rand_vec;

/// A typical section (b = 1 m, μ = 20, r_α² = 0.25, elastic axis and centre of mass at
/// mid-chord) with plunge at 2 Hz and pitch at 5 Hz as two mass-normalized modes, Theodorsen and
/// Sears GAFs on 41 reduced frequencies up to 4.
fn section() -> (GafTable, Vec<f64>) {
    let (b, rho) = (1.0, 1.225);
    let m = 20.0 * rho * std::f64::consts::PI * b * b;
    let phi = [1.0 / m.sqrt(), 1.0 / (0.25 * m * b * b).sqrt()];
    let k: Vec<f64> = (0..=40).map(|i| 4.0 * (i as f64 / 40.0).powi(2)).collect();
    let (q_ss, q_gs) = k
        .iter()
        .map(|&kk| {
            let (ss, gs) = strip_gafs(kk, b, 0.0);
            (
                (0..2)
                    .map(|r| (0..2).map(|c| ss[r][c] * phi[r] * phi[c]).collect())
                    .collect(),
                (0..2).map(|r| gs[r] * phi[r]).collect(),
            )
        })
        .unzip();
    let table = GafTable {
        mach: 0.0,
        b_ref: b,
        x_ref: 0.0,
        k,
        q_ss,
        q_gs,
    };
    let two_pi = 2.0 * std::f64::consts::PI;
    (table, vec![two_pi * 2.0, two_pi * 5.0])
}

fn problem<'a>(table: &'a GafTable, omega_n: &[f64], outputs: Vec<Vec<f64>>) -> GustProblem<'a> {
    GustProblem::for_transient(
        omega_n.to_vec(),
        0.02,
        table,
        0.5 * 1.225 * 100.0 * 100.0,
        100.0,
        outputs,
    )
}

/// The KS peak of the plunge displacement and of the pitch acceleration over three 1-cos gusts:
/// its reverse mode against central differences of the forward evaluation along random
/// perturbations of the whole GAF table, of ω_n² and of the output vectors, on the grid fixed
/// at the unperturbed design, at steps of 1e-4, 1e-5 and 1e-6 of each input: every step agrees
/// to 1e-6 (6 digits; measured: about 1e-10 at 1e-5, truncation ∝ ρ ε² above and round-off below).
#[test]
fn peak_ks_reverse_mode_matches_central_differences() {
    let (table, wn) = section();
    let s_out = vec![vec![1.0, 0.0], vec![0.0, 1.0]];
    let gusts: Vec<GustProfile> = [10.0, 25.0, 40.0]
        .iter()
        .map(|&h| GustProfile::OneMinusCosine {
            gradient: h,
            amplitude: 5.0,
            velocity: 100.0,
        })
        .collect();
    let p = problem(&table, &wn, s_out.clone());
    let settings = TransientSettings {
        span: None,
        omega_max: 400.0,
        derivative: vec![0, 2],
        keep_histories: false,
        max_bytes: 1e9,
    };
    let (r, mut model) = transient(&p, &gusts, &settings).unwrap();
    let grid = r.grid.clone();
    for y in 0..2 {
        let scale = r.largest_abs(y);
        let ks = PeakKs::evaluate(&mut model, &gusts, y, scale);
        assert!(
            ks.ks >= ks.peak && ks.ks - ks.peak <= PEAK_KS_GAP * 1.0001,
            "{} {}",
            ks.ks,
            ks.peak
        );
        let g = ks.vjp(&mut model, &p, &gusts, 1.0).unwrap();
        // random directions: table (complex), ω_n², S
        let nk = table.k.len();
        let rv = rand_vec(nk * 12 + 2 + 4, 7 + y as u64);
        let mut dt = table.clone();
        let mut pred = 0.0;
        let mut it = rv.iter();
        for i in 0..nk {
            for a in 0..2 {
                for b in 0..2 {
                    let d = c64::new(*it.next().unwrap(), *it.next().unwrap())
                        * table.q_ss[i][a][b].norm().max(1e-3);
                    dt.q_ss[i][a][b] = d;
                    pred += (g.table.q_ss[i][a][b].conj() * d).re;
                }
                let d = c64::new(*it.next().unwrap(), *it.next().unwrap())
                    * table.q_gs[i][a].norm().max(1e-3);
                dt.q_gs[i][a] = d;
                pred += (g.table.q_gs[i][a].conj() * d).re;
            }
        }
        let dl: Vec<f64> = (0..2).map(|m| it.next().unwrap() * wn[m] * wn[m]).collect();
        pred += g.lambda.iter().zip(&dl).map(|(a, b)| a * b).sum::<f64>();
        let ds: Vec<Vec<f64>> = (0..2)
            .map(|_| (0..2).map(|_| *it.next().unwrap()).collect())
            .collect();
        pred += (0..2)
            .flat_map(|a| (0..2).map(move |b| (a, b)))
            .map(|(a, b)| g.outputs[a][b] * ds[a][b])
            .sum::<f64>();
        let ks_at = |eps: f64| -> f64 {
            let mut t = table.clone();
            for i in 0..nk {
                for a in 0..2 {
                    for b in 0..2 {
                        t.q_ss[i][a][b] += dt.q_ss[i][a][b] * eps;
                    }
                    t.q_gs[i][a] += dt.q_gs[i][a] * eps;
                }
            }
            let w: Vec<f64> = (0..2)
                .map(|m| (wn[m] * wn[m] + eps * dl[m]).sqrt())
                .collect();
            let so: Vec<Vec<f64>> = (0..2)
                .map(|a| (0..2).map(|b| s_out[a][b] + eps * ds[a][b]).collect())
                .collect();
            let q = problem(&t, &w, so);
            let mut m = TransientModel::new(&q, &[0, 2], grid.clone()).unwrap();
            PeakKs::evaluate(&mut m, &gusts, y, scale).ks
        };
        let errors: Vec<f64> = [1e-4, 1e-5, 1e-6]
            .iter()
            .map(|&e| ((ks_at(e) - ks_at(-e)) / (2.0 * e) - pred).abs() / pred.abs())
            .collect();
        eprintln!("output {y}: {errors:?}");
        assert!(
            errors.iter().all(|e| *e < 1e-6),
            "output {y}: relative differences {errors:?} (derivative {pred:.6e})"
        );
    }
}
