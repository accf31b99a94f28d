//! Study files: the JSON case schema, its validation, and what a study builds.
//!
//! Every field is checked at load; an error names the file, the JSON path of the field and the
//! reason. Unknown fields are rejected (so a typo never silently falls back to a default).
//! Lengths are given in `length_unit` (m, in or ft) and converted to SI here; angles in degrees;
//! material constants in SI with the unit in the field name.

pub mod discrete;
pub mod limits;
pub mod ranges;
pub(crate) mod schema;
pub mod sweep;

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
    /// Reads and validates a study file.
    pub fn load(file: &Path) -> Result<Self, StudyError> {
        let text = read_text(file).map_err(|e| StudyError {
            file: file.to_path_buf(),
            path: ".".into(),
            reason: format!("cannot read the file: {e}"),
        })?;
        Self::from_str(file, &text)
    }

    /// Parses and validates study text; `file` is used in error messages.
    pub fn from_str(file: &Path, text: &str) -> Result<Self, StudyError> {
        let de = &mut serde_json::Deserializer::from_str(text);
        let spec: StudyFile = serde_path_to_error::deserialize(de).map_err(|e| {
            let path = e.path().to_string();
            let path = if path.is_empty() { ".".into() } else { path };
            let reason = explain_json_error(&path, &e.into_inner().to_string());
            StudyError {
                file: file.to_path_buf(),
                path,
                reason,
            }
        })?;
        let mut spec = spec;
        if let Some(aero) = spec.aero.as_mut() {
            // absolute, so that a study written out again and re-read keeps the same file
            let dir = file.parent().unwrap_or(Path::new(""));
            let dir = std::path::absolute(dir).unwrap_or_else(|_| dir.to_path_buf());
            aero.fidelity.resolve_paths(&dir);
            if let Some(other) = aero.compare_with.as_mut() {
                other.resolve_paths(&dir);
            }
        }
        let study = Self {
            file: file.to_path_buf(),
            spec,
            cache_dir: None,
        };
        study.validate()?;
        Ok(study)
    }

    pub(crate) fn err(&self, path: &str, reason: impl Into<String>) -> StudyError {
        StudyError {
            file: self.file.clone(),
            path: path.into(),
            reason: reason.into(),
        }
    }

    fn validate(&self) -> Result<(), StudyError> {
        let s = &self.spec;
        check_header(&self.file, s.schema_version, &s.name)?;
        self.check_ranges()?;
        self.discrete_gust_settings()?;
        self.peak_constraint()?;
        self.planform()?;
        self.airfoil()?;
        self.material()?;
        let st = &s.structure;
        match &st.modes {
            ModesSpec::Count(0) => {
                return Err(self.err("structure.modes", "must be at least 1"));
            }
            ModesSpec::Count(_) => {}
            ModesSpec::Cutoff(c) => {
                if c.min == 0 {
                    return Err(self.err(
                        "structure.modes.min",
                        "must be at least 1: a cutoff below the first mode would retain none",
                    ));
                }
                if c.max < c.min {
                    return Err(self.err(
                        "structure.modes.max",
                        format!("must be at least min ({}) (got {})", c.min, c.max),
                    ));
                }
                if let Some(f) = c.cutoff_hz {
                    if !(f > 0.0 && f.is_finite()) {
                        return Err(self.err(
                            "structure.modes.cutoff_hz",
                            format!("must be positive (got {f})"),
                        ));
                    }
                }
                if !(c.factor > 0.0 && c.factor <= 10.0) {
                    return Err(self.err(
                        "structure.modes.factor",
                        format!("must lie in (0, 10] (got {})", c.factor),
                    ));
                }
            }
        }
        if !(0.0..1.0).contains(&st.damping_ratio) {
            return Err(self.err(
                "structure.damping_ratio",
                format!("must lie in [0, 1) (got {})", st.damping_ratio),
            ));
        }
        // sizes before anything large is built
        if let Some(g) = &self.spec.gust {
            if g.points > limits::MAX_GUST_POINTS {
                return Err(self.err(
                    "gust.points",
                    format!(
                        "at most {} frequency points (got {}): the PSD integral converges long before",
                        limits::MAX_GUST_POINTS,
                        g.points
                    ),
                ));
            }
        }
        // the plate first (the mode count below needs its degrees of freedom), then everything
        let footprints = self.memory_footprints(self.spec.optimization.is_some());
        limits::check(self, &footprints[..1], 1, "the modal analysis")?;
        let plate = self.build_model()?;
        let dofs = self.retained_dofs(&plate);
        let (path, asked) = match &st.modes {
            ModesSpec::Count(n) => ("structure.modes", *n),
            ModesSpec::Cutoff(c) => ("structure.modes.min", c.min),
        };
        if asked > dofs {
            return Err(self.err(
                path,
                format!("the plate has {dofs} degrees of freedom in the retained fields, fewer than the {asked} modes asked for"),
            ));
        }
        self.mode_rule()?;
        self.check_memory(1)?;
        if self.spec.aero.is_some() || self.spec.flight.is_some() {
            self.flight_condition()?;
            let aero = self
                .spec
                .aero
                .as_ref()
                .expect("checked by flight_condition");
            gustkit_core::check_reduced_frequencies(&aero.reduced_frequencies)
                .map_err(|e| self.err("aero.reduced_frequencies", e.to_string()))?;
            // the fidelity's own checks, cheap: no model is built to validate a file
            self.with_wing_context(|wing| aero.fidelity.builder().validate(wing))?
                .map_err(|e| self.fidelity_err(&e))?;
            if let Some(k) = self.amplitude_fields_k() {
                if !aero
                    .reduced_frequencies
                    .iter()
                    .any(|kk| (kk - k).abs() <= 1e-12 * k.abs().max(1.0))
                {
                    return Err(self.err(
                        "aero.fidelity.lfd.amplitude_fields_k",
                        format!(
                            "{k} is not one of aero.reduced_frequencies ({:?}): the fields are those of the GAF table",
                            aero.reduced_frequencies
                        ),
                    ));
                }
            }
            self.compare_study()?;
        }
        if self.spec.gust.is_some() {
            self.gust_settings()?;
        }
        if self.spec.flutter.is_some() {
            self.flutter_velocities()?;
        }
        if self.spec.optimization.is_some() {
            self.design_bounds()?;
            self.warm_start_design()?;
            self.warm_start_hessian()?;
            self.require_reverse_mode("optimization", true)?;
        }
        Ok(())
    }

    /// Refuses a study whose fidelity has no reverse mode where `what` needs gradients (those of
    /// the planform variables too when `planform`).
    pub fn require_reverse_mode(&self, what: &str, planform: bool) -> Result<(), StudyError> {
        let aero = self.spec.aero.as_ref().ok_or_else(|| {
            self.err(
                "aero",
                format!("missing: {what} needs an aerodynamic model"),
            )
        })?;
        let builder = aero.fidelity.builder();
        let caps = builder.capabilities();
        let path = format!("aero.fidelity.{}", builder.name());
        if planform {
            caps.require_planform_reverse(builder.name(), what)
        } else {
            caps.require_reverse(builder.name(), what)
        }
        .map_err(|reason| self.err(&path, reason))?;
        self.with_wing_context(|wing| builder.validate_gradients(wing))?
            .map_err(|e| self.fidelity_err(&e))
    }

    /// Calls `f` with the study's wing as the fidelity builders' checks take it (planform,
    /// airfoil, flight condition; no cache folder), or the error of the first of them that is
    /// invalid.
    fn with_wing_context<T>(
        &self,
        f: impl FnOnce(&crate::aero::WingContext) -> T,
    ) -> Result<T, StudyError> {
        let flight = self.flight_condition()?;
        let (planform, airfoil) = (self.planform()?, self.airfoil()?);
        Ok(f(&crate::aero::WingContext {
            planform: &planform,
            airfoil: &airfoil,
            flight: &flight,
            cache_dir: None,
        }))
    }

    /// The fidelity's own checks (sizes, memory, flight condition) without building it, for a
    /// study edited after loading (the resolution check's refined model).
    pub fn validate_fidelity(&self) -> Result<(), StudyError> {
        let Some(aero) = self.spec.aero.as_ref() else {
            return Ok(());
        };
        self.with_wing_context(|wing| aero.fidelity.builder().validate(wing))?
            .map_err(|e| self.fidelity_err(&e))
    }

    /// A fidelity builder's error, with the JSON path of the field in this study.
    fn fidelity_err(&self, e: &crate::aero::BuildError) -> StudyError {
        let name = self
            .spec
            .aero
            .as_ref()
            .map_or("?", |a| a.fidelity.builder().name());
        self.err(
            &e.path_in(&format!("aero.fidelity.{name}")),
            e.reason.clone(),
        )
    }

    /// The study's aerodynamic model on a plate (its current planform), bound to it.
    pub fn aero_model(&self, plate: &PlateModel) -> Result<AeroModel, StudyError> {
        crate::case::aero_model(
            &self.file,
            self.aero_case()?.as_ref(),
            plate,
            &self.airfoil()?,
            self.cache_dir.as_deref(),
        )
    }

    /// The aerodynamic model's spec, flight condition and reduced frequencies (SI); None for a
    /// study without aerodynamics.
    fn aero_case(&self) -> Result<Option<AeroCase>, StudyError> {
        Ok(match &self.spec.aero {
            Some(a) if self.spec.flight.is_some() => Some(AeroCase {
                fidelity: a.fidelity.clone(),
                flight: self.flight_condition()?,
                reduced_frequencies: a.reduced_frequencies.clone(),
            }),
            _ => None,
        })
    }

    /// The reduced frequency at which the run writes the LFD amplitude fields, if any.
    pub fn amplitude_fields_k(&self) -> Option<f64> {
        match self.spec.aero.as_ref().map(|a| &a.fidelity) {
            Some(FidelitySpec::Lfd(l)) => l.amplitude_fields_k,
            _ => None,
        }
    }

    /// This study with the fidelity of `aero.compare_with` in place of its own (the same wing,
    /// flight, gust and reduced frequencies), checked as the fidelity checks a study; None
    /// without one.
    pub fn compare_study(&self) -> Result<Option<Study>, StudyError> {
        let Some(spec) = self
            .spec
            .aero
            .as_ref()
            .and_then(|a| a.compare_with.as_ref())
        else {
            return Ok(None);
        };
        let builder = spec.builder();
        self.with_wing_context(|wing| builder.validate(wing))?
            .map_err(|e| {
                self.err(
                    &e.path_in(&format!("aero.compare_with.{}", builder.name())),
                    e.reason.clone(),
                )
            })?;
        let mut other = self.clone();
        if let Some(aero) = other.spec.aero.as_mut() {
            aero.fidelity = spec.clone();
            aero.compare_with = None;
        }
        Ok(Some(other))
    }

    /// The starting design of the optimization: the final design of the run named by
    /// `optimization.warm_start.from`, checked against this study's design variables and bounds;
    /// None without a warm start.
    pub fn warm_start_design(&self) -> Result<Option<Vec<f64>>, StudyError> {
        let Some(w) = self
            .spec
            .optimization
            .as_ref()
            .and_then(|o| o.warm_start.as_ref())
        else {
            return Ok(None);
        };
        let path = "optimization.warm_start.from";
        let file = &w.from;
        // the command that makes the file: `gustkit run` of the study named after its folder
        let maker = || {
            let name = file
                .parent()
                .and_then(|d| d.file_name())
                .map(|n| n.to_string_lossy().to_string())
                .unwrap_or_else(|| "STUDY".into());
            let study = Path::new("studies").join(format!("{name}.json"));
            if study.exists() {
                format!("gustkit run {}", study.display())
            } else {
                format!("gustkit run on the optimization study named '{name}'")
            }
        };
        let text = read_text(file).map_err(|e| {
            self.err(
                path,
                format!(
                    "cannot read {} ({e}): run the optimization that writes it first ({})",
                    file.display(),
                    maker()
                ),
            )
        })?;
        let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| {
            self.err(
                path,
                format!("{} is not a results.json ({e})", file.display()),
            )
        })?;
        let names = v.get("design_variable_names").and_then(|n| n.as_array());
        let design = v
            .get("final")
            .and_then(|f| f.get("design_variables"))
            .and_then(|d| d.as_array());
        let (Some(names), Some(design)) = (names, design) else {
            return Err(self.err(
                path,
                format!(
                    "{} holds no finished optimization (no design_variable_names and final.design_variables): {}",
                    file.display(),
                    maker()
                ),
            ));
        };
        let own = self.initial_design()?;
        let n = own.to_vec().len();
        let theirs: Vec<String> = names
            .iter()
            .map(|s| s.as_str().unwrap_or("?").to_string())
            .collect();
        if theirs.len() != n || design.len() != n {
            return Err(self.err(
                path,
                format!(
                    "{} has {} design variables, this study {n}: the warm start needs the same plate mesh and planform parametrization",
                    file.display(),
                    theirs.len()
                ),
            ));
        }
        if let Some(i) = (0..n).find(|&i| theirs[i] != own.name(i)) {
            return Err(self.err(
                path,
                format!(
                    "{}: design variable {i} is '{}', this study's is '{}'",
                    file.display(),
                    theirs[i],
                    own.name(i)
                ),
            ));
        }
        let x: Vec<f64> = design
            .iter()
            .map(|d| d.as_f64().unwrap_or(f64::NAN))
            .collect();
        let (lower, upper) = self.design_bounds()?;
        if let Some(i) = (0..n).find(|&i| !(x[i] >= lower[i] && x[i] <= upper[i])) {
            return Err(self.err(
                path,
                format!(
                    "{}: the final {} = {} lies outside this study's bounds [{}, {}] (SI)",
                    file.display(),
                    own.name(i),
                    ranges::show(x[i]),
                    ranges::show(lower[i]),
                    ranges::show(upper[i])
                ),
            ));
        }
        Ok(Some(x))
    }

    /// The BFGS approximation to start from with `optimization.warm_start.hessian`: the final
    /// one of the run that wrote `from` (its `checkpoint.json` beside it), carried from that
    /// run's variable scaling to this study's by the optimizer's own rule
    /// ([`crate::optim::Scaling::rescale_hessian`]: H'ᵢⱼ = rᵢ rⱼ Hᵢⱼ with rᵢ the ratio of the
    /// scales, the bound ranges where both are ranges). None without it.
    pub fn warm_start_hessian(&self) -> Result<Option<Vec<Vec<f64>>>, StudyError> {
        let Some(w) = self
            .spec
            .optimization
            .as_ref()
            .and_then(|o| o.warm_start.as_ref())
            .filter(|w| w.hessian)
        else {
            return Ok(None);
        };
        let path = "optimization.warm_start.hessian";
        let n = self.initial_design()?.to_vec().len();
        let file = w.from.with_file_name("checkpoint.json");
        let text = read_text(&file).map_err(|e| {
            self.err(
                path,
                format!(
                    "cannot read {} ({e}): the run that wrote {} keeps its last checkpoint beside it; run it again, or set hessian to false",
                    file.display(),
                    w.from.display()
                ),
            )
        })?;
        let cp: crate::optim::Checkpoint = serde_json::from_str(&text).map_err(|e| {
            self.err(
                path,
                format!("{} is not a gustkit checkpoint ({e})", file.display()),
            )
        })?;
        let h = cp.hessian;
        if h.len() != n || h.iter().any(|r| r.len() != n) {
            return Err(self.err(
                path,
                format!(
                    "{} holds a Hessian of {} variables, this study has {n}",
                    file.display(),
                    h.len()
                ),
            ));
        }
        // that run's bounds, from its results.json (checked by warm_start_design)
        let results: serde_json::Value = read_text(&w.from)
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok())
            .unwrap_or_default();
        let bounds = |key: &str| -> Option<Vec<f64>> {
            results[key]
                .as_array()?
                .iter()
                .map(|v| v.as_f64())
                .collect::<Option<Vec<f64>>>()
                .filter(|b| b.len() == n)
        };
        let (Some(lo), Some(hi)) = (bounds("lower"), bounds("upper")) else {
            return Err(self.err(
                path,
                format!(
                    "{} records no design bounds (lower, upper) of {n} variables",
                    w.from.display()
                ),
            ));
        };
        // the optimizer's own scaling of both runs, at the design this run starts from
        let (lower, upper) = self.design_bounds()?;
        let start = self.warm_start_design()?.unwrap_or_else(|| {
            self.initial_design()
                .map(|d| d.to_vec())
                .unwrap_or_default()
        });
        if start.len() != n {
            return Err(self.err(
                path,
                format!(
                    "{} records no final design of {n} variables",
                    w.from.display()
                ),
            ));
        }
        let (from, to) = (
            crate::optim::Scaling::new(&lo, &hi, &start),
            crate::optim::Scaling::new(&lower, &upper, &start),
        );
        Ok(Some(to.rescale_hessian(&h, &from)))
    }

    /// Bounds of the design vector from the `optimization` section (SI), checked; the initial
    /// design must lie inside them.
    pub fn design_bounds(&self) -> Result<(Vec<f64>, Vec<f64>), StudyError> {
        let o =
            self.spec.optimization.as_ref().ok_or_else(|| {
                self.err("optimization", "missing: the study has no optimization")
            })?;
        let settings = self.gust_settings()?;
        if !settings.outputs.iter().any(|out| out.name == o.output) {
            return Err(self.err(
                "optimization.output",
                format!("no gust output named '{}'", o.output),
            ));
        }
        if !(o.rms_max > 0.0) {
            return Err(self.err(
                "optimization.rms_max",
                format!("must be positive (got {})", o.rms_max),
            ));
        }
        if let Some(m) = &o.flutter_margin {
            if !(m.speed_factor > 0.0 && m.speed_factor <= 3.0) {
                return Err(self.err(
                    "optimization.flutter_margin.speed_factor",
                    format!("must lie in (0, 3] (got {})", m.speed_factor),
                ));
            }
            if !(m.damping_max.abs() < 1.0) {
                return Err(self.err(
                    "optimization.flutter_margin.damping_max",
                    format!("must lie in (-1, 1) (got {})", m.damping_max),
                ));
            }
        }
        let to_m = self.spec.length_unit.to_m();
        if !(o.thickness_min > 0.0 && o.thickness_max >= o.thickness_min) {
            return Err(self.err(
                "optimization.thickness_min",
                format!(
                    "need 0 < thickness_min <= thickness_max (got {} and {})",
                    o.thickness_min, o.thickness_max
                ),
            ));
        }
        let x0 = self.initial_design()?.to_vec();
        let n = x0.len() - 4;
        let mut lower = vec![o.thickness_min * to_m; n];
        let mut upper = vec![o.thickness_max * to_m; n];
        if let Some([lo, hi]) = o.thickness_relative {
            if !(lo > 0.0 && lo <= 1.0 && hi >= 1.0 && hi.is_finite()) {
                return Err(self.err(
                    "optimization.thickness_relative",
                    format!("need 0 < lower <= 1 <= upper (got [{lo}, {hi}])"),
                ));
            }
            for i in 0..n {
                lower[i] = lower[i].max(lo * x0[i]);
                upper[i] = upper[i].min(hi * x0[i]);
            }
        }
        for (name, b, scale) in [
            ("span", o.span, to_m),
            ("sweep_c4_deg", o.sweep_c4_deg, std::f64::consts::PI / 180.0),
            ("root_chord", o.root_chord, to_m),
            ("tip_chord", o.tip_chord, to_m),
        ] {
            if !(b[0] <= b[1]) {
                return Err(self.err(
                    &format!("optimization.{name}"),
                    format!("lower bound {} exceeds upper bound {}", b[0], b[1]),
                ));
            }
            lower.push(b[0] * scale);
            upper.push(b[1] * scale);
        }
        if let Some(i) = (0..x0.len())
            .find(|&i| x0[i] < lower[i] * (1.0 - 1e-12) || x0[i] > upper[i] * (1.0 + 1e-12))
        {
            let field = if i < n {
                if x0[i] < lower[i] {
                    "optimization.thickness_min".to_string()
                } else {
                    "optimization.thickness_max".to_string()
                }
            } else {
                format!(
                    "optimization.{}",
                    ["span", "sweep_c4_deg", "root_chord", "tip_chord"][i - n]
                )
            };
            return Err(self.err(
                &field,
                format!("the initial design (variable {i}) lies outside the bounds"),
            ));
        }
        Ok((lower, upper))
    }

    /// The velocities of the study's p-k sweep, checked.
    pub fn flutter_velocities(&self) -> Result<Vec<f64>, StudyError> {
        let f = self
            .spec
            .flutter
            .as_ref()
            .ok_or_else(|| {
                let v = self.spec.flight.as_ref().map_or(100.0, |f| f.velocity_m_s);
                self.err(
                    "flutter",
                    format!(
                        "missing: the study has no flutter sweep; add for example \"flutter\": \
                         {{\"velocity_min_m_s\": {:.0}, \"velocity_max_m_s\": {:.0}, \"points\": 60}} \
                         (speeds in m/s at the study's Mach number and density; here 0.2 to 2 × the \
                         flight speed)",
                        0.2 * v,
                        2.0 * v
                    ),
                )
            })?;
        if self.spec.aero.is_none() {
            return Err(self.err(
                "aero",
                "missing: the flutter sweep needs an aerodynamic model",
            ));
        }
        if !(f.velocity_min_m_s > 0.0
            && f.velocity_max_m_s > f.velocity_min_m_s
            && f.velocity_max_m_s.is_finite())
        {
            return Err(self.err(
                "flutter.velocity_max_m_s",
                format!(
                    "need 0 < velocity_min_m_s < velocity_max_m_s (got {} and {})",
                    f.velocity_min_m_s, f.velocity_max_m_s
                ),
            ));
        }
        if f.points < 2 || f.points > limits::MAX_FLUTTER_POINTS {
            return Err(self.err(
                "flutter.points",
                format!(
                    "need 2 to {} speeds (got {}); the flutter crossing is refined between speeds, so a few hundred suffice",
                    limits::MAX_FLUTTER_POINTS,
                    f.points
                ),
            ));
        }
        Ok((0..f.points)
            .map(|i| {
                f.velocity_min_m_s
                    + (f.velocity_max_m_s - f.velocity_min_m_s) * i as f64 / (f.points - 1) as f64
            })
            .collect())
    }

    /// The gust settings in SI, checked.
    pub fn gust_settings(&self) -> Result<GustSettings, StudyError> {
        let g = self
            .spec
            .gust
            .as_ref()
            .ok_or_else(|| self.err("gust", "missing: the study has no gust analysis"))?;
        if self.spec.aero.is_none() {
            return Err(self.err(
                "aero",
                "missing: the gust analysis needs an aerodynamic model",
            ));
        }
        g.turbulence.validate().map_err(|e| {
            let (field, reason) = e.split_once(": ").unwrap_or(("", &e));
            self.err(&format!("gust.turbulence.{field}"), reason)
        })?;
        if !(g.omega_min_rad_s > 0.0 && g.omega_min_rad_s.is_finite()) {
            return Err(self.err(
                "gust.omega_min_rad_s",
                format!("must be positive (got {})", g.omega_min_rad_s),
            ));
        }
        if g.points < 10 {
            return Err(self.err(
                "gust.points",
                format!("need at least 10 grid points (got {})", g.points),
            ));
        }
        if !(g.max_tail > 0.0 && g.max_tail <= 0.1) {
            return Err(self.err(
                "gust.max_tail",
                format!("must lie in (0, 0.1] (got {})", g.max_tail),
            ));
        }
        if g.outputs.is_empty() {
            return Err(self.err("gust.outputs", "at least one output is needed"));
        }
        let mut outputs = Vec::new();
        for (i, o) in g.outputs.iter().enumerate() {
            let quantity = match (o.quantity.unwrap_or_default(), o.point) {
                (QuantityName::VerticalDisplacement, Some(point)) => {
                    if !point.iter().all(|v| (0.0..=1.0).contains(v)) {
                        return Err(self.err(
                            &format!("gust.outputs[{i}].point"),
                            format!("(ξ, η) must lie in [0, 1]² (got {point:?})"),
                        ));
                    }
                    Quantity::Displacement { point }
                }
                (QuantityName::VerticalDisplacement, None) => {
                    return Err(self.err(
                        &format!("gust.outputs[{i}].point"),
                        "missing: a displacement output needs a point [ξ, η]",
                    ))
                }
                (QuantityName::RootBendingMoment, None) => Quantity::RootBendingMoment,
                (QuantityName::RootBendingMoment, Some(_)) => {
                    return Err(self.err(
                        &format!("gust.outputs[{i}].point"),
                        "a root bending moment takes no point",
                    ))
                }
            };
            outputs.push(Output {
                name: o.name.clone(),
                quantity,
            });
            if g.outputs[..i].iter().any(|p| p.name == o.name) {
                return Err(self.err(
                    &format!("gust.outputs[{i}].name"),
                    format!("duplicate output name '{}'", o.name),
                ));
            }
        }
        Ok(GustSettings {
            turbulence: g.turbulence,
            omega_min: g.omega_min_rad_s,
            points: g.points,
            max_tail: g.max_tail,
            mode_acceleration: g.mode_acceleration,
            outputs,
        })
    }

    /// The flight condition with the GAF reference values (SI); needs `flight` and `aero`.
    pub fn flight_condition(&self) -> Result<gustkit_core::FlightCondition, StudyError> {
        let f = self.spec.flight.as_ref().ok_or_else(|| {
            self.err(
                "flight",
                "missing: the aerodynamic model needs a flight condition",
            )
        })?;
        let aero = self.spec.aero.as_ref().ok_or_else(|| {
            self.err(
                "aero",
                "missing: a flight condition needs an aerodynamic model",
            )
        })?;
        let to_m = self.spec.length_unit.to_m();
        if !(f.mach >= 0.0 && f.mach < 1.0) {
            return Err(self.err(
                "flight.mach",
                format!(
                    "must lie in [0, 1): the aerodynamic models are subsonic (got {})",
                    f.mach
                ),
            ));
        }
        for (path, v) in [
            ("flight.velocity_m_s", f.velocity_m_s),
            ("flight.density_kg_m3", f.density_kg_m3),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(self.err(path, format!("must be positive (got {v})")));
            }
        }
        let b_ref = match aero.reference_semichord {
            Some(b) if b > 0.0 && b.is_finite() => b * to_m,
            Some(b) => {
                return Err(self.err(
                    "aero.reference_semichord",
                    format!("must be positive (got {b})"),
                ))
            }
            None => 0.5 * self.planform()?.root_chord,
        };
        if !aero.gust_x_ref.is_finite() {
            return Err(self.err("aero.gust_x_ref", "must be finite"));
        }
        Ok(gustkit_core::FlightCondition {
            mach: f.mach,
            velocity: f.velocity_m_s,
            density: f.density_kg_m3,
            b_ref,
            x_ref: aero.gust_x_ref * to_m,
        })
    }

    /// The planform in SI.
    pub fn planform(&self) -> Result<Planform, StudyError> {
        let w = &self.spec.wing;
        let to_m = self.spec.length_unit.to_m();
        let p = Planform {
            span: w.span * to_m,
            sweep_c4: w.sweep_c4_deg.to_radians(),
            root_chord: w.root_chord * to_m,
            tip_chord: w.tip_chord * to_m,
        };
        p.validate().map_err(|e| {
            let path = match &e {
                crate::wing::PlanformError::NotPositive { field, .. } => format!("wing.{field}"),
                crate::wing::PlanformError::Sweep { .. } => "wing.sweep_c4_deg".into(),
            };
            self.err(
                &path,
                e.to_string()
                    .split_once(": ")
                    .map_or(e.to_string(), |x| x.1.to_string()),
            )
        })?;
        Ok(p)
    }

    /// The airfoil thickness table.
    pub fn airfoil(&self) -> Result<Airfoil, StudyError> {
        match &self.spec.wing.airfoil {
            AirfoilSpec::Builtin(name) => match name.to_ascii_lowercase().as_str() {
                "naca65a004" | "naca 65a004" => Ok(Airfoil::naca65a004()),
                other => Err(self.err(
                    "wing.airfoil",
                    format!("unknown built-in airfoil '{other}' (built in: naca65a004; or give {{\"name\", \"x_c\", \"z_c\"}})"),
                )),
            },
            AirfoilSpec::Table { name, x_c, z_c } => Airfoil::from_table(name, x_c.clone(), z_c.clone())
                .map_err(|e| self.err("wing.airfoil", e.to_string())),
        }
    }

    /// The material in SI.
    pub fn material(&self) -> Result<Orthotropic, StudyError> {
        let m = &self.spec.material;
        let mat = Orthotropic {
            e1: m.e1_pa,
            e2: m.e2_pa,
            g12: m.g12_pa,
            nu12: m.nu12,
            density: m.density_kg_m3,
            grain_angle: m.grain_angle_deg.to_radians(),
        };
        mat.validate().map_err(|e| {
            let path = match &e {
                crate::structure::MaterialError::NotPositive { field, .. } => match *field {
                    "density" => "material.density_kg_m3".to_string(),
                    f => format!("material.{f}_pa"),
                },
                crate::structure::MaterialError::NotPositiveDefinite { .. } => {
                    "material.nu12".into()
                }
            };
            self.err(&path, e.to_string())
        })?;
        Ok(mat)
    }

    /// The structural mesh.
    pub fn mesh(&self) -> Result<PlateMesh, StudyError> {
        let st = &self.spec.structure;
        let clamp = match &st.clamp {
            ClampSpec::Named(n) if n == "all" => Clamp::All,
            ClampSpec::Named(n) if n == "interior" => Clamp::Interior,
            ClampSpec::Named(n) => {
                return Err(self.err(
                    "structure.clamp",
                    format!(
                    "unknown clamp '{n}' (use \"all\", \"interior\" or {{\"root_nodes\": [...]}})"
                ),
                ))
            }
            ClampSpec::RootNodes { root_nodes } => Clamp::Nodes(root_nodes.clone()),
        };
        PlateMesh::new(st.mesh.chordwise, st.mesh.spanwise, st.mesh.refine, &clamp).map_err(|e| {
            let path = match e {
                crate::structure::mesh::MeshError::Empty => "structure.mesh",
                _ => "structure.clamp",
            };
            self.err(path, without_field(&e.to_string()))
        })
    }

    /// The initial design vector in SI: thicknesses from the airfoil (or the file), planform.
    pub fn initial_design(&self) -> Result<DesignVector, StudyError> {
        let mesh = self.mesh()?;
        let planform = self.planform()?;
        let thickness = match &self.spec.structure.thickness {
            Some(t) => {
                if t.len() != mesh.n_dv() {
                    return Err(self.err(
                        "structure.thickness",
                        format!(
                            "expected {} values (one a design patch), got {}",
                            mesh.n_dv(),
                            t.len()
                        ),
                    ));
                }
                let to_m = self.spec.length_unit.to_m();
                t.iter().map(|v| v * to_m).collect()
            }
            None => airfoil_thickness(&mesh, &planform, &self.airfoil()?),
        };
        let scale = self.spec.structure.thickness_scale;
        if !(scale > 0.0 && scale.is_finite()) {
            return Err(self.err(
                "structure.thickness_scale",
                format!("must be positive (got {scale})"),
            ));
        }
        let thickness = thickness.into_iter().map(|t| t * scale).collect();
        Ok(DesignVector {
            thickness,
            planform,
        })
    }

    /// The plate model of the initial design.
    pub fn build_model(&self) -> Result<PlateModel, StudyError> {
        self.model_at(self.initial_design()?)
    }

    /// The plate model of a given design.
    pub fn model_at(&self, design: DesignVector) -> Result<PlateModel, StudyError> {
        crate::case::plate_model(
            &self.file,
            self.spec.length_unit,
            &self.plate_source()?,
            design,
        )
    }

    /// The parametric plate wing's mesh, material and airfoil.
    pub fn plate_source(&self) -> Result<PlateSource, StudyError> {
        Ok(PlateSource {
            mesh: self.mesh()?,
            material: self.material()?,
            airfoil: self.airfoil()?,
        })
    }

    /// How the study chooses and damps the modes of a design.
    pub fn mode_selection(&self) -> Result<ModeSelection, StudyError> {
        Ok(ModeSelection {
            rule: self.mode_rule()?,
            damping_ratio: self.spec.structure.damping_ratio,
            fields: self.mode_fields(),
        })
    }

    /// The study resolved (SI, every default applied) for the pipeline: see [`Case`]. The study
    /// is validated at load, so this fails only for a study edited since.
    pub fn resolve(&self) -> Result<Case, StudyError> {
        let aero = self.aero_case()?;
        let gust = match &self.spec.gust {
            Some(_) => Some(self.gust_settings()?),
            None => None,
        };
        Ok(Case {
            file: self.file.clone(),
            length_unit: self.spec.length_unit,
            structure: self.plate_source()?,
            modes: self.mode_selection()?,
            initial: self.initial_design()?,
            aero,
            gust,
            cache_dir: self.cache_dir.clone(),
        })
    }

    /// Degrees of freedom of the plate in the retained fields: the most modes it has.
    pub fn retained_dofs(&self, plate: &PlateModel) -> usize {
        self.mode_fields().iter().map(|f| plate.n_dofs(*f)).sum()
    }

    /// The modal basis rule in SI (see [`ModeRule`]).
    pub fn mode_rule(&self) -> Result<ModeRule, StudyError> {
        let c = match &self.spec.structure.modes {
            ModesSpec::Count(n) => return Ok(ModeRule::Count(*n)),
            ModesSpec::Cutoff(c) => c,
        };
        let omega_cut = match c.cutoff_hz {
            Some(f) => 2.0 * std::f64::consts::PI * f,
            None => {
                if self.spec.aero.is_none() || self.spec.flight.is_none() {
                    return Err(self.err(
                        "structure.modes",
                        "the cutoff rule needs the GAF table's reduced frequencies and the flight condition (aero and flight): give structure.modes.cutoff_hz or a mode count",
                    ));
                }
                let f = self.flight_condition()?;
                let k_max = self
                    .spec
                    .aero
                    .as_ref()
                    .and_then(|a| a.reduced_frequencies.last().copied())
                    .unwrap_or(0.0);
                c.factor * k_max * self.top_speed()? / f.b_ref
            }
        };
        Ok(ModeRule::Cutoff {
            omega_cut,
            min: c.min,
            max: c.max,
        })
    }

    /// The highest speed any analysis of the study examines, m/s: the flight speed, the flutter
    /// margin's speed and the flutter sweep's last speed.
    pub fn top_speed(&self) -> Result<f64, StudyError> {
        let v = self.flight_condition()?.velocity;
        let margin = self
            .spec
            .optimization
            .as_ref()
            .and_then(|o| o.flutter_margin.as_ref())
            .map_or(v, |m| m.speed_factor * v);
        let sweep = self.spec.flutter.as_ref().map_or(v, |f| f.velocity_max_m_s);
        Ok(v.max(margin).max(sweep))
    }

    /// The most modes the study can retain (the count, or the rule's ceiling): what memory
    /// estimates are made for.
    pub fn max_modes(&self) -> usize {
        match &self.spec.structure.modes {
            ModesSpec::Count(n) => *n,
            ModesSpec::Cutoff(c) => c.max.max(c.min),
        }
    }

    /// The modal analysis of a plate of the study by its [`ModeRule`].
    pub fn solve_modes(&self, plate: &PlateModel) -> anyhow::Result<crate::structure::Modes> {
        self.mode_selection()?.solve(plate)
    }

    /// Plate fields whose modes are retained.
    pub fn mode_fields(&self) -> Vec<crate::structure::Field> {
        use crate::structure::Field;
        if self.spec.structure.in_plane_modes {
            vec![Field::Bending, Field::Membrane]
        } else {
            vec![Field::Bending]
        }
    }

    /// Report folder of this study under `root` (normally `reports/`).
    pub fn report_dir(&self, root: &Path) -> PathBuf {
        root.join(&self.spec.name)
    }
}

#[cfg(test)]
mod tests;
