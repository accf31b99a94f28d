//! `gustkit mesh-study`: the LFD analysis of a study's initial design on the built-in mesh levels
//! (coarse, medium, fine: each 8× the cells of the previous), with what each level costs (model
//! build, GAF table, peak memory) and how far its answer lies from the DLM of `aero.compare_with`;
//! over three levels the RMS's observed order of convergence and its Richardson extrapolate.
//!
//! Each level's row is written to `mesh_study.json` as soon as it is done, and a rerun keeps the
//! rows already there; within a level the GAF table is kept after each round of frequencies
//! (`partial_<level>.json`), so a level longer than a session (the fine one, about 2 h) resumes
//! where it was stopped.

use crate::aero::lfd::WingMeshLevel;
use crate::pipeline::{aeroelastic, analyse, Aeroelastic};
use crate::report::figures::{line_plot, Series};
use crate::report::results::FidelityComparison;
use crate::report::{save_figure, write_atomic};
use crate::runner::memory::{peak_memory_gb, reset_peak_memory, resident_memory_gb};
use crate::study::{FidelitySpec, Study};
use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::Instant;

/// The largest GAF difference to the DLM at one reduced frequency, of the largest entry.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct GafDifference {
    pub k: f64,
    /// Motion GAFs Q_ss.
    pub motion: f64,
    /// Gust GAFs Q_gs.
    pub gust: f64,
}

/// One mesh level's analysis.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct MeshStudyRow {
    pub level: String,
    pub cells: usize,
    /// RMS of the study's first gust output, m.
    pub rms: f64,
    /// RMS of every output, SI.
    pub rms_outputs: Vec<f64>,
    /// Peak resident memory of the process over the model build and the GAF table, GB.
    pub peak_memory_gb: Option<f64>,
    /// The process's resident memory when the level started (the DLM's and the structure's,
    /// and what the allocator kept of earlier levels), GB: the level's own peak is the
    /// difference.
    #[serde(default)]
    pub baseline_memory_gb: Option<f64>,
    /// The GAF table (every k, every mode and the gust), s.
    pub gaf_table_s: f64,
    /// The model build: mesh, steady Newton solve from the free stream, Jacobians, s.
    pub steady_s: f64,
    pub threads: usize,
    /// The largest GAF difference to the DLM at k = 0, 0.5, 1 and 2 (those in the table).
    pub gaf_difference_to_dlm: Vec<GafDifference>,
}

/// Richardson extrapolation of the RMS over three levels of constant refinement ratio.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct Richardson {
    /// Observed order p = ln(|r₂ − r₁| / |r₃ − r₂|) / ln(ratio).
    pub order: f64,
    /// r₃ + (r₃ − r₂) / (ratio^p − 1), m.
    pub extrapolate: f64,
    /// The DLM's RMS against the extrapolate, %.
    pub dlm_difference_percent: f64,
}

/// `mesh_study.json`.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct MeshStudy {
    pub study: String,
    /// The results.json whose final design is studied (`--design`); none: the study's initial
    /// design.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub design_from: Option<String>,
    /// Hash of what every row must share (wing, design, structure, modes, flight, gust,
    /// frequencies, the DLM compared with; not the LFD's level or solver settings): rows of
    /// another case are never mixed in. Absent in files written before it was kept.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub case_fingerprint: Option<String>,
    pub output: String,
    /// The DLM's RMS of the first output (the study's `aero.compare_with`), m.
    pub dlm_rms: f64,
    pub dlm_model: String,
    pub rows: Vec<MeshStudyRow>,
    pub richardson: Option<Richardson>,
}

/// The reduced frequencies at which the GAF differences are reported.
const REPORTED_K: [f64; 4] = [0.0, 0.5, 1.0, 2.0];

/// Cells refine by 2 in each direction from one level to the next.
const REFINEMENT_RATIO: f64 = 2.0;

/// Runs the levels of `levels` (names) that `dir/mesh_study.json` does not hold yet;
/// `design_from` names the results.json whose final design `study` carries (`--design`).
pub fn mesh_study(
    study: &Study,
    levels: &[String],
    dir: &Path,
    design_from: Option<&Path>,
) -> Result<()> {
    let file = study.file.display().to_string();
    let Some(crate::study::AeroSpec {
        fidelity: FidelitySpec::Lfd(_),
        ..
    }) = study.spec.aero.as_ref()
    else {
        bail!("{file}: aero.fidelity: the mesh study needs the LFD fidelity");
    };
    let other = study.compare_study()?.with_context(|| {
        format!("{file}: aero.compare_with: the mesh study compares with a DLM: give one")
    })?;
    let parsed: Vec<WingMeshLevel> = levels
        .iter()
        .map(|l| parse_level(l).map_err(|e| anyhow::anyhow!("--levels: {e}")))
        .collect::<Result<_>>()?;
    // every level is checked (its memory estimate against memory_limit_gb) before anything runs
    for &level in &parsed {
        level_study(study, level)?;
    }
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let path = dir.join("mesh_study.json");
    let settings = study.gust_settings()?;
    let output = settings
        .outputs
        .first()
        .map(|o| o.name.clone())
        .unwrap_or_default();
    // the DLM model once: its GAFs (and, for a new file, its RMS) are every level's reference
    let case_other = other.resolve()?;
    let mut dlm = Some(aeroelastic(&case_other, &case_other.initial.to_vec()).context("the DLM")?);
    let dlm_table = dlm.as_ref().expect("just built").table.clone();
    let case = case_fingerprint(study)?;
    let mut doc: MeshStudy = match std::fs::read_to_string(&path) {
        Ok(text) => {
            let doc: MeshStudy = serde_json::from_str(&text)
                .with_context(|| format!("{}: not a mesh study", path.display()))?;
            same_case(&doc, &case, &path)?;
            doc
        }
        Err(_) => {
            // the DLM's RMS: the reference of every level (its model built once, above)
            let rms = first_rms(dlm.take().expect("built once"), &settings)
                .context("the DLM's gust response")?;
            MeshStudy {
                study: study.spec.name.clone(),
                design_from: design_from.map(|d| d.display().to_string()),
                case_fingerprint: None,
                output: output.clone(),
                dlm_rms: rms[0],
                dlm_model: other.aero_model_words().unwrap_or_default(),
                rows: Vec::new(),
                richardson: None,
            }
        }
    };
    for level in parsed {
        if doc.rows.iter().any(|r| r.level == level.name()) {
            println!("{}: already in {}", level.name(), path.display());
            continue;
        }
        let row = run_level(study, level, &settings, &dlm_table, dir)?;
        println!(
            "{}: {} cells, RMS {:.6e} m, GAF table {:.1} s, model {:.1} s, peak {:.2} GB (from {:.2} GB at the start)",
            row.level,
            row.cells,
            row.rms,
            row.gaf_table_s,
            row.steady_s,
            row.peak_memory_gb.unwrap_or(f64::NAN),
            row.baseline_memory_gb.unwrap_or(f64::NAN)
        );
        doc.rows.push(row);
        doc.case_fingerprint = Some(case.clone());
        doc.rows.sort_by_key(|r| r.cells);
        doc.richardson = richardson(&doc);
        write_atomic(&path, serde_json::to_string_pretty(&doc)?.as_bytes())?;
        // the level's row written, its partial table is not needed
        let _ = std::fs::remove_file(partial_file(dir, level));
    }
    save_figure(dir, "mesh_study_rms", &figure(&doc))?;
    write_atomic(&dir.join("summary.md"), summary(&doc).as_bytes())?;
    Ok(())
}

/// A built-in mesh level by name.
fn parse_level(name: &str) -> Result<WingMeshLevel> {
    serde_json::from_value(serde_json::Value::String(name.into()))
        .map_err(|_| anyhow::anyhow!("unknown mesh level {name:?} (coarse, medium or fine)"))
}

/// Puts an LFD study on the built-in mesh level `name` (its own sizes or mesh file dropped).
pub fn set_level(study: &mut Study, name: &str) -> Result<()> {
    let level = parse_level(name).map_err(|e| anyhow::anyhow!("--mesh: {e}"))?;
    put_on_level(study, level)
        .map(|_| ())
        .map_err(|e| anyhow::anyhow!("--mesh: {e}"))
}

/// Puts an LFD study on a built-in mesh level; its cells.
fn put_on_level(study: &mut Study, level: WingMeshLevel) -> Result<usize> {
    match study.spec.aero.as_mut().map(|a| &mut a.fidelity) {
        Some(FidelitySpec::Lfd(spec)) => {
            spec.mesh = level;
            spec.mesh_sizes = None;
            spec.mesh_file = None;
            Ok(spec.mesh_spec().n_cells())
        }
        _ => bail!(
            "{}: the study's fidelity is not the LFD",
            study.file.display()
        ),
    }
}

/// The RMS of every output of an aeroelastic model.
fn first_rms(model: Aeroelastic, settings: &crate::gust::GustSettings) -> Result<Vec<f64>> {
    let analysis = analyse(model, settings)?;
    let ev = analysis
        .response()
        .map_err(|reason| anyhow::anyhow!("unstable: {reason}"))?;
    Ok(ev.rms_m.clone())
}

/// A level's GAF table so far (`partial_<level>.json` beside `mesh_study.json`, written after
/// each round of frequencies and removed when the level's row is written): a rerun of a level
/// that was stopped computes only the frequencies it lacks.
#[derive(Clone, Debug, Deserialize, Serialize)]
struct PartialLevel {
    level: String,
    cells: usize,
    /// Hash of the level's study (design, modes, k list, LFD settings): a partial table of
    /// another study is not used.
    fingerprint: String,
    /// The GAF table's time so far, s (summed over the runs).
    gaf_table_s: f64,
    /// The largest peak resident memory of the runs so far, GB.
    peak_memory_gb: Option<f64>,
    /// The rows computed so far.
    table: gustkit_core::GafTable,
}

/// The partial table file of `level` in `dir`.
fn partial_file(dir: &Path, level: WingMeshLevel) -> std::path::PathBuf {
    dir.join(format!("partial_{}.json", level.name()))
}

/// A hash of the level's study file (its design, modes, frequencies and LFD settings), without
/// the LFD's `warm_start_designs` and `gmres_batch` (they choose where a GMRES starts and how
/// many right-hand sides share a pass, not what it converges to):
/// the FNV-1a hash the checkpoints and the sweep use, stable across Rust releases.
fn fingerprint(s: &Study) -> Result<String> {
    let mut spec = s.spec.clone();
    if let Some(FidelitySpec::Lfd(l)) = spec.aero.as_mut().map(|a| &mut a.fidelity) {
        l.warm_start_designs = None;
        l.gmres_batch = None;
    }
    super::optimize::spec_hash(&spec)
}

/// A hash of what the rows of one mesh study share: the study without its name, description
/// and LFD fidelity (level and solver settings), so a row is of the same wing, design, modes,
/// flight, gust, frequencies and DLM as the others whatever memory limit or GMRES batch it ran
/// with.
fn case_fingerprint(s: &Study) -> Result<String> {
    let mut v = serde_json::to_value(&s.spec)?;
    if let Some(o) = v.as_object_mut() {
        o.remove("name");
        o.remove("description");
        if let Some(a) = o.get_mut("aero").and_then(|a| a.as_object_mut()) {
            a.remove("fidelity");
        }
    }
    super::optimize::spec_hash(&v)
}

/// Refuses a `mesh_study.json` whose rows are of another case (another design, modes,
/// frequencies, …): its rows and this run's must not share a table or an extrapolate.
fn same_case(doc: &MeshStudy, case: &str, path: &Path) -> Result<()> {
    match doc.case_fingerprint.as_deref() {
        Some(f) if f != case => bail!(
            "{}: its rows were computed for another case (design, modes, flight, gust, frequencies or the DLM compared with differ from this study's): move the file away or give --reports another folder",
            path.display()
        ),
        _ => Ok(()),
    }
}

/// The partial table in `file` when it is this level's, of this study and of `n_shapes`
/// shapes; else none, with a line saying why when the file is there (it is never trusted).
fn read_partial(
    file: &Path,
    level: WingMeshLevel,
    cells: usize,
    fingerprint: &str,
    n_shapes: usize,
) -> Option<PartialLevel> {
    let text = std::fs::read_to_string(file).ok()?;
    let why = match serde_json::from_str::<PartialLevel>(&text) {
        Err(e) => format!("not a partial GAF table ({e})"),
        Ok(p) if p.level != level.name() || p.cells != cells => format!(
            "it is level {} ({} cells), not {} ({cells} cells)",
            p.level,
            p.cells,
            level.name()
        ),
        Ok(p) if p.fingerprint != fingerprint => {
            "it was computed for another study (design, modes, frequencies or LFD settings)".into()
        }
        Ok(p)
            if p.table.q_ss.len() != p.table.k.len()
                || p.table.q_gs.len() != p.table.k.len()
                || p.table.q_gs.iter().any(|r| r.len() != n_shapes)
                || p.table
                    .q_ss
                    .iter()
                    .any(|r| r.len() != n_shapes || r.iter().any(|c| c.len() != n_shapes)) =>
        {
            format!("its table is not one of this analysis's {n_shapes} shapes")
        }
        Ok(p)
            if p.table
                .q_ss
                .iter()
                .flatten()
                .flatten()
                .any(|v| !v.is_finite())
                || p.table.q_gs.iter().flatten().any(|v| !v.is_finite()) =>
        {
            "its table holds non-finite GAFs".into()
        }
        Ok(p) => return Some(p),
    };
    println!(
        "{}: ignored, the level starts from its first frequency: {why}",
        file.display()
    );
    None
}

fn run_level(
    study: &Study,
    level: WingMeshLevel,
    settings: &crate::gust::GustSettings,
    dlm: &gustkit_core::GafTable,
    dir: &Path,
) -> Result<MeshStudyRow> {
    let (s, cells) = level_study(study, level)?;
    let print = fingerprint(&s)?;
    let case = s.resolve()?;
    let x = case.initial.to_vec();
    let plate = case
        .model_at(crate::wing::DesignVector::from_slice(&x))
        .map_err(|e| anyhow::anyhow!("design: {}", e.reason))?;
    let modes = case.solve_modes(&plate).context("modal analysis")?;
    reset_peak_memory();
    let baseline_memory_gb = resident_memory_gb();
    let t = Instant::now();
    let aero = case.aero_model(&plate)?;
    let steady_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    // the table in rounds of one frequency a thread, each round kept in the partial file
    let file = partial_file(dir, level);
    let n_shapes = crate::pipeline::table_shapes(&plate, &modes, Some(settings));
    let earlier = read_partial(&file, level, cells, &print, n_shapes);
    let (earlier_s, earlier_peak) = earlier
        .as_ref()
        .map_or((0.0, None), |p| (p.gaf_table_s, p.peak_memory_gb));
    if let Some(p) = &earlier {
        println!(
            "{}: {} of {} reduced frequencies from {} ({:.0} s)",
            level.name(),
            p.table.k.len(),
            aero.k.len(),
            file.display(),
            p.gaf_table_s
        );
    }
    let max_peak = |now: Option<f64>| match (now, earlier_peak) {
        (Some(a), Some(b)) => Some(a.max(b)),
        (a, b) => a.or(b),
    };
    let mut keep = |rows: &gustkit_core::GafTable| -> Result<()> {
        let partial = PartialLevel {
            level: level.name().into(),
            cells,
            fingerprint: print.clone(),
            gaf_table_s: earlier_s + t.elapsed().as_secs_f64(),
            peak_memory_gb: max_peak(peak_memory_gb()),
            table: rows.clone(),
        };
        write_atomic(&file, serde_json::to_string(&partial)?.as_bytes())
    };
    let (table, residual) = crate::pipeline::tables_in_groups(
        &plate,
        &modes,
        &aero,
        Some(settings),
        rayon::current_num_threads(),
        earlier.map(|p| p.table),
        &mut keep,
    )?;
    let gaf_table_s = earlier_s + t.elapsed().as_secs_f64();
    let peak_memory_gb = max_peak(peak_memory_gb());
    let (ss, gs) = FidelityComparison::differences(&table, dlm);
    let gaf_difference_to_dlm = REPORTED_K
        .iter()
        .filter_map(|&k| {
            let i = table.k.iter().position(|&t| (t - k).abs() < 1e-9)?;
            Some(GafDifference {
                k,
                motion: ss[i],
                gust: gs[i],
            })
        })
        .collect();
    let rms = first_rms(
        Aeroelastic {
            x,
            plate,
            modes,
            aero,
            table,
            residual,
        },
        settings,
    )?;
    Ok(MeshStudyRow {
        level: level.name().into(),
        cells,
        rms: rms[0],
        rms_outputs: rms,
        peak_memory_gb,
        baseline_memory_gb,
        gaf_table_s,
        steady_s,
        threads: rayon::current_num_threads(),
        gaf_difference_to_dlm,
    })
}

/// The study on `level` alone (no second fidelity, no steady-state cache: the steady state from
/// the free stream every time, its time part of the row) and its cells; refused, naming the
/// level, when its memory estimate is above the study's `memory_limit_gb`.
fn level_study(study: &Study, level: WingMeshLevel) -> Result<(Study, usize)> {
    let mut s = study.clone();
    let cells = put_on_level(&mut s, level)?;
    if let Some(aero) = s.spec.aero.as_mut() {
        aero.compare_with = None;
    }
    s.cache_dir = None;
    s.validate_fidelity().map_err(|e| {
        anyhow::anyhow!(
            "{}: level {}: {}: {}",
            s.file.display(),
            level.name(),
            e.path,
            e.reason
        )
    })?;
    Ok((s, cells))
}

/// The extrapolate of the finest three rows (each 8× the cells of the previous).
fn richardson(doc: &MeshStudy) -> Option<Richardson> {
    let n = doc.rows.len();
    if n < 3 {
        return None;
    }
    let (r1, r2, r3) = (
        doc.rows[n - 3].rms,
        doc.rows[n - 2].rms,
        doc.rows[n - 1].rms,
    );
    let ratio = ((r2 - r1) / (r3 - r2)).abs();
    // converging monotonically at a finite order (equal finest levels give no order)
    if !(ratio > 1.0 && ratio.is_finite()) {
        return None;
    }
    let order = ratio.ln() / REFINEMENT_RATIO.ln();
    let extrapolate = r3 + (r3 - r2) / (REFINEMENT_RATIO.powf(order) - 1.0);
    Some(Richardson {
        order,
        extrapolate,
        dlm_difference_percent: 100.0 * (doc.dlm_rms / extrapolate - 1.0),
    })
}

/// Cell size relative to the coarse level's: (coarse cells / cells)^(1/3).
fn relative_h(doc: &MeshStudy, cells: usize) -> f64 {
    let coarse = doc.rows.first().map_or(cells, |r| r.cells) as f64;
    (coarse / cells as f64).cbrt()
}

fn figure(doc: &MeshStudy) -> crate::report::figures::LinePlot {
    let to_in = 1.0 / 0.0254;
    let lfd: Vec<(f64, f64)> = doc
        .rows
        .iter()
        .map(|r| (relative_h(doc, r.cells), r.rms * to_in))
        .collect();
    let mut series: Vec<Series> = vec![(
        format!(
            "LFD ({})",
            doc.rows
                .iter()
                .map(|r| r.level.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ),
        lfd,
    )];
    series.push((
        doc.dlm_model.clone(),
        vec![(0.0, doc.dlm_rms * to_in), (1.0, doc.dlm_rms * to_in)],
    ));
    let mut dotted = vec![0];
    if let Some(r) = &doc.richardson {
        series.push((
            format!("Richardson extrapolate (observed order {:.2})", r.order),
            vec![(0.0, r.extrapolate * to_in)],
        ));
        dotted.push(2);
    }
    let mut plot = line_plot(
        format!("RMS of {} against cell size", doc.output),
        "cell size / coarse cell size",
        "RMS (in)",
        series,
    );
    plot.dotted = dotted;
    plot
}

fn summary(doc: &MeshStudy) -> String {
    let to_in = 1.0 / 0.0254;
    let design = match &doc.design_from {
        Some(f) => format!("the final design of `{f}`"),
        None => "the study's initial design".into(),
    };
    let mut s = format!(
        "# Mesh study: {}\n\nRMS of `{}` at {design} on the built-in LFD mesh levels; the DLM ({}) gives {:.4} in.\n\n| level | cells | RMS (in) | vs DLM | model build (s) | GAF table (s) | peak memory (GB) | threads |\n|---|---|---|---|---|---|---|---|\n",
        doc.study,
        doc.output,
        doc.dlm_model,
        doc.dlm_rms * to_in
    );
    for r in &doc.rows {
        s += &format!(
            "| {} | {} | {:.4} | {:+.1} % | {:.1} | {:.1} | {} | {} |\n",
            r.level,
            r.cells,
            r.rms * to_in,
            100.0 * (r.rms / doc.dlm_rms - 1.0),
            r.steady_s,
            r.gaf_table_s,
            r.peak_memory_gb.map_or("—".into(), |g| format!("{g:.2}")),
            r.threads
        );
    }
    s += "\nLargest GAF difference to the DLM (of the largest entry), motion / gust:\n\n| level |";
    for k in REPORTED_K {
        s += &format!(" k = {k} |");
    }
    s += "\n|---|---|---|---|---|\n";
    for r in &doc.rows {
        s += &format!("| {} |", r.level);
        for d in &r.gaf_difference_to_dlm {
            s += &format!(" {:.1} % / {:.1} % |", 100.0 * d.motion, 100.0 * d.gust);
        }
        s += "\n";
    }
    match &doc.richardson {
        Some(r) => {
            s += &format!(
                "\nRichardson extrapolate of the three levels: {:.4} in (observed order {:.2}); the DLM lies {:+.1} % from it",
                r.extrapolate * to_in,
                r.order,
                r.dlm_difference_percent
            );
            s += if doc.design_from.is_none() {
                " (at the flagship's initial design the paper finds DLM 1.94 in against its LFD's 1.88 in, the LFD −3.1 %).\n"
            } else {
                ".\n"
            };
        }
        None => s += "\nNo extrapolate: it needs three levels converging monotonically.\n",
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The minimal wing (DLM, 8 reduced frequencies), with or without mode acceleration.
    fn minimal(mode_acceleration: bool) -> Study {
        let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/minimal_wing.json");
        let mut v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
        v["gust"]["mode_acceleration"] = mode_acceleration.into();
        Study::from_str(&file, &v.to_string()).unwrap()
    }

    /// A table computed in rounds and stopped after its first round, then resumed from the rows
    /// it kept (given in another order), is the whole table; the resumed run computes only the
    /// frequencies it lacked (one call of `keep` a round) — with the residual shapes of mode
    /// acceleration too.
    #[test]
    fn a_table_in_rounds_resumes_to_the_whole_table() {
        for mode_acceleration in [false, true] {
            let study = minimal(mode_acceleration);
            let settings = study.gust_settings().unwrap();
            let case = study.resolve().unwrap();
            let plate = case
                .model_at(crate::wing::DesignVector::from_slice(
                    &case.initial.to_vec(),
                ))
                .unwrap();
            let modes = case.solve_modes(&plate).unwrap();
            let aero = case.aero_model(&plate).unwrap();
            let nk = aero.k.len();
            let (whole, residual) =
                crate::pipeline::tables(&plate, &modes, &aero, Some(&settings)).unwrap();
            assert_eq!(residual.is_some(), mode_acceleration);
            let shapes = crate::pipeline::table_shapes(&plate, &modes, Some(&settings));
            assert_eq!(shapes > modes.len(), mode_acceleration);
            let mut kept = Vec::new();
            let (rounds, _) = crate::pipeline::tables_in_groups(
                &plate,
                &modes,
                &aero,
                Some(&settings),
                3,
                None,
                &mut |t| {
                    kept.push(t.clone());
                    Ok(())
                },
            )
            .unwrap();
            assert_eq!(rounds, whole);
            assert_eq!(kept.len(), nk.div_ceil(3));
            for (i, t) in kept.iter().enumerate() {
                assert_eq!(t.k.len(), (3 * (i + 1)).min(nk));
                assert_eq!(t.q_gs[0].len(), shapes);
            }
            let mut first = kept[0].clone();
            first.k.reverse();
            first.q_ss.reverse();
            first.q_gs.reverse();
            let mut calls = 0;
            let (resumed, resumed_residual) = crate::pipeline::tables_in_groups(
                &plate,
                &modes,
                &aero,
                Some(&settings),
                3,
                Some(first),
                &mut |_| {
                    calls += 1;
                    Ok(())
                },
            )
            .unwrap();
            assert_eq!(calls, (nk - 3).div_ceil(3));
            // each frequency's GAFs are computed alone either way: the same numbers
            assert_eq!(resumed, whole);
            assert_eq!(
                resumed_residual.map(|r| r.gafs),
                residual.map(|r| r.gafs),
                "mode acceleration {mode_acceleration}"
            );
        }
    }

    /// The fingerprint of a level's study is that of the solution: the warm start's
    /// `warm_start_designs` and `gmres_batch` leave it, the GMRES tolerance changes it.
    #[test]
    fn the_warm_start_leaves_the_fingerprint() {
        let file =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/agard445_lfd_mesh_study.json");
        let study = Study::load(&file).unwrap();
        let print = |edit: &dyn Fn(&mut crate::aero::lfd::LfdWingSpec)| {
            let mut s = study.clone();
            match s.spec.aero.as_mut().map(|a| &mut a.fidelity) {
                Some(FidelitySpec::Lfd(l)) => edit(l),
                _ => panic!("an LFD study"),
            }
            fingerprint(&s).unwrap()
        };
        let plain = print(&|_| {});
        assert_eq!(plain, print(&|l| l.warm_start_designs = Some(1)));
        assert_eq!(plain, print(&|l| l.warm_start_designs = Some(3)));
        assert_eq!(plain, print(&|l| l.gmres_batch = Some(12)));
        assert_ne!(plain, print(&|l| l.gmres_tolerance *= 0.1));
    }

    /// The rows of one mesh study share a case: the LFD's level, memory limit and the study's
    /// name leave the case fingerprint; another design (a run's optimum, `--design`) or
    /// another mode count changes it, and a file of another case is refused (one written
    /// before the fingerprint was kept is accepted).
    #[test]
    fn rows_of_another_case_are_refused() {
        let file =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/agard445_lfd_mesh_study.json");
        let study = Study::load(&file).unwrap();
        let plain = case_fingerprint(&study).unwrap();
        let mut settings = study.clone();
        put_on_level(&mut settings, WingMeshLevel::Fine).unwrap();
        match settings.spec.aero.as_mut().map(|a| &mut a.fidelity) {
            Some(FidelitySpec::Lfd(l)) => l.memory_limit_gb = 23.0,
            _ => panic!("an LFD study"),
        }
        settings.spec.name = "renamed".into();
        assert_eq!(plain, case_fingerprint(&settings).unwrap());
        let mut modes = study.clone();
        modes.spec.structure.modes = crate::study::schema::ModesSpec::Count(7);
        assert_ne!(plain, case_fingerprint(&modes).unwrap());
        // a run's optimum: every thickness 10 % thinner
        let dir = std::env::temp_dir().join(format!("gustkit-mesh-case-{}", std::process::id()));
        let x = study.initial_design().unwrap();
        let names: Vec<String> = (0..x.len()).map(|i| x.name(i)).collect();
        let mut thin = x.to_vec();
        for t in thin.iter_mut().take(x.thickness.len()) {
            *t *= 0.9;
        }
        let results = dir.join("run").join("results.json");
        std::fs::create_dir_all(results.parent().unwrap()).unwrap();
        std::fs::write(
            &results,
            serde_json::json!({"design_variable_names": names, "final": {"design_variables": thin}})
                .to_string(),
        )
        .unwrap();
        let optimum = study.at_final_design(&results).unwrap();
        let other = case_fingerprint(&optimum).unwrap();
        assert_ne!(plain, other);
        let path = dir.join("mesh_study.json");
        let doc = MeshStudy {
            study: study.spec.name.clone(),
            design_from: None,
            case_fingerprint: Some(plain.clone()),
            output: "tip_te_w".into(),
            dlm_rms: 0.05,
            dlm_model: String::new(),
            rows: Vec::new(),
            richardson: None,
        };
        assert!(same_case(&doc, &plain, &path).is_ok());
        let refused = same_case(&doc, &other, &path).unwrap_err().to_string();
        assert!(refused.contains("mesh_study.json") && refused.contains("another case"));
        let older = MeshStudy {
            case_fingerprint: None,
            ..doc
        };
        assert!(same_case(&older, &other, &path).is_ok());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A partial table is used only when it is this level's, of this study and consistent;
    /// anything else is ignored (never trusted).
    #[test]
    fn a_partial_table_of_another_level_or_study_is_ignored() {
        let dir = std::env::temp_dir().join(format!("gustkit-partial-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = partial_file(&dir, WingMeshLevel::Coarse);
        let flight = gustkit_core::FlightCondition {
            mach: 0.5,
            velocity: 170.0,
            density: 0.4,
            b_ref: 0.3,
            x_ref: 0.0,
        };
        let good = PartialLevel {
            level: "coarse".into(),
            cells: 7168,
            fingerprint: "abc".into(),
            gaf_table_s: 12.0,
            peak_memory_gb: Some(0.3),
            table: gustkit_core::GafTable::zeros(&flight, &[0.0, 0.5], 2),
        };
        let write = |p: &PartialLevel| {
            std::fs::write(&file, serde_json::to_string(p).unwrap()).unwrap();
        };
        write(&good);
        let read = |cells, print: &str, shapes| {
            read_partial(&file, WingMeshLevel::Coarse, cells, print, shapes)
        };
        assert_eq!(
            read(7168, "abc", 2).map(|p| p.table.k),
            Some(vec![0.0, 0.5])
        );
        assert!(read(7168, "abd", 2).is_none());
        assert!(read(57344, "abc", 2).is_none());
        assert!(read(7168, "abc", 3).is_none());
        assert!(read_partial(&file, WingMeshLevel::Medium, 7168, "abc", 2).is_none());
        let mut bad = good.clone();
        bad.table.q_ss[1][0][1] = num_complex::Complex64::new(f64::NAN, 0.0);
        write(&bad);
        assert!(read(7168, "abc", 2).is_none());
        let mut short = good.clone();
        short.table.q_gs.pop();
        write(&short);
        assert!(read(7168, "abc", 2).is_none());
        std::fs::write(&file, "{ not json").unwrap();
        assert!(read(7168, "abc", 2).is_none());
        let _ = std::fs::remove_dir_all(&dir);
    }

    fn row(level: &str, cells: usize, rms: f64) -> MeshStudyRow {
        MeshStudyRow {
            level: level.into(),
            cells,
            rms,
            rms_outputs: vec![rms],
            peak_memory_gb: None,
            baseline_memory_gb: None,
            gaf_table_s: 0.0,
            steady_s: 0.0,
            threads: 1,
            gaf_difference_to_dlm: Vec::new(),
        }
    }

    /// A sequence r(h) = r₀ + C hᵖ on h = 1, ½, ¼ (cells × 8 a level) gives back p and r₀ to
    /// round-off, for p = 1 and 2 and either sign of C; two levels, or an oscillating sequence,
    /// give none.
    #[test]
    fn richardson_recovers_the_order_and_the_limit() {
        for (p, c) in [(2.0, 0.3), (1.0, -0.05), (1.5, 0.1)] {
            let r = |h: f64| 0.05 + c * f64::powf(h, p);
            let mut doc = MeshStudy {
                study: "s".into(),
                design_from: None,
                case_fingerprint: None,
                output: "o".into(),
                dlm_rms: 0.048,
                dlm_model: "DLM".into(),
                rows: vec![row("coarse", 1000, r(1.0)), row("medium", 8000, r(0.5))],
                richardson: None,
            };
            assert!(richardson(&doc).is_none());
            doc.rows.push(row("fine", 64000, r(0.25)));
            let e = richardson(&doc).expect("three converging levels");
            assert!((e.order - p).abs() < 1e-10, "{p}: {}", e.order);
            assert!((e.extrapolate - 0.05).abs() < 1e-13, "{}", e.extrapolate);
            assert!((e.dlm_difference_percent - (100.0 * (0.048 / 0.05 - 1.0))).abs() < 1e-9);
            assert!((relative_h(&doc, 64000) - 0.25).abs() < 1e-15);
        }
        let mut doc = MeshStudy {
            study: "s".into(),
            design_from: None,
            case_fingerprint: None,
            output: "o".into(),
            dlm_rms: 0.048,
            dlm_model: "DLM".into(),
            rows: vec![
                row("coarse", 1000, 0.05),
                row("medium", 8000, 0.051),
                row("fine", 64000, 0.049),
            ],
            richardson: None,
        };
        assert!(richardson(&doc).is_none(), "diverging differences");
        doc.rows[2].rms = 0.051;
        assert!(richardson(&doc).is_none(), "no change");
    }
}
