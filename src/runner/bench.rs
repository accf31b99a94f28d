//! `gustkit bench`: timings of the structural chain, the DLM and the gust pipeline of a study,
//! and optionally of its whole optimization.

use crate::runner::wing::{analyze, optimize::optimize};
use crate::structure::{mass_grad, modal, modes_vjp, ModalSeed, Sampler};
use crate::study::Study;
use anyhow::{Context, Result};
use serde::Serialize;
use std::time::Instant;

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
pub fn bench(study: &Study, repeat: usize, optimization: bool) -> Result<()> {
    let file = &study.file;
    let study = study.clone();
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
