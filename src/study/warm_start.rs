//! A warm start from another run's results: its final design and BFGS matrix carried to this study's variables.

use super::*;

impl Study {
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
        let x = self.final_design_in(file, &maker).map_err(|e| {
            let reason = match e.path.as_str() {
                "." => format!("{}: {}", file.display(), e.reason),
                at => format!("{}: {at}: {}", file.display(), e.reason),
            };
            self.err(path, reason)
        })?;
        let own = self.initial_design()?;
        let n = x.len();
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
}
