//! The typical-section run: the mass-normalized modes, each aerodynamic model from the fidelity
//! registry through the same gust-response (Eqs. 16–18) and p-k pipeline, and the results.

use super::schema::{SectionSpec, SectionStudyFile};
use crate::aero::lfd::SectionLfdSpec;
use crate::aero::strip::StripSpec;
use crate::aero::SectionFidelitySpec;
use crate::flutter::{FlutterResult, PkProblem};
use crate::gust::{self, FrequencyGrid, GustProblem};
use crate::kind::StudyKind;
use crate::report::figures::PsdSeries;
use anyhow::{bail, Result};
use gustkit_core::{Aerodynamics, FlightCondition, GafTable, ModalSurface};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::Instant;

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
    /// Always `typical_section`.
    pub kind: StudyKind,
    pub study: String,
    pub description: String,
    pub spec: SectionSpec,
    pub velocity_m_s: f64,
    pub natural_frequencies_hz: Vec<f64>,
    /// (h, α) of each mass-normalized mode.
    pub mode_shapes: Vec<[f64; 2]>,
    pub cells: usize,
    pub models: Vec<ModelResults>,
    /// The LFD on the O-mesh refined by two in each direction (absent before this field).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub resolution_check: Option<SectionResolution>,
    pub run_time_s: f64,
}

/// The typical section's resolution check: its two modes are exact, so what the model leaves out
/// is the LFD's mesh; the section analysed again on the O-mesh with twice the cells around and
/// across (the first spacing halved), the RMS and flutter speed at both meshes.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct SectionResolution {
    /// The study's mesh and the refined one ("64 × 32 O-mesh, 2048 cells").
    pub model: String,
    pub refined_model: String,
    /// RMS plunge (m) and pitch (rad), and the flutter speed (m/s, none in the sweep), at the
    /// study's mesh and at the refined one.
    pub rms_plunge_m: [f64; 2],
    pub rms_pitch_rad: [f64; 2],
    pub flutter_speed_m_s: [Option<f64>; 2],
    pub time_s: f64,
}

impl SectionResolution {
    /// The check in one paragraph, the changes in percent.
    pub fn words(&self) -> String {
        let change = |[a, b]: [f64; 2]| format!("{:+.2} %", 100.0 * (b / a - 1.0));
        let flutter = match self.flutter_speed_m_s {
            [Some(a), Some(b)] => format!("flutter {a:.2} → {b:.2} m/s ({})", change([a, b])),
            [a, b] => format!(
                "flutter {} → {}",
                a.map_or("none in the sweep".into(), |v| format!("{v:.2} m/s")),
                b.map_or("none in the sweep".into(), |v| format!("{v:.2} m/s"))
            ),
        };
        format!(
            "Resolution check: the LFD on the {} and on the {}: RMS plunge {}, RMS pitch {}, {flutter} ({:.1} s).",
            self.model,
            self.refined_model,
            change(self.rms_plunge_m),
            change(self.rms_pitch_rad),
            self.time_s
        )
    }
}

/// The O-mesh's words: sizes and cells.
fn mesh_words(m: &crate::aero::lfd::OMeshSpec) -> String {
    format!(
        "{} × {} O-mesh ({} cells)",
        m.n_around,
        m.n_radial,
        m.n_around * m.n_radial
    )
}

/// The resolution check of the LFD model `coarse` of the section: the same analysis on the
/// O-mesh refined by two in each direction.
fn resolution_check(
    spec: &SectionSpec,
    coarse: &ModelResults,
    flight: &FlightCondition,
    omega_n: &[f64],
    shapes: &[[f64; 2]],
) -> Result<SectionResolution> {
    let t0 = Instant::now();
    let mut cfd = spec.cfd.clone();
    cfd.mesh.n_around *= 2;
    cfd.mesh.n_radial *= 2;
    cfd.mesh.first_spacing_chords /= 2.0;
    let refined = SectionFidelitySpec::Lfd(cfd.clone());
    let (aero, _) = refined
        .build(spec.structure.chord_m, spec.flight.mach)
        .map_err(|e| anyhow::anyhow!("resolution check: the refined O-mesh: {e}"))?;
    let fine = analyze(
        refined.display_name(),
        aero.as_ref(),
        spec,
        flight,
        omega_n,
        shapes,
    )
    .map_err(|e| anyhow::anyhow!("resolution check: {e:#}"))?;
    Ok(SectionResolution {
        model: mesh_words(&spec.cfd.mesh),
        refined_model: mesh_words(&cfd.mesh),
        rms_plunge_m: [coarse.rms_plunge_m, fine.rms_plunge_m],
        rms_pitch_rad: [coarse.rms_pitch_rad, fine.rms_pitch_rad],
        flutter_speed_m_s: [
            coarse.flutter.flutter_speed_m_s,
            fine.flutter.flutter_speed_m_s,
        ],
        time_s: t0.elapsed().as_secs_f64(),
    })
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
        residual: None,
    };
    let r = gust::solve(&problem).map_err(|e| anyhow::anyhow!("{name}: gust response: {e}"))?;
    let f = &spec.flutter;
    let velocities: Vec<f64> = (0..f.velocities)
        .map(|i| {
            f.velocity_min_m_s
                + (f.velocity_max_m_s - f.velocity_min_m_s) * i as f64 / (f.velocities - 1) as f64
        })
        .collect();
    let pk = PkProblem::from_parts(omega_n.to_vec(), st.damping_ratio, &table, flight.density);
    let flutter = pk
        .sweep(&velocities)
        .map_err(|e| anyhow::anyhow!("{name}: flutter: {e}"))?;
    let verdict = crate::flutter::Verdict::of(&flutter);
    if !verdict.stable_up_to(flight.velocity) {
        bail!(
            "{name}: the section {}: its gust response has no steady state (stiffen the section or lower the Mach number)",
            verdict.words(flight.velocity)
        );
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
pub fn run(s: &SectionStudyFile, reports: &Path) -> Result<()> {
    let t0 = Instant::now();
    let spec = &s.typical_section;
    let final_dir = reports.join(&s.name);
    let folder = crate::report::folder::RunFolder::begin(&final_dir, false)?;
    let dir = folder.path().to_path_buf();
    let st = &spec.structure;
    let (omega_n, shapes) = super::modes(st, spec.flight.density_kg_m3);
    let b = 0.5 * st.chord_m;
    let flight = FlightCondition {
        mach: spec.flight.mach,
        velocity: spec.flight.mach * spec.flight.speed_of_sound_m_s,
        density: spec.flight.density_kg_m3,
        b_ref: b,
        x_ref: 0.0,
    };
    let fidelities = [
        SectionFidelitySpec::Lfd(SectionLfdSpec::clone(&spec.cfd)),
        SectionFidelitySpec::Strip(StripSpec::default()),
    ];
    let mut models = Vec::with_capacity(fidelities.len());
    let mut cells = 0;
    for f in &fidelities {
        let (aero, n) = f.build(st.chord_m, spec.flight.mach).map_err(|e| {
            anyhow::anyhow!("{}: {}: {e}", s_file(s), e.path_in("typical_section.cfd"))
        })?;
        cells = cells.max(n);
        models.push(analyze(
            f.display_name(),
            aero.as_ref(),
            spec,
            &flight,
            &omega_n,
            &shapes,
        )?);
    }
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
    let check = resolution_check(spec, &models[0], &flight, &omega_n, &shapes)?;
    println!("{}", check.words());
    let results = SectionResults {
        kind: StudyKind::TypicalSection,
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
        resolution_check: Some(check),
        run_time_s: t0.elapsed().as_secs_f64(),
    };
    super::render(&dir, &results)?;
    folder.commit()?;
    println!("report written to {}", final_dir.display());
    Ok(())
}

/// The study file's name for messages.
fn s_file(s: &SectionStudyFile) -> String {
    s.file.display().to_string()
}
