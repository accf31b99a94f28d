//! Scratch files for the LFD's forward solutions between a GAF table and its reverse sweep
//! ([`gustkit_cfd::forward_store::ForwardSpill`]): one unnamed temporary file a reduced frequency
//! in the system's temporary folder (`tempfile`: the operating system deletes it when the file is
//! closed, so a run that is killed leaves nothing behind), every column's complex values as
//! little-endian f64 pairs. Nothing here is a result: the run folder never sees these files.

use gustkit_cfd::forward_store::{ForwardSpill, Spilled};
use num_complex::Complex64 as C64;
use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::PathBuf;
use std::sync::Mutex;

/// A folder for scratch files.
#[derive(Debug)]
pub struct ScratchFolder(pub PathBuf);

/// One frequency's columns in an unnamed scratch file (read back under a lock: one reader at a
/// time moves its position).
struct ScratchFile {
    file: Mutex<File>,
    folder: PathBuf,
    n: usize,
    columns: usize,
}

impl ForwardSpill for ScratchFolder {
    fn put(&self, columns: &[Vec<C64>]) -> Result<Box<dyn Spilled>, String> {
        let fail = |e: std::io::Error| {
            format!(
                "the forward LFD solutions kept for the reverse sweep could not be written to a temporary file in {} ({e}): free space there, set TMPDIR, or choose forward_solutions: \"memory\"",
                self.0.display()
            )
        };
        let n = columns.first().map_or(0, Vec::len);
        let file = tempfile::tempfile_in(&self.0).map_err(fail)?;
        let mut w = BufWriter::with_capacity(1 << 20, &file);
        for x in columns {
            if x.len() != n {
                return Err(format!(
                    "columns of unequal lengths ({} and {n}) for a temporary file in {}",
                    x.len(),
                    self.0.display()
                ));
            }
            for v in x {
                w.write_all(&v.re.to_le_bytes()).map_err(fail)?;
                w.write_all(&v.im.to_le_bytes()).map_err(fail)?;
            }
        }
        w.flush().map_err(fail)?;
        drop(w);
        Ok(Box::new(ScratchFile {
            file: Mutex::new(file),
            folder: self.0.clone(),
            n,
            columns: columns.len(),
        }))
    }
}

impl Spilled for ScratchFile {
    fn read(&self) -> Result<Vec<Vec<C64>>, String> {
        let fail = |e: std::io::Error| {
            format!(
                "the forward LFD solutions kept for the reverse sweep could not be read from their temporary file in {}: {e}",
                self.folder.display()
            )
        };
        let mut file = self.file.lock().unwrap_or_else(|e| e.into_inner());
        file.seek(SeekFrom::Start(0)).map_err(fail)?;
        let mut r = BufReader::with_capacity(1 << 20, &*file);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A scratch file gives back every column bit for bit (subnormal, huge and negative-zero
    /// values among them), twice, and never has a name in its folder (so a killed run leaves no
    /// file behind).
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
        assert_eq!(files(), 0);
        let bits = |c: &[Vec<C64>]| -> Vec<u64> {
            c.iter()
                .flatten()
                .flat_map(|v| [v.re.to_bits(), v.im.to_bits()])
                .collect()
        };
        assert_eq!(bits(&kept.read().unwrap()), bits(&columns));
        assert_eq!(bits(&kept.read().unwrap()), bits(&columns));
        drop(kept);
        assert_eq!(files(), 0);
        std::fs::remove_dir(&dir).unwrap();
    }

    /// A folder that cannot take the file is an error naming the folder and the way out, not a
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
