//! Paper Fig. 1: the lift history of the section in a sinusoidal vertical gust in the time
//! domain, each period's amplitude against Sears with the Prandtl–Glauert factor.

use super::build;
use super::report::TimeGustResults;
use super::schema::{CfdSpec, TimeGustSpec};
use super::table1::pressure;
use crate::report::write_atomic;
use anyhow::Result;
use gustkit_cfd::residual::{free_stream, Gust};
use gustkit_cfd::steady::SteadyParams;
use gustkit_cfd::unsteady::{harmonic_fit, march};
use std::path::Path;

pub(crate) fn time_gust(
    c: &CfdSpec,
    t: &TimeGustSpec,
    base: &Path,
    dir: &Path,
) -> Result<(usize, TimeGustResults)> {
    let mut e = build(c, base, free_stream(c.mach, 0.0))?;
    let (q0, _) = e
        .solve_steady(vec![e.q_inf; e.mesh.n_cells], &SteadyParams::default())
        .map_err(|err| anyhow::anyhow!("cfd.time_gust (initial steady state): {err}"))?;
    let omega = 2.0 * t.reduced_frequency * c.mach; // b = ½ chord
    let period = 2.0 * std::f64::consts::PI / omega;
    let dt = period / t.steps_per_period as f64;
    let gust = Gust::Sine {
        amplitude: t.amplitude_mach,
        omega,
        convection: c.mach,
        x0: 0.0,
    };
    // one factorization of the preconditioner per time step
    let params = SteadyParams {
        tolerance: 1e-9,
        refactor_every: 1000,
        ..SteadyParams::default()
    };
    let (q, samples) = march(
        &mut e,
        q0,
        Some(&gust),
        None,
        dt,
        t.periods * t.steps_per_period,
        &params,
    )
    .map_err(|err| anyhow::anyhow!("cfd.time_gust: {err}"))?;
    let vtk = gustkit_cfd::vtk::flow_vtk(&e.mesh, &q, c.mach, "last time level of the gust run");
    write_atomic(&dir.join("flow_final.vtk"), vtk.as_bytes())?;
    let q_dyn = 0.5 * c.mach * c.mach;
    let lift: Vec<(f64, f64)> = samples
        .iter()
        .map(|s| (s.time, s.force[1] / q_dyn))
        .collect();
    let n = t.steps_per_period;
    let amplitudes = (0..t.periods)
        .map(|p| harmonic_fit(&lift[p * n..=(p + 1) * n], omega).1)
        .collect();
    let (sr, si) = gustkit_core::theory::sears(t.reduced_frequency);
    let beta = (1.0 - c.mach * c.mach).sqrt();
    Ok((
        e.mesh.n_cells,
        TimeGustResults {
            amplitude_mach: t.amplitude_mach,
            reduced_frequency: t.reduced_frequency,
            dt,
            lift_history: lift,
            amplitudes,
            sears_pg_amplitude: 2.0
                * std::f64::consts::PI
                * (t.amplitude_mach / c.mach)
                * sr.hypot(si)
                / beta,
            max_newton_iterations: samples.iter().map(|s| s.iterations).max().unwrap_or(0),
            pressure_final: pressure(&e, &q, c.mach, "final time level"),
        },
    ))
}
