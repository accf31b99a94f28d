//! Another run's final design read into this study: the warm start's starting point and the
//! design an analysis command examines with `--design` (a run's optimum analysed with another
//! fidelity, lattice or mode count).

use super::*;

impl Study {
    /// The final design (SI, design-vector order) recorded in the results.json `file`, checked
    /// against this study's design variables (same count, same names, finite values). Errors
    /// name `file` and the field; `maker` says which command writes the file.
    pub(crate) fn final_design_in(
        &self,
        file: &Path,
        maker: &dyn Fn() -> String,
    ) -> Result<Vec<f64>, StudyError> {
        let at = |path: &str, reason: String| StudyError {
            file: file.to_path_buf(),
            path: path.into(),
            reason,
        };
        let text = read_text(file).map_err(|e| {
            at(
                ".",
                format!(
                    "cannot read the file ({e}): run the optimization that writes it first ({})",
                    maker()
                ),
            )
        })?;
        let v: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| at(".", format!("not a results.json ({e})")))?;
        let names = v.get("design_variable_names").and_then(|n| n.as_array());
        let design = v
            .get("final")
            .and_then(|f| f.get("design_variables"))
            .and_then(|d| d.as_array());
        let (Some(names), Some(design)) = (names, design) else {
            return Err(at(
                ".",
                format!(
                    "holds no finished optimization (no design_variable_names and final.design_variables): {}",
                    maker()
                ),
            ));
        };
        let own = self.initial_design()?;
        let n = own.len();
        if names.len() != n || design.len() != n {
            return Err(at(
                "final.design_variables",
                format!(
                    "has {} design variables, this study {n}: the design must come from the same plate mesh and planform parametrization",
                    names.len().max(design.len()),
                ),
            ));
        }
        if let Some(i) = (0..n).find(|&i| names[i].as_str() != Some(own.name(i).as_str())) {
            return Err(at(
                &format!("design_variable_names[{i}]"),
                format!(
                    "'{}', where this study has '{}'",
                    names[i].as_str().unwrap_or("?"),
                    own.name(i)
                ),
            ));
        }
        let x: Vec<f64> = design
            .iter()
            .map(|d| d.as_f64().unwrap_or(f64::NAN))
            .collect();
        if let Some(i) = (0..n).find(|&i| !x[i].is_finite()) {
            return Err(at(
                &format!("final.design_variables[{i}]"),
                format!("{} is not a finite number", own.name(i)),
            ));
        }
        Ok(x)
    }

    /// This study with its wing replaced by the final design of the run whose results.json is
    /// `file` (thicknesses and planform, written back in the study's length unit and degrees),
    /// named `<study>_at_<run folder>` so that its reports never overwrite the study's own.
    /// The warm start is dropped: the design is given, not started from.
    pub fn at_final_design(&self, file: &Path) -> Result<Study, StudyError> {
        let maker = || {
            "`gustkit run` of an optimization study writes reports/<name>/results.json".to_string()
        };
        let x = self.final_design_in(file, &maker)?;
        let design = DesignVector::from_slice(&x);
        let to_m = self.spec.length_unit.to_m();
        let mut out = self.clone();
        let s = &mut out.spec;
        s.structure.thickness = Some(design.thickness.iter().map(|t| t / to_m).collect());
        s.structure.thickness_scale = 1.0;
        let p = design.planform;
        s.wing.span = p.span / to_m;
        s.wing.sweep_c4_deg = p.sweep_c4.to_degrees();
        s.wing.root_chord = p.root_chord / to_m;
        s.wing.tip_chord = p.tip_chord / to_m;
        if let Some(o) = s.optimization.as_mut() {
            o.warm_start = None;
        }
        let run = file
            .parent()
            .and_then(|d| d.file_name())
            .map(|n| n.to_string_lossy().to_string())
            .filter(|n| !n.is_empty())
            .unwrap_or_else(|| "design".into());
        let run: String = run
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.' {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        s.name = format!("{}_at_{}", self.spec.name, run.trim_start_matches('.'));
        // the design's own checks (positive thicknesses, a proper planform) on the new wing
        let check = |e: StudyError| StudyError {
            file: file.to_path_buf(),
            path: "final.design_variables".into(),
            reason: format!(
                "not a design this study can build: {}: {}",
                e.path, e.reason
            ),
        };
        out.planform().map_err(check)?;
        if let Some(i) = design.thickness.iter().position(|t| !(*t > 0.0)) {
            return Err(check(self.err(
                &format!("structure.thickness[{i}]"),
                format!(
                    "{} {} is not a positive thickness",
                    design.thickness[i] / to_m,
                    self.spec.length_unit.name()
                ),
            )));
        }
        Ok(out)
    }
}
