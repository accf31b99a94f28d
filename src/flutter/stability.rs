//! The stability check that must pass before a gust RMS means anything.

use super::PkProblem;
use crate::structure::Modes;
use anyhow::Result;
use gustkit_core::GafTable;

/// The gust response of an unstable aeroelastic system has no meaning: a p-k sweep from a fifth
/// of the flight speed up to it (12 speeds, so the branches are followed through any frequency
/// coalescence) must find every mode damped.
pub fn check_stability(
    modes: &Modes,
    table: &GafTable,
    flight: &gustkit_core::FlightCondition,
) -> Result<()> {
    let pk = PkProblem::new(modes, table, flight.density);
    let speeds: Vec<f64> = (0..12)
        .map(|i| flight.velocity * (0.2 + 0.8 * i as f64 / 11.0))
        .collect();
    let r = pk
        .sweep(&speeds)
        .map_err(|e| anyhow::anyhow!("stability check: {e}"))?;
    let last = speeds.len() - 1;
    let ks: Vec<f64> = r.curves.iter().map(|c| c.k[last]).collect();
    let gmax = pk
        .max_damping(flight.velocity, &ks)
        .map_err(|e| anyhow::anyhow!("stability check: {e}"))?;
    let unstable = r.flutter_speed_m_s.is_some() || gmax >= 0.0;
    if let Some(c) = r
        .curves
        .iter()
        .find(|c| unstable && (c.damping_g[last] >= 0.0 || r.flutter_mode == Some(c.mode)))
    {
        anyhow::bail!(
            "unstable: the aeroelastic system flutters at the flight condition (mode {} has damping g = {:.4} at {:.3} Hz, V = {} m/s, M = {}, rho = {} kg/m3); the gust RMS has no meaning",
            c.mode,
            c.damping_g[last],
            c.frequency_hz[last],
            flight.velocity,
            flight.mach,
            flight.density
        );
    }
    Ok(())
}
