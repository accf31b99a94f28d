//! Atomic file writes: a temporary file in the same folder, then a rename, so a reader never sees
//! a half-written file, an earlier file survives a failed write, and no temporary file is left.

use std::path::{Path, PathBuf};

/// The temporary file beside `path` that an atomic write fills first: `.NAME.tmpPID`.
fn temp_path(path: &Path) -> PathBuf {
    let dir = path.parent().unwrap_or(Path::new("."));
    dir.join(format!(
        ".{}.tmp{}",
        path.file_name().and_then(|n| n.to_str()).unwrap_or("out"),
        std::process::id()
    ))
}

/// Writes `bytes` to `path` atomically (the temporary file `.NAME.tmpPID` beside it is removed
/// when the write or the rename fails).
pub fn write(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = temp_path(path);
    std::fs::write(&tmp, bytes)
        .and_then(|()| std::fs::rename(&tmp, path))
        .inspect_err(|_| {
            let _ = std::fs::remove_file(&tmp);
        })
}

/// Writes a file atomically by streaming into the temporary file (for files too large to build
/// in memory first): `fill` writes through a buffered writer; on any error the temporary file is
/// removed and an earlier `path` survives.
pub fn write_with(
    path: &Path,
    fill: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let tmp = temp_path(path);
    let result = std::fs::File::create(&tmp).and_then(|f| {
        let mut w = std::io::BufWriter::new(f);
        fill(&mut w)?;
        use std::io::Write;
        w.flush()?;
        w.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        std::fs::rename(&tmp, path)
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}
