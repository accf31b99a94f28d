//! `gustkit run MODEL.bdf` (or `.dat`, `.inp`, `.nas`): the analysis a Nastran input's executive
//! and case control ask for — real modes (SOL 103), p-k flutter (SOL 145, APP AERO SOL 10), gust
//! response (SOL 146, APP AERO SOL 11: random with RANDOM, transient with TSTEP, else the
//! frequency response) — written to the usual run folder (results.json, summary.md, CSVs of
//! the histories and frequency responses). Values stay in the model's units.

use crate::nastran::bulk::BulkData;
use crate::nastran::case_control::{Selection, Solution};
use crate::nastran::random::{random_response, KInterpolation, Quantity, RandomRow};
use crate::nastran::structure::subcase_modes;
use crate::nastran::transient::transient_response;
use crate::nastran::{Input, Subcase};
use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

pub use crate::nastran::{is_nastran, EXTENSIONS};

#[derive(Serialize, Deserialize)]
struct ModeRow {
    mode: usize,
    eigenvalue: f64,
    frequency_hz: f64,
}

#[derive(Serialize, Deserialize)]
pub(crate) struct FlutterPoint {
    pub(crate) flutter_id: u32,
    pub(crate) method_run: String,
    pub(crate) mach: f64,
    pub(crate) density_ratio: f64,
    pub(crate) velocities: Vec<f64>,
    /// Per mode: damping g and frequency (Hz) at each velocity.
    pub(crate) damping_g: Vec<Vec<f64>>,
    pub(crate) frequency_hz: Vec<Vec<f64>>,
    pub(crate) flutter_speed: Option<f64>,
    pub(crate) flutter_frequency_hz: Option<f64>,
    pub(crate) flutter_mode: Option<usize>,
}

#[derive(Serialize, Deserialize)]
struct RandomResult {
    label: String,
    rms: f64,
    n0_hz: f64,
    unit: String,
    /// The PSD at the subcase's `random_frequencies_hz` (per Hz).
    #[serde(default)]
    psd: Vec<f64>,
}

/// One output's time history with its extremes (as Nastran's XY summary gives them).
#[derive(Serialize, Deserialize)]
struct TransientResult {
    label: String,
    unit: String,
    min: f64,
    time_at_min: f64,
    max: f64,
    time_at_max: f64,
    values: Vec<f64>,
}

#[derive(Serialize, Deserialize)]
struct TransientResults {
    /// The TSTEP's output times (the model's time unit).
    times: Vec<f64>,
    rows: Vec<TransientResult>,
}

/// One output's complex frequency response (real and imaginary parts, as Nastran's REAL/IMAG).
#[derive(Serialize, Deserialize)]
struct FrequencyResult {
    label: String,
    unit: String,
    real: Vec<f64>,
    imag: Vec<f64>,
}

#[derive(Serialize, Deserialize)]
struct FrequencyResults {
    frequencies_hz: Vec<f64>,
    rows: Vec<FrequencyResult>,
}

#[derive(Serialize, Deserialize)]
struct SubcaseResults {
    subcase: u32,
    modes: Vec<ModeRow>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    flutter: Vec<FlutterPoint>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    random_response: Vec<RandomResult>,
    /// The FREQ list of the random response (Hz).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    random_frequencies_hz: Vec<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    transient_response: Option<TransientResults>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    frequency_response: Option<FrequencyResults>,
}

#[derive(Serialize, Deserialize)]
struct NastranResults {
    kind: String,
    input: String,
    solution: String,
    units: String,
    warnings: Vec<String>,
    subcases: Vec<SubcaseResults>,
}

/// Runs a Nastran input and writes reports/<file stem>/.
pub fn run(file: &Path, reports: &Path) -> Result<crate::runner::Outcome> {
    let input = Input::read(file)?;
    let bulk = BulkData::from_cards(&input.deck.bulk)?;
    let mut warnings = input.warnings();
    warnings.extend(bulk.warnings.iter().cloned());
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    let solution = input.executive.solution().with_context(|| {
        format!(
            "{}: the executive control names no solution (SOL 103, 145 or 146)",
            file.display()
        )
    })?;
    let stem = file
        .file_stem()
        .and_then(|s| s.to_str())
        .context("the input file needs a name")?;
    let final_dir = reports.join(stem);
    let folder = crate::report::folder::RunFolder::begin(&final_dir, false)?;
    let mut subcases = Vec::new();
    for id in input.case_control.subcase_ids() {
        let sub = input.case_control.subcase(id).expect("listed subcase");
        let (results, notes) = run_subcase(&bulk, &sub, &solution, &input.case_control.sets)
            .with_context(|| format!("subcase {id}"))?;
        for w in &notes {
            eprintln!("warning: subcase {id}: {w}");
        }
        warnings.extend(notes.into_iter().map(|w| format!("subcase {id}: {w}")));
        subcases.push(results);
    }
    let results = NastranResults {
        kind: "nastran".into(),
        input: file.display().to_string(),
        solution: format!("{solution:?}"),
        units: "the model's own (gustkit converts nothing in a Nastran input)".into(),
        warnings,
        subcases,
    };
    let dir = folder.path().to_path_buf();
    for sc in &results.subcases {
        if let Some(f) = &sc.frequency_response {
            crate::report::write_atomic(
                &dir.join(format!("frequency_subcase{}.csv", sc.subcase)),
                frequency_csv(f).as_bytes(),
            )?;
        }
        if let Some(t) = &sc.transient_response {
            crate::report::write_atomic(
                &dir.join(format!("transient_subcase{}.csv", sc.subcase)),
                transient_csv(t).as_bytes(),
            )?;
        }
    }
    crate::report::write_atomic(
        &dir.join("results.json"),
        serde_json::to_string_pretty(&results)?.as_bytes(),
    )?;
    figures(&results, &dir)?;
    let summary = summary(&results);
    print!("{summary}");
    crate::report::write_atomic(&dir.join("summary.md"), summary.as_bytes())?;
    folder.commit()?;
    println!("results written to {}", final_dir.display());
    Ok(crate::runner::Outcome::Done)
}

/// The number of modes the aerodynamic analyses use: PARAM LMODES, else all found.
pub(crate) fn lmodes(b: &BulkData, found: usize) -> usize {
    b.params
        .get("LMODES")
        .and_then(|v| v.parse::<usize>().ok())
        .unwrap_or(found)
        .min(found)
}

/// Case control SETs by id (None: ALL).
type Sets = std::collections::BTreeMap<u32, Option<Vec<u32>>>;

/// One subcase's results and the warnings its analysis noticed.
fn run_subcase(
    b: &BulkData,
    sub: &Subcase,
    solution: &Solution,
    sets: &Sets,
) -> Result<(SubcaseResults, Vec<String>)> {
    let (s, modes) = subcase_modes(b, sub)?;
    let rows = modes
        .lambda
        .iter()
        .zip(modes.freq_hz())
        .enumerate()
        .map(|(i, (&l, f))| ModeRow {
            mode: i + 1,
            eigenvalue: l,
            frequency_hz: f,
        })
        .collect();
    let mut out = SubcaseResults {
        subcase: sub.id,
        modes: rows,
        flutter: Vec::new(),
        random_response: Vec::new(),
        random_frequencies_hz: Vec::new(),
        transient_response: None,
        frequency_response: None,
    };
    let mut warnings = Vec::new();
    match solution {
        Solution::Modes => {}
        Solution::Flutter => out.flutter = flutter(b, sub, &s, &modes)?,
        Solution::AeroResponse => {
            let requests = requests(b, sub, &s, sets, &modes)?;
            let interpolation = dense_k(b, sub)?;
            if sub.selections.contains_key("RANDOM") {
                let (rows, notes) = random_response(b, sub, &s, &modes, &requests, &interpolation)?;
                warnings.extend(notes);
                out.random_frequencies_hz = rows
                    .first()
                    .map(|r| r.frequencies_hz.clone())
                    .unwrap_or_default();
                out.random_response = rows
                    .into_iter()
                    .map(|r: RandomRow| RandomResult {
                        label: r.label,
                        rms: r.rms,
                        n0_hz: r.n0_hz,
                        unit: "model".into(),
                        psd: r.psd,
                    })
                    .collect();
            } else if sub.selections.contains_key("TSTEP") {
                let t = transient_response(b, sub, &s, &modes, &requests, &interpolation)?;
                warnings.extend(t.warnings);
                out.transient_response = Some(TransientResults {
                    rows: t
                        .rows
                        .into_iter()
                        .map(|r| {
                            let (mut lo, mut hi) = (0, 0);
                            for (i, v) in r.values.iter().enumerate() {
                                if *v < r.values[lo] {
                                    lo = i;
                                }
                                if *v > r.values[hi] {
                                    hi = i;
                                }
                            }
                            TransientResult {
                                label: r.label,
                                unit: "model".into(),
                                min: r.values[lo],
                                time_at_min: t.times[lo],
                                max: r.values[hi],
                                time_at_max: t.times[hi],
                                values: r.values,
                            }
                        })
                        .collect(),
                    times: t.times,
                });
            } else {
                let (frequencies_hz, rows, notes) = crate::nastran::response::frequency_rows(
                    b,
                    sub,
                    &s,
                    &modes,
                    &requests,
                    &interpolation,
                )?;
                warnings.extend(notes);
                out.frequency_response = Some(FrequencyResults {
                    frequencies_hz,
                    rows: rows
                        .into_iter()
                        .map(|r| FrequencyResult {
                            label: r.label,
                            unit: "model".into(),
                            real: r.values.iter().map(|v| v.re).collect(),
                            imag: r.values.iter().map(|v| v.im).collect(),
                        })
                        .collect(),
                });
            }
        }
        Solution::Other(sol) => bail!("SOL {sol} is not run by gustkit (it runs 103, 145 and 146)"),
    }
    Ok((out, warnings))
}

/// The frequency responses as CSV: a frequency column, then each output's magnitude and phase
/// (degrees, of e^{iωt}).
fn frequency_csv(f: &FrequencyResults) -> String {
    let mut out = String::from("frequency_hz");
    for r in &f.rows {
        out.push_str(&format!(",{0} magnitude,{0} phase_deg", r.label));
    }
    out.push('\n');
    for (i, hz) in f.frequencies_hz.iter().enumerate() {
        out.push_str(&format!("{hz:.6e}"));
        for r in &f.rows {
            let (re, im) = (r.real[i], r.imag[i]);
            out.push_str(&format!(
                ",{:.9e},{:.4}",
                re.hypot(im),
                im.atan2(re).to_degrees()
            ));
        }
        out.push('\n');
    }
    out
}

/// The time histories as CSV: a time column, then one column an output.
fn transient_csv(t: &TransientResults) -> String {
    let mut out = String::from("time");
    for r in &t.rows {
        out.push(',');
        out.push_str(&r.label);
    }
    out.push('\n');
    for (i, time) in t.times.iter().enumerate() {
        out.push_str(&format!("{time:.6e}"));
        for r in &t.rows {
            out.push_str(&format!(",{:.9e}", r.values[i]));
        }
        out.push('\n');
    }
    out
}

pub(crate) fn flutter(
    b: &BulkData,
    sub: &Subcase,
    s: &crate::nastran::structure::Structure,
    modes: &crate::nastran::structure::RealModes,
) -> Result<Vec<FlutterPoint>> {
    use gustkit_core::{Aerodynamics, FlightCondition};
    let fid = *sub.selections.get("FMETHOD").context(
        "the case control selects no FMETHOD: a flutter analysis needs the id of a FLUTTER card",
    )?;
    let f = b
        .flutter
        .get(&fid)
        .with_context(|| format!("FMETHOD = {fid}: no FLUTTER card has this id"))?;
    let list = |id: u32, what: &str| -> Result<Vec<f64>> {
        b.flfact
            .get(&id)
            .cloned()
            .with_context(|| format!("FLUTTER {fid}: its {what} FLFACT {id} is not defined"))
    };
    let (densities, machs) = (list(f.density, "density")?, list(f.mach, "Mach")?);
    let mut velocities: Vec<f64> = list(f.velocity, "velocity")?
        .iter()
        .map(|v| v.abs())
        .collect();
    velocities.sort_by(f64::total_cmp);
    velocities.dedup();
    if matches!(f.method.as_str(), "K" | "KE") {
        bail!(
            "FLUTTER {fid} asks for the {} method, whose FLFACT {} lists reduced frequencies; gustkit runs the p-k method, which needs velocities: set METHOD to PK and list the velocities in FLFACT {}",
            f.method,
            f.velocity,
            f.velocity
        );
    }
    let n_modes = lmodes(b, modes.lambda.len());
    let surf = crate::nastran::aero::lifting_surfaces(b, s)?;
    let (rows, unmoved) = crate::nastran::aero::spline_rows(b, s, &surf)?;
    if !unmoved.is_empty() {
        eprintln!(
            "warning: {} boxes are named by no spline and do not move (first: {})",
            unmoved.len(),
            unmoved[0]
        );
    }
    let ms = crate::nastran::aero::modal_surface(&surf, &rows, modes, n_modes);
    let omega: Vec<f64> = modes.lambda[..n_modes]
        .iter()
        .map(|l| l.max(0.0).sqrt())
        .collect();
    // reduced frequencies up to twice the highest mode's at the lowest speed (and MKAERO's)
    let v_min = velocities
        .first()
        .copied()
        .context("no velocity to analyse")?;
    let k_top = (2.0 * omega.iter().fold(0.0f64, |a, &w| a.max(w)) * surf.b_ref / v_min)
        .max(b.mkaero.iter().fold(0.0f64, |a, m| a.max(m.1)))
        .max(0.1);
    let k: Vec<f64> = (0..=60)
        .map(|i| k_top * (i as f64 / 60.0).powi(2))
        .collect();
    let mut points = Vec::new();
    for &mach in &machs {
        let flight = FlightCondition {
            mach,
            velocity: v_min,
            density: surf.rho_ref,
            b_ref: surf.b_ref,
            x_ref: 0.0,
        };
        let table = surf.dlm.gafs(&flight, &ms, &k)?;
        for &ratio in &densities {
            let pk = crate::flutter::PkProblem::from_parts(
                omega.clone(),
                0.0,
                &table,
                ratio * surf.rho_ref,
            );
            let r = pk.sweep(&velocities)?;
            points.push(FlutterPoint {
                flutter_id: fid,
                method_run: "PK".into(),
                mach,
                density_ratio: ratio,
                velocities: velocities.clone(),
                damping_g: r.curves.iter().map(|c| c.damping_g.clone()).collect(),
                frequency_hz: r.curves.iter().map(|c| c.frequency_hz.clone()).collect(),
                flutter_speed: r.flutter_speed_m_s,
                flutter_frequency_hz: r.flutter_frequency_hz,
                flutter_mode: r.flutter_mode,
            });
        }
    }
    Ok(points)
}

/// The outputs the case control requests of a gust response: DISPLACEMENT and ACCELERATION of
/// the free components, SPCFORCES of the constrained ones, SDISPLACEMENT's modes.
fn requests(
    b: &BulkData,
    sub: &Subcase,
    s: &crate::nastran::structure::Structure,
    sets: &Sets,
    modes: &crate::nastran::structure::RealModes,
) -> Result<Vec<(u32, u8, Quantity)>> {
    let n_modes = lmodes(b, modes.lambda.len());
    let spc = crate::nastran::structure::constrained(s, b, sub.selections.get("SPC").copied())?;
    let grids_of = |name: &str| -> Vec<u32> {
        match sub.outputs.get(name).map(|o| o.selection) {
            Some(Selection::All) => s.grid_ids.clone(),
            // the set's ids that are grids of the model (boxes and scalar points left out)
            Some(Selection::Id(id)) => match sets.get(&id) {
                Some(Some(ids)) => ids
                    .iter()
                    .copied()
                    .filter(|g| s.index.contains_key(g))
                    .collect(),
                _ => s.grid_ids.clone(),
            },
            _ => Vec::new(),
        }
    };
    let mut requests = Vec::new();
    for g in grids_of("DISPLACEMENT") {
        for c in 1..=6u8 {
            let dof = s.dof(g, c).expect("grid of the model");
            if !spc.contains(&dof) {
                requests.push((g, c, Quantity::Displacement));
            }
        }
    }
    for g in grids_of("ACCELERATION") {
        for c in 1..=6u8 {
            if !spc.contains(&s.dof(g, c).expect("grid of the model")) {
                requests.push((g, c, Quantity::Acceleration));
            }
        }
    }
    // SDISPLACEMENT: the set's ids are mode numbers (those beyond the modes kept are refused)
    if let Some(req) = sub.outputs.get("SDISPLACEMENT") {
        let modes: Vec<u32> = match req.selection {
            Selection::All => (1..=n_modes as u32).collect(),
            Selection::Id(id) => match sets.get(&id) {
                Some(Some(ids)) => ids.clone(),
                _ => (1..=n_modes as u32).collect(),
            },
            Selection::None => Vec::new(),
        };
        requests.extend(modes.into_iter().map(|m| (m, 0, Quantity::Mode)));
    }
    for g in grids_of("SPCFORCES") {
        for c in 1..=6u8 {
            if spc.contains(&s.dof(g, c).expect("grid of the model")) {
                requests.push((g, c, Quantity::SpcForce));
            }
        }
    }
    if requests.is_empty() && b.monitors.is_empty() {
        bail!("the case control requests no output and the model has no MONPNT1: give DISPLACEMENT, ACCELERATION, SPCFORCES = set (grids) or SDISPLACEMENT = set (modes)");
    }
    Ok(requests)
}

/// The reduced frequencies of a gust response's GAFs: 41 evenly spaced to 5 % beyond the
/// FREQ list's last frequency.
pub(crate) fn dense_k(b: &BulkData, sub: &Subcase) -> Result<KInterpolation> {
    // the DLM on reduced frequencies to 5 % beyond the FREQ list's last
    let freq_id = sub
        .selections
        .get("FREQUENCY")
        .context("no FREQUENCY selected")?;
    let f_max = b
        .freq
        .get(freq_id)
        .map_or(0.0, |f| f.iter().fold(0.0f64, |a, &x| a.max(x)));
    let gust = sub
        .selections
        .get("GUST")
        .and_then(|g| b.gusts.get(g))
        .context("no GUST selected, or its card is missing")?;
    let aero = b.aero.as_ref().context("no AERO card")?;
    let k_max = (1.05 * 2.0 * std::f64::consts::PI * f_max * 0.5 * aero.refc / gust.v).max(0.05);
    let k: Vec<f64> = (0..=40).map(|i| k_max * i as f64 / 40.0).collect();
    Ok(KInterpolation::Dense(k))
}

/// `gustkit report` of a Nastran run folder: summary.md again from results.json alone.
pub fn rerender(dir: &Path, value: serde_json::Value) -> Result<()> {
    let results: NastranResults = serde_json::from_value(value).with_context(|| {
        format!(
            "{}: not the results of a Nastran input run",
            dir.join("results.json").display()
        )
    })?;
    figures(&results, dir)?;
    crate::report::write_atomic(&dir.join("summary.md"), summary(&results).as_bytes())?;
    println!(
        "summary and figures of {} re-rendered in {}",
        results.input,
        dir.display()
    );
    Ok(())
}

/// The run's figures from its results alone: V-g and V-f per flutter point, the PSDs of the
/// random response, the magnitudes of the frequency response, the transient histories.
fn figures(r: &NastranResults, dir: &Path) -> Result<()> {
    use crate::report::figures::{line_plot, LinePlot, Panels};
    use crate::report::save_figure;
    for sc in &r.subcases {
        let id = sc.subcase;
        for (i, p) in sc.flutter.iter().enumerate() {
            let curves = |values: &Vec<Vec<f64>>| -> Vec<(String, Vec<(f64, f64)>)> {
                values
                    .iter()
                    .enumerate()
                    .map(|(m, v)| {
                        (
                            format!("mode {}", m + 1),
                            p.velocities
                                .iter()
                                .copied()
                                .zip(v.iter().copied())
                                .collect(),
                        )
                    })
                    .collect()
            };
            let fig = Panels {
                title: format!(
                    "Subcase {id}: p-k flutter, Mach {}, density ratio {}",
                    p.mach, p.density_ratio
                ),
                cols: 2,
                plots: vec![
                    line_plot(
                        "damping".into(),
                        "velocity (model units)",
                        "g",
                        curves(&p.damping_g),
                    ),
                    line_plot(
                        "frequency".into(),
                        "velocity (model units)",
                        "f (Hz)",
                        curves(&p.frequency_hz),
                    ),
                ],
            };
            save_figure(dir, &format!("flutter_subcase{id}_{}", i + 1), &fig)?;
        }
        if !sc.random_response.is_empty() && !sc.random_frequencies_hz.is_empty() {
            let series = sc
                .random_response
                .iter()
                .filter(|row| row.psd.len() == sc.random_frequencies_hz.len())
                .map(|row| {
                    (
                        row.label.clone(),
                        sc.random_frequencies_hz
                            .iter()
                            .copied()
                            .zip(row.psd.iter().copied())
                            .collect(),
                    )
                })
                .collect();
            let fig = LinePlot {
                log_y: true,
                ..line_plot(
                    format!("Subcase {id}: PSDs of the random gust response"),
                    "frequency (Hz)",
                    "PSD (model units² / Hz)",
                    series,
                )
            };
            save_figure(dir, &format!("psd_subcase{id}"), &fig)?;
        }
        if let Some(f) = &sc.frequency_response {
            let series = f
                .rows
                .iter()
                .map(|row| {
                    (
                        row.label.clone(),
                        f.frequencies_hz
                            .iter()
                            .zip(row.real.iter().zip(&row.imag))
                            .map(|(&hz, (a, b))| (hz, a.hypot(*b)))
                            .collect(),
                    )
                })
                .collect();
            let fig = LinePlot {
                log_y: true,
                ..line_plot(
                    format!("Subcase {id}: frequency response magnitudes"),
                    "frequency (Hz)",
                    "|y| (model units per unit gust angle scale)",
                    series,
                )
            };
            save_figure(dir, &format!("frequency_subcase{id}"), &fig)?;
        }
        if let Some(t) = &sc.transient_response {
            let plots = t
                .rows
                .iter()
                .map(|row| {
                    line_plot(
                        row.label.clone(),
                        "time",
                        "model units",
                        vec![(
                            row.label.clone(),
                            t.times
                                .iter()
                                .copied()
                                .zip(row.values.iter().copied())
                                .collect(),
                        )],
                    )
                })
                .collect();
            let fig = Panels {
                title: format!("Subcase {id}: transient gust response"),
                cols: 3,
                plots,
            };
            save_figure(dir, &format!("transient_subcase{id}"), &fig)?;
        }
    }
    Ok(())
}

fn summary(r: &NastranResults) -> String {
    let mut out = format!(
        "# {}\n\nSolution: {}. Units: {}.\n",
        r.input, r.solution, r.units
    );
    for sc in &r.subcases {
        out.push_str(&format!(
            "\n## Subcase {}\n\n| mode | frequency (Hz) |\n|---:|---:|\n",
            sc.subcase
        ));
        for m in &sc.modes {
            out.push_str(&format!("| {} | {:.4} |\n", m.mode, m.frequency_hz));
        }
        for p in &sc.flutter {
            out.push_str(&format!(
                "\nFlutter (p-k), Mach {}, density ratio {}: {}\n",
                p.mach,
                p.density_ratio,
                match (p.flutter_speed, p.flutter_frequency_hz, p.flutter_mode) {
                    (Some(v), Some(f), Some(m)) =>
                        format!("flutters at V = {v:.4} (mode {m}, {f:.3} Hz)"),
                    _ => "no flutter crossing in the velocity range".into(),
                }
            ));
        }
        if !sc.random_response.is_empty() {
            out.push_str("\n| output | RMS | N0 (Hz) |\n|---|---:|---:|\n");
            for row in &sc.random_response {
                out.push_str(&format!(
                    "| {} | {:.6e} | {:.5} |\n",
                    row.label, row.rms, row.n0_hz
                ));
            }
        }
        if let Some(f) = &sc.frequency_response {
            out.push_str(&format!(
                "\nFrequency response at {} frequencies from {} to {} Hz (magnitude and phase in frequency_subcase{}.csv); largest magnitude:\n\n| output | largest magnitude | at f (Hz) |\n|---|---:|---:|\n",
                f.frequencies_hz.len(),
                f.frequencies_hz.first().copied().unwrap_or(0.0),
                f.frequencies_hz.last().copied().unwrap_or(0.0),
                sc.subcase
            ));
            for row in &f.rows {
                let (i, m) = row
                    .real
                    .iter()
                    .zip(&row.imag)
                    .map(|(a, b)| a.hypot(*b))
                    .enumerate()
                    .fold((0, 0.0), |acc, (i, m)| if m > acc.1 { (i, m) } else { acc });
                out.push_str(&format!(
                    "| {} | {:.6e} | {:.4} |\n",
                    row.label, m, f.frequencies_hz[i]
                ));
            }
        }
        if let Some(t) = &sc.transient_response {
            out.push_str(&format!(
                "\nTransient response at {} times from {} to {} (time histories in transient_subcase{}.csv):\n\n| output | min | at t | max | at t |\n|---|---:|---:|---:|---:|\n",
                t.times.len(),
                t.times.first().copied().unwrap_or(0.0),
                t.times.last().copied().unwrap_or(0.0),
                sc.subcase
            ));
            for row in &t.rows {
                out.push_str(&format!(
                    "| {} | {:.6e} | {:.4} | {:.6e} | {:.4} |\n",
                    row.label, row.min, row.time_at_min, row.max, row.time_at_max
                ));
            }
        }
    }
    out
}
