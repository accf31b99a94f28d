//! Nastran input: the reader of MSC Nastran and COSMIC NASTRAN-95 input files (executive and
//! case control sections, bulk data in small, large and free field with continuations and
//! INCLUDE), the typed bulk data cards gustkit uses, and the errors that name card, id and line.
//!
//! Written for gustkit rather than taken from a crate: the one Rust Nastran reader published
//! (`nastran` 0.0.1) is an experimental GPL crate on nom 3 without the aeroelastic cards.
//! Values keep the model's own units: nothing is converted on reading.

pub mod aero;
pub mod bulk;
pub mod case_control;
pub mod deck;
pub mod design;
pub mod field;
pub mod lfd;
pub mod random;
pub mod response;
pub mod spline;
pub mod structure;
pub mod transient;

pub use case_control::{CaseControl, Executive, Subcase};
pub use deck::{Card, Deck, Source};

use std::path::{Path, PathBuf};

/// The file extensions read as Nastran input.
pub const EXTENSIONS: [&str; 5] = ["bdf", "dat", "inp", "nas", "blk"];

/// Whether `file` names a Nastran input (by its extension).
pub fn is_nastran(file: &Path) -> bool {
    file.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()))
}

/// An error in a Nastran input: where (file and line), which card or statement (and its id),
/// and why, in words that say what to change.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{place}: {what}: {reason}")]
pub struct NastranError {
    /// `file line N`, or the file alone.
    pub place: String,
    /// The card and its id (`CQUAD4 12`), or the statement.
    pub what: String,
    pub reason: String,
}

impl NastranError {
    /// An error at a source line about `what`.
    pub fn at(source: &Source, what: &str, reason: String) -> Self {
        Self {
            place: source.to_string(),
            what: what.to_string(),
            reason,
        }
    }

    /// An error about the model as a whole (`what`: the card, set or part concerned), where no
    /// one card line is to blame.
    pub fn model(what: &str, reason: String) -> Self {
        Self {
            place: "model".into(),
            what: what.into(),
            reason,
        }
    }

    /// An error about a whole file.
    pub fn file(file: &Path, reason: String) -> Self {
        Self {
            place: file.display().to_string(),
            what: "input file".into(),
            reason,
        }
    }

    /// An error about a card (named with its id where the card has one).
    pub fn card(card: &Card, reason: impl Into<String>) -> Self {
        let what = match card.id() {
            Some(id) => format!("{} {id}", card.name),
            None => card.name.clone(),
        };
        Self::at(&card.source, &what, reason.into())
    }
}

/// A read Nastran input: what the executive, case control and bulk data sections ask for, with
/// one warning line per section for what gustkit reads but does not use.
#[derive(Clone, Debug)]
pub struct Input {
    pub file: PathBuf,
    pub executive: Executive,
    pub case_control: CaseControl,
    pub deck: Deck,
}

impl Input {
    /// Reads a Nastran input file (and its INCLUDEs).
    pub fn read(file: &Path) -> Result<Self, NastranError> {
        let deck = Deck::read(file)?;
        let executive = Executive::parse(&deck.executive)?;
        let case_control = CaseControl::parse(&deck.case_control)?;
        Ok(Self {
            file: file.to_path_buf(),
            executive,
            case_control,
            deck,
        })
    }

    /// Every warning of the reading, one line each.
    pub fn warnings(&self) -> Vec<String> {
        self.executive
            .warnings
            .iter()
            .chain(&self.case_control.warnings)
            .cloned()
            .collect()
    }
}
