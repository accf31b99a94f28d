//! The memory a wing study's largest allocations take, estimated from its sizes at load, so that a
//! study too large for the machine is refused with the field to change before anything is
//! allocated (a dense plate eigenproblem, the DLM's influence matrices, the gust frequency grid).
//!
//! The per-item costs were measured on this build (peak resident memory of `gustkit modes`,
//! `gafs`, `run` and `check-gradient` at several sizes) and rounded up:
//! - plate: about 700 bytes per (node pair) for the dense K, M, the eigensolver's workspace and
//!   the sensitivities (1.86 GB at 1 681 nodes with the complete eigen-decomposition; the partial
//!   one of today takes 0.77 GB there, so the bound is now conservative by about 2.4×);
//! - the aerodynamic model: its builder's own estimate ([`crate::aero::WingBuilder::footprint`];
//!   the DLM's influence matrices, `crate::aero::dlm::dlm_bytes`);
//! - gust grid: 600 bytes per frequency point per mode for an analysis, 1 200 with gradients
//!   (0.64 GB at 100 000 points, 6 modes, gradients).

use super::{Study, StudyError};

/// Environment variable that sets the memory a run may take, in GB.
pub const MEMORY_LIMIT_ENV: &str = "GUSTKIT_MEMORY_LIMIT_GB";

/// The memory a run may take by default, GB: half of this 24 GB machine, which other jobs share.
pub const DEFAULT_MEMORY_LIMIT_GB: f64 = 12.0;

/// The most speeds of a p-k sweep (each costs a few eigensolutions per mode; beyond this the
/// sweep would run for hours and resolve nothing more than a refined crossing already does).
pub const MAX_FLUTTER_POINTS: usize = 10_000;

/// The most points of the gust frequency grid (the PSD integral converges long before).
pub const MAX_GUST_POINTS: usize = 1_000_000;

/// The memory limit in GB: `GUSTKIT_MEMORY_LIMIT_GB` when set (a positive number), else the
/// default.
pub fn memory_limit_gb() -> Result<f64, String> {
    match std::env::var(MEMORY_LIMIT_ENV) {
        Ok(v) => match v.trim().parse::<f64>() {
            Ok(gb) if gb > 0.0 && gb.is_finite() => Ok(gb),
            _ => Err(format!(
                "{MEMORY_LIMIT_ENV} = '{v}': must be a positive number of GB"
            )),
        },
        Err(_) => Ok(DEFAULT_MEMORY_LIMIT_GB),
    }
}

/// Refuses an allocation of `bytes` described by `what` (outside a study: a command's own
/// input) when it exceeds the memory limit.
pub fn check_bytes(what: &str, bytes: f64) -> Result<(), String> {
    let limit_gb = memory_limit_gb()?;
    if bytes / 1e9 <= limit_gb {
        return Ok(());
    }
    Err(format!(
        "{what} needs about {} of memory, {}",
        gb(bytes / 1e9),
        over_limit(limit_gb)
    ))
}

/// The end of every refusal: the limit, where it comes from, what to do.
fn over_limit(limit_gb: f64) -> String {
    format!("above the limit of {limit_gb} GB (this machine has 24 GB shared with other jobs; {MEMORY_LIMIT_ENV} sets the limit): make it smaller")
}

/// One large allocation of a run: what it is, the field that sizes it, and its bytes.
#[derive(Clone, Debug, PartialEq)]
pub struct Footprint {
    pub what: String,
    pub path: String,
    pub bytes: f64,
}

/// Bytes of the dense plate eigenproblem with `nodes` nodes.
pub fn plate_bytes(nodes: usize) -> f64 {
    700.0 * (nodes as f64).powi(2)
}

pub use crate::aero::dlm::dlm_bytes;

/// Bytes of the gust response on `points` frequencies with `modes` modes.
pub fn gust_bytes(points: usize, modes: usize, gradients: bool) -> f64 {
    let per = if gradients { 1200.0 } else { 600.0 };
    per * points as f64 * modes.max(1) as f64
}

/// Refuses `footprints` (all alive at once, `copies` times over: cases run in parallel) when they
/// exceed the memory limit; the error names the field of the largest.
pub fn check(
    study: &Study,
    footprints: &[Footprint],
    copies: usize,
    context: &str,
) -> Result<(), StudyError> {
    let limit_gb = memory_limit_gb().map_err(|r| study.err(".", r))?;
    let total_gb = copies.max(1) as f64 * footprints.iter().map(|f| f.bytes).sum::<f64>() / 1e9;
    if total_gb <= limit_gb {
        return Ok(());
    }
    let largest = footprints
        .iter()
        .max_by(|a, b| a.bytes.total_cmp(&b.bytes))
        .expect("a run over the limit has a footprint");
    let copies_note = if copies > 1 {
        format!(" ({copies} cases at once)")
    } else {
        String::new()
    };
    // the whole run's figure only where it says more than the largest part's
    let whole = if copies > 1 || total_gb > 1.05 * largest.bytes / 1e9 {
        format!("; {context}{copies_note} would take about {}", gb(total_gb))
    } else {
        String::new()
    };
    Err(study.err(
        &largest.path,
        format!(
            "{} needs about {} of memory{whole}, {}",
            largest.what,
            gb(largest.bytes / 1e9),
            over_limit(limit_gb)
        ),
    ))
}

/// A memory size in GB with sensible digits (`0.31 GB`, `44 000 GB`).
fn gb(v: f64) -> String {
    if v < 10.0 {
        format!("{v:.2} GB")
    } else if v < 1e6 {
        format!("{v:.0} GB")
    } else {
        format!("{v:.1e} GB")
    }
}

impl Study {
    /// The large allocations of one evaluation of this study (with gradients when it optimizes).
    pub fn memory_footprints(&self, gradients: bool) -> Vec<Footprint> {
        let st = &self.spec.structure;
        let (nx, ny) = (
            st.mesh.chordwise.saturating_mul(st.mesh.refine),
            st.mesh.spanwise.saturating_mul(st.mesh.refine),
        );
        let nodes = nx.saturating_add(1).saturating_mul(ny.saturating_add(1));
        let mut out = vec![Footprint {
            what: format!(
                "the dense modal analysis of the plate's {nodes} nodes ({nx} × {ny} elements)"
            ),
            path: "structure.mesh.refine".into(),
            bytes: plate_bytes(nodes),
        }];
        if let Some(aero) = &self.spec.aero {
            let n_k = aero.reduced_frequencies.len();
            // the fidelity's own estimate, for the threads it will run on
            let builder = aero.fidelity.builder();
            let sizing = crate::aero::Sizing {
                n_k,
                gradients,
                threads: rayon::current_num_threads(),
            };
            if let Some(f) = builder.footprint(&sizing) {
                out.push(Footprint {
                    what: f.what,
                    path: format!("aero.fidelity.{}.{}", builder.name(), f.path),
                    bytes: f.bytes,
                });
            }
        }
        if let Some(g) = &self.spec.gust {
            out.push(Footprint {
                what: format!(
                    "the gust response on {} frequencies with {} modes",
                    g.points,
                    self.max_modes()
                ),
                path: "gust.points".into(),
                bytes: gust_bytes(g.points, self.max_modes(), gradients),
            });
        }
        out
    }

    /// Refuses the study when one evaluation (`copies` at once) would exceed the memory limit.
    pub fn check_memory(&self, copies: usize) -> Result<(), StudyError> {
        let gradients = self.spec.optimization.is_some();
        let context = if gradients {
            "an optimization step"
        } else {
            "the analysis"
        };
        check(self, &self.memory_footprints(gradients), copies, context)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The estimates reproduce the measurements they were fitted to within a factor of 1.5 from
    /// above (an estimate may only err on the safe side, and not by orders of magnitude).
    #[test]
    fn estimates_cover_the_measurements() {
        for (estimate, measured) in [
            (plate_bytes(1681), 1.864e9),
            (plate_bytes(961), 0.619e9),
            (dlm_bytes(1536, 11, false), 0.823e9),
            (dlm_bytes(864, 11, true), 0.786e9),
            (gust_bytes(100_000, 6, true), 0.637e9),
            (gust_bytes(100_000, 12, false), 0.618e9),
        ] {
            assert!(
                estimate >= 0.75 * measured && estimate <= 1.5 * measured,
                "{estimate:.3e} vs {measured:.3e}"
            );
        }
    }
}
