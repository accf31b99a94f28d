//! The discrete gust section of a study, checked and resolved to SI: the tuned 1-cos search
//! (gradient range, grid, amplitude rule) or a tabulated profile, the time span and the
//! outputs' derivative orders.

use super::schema::{AmplitudeSpec, DesignSpeed, DiscreteProfileName};
use super::{Study, StudyError};
use crate::gust::discrete::profile::{cs25_amplitude, FOOT};
use crate::gust::discrete::GustProfile;

/// CS-25.341(a)(3)'s range of gust gradients, ft.
pub const CS25_GRADIENT_FT: [f64; 2] = [30.0, 350.0];

/// The amplitude of a 1-cos gust of gradient H.
#[derive(Clone, Debug, PartialEq)]
pub enum Amplitude {
    /// U_ds (m/s TAS) at every H.
    Fixed(f64),
    /// CS-25: U_ref by altitude (m), F_g, at V_D or not, at the flight density.
    Cs25 {
        altitude_m: f64,
        f_g: f64,
        dive_speed: bool,
        density: f64,
    },
}

impl Amplitude {
    /// U_ds (m/s, true airspeed) at gradient `h` (m).
    pub fn at(&self, h: f64) -> f64 {
        match *self {
            Amplitude::Fixed(u) => u,
            Amplitude::Cs25 {
                altitude_m,
                f_g,
                dive_speed,
                density,
            } => cs25_amplitude(h, altitude_m, f_g, dive_speed, density),
        }
    }

    /// The rule in words, for the report.
    pub fn words(&self) -> String {
        match *self {
            Amplitude::Fixed(u) => format!("U_ds = {u} m/s (true airspeed) at every gradient"),
            Amplitude::Cs25 {
                altitude_m,
                f_g,
                dive_speed,
                ..
            } => format!(
                "CS-25.341(a): U_ds = U_ref F_g (H/350 ft)^(1/6), U_ref {:.2} m/s EAS at {altitude_m} m{}, F_g = {f_g}, converted to true airspeed at the flight density",
                crate::gust::discrete::reference_gust_velocity(altitude_m)
                    * if dive_speed { 0.5 } else { 1.0 },
                if dive_speed { " (V_D: half the V_C value)" } else { "" }
            ),
        }
    }
}

/// What the discrete gust analysis does.
#[derive(Clone, Debug, PartialEq)]
pub enum DiscreteCase {
    /// The tuned search over H ∈ `range_m` on `points` values.
    Tuned {
        range_m: [f64; 2],
        points: usize,
        amplitude: Amplitude,
    },
    /// One tabulated profile.
    Tabulated(GustProfile),
}

impl DiscreteCase {
    /// The gusts of the case at flight speed `velocity`: the tuned search's grid of gradients
    /// (without its refinement), or the table.
    pub fn gusts(&self, velocity: f64) -> Vec<GustProfile> {
        match self {
            DiscreteCase::Tuned {
                range_m,
                points,
                amplitude,
            } => crate::gust::discrete::gradient_grid(*range_m, *points)
                .into_iter()
                .map(|h| GustProfile::OneMinusCosine {
                    gradient: h,
                    amplitude: amplitude.at(h),
                    velocity,
                })
                .collect(),
            DiscreteCase::Tabulated(p) => vec![p.clone()],
        }
    }
}

/// The discrete gust settings of a study (SI).
#[derive(Clone, Debug, PartialEq)]
pub struct DiscreteGustSettings {
    pub case: DiscreteCase,
    /// The time span, s; `None`: chosen.
    pub span: Option<f64>,
    /// Whether each displacement output gets its acceleration too.
    pub accelerations: bool,
}

impl Study {
    /// The study's discrete gust settings, none without the section; an error names the field.
    pub fn discrete_gust_settings(&self) -> Result<Option<DiscreteGustSettings>, StudyError> {
        let Some(d) = &self.spec.discrete_gust else {
            return Ok(None);
        };
        if self.spec.gust.is_none() {
            return Err(self.err(
                "discrete_gust",
                "needs the gust section: its outputs (and their aerodynamic model) are the ones the discrete gust analysis responds with",
            ));
        }
        let Some(flight) = &self.spec.flight else {
            return Err(self.err(
                "flight",
                "missing: the discrete gust analysis needs a flight condition",
            ));
        };
        if let Some(t) = d.time_span_s {
            if !(t > 0.0 && t <= 3600.0) {
                return Err(self.err(
                    "discrete_gust.time_span_s",
                    format!("must lie in (0, 3600] s (got {t} s); leave it out to have it chosen"),
                ));
            }
        }
        let case = match d.profile {
            DiscreteProfileName::OneMinusCosine => {
                if d.table.is_some() {
                    return Err(self.err(
                        "discrete_gust.table",
                        "given for a one_minus_cosine profile: set \"profile\": \"tabulated\" to use it, or remove it",
                    ));
                }
                let [lo, hi] = d.gradient_ft;
                if !(lo > 0.0 && hi >= lo && hi.is_finite()) {
                    return Err(self.err(
                        "discrete_gust.gradient_ft",
                        format!(
                            "must be [H_min, H_max] with 0 < H_min ≤ H_max (got [{lo}, {hi}] ft)"
                        ),
                    ));
                }
                let [cmin, cmax] = CS25_GRADIENT_FT;
                if !d.allow_any_gradient && (lo < cmin || hi > cmax) {
                    return Err(self.err(
                        "discrete_gust.gradient_ft",
                        format!("[{lo}, {hi}] ft lies outside CS-25's {cmin}–{cmax} ft; set \"allow_any_gradient\": true to analyse it anyway"),
                    ));
                }
                if d.gradient_points == 0
                    || d.gradient_points > 1000
                    || (d.gradient_points == 1 && hi > lo)
                {
                    return Err(self.err(
                        "discrete_gust.gradient_points",
                        format!("must lie in 2 … 1000 for a range of gradients, 1 for a single one (got {})", d.gradient_points),
                    ));
                }
                let amplitude = match &d.amplitude {
                    None => {
                        return Err(self.err(
                            "discrete_gust.amplitude",
                            "missing: give {\"u_ds_m_s\": U} or {\"cs25\": {\"altitude_m\": …, \"f_g\": …}}",
                        ))
                    }
                    Some(AmplitudeSpec::UDsMS(u)) => {
                        if !(u.is_finite() && *u != 0.0 && u.abs() <= 100.0) {
                            return Err(self.err(
                                "discrete_gust.amplitude.u_ds_m_s",
                                format!("must be non-zero and at most 100 m/s in size (got {u} m/s)"),
                            ));
                        }
                        Amplitude::Fixed(*u)
                    }
                    Some(AmplitudeSpec::Cs25(c)) => {
                        if !(c.altitude_m >= 0.0 && c.altitude_m <= 30_000.0) {
                            return Err(self.err(
                                "discrete_gust.amplitude.cs25.altitude_m",
                                format!("must lie in [0, 30000] m (got {} m)", c.altitude_m),
                            ));
                        }
                        if !(c.f_g > 0.0 && c.f_g <= 1.0) {
                            return Err(self.err(
                                "discrete_gust.amplitude.cs25.f_g",
                                format!("the flight profile alleviation factor must lie in (0, 1] (got {})", c.f_g),
                            ));
                        }
                        Amplitude::Cs25 {
                            altitude_m: c.altitude_m,
                            f_g: c.f_g,
                            dive_speed: c.speed == DesignSpeed::Vd,
                            density: flight.density_kg_m3,
                        }
                    }
                };
                DiscreteCase::Tuned {
                    range_m: [lo * FOOT, hi * FOOT],
                    points: d.gradient_points,
                    amplitude,
                }
            }
            DiscreteProfileName::Tabulated => {
                let Some(t) = &d.table else {
                    return Err(self.err(
                        "discrete_gust.table",
                        "missing: a tabulated profile needs {\"time_s\": [...], \"velocity_m_s\": [...]}",
                    ));
                };
                if t.time_s.len() != t.velocity_m_s.len() || t.time_s.len() < 2 {
                    return Err(self.err(
                        "discrete_gust.table",
                        format!("needs as many velocities as times, at least 2 (got {} times, {} velocities)", t.time_s.len(), t.velocity_m_s.len()),
                    ));
                }
                if let Some(i) = t.time_s.windows(2).position(|w| !(w[1] > w[0])) {
                    return Err(self.err(
                        &format!("discrete_gust.table.time_s[{}]", i + 1),
                        format!(
                            "the times must increase strictly (got {} s after {} s)",
                            t.time_s[i + 1],
                            t.time_s[i]
                        ),
                    ));
                }
                if let Some(i) = t.velocity_m_s.iter().position(|v| !(v.abs() <= 100.0)) {
                    return Err(self.err(
                        &format!("discrete_gust.table.velocity_m_s[{i}]"),
                        format!(
                            "must be at most 100 m/s in size (got {} m/s)",
                            t.velocity_m_s[i]
                        ),
                    ));
                }
                for (path, v) in [("amplitude", d.amplitude.is_some())] {
                    if v {
                        return Err(self.err(
                            &format!("discrete_gust.{path}"),
                            "applies to the one_minus_cosine profile only: a table gives its velocities itself",
                        ));
                    }
                }
                DiscreteCase::Tabulated(GustProfile::Tabulated {
                    time: t.time_s.clone(),
                    velocity: t.velocity_m_s.clone(),
                })
            }
        };
        Ok(Some(DiscreteGustSettings {
            case,
            span: d.time_span_s,
            accelerations: d.accelerations,
        }))
    }
}

pub use crate::case::PeakConstraint;

impl Study {
    /// The optimization's peak constraint (none without one); errors name the field.
    pub fn peak_constraint(&self) -> Result<Option<PeakConstraint>, StudyError> {
        let Some(pc) = self
            .spec
            .optimization
            .as_ref()
            .and_then(|o| o.peak_constraint.as_ref())
        else {
            return Ok(None);
        };
        let Some(settings) = self.discrete_gust_settings()? else {
            return Err(self.err(
                "optimization.peak_constraint",
                "needs a discrete_gust section: its gusts are the ones the peak is taken over",
            ));
        };
        let gust = self.gust_settings()?;
        let (base, derivative) = match pc.output.strip_suffix("_acceleration") {
            Some(b) if !gust.outputs.iter().any(|o| o.name == pc.output) => (b, 2),
            _ => (pc.output.as_str(), 0),
        };
        let Some(output) = gust.outputs.iter().position(|o| o.name == base) else {
            return Err(self.err(
                "optimization.peak_constraint.output",
                format!(
                    "no gust output named '{base}' (the outputs: {}; an acceleration is '<name>_acceleration')",
                    gust.outputs.iter().map(|o| o.name.as_str()).collect::<Vec<_>>().join(", ")
                ),
            ));
        };
        let quantity = &gust.outputs[output].quantity;
        if derivative == 2 && !matches!(quantity, crate::gust::Quantity::Displacement { .. }) {
            return Err(self.err(
                "optimization.peak_constraint.output",
                format!(
                    "'{}': only displacement outputs have an acceleration",
                    pc.output
                ),
            ));
        }
        let si_unit = if derivative == 2 {
            "m/s²"
        } else {
            quantity.unit()
        };
        let to_si = if si_unit == "m" {
            self.spec.length_unit.to_m()
        } else {
            1.0
        };
        if !(pc.max > 0.0 && pc.max.is_finite()) {
            return Err(self.err(
                "optimization.peak_constraint.max",
                format!("must be positive (got {})", pc.max),
            ));
        }
        let velocity = self.spec.flight.as_ref().map_or(0.0, |f| f.velocity_m_s);
        let gusts = settings.case.gusts(velocity);
        Ok(Some(PeakConstraint {
            name: pc.output.clone(),
            output,
            derivative,
            limit: pc.max * to_si,
            unit: si_unit.to_string(),
            gusts,
        }))
    }
}
