//! The CFD fidelity's settings and builders: the scheme (order, limiter), the built-in airfoil
//! O-mesh and mesh files with their boundary markers, and the LFD model of a 2-D section (steady
//! Euler flow converged on the built-in mesh about a scaled NACA 64A0xx). Every closed set of
//! strings in a CFD spec is a serde enum, so a typo is refused with its JSON path at load.

mod artifacts;
mod mesh_source;
mod scratch;
mod section;
mod settings;
mod steady_cache;

pub use artifacts::*;
pub use mesh_source::*;
pub use section::*;
pub use settings::*;
pub use steady_cache::*;

use super::contract::{
    BuildError, Capabilities, SurfaceBinding, WingBuilder, WingContext, WingFidelity,
};
use crate::wing::{N_PLANFORM, PLANFORM_NAMES};
use anyhow::{Context, Result};
use gustkit_cfd::airfoil::AirfoilShape;
use gustkit_cfd::forward_store::ForwardStorage;
use gustkit_cfd::ilu::{IluOrdering, IluParams, IluPrecision};
use gustkit_cfd::lfd::{LfdOperator, LfdParams, Preconditioner};
use gustkit_cfd::lfd_model::Lfd;
use gustkit_cfd::mesh::{Boundary, Mesh};
use gustkit_cfd::mesh_sensitivity::MeshTangent;
use gustkit_cfd::residual::{free_stream, Euler, Limiter, Order};
use gustkit_cfd::steady::NewtonLinearSolver;
use gustkit_cfd::steady::SteadyParams;
use gustkit_cfd::wing_mesh::{SectionCell, WingMesh, WingMeshSpec};
use gustkit_core::scalar::Dual;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The LFD fidelity of a wing study: `aero.fidelity: {"lfd": {...}}`. Every field has a default,
/// so `{"lfd": {}}` is the coarse built-in mesh at second order with block ILU(1) of the
/// first-order Jacobian in reverse Cuthill–McKee order.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct LfdWingSpec {
    /// The built-in mesh level: "coarse" (default), "medium" or "fine".
    #[serde(default)]
    pub mesh: WingMeshLevel,
    /// Explicit mesh sizes instead of the level.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh_sizes: Option<WingMeshSizes>,
    /// An external 3-D mesh (SU2 or Gmsh) instead of the built-in one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh_file: Option<WingMeshFile>,
    #[serde(default)]
    pub order: OrderSpec,
    #[serde(default)]
    pub limiter: LimiterSpec,
    #[serde(default)]
    pub preconditioner: LfdPreconditionerSpec,
    /// Fill level k of the block ILU(k) preconditioners (0 to 3; ignored by the LU ones).
    #[serde(default = "default_ilu_fill")]
    pub ilu_fill: usize,
    /// The ILU's elimination order: "rcm" (reverse Cuthill–McKee) or "natural" (the mesh's).
    #[serde(default)]
    pub ilu_ordering: IluOrderingSpec,
    /// The precision the ILU factors are stored in: "single" (the default: half the memory;
    /// the GMRES converges on the exact operator to its tolerance either way) or "double".
    /// Absent: single, not written back (a study's serialized form fingerprints partial results
    /// and checkpoints).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ilu_precision: Option<IluPrecisionSpec>,
    /// Where the forward LFD solutions of a GAF table wait for its reverse sweep: "disk" (the
    /// default: scratch files in the system's temporary folder, `TMPDIR`, 80 bytes a cell per
    /// reduced frequency and column off the process's memory, read back bit for bit) or
    /// "memory". Absent: disk, not written back.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub forward_solutions: Option<ForwardSolutionsSpec>,
    /// GMRES stops at ‖A q̂ + b‖ ≤ tolerance ‖b‖.
    #[serde(default = "default_gmres_tolerance")]
    pub gmres_tolerance: f64,
    /// GMRES restarts after this many iterations (its basis: restart + 1 vectors of 80 bytes a
    /// cell a right-hand side in flight). 40 by default: on the medium mesh (1 thread, 12
    /// right-hand sides at k = 0.5, interleaved runs) as fast as 80 in 6 % more iterations, and
    /// 0.15–0.3 GB lighter; at M = 0.954 the same time and GAFs within 4e-9.
    #[serde(default = "default_gmres_restart")]
    pub gmres_restart: usize,
    #[serde(default = "default_gmres_max")]
    pub gmres_max_iterations: usize,
    /// The right-hand sides of one reduced frequency (the modes and the gust, or their
    /// adjoints) are solved by GMRES in lockstep batches of this many: each step applies the
    /// operator and the ILU to the whole batch, reading their matrices once for all of it, and
    /// each column keeps its own GMRES basis (restart + 1 vectors of 80 bytes a cell), so the
    /// memory a thread grows with the batch. The answers are those of one at a time, bit for
    /// bit. Absent: 1 (not written back: a study's serialized form fingerprints partial results).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gmres_batch: Option<usize>,
    /// Mode shapes reach the volume mesh by inverse-distance weighting blended to zero at this
    /// many root chords from the wall.
    #[serde(default = "default_deform_radius")]
    pub deform_radius_chords: f64,
    /// The most memory the model may take, GB (refused before anything is allocated).
    #[serde(default = "default_memory_limit")]
    pub memory_limit_gb: f64,
    /// The most Newton iterations of the steady solve (transonic cases on finer meshes need
    /// more than the default 60).
    #[serde(default = "default_steady_iterations")]
    pub steady_max_iterations: usize,
    /// `gustkit run` writes the LFD amplitudes at this reduced frequency (one of
    /// `aero.reduced_frequencies`) of every mode and the gust at the initial design for
    /// ParaView: `lfd_mode<i>_k<k>.vtk`, `lfd_gust_k<k>.vtk` (pressure, C_p and velocity, real
    /// and imaginary parts).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub amplitude_fields_k: Option<f64>,
    /// In a run (an optimization's designs), the GMRES solves of a design start from the
    /// combination of the LFD solutions of this many previous designs that minimizes the
    /// residual (1: the last design's alone); each costs 40 bytes a cell per reduced frequency
    /// and column, forward and adjoint. Absent: [`gustkit_cfd::lfd_model::DEFAULT_WARM_DESIGNS`]
    /// (not written back then, so a study's serialized form, which fingerprints partial results,
    /// does not change with this key's arrival).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub warm_start_designs: Option<usize>,
}

impl LfdWingSpec {
    /// How many right-hand sides GMRES solves in one lockstep batch (the key, or 1).
    pub fn gmres_batch(&self) -> usize {
        self.gmres_batch.unwrap_or(1)
    }

    /// How many designs' solutions the warm start combines (the key, or its default).
    pub fn warm_start_designs(&self) -> usize {
        self.warm_start_designs
            .unwrap_or(gustkit_cfd::lfd_model::DEFAULT_WARM_DESIGNS)
    }
}

/// The most right-hand sides [`LfdWingSpec::gmres_batch`] may put in one batch (a frequency
/// of the flagship has 12).
const MAX_GMRES_BATCH: usize = 64;

/// The most designs [`LfdWingSpec::warm_start_designs`] may keep (more span little more).
const MAX_WARM_DESIGNS: usize = 8;

/// Bytes a cell of one design in the GMRES warm-start store of a run, forward and adjoint
/// solutions in single precision (40 B a cell each) for the flagship's table: 11 reduced
/// frequencies, 11 modes and the gust (12 forward columns, 11 adjoints).
const WARM_DESIGN_BYTES_PER_CELL: f64 = 40.0 * 11.0 * (12.0 + 11.0);

fn default_gmres_tolerance() -> f64 {
    1e-8
}

fn default_gmres_restart() -> usize {
    40
}

fn default_gmres_max() -> usize {
    800
}

fn default_deform_radius() -> f64 {
    5.0
}

/// The build error of a steady solve that failed: one that ran out of Newton iterations points
/// at the key that raises them, with how far the residual fell (the whole history follows).
fn steady_failure(err: gustkit_cfd::steady::SteadyError, limit: usize) -> BuildError {
    match &err {
        gustkit_cfd::steady::SteadyError::NoConvergence { history, .. } => {
            let first = history.first().copied().unwrap_or(f64::NAN);
            let last = history.last().copied().unwrap_or(f64::NAN);
            BuildError {
                path: "steady_max_iterations".into(),
                reason: format!(
                    "the steady state did not converge in {limit} Newton iterations (the residual fell from {first:.3e} to {last:.3e}, {:.1} decades): raise steady_max_iterations (transonic cases on the medium mesh need about 250); {err}",
                    (first / last).log10()
                ),
            }
        }
        _ => BuildError {
            path: String::new(),
            reason: format!("steady state did not converge: {err}"),
        },
    }
}

fn default_steady_iterations() -> usize {
    60
}

fn default_memory_limit() -> f64 {
    12.0
}

impl LfdWingSpec {
    /// The wing mesh sizes of the spec.
    pub fn mesh_spec(&self) -> WingMeshSpec {
        match &self.mesh_sizes {
            Some(m) => WingMeshSpec {
                n_around: m.n_around,
                n_radial: m.n_radial,
                n_span: m.n_span,
                n_outboard: m.n_outboard,
                far_field_chords: m.far_field_chords,
                first_spacing_chords: m.first_spacing_chords,
                tip_closure: m.tip_closure,
            },
            None => WingMeshSpec::level(self.mesh.name()).expect("built-in level"),
        }
    }

    /// Bytes per cell of the LFD wing model on `threads` threads (each works on one frequency
    /// at a time, with its factorization and one right-hand side's GMRES basis), from its parts:
    /// shared by the threads, the mesh, geometry, states and deformation, the exact second-order
    /// Jacobian (25 blocks a row, 5.2 kB) and the preconditioner's first-order blocks (10 kB
    /// in all: 7.5 kB covered the medium mesh, the fine one measured 9.9 kB above the per-thread
    /// part), and with `forward_solutions: "memory"` the forward solutions of one GAF table
    /// kept for the reverse sweep (11 k × 7 columns × 80 B, 6.2 kB); per thread the block
    /// ILU(k) of one frequency (6.9 blocks a row for ILU(0) and the fill blocks of ILU(k), the
    /// diagonal's inverse among them: 25 complex numbers each, 200 B in single precision or
    /// 400 B in double, and a 4-byte column), the GMRES bases of one batch of right-hand sides
    /// (`gmres_batch` × (restart + 1) complex vectors of 5 unknowns; the preconditioned vectors
    /// are not kept) and the
    /// frequency's right-hand sides and dual-number geometry (3 kB). 27.8 kB a cell on 2 threads
    /// at the defaults (restart 40, ILU(1) in single precision, forward solutions on disk).
    /// Measured (the whole process's peak): the medium wing mesh (57 344 cells, 2 threads,
    /// 6 modes, `gustkit gafs`) 1.44 GB (25.1 kB a cell) at the defaults and 1.75 GB (30.4 kB)
    /// with restart 80 (estimates 1.59 and 1.96 GB); the fine one (458 752 cells) 8.61 GB on
    /// 1 thread with restart 40 (18.8 kB a cell, estimate 8.67 GB) and 15.5 GB on 2 threads with
    /// restart 80 (33.8 kB, estimate 15.7 GB).
    fn bytes_per_cell(&self, threads: usize) -> f64 {
        let threads = threads.max(1) as f64;
        // the blocks a row of ILU(k) (measured on the medium wing mesh: 6.9, 12.7, 22.1 and
        // 33.2 for ILU(0) to ILU(3))
        let ilu_blocks = [6.9, 12.7, 22.1, 33.2][self.ilu_fill.min(3)];
        let block = if self.single_precision_ilu() {
            200.0
        } else {
            400.0
        } + 4.0;
        let forward = match self.forward_solutions.unwrap_or_default() {
            ForwardSolutionsSpec::Disk => 0.0,
            ForwardSolutionsSpec::Memory => 6.2e3,
        };
        10e3 + forward
            + threads
                * (ilu_blocks * block
                    + 16.0
                    + self.gmres_batch() as f64 * (self.gmres_restart as f64 + 1.0) * 5.0 * 16.0
                    + 3e3)
    }

    /// Whether the ILU's factors are stored in single precision (the default).
    fn single_precision_ilu(&self) -> bool {
        self.ilu_precision.unwrap_or_default() == IluPrecisionSpec::Single
    }

    /// The memory the model would take, GB.
    /// (on the threads of the pool it will run on: rayon's current pool).
    pub fn memory_estimate_gb(&self) -> f64 {
        self.mesh_spec().n_cells() as f64 * self.bytes_per_cell(rayon::current_num_threads()) / 1e9
    }

    fn params(&self) -> LfdParams {
        LfdParams {
            tolerance: self.gmres_tolerance,
            restart: self.gmres_restart,
            max_iterations: self.gmres_max_iterations,
            batch: self.gmres_batch(),
            ilu: IluParams {
                fill: self.ilu_fill,
                ordering: match self.ilu_ordering {
                    IluOrderingSpec::Rcm => IluOrdering::ReverseCuthillMckee,
                    IluOrderingSpec::Natural => IluOrdering::Natural,
                },
                precision: if self.single_precision_ilu() {
                    IluPrecision::Single
                } else {
                    IluPrecision::Double
                },
            },
        }
    }
}

impl WingBuilder for LfdWingSpec {
    fn name(&self) -> &'static str {
        "lfd"
    }

    fn check_mach(&self, mach: f64) -> Result<(), String> {
        if !(mach > 0.0 && mach < 1.0) {
            return Err(format!(
                "the LFD needs a subsonic free stream, 0 < M < 1 (got {})",
                crate::units::show(mach)
            ));
        }
        Ok(())
    }

    fn capabilities(&self) -> Capabilities {
        // the mode shapes by adjoint LFD solves, the planform through the mesh tangents
        // (not for an external mesh: its nodes do not move with the planform)
        Capabilities {
            reverse: true,
            reverse_planform: self.mesh_file.is_none(),
        }
    }

    fn validate(&self, wing: &WingContext) -> Result<(), BuildError> {
        let fail = |path: &str, reason: String| BuildError {
            path: path.into(),
            reason,
        };
        let mesh = self.mesh_spec();
        mesh.validate().map_err(|(field, reason)| {
            let path = if self.mesh_sizes.is_some() {
                format!("mesh_sizes.{field}")
            } else {
                "mesh".into()
            };
            fail(&path, reason)
        })?;
        if let Some(file) = &self.mesh_file {
            if self.mesh_sizes.is_some() {
                return Err(fail(
                    "mesh_file",
                    "give mesh_file or mesh_sizes, not both".into(),
                ));
            }
            if let Err(e) = std::fs::metadata(&file.path) {
                return Err(fail(
                    "mesh_file.path",
                    format!("cannot read {}: {e}", file.path),
                ));
            }
        }
        // a count of 1 to `max` `what`
        let count = |key: &str, got: usize, max: usize, what: &str| match (1..=max).contains(&got) {
            true => Ok(()),
            false => Err(fail(key, format!("must be 1 to {max} {what} (got {got})"))),
        };
        count(
            "gmres_batch",
            self.gmres_batch(),
            MAX_GMRES_BATCH,
            "right-hand sides solved together",
        )?;
        self.params()
            .ilu
            .validate()
            .map_err(|r| fail("ilu_fill", r))?;
        self.params()
            .validate()
            .map_err(|r| fail("gmres_tolerance", r))?;
        count(
            "warm_start_designs",
            self.warm_start_designs(),
            MAX_WARM_DESIGNS,
            "previous designs",
        )?;
        if self.steady_max_iterations == 0 {
            return Err(fail(
                "steady_max_iterations",
                "must be at least 1 (got 0)".into(),
            ));
        }
        if !(self.deform_radius_chords > 0.0 && self.deform_radius_chords.is_finite()) {
            return Err(fail(
                "deform_radius_chords",
                format!("must be positive (got {})", self.deform_radius_chords),
            ));
        }
        self.check_mach(wing.flight.mach)
            .map_err(|reason| fail("", format!("flight.mach: {reason}")))?;
        let gb = self.memory_estimate_gb();
        // (an external mesh's size is known once it is read: checked by `build`)
        if self.mesh_file.is_none() && !(gb <= self.memory_limit_gb) {
            return Err(fail(
                if self.mesh_sizes.is_some() {
                    "mesh_sizes"
                } else {
                    "mesh"
                },
                format!(
                    "the {} mesh ({} cells) needs about {gb:.1} GB, above memory_limit_gb = {} (this machine has 24 GB shared with other jobs): choose a coarser mesh or raise the limit",
                    if self.mesh_sizes.is_some() { "given" } else { self.mesh.name() },
                    mesh.n_cells(),
                    self.memory_limit_gb
                ),
            ));
        }
        Ok(())
    }

    fn validate_gradients(&self, wing: &WingContext) -> Result<(), BuildError> {
        self.validate(wing)?;
        let cells = self.mesh_spec().n_cells();
        let gb = self.memory_estimate_gb()
            + (gustkit_cfd::adjoint::LfdReverse::estimate_bytes(cells, rayon::current_num_threads())
                as f64
                + self.warm_start_designs() as f64 * WARM_DESIGN_BYTES_PER_CELL * cells as f64)
                / 1e9;
        if self.mesh_file.is_none() && !(gb <= self.memory_limit_gb) {
            return Err(BuildError {
                path: if self.mesh_sizes.is_some() {
                    "mesh_sizes".into()
                } else {
                    "mesh".into()
                },
                reason: format!(
                    "gradients on the {} mesh ({cells} cells) need about {gb:.1} GB with the reverse mode's Jacobians and the warm start's {} designs, above memory_limit_gb = {}: choose a coarser mesh, fewer warm_start_designs or raise the limit",
                    if self.mesh_sizes.is_some() { "given" } else { self.mesh.name() },
                    self.warm_start_designs(),
                    self.memory_limit_gb
                ),
            });
        }
        Ok(())
    }

    fn build(&self, wing: &WingContext) -> Result<WingFidelity, BuildError> {
        self.validate(wing)?;
        // the steady state is reused from `wing.cache_dir` when the mesh, the section, the
        // planform, the Mach number and the discretization are those it was solved for
        let fail = |reason: String| BuildError {
            path: String::new(),
            reason,
        };
        let p = wing.planform.to_array();
        let file_fail = |reason: String| BuildError {
            path: "mesh_file.path".into(),
            reason,
        };
        // the built-in mesh, or the external one (no planform tangents, no C_p sections)
        let (volume, built_in) = match &self.mesh_file {
            Some(file) => {
                let m = file.read().map_err(file_fail)?;
                m.check()
                    .map_err(|e| file_fail(format!("{}: invalid mesh: {e}", file.path)))?;
                let gb = m.n_cells as f64 * self.bytes_per_cell(rayon::current_num_threads()) / 1e9;
                if !(gb <= self.memory_limit_gb) {
                    return Err(file_fail(format!(
                        "{} ({} cells) needs about {gb:.1} GB, above memory_limit_gb = {}: choose a coarser mesh or raise the limit",
                        file.path, m.n_cells, self.memory_limit_gb
                    )));
                }
                (m, None)
            }
            None => {
                let wm = WingMesh::new(p, &|x| wing.airfoil.half_thickness(x), &self.mesh_spec());
                wm.mesh
                    .check()
                    .map_err(|e| fail(format!("the built-in wing mesh is invalid: {e}")))?;
                (wm.mesh.clone(), Some(wm))
            }
        };
        let mut e = Euler::new(volume.clone(), free_stream(wing.flight.mach, 0.0));
        e.order = self.order.order();
        e.limiter = self.limiter.limiter();
        // the LFD's ILU settings serve the Newton steps too (medium mesh: 65 s with ILU(0) in
        // the mesh's order, 30 s with ILU(1) in RCM order, 12 Newton iterations either way)
        let params = SteadyParams {
            linear_solver: NewtonLinearSolver::BlockIlu,
            ilu: self.params().ilu,
            max_iterations: self.steady_max_iterations,
            ..SteadyParams::default()
        };
        let cache = wing.cache_dir.map(|d| self.steady_file(wing, d));
        let q0 = match cache.as_deref().and_then(|f| converged_state(&e, f)) {
            Some(q) => q,
            None => {
                let free_stream = || vec![e.q_inf; e.mesh.n_cells];
                let from_guess = |q| e.solve_steady_from_guess(q, &params);
                // from the previous design's state; else, on the built-in mesh, from the steady
                // state of the mesh with half the cells in each direction (itself started the
                // same way): mesh sequencing, which converges transonic cases on the finer levels
                // in a few Newton iterations where the free-stream start needs hundreds; from the
                // free stream should those fail
                let warm = previous_state(&e, cache.as_deref())
                    .and_then(from_guess)
                    .or_else(|| {
                        let spec = self.mesh_spec();
                        let coarse = spec.halved().filter(|_| built_in.is_some())?;
                        let flow = gustkit_cfd::steady::WingFlow {
                            planform: wing.planform.to_array(),
                            half_thickness: &|x| wing.airfoil.half_thickness(x),
                            mach: wing.flight.mach,
                            order: self.order.order(),
                            limiter: self.limiter.limiter(),
                        };
                        let q = gustkit_cfd::steady::sequenced_wing_state(&flow, &coarse, &params)?;
                        from_guess(spec.prolong(&coarse, &q))
                    });
                let (q, _) = match warm {
                    Some(solved) => solved,
                    None => e
                        .solve_steady(free_stream(), &params)
                        .map_err(|err| steady_failure(err, self.steady_max_iterations))?,
                };
                if let Some(f) = &cache {
                    // a cache that cannot be written costs the next run a steady solve, no more
                    let _ = save_state(f, &q);
                }
                q
            }
        };
        let mut op = LfdOperator::with_preconditioner(e, q0, self.preconditioner.preconditioner());
        op.params = self.params();
        let mut model = Lfd::new(
            op,
            1.0,
            1.0,
            self.deform_radius_chords * wing.planform.root_chord,
        );
        // the designs of one run (one run folder) start their GMRES from the previous design's
        // solutions
        model.warm_start = wing.cache_dir.map(steady_cache::warm_start_store);
        model.forward_storage = match self.forward_solutions.unwrap_or_default() {
            ForwardSolutionsSpec::Disk => ForwardStorage::Spill(std::sync::Arc::new(
                scratch::ScratchFolder(std::env::temp_dir()),
            )),
            ForwardSolutionsSpec::Memory => ForwardStorage::Memory,
        };
        if let Some(w) = &model.warm_start {
            let mut w = w.lock().unwrap_or_else(|e| e.into_inner());
            w.designs = self.warm_start_designs();
            // a store read from a resumed run's file is used only on its own mesh
            if let Err(why) = w.fits(model.lfd.n()) {
                println!("{why}");
            }
        }
        let Some(mesh) = built_in else {
            // an external mesh: its wall nodes placed on the planform, or why they do not fit
            let unit = self
                .mesh_file
                .as_ref()
                .map_or(MeshUnit::M, |f| f.length_unit);
            let wall: Vec<[f64; 3]> = model
                .wall_nodes()
                .iter()
                .map(|&n| volume.nodes[n])
                .collect();
            let points = planform_coordinates(wing.planform, &wall, unit).map_err(|r| {
                file_fail(format!(
                    "{}: {r}",
                    self.mesh_file.as_ref().map_or("", |f| f.path.as_str())
                ))
            })?;
            return Ok(WingFidelity {
                model: Box::new(model),
                binding: SurfaceBinding {
                    points,
                    geometry_jacobian: Vec::new(),
                },
            });
        };
        let points = model
            .wall_nodes()
            .iter()
            .map(|&n| mesh.parametric(n))
            .collect();
        let mut model = model;
        // C_p at the root, mid-span and tip sections among its artifacts (the report draws them)
        model.sections = wall_sections(&mesh);
        if wing.fixed_planform {
            return Ok(WingFidelity {
                model: Box::new(model),
                binding: SurfaceBinding {
                    points,
                    geometry_jacobian: Vec::new(),
                },
            });
        }
        // the planform variables move the mesh (and the deformation radius, a multiple of the
        // root chord): their tangents, for the reverse mode's geometry gradient
        let pd: [Dual<N_PLANFORM>; N_PLANFORM] = std::array::from_fn(|k| Dual::var(p[k], k));
        let xd = mesh.nodes_at(pd);
        model.tangents = (0..N_PLANFORM)
            .map(|k| MeshTangent {
                name: PLANFORM_NAMES[k].to_string(),
                nodes: xd.iter().map(|x| x.map(|v| v.d[k])).collect(),
                radius: if k == 2 {
                    self.deform_radius_chords
                } else {
                    0.0
                },
            })
            .collect();
        let geometry_jacobian = (0..N_PLANFORM)
            .map(|k| std::array::from_fn(|j| if j == k { 1.0 } else { 0.0 }))
            .collect();
        Ok(WingFidelity {
            model: Box::new(model),
            binding: SurfaceBinding {
                points,
                geometry_jacobian,
            },
        })
    }
}

/// Moves an LFD spec to the next mesh: the built-in level above (coarse → medium → fine, each
/// 2× finer in every direction) or explicit sizes doubled the same way (the first spacing
/// halved); returns its words. An external mesh has no next level, nor has the fine one.
fn next_mesh(l: &mut LfdWingSpec) -> Result<String, String> {
    if l.mesh_file.is_some() {
        return Err("an external LFD mesh (mesh_file) has no next level to check it on: check it with a finer mesh file of your own".into());
    }
    if let Some(m) = &mut l.mesh_sizes {
        m.n_around *= 2;
        m.n_radial *= 2;
        m.n_span *= 2;
        m.n_outboard *= 2;
        m.first_spacing_chords /= 2.0;
        return Ok(format!(
            "LFD mesh sizes doubled ({} cells)",
            l.mesh_spec().n_cells()
        ));
    }
    l.mesh = match l.mesh {
        WingMeshLevel::Coarse => WingMeshLevel::Medium,
        WingMeshLevel::Medium => WingMeshLevel::Fine,
        WingMeshLevel::Fine => {
            return Err("the LFD runs on the fine mesh, the finest built-in level: there is no next level to check it on".into())
        }
    };
    Ok(format!(
        "LFD {} mesh ({} cells)",
        l.mesh.name(),
        l.mesh_spec().n_cells()
    ))
}

impl LfdWingSpec {
    /// The next resolution for the resolution check (the next mesh level) and its words, or why
    /// there is none.
    pub fn refined(&self) -> Result<(Self, String), String> {
        let mut l = self.clone();
        let words = next_mesh(&mut l)?;
        Ok((l, words))
    }

    /// The model in words: its mesh and cell count.
    pub fn words(&self) -> String {
        if self.mesh_file.is_some() {
            return "LFD on the external mesh".into();
        }
        format!(
            "LFD {} mesh ({} cells)",
            if self.mesh_sizes.is_some() {
                "given"
            } else {
                self.mesh.name()
            },
            self.mesh_spec().n_cells()
        )
    }
}
