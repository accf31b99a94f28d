//! Derivatives of the LFD along a motion of the mesh (the planform variables move the built-in
//! wing mesh): the steady tangent and the second-derivative terms of paper Eq. 19.
//!
//! For a mesh tangent δX (and the deformation radius's rate δr) the GAFs change through
//! - the steady state: δq₀ = −(∂R/∂q)⁻¹ ∂R/∂X δX (one steady tangent solve a direction, with the
//!   LFD machinery at ω = 0);
//! - the LFD operator and right-hand sides at the fixed solution q̂: t = δ(A q̂ + b), the mixed
//!   second derivatives of the residual, cell volumes and swept volumes, all in one evaluation
//!   over hyper-dual numbers (ε: the real and imaginary parts of the LFD perturbation, δ: the
//!   mesh direction, with δq₀ and the tangent δx̂ of the spread mode shape);
//! - the linearized wall forces at fixed q̂: the same evaluation's ∂f̂.
//!
//! With the adjoint solutions λ of the mode-shape reverse mode (and one more for the gust column)
//! the seeded GAFs' derivative is Σ_k Σ_columns Re(uᵀ ∂f̂ − λᵀ t): no LFD solve per direction.

use crate::gas::NVAR;
use crate::lfd::{Field, LfdError, LfdOperator, Symbol};
use crate::residual::State;
use gustkit_core::hyperdual::HyperDual;
use gustkit_core::scalar::{Dual, Scalar};
use num_complex::Complex64 as C64;
use rayon::prelude::*;

/// A direction of mesh motion: the nodes' rates (mesh units per unit of the parameter) and the
/// deformation radius's rate.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshTangent {
    /// The parameter's name (e.g. "span").
    pub name: String,
    pub nodes: Vec<[f64; 3]>,
    pub radius: f64,
}

/// A hyper-dual number of the column tangents: ε the real and imaginary LFD perturbation, `M`
/// mesh directions δ.
type Hd<const M: usize> = HyperDual<2, M>;

fn hd<const M: usize>(v: f64, a: C64, b: [f64; M], ab: [C64; M]) -> Hd<M> {
    HyperDual::new(v, [a.re, a.im], b, ab.map(|z| [z.re, z.im]))
}

fn a_part<const M: usize>(x: Hd<M>) -> C64 {
    C64::new(x.a[0], x.a[1])
}

/// The ε δ_m part.
fn ab_part<const M: usize>(x: Hd<M>, m: usize) -> C64 {
    C64::new(x.ab[m][0], x.ab[m][1])
}

/// What drives an LFD column: a mode motion (node displacements x̂ and their tangents δx̂ along
/// each of `M` mesh directions) or the gust (face volume fluxes ĝ, already scaled, and their
/// tangents δĝ).
pub enum Column<'a, const M: usize = 1> {
    Motion {
        x_hat: &'a [[C64; 3]],
        dx_hat: [&'a [[C64; 3]]; M],
        /// The faces' swept volumes of this motion along these directions
        /// ([`LfdOperator::swept_volumes`]): they do not depend on the frequency, so a reverse
        /// sweep computes them once a column instead of once a column and frequency.
        swept: &'a [SweptFace<M>],
    },
    Gust {
        g: &'a [C64],
        dg: [&'a [C64]; M],
    },
}

/// A face's volume swept from X to X + ε x̂ as both move along `M` mesh directions δ: its ε part
/// L_X(x̂) and the ε δ_m parts, the derivatives of that linearization. The grid-velocity flux of
/// a motion column at s is s times them.
pub type SweptFace<const M: usize> = (C64, [C64; M]);

/// A column's mode motion x̂ and its tangents δx̂ along `M` mesh directions.
type Motion<'a, const M: usize> = (&'a [[C64; 3]], [&'a [[C64; 3]]; M]);

/// The hyper-dual position of node `n`: the mesh's, moving along the `M` directions `d_nodes`,
/// plus ε times a column's motion x̂ (with its tangents δx̂) where one is given.
fn hd_node<const M: usize>(
    mesh: &crate::mesh::Mesh,
    d_nodes: [&[[f64; 3]]; M],
    motion: Option<Motion<M>>,
    n: usize,
) -> [Hd<M>; 3] {
    let zero = C64::new(0.0, 0.0);
    std::array::from_fn(|k| {
        let b = std::array::from_fn(|m| d_nodes[m][n][k]);
        match motion {
            Some((x_hat, dx_hat)) => hd(
                mesh.nodes[n][k],
                x_hat[n][k],
                b,
                std::array::from_fn(|m| dx_hat[m][n][k]),
            ),
            None => hd(mesh.nodes[n][k], zero, b, [zero; M]),
        }
    })
}

impl LfdOperator {
    /// Every face's swept volume of the mode motion `x_hat` (tangents `dx_hat`) along the `M`
    /// mesh directions `d_nodes`, for [`Column::Motion`]: one hyper-dual evaluation of each
    /// face's swept volume from X to X + ε x̂, both moving with δ.
    pub fn swept_volumes<const M: usize>(
        &self,
        x_hat: &[[C64; 3]],
        dx_hat: [&[[C64; 3]]; M],
        d_nodes: [&[[f64; 3]]; M],
    ) -> Vec<SweptFace<M>> {
        let mesh = &self.euler.mesh;
        mesh.faces
            .iter()
            .map(|f| {
                let a: Vec<[Hd<M>; 3]> = f
                    .nodes
                    .iter()
                    .map(|&n| hd_node(mesh, d_nodes, None, n))
                    .collect();
                let b: Vec<[Hd<M>; 3]> = f
                    .nodes
                    .iter()
                    .map(|&n| hd_node(mesh, d_nodes, Some((x_hat, dx_hat)), n))
                    .collect();
                let l = crate::mesh::swept_volume(&a, &b);
                (a_part(l), std::array::from_fn(|m| ab_part(l, m)))
            })
            .collect()
    }

    /// The steady tangents δq₀ = −(∂R/∂q)⁻¹ ∂R/∂X δX of mesh motions δX (each flattened like a
    /// field): the right-hand sides in parallel, then one ω = 0 factorization for all of them
    /// and one GMRES call (batched like the GAF table's right-hand sides).
    pub fn steady_tangents(&self, d_nodes: &[&[[f64; 3]]]) -> Result<Vec<Vec<f64>>, LfdError> {
        let e = &self.euler;
        let rhs: Vec<Field> = d_nodes
            .par_iter()
            .map(|d_nodes| {
                let nodes: Vec<[Dual<1>; 3]> = e
                    .mesh
                    .nodes
                    .iter()
                    .zip(d_nodes.iter())
                    .map(|(p, d)| std::array::from_fn(|k| Dual::new(p[k], [d[k]])))
                    .collect();
                let vg = e.face_vg.iter().map(|v| Dual::cst(*v)).collect();
                let geom = e.geometry_at(&nodes, vg, e.order);
                let q: Vec<State<Dual<1>>> = self.q0.iter().map(|s| s.map(Dual::cst)).collect();
                e.residual_in(&q, &geom)
                    .0
                    .iter()
                    .flatten()
                    .map(|r| C64::new(r.d[0], 0.0))
                    .collect()
            })
            .collect();
        if rhs.is_empty() {
            return Ok(Vec::new());
        }
        let f = self.factor(0.0, Symbol::Exact)?;
        Ok(self
            .solve(&f, &rhs)?
            .into_iter()
            .map(|(x, _)| x.iter().map(|z| z.re).collect())
            .collect())
    }

    /// The tangents δX · ∂/∂X at fixed LFD solution q̂ of one column along `M` mesh directions
    /// at once (one hyper-dual evaluation): per direction m, t = δ_m(A q̂ + b) per cell state and
    /// ∂f̂ per wall face (in the order of [`LfdOperator::wall_face_forces`]), for the mesh
    /// tangent `d_nodes[m]` and the steady tangent `dq0[m]`, at s.
    pub fn column_tangents<const M: usize>(
        &self,
        s: C64,
        q_hat: &[C64],
        column: &Column<M>,
        d_nodes: [&[[f64; 3]]; M],
        dq0: [&[f64]; M],
    ) -> [(Field, Vec<[C64; 3]>); M] {
        let e = &self.euler;
        let mesh = &e.mesh;
        let zero = C64::new(0.0, 0.0);
        let order = e.order;
        let motion = match column {
            Column::Motion { x_hat, dx_hat, .. } => Some((*x_hat, *dx_hat)),
            Column::Gust { .. } => None,
        };
        let nodes: Vec<[Hd<M>; 3]> = (0..mesh.nodes.len())
            .map(|n| hd_node(mesh, d_nodes, motion, n))
            .collect();
        let q: Vec<State<Hd<M>>> = self
            .q0
            .iter()
            .enumerate()
            .map(|(c, qc)| {
                std::array::from_fn(|k| {
                    let i = c * NVAR + k;
                    hd(
                        qc[k],
                        q_hat[i],
                        std::array::from_fn(|m| dq0[m][i]),
                        [zero; M],
                    )
                })
            })
            .collect();
        let vg: Vec<Hd<M>> = match column {
            Column::Motion { swept, .. } => {
                assert_eq!(swept.len(), mesh.faces.len(), "one swept volume a face");
                swept
                    .iter()
                    .zip(&e.face_vg)
                    .map(|((l, dl), vg)| hd(*vg, s * l, [0.0; M], dl.map(|d| s * d)))
                    .collect()
            }
            Column::Gust { g, dg } => (0..mesh.faces.len())
                .map(|fi| {
                    hd(
                        e.face_vg[fi],
                        g[fi],
                        [0.0; M],
                        std::array::from_fn(|m| dg[m][fi]),
                    )
                })
                .collect(),
        };
        let mut geom = e.geometry_at(&nodes, vg, order);
        let r = e.residual_in(&q, &geom).0;
        let v = mesh.volumes_at(&nodes);
        // the forces on the same geometry, static: only the face volume fluxes change (the
        // hyper-dual areas and reconstruction geometry, about a fifth of the work, are not
        // computed twice)
        geom.face_vg.iter_mut().for_each(|w| *w = Hd::cst(0.0));
        let forces = e.wall_face_forces(&q, &geom);
        std::array::from_fn(|m| {
            let mut t = vec![zero; self.n()];
            for c in 0..mesh.n_cells {
                for k in 0..NVAR {
                    t[c * NVAR + k] = ab_part(r[c][k], m) + s * ab_part(v[c] * q[c][k], m);
                }
            }
            let df = forces
                .iter()
                .map(|(_, f)| f.map(|x| ab_part(x, m)))
                .collect();
            (t, df)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::airfoil::AirfoilShape;
    use crate::residual::{free_stream, Euler};
    use crate::steady::SteadyParams;

    /// Every entry of `t` equals the central difference of `plus` and `minus` at step `h` to
    /// 1e-6 of the largest entry.
    fn assert_central(t: &[C64], plus: &[C64], minus: &[C64], h: f64, what: &str) {
        let scale = t.iter().fold(0.0f64, |a, v| a.max(v.norm()));
        for i in 0..t.len() {
            let fd = (plus[i] - minus[i]) / (2.0 * h);
            assert!(
                (fd - t[i]).norm() < 1e-6 * scale,
                "{what} t[{i}]: {} vs {fd}",
                t[i]
            );
        }
    }

    /// The hyper-dual tangents of a motion column (A q̂ + B x̂ and the linearized forces) and of
    /// the gust column (A q̂ + b_gust, with the generic gust fluxes' values equal to the plain
    /// ones) equal central differences (step 1e-6) of the forward pieces on the moved mesh with
    /// the moved steady state q₀ + h δq₀ and motion x̂ + h δx̂, to 1e-6 of their largest entry.
    #[test]
    fn column_tangents_match_differences_of_the_forward_pieces() {
        let mesh = AirfoilShape::naca64a010().o_mesh(24, 8, 20.0, 0.004 / 20.0, 1.0);
        let e = Euler::new(mesh, free_stream(0.5, 0.03));
        let (q0, _) = e
            .solve_steady(vec![e.q_inf; e.mesh.n_cells], &SteadyParams::default())
            .unwrap();
        let lfd = LfdOperator::new(e.clone(), q0.clone());
        let nn = e.mesh.nodes.len();
        // a smooth in-plane motion of the mesh and an arbitrary steady perturbation
        let d_nodes: Vec<[f64; 3]> = e
            .mesh
            .nodes
            .iter()
            .map(|p| [0.1 * p[0] * p[0].cos(), 0.05 * p[0] * p[1] + 0.02, 0.0])
            .collect();
        let r = gustkit_testkit::rand_vec(lfd.n() + 6 * nn + 2 * lfd.n(), 9);
        let dq0: Vec<f64> = (0..lfd.n()).map(|i| 1e-2 * r[i]).collect();
        let q_hat: Field = (0..lfd.n())
            .map(|i| C64::new(r[lfd.n() + 6 * nn + 2 * i], r[lfd.n() + 6 * nn + 2 * i + 1]))
            .collect();
        let motion = |seed: usize| -> Vec<[C64; 3]> {
            (0..nn)
                .map(|n| {
                    let p = e.mesh.nodes[n];
                    let on = if p[0].hypot(p[1]) < 8.0 { 1.0 } else { 0.0 };
                    let i = lfd.n() + seed * 3 * nn + 3 * n;
                    [
                        C64::new(r[i], r[i + 1]) * on,
                        C64::new(r[i + 2], -r[i]) * on,
                        C64::new(0.0, 0.0),
                    ]
                })
                .collect()
        };
        let (x_hat, dx_hat) = (motion(0), motion(1));
        let s = C64::new(0.0, 0.7);
        let swept = lfd.swept_volumes(&x_hat, [&dx_hat], [&d_nodes]);
        let [(t, df)] = lfd.column_tangents(
            s,
            &q_hat,
            &Column::Motion {
                x_hat: &x_hat,
                dx_hat: [&dx_hat],
                swept: &swept,
            },
            [&d_nodes],
            [&dq0],
        );
        // the forward pieces at mesh X + h δX, state q₀ + h δq₀, motion x̂ + h δx̂
        // the LFD problem on the mesh X + h δX about the state q₀ + h δq₀
        let moved = |h: f64| {
            let mut m = e.mesh.clone();
            for (p, d) in m.nodes.iter_mut().zip(&d_nodes) {
                for k in 0..3 {
                    p[k] += h * d[k];
                }
            }
            let mut eh = Euler::new(m, e.q_inf);
            eh.order = e.order;
            let qh: Vec<State<f64>> = q0
                .iter()
                .enumerate()
                .map(|(c, s)| std::array::from_fn(|k| s[k] + h * dq0[c * NVAR + k]))
                .collect();
            LfdOperator::new(eh, qh)
        };
        let at = |h: f64| {
            let op = moved(h);
            let xh: Vec<[C64; 3]> = x_hat
                .iter()
                .zip(&dx_hat)
                .map(|(a, b)| std::array::from_fn(|k| a[k] + b[k] * h))
                .collect();
            let aq = op.apply(s, &q_hat);
            let b = op.motion_rhs(s, &xh);
            let f = op.wall_face_forces(&q_hat, Some(&xh));
            (aq.iter().zip(&b).map(|(a, b)| a + b).collect::<Vec<_>>(), f)
        };
        let h = 1e-6;
        let ((tp, fp), (tm, fm)) = (at(h), at(-h));
        assert_central(&t, &tp, &tm, h, "motion");
        let fscale = df.iter().flatten().fold(0.0f64, |a, v| a.max(v.norm()));
        for (w, d) in df.iter().enumerate() {
            for k in 0..3 {
                let fd = (fp[w].1[k] - fm[w].1[k]) / (2.0 * h);
                assert!(
                    (fd - d[k]).norm() < 1e-6 * fscale,
                    "force {w}.{k}: {} vs {fd}",
                    d[k]
                );
            }
        }
        // the gust column: ĝ and δĝ from the generic fluxes on the moving mesh
        let nodes_d: Vec<[Dual<1>; 3]> = e
            .mesh
            .nodes
            .iter()
            .zip(&d_nodes)
            .map(|(p, d)| std::array::from_fn(|k| Dual::new(p[k], [d[k]])))
            .collect();
        let gd = e.harmonic_gust_fluxes_at(&nodes_d, 0.7, 0.5, 0.1);
        let g: Vec<C64> = gd.iter().map(|v| C64::new(v[0].v, v[1].v)).collect();
        let dg: Vec<C64> = gd.iter().map(|v| C64::new(v[0].d[0], v[1].d[0])).collect();
        let plain = e.harmonic_gust_fluxes(0.7, 0.5, 0.1);
        for (a, b) in g.iter().zip(&plain) {
            assert!((a - b).norm() < 1e-14, "{a} vs {b}");
        }
        let [(t, _)] = lfd.column_tangents(
            s,
            &q_hat,
            &Column::Gust { g: &g, dg: [&dg] },
            [&d_nodes],
            [&dq0],
        );
        let at = |h: f64| {
            let op = moved(h);
            let gh = op.euler.harmonic_gust_fluxes(0.7, 0.5, 0.1);
            let aq = op.apply(s, &q_hat);
            let b = op.volume_flux_rhs(&gh);
            aq.iter().zip(&b).map(|(a, b)| a + b).collect::<Vec<_>>()
        };
        let (tp, tm) = (at(h), at(-h));
        assert_central(&t, &tp, &tm, h, "gust");
        // three directions in one evaluation give each direction's own tangents (the δ parts
        // never mix): to round-off
        let scaled = |c: f64| -> (Vec<[f64; 3]>, Vec<f64>, Vec<[C64; 3]>) {
            (
                d_nodes.iter().map(|p| [c * p[0], p[1] - c, 0.0]).collect(),
                dq0.iter().map(|v| v * (1.0 + c)).collect(),
                dx_hat.iter().map(|p| p.map(|z| z * c)).collect(),
            )
        };
        let dirs = [scaled(1.0), scaled(-0.5), scaled(2.0)];
        let dx3: [&[[C64; 3]]; 3] = std::array::from_fn(|m| dirs[m].2.as_slice());
        let swept3 = lfd.swept_volumes(&x_hat, dx3, std::array::from_fn(|m| dirs[m].0.as_slice()));
        let column: Column<3> = Column::Motion {
            x_hat: &x_hat,
            dx_hat: dx3,
            swept: &swept3,
        };
        let many = lfd.column_tangents(
            s,
            &q_hat,
            &column,
            std::array::from_fn(|m| dirs[m].0.as_slice()),
            std::array::from_fn(|m| dirs[m].1.as_slice()),
        );
        for (m, (t3, f3)) in many.iter().enumerate() {
            let swept1 = lfd.swept_volumes(&x_hat, [&dirs[m].2], [&dirs[m].0]);
            let [(t1, f1)] = lfd.column_tangents(
                s,
                &q_hat,
                &Column::Motion {
                    x_hat: &x_hat,
                    dx_hat: [&dirs[m].2],
                    swept: &swept1,
                },
                [&dirs[m].0],
                [&dirs[m].1],
            );
            let scale = t1.iter().fold(0.0f64, |a, v| a.max(v.norm()));
            for (a, b) in t3.iter().zip(&t1) {
                assert!((a - b).norm() <= 1e-13 * scale, "direction {m}: {a} vs {b}");
            }
            for (a, b) in f3.iter().flatten().zip(f1.iter().flatten()) {
                assert!(
                    (a - b).norm() <= 1e-13 * scale.max(1.0),
                    "direction {m}: {a} vs {b}"
                );
            }
        }
    }
}
