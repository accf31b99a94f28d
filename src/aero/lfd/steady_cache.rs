//! The steady state kept between runs in the run folder: a file named by a hash of everything the
//! state depends on, read back only when it belongs to the mesh and is physical; a near state
//! (another design's) seeds the next solve.

use super::*;

impl LfdWingSpec {
    /// The file in `dir` that holds the steady state of this mesh, wing and flight condition:
    /// named by a hash of everything the state depends on, so a changed input misses it.
    pub fn steady_file(&self, wing: &WingContext, dir: &Path) -> PathBuf {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        format!(
            "{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}",
            self.mesh_file.as_ref().map(|f| f.content_hash()),
            self.mesh_spec(),
            wing.planform.to_array().map(f64::to_bits),
            wing.airfoil,
            wing.flight.mach.to_bits(),
            self.order,
            self.limiter
        )
        .hash(&mut h);
        dir.join(format!("{STEADY_PREFIX}{:016x}.bin", h.finish()))
    }
}

/// A state read from `file` if it is one of this mesh (length) and physical (finite, positive
/// density); `None` for anything else, with a line saying why when the file is there but not
/// this mesh's or not a flow state (it is never trusted).
pub(super) fn read_state(e: &Euler, file: &Path) -> Option<Vec<gustkit_cfd::residual::State<f64>>> {
    let bytes = std::fs::read(file).ok()?;
    let n = e.mesh.n_cells;
    let nvar = gustkit_cfd::gas::NVAR;
    if bytes.len() != 8 * nvar * n {
        println!(
            "{}: a steady state of another mesh ({} values, this mesh has {n} cells × {nvar}): not used",
            file.display(),
            bytes.len() / 8
        );
        return None;
    }
    let vals: Vec<f64> = bytes
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")))
        .collect();
    let q: Vec<gustkit_cfd::residual::State<f64>> = vals
        .chunks_exact(nvar)
        .map(|c| std::array::from_fn(|k| c[k]))
        .collect();
    if q.iter().flatten().any(|v| !v.is_finite()) || q.iter().any(|s| !(s[0] > 0.0)) {
        println!(
            "{}: not a flow state (non-finite values or a density not above zero): not used",
            file.display()
        );
        return None;
    }
    Some(q)
}

/// A steady state read from `file` if it is one of this mesh, physical, and converged
/// (‖R‖ within 1e-12 of the flux scale, well above round-off and far below any truncation
/// error); anything else is ignored and the state solved again.
pub(super) fn converged_state(
    e: &Euler,
    file: &Path,
) -> Option<Vec<gustkit_cfd::residual::State<f64>>> {
    let q = read_state(e, file)?;
    let r: f64 = e
        .residual(&q)
        .iter()
        .flatten()
        .map(|v| v * v)
        .sum::<f64>()
        .sqrt();
    (r <= 1e-12 * e.flux_scale(&q)).then_some(q)
}

/// The steady state of the folder's previous wing (another design of an optimization), when one
/// of this mesh's size is there: the initial guess of the next steady solve, which converges to
/// the same state as from the free stream in fewer Newton iterations.
pub(super) fn previous_state(
    e: &Euler,
    cache: Option<&Path>,
) -> Option<Vec<gustkit_cfd::residual::State<f64>>> {
    cache.and_then(Path::parent).and_then(|dir| {
        std::fs::read_dir(dir).ok()?.flatten().find_map(|entry| {
            let name = entry.file_name();
            let name = name.to_string_lossy();
            let ours = Some(entry.path()) == cache.map(Path::to_path_buf);
            (!ours && name.starts_with(STEADY_PREFIX) && name.ends_with(".bin"))
                .then(|| read_state(e, &entry.path()))
                .flatten()
        })
    })
}

/// Writes a steady state to `file` atomically (little-endian f64, cell by cell), and removes the
/// folder's other steady states (a run folder keeps the one of its latest wing).
pub(super) fn save_state(
    file: &Path,
    q: &[gustkit_cfd::residual::State<f64>],
) -> std::io::Result<()> {
    let bytes: Vec<u8> = q.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    crate::atomic::write(file, &bytes)?;
    if let Some(dir) = file.parent() {
        for entry in std::fs::read_dir(dir)?.flatten() {
            let path = entry.path();
            let name = entry.file_name();
            let name = name.to_string_lossy();
            if path != file && name.starts_with(STEADY_PREFIX) && name.ends_with(".bin") {
                let _ = std::fs::remove_file(path);
            }
        }
    }
    Ok(())
}

/// File-name prefix of the cached steady states (`steady_lfd_<hash>.bin`).
pub const STEADY_PREFIX: &str = "steady_lfd_";

type Store = std::sync::Arc<std::sync::Mutex<gustkit_cfd::lfd_model::WarmStart>>;

/// Every run folder's warm-start store in this process.
static STORES: std::sync::OnceLock<
    std::sync::Mutex<std::collections::BTreeMap<std::path::PathBuf, Store>>,
> = std::sync::OnceLock::new();

/// The GMRES warm-start store of the run whose folder is `dir`, shared by every LFD model built
/// for it in this process (the designs of one optimization); created empty on first use.
pub(crate) fn warm_start_store(dir: &Path) -> Store {
    let mut stores = STORES
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    stores.entry(dir.to_path_buf()).or_default().clone()
}

/// The GMRES iterations a right-hand side of the last GAF table and of the last reverse sweep's
/// adjoint solves in the warm-start store of the run folder `dir` (none where no LFD model of
/// that folder kept one, or it has not solved any).
pub fn warm_start_iterations(dir: &Path) -> (Option<f64>, Option<f64>) {
    let Some(stores) = STORES.get() else {
        return (None, None);
    };
    let stores = stores.lock().unwrap_or_else(|e| e.into_inner());
    let Some(store) = stores.get(dir) else {
        return (None, None);
    };
    let w = store.lock().unwrap_or_else(|e| e.into_inner());
    let per = |it: usize, rhs: usize| (rhs > 0).then(|| it as f64 / rhs as f64);
    (
        per(w.last_iterations, w.last_rhs),
        per(w.last_adjoint_iterations, w.last_adjoint_rhs),
    )
}

/// Empties the GMRES warm-start store of the run folder `dir` (its next table starts from zero).
pub fn clear_warm_start(dir: &Path) {
    let s = warm_start_store(dir);
    let mut w = s.lock().unwrap_or_else(|e| e.into_inner());
    *w = Default::default();
}

/// The file in a run folder that keeps the GMRES warm-start store across processes (written with
/// each optimization checkpoint, read by `--resume`, removed when the optimization ends).
pub const WARM_START_FILE: &str = "warm_start.bin";

/// Writes the warm-start store of the run folder `dir` to [`WARM_START_FILE`] atomically;
/// the bytes written, or None when the store holds nothing (no LFD model of that folder solved).
pub fn save_warm_start(dir: &Path) -> std::io::Result<Option<u64>> {
    let Some(store) = STORES.get().and_then(|s| {
        s.lock()
            .unwrap_or_else(|e| e.into_inner())
            .get(dir)
            .cloned()
    }) else {
        return Ok(None);
    };
    let w = store.lock().unwrap_or_else(|e| e.into_inner());
    if w.unknowns() == 0 {
        return Ok(None);
    }
    let bytes = w.file_bytes();
    crate::atomic::write_with(&dir.join(WARM_START_FILE), |f| w.write_to(f))?;
    Ok(Some(bytes))
}

/// Fills the warm-start store of the run folder `dir` from its [`WARM_START_FILE`] (a resumed
/// run): true when read. A file that is not a store, is damaged or holds non-finite values is
/// ignored with a line saying so; one of another mesh is dropped, with a line, by the first
/// model that checks it ([`gustkit_cfd::lfd_model::WarmStart::fits`]).
pub fn load_warm_start(dir: &Path) -> bool {
    let file = dir.join(WARM_START_FILE);
    let Ok(f) = std::fs::File::open(&file) else {
        return false;
    };
    match gustkit_cfd::lfd_model::WarmStart::read_from(&mut std::io::BufReader::new(f)) {
        Ok(mut read) => {
            let s = warm_start_store(dir);
            let mut w = s.lock().unwrap_or_else(|e| e.into_inner());
            read.designs = w.designs;
            read.from_file = Some(file);
            *w = read;
            true
        }
        Err(e) => {
            let e = match e.kind() {
                std::io::ErrorKind::UnexpectedEof => "the file ends early".to_string(),
                _ => e.to_string(),
            };
            println!(
                "{}: not a usable warm-start store ({e}): not used, the GMRES solves start from zero",
                file.display()
            );
            false
        }
    }
}

/// Removes the run folder's [`WARM_START_FILE`] (an ended optimization resumes no more).
pub fn remove_warm_start_file(dir: &Path) {
    let _ = std::fs::remove_file(dir.join(WARM_START_FILE));
}
