//! Reading a study file and the checks across its sections.

use super::*;

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

    pub(super) fn validate(&self) -> Result<(), StudyError> {
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
            self.low_fidelity_study()?;
        }
        Ok(())
    }
}
