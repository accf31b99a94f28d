//! The flutter check of an optimization's initial and final designs: a p-k sweep from a fifth of
//! the flight speed to twice it.

use super::*;

/// Speeds of the flutter check: from a fifth of the flight speed up to this factor of it.
pub(crate) const FLUTTER_CHECK_FACTOR: f64 = 2.0;

/// The p-k sweep of a modal model with its GAF table at 91 speeds from a fifth of the flight
/// speed up to `v_max`.
pub(crate) fn flutter_sweep(
    modes: &crate::structure::Modes,
    table: &gustkit_core::GafTable,
    flight: &gustkit_core::FlightCondition,
    v_max: f64,
) -> Result<crate::flutter::FlutterResult> {
    let v = flight.velocity;
    let speeds: Vec<f64> = (0..=90)
        .map(|i| v * 0.2 + (v_max - 0.2 * v) * i as f64 / 90.0)
        .collect();
    crate::flutter::PkProblem::new(modes, table, flight.density)
        .sweep(&speeds)
        .map_err(|e| anyhow::anyhow!("flutter check: {e}"))
}

/// Where the p-k sweep of a modal model with its GAF table crosses zero damping, from a fifth of
/// the flight speed up to `v_max`.
pub(super) fn flutter_point(
    modes: &crate::structure::Modes,
    table: &gustkit_core::GafTable,
    flight: &gustkit_core::FlightCondition,
    v_max: f64,
) -> Result<FlutterPoint> {
    let r = flutter_sweep(modes, table, flight, v_max)?;
    Ok(FlutterPoint {
        speed_m_s: r.flutter_speed_m_s,
        frequency_hz: r.flutter_frequency_hz,
        mode: r.flutter_mode,
    })
}

/// The flutter speeds of the initial and final designs (the resolution check of the run adds the
/// final design's at the refined resolution).
pub(super) fn flutter_check(
    ev0: &crate::pipeline::Evaluation,
    ev: &crate::pipeline::Evaluation,
) -> Result<FlutterCheck> {
    let flight = &ev.aero.flight;
    let v_max = FLUTTER_CHECK_FACTOR * flight.velocity;
    let final_sweep = flutter_sweep(&ev.modes, &ev.table, flight, v_max)?;
    Ok(FlutterCheck {
        flight_speed_m_s: flight.velocity,
        searched_up_to_m_s: v_max,
        initial: flutter_point(&ev0.modes, &ev0.table, &ev0.aero.flight, v_max)?,
        final_: FlutterPoint {
            speed_m_s: final_sweep.flutter_speed_m_s,
            frequency_hz: final_sweep.flutter_frequency_hz,
            mode: final_sweep.flutter_mode,
        },
        modes: ev.modes.len(),
        more_modes: None,
        final_more_modes: None,
        final_sweep: Some(final_sweep),
    })
}
