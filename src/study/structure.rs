//! The wing a study describes, in SI: planform, section, material, mesh, design variables with their bounds, and the modal basis rule.

use super::*;

impl Study {
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
        self.spec
            .wing
            .airfoil
            .airfoil()
            .map_err(|e| self.err("wing.airfoil", e))
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
}
