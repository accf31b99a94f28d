//! Exporters for cross-checks against other codes: `gustkit gafs` (the GAF table of a study) and
//! `gustkit aic` (DLM box geometry and influence matrices).

use crate::report::results::ModeRow;
use crate::report::write_atomic;
use crate::runner::wing::analyze;
use crate::study::Study;
use anyhow::{Context, Result};
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

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
pub fn gafs(study: &Study, out: &Path) -> Result<()> {
    let file = &study.file;
    let study = study.clone();
    let (plate, modes, summary) = analyze(&study)?;
    let aero = study.aero_model(&plate)?;
    // the CFD fidelity spends its first minute on the steady state with nothing to show: say so
    println!(
        "GAFs of {} modes at {} reduced frequencies with the {} fidelity{} …",
        modes.len(),
        aero.k.len(),
        aero.name,
        if aero.name == "lfd" {
            " (steady Euler solution, then one linear solve per reduced frequency and right-hand side)"
        } else {
            ""
        }
    );
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
        fidelity: aero.name.into(),
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
        "GAFs of {} modes at {} reduced frequencies ({}) written to {}",
        modes.len(),
        table.k.len(),
        if elapsed < 1.0 {
            format!("{:.0} ms", 1e3 * elapsed)
        } else {
            format!("{elapsed:.1} s")
        },
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
        crate::study::read_text(file).with_context(|| format!("cannot read {}", file.display()))?;
    let value: serde_json::Value = serde_json::from_str(&text)
        .with_context(|| format!("{}: not valid JSON", file.display()))?;
    let (dlm, b_ref) = if value.get("schema_version").is_some() {
        let study = crate::runner::LoadedStudy::load(file)?.into_wing(file, "aic")?;
        let plate = study.build_model()?;
        let Some(aero) = &study.spec.aero else {
            anyhow::bail!("{}: aero: missing (the study has no DLM)", file.display());
        };
        let crate::study::FidelitySpec::Dlm(spec) = &aero.fidelity else {
            anyhow::bail!(
                "{}: aero.fidelity: `gustkit aic` writes DLM influence matrices; this study's fidelity is {}",
                file.display(),
                aero.fidelity.builder().name()
            );
        };
        let boxes = spec.n_chord.saturating_mul(spec.n_span);
        crate::study::limits::check_bytes(
            &format!(
                "the influence matrices of {boxes} boxes at {} reduced frequencies",
                ks.len()
            ),
            crate::study::limits::dlm_bytes(boxes, ks.len(), false) * 4.0,
        )
        .map_err(|e| anyhow::anyhow!("{}: aero.fidelity.dlm: {e}", file.display()))?;
        let dlm = spec
            .lattice(plate.planform())
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
        let boxes = sf
            .surfaces
            .iter()
            .map(|s| s.n_chord.saturating_mul(s.n_span))
            .fold(0usize, usize::saturating_add);
        // the matrices, and their JSON text (about 50 bytes a number)
        crate::study::limits::check_bytes(
            &format!(
                "the influence matrices of {boxes} boxes at {} reduced frequencies",
                ks.len()
            ),
            crate::study::limits::dlm_bytes(boxes, ks.len(), false) * 4.0,
        )
        .map_err(|e| anyhow::anyhow!("{}: surfaces: {e}", file.display()))?;
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
