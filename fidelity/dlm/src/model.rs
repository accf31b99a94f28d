//! The DLM aerodynamic model: boxes, influence matrices per reduced frequency, GAFs and their
//! reverse mode.
//!
//! Boundary condition (no flow through the surface moving as u(x, t) e^{iωt}, gust w_g):
//!   w_j / U = n_j · (i ω/U u(cp_j) + ∂u/∂x(cp_j)) − (n_j · ẑ) e^{−i ω (x_cp,j − x_ref)/U}   (gust column)
//! pressure ΔCp = D⁻¹ w / U, and generalized forces Q_mn = Σ_j A_j (n_j · u_m(dp_j)) ΔCp_j^{(n)} at
//! the doublet (¼-chord) points, so that the modal force is q_inf Q η (see gustkit_core::aero).

use crate::cplx::Cplx;
use crate::geometry::{
    box_parametric_points, check_strip_alignment, surface_boxes, AeroBox, SurfaceSpec,
    SURFACE_PARAMS,
};
use crate::influence::{oscillatory_influences_shared, steady_influence, SharedEnd};
use crate::kernel::KernelScalar;
use faer::linalg::solvers::Solve;
use faer::{c64, Mat};
use gustkit_core::scalar::{Dual, Scalar};
use gustkit_core::{
    AeroError, AeroSurface, Aerodynamics, AerodynamicsReverse, FlightCondition, GafGradient,
    GafTable, ModalSurface,
};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Symmetry about the x-z plane (y = 0).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Symmetry {
    /// The surfaces are the whole configuration.
    #[default]
    None,
    /// Mirror image with the same pressure (symmetric motion; a wall-mounted half wing).
    Symmetric,
    /// Mirror image with opposite pressure (antisymmetric motion).
    Antisymmetric,
}

impl Symmetry {
    fn sign(self) -> Option<f64> {
        match self {
            Symmetry::None => None,
            Symmetry::Symmetric => Some(1.0),
            Symmetry::Antisymmetric => Some(-1.0),
        }
    }
}

/// The Doublet-Lattice model of a set of lifting surfaces.
#[derive(Clone, Debug)]
pub struct Dlm {
    pub surfaces: Vec<SurfaceSpec>,
    pub symmetry: Symmetry,
    /// Boxes of all surfaces in order.
    pub boxes: Vec<AeroBox<f64>>,
    surface: AeroSurface,
    /// Geometry parameters differentiated by the reverse mode, per surface.
    active: Vec<Vec<usize>>,
    /// The influence matrices of the last (geometry, Mach, frequencies) asked for, so that a
    /// reverse pass after the forward one does not build them again.
    cache: std::sync::Arc<std::sync::Mutex<Option<MatrixCache>>>,
}

/// Influence matrices (one per reduced frequency) and what they were built for.
#[derive(Debug)]
struct MatrixCache {
    key: u64,
    mats: std::sync::Arc<Vec<Vec<Cplx<f64>>>>,
}

/// Number of geometry parameters of one surface.
const NQ: usize = 8;

impl Dlm {
    /// Builds the boxes; checks every surface and the strip alignment of coplanar surfaces.
    pub fn new(surfaces: Vec<SurfaceSpec>, symmetry: Symmetry) -> Result<Self, AeroError> {
        if surfaces.is_empty() {
            return Err(AeroError::Input(
                "surfaces: at least one lifting surface is needed".into(),
            ));
        }
        for (i, s) in surfaces.iter().enumerate() {
            s.validate(i)?;
        }
        check_strip_alignment(&surfaces)?;
        let boxes: Vec<AeroBox<f64>> = surfaces
            .iter()
            .flat_map(|s| surface_boxes(s, s.params()))
            .collect();
        let n = boxes.len();
        let mut surface = AeroSurface::default();
        for b in &boxes {
            surface.points.push(b.cp);
            surface.normals.push(b.normal());
        }
        for b in &boxes {
            surface.points.push(b.dp);
            surface.normals.push(b.normal());
        }
        debug_assert_eq!(surface.points.len(), 2 * n);
        Ok(Self {
            cache: Default::default(),
            active: vec![(0..NQ).collect(); surfaces.len()],
            surfaces,
            symmetry,
            boxes,
            surface,
        })
    }

    pub fn n_boxes(&self) -> usize {
        self.boxes.len()
    }

    /// For every point of [`Aerodynamics::surface`] (control points, then doublet points): the
    /// surface it lies on and its parametric coordinates (ξ, η) there, so that a structural model
    /// laid on the same parametrization can sample its modes exactly at the aerodynamic points.
    pub fn parametric_points(&self) -> Vec<(usize, [f64; 2])> {
        let all: Vec<(usize, [f64; 2], [f64; 2])> = self
            .surfaces
            .iter()
            .enumerate()
            .flat_map(|(si, s)| {
                box_parametric_points(s)
                    .into_iter()
                    .map(move |(cp, dp)| (si, cp, dp))
            })
            .collect();
        all.iter()
            .map(|&(si, cp, _)| (si, cp))
            .chain(all.iter().map(|&(si, _, dp)| (si, dp)))
            .collect()
    }

    /// Influence matrix D (row: receiving control point, column: sending box) at Mach `mach` and
    /// ω/U = `kd`, for boxes of any scalar type.
    pub fn influence_matrix<S: KernelScalar>(
        &self,
        boxes: &[AeroBox<S>],
        mach: f64,
        kd: f64,
    ) -> Vec<Cplx<S>> {
        self.influence_matrices(boxes, mach, &[kd])
            .pop()
            .expect("one frequency")
    }

    /// Influence matrices at several ω/U at once, `[k][r n + s]`: the steady lattice and the
    /// frequency-independent kernel geometry are computed once per box pair, rows in parallel.
    pub fn influence_matrices<S: KernelScalar>(
        &self,
        boxes: &[AeroBox<S>],
        mach: f64,
        kds: &[f64],
    ) -> Vec<Vec<Cplx<S>>> {
        let n = boxes.len();
        let nk = kds.len();
        let mut out = vec![vec![Cplx::<S>::zero(); n * n]; nk];
        let rows: Vec<Vec<Cplx<S>>> = (0..n)
            .into_par_iter()
            .map(|r| {
                let mut row = vec![Cplx::<S>::zero(); n * nk];
                self.influence_row(boxes, r, mach, kds, |s, k, v| row[s * nk + k] = v);
                row
            })
            .collect();
        for (r, row) in rows.into_iter().enumerate() {
            for s in 0..n {
                for k in 0..nk {
                    out[k][r * n + s] = row[s * nk + k];
                }
            }
        }
        out
    }

    /// Calls `sink(s, k, D_rs(k))` for every sending box s and frequency k of receiving box r.
    /// The sending boxes are visited strip by strip along each chordwise row, so that the kernel
    /// at the line end two spanwise neighbours share is evaluated once ([`SharedEnd`]).
    fn influence_row<S: KernelScalar>(
        &self,
        boxes: &[AeroBox<S>],
        r: usize,
        mach: f64,
        kds: &[f64],
        mut sink: impl FnMut(usize, usize, Cplx<S>),
    ) {
        let sign = self.symmetry.sign();
        let rb = &boxes[r];
        let nk = kds.len();
        let mut osc = vec![Cplx::<S>::zero(); nk];
        let mut osc_img = vec![Cplx::<S>::zero(); nk];
        let mut end = vec![Cplx::<S>::zero(); nk];
        let mut end_img = vec![Cplx::<S>::zero(); nk];
        let mut offset = 0;
        for spec in &self.surfaces {
            let (nc, ns) = (spec.n_chord, spec.n_span);
            for i in 0..nc {
                for j in 0..ns {
                    let s = offset + j * nc + i;
                    let sb = &boxes[s];
                    // the inboard end of strip j is the outboard end of strip j − 1
                    let mut steady = steady_influence(rb, sb, mach);
                    oscillatory_influences_shared(
                        rb,
                        sb,
                        mach,
                        kds,
                        &mut osc,
                        Some(SharedEnd {
                            p1: &mut end,
                            given: (j > 0).then_some(0),
                            kept: 4,
                        }),
                    );
                    if let Some(sg) = sign {
                        // the image runs the other way: its outboard end (η = +e) is the
                        // previous image's inboard one
                        let img = sb.mirrored();
                        steady += steady_influence(rb, &img, mach) * sg;
                        oscillatory_influences_shared(
                            rb,
                            &img,
                            mach,
                            kds,
                            &mut osc_img,
                            Some(SharedEnd {
                                p1: &mut end_img,
                                given: (j > 0).then_some(4),
                                kept: 0,
                            }),
                        );
                        for (o, im) in osc.iter_mut().zip(&osc_img) {
                            *o = *o + im.scale_f(sg);
                        }
                    }
                    for (k, o) in osc.iter().enumerate() {
                        sink(s, k, Cplx::real(steady) + *o);
                    }
                }
            }
            offset += nc * ns;
        }
        debug_assert_eq!(offset, boxes.len());
    }

    fn check_inputs(
        &self,
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: &[f64],
    ) -> Result<(), AeroError> {
        gustkit_core::aero::check_request(flight, modes, k, self.surface.points.len())?;
        if !(flight.mach < 1.0) {
            return Err(AeroError::Input(format!(
                "mach: the doublet-lattice method is subsonic only (got M = {})",
                flight.mach
            )));
        }
        Ok(())
    }

    /// Right-hand sides w/U: one column a mode, then the gust column (n × (n_modes + 1)).
    fn normalwash<S: Scalar>(
        boxes: &[AeroBox<S>],
        modes: &ModalSurface,
        kd: f64,
        x_ref: f64,
    ) -> Vec<Vec<Cplx<S>>> {
        let nm = modes.n_modes();
        let mut cols = vec![Vec::with_capacity(boxes.len()); nm + 1];
        for (j, b) in boxes.iter().enumerate() {
            let nrm = b.normal();
            for m in 0..nm {
                let (u, ux) = (modes.disp[m][j], modes.disp_x[m][j]);
                let un = nrm[0] * u[0] + nrm[1] * u[1] + nrm[2] * u[2];
                let uxn = nrm[0] * ux[0] + nrm[1] * ux[1] + nrm[2] * ux[2];
                cols[m].push(Cplx::new(uxn, un * kd));
            }
            let phase = Cplx::expi_neg((b.cp[0] - x_ref) * kd);
            cols[nm].push(-phase.scale(nrm[2]));
        }
        cols
    }

    /// Generalized-force weights h_jm A_j = A_j n_j · u_m(dp_j).
    fn force_weights<S: Scalar>(boxes: &[AeroBox<S>], modes: &ModalSurface) -> Vec<Vec<S>> {
        let n = boxes.len();
        (0..modes.n_modes())
            .map(|m| {
                boxes
                    .iter()
                    .enumerate()
                    .map(|(j, b)| {
                        let nrm = b.normal();
                        let u = modes.disp[m][n + j];
                        (nrm[0] * u[0] + nrm[1] * u[1] + nrm[2] * u[2]) * b.area
                    })
                    .collect()
            })
            .collect()
    }

    /// The influence matrices of the model's own boxes at reduced frequencies `k`.
    fn matrices(&self, flight: &FlightCondition, k: &[f64]) -> std::sync::Arc<Vec<Vec<Cplx<f64>>>> {
        let kds: Vec<f64> = k.iter().map(|kk| kk / flight.b_ref).collect();
        // FNV-1a over every number the matrices depend on (the boxes are public, so their
        // geometry is part of the key)
        let mut key: u64 = 0xcbf2_9ce4_8422_2325;
        let mut mix = |v: f64| {
            for b in v.to_bits().to_le_bytes() {
                key = (key ^ b as u64).wrapping_mul(0x0100_0000_01b3);
            }
        };
        mix(flight.mach);
        kds.iter().for_each(|v| mix(*v));
        mix(match self.symmetry {
            Symmetry::None => 0.0,
            Symmetry::Symmetric => 1.0,
            Symmetry::Antisymmetric => 2.0,
        });
        for b in &self.boxes {
            let points = b.corners.iter().chain([&b.line_a, &b.line_b, &b.cp, &b.dp]);
            for p in points.flatten() {
                mix(*p);
            }
        }
        let mut cache = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(c) = cache.as_ref().filter(|c| c.key == key) {
            return c.mats.clone();
        }
        let mats = std::sync::Arc::new(self.influence_matrices(&self.boxes, flight.mach, &kds));
        *cache = Some(MatrixCache {
            key,
            mats: mats.clone(),
        });
        mats
    }

    /// Pressure solutions c = D⁻¹ W at one frequency (columns: modes, gust) with the factorization.
    fn solve_k(
        &self,
        d: &[Cplx<f64>],
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: f64,
    ) -> Result<(faer::linalg::solvers::PartialPivLu<c64>, Mat<c64>), AeroError> {
        let n = self.n_boxes();
        let kd = k / flight.b_ref;
        let dm = Mat::<c64>::from_fn(n, n, |i, j| d[i * n + j].value());
        let lu = dm.partial_piv_lu();
        let w = Self::normalwash(&self.boxes, modes, kd, flight.x_ref);
        let rhs = Mat::<c64>::from_fn(n, w.len(), |i, c| w[c][i].value());
        let c = lu.solve(&rhs);
        if c.col_iter()
            .flat_map(|col| col.iter().copied().collect::<Vec<_>>())
            .any(|v| !v.re.is_finite() || !v.im.is_finite())
        {
            return Err(AeroError::Singular { k });
        }
        Ok((lu, c))
    }
}

/// Quantities of one frequency held fixed while ℒ is differentiated with respect to the geometry.
struct FrozenK {
    c: Mat<c64>,
    lam: Mat<c64>,
    /// Σ_col conj(λ_j,col) c_i,col: the weights of D_ji in ℒ.
    lc: Mat<c64>,
    qbar: Mat<c64>,
    kd: f64,
}

impl Dlm {
    /// Restricts the geometry gradient of surface `surface` to the listed parameters (indices into
    /// [`crate::geometry::SURFACE_PARAMS`]); the others are reported as zero. Callers that chain
    /// through a few design variables save most of the reverse-mode cost this way.
    pub fn set_active_geometry(&mut self, surface: usize, params: &[usize]) {
        self.active[surface] = params.iter().copied().filter(|&p| p < NQ).collect();
    }

    /// ∂ℒ/∂q for up to N parameters of surface `si`, ℒ = Σ_k Re[Σ conj(Q̄) Hᵀ A c + Σ conj(λ)(W − D c)]:
    /// the influence matrices of all frequencies are differentiated in one pass over the box pairs
    /// (rows in parallel) and contracted on the fly.
    fn geometry_lagrangian<const N: usize>(
        &self,
        si: usize,
        params: &[usize],
        frozen: &[Vec<&FrozenK>],
        flight: &FlightCondition,
        modes: &ModalSurface,
    ) -> Vec<[f64; N]> {
        let n = self.n_boxes();
        let nm = modes.n_modes();
        let boxes: Vec<AeroBox<Dual<N>>> = self
            .surfaces
            .iter()
            .enumerate()
            .flat_map(|(sj, s)| {
                let q = s.params();
                let qd: [Dual<N>; NQ] = std::array::from_fn(|i| {
                    match params.iter().position(|&p| p == i).filter(|_| sj == si) {
                        Some(lane) => Dual::var(q[i], lane),
                        None => Dual::cst(q[i]),
                    }
                });
                surface_boxes(s, qd)
            })
            .collect();
        let ns = frozen.len();
        let kds: Vec<f64> = frozen[0].iter().map(|f| f.kd).collect();
        let hw = Self::force_weights(&boxes, modes);
        // − Re Σ_k Σ_ji D_ji(k) lc_ji(k), every seed contracted with the same dD_ji
        let zero = || vec![Dual::<N>::cst(0.0); ns];
        // rows in parallel, summed in row order: the same bits on every run and thread count
        let rows: Vec<Vec<Dual<N>>> = (0..n)
            .into_par_iter()
            .map(|j| {
                let mut acc = zero();
                self.influence_row(&boxes, j, flight.mach, &kds, |i, k, dji| {
                    for (a, f) in acc.iter_mut().zip(frozen) {
                        let l = f[k].lc[(j, i)];
                        *a -= dji.re * l.re - dji.im * l.im;
                    }
                });
                acc
            })
            .collect();
        let d_part: Vec<Dual<N>> = rows.into_iter().fold(zero(), |a, b| {
            a.into_iter().zip(b).map(|(x, y)| x + y).collect()
        });
        let mut out = Vec::with_capacity(ns);
        for (mut lag, seed) in d_part.into_iter().zip(frozen) {
            for f in seed {
                let w = Self::normalwash(&boxes, modes, f.kd, flight.x_ref);
                for col in 0..=nm {
                    for j in 0..n {
                        let cj = f.c[(j, col)];
                        for m in 0..nm {
                            lag += hw[m][j] * (f.qbar[(m, col)].conj() * cj).re;
                        }
                        let lj = f.lam[(j, col)];
                        lag += w[col][j].re * lj.re + w[col][j].im * lj.im;
                    }
                }
            }
            out.push(lag.d);
        }
        out
    }

    /// The boxes' normal forces per unit dynamic pressure, A_j Δc_p,j along each box normal, at
    /// each reduced frequency: `[k][box][column]`, one column a mode, then the gust (per unit
    /// w_g/U). The generalized forces are these weighted by the modes' normal displacements at
    /// the doublet points (`gafs`); a structural model takes them to its grids through the
    /// transpose of its spline (force summation of aerodynamic loads).
    pub fn box_forces(
        &self,
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: &[f64],
    ) -> Result<Vec<Vec<Vec<c64>>>, AeroError> {
        self.check_inputs(flight, modes, k)?;
        let mats = self.matrices(flight, k);
        k.par_iter()
            .enumerate()
            .map(|(ik, &kk)| {
                let (_, c) = self.solve_k(&mats[ik], flight, modes, kk)?;
                Ok(self
                    .boxes
                    .iter()
                    .enumerate()
                    .map(|(j, b)| (0..c.ncols()).map(|col| c[(j, col)] * b.area).collect())
                    .collect())
            })
            .collect()
    }

    /// Seeds on the modes' displacements and slopes at the control points from the adjoint λ
    /// of D c = W (one column a mode): W = n·u_x + i kd n·u gives ū = Re(conj(λ) i kd) n and
    /// ū_x = Re(conj(λ)) n.
    fn control_point_seeds(&self, lam: &Mat<c64>, kd: f64, out: &mut ModalSurface) {
        for m in 0..out.n_modes() {
            for (j, b) in self.boxes.iter().enumerate() {
                let nrm = b.normal();
                let l = lam[(j, m)].conj();
                let (sx, su) = (l.re, (l * c64::new(0.0, kd)).re);
                for a in 0..3 {
                    out.disp_x[m][j][a] += sx * nrm[a];
                    out.disp[m][j][a] += su * nrm[a];
                }
            }
        }
    }

    /// The reverse mode of [`Dlm::box_forces`] with respect to the mode shapes: seeds F̄ on every
    /// box force (`seeds[ik][box][col]`, conjugate convention δJ = Re Σ conj(F̄) δF; the gust
    /// column's are ignored, it does not depend on the shapes) to seeds on the modal surface's
    /// displacements and slopes at the control points. F = A c, D c = W: c̄ = A F̄, Dᴴ λ = c̄,
    /// and W = n·u_x + i k/b n·u gives ū_x = Re(conj λ) n, ū = Re(conj(λ) i k/b) n.
    pub fn box_forces_vjp(
        &self,
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: &[f64],
        seeds: &[Vec<Vec<c64>>],
    ) -> Result<ModalSurface, AeroError> {
        self.check_inputs(flight, modes, k)?;
        let n = self.n_boxes();
        let nm = modes.n_modes();
        if seeds.len() != k.len()
            || seeds
                .iter()
                .any(|s| s.len() != n || s.iter().any(|b| b.len() < nm))
        {
            return Err(AeroError::Input(format!(
                "seeds: one force seed a box ({n}) and mode ({nm}) at each of the {} reduced frequencies",
                k.len()
            )));
        }
        let mats = self.matrices(flight, k);
        let parts: Vec<ModalSurface> = k
            .par_iter()
            .enumerate()
            .map(|(ik, &kk)| {
                let kd = kk / flight.b_ref;
                let mut out = ModalSurface::zeros(nm, 2 * n);
                if seeds[ik]
                    .iter()
                    .all(|b| b[..nm].iter().all(|v| *v == c64::new(0.0, 0.0)))
                {
                    return Ok(out);
                }
                let dm = Mat::<c64>::from_fn(n, n, |i, j| mats[ik][i * n + j].value());
                let lu = dm.partial_piv_lu();
                let mut lam =
                    Mat::<c64>::from_fn(n, nm, |j, m| seeds[ik][j][m] * self.boxes[j].area);
                lu.solve_adjoint_in_place(lam.as_mut());
                self.control_point_seeds(&lam, kd, &mut out);
                Ok(out)
            })
            .collect::<Result<_, AeroError>>()?;
        let mut total = ModalSurface::zeros(nm, 2 * n);
        for part in &parts {
            for (t, p) in total.values_mut().zip(part.values()) {
                *t += p;
            }
        }
        Ok(total)
    }

    /// Forward mode with respect to the geometry parameters ([`Aerodynamics::geometry_names`]):
    /// dQ along `dq`, from the tangent equation dc = D⁻¹ (dW − dD c) with dD, dW and the force
    /// weights differentiated by dual numbers through the box geometry.
    pub fn gafs_geometry_jvp(
        &self,
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: &[f64],
        dq: &[f64],
    ) -> Result<GafTable, AeroError> {
        self.check_inputs(flight, modes, k)?;
        if dq.len() != NQ * self.surfaces.len() {
            return Err(AeroError::Input(format!(
                "geometry direction: expected {} values, got {}",
                NQ * self.surfaces.len(),
                dq.len()
            )));
        }
        let nm = modes.n_modes();
        let n = self.n_boxes();
        let boxes: Vec<AeroBox<Dual<1>>> = self
            .surfaces
            .iter()
            .enumerate()
            .flat_map(|(si, s)| {
                let q = s.params();
                surface_boxes(
                    s,
                    std::array::from_fn(|p| Dual::new(q[p], [dq[si * NQ + p]])),
                )
            })
            .collect();
        let hw = Self::force_weights(&boxes, modes);
        let mats = self.matrices(flight, k);
        let kds: Vec<f64> = k.iter().map(|kk| kk / flight.b_ref).collect();
        let dmats = self.influence_matrices(&boxes, flight.mach, &kds);
        let per_k: Vec<(Vec<Vec<c64>>, Vec<c64>)> = k
            .par_iter()
            .enumerate()
            .map(|(ik, &kk)| {
                let kd = kds[ik];
                let (lu, c) = self.solve_k(&mats[ik], flight, modes, kk)?;
                let d = &dmats[ik];
                let w = Self::normalwash(&boxes, modes, kd, flight.x_ref);
                let rhs = Mat::<c64>::from_fn(n, nm + 1, |j, col| {
                    let dw = c64::new(w[col][j].re.d[0], w[col][j].im.d[0]);
                    let ddc: c64 = (0..n)
                        .map(|i| c64::new(d[j * n + i].re.d[0], d[j * n + i].im.d[0]) * c[(i, col)])
                        .sum();
                    dw - ddc
                });
                let dc = lu.solve(&rhs);
                let dgaf = |col: usize, m: usize| -> c64 {
                    (0..n)
                        .map(|j| c[(j, col)] * hw[m][j].d[0] + dc[(j, col)] * hw[m][j].v)
                        .sum()
                };
                let q_ss = (0..nm)
                    .map(|m| (0..nm).map(|nn| dgaf(nn, m)).collect())
                    .collect();
                let q_gs = (0..nm).map(|m| dgaf(nm, m)).collect();
                Ok((q_ss, q_gs))
            })
            .collect::<Result<_, AeroError>>()?;
        Ok(GafTable::from_parts(flight, k, per_k))
    }
}

impl Aerodynamics for Dlm {
    fn surface(&self) -> &AeroSurface {
        &self.surface
    }

    fn geometry_names(&self) -> Vec<String> {
        self.surfaces
            .iter()
            .flat_map(|s| {
                SURFACE_PARAMS
                    .iter()
                    .map(move |p| format!("{}.{p}", s.name))
            })
            .collect()
    }

    fn gafs(
        &self,
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: &[f64],
    ) -> Result<GafTable, AeroError> {
        self.check_inputs(flight, modes, k)?;
        let nm = modes.n_modes();
        let weights = Self::force_weights(&self.boxes, modes);
        let mats = self.matrices(flight, k);
        let per_k: Vec<(Vec<Vec<c64>>, Vec<c64>)> = k
            .par_iter()
            .enumerate()
            .map(|(ik, &kk)| {
                let (_, c) = self.solve_k(&mats[ik], flight, modes, kk)?;
                let gaf = |col: usize, m: usize| -> c64 {
                    weights[m]
                        .iter()
                        .enumerate()
                        .map(|(j, h)| c[(j, col)] * h)
                        .sum()
                };
                let q_ss = (0..nm)
                    .map(|m| (0..nm).map(|n| gaf(n, m)).collect())
                    .collect();
                let q_gs = (0..nm).map(|m| gaf(nm, m)).collect();
                Ok((q_ss, q_gs))
            })
            .collect::<Result<_, AeroError>>()?;
        Ok(GafTable::from_parts(flight, k, per_k))
    }

    /// The influence matrices at every k (the cache `gafs` and the reverse mode read).
    fn prepare(&self, flight: &FlightCondition, k: &[f64]) {
        if flight.mach < 1.0 && flight.b_ref > 0.0 && k.iter().all(|v| v.is_finite()) {
            self.matrices(flight, k);
        }
    }

    fn reverse(&self) -> Option<&dyn AerodynamicsReverse> {
        Some(self)
    }
}

impl AerodynamicsReverse for Dlm {
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

    /// One influence matrix and LU per frequency and one dual-number pass over the box pairs for
    /// all seeds together.
    fn gafs_vjp_many(
        &self,
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: &[f64],
        seeds: &[GafTable],
    ) -> Result<Vec<GafGradient>, AeroError> {
        self.check_inputs(flight, modes, k)?;
        if seeds.is_empty() {
            return Ok(Vec::new());
        }
        let nm = modes.n_modes();
        gustkit_core::aero::check_seeds(seeds, k.len(), nm)?;
        let n = self.n_boxes();
        let weights = Self::force_weights(&self.boxes, modes);
        let mats = self.matrices(flight, k);
        let zero_gradient = || GafGradient {
            modes: ModalSurface::zeros(nm, 2 * n),
            geometry: vec![0.0; NQ * self.surfaces.len()],
        };
        // per frequency: per seed, its modal gradient part and its frozen adjoint quantities
        let parts: Vec<Vec<(GafGradient, FrozenK)>> = k
            .par_iter()
            .enumerate()
            .map(|(ik, &kk)| {
                let kd = kk / flight.b_ref;
                let (lu, c) = self.solve_k(&mats[ik], flight, modes, kk)?;
                let mut out = Vec::with_capacity(seeds.len());
                for seed in seeds {
                    // c̄_jn = Σ_m h_jm A_j Q̄_mn (gust column n = nm)
                    let qbar = |m: usize, col: usize| {
                        if col < nm {
                            seed.q_ss[ik][m][col]
                        } else {
                            seed.q_gs[ik][m]
                        }
                    };
                    let cbar = Mat::<c64>::from_fn(n, nm + 1, |j, col| {
                        (0..nm).map(|m| qbar(m, col) * weights[m][j]).sum()
                    });
                    let mut lam = cbar;
                    lu.solve_adjoint_in_place(lam.as_mut());
                    let mut g = zero_gradient();
                    // mode shapes at the doublet points: h̄_jm A_j = Re Σ_n conj(Q̄_mn) c_jn
                    for m in 0..nm {
                        for j in 0..n {
                            let b = &self.boxes[j];
                            let s: f64 = (0..=nm)
                                .map(|col| (qbar(m, col).conj() * c[(j, col)]).re)
                                .sum();
                            let nrm = b.normal();
                            for a in 0..3 {
                                g.modes.disp[m][n + j][a] += s * b.area * nrm[a];
                            }
                        }
                    }
                    // mode shapes at the control points through W: W̄ = λ
                    self.control_point_seeds(&lam, kd, &mut g.modes);
                    // geometry: ℒ(q) = Re[Σ conj(Q̄) Hᵀ A c + Σ conj(λ)(W − D c)] with c, λ
                    // frozen, differentiated by duals along the active parameters
                    let qbar_mat = Mat::<c64>::from_fn(nm, nm + 1, qbar);
                    // Σ_col conj(λ_j,col) c_i,col: the weights of D_ji in ℒ
                    let lc = Mat::<c64>::from_fn(n, n, |j, i| {
                        (0..=nm).map(|col| lam[(j, col)].conj() * c[(i, col)]).sum()
                    });
                    out.push((
                        g,
                        FrozenK {
                            c: c.clone(),
                            lam,
                            lc,
                            qbar: qbar_mat,
                            kd,
                        },
                    ));
                }
                Ok(out)
            })
            .collect::<Result<_, AeroError>>()?;
        // geometry, all frequencies and seeds in one pass over the box pairs
        let frozen: Vec<Vec<&FrozenK>> = (0..seeds.len())
            .map(|s| parts.iter().map(|per_k| &per_k[s].1).collect())
            .collect();
        let mut totals: Vec<GafGradient> = (0..seeds.len()).map(|_| zero_gradient()).collect();
        for (si, active) in self.active.iter().enumerate() {
            for chunk in active.chunks(4) {
                let d = self.geometry_lagrangian::<4>(si, chunk, &frozen, flight, modes);
                for (total, d) in totals.iter_mut().zip(d) {
                    for (p, &param) in chunk.iter().enumerate() {
                        total.geometry[si * NQ + param] += d[p];
                    }
                }
            }
        }
        for per_k in &parts {
            for (total, (p, _)) in totals.iter_mut().zip(per_k) {
                for m in 0..nm {
                    for j in 0..2 * n {
                        for a in 0..3 {
                            total.modes.disp[m][j][a] += p.modes.disp[m][j][a];
                            total.modes.disp_x[m][j][a] += p.modes.disp_x[m][j][a];
                        }
                    }
                }
            }
        }
        Ok(totals)
    }
}
