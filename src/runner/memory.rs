//! The process's resident memory as Linux reports it (VmRSS, VmHWM), for the benchmarks' and the
//! mesh study's per-stage peaks; None elsewhere.

/// A memory line of /proc/self/status (kB there), GB.
fn status_gb(key: &str) -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with(key))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024.0 / 1e9)
}

/// The process's peak resident memory since the last [`reset_peak_memory`], GB (Linux's VmHWM;
/// None elsewhere).
pub fn peak_memory_gb() -> Option<f64> {
    status_gb("VmHWM:")
}

/// The process's present resident memory, GB (Linux's VmRSS; None elsewhere).
pub fn resident_memory_gb() -> Option<f64> {
    status_gb("VmRSS:")
}

/// Restarts the peak resident memory from the present one (Linux: `/proc/self/clear_refs`), so
/// that each stage's peak is its own.
pub fn reset_peak_memory() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}
