//! What the LFD leaves for a person to read: steady C_p at span sections (CSV) and the flow field
//! (VTK) beside the run's report.

use super::*;

/// Span fractions of the C_p sections: root, mid-span and tip (inboard of the tip closure).
pub const CP_SECTIONS: [f64; 3] = [0.0, 0.5, 0.9];

/// The stem of the C_p section CSV written beside the steady state (and of its figure).
pub const CP_SECTIONS_STEM: &str = "steady_cp_sections";

/// C_p of the wall cells of the chordwise sections at [`CP_SECTIONS`] (each the strip whose
/// middle lies nearest): (η of the strip's middle, [(wall cell, C_p)] around the contour).
pub fn cp_sections(
    mesh: &WingMesh,
    q: &[gustkit_cfd::residual::State<f64>],
    mach: f64,
) -> Vec<(f64, Vec<(SectionCell, f64)>)> {
    CP_SECTIONS
        .iter()
        .map(|&eta| {
            let (eta_mid, cells) = mesh.wall_section(eta);
            let cp = cells
                .iter()
                .map(|&c| (c, gustkit_cfd::gas::pressure_coefficient(&q[c.cell], mach)))
                .collect();
            (eta_mid, cp)
        })
        .collect()
}

/// Writes [`cp_sections`] into `dir` as `steady_cp_sections.csv` (eta, x_c, side, cp), which the
/// run's report draws (upper and lower surface against x/c, one panel a section).
pub(super) fn write_cp_sections(
    mesh: &WingMesh,
    q: &[gustkit_cfd::residual::State<f64>],
    mach: f64,
    dir: &Path,
) -> std::io::Result<()> {
    let mut csv = String::from("eta,x_c,side,cp\n");
    for (eta, cells) in cp_sections(mesh, q, mach) {
        for (c, cp) in cells {
            let side = if c.upper { "upper" } else { "lower" };
            csv.push_str(&format!("{eta:.6},{:.6},{side},{cp:.8e}\n", c.x_c));
        }
    }
    crate::atomic::write(&dir.join(format!("{CP_SECTIONS_STEM}.csv")), csv.as_bytes())
}

/// The VTK file of the latest steady state beside it (its prefix carries it to the next run).
pub const STEADY_VTK: &str = "steady_lfd_flow.vtk";
