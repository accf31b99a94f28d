//! CFD verification studies: JSON files with a `cfd` section (the paper's NACA 64A010 cases), run
//! by `gustkit run` with the finite-volume Euler solver of `gustkit-cfd`; results.json, summary.md
//! and figures are rendered from the typed results alone (so `gustkit report` can redraw them).

pub mod fig1;
pub mod motion;
pub mod report;
pub mod schema;
pub mod table1;
pub mod table2;

pub use report::{render, summary, CfdResults};
pub use schema::{CfdSpec, CfdStudyFile};

use anyhow::{bail, Result};
use gustkit_cfd::residual::{Euler, State};
use std::path::Path;
use std::time::Instant;

/// The Euler solver of a verification case: its mesh (built-in or file, read relative to the
/// study file `base`) and scheme, at free-stream state `q_inf`.
pub(crate) fn build(c: &CfdSpec, base: &Path, q_inf: State<f64>) -> Result<Euler> {
    let mesh = match (&c.mesh, &c.mesh_file) {
        (Some(m), _) => m.mesh(&c.airfoil.shape()),
        (None, Some(f)) => f.read(base)?,
        (None, None) => bail!("cfd: no mesh"),
    };
    mesh.check()
        .map_err(|err| anyhow::anyhow!("cfd.mesh: {err}"))?;
    let mut e = Euler::new(mesh, q_inf);
    e.order = c.order.order();
    e.limiter = c.limiter.limiter();
    Ok(e)
}

/// `gustkit run` of a CFD verification study.
pub fn run(s: &CfdStudyFile, reports: &Path) -> Result<()> {
    let file = s.file.as_path();
    let final_dir = reports.join(&s.name);
    let folder = crate::report::folder::RunFolder::begin(&final_dir, false)?;
    let dir = folder.path().to_path_buf();
    let t0 = Instant::now();
    let mut cells = 0;
    let steady = match &s.cfd.steady_gust {
        Some(g) => {
            let (n, r) = table1::steady_gust(&s.cfd, g, file, &dir)?;
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
            let (n, r) = fig1::time_gust(&s.cfd, g, file, &dir)?;
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
        kind: crate::kind::StudyKind::CfdVerification,
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
    folder.commit()?;
    println!("report written to {}", final_dir.display());
    Ok(())
}
