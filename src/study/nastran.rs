//! The study file of a Nastran model (`"model": {"nastran": "wing.bdf"}`): design variables on
//! the model's properties related the way SOL 200's DVPREL1 relates them, the structural mass
//! as objective, and limits on the RMS or N0 of the subcase's random gust response. Values are
//! in the model's own units (gustkit converts nothing in a Nastran model). What the model
//! itself must hold (the properties, the outputs' grids) is checked when the runner reads it.

use anyhow::{bail, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A study of a Nastran model.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NastranStudyFile {
    pub schema_version: u32,
    pub name: String,
    #[serde(default)]
    pub description: String,
    pub model: ModelSpec,
    pub design_variables: Vec<VariableSpec>,
    /// DVPREL1-like relations: a property field = c0 + Σ coefficient · variable.
    pub properties: Vec<RelationSpec>,
    /// `"mass"`: the structural mass (the only objective so far).
    #[serde(default = "mass")]
    pub objective: String,
    pub constraints: Vec<ConstraintSpec>,
    /// The LFD in place of the model's DLM (`{"fidelity": {"lfd": {…}}, "airfoil": …,
    /// "reduced_frequencies": […]}`); the model's own CAERO1 DLM without it.
    #[serde(default)]
    pub aero: Option<NastranAeroSpec>,
    #[serde(default)]
    pub optimization: NastranOptimizationSpec,
    /// The study file (set at load).
    #[serde(skip)]
    pub file: PathBuf,
}

fn mass() -> String {
    "mass".into()
}

/// The Nastran model and the subcase the study designs against.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelSpec {
    /// The Nastran input, relative to the study file.
    pub nastran: String,
    /// The subcase whose random gust response is constrained (the model's only one when left
    /// out).
    #[serde(default)]
    pub subcase: Option<u32>,
    /// A subcase with FMETHOD (the model's FLUTTER, FLFACT and MKAERO cards): its p-k flutter
    /// points analysed at the initial and final designs; a final design that flutters within
    /// the FLFACT velocities ends the run with exit 3.
    #[serde(default)]
    pub flutter_subcase: Option<u32>,
}

/// A design variable (DESVAR): its name, initial value and bounds.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VariableSpec {
    pub name: String,
    pub initial: f64,
    pub lower: f64,
    pub upper: f64,
}

/// A DVPREL1-like relation.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RelationSpec {
    /// PSHELL, PBAR or PBEAM.
    pub card: String,
    pub id: u32,
    /// T (PSHELL), A, I1, I2 or J (PBAR, PBEAM).
    pub field: String,
    #[serde(default)]
    pub c0: f64,
    /// Design variable name → coefficient.
    pub terms: BTreeMap<String, f64>,
}

/// The LFD on the model's lifting surface: the wing mesh about its one CAERO1 panel with the
/// study's section (Nastran's panels are flat), solved at the reduced frequencies given (the
/// response interpolates between them, as it does between the DLM's).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NastranAeroSpec {
    /// `{"lfd": {…}}`, the keys of a wing study's LFD (mesh level or sizes, GMRES and steady
    /// settings, memory limit); a mesh file's coordinates are in the model's units.
    pub fidelity: crate::aero::FidelitySpec,
    /// The section: `"naca65a004"` or `{"name", "x_c", "z_c"}`.
    pub airfoil: super::AirfoilSpec,
    /// Reduced frequencies k = ω REFC / 2V of the LFD table, from 0 up to at least the FREQ
    /// list's highest.
    pub reduced_frequencies: Vec<f64>,
}

/// A limit on one output of the random gust response, by Nastran's label.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConstraintSpec {
    /// `9T3`, `ACCE 9T3`, `SPCF 11R3`, `MODE 2` or a MONPNT1 component (`ROOT CMX`).
    pub output: String,
    /// Largest RMS (the output's unit in the model's units).
    #[serde(default)]
    pub rms_max: Option<f64>,
    /// Largest zero-crossing rate N0, Hz.
    #[serde(default)]
    pub n0_max_hz: Option<f64>,
}

/// When the SQP stops.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NastranOptimizationSpec {
    #[serde(default = "max_iterations")]
    pub max_iterations: usize,
    #[serde(default = "tolerance")]
    pub tolerance: f64,
    /// The SQP line search's memory (1: monotone), as `optimization.nonmonotone_memory` of a
    /// wing study.
    #[serde(default = "super::schema::default_nonmonotone_memory")]
    pub nonmonotone_memory: usize,
}

fn max_iterations() -> usize {
    100
}

fn tolerance() -> f64 {
    1e-6
}

impl Default for NastranOptimizationSpec {
    fn default() -> Self {
        Self {
            max_iterations: max_iterations(),
            tolerance: tolerance(),
            nonmonotone_memory: super::schema::default_nonmonotone_memory(),
        }
    }
}

impl NastranStudyFile {
    /// Reads and checks a study document; every error names the file, the JSON path and why.
    pub fn from_value(file: &Path, doc: &serde_json::Value) -> Result<Self> {
        let mut s: Self = crate::report::from_json(file, doc)?;
        s.file = file.to_path_buf();
        if let Some(a) = s.aero.as_mut() {
            // a mesh file's path is relative to the study file, as the model's is
            a.fidelity
                .resolve_paths(file.parent().unwrap_or(Path::new(".")));
        }
        crate::study::check_header(file, s.schema_version, &s.name)?;
        s.check()
            .map_err(|(path, reason)| anyhow::anyhow!("{}: {path}: {reason}", file.display()))?;
        Ok(s)
    }

    /// The Nastran input's path (relative to the study file's folder).
    pub fn model_path(&self) -> PathBuf {
        self.file
            .parent()
            .unwrap_or(Path::new("."))
            .join(&self.model.nastran)
    }

    /// The index of the design variable `name`.
    pub fn variable(&self, name: &str) -> Option<usize> {
        self.design_variables.iter().position(|v| v.name == name)
    }

    fn check(&self) -> Result<(), (String, String)> {
        let bad = |path: String, reason: String| Err((path, reason));
        if self.model.nastran.trim().is_empty() {
            return bad("model.nastran".into(), "names no file".into());
        }
        if !crate::nastran::is_nastran(Path::new(&self.model.nastran)) {
            return bad(
                "model.nastran".into(),
                format!(
                    "\"{}\" is not a Nastran input by its extension ({})",
                    self.model.nastran,
                    crate::nastran::EXTENSIONS.join(", ")
                ),
            );
        }
        if self.design_variables.is_empty() {
            return bad(
                "design_variables".into(),
                "is empty: give at least one".into(),
            );
        }
        for (i, v) in self.design_variables.iter().enumerate() {
            let at = |f: &str| format!("design_variables[{i}].{f}");
            if v.name.trim().is_empty() {
                return bad(at("name"), "is empty".into());
            }
            if self.variable(&v.name) != Some(i) {
                return bad(at("name"), format!("\"{}\" is used twice", v.name));
            }
            for (f, x) in [
                ("initial", v.initial),
                ("lower", v.lower),
                ("upper", v.upper),
            ] {
                if !x.is_finite() {
                    return bad(at(f), format!("must be a finite number (got {x})"));
                }
            }
            if v.lower >= v.upper {
                return bad(
                    at("upper"),
                    format!("must exceed lower ({} ≥ {})", v.lower, v.upper),
                );
            }
            if v.initial < v.lower || v.initial > v.upper {
                return bad(
                    at("initial"),
                    format!(
                        "{} lies outside the bounds [{}, {}]",
                        v.initial, v.lower, v.upper
                    ),
                );
            }
        }
        if let Some(a) = &self.aero {
            if !matches!(a.fidelity, crate::aero::FidelitySpec::Lfd(_)) {
                return bad(
                    "aero.fidelity".into(),
                    "a Nastran model's DLM comes from its CAERO1 cards: the fidelity here may only be {\"lfd\": …} (leave \"aero\" out for the DLM)".into(),
                );
            }
            if let crate::aero::FidelitySpec::Lfd(l) = &a.fidelity {
                if let Some(f) = &l.mesh_file {
                    if f.length_unit != crate::aero::lfd::MeshUnit::M {
                        return bad(
                            "aero.fidelity.lfd.mesh_file.length_unit".into(),
                            format!("\"{}\": a Nastran model's mesh file is in the model's own units (gustkit converts nothing in a Nastran model): leave length_unit out", f.length_unit.name()),
                        );
                    }
                }
            }
            if let Err(e) = a.airfoil.airfoil() {
                return bad("aero.airfoil".into(), e);
            }
            if let Err(e) = gustkit_core::aero::check_reduced_frequencies(&a.reduced_frequencies) {
                return bad("aero.reduced_frequencies".into(), e.to_string());
            }
        }
        if self.properties.is_empty() {
            return bad(
                "properties".into(),
                "is empty: relate each design variable to a property field".into(),
            );
        }
        let mut used = vec![false; self.design_variables.len()];
        let mut seen = std::collections::BTreeSet::new();
        for (i, r) in self.properties.iter().enumerate() {
            let at = |f: &str| format!("properties[{i}].{f}");
            if !seen.insert((
                r.card.to_ascii_uppercase().replace("PBEAM", "PBAR"),
                r.id,
                r.field.to_ascii_uppercase(),
            )) {
                return bad(
                    at("field"),
                    format!(
                        "{} {} {} is related twice: give one relation a field (with several terms)",
                        r.card, r.id, r.field
                    ),
                );
            }
            if !r.c0.is_finite() {
                return bad(at("c0"), format!("must be finite (got {})", r.c0));
            }
            if r.terms.is_empty() {
                return bad(at("terms"), "is empty: name a design variable".into());
            }
            for (name, c) in &r.terms {
                let Some(v) = self.variable(name) else {
                    return bad(
                        format!("properties[{i}].terms.{name}"),
                        "is not a design variable of the study".into(),
                    );
                };
                if !(c.is_finite() && *c != 0.0) {
                    return bad(
                        format!("properties[{i}].terms.{name}"),
                        format!("the coefficient must be finite and non-zero (got {c})"),
                    );
                }
                used[v] = true;
            }
        }
        if let Some(v) = used.iter().position(|u| !u) {
            return bad(
                format!("design_variables[{v}]"),
                format!(
                    "\"{}\" moves no property: name it in a relation's terms",
                    self.design_variables[v].name
                ),
            );
        }
        if self.objective != "mass" {
            return bad(
                "objective".into(),
                format!(
                    "\"{}\" is not an objective: \"mass\" (the structural mass) is",
                    self.objective
                ),
            );
        }
        if self.constraints.is_empty() {
            return bad(
                "constraints".into(),
                "is empty: limit the RMS or N0 of at least one output".into(),
            );
        }
        for (i, c) in self.constraints.iter().enumerate() {
            let at = |f: &str| format!("constraints[{i}].{f}");
            if crate::nastran::design::parse_output(&c.output).is_none()
                && !crate::nastran::design::is_monitor_label(&c.output)
            {
                return bad(
                    at("output"),
                    format!("\"{}\" is not an output label: 9T3 (grid 9, component T3), 9R1, ACCE 9T3, SPCF 11R3, MODE 2 or a monitor point's component (ROOT CMX)", c.output),
                );
            }
            if c.rms_max.is_none() && c.n0_max_hz.is_none() {
                return bad(
                    at("rms_max"),
                    "missing: give rms_max, n0_max_hz or both".into(),
                );
            }
            for (f, v) in [("rms_max", c.rms_max), ("n0_max_hz", c.n0_max_hz)] {
                if let Some(v) = v {
                    if !(v > 0.0 && v.is_finite()) {
                        return bad(at(f), format!("must be positive (got {v})"));
                    }
                }
            }
        }
        let o = &self.optimization;
        if o.max_iterations == 0 {
            return bad(
                "optimization.max_iterations".into(),
                "must be at least 1".into(),
            );
        }
        if !(o.tolerance > 0.0 && o.tolerance < 1.0) {
            return bad(
                "optimization.tolerance".into(),
                format!("must lie in (0, 1) (got {})", o.tolerance),
            );
        }
        if let Err(reason) = crate::optim::check_nonmonotone_memory(o.nonmonotone_memory) {
            return bad("optimization.nonmonotone_memory".into(), reason);
        }
        Ok(())
    }
}

/// Reads a Nastran study file (`gustkit run` on a JSON with a `model` section).
pub fn load(file: &Path, doc: &serde_json::Value) -> Result<NastranStudyFile> {
    let s = NastranStudyFile::from_value(file, doc)?;
    if !s.model_path().is_file() {
        bail!(
            "{}: model.nastran: {} is not a file",
            file.display(),
            s.model_path().display()
        );
    }
    Ok(s)
}
