//! A study's aerodynamic fidelity: its builder's checks, the bound model, the second fidelity of a comparison.

use super::*;

impl Study {
    /// The aerodynamic model in words (lattice, mesh or strips), as results and reports name it;
    /// `None` without an `aero` section.
    pub fn aero_model_words(&self) -> Option<String> {
        self.spec.aero.as_ref().map(|a| a.fidelity.words())
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
    pub(super) fn with_wing_context<T>(
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
            fixed_planform: false,
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
    pub(super) fn fidelity_err(&self, e: &crate::aero::BuildError) -> StudyError {
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
    pub(super) fn aero_case(&self) -> Result<Option<AeroCase>, StudyError> {
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
        self.with_fidelity(spec, "aero.compare_with").map(Some)
    }

    /// This study with `spec` in place of its own fidelity (no comparison), checked as that
    /// fidelity checks a study; errors name the JSON path `at.<fidelity>`.
    fn with_fidelity(&self, spec: &FidelitySpec, at: &str) -> Result<Study, StudyError> {
        let builder = spec.builder();
        self.with_wing_context(|wing| builder.validate(wing))?
            .map_err(|e| {
                self.err(
                    &e.path_in(&format!("{at}.{}", builder.name())),
                    e.reason.clone(),
                )
            })?;
        let mut other = self.clone();
        if let Some(aero) = other.spec.aero.as_mut() {
            aero.fidelity = spec.clone();
            aero.compare_with = None;
        }
        Ok(other)
    }

    /// The study with its `optimization.model_management.low_fidelity` in place of its own
    /// fidelity (checked by that fidelity's builder, errors at that JSON path); None without one.
    pub fn low_fidelity_study(&self) -> Result<Option<Study>, StudyError> {
        let Some(spec) = self
            .spec
            .optimization
            .as_ref()
            .and_then(|o| o.model_management.as_ref())
            .map(|m| &m.low_fidelity)
        else {
            return Ok(None);
        };
        let mut low = self.with_fidelity(spec, "optimization.model_management.low_fidelity")?;
        if let Some(o) = low.spec.optimization.as_mut() {
            o.model_management = None;
        }
        low.require_reverse_mode("the model management's corrected problems", true)?;
        Ok(Some(low))
    }
}
