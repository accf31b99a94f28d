//! Paper Table 1: the steady flow at an angle of attack against the equivalent uniform gust (the
//! Field Velocity Method must give the same forces), with the wall pressure distributions.

use super::build;
use super::report::{ForceRow, PressureDistribution, SteadyGustResults};
use super::schema::{CfdSpec, SteadyGustSpec};
use crate::report::write_atomic;
use anyhow::Result;
use gustkit_cfd::gas::{primitive, GAMMA};
use gustkit_cfd::mesh::{Boundary, Side};
use gustkit_cfd::residual::{free_stream, Euler, Gust, State};
use gustkit_cfd::steady::SteadyParams;
use std::path::Path;

/// Wall C_p against x/c, upper and lower surface.
pub(crate) fn pressure(
    e: &Euler,
    q: &[State<f64>],
    mach: f64,
    label: &str,
) -> PressureDistribution {
    let q_dyn = 0.5 * mach * mach;
    let (mut upper, mut lower) = (Vec::new(), Vec::new());
    for (fi, f) in e.mesh.faces.iter().enumerate() {
        if f.right == Side::Boundary(Boundary::Wall) {
            let c = e.lsq.face_centers[fi];
            let cp = (primitive(&q[f.left]).p - 1.0 / GAMMA) / q_dyn;
            if c[1] >= 0.0 {
                upper.push((c[0] + 0.5, cp));
            } else {
                lower.push((c[0] + 0.5, cp));
            }
        }
    }
    upper.sort_by(|a, b| a.0.total_cmp(&b.0));
    lower.sort_by(|a, b| a.0.total_cmp(&b.0));
    PressureDistribution {
        label: label.to_string(),
        upper,
        lower,
    }
}

pub(crate) fn steady_gust(
    c: &CfdSpec,
    s: &SteadyGustSpec,
    base: &Path,
    dir: &Path,
) -> Result<(usize, SteadyGustResults)> {
    let alpha = s.alpha_deg.to_radians();
    let (w, m_red) = (c.mach * alpha.sin(), c.mach * alpha.cos());
    let q_dyn = 0.5 * c.mach * c.mach;
    // to round-off: the two solutions are compared digit by digit
    let params = SteadyParams {
        tolerance: 1e-16,
        ..SteadyParams::default()
    };
    let mut rows = Vec::new();
    let mut pressures = Vec::new();
    let mut cells = 0;
    for gust in [false, true] {
        let e = if gust {
            let mut e = build(c, base, free_stream(m_red, 0.0))?;
            e.set_gust(&Gust::Uniform([0.0, w, 0.0]), 0.0);
            e
        } else {
            build(c, base, free_stream(c.mach, alpha))?
        };
        cells = e.mesh.n_cells;
        let (q, info) = e
            .solve_steady(vec![e.q_inf; e.mesh.n_cells], &params)
            .map_err(|err| {
                anyhow::anyhow!(
                    "cfd.steady_gust ({}): {err}",
                    if gust { "gust" } else { "angle of attack" }
                )
            })?;
        let f = e.wall_force(&q);
        let name = if gust {
            "uniform vertical gust (FVM), reduced free stream"
        } else {
            "angle of attack at the far field"
        };
        rows.push(ForceRow {
            case: name.into(),
            cx: f[0] / q_dyn,
            cz: f[1] / q_dyn,
            newton_iterations: info.iterations,
            residual_history: info.residual_history,
        });
        pressures.push(pressure(&e, &q, c.mach, name));
        let vtk = gustkit_cfd::vtk::flow_vtk(&e.mesh, &q, c.mach, name);
        let file = if gust {
            "flow_gust.vtk"
        } else {
            "flow_aoa.vtk"
        };
        write_atomic(&dir.join(file), vtk.as_bytes())?;
    }
    let digits = |a: f64, b: f64| -> f64 {
        if a == b {
            16.0
        } else {
            (-((a - b).abs() / a.abs().max(b.abs())).log10()).min(16.0)
        }
    };
    Ok((
        cells,
        SteadyGustResults {
            alpha_deg: s.alpha_deg,
            gust_mach: w,
            reduced_mach: m_red,
            digits_cx: digits(rows[0].cx, rows[1].cx),
            digits_cz: digits(rows[0].cz, rows[1].cz),
            table1: rows,
            pressure: pressures,
        },
    ))
}
