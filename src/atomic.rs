//! Atomic file writes: a temporary file in the same folder, then a rename, so a reader never sees
//! a half-written file, an earlier file survives a failed write, and no temporary file is left.

use std::path::Path;

/// Writes `bytes` to `path` atomically (the temporary file `.NAME.tmpPID` beside it is removed
/// when the write or the rename fails).
pub fn write(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let tmp = dir.join(format!(
        ".{}.tmp{}",
        path.file_name().and_then(|n| n.to_str()).unwrap_or("out"),
        std::process::id()
    ));
    std::fs::write(&tmp, bytes)
        .and_then(|()| std::fs::rename(&tmp, path))
        .inspect_err(|_| {
            let _ = std::fs::remove_file(&tmp);
        })
}
