//! CFD verification studies: JSON files with a `cfd` section (the paper's NACA 64A010 cases), run
//! by `gustkit run` with the finite-volume Euler solver of `gustkit-lfd`; results.json, summary.md
//! and figures are rendered from the typed results alone (so `gustkit report` can redraw them).

use crate::report::figures::{LinePlot, Series};
use crate::report::{save_figure, write_atomic};
use anyhow::{bail, Context, Result};
use gustkit_lfd::airfoil::Section;
use gustkit_lfd::gas::{primitive, GAMMA};
use gustkit_lfd::mesh::{Boundary, Side};
use gustkit_lfd::residual::{free_stream, Euler, Gust, Order, State};
use gustkit_lfd::steady::SteadyParams;
use gustkit_lfd::unsteady::{harmonic_fit, march};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::Instant;

pub mod motion;
pub mod table2;

/// A CFD verification study file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CfdStudyFile {
    pub schema_version: u32,
    pub name: String,
    #[serde(default)]
    pub description: String,
    pub cfd: CfdSpec,
}

/// The case: airfoil, mesh, scheme, Mach number and the analyses to run.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CfdSpec {
    /// Built-in section: "naca64a010" (from its NACA Report 903 ordinates).
    pub airfoil: String,
    /// The built-in O-mesh about the airfoil, or …
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<OMeshSpec>,
    /// … a mesh file (chord 1 along x, the wall around the airfoil).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh_file: Option<MeshFileSpec>,
    /// "first" or "second" (default) order.
    #[serde(default = "default_order")]
    pub order: String,
    /// Second order: "none" (default) or "van_albada" (smooth, differentiable).
    #[serde(default = "default_limiter")]
    pub limiter: String,
    pub mach: f64,
    /// Paper Table 1: angle of attack at the far field against the equivalent uniform gust.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steady_gust: Option<SteadyGustSpec>,
    /// Paper Fig. 1: a sinusoidal vertical gust in the time domain.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_gust: Option<TimeGustSpec>,
    /// Paper Table 2: the LFD gust solution against the time domain.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lfd_gust: Option<table2::LfdGustSpec>,
    /// Prescribed rigid pitching or plunging in the time domain, against the LFD and Theodorsen.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_motion: Option<motion::TimeMotionSpec>,
}

fn default_order() -> String {
    "second".into()
}

fn default_limiter() -> String {
    "none".into()
}

/// The built-in O-mesh (chord 1, lengths in chords).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct OMeshSpec {
    pub n_around: usize,
    pub n_radial: usize,
    #[serde(default = "default_far")]
    pub far_field_chords: f64,
    /// Height of the first cell at the wall.
    pub first_spacing_chords: f64,
}

fn default_far() -> f64 {
    50.0
}

/// A mesh file: Gmsh 4.1 (`.msh`) or SU2 (`.su2`), its markers mapped to boundary conditions
/// ("wall", "far_field", "symmetry"); 2-D meshes are extruded to `span`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MeshFileSpec {
    /// Relative to the study file.
    pub path: String,
    pub markers: std::collections::BTreeMap<String, String>,
    #[serde(default = "default_span")]
    pub span: f64,
}

fn default_span() -> f64 {
    1.0
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SteadyGustSpec {
    pub alpha_deg: f64,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TimeGustSpec {
    /// Gust amplitude in units of the free-stream speed of sound.
    pub amplitude_mach: f64,
    /// k = ω b / U with b the semichord.
    pub reduced_frequency: f64,
    pub periods: usize,
    pub steps_per_period: usize,
}

/// One row of Table 1: force coefficients in body axes (x along the chord, z up), normalized by
/// the dynamic pressure of the total speed and the chord.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct ForceRow {
    pub case: String,
    pub cx: f64,
    pub cz: f64,
    pub newton_iterations: usize,
    pub residual_history: Vec<f64>,
}

/// Wall pressure coefficients, (x/c, C_p), upper and lower surface.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct PressureDistribution {
    pub label: String,
    pub upper: Vec<(f64, f64)>,
    pub lower: Vec<(f64, f64)>,
}

/// Results of the steady-gust verification.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct SteadyGustResults {
    pub alpha_deg: f64,
    pub gust_mach: f64,
    pub reduced_mach: f64,
    pub table1: Vec<ForceRow>,
    pub digits_cx: f64,
    pub digits_cz: f64,
    pub pressure: Vec<PressureDistribution>,
}

/// Results of the time-domain gust run.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct TimeGustResults {
    pub amplitude_mach: f64,
    pub reduced_frequency: f64,
    pub dt: f64,
    /// (t, C_L) at every time level, t in units of chord / a∞.
    pub lift_history: Vec<(f64, f64)>,
    /// C_L amplitude fitted over each period.
    pub amplitudes: Vec<f64>,
    /// Sears's incompressible amplitude with the Prandtl–Glauert factor.
    pub sears_pg_amplitude: f64,
    pub max_newton_iterations: usize,
    pub pressure_final: PressureDistribution,
}

/// Everything a CFD verification run writes to results.json.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct CfdResults {
    pub study: String,
    pub description: String,
    pub cfd: CfdSpec,
    pub cells: usize,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steady_gust: Option<SteadyGustResults>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_gust: Option<TimeGustResults>,
    /// Paper Table 2 (with `digits_fourier` and `digits_bdf2`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub table2: Option<table2::Table2>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_motion: Option<motion::TimeMotionResults>,
    pub run_time_s: f64,
}

impl CfdStudyFile {
    /// Reads and checks a CFD study; errors name the file and the JSON path.
    pub fn load(file: &Path) -> Result<Self> {
        let s: Self = crate::report::from_json(file, &crate::report::read_json(file)?)?;
        let bad = |path: &str, reason: String| -> Result<Self> {
            bail!("{}: {path}: {reason}", file.display())
        };
        let c = &s.cfd;
        if s.schema_version != crate::study::SCHEMA_VERSION {
            return bad(
                "schema_version",
                format!("unsupported ({})", s.schema_version),
            );
        }
        if c.airfoil != "naca64a010" {
            return bad(
                "cfd.airfoil",
                format!(
                    "unknown built-in section '{}' (use \"naca64a010\")",
                    c.airfoil
                ),
            );
        }
        if c.order != "first" && c.order != "second" {
            return bad(
                "cfd.order",
                format!("must be \"first\" or \"second\" (got '{}')", c.order),
            );
        }
        if c.limiter != "none" && c.limiter != "van_albada" {
            return bad(
                "cfd.limiter",
                format!("must be \"none\" or \"van_albada\" (got '{}')", c.limiter),
            );
        }
        if !(c.mach > 0.0 && c.mach < 1.0) {
            return bad("cfd.mach", format!("must lie in (0, 1) (got {})", c.mach));
        }
        match (&c.mesh, &c.mesh_file) {
            (Some(_), None) | (None, Some(_)) => {}
            _ => {
                return bad(
                    "cfd",
                    "give exactly one of mesh (built-in) and mesh_file".into(),
                )
            }
        }
        if let Some(f) = &c.mesh_file {
            for (name, kind) in &f.markers {
                if !["wall", "far_field", "symmetry"].contains(&kind.as_str()) {
                    return bad(
                        &format!("cfd.mesh_file.markers.{name}"),
                        format!("'{kind}' is not a boundary condition (wall, far_field, symmetry)"),
                    );
                }
            }
        }
        if let Some(m) = &c.mesh {
            if m.n_around < 8 || m.n_radial < 2 {
                return bad("cfd.mesh", "need n_around >= 8 and n_radial >= 2".into());
            }
            if !(m.far_field_chords >= 5.0) {
                return bad(
                    "cfd.mesh.far_field_chords",
                    format!("must be at least 5 (got {})", m.far_field_chords),
                );
            }
            if !(m.first_spacing_chords > 0.0
                && m.first_spacing_chords * (m.n_radial as f64) < m.far_field_chords)
            {
                return bad(
                    "cfd.mesh.first_spacing_chords",
                    format!(
                        "must be positive and below far_field_chords / n_radial (got {})",
                        m.first_spacing_chords
                    ),
                );
            }
        }
        if let Some(t) = &c.time_gust {
            if t.periods == 0 || t.steps_per_period < 4 || !(t.reduced_frequency > 0.0) {
                return bad(
                    "cfd.time_gust",
                    "need periods >= 1, steps_per_period >= 4 and a positive reduced_frequency"
                        .into(),
                );
            }
        }
        if let Some(t) = &c.lfd_gust {
            if !(t.reduced_frequency > 0.0 && t.reduced_frequency.is_finite()) {
                return bad(
                    "cfd.lfd_gust.reduced_frequency",
                    format!("must be positive (got {})", t.reduced_frequency),
                );
            }
            if !(t.amplitude_mach > 0.0 && t.amplitude_mach < 0.1) {
                return bad(
                    "cfd.lfd_gust.amplitude_mach",
                    format!(
                        "must lie in (0, 0.1): a small perturbation (got {})",
                        t.amplitude_mach
                    ),
                );
            }
            if t.steps_per_period < 4
                || t.linear_steps_per_period < 4
                || t.fit_periods == 0
                || t.linear_periods == 0
            {
                return bad(
                    "cfd.lfd_gust",
                    "need steps_per_period and linear_steps_per_period >= 4, fit_periods and linear_periods >= 1".into(),
                );
            }
        }
        if let Some(m) = &c.time_motion {
            if let Err((path, reason)) = motion::check(m) {
                return bad(&path, reason);
            }
        }
        if c.steady_gust.is_none()
            && c.time_gust.is_none()
            && c.lfd_gust.is_none()
            && c.time_motion.is_none()
        {
            return bad(
                "cfd",
                "nothing to run: add steady_gust, time_gust, lfd_gust or time_motion".into(),
            );
        }
        Ok(s)
    }
}

pub(crate) fn build(c: &CfdSpec, base: &Path, q_inf: State<f64>) -> Result<Euler> {
    let mesh = match (&c.mesh, &c.mesh_file) {
        (Some(m), _) => builtin_mesh(m, &Section::naca64a010()),
        (None, Some(f)) => file_mesh(f, base)?,
        (None, None) => bail!("cfd: no mesh"),
    };
    mesh.check()
        .map_err(|err| anyhow::anyhow!("cfd.mesh: {err}"))?;
    let mut e = Euler::new(mesh, q_inf);
    if c.order == "first" {
        e.order = Order::First;
    }
    if c.limiter == "van_albada" {
        e.limiter = gustkit_lfd::residual::Limiter::VanAlbada { eps: 1e-3 };
    }
    Ok(e)
}

/// The built-in O-mesh of `m` about a section (chord 1, mid-chord at the origin).
pub(crate) fn builtin_mesh(m: &OMeshSpec, sec: &Section) -> gustkit_lfd::mesh::Mesh {
    sec.o_mesh(
        m.n_around,
        m.n_radial,
        m.far_field_chords,
        m.first_spacing_chords / m.far_field_chords,
        1.0,
    )
}

/// Reads a mesh file with its marker map.
fn file_mesh(f: &MeshFileSpec, base: &Path) -> Result<gustkit_lfd::mesh::Mesh> {
    let path = base.parent().unwrap_or(Path::new(".")).join(&f.path);
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("cfd.mesh_file.path: cannot read {}", path.display()))?;
    let markers = f
        .markers
        .iter()
        .map(|(name, kind)| {
            let b = match kind.as_str() {
                "wall" => Boundary::Wall,
                "far_field" => Boundary::FarField,
                _ => Boundary::Symmetry,
            };
            (name.clone(), b)
        })
        .collect();
    let mesh = if f.path.ends_with(".su2") {
        gustkit_lfd::readers::read_su2(&text, &markers, f.span)
    } else {
        gustkit_lfd::readers::read_gmsh(&text, &markers, f.span)
    };
    mesh.map_err(|e| anyhow::anyhow!("cfd.mesh_file: {}: {e}", path.display()))
}

/// Wall C_p against x/c, upper and lower surface.
fn pressure(e: &Euler, q: &[State<f64>], mach: f64, label: &str) -> PressureDistribution {
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

fn steady_gust(
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
        let vtk = gustkit_lfd::vtk::flow_vtk(&e.mesh, &q, c.mach, name);
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

fn time_gust(
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
    let vtk = gustkit_lfd::vtk::flow_vtk(&e.mesh, &q, c.mach, "last time level of the gust run");
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

/// The markdown summary of a CFD verification run.
pub fn summary(r: &CfdResults) -> String {
    let mesh = match (&r.cfd.mesh, &r.cfd.mesh_file) {
        (Some(m), _) => format!(
            "NACA 64A010 (NACA Report 903 ordinates), O-mesh {} × {} = {} cells, far field at {} chords, first cell {} chords",
            m.n_around, m.n_radial, r.cells, m.far_field_chords, m.first_spacing_chords
        ),
        (None, Some(f)) => format!("mesh file {} ({} cells)", f.path, r.cells),
        (None, None) => String::new(),
    };
    let mut md = format!(
        "# {}\n\n{}\n\n{mesh}; {} order, Roe flux; M = {}.\n",
        r.study, r.description, r.cfd.order, r.cfd.mach
    );
    if let Some(s) = &r.steady_gust {
        md += &format!(
            "\n## Table 1: angle of attack vs uniform gust\n\nα = {}°; gust w = {:.6} (Mach) with the free stream reduced to M = {:.6} (same total speed). Body-axis coefficients.\n\n| case | C_x | C_z | Newton iterations |\n|---|---:|---:|---:|\n",
            s.alpha_deg, s.gust_mach, s.reduced_mach
        );
        for row in &s.table1 {
            md += &format!(
                "| {} | {:.15e} | {:.15e} | {} |\n",
                row.case, row.cx, row.cz, row.newton_iterations
            );
        }
        md += &format!(
            "\nAgreeing significant digits: C_x {:.1}, C_z {:.1} (the paper: 12 and 11).\n\n![residuals](residuals.png)\n\n![pressure](pressure.png)\n\nFlow fields for ParaView: `flow_aoa.vtk`, `flow_gust.vtk`.\n",
            s.digits_cx, s.digits_cz
        );
    }
    if let Some(t) = &r.time_gust {
        md += &format!(
            "\n## Fig. 1: sinusoidal gust in the time domain\n\nAmplitude {} (Mach), k = {}; BDF2 with Δt = {:.4} (chord/a∞), dual-time Newton–Krylov (at most {} iterations a step).\n\n| period | C_L amplitude |\n|---:|---:|\n",
            t.amplitude_mach, t.reduced_frequency, t.dt, t.max_newton_iterations
        );
        for (i, a) in t.amplitudes.iter().enumerate() {
            md += &format!("| {} | {:.5} |\n", i + 1, a);
        }
        md += &format!(
            "\nSears's incompressible amplitude with the Prandtl–Glauert factor: {:.5} (last period / Sears-PG = {:.3}).\n\n![lift](lift_history.png)\n\n![pressure](pressure_final.png)\n\nFlow field at the last step for ParaView: `flow_final.vtk`.\n",
            t.sears_pg_amplitude,
            t.amplitudes.last().copied().unwrap_or(f64::NAN) / t.sears_pg_amplitude
        );
    }
    if let Some(t) = &r.table2 {
        md += &format!(
            "\n## Table 2: LFD gust response against the time domain\n\nk = {}; probe cell {} at ({:.4}, {:.4}) chords from the leading edge; amplitudes per unit gust velocity (in a∞). LFD (s = iω) against the least-squares Fourier fit of a nonlinear BDF2 run with gust amplitude {:e}; LFD with the BDF2 symbol against the linearized BDF2 march.\n\n| quantity | LFD | Fourier fit | digits | LFD (BDF2 symbol) | linearized BDF2 | digits |\n|---|---|---|---:|---|---|---:|\n",
            t.reduced_frequency, t.probe_cell, t.probe_center[0], t.probe_center[1], t.amplitude_mach
        );
        let z = |v: [f64; 2]| format!("{:.9} {:+.9}i", v[0], v[1]);
        for row in &t.rows {
            md += &format!(
                "| {} | {} | {} | {:.1} | {} | {} | {:.1} |\n",
                row.variable,
                z(row.lfd),
                z(row.fourier),
                row.digits_fourier,
                z(row.lfd_bdf2),
                z(row.linear_bdf2),
                row.digits_bdf2
            );
        }
        md += &format!(
            "\nAgreeing digits (smallest over the rows): Fourier fit {:.1} (the paper: 3–5), BDF2 symbol {:.1}.\n\nOne LFD frequency (factorization and solve, {} GMRES iterations): {:.2} s; the nonlinear time-domain run: {:.1} s ({:.0}× the LFD); the linearized march: {:.1} s.\n\n![lift](table2_lift.png)\n",
            t.digits_fourier,
            t.digits_bdf2,
            t.gmres_iterations,
            t.lfd_time_s,
            t.time_domain_time_s,
            t.time_domain_time_s / t.lfd_time_s,
            t.linear_march_time_s
        );
    }
    if let Some(m) = &r.time_motion {
        let z = |v: [f64; 2]| {
            let c = num_complex::Complex64::new(v[0], v[1]);
            format!("{:.5} ({:+.2}°)", c.norm(), c.arg().to_degrees())
        };
        md += &format!(
            "\n## Prescribed {} in the time domain\n\nk = {}, BDF2 with Δt = {:.4} (chord/a∞), at most {} Newton iterations a step; the whole mesh moves rigidly.\n\n| C_L harmonic (amplitude, phase to the motion's e^{{iωt}}) | |\n|---|---:|\n| time domain, last period | {} |\n| LFD, s = iω | {} |\n| LFD, BDF2 symbol | {} |\n| Theodorsen, Prandtl–Glauert | {} |\n\nTime domain against the BDF2-symbol LFD: {:.1} digits (the motion's amplitude and the transient make the difference: the LFD is the linearization).\n\n![lift](motion_lift.png)\n",
            m.motion,
            m.reduced_frequency,
            m.dt,
            m.max_newton_iterations,
            z(m.time_domain),
            z(m.lfd),
            z(m.lfd_bdf2),
            z(m.theodorsen_pg),
            m.digits_lfd_bdf2
        );
    }
    md += &format!("\nRun time {:.1} s.\n", r.run_time_s);
    md
}

fn cp_plot(title: &str, ps: &[&PressureDistribution]) -> LinePlot {
    let mut series: Vec<Series> = Vec::new();
    for p in ps {
        series.push((format!("{} (upper)", p.label), p.upper.clone()));
        series.push((format!("{} (lower)", p.label), p.lower.clone()));
    }
    LinePlot {
        title: title.into(),
        x_label: "x/c".into(),
        y_label: "C_p (up: negative)".into(),
        series,
        log_y: false,
        flip_y: true,
    }
}

/// Writes results.json, summary.md and the figures of a CFD run into `dir`.
pub fn render(dir: &Path, r: &CfdResults) -> Result<()> {
    if let Some(s) = &r.steady_gust {
        let series = s
            .table1
            .iter()
            .map(|row| {
                (
                    row.case.clone(),
                    row.residual_history
                        .iter()
                        .enumerate()
                        .map(|(i, v)| (i as f64, *v))
                        .collect(),
                )
            })
            .collect();
        save_figure(
            dir,
            "residuals",
            &LinePlot {
                title: format!("{}: Newton residual", r.study),
                x_label: "Newton iteration".into(),
                y_label: "||R||".into(),
                series,
                log_y: true,
                flip_y: false,
            },
        )?;
        let ps: Vec<&PressureDistribution> = s.pressure.iter().collect();
        save_figure(
            dir,
            "pressure",
            &cp_plot(&format!("{}: wall pressure", r.study), &ps),
        )?;
    }
    if let Some(t) = &r.time_gust {
        save_figure(
            dir,
            "lift_history",
            &LinePlot {
                title: format!("{}: lift in the sinusoidal gust", r.study),
                x_label: "t a∞ / c".into(),
                y_label: "C_L".into(),
                series: vec![("C_L".into(), t.lift_history.clone())],
                log_y: false,
                flip_y: false,
            },
        )?;
        save_figure(
            dir,
            "pressure_final",
            &cp_plot(
                &format!("{}: wall pressure at the last step", r.study),
                &[&t.pressure_final],
            ),
        )?;
    }
    if let Some(m) = &r.time_motion {
        save_figure(
            dir,
            "motion_lift",
            &LinePlot {
                title: format!("{}: lift in prescribed {}", r.study, m.motion),
                x_label: "t a∞ / c".into(),
                y_label: "C_L".into(),
                series: vec![("C_L".into(), m.lift_history.clone())],
                log_y: false,
                flip_y: false,
            },
        )?;
    }
    if let Some(t) = &r.table2 {
        save_figure(
            dir,
            "table2_lift",
            &LinePlot {
                title: format!("{}: lift per unit gust, time domain vs LFD", r.study),
                x_label: "t a∞ / c".into(),
                y_label: "C_L / (w_g / a∞)".into(),
                series: vec![
                    (
                        "time domain (mean removed)".into(),
                        t.lift_time_domain.clone(),
                    ),
                    ("LFD Re(−i L̂ e^{iωt})".into(), t.lift_lfd.clone()),
                ],
                log_y: false,
                flip_y: false,
            },
        )?;
    }
    crate::report::write_results(dir, r, &summary(r))
}

/// `gustkit run` of a CFD verification study.
pub fn run(file: &Path, reports: &Path) -> Result<()> {
    let s = CfdStudyFile::load(file)?;
    let dir = reports.join(&s.name);
    std::fs::create_dir_all(&dir)
        .with_context(|| format!("cannot create the run folder {}", dir.display()))?;
    let t0 = Instant::now();
    let mut cells = 0;
    let steady = match &s.cfd.steady_gust {
        Some(g) => {
            let (n, r) = steady_gust(&s.cfd, g, file, &dir)?;
            cells = n;
            println!(
                "Table 1: C_x {:.15e} / {:.15e}, C_z {:.15e} / {:.15e}: {:.1} and {:.1} digits",
                r.table1[0].cx,
                r.table1[1].cx,
                r.table1[0].cz,
                r.table1[1].cz,
                r.digits_cx,
                r.digits_cz
            );
            Some(r)
        }
        None => None,
    };
    let time = match &s.cfd.time_gust {
        Some(g) => {
            let (n, r) = time_gust(&s.cfd, g, file, &dir)?;
            cells = n;
            println!(
                "gust C_L amplitude per period {:?}; Sears-PG {:.5}",
                r.amplitudes, r.sears_pg_amplitude
            );
            Some(r)
        }
        None => None,
    };
    let table2 = match &s.cfd.lfd_gust {
        Some(g) => {
            let (n, t) = table2::run(&s.cfd, g, file)?;
            cells = n;
            println!(
                "Table 2: LFD vs Fourier fit {:.1} digits, BDF2-symbol LFD vs linearized BDF2 {:.1} digits; one LFD frequency {:.2} s vs time domain {:.1} s ({:.0}x)",
                t.digits_fourier,
                t.digits_bdf2,
                t.lfd_time_s,
                t.time_domain_time_s,
                t.time_domain_time_s / t.lfd_time_s
            );
            Some(t)
        }
        None => None,
    };
    let time_motion = match &s.cfd.time_motion {
        Some(m) => {
            let (n, r) = motion::run(&s.cfd, m, file)?;
            cells = n;
            println!(
                "{}: C_L amplitude time domain {:.5}, LFD {:.5} (BDF2 symbol {:.5}: {:.1} digits), Theodorsen-PG {:.5}",
                r.motion,
                r.time_domain[0].hypot(r.time_domain[1]),
                r.lfd[0].hypot(r.lfd[1]),
                r.lfd_bdf2[0].hypot(r.lfd_bdf2[1]),
                r.digits_lfd_bdf2,
                r.theodorsen_pg[0].hypot(r.theodorsen_pg[1])
            );
            Some(r)
        }
        None => None,
    };
    let results = CfdResults {
        study: s.name.clone(),
        description: s.description.clone(),
        cfd: s.cfd.clone(),
        cells,
        steady_gust: steady,
        time_gust: time,
        table2,
        time_motion,
        run_time_s: t0.elapsed().as_secs_f64(),
    };
    render(&dir, &results)?;
    println!("report written to {}", dir.display());
    Ok(())
}
