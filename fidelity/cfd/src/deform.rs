//! Volume-mesh deformation for mode shapes: displacements given at the wall nodes are spread
//! through the mesh by inverse-distance weighting (weights 1/d³ to every wall node), blended to zero
//! towards the far field so the outer boundary stays still. The map is linear, so it serves real
//! time-domain motion and complex LFD mode shapes alike, and the LFD and the time domain move the
//! mesh the same way.

use crate::krylov::Field;
use crate::mesh::{Boundary, Mesh, Side};

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
    pub fn apply_at<S: gustkit_core::scalar::Scalar>(
        &self,
        nodes: &[[S; 3]],
        radius: S,
        wall: &[[f64; 3]],
    ) -> Vec<[S; 3]> {
        let dist = |a: &[S; 3], b: &[S; 3]| {
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        };
        nodes
            .iter()
            .enumerate()
            .map(|(n, p)| {
                if let Some(i) = self.on_wall[n] {
                    return wall[i].map(S::cst);
                }
                if self.blend[n] == 0.0 {
                    return [S::zero(); 3];
                }
                let mut nearest = S::cst(f64::MAX);
                let mut sum = [S::zero(); 3];
                let mut total = S::zero();
                for (i, &w) in self.wall_nodes.iter().enumerate() {
                    let d = dist(p, &nodes[w]);
                    if d.re() < nearest.re() {
                        nearest = d;
                    }
                    let weight = d.powi(-POWER);
                    total += weight;
                    for k in 0..3 {
                        sum[k] += weight * wall[i][k];
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
                sum.map(|v| v * scale)
            })
            .collect()
    }

    /// The displacement of every mesh node for displacements `wall` of the wall nodes.
    pub fn apply<T: Field>(&self, wall: &[[T; 3]]) -> Vec<[T; 3]> {
        self.nodes
            .iter()
            .enumerate()
            .map(|(n, p)| {
                if let Some(i) = self.on_wall[n] {
                    return wall[i];
                }
                if self.blend[n] == 0.0 {
                    return [T::zero(); 3];
                }
                let mut sum = [T::zero(); 3];
                let mut total = 0.0;
                for (i, &w) in self.wall_nodes.iter().enumerate() {
                    let weight = dist(p, &self.nodes[w]).powi(-POWER);
                    total += weight;
                    for k in 0..3 {
                        sum[k] = sum[k] + wall[i][k] * weight;
                    }
                }
                let scale = self.blend[n] / total;
                sum.map(|v| v * scale)
            })
            .collect()
    }

    /// The transpose of [`Deformation::apply`]: for a seed on every mesh node's displacement, the
    /// seed on the wall nodes' displacements (the map is real, so complex seeds go through as
    /// they are).
    pub fn apply_transpose<T: Field>(&self, seed: &[[T; 3]]) -> Vec<[T; 3]> {
        let mut wall = vec![[T::zero(); 3]; self.wall_nodes.len()];
        for (n, p) in self.nodes.iter().enumerate() {
            if let Some(i) = self.on_wall[n] {
                for k in 0..3 {
                    wall[i][k] = wall[i][k] + seed[n][k];
                }
                continue;
            }
            if self.blend[n] == 0.0 {
                continue;
            }
            let total: f64 = self
                .wall_nodes
                .iter()
                .map(|&w| dist(p, &self.nodes[w]).powi(-POWER))
                .sum();
            let scale = self.blend[n] / total;
            for (i, &w) in self.wall_nodes.iter().enumerate() {
                let weight = dist(p, &self.nodes[w]).powi(-POWER) * scale;
                for k in 0..3 {
                    wall[i][k] = wall[i][k] + seed[n][k] * weight;
                }
            }
        }
        wall
    }
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::airfoil::AirfoilShape;

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
}
