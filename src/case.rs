//! The resolved case: what a study asks for, in SI, validated, with every default applied, built
//! once from the study file ([`crate::study::Study::resolve`]). The pipeline and the design
//! problem evaluate designs of a case and never read the study's JSON; a new structure source (a
//! Nastran model) or fidelity enters here, not in the pipeline.

use crate::aero::{AeroModel, FidelitySpec};
use crate::gust::GustSettings;
use crate::structure::model::ModelError;
use crate::structure::{Field, Modes, Orthotropic, PlateMesh, PlateModel};
use crate::units::LengthUnit;
use crate::wing::{Airfoil, DesignVector};
use gustkit_core::FlightCondition;
use std::path::PathBuf;

/// A study input error: which file, which field (its JSON path), why.
#[derive(Debug, thiserror::Error)]
#[error("{file}: {path}: {reason}")]
pub struct StudyError {
    pub file: PathBuf,
    /// JSON path of the offending field (`.` for the whole document).
    pub path: String,
    pub reason: String,
}

/// How the modes of a design are chosen (SI): a fixed count, or every mode with ω ≤ `omega_cut`,
/// at least `min` and at most `max`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ModeRule {
    Count(usize),
    Cutoff {
        omega_cut: f64,
        min: usize,
        max: usize,
    },
}

/// Where the structure comes from: the parametric plate wing (its mesh, material and airfoil;
/// the design vector gives thicknesses and planform).
#[derive(Clone, Debug)]
pub struct PlateSource {
    pub mesh: PlateMesh,
    pub material: Orthotropic,
    pub airfoil: Airfoil,
}

/// How the modal basis of a design is chosen and damped.
#[derive(Clone, Debug)]
pub struct ModeSelection {
    pub rule: ModeRule,
    /// Modal structural damping ratio ζ of every mode.
    pub damping_ratio: f64,
    /// The plate fields whose modes are retained.
    pub fields: Vec<Field>,
}

impl ModeSelection {
    /// The modes of a plate by the rule.
    pub fn solve(&self, plate: &PlateModel) -> anyhow::Result<Modes> {
        Ok(match self.rule {
            ModeRule::Count(n) => self.solve_count(plate, n)?,
            ModeRule::Cutoff {
                omega_cut,
                min,
                max,
            } => crate::structure::modal::solve_below(
                plate,
                omega_cut,
                min,
                max,
                self.damping_ratio,
                &self.fields,
            )?,
        })
    }

    /// The first `n` modes of a plate, whatever the rule.
    pub fn solve_count(&self, plate: &PlateModel, n: usize) -> anyhow::Result<Modes> {
        Ok(crate::structure::modal::solve(
            plate,
            n,
            self.damping_ratio,
            &self.fields,
        )?)
    }

    /// Degrees of freedom of a plate in the retained fields: the most modes it has.
    pub fn retained_dofs(&self, plate: &PlateModel) -> usize {
        self.fields.iter().map(|f| plate.n_dofs(*f)).sum()
    }

    /// The most modes the rule can retain (the count, or the ceiling): what memory estimates
    /// are made for.
    pub fn max_modes(&self) -> usize {
        match self.rule {
            ModeRule::Count(n) => n,
            ModeRule::Cutoff { min, max, .. } => max.max(min),
        }
    }
}

/// The aerodynamic model of a case: which fidelity, at which flight condition and reduced
/// frequencies of the GAF table.
#[derive(Clone, Debug)]
pub struct AeroCase {
    pub fidelity: FidelitySpec,
    pub flight: FlightCondition,
    pub reduced_frequencies: Vec<f64>,
}

/// The peak constraint of an optimization, resolved: the gust output it bounds, the order of
/// the time derivative (2 for `<name>_acceleration`), its limit in SI and the gusts it spans
/// (the tuned search's grid of gradients, or the table).
#[derive(Clone, Debug, PartialEq)]
pub struct PeakConstraint {
    pub name: String,
    pub output: usize,
    pub derivative: u32,
    pub limit: f64,
    pub unit: String,
    pub gusts: Vec<crate::gust::discrete::GustProfile>,
}

impl PeakConstraint {
    /// The time-derivative order of each of `n_outputs` outputs: this constraint's on its
    /// output, 0 on the others.
    pub fn derivatives(&self, n_outputs: usize) -> Vec<u32> {
        let mut d = vec![0; n_outputs];
        d[self.output] = self.derivative;
        d
    }
}

/// A study resolved: everything the pipeline needs to evaluate a design.
#[derive(Clone, Debug)]
pub struct Case {
    /// The study file, named by input errors.
    pub file: PathBuf,
    /// The study's length unit (for messages; everything here is SI).
    pub length_unit: LengthUnit,
    pub structure: PlateSource,
    pub modes: ModeSelection,
    /// The initial design (SI).
    pub initial: DesignVector,
    /// None for a study without aerodynamics (modes only).
    pub aero: Option<AeroCase>,
    /// None for a study without a gust section.
    pub gust: Option<GustSettings>,
    /// Where a fidelity may keep and reuse expensive state between runs (the run folder).
    pub cache_dir: Option<PathBuf>,
}

impl Case {
    fn err(&self, path: &str, reason: impl Into<String>) -> StudyError {
        StudyError {
            file: self.file.clone(),
            path: path.into(),
            reason: reason.into(),
        }
    }

    /// The gust settings, or an error naming the missing section.
    pub fn gust_settings(&self) -> Result<&GustSettings, StudyError> {
        self.gust.as_ref().ok_or_else(|| {
            self.err(
                "gust",
                "the study has no gust section (add one for a gust response)",
            )
        })
    }

    /// The plate model of a design.
    pub fn model_at(&self, design: DesignVector) -> Result<PlateModel, StudyError> {
        plate_model(&self.file, self.length_unit, &self.structure, design)
    }

    /// The modes of a plate of this case by its rule.
    pub fn solve_modes(&self, plate: &PlateModel) -> anyhow::Result<Modes> {
        self.modes.solve(plate)
    }

    /// The aerodynamic model on a plate (its current planform), bound to it.
    pub fn aero_model(&self, plate: &PlateModel) -> Result<AeroModel, StudyError> {
        aero_model(
            &self.file,
            self.aero.as_ref(),
            plate,
            &self.structure.airfoil,
            self.cache_dir.as_deref(),
        )
    }
}

/// The aerodynamic model of `aero` on a plate, bound to it; an error names the study field
/// (`aero` when there is none).
pub fn aero_model(
    file: &std::path::Path,
    aero: Option<&AeroCase>,
    plate: &PlateModel,
    airfoil: &Airfoil,
    cache_dir: Option<&std::path::Path>,
) -> Result<AeroModel, StudyError> {
    let err = |path: &str, reason: String| StudyError {
        file: file.to_path_buf(),
        path: path.into(),
        reason,
    };
    let aero = aero.ok_or_else(|| {
        err(
            "aero",
            "the study has no aerodynamic model (add an \"aero\" section)".into(),
        )
    })?;
    AeroModel::new(
        &aero.fidelity,
        aero.flight,
        aero.reduced_frequencies.clone(),
        plate,
        airfoil,
        cache_dir,
    )
    .map_err(|e| {
        err(
            &e.path_in(&format!("aero.fidelity.{}", aero.fidelity.builder().name())),
            e.reason.clone(),
        )
    })
}

/// The plate model of a design from a plate source; an error names the study field (a
/// thickness in the study's length unit).
pub fn plate_model(
    file: &std::path::Path,
    unit: LengthUnit,
    source: &PlateSource,
    design: DesignVector,
) -> Result<PlateModel, StudyError> {
    PlateModel::new(source.mesh.clone(), source.material, design).map_err(|e| {
        let path = match &e {
            ModelError::Thickness { index, .. } => format!("structure.thickness[{index}]"),
            ModelError::ThicknessCount { .. } => "structure.thickness".into(),
            ModelError::Material(_) => "material".into(),
            _ => "wing".into(),
        };
        let reason = match &e {
            ModelError::Thickness { value, .. } => format!(
                "must be positive and finite (got {} {})",
                crate::units::show(value / unit.to_m()),
                unit.name()
            ),
            _ => without_field(&e.to_string()),
        };
        StudyError {
            file: file.to_path_buf(),
            path,
            reason,
        }
    })
}

/// An error message without its leading field name (`clamp: …` → `…`), where the JSON path
/// already names the field.
pub fn without_field(msg: &str) -> String {
    match msg.split_once(": ") {
        Some((head, rest)) if !head.contains(' ') => rest.to_string(),
        _ => msg.to_string(),
    }
}
