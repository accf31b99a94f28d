//! The run folder of `gustkit run`, written whole or not at all: a run works in a staging folder
//! beside it (`reports/.<name>.partial/`) and only a run that wrote all its results replaces the
//! previous folder, by renames. A failed run leaves the previous results intact and no partial
//! folder, except the staging folder of an optimization that has a checkpoint, which
//! `gustkit run --resume` continues.

use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

/// Entries of a previous run folder that other commands wrote there and a new run keeps
/// (`gustkit sweep` writes its cases and table into `sweep/`).
const KEPT_FROM_OTHER_COMMANDS: &[&str] = &["sweep"];

/// Files of a previous run that a new one may reuse, by name prefix (the LFD's steady states,
/// `steady_lfd_<hash>.bin`: the reader checks that a state fits and is converged).
const REUSABLE_PREFIXES: &[&str] = &[crate::aero::lfd::STEADY_PREFIX];

/// The first pass's checkpoint: a staging folder with one is a run that `--resume` continues.
const CHECKPOINT: &str = "checkpoint.json";

/// Files that make a staging folder worth keeping after a failure: an optimization's checkpoints
/// (`checkpoint.json`, `checkpoint_pass2.json`, … of the resolution corrections) and the study
/// they belong to (`checkpoint_study.json`).
fn is_checkpoint(name: &str) -> bool {
    name.starts_with("checkpoint") && name.ends_with(".json")
}

/// The checkpoint files in `dir` with their contents (the study copy left out: it does not change
/// while a run goes on).
fn checkpoints(dir: &Path) -> Vec<(std::ffi::OsString, Vec<u8>)> {
    let mut found: Vec<_> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .filter(|e| {
            let n = e.file_name();
            let n = n.to_string_lossy();
            is_checkpoint(&n) && n != "checkpoint_study.json"
        })
        .filter_map(|e| Some((e.file_name(), std::fs::read(e.path()).ok()?)))
        .collect();
    found.sort();
    found
}

/// A run folder being written.
pub struct RunFolder {
    final_dir: PathBuf,
    stage: PathBuf,
    committed: bool,
}

impl RunFolder {
    /// Starts a run whose results go to `final_dir`. Without `resume` any staging folder of an
    /// earlier, interrupted run is cleared; with it, that folder's checkpoint is kept (or, after a
    /// completed run, the checkpoint of `final_dir` is copied in to continue from).
    pub fn begin(final_dir: &Path, resume: bool) -> Result<Self> {
        let name = final_dir
            .file_name()
            .and_then(|n| n.to_str())
            .context("the run folder needs a name")?;
        let parent = final_dir.parent().unwrap_or(Path::new("."));
        let stage = parent.join(format!(".{name}.partial"));
        if stage.exists() && !resume {
            std::fs::remove_dir_all(&stage)
                .with_context(|| format!("cannot clear the staging folder {}", stage.display()))?;
        }
        std::fs::create_dir_all(&stage)
            .with_context(|| format!("cannot create the run folder {}", stage.display()))?;
        // state a run may reuse (the LFD's steady solution) comes along from the previous run
        if let Ok(entries) = std::fs::read_dir(final_dir) {
            for entry in entries.flatten() {
                let name = entry.file_name();
                let reusable = REUSABLE_PREFIXES
                    .iter()
                    .any(|p| name.to_string_lossy().starts_with(p));
                if reusable && !stage.join(&name).exists() {
                    let _ = std::fs::copy(entry.path(), stage.join(&name));
                }
            }
        }
        if resume && !stage.join(CHECKPOINT).exists() {
            for entry in std::fs::read_dir(final_dir).into_iter().flatten().flatten() {
                if is_checkpoint(&entry.file_name().to_string_lossy()) {
                    let from = entry.path();
                    std::fs::copy(&from, stage.join(entry.file_name()))
                        .with_context(|| format!("cannot copy {}", from.display()))?;
                }
            }
        }
        Ok(Self {
            final_dir: final_dir.to_path_buf(),
            stage,
            committed: false,
        })
    }

    /// The folder the run writes into.
    pub fn path(&self) -> &Path {
        &self.stage
    }

    /// Puts the finished run in place of the previous one (keeping what other commands wrote
    /// there, see [`KEPT_FROM_OTHER_COMMANDS`]).
    pub fn commit(mut self) -> Result<()> {
        let old = self.final_dir.with_file_name(format!(
            ".{}.old{}",
            self.final_dir
                .file_name()
                .and_then(|n| n.to_str())
                .unwrap_or("run"),
            std::process::id()
        ));
        if self.final_dir.exists() {
            for keep in KEPT_FROM_OTHER_COMMANDS {
                let (from, to) = (self.final_dir.join(keep), self.stage.join(keep));
                if from.exists() && !to.exists() {
                    std::fs::rename(&from, &to)
                        .with_context(|| format!("cannot keep {}", from.display()))?;
                }
            }
            std::fs::rename(&self.final_dir, &old).with_context(|| {
                format!(
                    "cannot move the previous run {} aside",
                    self.final_dir.display()
                )
            })?;
        }
        std::fs::rename(&self.stage, &self.final_dir).with_context(|| {
            format!(
                "cannot move the finished run into {}",
                self.final_dir.display()
            )
        })?;
        self.committed = true;
        if old.exists() {
            let _ = std::fs::remove_dir_all(&old);
        }
        Ok(())
    }
}

impl Drop for RunFolder {
    /// A run that did not commit removes its staging folder, unless it holds a checkpoint that
    /// the finished run folder does not already have.
    fn drop(&mut self) {
        if self.committed {
            return;
        }
        let staged = checkpoints(&self.stage);
        // a checkpoint worth keeping: one this run wrote, not the finished run's copy
        if !staged.is_empty() && staged != checkpoints(&self.final_dir) {
            eprintln!(
                "the checkpoint of this run is kept in {}: `gustkit run --resume` continues it",
                self.stage.display()
            );
        } else {
            let _ = std::fs::remove_dir_all(&self.stage);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("gustkit-folder-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// A failed run leaves the previous folder as it was and no staging folder; a finished one
    /// replaces it and keeps the sweep folder.
    #[test]
    fn failed_runs_leave_the_previous_folder_intact() {
        let root = scratch("fail");
        let dir = root.join("study");
        std::fs::create_dir_all(dir.join("sweep")).unwrap();
        std::fs::write(dir.join("results.json"), "old").unwrap();
        std::fs::write(dir.join("sweep/table.csv"), "sweep").unwrap();
        {
            let f = RunFolder::begin(&dir, false).unwrap();
            std::fs::write(f.path().join("modes.vtk"), "half").unwrap();
            // dropped without commit: the run failed
        }
        assert_eq!(
            std::fs::read_to_string(dir.join("results.json")).unwrap(),
            "old"
        );
        assert!(!dir.join("modes.vtk").exists());
        assert!(!root.join(".study.partial").exists());
        let f = RunFolder::begin(&dir, false).unwrap();
        std::fs::write(f.path().join("results.json"), "new").unwrap();
        f.commit().unwrap();
        assert_eq!(
            std::fs::read_to_string(dir.join("results.json")).unwrap(),
            "new"
        );
        assert_eq!(
            std::fs::read_to_string(dir.join("sweep/table.csv")).unwrap(),
            "sweep"
        );
        let left: Vec<_> = std::fs::read_dir(&root).unwrap().collect();
        assert_eq!(left.len(), 1, "only the run folder remains: {left:?}");
        std::fs::remove_dir_all(&root).unwrap();
    }

    /// The staging folder of a failed optimization keeps its checkpoint for `--resume`, and a
    /// resumed run after a completed one starts from the completed run's checkpoint.
    #[test]
    fn checkpoints_survive_for_resume() {
        let root = scratch("resume");
        let dir = root.join("study");
        {
            let f = RunFolder::begin(&dir, false).unwrap();
            std::fs::write(f.path().join("checkpoint.json"), "cp").unwrap();
        }
        let stage = root.join(".study.partial");
        assert!(stage.join("checkpoint.json").exists());
        let f = RunFolder::begin(&dir, true).unwrap();
        assert_eq!(
            std::fs::read_to_string(f.path().join("checkpoint.json")).unwrap(),
            "cp"
        );
        f.commit().unwrap();
        let f = RunFolder::begin(&dir, true).unwrap();
        assert!(f.path().join("checkpoint.json").exists());
        drop(f);
        // without --resume the staging folder starts empty
        let f = RunFolder::begin(&dir, false).unwrap();
        assert!(!f.path().join("checkpoint.json").exists());
        drop(f);
        std::fs::remove_dir_all(&root).unwrap();
    }
}
