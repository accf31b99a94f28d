//! Loading a study file of any kind, once: read, decide the kind, validate as that kind.

use crate::kind::StudyKind;
use crate::study::Study;
use crate::typical_section::SectionStudyFile;
use crate::verification::CfdStudyFile;
use anyhow::{bail, Context, Result};
use std::path::Path;

/// A loaded and validated study of any kind.
pub enum LoadedStudy {
    Wing(Box<Study>),
    TypicalSection(Box<SectionStudyFile>),
    CfdVerification(Box<CfdStudyFile>),
    NastranDesign(Box<crate::study::nastran::NastranStudyFile>),
}

impl LoadedStudy {
    /// Reads a study file once, decides its kind and validates it as that kind.
    pub fn load(file: &Path) -> Result<Self> {
        let text = crate::study::read_text(file)
            .with_context(|| format!("{}: .: cannot read the file", file.display()))?;
        let doc: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| anyhow::anyhow!("{}: .: not valid JSON: {e}", file.display()))?;
        Ok(match StudyKind::of(file, &doc)? {
            StudyKind::Wing => LoadedStudy::Wing(Box::new(Study::from_str(file, &text)?)),
            StudyKind::TypicalSection => {
                LoadedStudy::TypicalSection(Box::new(SectionStudyFile::from_value(file, &doc)?))
            }
            StudyKind::CfdVerification => {
                LoadedStudy::CfdVerification(Box::new(CfdStudyFile::from_value(file, &doc)?))
            }
            StudyKind::NastranDesign => {
                LoadedStudy::NastranDesign(Box::new(crate::study::nastran::load(file, &doc)?))
            }
        })
    }

    pub fn kind(&self) -> StudyKind {
        match self {
            LoadedStudy::Wing(_) => StudyKind::Wing,
            LoadedStudy::TypicalSection(_) => StudyKind::TypicalSection,
            LoadedStudy::CfdVerification(_) => StudyKind::CfdVerification,
            LoadedStudy::NastranDesign(_) => StudyKind::NastranDesign,
        }
    }

    /// The wing study, or an error saying that `command` works on wing studies only.
    pub fn into_wing(self, file: &Path, command: &str) -> Result<Study> {
        match self {
            LoadedStudy::Wing(s) => Ok(*s),
            other => bail!(
                "{}: `gustkit {command}` works on wing studies; this is a {} study",
                file.display(),
                other.kind().name()
            ),
        }
    }
}
