//! Paper Table 2: the LFD gust solution against the time domain, NACA 64A010 at M = 0.4, k = 0.5.
//! Two comparisons: (1) the LFD with s = iω against a least-squares Fourier fit of a nonlinear
//! BDF2 run with a tiny gust (the paper's: differences from the time step, the amplitude and the
//! transient); (2) the LFD with the BDF2 symbol for s against the linearized BDF2 march (the same
//! discrete problem: only the decayed transient and the solver tolerances remain).

use super::{build, CfdSpec};
use anyhow::Result;
use gustkit_cfd::gas::{primitive, GAMMA, NVAR};
use gustkit_cfd::lfd::{fourier_coefficient, HarmonicGust, LfdOperator, Symbol};
use gustkit_cfd::residual::{free_stream, Gust, State};
use gustkit_cfd::steady::SteadyParams;
use gustkit_cfd::unsteady::{fourier_fit, march_observed};
use gustkit_core::scalar::Dual;
use num_complex::Complex64 as C64;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// The LFD gust verification (key `lfd_gust` of a CFD study).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct LfdGustSpec {
    /// k = ω b / U, b the semichord.
    pub reduced_frequency: f64,
    /// Gust amplitude of the nonlinear run, in units of a∞ (the paper: 1e-5).
    pub amplitude_mach: f64,
    /// Nonlinear run: BDF2 steps a period, periods before the fit and periods fitted.
    pub steps_per_period: usize,
    pub transient_periods: usize,
    pub fit_periods: usize,
    /// Linearized BDF2 march: steps a period and periods (the last one is transformed).
    pub linear_steps_per_period: usize,
    pub linear_periods: usize,
    /// Where the state is compared: (x, y) in chords from the leading edge (the cell whose centre
    /// is nearest).
    #[serde(default = "default_probe")]
    pub probe: [f64; 2],
}

fn default_probe() -> [f64; 2] {
    [0.0, 0.02]
}

/// One compared quantity: complex amplitudes per unit gust velocity (in a∞).
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct Table2Row {
    pub variable: String,
    /// LFD with s = iω, and the Fourier fit of the nonlinear run.
    pub lfd: [f64; 2],
    pub fourier: [f64; 2],
    pub digits_fourier: f64,
    /// LFD with the BDF2 symbol, and the transformed linearized BDF2 march.
    pub lfd_bdf2: [f64; 2],
    pub linear_bdf2: [f64; 2],
    pub digits_bdf2: f64,
}

/// Table 2 with its agreeing significant digits (the smallest over the rows).
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct Table2 {
    pub reduced_frequency: f64,
    pub amplitude_mach: f64,
    pub probe_cell: usize,
    pub probe_center: [f64; 2],
    pub rows: Vec<Table2Row>,
    pub digits_fourier: f64,
    pub digits_bdf2: f64,
    /// Wall time of one LFD frequency (factorization and solve) and of the nonlinear time-domain
    /// run that gives the same answer, s.
    pub lfd_time_s: f64,
    pub time_domain_time_s: f64,
    pub linear_march_time_s: f64,
    pub gmres_iterations: usize,
    /// Lift of the nonlinear run's fitted periods with the mean removed, per unit gust, against
    /// the LFD reconstruction Re(−i L̂ e^{iωt}) (t in chord / a∞).
    pub lift_time_domain: Vec<(f64, f64)>,
    pub lift_lfd: Vec<(f64, f64)>,
}

fn digits(a: C64, b: C64) -> f64 {
    if a == b {
        return 16.0;
    }
    (-((a - b).norm() / b.norm()).log10()).min(16.0)
}

/// The compared quantities of a state perturbation at the probe cell: ρ̂, û, v̂ (vertical), T̂ =
/// (γ p / ρ)^ and the lift coefficient, from a complex state perturbation and its lift.
fn quantities(q0: &State<f64>, q_hat: &[C64], lift: C64, q_dyn: f64) -> [C64; 5] {
    let q: State<Dual<2>> = std::array::from_fn(|k| Dual::new(q0[k], [q_hat[k].re, q_hat[k].im]));
    let w = primitive(&q);
    let t = w.p * GAMMA / w.rho;
    let c = |d: Dual<2>| C64::new(d.d[0], d.d[1]);
    [c(w.rho), c(w.vel[0]), c(w.vel[1]), c(t), lift / q_dyn]
}

const NAMES: [&str; 5] = ["rho", "u", "w (vertical)", "T", "C_L"];

/// Runs the comparison; returns the cell count and the table.
pub fn run(c: &CfdSpec, s: &LfdGustSpec, base: &std::path::Path) -> Result<(usize, Table2)> {
    let e = build(c, base, free_stream(c.mach, 0.0))?;
    let params = SteadyParams {
        tolerance: 1e-16,
        ..SteadyParams::default()
    };
    let (q0, _) = e
        .solve_steady(vec![e.q_inf; e.mesh.n_cells], &params)
        .map_err(|err| anyhow::anyhow!("cfd.lfd_gust (steady state): {err}"))?;
    let mut lfd = LfdOperator::new(e, q0);
    lfd.params.tolerance = 1e-12;
    let omega = 2.0 * s.reduced_frequency * c.mach; // b = ½ chord, U = M a∞
    let period = 2.0 * std::f64::consts::PI / omega;
    let q_dyn = 0.5 * c.mach * c.mach;
    let centers = &lfd.euler.lsq.centers;
    let (px, py) = (s.probe[0] - 0.5, s.probe[1]);
    let cell = (0..lfd.euler.mesh.n_cells)
        .min_by(|&a, &b| {
            let d = |i: usize| (centers[i][0] - px).hypot(centers[i][1] - py);
            d(a).total_cmp(&d(b))
        })
        .expect("a mesh has cells");
    let probe = |q: &[C64]| -> [C64; NVAR] { std::array::from_fn(|k| q[cell * NVAR + k]) };
    let gust = HarmonicGust {
        convection: c.mach,
        x0: 0.0,
    };
    let lfd_err = |e: gustkit_cfd::lfd::LfdError| anyhow::anyhow!("cfd.lfd_gust: {e}");
    // (1) continuous LFD
    let t0 = Instant::now();
    let f = lfd.factor(omega, Symbol::Exact).map_err(lfd_err)?;
    let (q_hat, info) = lfd
        .solve(&f, &[lfd.gust_rhs(omega, &gust)])
        .map_err(lfd_err)?
        .pop()
        .expect("one right-hand side");
    let lfd_time = t0.elapsed().as_secs_f64();
    let exact = quantities(
        &lfd.q0[cell],
        &probe(&q_hat),
        lfd.force(&q_hat, None)[1],
        q_dyn,
    );
    // the nonlinear run: w = A sin(ω(t − x/U)) = Re(−i A ŵ e^{iωt})
    let t0 = Instant::now();
    let dt = period / s.steps_per_period as f64;
    let sine = Gust::Sine {
        amplitude: s.amplitude_mach,
        omega,
        convection: c.mach,
        x0: 0.0,
    };
    let steps = (s.transient_periods + s.fit_periods) * s.steps_per_period;
    let fit_from = s.transient_periods * s.steps_per_period;
    let lift0 = lfd.euler.wall_force(&lfd.q0)[1];
    let mut series: Vec<Vec<(f64, f64)>> = vec![Vec::new(); 5];
    let mut step = 0;
    let mut euler = lfd.euler.clone();
    // the sparser first-order LU, kept for the whole run, is the cheaper preconditioner of these
    // small-step systems (97 against 130 ms a step on 2048 cells): no exact_jacobian
    let nonlinear = SteadyParams::small_amplitude();
    let (_, samples) = march_observed(
        &mut euler,
        lfd.q0.clone(),
        Some(&sine),
        None,
        dt,
        steps,
        &nonlinear,
        &mut |t, q| {
            step += 1;
            if step > fit_from {
                // the exact change of the primitives (not linearized)
                let w1 = primitive(&q[cell]);
                let w0 = primitive(&lfd.q0[cell]);
                let vals = [
                    w1.rho - w0.rho,
                    w1.vel[0] - w0.vel[0],
                    w1.vel[1] - w0.vel[1],
                    GAMMA * (w1.p / w1.rho - w0.p / w0.rho),
                    0.0,
                ];
                for k in 0..4 {
                    series[k].push((t, vals[k]));
                }
            }
        },
    )
    .map_err(|err| anyhow::anyhow!("cfd.lfd_gust (time domain): {err}"))?;
    for smp in &samples[fit_from + 1..] {
        series[4].push((smp.time, (smp.force[1] - lift0) / q_dyn));
    }
    let time_domain_time = t0.elapsed().as_secs_f64();
    let i_over_a = C64::new(0.0, 1.0 / s.amplitude_mach);
    let fourier: Vec<C64> = series
        .iter()
        .map(|ser| fourier_fit(ser, omega).1 * i_over_a)
        .collect();
    // (2) the BDF2 symbol against the linearized march
    let t0 = Instant::now();
    let dt_lin = period / s.linear_steps_per_period as f64;
    let f = lfd
        .factor(omega, Symbol::Bdf2 { dt: dt_lin })
        .map_err(lfd_err)?;
    let (q_bdf2, _) = lfd
        .solve(&f, &[lfd.gust_rhs(omega, &gust)])
        .map_err(lfd_err)?
        .pop()
        .expect("one right-hand side");
    let lfd_bdf2 = quantities(
        &lfd.q0[cell],
        &probe(&q_bdf2),
        lfd.force(&q_bdf2, None)[1],
        q_dyn,
    );
    let unit_sine = Gust::Sine {
        amplitude: 1.0,
        omega,
        convection: c.mach,
        x0: 0.0,
    };
    let forcing = |t: f64| -> Vec<C64> {
        let g: Vec<C64> = lfd
            .euler
            .gust_fluxes(&unit_sine, t)
            .iter()
            .map(|v| C64::new(*v, 0.0))
            .collect();
        lfd.volume_flux_rhs(&g)
    };
    let last = (s.linear_periods - 1) * s.linear_steps_per_period;
    let mut lin: Vec<Vec<(f64, f64)>> = vec![Vec::new(); 5];
    lfd.linear_march(
        dt_lin,
        s.linear_periods * s.linear_steps_per_period,
        &forcing,
        &mut |n, t, q| {
            if n > last {
                let v = quantities(&lfd.q0[cell], &probe(q), lfd.force(q, None)[1], q_dyn);
                for k in 0..5 {
                    lin[k].push((t, v[k].re));
                }
            }
        },
    )
    .map_err(lfd_err)?;
    let linear_time = t0.elapsed().as_secs_f64();
    let linear: Vec<C64> = lin
        .iter()
        .map(|ser| fourier_coefficient(ser, omega) * C64::new(0.0, 1.0))
        .collect();
    let pair = |z: C64| [z.re, z.im];
    let rows: Vec<Table2Row> = (0..5)
        .map(|k| Table2Row {
            variable: NAMES[k].into(),
            lfd: pair(exact[k]),
            fourier: pair(fourier[k]),
            digits_fourier: digits(fourier[k], exact[k]),
            lfd_bdf2: pair(lfd_bdf2[k]),
            linear_bdf2: pair(linear[k]),
            digits_bdf2: digits(linear[k], lfd_bdf2[k]),
        })
        .collect();
    let lift_lfd = series[4]
        .iter()
        .map(|&(t, _)| {
            (
                t,
                (C64::new(0.0, -1.0) * exact[4] * C64::new(0.0, omega * t).exp()).re,
            )
        })
        .collect();
    let mean = series[4].iter().map(|p| p.1).sum::<f64>() / series[4].len().max(1) as f64;
    let lift_time_domain = series[4]
        .iter()
        .map(|&(t, v)| (t, (v - mean) / s.amplitude_mach))
        .collect();
    Ok((
        lfd.euler.mesh.n_cells,
        Table2 {
            reduced_frequency: s.reduced_frequency,
            amplitude_mach: s.amplitude_mach,
            probe_cell: cell,
            probe_center: [centers[cell][0] + 0.5, centers[cell][1]],
            digits_fourier: rows
                .iter()
                .map(|r| r.digits_fourier)
                .fold(f64::MAX, f64::min),
            digits_bdf2: rows.iter().map(|r| r.digits_bdf2).fold(f64::MAX, f64::min),
            rows,
            lfd_time_s: lfd_time,
            time_domain_time_s: time_domain_time,
            linear_march_time_s: linear_time,
            gmres_iterations: info.iterations,
            lift_time_domain,
            lift_lfd,
        },
    ))
}
