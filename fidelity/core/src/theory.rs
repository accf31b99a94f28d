//! Bessel functions of the first and second kind of integer order n ∈ {0, 1} and x > 0, from
//! their integral representations (Simpson quadrature): accurate to ~1e-10, for reference values
//! in tests and reports (Theodorsen and Sears functions).

use num_complex::Complex64;
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

/// Strip-theory GAFs per unit span of a flat-plate section of semichord `b` (m), divided by q∞
/// (the trait's normalization), at reduced frequency k = ωb/U: plunge h (up, m) and pitch α (nose
/// up about the mid-chord, rad) by Theodorsen, the vertical gust (w_g/U = 1, phase zero at the
/// mid-chord) by Sears. The circulatory parts carry the Prandtl–Glauert factor 1/β of `mach`
/// (0 for the incompressible theory). Returns ([[L_h, L_α], [M_h, M_α]], [L_g, M_g]): row 0 the
/// lift (the force on the plunge mode), row 1 the nose-up moment about the mid-chord.
pub fn strip_gafs(k: f64, b: f64, mach: f64) -> ([[Complex64; 2]; 2], [Complex64; 2]) {
    let (cr, ci) = if k == 0.0 { (1.0, 0.0) } else { theodorsen(k) };
    let (sr, si) = if k == 0.0 { (1.0, 0.0) } else { sears(k) };
    let c = Complex64::new(cr, ci);
    let i = Complex64::new(0.0, 1.0);
    let beta = (1.0 - mach * mach).sqrt();
    // ρ = 2, U = 1 (q∞ = 1), ω = k / b; Theodorsen's a = 0 (mid-chord), h positive up
    let (rho, u, w) = (2.0, 1.0, k / b);
    let circ = 2.0 * PI * rho * u * b / beta;
    // downwash at the three-quarter chord: −ḣ + U α + (b/2) α̇
    let l_h = PI * rho * b * b * w * w - circ * c * i * w;
    let l_a = PI * rho * b * b * u * i * w + circ * c * (u + b / 2.0 * i * w);
    let m_h = -circ * c * i * w * b / 2.0;
    let m_a = PI * rho * b * b * (b * b / 8.0 * w * w - u * b / 2.0 * i * w)
        + circ * c * (u + b / 2.0 * i * w) * b / 2.0;
    let l_g = circ * u * Complex64::new(sr, si);
    ([[l_h, l_a], [m_h, m_a]], [l_g, l_g * b / 2.0])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Tabulated values (Abramowitz & Stegun 9.1): J0(1) = 0.7651976866, J1(1) = 0.4400505857,
    /// Y0(1) = 0.0882569642, Y1(1) = −0.7812128213; Theodorsen C(0.5) ≈ 0.5979 − 0.1507 i.
    /// Quasi-steady limits of the strip GAFs: at k = 0 the lift of a unit pitch is 2π b ρU²/q∞ =
    /// 4πb (twice the section lift slope per unit span), acting at the quarter chord (moment
    /// b/2 × lift), a static plunge makes no force, and the gust lift equals the pitch lift (w/U =
    /// 1 is a unit angle of attack); the Prandtl–Glauert factor scales them by 1/β.
    #[test]
    fn strip_gafs_steady_limits() {
        let b = 0.7;
        let (ss, gs) = strip_gafs(0.0, b, 0.0);
        let l = 4.0 * PI * b;
        assert!((ss[0][1].re - l).abs() < 1e-12 && ss[0][1].im == 0.0);
        assert!((ss[1][1].re - l * b / 2.0).abs() < 1e-12);
        assert!(ss[0][0].norm() == 0.0 && ss[1][0].norm() == 0.0);
        assert!((gs[0] - ss[0][1]).norm() < 1e-12);
        let (ssc, _) = strip_gafs(0.0, b, 0.6);
        assert!((ssc[0][1].re - l / 0.8).abs() < 1e-12);
    }

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
