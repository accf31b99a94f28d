//! Study files: the JSON case schema, its validation, and what a study builds.
//!
//! Every field is checked at load; an error names the file, the JSON path of the field and the
//! reason. Unknown fields are rejected (so a typo never silently falls back to a default).
//! Lengths are given in `length_unit` (m, in or ft) and converted to SI here; angles in degrees;
//! material constants in SI with the unit in the field name.
//!
//! The `Study` methods live by idea: `load` (reading and the cross-section checks),
//! `structure` (the wing in SI, the design variables, the modal rule), `fidelity` (the
//! aerodynamic builder's checks and the comparison's second fidelity), `design_file` (another
//! run's final design read into the study), `warm_start` (that design and the run's BFGS matrix
//! as a starting point) and `resolve` (the resolved [`Case`] the pipeline takes). The
//! runners read the study; nothing below them does (`tests/architecture.rs`).

mod design_file;
pub mod discrete;
mod fidelity;
pub mod limits;
mod load;
pub mod nastran;
pub mod ranges;
mod resolve;
pub(crate) mod schema;
mod structure;
pub mod sweep;
mod warm_start;

pub use crate::aero::{dlm::DlmSpec, FidelitySpec};
pub use schema::{
    AeroSpec, AirfoilSpec, ClampSpec, FlightSpec, FlutterSpec, GustSpec, LengthUnit, MaterialSpec,
    MeshSpec, ModeCutoffSpec, ModesSpec, OptimizationSpec, OutputSpec, ReferenceSpec,
    StructureSpec, StudyFile, SweepCombine, SweepParameter, SweepSpec, WarmStartSpec, WingSpec,
};

use crate::aero::AeroModel;
use crate::case::{without_field, AeroCase, Case, ModeSelection, PlateSource};
pub use crate::case::{ModeRule, StudyError};
use crate::gust::{GustSettings, Output, Quantity, QuantityName};
use crate::structure::{airfoil_thickness, Clamp, Orthotropic, PlateMesh, PlateModel};
use crate::wing::{Airfoil, DesignVector, Planform};
use std::path::{Path, PathBuf};

/// The schema version this build reads.
pub const SCHEMA_VERSION: u32 = 1;

/// The checks every study kind shares: the schema version this build reads, and a name that is
/// safe as the run folder's name (it becomes `reports/<name>/`).
pub fn check_header(file: &Path, schema_version: u32, name: &str) -> Result<(), StudyError> {
    let err = |path: &str, reason: String| StudyError {
        file: file.to_path_buf(),
        path: path.into(),
        reason,
    };
    if schema_version != SCHEMA_VERSION {
        return Err(err(
            "schema_version",
            format!(
                "this gustkit reads schema version {SCHEMA_VERSION}, the file has {schema_version}"
            ),
        ));
    }
    if name.is_empty()
        || name.starts_with('.')
        || !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.')
    {
        return Err(err(
            "name",
            "must be a non-empty file-name-safe string (letters, digits, '_', '-', '.'; not starting with '.')".into(),
        ));
    }
    Ok(())
}

/// Reads a text input file; a leading UTF-8 byte-order mark (as some Windows editors write) is
/// dropped, since JSON parsers refuse it.
pub fn read_text(file: &Path) -> std::io::Result<String> {
    let text = std::fs::read_to_string(file)?;
    Ok(match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_string(),
        None => text,
    })
}

/// A JSON decoding message in words a study author reads: serde's "trailing characters" inside a
/// field means a list with more entries than the field takes (a point is [ξ, η]).
pub fn explain_json_error(path: &str, reason: &str) -> String {
    match reason.strip_prefix("trailing characters") {
        Some(at) if path != "." && !path.is_empty() => {
            format!("more entries than this field takes{at}")
        }
        Some(at) => format!("text after the end of the JSON document{at}"),
        None => reason.to_string(),
    }
}

/// A loaded, validated study.
#[derive(Clone, Debug)]
pub struct Study {
    pub file: PathBuf,
    pub spec: StudyFile,
    /// Where a fidelity may keep and reuse expensive state between runs (the LFD's steady
    /// solution): the run folder, set by the runner; none for a study used as a library.
    pub cache_dir: Option<PathBuf>,
}

impl Study {
    /// A study error at the JSON path `path` of this study's file.
    pub(crate) fn err(&self, path: &str, reason: impl Into<String>) -> StudyError {
        StudyError {
            file: self.file.clone(),
            path: path.into(),
            reason: reason.into(),
        }
    }
}

#[cfg(test)]
mod tests;
