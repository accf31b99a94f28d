//! `gustkit check-gradient`: the adjoint gradient of the first gust output's RMS against central
//! finite differences, like the paper's Table 4.

use crate::study::Study;
use anyhow::Result;
use serde::Serialize;
use std::time::Instant;

/// A scratch folder removed when dropped.
struct ScratchDir(std::path::PathBuf);

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
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
pub fn check_gradient(study: &Study, dvs: &[String], json: bool) -> Result<()> {
    let planform = dvs.iter().any(|d| !d.starts_with("t["));
    study.require_reverse_mode(&format!("check-gradient --dv {}", dvs.join(" ")), planform)?;
    let mut study = study.clone();
    // a fidelity that keeps state between builds (the LFD's steady solution) keeps it here for
    // the finite differences, which do not move it (thickness steps) or restart from it
    let _scratch = match study.cache_dir {
        Some(_) => None,
        None => {
            let dir =
                std::env::temp_dir().join(format!("gustkit-check-gradient-{}", std::process::id()));
            std::fs::create_dir_all(&dir)?;
            study.cache_dir = Some(dir.clone());
            Some(ScratchDir(dir))
        }
    };
    let case = study.resolve()?;
    let settings = case.gust_settings()?;
    let x0 = case.initial.to_vec();
    let design = &case.initial;
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
    let ev = crate::pipeline::evaluate(&case, settings, &x0)?;
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
    let f =
        |x: &[f64]| -> Result<f64> { Ok(crate::pipeline::evaluate(&case, settings, x)?.rms_m[0]) };
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

/// `gustkit check-linearization`: the aerodynamic model's linearization table (paper Table 3) at
/// the study's initial design: each linearization's forward pairing, its transposed pairing and
/// real finite differences at steps 1e-8 … 1e-13, with the digits of agreement.
pub fn check_linearization(study: &Study, json: bool) -> Result<()> {
    let plate = study.build_model()?;
    let aero = study.aero_model(&plate)?;
    let rows = aero.fidelity.linearization_checks();
    if rows.is_empty() {
        anyhow::bail!(
            "check-linearization: the {} fidelity has no linearization table (its reverse mode is checked by the dot-product tests of its crate); use an lfd study",
            aero.name
        );
    }
    let digits = |a: f64, b: f64| -((a - b).abs() / a.abs().max(f64::MIN_POSITIVE)).log10();
    if json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
        return Ok(());
    }
    println!(
        "{}: the {} model's linearizations about its steady state (random real vectors; digits of agreement with the forward pairing)",
        study.spec.name, aero.name
    );
    print!(
        "{:<42}{:>24}{:>24}{:>8}",
        "linearization", "forward", "reverse", "digits"
    );
    for (h, _) in &rows[0].fd {
        print!("{:>10}", format!("FD {h:.0e}"));
    }
    println!();
    for r in &rows {
        print!("{:<42}{:>24.15e}", r.name, r.forward);
        match r.reverse {
            Some(v) => print!("{v:>24.15e}{:>8.1}", digits(r.forward, v)),
            None => print!("{:>24}{:>8}", "(forward mode)", "-"),
        }
        for (_, v) in &r.fd {
            print!("{:>10.1}", digits(r.forward, *v));
        }
        println!();
    }
    Ok(())
}
