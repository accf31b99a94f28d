//! The forward LFD solutions of a GAF table, kept for a reverse sweep at the same point: in
//! memory, or handed to a [`ForwardSpill`] as each frequency is solved (80 bytes a cell per
//! frequency and column that the process need not hold — 4.8 GB on the fine wing mesh with 11
//! modes and the gust) and read back by the reverse sweep's frequency. The fidelity writes no
//! files itself: the application supplies the spill (gustkit's scratch files in `TMPDIR`).

use crate::krylov::GmresInfo;
use num_complex::Complex64 as C64;
use std::borrow::Cow;
use std::sync::Arc;

/// One LFD solution with its GMRES record.
pub type Solution = (Vec<C64>, GmresInfo);

/// A place outside the process's memory for one frequency's solution columns.
pub trait ForwardSpill: Send + Sync + std::fmt::Debug {
    /// Keeps the columns (equal lengths); an error says why, naming where.
    fn put(&self, columns: &[Vec<C64>]) -> Result<Box<dyn Spilled>, String>;
}

/// Columns kept by a [`ForwardSpill`]; dropping it releases them.
pub trait Spilled: Send + Sync {
    /// The columns, bit for bit as they were put.
    fn read(&self) -> Result<Vec<Vec<C64>>, String>;
}

/// Where a model keeps its forward solutions between a GAF table and its reverse sweep.
#[derive(Clone, Debug, Default)]
pub enum ForwardStorage {
    /// In memory (the default of a model built in code).
    #[default]
    Memory,
    /// Handed to a spill.
    Spill(Arc<dyn ForwardSpill>),
}

/// A table's forward solutions, per reduced frequency in the order they were pushed.
pub(crate) enum ForwardSolutions {
    Memory(Vec<Vec<Solution>>),
    Spilled {
        spill: Arc<dyn ForwardSpill>,
        /// Per frequency: the kept columns and their GMRES records.
        frequencies: Vec<(Box<dyn Spilled>, Vec<GmresInfo>)>,
    },
}

impl ForwardSolutions {
    /// An empty store.
    pub fn new(storage: &ForwardStorage) -> Self {
        match storage {
            ForwardStorage::Memory => Self::Memory(Vec::new()),
            ForwardStorage::Spill(spill) => Self::Spilled {
                spill: spill.clone(),
                frequencies: Vec::new(),
            },
        }
    }

    /// Keeps the next frequency's solutions (for a spill, handed over and dropped from memory).
    pub fn push(&mut self, solutions: Vec<Solution>) -> Result<(), String> {
        match self {
            Self::Memory(list) => list.push(solutions),
            Self::Spilled { spill, frequencies } => {
                let (columns, info): (Vec<Vec<C64>>, Vec<GmresInfo>) =
                    solutions.into_iter().unzip();
                frequencies.push((spill.put(&columns)?, info));
            }
        }
        Ok(())
    }

    /// The solutions of the `i`-th frequency pushed (read back from the spill).
    pub fn get(&self, i: usize) -> Result<Cow<'_, [Solution]>, String> {
        match self {
            Self::Memory(list) => Ok(Cow::Borrowed(&list[i])),
            Self::Spilled { frequencies, .. } => {
                let (kept, info) = &frequencies[i];
                let columns = kept.read()?;
                if columns.len() != info.len() {
                    return Err(format!(
                        "the forward LFD solutions read back hold {} columns, {} were kept",
                        columns.len(),
                        info.len()
                    ));
                }
                Ok(Cow::Owned(
                    columns.into_iter().zip(info.iter().cloned()).collect(),
                ))
            }
        }
    }
}
