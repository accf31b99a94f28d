//! The stability check that must pass before a gust RMS means anything.

use super::verdict::Verdict;
use super::PkProblem;
use crate::structure::Modes;
use anyhow::Result;
use gustkit_core::GafTable;

/// The gust response of an unstable aeroelastic system has no meaning: a p-k sweep from a fifth
/// of the flight speed up to it (12 speeds, so the branches are followed through any frequency
/// coalescence) must find every mode damped, and no consistent root at the flight speed may be
/// undamped (whichever branch the tracking followed). The words are the [`Verdict`]'s.
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
    let conditions = format!(
        "M = {}, rho = {} kg/m3; the gust RMS has no meaning",
        flight.mach, flight.density
    );
    let verdict = Verdict::of(&r);
    if !verdict.stable_up_to(flight.velocity) {
        anyhow::bail!(
            "unstable: the aeroelastic system {} ({conditions})",
            verdict.words(flight.velocity)
        );
    }
    let last = speeds.len() - 1;
    let ks: Vec<f64> = r.curves.iter().map(|c| c.k[last]).collect();
    let gmax = pk
        .max_damping(flight.velocity, &ks)
        .map_err(|e| anyhow::anyhow!("stability check: {e}"))?;
    if gmax > crate::flutter::G_ROUNDOFF {
        anyhow::bail!(
            "unstable: the aeroelastic system has an undamped p-k root at the flight speed V = {:.1} m/s (g = {gmax:+.4}, on a branch the mode tracking did not follow; {conditions})",
            flight.velocity
        );
    }
    Ok(())
}
