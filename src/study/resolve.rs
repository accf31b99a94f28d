//! The resolved case of a study (built once, what the pipeline takes), its flight condition, gust settings and flutter sweep.

use super::*;

impl Study {
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

    /// Report folder of this study under `root` (normally `reports/`).
    pub fn report_dir(&self, root: &Path) -> PathBuf {
        root.join(&self.spec.name)
    }
}
