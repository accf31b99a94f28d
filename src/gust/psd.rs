//! Atmospheric turbulence spectra, one-sided in circular frequency ω (rad/s), each integrating to
//! σ_w² over [0, ∞).
//!
//! Scale-length convention: `scale_length` is the MIL-F-8785C L_w of the vertical gust. The same
//! Dryden spectrum appears in MIL-HDBK-1797 with L₁₇₉₇ = 2 L_w; pass L₁₇₉₇ / 2 here.

use serde::{Deserialize, Serialize};

/// A turbulence model of the vertical gust velocity.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "model", rename_all = "snake_case", deny_unknown_fields)]
pub enum Turbulence {
    /// Φ(ω) = σ² L/(π V) · [1 + 3 (Lω/V)²] / [1 + (Lω/V)²]²  (MIL-F-8785C, vertical).
    Dryden {
        sigma_w_m_s: f64,
        scale_length_m: f64,
    },
    /// Φ(ω) = σ² L/(π V) · [1 + (8/3)(a Lω/V)²] / [1 + (a Lω/V)²]^{11/6}, a = 1.339 (see [`KARMAN_A`]).
    VonKarman {
        sigma_w_m_s: f64,
        scale_length_m: f64,
    },
}

impl std::fmt::Display for Turbulence {
    /// The spectrum in words, as a report states it.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (name, sigma, l) = match self {
            Turbulence::Dryden {
                sigma_w_m_s,
                scale_length_m,
            } => ("Dryden", sigma_w_m_s, scale_length_m),
            Turbulence::VonKarman {
                sigma_w_m_s,
                scale_length_m,
            } => ("von Kármán", sigma_w_m_s, scale_length_m),
        };
        write!(
            f,
            "{name} turbulence, σ_w = {sigma:.4} m/s, scale length L = {l:.1} m"
        )
    }
}

/// von Kármán constant a = Γ(1/3) / (√π Γ(5/6)) = 1.33899 (quoted as 1.339), the value for which
/// the spectrum integrates exactly to σ².
const KARMAN_A: f64 = 1.338_985_279_065_280_3;

impl Turbulence {
    pub fn sigma(&self) -> f64 {
        match *self {
            Turbulence::Dryden { sigma_w_m_s, .. } | Turbulence::VonKarman { sigma_w_m_s, .. } => {
                sigma_w_m_s
            }
        }
    }

    pub fn scale_length(&self) -> f64 {
        match *self {
            Turbulence::Dryden { scale_length_m, .. }
            | Turbulence::VonKarman { scale_length_m, .. } => scale_length_m,
        }
    }

    /// Checks σ_w > 0 and L > 0; the message names the field.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.sigma() > 0.0 && self.sigma().is_finite()) {
            return Err(format!(
                "sigma_w_m_s: must be positive (got {})",
                self.sigma()
            ));
        }
        if !(self.scale_length() > 0.0 && self.scale_length().is_finite()) {
            return Err(format!(
                "scale_length_m: must be positive (got {})",
                self.scale_length()
            ));
        }
        Ok(())
    }

    /// One-sided PSD of the vertical gust velocity at ω for flight speed `v`, (m/s)² per rad/s.
    pub fn psd(&self, omega: f64, v: f64) -> f64 {
        let (s, l) = (self.sigma(), self.scale_length());
        let base = s * s * l / (std::f64::consts::PI * v);
        let x = l * omega / v;
        match self {
            Turbulence::Dryden { .. } => base * (1.0 + 3.0 * x * x) / (1.0 + x * x).powi(2),
            Turbulence::VonKarman { .. } => {
                let ax = KARMAN_A * x;
                base * (1.0 + 8.0 / 3.0 * ax * ax) / (1.0 + ax * ax).powf(11.0 / 6.0)
            }
        }
    }

    /// Fraction of σ_w² above ω (the tail the frequency grid leaves out).
    pub fn tail_fraction(&self, omega: f64, v: f64) -> f64 {
        let x = self.scale_length() * omega / v;
        match self {
            // ∫_x^∞ (1 + 3t²)/(1 + t²)² dt / (π/2) = 1 − (2/π)(atan x + x/(1 + x²))·… closed form:
            // antiderivative of (1+3t²)/(1+t²)² is 2 atan t − t/(1 + t²)
            Turbulence::Dryden { .. } => {
                let total = std::f64::consts::PI; // 2·(π/2)
                (total - (2.0 * x.atan() - x / (1.0 + x * x))) / total
            }
            // numerically on [x, X] (t = tan θ keeps the integrand smooth there) plus the
            // asymptotic tail ∫_X^∞ (8/3) a^{−5/3} t^{−5/3} dt = 4 a^{−5/3} X^{−2/3}
            Turbulence::VonKarman { .. } => karman_integral(x) / karman_integral(0.0),
        }
    }
}

/// ∫_x^∞ g(t) dt for a spectrum shape g decaying like c t^{−p} (p > 1): Simpson in s = ln t on
/// [ln max(x, 1e−9), ln X] (smooth there), ∫₀^{1e−9} ≈ g(0)·1e−9, and the power-law tail beyond X.
pub(crate) fn shape_integral(g: impl Fn(f64) -> f64, x: f64, c: f64, p: f64) -> f64 {
    let lo = x.max(1e-9);
    let upper = 1e6f64.max(1e3 * lo);
    let (s0, s1) = (lo.ln(), upper.ln());
    let n = 20_000;
    let h = (s1 - s0) / n as f64;
    let f = |s: f64| {
        let t = s.exp();
        g(t) * t
    };
    let mut acc = 0.0;
    for i in 0..n {
        let a = s0 + i as f64 * h;
        acc += (f(a) + 4.0 * f(a + 0.5 * h) + f(a + h)) * h / 6.0;
    }
    let head = if x < 1e-9 { g(0.0) * (1e-9 - x) } else { 0.0 };
    head + acc + c * upper.powf(1.0 - p) / (p - 1.0)
}

/// ∫_x^∞ (1 + (8/3)(a t)²)/(1 + (a t)²)^{11/6} dt.
fn karman_integral(x: f64) -> f64 {
    let g = |t: f64| {
        let at = KARMAN_A * t;
        (1.0 + 8.0 / 3.0 * at * at) / (1.0 + at * at).powf(11.0 / 6.0)
    };
    shape_integral(g, x, 8.0 / 3.0 * KARMAN_A.powf(-5.0 / 3.0), 5.0 / 3.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫₀^∞ Φ dω = σ² for both spectra, by quadrature in θ = atan(Lω/V) (the tails decay slowly
    /// in ω); the closed-form Dryden tail agrees with quadrature.
    #[test]
    fn spectra_integrate_to_sigma_squared() {
        let v = 172.8;
        for t in [
            Turbulence::Dryden {
                sigma_w_m_s: 1.7,
                scale_length_m: 266.7,
            },
            Turbulence::VonKarman {
                sigma_w_m_s: 1.7,
                scale_length_m: 762.0,
            },
        ] {
            let l = t.scale_length();
            // ∫ Φ dω = (σ² /π) ∫ shape(x) dx with x = Lω/V
            let integral = |x0: f64| {
                let g = |x: f64| t.psd(v / l * x, v) * std::f64::consts::PI / (1.7 * 1.7) * v / l;
                let (c, p) = match t {
                    Turbulence::Dryden { .. } => (3.0, 2.0),
                    Turbulence::VonKarman { .. } => {
                        (8.0 / 3.0 * KARMAN_A.powf(-5.0 / 3.0), 5.0 / 3.0)
                    }
                };
                1.7 * 1.7 / std::f64::consts::PI * shape_integral(g, x0, c, p)
            };
            let s = integral(0.0);
            assert!((s / (1.7 * 1.7) - 1.0).abs() < 1e-6, "{t:?}: {s}");
            // tail fraction: at ω = 0 all of it; above 3 V/L it matches the quadrature
            assert!((t.tail_fraction(0.0, v) - 1.0).abs() < 1e-9);
            let w = 3.0 * v / l;
            assert!((t.tail_fraction(w, v) - integral(3.0) / s).abs() < 1e-6);
        }
    }

    #[test]
    fn bad_turbulence_is_rejected() {
        let t = Turbulence::Dryden {
            sigma_w_m_s: 0.0,
            scale_length_m: 10.0,
        };
        assert!(t.validate().unwrap_err().contains("sigma_w_m_s"));
        let t = Turbulence::VonKarman {
            sigma_w_m_s: 1.0,
            scale_length_m: -1.0,
        };
        assert!(t.validate().unwrap_err().contains("scale_length_m"));
    }
}
