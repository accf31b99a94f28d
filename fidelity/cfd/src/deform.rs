//! Volume-mesh deformation for mode shapes: displacements given at the wall nodes are spread
//! through the mesh by inverse-distance weighting (weights 1/d³ to every wall node), blended to zero
//! towards the far field so the outer boundary stays still. The map is linear, so it serves real
//! time-domain motion and complex LFD mode shapes alike, and the LFD and the time domain move the
//! mesh the same way.

use crate::krylov::Field;
use crate::mesh::{Boundary, Mesh, Side};
use rayon::prelude::*;

/// The deformation map of a mesh.
#[derive(Clone, Debug)]
pub struct Deformation {
    /// Wall nodes, in a fixed order: displacements are given in this order.
    pub wall_nodes: Vec<usize>,
    /// Per mesh node: its index among the wall nodes, if it is one.
    on_wall: Vec<Option<usize>>,
    /// Per mesh node: the blending factor (1 at the wall, 0 beyond `radius`).
    blend: Vec<f64>,
    nodes: Vec<[f64; 3]>,
    /// The blending radius (mesh units).
    pub radius: f64,
}

/// Inverse-distance exponent.
const POWER: i32 = 3;

impl Deformation {
    /// The map for `mesh`, the displacement decaying smoothly to zero between `radius`/10 and
    /// `radius` from the nearest wall node.
    pub fn new(mesh: &Mesh, radius: f64) -> Self {
        let mut on_wall = vec![None; mesh.nodes.len()];
        let mut wall_nodes = Vec::new();
        for f in &mesh.faces {
            if f.right == Side::Boundary(Boundary::Wall) {
                for &n in &f.nodes {
                    if on_wall[n].is_none() {
                        on_wall[n] = Some(wall_nodes.len());
                        wall_nodes.push(n);
                    }
                }
            }
        }
        let blend = mesh
            .nodes
            .iter()
            .map(|p| {
                let d = wall_nodes
                    .iter()
                    .map(|&w| dist(p, &mesh.nodes[w]))
                    .fold(f64::MAX, f64::min);
                // smoothstep from 1 at radius/10 to 0 at radius
                let t = ((d - 0.1 * radius) / (0.9 * radius)).clamp(0.0, 1.0);
                1.0 - t * t * (3.0 - 2.0 * t)
            })
            .collect();
        Self {
            wall_nodes,
            on_wall,
            blend,
            nodes: mesh.nodes.clone(),
            radius,
        }
    }

    /// [`Deformation::apply`] with the mesh nodes at `nodes` and the blending radius `radius`, in
    /// any scalar: with dual numbers, the derivative of the spread displacements as the mesh (and
    /// the radius, which follows the root chord) moves with the planform. The topology (which
    /// nodes are wall nodes) stays.
    pub fn apply_at<S: gustkit_core::scalar::Scalar + Send + Sync>(
        &self,
        nodes: &[[S; 3]],
        radius: S,
        wall: &[[f64; 3]],
    ) -> Vec<[S; 3]> {
        self.apply_at_many(nodes, radius, &[wall])
            .pop()
            .expect("one field")
    }

    /// [`Deformation::apply_at`] of several wall displacement fields (one a mode): a node's
    /// distances, weights and blend are computed once for all of them (they are most of the
    /// work), the nodes in parallel. Each field's result is that of its own call bit for bit.
    pub fn apply_at_many<S: gustkit_core::scalar::Scalar + Send + Sync>(
        &self,
        nodes: &[[S; 3]],
        radius: S,
        walls: &[&[[f64; 3]]],
    ) -> Vec<Vec<[S; 3]>> {
        let dist = |a: &[S; 3], b: &[S; 3]| {
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        };
        let nf = walls.len();
        let mut flat = vec![[S::zero(); 3]; nodes.len() * nf];
        if nf == 0 {
            return Vec::new();
        }
        flat.par_chunks_mut(nf)
            .zip(nodes.par_iter())
            .enumerate()
            .for_each(|(n, (out, p))| {
                if let Some(i) = self.on_wall[n] {
                    for (o, wall) in out.iter_mut().zip(walls) {
                        *o = wall[i].map(S::cst);
                    }
                    return;
                }
                if self.blend[n] == 0.0 {
                    return;
                }
                let mut nearest = S::cst(f64::MAX);
                let mut total = S::zero();
                for (i, &w) in self.wall_nodes.iter().enumerate() {
                    let d = dist(p, &nodes[w]);
                    if d.re() < nearest.re() {
                        nearest = d;
                    }
                    let weight = d.powi(-POWER);
                    total += weight;
                    for (sum, wall) in out.iter_mut().zip(walls) {
                        for k in 0..3 {
                            sum[k] += weight * wall[i][k];
                        }
                    }
                }
                let t = (nearest - radius * 0.1) / (radius * 0.9);
                let blend = if t.re() <= 0.0 {
                    S::one()
                } else if t.re() >= 1.0 {
                    S::zero()
                } else {
                    S::one() - t * t * (S::cst(3.0) - t * 2.0)
                };
                let scale = blend / total;
                for sum in out.iter_mut() {
                    *sum = sum.map(|v| v * scale);
                }
            });
        unflatten(&flat, nf)
    }

    /// The displacement of every mesh node for displacements `wall` of the wall nodes.
    pub fn apply<T: Field>(&self, wall: &[[T; 3]]) -> Vec<[T; 3]> {
        self.apply_many(&[wall]).pop().expect("one field")
    }

    /// [`Deformation::apply`] of several wall displacement fields (one a mode): a node's weights
    /// are computed once for all of them, the nodes in parallel. Each field's result is that of
    /// its own call bit for bit.
    pub fn apply_many<T: Field>(&self, walls: &[&[[T; 3]]]) -> Vec<Vec<[T; 3]>> {
        let nf = walls.len();
        if nf == 0 {
            return Vec::new();
        }
        let mut flat = vec![[T::zero(); 3]; self.nodes.len() * nf];
        flat.par_chunks_mut(nf)
            .zip(self.nodes.par_iter())
            .enumerate()
            .for_each(|(n, (out, p))| {
                if let Some(i) = self.on_wall[n] {
                    for (o, wall) in out.iter_mut().zip(walls) {
                        *o = wall[i];
                    }
                    return;
                }
                if self.blend[n] == 0.0 {
                    return;
                }
                let mut total = 0.0;
                for (i, &w) in self.wall_nodes.iter().enumerate() {
                    let weight = dist(p, &self.nodes[w]).powi(-POWER);
                    total += weight;
                    for (sum, wall) in out.iter_mut().zip(walls) {
                        for k in 0..3 {
                            sum[k] = sum[k] + wall[i][k] * weight;
                        }
                    }
                }
                let scale = self.blend[n] / total;
                for sum in out.iter_mut() {
                    *sum = sum.map(|v| v * scale);
                }
            });
        unflatten(&flat, nf)
    }

    /// The transpose of [`Deformation::apply`]: for a seed on every mesh node's displacement, the
    /// seed on the wall nodes' displacements (the map is real, so complex seeds go through as
    /// they are).
    pub fn apply_transpose<T: Field>(&self, seed: &[[T; 3]]) -> Vec<[T; 3]> {
        self.transpose_group(&[seed]).pop().expect("one seed")
    }

    /// [`Deformation::apply_transpose`] of several seeds (one a mode and gradient): the seeds
    /// in one group a thread, each group's weights computed once a node for all its seeds.
    /// Each seed's result is that of its own call bit for bit.
    pub fn apply_transpose_many<T: Field>(&self, seeds: &[&[[T; 3]]]) -> Vec<Vec<[T; 3]>> {
        let per_group = seeds
            .len()
            .div_ceil(rayon::current_num_threads().max(1))
            .max(1);
        seeds
            .par_chunks(per_group)
            .map(|group| self.transpose_group(group))
            .collect::<Vec<_>>()
            .into_iter()
            .flatten()
            .collect()
    }

    /// The transpose for `seeds` in one pass over the nodes (one weight buffer for all).
    fn transpose_group<T: Field>(&self, seeds: &[&[[T; 3]]]) -> Vec<Vec<[T; 3]>> {
        let mut walls = vec![vec![[T::zero(); 3]; self.wall_nodes.len()]; seeds.len()];
        let mut weights = vec![0.0; self.wall_nodes.len()];
        for (n, p) in self.nodes.iter().enumerate() {
            if let Some(i) = self.on_wall[n] {
                for (wall, seed) in walls.iter_mut().zip(seeds) {
                    for k in 0..3 {
                        wall[i][k] = wall[i][k] + seed[n][k];
                    }
                }
                continue;
            }
            if self.blend[n] == 0.0 {
                continue;
            }
            for (wt, &w) in weights.iter_mut().zip(&self.wall_nodes) {
                *wt = dist(p, &self.nodes[w]).powi(-POWER);
            }
            let total: f64 = weights.iter().sum();
            let scale = self.blend[n] / total;
            for (i, wt) in weights.iter().enumerate() {
                let weight = wt * scale;
                for (wall, seed) in walls.iter_mut().zip(seeds) {
                    for k in 0..3 {
                        wall[i][k] = wall[i][k] + seed[n][k] * weight;
                    }
                }
            }
        }
        walls
    }
}

/// Node-major results (`nf` fields a node) as one vector a field.
fn unflatten<T: Copy>(flat: &[[T; 3]], nf: usize) -> Vec<Vec<[T; 3]>> {
    (0..nf)
        .map(|f| flat.iter().skip(f).step_by(nf).copied().collect())
        .collect()
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::airfoil::AirfoilShape;
    use gustkit_core::scalar::Dual;

    /// Wall nodes move exactly as given, the far field stays still, a uniform wall translation
    /// moves the near field rigidly, and the deformed mesh keeps positive volumes for a pitch of
    /// 5° about the quarter chord.
    #[test]
    fn idw_deformation() {
        let mesh = AirfoilShape::naca64a010().o_mesh(32, 12, 20.0, 0.004 / 20.0, 1.0);
        let d = Deformation::new(&mesh, 10.0);
        let shift: Vec<[f64; 3]> = vec![[0.0, 0.01, 0.0]; d.wall_nodes.len()];
        let moved = d.apply(&shift);
        for (n, (p, m)) in mesh.nodes.iter().zip(&moved).enumerate() {
            let r = p[0].hypot(p[1]);
            if r > 15.0 {
                assert_eq!(m, &[0.0; 3], "far node {n}");
            }
            if r < 0.9 {
                assert!(
                    (m[1] - 0.01).abs() < 1e-15 && m[0] == 0.0,
                    "near node {n}: {m:?}"
                );
            }
        }
        let a = 5f64.to_radians();
        let pitch: Vec<[f64; 3]> = d
            .wall_nodes
            .iter()
            .map(|&n| {
                let p = mesh.nodes[n];
                let (x, y) = (p[0] + 0.25, p[1]);
                [
                    x * a.cos() - y * a.sin() - x,
                    x * a.sin() + y * a.cos() - y,
                    0.0,
                ]
            })
            .collect();
        let disp = d.apply(&pitch);
        let mut m = mesh.clone();
        for (p, u) in m.nodes.iter_mut().zip(&disp) {
            for k in 0..3 {
                p[k] += u[k];
            }
        }
        assert!(m.check().is_ok());
        for &n in &d.wall_nodes {
            assert!(
                (m.nodes[n][0] - mesh.nodes[n][0] - pitch[d.on_wall[n].unwrap()][0]).abs() < 1e-15
            );
        }
    }

    /// The many-field forms (a node's weights once for every field, the nodes or the seed
    /// groups in parallel) give each field exactly what a call of its own gives: spread shapes,
    /// the transpose and the dual-number form along a mesh tangent, bit for bit.
    #[test]
    fn many_fields_give_each_field_its_own_bits() {
        let mesh = AirfoilShape::naca64a010().o_mesh(32, 12, 20.0, 0.004 / 20.0, 1.0);
        let d = Deformation::new(&mesh, 10.0);
        let nw = d.wall_nodes.len();
        let walls: Vec<Vec<[f64; 3]>> = (0..5)
            .map(|m| {
                (0..nw)
                    .map(|i| {
                        let x = (i * (m + 2)) as f64;
                        [0.01 * x.sin(), 0.02 * x.cos(), 0.0]
                    })
                    .collect()
            })
            .collect();
        let walls: Vec<&[[f64; 3]]> = walls.iter().map(Vec::as_slice).collect();
        let together = d.apply_many(&walls);
        for (w, t) in walls.iter().zip(&together) {
            assert_eq!(&d.apply(w), t);
        }
        let seeds: Vec<Vec<[f64; 3]>> = (0..7)
            .map(|m| {
                (0..mesh.nodes.len())
                    .map(|n| [((n + m) as f64).sin(), ((n * m) as f64).cos(), 0.0])
                    .collect()
            })
            .collect();
        let seeds: Vec<&[[f64; 3]]> = seeds.iter().map(Vec::as_slice).collect();
        let together = d.apply_transpose_many(&seeds);
        assert_eq!(together.len(), seeds.len());
        for (s, t) in seeds.iter().zip(&together) {
            assert_eq!(&d.apply_transpose(s), t);
        }
        let nodes: Vec<[Dual<1>; 3]> = mesh
            .nodes
            .iter()
            .map(|p| {
                [
                    Dual::new(p[0], [0.1 * p[0]]),
                    Dual::new(p[1], [0.2 * p[1]]),
                    Dual::new(p[2], [0.0]),
                ]
            })
            .collect();
        let radius = Dual::new(d.radius, [1.5]);
        let together = d.apply_at_many(&nodes, radius, &walls);
        for (w, t) in walls.iter().zip(&together) {
            let own = d.apply_at(&nodes, radius, w);
            for (a, b) in own.iter().flatten().zip(t.iter().flatten()) {
                assert_eq!(
                    (a.v.to_bits(), a.d[0].to_bits()),
                    (b.v.to_bits(), b.d[0].to_bits())
                );
            }
        }
    }
}
