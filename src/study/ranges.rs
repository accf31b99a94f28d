//! The physical ranges of a wing study's values, checked at load in the file's own units (a span
//! given in inches is reported in inches), so that garbage — a 1e-6 in wing with MHz modes, a
//! grain angle of 1e308, Mach 0.999 with the DLM — is refused with its JSON path instead of
//! producing results or a misleading error further down.
//!
//! The ranges are wide on purpose: they admit every wing from a wind-tunnel model to an airliner
//! and refuse only what no model of this kind can mean.

use super::{Study, StudyError};

/// Shortest and longest length of a wing dimension, m (1 mm to 1 km).
pub const LENGTH_RANGE_M: (f64, f64) = (1e-3, 1e3);

/// Range of the aspect ratio semispan / mean chord of the trapezoid.
pub const SPAN_TO_CHORD: (f64, f64) = (0.1, 50.0);

/// Largest taper ratio tip chord / root chord (an inverse taper of up to 5 is admitted).
pub const MAX_TAPER: f64 = 5.0;

/// Largest |quarter-chord sweep|, degrees (exclusive).
pub const MAX_SWEEP_DEG: f64 = 80.0;

/// Largest plate thickness as a fraction of the longer of root and tip chord.
pub const MAX_THICKNESS_TO_CHORD: f64 = 0.5;

pub use crate::aero::dlm::DLM_MAX_MACH;

/// Largest flight or p-k speed, m/s (far beyond any subsonic flight; keeps tables readable).
pub const MAX_SPEED_M_S: f64 = 1e4;

/// Ranges of the material constants (SI): moduli in Pa, density in kg/m³.
pub const MODULUS_RANGE_PA: (f64, f64) = (1e3, 1e13);
pub const DENSITY_RANGE_KG_M3: (f64, f64) = (1.0, 1e5);

/// Largest air density, kg/m³ (sea level is 1.225).
pub const MAX_AIR_DENSITY: f64 = 10.0;

pub use crate::units::show;

/// Why `v` (in `unit`) is outside [lo, hi] with lo > 0: not positive, or out of range.
fn out_of_range(v: f64, lo: f64, hi: f64, unit: &str) -> Option<String> {
    let sp = if unit.is_empty() { "" } else { " " };
    if !(v > 0.0) {
        Some(format!("must be positive (got {}{sp}{unit})", show(v)))
    } else if !(v >= lo && v <= hi) {
        Some(format!(
            "must lie between {}{sp}{unit} and {}{sp}{unit} (got {}{sp}{unit})",
            show(lo),
            show(hi),
            show(v)
        ))
    } else {
        None
    }
}

impl Study {
    /// Checks every value against its physical range, in the file's units.
    pub(crate) fn check_ranges(&self) -> Result<(), StudyError> {
        let s = &self.spec;
        let unit = s.length_unit.name();
        let to_m = s.length_unit.to_m();
        let (lmin, lmax) = (LENGTH_RANGE_M.0 / to_m, LENGTH_RANGE_M.1 / to_m);
        let length = |path: &str, v: f64| -> Result<(), StudyError> {
            match out_of_range(v, lmin, lmax, unit) {
                Some(why) => Err(self.err(path, why)),
                None => Ok(()),
            }
        };
        let w = &s.wing;
        length("wing.span", w.span)?;
        length("wing.root_chord", w.root_chord)?;
        length("wing.tip_chord", w.tip_chord)?;
        let sweep = |path: &str, deg: f64| -> Result<(), StudyError> {
            if !(deg.abs() < MAX_SWEEP_DEG) {
                return Err(self.err(
                    path,
                    format!(
                        "must lie strictly between -{MAX_SWEEP_DEG} and {MAX_SWEEP_DEG} degrees (got {} deg)",
                        show(deg)
                    ),
                ));
            }
            Ok(())
        };
        sweep("wing.sweep_c4_deg", w.sweep_c4_deg)?;
        self.check_proportions("wing", w.span, w.root_chord, w.tip_chord)?;

        let m = &s.material;
        for (path, v) in [
            ("material.e1_pa", m.e1_pa),
            ("material.e2_pa", m.e2_pa),
            ("material.g12_pa", m.g12_pa),
        ] {
            if let Some(why) = out_of_range(v, MODULUS_RANGE_PA.0, MODULUS_RANGE_PA.1, "Pa") {
                return Err(self.err(path, why));
            }
        }
        if let Some(why) = out_of_range(
            m.density_kg_m3,
            DENSITY_RANGE_KG_M3.0,
            DENSITY_RANGE_KG_M3.1,
            "kg/m³",
        ) {
            return Err(self.err("material.density_kg_m3", why));
        }
        if !(m.grain_angle_deg.abs() <= 360.0) {
            return Err(self.err(
                "material.grain_angle_deg",
                format!(
                    "must lie between -360 and 360 degrees (got {} deg)",
                    show(m.grain_angle_deg)
                ),
            ));
        }

        let t_max = MAX_THICKNESS_TO_CHORD * w.root_chord.max(w.tip_chord);
        if let Some(t) = &s.structure.thickness {
            for (i, v) in t.iter().enumerate() {
                if !(v.is_finite() && *v > 0.0 && *v <= t_max) {
                    return Err(self.err(
                        &format!("structure.thickness[{i}]"),
                        format!(
                            "must be positive and at most {MAX_THICKNESS_TO_CHORD} × the longer chord, {} {unit} (got {} {unit})",
                            show(t_max),
                            show(*v)
                        ),
                    ));
                }
            }
        }
        let scale = s.structure.thickness_scale;
        if let Some(why) = out_of_range(scale, 1e-3, 100.0, "") {
            return Err(self.err("structure.thickness_scale", why));
        }

        if let Some(f) = &s.flight {
            if !(f.velocity_m_s > 0.0 && f.velocity_m_s <= MAX_SPEED_M_S) {
                return Err(self.err(
                    "flight.velocity_m_s",
                    format!(
                        "must lie in (0, {}] m/s (got {} m/s)",
                        show(MAX_SPEED_M_S),
                        show(f.velocity_m_s)
                    ),
                ));
            }
            if !(f.density_kg_m3 > 0.0 && f.density_kg_m3 <= MAX_AIR_DENSITY) {
                return Err(self.err(
                    "flight.density_kg_m3",
                    format!(
                        "must lie in (0, {MAX_AIR_DENSITY}] kg/m³ (got {} kg/m³)",
                        show(f.density_kg_m3)
                    ),
                ));
            }
            // the fidelity's own range (M ≥ 1 is refused for every fidelity with the flight
            // condition)
            if let Some(aero) = s.aero.as_ref().filter(|_| f.mach < 1.0) {
                aero.fidelity
                    .builder()
                    .check_mach(f.mach)
                    .map_err(|reason| self.err("flight.mach", reason))?;
            }
        }
        if let Some(aero) = &s.aero {
            let k = &aero.reduced_frequencies;
            let interpolated = s.gust.is_some() || s.flutter.is_some();
            if interpolated && k.len() < 4 {
                return Err(self.err(
                    "aero.reduced_frequencies",
                    format!(
                        "the gust and flutter analyses interpolate the GAFs by a cubic spline in k: at least 4 reduced frequencies are needed (got {})",
                        k.len()
                    ),
                ));
            }
            if let Some(i) = (1..k.len()).find(|&i| !(k[i] > k[i - 1])) {
                return Err(self.err(
                    &format!("aero.reduced_frequencies[{i}]"),
                    format!(
                        "the reduced frequencies must increase (got {} after {})",
                        show(k[i]),
                        show(k[i - 1])
                    ),
                ));
            }
        }
        if let Some(f) = &s.flutter {
            for (path, v) in [
                ("flutter.velocity_min_m_s", f.velocity_min_m_s),
                ("flutter.velocity_max_m_s", f.velocity_max_m_s),
            ] {
                if !(v > 0.0 && v <= MAX_SPEED_M_S) {
                    return Err(self.err(
                        path,
                        format!(
                            "must lie in (0, {}] m/s (got {} m/s)",
                            show(MAX_SPEED_M_S),
                            show(v)
                        ),
                    ));
                }
            }
        }
        if let Some(o) = &s.optimization {
            for (name, b) in [
                ("span", o.span),
                ("root_chord", o.root_chord),
                ("tip_chord", o.tip_chord),
            ] {
                length(&format!("optimization.{name}[0]"), b[0])?;
                length(&format!("optimization.{name}[1]"), b[1])?;
            }
            sweep("optimization.sweep_c4_deg[0]", o.sweep_c4_deg[0])?;
            sweep("optimization.sweep_c4_deg[1]", o.sweep_c4_deg[1])?;
            let t_max_bound = MAX_THICKNESS_TO_CHORD * o.root_chord[1].max(o.tip_chord[1]);
            if !(o.thickness_max.is_finite() && o.thickness_max <= t_max_bound) {
                return Err(self.err(
                    "optimization.thickness_max",
                    format!(
                        "must be at most {MAX_THICKNESS_TO_CHORD} × the longest chord the bounds allow, {} {unit} (got {} {unit})",
                        show(t_max_bound),
                        show(o.thickness_max)
                    ),
                ));
            }
            if o.max_iterations == 0 {
                return Err(self.err("optimization.max_iterations", "must be at least 1"));
            }
            if o.resolution_corrections > super::schema::MAX_RESOLUTION_CORRECTIONS {
                return Err(self.err(
                    "optimization.resolution_corrections",
                    format!(
                        "must be between 0 and {} (got {}): each correction is a whole optimization from the last optimum",
                        super::schema::MAX_RESOLUTION_CORRECTIONS,
                        o.resolution_corrections
                    ),
                ));
            }
            if !(o.tolerance > 0.0 && o.tolerance < 1.0) {
                return Err(self.err(
                    "optimization.tolerance",
                    format!("must lie in (0, 1) (got {})", show(o.tolerance)),
                ));
            }
            if let Some(m) = &o.model_management {
                if !(m.initial_radius > 0.0 && m.initial_radius <= 1.0) {
                    return Err(self.err(
                        "optimization.model_management.initial_radius",
                        format!(
                            "must lie in (0, 1], a fraction of each bound range (got {})",
                            show(m.initial_radius)
                        ),
                    ));
                }
                if m.max_iterations == 0 {
                    return Err(self.err(
                        "optimization.model_management.max_iterations",
                        "must be at least 1",
                    ));
                }
                if o.warm_start.as_ref().is_some_and(|w| w.hessian) {
                    return Err(self.err(
                        "optimization.warm_start.hessian",
                        "is not used with optimization.model_management (each corrected problem's SQP starts afresh in its trust region): set it to false",
                    ));
                }
            }
            if let Err(reason) = crate::optim::check_nonmonotone_memory(o.nonmonotone_memory) {
                return Err(self.err("optimization.nonmonotone_memory", reason));
            }
        }
        Ok(())
    }

    /// The proportions of a trapezoid (`what` is the JSON object): aspect and taper ratios.
    fn check_proportions(
        &self,
        what: &str,
        span: f64,
        root: f64,
        tip: f64,
    ) -> Result<(), StudyError> {
        let ar = span / (0.5 * (root + tip));
        if !(ar >= SPAN_TO_CHORD.0 && ar <= SPAN_TO_CHORD.1) {
            return Err(self.err(
                &format!("{what}.span"),
                format!(
                    "the semispan is {} mean chords; a wing has {} to {}",
                    show(ar),
                    SPAN_TO_CHORD.0,
                    SPAN_TO_CHORD.1
                ),
            ));
        }
        if !(tip / root <= MAX_TAPER) {
            return Err(self.err(
                &format!("{what}.tip_chord"),
                format!(
                    "the tip chord is {} root chords; at most {MAX_TAPER} is admitted",
                    show(tip / root)
                ),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::show;

    #[test]
    fn numbers_stay_short() {
        assert_eq!(show(1e308), "1.0000e308");
        assert_eq!(show(-30.0), "-30");
        assert_eq!(show(0.0254), "0.0254");
        assert_eq!(show(1e-6), "1.0000e-6");
    }
}
