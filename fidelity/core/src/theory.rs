//! Bessel functions of the first and second kind of integer order n ∈ {0, 1} and x > 0, from
//! their integral representations (Simpson quadrature): accurate to ~1e-10, for reference values
//! in tests and reports (Theodorsen and Sears functions).

use std::f64::consts::PI;

fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    let n = n + n % 2;
    let h = (b - a) / n as f64;
    let mut s = f(a) + f(b);
    for i in 1..n {
        s += f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0
}

/// J_n(x) = (1/π) ∫₀^π cos(n τ − x sin τ) dτ.
pub fn j(n: i32, x: f64) -> f64 {
    simpson(|t| (n as f64 * t - x * t.sin()).cos(), 0.0, PI, 2000) / PI
}

/// Y_n(x) = (1/π) ∫₀^π sin(x sin τ − n τ) dτ − (1/π) ∫₀^∞ (e^{n t} + (−1)ⁿ e^{−n t}) e^{−x sinh t} dt.
pub fn y(n: i32, x: f64) -> f64 {
    let a = simpson(|t| (x * t.sin() - n as f64 * t).sin(), 0.0, PI, 2000) / PI;
    let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
    // the integrand decays like exp(−x e^t / 2): truncate where it is below 1e-300
    let upper = (2.0 * 700.0 / x).ln().max(1.0) + 1.0;
    let b = simpson(
        |t| ((n as f64 * t).exp() + sign * (-(n as f64) * t).exp()) * (-x * t.sinh()).exp(),
        0.0,
        upper,
        20_000,
    ) / PI;
    a - b
}

/// Theodorsen's function C(k) = H₁⁽²⁾(k) / (H₁⁽²⁾(k) + i H₀⁽²⁾(k)), H⁽²⁾ = J − iY, as (re, im).
pub fn theodorsen(k: f64) -> (f64, f64) {
    let (j0, j1, y0, y1) = (j(0, k), j(1, k), y(0, k), y(1, k));
    // H1 = j1 − i y1; H0 = j0 − i y0; den = H1 + i H0 = (j1 + y0) + i (j0 − y1)
    let (nr, ni) = (j1, -y1);
    let (dr, di) = (j1 + y0, j0 - y1);
    let d2 = dr * dr + di * di;
    ((nr * dr + ni * di) / d2, (ni * dr - nr * di) / d2)
}

/// Sears's function S(k) = (J₀ − i J₁) C(k) + i J₁, gust phase referred to the mid-chord.
pub fn sears(k: f64) -> (f64, f64) {
    let (cr, ci) = theodorsen(k);
    let (j0, j1) = (j(0, k), j(1, k));
    // (j0 − i j1)(cr + i ci) + i j1
    (j0 * cr + j1 * ci, j0 * ci - j1 * cr + j1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Tabulated values (Abramowitz & Stegun 9.1): J0(1) = 0.7651976866, J1(1) = 0.4400505857,
    /// Y0(1) = 0.0882569642, Y1(1) = −0.7812128213; Theodorsen C(0.5) ≈ 0.5979 − 0.1507 i.
    #[test]
    fn bessel_and_theodorsen_values() {
        assert!((j(0, 1.0) - 0.7651976866).abs() < 1e-9);
        assert!((j(1, 1.0) - 0.4400505857).abs() < 1e-9);
        assert!((y(0, 1.0) - 0.0882569642).abs() < 1e-8);
        assert!((y(1, 1.0) + 0.7812128213).abs() < 1e-8);
        let (cr, ci) = theodorsen(0.5);
        assert!(
            (cr - 0.5979).abs() < 2e-4 && (ci + 0.1507).abs() < 2e-4,
            "{cr} {ci}"
        );
    }
}
