//! The structure of a Nastran model: coordinate systems, the g-set (six components a grid in its
//! displacement system), stiffness and mass of bars and beams, springs, scalar and lumped masses
//! and general elements; rigid elements, MPCs and SPCs eliminated by a transformation
//! u_g = T u_a; and the real modes the case control's METHOD asks for.
//!
//! Dense matrices: the models this reads first are stick and box models of tens to a few hundred
//! grids (a g-set of n components takes 16 n² bytes a matrix; [`Structure::assemble`] refuses
//! beyond [`MAX_DENSE_DOFS`]).

use super::bulk::{Bar, BulkData, Conm, Material, Orientation, Rigid, Scalar};
use super::NastranError;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::{Mat, Par, Side};
use gustkit_core::scalar::{Dual, Scalar as ScalarOps};
use std::collections::{BTreeMap, BTreeSet};

/// The largest g-set the dense assembly takes (two matrices of 16 n² bytes: 1.2 GB at 6 000).
pub const MAX_DENSE_DOFS: usize = 6000;

/// Whether PARAM COUPMASS asks for consistent (coupled) element masses.
fn coupled_mass(b: &BulkData) -> bool {
    b.params
        .get("COUPMASS")
        .and_then(|v| v.parse::<i64>().ok())
        .is_some_and(|v| v > 0)
}

/// PARAM WTMASS, the factor on every mass term, where the model gives one.
fn wtmass(b: &BulkData) -> R<Option<f64>> {
    b.params
        .get("WTMASS")
        .map(|w| {
            super::field::parse_real(w)
                .or_else(|| w.parse::<i64>().ok().map(|v| v as f64))
                .filter(|v| *v > 0.0)
                .ok_or_else(|| {
                    NastranError::model(
                        "PARAM WTMASS",
                        format!("must be a positive real (got '{w}')"),
                    )
                })
        })
        .transpose()
}

/// What a shell contributes to an assembly: its matrices, or their derivatives in its PSHELL's
/// thickness.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum ShellPart {
    Value,
    ThicknessDerivative,
}

type R<T> = Result<T, NastranError>;

/// A rectangular frame: origin and axes (columns) in the basic system.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub origin: [f64; 3],
    pub axes: [[f64; 3]; 3],
}

impl Frame {
    const BASIC: Frame = Frame {
        origin: [0.0; 3],
        axes: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
    };

    /// A point given in this frame, in basic.
    pub fn to_basic(&self, x: [f64; 3]) -> [f64; 3] {
        let mut p = self.origin;
        for (j, axis) in self.axes.iter().enumerate() {
            for i in 0..3 {
                p[i] += axis[i] * x[j];
            }
        }
        p
    }

    /// A vector given in this frame, in basic.
    pub fn rotate(&self, v: [f64; 3]) -> [f64; 3] {
        let mut p = [0.0; 3];
        for (j, axis) in self.axes.iter().enumerate() {
            for i in 0..3 {
                p[i] += axis[i] * v[j];
            }
        }
        p
    }

    /// The 3 × 3 rotation (basic = R · local), row-major.
    fn matrix(&self) -> [[f64; 3]; 3] {
        std::array::from_fn(|i| std::array::from_fn(|j| self.axes[j][i]))
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}
fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// Resolves every CORD2R (through its reference systems) to a frame in basic.
fn frames(b: &BulkData) -> R<BTreeMap<u32, Frame>> {
    let mut done: BTreeMap<u32, Frame> = BTreeMap::new();
    done.insert(0, Frame::BASIC);
    for &id in b.coords.keys() {
        let mut chain = vec![id];
        while let Some(&top) = chain.last() {
            if done.contains_key(&top) {
                chain.pop();
                continue;
            }
            let c = &b.coords[&top];
            match done.get(&c.rid) {
                Some(reference) => {
                    let (a, bb, cc) = (
                        reference.to_basic(c.a),
                        reference.to_basic(c.b),
                        reference.to_basic(c.c),
                    );
                    let z = sub(bb, a);
                    let y = cross(z, sub(cc, a));
                    let (nz, ny) = (norm(z), norm(y));
                    if !(nz > 0.0 && ny > 1e-12 * nz * norm(sub(cc, a)).max(f64::MIN_POSITIVE)) {
                        return Err(NastranError::model(
                            &format!("CORD2R {top}"),
                            "its points A, B and C do not span a frame (B = A, or C on the z axis)"
                                .into(),
                        ));
                    }
                    let z = scale(z, 1.0 / nz);
                    let y = scale(y, 1.0 / ny);
                    let x = cross(y, z);
                    done.insert(
                        top,
                        Frame {
                            origin: a,
                            axes: [x, y, z],
                        },
                    );
                    chain.pop();
                }
                None => {
                    if !b.coords.contains_key(&c.rid) {
                        return Err(NastranError::model(
                            &format!("CORD2R {top}"),
                            format!(
                                "refers to coordinate system {}, which the model does not define",
                                c.rid
                            ),
                        ));
                    }
                    if chain.contains(&c.rid) {
                        return Err(NastranError::model(
                            &format!("CORD2R {top}"),
                            "its reference systems form a circle".into(),
                        ));
                    }
                    chain.push(c.rid);
                }
            }
        }
    }
    Ok(done)
}

/// The assembled structure in the g-set: six components a grid (in the grid's displacement
/// system), grids in increasing id.
#[derive(Clone, Debug)]
pub struct Structure {
    pub grid_ids: Vec<u32>,
    pub index: BTreeMap<u32, usize>,
    /// Grid locations in basic.
    pub position: Vec<[f64; 3]>,
    /// Displacement frames of the grids.
    pub cd: Vec<Frame>,
    pub k_gg: Mat<f64>,
    pub m_gg: Mat<f64>,
    /// Dependent components (m-set) as combinations of others: g index → [(g index, factor)].
    pub dependent: BTreeMap<usize, Vec<(usize, f64)>>,
    /// Frames by id (0: basic).
    pub frames: BTreeMap<u32, Frame>,
}

impl Structure {
    /// The g index of component `c` (1–6) of grid `g`.
    pub fn dof(&self, g: u32, c: u8) -> Option<usize> {
        self.index.get(&g).map(|&i| 6 * i + c as usize - 1)
    }

    /// Assembles stiffness and mass from the bulk data; `mpc` selects MPC equations (rigid
    /// elements always act).
    pub fn assemble(b: &BulkData, mpc: Option<u32>) -> R<Self> {
        let frames = frames(b)?;
        let grid_ids: Vec<u32> = b.grids.keys().copied().collect();
        let n = 6 * grid_ids.len();
        if n == 0 {
            return Err(NastranError::model("bulk data", "has no GRID".into()));
        }
        if n > MAX_DENSE_DOFS {
            return Err(NastranError::model(
                "bulk data",
                format!(
                    "{} grids ({n} components) exceed the dense assembly's limit of {MAX_DENSE_DOFS} components (about {:.1} GB for stiffness and mass)",
                    grid_ids.len(),
                    2.0 * 8.0 * (n as f64).powi(2) / 1e9
                ),
            ));
        }
        let index: BTreeMap<u32, usize> =
            grid_ids.iter().enumerate().map(|(i, &g)| (g, i)).collect();
        let frame_of = |cid: u32, what: &str| -> R<Frame> {
            frames.get(&cid).copied().ok_or_else(|| {
                NastranError::model(
                    what,
                    format!("uses coordinate system {cid}, which the model does not define"),
                )
            })
        };
        let mut position = Vec::with_capacity(grid_ids.len());
        let mut cd = Vec::with_capacity(grid_ids.len());
        for g in b.grids.values() {
            position.push(frame_of(g.cp, &format!("GRID {}", g.id))?.to_basic(g.x));
            cd.push(frame_of(g.cd, &format!("GRID {}", g.id))?);
        }
        let mut s = Structure {
            grid_ids,
            index,
            position,
            cd,
            k_gg: Mat::zeros(n, n),
            m_gg: Mat::zeros(n, n),
            dependent: BTreeMap::new(),
            frames,
        };
        let coupled = coupled_mass(b);
        for bar in b.bars.values() {
            s.add_bar(b, bar, coupled)?;
        }
        for e in b.springs.values() {
            s.add_scalar(e, true, "CELAS2")?;
        }
        for e in b.scalar_masses.values() {
            s.add_scalar(e, false, "CMASS2")?;
        }
        for m in b.masses.values() {
            s.add_conm(m)?;
        }
        for g in b.genels.values() {
            s.add_genel(g)?;
        }
        for e in b.shells.values() {
            s.add_shell(b, e, coupled, ShellPart::Value)?;
        }
        if let Some(w) = wtmass(b)? {
            let n = s.m_gg.nrows();
            for j in 0..n {
                for i in 0..n {
                    s.m_gg[(i, j)] *= w;
                }
            }
        }
        for r in b.rigids.values() {
            s.add_rigid(r)?;
        }
        if let Some(sid) = mpc {
            let eqs: Vec<_> = b.mpcs.iter().filter(|m| m.sid == sid).collect();
            if eqs.is_empty() {
                return Err(NastranError::model(
                    &format!("MPC = {sid}"),
                    "the case control selects an MPC set that no MPC card defines".into(),
                ));
            }
            for e in eqs {
                let place = |g: u32, c: u8| {
                    s.dof(g, c).ok_or_else(|| {
                        NastranError::at(
                            &e.source,
                            &format!("MPC {}", e.sid),
                            format!("refers to grid {g}, which the model does not define"),
                        )
                    })
                };
                let (g0, c0, a0) = e.terms[0];
                let d = place(g0, c0)?;
                let mut rhs = Vec::new();
                for &(g, c, a) in &e.terms[1..] {
                    rhs.push((place(g, c)?, -a / a0));
                }
                s.add_dependent(d, rhs, &format!("MPC {}", e.sid))?;
            }
        }
        Ok(s)
    }

    fn grid(&self, g: u32, what: &str) -> R<usize> {
        self.index.get(&g).copied().ok_or_else(|| {
            NastranError::model(
                what,
                format!("refers to grid {g}, which the model does not define"),
            )
        })
    }

    /// Adds a 12 × 12 (or any) element matrix on g indices.
    fn scatter(target: &mut Mat<f64>, dofs: &[usize], k: &[Vec<f64>]) {
        for (a, &i) in dofs.iter().enumerate() {
            for (b, &j) in dofs.iter().enumerate() {
                target[(i, j)] += k[a][b];
            }
        }
    }

    /// A bar or beam: Euler–Bernoulli (or Timoshenko where K1, K2 are given) stiffness in the
    /// element frame, pins condensed out, lumped (or with COUPMASS, consistent) translational
    /// mass; then offsets and the grids' displacement frames.
    fn add_bar(&mut self, b: &BulkData, bar: &Bar, coupled: bool) -> R<()> {
        self.add_bar_part(b, bar, coupled, None)
    }

    /// A CBAR or CBEAM's matrices (`wrt` none) or their derivatives in one dimension of its
    /// PBAR/PBEAM (exact: the element matrices in forward-mode dual numbers, the pin
    /// condensation included).
    fn add_bar_part(
        &mut self,
        b: &BulkData,
        bar: &Bar,
        coupled: bool,
        wrt: Option<BarDimension>,
    ) -> R<()> {
        let what = format!("{} {}", if bar.beam { "CBEAM" } else { "CBAR" }, bar.id);
        let p = b.bar_properties.get(&bar.pid).ok_or_else(|| {
            NastranError::model(
                &what,
                format!(
                    "refers to property {}, which no PBAR or PBEAM defines",
                    bar.pid
                ),
            )
        })?;
        let (e, g, rho) = match b.materials.get(&p.mid) {
            Some(Material::Mat1 { e, g, rho, .. }) => (*e, *g, *rho),
            Some(Material::Mat8 { .. }) => {
                return Err(NastranError::model(
                    &what,
                    format!("property {} uses the shell material MAT8 {}", p.id, p.mid),
                ))
            }
            None => {
                return Err(NastranError::model(
                    &what,
                    format!(
                        "property {} refers to material {}, which no MAT1 defines",
                        p.id, p.mid
                    ),
                ))
            }
        };
        if p.i12 != 0.0 {
            return Err(NastranError::model(
                &what,
                format!(
                    "property {} has a product of inertia I12; unsymmetric sections are not read",
                    p.id
                ),
            ));
        }
        let (ia, ib) = (self.grid(bar.ga, &what)?, self.grid(bar.gb, &what)?);
        let (fa, fb) = (self.cd[ia], self.cd[ib]);
        let wa = fa.rotate(bar.wa);
        let wb = fb.rotate(bar.wb);
        let xa = [
            self.position[ia][0] + wa[0],
            self.position[ia][1] + wa[1],
            self.position[ia][2] + wa[2],
        ];
        let xb = [
            self.position[ib][0] + wb[0],
            self.position[ib][1] + wb[1],
            self.position[ib][2] + wb[2],
        ];
        let axis = sub(xb, xa);
        let l = norm(axis);
        if !(l > 0.0) {
            return Err(NastranError::model(&what, "has zero length".into()));
        }
        let ex = scale(axis, 1.0 / l);
        let v = match bar.orientation {
            Orientation::Vector(v) => fa.rotate(v),
            Orientation::Grid(g0) => {
                let i0 = self.grid(g0, &what)?;
                sub(self.position[i0], self.position[ia])
            }
        };
        let ez = cross(ex, v);
        if !(norm(ez) > 1e-9 * norm(v).max(f64::MIN_POSITIVE)) || norm(v) == 0.0 {
            return Err(NastranError::model(
                &what,
                "its orientation vector is zero or parallel to the bar axis".into(),
            ));
        }
        let ez = scale(ez, 1.0 / norm(ez));
        let ey = cross(ez, ex);
        let released: Vec<usize> = bar
            .pa
            .iter()
            .map(|&c| c as usize - 1)
            .chain(bar.pb.iter().map(|&c| c as usize + 5))
            .collect();
        let material = BarMaterial { e, g, rho };
        let (k, m) = match wrt {
            None => bar_local(&material, &BarSection::<f64>::of(p), l, &released, coupled)
                .map_err(|r| NastranError::model(&what, r))?,
            Some(dim) => {
                let section = BarSection::<Dual<1>>::along(p, dim);
                let (k, m) = bar_local(&material, &section, l, &released, coupled)
                    .map_err(|r| NastranError::model(&what, r))?;
                let d = |a: Vec<Vec<Dual<1>>>| -> Vec<Vec<f64>> {
                    a.into_iter()
                        .map(|r| r.into_iter().map(|v| v.d[0]).collect())
                        .collect()
                };
                (d(k), d(m))
            }
        };
        // element frame → basic at the ends → grids (offsets) → displacement frames
        let lambda = [ex, ey, ez];
        let mut t = vec![vec![0.0; 12]; 12];
        for (end, (frame, w)) in [(fa, wa), (fb, wb)].into_iter().enumerate() {
            let r = frame.matrix();
            // u_end = u_g − S(w) θ_g  (θ × w = −w × θ), both in basic
            let sw = [[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]];
            for blk in 0..2 {
                for i in 0..3 {
                    for j in 0..3 {
                        // translation block: Λ R ; rotation block: Λ R ; coupling: −Λ S(w) R
                        let lr: f64 = (0..3).map(|q| lambda[i][q] * r[q][j]).sum();
                        t[6 * end + 3 * blk + i][6 * end + 3 * blk + j] = lr;
                        if blk == 0 {
                            let lsr: f64 = (0..3)
                                .map(|q| {
                                    lambda[i][q] * (0..3).map(|z| sw[q][z] * r[z][j]).sum::<f64>()
                                })
                                .sum();
                            t[6 * end + i][6 * end + 3 + j] = -lsr;
                        }
                    }
                }
            }
        }
        let dofs: Vec<usize> = (0..6)
            .map(|c| 6 * ia + c)
            .chain((0..6).map(|c| 6 * ib + c))
            .collect();
        Self::scatter(&mut self.k_gg, &dofs, &congruence(&k, &t));
        Self::scatter(&mut self.m_gg, &dofs, &congruence(&m, &t));
        Ok(())
    }

    /// A CQUAD4 or CTRIA3: gustkit's flat-plate elements in the element's plane (CQUAD4: DKQ
    /// bending, bilinear membrane; CTRIA3: DKT bending, constant-strain membrane; Kirchhoff
    /// theory, so PSHELL's transverse shear MID3 is not used), in the frame x along G1→G2, z
    /// along the normal of the diagonals (of G1G2 × G1G3 for a triangle); the material's axis 1
    /// from MCID or THETA; lumped translational mass, or with COUPMASS the consistent mass. No
    /// drilling stiffness: the in-plane rotation of a grid that nothing else holds is removed as
    /// unconnected.
    fn add_shell(
        &mut self,
        b: &BulkData,
        e: &super::bulk::Shell,
        coupled: bool,
        part: ShellPart,
    ) -> R<()> {
        use crate::structure::element;
        let what = format!(
            "{} {}",
            if e.grids.len() == 4 {
                "CQUAD4"
            } else {
                "CTRIA3"
            },
            e.id
        );
        let nodes = e.grids.len();
        if e.zoffs != 0.0 {
            return Err(NastranError::model(
                &what,
                format!(
                    "ZOFFS = {} is not read: give 0 (the mid-surface at the grids)",
                    e.zoffs
                ),
            ));
        }
        let p = b.pshells.get(&e.pid).ok_or_else(|| {
            NastranError::model(
                &what,
                format!("refers to property {}, which no PSHELL defines", e.pid),
            )
        })?;
        let t = match e.corner_t.iter().flatten().next() {
            None => p.t,
            Some(&t0) => {
                if e.corner_t
                    .iter()
                    .any(|c| c.is_some_and(|v| (v - t0).abs() > 1e-12 * t0.abs()))
                {
                    return Err(NastranError::model(
                        &what,
                        "corner thicknesses that differ are not read: give one thickness".into(),
                    ));
                }
                t0
            }
        };
        if !(t > 0.0) {
            return Err(NastranError::model(
                &what,
                format!("its thickness must be positive (got {t})"),
            ));
        }
        let idx: Vec<usize> = e
            .grids
            .iter()
            .map(|&g| self.grid(g, &what))
            .collect::<R<_>>()?;
        let x: Vec<[f64; 3]> = idx.iter().map(|&i| self.position[i]).collect();
        let n = if nodes == 4 {
            cross(sub(x[2], x[0]), sub(x[3], x[1]))
        } else {
            cross(sub(x[1], x[0]), sub(x[2], x[0]))
        };
        if !(norm(n) > 0.0) {
            return Err(NastranError::model(
                &what,
                if nodes == 4 {
                    "its diagonals are parallel: a degenerate quadrilateral".into()
                } else {
                    "its grids lie on one line: a degenerate triangle".into()
                },
            ));
        }
        let ez = scale(n, 1.0 / norm(n));
        let d12 = sub(x[1], x[0]);
        let ex = sub(d12, scale(ez, dot(d12, ez)));
        let ex = scale(ex, 1.0 / norm(ex));
        let ey = cross(ez, ex);
        let centre = scale(
            x.iter()
                .fold([0.0; 3], |a, p| [a[0] + p[0], a[1] + p[1], a[2] + p[2]]),
            1.0 / nodes as f64,
        );
        let local: Vec<[f64; 2]> = x
            .iter()
            .map(|&p| {
                let d = sub(p, centre);
                [dot(d, ex), dot(d, ey)]
            })
            .collect();
        let xy: element::Quad<f64> = std::array::from_fn(|i| local[i % nodes]);
        let tri: crate::structure::triangle::Tri = std::array::from_fn(|i| local[i]);
        if nodes == 4 && !element::is_valid(&xy) {
            return Err(NastranError::model(
                &what,
                "is not a convex quadrilateral ordered around its normal (G1–G4 in turn)".into(),
            ));
        }
        // the material's axis 1 in the element frame
        let axis1 = match e.mcid {
            Some(cid) => {
                let f = *self.frames.get(&cid).ok_or_else(|| {
                    NastranError::model(
                        &what,
                        format!("MCID {cid} is not a coordinate system of the model"),
                    )
                })?;
                let a = f.axes[0];
                let a = sub(a, scale(ez, dot(a, ez)));
                if !(norm(a) > 1e-9) {
                    return Err(NastranError::model(
                        &what,
                        format!("the x axis of MCID {cid} is normal to the element"),
                    ));
                }
                scale(a, 1.0 / norm(a))
            }
            None => {
                let (s_, c_) = e.theta.to_radians().sin_cos();
                [
                    ex[0] * c_ + ey[0] * s_,
                    ex[1] * c_ + ey[1] * s_,
                    ex[2] * c_ + ey[2] * s_,
                ]
            }
        };
        // gustkit's grain angle: from the frame's +y toward +x
        let grain = dot(axis1, ex).atan2(dot(axis1, ey));
        let material = |mid: u32| -> R<(crate::structure::Orthotropic, f64)> {
            match b.materials.get(&mid) {
                Some(Material::Mat1 { e, g, nu, rho, .. }) => Ok((
                    crate::structure::Orthotropic {
                        e1: *e,
                        e2: *e,
                        g12: *g,
                        nu12: *nu,
                        density: *rho,
                        grain_angle: grain,
                    },
                    *rho,
                )),
                Some(Material::Mat8 {
                    e1,
                    e2,
                    nu12,
                    g12,
                    rho,
                    ..
                }) => Ok((
                    crate::structure::Orthotropic {
                        e1: *e1,
                        e2: *e2,
                        g12: *g12,
                        nu12: *nu12,
                        density: *rho,
                        grain_angle: grain,
                    },
                    *rho,
                )),
                None => Err(NastranError::model(
                    &what,
                    format!(
                        "PSHELL {} refers to material {mid}, which no MAT1 or MAT8 defines",
                        p.id
                    ),
                )),
            }
        };
        use crate::structure::triangle;
        let nl = 5 * nodes;
        let mut k_loc = vec![vec![0.0; nl]; nl];
        let mut m_loc = vec![vec![0.0; nl]; nl];
        // local dofs per node: (w, w_x, w_y, u, v); bending block at 5i..5i+3, membrane 5i+3..
        // the matrices' factors in t: membrane t, bending t³, mass NSM + ρ t (or their
        // derivatives in t)
        let derivative = part == ShellPart::ThicknessDerivative;
        let (f_membrane, f_bending) = if derivative {
            (1.0, 3.0 * t * t)
        } else {
            (t, t * t * t)
        };
        let mut rho_t = if derivative { 0.0 } else { p.nsm };
        if let Some(m1) = p.mid1 {
            let (mat, rho) = material(m1)?;
            rho_t += if derivative { rho } else { rho * t };
            let km: Vec<Vec<f64>> = if nodes == 4 {
                element::membrane_stiffness(&xy, &mat.qbar())
                    .iter()
                    .map(|r| r.to_vec())
                    .collect()
            } else {
                triangle::cst_stiffness(&tri, &mat.qbar())
                    .iter()
                    .map(|r| r.to_vec())
                    .collect()
            };
            for a in 0..2 * nodes {
                for c in 0..2 * nodes {
                    k_loc[5 * (a / 2) + 3 + a % 2][5 * (c / 2) + 3 + c % 2] +=
                        km[a][c] * f_membrane;
                }
            }
        }
        if let Some(m2) = p.mid2 {
            let (mat, _) = material(m2)?;
            let d_unit = mat.qbar().map(|r| r.map(|v| v * p.bending_ratio / 12.0));
            let kb: Vec<Vec<f64>> = if nodes == 4 {
                element::dkq_stiffness(&xy, &d_unit)
                    .iter()
                    .map(|r| r.to_vec())
                    .collect()
            } else {
                triangle::dkt_stiffness(&tri, &d_unit)
                    .iter()
                    .map(|r| r.to_vec())
                    .collect()
            };
            for a in 0..3 * nodes {
                for c in 0..3 * nodes {
                    k_loc[5 * (a / 3) + a % 3][5 * (c / 3) + c % 3] += kb[a][c] * f_bending;
                }
            }
        }
        if coupled && nodes == 3 {
            // linear w, u and v: the consistent mass on each translation
            let ml = triangle::linear_mass(&tri);
            for i in 0..3 {
                for j in 0..3 {
                    for d in [0, 3, 4] {
                        m_loc[5 * i + d][5 * j + d] += ml[i][j] * rho_t;
                    }
                }
            }
        } else if coupled {
            let mb = element::bending_mass(&xy);
            let mm = element::membrane_mass(&xy);
            for a in 0..12 {
                for c in 0..12 {
                    m_loc[5 * (a / 3) + a % 3][5 * (c / 3) + c % 3] += mb[a][c] * rho_t;
                }
            }
            for a in 0..8 {
                for c in 0..8 {
                    m_loc[5 * (a / 2) + 3 + a % 2][5 * (c / 2) + 3 + c % 2] += mm[a][c] * rho_t;
                }
            }
        } else {
            let area = if nodes == 4 {
                element::area(&xy)
            } else {
                0.5 * triangle::twice_area(&tri)
            };
            let share = rho_t * area / nodes as f64;
            for i in 0..nodes {
                for d in [0, 3, 4] {
                    m_loc[5 * i + d][5 * i + d] = share;
                }
            }
        }
        // local (w, w_x, w_y, u, v) of node i from its six components (displacement frame):
        // w = n·u, w_x = −(e_y·θ), w_y = e_x·θ, u = e_x·u, v = e_y·u
        let mut t_mat = vec![vec![0.0; 6 * nodes]; nl];
        for (i, &gi) in idx.iter().enumerate() {
            let r = self.cd[gi];
            for c in 0..3 {
                let axis = r.axes[c];
                t_mat[5 * i][6 * i + c] = dot(ez, axis);
                t_mat[5 * i + 1][6 * i + 3 + c] = -dot(ey, axis);
                t_mat[5 * i + 2][6 * i + 3 + c] = dot(ex, axis);
                t_mat[5 * i + 3][6 * i + c] = dot(ex, axis);
                t_mat[5 * i + 4][6 * i + c] = dot(ey, axis);
            }
        }
        let dofs: Vec<usize> = idx
            .iter()
            .flat_map(|&gi| (0..6).map(move |c| 6 * gi + c))
            .collect();
        let ng = 6 * nodes;
        let project = |loc: &Vec<Vec<f64>>| -> Vec<Vec<f64>> {
            let lt: Vec<Vec<f64>> = (0..nl)
                .map(|a| {
                    (0..ng)
                        .map(|j| (0..nl).map(|q| loc[a][q] * t_mat[q][j]).sum())
                        .collect()
                })
                .collect();
            (0..ng)
                .map(|i| {
                    (0..ng)
                        .map(|j| (0..nl).map(|a| t_mat[a][i] * lt[a][j]).sum())
                        .collect()
                })
                .collect()
        };
        Self::scatter(&mut self.k_gg, &dofs, &project(&k_loc));
        Self::scatter(&mut self.m_gg, &dofs, &project(&m_loc));
        Ok(())
    }

    /// ∂K/∂T and ∂M/∂T (g-set) of the shells whose PSHELL `pid` gives their thickness (shells
    /// with corner thicknesses T1–T4 do not depend on it): exact, the element matrices being
    /// t (membrane), t³ (bending) and NSM + ρt (mass) times fixed matrices; PARAM WTMASS
    /// applied to ∂M. With mass-normalized modes, ∂λᵢ/∂T = φᵢᵀ (∂K − λᵢ ∂M) φᵢ.
    pub fn shell_thickness_derivative(&self, b: &BulkData, pid: u32) -> R<(Mat<f64>, Mat<f64>)> {
        if !b.pshells.contains_key(&pid) {
            return Err(NastranError::model(
                &format!("PSHELL {pid}"),
                "is not defined: no thickness to differentiate".into(),
            ));
        }
        let coupled = coupled_mass(b);
        let mut d = self.zeroed();
        for e in b.shells.values() {
            if e.pid == pid && e.corner_t.iter().all(|c| c.is_none()) {
                d.add_shell(b, e, coupled, ShellPart::ThicknessDerivative)?;
            }
        }
        d.derivative_matrices(b)
    }

    /// ∂K/∂p and ∂M/∂p (g-set) of the bars and beams whose PBAR/PBEAM `pid` gives dimension
    /// `dim` (A, I1, I2 or J): exact (the element matrices in forward-mode dual numbers, with
    /// the shear flexibility and the pin condensation, which make them nonlinear in the
    /// dimensions); PARAM WTMASS applied to ∂M.
    pub fn bar_property_derivative(
        &self,
        b: &BulkData,
        pid: u32,
        dim: BarDimension,
    ) -> R<(Mat<f64>, Mat<f64>)> {
        if !b.bar_properties.contains_key(&pid) {
            return Err(NastranError::model(
                &format!("PBAR {pid}"),
                "is not defined (no PBAR or PBEAM): no dimension to differentiate".into(),
            ));
        }
        let coupled = coupled_mass(b);
        let mut d = self.zeroed();
        for bar in b.bars.values().filter(|bar| bar.pid == pid) {
            d.add_bar_part(b, bar, coupled, Some(dim))?;
        }
        d.derivative_matrices(b)
    }

    /// This structure's grids and frames with zero matrices (to assemble derivatives into).
    fn zeroed(&self) -> Structure {
        let n = self.k_gg.nrows();
        Structure {
            grid_ids: self.grid_ids.clone(),
            index: self.index.clone(),
            position: self.position.clone(),
            cd: self.cd.clone(),
            k_gg: Mat::zeros(n, n),
            m_gg: Mat::zeros(n, n),
            dependent: BTreeMap::new(),
            frames: self.frames.clone(),
        }
    }

    /// The assembled derivative matrices, PARAM WTMASS applied to the mass.
    fn derivative_matrices(mut self, b: &BulkData) -> R<(Mat<f64>, Mat<f64>)> {
        if let Some(w) = wtmass(b)? {
            let n = self.m_gg.nrows();
            for j in 0..n {
                for i in 0..n {
                    self.m_gg[(i, j)] *= w;
                }
            }
        }
        Ok((self.k_gg, self.m_gg))
    }

    /// A scalar spring or mass between two grid components (or one and ground).
    fn add_scalar(&mut self, e: &Scalar, stiffness: bool, card: &str) -> R<()> {
        let what = format!("{card} {}", e.id);
        let mut ends = Vec::new();
        for (g, c, sign) in [(e.g1, e.c1, 1.0), (e.g2, e.c2, -1.0)] {
            if g == 0 {
                continue;
            }
            if c == 0 {
                return Err(NastranError::model(
                    &what,
                    format!("names grid {g} without a component (scalar points are not read)"),
                ));
            }
            ends.push((6 * self.grid(g, &what)? + c as usize - 1, sign));
        }
        let target = if stiffness {
            &mut self.k_gg
        } else {
            &mut self.m_gg
        };
        for &(i, si) in &ends {
            for &(j, sj) in &ends {
                target[(i, j)] += si * sj * e.value;
            }
        }
        Ok(())
    }

    /// CONM2 (mass, offset and inertia about the centre of gravity) or CONM1 (a 6 × 6 matrix)
    /// at a grid, into its displacement frame.
    fn add_conm(&mut self, c: &Conm) -> R<()> {
        let (id, grid) = match c {
            Conm::Conm2 { id, grid, .. } | Conm::Conm1 { id, grid, .. } => (*id, *grid),
        };
        let what = format!(
            "{} {id}",
            if matches!(c, Conm::Conm2 { .. }) {
                "CONM2"
            } else {
                "CONM1"
            }
        );
        let i = self.grid(grid, &what)?;
        let frame_of = |cid: u32| -> R<Frame> {
            self.frames.get(&cid).copied().ok_or_else(|| {
                NastranError::model(
                    &what,
                    format!("uses coordinate system {cid}, which the model does not define"),
                )
            })
        };
        // the 6 × 6 mass about the grid in basic
        let mut mb = [[0.0; 6]; 6];
        match c {
            Conm::Conm2 {
                cid,
                mass,
                offset,
                inertia,
                ..
            } => {
                let (frame, r) = match *cid {
                    -1 => (Frame::BASIC, sub(*offset, self.position[i])),
                    c if c >= 0 => {
                        let f = frame_of(c as u32)?;
                        (f, f.rotate(*offset))
                    }
                    c => {
                        return Err(NastranError::model(
                            &what,
                            format!("CID must be −1 or a coordinate system (got {c})"),
                        ))
                    }
                };
                let [i11, i21, i22, i31, i32, i33] = *inertia;
                let local = [[i11, -i21, -i31], [-i21, i22, -i32], [-i31, -i32, i33]];
                let rm = frame.matrix();
                let mut j = [[0.0; 3]; 3];
                for a in 0..3 {
                    for bb in 0..3 {
                        j[a][bb] = (0..3)
                            .map(|p| {
                                (0..3)
                                    .map(|q| rm[a][p] * local[p][q] * rm[bb][q])
                                    .sum::<f64>()
                            })
                            .sum();
                    }
                }
                // E = [[I, −S(r)], [0, I]]: M = Eᵀ diag(m I, J) E
                let s = [[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]];
                for a in 0..3 {
                    mb[a][a] = *mass;
                    for bb in 0..3 {
                        mb[a][3 + bb] = -mass * s[a][bb];
                        mb[3 + bb][a] = -mass * s[a][bb];
                        let sts: f64 = (0..3).map(|q| s[q][a] * s[q][bb]).sum();
                        mb[3 + a][3 + bb] = j[a][bb] + mass * sts;
                    }
                }
            }
            Conm::Conm1 { cid, lower, .. } => {
                let f = frame_of(*cid)?;
                let mut local = [[0.0; 6]; 6];
                let mut k = 0;
                for a in 0..6 {
                    for bb in 0..=a {
                        local[a][bb] = lower[k];
                        local[bb][a] = lower[k];
                        k += 1;
                    }
                }
                let r6 = block_rotation(&f);
                for a in 0..6 {
                    for bb in 0..6 {
                        mb[a][bb] = (0..6)
                            .map(|p| {
                                (0..6)
                                    .map(|q| r6[a][p] * local[p][q] * r6[bb][q])
                                    .sum::<f64>()
                            })
                            .sum();
                    }
                }
            }
        }
        // basic → the grid's displacement frame: M_cd = Rᵀ M_basic R
        let r6 = block_rotation(&self.cd[i]);
        for a in 0..6 {
            for bb in 0..6 {
                let v: f64 = (0..6)
                    .map(|p| (0..6).map(|q| r6[p][a] * mb[p][q] * r6[q][bb]).sum::<f64>())
                    .sum();
                self.m_gg[(6 * i + a, 6 * i + bb)] += v;
            }
        }
        Ok(())
    }

    /// GENEL: K (or Z⁻¹) on the independent components, with S the dependent ones:
    /// [K, −K S; −Sᵀ K, Sᵀ K S].
    fn add_genel(&mut self, g: &super::bulk::Genel) -> R<()> {
        let what = format!("GENEL {}", g.id);
        let m = g.ui.len();
        let n = g.ud.len();
        let mut dofs = Vec::with_capacity(m + n);
        for &(grid, c) in g.ui.iter().chain(&g.ud) {
            if c == 0 {
                return Err(NastranError::model(
                    &what,
                    format!("names grid {grid} without a component"),
                ));
            }
            dofs.push(6 * self.grid(grid, &what)? + c as usize - 1);
        }
        // the lower triangle column by column
        let mut mat = Mat::<f64>::zeros(m, m);
        let mut k = 0;
        for j in 0..m {
            for i in j..m {
                mat[(i, j)] = g.matrix[k];
                mat[(j, i)] = g.matrix[k];
                k += 1;
            }
        }
        let kk = if g.flexibility {
            let llt = mat.llt(Side::Lower).map_err(|_| {
                NastranError::model(
                    &what,
                    "its flexibility matrix Z is not positive definite".into(),
                )
            })?;
            faer::linalg::solvers::DenseSolveCore::inverse(&llt)
        } else {
            mat
        };
        let s = Mat::<f64>::from_fn(m, n, |i, j| g.s[i * n + j]);
        let ks = &kk * &s;
        let stks = s.transpose() * &ks;
        let mut full = vec![vec![0.0; m + n]; m + n];
        for i in 0..m {
            for j in 0..m {
                full[i][j] = kk[(i, j)];
            }
            for j in 0..n {
                full[i][m + j] = -ks[(i, j)];
                full[m + j][i] = -ks[(i, j)];
            }
        }
        for i in 0..n {
            for j in 0..n {
                full[m + i][m + j] = stks[(i, j)];
            }
        }
        Self::scatter(&mut self.k_gg, &dofs, &full);
        Ok(())
    }

    /// A rigid element as dependent components: RBE2 (every listed component of GM follows GN
    /// rigidly) and RBAR with all six components independent at one end.
    fn add_rigid(&mut self, r: &Rigid) -> R<()> {
        let (id, indep, deps): (u32, u32, Vec<(u32, Vec<u8>)>) = match r {
            Rigid::Rbe2 { id, gn, cm, gm } => {
                (*id, *gn, gm.iter().map(|&g| (g, cm.clone())).collect())
            }
            Rigid::Rbar {
                id,
                ga,
                gb,
                cna,
                cnb,
                cma,
                cmb,
            } => {
                let all = vec![1u8, 2, 3, 4, 5, 6];
                if *cna == all && cnb.is_empty() && cma.is_empty() {
                    (
                        *id,
                        *ga,
                        vec![(*gb, if cmb.is_empty() { all } else { cmb.clone() })],
                    )
                } else if *cnb == all && cna.is_empty() && cmb.is_empty() {
                    (
                        *id,
                        *gb,
                        vec![(*ga, if cma.is_empty() { all } else { cma.clone() })],
                    )
                } else {
                    return Err(NastranError::model(&format!("RBAR {id}"), "only an RBAR with all six components independent at one end (CNA = 123456 or CNB = 123456) is read".into()));
                }
            }
        };
        let what = format!("rigid element {id}");
        let n = self.grid(indep, &what)?;
        let rn = block_rotation(&self.cd[n]);
        for (gm, comps) in deps {
            let m = self.grid(gm, &what)?;
            let d = sub(self.position[m], self.position[n]);
            // basic: u_m = u_n + θ_n × d = u_n − S(d) θ_n, θ_m = θ_n
            let s = [[0.0, -d[2], d[1]], [d[2], 0.0, -d[0]], [-d[1], d[0], 0.0]];
            let mut e = [[0.0; 6]; 6];
            for i in 0..6 {
                e[i][i] = 1.0;
            }
            for i in 0..3 {
                for j in 0..3 {
                    e[i][3 + j] = -s[i][j];
                }
            }
            let rm = block_rotation(&self.cd[m]);
            // u_m(cd) = R_mᵀ E R_n u_n(cd)
            for &c in &comps {
                let row = c as usize - 1;
                let mut terms = Vec::new();
                for j in 0..6 {
                    let v: f64 = (0..6)
                        .map(|p| rm[p][row] * (0..6).map(|q| e[p][q] * rn[q][j]).sum::<f64>())
                        .sum();
                    if v.abs() > 1e-14 {
                        terms.push((6 * n + j, v));
                    }
                }
                self.add_dependent(6 * m + row, terms, &what)?;
            }
        }
        Ok(())
    }

    fn add_dependent(&mut self, d: usize, terms: Vec<(usize, f64)>, what: &str) -> R<()> {
        if self.dependent.insert(d, terms).is_some() {
            return Err(NastranError::model(what, format!(
                "makes component {} of grid {} dependent a second time (a component belongs to one rigid element or MPC)",
                d % 6 + 1,
                self.grid_ids[d / 6]
            )));
        }
        Ok(())
    }

    /// The transformation u_g = T u_a onto the analysis set: dependent components expressed in
    /// independent ones, the constrained (`spc`, g indices) and unconnected (neither stiffness
    /// nor mass: Nastran's AUTOSPC) components removed. Returns T (one column an a-set
    /// coordinate: an independent component, or a direction of a grid's translations or
    /// rotations) and the components AUTOSPC removed.
    pub fn reduction(&self, spc: &BTreeSet<usize>) -> R<(Mat<f64>, Vec<usize>)> {
        let n = self.k_gg.nrows();
        for d in spc {
            if self.dependent.contains_key(d) {
                return Err(NastranError::model("SPC", format!(
                    "constrains component {} of grid {}, which a rigid element or MPC makes dependent",
                    d % 6 + 1,
                    self.grid_ids[d / 6]
                )));
            }
        }
        // dependent components in independent ones (chains resolved, circles refused)
        let mut resolved: BTreeMap<usize, Vec<(usize, f64)>> = BTreeMap::new();
        fn resolve(
            d: usize,
            dep: &BTreeMap<usize, Vec<(usize, f64)>>,
            done: &mut BTreeMap<usize, Vec<(usize, f64)>>,
            stack: &mut Vec<usize>,
        ) -> Result<Vec<(usize, f64)>, usize> {
            if let Some(r) = done.get(&d) {
                return Ok(r.clone());
            }
            if stack.contains(&d) {
                return Err(d);
            }
            stack.push(d);
            let mut acc: BTreeMap<usize, f64> = BTreeMap::new();
            for &(j, f) in &dep[&d] {
                if dep.contains_key(&j) {
                    for (q, g) in resolve(j, dep, done, stack)? {
                        *acc.entry(q).or_default() += f * g;
                    }
                } else {
                    *acc.entry(j).or_default() += f;
                }
            }
            stack.pop();
            let r: Vec<(usize, f64)> = acc.into_iter().collect();
            done.insert(d, r.clone());
            Ok(r)
        }
        for &d in self.dependent.keys() {
            resolve(d, &self.dependent, &mut resolved, &mut Vec::new()).map_err(|c| {
                NastranError::model(
                    "rigid elements and MPCs",
                    format!(
                        "make component {} of grid {} depend on itself",
                        c % 6 + 1,
                        self.grid_ids[c / 6]
                    ),
                )
            })?;
        }
        // the independent, unconstrained components that something connects
        let touched =
            |i: usize| (0..n).any(|j| self.k_gg[(i, j)] != 0.0 || self.m_gg[(i, j)] != 0.0);
        let mut used: BTreeSet<usize> = BTreeSet::new();
        for (&d, terms) in &resolved {
            if touched(d) {
                used.extend(terms.iter().map(|t| t.0));
            }
        }
        let mut a_set = Vec::new();
        let mut auto_spc = Vec::new();
        for i in 0..n {
            if resolved.contains_key(&i) || spc.contains(&i) {
                continue;
            }
            if touched(i) || used.contains(&i) {
                a_set.push(i);
            } else {
                auto_spc.push(i);
            }
        }
        // AUTOSPC in any direction: a grid's translations or rotations, all three independent
        // and free, whose stiffness and mass rows vanish along some direction (the normal
        // rotation of a grid that only coplanar shells hold) lose that direction
        let scale_k = (0..n).map(|i| self.k_gg[(i, i)].abs()).fold(0.0, f64::max);
        let scale_m = (0..n).map(|i| self.m_gg[(i, i)].abs()).fold(0.0, f64::max);
        let w = if scale_m > 0.0 {
            scale_k / scale_m
        } else {
            1.0
        };
        let in_a: BTreeSet<usize> = a_set.iter().copied().collect();
        // the a-set's columns as combinations of g components
        let mut columns: Vec<Vec<(usize, f64)>> = Vec::new();
        let mut done: BTreeSet<usize> = BTreeSet::new();
        for &i in &a_set {
            if done.contains(&i) {
                continue;
            }
            let block = 3 * (i / 3);
            let members = [block, block + 1, block + 2];
            let whole = members
                .iter()
                .all(|m| in_a.contains(m) && !used.contains(m));
            if !whole {
                columns.push(vec![(i, 1.0)]);
                done.insert(i);
                continue;
            }
            done.extend(members);
            let gram = Mat::<f64>::from_fn(3, 3, |a, c| {
                (0..n)
                    .map(|j| {
                        self.k_gg[(members[a], j)] * self.k_gg[(members[c], j)]
                            + w * w * self.m_gg[(members[a], j)] * self.m_gg[(members[c], j)]
                    })
                    .sum()
            });
            let eig = gram.self_adjoint_eigen(Side::Lower).map_err(|_| {
                NastranError::model("model", "the eigensolver did not converge".into())
            })?;
            // the rows' size along each eigenvector, measured on the rows themselves (the
            // Gram matrix's small eigenvalues carry its round-off, ε ‖G‖)
            let size: Vec<f64> = (0..3)
                .map(|d| {
                    (0..n)
                        .map(|j| {
                            let (mut kr, mut mr) = (0.0, 0.0);
                            for (a, &m) in members.iter().enumerate() {
                                kr += eig.U()[(a, d)] * self.k_gg[(m, j)];
                                mr += eig.U()[(a, d)] * self.m_gg[(m, j)];
                            }
                            kr * kr + w * w * mr * mr
                        })
                        .sum::<f64>()
                        .sqrt()
                })
                .collect();
            let top = size.iter().fold(0.0f64, |a, &b| a.max(b));
            for d in 0..3 {
                if size[d] > 1e-10 * top {
                    columns.push(
                        members
                            .iter()
                            .enumerate()
                            .map(|(a, &m)| (m, eig.U()[(a, d)]))
                            .collect(),
                    );
                } else {
                    auto_spc.push(members[d]);
                }
            }
        }
        let mut t = Mat::<f64>::zeros(n, columns.len());
        let mut col_of: BTreeMap<usize, Vec<(usize, f64)>> = BTreeMap::new();
        for (c, terms) in columns.iter().enumerate() {
            for &(i, f) in terms {
                t[(i, c)] = f;
                col_of.entry(i).or_default().push((c, f));
            }
        }
        for (&d, terms) in &resolved {
            for &(j, f) in terms {
                for &(c, g) in col_of.get(&j).into_iter().flatten() {
                    t[(d, c)] += f * g;
                }
            }
        }
        Ok((t, auto_spc))
    }
}

/// Tᵀ k T for small dense element matrices.
fn congruence(k: &[Vec<f64>], t: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let n = k.len();
    let kt: Vec<Vec<f64>> = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| (0..n).map(|q| k[i][q] * t[q][j]).sum())
                .collect()
        })
        .collect();
    (0..n)
        .map(|i| {
            (0..n)
                .map(|j| (0..n).map(|q| t[q][i] * kt[q][j]).sum())
                .collect()
        })
        .collect()
}

/// The 6 × 6 block rotation diag(R, R) of a frame (basic = R · local).
fn block_rotation(f: &Frame) -> [[f64; 6]; 6] {
    let r = f.matrix();
    let mut out = [[0.0; 6]; 6];
    for b in 0..2 {
        for i in 0..3 {
            for j in 0..3 {
                out[3 * b + i][3 * b + j] = r[i][j];
            }
        }
    }
    out
}

/// Static condensation of the `released` rows and columns (they carry no force).
fn condense<T: ScalarOps>(k: &mut [Vec<T>], released: &[usize]) -> Result<(), String> {
    for &r in released {
        let p = k[r][r];
        if !(p.re().abs() > 0.0) {
            // already free (a released component with no stiffness)
            continue;
        }
        let n = k.len();
        let row = k[r].clone();
        for i in 0..n {
            let f = k[i][r] / p;
            for j in 0..n {
                k[i][j] -= f * row[j];
            }
        }
        for i in 0..n {
            k[i][r] = T::cst(0.0);
            k[r][i] = T::cst(0.0);
        }
    }
    if k.iter().flatten().any(|v| !v.re().is_finite()) {
        return Err("its pin flags leave a singular element".into());
    }
    Ok(())
}

/// Real modes of the a-set: eigenvalues λ = ω² ascending and mass-normalized shapes in the
/// g-set.
#[derive(Clone, Debug)]
pub struct RealModes {
    pub lambda: Vec<f64>,
    /// One column a mode, g-set (every grid's six components in its displacement frame).
    pub phi_g: Mat<f64>,
    /// The same modes in the a-set coordinates (u_g = T u_a): what NORM MAX scales.
    pub phi_a: Mat<f64>,
    /// The a-set size and the components removed as unconnected.
    pub n_a: usize,
    pub auto_spc: Vec<usize>,
}

impl RealModes {
    pub fn freq_hz(&self) -> Vec<f64> {
        self.lambda
            .iter()
            .map(|l| l.max(0.0).sqrt() / (2.0 * std::f64::consts::PI))
            .collect()
    }
}

/// Solves K φ = λ M φ on the a-set (every root, dense): K + σM = L Lᵀ with a shift σ > 0 when K
/// is singular (a free body), the eigenvalues of L⁻¹ M L⁻ᵀ (μ = 1/(λ + σ); μ = 0 belongs to
/// massless components and is dropped), each λ refined by its Rayleigh quotient.
pub fn real_modes(s: &Structure, spc: &BTreeSet<usize>, rigid_body: usize) -> R<RealModes> {
    let (t, auto_spc) = s.reduction(spc)?;
    let k = t.transpose() * &s.k_gg * &t;
    let m = t.transpose() * &s.m_gg * &t;
    let n = k.nrows();
    if n == 0 {
        return Err(NastranError::model(
            "model",
            "every component is constrained: no mode is left".into(),
        ));
    }
    let k = Mat::from_fn(n, n, |i, j| 0.5 * (k[(i, j)] + k[(j, i)]));
    let m = Mat::from_fn(n, n, |i, j| 0.5 * (m[(i, j)] + m[(j, i)]));
    let scale_k = (0..n).map(|i| k[(i, i)].abs()).fold(0.0, f64::max);
    let scale_m = (0..n).map(|i| m[(i, i)].abs()).fold(0.0, f64::max);
    if !(scale_m > 0.0) {
        return Err(NastranError::model(
            "model",
            "has no mass on its free components".into(),
        ));
    }
    let (_, chol) = match k.llt(Side::Lower) {
        Ok(l) if rigid_body == 0 => (0.0, l.L().to_owned()),
        _ => {
            // a free body (or a mechanism): shift by a fraction of the stiffness-to-mass scale
            let sigma = 1e-6 * scale_k / scale_m;
            let shifted = Mat::from_fn(n, n, |i, j| k[(i, j)] + sigma * m[(i, j)]);
            let l = shifted.llt(Side::Lower).map_err(|_| {
                NastranError::model("model", "stiffness plus a shifted mass is not positive definite: a component with neither stiffness nor mass coupling, or negative stiffness".into())
            })?;
            (sigma, l.L().to_owned())
        }
    };
    let mut b = m.clone();
    solve_lower_triangular_in_place(chol.as_ref(), b.as_mut(), Par::Seq);
    let mut bt = b.transpose().to_owned();
    solve_lower_triangular_in_place(chol.as_ref(), bt.as_mut(), Par::Seq);
    let c = Mat::from_fn(n, n, |i, j| 0.5 * (bt[(i, j)] + bt[(j, i)]));
    let eig = c
        .self_adjoint_eigen(Side::Lower)
        .map_err(|_| NastranError::model("model", "the eigensolver did not converge".into()))?;
    let mu_max = eig.S()[n - 1];
    let mut pairs: Vec<(f64, Vec<f64>)> = Vec::new();
    for j in (0..n).rev() {
        let mu = eig.S()[j];
        if !(mu > 1e-13 * mu_max) {
            break;
        }
        let mut y = Mat::from_fn(n, 1, |i, _| eig.U()[(i, j)]);
        solve_upper_triangular_in_place(chol.transpose(), y.as_mut(), Par::Seq);
        let phi: Vec<f64> = (0..n).map(|i| y[(i, 0)]).collect();
        let quad = |a: &Mat<f64>| -> f64 {
            (0..n)
                .map(|i| phi[i] * (0..n).map(|q| a[(i, q)] * phi[q]).sum::<f64>())
                .sum()
        };
        let (pk, pm) = (quad(&k), quad(&m));
        let lambda = pk / pm;
        let norm = 1.0 / pm.sqrt();
        pairs.push((lambda, phi.iter().map(|v| v * norm).collect()));
    }
    let zero = pairs
        .iter()
        .filter(|(l, _)| l.abs() < 1e-8 * scale_k / scale_m)
        .count();
    if zero > rigid_body {
        return Err(NastranError::model("model", format!(
            "has {zero} zero-frequency modes but SUPORT names {rigid_body} components: a mechanism (an unconnected or unconstrained component); constrain it (SPC, GRID PS) or add it to SUPORT for a free body"
        )));
    }
    let n_modes = pairs.len();
    let ng = t.nrows();
    let mut phi_g = Mat::<f64>::zeros(ng, n_modes);
    for (c, (_, phi)) in pairs.iter().enumerate() {
        for i in 0..ng {
            phi_g[(i, c)] = (0..n).map(|q| t[(i, q)] * phi[q]).sum();
        }
    }
    let phi_a = Mat::<f64>::from_fn(n, n_modes, |q, c| pairs[c].1[q]);
    Ok(RealModes {
        lambda: pairs.iter().map(|p| p.0).collect(),
        phi_g,
        phi_a,
        n_a: t.ncols(),
        auto_spc,
    })
}

/// The constrained components of a subcase: the SPC set it selects (SPC, SPC1; enforced values
/// must be zero in a modal analysis) and every grid's permanent constraints (GRID PS, GRDSET).
pub fn constrained(s: &Structure, b: &BulkData, spc: Option<u32>) -> R<BTreeSet<usize>> {
    let mut out = BTreeSet::new();
    for g in b.grids.values() {
        for &c in &g.ps {
            out.insert(s.dof(g.id, c).expect("grid is in the structure"));
        }
    }
    if let Some(sid) = spc {
        let cards: Vec<_> = b.spcs.iter().filter(|c| c.sid == sid).collect();
        if cards.is_empty() {
            return Err(NastranError::model(
                &format!("SPC = {sid}"),
                "the case control selects an SPC set that no SPC or SPC1 card defines".into(),
            ));
        }
        for c in cards {
            let what = format!("SPC {sid}");
            if c.value != 0.0 {
                return Err(NastranError::at(&c.source, &what, format!("enforces {} on grid {}: enforced motion is not read (a modal analysis needs zero)", c.value, c.grid)));
            }
            for &comp in &c.components {
                out.insert(s.dof(c.grid, comp).ok_or_else(|| {
                    NastranError::at(
                        &c.source,
                        &what,
                        format!(
                            "constrains grid {}, which the model does not define",
                            c.grid
                        ),
                    )
                })?);
            }
        }
    }
    Ok(out)
}

/// The modes a subcase asks for: its SPC and MPC sets, SUPORT, and the EIGR/EIGRL of its METHOD
/// (roots in [F1, F2] Hz, at most ND of them; Givens and Householder with ND: the lowest ND).
pub fn subcase_modes(b: &BulkData, sub: &super::Subcase) -> R<(Structure, RealModes)> {
    let s = Structure::assemble(b, sub.selections.get("MPC").copied())?;
    let spc = constrained(&s, b, sub.selections.get("SPC").copied())?;
    let method = sub.selections.get("METHOD").copied().ok_or_else(|| {
        NastranError::model(
            "case control",
            "selects no METHOD: a modal analysis needs METHOD = the id of an EIGR or EIGRL".into(),
        )
    })?;
    let eig = b.eigr.get(&method).ok_or_else(|| {
        NastranError::model(
            &format!("METHOD = {method}"),
            "no EIGR or EIGRL card has this id".into(),
        )
    })?;
    let rigid_body: usize = b.suport.iter().map(|(_, c)| c.len()).sum();
    let mut modes = real_modes(&s, &spc, rigid_body)?;
    let two_pi = 2.0 * std::f64::consts::PI;
    // the tridiagonal methods (Givens, Householder) find the lowest ND roots whatever F1 and F2
    // say when ND is given; Lanczos and inverse power keep to the range as well
    let tridiagonal = matches!(
        eig.method.as_str(),
        "GIV" | "MGIV" | "HOU" | "MHOU" | "AGIV" | "AHOU"
    );
    let (lo, hi) = if tridiagonal && eig.nd.is_some() {
        (f64::NEG_INFINITY, f64::INFINITY)
    } else {
        (
            eig.f1
                .map_or(f64::NEG_INFINITY, |f| (two_pi * f).powi(2) * f.signum()),
            eig.f2.map_or(f64::INFINITY, |f| (two_pi * f).powi(2)),
        )
    };
    let tol = 1e-8 * modes.lambda.iter().fold(0.0f64, |a, l| a.max(l.abs()));
    let keep: Vec<usize> = modes
        .lambda
        .iter()
        .enumerate()
        .filter(|(_, &l)| l >= lo - tol && l <= hi + tol || l.abs() <= tol)
        .map(|(i, _)| i)
        .take(eig.nd.map_or(usize::MAX, |n| n as usize))
        .collect();
    // a free body's rigid-body roots, zero to the solution's accuracy, are zero (the response
    // would otherwise see a round-off stiffness that changes from one design to the next)
    modes.lambda = keep
        .iter()
        .map(|&i| {
            let l = modes.lambda[i];
            if rigid_body > 0 && l.abs() <= tol {
                0.0
            } else {
                l
            }
        })
        .collect();
    modes.phi_g = Mat::from_fn(modes.phi_g.nrows(), keep.len(), |i, j| {
        modes.phi_g[(i, keep[j])]
    });
    modes.phi_a = Mat::from_fn(modes.phi_a.nrows(), keep.len(), |i, j| {
        modes.phi_a[(i, keep[j])]
    });
    Ok((s, modes))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nastran::Deck;
    use std::path::Path;

    fn bulk(text: &str) -> BulkData {
        let d =
            Deck::from_text(Path::new("m.bdf"), &format!("BEGIN BULK\n{text}ENDDATA\n")).unwrap();
        BulkData::from_cards(&d.bulk).unwrap()
    }

    /// Shells that cannot be built: a triangle on one line, a quadrilateral ordered across
    /// itself, a missing PSHELL, a zero thickness: each an error naming the element.
    #[test]
    fn bad_shells_are_refused() {
        let grids = "GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,2.,0.,0.\nGRID,4,,0.,1.,0.\nGRID,5,,1.,1.,0.\nMAT1,1,7.0e10,,0.3,2700.\nPSHELL,1,1,0.01,1,,1\nPSHELL,2,1,0.,1,,1\n";
        for (card, needle) in [
            ("CTRIA3,7,1,1,2,3\n", "CTRIA3 7"),
            ("CQUAD4,8,1,1,2,4,5\n", "CQUAD4 8"),
            ("CTRIA3,9,5,1,2,5\n", "property 5"),
            ("CTRIA3,10,2,1,2,5\n", "thickness"),
        ] {
            let b = bulk(&format!("{grids}{card}"));
            let e = Structure::assemble(&b, None).unwrap_err().to_string();
            assert!(e.contains(needle), "{card}: {e}");
        }
        let e = Structure::assemble(&bulk(&format!("{grids}CTRIA3,7,1,1,2,3\n")), None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("one line"), "{e}");
    }

    /// A cantilever of 20 bars against Euler–Bernoulli theory: the first bending frequencies
    /// (β L = 1.8751, 4.6941, 7.8548) in both planes and the first axial mode: lumped mass
    /// (Nastran's default) from below, within 1 % (measured −1.2e-3, −4.0e-3, −6.5e-3 for the
    /// three bending modes: the (β h)² error of lumping), consistent mass (PARAM COUPMASS) from
    /// above within 1e-4; the same beam along a rotated axis with its grids in a rotated
    /// displacement frame (CORD2R) gives the same frequencies. (A bar carries no torsional
    /// inertia in Nastran, so torsion is massless here.)
    #[test]
    fn cantilever_bars_match_beam_theory() {
        let (l, n) = (2.0, 20usize);
        let (e, g, rho, a, i1, i2, j) = (70e9, 26e9, 2700.0, 1e-3, 2e-7, 5e-7, 3e-7);
        let deck = |dir: [f64; 3], cd: bool, coupled: bool| {
            let mut t = String::new();
            t.push_str("CORD2R,7,,0.,0.,0.,0.3,0.2,1.\n,1.,0.5,0.\n");
            for k in 0..=n {
                let s = l * k as f64 / n as f64;
                t.push_str(&format!(
                    "GRID,{},,{},{},{},{}\n",
                    k + 1,
                    s * dir[0],
                    s * dir[1],
                    s * dir[2],
                    if cd { "7" } else { "" }
                ));
            }
            // the orientation vector: any direction off the axis (here basic z or y)
            let v = if dir[2].abs() < 0.9 {
                [0.0, 0.0, 1.0]
            } else {
                [0.0, 1.0, 0.0]
            };
            for k in 1..=n {
                t.push_str(&format!(
                    "CBAR,{k},1,{},{},{},{},{}\n",
                    k,
                    k + 1,
                    v[0],
                    v[1],
                    v[2]
                ));
            }
            t.push_str(&format!(
                "PBAR,1,1,{a},{i1},{i2},{j}\nMAT1,1,{e},{g},,{rho}\nSPC1,1,123456,1\n"
            ));
            if coupled {
                t.push_str("PARAM,COUPMASS,1\n");
            }
            t
        };
        let mass = rho * a;
        let beta: [f64; 3] = [
            1.875_104_068_711_96,
            4.694_091_132_974_17,
            7.854_757_438_237_61,
        ];
        for coupled in [false, true] {
            for (dir, cd) in [([1.0, 0.0, 0.0], false), ([0.6, 0.0, 0.8], true)] {
                let b = bulk(&deck(dir, cd, coupled));
                let s = Structure::assemble(&b, None).unwrap();
                let spc = constrained(&s, &b, Some(1)).unwrap();
                let modes = real_modes(&s, &spc, 0).unwrap();
                let f = modes.freq_hz();
                let two_pi = 2.0 * std::f64::consts::PI;
                let bending = |inertia: f64, k: usize| {
                    beta[k].powi(2) / (l * l) * (e * inertia / mass).sqrt() / two_pi
                };
                let torsion = (g * j / (rho * (i1 + i2))).sqrt() / (4.0 * l);
                let axial = (e / rho).sqrt() / (4.0 * l);
                let mut expected = [
                    bending(i1, 0),
                    bending(i1, 1),
                    bending(i1, 2),
                    bending(i2, 0),
                    bending(i2, 1),
                    bending(i2, 2),
                    axial,
                ];
                // torsion has no mass in a bar (Nastran's CBAR carries none): it is not a mode
                let _ = torsion;
                expected.sort_by(f64::total_cmp);
                for ex in &expected[..6] {
                    let got = f
                        .iter()
                        .copied()
                        .min_by(|a, b| (a - ex).abs().total_cmp(&(b - ex).abs()))
                        .unwrap();
                    let err = (got - ex) / ex;
                    eprintln!(
                        "coupled {coupled}, axis {dir:?}: {got:.4} Hz vs {ex:.4} ({err:+.2e})"
                    );
                    if coupled {
                        assert!(err > -1e-9 && err < 1e-4, "consistent mass: {got} vs {ex}");
                    } else {
                        assert!(err < 0.0 && err > -1e-2, "lumped mass: {got} vs {ex}");
                    }
                }
            }
        }
    }
}

/// A dimension of a PBAR/PBEAM section that can be a design variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BarDimension {
    Area,
    I1,
    I2,
    J,
}

impl BarDimension {
    /// The dimension by its PBAR field name (A, I1, I2, J), for DVPREL1-like input.
    pub fn from_field(name: &str) -> Option<Self> {
        match name.to_ascii_uppercase().as_str() {
            "A" => Some(Self::Area),
            "I1" => Some(Self::I1),
            "I2" => Some(Self::I2),
            "J" => Some(Self::J),
            _ => None,
        }
    }
}

/// The material constants a bar uses (MAT1).
struct BarMaterial {
    e: f64,
    g: f64,
    rho: f64,
}

/// A bar section's dimensions as scalars (values, or duals along one dimension) and its fixed
/// data.
struct BarSection<T> {
    area: T,
    i1: T,
    i2: T,
    j: T,
    nsm: f64,
    k1: Option<f64>,
    k2: Option<f64>,
}

impl BarSection<f64> {
    fn of(p: &super::bulk::BarProperty) -> Self {
        Self {
            area: p.area,
            i1: p.i1,
            i2: p.i2,
            j: p.j,
            nsm: p.nsm,
            k1: p.k1,
            k2: p.k2,
        }
    }
}

impl BarSection<Dual<1>> {
    /// The section with a unit derivative along `dim`.
    fn along(p: &super::bulk::BarProperty, dim: BarDimension) -> Self {
        let v = |x: f64, d: BarDimension| Dual::new(x, [if d == dim { 1.0 } else { 0.0 }]);
        Self {
            area: v(p.area, BarDimension::Area),
            i1: v(p.i1, BarDimension::I1),
            i2: v(p.i2, BarDimension::I2),
            j: v(p.j, BarDimension::J),
            nsm: p.nsm,
            k1: p.k1,
            k2: p.k2,
        }
    }
}

/// An element's stiffness and mass, row by row.
type ElementMatrices<T> = (Vec<Vec<T>>, Vec<Vec<T>>);

/// A bar's stiffness and mass in its element frame, dofs [u v w θx θy θz] at A then B: axial
/// EA/L, torsion GJ/L, bending in plane 1 (x–y: v, θz) with I1 and in plane 2 (x–z: w, θy) with
/// I2, each with the shear flexibility φ = 12EI/(GK A L²) where PBAR gives K; the pin flags'
/// components condensed out; lumped (half the mass at each end) or consistent mass.
fn bar_local<T: ScalarOps>(
    mat: &BarMaterial,
    p: &BarSection<T>,
    l: f64,
    released: &[usize],
    coupled: bool,
) -> Result<ElementMatrices<T>, String> {
    let (e, g, rho) = (mat.e, mat.g, mat.rho);
    let zero = T::cst(0.0);
    let mut k = vec![vec![zero; 12]; 12];
    let ea = p.area * e / l;
    let gj = p.j * g / l;
    for (i, j, val) in [
        (0, 0, ea),
        (6, 6, ea),
        (0, 6, -ea),
        (3, 3, gj),
        (9, 9, gj),
        (3, 9, -gj),
    ] {
        k[i][j] += val;
        if i != j {
            k[j][i] += val;
        }
    }
    for (inertia, kf, dofs, sign) in [
        (p.i1, p.k1, [1usize, 5, 7, 11], 1.0),
        (p.i2, p.k2, [2usize, 4, 8, 10], -1.0),
    ] {
        let phi = match kf {
            Some(kf) if kf > 0.0 && g > 0.0 && p.area.re() > 0.0 => {
                inertia * (12.0 * e) / (p.area * (g * kf) * l * l)
            }
            _ => zero,
        };
        let c = inertia * e / ((phi + 1.0) * (l * l * l));
        let s = sign * l;
        let cst = T::cst;
        let kb = [
            [cst(12.0), cst(6.0 * s), cst(-12.0), cst(6.0 * s)],
            [
                cst(6.0 * s),
                (phi + 4.0) * l * l,
                cst(-6.0 * s),
                (-phi + 2.0) * l * l,
            ],
            [cst(-12.0), cst(-6.0 * s), cst(12.0), cst(-6.0 * s)],
            [
                cst(6.0 * s),
                (-phi + 2.0) * l * l,
                cst(-6.0 * s),
                (phi + 4.0) * l * l,
            ],
        ];
        for a in 0..4 {
            for bb in 0..4 {
                k[dofs[a]][dofs[bb]] += c * kb[a][bb];
            }
        }
    }
    if !released.is_empty() {
        condense(&mut k, released)?;
    }
    let mass_per_length = p.area * rho + p.nsm;
    let mut m = vec![vec![zero; 12]; 12];
    let mt = mass_per_length * l;
    if coupled {
        for (i, j, val) in [(0, 0, 2.0), (6, 6, 2.0), (0, 6, 1.0)] {
            m[i][j] += mt * val / 6.0;
            if i != j {
                m[j][i] += mt * val / 6.0;
            }
        }
        for (dofs, sign) in [([1usize, 5, 7, 11], 1.0), ([2usize, 4, 8, 10], -1.0)] {
            let s = sign * l;
            let mb = [
                [156.0, 22.0 * s, 54.0, -13.0 * s],
                [22.0 * s, 4.0 * l * l, 13.0 * s, -3.0 * l * l],
                [54.0, 13.0 * s, 156.0, -22.0 * s],
                [-13.0 * s, -3.0 * l * l, -22.0 * s, 4.0 * l * l],
            ];
            for a in 0..4 {
                for bb in 0..4 {
                    m[dofs[a]][dofs[bb]] += mt / 420.0 * mb[a][bb];
                }
            }
        }
    } else {
        for i in [0, 1, 2, 6, 7, 8] {
            m[i][i] = mt * 0.5;
        }
    }
    Ok((k, m))
}

/// (A + Aᵀ)/2: the reduced matrices symmetric to the last bit.
fn symmetric_part(a: Mat<f64>) -> Mat<f64> {
    let n = a.nrows();
    Mat::from_fn(n, n, |i, j| 0.5 * (a[(i, j)] + a[(j, i)]))
}

/// The reduction u_g = T u_a of a subcase's constraints and the a-set's K and M.
fn a_set_matrices(s: &Structure, spc: &BTreeSet<usize>) -> R<(Mat<f64>, Mat<f64>, Mat<f64>)> {
    let (t, _) = s.reduction(spc)?;
    let k = symmetric_part(t.transpose() * &s.k_gg * &t);
    let m = symmetric_part(t.transpose() * &s.m_gg * &t);
    Ok((t, k, m))
}

fn vdot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>()
}

/// The rigid-body modes of a free body (SUPORT): the roots zero to 1e-8 of the largest, as
/// [`subcase_modes`] tells them. They span K's null space, which no sizing moves; the response
/// depends on them only through that space (any M-orthonormal basis of it gives the same), so
/// their repeated zero root needs no derivative of its own shapes.
fn rigid_body_modes(modes: &RealModes) -> Vec<usize> {
    let tol = 1e-8 * modes.lambda.iter().fold(0.0f64, |a, l| a.max(l.abs()));
    (0..modes.lambda.len())
        .filter(|&i| modes.lambda[i].abs() <= tol)
        .collect()
}

/// The checks a mode's derivative needs: mass-normalized, and its root not repeated.
fn check_mode(modes: &RealModes, i: usize, phi: &[f64], m_phi: &[f64]) -> R<()> {
    let lambda = modes.lambda[i];
    if !((vdot(phi, m_phi) - 1.0).abs() < 1e-8) {
        return Err(NastranError::model(
            &format!("mode {}", i + 1),
            format!("is not mass-normalized (φᵀMφ = {:.6e}): the derivative is taken of the mass-normalized modes `real_modes` and `subcase_modes` give (whatever the EIGR/EIGRL NORM, which scales only the printed modal coordinates)", vdot(phi, m_phi)),
        ));
    }
    // a root repeated within the solution's accuracy (the dense solve finds every root)
    if let Some(j) = (0..modes.lambda.len()).find(|&j| {
        j != i && (modes.lambda[j] - lambda).abs() <= 1e-8 * lambda.abs().max(f64::MIN_POSITIVE)
    }) {
        return Err(NastranError::model(
            &format!("mode {}", i + 1),
            format!(
                "its eigenvalue {lambda:.6e} is repeated (mode {} has the same to 1e-8): a repeated root has no derivative of its own mode shape (the pair's shapes mix under any change); derive a quantity of the pair (the sum of their responses) or break the symmetry",
                j + 1
            ),
        ));
    }
    Ok(())
}

/// Solves (K − λM) v = rhs with the row and column of φ's largest component removed (v zero
/// there): Nelson's system, symmetric, so its adjoint is the same solve. A nearly repeated root
/// leaves it singular: refused.
fn pivoted_solve(
    (k, m): (&Mat<f64>, &Mat<f64>),
    (i, lambda): (usize, f64),
    phi: &[f64],
    rhs: &[f64],
) -> R<Vec<f64>> {
    use faer::prelude::Solve;
    let n = k.nrows();
    let pivot = (0..n)
        .max_by(|&a, &b| phi[a].abs().total_cmp(&phi[b].abs()))
        .expect("an a-set has components");
    let full = |r: usize| if r < pivot { r } else { r + 1 };
    let a = Mat::<f64>::from_fn(n - 1, n - 1, |r, c| {
        k[(full(r), full(c))] - lambda * m[(full(r), full(c))]
    });
    let rhs_red = Mat::<f64>::from_fn(n - 1, 1, |r, _| rhs[full(r)]);
    let v_red = a.full_piv_lu().solve(&rhs_red);
    let mut v = vec![0.0; n];
    for r in 0..n - 1 {
        v[full(r)] = v_red[(r, 0)];
    }
    // a repeated eigenvalue leaves the reduced matrix singular: the solve is not finite or
    // does not satisfy its equations
    let residual = (0..n - 1)
        .map(|r| {
            let row: f64 = (0..n - 1).map(|c| a[(r, c)] * v_red[(c, 0)]).sum();
            (row - rhs_red[(r, 0)]).abs()
        })
        .fold(0.0f64, f64::max);
    let rhs_n = (0..n - 1)
        .map(|r| rhs_red[(r, 0)].abs())
        .fold(0.0f64, f64::max);
    let scale = (0..n).map(|r| k[(r, r)].abs()).fold(0.0f64, f64::max);
    let v_n = v.iter().map(|x| x.abs()).fold(0.0f64, f64::max);
    if v.iter().any(|x| !x.is_finite()) || residual > 1e-8 * (rhs_n + scale * v_n) {
        return Err(NastranError::model(
            &format!("mode {}", i + 1),
            format!(
                "its eigenvalue {lambda:.6e} is nearly repeated: K − λM without the pivot's row and column is singular to the solution's accuracy"
            ),
        ));
    }
    Ok(v)
}

/// The adjoint of [`mode_derivatives`] for seeds λ̄ᵢ and φ̄ᵢ (g-set columns) on the modes
/// `which`: per mode a g-set vector uᵢ and a scalar cᵢ such that, for every design direction
/// (∂K, ∂M),
///   Σᵢ λ̄ᵢ ∂λᵢ + φ̄ᵢᵀ ∂φᵢ = Σᵢ uᵢᵀ (∂K − λᵢ ∂M) φᵢ − cᵢ φᵢᵀ ∂M φᵢ,
/// from Nelson's ∂φ = v − (φᵀMv + ½ φᵀ∂Mφ) φ: with w = φ̄ − (φ̄ᵀφ) Mφ (a-set) and (K − λM) ψ = w
/// on the pivoted system, uᵢ = λ̄ᵢ φᵢ − ψ̃ᵢ, ψ̃ = ψ − (ψᵀMφ) φ, cᵢ = ½ φ̄ᵢᵀφᵢ. One solve a mode
/// whatever the number of design variables (the forward mode needs one a mode and variable).
pub fn mode_adjoint(
    s: &Structure,
    spc: &BTreeSet<usize>,
    modes: &RealModes,
    which: &[usize],
    (lambda_bar, phi_bar_g): (&[f64], &Mat<f64>),
) -> R<ModeAdjoint> {
    let (t, k, m) = a_set_matrices(s, spc)?;
    let n = k.nrows();
    let ng = t.nrows();
    let phi_bar_a = t.transpose() * phi_bar_g;
    let mut u_g = Mat::<f64>::zeros(ng, which.len());
    let mut c = Vec::with_capacity(which.len());
    // the rigid-body modes kept: B_rs = φ̄_rᵀ φ_s (g-set), met by −½ Σ B_rs φ_sᵀ ∂M φ_r
    let rigid: Vec<usize> = rigid_body_modes(modes)
        .into_iter()
        .filter(|r| which.contains(r))
        .collect();
    let rigid_b = Mat::<f64>::from_fn(rigid.len(), rigid.len(), |a, b| {
        let col = which.iter().position(|w| *w == rigid[a]).expect("kept");
        (0..ng)
            .map(|q| phi_bar_g[(q, col)] * modes.phi_g[(q, rigid[b])])
            .sum()
    });
    for (col, &i) in which.iter().enumerate() {
        if rigid.contains(&i) {
            c.push(0.0);
            continue;
        }
        let lambda = modes.lambda[i];
        let phi: Vec<f64> = modes.phi_a.col(i).iter().copied().collect();
        let m_phi: Vec<f64> = (0..n)
            .map(|r| (0..n).map(|q| m[(r, q)] * phi[q]).sum())
            .collect();
        check_mode(modes, i, &phi, &m_phi)?;
        let bar: Vec<f64> = phi_bar_a.col(col).iter().copied().collect();
        let along = vdot(&bar, &phi);
        let w: Vec<f64> = bar
            .iter()
            .zip(&m_phi)
            .map(|(b, mp)| b - along * mp)
            .collect();
        let psi = pivoted_solve((&k, &m), (i, lambda), &phi, &w)?;
        let psi_m_phi = vdot(&psi, &m_phi);
        let u_a: Vec<f64> = (0..n)
            .map(|r| lambda_bar[col] * phi[r] - (psi[r] - psi_m_phi * phi[r]))
            .collect();
        for r in 0..ng {
            u_g[(r, col)] = (0..n).map(|q| t[(r, q)] * u_a[q]).sum();
        }
        c.push(0.5 * along);
    }
    Ok(ModeAdjoint {
        which: which.to_vec(),
        u_g,
        c,
        rigid,
        rigid_b,
    })
}

/// What [`mode_adjoint`] gives: per mode the g-set vector uᵢ (a column) and the scalar cᵢ.
#[derive(Clone, Debug)]
pub struct ModeAdjoint {
    pub which: Vec<usize>,
    pub u_g: Mat<f64>,
    pub c: Vec<f64>,
    /// The rigid-body modes among them and B_rs = φ̄_rᵀ φ_s: their share is
    /// −½ Σ B_rs φ_sᵀ ∂M φ_r.
    pub rigid: Vec<usize>,
    pub rigid_b: Mat<f64>,
}

impl ModeAdjoint {
    /// Σᵢ λ̄ᵢ ∂λᵢ + φ̄ᵢᵀ ∂φᵢ along one design direction (∂K, ∂M in the g-set).
    pub fn along(&self, modes: &RealModes, (dk_g, dm_g): (&Mat<f64>, &Mat<f64>)) -> f64 {
        let ng = dk_g.nrows();
        // ∂K Φ and ∂M Φ of the modes concerned, by two products
        let phi = Mat::<f64>::from_fn(ng, self.which.len(), |r, col| {
            modes.phi_g[(r, self.which[col])]
        });
        let dk_phi = dk_g * &phi;
        let dm_phi = dm_g * &phi;
        let mut total = 0.0;
        for (col, &i) in self.which.iter().enumerate() {
            let lambda = modes.lambda[i];
            for r in 0..ng {
                total += self.u_g[(r, col)] * (dk_phi[(r, col)] - lambda * dm_phi[(r, col)])
                    - self.c[col] * phi[(r, col)] * dm_phi[(r, col)];
            }
        }
        let column = |mode: usize| self.which.iter().position(|w| *w == mode).expect("kept");
        for (a, &r) in self.rigid.iter().enumerate() {
            let cr = column(r);
            for (b, &other) in self.rigid.iter().enumerate() {
                let cs = column(other);
                let pair: f64 = (0..ng).map(|q| phi[(q, cs)] * dm_phi[(q, cr)]).sum();
                total -= 0.5 * self.rigid_b[(a, b)] * pair;
            }
        }
        total
    }
}

/// Exact derivatives of mass-normalized real modes (as [`real_modes`] gives them) along one
/// design direction (∂K, ∂M in the g-set, e.g. from [`Structure::shell_thickness_derivative`]
/// or [`Structure::bar_property_derivative`]) for the modes `which` of `modes` (solved by
/// [`real_modes`] with the same constraints): per mode, ∂λ
/// and ∂φ in the g-set. ∂λ = φᵀ(∂K − λ∂M)φ; ∂φ by Nelson's method on the a-set: (K − λM) v =
/// −(∂K − λ∂M)φ + ∂λ Mφ with the row and column of φ's largest entry removed (v zero there),
/// then ∂φ = v − (φᵀMv + ½ φᵀ∂Mφ) φ, which keeps φᵀMφ = 1. Dense: O(n_a³) a mode. A repeated
/// elastic eigenvalue (the reduced matrix singular) is refused: its modes have no derivative
/// of their own. A free body's rigid-body modes (zero roots, [`rigid_body_modes`]) take ∂λ = 0
/// and ∂φ_r = −½ Σ_s φ_s (φ_sᵀ ∂M φ_r): K's null space does not move, and of its
/// M-orthonormal bases this is the symmetric choice (the response depends on the space only).
pub fn mode_derivatives(
    s: &Structure,
    spc: &BTreeSet<usize>,
    modes: &RealModes,
    (dk_g, dm_g): (&Mat<f64>, &Mat<f64>),
    which: &[usize],
) -> R<Vec<(f64, Vec<f64>)>> {
    let (t, k, m) = a_set_matrices(s, spc)?;
    let dk = symmetric_part(t.transpose() * dk_g * &t);
    let dm = symmetric_part(t.transpose() * dm_g * &t);
    let n = k.nrows();
    let rigid = rigid_body_modes(modes);
    which
        .iter()
        .map(|&i| {
            let lambda = modes.lambda[i];
            let phi = modes.phi_a.col(i);
            let times = |a: &Mat<f64>, v: &[f64]| -> Vec<f64> {
                (0..n)
                    .map(|r| (0..n).map(|c| a[(r, c)] * v[c]).sum())
                    .collect()
            };
            let phi_v: Vec<f64> = phi.iter().copied().collect();
            let dk_phi = times(&dk, &phi_v);
            let dm_phi = times(&dm, &phi_v);
            let m_phi = times(&m, &phi_v);
            if rigid.contains(&i) {
                // K's null space does not move: ∂λ = 0 and, of the M-orthonormal bases of that
                // space, the symmetric choice ∂φ_r = −½ Σ_s φ_s (φ_sᵀ ∂M φ_r)
                let mut d_phi_a = vec![0.0; n];
                for &r in &rigid {
                    let phi_r: Vec<f64> = modes.phi_a.col(r).iter().copied().collect();
                    let c = -0.5 * vdot(&phi_r, &dm_phi);
                    for q in 0..n {
                        d_phi_a[q] += c * phi_r[q];
                    }
                }
                let ng = t.nrows();
                let d_phi_g = (0..ng)
                    .map(|r| (0..n).map(|q| t[(r, q)] * d_phi_a[q]).sum())
                    .collect();
                return Ok((0.0, d_phi_g));
            }
            check_mode(modes, i, &phi_v, &m_phi)?;
            let d_lambda = vdot(&phi_v, &dk_phi) - lambda * vdot(&phi_v, &dm_phi);
            let rhs: Vec<f64> = (0..n)
                .map(|r| -(dk_phi[r] - lambda * dm_phi[r]) + d_lambda * m_phi[r])
                .collect();
            let v = pivoted_solve((&k, &m), (i, lambda), &phi_v, &rhs)?;
            let c = -(vdot(&m_phi, &v) + 0.5 * vdot(&phi_v, &dm_phi));
            let d_phi_a: Vec<f64> = v.iter().zip(&phi_v).map(|(x, p)| x + c * p).collect();
            let ng = t.nrows();
            let d_phi_g = (0..ng)
                .map(|r| (0..n).map(|q| t[(r, q)] * d_phi_a[q]).sum())
                .collect();
            Ok((d_lambda, d_phi_g))
        })
        .collect()
}
