//! The typical-section study file (top-level key `typical_section`) and its checks.

use crate::gust::Turbulence;
use anyhow::{bail, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A typical-section study file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SectionStudyFile {
    /// The file it was read from (not part of the document).
    #[serde(skip)]
    pub file: std::path::PathBuf,
    pub schema_version: u32,
    pub name: String,
    #[serde(default)]
    pub description: String,
    pub typical_section: SectionSpec,
}

/// The case.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SectionSpec {
    pub structure: SectionStructure,
    pub flight: SectionFlight,
    pub cfd: SectionCfd,
    /// Reduced frequencies k = ω b / U of the GAF tables (both models).
    pub reduced_frequencies: Vec<f64>,
    pub gust: SectionGust,
    pub flutter: SectionFlutter,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SectionStructure {
    pub chord_m: f64,
    /// Theodorsen's a: elastic axis behind the mid-chord, semichords.
    pub elastic_axis: f64,
    /// Centre of gravity behind the elastic axis, semichords.
    pub x_alpha: f64,
    /// Radius of gyration about the elastic axis, semichords.
    pub r_alpha: f64,
    /// μ = m / (π ρ b²).
    pub mass_ratio: f64,
    pub plunge_frequency_hz: f64,
    pub pitch_frequency_hz: f64,
    pub damping_ratio: f64,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SectionFlight {
    pub mach: f64,
    pub density_kg_m3: f64,
    pub speed_of_sound_m_s: f64,
}

/// The CFD model of the section (the LFD fidelity's section spec: thickness, mesh, order).
pub type SectionCfd = crate::aero::lfd::SectionLfdSpec;

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SectionGust {
    pub turbulence: Turbulence,
    #[serde(default = "crate::study::schema::default_omega_min")]
    pub omega_min_rad_s: f64,
    #[serde(default = "crate::study::schema::default_points")]
    pub points: usize,
    #[serde(default = "crate::study::schema::default_max_tail")]
    pub max_tail: f64,
}

/// p-k sweep speeds.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SectionFlutter {
    pub velocity_min_m_s: f64,
    pub velocity_max_m_s: f64,
    pub velocities: usize,
}

impl SectionStudyFile {
    /// Checks a parsed study document; errors name the file and the field.
    pub fn from_value(file: &Path, doc: &serde_json::Value) -> Result<Self> {
        let mut s: Self = crate::report::from_json(file, doc)?;
        s.file = file.to_path_buf();
        let bad = |path: &str, reason: String| -> Result<Self> {
            bail!("{}: typical_section.{path}: {reason}", file.display())
        };
        crate::study::check_header(file, s.schema_version, &s.name)?;
        let t = &s.typical_section;
        let st = &t.structure;
        for (name, v) in [
            ("structure.chord_m", st.chord_m),
            ("structure.r_alpha", st.r_alpha),
            ("structure.mass_ratio", st.mass_ratio),
            ("structure.plunge_frequency_hz", st.plunge_frequency_hz),
            ("structure.pitch_frequency_hz", st.pitch_frequency_hz),
            ("flight.density_kg_m3", t.flight.density_kg_m3),
            ("flight.speed_of_sound_m_s", t.flight.speed_of_sound_m_s),
            ("flutter.velocity_min_m_s", t.flutter.velocity_min_m_s),
            ("cfd.thickness", t.cfd.thickness),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return bad(name, format!("must be positive (got {v})"));
            }
        }
        if !(st.elastic_axis.abs() < 1.0) || !st.x_alpha.is_finite() {
            return bad(
                "structure.elastic_axis",
                format!(
                    "must lie on the chord, in (−1, 1) (got {})",
                    st.elastic_axis
                ),
            );
        }
        if st.r_alpha * st.r_alpha <= st.x_alpha * st.x_alpha {
            return bad(
                "structure.r_alpha",
                format!(
                    "r_alpha² must exceed x_alpha² (a positive-definite mass matrix; got r_alpha {} and x_alpha {})",
                    st.r_alpha, st.x_alpha
                ),
            );
        }
        if !(st.damping_ratio >= 0.0 && st.damping_ratio < 1.0) {
            return bad(
                "structure.damping_ratio",
                format!("must lie in [0, 1) (got {})", st.damping_ratio),
            );
        }
        if !(t.flight.mach > 0.0 && t.flight.mach < 0.8) {
            return bad(
                "flight.mach",
                format!(
                    "must lie in (0, 0.8): subsonic, shock-free (got {})",
                    t.flight.mach
                ),
            );
        }
        if !(t.flutter.velocity_max_m_s > t.flutter.velocity_min_m_s) || t.flutter.velocities < 2 {
            return bad(
                "flutter",
                "need velocity_max_m_s > velocity_min_m_s and at least 2 velocities".into(),
            );
        }
        if let Err(e) = gustkit_core::check_reduced_frequencies(&t.reduced_frequencies) {
            return bad("reduced_frequencies", e.to_string());
        }
        if t.reduced_frequencies.len() < 4 {
            return bad(
                "reduced_frequencies",
                "need at least 4 (cubic-spline interpolation)".into(),
            );
        }
        if let Err(e) = t.gust.turbulence.validate() {
            return bad("gust.turbulence", e);
        }
        let m = &t.cfd.mesh;
        if m.n_around < 8 || m.n_radial < 2 || !(m.first_spacing_chords > 0.0) {
            return bad(
                "cfd.mesh",
                "need n_around >= 8, n_radial >= 2 and a positive first_spacing_chords".into(),
            );
        }
        Ok(s)
    }
}
