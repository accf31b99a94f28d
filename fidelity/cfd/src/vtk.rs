//! Legacy-VTK output of a flow field on the mesh (for ParaView): hexahedral cells with density,
//! velocity, pressure, Mach number and pressure coefficient as cell data.

use crate::gas::NVAR;
use crate::gas::{pressure_coefficient, primitive, sound_speed, GAMMA};
use crate::mesh::Mesh;
use crate::residual::State;
use num_complex::Complex64 as C64;
use std::fmt::Write;

/// The legacy-VTK header, points and hexahedral cells of `mesh`, and the cells written.
fn grid(s: &mut String, mesh: &Mesh, title: &str) -> Vec<usize> {
    let hexes: Vec<usize> = (0..mesh.n_cells)
        .filter(|&c| mesh.cells.get(c).is_some_and(|n| n.len() == 8))
        .collect();
    let _ = writeln!(
        s,
        "# vtk DataFile Version 3.0\n{title}\nASCII\nDATASET UNSTRUCTURED_GRID"
    );
    let _ = writeln!(s, "POINTS {} double", mesh.nodes.len());
    for p in &mesh.nodes {
        let _ = writeln!(s, "{:.10e} {:.10e} {:.10e}", p[0], p[1], p[2]);
    }
    let _ = writeln!(s, "CELLS {} {}", hexes.len(), 9 * hexes.len());
    for &c in &hexes {
        let n = &mesh.cells[c];
        let _ = writeln!(
            s,
            "8 {} {} {} {} {} {} {} {}",
            n[0], n[1], n[2], n[3], n[4], n[5], n[6], n[7]
        );
    }
    let _ = writeln!(s, "CELL_TYPES {}", hexes.len());
    for _ in &hexes {
        let _ = writeln!(s, "12");
    }
    let _ = writeln!(s, "CELL_DATA {}", hexes.len());
    hexes
}

/// The amplitudes of pressure and velocity of a harmonic perturbation `q_hat` (conservative,
/// complex, [`NVAR`] per cell) of the steady state `q0`: p̂ = (γ − 1)(Ê − u·m̂ + ½|u|² ρ̂),
/// û = (m̂ − u ρ̂)/ρ, the linearizations of the primitive variables at q0.
pub fn primitive_amplitudes(q0: &State<f64>, q_hat: &[C64]) -> (C64, [C64; 3]) {
    let rho = q0[0];
    let u = [q0[1] / rho, q0[2] / rho, q0[3] / rho];
    let u2 = u.iter().map(|v| v * v).sum::<f64>();
    let u_dot_m = (0..3).map(|k| q_hat[1 + k] * u[k]).sum::<C64>();
    let p = (q_hat[4] - u_dot_m + q_hat[0] * (0.5 * u2)) * (GAMMA - 1.0);
    let vel = std::array::from_fn(|k| (q_hat[1 + k] - q_hat[0] * u[k]) / rho);
    (p, vel)
}

/// The VTK text of the amplitudes `q_hat` (complex, [`NVAR`] per cell) of a harmonic
/// perturbation of `q0` on `mesh`: real and imaginary parts of the pressure, the pressure
/// coefficient (free-stream Mach number `mach`) and the velocity, as cell data.
pub fn amplitude_vtk(
    mesh: &Mesh,
    q0: &[State<f64>],
    q_hat: &[C64],
    mach: f64,
    title: &str,
) -> String {
    let mut s = String::new();
    let hexes = grid(&mut s, mesh, title);
    let amp: Vec<(C64, [C64; 3])> = hexes
        .iter()
        .map(|&c| primitive_amplitudes(&q0[c], &q_hat[NVAR * c..NVAR * (c + 1)]))
        .collect();
    let q_dyn = 0.5 * mach * mach;
    for (part, name) in [(0, "re"), (1, "im")] {
        let pick = move |v: C64| if part == 0 { v.re } else { v.im };
        let _ = writeln!(s, "SCALARS pressure_{name} double 1\nLOOKUP_TABLE default");
        for a in &amp {
            let _ = writeln!(s, "{:.10e}", pick(a.0));
        }
        let _ = writeln!(s, "SCALARS cp_{name} double 1\nLOOKUP_TABLE default");
        for a in &amp {
            let _ = writeln!(s, "{:.10e}", pick(a.0) / q_dyn);
        }
        let _ = writeln!(s, "VECTORS velocity_{name} double");
        for a in &amp {
            let v = a.1;
            let _ = writeln!(
                s,
                "{:.10e} {:.10e} {:.10e}",
                pick(v[0]),
                pick(v[1]),
                pick(v[2])
            );
        }
    }
    s
}

/// The VTK text of `q` on `mesh` (non-dimensional: ρ∞ = 1, a∞ = 1; C_p with the free-stream Mach
/// number `mach`). Cells without a hexahedral node list are left out.
pub fn flow_vtk(mesh: &Mesh, q: &[State<f64>], mach: f64, title: &str) -> String {
    let mut s = String::new();
    let hexes = grid(&mut s, mesh, title);
    let scalar = |s: &mut String, name: &str, f: &dyn Fn(usize) -> f64| {
        let _ = writeln!(s, "SCALARS {name} double 1\nLOOKUP_TABLE default");
        for &c in &hexes {
            let _ = writeln!(s, "{:.10e}", f(c));
        }
    };
    scalar(&mut s, "density", &|c| q[c][0]);
    scalar(&mut s, "pressure", &|c| primitive(&q[c]).p);
    scalar(&mut s, "cp", &|c| pressure_coefficient(&q[c], mach));
    scalar(&mut s, "mach", &|c| {
        let w = primitive(&q[c]);
        w.vel.iter().map(|v| v * v).sum::<f64>().sqrt() / sound_speed(&w)
    });
    let _ = writeln!(s, "VECTORS velocity double");
    for &c in &hexes {
        let w = primitive(&q[c]);
        let _ = writeln!(s, "{:.10e} {:.10e} {:.10e}", w.vel[0], w.vel[1], w.vel[2]);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::o_mesh;
    use crate::residual::free_stream;

    /// The file lists every node and hexahedron, and every cell of a uniform flow has the
    /// free-stream Mach number and C_p = 0.
    #[test]
    fn uniform_flow_file() {
        let m = o_mesh(
            &|t| {
                let a = 2.0 * std::f64::consts::PI * t;
                [0.5 * a.cos(), 0.5 * a.sin()]
            },
            8,
            3,
            5.0,
            0.1,
            0.1,
        );
        let q = vec![free_stream(0.5, 0.0); m.n_cells];
        let text = flow_vtk(&m, &q, 0.5, "test");
        assert!(text.contains(&format!("POINTS {} double", m.nodes.len())));
        assert!(text.contains("CELLS 24 216"));
        let mach_block = text
            .split("SCALARS mach double 1\nLOOKUP_TABLE default\n")
            .nth(1)
            .unwrap();
        for line in mach_block.lines().take(24) {
            assert!((line.parse::<f64>().unwrap() - 0.5).abs() < 1e-12);
        }
        let cp_block = text
            .split("SCALARS cp double 1\nLOOKUP_TABLE default\n")
            .nth(1)
            .unwrap();
        for line in cp_block.lines().take(24) {
            assert!(line.parse::<f64>().unwrap().abs() < 1e-12);
        }
    }

    /// The pressure and velocity amplitudes are the derivatives of the primitive variables along
    /// the perturbation: against central differences of `primitive` at q0 ± h Re q̂ and
    /// q0 ± h Im q̂ (h = 1e-6, truncation O(h²) ≈ 1e-12), to 1e-9.
    #[test]
    fn primitive_amplitudes_are_the_linearization() {
        let q0: State<f64> = [1.1, 0.45, -0.05, 0.02, 2.3];
        let q_hat = [
            C64::new(0.3, -0.1),
            C64::new(-0.2, 0.4),
            C64::new(0.05, 0.07),
            C64::new(0.1, -0.3),
            C64::new(0.6, 0.2),
        ];
        let (p, vel) = primitive_amplitudes(&q0, &q_hat);
        let h = 1e-6;
        for (part, get) in [(0, (|v: C64| v.re) as fn(C64) -> f64), (1, |v: C64| v.im)] {
            let at = |sign: f64| {
                let q: State<f64> = std::array::from_fn(|k| q0[k] + sign * h * get(q_hat[k]));
                primitive(&q)
            };
            let (a, b) = (at(1.0), at(-1.0));
            let dp = (a.p - b.p) / (2.0 * h);
            assert!(
                (dp - get(p)).abs() < 1e-9,
                "part {part}: p {dp} against {}",
                get(p)
            );
            for k in 0..3 {
                let du = (a.vel[k] - b.vel[k]) / (2.0 * h);
                assert!((du - get(vel[k])).abs() < 1e-9, "part {part}: u[{k}]");
            }
        }
    }
}
