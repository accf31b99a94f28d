//! Checkpoints and `--resume`: the checkpoint written atomically after every iteration, tied to
//! the part of the study that defines the problem (a changed study is named field by field).

use super::*;

/// Keeps every iteration's checkpoint in `checkpoint.json` of the run folder, written
/// atomically (a kill never leaves half a checkpoint).
pub(crate) struct FileCheckpoint {
    pub(crate) path: std::path::PathBuf,
}

impl Checkpointing for FileCheckpoint {
    fn save(&mut self, cp: &crate::optim::Checkpoint) -> Result<(), String> {
        save_checkpoint(&self.path, cp)
    }
}

/// Writes a checkpoint atomically, with the LFD's GMRES warm-start store beside it, so that
/// `--resume` in another process starts from the last designs' solutions (a failed store write
/// costs only iterations, so it warns).
pub(crate) fn save_checkpoint(path: &Path, cp: &impl serde::Serialize) -> Result<(), String> {
    serde_json::to_vec(cp)
        .map_err(anyhow::Error::from)
        .and_then(|b| write_atomic(path, &b))
        .map_err(|e| format!("{e:#}"))?;
    if let Some(dir) = path.parent() {
        if let Err(e) = crate::aero::lfd::save_warm_start(dir) {
            eprintln!(
                "warning: cannot write {} ({e}): a resumed run starts its GMRES from zero",
                dir.join(crate::aero::lfd::WARM_START_FILE).display()
            );
        }
    }
    Ok(())
}

/// FNV-1a hash of a string, to tie a checkpoint to the study that wrote it.
pub(crate) fn fnv(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The FNV-1a hash of a value's JSON text as 16 hex digits: what ties a checkpoint, a sweep's
/// case file or a mesh study's rows to the study that wrote them (stable across Rust releases).
pub(crate) fn spec_hash<T: serde::Serialize + ?Sized>(value: &T) -> Result<String> {
    Ok(format!("{:016x}", fnv(&serde_json::to_string(value)?)))
}

/// The part of a study that defines its optimization problem: everything but what only labels
/// the run (description, reference), decides when it stops or what the line search accepts from
/// here on (max_iterations, tolerance, nonmonotone_memory), belongs
/// to other analyses (the flutter sweep, the sweep section) or only starts the LFD's GMRES
/// (`warm_start_designs`). A checkpoint resumes only when this
/// is unchanged.
pub(super) fn defining_spec(study: &Study) -> Result<serde_json::Value> {
    let mut v = serde_json::to_value(&study.spec)?;
    if let Some(m) = v.as_object_mut() {
        for key in ["description", "flutter", "sweep"] {
            m.remove(key);
        }
        // the second fidelity only analyses the designs the optimization reaches; the LFD's
        // warm start chooses where its GMRES starts, not what it converges to, and its batch
        // how many right-hand sides share a pass (the answers are those of one at a time, bit
        // for bit)
        if let Some(a) = m.get_mut("aero").and_then(|a| a.as_object_mut()) {
            a.remove("compare_with");
            if let Some(l) = a
                .get_mut("fidelity")
                .and_then(|f| f.get_mut("lfd"))
                .and_then(|l| l.as_object_mut())
            {
                l.remove("warm_start_designs");
                l.remove("gmres_batch");
            }
        }
        if let Some(o) = m.get_mut("optimization").and_then(|o| o.as_object_mut()) {
            for key in [
                "max_iterations",
                "tolerance",
                "nonmonotone_memory",
                "reference",
                "resolution_corrections",
            ] {
                o.remove(key);
            }
            // the outer iteration limit decides only when a managed run stops
            if let Some(m) = o
                .get_mut("model_management")
                .and_then(|m| m.as_object_mut())
            {
                m.remove("max_iterations");
            }
        }
    }
    Ok(v)
}

/// The JSON paths at which `a` and `b` differ (below `at`).
pub(crate) fn json_differences(
    a: &serde_json::Value,
    b: &serde_json::Value,
    at: &str,
) -> Vec<String> {
    use serde_json::Value;
    let join = |k: &str| {
        if at.is_empty() {
            k.to_string()
        } else {
            format!("{at}.{k}")
        }
    };
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            let mut keys: Vec<&String> = x.keys().chain(y.keys()).collect();
            keys.sort();
            keys.dedup();
            keys.into_iter()
                .flat_map(|k| match (x.get(k), y.get(k)) {
                    (Some(p), Some(q)) => json_differences(p, q, &join(k)),
                    _ => vec![join(k)],
                })
                .collect()
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => x
            .iter()
            .zip(y)
            .enumerate()
            .flat_map(|(i, (p, q))| json_differences(p, q, &format!("{at}[{i}]")))
            .collect(),
        _ if a == b => Vec::new(),
        _ => vec![if at.is_empty() {
            ".".into()
        } else {
            at.to_string()
        }],
    }
}

/// The formulation of the constraints the code builds from a study, part of the problem's
/// identity: a checkpoint written when a constraint meant something else is not resumed
/// (2: the modal floor as a KS aggregate over a band of modes, no longer the first mode alone).
pub(crate) const FORMULATION: u32 = 2;

/// The checkpoint file of a pass in the run folder (`checkpoint.json` for the first, which warm
/// starts of later runs read).
pub fn checkpoint_file(dir: &Path, pass: usize) -> std::path::PathBuf {
    match pass {
        1 => dir.join("checkpoint.json"),
        n => dir.join(format!("checkpoint_pass{n}.json")),
    }
}

/// The problem's identity (the study's name and a hash of the part that defines the problem,
/// with the pass) and, with `resume`, the checkpoint of pass `pass` to continue from; a
/// checkpoint of another problem is refused with the fields that changed. A first pass started
/// afresh keeps the defining part beside its checkpoint, for that comparison.
pub(super) fn open_checkpoint(
    study: &Study,
    dir: &Path,
    pass: usize,
    resume: bool,
    quiet: bool,
) -> Result<(String, Option<crate::optim::Checkpoint>)> {
    let defining = defining_spec(study)?;
    let mut problem_id = format!(
        "{}:{}:f{FORMULATION}",
        study.spec.name,
        spec_hash(&defining)?
    );
    if pass > 1 {
        problem_id += &format!(":pass{}", pass);
    }
    let study_copy = dir.join("checkpoint_study.json");
    let checkpoint_path = checkpoint_file(dir, pass);
    // a correction pass that had not begun when the run stopped begins now
    let resume = resume && (pass == 1 || checkpoint_path.exists());
    let checkpoint = if resume {
        let path = checkpoint_path.clone();
        let text = std::fs::read_to_string(&path).with_context(|| {
            format!(
                "--resume: cannot read {} (no interrupted run to continue: run without --resume)",
                path.display()
            )
        })?;
        let cp: crate::optim::Checkpoint = serde_json::from_str(&text).with_context(|| {
            format!(
                "--resume: {} is not a gustkit checkpoint (corrupted?)",
                path.display()
            )
        })?;
        if cp.problem_id != problem_id {
            let changed = std::fs::read_to_string(&study_copy)
                .ok()
                .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
                .map(|old| json_differences(&old, &defining, ""))
                .filter(|d| !d.is_empty());
            let what = match changed {
                Some(d) => format!(
                    "the study changed since the checkpoint was written: {}",
                    d.iter().take(6).cloned().collect::<Vec<_>>().join(", ")
                ),
                None => "the checkpoint belongs to another problem (or to an earlier gustkit's formulation of the constraints)".to_string(),
            };
            anyhow::bail!(
                "{}: --resume: {what}; only the description, the reference, max_iterations, tolerance, nonmonotone_memory, aero.compare_with, aero.fidelity.lfd.warm_start_designs, aero.fidelity.lfd.gmres_batch, the flutter sweep and the sweep section may change between a run and its resumption. Run without --resume to start over",
                study.file.display()
            );
        }
        if !quiet {
            println!("resuming from iteration {}", cp.iteration);
        }
        Some(cp)
    } else {
        if pass == 1 {
            write_atomic(
                &study_copy,
                serde_json::to_string_pretty(&defining)?.as_bytes(),
            )?;
        }
        None
    };
    Ok((problem_id, checkpoint))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The LFD study's problem is the same whatever warm start its GMRES takes and however many
    /// right-hand sides it batches (a run resumes with another `warm_start_designs` or
    /// `gmres_batch`), and another whenever what it converges to changes (the GMRES tolerance,
    /// say).
    #[test]
    fn the_warm_start_does_not_define_the_problem() {
        let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/agard445_lfd_analysis.json");
        let text = std::fs::read_to_string(&file).unwrap();
        let with = |lfd: serde_json::Value| {
            let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
            v["aero"]["fidelity"] = serde_json::json!({ "lfd": lfd });
            let study = Study::from_str(&file, &v.to_string()).unwrap();
            defining_spec(&study).unwrap()
        };
        let plain = with(serde_json::json!({}));
        assert_eq!(plain, with(serde_json::json!({"warm_start_designs": 1})));
        assert_eq!(plain, with(serde_json::json!({"gmres_batch": 12})));
        assert_ne!(plain, with(serde_json::json!({"gmres_tolerance": 1e-9})));
    }
}
