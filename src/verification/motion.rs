//! Prescribed rigid pitching or plunging in the time domain: the whole mesh moves rigidly (ALE,
//! swept-volume GCL), the lift history is recorded, and its harmonic over the last period is
//! compared with the LFD of the same motion (one linear solve; with s = iω and with the BDF2
//! symbol) and with Theodorsen's function with the Prandtl–Glauert factor (a sanity band: thick
//! section, compressible flow).

use super::{build, CfdSpec};
use anyhow::{bail, Result};
use gustkit_cfd::lfd::{LfdOperator, Symbol};
use gustkit_cfd::residual::free_stream;
use gustkit_cfd::steady::SteadyParams;
use gustkit_cfd::unsteady::{fourier_fit, march};
use num_complex::Complex64 as C64;
use serde::{Deserialize, Serialize};

/// The motion (key `time_motion` of a CFD study).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TimeMotionSpec {
    /// "pitch" (nose up about `pivot_chord`) or "plunge" (up).
    pub motion: String,
    /// Degrees for pitch, chords for plunge: θ(t) = amplitude · sin ωt.
    pub amplitude: f64,
    /// Pitch axis, fraction of the chord from the leading edge.
    #[serde(default = "default_pivot")]
    pub pivot_chord: f64,
    pub reduced_frequency: f64,
    pub periods: usize,
    pub steps_per_period: usize,
}

fn default_pivot() -> f64 {
    0.25
}

/// Results of the prescribed-motion run.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct TimeMotionResults {
    pub motion: String,
    pub reduced_frequency: f64,
    pub dt: f64,
    /// (t, C_L) at every time level, t in units of chord / a∞.
    pub lift_history: Vec<(f64, f64)>,
    /// Complex C_L amplitude Ĉ (C_L = mean + Re(Ĉ e^{iωt})) fitted over the last period, of the
    /// LFD (s = iω and the BDF2 symbol) and of Theodorsen with the Prandtl–Glauert factor.
    pub time_domain: [f64; 2],
    pub lfd: [f64; 2],
    pub lfd_bdf2: [f64; 2],
    pub theodorsen_pg: [f64; 2],
    /// Agreeing significant digits of the time-domain and the BDF2-symbol LFD amplitudes.
    pub digits_lfd_bdf2: f64,
    pub max_newton_iterations: usize,
}

/// Validates the spec (errors name the JSON path).
pub fn check(m: &TimeMotionSpec) -> Result<(), (String, String)> {
    let bad = |p: &str, r: String| Err((format!("cfd.time_motion.{p}"), r));
    if m.motion != "pitch" && m.motion != "plunge" {
        return bad(
            "motion",
            format!("must be \"pitch\" or \"plunge\" (got '{}')", m.motion),
        );
    }
    if !(m.amplitude > 0.0 && m.amplitude.is_finite()) {
        return bad(
            "amplitude",
            format!("must be positive (got {})", m.amplitude),
        );
    }
    if !(m.reduced_frequency > 0.0) {
        return bad(
            "reduced_frequency",
            format!("must be positive (got {})", m.reduced_frequency),
        );
    }
    if m.periods == 0 || m.steps_per_period < 4 {
        return bad(
            "periods",
            "need periods >= 1 and steps_per_period >= 4".into(),
        );
    }
    Ok(())
}

/// Runs the motion; returns the cell count and the results.
pub fn run(
    c: &CfdSpec,
    m: &TimeMotionSpec,
    base: &std::path::Path,
) -> Result<(usize, TimeMotionResults)> {
    let e = build(c, base, free_stream(c.mach, 0.0))?;
    let (q0, _) = e
        .solve_steady(vec![e.q_inf; e.mesh.n_cells], &SteadyParams::default())
        .map_err(|err| anyhow::anyhow!("cfd.time_motion (initial steady state): {err}"))?;
    let omega = 2.0 * m.reduced_frequency * c.mach;
    let dt = 2.0 * std::f64::consts::PI / omega / m.steps_per_period as f64;
    let x0 = e.mesh.nodes.clone();
    // the pivot in mesh coordinates (mid-chord at the origin)
    let xp = m.pivot_chord - 0.5;
    let pitch = m.motion == "pitch";
    let amp = if pitch {
        m.amplitude.to_radians()
    } else {
        m.amplitude
    };
    let nodes0 = x0.clone();
    let motion = move |t: f64| -> Vec<[f64; 3]> {
        let a = amp * (omega * t).sin();
        nodes0
            .iter()
            .map(|p| {
                if pitch {
                    // nose up: clockwise in the x-y plane about (xp, 0)
                    let (s, co) = a.sin_cos();
                    let (dx, dy) = (p[0] - xp, p[1]);
                    [xp + dx * co + dy * s, -dx * s + dy * co, p[2]]
                } else {
                    [p[0], p[1] + a, p[2]]
                }
            })
            .collect()
    };
    let params = SteadyParams {
        tolerance: 1e-10,
        refactor_every: 1000,
        ..SteadyParams::default()
    };
    let steps = m.periods * m.steps_per_period;
    let mut moving = e.clone();
    let (_, samples) = march(
        &mut moving,
        q0.clone(),
        None,
        Some(&motion),
        dt,
        steps,
        &params,
    )
    .map_err(|err| anyhow::anyhow!("cfd.time_motion: {err}"))?;
    let q_dyn = 0.5 * c.mach * c.mach;
    let lift: Vec<(f64, f64)> = samples
        .iter()
        .map(|s| (s.time, s.force[1] / q_dyn))
        .collect();
    if lift.iter().any(|(_, v)| !v.is_finite()) {
        bail!("cfd.time_motion: the lift is not finite");
    }
    let last = &lift[lift.len() - m.steps_per_period - 1..];
    let (_, td) = fourier_fit(last, omega);
    // the LFD of the same motion: x̂ = −i amp × the unit rigid field (θ = Re(−i amp e^{iωt}))
    let unit: Vec<[C64; 3]> = x0
        .iter()
        .map(|p| {
            let d = if pitch {
                [p[1], -(p[0] - xp), 0.0]
            } else {
                [0.0, 1.0, 0.0]
            };
            d.map(|v| C64::new(0.0, -amp * v))
        })
        .collect();
    let lfd = LfdOperator::new(e, q0);
    let lift_lfd = |symbol: Symbol| -> Result<C64> {
        let f = lfd
            .factor(omega, symbol)
            .map_err(|e| anyhow::anyhow!("cfd.time_motion (LFD): {e}"))?;
        let (q, _) = lfd
            .solve(&f, &[lfd.motion_rhs(f.s, &unit)])
            .map_err(|e| anyhow::anyhow!("cfd.time_motion (LFD): {e}"))?
            .pop()
            .expect("one right-hand side");
        Ok(lfd.force(&q, Some(&unit))[1] / q_dyn)
    };
    let exact = lift_lfd(Symbol::Exact)?;
    let bdf2 = lift_lfd(Symbol::Bdf2 { dt })?;
    // Theodorsen (chord 1, b = ½): plunge of the mid-chord and pitch about it
    let (ss, _) = gustkit_core::theory::strip_gafs(m.reduced_frequency, 0.5, c.mach);
    let (h, a) = if pitch { (amp * xp, amp) } else { (amp, 0.0) };
    let theo = C64::new(0.0, -1.0) * (ss[0][0] * h + ss[0][1] * a);
    let pair = |z: C64| [z.re, z.im];
    let tdc = C64::new(td.re, td.im);
    Ok((
        lfd.euler.mesh.n_cells,
        TimeMotionResults {
            motion: m.motion.clone(),
            reduced_frequency: m.reduced_frequency,
            dt,
            lift_history: lift,
            time_domain: pair(tdc),
            lfd: pair(exact),
            lfd_bdf2: pair(bdf2),
            theodorsen_pg: pair(theo),
            digits_lfd_bdf2: -((tdc - bdf2).norm() / bdf2.norm()).log10(),
            max_newton_iterations: samples.iter().map(|s| s.iterations).max().unwrap_or(0),
        },
    ))
}
