//! The LFD fidelity behind the shared [`Aerodynamics`] trait: structure-on-structure GAFs from the
//! mode-motion LFD (paper Eqs. 7–9) and gust-on-structure GAFs from the gust LFD (Eqs. 12–15), one
//! factorization per reduced frequency for all right-hand sides, frequencies in parallel; and its
//! reverse mode with respect to the mode shapes (adjoint LFD solves with the same factorization,
//! see [`crate::adjoint`]).
//!
//! Frames and units: the CFD mesh is non-dimensional (lengths in mesh units, ρ∞ = 1, a∞ = 1) with
//! y up and, for 2-D sections, z along the extrusion; the trait's frame has z up and y along the
//! span, so a vector (x, y, z) of the trait is (x, z, y) on the mesh. Mode shapes reach the wall
//! nodes in metres and are spread through the mesh by [`Deformation`]. Forces scale by
//! ρ∞ a∞² · `area_m2` (m² per mesh area unit: for a 2-D section per unit span, chord scale /
//! mesh thickness).

use crate::adjoint::LfdReverse;
use crate::deform::Deformation;
use crate::forward_store::{ForwardSolutions, ForwardStorage, Solution};
use crate::gas::primitive;
use crate::lfd::{Factored, Guess, HarmonicGust, LfdError, LfdOperator, Symbol};
use crate::mesh::{Boundary, Side};
use crate::mesh_sensitivity::{Column, MeshTangent, SweptFace};
use crate::wing_mesh::SectionCell;
use gustkit_core::aero::check_request;
use gustkit_core::{
    AeroError, AeroSurface, Aerodynamics, AerodynamicsReverse, FlightCondition, GafGradient,
    GafTable, ModalSurface, SolverFailure,
};
use num_complex::Complex64 as C64;
use rayon::prelude::*;
use std::borrow::Cow;

/// The LFD aerodynamic model of a converged steady flow.
pub struct Lfd {
    pub lfd: LfdOperator,
    deform: Deformation,
    surface: AeroSurface,
    /// Metres per mesh length unit.
    pub length_m: f64,
    /// Square metres per mesh area unit.
    pub area_m2: f64,
    /// Free-stream Mach number of the steady state.
    pub mach: f64,
    /// The reverse mode's Jacobians, assembled at the first gradient (about 11 kB a cell, so a
    /// model that only supplies GAFs never pays for them).
    reverse: std::sync::OnceLock<LfdReverse>,
    /// The mesh motions of the geometry parameters (the builder's planform variables), whose
    /// derivatives the reverse mode gives in [`GafGradient::geometry`]; none for a fixed mesh.
    pub tangents: Vec<MeshTangent>,
    /// The forward solutions of the last GAF table, reused by a reverse sweep at the same point.
    last_forward: std::sync::Mutex<Option<ForwardCache>>,
    /// Where the forward solutions are kept between a table and its reverse sweep (memory by
    /// default; scratch files take their 80 bytes a cell per frequency and column off the
    /// process's memory).
    pub forward_storage: ForwardStorage,
    /// Chordwise wall sections whose steady C_p the model reports among its artifacts (a
    /// built-in wing mesh's root, mid-span and tip, say): (η of the section, its wall cells).
    pub sections: Vec<(f64, Vec<SectionCell>)>,
    /// The LFD solutions of the last GAF table of this model or of the models sharing the store
    /// (the previous designs of an optimization), which start the next table's GMRES; none by
    /// default (every table from zero).
    pub warm_start: Option<std::sync::Arc<std::sync::Mutex<WarmStart>>>,
}

/// The solutions of one design's GAF table (or reverse sweep), single precision: per reduced
/// frequency, one per column.
type KeptDesign = Vec<(f64, Vec<Vec<num_complex::Complex32>>)>;

/// How many designs' solutions a [`WarmStart`] keeps by default: the last three span a line
/// search's trial points and the step before (see [`crate::lfd::combined_guess`]).
pub const DEFAULT_WARM_DESIGNS: usize = 3;

/// The LFD solutions of the last few GAF tables, per reduced frequency and column (the modes,
/// then the gust), kept as GMRES initial guesses for the next table on a mesh of the same size:
/// consecutive designs of an optimization differ little, and the combination of the last few
/// solutions that minimizes the residual follows a design that moves along a line. Single
/// precision (a guess needs no more): 40 bytes a cell per (design, k, column), 5.3 kB a cell a
/// design for 11 k and 12 columns. A store of another size (another mesh) is not used, and is
/// replaced.
#[derive(Debug)]
pub struct WarmStart {
    /// Length of each solution (cells × 5).
    n: usize,
    /// The last designs' tables, newest first.
    tables: Vec<KeptDesign>,
    /// The last reverse sweeps' adjoint solutions (one per mode, of its generalized force),
    /// newest first.
    adjoints: Vec<KeptDesign>,
    /// How many designs to keep (at least one).
    pub designs: usize,
    /// GMRES iterations of the last table.
    pub last_iterations: usize,
    /// GMRES iterations of the last reverse sweep's adjoint solves.
    pub last_adjoint_iterations: usize,
    /// Right-hand sides of the last table and of the last reverse sweep's adjoint solves.
    pub last_rhs: usize,
    pub last_adjoint_rhs: usize,
    /// The file this store was read from, until a model of a mesh checks that it fits (see
    /// [`WarmStart::fits`]).
    pub from_file: Option<std::path::PathBuf>,
}

impl Default for WarmStart {
    fn default() -> Self {
        Self {
            n: 0,
            tables: Vec::new(),
            adjoints: Vec::new(),
            designs: DEFAULT_WARM_DESIGNS,
            last_iterations: 0,
            last_adjoint_iterations: 0,
            last_rhs: 0,
            last_adjoint_rhs: 0,
            from_file: None,
        }
    }
}

impl WarmStart {
    /// Whether the kept solutions fit a mesh of `n` unknowns (cells × 5). A store read from a
    /// file of another mesh is emptied here (keeping its `designs`) and the reason returned once,
    /// for the caller to say; a store that grew in this process fits or is replaced by
    /// [`WarmStart::keep`] as before.
    pub fn fits(&mut self, n: usize) -> Result<(), String> {
        let Some(file) = self.from_file.take() else {
            return Ok(());
        };
        if self.n == 0 || self.n == n {
            return Ok(());
        }
        let reason = format!(
            "{}: GMRES guesses of another mesh ({} cells; this mesh has {}): not used",
            file.display(),
            self.n / crate::gas::NVAR,
            n / crate::gas::NVAR
        );
        *self = WarmStart {
            designs: self.designs,
            ..Default::default()
        };
        Err(reason)
    }

    /// The guesses for reduced frequency `k`, per column the kept designs' solutions (none where
    /// this store holds another mesh's).
    fn guesses(&self, k: f64, n: usize) -> Vec<Vec<Guess<'_>>> {
        Self::find(&self.tables, self.n, k, n)
    }

    /// The adjoint guesses for reduced frequency `k`, per mode.
    fn adjoint_guesses(&self, k: f64, n: usize) -> Vec<Vec<Guess<'_>>> {
        Self::find(&self.adjoints, self.n, k, n)
    }

    /// The designs kept (tables, reverse sweeps).
    pub fn kept_designs(&self) -> (usize, usize) {
        (self.tables.len(), self.adjoints.len())
    }

    /// One frequency's solutions in single precision, and their GMRES iterations.
    fn single(solved: &[Solution]) -> (Vec<Vec<num_complex::Complex32>>, usize) {
        let iterations = solved.iter().map(|(_, i)| i.iterations).sum();
        let single = solved
            .iter()
            .map(|(x, _)| {
                x.iter()
                    .map(|v| num_complex::Complex32::new(v.re as f32, v.im as f32))
                    .collect()
            })
            .collect();
        (single, iterations)
    }

    /// Keeps the solutions of a table (`adjoint`: of a reverse sweep) per reduced frequency, in
    /// single precision ([`WarmStart::single`]), for a mesh of `n` unknowns (another mesh's are
    /// dropped), as the newest of the last [`WarmStart::designs`], with their GMRES iterations.
    fn keep(&mut self, n: usize, kept: KeptDesign, iterations: usize, adjoint: bool) {
        if self.n != n {
            self.tables.clear();
            self.adjoints.clear();
        }
        self.n = n;
        let designs = self.designs.max(1);
        let rhs = kept.iter().map(|(_, x)| x.len()).sum();
        let list = if adjoint {
            self.last_adjoint_iterations = iterations;
            self.last_adjoint_rhs = rhs;
            &mut self.adjoints
        } else {
            self.last_iterations = iterations;
            self.last_rhs = rhs;
            &mut self.tables
        };
        list.truncate(designs - 1);
        list.insert(0, kept);
    }

    /// Per column, the solutions at reduced frequency `k` of the kept designs, newest first.
    fn find(designs: &[KeptDesign], stored_n: usize, k: f64, n: usize) -> Vec<Vec<Guess<'_>>> {
        let mut columns: Vec<Vec<Guess>> = Vec::new();
        if stored_n != n {
            return columns;
        }
        for design in designs {
            let Some((_, solutions)) = design
                .iter()
                .find(|(kk, _)| gustkit_core::aero::same_k(*kk, k))
            else {
                continue;
            };
            if columns.len() < solutions.len() {
                columns.resize_with(solutions.len(), Vec::new);
            }
            for (c, x) in columns.iter_mut().zip(solutions) {
                c.push(x.as_slice());
            }
        }
        columns
    }
}

mod warm_file;

/// The file name of the steady flow field among an LFD model's artifacts (legacy VTK).
pub const STEADY_FLOW_FILE: &str = "steady_lfd_flow.vtk";

/// The stem of the steady C_p sections among an LFD model's artifacts (CSV: eta, x_c, side, cp).
pub const CP_SECTIONS_STEM: &str = "steady_cp_sections";

/// Steady C_p of the wall cells of `sections`: (η, [(wall cell, C_p)] around the contour).
pub fn section_pressures(
    sections: &[(f64, Vec<SectionCell>)],
    q: &[crate::residual::State<f64>],
    mach: f64,
) -> Vec<(f64, Vec<(SectionCell, f64)>)> {
    sections
        .iter()
        .map(|(eta, cells)| {
            let cp = cells
                .iter()
                .map(|&c| (c, crate::gas::pressure_coefficient(&q[c.cell], mach)))
                .collect();
            (*eta, cp)
        })
        .collect()
}

/// [`section_pressures`] as CSV: a header `eta,x_c,side,cp`, then one row a wall cell.
pub fn section_pressures_csv(sections: &[(f64, Vec<(SectionCell, f64)>)]) -> String {
    let mut csv = String::from("eta,x_c,side,cp\n");
    for (eta, cells) in sections {
        for (c, cp) in cells {
            let side = if c.upper { "upper" } else { "lower" };
            csv.push_str(&format!("{eta:.6},{:.6},{side},{cp:.8e}\n", c.x_c));
        }
    }
    csv
}

/// The LFD solutions of one GAF table and what they were solved for.
struct ForwardCache {
    flight: FlightCondition,
    modes: ModalSurface,
    k: Vec<f64>,
    /// Per reduced frequency: the mode columns, then the gust.
    solutions: ForwardSolutions,
}

/// Complex node displacements (mesh frame, mesh units).
type NodeField = Vec<[C64; 3]>;

/// An LFD solver failure at reduced frequency `k` as the shared contract's typed error: the
/// right-hand sides are the `n_modes` mode motions, then the gust.
fn solver_error(e: LfdError, k: f64, n_modes: usize) -> AeroError {
    match e {
        LfdError::Gmres { rhs, source, .. } => AeroError::Solver {
            k,
            rhs: if rhs < n_modes {
                format!("mode {}", rhs + 1)
            } else {
                "gust".into()
            },
            failure: SolverFailure {
                reason: format!(
                    "GMRES stalled at relative residual {:.3e} (wanted {:.1e}) after {} iterations",
                    source.reached, source.wanted, source.iterations
                ),
                history: source.history,
            },
        },
        LfdError::Factor { reason, .. } => AeroError::Solver {
            k,
            rhs: "preconditioner".into(),
            failure: SolverFailure {
                reason,
                history: Vec::new(),
            },
        },
        LfdError::Input(reason) => AeroError::Input(reason),
    }
}

/// An adjoint LFD failure at `k`: the right-hand sides are the adjoints of the `n_modes`
/// modes' generalized forces (one per mode, whatever the seeds).
fn adjoint_error(e: LfdError, k: f64, n_modes: usize) -> AeroError {
    let rhs_index = match &e {
        LfdError::Gmres { rhs, .. } => Some(*rhs),
        _ => None,
    };
    match (solver_error(e, k, usize::MAX), rhs_index) {
        (AeroError::Solver { k, failure, .. }, Some(i)) if i < n_modes => AeroError::Solver {
            k,
            rhs: format!("adjoint of mode {}'s generalized force", i + 1),
            failure,
        },
        (other, _) => other,
    }
}

/// A trait-frame vector on the mesh and back (the swap is its own inverse).
fn swap_yz(v: [f64; 3]) -> [f64; 3] {
    [v[0], v[2], v[1]]
}

impl Lfd {
    /// The model of `lfd` (steady state converged), with the mesh deformation blended out at
    /// `deform_radius` mesh units from the wall.
    pub fn new(lfd: LfdOperator, length_m: f64, area_m2: f64, deform_radius: f64) -> Self {
        let e = &lfd.euler;
        let deform = Deformation::new(&e.mesh, deform_radius);
        // outward body normal at each wall node: minus the mean of its faces' area vectors (they
        // point from the fluid into the body)
        let mut normals = vec![[0.0; 3]; deform.wall_nodes.len()];
        let index: std::collections::HashMap<usize, usize> = deform
            .wall_nodes
            .iter()
            .enumerate()
            .map(|(i, &n)| (n, i))
            .collect();
        for (fi, f) in e.mesh.faces.iter().enumerate() {
            if f.right == Side::Boundary(Boundary::Wall) {
                for n in &f.nodes {
                    for k in 0..3 {
                        normals[index[n]][k] -= e.areas[fi][k];
                    }
                }
            }
        }
        let surface = AeroSurface {
            points: deform
                .wall_nodes
                .iter()
                .map(|&n| swap_yz(e.mesh.nodes[n].map(|v| v * length_m)))
                .collect(),
            normals: normals
                .iter()
                .map(|v| {
                    let a = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                    swap_yz(v.map(|x| x / a))
                })
                .collect(),
        };
        let q = &e.q_inf;
        let w = primitive(q);
        let mach = w.vel[0].hypot(w.vel[1]).hypot(w.vel[2]) / crate::gas::sound_speed(&w);
        Self {
            lfd,
            deform,
            surface,
            length_m,
            area_m2,
            mach,
            reverse: std::sync::OnceLock::new(),
            tangents: Vec::new(),
            last_forward: std::sync::Mutex::new(None),
            forward_storage: ForwardStorage::Memory,
            sections: Vec::new(),
            warm_start: None,
        }
    }

    /// Each mode's wall-node displacements in the mesh's frame and units (what the deformation
    /// spreads).
    fn wall_motion(&self, modes: &ModalSurface) -> Vec<Vec<[f64; 3]>> {
        let l = self.length_m;
        modes
            .disp
            .iter()
            .map(|d| d.iter().map(|v| swap_yz(*v).map(|x| x / l)).collect())
            .collect()
    }

    /// The node displacements of each mode: mesh units (complex) for the LFD, and metres (mesh
    /// frame) for the projection of the forces.
    fn mode_motion(&self, modes: &ModalSurface) -> (Vec<NodeField>, Vec<Vec<[f64; 3]>>) {
        let l = self.length_m;
        let walls = self.wall_motion(modes);
        let walls: Vec<&[[f64; 3]]> = walls.iter().map(Vec::as_slice).collect();
        let x_hat: Vec<Vec<[C64; 3]>> = self
            .deform
            .apply_many(&walls)
            .iter()
            .map(|x| x.iter().map(|p| p.map(|v| C64::new(v, 0.0))).collect())
            .collect();
        let shapes = x_hat
            .iter()
            .map(|x| x.iter().map(|p| p.map(|v| v.re * l)).collect())
            .collect();
        (x_hat, shapes)
    }

    /// One frequency's GAF column parts from its LFD solutions (the modes', then the gust's):
    /// Q_ss[i][j] and Q_gs[i], mode i's generalized force of column j in GAF units.
    fn project(
        &self,
        sol: &[Solution],
        x_hat: &[NodeField],
        shapes: &[Vec<[f64; 3]>],
        scale: f64,
    ) -> (Vec<Vec<C64>>, Vec<C64>) {
        let n = x_hat.len();
        let mut q_ss = vec![vec![C64::new(0.0, 0.0); n]; n];
        for (j, (q, _)) in sol[..n].iter().enumerate() {
            let g = self.lfd.generalized_forces(q, Some(&x_hat[j]), shapes);
            for i in 0..n {
                q_ss[i][j] = g[i] * scale;
            }
        }
        let q_gs = self
            .lfd
            .generalized_forces(&sol[n].0, None, shapes)
            .iter()
            .map(|g| g * scale)
            .collect();
        (q_ss, q_gs)
    }

    /// GAF units per non-dimensional generalized force: 2 × area / M² (forces in ρ∞ a∞² times
    /// mesh area, divided by q∞ = ρ∞ U² / 2).
    fn force_scale(&self) -> f64 {
        2.0 * self.area_m2 / (self.mach * self.mach)
    }

    /// The factored preconditioner at reduced frequency `kk` and the LFD solutions of every mode
    /// motion and of the unit gust (last).
    fn forward(
        &self,
        flight: &FlightCondition,
        kk: f64,
        x_hat: &[NodeField],
    ) -> Result<(Factored, Vec<Solution>), AeroError> {
        self.forward_from(flight, kk, x_hat, &[])
    }

    /// [`Lfd::forward`] with GMRES initial guesses per column (`guesses[j]`: none, or previous
    /// designs' solutions).
    fn forward_from(
        &self,
        flight: &FlightCondition,
        kk: f64,
        x_hat: &[NodeField],
        guesses: &[Vec<Guess>],
    ) -> Result<(Factored, Vec<Solution>), AeroError> {
        let (l, m) = (self.length_m, self.mach);
        // the unit gust w_g/U = 1 is a vertical velocity M in units of a∞
        let gust = HarmonicGust {
            convection: m,
            x0: flight.x_ref / l,
        };
        let omega = kk * m * l / flight.b_ref;
        let f = self
            .lfd
            .factor(omega, Symbol::Exact)
            .map_err(|e| solver_error(e, kk, x_hat.len()))?;
        let mut rhs: Vec<Vec<C64>> = x_hat.iter().map(|x| self.lfd.motion_rhs(f.s, x)).collect();
        rhs.push(
            self.lfd
                .gust_rhs(omega, &gust)
                .iter()
                .map(|v| v * m)
                .collect(),
        );
        let sol = self
            .lfd
            .solve_from(&f, &rhs, guesses)
            .map_err(|e| solver_error(e, kk, x_hat.len()))?;
        Ok((f, sol))
    }

    /// Per geometry tangent: the steady tangent δq₀ and, per mode, the tangent δx̂ of its spread
    /// displacements (mesh units) as the mesh and the deformation radius move.
    #[allow(clippy::type_complexity)]
    fn geometry_tangents(
        &self,
        modes: &ModalSurface,
    ) -> Result<Vec<(Vec<f64>, Vec<NodeField>)>, AeroError> {
        let mesh = &self.lfd.euler.mesh;
        let d_nodes: Vec<&[[f64; 3]]> = self.tangents.iter().map(|t| t.nodes.as_slice()).collect();
        let dq0 = self
            .lfd
            .steady_tangents(&d_nodes)
            .map_err(|e| solver_error(e, 0.0, 0))?;
        let walls = self.wall_motion(modes);
        let walls: Vec<&[[f64; 3]]> = walls.iter().map(Vec::as_slice).collect();
        Ok(self
            .tangents
            .iter()
            .zip(dq0)
            .map(|(t, dq0)| {
                let nodes: Vec<[gustkit_core::scalar::Dual<1>; 3]> = mesh
                    .nodes
                    .iter()
                    .zip(&t.nodes)
                    .map(|(p, d)| {
                        std::array::from_fn(|k| gustkit_core::scalar::Dual::new(p[k], [d[k]]))
                    })
                    .collect();
                let radius = gustkit_core::scalar::Dual::new(self.deform.radius, [t.radius]);
                let dx: Vec<NodeField> = self
                    .deform
                    .apply_at_many(&nodes, radius, &walls)
                    .iter()
                    .map(|x| x.iter().map(|p| p.map(|v| C64::new(v.d[0], 0.0))).collect())
                    .collect();
                (dq0, dx)
            })
            .collect())
    }

    /// The mode motions' swept face volumes for every batch of [`TANGENT_BATCH`] geometry
    /// tangents (indexed batch, then mode; the last batch padded like the sweep's): they do not
    /// depend on the frequency, so a reverse sweep computes them once, in parallel over the modes, and every
    /// frequency's column tangents reuse them (about a third of their work on the coarse wing
    /// mesh). Memory: faces × modes × 80 B a batch.
    fn swept_per_batch(
        &self,
        x_hat: &[NodeField],
        geometry: &[(Vec<f64>, Vec<NodeField>)],
    ) -> Vec<Vec<Vec<SweptFace<TANGENT_BATCH>>>> {
        let n_geo = geometry.len();
        (0..n_geo)
            .step_by(TANGENT_BATCH)
            .map(|start| {
                let ds = tangent_batch(start, n_geo);
                x_hat
                    .par_iter()
                    .enumerate()
                    .map(|(j, x)| {
                        self.lfd.swept_volumes(
                            x,
                            ds.map(|d| geometry[d].1[j].as_slice()),
                            ds.map(|d| self.tangents[d].nodes.as_slice()),
                        )
                    })
                    .collect()
            })
            .collect()
    }

    /// The scaled gust face fluxes at reduced frequency `kk` and their tangent along `t`.
    fn gust_flux_tangent(
        &self,
        flight: &FlightCondition,
        kk: f64,
        t: &MeshTangent,
    ) -> (Vec<C64>, Vec<C64>) {
        let (l, m) = (self.length_m, self.mach);
        let omega = kk * m * l / flight.b_ref;
        let e = &self.lfd.euler;
        let nodes: Vec<[gustkit_core::scalar::Dual<1>; 3]> = e
            .mesh
            .nodes
            .iter()
            .zip(&t.nodes)
            .map(|(p, d)| std::array::from_fn(|k| gustkit_core::scalar::Dual::new(p[k], [d[k]])))
            .collect();
        e.harmonic_gust_fluxes_at(&nodes, omega, m, flight.x_ref / l)
            .iter()
            .map(|v| {
                (
                    C64::new(v[0].v, v[1].v) * m,
                    C64::new(v[0].d[0], v[1].d[0]) * m,
                )
            })
            .unzip()
    }

    /// The factored preconditioner at reduced frequency `kk`.
    fn factor_at(
        &self,
        flight: &FlightCondition,
        kk: f64,
        n_modes: usize,
    ) -> Result<Factored, AeroError> {
        let omega = kk * self.mach * self.length_m / flight.b_ref;
        self.lfd
            .factor(omega, Symbol::Exact)
            .map_err(|e| solver_error(e, kk, n_modes))
    }

    /// The reverse mode's Jacobians, assembled at the first call (∂R/∂x not kept: the sweep
    /// applies it once, recomputed, to the adjoints summed over the frequencies).
    pub fn reverse_linearizations(&self) -> &LfdReverse {
        self.reverse
            .get_or_init(|| LfdReverse::recomputing(&self.lfd))
    }

    /// The mesh nodes of the surface points, in the order of [`Aerodynamics::surface`].
    pub fn wall_nodes(&self) -> &[usize] {
        &self.deform.wall_nodes
    }

    fn check(
        &self,
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: &[f64],
    ) -> Result<(), AeroError> {
        check_request(flight, modes, k, self.surface.points.len())?;
        if (flight.mach - self.mach).abs() > 1e-6 * self.mach.max(1.0) {
            return Err(AeroError::Input(format!(
                "mach: the LFD steady state was converged at Mach {}, the flight condition asks for {}",
                self.mach, flight.mach
            )));
        }
        if !(self.mach > 0.0) {
            return Err(AeroError::Input(
                "mach: the LFD needs a moving free stream".into(),
            ));
        }
        Ok(())
    }
}

impl Aerodynamics for Lfd {
    fn surface(&self) -> &AeroSurface {
        &self.surface
    }

    fn geometry_names(&self) -> Vec<String> {
        self.tangents.iter().map(|t| t.name.clone()).collect()
    }

    fn gafs(
        &self,
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: &[f64],
    ) -> Result<GafTable, AeroError> {
        self.check(flight, modes, k)?;
        let (x_hat, shapes) = self.mode_motion(modes);
        let scale = self.force_scale();
        let n = self.lfd.n();
        let warm = self
            .warm_start
            .as_ref()
            .map(|w| w.lock().unwrap_or_else(|e| e.into_inner()));
        // the frequencies in rounds of one a thread: the factorizations and right-hand sides
        // of one round only are held at once; each frequency's solutions are projected, copied
        // for the warm start and stored (in memory or a file) as its round ends
        // the last table's solutions are for another point: let them go before this table's
        // arrive (not held beside them)
        *self.last_forward.lock().unwrap_or_else(|e| e.into_inner()) = None;
        let mut solved = ForwardSolutions::new(&self.forward_storage);
        let mut parts = Vec::with_capacity(k.len());
        let (mut kept, mut iterations) = (Vec::new(), 0);
        for round in k.chunks(rayon::current_num_threads().max(1)) {
            let part: Result<Vec<_>, AeroError> = round
                .par_iter()
                .map(|&kk| {
                    let guesses = warm.as_ref().map(|w| w.guesses(kk, n)).unwrap_or_default();
                    let sol = self.forward_from(flight, kk, &x_hat, &guesses)?.1;
                    let gafs = self.project(&sol, &x_hat, &shapes, scale);
                    Ok((sol, gafs))
                })
                .collect();
            for ((sol, gafs), &kk) in part?.into_iter().zip(round) {
                if self.warm_start.is_some() {
                    let (single, i) = WarmStart::single(&sol);
                    kept.push((kk, single));
                    iterations += i;
                }
                parts.push(gafs);
                solved.push(sol).map_err(AeroError::Input)?;
            }
        }
        drop(warm);
        if let Some(w) = &self.warm_start {
            let mut w = w.lock().unwrap_or_else(|e| e.into_inner());
            w.keep(n, kept, iterations, false);
        }
        let table = GafTable::from_parts(flight, k, parts);
        // kept for a reverse sweep at the same point (the pipeline's gradient follows its function)
        *self.last_forward.lock().unwrap_or_else(|e| e.into_inner()) = Some(ForwardCache {
            flight: *flight,
            modes: modes.clone(),
            k: k.to_vec(),
            solutions: solved,
        });
        Ok(table)
    }

    fn reverse(&self) -> Option<&dyn AerodynamicsReverse> {
        Some(self)
    }

    fn amplitude_fields(&self, k: f64, title: &str) -> Vec<(String, String)> {
        let cache = self.last_forward.lock().unwrap_or_else(|e| e.into_inner());
        let Some(c) = cache.as_ref() else {
            return Vec::new();
        };
        let Some(i) =
            c.k.iter()
                .position(|kk| (kk - k).abs() <= 1e-12 * k.abs().max(1.0))
        else {
            return Vec::new();
        };
        let solutions = match c.solutions.get(i) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("warning: no LFD amplitude fields at k = {k}: {e}");
                return Vec::new();
            }
        };
        let n = solutions.len();
        solutions
            .iter()
            .enumerate()
            .map(|(j, (q_hat, _))| {
                let (stem, what) = if j + 1 == n {
                    (
                        format!("lfd_gust_k{k}"),
                        "the unit gust w_g/U = 1".to_string(),
                    )
                } else {
                    (
                        format!("lfd_mode{}_k{k}", j + 1),
                        format!("mode {} at unit modal coordinate", j + 1),
                    )
                };
                let text = crate::vtk::amplitude_vtk(
                    &self.lfd.euler.mesh,
                    &self.lfd.q0,
                    q_hat,
                    self.mach,
                    &format!("{title}: LFD amplitudes of {what}, k = {k} (rho_inf = a_inf = 1)"),
                );
                (stem, text)
            })
            .collect()
    }

    /// The steady flow field for ParaView (ρ, p, C_p, Mach, velocity per cell) and, where the
    /// model has sections, their C_p (the run's report draws them).
    fn artifacts(&self, title: &str) -> Vec<(String, String)> {
        let e = &self.lfd.euler;
        let mut files = vec![(
            STEADY_FLOW_FILE.to_string(),
            crate::vtk::flow_vtk(
                &e.mesh,
                &self.lfd.q0,
                self.mach,
                &format!("{title}: steady Euler flow at M = {}", self.mach),
            ),
        )];
        if !self.sections.is_empty() {
            let cp = section_pressures(&self.sections, &self.lfd.q0, self.mach);
            files.push((
                format!("{CP_SECTIONS_STEM}.csv"),
                section_pressures_csv(&cp),
            ));
        }
        files
    }

    fn linearization_checks(&self) -> Vec<gustkit_core::LinearizationCheck> {
        crate::adjoint::linearization_table(
            &self.lfd,
            self.reverse_linearizations(),
            &self.deform,
            7,
        )
    }
}

/// One seed's gradient parts at one frequency: per mode, on every mesh node (mesh frame), the
/// seed from the force projection (per metre of shape) and from the mode motion (per mesh unit).
type NodeSeeds = (Vec<Vec<[f64; 3]>>, Vec<Vec<[f64; 3]>>);

impl AerodynamicsReverse for Lfd {
    /// The adjoint of the GAFs with respect to the mode shapes at the wall nodes and, along the
    /// model's mesh tangents, the geometry parameters (see [`crate::adjoint`] and
    /// [`crate::mesh_sensitivity`]). Per frequency: the forward solutions of the GAF table (kept
    /// from the last one at this point, else solved), then per mode i the adjoint LFD solve
    /// (s V + ∂R/∂q)ᵀ μ_i = F_qᵀ u_i with u_i = scale · φ̄_i on the wall faces (mode i's
    /// generalized force), and for every seed and mode j the shape seed Re(F_xᵀ u_j − Bᵀ λ_j)
    /// with u_j = Σ_i conj(Q̄_ij) u_i and λ_j = Σ_i conj(Q̄_ij) μ_i, carried back through the
    /// mesh deformation; the projection's own seed Re(conj(Q̄) · scale · f̂) goes to the
    /// projecting mode. One factorization per frequency serves the forward and the adjoint
    /// solves; the adjoint solves are one a mode whatever the number of seeds.
    fn gafs_vjp(
        &self,
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: &[f64],
        seed: &GafTable,
    ) -> Result<GafGradient, AeroError> {
        let mut g = self.gafs_vjp_many(flight, modes, k, std::slice::from_ref(seed))?;
        Ok(g.pop().expect("one seed, one gradient"))
    }

    fn gafs_vjp_many(
        &self,
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: &[f64],
        seeds: &[GafTable],
    ) -> Result<Vec<GafGradient>, AeroError> {
        self.check(flight, modes, k)?;
        let nm = modes.n_modes();
        if seeds.is_empty() {
            return Ok(Vec::new());
        }
        gustkit_core::aero::check_seeds(seeds, k.len(), nm)?;
        let (x_hat, shapes) = self.mode_motion(modes);
        // the geometry directions: steady tangents δq₀ and the spread shapes' tangents δx̂
        let geometry = self.geometry_tangents(modes)?;
        let swept = self.swept_per_batch(&x_hat, &geometry);
        // the forward solutions of the last GAF table, when it was this one (taken out of the
        // cache for the sweep and put back after it, not copied)
        let cached: Option<ForwardCache> = {
            let mut last = self.last_forward.lock().unwrap_or_else(|e| e.into_inner());
            match last.as_ref() {
                Some(c) if c.flight == *flight && c.k == k && c.modes == *modes => last.take(),
                _ => None,
            }
        };
        let sweep = SeedSweep {
            model: self,
            rev: self.reverse_linearizations(),
            flight,
            face_shape: self.face_means(&shapes),
            geometry,
            swept,
            x_hat,
            scale: self.force_scale(),
            nm,
            n_cols: if self.tangents.is_empty() { nm } else { nm + 1 },
        };
        let n = self.lfd.n();
        let warm = self
            .warm_start
            .as_ref()
            .map(|w| w.lock().unwrap_or_else(|e| e.into_inner()));
        // the frequencies in rounds of one a thread, each round's node seeds added to the sums
        // in the frequencies' order (deterministic) before the next round starts: one round's
        // factorizations, adjoint solutions and node seeds are held at once
        let mut sum = FrequencySum::new(seeds.len(), nm, self.lfd.euler.mesh.nodes.len());
        let mut adjoints = Vec::with_capacity(k.len());
        let mut adjoint_iterations = 0;
        let indices: Vec<usize> = (0..k.len()).collect();
        let mut result = Ok(());
        for round in indices.chunks(rayon::current_num_threads().max(1)) {
            let swept: Result<Vec<(PerFrequency, Vec<Solution>)>, AeroError> = round
                .par_iter()
                .map(|&ik| {
                    let kk = k[ik];
                    let (f, sol): (Factored, Cow<[Solution]>) = match cached.as_ref() {
                        Some(c) => (
                            self.factor_at(flight, kk, nm)?,
                            c.solutions.get(ik).map_err(AeroError::Input)?,
                        ),
                        None => {
                            let (f, s) = self.forward(flight, kk, &sweep.x_hat)?;
                            (f, Cow::Owned(s))
                        }
                    };
                    let guesses = warm
                        .as_ref()
                        .map(|w| w.adjoint_guesses(kk, n))
                        .unwrap_or_default();
                    sweep.at_frequency(ik, kk, f, &sol, seeds, &guesses)
                })
                .collect();
            match swept {
                Ok(swept) => {
                    for ((part, lambda), &ik) in swept.into_iter().zip(round) {
                        sum.add(part);
                        if self.warm_start.is_some() {
                            let (single, i) = WarmStart::single(&lambda);
                            adjoints.push((k[ik], single));
                            adjoint_iterations += i;
                        }
                    }
                }
                Err(e) => {
                    result = Err(e);
                    break;
                }
            }
        }
        drop(warm);
        if let Some(c) = cached {
            *self.last_forward.lock().unwrap_or_else(|e| e.into_inner()) = Some(c);
        }
        result?;
        if let Some(w) = &self.warm_start {
            let mut w = w.lock().unwrap_or_else(|e| e.into_inner());
            w.keep(n, adjoints, adjoint_iterations, true);
        }
        sum.add_positions(sweep.rev, &self.lfd);
        Ok(self.finish_gradients(sum, nm))
    }
}

/// One frequency's part of the reverse sweep: per seed, the node seeds of every mode (from the
/// force projection, per metre of shape, and from the mode motion's terms in s, per mesh unit),
/// the geometry gradient, and the adjoint of every mode column λ_j = Σ_i c_ij μ_i (whose
/// ∂R/∂xᵀ λ_j, the same at every frequency, is applied once to their sum).
type PerFrequency = (Vec<NodeSeeds>, Vec<Vec<f64>>, Vec<Vec<Vec<C64>>>);

/// The reverse sweep's parts summed over the frequencies: per seed, the node seeds of every
/// mode, the geometry gradient, and the mode columns' adjoints.
struct FrequencySum {
    nodes: Vec<NodeSeeds>,
    geometry: Vec<Vec<f64>>,
    adjoints: Vec<Vec<Vec<C64>>>,
}

impl FrequencySum {
    fn new(n_seeds: usize, nm: usize, n_nodes: usize) -> Self {
        Self {
            nodes: (0..n_seeds)
                .map(|_| {
                    (
                        vec![vec![[0.0; 3]; n_nodes]; nm],
                        vec![vec![[0.0; 3]; n_nodes]; nm],
                    )
                })
                .collect(),
            geometry: vec![Vec::new(); n_seeds],
            adjoints: vec![Vec::new(); n_seeds],
        }
    }

    /// Adds one frequency's part (in the frequencies' order: the sums are deterministic).
    fn add(&mut self, (nodes, geometry, adjoints): PerFrequency) {
        for (acc, part) in self.nodes.iter_mut().zip(nodes) {
            for (a, p) in acc
                .0
                .iter_mut()
                .zip(&part.0)
                .chain(acc.1.iter_mut().zip(&part.1))
            {
                for (x, y) in a.iter_mut().zip(p) {
                    for c in 0..3 {
                        x[c] += y[c];
                    }
                }
            }
        }
        for (acc, g) in self.geometry.iter_mut().zip(geometry) {
            if acc.is_empty() {
                acc.resize(g.len(), 0.0);
            }
            for (a, v) in acc.iter_mut().zip(g) {
                *a += v;
            }
        }
        for (acc, part) in self.adjoints.iter_mut().zip(adjoints) {
            if acc.is_empty() {
                *acc = part;
                continue;
            }
            for (a, p) in acc.iter_mut().zip(part) {
                for (x, y) in a.iter_mut().zip(p) {
                    *x += y;
                }
            }
        }
    }

    /// The mode motions' frequency-independent term, −Re ∂R/∂xᵀ Σ_k λ_j, into every seed's
    /// motion seeds: one recomputing pass of ∂R/∂x for all seeds and modes, the adjoints'
    /// sums dropped after it.
    fn add_positions(&mut self, rev: &LfdReverse, lfd: &LfdOperator) {
        let adjoints = std::mem::take(&mut self.adjoints);
        let ws: Vec<&[C64]> = adjoints.iter().flatten().map(|w| w.as_slice()).collect();
        if ws.is_empty() {
            return;
        }
        let moved = rev.position_transpose(lfd, &ws);
        drop(ws);
        drop(adjoints);
        let mut moved = moved.into_iter();
        for (_, motion) in &mut self.nodes {
            for m in motion.iter_mut() {
                let p = moved.next().expect("one field a seed and mode");
                for (x, y) in m.iter_mut().zip(&p) {
                    for c in 0..3 {
                        x[c] -= y[c].re;
                    }
                }
            }
        }
    }
}

/// What the reverse sweep of one GAF table shares across its frequencies.
struct SeedSweep<'a> {
    model: &'a Lfd,
    rev: &'a LfdReverse,
    flight: &'a FlightCondition,
    /// The spread mode motions (mesh units).
    x_hat: Vec<NodeField>,
    /// φ̄_i on each wall face: the mean of its nodes' shapes (metres, mesh frame).
    face_shape: Vec<Vec<[f64; 3]>>,
    /// Per geometry tangent: δq₀ and the δx̂ of every mode.
    geometry: Vec<(Vec<f64>, Vec<NodeField>)>,
    /// Per batch of tangents and mode, the faces' swept volumes (frequency-independent).
    swept: Vec<Vec<Vec<SweptFace<TANGENT_BATCH>>>>,
    scale: f64,
    nm: usize,
    /// Adjoint columns a seed: the modes, and the gust where the geometry needs it.
    n_cols: usize,
}

impl SeedSweep<'_> {
    /// The reverse sweep at reduced frequency `kk` (index `ik`) with its factorization and the
    /// forward solutions: the projection's seeds, one adjoint solve (sᵀV + ∂R/∂q)ᵀ μ_i = F_qᵀ u_i
    /// per mode i with u_i = scale · φ̄_i (mode i's generalized force), and from them, for every
    /// seed, the geometry gradient and the motion seeds. A column's adjoint is a combination of
    /// the μ_i (λ_j = Σ_i conj(Q̄_ij) μ_i, the equations being linear), so the solves do not
    /// depend on the seeds: their number is the modes', whatever the seeds, and the previous
    /// design's μ_i start them well (their right-hand sides move only with the mode shapes).
    /// The factorization is dropped once the adjoints are solved: the geometry tangents'
    /// hyper-dual evaluations that follow never hold it beside them.
    fn at_frequency(
        &self,
        ik: usize,
        kk: f64,
        f: Factored,
        sol: &[Solution],
        seeds: &[GafTable],
        guesses: &[Vec<Guess>],
    ) -> Result<(PerFrequency, Vec<Solution>), AeroError> {
        let nm = self.nm;
        let lfd = &self.model.lfd;
        // linearized wall forces of each mode motion and of the gust
        let forces: Vec<Vec<[C64; 3]>> = (0..=nm)
            .map(|j| {
                let x = (j < nm).then(|| self.x_hat[j].as_slice());
                lfd.wall_face_forces(&sol[j].0, x)
                    .into_iter()
                    .map(|(_, v)| v)
                    .collect()
            })
            .collect();
        // u_i on the wall faces, F_qᵀ u_i (the adjoint right-hand side) and F_xᵀ u_i
        let units: Vec<Vec<[C64; 3]>> = (0..nm)
            .map(|i| self.force_seed(|m| C64::new(if m == i { 1.0 } else { 0.0 }, 0.0)))
            .collect();
        let (adjoint_rhs, direct): (Vec<Vec<C64>>, Vec<NodeField>) = units
            .iter()
            .map(|u| self.rev.wall_forces_transpose(u))
            .unzip();
        let mu = self
            .rev
            .solve_transpose_from(lfd, &f, &adjoint_rhs, guesses)
            .map_err(|e| adjoint_error(e, kk, nm))?;
        drop(adjoint_rhs);
        let s = f.s;
        drop(f);
        let coefficients: Vec<Coefficients> = seeds
            .iter()
            .map(|seed| Coefficients {
                ss: &seed.q_ss[ik],
                gs: &seed.q_gs[ik],
            })
            .collect();
        let geo = self.geometry_gradient(kk, s, sol, &mu, &units, &coefficients);
        let mut out: Vec<NodeSeeds> = coefficients
            .iter()
            .map(|c| (self.projection_seed(c.ss, c.gs, &forces), Vec::new()))
            .collect();
        self.motion_seeds(s, &mu, direct, &coefficients, &mut out);
        let columns = coefficients
            .iter()
            .map(|c| self.column_adjoints(&mu, c))
            .collect();
        Ok(((out, geo, columns), mu))
    }

    /// The seed of the force projection on the node shapes: Re(conj(Q̄_ij) scale f̂_j) on φ_i
    /// for every mode i, each face's value spread evenly over its nodes.
    fn projection_seed(
        &self,
        s_ss: &[Vec<C64>],
        s_gs: &[C64],
        forces: &[Vec<[C64; 3]>],
    ) -> Vec<Vec<[f64; 3]>> {
        let nm = self.nm;
        let mesh = &self.model.lfd.euler.mesh;
        let mut proj = vec![vec![[0.0; 3]; mesh.nodes.len()]; nm];
        for i in 0..nm {
            for (w, &fi) in self.rev.wall_faces.iter().enumerate() {
                let mut g = [0.0; 3];
                for c in 0..3 {
                    let mut acc = s_gs[i].conj() * forces[nm][w][c];
                    for j in 0..nm {
                        acc += s_ss[i][j].conj() * forces[j][w][c];
                    }
                    g[c] = acc.re * self.scale;
                }
                let nodes = &mesh.faces[fi].nodes;
                let wn = 1.0 / nodes.len() as f64;
                for &n in nodes {
                    for c in 0..3 {
                        proj[i][n][c] += g[c] * wn;
                    }
                }
            }
        }
        proj
    }

    /// The seed on a column's wall-face forces: u = Σ_i coefficient(i) · φ̄_i · scale.
    fn force_seed(&self, coefficient: impl Fn(usize) -> C64) -> Vec<[C64; 3]> {
        (0..self.rev.wall_faces.len())
            .map(|w| {
                std::array::from_fn(|c| {
                    (0..self.nm)
                        .map(|i| coefficient(i) * self.face_shape[i][w][c])
                        .sum::<C64>()
                        * self.scale
                })
            })
            .collect()
    }

    /// Per seed, the geometry gradient at one frequency: Σ_columns Re(u_jᵀ ∂f̂ − λ_jᵀ t) along
    /// each mesh tangent, where t and ∂f̂ are the column's residual and force tangents, with
    /// u_j = Σ_i c_ij u_i and λ_j = Σ_i c_ij μ_i: the products with the μ_i and u_i are taken
    /// once and combined per seed.
    fn geometry_gradient(
        &self,
        kk: f64,
        s: C64,
        sol: &[Solution],
        mu: &[Solution],
        units: &[Vec<[C64; 3]>],
        coefficients: &[Coefficients],
    ) -> Vec<Vec<f64>> {
        let tangents = &self.model.tangents;
        let n_geo = self.geometry.len();
        let mut geo = vec![vec![0.0; tangents.len()]; coefficients.len()];
        // the tangents in batches of TANGENT_BATCH, one hyper-dual evaluation a batch and column
        for start in (0..n_geo).step_by(TANGENT_BATCH) {
            let ds = tangent_batch(start, n_geo);
            for col in 0..self.n_cols {
                let gust_fluxes: Vec<(Vec<C64>, Vec<C64>)>;
                let column = if col < self.nm {
                    Column::Motion {
                        x_hat: &self.x_hat[col],
                        dx_hat: ds.map(|d| self.geometry[d].1[col].as_slice()),
                        swept: &self.swept[start / TANGENT_BATCH][col],
                    }
                } else {
                    gust_fluxes = ds
                        .iter()
                        .map(|&d| self.model.gust_flux_tangent(self.flight, kk, &tangents[d]))
                        .collect();
                    Column::Gust {
                        g: &gust_fluxes[0].0,
                        dg: std::array::from_fn(|m| gust_fluxes[m].1.as_slice()),
                    }
                };
                let batch = self.model.lfd.column_tangents(
                    s,
                    &sol[col].0,
                    &column,
                    ds.map(|d| tangents[d].nodes.as_slice()),
                    ds.map(|d| self.geometry[d].0.as_slice()),
                );
                for (m, (t, df)) in batch.iter().enumerate() {
                    if start + m >= n_geo {
                        break;
                    }
                    let d = ds[m];
                    // a_i = u_iᵀ ∂f̂ − μ_iᵀ t
                    let a: Vec<C64> = units
                        .iter()
                        .zip(mu)
                        .map(|(u, (mi, _))| {
                            let mut acc = C64::new(0.0, 0.0);
                            for (uw, fw) in u.iter().zip(df) {
                                for c in 0..3 {
                                    acc += uw[c] * fw[c];
                                }
                            }
                            for (x, y) in mi.iter().zip(t) {
                                acc -= x * y;
                            }
                            acc
                        })
                        .collect();
                    for (g, c) in geo.iter_mut().zip(coefficients) {
                        g[d] += (0..self.nm).map(|i| c.of(i, col) * a[i]).sum::<C64>().re;
                    }
                }
            }
        }
        geo
    }

    /// The mode columns' adjoints of one seed: λ_j = Σ_i c_ij μ_i.
    fn column_adjoints(&self, mu: &[Solution], c: &Coefficients) -> Vec<Vec<C64>> {
        (0..self.nm)
            .map(|j| {
                let mut lambda = vec![C64::new(0.0, 0.0); mu.first().map_or(0, |m| m.0.len())];
                for (i, (m, _)) in mu.iter().enumerate().take(self.nm) {
                    let cij = c.of(i, j);
                    for (l, x) in lambda.iter_mut().zip(m) {
                        *l += cij * x;
                    }
                }
                lambda
            })
            .collect()
    }

    /// The seeds on the mode motions, into each seed's second part: Re(F_xᵀ u_j − B_sᵀ λ_j) =
    /// Re Σ_i c_ij (F_xᵀ u_i − B_sᵀ μ_i) on every mesh node, B_s the terms of B in s (the gust
    /// column has none; the rest of B, ∂R/∂x, is applied to the λ_j summed over the
    /// frequencies: [`FrequencySum::add_positions`]).
    fn motion_seeds(
        &self,
        s: C64,
        mu: &[Solution],
        direct: Vec<NodeField>,
        coefficients: &[Coefficients],
        out: &mut [NodeSeeds],
    ) {
        // w_i = F_xᵀ u_i − Bᵀ μ_i
        let w: Vec<NodeField> = direct
            .into_iter()
            .zip(mu)
            .map(|(mut ux, (m, _))| {
                let bt = self.rev.motion_rhs_transpose_s_terms(&self.model.lfd, s, m);
                for (a, b) in ux.iter_mut().zip(&bt) {
                    for c in 0..3 {
                        a[c] -= b[c];
                    }
                }
                ux
            })
            .collect();
        let n_nodes = w.first().map_or(0, |x| x.len());
        for (seeds, c) in out.iter_mut().zip(coefficients) {
            seeds.1 = (0..self.nm)
                .map(|j| {
                    let cij: Vec<C64> = (0..self.nm).map(|i| c.of(i, j)).collect();
                    (0..n_nodes)
                        .map(|n| {
                            std::array::from_fn(|k| {
                                cij.iter()
                                    .zip(&w)
                                    .map(|(ci, wi)| ci * wi[n][k])
                                    .sum::<C64>()
                                    .re
                            })
                        })
                        .collect()
                })
                .collect();
        }
    }
}

/// Mesh tangents (geometry parameters) differentiated in one hyper-dual evaluation: the
/// planform's four.
const TANGENT_BATCH: usize = 4;

/// The tangents of the batch starting at `start` among `n_geo`: the last batch padded with
/// repeats of the last tangent, whose results are dropped.
fn tangent_batch(start: usize, n_geo: usize) -> [usize; TANGENT_BATCH] {
    std::array::from_fn(|m| (start + m).min(n_geo - 1))
}

/// One seed's coefficients at one frequency: column j's adjoint is Σ_i of(i, j) μ_i.
struct Coefficients<'a> {
    ss: &'a [Vec<C64>],
    gs: &'a [C64],
}

impl Coefficients<'_> {
    /// conj(Q̄_ij) for a mode column j, conj(Q̄_gs,i) for the gust column (j = modes).
    fn of(&self, i: usize, j: usize) -> C64 {
        if j < self.ss.len() {
            self.ss[i][j].conj()
        } else {
            self.gs[i].conj()
        }
    }
}

impl Lfd {
    /// φ̄ of every shape on each wall face of the reverse mode's force Jacobian: the mean of its nodes' values.
    fn face_means(&self, shapes: &[Vec<[f64; 3]>]) -> Vec<Vec<[f64; 3]>> {
        let mesh = &self.lfd.euler.mesh;
        let wall_faces = &self.reverse_linearizations().wall_faces;
        shapes
            .iter()
            .map(|phi| {
                wall_faces
                    .iter()
                    .map(|&fi| {
                        let nodes = &mesh.faces[fi].nodes;
                        let w = 1.0 / nodes.len() as f64;
                        std::array::from_fn(|k| nodes.iter().map(|&n| phi[n][k]).sum::<f64>() * w)
                    })
                    .collect()
            })
            .collect()
    }

    /// Every seed's gradient from its sums over the frequencies: the motion part carried to the
    /// wall through the mesh deformation's transpose.
    fn finish_gradients(&self, sum: FrequencySum, nm: usize) -> Vec<GafGradient> {
        let wall = self.wall_nodes();
        let l = self.length_m;
        // every seed's and mode's motion seed through the transpose at once (seeds, then modes)
        let motions: Vec<&[[f64; 3]]> = sum
            .nodes
            .iter()
            .flat_map(|(_, motion)| motion.iter().take(nm).map(Vec::as_slice))
            .collect();
        let mut through_mesh = self.deform.apply_transpose_many(&motions).into_iter();
        sum.nodes
            .iter()
            .zip(sum.geometry)
            .map(|((proj, _), geometry)| {
                let mut grad = ModalSurface::zeros(nm, wall.len());
                for m in 0..nm {
                    let through_mesh = through_mesh.next().expect("one a seed and mode");
                    for (w, &n) in wall.iter().enumerate() {
                        let v: [f64; 3] =
                            std::array::from_fn(|c| proj[m][n][c] + through_mesh[w][c] / l);
                        grad.disp[m][w] = swap_yz(v);
                    }
                }
                let geometry = if geometry.is_empty() {
                    vec![0.0; self.tangents.len()]
                } else {
                    geometry
                };
                GafGradient {
                    modes: grad,
                    geometry,
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::airfoil::AirfoilShape;
    use crate::residual::{free_stream, Euler, Order};
    use crate::steady::SteadyParams;
    use gustkit_core::theory::strip_gafs;

    /// A 4 %-thick section (the 64A010 ordinates scaled) at Mach `mach`, chord 1 m, per unit span.
    pub(crate) fn thin_section(n_around: usize, n_radial: usize, mach: f64, order: Order) -> Lfd {
        let mesh = AirfoilShape::naca64a010().scaled(0.4).o_mesh(
            n_around,
            n_radial,
            50.0,
            0.002 / 50.0,
            1.0,
        );
        let mut e = Euler::new(mesh, free_stream(mach, 0.0));
        e.order = order;
        let (q0, _) = e
            .solve_steady(vec![e.q_inf; e.mesh.n_cells], &SteadyParams::default())
            .unwrap();
        let mut lfd = LfdOperator::new(e, q0);
        lfd.params.tolerance = 1e-9;
        Lfd::new(lfd, 1.0, 1.0, 10.0)
    }

    /// Plunge (z up, 1 m) and pitch (nose up about mid-chord, 1 rad) of the section's wall nodes.
    pub(crate) fn rigid_modes(aero: &Lfd) -> ModalSurface {
        let pts = &aero.surface().points;
        let mut m = ModalSurface::zeros(2, pts.len());
        for (i, p) in pts.iter().enumerate() {
            m.disp[0][i] = [0.0, 0.0, 1.0];
            m.disp[1][i] = [p[2], 0.0, -p[0]];
        }
        m
    }

    /// The LFD GAFs through the trait for a 4 %-thick section at Mach 0.1 (plunge, pitch about
    /// mid-chord, gust) against Theodorsen and Sears with the Prandtl–Glauert factor on the
    /// circulatory parts: every entry within 4 % at k = 0 and 0.5 on the 64 × 32 mesh, each lift
    /// entry closer than on the 32 × 16 one. (On 128 × 64 the k = 0 entries agree to 0.1–0.6 %; at
    /// k = 0.5 they stay 0.5–3 % off, growing with Mach: 5–8 % at M = 0.3, the compressible
    /// unsteady flow that PG-scaled incompressible theory does not capture, plus thickness.)
    #[test]
    fn thin_airfoil_gafs_match_theodorsen_and_sears() {
        let mach = 0.1;
        let flight = FlightCondition {
            mach,
            velocity: 34.0,
            density: 1.2,
            b_ref: 0.5,
            x_ref: 0.0,
        };
        let ks = [0.0, 0.5];
        let mut coarse_errors = Vec::new();
        for (na, nr) in [(32, 16), (64, 32)] {
            let aero = thin_section(na, nr, mach, Order::Second);
            let t = aero.gafs(&flight, &rigid_modes(&aero), &ks).unwrap();
            for (j, &k) in ks.iter().enumerate() {
                let (ss, gs) = strip_gafs(k, 0.5, mach);
                let rel = |a: C64, b: C64| (a - b).norm() / b.norm();
                let mut errors = vec![
                    rel(t.q_ss[j][0][1], ss[0][1]),
                    rel(t.q_ss[j][1][1], ss[1][1]),
                    rel(t.q_gs[j][0], gs[0]),
                    rel(t.q_gs[j][1], gs[1]),
                ];
                if k > 0.0 {
                    errors.push(rel(t.q_ss[j][0][0], ss[0][0]));
                    errors.push(rel(t.q_ss[j][1][0], ss[1][0]));
                } else {
                    let scale = ss[0][1].norm();
                    // a static plunge moves the near mesh rigidly and deforms the far one: a
                    // force of the discretization's size only (4e-5 of the lift slope)
                    assert!(
                        t.q_ss[j][0][0].norm() < 1e-4 * scale
                            && t.q_ss[j][1][0].norm() < 1e-4 * scale
                    );
                }
                eprintln!("{na}x{nr} k = {k}: relative errors {errors:.4?}");
                if na == 32 {
                    coarse_errors.push(errors);
                } else {
                    for (e, c) in errors.iter().zip(&coarse_errors[j]) {
                        assert!(*e < 0.04, "k = {k}: {errors:?}");
                        assert!(e < c, "k = {k}: {errors:?} not below the coarse mesh's {c}");
                    }
                }
            }
        }
    }

    /// The flight condition of the reverse-mode tests: M 0.5, 1 m chord.
    fn subsonic_test_flight() -> FlightCondition {
        FlightCondition {
            mach: 0.5,
            velocity: 170.0,
            density: 1.2,
            b_ref: 0.5,
            x_ref: 0.1,
        }
    }

    /// The 4 %-thick section's O-mesh of the reverse-mode tests (32 × 12, far field 30 chords).
    fn lifting_mesh() -> crate::mesh::Mesh {
        AirfoilShape::naca64a010()
            .scaled(0.4)
            .o_mesh(32, 12, 30.0, 0.002 / 30.0, 1.0)
    }

    /// The LFD model of `mesh` at M 0.5 and 2° (second order, steady state solved, GMRES to
    /// `tolerance`, the deformation blended out at `radius` chords).
    fn lifting_section(mesh: crate::mesh::Mesh, tolerance: f64, radius: f64) -> Lfd {
        let mut e = Euler::new(mesh, free_stream(0.5, 2f64.to_radians()));
        e.order = Order::Second;
        let (q0, _) = e
            .solve_steady(vec![e.q_inf; e.mesh.n_cells], &SteadyParams::default())
            .unwrap();
        let mut lfd = LfdOperator::new(e, q0);
        lfd.params.tolerance = tolerance;
        Lfd::new(lfd, 1.0, 1.0, radius)
    }

    /// The lifting test section with the block ILU(0) preconditioner of large meshes (the exact
    /// LU needs one or two GMRES iterations from any start) and GMRES to 1e-10.
    fn ilu_section() -> Lfd {
        let mut e = Euler::new(lifting_mesh(), free_stream(0.5, 2f64.to_radians()));
        e.order = Order::Second;
        let (q0, _) = e
            .solve_steady(vec![e.q_inf; e.mesh.n_cells], &SteadyParams::default())
            .unwrap();
        let mut lfd = LfdOperator::with_preconditioner(e, q0, crate::lfd::Preconditioner::BlockIlu);
        lfd.params.tolerance = 1e-10;
        Lfd::new(lfd, 1.0, 1.0, 10.0)
    }

    /// The largest entry of table `a` (Q_ss and Q_gs) and the largest difference of `b` from it.
    fn table_difference(a: &GafTable, b: &GafTable) -> (f64, f64) {
        let (mut big, mut d) = (0.0f64, 0.0f64);
        for (qa, qb) in a
            .q_ss
            .iter()
            .flatten()
            .flatten()
            .zip(b.q_ss.iter().flatten().flatten())
        {
            big = big.max(qa.norm());
            d = d.max((qa - qb).norm());
        }
        for (qa, qb) in a.q_gs.iter().flatten().zip(b.q_gs.iter().flatten()) {
            big = big.max(qa.norm());
            d = d.max((qa - qb).norm());
        }
        (big, d)
    }

    /// A spill that keeps each frequency's columns as little-endian bytes (as a file would),
    /// counting what it holds.
    #[derive(Debug, Default)]
    struct ByteSpill {
        held: std::sync::Arc<std::sync::atomic::AtomicUsize>,
    }

    struct ByteColumns {
        bytes: Vec<u8>,
        n: usize,
        held: std::sync::Arc<std::sync::atomic::AtomicUsize>,
    }

    impl crate::forward_store::ForwardSpill for ByteSpill {
        fn put(
            &self,
            columns: &[Vec<C64>],
        ) -> Result<Box<dyn crate::forward_store::Spilled>, String> {
            let bytes = columns
                .iter()
                .flatten()
                .flat_map(|v| [v.re.to_le_bytes(), v.im.to_le_bytes()])
                .flatten()
                .collect();
            self.held.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
            Ok(Box::new(ByteColumns {
                bytes,
                n: columns[0].len(),
                held: self.held.clone(),
            }))
        }
    }

    impl crate::forward_store::Spilled for ByteColumns {
        fn read(&self) -> Result<Vec<Vec<C64>>, String> {
            let values: Vec<C64> = self
                .bytes
                .chunks(16)
                .map(|c| {
                    C64::new(
                        f64::from_le_bytes(c[..8].try_into().unwrap()),
                        f64::from_le_bytes(c[8..].try_into().unwrap()),
                    )
                })
                .collect();
            Ok(values.chunks(self.n).map(<[C64]>::to_vec).collect())
        }
    }

    impl Drop for ByteColumns {
        fn drop(&mut self) {
            self.held.fetch_sub(1, std::sync::atomic::Ordering::SeqCst);
        }
    }

    /// Forward solutions handed to a spill instead of kept in memory change no number: the
    /// table, a reverse sweep (every entry seeded, the solutions read back) and the amplitude
    /// fields are those of the memory store bit for bit; the spill holds one entry a frequency
    /// and none once the model is gone.
    #[test]
    fn spilled_forward_solutions_change_no_number() {
        let flight = subsonic_test_flight();
        let ks = [0.0, 0.4];
        let mut aero = ilu_section();
        let modes = rigid_modes(&aero);
        let seed = random_seed(&flight, &ks, 2, 5);
        let spill = std::sync::Arc::new(ByteSpill::default());
        let held = spill.held.clone();
        let count = || held.load(std::sync::atomic::Ordering::SeqCst);
        let mut runs = Vec::new();
        for storage in [ForwardStorage::Memory, ForwardStorage::Spill(spill)] {
            aero.forward_storage = storage;
            let table = aero.gafs(&flight, &modes, &ks).unwrap();
            let entries = count();
            let g = aero.gafs_vjp(&flight, &modes, &ks, &seed).unwrap();
            let fields = aero.amplitude_fields(0.4, "test");
            runs.push((table, g, fields, entries));
        }
        let ((t0, g0, f0, held0), (t1, g1, f1, held1)) = (&runs[0], &runs[1]);
        assert_eq!((*held0, *held1), (0, ks.len()));
        let bits = |t: &GafTable| -> Vec<u64> {
            let mut v = Vec::new();
            for i in 0..ks.len() {
                for row in &t.q_ss[i] {
                    v.extend(row.iter().flat_map(|c| [c.re.to_bits(), c.im.to_bits()]));
                }
                v.extend(
                    t.q_gs[i]
                        .iter()
                        .flat_map(|c| [c.re.to_bits(), c.im.to_bits()]),
                );
            }
            v
        };
        assert_eq!(bits(t0), bits(t1));
        let g_bits = |g: &GafGradient| g.modes.values().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(g_bits(g0), g_bits(g1));
        assert_eq!(f0.len(), 3);
        assert_eq!(f0, f1);
        drop(aero);
        assert_eq!(count(), 0);
    }

    /// The ILU's factors stored in single precision change the GMRES's path, not its answer:
    /// with GMRES to 1e-12 the GAF table and a reverse sweep (every entry seeded) equal those
    /// of double-precision factors to 1e-10 of their largest entries (the bound for a
    /// memory reduction), in about as many iterations (f32 round-off, 6e-8, is far below the
    /// ILU's own error as an inverse).
    #[test]
    fn single_precision_ilu_factors_give_the_double_precision_answer() {
        let flight = subsonic_test_flight();
        let ks = [0.0, 0.4, 1.5];
        let mut aero = ilu_section();
        aero.lfd.params.tolerance = 1e-12;
        let modes = rigid_modes(&aero);
        let seed = random_seed(&flight, &ks, 2, 5);
        let mut runs = Vec::new();
        for precision in [
            crate::ilu::IluPrecision::Double,
            crate::ilu::IluPrecision::Single,
        ] {
            aero.lfd.params.ilu.precision = precision;
            let store = std::sync::Arc::new(std::sync::Mutex::new(WarmStart::default()));
            aero.warm_start = Some(store.clone());
            let table = aero.gafs(&flight, &modes, &ks).unwrap();
            let g = aero.gafs_vjp(&flight, &modes, &ks, &seed).unwrap();
            let s = store.lock().unwrap();
            let bytes = aero.lfd.factor(1.0, Symbol::Exact).unwrap().bytes();
            runs.push((
                table,
                g,
                s.last_iterations,
                s.last_adjoint_iterations,
                bytes,
            ));
        }
        let ((t64, g64, it64, adj64, b64), (t32, g32, it32, adj32, b32)) = (&runs[0], &runs[1]);
        // the numbers (25 complex values a block) halve; the column indices and row starts not
        assert!(
            (*b32 as f64) < 0.55 * *b64 as f64,
            "factors {b64} → {b32} bytes"
        );
        let (big, d) = table_difference(t64, t32);
        let (mut g_big, mut g_d) = (0.0f64, 0.0f64);
        for (x, y) in g64.modes.values().zip(g32.modes.values()) {
            g_big = g_big.max(x.abs());
            g_d = g_d.max((x - y).abs());
        }
        eprintln!(
            "single against double ILU factors: table {:.1e}, reverse {:.1e} of the largest entry; GMRES iterations {it64} → {it32}, adjoint {adj64} → {adj32}; factors {b64} → {b32} bytes",
            d / big,
            g_d / g_big
        );
        assert!(d < 1e-10 * big && g_d < 1e-10 * g_big);
        let close = |a: usize, b: usize| b <= a + a / 10 + 1;
        assert!(close(*it64, *it32) && close(*adj64, *adj32));
    }

    /// Three designs on a line (plunge × 1, 1.01, 1.02; pitch axis at 0, 2 and 4 % of the chord:
    /// the right-hand sides, and so the solutions, are linear along it, as a line search's trial
    /// points are to first order): keeping the last two designs, the third table starts from
    /// the combination of their solutions and needs fewer GMRES iterations than from the
    /// second's alone, for the same table (1e-8 of its largest entry, GMRES to 1e-10); the store
    /// keeps no more designs than it is told.
    #[test]
    fn several_kept_designs_follow_a_design_moving_on_a_line() {
        let flight = subsonic_test_flight();
        let ks = [0.0, 0.4, 1.5];
        let mut aero = ilu_section();
        let pts = aero.surface().points.clone();
        let design = |t: f64| {
            let mut m = rigid_modes(&aero);
            for (i, p) in pts.iter().enumerate() {
                m.disp[0][i] = [0.0, 0.0, 1.0 + 0.01 * t];
                m.disp[1][i] = [p[2], 0.0, -(p[0] - 0.02 * t)];
            }
            m
        };
        let (first, second, third) = (design(0.0), design(1.0), design(2.0));
        let mut runs = Vec::new();
        for kept in [1, 2] {
            let store = std::sync::Arc::new(std::sync::Mutex::new(WarmStart {
                designs: kept,
                ..Default::default()
            }));
            aero.warm_start = Some(store.clone());
            aero.gafs(&flight, &first, &ks).unwrap();
            aero.gafs(&flight, &second, &ks).unwrap();
            let table = aero.gafs(&flight, &third, &ks).unwrap();
            let s = store.lock().unwrap();
            assert_eq!(s.kept_designs().0, kept);
            runs.push((table, s.last_iterations));
        }
        let ((one, it_one), (two, it_two)) = (&runs[0], &runs[1]);
        let (big, d) = table_difference(one, two);
        eprintln!(
            "third design's GMRES iterations: from the second design {it_one}, from the last two {it_two}; tables differ by {:.1e}",
            d / big
        );
        assert!(d < 1e-8 * big);
        assert!(it_two < it_one, "{it_one} {it_two}");
    }

    /// GMRES started from the previous table's solutions (a shared [`WarmStart`]), with the
    /// block ILU(0) preconditioner of large meshes (the exact LU needs one or two iterations
    /// from any start): the table of a "next design" (plunge scaled by 1.01, pitch axis moved 2 %
    /// of the chord) equals its cold table to 1e-8 of the largest entry (GMRES to 1e-10 from
    /// either start) in fewer iterations; the same design with its mode shapes' signs flipped
    /// (as an eigensolver may return them) starts from the scaled guesses just as well; a store
    /// of another mesh is not used.
    #[test]
    fn warm_started_tables_give_the_cold_answer_in_fewer_iterations() {
        let flight = subsonic_test_flight();
        let ks = [0.0, 0.4, 1.5];
        let mut aero = ilu_section();
        let first = rigid_modes(&aero);
        let mut next = first.clone();
        let pts = aero.surface().points.clone();
        for (i, p) in pts.iter().enumerate() {
            next.disp[0][i] = [0.0, 0.0, 1.01];
            next.disp[1][i] = [p[2], 0.0, -(p[0] - 0.02)];
        }
        let mut flipped = next.clone();
        flipped.values_mut().for_each(|v| *v = -*v);
        let store = || std::sync::Arc::new(std::sync::Mutex::new(WarmStart::default()));
        let iterations =
            |w: &std::sync::Arc<std::sync::Mutex<WarmStart>>| w.lock().unwrap().last_iterations;
        // cold: an empty store
        let cold_store = store();
        aero.warm_start = Some(cold_store.clone());
        let cold = aero.gafs(&flight, &next, &ks).unwrap();
        let cold_it = iterations(&cold_store);
        // warm: the first design, then the next
        let warm_store = store();
        aero.warm_start = Some(warm_store.clone());
        aero.gafs(&flight, &first, &ks).unwrap();
        let warm = aero.gafs(&flight, &next, &ks).unwrap();
        let warm_it = iterations(&warm_store);
        let again = aero.gafs(&flight, &flipped, &ks).unwrap();
        let flipped_it = iterations(&warm_store);
        eprintln!(
            "GMRES iterations: cold {cold_it}, warm {warm_it}, flipped after warm {flipped_it}"
        );
        let mut big = 0.0f64;
        let (mut d_warm, mut d_flip) = (0.0f64, 0.0f64);
        for i in 0..ks.len() {
            for r in 0..2 {
                for c in 0..2 {
                    big = big.max(cold.q_ss[i][r][c].norm());
                    d_warm = d_warm.max((warm.q_ss[i][r][c] - cold.q_ss[i][r][c]).norm());
                    d_flip = d_flip.max((again.q_ss[i][r][c] - cold.q_ss[i][r][c]).norm());
                }
                big = big.max(cold.q_gs[i][r].norm());
                d_warm = d_warm.max((warm.q_gs[i][r] - cold.q_gs[i][r]).norm());
                // the flipped modes' gust column flips with them
                d_flip = d_flip.max((again.q_gs[i][r] + cold.q_gs[i][r]).norm());
            }
        }
        eprintln!(
            "largest differences from the cold table: warm {:.1e}, flipped {:.1e}",
            d_warm / big,
            d_flip / big
        );
        assert!(d_warm < 1e-8 * big && d_flip < 1e-8 * big);
        assert!(
            warm_it < cold_it && flipped_it < cold_it,
            "{cold_it} {warm_it} {flipped_it}"
        );
        // the reverse sweeps likewise: the next design's adjoint solves from the first's
        let seed = random_seed(&flight, &ks, 2, 5);
        let adjoint_iterations = |w: &std::sync::Arc<std::sync::Mutex<WarmStart>>| {
            w.lock().unwrap().last_adjoint_iterations
        };
        let cold_store = store();
        aero.warm_start = Some(cold_store.clone());
        let g_cold = aero.gafs_vjp(&flight, &next, &ks, &seed).unwrap();
        let adj_cold = adjoint_iterations(&cold_store);
        let warm_store = store();
        aero.warm_start = Some(warm_store.clone());
        aero.gafs_vjp(&flight, &first, &ks, &seed).unwrap();
        let g_warm = aero.gafs_vjp(&flight, &next, &ks, &seed).unwrap();
        let adj_warm = adjoint_iterations(&warm_store);
        let (mut d, mut big) = (0.0f64, 0.0f64);
        for (a, b) in g_warm.modes.values().zip(g_cold.modes.values()) {
            d = d.max((a - b).abs());
            big = big.max(b.abs());
        }
        eprintln!("adjoint GMRES iterations: cold {adj_cold}, warm {adj_warm}; gradients differ by {:.1e}", d / big);
        assert!(
            d < 1e-8 * big && adj_warm < adj_cold,
            "{adj_cold} {adj_warm}"
        );
        // several seeds at once: each seed's gradient is the one it has alone, from the same
        // adjoint solves (one a mode: the seeds only combine them)
        let other_seed = random_seed(&flight, &ks, 2, 11);
        // and the warm start does not care how the seed moved between the designs (in an
        // optimization it moves with the response's PSD and the multipliers)
        let moved_store = store();
        aero.warm_start = Some(moved_store.clone());
        aero.gafs_vjp(&flight, &first, &ks, &other_seed).unwrap();
        aero.gafs_vjp(&flight, &next, &ks, &seed).unwrap();
        assert_eq!(adjoint_iterations(&moved_store), adj_warm);
        let cold_store = store();
        aero.warm_start = Some(cold_store.clone());
        let both = aero
            .gafs_vjp_many(&flight, &next, &ks, &[seed.clone(), other_seed.clone()])
            .unwrap();
        assert_eq!(adjoint_iterations(&cold_store), adj_cold);
        let alone = aero.gafs_vjp(&flight, &next, &ks, &other_seed).unwrap();
        for (many, one) in both.iter().zip([&g_cold, &alone]) {
            let (mut d, mut big) = (0.0f64, 0.0f64);
            for (a, b) in many.modes.values().zip(one.modes.values()) {
                d = d.max((a - b).abs());
                big = big.max(b.abs());
            }
            // to the GMRES tolerance (1e-10: the lone seed's solves start from the pair's)
            assert!(d <= 1e-8 * big, "{d:e} of {big:e}");
        }
        // a store of another mesh is not used (and is replaced)
        let other = store();
        other.lock().unwrap().n = 7;
        other.lock().unwrap().tables = vec![ks
            .iter()
            .map(|&k| (k, vec![vec![num_complex::Complex32::new(1.0, 0.0); 7]; 3]))
            .collect()];
        aero.warm_start = Some(other.clone());
        let fresh = aero.gafs(&flight, &next, &ks).unwrap();
        assert_eq!(iterations(&other), cold_it);
        assert_eq!(fresh.q_ss, cold.q_ss);
    }

    /// A seed table of random complex entries for `n` modes.
    fn random_seed(flight: &FlightCondition, ks: &[f64], n: usize, seed: u64) -> GafTable {
        let mut t = GafTable::zeros(flight, ks, n);
        let v = gustkit_testkit::rand_vec(ks.len() * 2 * n * (n + 1), seed);
        let mut it = v.chunks(2).map(|c| C64::new(c[0], c[1]));
        for ik in 0..ks.len() {
            for i in 0..n {
                for j in 0..n {
                    t.q_ss[ik][i][j] = it.next().expect("enough numbers");
                }
                t.q_gs[ik][i] = it.next().expect("enough numbers");
            }
        }
        t
    }

    /// The reverse mode against central differences of the seeded GAFs along a random
    /// direction of the wall mode shapes, at steps 1e-1 … 1e-4 (m of a 1 m chord): the GAFs are
    /// bilinear in the shapes, so the central difference is exact up to round-off and the GMRES
    /// tolerance (1e-9), at every step. Second order, M 0.5 at 2° incidence (lift, so the
    /// static-pressure terms count), k = 0, 0.4 and 1.5, two modes with the gust, two seeds in
    /// one call. Agreement: 10 digits or more (measured 13 to 14 at h = 0.1, 11 at 1e-4). The
    /// same gradients with ∂R/∂x kept instead of recomputed: 1e-12 of the largest entry
    /// (measured: identical).
    #[test]
    fn reverse_mode_matches_central_differences() {
        let aero = lifting_section(lifting_mesh(), 1e-12, 10.0);
        let flight = subsonic_test_flight();
        let ks = [0.0, 0.4, 1.5];
        let base = rigid_modes(&aero);
        let np = base.disp[0].len();
        let r = gustkit_testkit::rand_vec(2 * 3 * np, 5);
        let mut dir = ModalSurface::zeros(2, np);
        let mut modes = base.clone();
        for m in 0..2 {
            for p in 0..np {
                // in-plane shapes only: the section is 2-D (x, z)
                dir.disp[m][p] = [r[(m * np + p) * 3], 0.0, r[(m * np + p) * 3 + 2]];
                modes.disp[m][p][0] += 0.1 * r[(m * np + p) * 3 + 1];
            }
        }
        let seeds: Vec<GafTable> = [7, 8].map(|sd| random_seed(&flight, &ks, 2, sd)).to_vec();
        let grads = aero.gafs_vjp_many(&flight, &modes, &ks, &seeds).unwrap();
        // ∂R/∂x recomputed by colouring (the model's way) or kept from the assembly: the same
        // blocks and contraction, so the same gradient (measured bit for bit)
        let kept = lifting_section(lifting_mesh(), 1e-12, 10.0);
        assert!(kept.reverse.set(LfdReverse::new(&kept.lfd)).is_ok());
        assert!(kept.reverse_linearizations().motion.keeps_dr_dx());
        assert!(!aero.reverse_linearizations().motion.keeps_dr_dx());
        let by_kept = kept.gafs_vjp_many(&flight, &modes, &ks, &seeds).unwrap();
        for (a, b) in grads.iter().zip(&by_kept) {
            let scale = b.modes.values().fold(0.0f64, |m, v| m.max(v.abs()));
            let err = a
                .modes
                .values()
                .zip(b.modes.values())
                .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
            eprintln!(
                "recomputed against kept ∂R/∂x: {:.1e} of the largest entry",
                err / scale
            );
            assert!(err <= 1e-12 * scale, "{err:e} of {scale:e}");
        }
        let moved = |h: f64| {
            let mut m = modes.clone();
            for (a, d) in m.values_mut().zip(dir.values()) {
                *a += h * d;
            }
            aero.gafs(&flight, &m, &ks).unwrap()
        };
        for h in [1e-1, 1e-2, 1e-3, 1e-4] {
            let (plus, minus) = (moved(h), moved(-h));
            for (seed, g) in seeds.iter().zip(&grads) {
                let fd = (seed.pair(&plus) - seed.pair(&minus)) / (2.0 * h);
                let adj: f64 = g.modes.values().zip(dir.values()).map(|(a, b)| a * b).sum();
                let err = (fd - adj).abs() / adj.abs();
                eprintln!("h = {h:e}: adjoint {adj:.12e}, central difference {fd:.12e}, {err:.1e}");
                assert!(err < 1e-10, "h = {h}: {adj} vs {fd}");
            }
        }
    }

    /// The geometry part of the reverse mode: the derivative of seeded GAFs along a smooth
    /// motion of the whole mesh (the wall included, so the section's shape changes) and of the
    /// deformation radius, against differences of models rebuilt on the moved mesh with their
    /// steady state solved again (to 1e-13): the steady tangent, the second-derivative terms,
    /// the gust fluxes' and the deformation's tangents together. Second order, M 0.5 at 2°,
    /// k = 0, 0.4 and 1.5, two modes with the gust. Fourth-order differences at steps 1e-3 and
    /// 3e-4 agree to 8 digits or more (measured 3.8e-11 at 1e-3; the central ones 3.0e-9).
    #[test]
    fn geometry_reverse_mode_matches_differences() {
        let base = lifting_mesh();
        let d_nodes: Vec<[f64; 3]> = base
            .nodes
            .iter()
            .map(|p| {
                let r = p[0].hypot(p[1]);
                let w = (-r / 3.0).exp();
                [0.05 * w * p[0], 0.1 * w * p[1] + 0.03 * w * p[0], 0.0]
            })
            .collect();
        let (radius, d_radius) = (10.0, 2.0);
        let model = |h: f64| {
            let mut mesh = base.clone();
            for (p, d) in mesh.nodes.iter_mut().zip(&d_nodes) {
                for k in 0..3 {
                    p[k] += h * d[k];
                }
            }
            lifting_section(mesh, 1e-13, radius + h * d_radius)
        };
        let flight = subsonic_test_flight();
        let ks = [0.0, 0.4, 1.5];
        let mut aero = model(0.0);
        aero.tangents = vec![MeshTangent {
            name: "stretch".into(),
            nodes: d_nodes.clone(),
            radius: d_radius,
        }];
        assert_eq!(aero.geometry_names(), ["stretch"]);
        let modes = rigid_modes(&aero);
        let seed = random_seed(&flight, &ks, 2, 3);
        let g = aero.gafs_vjp(&flight, &modes, &ks, &seed).unwrap();
        let adj = g.geometry[0];
        let f = |h: f64| seed.pair(&model(h).gafs(&flight, &modes, &ks).unwrap());
        for h in [1e-3, 3e-4] {
            let (p1, m1, p2, m2) = (f(h), f(-h), f(2.0 * h), f(-2.0 * h));
            let fd2 = (p1 - m1) / (2.0 * h);
            let fd4 = (8.0 * (p1 - m1) - (p2 - m2)) / (12.0 * h);
            let (e2, e4) = ((fd2 - adj).abs() / adj.abs(), (fd4 - adj).abs() / adj.abs());
            eprintln!("h = {h:e}: adjoint {adj:.12e}, central {fd2:.12e} ({e2:.1e}), fourth order {fd4:.12e} ({e4:.1e})");
            assert!(e4 < 1e-8, "h = {h}: {adj} vs {fd4}");
        }
    }

    /// A stalled adjoint GMRES names the frequency and the mode whose generalized force's
    /// adjoint it solved (one right-hand side a mode, whatever the seeds), and keeps the
    /// residual history.
    #[test]
    fn adjoint_failures_name_the_mode() {
        let stalled = |rhs: usize| LfdError::Gmres {
            omega: 0.3,
            rhs,
            source: crate::krylov::GmresError {
                reached: 1e-3,
                wanted: 1e-10,
                iterations: 2,
                history: vec![1.0, 1e-2, 1e-3],
            },
        };
        for (rhs, want) in [
            (0, "adjoint of mode 1's generalized force"),
            (2, "adjoint of mode 3's generalized force"),
        ] {
            match adjoint_error(stalled(rhs), 0.5, 3) {
                AeroError::Solver { k, rhs, failure } => {
                    assert_eq!((k, rhs.as_str()), (0.5, want));
                    assert_eq!(failure.history, vec![1.0, 1e-2, 1e-3]);
                }
                other => panic!("{other:?}"),
            }
        }
    }

    /// Bad input named: a negative reduced frequency, modes that do not match the surface, a
    /// Mach number other than the steady state's, and a GMRES that cannot converge (its residual
    /// history in the error).
    #[test]
    fn bad_input_is_named() {
        let mut aero = thin_section(24, 8, 0.3, Order::First);
        let modes = rigid_modes(&aero);
        let flight = FlightCondition {
            mach: 0.3,
            velocity: 100.0,
            density: 1.2,
            b_ref: 0.5,
            x_ref: 0.0,
        };
        let e = aero
            .gafs(&flight, &modes, &[0.1, -0.2])
            .unwrap_err()
            .to_string();
        assert!(e.contains("k[1]"), "{e}");
        let short = ModalSurface::zeros(2, 3);
        let e = aero.gafs(&flight, &short, &[0.1]).unwrap_err().to_string();
        assert!(e.contains("aerodynamic surface has"), "{e}");
        let mut other = flight;
        other.mach = 0.5;
        let e = aero.gafs(&other, &modes, &[0.1]).unwrap_err().to_string();
        assert!(e.contains("mach"), "{e}");
        aero.lfd = LfdOperator::with_preconditioner(
            aero.lfd.euler.clone(),
            aero.lfd.q0.clone(),
            crate::lfd::Preconditioner::BlockIlu,
        );
        aero.lfd.params.max_iterations = 2;
        aero.lfd.params.tolerance = 1e-14;
        let err = aero.gafs(&flight, &modes, &[0.5]).unwrap_err();
        let e = err.to_string();
        assert!(e.contains("GMRES stalled") && e.contains("history"), "{e}");
        // a typed solver failure: the reduced frequency, the right-hand side and the history
        match err {
            AeroError::Solver { k, rhs, failure } => {
                assert_eq!(k, 0.5);
                assert!(rhs == "mode 1" || rhs == "mode 2" || rhs == "gust", "{rhs}");
                assert!(!failure.history.is_empty());
            }
            other => panic!("expected a solver error, got {other:?}"),
        }
    }
}
