//! The 2-D typical section (pitch–plunge airfoil on springs) through the same stochastic-gust
//! (paper Eqs. 16–18) and p-k flutter pipeline as the wing, with two aerodynamic models behind the
//! shared trait side by side: the LFD of the Euler solver and Theodorsen/Sears strip theory.
//! Studies are JSON files with a top-level `typical_section` key, run by `gustkit run`.
//!
//! Structure (per unit span, Theodorsen's notation): semichord b, elastic axis a semichords behind
//! the mid-chord, centre of gravity x_α semichords behind the elastic axis, radius of gyration
//! r_α b about it, mass m = μ π ρ b²; plunge h up and pitch α nose up, so a chord point x moves by
//! w = h − α (x − x_ea). Mass matrix [[m, −m x_α b], [−m x_α b, m r_α² b²]], stiffness
//! diag(m ω_h², m r_α² b² ω_α²); its two mass-normalized modes are the modes of the pipeline.

pub mod report;
pub mod run;
pub mod schema;

pub use report::{render, summary};
pub use run::{run, ModelResults, SectionResults};
pub use schema::{
    SectionCfd, SectionFlight, SectionFlutter, SectionGust, SectionSpec, SectionStructure,
    SectionStudyFile,
};

/// Natural frequencies (rad/s) and mass-normalized mode shapes (h, α) of the section.
pub fn modes(st: &SectionStructure, density: f64) -> (Vec<f64>, Vec<[f64; 2]>) {
    let b = 0.5 * st.chord_m;
    let m = st.mass_ratio * std::f64::consts::PI * density * b * b;
    let s = m * st.x_alpha * b;
    let i = m * st.r_alpha * st.r_alpha * b * b;
    let (wh, wa) = (
        2.0 * std::f64::consts::PI * st.plunge_frequency_hz,
        2.0 * std::f64::consts::PI * st.pitch_frequency_hz,
    );
    let mass = nalgebra::Matrix2::new(m, -s, -s, i);
    let stiff = nalgebra::Matrix2::new(m * wh * wh, 0.0, 0.0, i * wa * wa);
    // L⁻¹ K L⁻ᵀ with M = L Lᵀ: symmetric, its eigenvectors v give mass-normalized φ = L⁻ᵀ v
    let l = mass.cholesky().expect("checked positive definite").l();
    let l_inv = l.try_inverse().expect("a Cholesky factor is invertible");
    let a = l_inv * stiff * l_inv.transpose();
    let eig = a.symmetric_eigen();
    let mut order: Vec<usize> = vec![0, 1];
    order.sort_by(|&p, &q| eig.eigenvalues[p].total_cmp(&eig.eigenvalues[q]));
    let omega = order.iter().map(|&k| eig.eigenvalues[k].sqrt()).collect();
    let shapes = order
        .iter()
        .map(|&k| {
            let phi = l_inv.transpose() * eig.eigenvectors.column(k);
            // sign: positive plunge
            let sign = if phi[0] < 0.0 { -1.0 } else { 1.0 };
            [sign * phi[0], sign * phi[1]]
        })
        .collect();
    (omega, shapes)
}
