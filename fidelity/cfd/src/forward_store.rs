//! The forward LFD solutions of a GAF table, kept for a reverse sweep at the same point: in
//! memory, or in scratch files (one a reduced frequency, every column's complex values as
//! little-endian f64 pairs: 80 bytes a cell per frequency and column that the process does not
//! hold — 4.8 GB on the fine wing mesh with 11 modes and the gust). Written once a frequency is
//! solved, read back by the reverse sweep's frequency: the numbers come back bit for bit.

use crate::krylov::GmresInfo;
use num_complex::Complex64 as C64;
use std::borrow::Cow;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// One LFD solution with its GMRES record.
pub type Solution = (Vec<C64>, GmresInfo);

/// Where a model keeps its forward solutions between a GAF table and its reverse sweep.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum ForwardStorage {
    /// In memory (the default of a model built in code).
    #[default]
    Memory,
    /// In scratch files of this folder (deleted when the table's solutions are replaced or the
    /// model dropped).
    Files(PathBuf),
}

/// A table's forward solutions, per reduced frequency in the order they were pushed.
pub(crate) enum ForwardSolutions {
    Memory(Vec<Vec<Solution>>),
    Files {
        /// Per frequency: its file and its columns' GMRES records.
        frequencies: Vec<(PathBuf, Vec<GmresInfo>)>,
        dir: PathBuf,
        /// This store's number within the process (file names).
        id: usize,
        /// Unknowns a column.
        n: usize,
    },
}

/// Stores numbered within the process, so that models sharing a folder never share files.
static NEXT_STORE: AtomicUsize = AtomicUsize::new(0);

impl ForwardSolutions {
    /// An empty store for columns of `n` unknowns.
    pub fn new(storage: &ForwardStorage, n: usize) -> Self {
        match storage {
            ForwardStorage::Memory => Self::Memory(Vec::new()),
            ForwardStorage::Files(dir) => Self::Files {
                frequencies: Vec::new(),
                dir: dir.clone(),
                id: NEXT_STORE.fetch_add(1, Ordering::Relaxed),
                n,
            },
        }
    }

    /// Keeps the next frequency's solutions (for a file store, written and dropped from memory);
    /// an I/O failure names the file.
    pub fn push(&mut self, solutions: Vec<Solution>) -> Result<(), String> {
        match self {
            Self::Memory(list) => list.push(solutions),
            Self::Files {
                frequencies,
                dir,
                id,
                n,
            } => {
                let path = dir.join(format!(
                    "gustkit_lfd_forward_{}_{id}_{}.bin",
                    std::process::id(),
                    frequencies.len()
                ));
                let fail = |e: std::io::Error| {
                    format!(
                        "the forward LFD solutions kept for the reverse sweep could not be written to {}: {e}",
                        path.display()
                    )
                };
                let file = std::fs::File::create(&path).map_err(fail)?;
                let mut w = BufWriter::with_capacity(1 << 20, file);
                for (x, _) in &solutions {
                    assert_eq!(x.len(), *n, "a column of the store's size");
                    for v in x {
                        w.write_all(&v.re.to_le_bytes()).map_err(fail)?;
                        w.write_all(&v.im.to_le_bytes()).map_err(fail)?;
                    }
                }
                w.flush().map_err(fail)?;
                frequencies.push((path, solutions.into_iter().map(|(_, i)| i).collect()));
            }
        }
        Ok(())
    }

    /// The solutions of the `i`-th frequency pushed (read back from its file for a file store).
    pub fn get(&self, i: usize) -> Result<Cow<'_, [Solution]>, String> {
        match self {
            Self::Memory(list) => Ok(Cow::Borrowed(&list[i])),
            Self::Files { frequencies, n, .. } => {
                let (path, info) = &frequencies[i];
                read_columns(path, *n, info).map(Cow::Owned)
            }
        }
    }
}

/// The columns of a file written by [`ForwardSolutions::push`].
fn read_columns(path: &Path, n: usize, info: &[GmresInfo]) -> Result<Vec<Solution>, String> {
    let fail = |e: std::io::Error| {
        format!(
            "the forward LFD solutions kept for the reverse sweep could not be read from {}: {e}",
            path.display()
        )
    };
    let file = std::fs::File::open(path).map_err(fail)?;
    let mut r = BufReader::with_capacity(1 << 20, file);
    let mut buf = [0u8; 16];
    let mut out = Vec::with_capacity(info.len());
    for i in info {
        let mut x = Vec::with_capacity(n);
        for _ in 0..n {
            r.read_exact(&mut buf).map_err(fail)?;
            let (re, im) = buf.split_at(8);
            x.push(C64::new(
                f64::from_le_bytes(re.try_into().expect("8 bytes")),
                f64::from_le_bytes(im.try_into().expect("8 bytes")),
            ));
        }
        out.push((x, i.clone()));
    }
    Ok(out)
}

impl Drop for ForwardSolutions {
    fn drop(&mut self) {
        if let Self::Files { frequencies, .. } = self {
            for (path, _) in frequencies.iter() {
                let _ = std::fs::remove_file(path);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(iterations: usize) -> GmresInfo {
        GmresInfo {
            iterations,
            history: vec![0.5; iterations],
        }
    }

    /// A file store gives back every column bit for bit with its GMRES record, the memory store
    /// the same, and dropping the file store removes its files.
    #[test]
    fn file_store_returns_the_columns_bit_for_bit() {
        let dir = std::env::temp_dir();
        let n = 7;
        let column = |f: usize, c: usize| -> Vec<C64> {
            (0..n)
                .map(|i| {
                    let t = (f * 31 + c * 7 + i) as f64;
                    C64::new(t.sin() * 1e-300_f64.max(t.cos()), 1.0 / (t + 0.3))
                })
                .collect()
        };
        let table: Vec<Vec<Solution>> = (0..3)
            .map(|f| (0..2).map(|c| (column(f, c), record(f + c))).collect())
            .collect();
        let mut files = ForwardSolutions::new(&ForwardStorage::Files(dir), n);
        let mut memory = ForwardSolutions::new(&ForwardStorage::Memory, n);
        for f in &table {
            files.push(f.clone()).unwrap();
            memory.push(f.clone()).unwrap();
        }
        let paths: Vec<PathBuf> = match &files {
            ForwardSolutions::Files { frequencies, .. } => {
                frequencies.iter().map(|(p, _)| p.clone()).collect()
            }
            ForwardSolutions::Memory(_) => unreachable!(),
        };
        assert!(paths.iter().all(|p| p.exists()));
        for (f, expect) in table.iter().enumerate() {
            for store in [&files, &memory] {
                let got = store.get(f).unwrap();
                assert_eq!(got.len(), expect.len());
                for ((x, i), (y, j)) in got.iter().zip(expect) {
                    assert_eq!(i.iterations, j.iterations);
                    assert!(x
                        .iter()
                        .zip(y)
                        .all(|(a, b)| a.re.to_bits() == b.re.to_bits()
                            && a.im.to_bits() == b.im.to_bits()));
                }
            }
        }
        drop(files);
        assert!(paths.iter().all(|p| !p.exists()));
    }

    /// A folder that cannot take the files is an error naming the file, not a panic.
    #[test]
    fn an_unwritable_folder_is_named() {
        let dir = std::env::temp_dir().join("gustkit_no_such_folder_for_the_forward_store");
        let mut store = ForwardSolutions::new(&ForwardStorage::Files(dir), 1);
        let err = store
            .push(vec![(vec![C64::new(1.0, 0.0)], record(1))])
            .unwrap_err();
        assert!(
            err.contains("gustkit_no_such_folder_for_the_forward_store"),
            "{err}"
        );
    }
}
