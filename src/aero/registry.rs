//! The one place where a study's fidelity spec becomes a builder: a wing study names its fidelity
//! as `aero.fidelity: {"dlm": {...}}`, and [`FidelitySpec::builder`] gives the builder of that
//! fidelity ([`super::contract::WingBuilder`]), so the transfer and the pipeline never ask which
//! fidelity they hold. What a fidelity can do is known from its spec alone, so a study that needs
//! a reverse mode its fidelity lacks is refused when it is loaded.

use super::contract::{BuildError, Capabilities, WingBuilder};
use gustkit_core::Aerodynamics;
use serde::{Deserialize, Serialize};

/// The aerodynamic fidelities a wing study can name.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
pub enum FidelitySpec {
    /// Doublet-Lattice Method on the wing planform.
    Dlm(super::dlm::DlmSpec),
    /// Euler LFD on the built-in wing mesh (or a mesh file).
    Lfd(super::lfd::LfdWingSpec),
    /// Theodorsen/Sears strip theory on streamwise strips of the planform.
    Strip(super::strip::StripWingSpec),
}

impl FidelitySpec {
    /// Makes a relative mesh-file path relative to `dir` (the study file's folder), as a study
    /// file's paths are.
    pub fn resolve_paths(&mut self, dir: &std::path::Path) {
        if let FidelitySpec::Lfd(spec) = self {
            if let Some(file) = spec.mesh_file.as_mut() {
                if std::path::Path::new(&file.path).is_relative() {
                    file.path = dir.join(&file.path).to_string_lossy().into_owned();
                }
            }
        }
    }

    /// The next resolution of this model for the resolution check (a lattice twice as fine, the
    /// next mesh level, twice the strips) with its words, or why there is none.
    pub fn refined(&self) -> Result<(FidelitySpec, String), String> {
        Ok(match self {
            FidelitySpec::Dlm(d) => {
                let (d, w) = d.refined();
                (FidelitySpec::Dlm(d), w)
            }
            FidelitySpec::Lfd(l) => {
                let (l, w) = l.refined()?;
                (FidelitySpec::Lfd(l), w)
            }
            FidelitySpec::Strip(s) => {
                let (s, w) = s.refined();
                (FidelitySpec::Strip(s), w)
            }
        })
    }

    /// The model in words (its lattice, mesh or strips), for reports.
    pub fn words(&self) -> String {
        match self {
            FidelitySpec::Dlm(d) => d.words(),
            FidelitySpec::Lfd(l) => l.words(),
            FidelitySpec::Strip(s) => s.words(),
        }
    }

    /// The builder of this fidelity.
    pub fn builder(&self) -> &dyn WingBuilder {
        match self {
            FidelitySpec::Dlm(spec) => spec,
            FidelitySpec::Lfd(spec) => spec,
            FidelitySpec::Strip(spec) => spec,
        }
    }
}

/// The aerodynamic models of a 2-D typical section (rigid plunge and pitch: the section models
/// bind to the structure through their own surface points, so they need no plate binding).
#[derive(Clone, Debug)]
pub enum SectionFidelitySpec {
    /// The LFD of the Euler solver on the built-in O-mesh.
    Lfd(super::lfd::SectionLfdSpec),
    /// Theodorsen/Sears strip theory with the Prandtl–Glauert factor.
    Strip(super::strip::StripSpec),
}

impl SectionFidelitySpec {
    /// What the fidelity can do: the LFD has no reverse mode yet (the LFD adjoint), strip
    /// theory has one.
    pub fn capabilities(&self) -> Capabilities {
        match self {
            SectionFidelitySpec::Lfd(_) => Capabilities {
                reverse: true,
                reverse_planform: true,
            },
            SectionFidelitySpec::Strip(_) => Capabilities {
                reverse: true,
                reverse_planform: true,
            },
        }
    }

    /// The fidelity's display name.
    pub fn display_name(&self) -> &'static str {
        match self {
            SectionFidelitySpec::Lfd(_) => "LFD (Euler)",
            SectionFidelitySpec::Strip(_) => "Theodorsen/Sears strip (Prandtl–Glauert)",
        }
    }

    /// The model of a section of chord `chord_m` at `mach`, and its cell count (0 for a model
    /// without a mesh).
    pub fn build(
        &self,
        chord_m: f64,
        mach: f64,
    ) -> Result<(Box<dyn Aerodynamics>, usize), BuildError> {
        match self {
            SectionFidelitySpec::Lfd(s) => {
                let m = s.build(chord_m, mach)?;
                let cells = m.lfd.euler.mesh.n_cells;
                Ok((Box::new(m), cells))
            }
            SectionFidelitySpec::Strip(s) => Ok((Box::new(s.build(chord_m)), 0)),
        }
    }
}
