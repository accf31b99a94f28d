//! Parameter sweeps: the cases of a study's `sweep` section, each the study with some numbers
//! replaced, named by their dotted path in the file (e.g. `flight.mach`).

use super::schema::SweepCombine;
use super::{Study, StudyError};
use serde_json::Value;

/// The most cases of one sweep.
pub const MAX_CASES: usize = 10_000;

/// One case of a sweep: the parameter values and the study they give.
#[derive(Clone, Debug)]
pub struct SweepCase {
    pub index: usize,
    pub values: Vec<f64>,
    /// The fidelity's label when the sweep names `fidelities` (`dlm`, `lfd`; a repeated name
    /// gets its position, `dlm 2`).
    pub fidelity: Option<String>,
    pub study: Study,
}

/// Sets the number at dotted `path` in `doc` (object keys, or array indices for arrays); the last
/// key may be absent (a defaulted field), anything else must exist.
fn set_number(doc: &mut Value, path: &str, v: f64) -> Result<(), String> {
    let keys: Vec<&str> = path.split('.').collect();
    if path.is_empty() || keys.iter().any(|k| k.is_empty()) {
        return Err(format!("'{path}' is not a dotted path"));
    }
    let mut node = doc;
    for (i, key) in keys.iter().enumerate() {
        let last = i + 1 == keys.len();
        node = match node {
            Value::Object(map) => {
                if last {
                    if let Some(old) = map.get(*key) {
                        if !old.is_number() {
                            return Err(format!("'{path}' is not a number in the study"));
                        }
                    }
                    map.insert(key.to_string(), v.into());
                    return Ok(());
                }
                map.get_mut(*key)
                    .ok_or_else(|| format!("'{path}': the study has no '{key}'"))?
            }
            Value::Array(items) => {
                let idx: usize = key
                    .parse()
                    .map_err(|_| format!("'{path}': '{key}' is not an index of an array"))?;
                let n = items.len();
                let item = items
                    .get_mut(idx)
                    .ok_or_else(|| format!("'{path}': index {idx} beyond {n} entries"))?;
                if last {
                    if !item.is_number() {
                        return Err(format!("'{path}' is not a number in the study"));
                    }
                    *item = v.into();
                    return Ok(());
                }
                item
            }
            _ => return Err(format!("'{path}': '{key}' is inside a number or string")),
        };
    }
    unreachable!("the loop returns at the last key")
}

impl Study {
    /// The cases of the study's sweep, each a validated study (without the sweep section).
    pub fn sweep_cases(&self) -> Result<Vec<SweepCase>, StudyError> {
        let sweep = self
            .spec
            .sweep
            .as_ref()
            .ok_or_else(|| self.err("sweep", "missing: the study defines no sweep"))?;
        if sweep.parameters.is_empty() {
            return Err(self.err("sweep.parameters", "at least one parameter is needed"));
        }
        for (i, p) in sweep.parameters.iter().enumerate() {
            if p.values.is_empty() || p.values.iter().any(|v| !v.is_finite()) {
                return Err(self.err(
                    &format!("sweep.parameters[{i}].values"),
                    "need at least one value, all finite",
                ));
            }
        }
        if sweep.optimize && self.spec.optimization.is_none() {
            return Err(self.err(
                "sweep.optimize",
                "the study has no optimization section to run",
            ));
        }
        let lens: Vec<usize> = sweep.parameters.iter().map(|p| p.values.len()).collect();
        let n_cases = match sweep.combine {
            SweepCombine::Zip => lens[0],
            SweepCombine::Grid => lens
                .iter()
                .try_fold(1usize, |a, &l| a.checked_mul(l))
                .unwrap_or(usize::MAX),
        };
        if n_cases > MAX_CASES {
            return Err(self.err(
                "sweep.parameters",
                format!("the sweep has {n_cases} cases, more than {MAX_CASES}: use fewer values"),
            ));
        }
        let combos: Vec<Vec<f64>> = match sweep.combine {
            SweepCombine::Zip => {
                if lens.iter().any(|&l| l != lens[0]) {
                    return Err(self.err(
                        "sweep.combine",
                        format!("\"zip\" needs equally long value lists (got {lens:?})"),
                    ));
                }
                (0..lens[0])
                    .map(|j| sweep.parameters.iter().map(|p| p.values[j]).collect())
                    .collect()
            }
            SweepCombine::Grid => {
                let total: usize = lens.iter().product();
                (0..total)
                    .map(|mut c| {
                        sweep
                            .parameters
                            .iter()
                            .map(|p| {
                                let v = p.values[c % p.values.len()];
                                c /= p.values.len();
                                v
                            })
                            .collect()
                    })
                    .collect()
            }
        };
        let mut base =
            serde_json::to_value(&self.spec).map_err(|e| self.err(".", e.to_string()))?;
        base.as_object_mut()
            .expect("a study is an object")
            .remove("sweep");
        // each combination with each fidelity of the sweep (or the study's own)
        let fidelities: Vec<Option<(String, Value)>> = if sweep.fidelities.is_empty() {
            vec![None]
        } else {
            let names: Vec<&str> = sweep
                .fidelities
                .iter()
                .map(|f| f.builder().name())
                .collect();
            sweep
                .fidelities
                .iter()
                .enumerate()
                .map(|(i, f)| {
                    let name = names[i];
                    let label = if names.iter().filter(|n| **n == name).count() > 1 {
                        format!("{name} {}", i + 1)
                    } else {
                        name.to_string()
                    };
                    let value = serde_json::to_value(f)
                        .map_err(|e| self.err(&format!("sweep.fidelities[{i}]"), e.to_string()))?;
                    Ok(Some((label, value)))
                })
                .collect::<Result<_, StudyError>>()?
        };
        let n_cases = combos.len() * fidelities.len();
        if n_cases > MAX_CASES {
            return Err(self.err(
                "sweep.fidelities",
                format!("the sweep has {n_cases} cases, more than {MAX_CASES}: use fewer values"),
            ));
        }
        let mut cases = Vec::with_capacity(n_cases);
        for (fi, fidelity) in fidelities.iter().enumerate() {
            for values in &combos {
                let index = cases.len();
                let mut doc = base.clone();
                if let Some((_, spec)) = fidelity {
                    match doc.get_mut("aero") {
                        Some(aero) => aero["fidelity"] = spec.clone(),
                        None => {
                            return Err(self.err(
                                "sweep.fidelities",
                                "the study has no aero section whose fidelity to replace",
                            ))
                        }
                    }
                }
                for (i, (p, v)) in sweep.parameters.iter().zip(values).enumerate() {
                    set_number(&mut doc, &p.path, *v)
                        .map_err(|e| self.err(&format!("sweep.parameters[{i}].path"), e))?;
                }
                let file = self.file.with_file_name(format!(
                    "{}#case{index}",
                    self.file
                        .file_name()
                        .and_then(|n| n.to_str())
                        .unwrap_or("study")
                ));
                let study = Study::from_str(&file, &doc.to_string()).map_err(|e| {
                    let mut values: Vec<String> = sweep
                        .parameters
                        .iter()
                        .zip(values)
                        .map(|(p, v)| format!("{} = {v}", p.path))
                        .collect();
                    if let Some((label, _)) = fidelity {
                        values.push(format!("sweep.fidelities[{fi}] ({label})"));
                    }
                    self.err(
                        "sweep",
                        format!(
                            "case {index} ({}): {}: {}",
                            values.join(", "),
                            e.path,
                            e.reason
                        ),
                    )
                })?;
                cases.push(SweepCase {
                    index,
                    values: values.clone(),
                    fidelity: fidelity.as_ref().map(|(label, _)| label.clone()),
                    study,
                });
            }
        }
        Ok(cases)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn set_number_paths() {
        let mut v = serde_json::json!({"a": {"b": 1.0, "c": [1.0, 2.0], "s": "x"}});
        set_number(&mut v, "a.b", 3.0).unwrap();
        set_number(&mut v, "a.c.1", 5.0).unwrap();
        set_number(&mut v, "a.new", 7.0).unwrap();
        assert_eq!(v["a"]["b"], 3.0);
        assert_eq!(v["a"]["c"][1], 5.0);
        assert_eq!(v["a"]["new"], 7.0);
        assert!(set_number(&mut v, "a.s", 1.0)
            .unwrap_err()
            .contains("not a number"));
        assert!(set_number(&mut v, "x.y", 1.0)
            .unwrap_err()
            .contains("no 'x'"));
        assert!(set_number(&mut v, "a.c.9", 1.0)
            .unwrap_err()
            .contains("beyond"));
        assert!(set_number(&mut v, "a..b", 1.0)
            .unwrap_err()
            .contains("dotted"));
    }
}
