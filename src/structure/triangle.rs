//! Flat triangular plate element: DKT bending plus constant-strain membrane, for Nastran's
//! CTRIA3 (gustkit's own wing is meshed with quadrilaterals, `element.rs`).
//!
//! **Bending: DKT** (Discrete Kirchhoff Triangle, Batoz, Bathe & Ho 1980), built as `element.rs`
//! builds the DKQ: the slopes (β_x, β_y) are interpolated with the 6-node quadratic triangle,
//! the mid-side values eliminated by the discrete Kirchhoff constraints (cubic w along each edge,
//! linear normal slope), so no transverse shear enters. The curvature is linear in the element,
//! so the 3-point rule at (1/6, 1/6), (2/3, 1/6), (1/6, 2/3) integrates Bᵀ D B exactly. Nodal
//! bending DOFs are `(w, w_x, w_y)` as the DKQ's.
//!
//! **Membrane**: the constant-strain triangle (u, v per node). **Mass**: lumped (a third of the
//! element's mass on each node's translations) or, for Nastran's COUPMASS, the consistent mass
//! of linear w, u and v (ρtA/12 · [2 1 1; 1 2 1; 1 1 2]; no rotary inertia, as the DKT defines w
//! only on its edges).

/// Node coordinates (x, y) of a triangle, counter-clockwise.
pub type Tri = [[f64; 2]; 3];

/// Twice the signed area: positive for counter-clockwise nodes.
pub fn twice_area(xy: &Tri) -> f64 {
    (xy[1][0] - xy[0][0]) * (xy[2][1] - xy[0][1]) - (xy[2][0] - xy[0][0]) * (xy[1][1] - xy[0][1])
}

/// The DKT map from the 9 nodal DOFs to the slopes (β_x, β_y) at the 6 quadratic nodes (corners
/// 0–2, mid-sides 3–5 of edges 0-1, 1-2, 2-0): `t[k][c][dof]`, the mid-sides by the DKQ's
/// edge constraints (`element::kirchhoff_midside`).
fn nodal_slopes(xy: &Tri) -> [[[f64; 9]; 2]; 6] {
    let mut t = [[[0.0; 9]; 2]; 6];
    for k in 0..3 {
        t[k][0][3 * k + 1] = 1.0;
        t[k][1][3 * k + 2] = 1.0;
    }
    for e in 0..3 {
        let (i, j) = (e, (e + 1) % 3);
        super::element::kirchhoff_midside(xy[i], xy[j], i, j, &mut t[3 + e]);
    }
    t
}

/// Physical derivatives (∂/∂x, ∂/∂y) of the 6 quadratic shape functions at (ξ, η).
fn quadratic_gradients(xy: &Tri, xi: f64, eta: f64) -> [[f64; 2]; 6] {
    let l = [1.0 - xi - eta, xi, eta];
    let dl = [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]];
    let mut dn = [[0.0; 2]; 6];
    for i in 0..3 {
        for c in 0..2 {
            dn[i][c] = (4.0 * l[i] - 1.0) * dl[i][c];
        }
    }
    for e in 0..3 {
        let (a, b) = (e, (e + 1) % 3);
        for c in 0..2 {
            dn[3 + e][c] = 4.0 * (l[b] * dl[a][c] + l[a] * dl[b][c]);
        }
    }
    // J = [[x_ξ, y_ξ], [x_η, y_η]]; [∂x, ∂y] = J⁻¹ [∂ξ, ∂η]
    let j = [
        [xy[1][0] - xy[0][0], xy[1][1] - xy[0][1]],
        [xy[2][0] - xy[0][0], xy[2][1] - xy[0][1]],
    ];
    let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
    let inv = [
        [j[1][1] / det, -j[0][1] / det],
        [-j[1][0] / det, j[0][0] / det],
    ];
    dn.map(|d| {
        [
            inv[0][0] * d[0] + inv[0][1] * d[1],
            inv[1][0] * d[0] + inv[1][1] * d[1],
        ]
    })
}

/// DKT curvature matrix B (3 × 9) at (ξ, η): κ = [w_xx, w_yy, 2 w_xy] = B u.
pub fn dkt_curvature(xy: &Tri, xi: f64, eta: f64) -> [[f64; 9]; 3] {
    let t = nodal_slopes(xy);
    let dn = quadratic_gradients(xy, xi, eta);
    let mut b = [[0.0; 9]; 3];
    for k in 0..6 {
        let [nx, ny] = dn[k];
        for dof in 0..9 {
            let (tx, ty) = (t[k][0][dof], t[k][1][dof]);
            b[0][dof] += nx * tx;
            b[1][dof] += ny * ty;
            b[2][dof] += ny * tx + nx * ty;
        }
    }
    b
}

/// The 3-point rule exact for quadratics on the reference triangle (weights sum to its area ½).
const RULE: [(f64, f64, f64); 3] = [
    (1.0 / 6.0, 1.0 / 6.0, 1.0 / 6.0),
    (2.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0),
    (1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0),
];

/// DKT bending stiffness for the rigidity `d_unit` = Q̄/12 (per unit t³): the element's
/// stiffness for thickness t is t³ times this matrix.
pub fn dkt_stiffness(xy: &Tri, d_unit: &[[f64; 3]; 3]) -> [[f64; 9]; 9] {
    let det = twice_area(xy);
    let mut k = [[0.0; 9]; 9];
    for (xi, eta, w) in RULE {
        let b = dkt_curvature(xy, xi, eta);
        for i in 0..9 {
            for j in 0..9 {
                let mut acc = 0.0;
                for r in 0..3 {
                    for q in 0..3 {
                        acc += b[r][i] * d_unit[r][q] * b[q][j];
                    }
                }
                k[i][j] += acc * w * det;
            }
        }
    }
    k
}

/// Constant-strain membrane stiffness per unit thickness, DOFs (u, v) per node:
/// A Bᵀ Q̄ B with ε = [u_x, v_y, u_y + v_x] = B u.
pub fn cst_stiffness(xy: &Tri, qbar: &[[f64; 3]; 3]) -> [[f64; 6]; 6] {
    let a2 = twice_area(xy);
    let mut b = [[0.0; 6]; 3];
    for i in 0..3 {
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        // ∂N_i/∂x = (y_j − y_k)/2A, ∂N_i/∂y = (x_k − x_j)/2A
        let nx = (xy[j][1] - xy[k][1]) / a2;
        let ny = (xy[k][0] - xy[j][0]) / a2;
        b[0][2 * i] = nx;
        b[1][2 * i + 1] = ny;
        b[2][2 * i] = ny;
        b[2][2 * i + 1] = nx;
    }
    let mut k = [[0.0; 6]; 6];
    for i in 0..6 {
        for j in 0..6 {
            let mut acc = 0.0;
            for r in 0..3 {
                for q in 0..3 {
                    acc += b[r][i] * qbar[r][q] * b[q][j];
                }
            }
            k[i][j] = 0.5 * a2 * acc;
        }
    }
    k
}

/// The consistent mass of a linear field over the triangle per unit mass per area:
/// A/12 · [2 1 1; 1 2 1; 1 1 2].
pub fn linear_mass(xy: &Tri) -> [[f64; 3]; 3] {
    let a = 0.5 * twice_area(xy);
    std::array::from_fn(|i| std::array::from_fn(|j| a / 12.0 * if i == j { 2.0 } else { 1.0 }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An oblique, stretched triangle (no edge along an axis).
    const TRI: Tri = [[0.3, -0.2], [2.1, 0.4], [0.9, 1.7]];

    /// The patch test: for any quadratic w = c₀ + c₁x + c₂y + c₃x² + c₄xy + c₅y² the nodal
    /// (w, w_x, w_y) give the exact constant curvature κ = [2c₃, 2c₅, 2c₄] at every point
    /// (1e-13) and the strain energy ½ uᵀKu = ½ A κᵀDκ (1e-13); a linear w has none.
    #[test]
    fn dkt_passes_the_patch_test() {
        let d = [[1.3, 0.4, 0.1], [0.4, 0.9, -0.2], [0.1, -0.2, 0.5]];
        let k = dkt_stiffness(&TRI, &d);
        for c in [
            [0.2, -0.5, 0.7, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
            [0.4, 0.3, -0.2, 0.8, -1.1, 0.6],
        ] {
            let u: Vec<f64> = TRI
                .iter()
                .flat_map(|&[x, y]| {
                    [
                        c[0] + c[1] * x + c[2] * y + c[3] * x * x + c[4] * x * y + c[5] * y * y,
                        c[1] + 2.0 * c[3] * x + c[4] * y,
                        c[2] + c[4] * x + 2.0 * c[5] * y,
                    ]
                })
                .collect();
            let kappa = [2.0 * c[3], 2.0 * c[5], 2.0 * c[4]];
            for (xi, eta) in [(0.1, 0.2), (0.7, 0.05), (0.3, 0.6)] {
                let b = dkt_curvature(&TRI, xi, eta);
                for r in 0..3 {
                    let got: f64 = (0..9).map(|j| b[r][j] * u[j]).sum();
                    assert!(
                        (got - kappa[r]).abs() < 1e-13,
                        "{c:?} κ{r}: {got} vs {}",
                        kappa[r]
                    );
                }
            }
            let energy: f64 = (0..9)
                .map(|i| (0..9).map(|j| u[i] * k[i][j] * u[j]).sum::<f64>())
                .sum::<f64>()
                * 0.5;
            let exact: f64 = 0.25
                * twice_area(&TRI)
                * (0..3)
                    .map(|r| (0..3).map(|q| kappa[r] * d[r][q] * kappa[q]).sum::<f64>())
                    .sum::<f64>();
            assert!(
                (energy - exact).abs() < 1e-13 * exact.abs().max(1.0),
                "{energy} vs {exact}"
            );
        }
    }

    /// The membrane: constant strain exact (energy ½ A εᵀQ̄ε to 1e-14), rigid motions free.
    #[test]
    fn cst_energy_is_exact_for_constant_strain() {
        let q = [[2.0, 0.6, 0.0], [0.6, 1.5, 0.0], [0.0, 0.0, 0.7]];
        let k = cst_stiffness(&TRI, &q);
        // u = a + e₁x + γ/2 y − ωy, v = b + e₂y + γ/2 x + ωx
        for (e1, e2, g, w) in [(0.0, 0.0, 0.0, 0.3), (0.1, -0.2, 0.3, 0.2)] {
            let u: Vec<f64> = TRI
                .iter()
                .flat_map(|&[x, y]| {
                    [
                        0.1 + e1 * x + 0.5 * g * y - w * y,
                        -0.2 + e2 * y + 0.5 * g * x + w * x,
                    ]
                })
                .collect();
            let energy: f64 = (0..6)
                .map(|i| (0..6).map(|j| u[i] * k[i][j] * u[j]).sum::<f64>())
                .sum::<f64>()
                * 0.5;
            let eps = [e1, e2, g];
            let exact = 0.25
                * twice_area(&TRI)
                * (0..3)
                    .map(|r| (0..3).map(|c| eps[r] * q[r][c] * eps[c]).sum::<f64>())
                    .sum::<f64>();
            assert!((energy - exact).abs() < 1e-14, "{energy} vs {exact}");
        }
    }
}
