//! Unstructured finite-volume meshes (faces with area vectors, cells with volumes) and the built-in
//! 2-D O-mesh around a closed profile, extruded one cell thick so that 2-D cases run on the 3-D
//! code path. Geometry functions are generic over the scalar, for mesh-motion derivatives.

use gustkit_core::scalar::Scalar;

/// Boundary condition of a boundary face.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Boundary {
    Wall,
    FarField,
    Symmetry,
}

/// A face: its nodes (counter-clockwise seen from the right side, so the area vector points from
/// `left` to `right`), the cell on each side, or the boundary on the right.
#[derive(Clone, Debug, PartialEq)]
pub struct Face {
    pub nodes: Vec<usize>,
    pub left: usize,
    pub right: Side,
}

/// What lies on the right of a face.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Side {
    Cell(usize),
    Boundary(Boundary),
}

/// A mesh: nodes, the faces with their neighbour cells, the number of cells and, for output, each
/// cell's nodes in VTK order (hexahedra: bottom quad, then the top quad above it).
#[derive(Clone, Debug)]
pub struct Mesh {
    pub nodes: Vec<[f64; 3]>,
    pub faces: Vec<Face>,
    pub n_cells: usize,
    pub cells: Vec<Vec<usize>>,
}

/// Why a mesh cannot be used.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MeshError {
    #[error("cell {cell} is inverted or degenerate (volume {volume:e}, mean {mean:e})")]
    BadVolume { cell: usize, volume: f64, mean: f64 },
    #[error(
        "cell {cell} is not closed (its face area vectors sum to {sum:e}, face size {size:e})"
    )]
    Open { cell: usize, sum: f64, size: f64 },
    #[error("face {face} has zero area or joins cell {cell} to itself")]
    BadFace { face: usize, cell: usize },
}

/// Area vector of a polygonal face (|S| = area, normal by the right-hand rule of the node order),
/// from the triangle fan about its centroid: exact for planar faces and consistent for warped
/// ones, so that every closed cell sums to zero.
pub fn face_area<S: Scalar>(pts: &[[S; 3]]) -> [S; 3] {
    let n = pts.len();
    let c: [S; 3] = std::array::from_fn(|i| pts.iter().fold(S::zero(), |a, p| a + p[i]) / n as f64);
    let mut s = [S::zero(); 3];
    for k in 0..n {
        let a: [S; 3] = std::array::from_fn(|i| pts[k][i] - c[i]);
        let b: [S; 3] = std::array::from_fn(|i| pts[(k + 1) % n][i] - c[i]);
        s[0] += (a[1] * b[2] - a[2] * b[1]) * 0.5;
        s[1] += (a[2] * b[0] - a[0] * b[2]) * 0.5;
        s[2] += (a[0] * b[1] - a[1] * b[0]) * 0.5;
    }
    s
}

/// Centroid of a face's nodes.
pub fn face_center<S: Scalar>(pts: &[[S; 3]]) -> [S; 3] {
    std::array::from_fn(|i| pts.iter().fold(S::zero(), |a, p| a + p[i]) / pts.len() as f64)
}

/// Volume swept by a face moving from node positions `a` to `b` (signed: positive along its area
/// vector), the volume of the polyhedron between the two positions computed by the divergence
/// theorem with the same face formulas as the cells. The side quads of an edge shared by two faces
/// of a cell cancel, so the swept volumes of a cell's faces sum to its volume change exactly (the
/// discrete geometric conservation law).
pub fn swept_volume<S: Scalar>(a: &[[S; 3]], b: &[[S; 3]]) -> S {
    let flux = |pts: &[[S; 3]]| {
        let s = face_area(pts);
        let c = face_center(pts);
        c[0] * s[0] + c[1] * s[1] + c[2] * s[2]
    };
    let n = a.len();
    let mut v = flux(b) - flux(a);
    for i in 0..n {
        let j = (i + 1) % n;
        v += flux(&[a[i], a[j], b[j], b[i]]);
    }
    v / 3.0
}

impl Mesh {
    /// Σ over each cell's faces of the volume they sweep as the nodes move from `a` to `b`
    /// (outward positive): the left-hand side of the discrete GCL, equal to the cell's volume
    /// change.
    pub fn swept_volume_sums(&self, a: &[[f64; 3]], b: &[[f64; 3]]) -> Vec<f64> {
        let mut sum = vec![0.0; self.n_cells];
        for f in &self.faces {
            let pa: Vec<[f64; 3]> = f.nodes.iter().map(|&n| a[n]).collect();
            let pb: Vec<[f64; 3]> = f.nodes.iter().map(|&n| b[n]).collect();
            let dv = swept_volume(&pa, &pb);
            sum[f.left] += dv;
            if let Side::Cell(c) = f.right {
                sum[c] -= dv;
            }
        }
        sum
    }

    /// Area vector of face `f`.
    pub fn area(&self, f: usize) -> [f64; 3] {
        let pts: Vec<[f64; 3]> = self.faces[f].nodes.iter().map(|&n| self.nodes[n]).collect();
        face_area(&pts)
    }

    /// Cell volumes by the divergence theorem, V = ⅓ Σ_faces x_f · S_f (outward S).
    pub fn volumes(&self) -> Vec<f64> {
        self.volumes_at(&self.nodes)
    }

    /// Cell volumes with the nodes at `nodes` (any scalar: volume derivatives by dual numbers).
    pub fn volumes_at<S: Scalar>(&self, nodes: &[[S; 3]]) -> Vec<S> {
        let mut v = vec![S::zero(); self.n_cells];
        for f in &self.faces {
            let pts: Vec<[S; 3]> = f.nodes.iter().map(|&n| nodes[n]).collect();
            let s = face_area(&pts);
            let c = face_center(&pts);
            let flux = (c[0] * s[0] + c[1] * s[1] + c[2] * s[2]) / 3.0;
            v[f.left] += flux;
            if let Side::Cell(r) = f.right {
                v[r] -= flux;
            }
        }
        v
    }

    /// Gives every boundary face of condition `from` the condition `to` (e.g. a body's wall
    /// replaced by far field, where a uniform flow must be preserved).
    pub fn relabel(&mut self, from: Boundary, to: Boundary) {
        for f in &mut self.faces {
            if f.right == Side::Boundary(from) {
                f.right = Side::Boundary(to);
            }
        }
    }

    /// Checks that every cell has a positive volume (above 1e-12 of the mean), is closed, and
    /// that every face has an area and two different cells.
    pub fn check(&self) -> Result<(), MeshError> {
        for (fi, f) in self.faces.iter().enumerate() {
            let a = self.area(fi);
            let same = matches!(f.right, Side::Cell(r) if r == f.left);
            if a.iter().all(|v| *v == 0.0) || same || f.left >= self.n_cells {
                return Err(MeshError::BadFace {
                    face: fi,
                    cell: f.left,
                });
            }
        }
        let v = self.volumes();
        let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
        if let Some((cell, &volume)) = v
            .iter()
            .enumerate()
            .find(|(_, v)| !(**v > 1e-12 * mean.abs()))
        {
            return Err(MeshError::BadVolume { cell, volume, mean });
        }
        let mut size = vec![0.0f64; self.n_cells];
        for (fi, f) in self.faces.iter().enumerate() {
            let a = self.area(fi);
            let m = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
            size[f.left] = size[f.left].max(m);
            if let Side::Cell(r) = f.right {
                size[r] = size[r].max(m);
            }
        }
        for (cell, c) in self.closure().iter().enumerate() {
            let sum = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
            if sum > 1e-10 * size[cell] {
                return Err(MeshError::Open {
                    cell,
                    sum,
                    size: size[cell],
                });
            }
        }
        Ok(())
    }

    /// Σ of outward area vectors of every cell (zero for closed cells).
    pub fn closure(&self) -> Vec<[f64; 3]> {
        let mut c = vec![[0.0; 3]; self.n_cells];
        for (fi, f) in self.faces.iter().enumerate() {
            let s = self.area(fi);
            for i in 0..3 {
                c[f.left][i] += s[i];
                if let Side::Cell(r) = f.right {
                    c[r][i] -= s[i];
                }
            }
        }
        c
    }
}

/// n + 1 points s_0 = 0 < … < s_n = 1 with geometrically growing steps, the first `first`.
pub fn geometric_distribution(first: f64, n: usize) -> Vec<f64> {
    geometric_distribution_at(first, n)
}

/// [`geometric_distribution`] in any scalar: the growth ratio g of first · Σ_{k<n} g^k = 1 found
/// in f64 (within [1e-6, 10], as the f64 version), then one Newton step in S (exact first
/// derivatives by the implicit function theorem; none when g sits at the bound).
pub fn geometric_distribution_at<S: Scalar>(first: S, n: usize) -> Vec<S> {
    let g0 = ratio_of(first.re(), n);
    let powers: Vec<f64> = (0..n).map(|k| g0.powi(k as i32)).collect();
    let residual = first * powers.iter().sum::<f64>() - 1.0;
    let slope = first.re() * (1..n).map(|k| k as f64 * powers[k - 1]).sum::<f64>();
    // a ratio held at the bisection's bound (very few, very stretched steps) does not move
    let g = if residual.re().abs() < 1e-10 && slope != 0.0 {
        S::cst(g0) - residual / slope
    } else {
        S::cst(g0)
    };
    let mut s = vec![S::zero()];
    let mut step = first;
    for _ in 0..n {
        let last = *s.last().expect("starts with 0");
        s.push(last + step);
        step *= g;
    }
    let top = *s.last().expect("n > 0");
    s.into_iter().map(|v| v / top).collect()
}

/// The growth ratio g with first · (g^n − 1)/(g − 1) = 1, by bisection.
fn ratio_of(first: f64, n: usize) -> f64 {
    let sum = |g: f64| (0..n).map(|k| g.powi(k as i32)).sum::<f64>() * first;
    let (mut lo, mut hi) = (1e-6, 10.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if sum(mid) > 1.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

/// A 2-D O-mesh around the closed curve `body(t)`, t ∈ [0, 1) counter-clockwise, with
/// `n_around` × `n_radial` cells out to a circle of radius `r_far` about the origin, the radial
/// spacing growing geometrically from `first` (a fraction of the distance to the far field),
/// extruded to one hexahedron of thickness `dz` (symmetry planes at z = 0 and z = dz).
pub fn o_mesh(
    body: &dyn Fn(f64) -> [f64; 2],
    n_around: usize,
    n_radial: usize,
    r_far: f64,
    first: f64,
    dz: f64,
) -> Mesh {
    let s = geometric_distribution(first, n_radial);
    // nodes: ring j, point i, layer k (z = 0, dz)
    let id = |i: usize, j: usize, k: usize| (k * (n_radial + 1) + j) * n_around + i % n_around;
    let mut nodes = vec![[0.0; 3]; 2 * (n_radial + 1) * n_around];
    for i in 0..n_around {
        let t = i as f64 / n_around as f64;
        let b = body(t);
        let ang = 2.0 * std::f64::consts::PI * (i as f64 + 0.5) / n_around as f64;
        let far = [r_far * ang.cos(), r_far * ang.sin()];
        for (j, sj) in s.iter().enumerate() {
            for k in 0..2 {
                nodes[id(i, j, k)] = [
                    b[0] + sj * (far[0] - b[0]),
                    b[1] + sj * (far[1] - b[1]),
                    k as f64 * dz,
                ];
            }
        }
    }
    let cell = |i: usize, j: usize| j * n_around + i % n_around;
    let mut faces = Vec::new();
    for j in 0..n_radial {
        for i in 0..n_around {
            let c = cell(i, j);
            // radial-direction face between rings j+1 (outer side of cell c): normal outward
            let outer = vec![
                id(i, j + 1, 0),
                id(i + 1, j + 1, 0),
                id(i + 1, j + 1, 1),
                id(i, j + 1, 1),
            ];
            faces.push(Face {
                nodes: outer,
                left: c,
                right: if j + 1 < n_radial {
                    Side::Cell(cell(i, j + 1))
                } else {
                    Side::Boundary(Boundary::FarField)
                },
            });
            // face between point columns i+1 (counter-clockwise side of cell c)
            faces.push(Face {
                nodes: vec![
                    id(i + 1, j, 0),
                    id(i + 1, j, 1),
                    id(i + 1, j + 1, 1),
                    id(i + 1, j + 1, 0),
                ],
                left: c,
                right: Side::Cell(cell(i + 1, j)),
            });
            // the two symmetry planes (i runs counter-clockwise and j outward, so (i, j) → (i+1, j)
            // → (i+1, j+1) turns about −z)
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
            faces.push(Face {
                nodes: vec![
                    id(i, j, 1),
                    id(i, j + 1, 1),
                    id(i + 1, j + 1, 1),
                    id(i + 1, j, 1),
                ],
                left: c,
                right: Side::Boundary(Boundary::Symmetry),
            });
            if j == 0 {
                // the wall, outward from the cell (towards the body)
                faces.push(Face {
                    nodes: vec![id(i, 0, 0), id(i, 0, 1), id(i + 1, 0, 1), id(i + 1, 0, 0)],
                    left: c,
                    right: Side::Boundary(Boundary::Wall),
                });
            }
        }
    }
    let cells = (0..n_radial)
        .flat_map(|j| {
            (0..n_around).map(move |i| {
                // the bottom quad turns about +z, towards the top one (VTK's orientation)
                vec![
                    id(i, j, 0),
                    id(i, j + 1, 0),
                    id(i + 1, j + 1, 0),
                    id(i + 1, j, 0),
                    id(i, j, 1),
                    id(i, j + 1, 1),
                    id(i + 1, j + 1, 1),
                    id(i + 1, j, 1),
                ]
            })
        })
        .collect();
    Mesh {
        nodes,
        faces,
        n_cells: n_around * n_radial,
        cells,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(r: f64) -> impl Fn(f64) -> [f64; 2] {
        move |t: f64| {
            let a = 2.0 * std::f64::consts::PI * t;
            [r * a.cos(), r * a.sin()]
        }
    }

    /// Every cell is closed (Σ S = 0 to round-off), every volume positive, the wall and the far
    /// field are closed surfaces, and the total volume of the ring between two circles converges
    /// to π (R² − r²) dz at second order (inscribed polygons lose area ∝ 1/n²).
    #[test]
    fn o_mesh_geometry() {
        let (r, big, dz) = (0.5, 20.0, 0.1);
        let mut errors = Vec::new();
        for &n in &[16usize, 32, 64] {
            let m = o_mesh(&circle(r), n, n / 2, big, 0.01, dz);
            let scale = big * dz;
            for c in m.closure() {
                assert!(c.iter().all(|v| v.abs() < 1e-12 * scale), "{c:?}");
            }
            let v = m.volumes();
            assert!(v.iter().all(|v| *v > 0.0));
            for b in [Boundary::Wall, Boundary::FarField] {
                let mut s = [0.0; 3];
                for (fi, f) in m.faces.iter().enumerate() {
                    if f.right == Side::Boundary(b) {
                        let a = m.area(fi);
                        for i in 0..3 {
                            s[i] += a[i];
                        }
                    }
                }
                assert!(s.iter().all(|v| v.abs() < 1e-12 * scale), "{b:?}: {s:?}");
            }
            let exact = std::f64::consts::PI * (big * big - r * r) * dz;
            errors.push((v.iter().sum::<f64>() - exact).abs() / exact);
        }
        let (e1, e2, e3) = (errors[0], errors[1], errors[2]);
        assert!(e1 / e2 > 3.5 && e2 / e3 > 3.5, "{errors:?}");
    }

    /// Every face's area vector points out of its left cell (from the cell's node centroid to
    /// the face centre), independently of the closure test (which uniformly flipped opposite
    /// faces would pass).
    #[test]
    fn faces_point_out_of_their_left_cell() {
        let m = o_mesh(&circle(0.5), 12, 5, 10.0, 0.02, 0.1);
        let mut centre = vec![[0.0; 3]; m.n_cells];
        let mut count = vec![0.0; m.n_cells];
        for f in &m.faces {
            for &n in &f.nodes {
                for i in 0..3 {
                    centre[f.left][i] += m.nodes[n][i];
                }
                count[f.left] += 1.0;
            }
        }
        for (c, k) in centre.iter_mut().zip(&count) {
            c.iter_mut().for_each(|v| *v /= k);
        }
        for (fi, f) in m.faces.iter().enumerate() {
            let pts: Vec<[f64; 3]> = f.nodes.iter().map(|&n| m.nodes[n]).collect();
            let fc = face_center(&pts);
            let s = m.area(fi);
            let d: f64 = (0..3).map(|i| (fc[i] - centre[f.left][i]) * s[i]).sum();
            assert!(d > 0.0, "face {fi} points into its left cell");
        }
    }

    /// A valid mesh passes the checks; an inverted cell (two nodes of a ring swapped) and a
    /// collapsed one are errors that name the cell.
    #[test]
    fn mesh_checks_name_bad_cells() {
        let m = o_mesh(&circle(0.5), 12, 5, 10.0, 0.02, 0.1);
        assert_eq!(m.check(), Ok(()));
        let mut bad = m.clone();
        // collapse the outer ring of one cell onto its inner ring: zero volume
        for k in 0..2 {
            let (inner, outer) = ((k * 6) * 12 + 3, (k * 6 + 1) * 12 + 3);
            bad.nodes[outer] = bad.nodes[inner];
        }
        // a collapsed cell: its radial faces have no area, or it has no volume
        let e = bad.check().unwrap_err();
        assert!(
            matches!(
                e,
                MeshError::BadFace { cell: 2 | 3, .. } | MeshError::BadVolume { cell: 2 | 3, .. }
            ),
            "{e:?}"
        );
        let mut inverted = m.clone();
        for k in 0..2 {
            let (inner, outer) = ((k * 6) * 12 + 7, (k * 6 + 1) * 12 + 7);
            inverted.nodes.swap(inner, outer);
        }
        let e = inverted.check().unwrap_err();
        assert!(matches!(e, MeshError::BadVolume { .. }), "{e:?}");
        assert!(e.to_string().contains("inverted"));
    }

    /// The cells' node lists follow VTK's hexahedron orientation: the bottom quad's area vector
    /// points towards the top quad.
    #[test]
    fn hexahedra_in_vtk_order() {
        let m = o_mesh(&circle(0.5), 12, 5, 10.0, 0.02, 0.1);
        for c in &m.cells {
            let bottom: Vec<[f64; 3]> = c[..4].iter().map(|&n| m.nodes[n]).collect();
            let top: Vec<[f64; 3]> = c[4..].iter().map(|&n| m.nodes[n]).collect();
            let (s, b, t) = (face_area(&bottom), face_center(&bottom), face_center(&top));
            let d: f64 = (0..3).map(|i| s[i] * (t[i] - b[i])).sum();
            assert!(d > 0.0);
        }
    }

    /// Interior faces are shared: each cell of the O-mesh has exactly six faces.
    #[test]
    fn every_hexahedron_has_six_faces() {
        let m = o_mesh(&circle(0.5), 12, 5, 10.0, 0.02, 0.1);
        let mut count = vec![0; m.n_cells];
        for f in &m.faces {
            count[f.left] += 1;
            if let Side::Cell(r) = f.right {
                count[r] += 1;
            }
        }
        assert!(count.iter().all(|&c| c == 6), "{count:?}");
    }
}
