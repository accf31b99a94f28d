//! The built-in O-H mesh about a trapezoidal wing, made from the wing's own planform and section.
//!
//! Topology: in every spanwise plane (mesh z = span) an O-grid about the section, `n_around`
//! points around a sharp-trailing-edge contour and `n_radial` cells out to a far-field circle;
//! the planes are stacked from the root (a symmetry plane) over `n_span` cells to the tip and
//! `n_outboard` cells beyond it to a far-field plane. Frame: x streamwise, y up, z along the span
//! (the CFD frame; the aerodynamic contract's (x, y, z) is (x, z, y) here). Lengths in metres.
//!
//! The tip is closed by sections that thin smoothly to zero thickness: the half-thickness is
//! scaled by √(1 − ((η − η_c)/(1 − η_c))²) over the outer `tip_closure` of the span (η_c = 1 −
//! tip_closure), so the tip station is a flat line and the upper and lower wall nodes meet there.
//! Outboard of the tip the section is collapsed to that line (the tip chord at the tip's leading
//! edge): the upper and lower nodes of the contour are one node, and the faces between the cells
//! above and below the line are interior faces — the grid continues outboard without a cut.
//!
//! Far field: a cylinder of radius `far_field_chords` root chords about the root's mid-chord
//! line and the outboard plane the same distance beyond the tip. At 15 root chords the disturbance
//! of a lifting wing (a horseshoe vortex: velocities falling as 1/r² of the bound vortex, the
//! trailing pair's 1/r in the Trefftz plane downstream) is below 0.5 % of its value one chord away
//! where the far-field Roe flux against the free stream imposes it; the LFD gust enters through
//! the face volume fluxes (Field Velocity Method) everywhere, so no boundary carries it, and for
//! k → 0 the far-field distance only has to hold the steady disturbance.
//!
//! Node positions are written over the generic scalar ([`WingMesh::nodes_at`]): with dual numbers
//! for the planform variables (span, quarter-chord sweep, root and tip chords) they give dx/dp
//! exactly; every distribution (spanwise, radial, outboard) is a fixed fraction, so the mesh is one
//! smooth function of the planform.

use crate::mesh::{geometric_distribution, geometric_distribution_at, Boundary, Face, Mesh, Side};
use gustkit_core::scalar::Scalar;

/// The planform variables in the order the structural side uses: semispan, quarter-chord sweep
/// (rad), root chord, tip chord (m).
pub const N_PLANFORM: usize = 4;

/// Sizes and distances of the wing mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct WingMeshSpec {
    /// Points around each section (even).
    pub n_around: usize,
    /// Cells from the wall to the far-field cylinder.
    pub n_radial: usize,
    /// Cells along the span from the root to the tip.
    pub n_span: usize,
    /// Cells from the tip to the far-field plane.
    pub n_outboard: usize,
    /// Radius of the far-field cylinder and distance of the outboard plane beyond the tip, in
    /// root chords.
    pub far_field_chords: f64,
    /// Height of the first cell at the wall, in root chords.
    pub first_spacing_chords: f64,
    /// Fraction of the span over which the sections close to zero thickness.
    pub tip_closure: f64,
}

impl WingMeshSpec {
    /// The named levels: `coarse` (7 168 cells), `medium` and `fine` (each about 2× finer in
    /// every direction, 8× the cells).
    pub fn level(name: &str) -> Option<Self> {
        let base = |f: usize| Self {
            n_around: 32 * f,
            n_radial: 14 * f,
            n_span: 10 * f,
            n_outboard: 6 * f,
            far_field_chords: 15.0,
            first_spacing_chords: 0.01 / f as f64,
            tip_closure: 0.05,
        };
        match name {
            "coarse" => Some(base(1)),
            "medium" => Some(base(2)),
            "fine" => Some(base(4)),
            _ => None,
        }
    }

    /// Cells of the mesh.
    pub fn n_cells(&self) -> usize {
        self.n_around * self.n_radial * (self.n_span + self.n_outboard)
    }

    /// Checks the sizes: the JSON field name and the reason on failure.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        if self.n_around < 8 || self.n_around % 2 != 0 {
            return Err((
                "n_around",
                format!("must be even and at least 8 (got {})", self.n_around),
            ));
        }
        for (name, v) in [
            ("n_radial", self.n_radial),
            ("n_span", self.n_span),
            ("n_outboard", self.n_outboard),
        ] {
            if v < 2 {
                return Err((name, format!("must be at least 2 (got {v})")));
            }
        }
        if !(self.far_field_chords >= 5.0 && self.far_field_chords.is_finite()) {
            return Err((
                "far_field_chords",
                format!("must be at least 5 (got {})", self.far_field_chords),
            ));
        }
        if !(self.first_spacing_chords > 0.0
            && self.first_spacing_chords * (self.n_radial as f64) < self.far_field_chords)
        {
            return Err((
                "first_spacing_chords",
                format!(
                    "must be positive and below far_field_chords / n_radial (got {})",
                    self.first_spacing_chords
                ),
            ));
        }
        if !(self.tip_closure > 0.0 && self.tip_closure < 0.5) {
            return Err((
                "tip_closure",
                format!("must lie in (0, 0.5) (got {})", self.tip_closure),
            ));
        }
        Ok(())
    }

    /// The mesh with half the cells in every direction (first spacing doubled), if every count
    /// halves into a valid mesh: the start of mesh sequencing.
    pub fn halved(&self) -> Option<Self> {
        let even = |v: usize| v % 2 == 0;
        let counts = [self.n_around, self.n_radial, self.n_span, self.n_outboard];
        if !counts.iter().all(|&v| even(v)) {
            return None;
        }
        let h = Self {
            n_around: self.n_around / 2,
            n_radial: self.n_radial / 2,
            n_span: self.n_span / 2,
            n_outboard: self.n_outboard / 2,
            first_spacing_chords: 2.0 * self.first_spacing_chords,
            ..self.clone()
        };
        h.validate().ok().map(|_| h)
    }

    /// Cell values of a `coarse` mesh of the same topology carried to this one: each cell takes
    /// the value of the coarse cell at the same fraction of each index range (around, radial, and
    /// span inboard and outboard of the tip separately), the injection of mesh sequencing. The
    /// cells are ordered as the generator numbers them, (s n_radial + j) n_around + i.
    pub fn prolong<T: Copy>(&self, coarse: &WingMeshSpec, values: &[T]) -> Vec<T> {
        let (nc, njc) = (coarse.n_around, coarse.n_radial);
        let (nf, njf) = (self.n_around, self.n_radial);
        let span = |s: usize| {
            if s < self.n_span {
                s * coarse.n_span / self.n_span
            } else {
                coarse.n_span + (s - self.n_span) * coarse.n_outboard / self.n_outboard
            }
        };
        let mut out = Vec::with_capacity(self.n_cells());
        for s in 0..self.n_span + self.n_outboard {
            let sc = span(s);
            for j in 0..njf {
                let jc = j * njc / njf;
                for i in 0..nf {
                    out.push(values[(sc * njc + jc) * nc + i * nc / nf]);
                }
            }
        }
        out
    }
}

/// The built-in wing mesh: the mesh at the planform it was made for, and what it needs to place
/// its nodes at another planform (the generator's indices of each node and the fixed
/// distributions).
#[derive(Clone, Debug)]
pub struct WingMesh {
    pub mesh: Mesh,
    pub spec: WingMeshSpec,
    /// Half-thickness over chord at each of the `n_around` contour points (sharp trailing edge,
    /// before the tip closure), and x/c there.
    half_thickness: Vec<f64>,
    x_c: Vec<f64>,
    /// Spanwise station of each plane: η on the wing (s ≤ n_span), then the outboard distance as
    /// a fraction of the far-field distance.
    stations: Vec<f64>,
    /// Radial fraction of each ring, 0 at the wall, 1 at the far field.
    radial: Vec<f64>,
    /// (i, j, s) of each node: contour point, ring, spanwise plane.
    node_index: Vec<[usize; 3]>,
}

/// A wall cell of a chordwise section (see [`WingMesh::wall_section`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SectionCell {
    /// Chord fraction of the middle of the cell's wall face.
    pub x_c: f64,
    /// The face's extent in x/c (for integrals over the chord).
    pub width: f64,
    /// On the upper surface (y > 0 of the section)?
    pub upper: bool,
    pub cell: usize,
}

/// Quality figures of a mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshQuality {
    pub cells: usize,
    pub min_volume: f64,
    pub max_volume: f64,
    /// Largest ratio of a cell's longest to its shortest edge.
    pub max_aspect_ratio: f64,
    /// Largest angle between an interior face's normal and the line joining the centroids of
    /// its two cells (non-orthogonality), degrees.
    pub max_skewness_deg: f64,
}

impl WingMesh {
    /// The mesh of `spec` about the planform `p` = (semispan, quarter-chord sweep, root chord,
    /// tip chord) in m and rad, with the section's half-thickness over chord `half_thickness`
    /// (any trailing-edge thickness is ramped off linearly: the contour closes at a sharp edge).
    pub fn new(
        p: [f64; N_PLANFORM],
        half_thickness: &dyn Fn(f64) -> f64,
        spec: &WingMeshSpec,
    ) -> Self {
        let n = spec.n_around;
        let te = half_thickness(1.0);
        let x_c: Vec<f64> = (0..n)
            .map(|i| 0.5 * (1.0 + (2.0 * std::f64::consts::PI * i as f64 / n as f64).cos()))
            .collect();
        let half: Vec<f64> = x_c
            .iter()
            .map(|&x| (half_thickness(x) - x * te).max(0.0))
            .collect();
        // spanwise: sine clustering towards the tip on the wing, geometric outboard from the
        // last wing spacing (as a fraction of the far-field distance)
        let mut stations: Vec<f64> = (0..=spec.n_span)
            .map(|s| (0.5 * std::f64::consts::PI * s as f64 / spec.n_span as f64).sin())
            .collect();
        let outboard = outboard_stations(p, &stations, spec);
        stations.extend(outboard.iter().skip(1));
        let radial = geometric_distribution(
            spec.first_spacing_chords / spec.far_field_chords,
            spec.n_radial,
        );
        let (mesh, node_index) = topology(spec);
        let mut wing = Self {
            mesh,
            spec: spec.clone(),
            half_thickness: half,
            x_c,
            stations,
            radial,
            node_index,
        };
        wing.mesh.nodes = wing.nodes_at(p);
        wing
    }

    /// Whether spanwise plane `s` lies outboard of the wing or on its tip (a collapsed section).
    fn collapsed(&self, s: usize) -> bool {
        s >= self.spec.n_span
    }

    /// Every node's position for the planform `p` (any scalar: dual numbers give dx/dp).
    pub fn nodes_at<S: Scalar>(&self, p: [S; N_PLANFORM]) -> Vec<[S; 3]> {
        // the outboard planes follow the planform (their first spacing matches the tip's)
        let outboard = outboard_stations(p, &self.stations, &self.spec);
        let [span, sweep, cr, ct] = p;
        let tan_le = sweep.tan() + (cr - ct) / (span * 4.0);
        let far = cr * self.spec.far_field_chords;
        let x_center = cr * 0.5;
        let n = self.spec.n_around;
        let eta_c = 1.0 - self.spec.tip_closure;
        self.node_index
            .iter()
            .map(|&[i, j, s]| {
                let (z, x_le, chord, scale) = if s <= self.spec.n_span {
                    let eta = self.stations[s];
                    let z = span * eta;
                    let closure = if eta > eta_c {
                        let u = (eta - eta_c) / self.spec.tip_closure;
                        (1.0 - u * u).max(0.0).sqrt()
                    } else {
                        1.0
                    };
                    let closure = if self.collapsed(s) { 0.0 } else { closure };
                    (z, z * tan_le, cr + (ct - cr) * eta, closure)
                } else {
                    (
                        span + far * outboard[s - self.spec.n_span],
                        span * tan_le,
                        ct,
                        0.0,
                    )
                };
                let sign = if 2 * i < n { 1.0 } else { -1.0 };
                let bx = x_le + chord * self.x_c[i];
                let by = chord * (sign * scale * self.half_thickness[i]);
                // the far-field point at the contour point's own angle: node n − i mirrors node
                // i, so the mesh is symmetric top to bottom (a half-spacing offset here once gave
                // the symmetric section C_L = −6.5e-4 at α = 0 on the coarse mesh)
                let theta = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
                let fx = x_center + far * theta.cos();
                let fy = far * theta.sin();
                let r = self.radial[j];
                [bx + (fx - bx) * r, by + (fy - by) * r, z]
            })
            .collect()
    }

    /// The wall nodes' (ξ, η) on the planform: chord fraction and span fraction of each node of
    /// a wall face (in the order of `nodes`), for the structural transfer.
    pub fn parametric(&self, node: usize) -> [f64; 2] {
        let [i, _, s] = self.node_index[node];
        let eta = if s <= self.spec.n_span {
            self.stations[s]
        } else {
            1.0
        };
        [self.x_c[i], eta]
    }

    /// The wall cells of the spanwise strip whose middle lies nearest the span fraction `eta`
    /// (on the wing: the tip's collapsed planes are not wall), as the strip's mid-station η and,
    /// around the contour from the trailing edge over the upper surface, each wall cell with the
    /// x/c of its face's middle and whether it is on the upper side.
    pub fn wall_section(&self, eta: f64) -> (f64, Vec<SectionCell>) {
        let mid = |s: usize| 0.5 * (self.stations[s] + self.stations[s + 1]);
        let s = (0..self.spec.n_span)
            .min_by(|&a, &b| (mid(a) - eta).abs().total_cmp(&(mid(b) - eta).abs()))
            .expect("the wing has spanwise strips");
        let n = self.spec.n_around;
        let cells = (0..n)
            .map(|i| SectionCell {
                x_c: 0.5 * (self.x_c[i] + self.x_c[(i + 1) % n]),
                width: (self.x_c[(i + 1) % n] - self.x_c[i]).abs(),
                upper: 2 * i < n,
                // the cell numbering of `topology`: ring 0 of plane strip s
                cell: s * self.spec.n_radial * n + i,
            })
            .collect();
        (mid(s), cells)
    }

    /// Quality figures (cell volumes, aspect ratios, non-orthogonality).
    pub fn quality(&self) -> MeshQuality {
        quality(&self.mesh)
    }
}

/// The outboard planes' stations (fractions of the far-field distance, from 0 at the tip) for
/// the planform `p`: a geometric distribution whose first step, as a length, equals the last
/// spanwise step on the wing; `wing` holds the wing's η stations. Any scalar, so that node
/// positions are differentiable in the planform.
fn outboard_stations<S: Scalar>(p: [S; N_PLANFORM], wing: &[f64], spec: &WingMeshSpec) -> Vec<S> {
    let last = p[0] * (1.0 - wing[spec.n_span - 1]);
    let far = p[2] * spec.far_field_chords;
    let first = last / far;
    let first = if first.re() > 0.5 { S::cst(0.5) } else { first };
    geometric_distribution_at(first, spec.n_outboard)
}

/// Quality figures of any mesh with cell node lists.
pub fn quality(mesh: &Mesh) -> MeshQuality {
    let vol = mesh.volumes();
    let centroid = |c: &[usize]| -> [f64; 3] {
        let mut x = [0.0; 3];
        for &n in c {
            for k in 0..3 {
                x[k] += mesh.nodes[n][k] / c.len() as f64;
            }
        }
        x
    };
    let centers: Vec<[f64; 3]> = mesh.cells.iter().map(|c| centroid(c)).collect();
    let dist = |a: [f64; 3], b: [f64; 3]| {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    };
    // hexahedron edges in VTK order (bottom quad, top quad, verticals); collapsed edges of a
    // wedge-like cell have zero length and are skipped
    const EDGES: [[usize; 2]; 12] = [
        [0, 1],
        [1, 2],
        [2, 3],
        [3, 0],
        [4, 5],
        [5, 6],
        [6, 7],
        [7, 4],
        [0, 4],
        [1, 5],
        [2, 6],
        [3, 7],
    ];
    let mut max_aspect: f64 = 1.0;
    for c in &mesh.cells {
        if c.len() != 8 {
            continue;
        }
        let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
        for [a, b] in EDGES {
            let l = dist(mesh.nodes[c[a]], mesh.nodes[c[b]]);
            if l > 0.0 {
                lo = lo.min(l);
                hi = hi.max(l);
            }
        }
        if lo.is_finite() {
            max_aspect = max_aspect.max(hi / lo);
        }
    }
    let mut max_skew: f64 = 0.0;
    for (fi, f) in mesh.faces.iter().enumerate() {
        if let Side::Cell(r) = f.right {
            let s = mesh.area(fi);
            let d: [f64; 3] = std::array::from_fn(|k| centers[r][k] - centers[f.left][k]);
            let (ns, nd) = (
                (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt(),
                (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt(),
            );
            if ns > 0.0 && nd > 0.0 {
                let c = ((s[0] * d[0] + s[1] * d[1] + s[2] * d[2]) / (ns * nd)).clamp(-1.0, 1.0);
                max_skew = max_skew.max(c.acos().to_degrees());
            }
        }
    }
    MeshQuality {
        cells: mesh.n_cells,
        min_volume: vol.iter().copied().fold(f64::INFINITY, f64::min),
        max_volume: vol.iter().copied().fold(0.0, f64::max),
        max_aspect_ratio: max_aspect,
        max_skewness_deg: max_skew,
    }
}

/// Faces, cells and the (i, j, s) of each node of the O-H topology (node positions zero).
fn topology(spec: &WingMeshSpec) -> (Mesh, Vec<[usize; 3]>) {
    let (n, nj, ns) = (spec.n_around, spec.n_radial, spec.n_span + spec.n_outboard);
    // node numbering: the wall ring of a collapsed plane keeps only the upper contour points
    // (and the two edge points); the lower ones are the same nodes
    let mut index = vec![usize::MAX; n * (nj + 1) * (ns + 1)];
    let mut node_index = Vec::new();
    let key = |i: usize, j: usize, s: usize| (s * (nj + 1) + j) * n + i;
    for s in 0..=ns {
        for j in 0..=nj {
            for i in 0..n {
                if j == 0 && s >= spec.n_span && 2 * i > n {
                    continue;
                }
                index[key(i, j, s)] = node_index.len();
                node_index.push([i, j, s]);
            }
        }
    }
    let id = |i: usize, j: usize, s: usize| -> usize {
        let i = i % n;
        let i = if j == 0 && s >= spec.n_span && 2 * i > n {
            n - i
        } else {
            i
        };
        index[key(i, j, s)]
    };
    let cell = |i: usize, j: usize, s: usize| (s * nj + j) * n + i % n;
    let mut faces = Vec::new();
    for s in 0..ns {
        for j in 0..nj {
            for i in 0..n {
                let c = cell(i, j, s);
                faces.push(Face {
                    nodes: vec![
                        id(i, j + 1, s),
                        id(i + 1, j + 1, s),
                        id(i + 1, j + 1, s + 1),
                        id(i, j + 1, s + 1),
                    ],
                    left: c,
                    right: if j + 1 < nj {
                        Side::Cell(cell(i, j + 1, s))
                    } else {
                        Side::Boundary(Boundary::FarField)
                    },
                });
                faces.push(Face {
                    nodes: vec![
                        id(i + 1, j, s),
                        id(i + 1, j, s + 1),
                        id(i + 1, j + 1, s + 1),
                        id(i + 1, j + 1, s),
                    ],
                    left: c,
                    right: Side::Cell(cell(i + 1, j, s)),
                });
                faces.push(Face {
                    nodes: vec![
                        id(i, j, s + 1),
                        id(i, j + 1, s + 1),
                        id(i + 1, j + 1, s + 1),
                        id(i + 1, j, s + 1),
                    ],
                    left: c,
                    right: if s + 1 < ns {
                        Side::Cell(cell(i, j, s + 1))
                    } else {
                        Side::Boundary(Boundary::FarField)
                    },
                });
                if s == 0 {
                    faces.push(Face {
                        nodes: vec![
                            id(i, j, 0),
                            id(i + 1, j, 0),
                            id(i + 1, j + 1, 0),
                            id(i, j + 1, 0),
                        ],
                        left: c,
                        right: Side::Boundary(Boundary::Symmetry),
                    });
                }
                if j == 0 {
                    let nodes = vec![
                        id(i, 0, s),
                        id(i, 0, s + 1),
                        id(i + 1, 0, s + 1),
                        id(i + 1, 0, s),
                    ];
                    if s < spec.n_span {
                        faces.push(Face {
                            nodes,
                            left: c,
                            right: Side::Boundary(Boundary::Wall),
                        });
                    } else if 2 * i < n {
                        // outboard of the tip: the upper cell meets the lower one across the line
                        faces.push(Face {
                            nodes,
                            left: c,
                            right: Side::Cell(cell(n - 1 - i, 0, s)),
                        });
                    }
                }
            }
        }
    }
    let cells = (0..ns)
        .flat_map(|s| {
            (0..nj).flat_map(move |j| {
                (0..n).map(move |i| {
                    vec![
                        id(i, j, s),
                        id(i, j + 1, s),
                        id(i + 1, j + 1, s),
                        id(i + 1, j, s),
                        id(i, j, s + 1),
                        id(i, j + 1, s + 1),
                        id(i + 1, j + 1, s + 1),
                        id(i + 1, j, s + 1),
                    ]
                })
            })
        })
        .collect();
    let mesh = Mesh {
        nodes: vec![[0.0; 3]; node_index.len()],
        faces,
        n_cells: n * nj * ns,
        cells,
    };
    (mesh, node_index)
}

#[cfg(test)]
mod tests;
