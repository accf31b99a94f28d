//! `gustkit bench`: timings of the structural chain, the DLM and the gust pipeline of a study,
//! and optionally of its whole optimization. Every timing is taken after a warm-up run and
//! reported as the median, minimum and maximum of its repetitions, with the thread count in use.

use crate::runner::memory::{peak_memory_gb, reset_peak_memory};
use crate::runner::wing::{analyze, optimize::optimize};
use crate::structure::{mass_grad, modes_vjp, ModalSeed, Sampler};
use crate::study::Study;
use anyhow::{Context, Result};
use serde::Serialize;
use std::time::Instant;

/// The paper's LFD costs: function and gradient wall minutes on its cores, and its mesh's nodes.
const PAPER_FUNCTION_MIN: f64 = 70.5;
const PAPER_GRADIENT_MIN: f64 = 146.4;
const PAPER_CORES: f64 = 400.0;
const PAPER_NODES: f64 = 219_555.0;

/// Warm-up runs before any timing (discarded: page faults, caches, the thread pool's start).
pub const WARMUP: usize = 1;

pub use crate::report::results::Stats;

/// Runs `f` [`WARMUP`] times untimed, then `repeat` times timed; `f` returns the wall time of
/// its part of interest (so setup it needs is not counted).
pub fn measure(repeat: usize, mut f: impl FnMut() -> Result<f64>) -> Result<Stats> {
    for _ in 0..WARMUP {
        f()?;
    }
    let samples = (0..repeat.max(1))
        .map(|_| f())
        .collect::<Result<Vec<_>>>()?;
    Ok(Stats::of(samples))
}

/// Timings of the structural chain.
#[derive(Debug, Serialize)]
pub struct StructureTimings {
    /// Assembly of K and M alone (informational: the modal analysis includes it).
    pub assembly: Stats,
    /// Assembly + Cholesky + the partial eigensolve of the retained modes.
    pub modes: Stats,
    pub sensitivities: Stats,
    pub total: Stats,
    pub n_dv: usize,
    pub n_modes: usize,
}

/// Times assembly + modal analysis + the gradients of every frequency, the tip deflection of every
/// mode and the mass with respect to all design variables (one reverse sweep each).
pub fn bench_structure(study: &Study, repeat: usize) -> Result<StructureTimings> {
    let (mut ta, mut tm, mut ts, mut tt) = (vec![], vec![], vec![], vec![]);
    let (mut n_dv, mut n_modes) = (0, 0);
    for rep in 0..WARMUP + repeat.max(1) {
        let t0 = Instant::now();
        let model = study.build_model()?;
        let t0b = Instant::now();
        for f in study.mode_fields() {
            std::hint::black_box(model.assemble(f));
        }
        let t1 = Instant::now();
        let modes = study.solve_modes(&model)?;
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
        if rep < WARMUP {
            continue;
        }
        ta.push((t1 - t0).as_secs_f64());
        tm.push((t2 - t1).as_secs_f64());
        ts.push((t3 - t2).as_secs_f64());
        // the modal analysis assembles again: the chain is model + modes + sensitivities
        tt.push((t3 - t1).as_secs_f64() + (t0b - t0).as_secs_f64());
    }
    Ok(StructureTimings {
        assembly: Stats::of(ta),
        modes: Stats::of(tm),
        sensitivities: Stats::of(ts),
        total: Stats::of(tt),
        n_dv,
        n_modes,
    })
}

/// `gustkit bench`.
pub fn bench(study: &Study, repeat: Option<usize>, optimization: bool) -> Result<()> {
    let lfd = matches!(
        study.spec.aero.as_ref().map(|a| &a.fidelity),
        Some(crate::study::FidelitySpec::Lfd(_))
    );
    let repeat = repeat.unwrap_or(if lfd { 1 } else { 20 });
    if repeat == 0 && !lfd {
        anyhow::bail!(
            "--repeat 0 (the first calls only) is for an LFD study; this study's aerodynamics repeat in seconds: give --repeat 1 or more"
        );
    }
    let file = &study.file;
    let study = study.clone();
    println!(
        "{}: {} threads (RAYON_NUM_THREADS sets them), {WARMUP} warm-up run, {repeat} repetitions a line; wall times",
        study.spec.name,
        rayon::current_num_threads()
    );
    let t = bench_structure(&study, repeat.max(1))?;
    println!(
        "structure ({} design variables, {} modes):",
        t.n_dv, t.n_modes
    );
    println!("{}", t.assembly.line("assembly of K, M alone"));
    println!("{}", t.modes.line("modal analysis (+ assembly)"));
    println!("{}", t.sensitivities.line("sensitivities (2N+1 gradients)"));
    println!("{}", t.total.line("total (model, modes, gradients)"));
    if matches!(
        study.spec.aero.as_ref().map(|a| &a.fidelity),
        Some(crate::study::FidelitySpec::Dlm(_))
    ) {
        let a = bench_aero(&study, repeat)?;
        println!(
            "aerodynamics (DLM, {} boxes, {} reduced frequencies, {} modes):",
            a.n_boxes, a.n_k, a.n_modes
        );
        println!("{}", a.assembly.line("influence matrices (all k)"));
        println!(
            "{}",
            a.factorization.line("LU factorizations (all k, 1 thread)")
        );
        println!("{}", a.gafs.line("GAFs (all k, with matrices)"));
        println!("{}", a.gafs_vjp.line("GAF reverse (matrices reused)"));
    }
    if let Some(crate::study::FidelitySpec::Lfd(spec)) =
        study.spec.aero.as_ref().map(|a| &a.fidelity)
    {
        // the first GAF table and the first reverse call (which assembles the reverse mode's
        // Jacobians) are the warm-up runs, printed on their own
        let t = bench_lfd(&study, repeat)?;
        println!(
            "aerodynamics (LFD, {} cells, {} reduced frequencies, {} modes + gust):",
            spec.mesh_spec().n_cells(),
            t.n_k,
            t.n_modes
        );
        println!(
            "  model: mesh, steady Euler (from the free stream), Jacobians   {:>9.2} s (once)",
            t.build_s
        );
        println!(
            "  GAF table, first call                                        {:>9.2} s",
            t.gafs_first_s
        );
        if let Some(gafs) = &t.gafs {
            println!("{}", gafs.line_s("GAF table (the function's aerodynamics)"));
        }
        println!(
            "  GAF reverse, first call (assembles the Jacobians), all variables {:>7.2} s",
            t.vjp_first_s
        );
        if let Some(vjp) = &t.vjp {
            println!(
                "{}",
                vjp.line_s("GAF reverse, Jacobians reused (∂R/∂x recomputed a call)")
            );
        }
        let cells = spec.mesh_spec().n_cells() as f64;
        for (what, peak) in [
            ("model (mesh, steady state, Jacobians)", t.peak_build_gb),
            ("GAF table", t.peak_gafs_gb),
            ("GAF reverse", t.peak_vjp_gb),
        ] {
            if let Some(gb) = peak {
                println!(
                    "  peak resident memory, {what:<38} {gb:>6.2} GB ({:.1} kB a cell)",
                    gb * 1e6 / cells
                );
            }
        }
        // the medians of the repetitions, or the first calls where there were none
        let (function_s, reverse_s, which) = match (&t.gafs, &t.vjp) {
            (Some(g), Some(v)) => (g.median_s, v.median_s, "medians"),
            _ => (t.gafs_first_s, t.vjp_first_s, "first calls"),
        };
        println!(
            "  reverse / function ({which}): {:.2} (paper: 146.4 / 70.5 min = 2.08 on 400 cores)",
            reverse_s / function_s
        );
        let threads = rayon::current_num_threads() as f64;
        println!(
            "  core-seconds a cell ({which}): function {:.4}, reverse {:.4} (paper: {:.1} and {:.1} a node: 70.5 and 146.4 min on 400 cores, 219 555 nodes)",
            function_s * threads / cells,
            reverse_s * threads / cells,
            PAPER_FUNCTION_MIN * 60.0 * PAPER_CORES / PAPER_NODES,
            PAPER_GRADIENT_MIN * 60.0 * PAPER_CORES / PAPER_NODES
        );
        if repeat == 0 {
            println!("  (--repeat 0: the first calls only; no warm-start or line-search figures)");
            return Ok(());
        }
        let w = bench_lfd_warm_start(&study)?;
        println!(
            "  the function at a neighbouring design (every thickness × 1.01), GMRES from zero      {:>9.2} s, {} iterations ({:.1} a right-hand side)",
            w.cold_s, w.cold_iterations, w.cold_iterations as f64 / w.rhs as f64
        );
        println!(
            "  the same, GMRES from the previous design's solutions                             {:>9.2} s, {} iterations ({:.1} a right-hand side)",
            w.warm_s, w.warm_iterations, w.warm_iterations as f64 / w.rhs as f64
        );
        println!(
            "  its gradient (the first output's RMS), adjoint GMRES from zero                     {:>9.2} s, {} iterations",
            w.gradient_cold_s, w.gradient_cold_iterations
        );
        println!(
            "  the same, adjoint GMRES from the previous design's adjoint solutions              {:>9.2} s, {} iterations",
            w.gradient_warm_s, w.gradient_warm_iterations
        );
        let l = bench_lfd_line_search(&study)?;
        println!(
            "  a line search's backtrack (x0, x0 + p, x0 + p/2; p: thicknesses × 1.01, planform × 1.002), GMRES from the last design's solutions {:>9.2} s, {} iterations ({:.1} a right-hand side)",
            l.one_design_s, l.one_design_iterations, l.one_design_iterations as f64 / l.rhs as f64
        );
        println!(
            "  the same, GMRES from the combination of the last {} designs' solutions          {:>9.2} s, {} iterations ({:.1} a right-hand side)",
            l.designs, l.several_designs_s, l.several_designs_iterations, l.several_designs_iterations as f64 / l.rhs as f64
        );
        return Ok(());
    }
    if study.spec.gust.is_some() {
        let p = bench_pipeline(&study, repeat)?;
        println!(
            "gust pipeline (all {} design variables):",
            study.initial_design()?.len()
        );
        println!(
            "{}",
            p.function.line("function (modes, GAFs, stability, RMS)")
        );
        println!("{}", p.aeroelastic.line("  plate, modes, GAFs"));
        println!("{}", p.stability.line("  stability check (p-k, 12 speeds)"));
        println!("{}", p.response.line("  stability check + gust response"));
        if let Some(m) = &p.margin {
            println!("{}", m.line("flutter margin (p-k roots up to the margin)"));
        }
        println!("{}", p.gradient.line("gradient (one reverse sweep)"));
        if let (Some(f), Some(g)) = (&p.discrete_function, &p.discrete_gradient) {
            println!(
                "discrete gusts (the discrete_gust section's {} gusts, every output, on the grid its decay rule picks):",
                p.discrete_gusts
            );
            println!(
                "{}",
                f.line("function (Eq. 16 on the grid, FFTs, KS of one output)")
            );
            println!(
                "{}",
                g.line("gradient of the KS (adjoint FFTs, reverse sweep)")
            );
        }
        if let (Some(f), Some(g)) = (&p.design_function, &p.design_gradient) {
            println!("design problem (what the SQP asks for at each point):");
            println!(
                "{}",
                f.line("function (the above, the flutter margin, a peak limit)")
            );
            println!("{}", g.line("gradient (objective and every constraint)"));
        }
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

/// Timings of the LFD chain for a study: the model build once, the first GAF table and reverse
/// call on their own (the warm-up), then `repeat` timed runs of each.
#[derive(Debug, Serialize)]
pub struct LfdTimings {
    pub n_k: usize,
    pub n_modes: usize,
    /// Mesh, steady state from the free stream, Jacobians and colouring.
    pub build_s: f64,
    /// The first `Aerodynamics::gafs` call: every k, every mode and the gust.
    pub gafs_first_s: f64,
    /// The timed GAF tables after it (none with `repeat` 0).
    pub gafs: Option<Stats>,
    /// The first reverse call (it assembles the reverse mode's Jacobians) with a seed on every
    /// GAF entry.
    pub vjp_first_s: f64,
    /// The timed reverse calls after it (Jacobians reused; none with `repeat` 0).
    pub vjp: Option<Stats>,
    /// Peak resident memory of the process over the model's build, the GAF tables and the
    /// reverse calls (GB; where the system reports it: Linux).
    pub peak_build_gb: Option<f64>,
    pub peak_gafs_gb: Option<f64>,
    pub peak_vjp_gb: Option<f64>,
}

/// Puts the LFD study's GAF table on the reduced frequencies `k` for a first-calls-only bench
/// (`--k` with `--repeat 0`): the gust response and warm-start figures need the study's own
/// list (at least 4 frequencies for its spline), so other repeat counts are refused.
pub fn set_frequencies(study: &mut Study, k: &[f64], repeat: Option<usize>) -> Result<()> {
    if repeat != Some(0) {
        anyhow::bail!(
            "--k needs --repeat 0: the repetitions' gust response and warm starts use the study's own reduced frequencies"
        );
    }
    gustkit_core::check_reduced_frequencies(k).map_err(|e| anyhow::anyhow!("--k: {e}"))?;
    match study.spec.aero.as_mut() {
        Some(aero) if matches!(aero.fidelity, crate::study::FidelitySpec::Lfd(_)) => {
            aero.reduced_frequencies = k.to_vec();
            Ok(())
        }
        _ => anyhow::bail!(
            "--k: {}: the study's fidelity is not the LFD",
            study.file.display()
        ),
    }
}

/// `repeat` timed calls of `f` (none for 0: a level where one call takes hours).
fn repeated(repeat: usize, mut f: impl FnMut() -> Result<f64>) -> Result<Option<Stats>> {
    if repeat == 0 {
        return Ok(None);
    }
    Ok(Some(Stats::of(
        (0..repeat).map(|_| f()).collect::<Result<_>>()?,
    )))
}

/// The LFD stages on the study's initial design (no steady-state cache), see [`LfdTimings`];
/// `repeat` 0 times the first calls alone.
pub fn bench_lfd(study: &Study, repeat: usize) -> Result<LfdTimings> {
    let (plate, modes, _) = analyze(study)?;
    let mut study = study.clone();
    study.cache_dir = None;
    reset_peak_memory();
    let t = Instant::now();
    let aero = study.aero_model(&plate)?;
    let build_s = t.elapsed().as_secs_f64();
    let peak_build_gb = peak_memory_gb();
    reset_peak_memory();
    let mut table = None;
    let mut gafs = || -> Result<f64> {
        let t = Instant::now();
        table = Some(
            aero.gafs(&plate, &modes)
                .map_err(|e| anyhow::anyhow!("aerodynamics: {e}"))?,
        );
        Ok(t.elapsed().as_secs_f64())
    };
    let gafs_first_s = gafs()?;
    let gafs = repeated(repeat, gafs)?;
    let peak_gafs_gb = peak_memory_gb();
    reset_peak_memory();
    let mut seed = table.expect("computed above");
    let (n_k, n_modes) = (seed.k.len(), seed.n_modes());
    for q in seed.q_ss.iter_mut().flatten().flatten() {
        *q = faer::c64::new(1.0, 0.5);
    }
    for q in seed.q_gs.iter_mut().flatten() {
        *q = faer::c64::new(0.5, -1.0);
    }
    let vjp = || -> Result<f64> {
        let t = Instant::now();
        std::hint::black_box(
            aero.gafs_vjp(&plate, &modes, &seed)
                .map_err(|e| anyhow::anyhow!("aerodynamics reverse: {e}"))?,
        );
        Ok(t.elapsed().as_secs_f64())
    };
    let vjp_first_s = vjp()?;
    let vjp = repeated(repeat, vjp)?;
    let peak_vjp_gb = peak_memory_gb();
    Ok(LfdTimings {
        n_k,
        n_modes,
        build_s,
        gafs_first_s,
        gafs,
        vjp_first_s,
        vjp,
        peak_build_gb,
        peak_gafs_gb,
        peak_vjp_gb,
    })
}

/// The LFD function (modes, GAFs, response) at a design next to the initial one, its GMRES
/// started from zero and from the initial design's solutions.
#[derive(Debug, Serialize)]
pub struct WarmStartTimings {
    /// Right-hand sides of a GAF table (k × (modes + gust)).
    pub rhs: usize,
    pub cold_s: f64,
    pub cold_iterations: usize,
    pub warm_s: f64,
    pub warm_iterations: usize,
    /// The gradient (the first output's RMS) there: adjoint GMRES from zero and from the
    /// previous design's adjoint solutions.
    pub gradient_cold_s: f64,
    pub gradient_cold_iterations: usize,
    pub gradient_warm_s: f64,
    pub gradient_warm_iterations: usize,
}

/// A fresh, empty scratch run folder `gustkit-bench-<name>-<pid>` in the temp dir and the case of
/// `study` with it as its run folder (the LFD's steady state and GMRES warm start live there).
fn scratch_case(study: &Study, name: &str) -> Result<(std::path::PathBuf, crate::case::Case)> {
    let dir = std::env::temp_dir().join(format!("gustkit-bench-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir)?;
    let mut s = study.clone();
    s.cache_dir = Some(dir.clone());
    Ok((dir, s.resolve()?))
}

/// Removes a scratch run folder and its process-wide GMRES warm-start store.
fn remove_scratch(dir: &std::path::Path) {
    let _ = std::fs::remove_dir_all(dir);
    crate::aero::lfd::clear_warm_start(dir);
}

/// See [`WarmStartTimings`]: the pipeline's function in two fresh scratch run folders, one
/// that first evaluated the initial design (its steady state and LFD solutions are the next
/// design's start) and one that did not (its steady state cached beforehand, so that only the
/// GAF table's start differs).
pub fn bench_lfd_warm_start(study: &Study) -> Result<WarmStartTimings> {
    let settings = study.gust_settings()?;
    let design = study.initial_design()?;
    let n_t = design.thickness.len();
    let x0 = design.to_vec();
    let mut x1 = x0.clone();
    for t in x1.iter_mut().take(n_t) {
        *t *= 1.01;
    }
    // the function, then the gradient of the first output's RMS: (function s, gradient s)
    let timed = |case: &crate::case::Case, x: &[f64]| -> Result<(f64, f64)> {
        let t = Instant::now();
        let ev = crate::pipeline::evaluate(case, &settings, x)?;
        let function = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let seeds = crate::pipeline::OutputSeeds {
            rms: (0..ev.rms_m.len())
                .map(|i| if i == 0 { 1.0 } else { 0.0 })
                .collect(),
            ..Default::default()
        };
        crate::pipeline::gradient(&ev, &seeds)?;
        Ok((function, t.elapsed().as_secs_f64()))
    };
    let (warm_dir, warm_case) = scratch_case(study, "warm-warm")?;
    timed(&warm_case, &x0)?;
    let (warm_s, gradient_warm_s) = timed(&warm_case, &x1)?;
    let store = |d: &std::path::Path| {
        let s = crate::aero::lfd::warm_start_store(d);
        let w = s.lock().unwrap_or_else(|e| e.into_inner());
        (w.last_iterations, w.last_adjoint_iterations)
    };
    // the gradient's reverse sweep reuses the function's forward solutions (no table of its
    // own): the store's last table is the function's
    let (warm_iterations, gradient_warm_iterations) = store(&warm_dir);
    // the cold folder: the next design's steady state solved first, its GMRES store then
    // emptied
    let (cold_dir, cold_case) = scratch_case(study, "warm-cold")?;
    timed(&cold_case, &x1)?;
    crate::aero::lfd::clear_warm_start(&cold_dir);
    let (cold_s, gradient_cold_s) = timed(&cold_case, &x1)?;
    let (cold_iterations, gradient_cold_iterations) = store(&cold_dir);
    let modes = settings_modes(study)?;
    let n_k = study
        .spec
        .aero
        .as_ref()
        .map_or(0, |a| a.reduced_frequencies.len());
    remove_scratch(&warm_dir);
    remove_scratch(&cold_dir);
    Ok(WarmStartTimings {
        rhs: n_k * (modes + 1),
        cold_s,
        cold_iterations,
        warm_s,
        warm_iterations,
        gradient_cold_s,
        gradient_cold_iterations,
        gradient_warm_s,
        gradient_warm_iterations,
    })
}

/// A line search's backtrack on the LFD study with the planform moving: the function at the
/// initial design x₀, at the trial point x₀ + p (every thickness × 1.01, every planform
/// parameter × 1.002) and at the backtracked x₀ + p/2, in a fresh run folder whose GMRES
/// starts from the last design's solutions alone, then from the combination of the last
/// `designs` (the study's `warm_start_designs`): the backtrack's GMRES iterations and time.
#[derive(Debug, Serialize)]
pub struct LineSearchTimings {
    pub rhs: usize,
    pub designs: usize,
    pub one_design_s: f64,
    pub one_design_iterations: usize,
    pub several_designs_s: f64,
    pub several_designs_iterations: usize,
}

/// See [`LineSearchTimings`].
pub fn bench_lfd_line_search(study: &Study) -> Result<LineSearchTimings> {
    let settings = study.gust_settings()?;
    let x0 = study.initial_design()?.to_vec();
    let n_t = x0.len() - crate::wing::N_PLANFORM;
    let step = |t: f64| -> Vec<f64> {
        x0.iter()
            .enumerate()
            .map(|(i, v)| v * (1.0 + t * if i < n_t { 0.01 } else { 0.002 }))
            .collect()
    };
    let designs = match study.spec.aero.as_ref().map(|a| &a.fidelity) {
        Some(crate::aero::FidelitySpec::Lfd(l)) => l.warm_start_designs(),
        _ => anyhow::bail!("the line-search bench needs an LFD study"),
    };
    let run = |kept: usize| -> Result<(f64, usize)> {
        let mut s = study.clone();
        if let Some(crate::aero::FidelitySpec::Lfd(l)) =
            s.spec.aero.as_mut().map(|a| &mut a.fidelity)
        {
            l.warm_start_designs = Some(kept);
        }
        let (dir, case) = scratch_case(&s, &format!("line-{kept}"))?;
        crate::pipeline::evaluate(&case, &settings, &x0)?;
        crate::pipeline::evaluate(&case, &settings, &step(1.0))?;
        let t = Instant::now();
        crate::pipeline::evaluate(&case, &settings, &step(0.5))?;
        let elapsed = t.elapsed().as_secs_f64();
        let iterations = {
            let w = crate::aero::lfd::warm_start_store(&dir);
            let w = w.lock().unwrap_or_else(|e| e.into_inner());
            w.last_iterations
        };
        remove_scratch(&dir);
        Ok((elapsed, iterations))
    };
    let (one_design_s, one_design_iterations) = run(1)?;
    let (several_designs_s, several_designs_iterations) = run(designs)?;
    let n_k = study
        .spec
        .aero
        .as_ref()
        .map_or(0, |a| a.reduced_frequencies.len());
    Ok(LineSearchTimings {
        rhs: n_k * (settings_modes(study)? + 1),
        designs,
        one_design_s,
        one_design_iterations,
        several_designs_s,
        several_designs_iterations,
    })
}

/// The modes the study's initial design retains.
fn settings_modes(study: &Study) -> Result<usize> {
    Ok(analyze(study)?.1.len())
}

/// Timings of the aerodynamic chain for a study.
#[derive(Debug, Serialize)]
pub struct AeroTimings {
    pub n_boxes: usize,
    pub n_k: usize,
    pub n_modes: usize,
    /// Influence matrices at every k (one pass over the box pairs, rows in parallel).
    pub assembly: Stats,
    /// LU factorizations at every k, one thread.
    pub factorization: Stats,
    /// `Aerodynamics::gafs` as used (rayon over k): assembly, factorization, solves, GAFs.
    pub gafs: Stats,
    /// `gafs_vjp` (reverse mode incl. geometry), rayon over k.
    pub gafs_vjp: Stats,
}

/// Times the DLM of a study (see [`AeroTimings`]); medians of `repeat` runs for the parallel parts.
pub fn bench_aero(study: &Study, repeat: usize) -> Result<AeroTimings> {
    use faer::{c64, Mat};
    let (plate, modes, _) = analyze(study)?;
    let aero = study.aero_model(&plate)?;
    let Some(crate::study::AeroSpec {
        fidelity: crate::study::FidelitySpec::Dlm(spec),
        ..
    }) = &study.spec.aero
    else {
        anyhow::bail!("the study has no DLM");
    };
    let dlm = spec
        .lattice(plate.planform())
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let f = aero.flight;
    let n = dlm.n_boxes();
    let kds: Vec<f64> = aero.k.iter().map(|k| k / f.b_ref).collect();
    let matrices = || -> Vec<Mat<c64>> {
        dlm.influence_matrices(&dlm.boxes, f.mach, &kds)
            .iter()
            .map(|d| Mat::from_fn(n, n, |i, j| d[i * n + j].value()))
            .collect()
    };
    let assembly = measure(repeat, || {
        let t = Instant::now();
        std::hint::black_box(matrices());
        Ok(t.elapsed().as_secs_f64())
    })?;
    let mats = matrices();
    let factorization = measure(repeat, || {
        let t = Instant::now();
        for m in &mats {
            std::hint::black_box(m.partial_piv_lu());
        }
        Ok(t.elapsed().as_secs_f64())
    })?;
    let (mut tg, mut tv) = (Vec::new(), Vec::new());
    for rep in 0..WARMUP + repeat.max(1) {
        // a fresh model each time: the GAFs build the influence matrices, the reverse mode then
        // reuses them as in the pipeline
        let aero = study.aero_model(&plate)?;
        let a = Instant::now();
        let table = aero
            .gafs(&plate, &modes)
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        let b = Instant::now();
        std::hint::black_box(
            aero.gafs_vjp(&plate, &modes, &table)
                .map_err(|e| anyhow::anyhow!("{e}"))?,
        );
        if rep >= WARMUP {
            tg.push((b - a).as_secs_f64());
            tv.push(b.elapsed().as_secs_f64());
        }
    }
    Ok(AeroTimings {
        n_boxes: n,
        n_k: aero.k.len(),
        n_modes: modes.len(),
        assembly,
        factorization,
        gafs: Stats::of(tg),
        gafs_vjp: Stats::of(tv),
    })
}

/// Timings of the gust pipeline at the initial design.
#[derive(Debug, Serialize)]
pub struct PipelineTimings {
    /// One function evaluation: modes, GAFs (the influence matrices rebuilt, as when the planform
    /// changes), the stability check and every RMS.
    pub function: Stats,
    /// Its parts: the aeroelastic model (plate, modes, GAFs) …
    pub aeroelastic: Stats,
    /// … the stability check at the flight condition (p-k at 12 speeds) …
    pub stability: Stats,
    /// … and the gust response (Eqs. 16–18, every RMS; the stability check included).
    pub response: Stats,
    /// The flutter-margin constraint's p-k roots, when the study's optimization has one.
    pub margin: Option<Stats>,
    /// One gradient of every output (one reverse sweep).
    pub gradient: Stats,
    /// When the study has an optimization: one function as the optimizer asks for it (the above
    /// and the flutter margin) and one gradient of the objective and every constraint.
    pub design_function: Option<Stats>,
    pub design_gradient: Option<Stats>,
    /// With a `discrete_gust` section: the transient model on its grid with the histories of
    /// every output for every gust of the section (the tuned grid without refinement) and the
    /// KS peak of the first output (the constraint's output, with a peak limit) …
    pub discrete_function: Option<Stats>,
    /// … and the gradient of that KS in every design variable (the adjoint FFTs, the reverse
    /// sweep of Eq. 16 on the grid, the GAF reverse mode, modes, planform).
    pub discrete_gradient: Option<Stats>,
    pub discrete_gusts: usize,
}

/// Times one function evaluation, its parts, the flutter margin and one gradient of the gust
/// pipeline, and the design problem's function and gradient.
pub fn bench_pipeline(study: &Study, repeat: usize) -> Result<PipelineTimings> {
    use crate::optim::Problem;
    let case = study.resolve()?;
    let settings = case.gust_settings()?;
    let x = case.initial.to_vec();
    let margin = study
        .spec
        .optimization
        .as_ref()
        .and_then(|o| o.flutter_margin.as_ref())
        .map(|m| crate::flutter::margin::FlutterMargin {
            speed_factor: m.speed_factor,
            damping_max: m.damping_max,
        });
    let timed = |f: &mut dyn FnMut() -> Result<()>| -> Result<f64> {
        let t = Instant::now();
        f()?;
        Ok(t.elapsed().as_secs_f64())
    };
    let function = measure(repeat, || {
        timed(&mut || {
            std::hint::black_box(crate::pipeline::evaluate(&case, settings, &x)?);
            Ok(())
        })
    })?;
    let aeroelastic = measure(repeat, || {
        timed(&mut || {
            std::hint::black_box(crate::pipeline::aeroelastic(&case, &x)?);
            Ok(())
        })
    })?;
    let ev = crate::pipeline::evaluate(&case, settings, &x)?;
    let stability = measure(repeat, || {
        timed(&mut || crate::flutter::check_stability(&ev.modes, &ev.table, &ev.aero.flight))
    })?;
    let mut response = Vec::new();
    for rep in 0..WARMUP + repeat.max(1) {
        let a = crate::pipeline::aeroelastic(&case, &x)?;
        let t = Instant::now();
        std::hint::black_box(crate::pipeline::respond(a, settings)?);
        let t = t.elapsed().as_secs_f64();
        if rep >= WARMUP {
            response.push(t);
        }
    }
    let margin = match &margin {
        Some(m) => Some(measure(repeat, || {
            timed(&mut || {
                std::hint::black_box(ev.flutter_damping(m)?);
                Ok(())
            })
        })?),
        None => None,
    };
    let seeds = crate::pipeline::OutputSeeds {
        mass: 1.0,
        area: 1.0,
        rms: vec![1.0; ev.rms_m.len()],
        damping: None,
        gust: None,
    };
    let gradient = measure(repeat, || {
        timed(&mut || {
            std::hint::black_box(crate::pipeline::gradient(&ev, &seeds)?);
            Ok(())
        })
    })?;
    let (mut design_function, mut design_gradient) = (None, None);
    if study.spec.optimization.is_some() {
        let (lower, upper) = study.design_bounds()?;
        let mut spec =
            crate::runner::wing::optimize::design_spec(study, settings, &ev, lower, upper)?;
        spec.peak = crate::runner::wing::optimize::peak_limit(study, &ev)?;
        let mut problem = crate::problem::DesignProblem::new(&case, settings.clone(), spec);
        design_function = Some(measure(repeat, || {
            timed(&mut || {
                problem.values(&x)?;
                Ok(())
            })
        })?);
        // the gradient at the point just evaluated, as the SQP asks for it
        design_gradient = Some(measure(repeat, || {
            timed(&mut || {
                problem.gradients(&x)?;
                Ok(())
            })
        })?);
    }
    let (mut discrete_function, mut discrete_gradient, mut discrete_gusts) = (None, None, 0);
    if let Some(d) = study.discrete_gust_settings()? {
        // the peak limit where the optimization has one, else the same over the section's
        // gusts on the first output
        let pc = match study.peak_constraint()? {
            Some(c) => c,
            None => crate::study::discrete::PeakConstraint {
                name: String::new(),
                output: 0,
                derivative: 0,
                limit: 1.0,
                unit: String::new(),
                gusts: d.case.gusts(ev.aero.flight.velocity),
            },
        };
        let (gusts, output) = (&pc.gusts, pc.output);
        let p = ev.problem();
        let der = pc.derivatives(p.outputs.len());
        let r = crate::problem::peak_response(&ev, &pc, d.span)?;
        let grid = r.grid.clone();
        let scale = r.largest_abs(output).max(f64::MIN_POSITIVE);
        discrete_function = Some(measure(repeat, || {
            timed(&mut || {
                let mut model = crate::gust::discrete::TransientModel::new(&p, &der, grid.clone())?;
                for g in gusts {
                    std::hint::black_box(model.respond(g, false));
                }
                std::hint::black_box(crate::gust::discrete::PeakKs::evaluate(
                    &mut model, gusts, output, scale,
                ));
                Ok(())
            })
        })?);
        let mut model = crate::gust::discrete::TransientModel::new(&p, &der, grid.clone())?;
        let ks = crate::gust::discrete::PeakKs::evaluate(&mut model, gusts, output, scale);
        discrete_gradient = Some(measure(repeat, || {
            timed(&mut || {
                let gg = ks.vjp(&mut model, &p, gusts, 1.0)?;
                let seeds = crate::pipeline::OutputSeeds {
                    mass: 0.0,
                    area: 0.0,
                    rms: vec![0.0; ev.rms_m.len()],
                    damping: None,
                    gust: Some(gg),
                };
                std::hint::black_box(crate::pipeline::gradient(&ev, &seeds)?);
                Ok(())
            })
        })?);
        discrete_gusts = gusts.len();
    }
    Ok(PipelineTimings {
        function,
        aeroelastic,
        stability,
        response: Stats::of(response),
        margin,
        gradient,
        design_function,
        design_gradient,
        discrete_function,
        discrete_gradient,
        discrete_gusts,
    })
}
