//! Flat quadrilateral plate element: DKQ bending plus bilinear membrane, generic over the scalar.
//!
//! **Bending: DKQ** (Discrete Kirchhoff Quadrilateral, Batoz & Tahar 1982). The rotations are
//! interpolated with 8-node serendipity functions; the mid-side values are eliminated with the
//! discrete Kirchhoff constraints (cubic w along each edge, linear normal rotation), so transverse
//! shear never enters and the element cannot shear-lock: thin-plate (Kirchhoff) theory is recovered
//! exactly, which is what Leissa's plate results and the 4 %-thick AGARD wing need, and no
//! transverse shear moduli (unknown for the AGARD mahogany) are required. MITC4 would need them.
//!
//! Nodal bending DOFs are `(w, w_x, w_y)`: deflection and its slopes ∂w/∂x, ∂w/∂y (a right-handed
//! rotation about +y is −w_x). Slopes as DOFs make the streamwise slope needed by the aerodynamics
//! a nodal value.
//!
//! **Deflection inside the element** (consistent mass and sampling of mode shapes): DKQ defines w only
//! on the edges, so the interior w uses the 12-term Adini–Clough–Melosh polynomial in natural
//! coordinates, whose nodal natural slopes come from the physical ones through the nodal Jacobian. It
//! reproduces physical quadratics exactly on parallelograms.
//!
//! **Membrane**: bilinear 4-node (u, v) with 2 × 2 Gauss integration (exact for constant strain).
//! For a flat plate at its mid-surface the membrane and bending fields are uncoupled.

use gustkit_core::scalar::Scalar;

/// Node coordinates (x, y) of a quadrilateral, counter-clockwise.
pub type Quad<S> = [[S; 2]; 4];
/// 12 × 12 bending matrix.
pub type Mat12<S> = [[S; 12]; 12];
/// 8 × 8 membrane matrix.
pub type Mat8<S> = [[S; 8]; 8];

const G2: f64 = 0.577_350_269_189_625_8;
/// 2-point Gauss rule on [-1, 1].
pub(crate) const GAUSS2: [(f64, f64); 2] = [(-G2, 1.0), (G2, 1.0)];
/// 4-point Gauss rule on [-1, 1].
pub(crate) const GAUSS4: [(f64, f64); 4] = [
    (-0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
    (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
];
/// Natural coordinates of the corners.
const CORNER: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];

/// Bilinear geometry at a natural point: Jacobian J = [[x_ξ, y_ξ], [x_η, y_η]], det J and J⁻¹.
#[derive(Clone, Copy, Debug)]
pub struct Geometry<S> {
    pub jac: [[S; 2]; 2],
    pub det: S,
    pub inv: [[S; 2]; 2],
}

/// Bilinear shape functions and their natural derivatives at (ξ, η).
fn bilinear(xi: f64, eta: f64) -> ([f64; 4], [[f64; 2]; 4]) {
    let mut n = [0.0; 4];
    let mut d = [[0.0; 2]; 4];
    for (i, c) in CORNER.iter().enumerate() {
        n[i] = 0.25 * (1.0 + xi * c[0]) * (1.0 + eta * c[1]);
        d[i] = [
            0.25 * c[0] * (1.0 + eta * c[1]),
            0.25 * c[1] * (1.0 + xi * c[0]),
        ];
    }
    (n, d)
}

/// Bilinear geometry of quad `xy` at (ξ, η).
pub fn geometry<S: Scalar>(xy: &Quad<S>, xi: f64, eta: f64) -> Geometry<S> {
    let (_, d) = bilinear(xi, eta);
    let mut jac = [[S::zero(); 2]; 2];
    for i in 0..4 {
        for a in 0..2 {
            for c in 0..2 {
                jac[a][c] += xy[i][c] * d[i][a];
            }
        }
    }
    let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
    let inv = [
        [jac[1][1] / det, -jac[0][1] / det],
        [-jac[1][0] / det, jac[0][0] / det],
    ];
    Geometry { jac, det, inv }
}

/// Natural derivatives → physical: [∂/∂x, ∂/∂y] = J⁻¹ [∂/∂ξ, ∂/∂η].
#[inline]
fn to_physical<S: Scalar>(g: &Geometry<S>, dn: [S; 2]) -> [S; 2] {
    [
        g.inv[0][0] * dn[0] + g.inv[0][1] * dn[1],
        g.inv[1][0] * dn[0] + g.inv[1][1] * dn[1],
    ]
}

/// Area of the quadrilateral (2 × 2 Gauss is exact for the bilinear det J).
pub fn area<S: Scalar>(xy: &Quad<S>) -> S {
    let mut a = S::zero();
    for (xi, wx) in GAUSS2 {
        for (eta, wy) in GAUSS2 {
            a += geometry(xy, xi, eta).det * (wx * wy);
        }
    }
    a
}

/// Whether the quad is convex and counter-clockwise (det J > 0 at every corner).
pub fn is_valid(xy: &Quad<f64>) -> bool {
    CORNER.iter().all(|c| geometry(xy, c[0], c[1]).det > 0.0)
}

/// Serendipity 8-node functions and natural derivatives; nodes 0–3 corners, 4–7 mid-sides of
/// edges 0-1, 1-2, 2-3, 3-0.
fn serendipity(xi: f64, eta: f64) -> ([f64; 8], [[f64; 2]; 8]) {
    let mut n = [0.0; 8];
    let mut d = [[0.0; 2]; 8];
    for (i, c) in CORNER.iter().enumerate() {
        let (a, b) = (1.0 + xi * c[0], 1.0 + eta * c[1]);
        let g = xi * c[0] + eta * c[1] - 1.0;
        n[i] = 0.25 * a * b * g;
        d[i] = [0.25 * c[0] * b * (g + a), 0.25 * c[1] * a * (g + b)];
    }
    n[4] = 0.5 * (1.0 - xi * xi) * (1.0 - eta);
    d[4] = [-xi * (1.0 - eta), -0.5 * (1.0 - xi * xi)];
    n[5] = 0.5 * (1.0 + xi) * (1.0 - eta * eta);
    d[5] = [0.5 * (1.0 - eta * eta), -eta * (1.0 + xi)];
    n[6] = 0.5 * (1.0 - xi * xi) * (1.0 + eta);
    d[6] = [-xi * (1.0 + eta), 0.5 * (1.0 - xi * xi)];
    n[7] = 0.5 * (1.0 - xi) * (1.0 - eta * eta);
    d[7] = [-0.5 * (1.0 - eta * eta), -eta * (1.0 - xi)];
    (n, d)
}

/// The DKQ map from the 12 nodal DOFs to the slope field (β_x, β_y) at the 8 serendipity nodes:
/// `t[k][c][dof]`. Mid-side k on edge i–j with unit tangent s and normal n:
/// β = 3/(2 l) (w_j − w_i) s + (½ n nᵀ − ¼ s sᵀ)(β_i + β_j).
fn dkq_nodal_slopes<S: Scalar>(xy: &Quad<S>) -> [[[S; 12]; 2]; 8] {
    let mut t = [[[S::zero(); 12]; 2]; 8];
    for k in 0..4 {
        t[k][0][3 * k + 1] = S::one();
        t[k][1][3 * k + 2] = S::one();
    }
    for e in 0..4 {
        let (i, j) = (e, (e + 1) % 4);
        kirchhoff_midside(xy[i], xy[j], i, j, &mut t[4 + e]);
    }
    t
}

/// The discrete Kirchhoff constraints of one edge i–j (corners at `pi`, `pj`, DOFs (w, w_x,
/// w_y) per corner): the mid-side slopes (β_x, β_y) over the element's DOFs, cubic w along the
/// edge and linear normal slope, β = 3/(2 l) (w_j − w_i) s + (½ n nᵀ − ¼ s sᵀ)(β_i + β_j).
/// Shared by the DKQ and the DKT (`triangle.rs`).
pub(crate) fn kirchhoff_midside<S: Scalar, const D: usize>(
    pi: [S; 2],
    pj: [S; 2],
    i: usize,
    j: usize,
    out: &mut [[S; D]; 2],
) {
    let dx = pj[0] - pi[0];
    let dy = pj[1] - pi[1];
    let l = (dx * dx + dy * dy).sqrt();
    let s = [dx / l, dy / l];
    let n = [s[1], -s[0]];
    for c in 0..2 {
        let a = s[c] * 1.5 / l;
        out[c][3 * j] += a;
        out[c][3 * i] -= a;
        for dd in 0..2 {
            let p = n[c] * n[dd] * 0.5 - s[c] * s[dd] * 0.25;
            out[c][3 * i + 1 + dd] += p;
            out[c][3 * j + 1 + dd] += p;
        }
    }
}

/// Symmetric bilinear accumulation K += w Bᵀ D B for a 3 × n strain matrix B.
#[inline]
fn add_btdb<S: Scalar, const N: usize>(
    k: &mut [[S; N]; N],
    b: &[[S; N]; 3],
    d: &[[f64; 3]; 3],
    w: S,
) {
    let mut db = [[S::zero(); N]; 3];
    for r in 0..3 {
        for c in 0..N {
            let mut acc = S::zero();
            for q in 0..3 {
                if d[r][q] != 0.0 {
                    acc += b[q][c] * d[r][q];
                }
            }
            db[r][c] = acc * w;
        }
    }
    for i in 0..N {
        for j in i..N {
            let mut acc = S::zero();
            for r in 0..3 {
                acc += b[r][i] * db[r][j];
            }
            k[i][j] += acc;
        }
    }
}

/// Copies the upper triangle into the lower.
fn symmetrize<S: Scalar, const N: usize>(k: &mut [[S; N]; N]) {
    for i in 0..N {
        for j in 0..i {
            k[i][j] = k[j][i];
        }
    }
}

/// DKQ curvature matrix B (3 × 12) at (ξ, η): κ = [w_xx, w_yy, 2 w_xy] = B u.
pub fn dkq_curvature<S: Scalar>(
    xy: &Quad<S>,
    t: &[[[S; 12]; 2]; 8],
    xi: f64,
    eta: f64,
) -> ([[S; 12]; 3], S) {
    let g = geometry(xy, xi, eta);
    let (_, dn) = serendipity(xi, eta);
    let mut b = [[S::zero(); 12]; 3];
    for k in 0..8 {
        let [nx, ny] = to_physical(&g, [S::cst(dn[k][0]), S::cst(dn[k][1])]);
        for dof in 0..12 {
            let (tx, ty) = (t[k][0][dof], t[k][1][dof]);
            b[0][dof] += nx * tx;
            b[1][dof] += ny * ty;
            b[2][dof] += ny * tx + nx * ty;
        }
    }
    (b, g.det)
}

/// DKQ bending stiffness for bending rigidity `d` = Q̄ t³/12 given per unit t³ (i.e. Q̄/12):
/// the element stiffness for thickness t is `t³ ·` this matrix.
pub fn dkq_stiffness<S: Scalar>(xy: &Quad<S>, d_unit: &[[f64; 3]; 3]) -> Mat12<S> {
    let t = dkq_nodal_slopes(xy);
    let mut k = [[S::zero(); 12]; 12];
    for (xi, wx) in GAUSS2 {
        for (eta, wy) in GAUSS2 {
            let (b, det) = dkq_curvature(xy, &t, xi, eta);
            add_btdb(&mut k, &b, d_unit, det * (wx * wy));
        }
    }
    symmetrize(&mut k);
    k
}

/// Interior deflection interpolation: the 12 coefficients of w and of its physical slopes w_x, w_y
/// at (ξ, η), so that w = Σ n_w[d] u[d] (Adini–Clough–Melosh polynomial; see module docs).
pub fn deflection_functions<S: Scalar>(xy: &Quad<S>, xi: f64, eta: f64) -> [[S; 12]; 3] {
    // nodal Jacobians map physical slopes to natural ones: [w_ξ, w_η] = J_i [w_x, w_y]
    let jn: [Geometry<S>; 4] = std::array::from_fn(|i| geometry(xy, CORNER[i][0], CORNER[i][1]));
    let g = geometry(xy, xi, eta);
    let mut out = [[S::zero(); 12]; 3];
    for (i, c) in CORNER.iter().enumerate() {
        let (xi0, eta0) = (xi * c[0], eta * c[1]);
        let (a, b) = (1.0 + xi0, 1.0 + eta0);
        let gq = 2.0 + xi0 + eta0 - xi * xi - eta * eta;
        // value and natural derivatives of the three nodal functions (w, w_ξ, w_η)
        let nw = [
            0.125 * a * b * gq,
            0.125 * (c[0] * b * gq + a * b * (c[0] - 2.0 * xi)),
            0.125 * (c[1] * a * gq + a * b * (c[1] - 2.0 * eta)),
        ];
        let nxi = [
            0.125 * c[0] * a * a * (xi0 - 1.0) * b,
            0.125 * b * a * (3.0 * xi0 - 1.0),
            0.125 * c[0] * a * a * (xi0 - 1.0) * c[1],
        ];
        let neta = [
            0.125 * c[1] * b * b * (eta0 - 1.0) * a,
            0.125 * c[1] * b * b * (eta0 - 1.0) * c[0],
            0.125 * a * b * (3.0 * eta0 - 1.0),
        ];
        let j = &jn[i].jac;
        // coefficient of nodal w_x: N_ξ J00 + N_η J10 ; of w_y: N_ξ J01 + N_η J11
        let fx: [S; 3] = std::array::from_fn(|q| j[0][0] * nxi[q] + j[1][0] * neta[q]);
        let fy: [S; 3] = std::array::from_fn(|q| j[0][1] * nxi[q] + j[1][1] * neta[q]);
        let fw: [S; 3] = std::array::from_fn(|q| S::cst(nw[q]));
        for (col, f) in [(3 * i, fw), (3 * i + 1, fx), (3 * i + 2, fy)] {
            out[0][col] = f[0];
            let [dx, dy] = to_physical(&g, [f[1], f[2]]);
            out[1][col] = dx;
            out[2][col] = dy;
        }
    }
    out
}

/// Consistent bending mass per unit areal density ρt: ∫ n_w n_wᵀ dA (4 × 4 Gauss).
pub fn bending_mass<S: Scalar>(xy: &Quad<S>) -> Mat12<S> {
    let mut m = [[S::zero(); 12]; 12];
    for (xi, wx) in GAUSS4 {
        for (eta, wy) in GAUSS4 {
            let nw = deflection_functions(xy, xi, eta)[0];
            let det = geometry(xy, xi, eta).det * (wx * wy);
            for i in 0..12 {
                let a = nw[i] * det;
                for j in i..12 {
                    m[i][j] += a * nw[j];
                }
            }
        }
    }
    symmetrize(&mut m);
    m
}

/// Membrane strain matrix (3 × 8) at (ξ, η) for DOFs (u0, v0, u1, v1, …) and det J.
pub fn membrane_strain<S: Scalar>(xy: &Quad<S>, xi: f64, eta: f64) -> ([[S; 8]; 3], S) {
    let g = geometry(xy, xi, eta);
    let (_, dn) = bilinear(xi, eta);
    let mut b = [[S::zero(); 8]; 3];
    for i in 0..4 {
        let [nx, ny] = to_physical(&g, [S::cst(dn[i][0]), S::cst(dn[i][1])]);
        b[0][2 * i] = nx;
        b[1][2 * i + 1] = ny;
        b[2][2 * i] = ny;
        b[2][2 * i + 1] = nx;
    }
    (b, g.det)
}

/// Membrane stiffness per unit thickness (Q̄ given): the element stiffness is `t ·` this matrix.
pub fn membrane_stiffness<S: Scalar>(xy: &Quad<S>, qbar: &[[f64; 3]; 3]) -> Mat8<S> {
    let mut k = [[S::zero(); 8]; 8];
    for (xi, wx) in GAUSS2 {
        for (eta, wy) in GAUSS2 {
            let (b, det) = membrane_strain(xy, xi, eta);
            add_btdb(&mut k, &b, qbar, det * (wx * wy));
        }
    }
    symmetrize(&mut k);
    k
}

/// Consistent membrane mass per unit areal density ρt.
pub fn membrane_mass<S: Scalar>(xy: &Quad<S>) -> Mat8<S> {
    let mut m = [[S::zero(); 8]; 8];
    for (xi, wx) in GAUSS2 {
        for (eta, wy) in GAUSS2 {
            let (n, _) = bilinear(xi, eta);
            let det = geometry(xy, xi, eta).det * (wx * wy);
            for i in 0..4 {
                for j in 0..4 {
                    let v = det * (n[i] * n[j]);
                    m[2 * i][2 * j] += v;
                    m[2 * i + 1][2 * j + 1] += v;
                }
            }
        }
    }
    m
}

/// Membrane displacement functions (u or v) at (ξ, η): the bilinear weights of the corners.
pub fn membrane_functions(xi: f64, eta: f64) -> [f64; 4] {
    bilinear(xi, eta).0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A distorted, non-parallelogram quad to make the tests meaningful.
    fn quad() -> Quad<f64> {
        [[0.0, 0.0], [1.1, 0.1], [1.3, 0.9], [0.2, 1.2]]
    }
    fn parallelogram() -> Quad<f64> {
        [[0.0, 0.0], [1.0, 0.0], [1.6, 0.8], [0.6, 0.8]]
    }

    fn dofs_of(xy: &Quad<f64>, w: impl Fn(f64, f64) -> [f64; 3]) -> [f64; 12] {
        let mut u = [0.0; 12];
        for i in 0..4 {
            let v = w(xy[i][0], xy[i][1]);
            u[3 * i..3 * i + 3].copy_from_slice(&v);
        }
        u
    }

    fn energy<const N: usize>(k: &[[f64; N]; N], u: &[f64; N]) -> f64 {
        let mut e = 0.0;
        for i in 0..N {
            for j in 0..N {
                e += u[i] * k[i][j] * u[j];
            }
        }
        0.5 * e
    }

    fn dmat() -> [[f64; 3]; 3] {
        [[2.0, 0.6, 0.1], [0.6, 1.5, 0.2], [0.1, 0.2, 0.7]]
    }

    /// Rigid-body motions (w = a + b x + c y) store no bending energy; rigid in-plane motions
    /// (translations, rotation) none in the membrane.
    #[test]
    fn rigid_body_modes_have_zero_energy() {
        let xy = quad();
        let k = dkq_stiffness(&xy, &dmat());
        let scale = k.iter().flatten().fold(0.0f64, |a, b| a.max(b.abs()));
        for f in [
            |_: f64, _: f64| [1.0, 0.0, 0.0],
            |x: f64, _: f64| [x, 1.0, 0.0],
            |_: f64, y: f64| [y, 0.0, 1.0],
        ] {
            let u = dofs_of(&xy, f);
            assert!(energy(&k, &u).abs() < 1e-13 * scale);
        }
        let km = membrane_stiffness(&xy, &dmat());
        let mut rigid = [[0.0; 8]; 3];
        for i in 0..4 {
            rigid[0][2 * i] = 1.0;
            rigid[1][2 * i + 1] = 1.0;
            rigid[2][2 * i] = -xy[i][1];
            rigid[2][2 * i + 1] = xy[i][0];
        }
        for u in rigid {
            assert!(energy(&km, &u).abs() < 1e-13);
        }
    }

    /// Constant-curvature patch: for w = a x² + b x y + c y² the element energy is exactly
    /// ½ κᵀ D κ A, with κ = (2a, 2c, 2b), on a distorted quad.
    #[test]
    fn constant_curvature_patch_is_exact() {
        let xy = quad();
        let d = dmat();
        let k = dkq_stiffness(&xy, &d);
        let (a, b, c) = (0.3, -0.7, 0.45);
        let u = dofs_of(&xy, |x, y| {
            [
                a * x * x + b * x * y + c * y * y,
                2.0 * a * x + b * y,
                b * x + 2.0 * c * y,
            ]
        });
        let kappa = [2.0 * a, 2.0 * c, 2.0 * b];
        let mut exact = 0.0;
        for i in 0..3 {
            for j in 0..3 {
                exact += kappa[i] * d[i][j] * kappa[j];
            }
        }
        exact *= 0.5 * area(&xy);
        let e = energy(&k, &u);
        assert!((e - exact).abs() < 1e-12 * exact.abs(), "{e} vs {exact}");
        // and the curvature is reproduced pointwise at the Gauss points
        let t = dkq_nodal_slopes(&xy);
        let (bm, _) = dkq_curvature(&xy, &t, 0.3, -0.6);
        for r in 0..3 {
            let kr: f64 = (0..12).map(|q| bm[r][q] * u[q]).sum();
            assert!((kr - kappa[r]).abs() < 1e-12);
        }
    }

    /// Constant-strain membrane patch: u = a x + b y, v = c x + d y gives energy ½ εᵀ Q ε A.
    #[test]
    fn constant_strain_patch_is_exact() {
        let xy = quad();
        let q = dmat();
        let km = membrane_stiffness(&xy, &q);
        let (a, b, c, dd) = (0.2, -0.1, 0.4, 0.3);
        let mut u = [0.0; 8];
        for i in 0..4 {
            u[2 * i] = a * xy[i][0] + b * xy[i][1];
            u[2 * i + 1] = c * xy[i][0] + dd * xy[i][1];
        }
        let eps = [a, dd, b + c];
        let mut exact = 0.0;
        for i in 0..3 {
            for j in 0..3 {
                exact += eps[i] * q[i][j] * eps[j];
            }
        }
        exact *= 0.5 * area(&xy);
        assert!((energy(&km, &u) - exact).abs() < 1e-13 * exact);
    }

    /// The interior deflection reproduces any physical quadratic on a parallelogram (value and slopes),
    /// and the consistent mass integrates the density exactly: uᵀ M 1 for w = 1 is the area.
    #[test]
    fn deflection_interpolation_reproduces_quadratics() {
        let xy = parallelogram();
        let w = |x: f64, y: f64| 0.4 + 0.3 * x - 0.2 * y + 0.5 * x * x - 0.6 * x * y + 0.25 * y * y;
        let u = dofs_of(&xy, |x, y| {
            [w(x, y), 0.3 + x - 0.6 * y, -0.2 - 0.6 * x + 0.5 * y]
        });
        for (xi, eta) in [(0.1, 0.2), (-0.7, 0.5), (0.9, -0.3)] {
            let f = deflection_functions(&xy, xi, eta);
            let (n, _) = bilinear(xi, eta);
            let x: f64 = (0..4).map(|i| n[i] * xy[i][0]).sum();
            let y: f64 = (0..4).map(|i| n[i] * xy[i][1]).sum();
            let val: [f64; 3] = std::array::from_fn(|r| (0..12).map(|q| f[r][q] * u[q]).sum());
            assert!((val[0] - w(x, y)).abs() < 1e-13);
            assert!((val[1] - (0.3 + x - 0.6 * y)).abs() < 1e-13);
            assert!((val[2] - (-0.2 - 0.6 * x + 0.5 * y)).abs() < 1e-13);
        }
        let m = bending_mass(&quad());
        let one = dofs_of(&quad(), |_, _| [1.0, 0.0, 0.0]);
        let total = 2.0 * energy(&m, &one);
        assert!((total - area(&quad())).abs() < 1e-13);
        let mm = membrane_mass(&quad());
        let ux: [f64; 8] = std::array::from_fn(|i| if i % 2 == 0 { 1.0 } else { 0.0 });
        assert!((2.0 * energy(&mm, &ux) - area(&quad())).abs() < 1e-13);
    }

    /// Shoelace area against the Gauss-integrated det J.
    #[test]
    fn area_matches_shoelace() {
        let xy = quad();
        let mut s = 0.0;
        for i in 0..4 {
            let j = (i + 1) % 4;
            s += xy[i][0] * xy[j][1] - xy[j][0] * xy[i][1];
        }
        assert!((area(&xy) - 0.5 * s).abs() < 1e-14);
        assert!(is_valid(&xy));
        let crossed = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
        assert!(!is_valid(&crossed));
    }
}
