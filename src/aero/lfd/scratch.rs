//! Scratch files for the LFD's forward solutions between a GAF table and its reverse sweep
//! ([`gustkit_cfd::forward_store::ForwardSpill`]): one file a reduced frequency in the system's
//! temporary folder, every column's complex values as little-endian f64 pairs, deleted when the
//! model lets the table go. Nothing here is a result: the run folder never sees these files.

use gustkit_cfd::forward_store::{ForwardSpill, Spilled};
use num_complex::Complex64 as C64;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Files numbered within the process (with its id in the name, so processes sharing the folder
/// never share files).
static NEXT_FILE: AtomicUsize = AtomicUsize::new(0);

/// A folder for scratch files.
#[derive(Debug)]
pub struct ScratchFolder(pub PathBuf);

/// One frequency's columns in a scratch file.
struct ScratchFile {
    path: PathBuf,
    n: usize,
    columns: usize,
}

impl ForwardSpill for ScratchFolder {
    fn put(&self, columns: &[Vec<C64>]) -> Result<Box<dyn Spilled>, String> {
        let path = self.0.join(format!(
            "gustkit_lfd_forward_{}_{}.bin",
            std::process::id(),
            NEXT_FILE.fetch_add(1, Ordering::Relaxed)
        ));
        let fail = |e: std::io::Error| {
            format!(
                "the forward LFD solutions kept for the reverse sweep could not be written to {} ({e}): free space there, set TMPDIR, or choose forward_solutions: \"memory\"",
                path.display()
            )
        };
        let n = columns.first().map_or(0, Vec::len);
        // the file exists from here on: removed again should a write fail
        let file = ScratchFile {
            path: path.clone(),
            n,
            columns: columns.len(),
        };
        let mut w = BufWriter::with_capacity(1 << 20, std::fs::File::create(&path).map_err(fail)?);
        for x in columns {
            if x.len() != n {
                return Err(format!(
                    "columns of unequal lengths ({} and {n}) for {}",
                    x.len(),
                    path.display()
                ));
            }
            for v in x {
                w.write_all(&v.re.to_le_bytes()).map_err(fail)?;
                w.write_all(&v.im.to_le_bytes()).map_err(fail)?;
            }
        }
        w.flush().map_err(fail)?;
        Ok(Box::new(file))
    }
}

impl Spilled for ScratchFile {
    fn read(&self) -> Result<Vec<Vec<C64>>, String> {
        let fail = |e: std::io::Error| {
            format!(
                "the forward LFD solutions kept for the reverse sweep could not be read from {}: {e}",
                self.path.display()
            )
        };
        let mut r =
            BufReader::with_capacity(1 << 20, std::fs::File::open(&self.path).map_err(fail)?);
        let mut buf = [0u8; 16];
        let mut out = Vec::with_capacity(self.columns);
        for _ in 0..self.columns {
            let mut x = Vec::with_capacity(self.n);
            for _ in 0..self.n {
                r.read_exact(&mut buf).map_err(fail)?;
                let (re, im) = buf.split_at(8);
                x.push(C64::new(
                    f64::from_le_bytes(re.try_into().expect("8 bytes")),
                    f64::from_le_bytes(im.try_into().expect("8 bytes")),
                ));
            }
            out.push(x);
        }
        Ok(out)
    }
}

impl Drop for ScratchFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scratch file gives back every column bit for bit (subnormal, huge and negative-zero
    /// values among them) and is gone once dropped.
    #[test]
    fn scratch_files_return_the_columns_bit_for_bit() {
        let dir = std::env::temp_dir().join(format!("gustkit_scratch_test_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let folder = ScratchFolder(dir.clone());
        let columns: Vec<Vec<C64>> = (0..3)
            .map(|c| {
                (0..7)
                    .map(|i| {
                        let t = (c * 7 + i) as f64;
                        C64::new(
                            t.sin() * 1e-310,
                            if i == 3 { -0.0 } else { 1e300 / (t + 0.3) },
                        )
                    })
                    .collect()
            })
            .collect();
        let files = || std::fs::read_dir(&dir).unwrap().count();
        let kept = folder.put(&columns).unwrap();
        assert_eq!(files(), 1);
        let bits = |c: &[Vec<C64>]| -> Vec<u64> {
            c.iter()
                .flatten()
                .flat_map(|v| [v.re.to_bits(), v.im.to_bits()])
                .collect()
        };
        assert_eq!(bits(&kept.read().unwrap()), bits(&columns));
        drop(kept);
        assert_eq!(files(), 0);
        std::fs::remove_dir(&dir).unwrap();
    }

    /// A folder that cannot take the file is an error naming the file and the way out, not a
    /// panic.
    #[test]
    fn an_unwritable_folder_is_named() {
        let folder = ScratchFolder(std::env::temp_dir().join("gustkit_no_such_folder_for_scratch"));
        let err = folder
            .put(&[vec![C64::new(1.0, 0.0)]])
            .err()
            .expect("no such folder");
        assert!(
            err.contains("gustkit_no_such_folder_for_scratch") && err.contains("TMPDIR"),
            "{err}"
        );
    }
}
