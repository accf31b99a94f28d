//! What the `gustkit` subcommands do; `main.rs` only parses arguments.

use crate::report::run::{
    flutter_point, frequency_table, DesignSnapshot, FlutterSummary, GustResults, HistoryRow,
    ModeRow, OptimizationResults, OutputRow, RunResults,
};
use crate::report::{self, figures::ModeShapes, figures::PsdSeries, save_figure, write_atomic};
use crate::structure::model::Field;
use crate::structure::{mass_grad, modal, modes_vjp, ModalSeed, Modes, PlateModel, Sampler};
use crate::study::Study;
use anyhow::{Context, Result};
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// The modal analysis of a study as written to JSON.
#[derive(Serialize)]
pub struct ModalSummary {
    pub study: String,
    pub mass_kg: f64,
    pub area_m2: f64,
    pub frequencies_hz: Vec<f64>,
    pub modes: Vec<ModeRow>,
}

fn field_name(f: Field) -> &'static str {
    match f {
        Field::Bending => "bending",
        Field::Membrane => "membrane",
    }
}

/// Builds the model of a study and solves its modes.
pub fn analyze(study: &Study) -> Result<(PlateModel, Modes, ModalSummary)> {
    let model = study.build_model()?;
    let st = &study.spec.structure;
    let modes = modal::solve(&model, st.modes, st.damping_ratio, &study.mode_fields())
        .with_context(|| format!("{}: modal analysis", study.file.display()))?;
    let tip = Sampler::new(&model, &[[1.0, 1.0]]);
    let summary = ModalSummary {
        study: study.spec.name.clone(),
        mass_kg: model.mass(),
        area_m2: model.planform().area(),
        frequencies_hz: modes.freq_hz(),
        modes: modes
            .modes
            .iter()
            .enumerate()
            .map(|(i, m)| ModeRow {
                mode: i + 1,
                frequency_hz: m.freq_hz(),
                field: field_name(m.field).to_string(),
                tip_te_w: tip.sample(&model, &m.shape)[0][0],
            })
            .collect(),
    };
    Ok((model, modes, summary))
}

/// Name of the study's display length unit.
fn unit_label(study: &Study) -> &'static str {
    match study.spec.length_unit {
        crate::study::LengthUnit::M => "m",
        crate::study::LengthUnit::In => "in",
        crate::study::LengthUnit::Ft => "ft",
    }
}

/// The mode-shape figure data of a model.
fn mode_shapes(study: &Study, model: &PlateModel, modes: &Modes) -> ModeShapes {
    ModeShapes::new(
        model,
        modes,
        unit_label(study),
        study.spec.length_unit.to_m(),
    )
}

/// Writes the modal figures and the VTK file into `dir`.
fn write_modal_files(study: &Study, model: &PlateModel, modes: &Modes, dir: &Path) -> Result<()> {
    save_figure(dir, "modes", &mode_shapes(study, model, modes))?;
    let vtk = report::vtk::plate_modes(model, modes, &format!("gustkit {} modes", study.spec.name));
    write_atomic(&dir.join("modes.vtk"), vtk.as_bytes())
}

/// `gustkit modes`.
pub fn modes(file: &Path, json: bool, reports: &Path) -> Result<()> {
    let study = Study::load(file)?;
    let (model, modes, summary) = analyze(&study)?;
    let dir = study.report_dir(reports);
    write_modal_files(&study, &model, &modes, &dir)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
        eprintln!("figures and VTK written to {}", dir.display());
    } else {
        println!(
            "{}: mass {:.4} kg, planform area {:.4} m²",
            summary.study, summary.mass_kg, summary.area_m2
        );
        print!("{}", frequency_table(&summary.modes));
        println!("figures and VTK written to {}", dir.display());
    }
    Ok(())
}

/// The response PSD of output `i` of an evaluation, for the figures: at most about 500 of the
/// log-spaced grid points (every n-th and the last), so that results.json stays small.
fn psd_series(ev: &crate::pipeline::Evaluation, i: usize) -> PsdSeries {
    let o = &ev.settings().outputs[i];
    let n = ev.grid.omega.len();
    let stride = n.div_ceil(500).max(1);
    let keep: Vec<usize> = (0..n).filter(|j| j % stride == 0 || *j == n - 1).collect();
    PsdSeries {
        label: o.name.clone(),
        unit: o.quantity.unit().to_string(),
        omega_rad_s: keep.iter().map(|&j| ev.grid.omega[j]).collect(),
        psd: keep.iter().map(|&j| ev.response.psd[i][j]).collect(),
    }
}

/// The gust response part of the results at the study's design.
fn gust_results(study: &Study) -> Result<GustResults> {
    let settings = study.gust_settings()?;
    let x = study.initial_design()?.to_vec();
    let ev = crate::pipeline::evaluate(study, &settings, &x)
        .with_context(|| format!("{}: gust analysis", study.file.display()))?;
    let f = ev.aero.flight;
    let outputs: Vec<OutputRow> = settings
        .outputs
        .iter()
        .enumerate()
        .map(|(i, o)| OutputRow {
            name: o.name.clone(),
            rms: ev.rms_m[i],
            unit: o.quantity.unit().to_string(),
            n0_hz: ev.n0_hz[i],
        })
        .collect();
    for o in &outputs {
        println!("RMS {}: {:.6e} {}", o.name, o.rms, o.unit);
    }
    let spec = study.spec.gust.as_ref().expect("checked by gust_settings");
    let calibration = match &spec.calibration {
        Some(c) => {
            let i = settings
                .outputs
                .iter()
                .position(|o| o.name == c.output)
                .with_context(|| {
                    format!(
                        "{}: gust.calibration.output: no gust output named '{}'",
                        study.file.display(),
                        c.output
                    )
                })?;
            let (to_unit, unit) = match settings.outputs[i].quantity {
                crate::pipeline::Quantity::Displacement { .. } => {
                    (1.0 / study.spec.length_unit.to_m(), unit_label(study))
                }
                crate::pipeline::Quantity::RootBendingMoment => (1.0, "N m"),
            };
            let rms = ev.rms_m[i] * to_unit;
            let sigma = settings.turbulence.sigma();
            println!(
                "σ_w calibration: RMS {} {rms:.5} {unit} (target {} {unit}); σ_w for the target {:.5} m/s",
                c.output,
                c.target_rms,
                sigma * c.target_rms / rms
            );
            Some(crate::report::run::Calibration {
                output: c.output.clone(),
                target_rms: c.target_rms,
                rms,
                unit: unit.to_string(),
                sigma_w_m_s: sigma,
                sigma_w_for_target_m_s: sigma * c.target_rms / rms,
                source: c.source.clone(),
            })
        }
        None => None,
    };
    Ok(GustResults {
        mach: f.mach,
        velocity_m_s: f.velocity,
        density_kg_m3: f.density,
        q_inf_pa: f.q_inf(),
        turbulence: settings.turbulence,
        n_omega: ev.grid.omega.len(),
        omega_max_rad_s: ev.grid.omega.last().copied().unwrap_or(0.0),
        psd: (0..outputs.len()).map(|i| psd_series(&ev, i)).collect(),
        outputs,
        calibration,
    })
}

/// `gustkit run`: every analysis the study defines, with its report.
pub fn run(file: &Path, reports: &Path, resume: bool) -> Result<()> {
    match top_level_key(file, &["typical_section", "cfd"]) {
        Some("typical_section") => return crate::section::run(file, reports),
        Some(_) => return crate::cfd::run(file, reports),
        None => {}
    }
    let study = Study::load(file)?;
    let t0 = Instant::now();
    let (model, modes, summary) = analyze(&study)?;
    let dir = study.report_dir(reports);
    // fail early, before any long computation, when the run folder cannot be written
    std::fs::create_dir_all(&dir)
        .with_context(|| format!("cannot create the run folder {}", dir.display()))?;
    let vtk = report::vtk::plate_modes(
        &model,
        &modes,
        &format!("gustkit {} modes", study.spec.name),
    );
    write_atomic(&dir.join("modes.vtk"), vtk.as_bytes())?;
    println!("{}", frequency_table(&summary.modes));
    let gust = match study.spec.gust {
        Some(_) => Some(gust_results(&study)?),
        None => None,
    };
    let flutter = match study.spec.flutter {
        Some(_) => {
            let (doc, r, velocities) = flutter_analysis(&study, reports)?;
            print_flutter(&study, &r, &velocities, &doc);
            Some(FlutterSummary {
                mach: doc["mach"].as_f64().unwrap_or(f64::NAN),
                density_kg_m3: doc["density_kg_m3"].as_f64().unwrap_or(f64::NAN),
                result: r,
            })
        }
        None => None,
    };
    let optimization = match study.spec.optimization {
        Some(_) => Some(optimize(&study, &dir, resume, false)?),
        None => None,
    };
    let results = RunResults {
        study: study.spec.name.clone(),
        description: study.spec.description.clone(),
        length_unit: unit_label(&study).to_string(),
        mass_kg: summary.mass_kg,
        area_m2: summary.area_m2,
        n_design_variables: model.design.len(),
        frequencies_hz: summary.frequencies_hz,
        modes: summary.modes,
        mode_shapes: mode_shapes(&study, &model, &modes),
        gust,
        flutter,
        optimization,
        run_time_s: t0.elapsed().as_secs_f64(),
    };
    report::run::render(&dir, &results)?;
    println!("report written to {}", dir.display());
    Ok(())
}

/// The first of `keys` that a JSON study file has at its top level: `typical_section` studies
/// and CFD verification studies (`cfd`) run by their own modules.
fn top_level_key(file: &Path, keys: &[&'static str]) -> Option<&'static str> {
    let v = std::fs::read_to_string(file)
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())?;
    keys.iter().copied().find(|k| v.get(*k).is_some())
}

/// `gustkit report RUN_DIR`: every figure and the summary again, from results.json alone (or, for
/// a sweep folder, from sweep_results.json).
pub fn report(dir: &Path) -> Result<()> {
    if dir.join("sweep_results.json").is_file() {
        let r = report::sweep::rerender(dir)?;
        println!(
            "sweep report of {} re-rendered from {}",
            r.study,
            dir.join("sweep_results.json").display()
        );
        return Ok(());
    }
    let results = dir.join("results.json");
    let value = report::read_json(&results)?;
    let study = if value.get("models").is_some() && value.get("spec").is_some() {
        let r: crate::section::SectionResults = report::from_json(&results, &value)?;
        crate::section::render(dir, &r)?;
        r.study
    } else if value.get("cfd").is_some() {
        let r: crate::cfd::CfdResults = report::from_json(&results, &value)?;
        crate::cfd::render(dir, &r)?;
        r.study
    } else {
        report::run::rerender(dir, &results, &value)?.study
    };
    println!("report of {study} re-rendered from {}", results.display());
    Ok(())
}

/// Timings of the structural chain, seconds (medians).
#[derive(Debug, Serialize)]
pub struct StructureTimings {
    /// Assembly of K and M alone (informational: the modal analysis includes it).
    pub assembly_s: f64,
    /// Assembly + Cholesky + complete eigen-decomposition.
    pub modes_s: f64,
    pub sensitivities_s: f64,
    pub total_s: f64,
    pub n_dv: usize,
    pub n_modes: usize,
}

/// Times assembly + modal analysis + the gradients of every frequency, the tip deflection of every
/// mode and the mass with respect to all design variables (one reverse sweep each).
pub fn bench_structure(study: &Study, repeat: usize) -> Result<StructureTimings> {
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (mut ta, mut tm, mut ts, mut tt) = (vec![], vec![], vec![], vec![]);
    let st = &study.spec.structure;
    let (mut n_dv, mut n_modes) = (0, 0);
    for _ in 0..repeat.max(1) {
        let t0 = Instant::now();
        let model = study.build_model()?;
        let t0b = Instant::now();
        for f in study.mode_fields() {
            std::hint::black_box(model.assemble(f));
        }
        let t1 = Instant::now();
        let modes = modal::solve(&model, st.modes, st.damping_ratio, &study.mode_fields())?;
        let t2 = Instant::now();
        let tip = Sampler::new(&model, &[[1.0, 1.0]]);
        let mut grads = vec![mass_grad(&model)];
        for i in 0..modes.len() {
            let mut seed = ModalSeed::zeros(&modes);
            seed.lambda[i] = 1.0;
            grads.push(modes_vjp(&model, &modes, &seed));
            let mut seed = ModalSeed::zeros(&modes);
            let (nodal_bar, _) =
                tip.sample_vjp(&model, &modes.modes[i].shape, &[[1.0, 0.0, 0.0, 0.0, 0.0]]);
            seed.shape[i] = nodal_bar;
            grads.push(modes_vjp(&model, &modes, &seed));
        }
        let t3 = Instant::now();
        n_dv = grads[0].len();
        n_modes = modes.len();
        std::hint::black_box(grads);
        ta.push((t1 - t0).as_secs_f64());
        tm.push((t2 - t1).as_secs_f64());
        ts.push((t3 - t2).as_secs_f64());
        // the modal analysis assembles again: the chain is model + modes + sensitivities
        tt.push((t3 - t1).as_secs_f64() + (t0b - t0).as_secs_f64());
    }
    Ok(StructureTimings {
        assembly_s: median(ta),
        modes_s: median(tm),
        sensitivities_s: median(ts),
        total_s: median(tt),
        n_dv,
        n_modes,
    })
}

/// `gustkit bench`.
pub fn bench(file: &Path, repeat: usize, optimization: bool) -> Result<()> {
    let study = Study::load(file)?;
    let t = bench_structure(&study, repeat)?;
    println!(
        "structure ({}; {} design variables, {} modes, median of {repeat}):",
        study.spec.name, t.n_dv, t.n_modes
    );
    println!(
        "  assembly of K, M alone        {:8.2} ms",
        1e3 * t.assembly_s
    );
    println!("  modal analysis (+ assembly)   {:8.2} ms", 1e3 * t.modes_s);
    println!(
        "  sensitivities (2N+1 gradients){:8.2} ms",
        1e3 * t.sensitivities_s
    );
    println!("  total (model, modes, grads)   {:8.2} ms", 1e3 * t.total_s);
    if study.spec.aero.is_some() {
        let a = bench_aero(&study, 3)?;
        println!(
            "aerodynamics (DLM, {} boxes, {} reduced frequencies, {} modes):",
            a.n_boxes, a.n_k, a.n_modes
        );
        println!(
            "  influence matrices (all k)    {:8.1} ms",
            1e3 * a.assembly_s
        );
        println!(
            "  LU factorizations, 1 thread   {:8.1} ms",
            1e3 * a.factorization_s
        );
        println!("  GAFs (all k, with matrices)   {:8.1} ms", 1e3 * a.gafs_s);
        println!(
            "  GAF reverse (matrices reused) {:8.1} ms",
            1e3 * a.gafs_vjp_s
        );
    }
    if study.spec.gust.is_some() {
        let (f, g) = bench_pipeline(&study)?;
        println!(
            "gust pipeline (all {} design variables):",
            study.initial_design()?.len()
        );
        println!(
            "  function (modes, GAFs, stability, RMS)  {:8.1} ms",
            1e3 * f
        );
        println!(
            "  gradient (one reverse sweep)            {:8.1} ms",
            1e3 * g
        );
    }
    if optimization {
        if study.spec.optimization.is_none() {
            anyhow::bail!(
                "{}: --optimization: the study has no optimization section",
                file.display()
            );
        }
        let dir = std::env::temp_dir().join(format!("gustkit-bench-{}", std::process::id()));
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("cannot create {}", dir.display()))?;
        let t = Instant::now();
        let o = optimize(&study, &dir, false, true);
        let wall = t.elapsed().as_secs_f64();
        let _ = std::fs::remove_dir_all(&dir);
        let o = o?;
        println!(
            "whole optimization ({}): {:.1} s wall, {} iterations, {} evaluations, {:.0} ms per iteration; mass {:+.1} %",
            o.message,
            wall,
            o.iterations,
            o.evaluations,
            1e3 * wall / o.iterations.max(1) as f64,
            100.0 * (o.final_.mass_kg / o.initial.mass_kg - 1.0)
        );
    }
    Ok(())
}

/// Conventions written into every GAF and AIC file.
const CONVENTIONS: [&str; 5] = [
    "time dependence exp(+i omega t); reduced frequency k = omega b_ref / U (b_ref a semichord)",
    "modal force = q_inf * Q_ss(ik) * eta + q_inf * Q_gs(ik) * (w_g / U)",
    "gust: vertical, unit w_g/U, phase exp(-i k (x - x_ref) / b_ref)",
    "Q_ss[k][m][n]: force on mode m from unit motion of mode n; modes mass-normalized (kg^-1/2 m)",
    "AIC: w_j / U = sum_s D[j][s] dCp_s, normalwash at control points, dCp = (p_lower - p_upper) / q_inf",
];

/// The GAF table as written by `gustkit gafs`.
#[derive(Serialize)]
pub struct GafFile {
    pub conventions: Vec<String>,
    pub study: String,
    pub fidelity: String,
    pub mach: f64,
    pub velocity_m_s: f64,
    pub density_kg_m3: f64,
    pub q_inf_pa: f64,
    pub b_ref_m: f64,
    pub x_ref_m: f64,
    pub k: Vec<f64>,
    pub modes: Vec<ModeRow>,
    pub q_ss_re: Vec<Vec<Vec<f64>>>,
    pub q_ss_im: Vec<Vec<Vec<f64>>>,
    pub q_gs_re: Vec<Vec<f64>>,
    pub q_gs_im: Vec<Vec<f64>>,
}

/// `gustkit gafs`: modes, transfer and GAFs of a study, written to `out` as JSON.
pub fn gafs(file: &Path, out: &Path) -> Result<()> {
    let study = Study::load(file)?;
    let (plate, modes, summary) = analyze(&study)?;
    let aero = crate::study::AeroModel::new(&study, &plate)?;
    let t0 = Instant::now();
    let table = aero
        .gafs(&plate, &modes)
        .map_err(|e| anyhow::anyhow!("{}: aero: {e}", file.display()))?;
    let elapsed = t0.elapsed().as_secs_f64();
    let f = &aero.flight;
    let parts = |g: &dyn Fn(num_complex::Complex64) -> f64| {
        table
            .q_ss
            .iter()
            .map(|k| {
                k.iter()
                    .map(|r| r.iter().map(|v| g(*v)).collect())
                    .collect()
            })
            .collect::<Vec<Vec<Vec<f64>>>>()
    };
    let gparts = |g: &dyn Fn(num_complex::Complex64) -> f64| {
        table
            .q_gs
            .iter()
            .map(|k| k.iter().map(|v| g(*v)).collect())
            .collect::<Vec<Vec<f64>>>()
    };
    let doc = GafFile {
        conventions: CONVENTIONS.iter().map(|s| s.to_string()).collect(),
        study: study.spec.name.clone(),
        fidelity: "dlm".into(),
        mach: f.mach,
        velocity_m_s: f.velocity,
        density_kg_m3: f.density,
        q_inf_pa: f.q_inf(),
        b_ref_m: f.b_ref,
        x_ref_m: f.x_ref,
        k: table.k.clone(),
        modes: summary.modes,
        q_ss_re: parts(&|v| v.re),
        q_ss_im: parts(&|v| v.im),
        q_gs_re: gparts(&|v| v.re),
        q_gs_im: gparts(&|v| v.im),
    };
    write_atomic(out, serde_json::to_string_pretty(&doc)?.as_bytes())?;
    println!(
        "GAFs of {} modes at {} reduced frequencies ({:.1} ms) written to {}",
        modes.len(),
        table.k.len(),
        1e3 * elapsed,
        out.display()
    );
    Ok(())
}

/// A bare lifting-surface file for `gustkit aic` (SI).
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct SurfaceFile {
    /// Reference semichord of the reduced frequencies, m.
    b_ref: f64,
    #[serde(default)]
    symmetry: gustkit_dlm::Symmetry,
    surfaces: Vec<gustkit_dlm::SurfaceSpec>,
}

/// One box as written by `gustkit aic`.
#[derive(Serialize)]
struct BoxRow {
    corners: [[f64; 3]; 4],
    control_point: [f64; 3],
    doublet_point: [f64; 3],
    area: f64,
    chord: f64,
    normal: [f64; 3],
}

/// The influence matrix at one reduced frequency.
#[derive(Serialize)]
struct AicRow {
    k: f64,
    re: Vec<Vec<f64>>,
    im: Vec<Vec<f64>>,
}

/// `gustkit aic`: box geometry and the complex influence matrices of a study's DLM or of a bare
/// surface file, for cross-checks against other DLM codes.
pub fn aic(file: &Path, mach: f64, ks: &[f64], out: &Path) -> Result<()> {
    let text =
        std::fs::read_to_string(file).with_context(|| format!("cannot read {}", file.display()))?;
    let value: serde_json::Value = serde_json::from_str(&text)
        .with_context(|| format!("{}: not valid JSON", file.display()))?;
    let (dlm, b_ref) = if value.get("schema_version").is_some() {
        let study = Study::load(file)?;
        let plate = study.build_model()?;
        let Some(aero) = &study.spec.aero else {
            anyhow::bail!("{}: aero: missing (the study has no DLM)", file.display());
        };
        let crate::study::FidelitySpec::Dlm(spec) = &aero.fidelity;
        let (surface, _) = crate::study::fidelity::dlm_surface(plate.planform(), spec);
        let dlm = gustkit_dlm::Dlm::new(vec![surface], spec.symmetry)
            .map_err(|e| anyhow::anyhow!("{}: aero.fidelity.dlm: {e}", file.display()))?;
        let b_ref = study
            .flight_condition()
            .map(|f| f.b_ref)
            .unwrap_or(0.5 * plate.planform().root_chord);
        (dlm, b_ref)
    } else {
        let de = &mut serde_json::Deserializer::from_str(&text);
        let sf: SurfaceFile = serde_path_to_error::deserialize(de)
            .map_err(|e| anyhow::anyhow!("{}: {}: {}", file.display(), e.path(), e.inner()))?;
        if !(sf.b_ref > 0.0) {
            anyhow::bail!(
                "{}: b_ref: must be positive (got {})",
                file.display(),
                sf.b_ref
            );
        }
        let dlm = gustkit_dlm::Dlm::new(sf.surfaces, sf.symmetry)
            .map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
        (dlm, sf.b_ref)
    };
    if !(0.0..1.0).contains(&mach) {
        anyhow::bail!(
            "--mach: the doublet-lattice method is subsonic only, need 0 <= M < 1 (got {mach})"
        );
    }
    gustkit_core::check_reduced_frequencies(ks).map_err(|e| anyhow::anyhow!("--k: {e}"))?;
    let n = dlm.n_boxes();
    let boxes: Vec<BoxRow> = dlm
        .boxes
        .iter()
        .map(|b| BoxRow {
            corners: b.corners,
            control_point: b.cp,
            doublet_point: b.dp,
            area: b.area,
            chord: b.chord,
            normal: b.normal(),
        })
        .collect();
    let aics: Vec<AicRow> = ks
        .iter()
        .map(|&k| {
            let d = dlm.influence_matrix(&dlm.boxes, mach, k / b_ref);
            AicRow {
                k,
                re: (0..n)
                    .map(|i| (0..n).map(|j| d[i * n + j].re).collect())
                    .collect(),
                im: (0..n)
                    .map(|i| (0..n).map(|j| d[i * n + j].im).collect())
                    .collect(),
            }
        })
        .collect();
    let doc = serde_json::json!({
        "conventions": CONVENTIONS,
        "mach": mach,
        "b_ref_m": b_ref,
        "symmetry": dlm.symmetry,
        "boxes": boxes,
        "aic": aics,
    });
    write_atomic(out, serde_json::to_string(&doc)?.as_bytes())?;
    println!(
        "{n} boxes, {} influence matrices written to {}",
        ks.len(),
        out.display()
    );
    Ok(())
}

/// Timings of the aerodynamic chain for a study, seconds.
#[derive(Debug, Serialize)]
pub struct AeroTimings {
    pub n_boxes: usize,
    pub n_k: usize,
    pub n_modes: usize,
    /// Influence matrices at every k (one pass over the box pairs, rows in parallel).
    pub assembly_s: f64,
    /// LU factorizations at every k, one thread.
    pub factorization_s: f64,
    /// `Aerodynamics::gafs` as used (rayon over k): assembly, factorization, solves, GAFs.
    pub gafs_s: f64,
    /// `gafs_vjp` (reverse mode incl. geometry), rayon over k.
    pub gafs_vjp_s: f64,
}

/// Times the DLM of a study (see [`AeroTimings`]); medians of `repeat` runs for the parallel parts.
pub fn bench_aero(study: &Study, repeat: usize) -> Result<AeroTimings> {
    use faer::{c64, Mat};
    let (plate, modes, _) = analyze(study)?;
    let aero = crate::study::AeroModel::new(study, &plate)?;
    let Some(crate::study::AeroSpec {
        fidelity: crate::study::FidelitySpec::Dlm(spec),
        ..
    }) = &study.spec.aero
    else {
        anyhow::bail!("the study has no DLM");
    };
    let (surface, _) = crate::study::fidelity::dlm_surface(plate.planform(), spec);
    let dlm =
        gustkit_dlm::Dlm::new(vec![surface], spec.symmetry).map_err(|e| anyhow::anyhow!("{e}"))?;
    let f = aero.flight;
    let n = dlm.n_boxes();
    let t0 = Instant::now();
    let kds: Vec<f64> = aero.k.iter().map(|k| k / f.b_ref).collect();
    let mats: Vec<Mat<c64>> = dlm
        .influence_matrices(&dlm.boxes, f.mach, &kds)
        .iter()
        .map(|d| Mat::from_fn(n, n, |i, j| d[i * n + j].value()))
        .collect();
    let t1 = Instant::now();
    for m in &mats {
        std::hint::black_box(m.partial_piv_lu());
    }
    let t2 = Instant::now();
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let mut tg = Vec::new();
    let mut tv = Vec::new();
    for _ in 0..repeat.max(1) {
        // a fresh model each time: the GAFs build the influence matrices, the reverse mode then
        // reuses them as in the pipeline
        let aero = crate::study::AeroModel::new(study, &plate)?;
        let a = Instant::now();
        let table = aero
            .gafs(&plate, &modes)
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        let b = Instant::now();
        std::hint::black_box(
            aero.gafs_vjp(&plate, &modes, &table)
                .map_err(|e| anyhow::anyhow!("{e}"))?,
        );
        tg.push((b - a).as_secs_f64());
        tv.push(b.elapsed().as_secs_f64());
    }
    Ok(AeroTimings {
        n_boxes: n,
        n_k: aero.k.len(),
        n_modes: modes.len(),
        assembly_s: (t1 - t0).as_secs_f64(),
        factorization_s: (t2 - t1).as_secs_f64(),
        gafs_s: median(tg),
        gafs_vjp_s: median(tv),
    })
}

/// One row of `gustkit check-gradient`.
#[derive(Serialize)]
pub struct GradientRow {
    pub dv: String,
    pub adjoint: f64,
    /// (relative step, central difference) pairs.
    pub fd: Vec<(f64, f64)>,
    pub fd_best: f64,
    pub rel_error: f64,
}

/// `gustkit check-gradient`: the adjoint gradient of the first gust output's RMS against central
/// finite differences at relative steps 1e-2 … 1e-8 (paper Table 4), in SI units.
pub fn check_gradient(file: &Path, dvs: &[String], json: bool) -> Result<()> {
    let study = Study::load(file)?;
    let settings = study.gust_settings()?;
    let x0 = study.initial_design()?.to_vec();
    let design = study.initial_design()?;
    let names: Vec<String> = (0..x0.len()).map(|i| design.name(i)).collect();
    let index: Vec<usize> = dvs
        .iter()
        .map(|d| {
            names
                .iter()
                .position(|n| n == d)
                .ok_or_else(|| anyhow::anyhow!("--dv {d}: unknown design variable (use t[i] or one of span, sweep_c4, root_chord, tip_chord)"))
        })
        .collect::<Result<_>>()?;
    let ev = crate::pipeline::evaluate(&study, &settings, &x0)?;
    let t0 = Instant::now();
    let g = crate::pipeline::gradient(
        &ev,
        &crate::pipeline::OutputSeeds {
            rms: std::iter::once(1.0)
                .chain(std::iter::repeat(0.0))
                .take(ev.rms_m.len())
                .collect(),
            ..Default::default()
        },
    )?;
    let t_grad = t0.elapsed().as_secs_f64();
    let f = |x: &[f64]| -> Result<f64> {
        Ok(crate::pipeline::evaluate(&study, &settings, x)?.rms_m[0])
    };
    let mut rows = Vec::new();
    for (&k, name) in index.iter().zip(dvs) {
        let mut fd = Vec::new();
        for e in 2..=8 {
            let rel = 10f64.powi(-e);
            let h = rel * if x0[k] == 0.0 { 1.0 } else { x0[k].abs() };
            let mut a = x0.clone();
            let mut b = x0.clone();
            a[k] += h;
            b[k] -= h;
            fd.push((rel, (f(&a)? - f(&b)?) / (2.0 * h)));
        }
        let (fd_best, err) = fd
            .iter()
            .map(|&(_, v)| (v, (v - g[k]).abs() / g[k].abs().max(f64::MIN_POSITIVE)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .expect("steps");
        rows.push(GradientRow {
            dv: name.clone(),
            adjoint: g[k],
            fd,
            fd_best,
            rel_error: err,
        });
    }
    if json {
        println!(
            "{}",
            serde_json::to_string_pretty(&serde_json::json!({
                "study": study.spec.name,
                "output": settings.outputs[0].name,
                "rms_m": ev.rms_m[0],
                "units": "d(RMS in m)/d(design variable in SI: m, rad)",
                "gradient_time_s": t_grad,
                "rows": rows,
            }))?
        );
    } else {
        println!(
            "{}: RMS of {} = {:.6e} m; gradient of all {} variables in {:.2} s",
            study.spec.name,
            settings.outputs[0].name,
            ev.rms_m[0],
            x0.len(),
            t_grad
        );
        print!("{:<22}", "method");
        for r in &rows {
            print!("{:>24}", r.dv);
        }
        println!();
        print!("{:<22}", "adjoint (reverse)");
        for r in &rows {
            print!("{:>24.15e}", r.adjoint);
        }
        println!();
        for (i, &(rel, _)) in rows[0].fd.iter().enumerate() {
            print!("{:<22}", format!("FD (h = {rel:.0e} |x|)"));
            for r in &rows {
                print!("{:>24.15e}", r.fd[i].1);
            }
            println!();
        }
        print!("{:<22}", "best rel. error");
        for r in &rows {
            print!("{:>24.2e}", r.rel_error);
        }
        println!();
    }
    Ok(())
}

/// `gustkit flutter`: p-k sweep of a study at its flight Mach number and density.
pub fn flutter(file: &Path, json: bool, reports: &Path) -> Result<()> {
    let study = Study::load(file)?;
    let (doc, r, velocities) = flutter_analysis(&study, reports)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&doc)?);
        return Ok(());
    }
    print_flutter(&study, &r, &velocities, &doc);
    println!(
        "V-g/V-f figures and flutter.json written to {}",
        study.report_dir(reports).display()
    );
    Ok(())
}

/// The p-k sweep of a study with its V-g/V-f figures and `flutter.json`.
fn flutter_analysis(
    study: &Study,
    reports: &Path,
) -> Result<(serde_json::Value, crate::flutter::FlutterResult, Vec<f64>)> {
    let file = &study.file;
    let velocities = study.flutter_velocities()?;
    let (plate, modes, _) = analyze(study)?;
    let aero = crate::study::AeroModel::new(study, &plate)?;
    let table = aero
        .gafs(&plate, &modes)
        .map_err(|e| anyhow::anyhow!("{}: aero: {e}", file.display()))?;
    let pk = crate::flutter::PkProblem::new(&modes, &table, aero.flight.density);
    let r = pk
        .sweep(&velocities)
        .map_err(|e| anyhow::anyhow!("{}: flutter: {e}", file.display()))?;
    let dir = study.report_dir(reports);
    save_figure(
        &dir,
        "flutter_vg",
        &report::figures::VgVf {
            result: &r,
            title: format!(
                "{}: p-k, M = {}, rho = {} kg/m3",
                study.spec.name, aero.flight.mach, aero.flight.density
            ),
        },
    )?;
    let doc = serde_json::json!({
        "study": study.spec.name,
        "mach": aero.flight.mach,
        "density_kg_m3": aero.flight.density,
        "flutter_speed_m_s": r.flutter_speed_m_s,
        "flutter_frequency_hz": r.flutter_frequency_hz,
        "flutter_mode": r.flutter_mode,
        "curves": r.curves,
    });
    write_atomic(
        &dir.join("flutter.json"),
        serde_json::to_string_pretty(&doc)?.as_bytes(),
    )?;
    Ok((doc, r, velocities))
}

/// The p-k table and the flutter point on stdout.
fn print_flutter(
    study: &Study,
    r: &crate::flutter::FlutterResult,
    velocities: &[f64],
    doc: &serde_json::Value,
) {
    println!(
        "{}: p-k at M = {}, ρ = {} kg/m³",
        study.spec.name, doc["mach"], doc["density_kg_m3"]
    );
    print!("{:>10}", "V [m/s]");
    for c in &r.curves {
        print!("{:>22}", format!("mode {} g / f [Hz]", c.mode));
    }
    println!();
    for i in 0..velocities.len() {
        print!("{:>10.2}", velocities[i]);
        for c in &r.curves {
            print!("{:>12.4} {:>9.3}", c.damping_g[i], c.frequency_hz[i]);
        }
        println!();
    }
    println!("{}", flutter_point(r));
}

/// Wall time of one function evaluation and one gradient of the gust pipeline at the initial
/// design (the influence matrices are rebuilt, as when the planform changes), seconds.
pub fn bench_pipeline(study: &Study) -> Result<(f64, f64)> {
    let settings = study.gust_settings()?;
    let x = study.initial_design()?.to_vec();
    let t0 = Instant::now();
    let ev = crate::pipeline::evaluate(study, &settings, &x)?;
    let t1 = Instant::now();
    let seeds = crate::pipeline::OutputSeeds {
        mass: 1.0,
        area: 1.0,
        rms: vec![1.0; ev.rms_m.len()],
        damping: None,
    };
    std::hint::black_box(crate::pipeline::gradient(&ev, &seeds)?);
    Ok(((t1 - t0).as_secs_f64(), t1.elapsed().as_secs_f64()))
}

/// Shows each SQP iteration on a progress bar (and as a line on stdout) and writes the checkpoint
/// atomically.
struct RunObserver {
    dir: std::path::PathBuf,
    mass0: f64,
    rms_scale: f64,
    rms_unit: &'static str,
    rms_limit: f64,
    /// Damping limit of the flutter-margin constraint, when there is one.
    damping_max: Option<f64>,
    quiet: bool,
    bar: indicatif::ProgressBar,
    error: Option<anyhow::Error>,
}

impl crate::optim::Observer for RunObserver {
    fn iteration(&mut self, it: &crate::optim::Iterate, cp: &crate::optim::Checkpoint) -> bool {
        let rms = (it.values.ineq[0] + 1.0) * self.rms_limit;
        let flutter = match (it.values.ineq.get(1), self.damping_max) {
            (Some(c), Some(g_max)) => format!(
                ", g_KS {:+.4}",
                g_max + c * crate::study::design::DAMPING_SCALE
            ),
            _ => String::new(),
        };
        let line = format!(
            "iteration {:>3}: mass {:.5} kg ({:+.2} %), RMS {:.4} {} (limit {:.4}){flutter}, violation {:.2e}, KKT {:.2e}, step {:.3}{}",
            it.iteration,
            it.values.f * self.mass0,
            100.0 * (it.values.f - 1.0),
            rms * self.rms_scale,
            self.rms_unit,
            self.rms_limit * self.rms_scale,
            it.violation,
            it.kkt,
            it.alpha,
            if it.failed_trials > 0 {
                format!(" ({} trial points failed)", it.failed_trials)
            } else {
                String::new()
            }
        );
        if !self.quiet {
            self.bar.suspend(|| println!("{line}"));
        }
        self.bar.set_position(cp.iteration as u64);
        self.bar.set_message(format!(
            "mass {:+.1} %, RMS {:.3} {}, KKT {:.1e}",
            100.0 * (it.values.f - 1.0),
            rms * self.rms_scale,
            self.rms_unit,
            it.kkt
        ));
        match serde_json::to_vec(cp)
            .map_err(anyhow::Error::from)
            .and_then(|b| write_atomic(&self.dir.join("checkpoint.json"), &b))
        {
            Ok(()) => true,
            Err(e) => {
                self.error = Some(e);
                false
            }
        }
    }
}

/// FNV-1a hash of a string, to tie a checkpoint to the study that wrote it.
fn fnv(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// A design as the report shows it: values, planform, thickness map and the PSD of `output`.
fn snapshot(
    study: &Study,
    ev: &crate::pipeline::Evaluation,
    output: usize,
    unit_scale: f64,
) -> DesignSnapshot {
    let to_m = study.spec.length_unit.to_m();
    let xy = ev.plate.node_xy();
    let mesh = &ev.plate.mesh;
    DesignSnapshot {
        mass_kg: ev.mass_kg,
        area_m2: ev.area_m2,
        rms_tip_in: ev.rms_m[output] * unit_scale,
        rms: ev.rms_m[output],
        frequencies_hz: ev.freq_hz.clone(),
        design_variables: ev.x.clone(),
        elements: mesh
            .elements
            .iter()
            .map(|e| {
                e.iter()
                    .map(|&n| (xy[n][0] / to_m, xy[n][1] / to_m))
                    .collect()
            })
            .collect(),
        thickness: (0..mesh.elements.len())
            .map(|e| ev.plate.element_thickness(e) / to_m)
            .collect(),
        psd: psd_series(ev, output),
    }
}

/// The gust-constrained mass minimization of a study (the `optimization` section).
pub fn optimize(
    study: &Study,
    dir: &Path,
    resume: bool,
    quiet: bool,
) -> Result<OptimizationResults> {
    use crate::study::design::{DesignProblem, DesignSpec};
    let o = study.spec.optimization.as_ref().expect("caller checked");
    let settings = study.gust_settings()?;
    let (lower, upper) = study.design_bounds()?;
    let x0 = study.initial_design()?.to_vec();
    let output = settings
        .outputs
        .iter()
        .position(|out| out.name == o.output)
        .expect("checked");
    let is_disp = matches!(
        settings.outputs[output].quantity,
        crate::pipeline::Quantity::Displacement { .. }
    );
    let to_m = study.spec.length_unit.to_m();
    let (unit_scale, unit) = if is_disp {
        (1.0 / 0.0254, "in")
    } else {
        (1.0, "N m")
    };
    let rms_limit = if is_disp { o.rms_max * to_m } else { o.rms_max };
    let ev0 = crate::pipeline::evaluate(study, &settings, &x0).context("initial design")?;
    let spec = DesignSpec {
        lower,
        upper,
        output,
        rms_limit,
        mass0: ev0.mass_kg,
        area0: ev0.area_m2,
        fix_area: o.fix_area,
        flutter: o
            .flutter_margin
            .as_ref()
            .map(|m| crate::pipeline::FlutterMargin {
                speed_factor: m.speed_factor,
                damping_max: m.damping_max,
            }),
    };
    let params = crate::optim::SqpParams {
        max_iterations: o.max_iterations,
        tolerance: o.tolerance,
        ..Default::default()
    };
    // the study defines the problem; its iteration limit does not (a run may be continued with a
    // higher one)
    let mut defining = study.spec.clone();
    if let Some(o) = defining.optimization.as_mut() {
        o.max_iterations = 0;
    }
    let problem_id = format!(
        "{}:{:016x}",
        study.spec.name,
        fnv(&serde_json::to_string(&defining)?)
    );
    let checkpoint = if resume {
        let path = dir.join("checkpoint.json");
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("--resume: cannot read {}", path.display()))?;
        let cp: crate::optim::Checkpoint = serde_json::from_str(&text).with_context(|| {
            format!(
                "--resume: {} is not a gustkit checkpoint (corrupted?)",
                path.display()
            )
        })?;
        if !quiet {
            println!("resuming from iteration {}", cp.iteration);
        }
        Some(cp)
    } else {
        None
    };
    let bar = if quiet {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(o.max_iterations as u64)
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} SQP [{elapsed_precise}] {bar:30} {pos}/{len} iterations  {msg}",
        )
        .expect("valid template"),
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    let mut observer = RunObserver {
        dir: dir.to_path_buf(),
        mass0: ev0.mass_kg,
        rms_scale: unit_scale,
        rms_unit: unit,
        rms_limit,
        damping_max: spec.flutter.map(|m| m.damping_max),
        quiet,
        bar,
        error: None,
    };
    let mut problem = DesignProblem::new(study, settings.clone(), spec.clone());
    let t0 = Instant::now();
    let info = crate::optim::minimize(
        &mut problem,
        &x0,
        &params,
        &problem_id,
        checkpoint,
        &mut observer,
    );
    observer.bar.finish_and_clear();
    let info = info.map_err(|e| anyhow::anyhow!("optimization: {e}"))?;
    if let Some(e) = observer.error {
        return Err(e.context("cannot write the checkpoint"));
    }
    let wall_time_s = t0.elapsed().as_secs_f64();
    let ev = crate::pipeline::evaluate(study, &settings, &info.x).context("final design")?;
    let history = info
        .history
        .iter()
        .map(|it| HistoryRow {
            iteration: it.iteration,
            mass_kg: it.values.f * ev0.mass_kg,
            rms_tip_in: (it.values.ineq[0] + 1.0) * rms_limit * unit_scale,
            area_m2: it
                .values
                .eq
                .first()
                .map_or(ev0.area_m2, |h| (h + 1.0) * ev0.area_m2),
            flutter_damping: match (it.values.ineq.get(1), &spec.flutter) {
                (Some(c), Some(m)) => Some(m.damping_max + c * crate::study::design::DAMPING_SCALE),
                _ => None,
            },
            violation: it.violation,
            kkt: it.kkt,
            evaluations: it.evaluations,
        })
        .collect();
    if !quiet {
        println!(
        "{} after {} iterations ({} evaluations, {:.1} s): mass {:.4} → {:.4} kg ({:+.1} %), RMS {:.4} → {:.4} {unit}",
        info.message,
        info.iterations,
        info.evaluations,
        wall_time_s,
        ev0.mass_kg,
        ev.mass_kg,
        100.0 * (ev.mass_kg / ev0.mass_kg - 1.0),
        ev0.rms_m[output] * unit_scale,
        ev.rms_m[output] * unit_scale
    );
    }
    let design = study.initial_design()?;
    Ok(OptimizationResults {
        converged: info.converged,
        message: info.message.clone(),
        iterations: info.iterations,
        evaluations: info.evaluations,
        wall_time_s,
        output: o.output.clone(),
        rms_limit: if is_disp {
            rms_limit * unit_scale
        } else {
            rms_limit
        },
        unit: unit.to_string(),
        fix_area: o.fix_area,
        flutter_margin: spec.flutter.map(|m| (m.speed_factor, m.damping_max)),
        reference: o.reference.clone(),
        design_variable_names: (0..x0.len()).map(|i| design.name(i)).collect(),
        lower: spec.lower,
        upper: spec.upper,
        initial: snapshot(study, &ev0, output, unit_scale),
        final_: snapshot(study, &ev, output, unit_scale),
        history,
    })
}

/// The metrics of one sweep case, as far as they could be computed: mass and first frequency;
/// flutter speed (with a flutter section; none found in the range gives no value); RMS of every
/// gust output; the optimum (with `optimize`). A stage that fails (e.g. the flight condition
/// flutters, so there is no RMS) ends the case with its error and keeps what came before.
fn sweep_metrics(
    case: &crate::study::sweep::SweepCase,
    dir: &Path,
    optimize_case: bool,
) -> (
    Vec<crate::report::sweep::Metric>,
    Option<String>,
    Option<String>,
) {
    use crate::report::sweep::Metric;
    let metric = |name: &str, unit: &str, value: f64| Metric {
        name: name.to_string(),
        unit: unit.to_string(),
        value,
    };
    let study = &case.study;
    let mut out = Vec::new();
    let mut message = None;
    let mut stages = || -> Result<()> {
        let (plate, modes, summary) = analyze(study)?;
        out.push(metric("mass", "kg", summary.mass_kg));
        out.push(metric("f1", "Hz", summary.frequencies_hz[0]));
        if study.spec.flutter.is_some() {
            let aero = crate::study::AeroModel::new(study, &plate)?;
            let table = aero
                .gafs(&plate, &modes)
                .map_err(|e| anyhow::anyhow!("aero: {e}"))?;
            let pk = crate::flutter::PkProblem::new(&modes, &table, aero.flight.density);
            let r = pk.sweep(&study.flutter_velocities()?)?;
            if let Some(v) = r.flutter_speed_m_s {
                out.push(metric("flutter speed", "m/s", v));
            }
        }
        if study.spec.gust.is_some() {
            let settings = study.gust_settings()?;
            let x = study.initial_design()?.to_vec();
            let ev = crate::pipeline::evaluate(study, &settings, &x)?;
            for (o, rms) in settings.outputs.iter().zip(&ev.rms_m) {
                out.push(metric(&format!("RMS {}", o.name), o.quantity.unit(), *rms));
            }
        }
        if optimize_case {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create {}", dir.display()))?;
            let o = optimize(study, dir, false, true)?;
            out.push(metric("optimum mass", "kg", o.final_.mass_kg));
            out.push(metric(
                &format!("optimum RMS {}", o.output),
                &o.unit,
                o.final_.rms_tip_in,
            ));
            out.push(metric("iterations", "-", o.iterations as f64));
            out.push(metric(
                "converged",
                "-",
                if o.converged { 1.0 } else { 0.0 },
            ));
            message = Some(o.message);
        }
        Ok(())
    };
    let error = stages().err().map(|e| format!("{e:#}"));
    (out, message, error)
}

/// `gustkit sweep`: every case of the study's sweep in parallel (rayon), each case's result
/// written as it finishes so that `--resume` skips it; then the table, CSV and figure.
pub fn sweep(file: &Path, reports: &Path, resume: bool) -> Result<()> {
    use crate::report::sweep::{CaseResult, SweepResults};
    use rayon::prelude::*;
    let study = Study::load(file)?;
    let cases = study.sweep_cases()?;
    let spec = study.spec.sweep.as_ref().expect("checked by sweep_cases");
    let dir = study.report_dir(reports).join("sweep");
    std::fs::create_dir_all(dir.join("cases"))
        .with_context(|| format!("cannot create the sweep folder {}", dir.display()))?;
    println!(
        "{}: {} cases over {}",
        study.spec.name,
        cases.len(),
        spec.parameters
            .iter()
            .map(|p| p.path.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    );
    let t0 = Instant::now();
    let bar = indicatif::ProgressBar::new(cases.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} sweep [{elapsed_precise}] {bar:30} {pos}/{len} cases  {msg}",
        )
        .expect("valid template"),
    );
    let results: Vec<Result<CaseResult>> = cases
        .par_iter()
        .map(|case| {
            let hash = format!("{:016x}", fnv(&serde_json::to_string(&case.study.spec)?));
            let path = dir.join(format!("cases/case_{:04}.json", case.index));
            if resume {
                if let Ok(text) = std::fs::read_to_string(&path) {
                    if let Ok(r) = serde_json::from_str::<CaseResult>(&text) {
                        if r.study_hash == hash {
                            bar.inc(1);
                            return Ok(r);
                        }
                    }
                }
            }
            let t = Instant::now();
            let case_dir = dir.join(format!("cases/case_{:04}", case.index));
            let (metrics, message, error) = sweep_metrics(case, &case_dir, spec.optimize);
            let r = CaseResult {
                index: case.index,
                values: case.values.clone(),
                study_hash: hash,
                metrics,
                error,
                message,
                wall_time_s: t.elapsed().as_secs_f64(),
            };
            write_atomic(&path, serde_json::to_string_pretty(&r)?.as_bytes())?;
            bar.inc(1);
            bar.set_message(format!("case {} done", case.index));
            Ok(r)
        })
        .collect();
    bar.finish_and_clear();
    let cases = results.into_iter().collect::<Result<Vec<_>>>()?;
    let r = SweepResults {
        study: study.spec.name.clone(),
        parameters: spec.parameters.iter().map(|p| p.path.clone()).collect(),
        optimize: spec.optimize,
        cases,
        wall_time_s: t0.elapsed().as_secs_f64(),
    };
    crate::report::sweep::render(&dir, &r)?;
    print!("{}", crate::report::sweep::summary(&r));
    println!("sweep written to {}", dir.display());
    Ok(())
}
