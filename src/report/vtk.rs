//! Legacy-format VTK output of the plate and its modes, for ParaView.

use crate::structure::{Modes, PlateModel};
use std::fmt::Write;

/// The plate as an unstructured grid of quads (coordinates in m) with the element thickness as
/// cell data and each mode's displacement (u, v, w) as point vectors named `mode_1`, `mode_2`, ….
pub fn plate_modes(model: &PlateModel, modes: &Modes, title: &str) -> String {
    let xy = model.node_xy();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# vtk DataFile Version 3.0\n{title}\nASCII\nDATASET UNSTRUCTURED_GRID"
    );
    let _ = writeln!(s, "POINTS {} double", xy.len());
    for p in &xy {
        let _ = writeln!(s, "{:.9e} {:.9e} 0", p[0], p[1]);
    }
    let ne = model.mesh.elements.len();
    let _ = writeln!(s, "CELLS {ne} {}", ne * 5);
    for e in &model.mesh.elements {
        let _ = writeln!(s, "4 {} {} {} {}", e[0], e[1], e[2], e[3]);
    }
    let _ = writeln!(s, "CELL_TYPES {ne}");
    for _ in 0..ne {
        let _ = writeln!(s, "9");
    }
    let _ = writeln!(
        s,
        "CELL_DATA {ne}\nSCALARS thickness_m double 1\nLOOKUP_TABLE default"
    );
    for e in 0..ne {
        let _ = writeln!(s, "{:.9e}", model.element_thickness(e));
    }
    let _ = writeln!(s, "POINT_DATA {}", xy.len());
    for (i, m) in modes.modes.iter().enumerate() {
        let _ = writeln!(s, "VECTORS mode_{} double", i + 1);
        for c in m.shape.chunks(crate::structure::model::NODAL) {
            let _ = writeln!(s, "{:.9e} {:.9e} {:.9e}", c[3], c[4], c[0]);
        }
    }
    s
}
