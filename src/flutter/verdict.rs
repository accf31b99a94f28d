//! One stability verdict for every place that states one (the gust response's stability check, the
//! optimizer's trial points, `gustkit flutter`, the resolution check, the reports): the same test on
//! a p-k sweep and the same words.

use super::FlutterResult;

/// What a p-k sweep says about a design's stability over the speeds it examined.
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// Every root damped at every speed examined, up to `up_to_m_s`.
    Stable { up_to_m_s: f64 },
    /// A root's damping crosses zero (from below) at `speed_m_s`.
    Flutters {
        speed_m_s: f64,
        frequency_hz: f64,
        mode: usize,
        /// The root's reduced frequency lies beyond the GAF table there (its aerodynamics held
        /// at the table's last k): the crossing is an extrapolation.
        extrapolated: bool,
    },
    /// A root is undamped (g ≥ 0) already at the lowest speed examined: no crossing to refine.
    UndampedFromStart {
        speed_m_s: f64,
        frequency_hz: f64,
        mode: usize,
        damping_g: f64,
    },
}

impl Verdict {
    /// The verdict of sweep `r` (speeds increasing).
    pub fn of(r: &FlutterResult) -> Self {
        if let (Some(v), Some(f), Some(m)) =
            (r.flutter_speed_m_s, r.flutter_frequency_hz, r.flutter_mode)
        {
            let extrapolated = r
                .curves
                .iter()
                .find(|c| c.mode == m)
                .and_then(|c| {
                    let i = c.velocity_m_s.iter().position(|&cv| cv >= v)?;
                    Some(c.extrapolated[i] || i > 0 && c.extrapolated[i - 1])
                })
                .unwrap_or(false);
            return Verdict::Flutters {
                speed_m_s: v,
                frequency_hz: f,
                mode: m,
                extrapolated,
            };
        }
        let start = r
            .curves
            .iter()
            .filter(|c| c.damping_g.first().is_some_and(|g| *g > super::G_ROUNDOFF))
            .max_by(|a, b| a.damping_g[0].total_cmp(&b.damping_g[0]));
        if let Some(c) = start {
            return Verdict::UndampedFromStart {
                speed_m_s: c.velocity_m_s[0],
                frequency_hz: c.frequency_hz[0],
                mode: c.mode,
                damping_g: c.damping_g[0],
            };
        }
        let up_to_m_s = r
            .curves
            .first()
            .and_then(|c| c.velocity_m_s.last().copied())
            .unwrap_or(0.0);
        Verdict::Stable { up_to_m_s }
    }

    /// The lowest speed at which the design is not stable, if any.
    pub fn unstable_from(&self) -> Option<f64> {
        match self {
            Verdict::Stable { .. } => None,
            Verdict::Flutters { speed_m_s, .. } | Verdict::UndampedFromStart { speed_m_s, .. } => {
                Some(*speed_m_s)
            }
        }
    }

    /// Whether the design is stable at every speed examined up to and including `v`.
    pub fn stable_up_to(&self, v: f64) -> bool {
        self.unstable_from().is_none_or(|u| u > v)
    }

    /// The verdict in words (a verb phrase: "the design …"), with speeds relative to
    /// `flight_speed_m_s`: "flutters at V = 149.5 m/s (0.87 × the flight speed), mode 7, 104.7 Hz".
    pub fn words(&self, flight_speed_m_s: f64) -> String {
        match self {
            Verdict::Stable { up_to_m_s } => format!(
                "does not flutter up to V = {up_to_m_s:.1} m/s ({:.2} × the flight speed)",
                up_to_m_s / flight_speed_m_s
            ),
            Verdict::Flutters {
                speed_m_s,
                frequency_hz,
                mode,
                extrapolated,
            } => format!(
                "flutters at V = {speed_m_s:.1} m/s ({:.2} × the flight speed), mode {mode}, {frequency_hz:.1} Hz{}",
                speed_m_s / flight_speed_m_s,
                if *extrapolated {
                    " (beyond the GAF table's largest reduced frequency there: extend aero.reduced_frequencies)"
                } else {
                    ""
                }
            ),
            Verdict::UndampedFromStart {
                speed_m_s,
                frequency_hz,
                mode,
                damping_g,
            } => format!(
                "is undamped from the lowest speed examined, V = {speed_m_s:.1} m/s ({:.2} × the flight speed), mode {mode}, {frequency_hz:.1} Hz, g = {damping_g:+.4}",
                speed_m_s / flight_speed_m_s
            ),
        }
    }
}

/// A flutter point's words ("flutters at V = … m/s (… × the flight speed), mode …, … Hz"), or
/// "does not flutter up to …" for a point without a crossing: for results that keep only the point.
pub fn point_words(
    speed_m_s: Option<f64>,
    frequency_hz: Option<f64>,
    mode: Option<usize>,
    flight_speed_m_s: f64,
    searched_up_to_m_s: f64,
) -> String {
    match (speed_m_s, frequency_hz, mode) {
        (Some(v), Some(f), Some(m)) => Verdict::Flutters {
            speed_m_s: v,
            frequency_hz: f,
            mode: m,
            extrapolated: false,
        }
        .words(flight_speed_m_s),
        _ => Verdict::Stable {
            up_to_m_s: searched_up_to_m_s,
        }
        .words(flight_speed_m_s),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flutter::ModeCurve;

    fn curve(mode: usize, g: &[f64]) -> ModeCurve {
        let n = g.len();
        ModeCurve {
            mode,
            velocity_m_s: (0..n).map(|i| 100.0 + 10.0 * i as f64).collect(),
            damping_g: g.to_vec(),
            frequency_hz: vec![104.0; n],
            k: vec![0.5; n],
            extrapolated: vec![false; n],
            aperiodic: vec![false; n],
        }
    }

    /// A hump mode (damped again at the flight speed) still flutters, in the same words; the
    /// words never quote the negative damping at the flight speed.
    #[test]
    fn hump_mode_is_a_flutter_in_one_set_of_words() {
        let r = FlutterResult {
            flutter_speed_m_s: Some(115.0),
            flutter_frequency_hz: Some(104.0),
            flutter_mode: Some(7),
            curves: vec![
                curve(1, &[-0.1, -0.1, -0.1, -0.1]),
                curve(7, &[-0.02, 0.01, -0.01, -0.03]),
            ],
        };
        let v = Verdict::of(&r);
        assert!(!v.stable_up_to(130.0) && v.stable_up_to(114.0));
        let w = v.words(124.0);
        assert_eq!(
            w,
            "flutters at V = 115.0 m/s (0.93 × the flight speed), mode 7, 104.0 Hz"
        );
        assert!(!w.contains("-0.0"), "{w}");
    }

    /// A root undamped at the lowest speed has no crossing: the verdict says so and quotes the
    /// (non-negative) damping; all-damped sweeps are stable up to their last speed.
    #[test]
    fn undamped_from_start_and_stable() {
        let r = FlutterResult {
            flutter_speed_m_s: None,
            flutter_frequency_hz: None,
            flutter_mode: None,
            curves: vec![curve(1, &[-0.1, -0.2]), curve(3, &[0.02, 0.03])],
        };
        let v = Verdict::of(&r);
        assert_eq!(v.unstable_from(), Some(100.0));
        assert!(v.words(100.0).contains("mode 3") && v.words(100.0).contains("g = +0.0200"));
        let r = FlutterResult {
            curves: vec![curve(1, &[-0.1, -0.2])],
            ..r
        };
        assert_eq!(Verdict::of(&r), Verdict::Stable { up_to_m_s: 110.0 });
        assert!(Verdict::of(&r).stable_up_to(1e9));
    }
}
