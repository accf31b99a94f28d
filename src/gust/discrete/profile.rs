//! Discrete gust profiles w_g(t): the vertical gust velocity at the gust reference point
//! (`aero.gust_x_ref`) as the gust convects over the wing at the flight speed, and their exact
//! Fourier transforms W(ω) = ∫ w_g(t) e^{−iωt} dt, which the transient response multiplies by
//! the transfer functions.

use faer::c64;

/// A discrete gust profile (SI: seconds, m/s of true gust velocity).
#[derive(Clone, Debug, PartialEq)]
pub enum GustProfile {
    /// CS-25.341(a)/FAR 25.341(a): w = (U_ds/2)(1 − cos(π s/H)) for 0 ≤ s = V t ≤ 2H: gust
    /// gradient `gradient` H (m), peak `amplitude` U_ds (m/s), penetrated at `velocity` V (m/s).
    OneMinusCosine {
        gradient: f64,
        amplitude: f64,
        velocity: f64,
    },
    /// A piecewise-linear table (t_i strictly increasing, s; w_i, m/s), zero outside it: a step
    /// is a table held for longer than the response takes to settle.
    Tabulated { time: Vec<f64>, velocity: Vec<f64> },
}

/// sin(x)/x, by its series near zero.
fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-4 {
        1.0 - x * x / 6.0
    } else {
        x.sin() / x
    }
}

/// E0(x) = ∫₀¹ e^{−ixs} ds and E1(x) = ∫₀¹ s e^{−ixs} ds: closed forms, by their series for
/// |x| < 1 where the closed forms cancel.
fn segment_moments(x: f64) -> (c64, c64) {
    let i = c64::new(0.0, 1.0);
    if x.abs() < 1.0 {
        // Σ (−ix)ⁿ/(n+1)! and Σ (−ix)ⁿ/(n! (n+2)): 24 terms leave < 1e-23
        let (mut e0, mut e1) = (c64::new(0.0, 0.0), c64::new(0.0, 0.0));
        let mut pow_over_fact = c64::new(1.0, 0.0); // (−ix)ⁿ/n!
        for n in 0..24 {
            let nf = n as f64;
            e0 += pow_over_fact / (nf + 1.0);
            e1 += pow_over_fact / (nf + 2.0);
            pow_over_fact *= -i * x / (nf + 1.0);
        }
        (e0, e1)
    } else {
        let e = c64::new(x.cos(), -x.sin());
        let e0 = (c64::new(1.0, 0.0) - e) / (i * x);
        let e1 = i * e / x - (c64::new(1.0, 0.0) - e) / (x * x);
        (e0, e1)
    }
}

impl GustProfile {
    /// Checks the profile's numbers; the message names what is wrong and the fix.
    pub fn validate(&self) -> Result<(), String> {
        match self {
            GustProfile::OneMinusCosine {
                gradient,
                amplitude,
                velocity,
            } => {
                if !(*gradient > 0.0 && gradient.is_finite()) {
                    return Err(format!(
                        "the gust gradient must be positive (got {gradient} m)"
                    ));
                }
                if !amplitude.is_finite() {
                    return Err(format!(
                        "the gust amplitude must be finite (got {amplitude} m/s)"
                    ));
                }
                if !(*velocity > 0.0 && velocity.is_finite()) {
                    return Err(format!(
                        "the flight speed must be positive (got {velocity} m/s)"
                    ));
                }
                Ok(())
            }
            GustProfile::Tabulated { time, velocity } => {
                if time.len() != velocity.len() || time.len() < 2 {
                    return Err(format!(
                        "a tabulated gust needs as many velocities as times, at least 2 (got {} times, {} velocities)",
                        time.len(),
                        velocity.len()
                    ));
                }
                if let Some(i) = time.iter().chain(velocity).position(|v| !v.is_finite()) {
                    return Err(format!("entry {i} of the table is not a finite number"));
                }
                if let Some(i) = time.windows(2).position(|w| !(w[1] > w[0])) {
                    return Err(format!(
                        "the times must increase strictly: time[{}] = {} s is not after time[{i}] = {} s",
                        i + 1,
                        time[i + 1],
                        time[i]
                    ));
                }
                Ok(())
            }
        }
    }

    /// The interval [t_start, t_end] (s) outside which the profile is zero.
    pub fn support(&self) -> (f64, f64) {
        match self {
            GustProfile::OneMinusCosine {
                gradient, velocity, ..
            } => (0.0, 2.0 * gradient / velocity),
            GustProfile::Tabulated { time, .. } => (time[0], time[time.len() - 1]),
        }
    }

    /// w_g(t), m/s.
    pub fn value(&self, t: f64) -> f64 {
        let (t0, t1) = self.support();
        if t < t0 || t > t1 {
            return 0.0;
        }
        match self {
            GustProfile::OneMinusCosine { amplitude, .. } => {
                0.5 * amplitude * (1.0 - (2.0 * std::f64::consts::PI * (t - t0) / (t1 - t0)).cos())
            }
            GustProfile::Tabulated { time, velocity } => {
                let i = time.partition_point(|&ti| ti <= t).clamp(1, time.len() - 1);
                let s = (t - time[i - 1]) / (time[i] - time[i - 1]);
                velocity[i - 1] + s * (velocity[i] - velocity[i - 1])
            }
        }
    }

    /// The largest |w_g| (m/s).
    pub fn peak(&self) -> f64 {
        match self {
            GustProfile::OneMinusCosine { amplitude, .. } => amplitude.abs(),
            GustProfile::Tabulated { velocity, .. } => {
                velocity.iter().fold(0.0, |a, v| a.max(v.abs()))
            }
        }
    }

    /// W(ω) = ∫ w_g(t) e^{−iωt} dt, exactly: for the 1-cos gust of duration T = 2H/V,
    ///   W = (U T/2) e^{−iωT/2} [sinc(ωT/2) + ½ sinc((ω−Ω)T/2) + ½ sinc((ω+Ω)T/2)],  Ω = 2π/T,
    /// (no removable singularity left: W(0) = UT/2, W(Ω) = −UT/4); for a table, the sum over its
    /// linear segments of e^{−iωt_a} h [w_a E0(ωh) + (w_b − w_a) E1(ωh)].
    pub fn spectrum(&self, omega: f64) -> c64 {
        match self {
            GustProfile::OneMinusCosine { amplitude, .. } => {
                let (_, t) = self.support();
                let big = 2.0 * std::f64::consts::PI / t;
                let bracket = sinc(omega * t / 2.0)
                    + 0.5 * sinc((omega - big) * t / 2.0)
                    + 0.5 * sinc((omega + big) * t / 2.0);
                let phase = c64::new((omega * t / 2.0).cos(), -(omega * t / 2.0).sin());
                phase * (0.5 * amplitude * t * bracket)
            }
            GustProfile::Tabulated { time, velocity } => {
                let mut w = c64::new(0.0, 0.0);
                for i in 1..time.len() {
                    let h = time[i] - time[i - 1];
                    let (e0, e1) = segment_moments(omega * h);
                    let ta = time[i - 1];
                    let phase = c64::new((omega * ta).cos(), -(omega * ta).sin());
                    w += phase * (e0 * velocity[i - 1] + e1 * (velocity[i] - velocity[i - 1])) * h;
                }
                w
            }
        }
    }

    /// ∫ w_g² dt (m²/s): by Parseval π times ∫₀^∞ |W|² dω, so the fraction of it a truncated
    /// frequency grid misses measures what the truncation leaves out.
    pub fn energy(&self) -> f64 {
        match self {
            GustProfile::OneMinusCosine { amplitude, .. } => {
                let (t0, t1) = self.support();
                0.375 * amplitude * amplitude * (t1 - t0)
            }
            GustProfile::Tabulated { time, velocity } => (1..time.len())
                .map(|i| {
                    let (a, b) = (velocity[i - 1], velocity[i]);
                    (time[i] - time[i - 1]) / 3.0 * (a * a + a * b + b * b)
                })
                .sum(),
        }
    }
}

/// Metres in a foot: CS-25 states gust gradients and reference velocities in feet.
pub const FOOT: f64 = 0.3048;

/// Sea-level standard density (kg/m³): equivalent airspeed to true by √(ρ₀/ρ).
pub const RHO_SEA_LEVEL: f64 = 1.225;

/// The CS-25.341(a)(5) reference gust velocity U_ref (m/s EAS) at the design cruising speed V_C
/// and altitude `altitude` (m): 17.07 m/s at sea level, linearly to 13.41 m/s at 4 572 m and
/// on to 6.36 m/s at 18 288 m (56, 44 and 20.86 ft/s at 0, 15 000 and 60 000 ft); at the
/// design dive speed V_D half of it. Beyond 18 288 m the last value is held.
pub fn reference_gust_velocity(altitude: f64) -> f64 {
    let pts = [(0.0, 17.07), (4572.0, 13.41), (18288.0, 6.36)];
    if altitude <= pts[0].0 {
        return pts[0].1;
    }
    for w in pts.windows(2) {
        let ((z0, u0), (z1, u1)) = (w[0], w[1]);
        if altitude <= z1 {
            return u0 + (u1 - u0) * (altitude - z0) / (z1 - z0);
        }
    }
    pts[2].1
}

/// The CS-25 design gust amplitude (true airspeed, m/s) of gradient `gradient` H (m):
/// U_ds = U_ref F_g (H / 106.68 m)^{1/6}, U_ref from [`reference_gust_velocity`] (halved at V_D),
/// converted from EAS to TAS at `density` by √(ρ₀/ρ).
pub fn cs25_amplitude(
    gradient: f64,
    altitude: f64,
    f_g: f64,
    dive_speed: bool,
    density: f64,
) -> f64 {
    let u_ref = reference_gust_velocity(altitude) * if dive_speed { 0.5 } else { 1.0 };
    u_ref * f_g * (gradient / (350.0 * FOOT)).powf(1.0 / 6.0) * (RHO_SEA_LEVEL / density).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// W(ω) against a composite Simpson quadrature of ∫ w e^{−iωt} dt (20 000 panels per unit
    /// of the support, error ~1e-12 of W(0)), at frequencies around the 1-cos gust's own Ω and
    /// its removable singularities, and for a table with short and long segments (both branches
    /// of the segment moments).
    #[test]
    fn spectra_match_quadrature() {
        let gusts = [
            GustProfile::OneMinusCosine {
                gradient: 20.0,
                amplitude: 7.0,
                velocity: 150.0,
            },
            GustProfile::Tabulated {
                time: vec![-0.05, 0.0, 0.001, 0.3, 0.31],
                velocity: vec![0.0, 0.0, 5.0, 5.0, -1.0],
            },
        ];
        for g in &gusts {
            let (t0, t1) = g.support();
            let n = 200_000;
            let h = (t1 - t0) / n as f64;
            let scale = g.spectrum(0.0).norm();
            let big = 2.0 * std::f64::consts::PI / (t1 - t0);
            for omega in [
                0.0,
                1e-6,
                0.3 * big,
                big,
                big * (1.0 + 1e-9),
                2.0 * big,
                17.0,
                400.0,
                3000.0,
            ] {
                // Simpson over the pieces where w is smooth: the table's kinks sit on panel
                // boundaries only for the 1-cos, so the table is integrated segment by segment
                let mut q = c64::new(0.0, 0.0);
                let knots: Vec<f64> = match g {
                    GustProfile::Tabulated { time, .. } => time.clone(),
                    _ => vec![t0, t1],
                };
                for seg in knots.windows(2) {
                    let m = ((seg[1] - seg[0]) / h).ceil().max(2.0) as usize * 2;
                    let hs = (seg[1] - seg[0]) / m as f64;
                    let f = |t: f64| {
                        // the value inside the segment (the table's end points are one-sided)
                        let tt = t.clamp(seg[0] + 1e-15, seg[1] - 1e-15);
                        c64::new((omega * t).cos(), -(omega * t).sin()) * g.value(tt)
                    };
                    let mut s = f(seg[0]) + f(seg[1]);
                    for k in 1..m {
                        s += f(seg[0] + k as f64 * hs) * if k % 2 == 1 { 4.0 } else { 2.0 };
                    }
                    q += s * hs / 3.0;
                }
                let w = g.spectrum(omega);
                assert!(
                    (w - q).norm() < 1e-9 * scale,
                    "{g:?} at {omega} rad/s: exact {w}, quadrature {q}"
                );
            }
            // Parseval's energy against the same Simpson rule on w²
            let m = 200_000;
            let hs = (t1 - t0) / m as f64;
            let mut s = 0.0;
            for k in 0..m {
                let (a, b) = (t0 + k as f64 * hs, t0 + (k + 1) as f64 * hs);
                let mid = 0.5 * (a + b);
                let f = |t: f64| g.value(t.clamp(a + 1e-15, b - 1e-15)).powi(2);
                s += (f(a) + 4.0 * f(mid) + f(b)) * hs / 6.0;
            }
            assert!(
                (g.energy() - s).abs() < 1e-6 * g.energy(),
                "{g:?}: {} against {s}",
                g.energy()
            );
        }
    }

    /// CS-25's numbers: U_ref 56 ft/s EAS at sea level and 44 ft/s at 15 000 ft (17.07 and
    /// 13.41 m/s), U_ds = U_ref at H = 350 ft, (30/350)^{1/6} = 0.6640 of it at 30 ft, half at V_D,
    /// and the EAS-to-TAS factor at ρ = 0.4135 kg/m³ (about 10 km) √(1.225/0.4135) = 1.7212.
    #[test]
    fn cs25_amplitudes() {
        assert!((reference_gust_velocity(0.0) - 56.0 * FOOT).abs() < 0.005);
        assert!((reference_gust_velocity(15_000.0 * FOOT) - 44.0 * FOOT).abs() < 0.005);
        assert!((reference_gust_velocity(60_000.0 * FOOT) - 20.86 * FOOT).abs() < 0.005);
        let h350 = 350.0 * FOOT;
        assert!((cs25_amplitude(h350, 0.0, 1.0, false, RHO_SEA_LEVEL) - 17.07).abs() < 1e-12);
        let r = cs25_amplitude(30.0 * FOOT, 0.0, 1.0, false, RHO_SEA_LEVEL) / 17.07;
        assert!((r - (30.0f64 / 350.0).powf(1.0 / 6.0)).abs() < 1e-12 && (r - 0.6640).abs() < 1e-4);
        assert!((cs25_amplitude(h350, 0.0, 0.8, true, RHO_SEA_LEVEL) - 0.4 * 17.07).abs() < 1e-12);
        let tas = cs25_amplitude(h350, 0.0, 1.0, false, 0.4135) / 17.07;
        assert!((tas - 1.7212).abs() < 1e-4);
    }
}
