//! What the `gustkit` subcommands run: one runner per study kind (wing studies in [`wing`], the
//! typical section in `crate::typical_section`, the CFD verification cases in
//! `crate::verification`) and per tool ([`sweep`], [`bench`], [`export`]). `crate::cli` only
//! parses arguments and calls these.

pub mod bench;
pub mod export;
pub mod load;
pub mod memory;
pub mod nastran;
mod nastran_design;
pub mod sweep;
pub mod wing;

use crate::kind::StudyKind;
use crate::report;
use anyhow::Result;
pub use load::LoadedStudy;
use std::path::Path;

/// How a run that wrote its results ended: it reached its goal, or it did not (an optimization
/// stopped before its KKT test passed, sweep cases failed); the command line exits with
/// [`EXIT_GOAL_NOT_REACHED`] then.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Outcome {
    Done,
    GoalNotReached(String),
}

/// Exit status of a run that wrote its results without reaching its goal.
pub const EXIT_GOAL_NOT_REACHED: u8 = 3;

/// `gustkit run`: every analysis the study defines, with its report, whatever its kind.
pub fn run(file: &Path, reports: &Path, resume: bool) -> Result<Outcome> {
    if nastran::is_nastran(file) {
        if resume {
            anyhow::bail!(
                "--resume applies to optimization studies; a Nastran input runs from the start"
            );
        }
        return nastran::run(file, reports);
    }
    match LoadedStudy::load(file)? {
        LoadedStudy::Wing(study) => wing::run(&study, reports, resume),
        LoadedStudy::TypicalSection(study) => {
            crate::typical_section::run(&study, reports).map(|()| Outcome::Done)
        }
        LoadedStudy::CfdVerification(study) => {
            crate::verification::run(&study, reports).map(|()| Outcome::Done)
        }
        LoadedStudy::NastranDesign(study) => nastran_design::run(&study, reports, resume),
    }
}

/// `gustkit run STUDY --design RUN/results.json`: the analyses of a wing study without an
/// optimization section, on the final design of another run. An optimization study is refused:
/// its constraints' modal basis depends on its flutter margin, and a design to start from is
/// `optimization.warm_start`.
pub fn run_design(file: &Path, reports: &Path, design: &Path) -> Result<Outcome> {
    let study = LoadedStudy::load(file)?.into_wing(file, "run --design")?;
    if study.spec.optimization.is_some() {
        anyhow::bail!(
            "{}: --design analyses a run's design with an analysis study, and this one has an `optimization` section: to start an optimization from the design use optimization.warm_start; for its flutter, `gustkit flutter {} --design {}`",
            file.display(),
            file.display(),
            design.display()
        );
    }
    wing::run(&study.at_final_design(design)?, reports, false)
}

/// `gustkit report RUN_DIR`: every figure and the summary again, from results.json alone (or,
/// for a sweep folder, from sweep_results.json). The kind recorded in results.json chooses the
/// renderer.
pub fn report(dir: &Path) -> Result<()> {
    if dir.join("sweep_results.json").is_file() {
        let r = report::sweep::rerender(dir)?;
        println!(
            "sweep report of {} re-rendered from {}",
            r.study,
            dir.join("sweep_results.json").display()
        );
        return Ok(());
    }
    let results = dir.join("results.json");
    let value = report::read_json(&results)?;
    if value["kind"] == "nastran" {
        return nastran::rerender(dir, value);
    }
    let kind = StudyKind::of_results(&results, &value)?;
    let mismatch = |e: anyhow::Error| {
        anyhow::anyhow!(
            "{}: does not hold {} results: {e}",
            results.display(),
            kind.name()
        )
    };
    let study = match kind {
        StudyKind::TypicalSection => {
            let r: crate::typical_section::SectionResults =
                report::from_json(&results, &value).map_err(mismatch)?;
            crate::typical_section::render(dir, &r)?;
            r.study
        }
        StudyKind::CfdVerification => {
            let r: crate::verification::CfdResults =
                report::from_json(&results, &value).map_err(mismatch)?;
            crate::verification::render(dir, &r)?;
            r.study
        }
        StudyKind::NastranDesign => nastran_design::rerender(dir, &value).map_err(mismatch)?,
        StudyKind::Wing => {
            let r: crate::report::results::RunResults =
                report::from_json(&results, &value).map_err(mismatch)?;
            report::run::rerender(dir, &results, &value, r)?.study
        }
    };
    println!("report of {study} re-rendered from {}", results.display());
    Ok(())
}
