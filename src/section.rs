//! The 2-D typical section (pitch–plunge airfoil on springs) through the same stochastic-gust
//! (paper Eqs. 16–18) and p-k flutter pipeline as the wing, with two aerodynamic models behind the
//! shared trait side by side: the LFD of the Euler solver and Theodorsen/Sears strip theory.
//! Studies are JSON files with a top-level `typical_section` key, run by `gustkit run`.
//!
//! Structure (per unit span, Theodorsen's notation): semichord b, elastic axis a semichords behind
//! the mid-chord, centre of gravity x_α semichords behind the elastic axis, radius of gyration
//! r_α b about it, mass m = μ π ρ b²; plunge h up and pitch α nose up, so a chord point x moves by
//! w = h − α (x − x_ea). Mass matrix [[m, −m x_α b], [−m x_α b, m r_α² b²]], stiffness
//! diag(m ω_h², m r_α² b² ω_α²); its two mass-normalized modes are the modes of the pipeline.

use crate::flutter::{FlutterResult, PkProblem};
use crate::gust::{self, FrequencyGrid, GustProblem, Turbulence};
use crate::report::figures::{LinePlot, PsdPlot, PsdSeries, VgVf};
use crate::report::save_figure;
use anyhow::{bail, Context, Result};
use gustkit_core::strip::StripSection;
use gustkit_core::{Aerodynamics, FlightCondition, GafTable, ModalSurface};
use gustkit_lfd::airfoil::Section;
use gustkit_lfd::gafs::LfdAero;
use gustkit_lfd::lfd::Lfd;
use gustkit_lfd::residual::{free_stream, Euler, Order};
use gustkit_lfd::steady::SteadyParams;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::Instant;

/// A typical-section study file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SectionStudyFile {
    pub schema_version: u32,
    pub name: String,
    #[serde(default)]
    pub description: String,
    pub typical_section: SectionSpec,
}

/// The case.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SectionSpec {
    pub structure: SectionStructure,
    pub flight: SectionFlight,
    pub cfd: SectionCfd,
    /// Reduced frequencies k = ω b / U of the GAF tables (both models).
    pub reduced_frequencies: Vec<f64>,
    pub gust: SectionGust,
    pub flutter: SectionFlutter,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SectionStructure {
    pub chord_m: f64,
    /// Theodorsen's a: elastic axis behind the mid-chord, semichords.
    pub elastic_axis: f64,
    /// Centre of gravity behind the elastic axis, semichords.
    pub x_alpha: f64,
    /// Radius of gyration about the elastic axis, semichords.
    pub r_alpha: f64,
    /// μ = m / (π ρ b²).
    pub mass_ratio: f64,
    pub plunge_frequency_hz: f64,
    pub pitch_frequency_hz: f64,
    pub damping_ratio: f64,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SectionFlight {
    pub mach: f64,
    pub density_kg_m3: f64,
    pub speed_of_sound_m_s: f64,
}

/// The CFD model: the NACA 64A010 ordinates scaled to `thickness` (fraction of the chord) on the
/// built-in O-mesh.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SectionCfd {
    #[serde(default = "default_thickness")]
    pub thickness: f64,
    pub mesh: crate::cfd::OMeshSpec,
    /// "first" or "second" (default) order.
    #[serde(default = "default_order")]
    pub order: String,
}

fn default_thickness() -> f64 {
    0.10
}
fn default_order() -> String {
    "second".into()
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SectionGust {
    pub turbulence: Turbulence,
    #[serde(default = "crate::study::schema::default_omega_min")]
    pub omega_min_rad_s: f64,
    #[serde(default = "crate::study::schema::default_points")]
    pub points: usize,
    #[serde(default = "crate::study::schema::default_max_tail")]
    pub max_tail: f64,
}

/// p-k sweep speeds.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SectionFlutter {
    pub velocity_min_m_s: f64,
    pub velocity_max_m_s: f64,
    pub velocities: usize,
}

/// The results of one aerodynamic model.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct ModelResults {
    pub model: String,
    pub gafs: GafTable,
    pub rms_plunge_m: f64,
    pub rms_pitch_rad: f64,
    pub psd_plunge: PsdSeries,
    pub psd_pitch: PsdSeries,
    pub flutter: FlutterResult,
    pub time_s: f64,
}

/// Everything a typical-section run writes to results.json.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct SectionResults {
    pub study: String,
    pub description: String,
    pub spec: SectionSpec,
    pub velocity_m_s: f64,
    pub natural_frequencies_hz: Vec<f64>,
    /// (h, α) of each mass-normalized mode.
    pub mode_shapes: Vec<[f64; 2]>,
    pub cells: usize,
    pub models: Vec<ModelResults>,
    pub run_time_s: f64,
}

impl SectionStudyFile {
    /// Reads and checks a study; errors name the file and the field.
    pub fn load(file: &Path) -> Result<Self> {
        let s: Self = crate::report::from_json(file, &crate::report::read_json(file)?)?;
        let bad = |path: &str, reason: String| -> Result<Self> {
            bail!("{}: typical_section.{path}: {reason}", file.display())
        };
        if s.schema_version != crate::study::SCHEMA_VERSION {
            bail!(
                "{}: schema_version: unsupported ({})",
                file.display(),
                s.schema_version
            );
        }
        let t = &s.typical_section;
        let st = &t.structure;
        for (name, v) in [
            ("structure.chord_m", st.chord_m),
            ("structure.r_alpha", st.r_alpha),
            ("structure.mass_ratio", st.mass_ratio),
            ("structure.plunge_frequency_hz", st.plunge_frequency_hz),
            ("structure.pitch_frequency_hz", st.pitch_frequency_hz),
            ("flight.density_kg_m3", t.flight.density_kg_m3),
            ("flight.speed_of_sound_m_s", t.flight.speed_of_sound_m_s),
            ("flutter.velocity_min_m_s", t.flutter.velocity_min_m_s),
            ("cfd.thickness", t.cfd.thickness),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return bad(name, format!("must be positive (got {v})"));
            }
        }
        if !(st.elastic_axis.abs() < 1.0) || !st.x_alpha.is_finite() {
            return bad(
                "structure.elastic_axis",
                format!(
                    "must lie on the chord, in (−1, 1) (got {})",
                    st.elastic_axis
                ),
            );
        }
        if st.r_alpha * st.r_alpha <= st.x_alpha * st.x_alpha {
            return bad(
                "structure.r_alpha",
                format!(
                    "r_alpha² must exceed x_alpha² (a positive-definite mass matrix; got r_alpha {} and x_alpha {})",
                    st.r_alpha, st.x_alpha
                ),
            );
        }
        if !(st.damping_ratio >= 0.0 && st.damping_ratio < 1.0) {
            return bad(
                "structure.damping_ratio",
                format!("must lie in [0, 1) (got {})", st.damping_ratio),
            );
        }
        if !(t.flight.mach > 0.0 && t.flight.mach < 0.8) {
            return bad(
                "flight.mach",
                format!(
                    "must lie in (0, 0.8): subsonic, shock-free (got {})",
                    t.flight.mach
                ),
            );
        }
        if !(t.flutter.velocity_max_m_s > t.flutter.velocity_min_m_s) || t.flutter.velocities < 2 {
            return bad(
                "flutter",
                "need velocity_max_m_s > velocity_min_m_s and at least 2 velocities".into(),
            );
        }
        if t.cfd.order != "first" && t.cfd.order != "second" {
            return bad(
                "cfd.order",
                format!("must be \"first\" or \"second\" (got '{}')", t.cfd.order),
            );
        }
        if let Err(e) = gustkit_core::check_reduced_frequencies(&t.reduced_frequencies) {
            return bad("reduced_frequencies", e.to_string());
        }
        if t.reduced_frequencies.len() < 4 {
            return bad(
                "reduced_frequencies",
                "need at least 4 (cubic-spline interpolation)".into(),
            );
        }
        if let Err(e) = t.gust.turbulence.validate() {
            return bad("gust.turbulence", e);
        }
        let m = &t.cfd.mesh;
        if m.n_around < 8 || m.n_radial < 2 || !(m.first_spacing_chords > 0.0) {
            return bad(
                "cfd.mesh",
                "need n_around >= 8, n_radial >= 2 and a positive first_spacing_chords".into(),
            );
        }
        Ok(s)
    }
}

/// Natural frequencies (rad/s) and mass-normalized mode shapes (h, α) of the section.
pub fn modes(st: &SectionStructure, density: f64) -> (Vec<f64>, Vec<[f64; 2]>) {
    let b = 0.5 * st.chord_m;
    let m = st.mass_ratio * std::f64::consts::PI * density * b * b;
    let s = m * st.x_alpha * b;
    let i = m * st.r_alpha * st.r_alpha * b * b;
    let (wh, wa) = (
        2.0 * std::f64::consts::PI * st.plunge_frequency_hz,
        2.0 * std::f64::consts::PI * st.pitch_frequency_hz,
    );
    let mass = nalgebra::Matrix2::new(m, -s, -s, i);
    let stiff = nalgebra::Matrix2::new(m * wh * wh, 0.0, 0.0, i * wa * wa);
    // L⁻¹ K L⁻ᵀ with M = L Lᵀ: symmetric, its eigenvectors v give mass-normalized φ = L⁻ᵀ v
    let l = mass.cholesky().expect("checked positive definite").l();
    let l_inv = l.try_inverse().expect("a Cholesky factor is invertible");
    let a = l_inv * stiff * l_inv.transpose();
    let eig = a.symmetric_eigen();
    let mut order: Vec<usize> = vec![0, 1];
    order.sort_by(|&p, &q| eig.eigenvalues[p].total_cmp(&eig.eigenvalues[q]));
    let omega = order.iter().map(|&k| eig.eigenvalues[k].sqrt()).collect();
    let shapes = order
        .iter()
        .map(|&k| {
            let phi = l_inv.transpose() * eig.eigenvectors.column(k);
            // sign: positive plunge
            let sign = if phi[0] < 0.0 { -1.0 } else { 1.0 };
            [sign * phi[0], sign * phi[1]]
        })
        .collect();
    (omega, shapes)
}

/// The rigid motion of each mode at an aerodynamic model's surface points (trait frame: z up),
/// rotating about the elastic axis at x_ea (mid-chord at x = 0).
fn modal_surface(aero: &dyn Aerodynamics, shapes: &[[f64; 2]], x_ea: f64) -> ModalSurface {
    let pts = &aero.surface().points;
    let mut m = ModalSurface::zeros(shapes.len(), pts.len());
    for (k, [h, a]) in shapes.iter().enumerate() {
        for (i, p) in pts.iter().enumerate() {
            m.disp[k][i] = [a * p[2], 0.0, h - a * (p[0] - x_ea)];
            m.disp_x[k][i] = [0.0, 0.0, -a];
        }
    }
    m
}

/// The LFD model of the section: the steady flow converged on the built-in mesh.
fn lfd_model(spec: &SectionSpec) -> Result<LfdAero> {
    let c = &spec.cfd;
    let mesh = crate::cfd::builtin_mesh(&c.mesh, &Section::naca64a010().scaled(c.thickness / 0.10));
    mesh.check()
        .map_err(|e| anyhow::anyhow!("typical_section.cfd.mesh: {e}"))?;
    let mut e = Euler::new(mesh, free_stream(spec.flight.mach, 0.0));
    if c.order == "first" {
        e.order = Order::First;
    }
    let params = SteadyParams {
        exact_jacobian: true,
        ..SteadyParams::default()
    };
    let (q0, _) = e
        .solve_steady(vec![e.q_inf; e.mesh.n_cells], &params)
        .map_err(|err| anyhow::anyhow!("typical_section.cfd (steady state): {err}"))?;
    let chord = spec.structure.chord_m;
    // mesh chord 1; the mesh's unit thickness stands for one metre of span (forces per metre)
    Ok(LfdAero::new(Lfd::new(e, q0), chord, chord, 10.0))
}

/// Gust response and flutter of one aerodynamic model.
fn analyze(
    name: &str,
    aero: &dyn Aerodynamics,
    spec: &SectionSpec,
    flight: &FlightCondition,
    omega_n: &[f64],
    shapes: &[[f64; 2]],
) -> Result<ModelResults> {
    let t0 = Instant::now();
    let st = &spec.structure;
    let b = 0.5 * st.chord_m;
    let modes = modal_surface(aero, shapes, st.elastic_axis * b);
    let table = aero
        .gafs(flight, &modes, &spec.reduced_frequencies)
        .map_err(|e| anyhow::anyhow!("{name}: GAFs: {e}"))?;
    let omega_max = table.k.last().copied().unwrap_or(0.0) * flight.velocity / b;
    let g = &spec.gust;
    let grid = FrequencyGrid::log(g.omega_min_rad_s, omega_max, g.points)
        .map_err(|e| anyhow::anyhow!("typical_section.gust: {e}"))?;
    let problem = GustProblem {
        omega_n: omega_n.to_vec(),
        damping_ratio: st.damping_ratio,
        table: &table,
        q_inf: flight.q_inf(),
        velocity: flight.velocity,
        turbulence: g.turbulence,
        grid: grid.clone(),
        outputs: vec![
            shapes.iter().map(|s| s[0]).collect(),
            shapes.iter().map(|s| s[1]).collect(),
        ],
        max_tail: g.max_tail,
    };
    let r = gust::solve(&problem).map_err(|e| anyhow::anyhow!("{name}: gust response: {e}"))?;
    let f = &spec.flutter;
    let velocities: Vec<f64> = (0..f.velocities)
        .map(|i| {
            f.velocity_min_m_s
                + (f.velocity_max_m_s - f.velocity_min_m_s) * i as f64 / (f.velocities - 1) as f64
        })
        .collect();
    let pk = PkProblem {
        omega_n: omega_n.to_vec(),
        damping_ratio: st.damping_ratio,
        table: &table,
        density: flight.density,
    };
    let flutter = pk
        .sweep(&velocities)
        .map_err(|e| anyhow::anyhow!("{name}: flutter: {e}"))?;
    if let Some(v) = flutter.flutter_speed_m_s {
        if v <= flight.velocity {
            bail!(
                "{name}: the section flutters at {v:.2} m/s, below the flight speed {:.2} m/s: its gust response has no steady state (stiffen the section or lower the Mach number)",
                flight.velocity
            );
        }
    }
    let psd = |i: usize, label: &str, unit: &str| PsdSeries {
        label: format!("{name}: {label}"),
        unit: unit.into(),
        omega_rad_s: grid.omega.clone(),
        psd: r.psd[i].clone(),
    };
    Ok(ModelResults {
        model: name.into(),
        rms_plunge_m: r.rms[0],
        rms_pitch_rad: r.rms[1],
        psd_plunge: psd(0, "plunge", "m"),
        psd_pitch: psd(1, "pitch", "rad"),
        gafs: table,
        flutter,
        time_s: t0.elapsed().as_secs_f64(),
    })
}

/// `gustkit run` of a typical-section study.
pub fn run(file: &Path, reports: &Path) -> Result<()> {
    let s = SectionStudyFile::load(file)?;
    let t0 = Instant::now();
    let spec = &s.typical_section;
    let dir = reports.join(&s.name);
    std::fs::create_dir_all(&dir)
        .with_context(|| format!("cannot create the run folder {}", dir.display()))?;
    let st = &spec.structure;
    let (omega_n, shapes) = modes(st, spec.flight.density_kg_m3);
    let b = 0.5 * st.chord_m;
    let flight = FlightCondition {
        mach: spec.flight.mach,
        velocity: spec.flight.mach * spec.flight.speed_of_sound_m_s,
        density: spec.flight.density_kg_m3,
        b_ref: b,
        x_ref: 0.0,
    };
    let lfd = lfd_model(spec)?;
    let cells = lfd.lfd.euler.mesh.n_cells;
    let strip = StripSection::new(b, 0.0, 1.0, 41);
    let models = vec![
        analyze("LFD (Euler)", &lfd, spec, &flight, &omega_n, &shapes)?,
        analyze(
            "Theodorsen/Sears strip (Prandtl–Glauert)",
            &strip,
            spec,
            &flight,
            &omega_n,
            &shapes,
        )?,
    ];
    for m in &models {
        println!(
            "{}: RMS plunge {:.4e} m, pitch {:.4e} rad; flutter {}",
            m.model,
            m.rms_plunge_m,
            m.rms_pitch_rad,
            m.flutter
                .flutter_speed_m_s
                .map_or("none in the sweep".to_string(), |v| format!("{v:.2} m/s"))
        );
    }
    let results = SectionResults {
        study: s.name.clone(),
        description: s.description.clone(),
        spec: spec.clone(),
        velocity_m_s: flight.velocity,
        natural_frequencies_hz: omega_n
            .iter()
            .map(|w| w / (2.0 * std::f64::consts::PI))
            .collect(),
        mode_shapes: shapes,
        cells,
        models,
        run_time_s: t0.elapsed().as_secs_f64(),
    };
    render(&dir, &results)?;
    println!("report written to {}", dir.display());
    Ok(())
}

/// The markdown summary.
pub fn summary(r: &SectionResults) -> String {
    let st = &r.spec.structure;
    let mut md = format!(
        "# {}\n\n{}\n\nTypical section: chord {} m, a = {}, x_α = {}, r_α = {}, μ = {}, ζ = {}; natural frequencies {:.3} and {:.3} Hz. Flight: M = {}, U = {:.2} m/s, ρ = {} kg/m³. LFD: NACA 64A0xx ({:.1} % thick) on a {} × {} O-mesh ({} cells), {} order.\n",
        r.study,
        r.description,
        st.chord_m,
        st.elastic_axis,
        st.x_alpha,
        st.r_alpha,
        st.mass_ratio,
        st.damping_ratio,
        r.natural_frequencies_hz[0],
        r.natural_frequencies_hz[1],
        r.spec.flight.mach,
        r.velocity_m_s,
        r.spec.flight.density_kg_m3,
        100.0 * r.spec.cfd.thickness,
        r.spec.cfd.mesh.n_around,
        r.spec.cfd.mesh.n_radial,
        r.cells,
        r.spec.cfd.order
    );
    md += "\n## Gust response and flutter\n\n| model | RMS plunge (mm) | RMS pitch (deg) | flutter speed (m/s) | flutter frequency (Hz) | time (s) |\n|---|---:|---:|---:|---:|---:|\n";
    for m in &r.models {
        let opt = |v: Option<f64>| v.map_or("—".to_string(), |x| format!("{x:.2}"));
        md += &format!(
            "| {} | {:.4} | {:.4} | {} | {} | {:.1} |\n",
            m.model,
            1e3 * m.rms_plunge_m,
            m.rms_pitch_rad.to_degrees(),
            opt(m.flutter.flutter_speed_m_s),
            opt(m.flutter.flutter_frequency_hz),
            m.time_s
        );
    }
    if let [a, b] = &r.models[..] {
        md += &format!(
            "\nLFD / strip theory: RMS plunge {:.3}, RMS pitch {:.3}. The p-k sweep keeps the GAFs of the study's Mach number at every speed (Nastran PK at fixed Mach).\n",
            a.rms_plunge_m / b.rms_plunge_m,
            a.rms_pitch_rad / b.rms_pitch_rad
        );
    }
    md += "\n## GAFs (per unit span, divided by q∞; modes mass-normalized)\n\n| k | entry | LFD | strip theory |\n|---:|---|---|---|\n";
    if let [a, b] = &r.models[..] {
        for (i, k) in a.gafs.k.iter().enumerate() {
            for (name, x, y) in gaf_entries(&a.gafs, &b.gafs, i) {
                md += &format!(
                    "| {k} | {name} | {:.4} {:+.4}i | {:.4} {:+.4}i |\n",
                    x.re, x.im, y.re, y.im
                );
            }
        }
    }
    md += "\n![GAFs](gafs.png)\n\n![PSD](psd.png)\n\n![V-g LFD](vg_lfd.png)\n\n![V-g strip](vg_strip.png)\n";
    md += &format!("\nRun time {:.1} s.\n", r.run_time_s);
    md
}

type Entry = (String, num_complex::Complex64, num_complex::Complex64);

/// The named GAF entries of two tables at frequency index i.
fn gaf_entries(a: &GafTable, b: &GafTable, i: usize) -> Vec<Entry> {
    let n = a.n_modes();
    let mut out = Vec::new();
    for m in 0..n {
        for k in 0..n {
            out.push((
                format!("Q_ss[{}][{}]", m + 1, k + 1),
                a.q_ss[i][m][k],
                b.q_ss[i][m][k],
            ));
        }
    }
    for m in 0..n {
        out.push((format!("Q_gs[{}]", m + 1), a.q_gs[i][m], b.q_gs[i][m]));
    }
    out
}

/// Writes results.json, summary.md and the figures into `dir`.
pub fn render(dir: &Path, r: &SectionResults) -> Result<()> {
    if let [a, b] = &r.models[..] {
        let mut series = Vec::new();
        let n = a.gafs.k.len();
        for (e, name) in gaf_entries(&a.gafs, &b.gafs, 0)
            .iter()
            .map(|e| &e.0)
            .enumerate()
        {
            for (label, table) in [("LFD", &a.gafs), ("strip", &b.gafs)] {
                let pts: Vec<(f64, f64)> = (0..n)
                    .map(|i| (table.k[i], gaf_entries(table, table, i)[e].1.norm()))
                    .collect();
                series.push((format!("|{name}| {label}"), pts));
            }
        }
        save_figure(
            dir,
            "gafs",
            &LinePlot {
                title: format!("{}: GAF magnitudes against k", r.study),
                x_label: "k = ω b / U".into(),
                y_label: "|Q| (per unit span)".into(),
                series,
                log_y: true,
                flip_y: false,
            },
        )?;
        save_figure(
            dir,
            "psd",
            &PsdPlot {
                title: format!("{}: response PSD", r.study),
                panels: vec![
                    vec![a.psd_plunge.clone(), b.psd_plunge.clone()],
                    vec![a.psd_pitch.clone(), b.psd_pitch.clone()],
                ],
            },
        )?;
        for (m, stem) in [(a, "vg_lfd"), (b, "vg_strip")] {
            save_figure(
                dir,
                stem,
                &VgVf {
                    result: &m.flutter,
                    title: format!("{}: p-k, {}", r.study, m.model),
                },
            )?;
        }
    }
    crate::report::write_results(dir, r, &summary(r))
}
