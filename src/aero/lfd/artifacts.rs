//! What the LFD model reports for a person to read (its
//! [`Aerodynamics::artifacts`](gustkit_core::Aerodynamics::artifacts), written by the run folder,
//! never by the builder): the steady flow field (VTK) and C_p at the span sections chosen here.

use super::*;

pub use gustkit_cfd::lfd_model::{CP_SECTIONS_STEM, STEADY_FLOW_FILE};

/// Span fractions of the C_p sections: root, mid-span and tip (inboard of the tip closure).
pub const CP_SECTIONS: [f64; 3] = [0.0, 0.5, 0.9];

/// The wall cells of the chordwise sections of a built-in mesh at [`CP_SECTIONS`] (each the
/// strip whose middle lies nearest): (η of the strip's middle, its wall cells around the contour).
pub fn wall_sections(mesh: &WingMesh) -> Vec<(f64, Vec<SectionCell>)> {
    CP_SECTIONS
        .iter()
        .map(|&eta| mesh.wall_section(eta))
        .collect()
}

/// C_p of the wall cells of the sections at [`CP_SECTIONS`]: (η of the strip's middle,
/// [(wall cell, C_p)] around the contour).
pub fn cp_sections(
    mesh: &WingMesh,
    q: &[gustkit_cfd::residual::State<f64>],
    mach: f64,
) -> Vec<(f64, Vec<(SectionCell, f64)>)> {
    gustkit_cfd::lfd_model::section_pressures(&wall_sections(mesh), q, mach)
}
