//! The CFD verification study file (top-level key `cfd`) and its checks. The mesh and scheme
//! settings are the CFD fidelity's own (`crate::aero::lfd`).

use crate::aero::lfd::{CfdAirfoil, LimiterSpec, MeshFileSpec, OMeshSpec, OrderSpec};
use anyhow::{bail, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A CFD verification study file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CfdStudyFile {
    /// The file it was read from (not part of the document).
    #[serde(skip)]
    pub file: std::path::PathBuf,
    pub schema_version: u32,
    pub name: String,
    #[serde(default)]
    pub description: String,
    pub cfd: CfdSpec,
}

/// The case: airfoil, mesh, scheme, Mach number and the analyses to run.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CfdSpec {
    /// Built-in section: "naca64a010" (from its NACA Report 903 ordinates).
    pub airfoil: CfdAirfoil,
    /// The built-in O-mesh about the airfoil, or …
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<OMeshSpec>,
    /// … a mesh file (chord 1 along x, the wall around the airfoil).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh_file: Option<MeshFileSpec>,
    /// "first" or "second" (default) order.
    #[serde(default)]
    pub order: OrderSpec,
    /// Second order: "none" (default) or "van_albada" (smooth, differentiable).
    #[serde(default)]
    pub limiter: LimiterSpec,
    pub mach: f64,
    /// Paper Table 1: angle of attack at the far field against the equivalent uniform gust.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steady_gust: Option<SteadyGustSpec>,
    /// Paper Fig. 1: a sinusoidal vertical gust in the time domain.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_gust: Option<TimeGustSpec>,
    /// Paper Table 2: the LFD gust solution against the time domain.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lfd_gust: Option<super::table2::LfdGustSpec>,
    /// Prescribed rigid pitching or plunging in the time domain, against the LFD and Theodorsen.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_motion: Option<super::motion::TimeMotionSpec>,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SteadyGustSpec {
    pub alpha_deg: f64,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TimeGustSpec {
    /// Gust amplitude in units of the free-stream speed of sound.
    pub amplitude_mach: f64,
    /// k = ω b / U with b the semichord.
    pub reduced_frequency: f64,
    pub periods: usize,
    pub steps_per_period: usize,
}

impl CfdStudyFile {
    /// Checks a parsed CFD study document; errors name the file and the JSON path.
    pub fn from_value(file: &Path, doc: &serde_json::Value) -> Result<Self> {
        let mut s: Self = crate::report::from_json(file, doc)?;
        s.file = file.to_path_buf();
        let bad = |path: &str, reason: String| -> Result<Self> {
            bail!("{}: {path}: {reason}", file.display())
        };
        let c = &s.cfd;
        crate::study::check_header(file, s.schema_version, &s.name)?;
        if !(c.mach > 0.0 && c.mach < 1.0) {
            return bad("cfd.mach", format!("must lie in (0, 1) (got {})", c.mach));
        }
        match (&c.mesh, &c.mesh_file) {
            (Some(_), None) | (None, Some(_)) => {}
            _ => {
                return bad(
                    "cfd",
                    "give exactly one of mesh (built-in) and mesh_file".into(),
                )
            }
        }
        if let Some(m) = &c.mesh {
            if m.n_around < 8 || m.n_radial < 2 {
                return bad("cfd.mesh", "need n_around >= 8 and n_radial >= 2".into());
            }
            if !(m.far_field_chords >= 5.0) {
                return bad(
                    "cfd.mesh.far_field_chords",
                    format!("must be at least 5 (got {})", m.far_field_chords),
                );
            }
            if !(m.first_spacing_chords > 0.0
                && m.first_spacing_chords * (m.n_radial as f64) < m.far_field_chords)
            {
                return bad(
                    "cfd.mesh.first_spacing_chords",
                    format!(
                        "must be positive and below far_field_chords / n_radial (got {})",
                        m.first_spacing_chords
                    ),
                );
            }
        }
        if let Some(t) = &c.time_gust {
            if t.periods == 0 || t.steps_per_period < 4 || !(t.reduced_frequency > 0.0) {
                return bad(
                    "cfd.time_gust",
                    "need periods >= 1, steps_per_period >= 4 and a positive reduced_frequency"
                        .into(),
                );
            }
        }
        if let Some(t) = &c.lfd_gust {
            if !(t.reduced_frequency > 0.0 && t.reduced_frequency.is_finite()) {
                return bad(
                    "cfd.lfd_gust.reduced_frequency",
                    format!("must be positive (got {})", t.reduced_frequency),
                );
            }
            if !(t.amplitude_mach > 0.0 && t.amplitude_mach < 0.1) {
                return bad(
                    "cfd.lfd_gust.amplitude_mach",
                    format!(
                        "must lie in (0, 0.1): a small perturbation (got {})",
                        t.amplitude_mach
                    ),
                );
            }
            if t.steps_per_period < 4
                || t.linear_steps_per_period < 4
                || t.fit_periods == 0
                || t.linear_periods == 0
            {
                return bad(
                    "cfd.lfd_gust",
                    "need steps_per_period and linear_steps_per_period >= 4, fit_periods and linear_periods >= 1".into(),
                );
            }
        }
        if let Some(m) = &c.time_motion {
            if let Err((path, reason)) = super::motion::check(m) {
                return bad(&path, reason);
            }
        }
        if c.steady_gust.is_none()
            && c.time_gust.is_none()
            && c.lfd_gust.is_none()
            && c.time_motion.is_none()
        {
            return bad(
                "cfd",
                "nothing to run: add steady_gust, time_gust, lfd_gust or time_motion".into(),
            );
        }
        Ok(s)
    }
}
