//! The kinds of study file, told apart in one place: each kind has its own top-level section
//! (`wing`, `typical_section`, `cfd` or `model`), exactly one of which a study holds. The kind is decided
//! once, when the file is loaded (`crate::runner::LoadedStudy`), and written into results.json
//! as `kind`, which `gustkit report` reads back instead of guessing from the layout. A leaf
//! module: every study kind's results name it, it names none of them.

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A kind of study.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum StudyKind {
    /// A wing: plate structure, aerodynamics, gust, flutter, optimization, sweeps.
    Wing,
    /// A 2-D pitch–plunge typical section with LFD and strip aerodynamics side by side.
    TypicalSection,
    /// A CFD verification case of the paper (NACA 64A010: Table 1, Fig. 1, Table 2).
    CfdVerification,
    /// A Nastran model's properties designed against its random gust response.
    NastranDesign,
}

impl StudyKind {
    /// The top-level section that marks the kind.
    pub fn section(self) -> &'static str {
        match self {
            StudyKind::Wing => "wing",
            StudyKind::TypicalSection => "typical_section",
            StudyKind::CfdVerification => "cfd",
            StudyKind::NastranDesign => "model",
        }
    }

    /// The name written into results.json.
    pub fn name(self) -> &'static str {
        match self {
            StudyKind::Wing => "wing",
            StudyKind::TypicalSection => "typical_section",
            StudyKind::CfdVerification => "cfd_verification",
            StudyKind::NastranDesign => "nastran_design",
        }
    }

    const ALL: [StudyKind; 4] = [
        StudyKind::Wing,
        StudyKind::TypicalSection,
        StudyKind::CfdVerification,
        StudyKind::NastranDesign,
    ];

    /// The kind of a study document: the one kind whose section it has.
    pub fn of(file: &Path, doc: &serde_json::Value) -> Result<Self> {
        let Some(obj) = doc.as_object() else {
            bail!("{}: .: a study file is a JSON object", file.display());
        };
        let found: Vec<StudyKind> = Self::ALL
            .into_iter()
            .filter(|k| obj.contains_key(k.section()))
            .collect();
        match found.as_slice() {
            [k] => Ok(*k),
            [] => bail!(
                "{}: .: unknown study kind: the file has none of the sections \"wing\" (a wing study), \"typical_section\", \"cfd\" (a CFD verification case) or \"model\" (a Nastran model: {{\"nastran\": \"wing.bdf\"}})",
                file.display()
            ),
            _ => bail!(
                "{}: .: the file mixes study kinds (sections {}): keep one",
                file.display(),
                found
                    .iter()
                    .map(|k| format!("\"{}\"", k.section()))
                    .collect::<Vec<_>>()
                    .join(" and ")
            ),
        }
    }

    /// The kind recorded in a results.json document at `path`.
    pub fn of_results(path: &Path, doc: &serde_json::Value) -> Result<Self> {
        let Some(kind) = doc.get("kind") else {
            bail!(
                "{}: kind: missing — this results.json was written before results files recorded their study kind (results schema 1); run the study again with this gustkit to re-create it",
                path.display()
            );
        };
        serde_json::from_value(kind.clone()).with_context(|| {
            format!(
                "{}: kind: {kind} is not a study kind (wing, typical_section, cfd_verification, nastran_design)",
                path.display()
            )
        })
    }
}
