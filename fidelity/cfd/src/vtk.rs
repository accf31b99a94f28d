//! Legacy-VTK output of a flow field on the mesh (for ParaView): hexahedral cells with density,
//! velocity, pressure, Mach number and pressure coefficient as cell data.

use crate::gas::{primitive, sound_speed, GAMMA};
use crate::mesh::Mesh;
use crate::residual::State;
use std::fmt::Write;

/// The VTK text of `q` on `mesh` (non-dimensional: ρ∞ = 1, a∞ = 1; C_p with the free-stream Mach
/// number `mach`). Cells without a hexahedral node list are left out.
pub fn flow_vtk(mesh: &Mesh, q: &[State<f64>], mach: f64, title: &str) -> String {
    let mut s = String::new();
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
    let q_dyn = 0.5 * mach * mach;
    let scalar = |s: &mut String, name: &str, f: &dyn Fn(usize) -> f64| {
        let _ = writeln!(s, "SCALARS {name} double 1\nLOOKUP_TABLE default");
        for &c in &hexes {
            let _ = writeln!(s, "{:.10e}", f(c));
        }
    };
    scalar(&mut s, "density", &|c| q[c][0]);
    scalar(&mut s, "pressure", &|c| primitive(&q[c]).p);
    scalar(&mut s, "cp", &|c| {
        (primitive(&q[c]).p - 1.0 / GAMMA) / q_dyn
    });
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
}
