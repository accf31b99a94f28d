//! Transient gust response of a Nastran model the way NASTRAN-95's APP AERO SOL 11 (and MSC's
//! SOL 146 with TSTEP) computes it: the modal frequency response to the GUST's TLOAD1
//! (`response.rs`: the table's exact Fourier transform times the frequency response) on the
//! FREQ list, taken back to time by the inverse Fourier transform
//!   y(t) = (1/π) ∫₀^∞ Re(Y(ω) e^{iωt}) dω
//! at TSTEP's output times, integrated over the list as PARAM IFTM asks:
//!   IFTM 0 (default): rectangles — y(t) = (1/π) Σⱼ cⱼ Re(Yⱼ e^{iωⱼt}), cⱼ = (ωⱼ₊₁ − ωⱼ₋₁)/2
//!     inside, ω₁ − ω₀ at the start (halved where ω₀ = 0), ωₙ − ωₙ₋₁ at the end;
//!   IFTM 1: Y linear between the frequencies, each segment's integral exact:
//!     ∫ = R [Yₐ e^{iωₐt} conj G(Rt) + Y_b e^{iω_b t} G(Rt)],  R = ω_b − ωₐ, G of `hat_weight`;
//!   IFTM 2 (cubic spline) is refused.
//! With frequencies spaced Δf the result is periodic in 1/Δf: a response that has not died
//! out by then wraps around (the user's FREQ list decides, as in Nastran). NASTRAN-95 also
//! nudges DT so that 1/(Δf DT) is an integer; gustkit keeps the TSTEP's DT.

use super::bulk::BulkData;
use super::response::{
    gust_frequency_response, hat_weight, GustFrequencyResponse, KInterpolation, Quantity,
};
use super::structure::{RealModes, Structure};
use super::{NastranError, Subcase};
use faer::c64;

type R<T> = Result<T, NastranError>;

/// One output's time history at the subcase's output times.
#[derive(Clone, Debug, PartialEq)]
pub struct TransientRow {
    /// Nastran's label: `9T3`, `SPCF 11R3`, `MODE 1`.
    pub label: String,
    pub values: Vec<f64>,
}

/// The transient response: output times (the TSTEP's, in the model's time unit) and one row a
/// request.
#[derive(Clone, Debug, PartialEq)]
pub struct TransientResponse {
    pub times: Vec<f64>,
    pub rows: Vec<TransientRow>,
    /// What the reading noticed and let pass.
    pub warnings: Vec<String>,
}

/// How the inverse transform integrates over the frequency list (PARAM IFTM).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InverseTransform {
    Rectangles,
    Trapezoids,
}

/// The output times of a TSTEP: t = 0, then each group's N steps of DT, every NO-th kept (and
/// each group's last).
pub fn output_times(b: &BulkData, tstep_id: u32) -> R<Vec<f64>> {
    let t = b.tstep.get(&tstep_id).ok_or_else(|| {
        NastranError::model(
            &format!("TSTEP = {tstep_id}"),
            "no TSTEP card has this id".into(),
        )
    })?;
    let mut times = vec![0.0];
    let mut now = 0.0;
    for &(n, dt, no) in &t.intervals {
        if n == 0 || dt <= 0.0 || !dt.is_finite() {
            return Err(NastranError::model(
                &format!("TSTEP {tstep_id}"),
                format!("a group needs N ≥ 1 steps of DT > 0 (got N = {n}, DT = {dt})"),
            ));
        }
        let no = no.max(1);
        for j in 1..=n {
            now += dt;
            if j % no == 0 || j == n {
                times.push(now);
            }
        }
    }
    Ok(times)
}

/// The inverse Fourier transform of y on the frequency list (Hz) at `times`.
pub fn inverse_transform(
    frequencies_hz: &[f64],
    y: &[c64],
    times: &[f64],
    method: InverseTransform,
) -> Vec<f64> {
    let w: Vec<f64> = frequencies_hz
        .iter()
        .map(|f| 2.0 * std::f64::consts::PI * f)
        .collect();
    let n = w.len();
    let phase = |omega: f64, t: f64| c64::new((omega * t).cos(), (omega * t).sin());
    times
        .iter()
        .map(|&t| {
            let sum: c64 = match method {
                InverseTransform::Rectangles => (0..n)
                    .map(|j| {
                        let c = if j == 0 {
                            let c = w[1] - w[0];
                            if w[0] == 0.0 {
                                0.5 * c
                            } else {
                                c
                            }
                        } else if j == n - 1 {
                            w[j] - w[j - 1]
                        } else {
                            0.5 * (w[j + 1] - w[j - 1])
                        };
                        y[j] * phase(w[j], t) * c
                    })
                    .sum(),
                InverseTransform::Trapezoids => (1..n)
                    .map(|j| {
                        let r = w[j] - w[j - 1];
                        let g = hat_weight(r * t);
                        (y[j - 1] * phase(w[j - 1], t) * g.conj() + y[j] * phase(w[j], t) * g) * r
                    })
                    .sum(),
            };
            sum.re / std::f64::consts::PI
        })
        .collect()
}

/// The transient gust response of `requests` for subcase `sub` (TSTEP, GUST → TLOAD1, FREQ),
/// whose structure and modes the caller has solved once.
pub fn transient_response(
    b: &BulkData,
    sub: &Subcase,
    s: &Structure,
    modes: &RealModes,
    requests: &[(u32, u8, Quantity)],
    interpolation: &KInterpolation,
) -> R<TransientResponse> {
    let tstep = sub.selections.get("TSTEP").copied().ok_or_else(|| {
        NastranError::model(
            "case control",
            "selects no TSTEP: a transient gust response needs GUST, FREQUENCY and TSTEP".into(),
        )
    })?;
    let method = match b.params.get("IFTM").map(|v| v.trim()) {
        None | Some("0") => InverseTransform::Rectangles,
        Some("1") => InverseTransform::Trapezoids,
        Some(v) => {
            return Err(NastranError::model(
                "PARAM IFTM",
                format!("{v}: gustkit integrates the inverse Fourier transform by rectangles (0) or trapezoids (1); the cubic spline (2) is not implemented"),
            ))
        }
    };
    let times = output_times(b, tstep)?;
    let response: GustFrequencyResponse = gust_frequency_response(b, sub, s, modes, interpolation)?;
    if response.frequencies_hz.len() < 2 {
        return Err(NastranError::model(
            "FREQUENCY",
            "a transient response needs at least two frequencies to integrate over".into(),
        ));
    }
    let rows = response
        .rows(b, sub, s, modes, requests)?
        .iter()
        .map(|row| TransientRow {
            label: row.label.clone(),
            values: inverse_transform(
                &response.frequencies_hz,
                &response.output(row),
                &times,
                method,
            ),
        })
        .collect();
    Ok(TransientResponse {
        times,
        rows,
        warnings: response.warnings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nastran::bulk::Table;
    use crate::nastran::response::table_transform;

    fn table(points: &[(f64, f64)]) -> Table {
        Table {
            id: 1,
            card: "TABLED1",
            x_axis: "LINEAR".into(),
            y_axis: "LINEAR".into(),
            damping_type: String::new(),
            points: points.to_vec(),
        }
    }

    /// The table transform is exact: a unit square pulse on [0, 1] s against (1 − e^{−iω})/(iω)
    /// to 1e-12, across the series/closed-form switch of G at θ = 1e-2; a table of ramps and a
    /// step (a repeated x) against Simpson's rule per piece on 40 001 points (error ≈ h⁴ω⁴/180
    /// < 1e-13 at ω = 20) to 1e-10.
    #[test]
    fn table_transform_is_exact_for_linear_segments() {
        let square = table(&[(0.0, 1.0), (1.0, 1.0)]);
        for omega in [0.0, 1e-4, 5e-3, 1e-2, 0.3, 2.0, 40.0] {
            let got = table_transform(&square, omega);
            let want = if omega == 0.0 {
                c64::new(1.0, 0.0)
            } else {
                (c64::new(1.0, 0.0) - c64::new(omega.cos(), -omega.sin())) / c64::new(0.0, omega)
            };
            assert!((got - want).norm() < 1e-12, "ω {omega}: {got} vs {want}");
        }
        let shape = table(&[(0.2, 0.0), (0.7, 2.0), (1.1, -1.0), (1.1, 0.5), (1.6, 0.5)]);
        // the table's pieces as lines: (start, end, value at start, value at end)
        let pieces = [
            (0.2, 0.7, 0.0, 2.0),
            (0.7, 1.1, 2.0, -1.0),
            (1.1, 1.6, 0.5, 0.5),
        ];
        for omega in [0.0, 0.7, 6.0, 20.0] {
            let mut want = c64::new(0.0, 0.0);
            for (lo, hi, ya, yb) in pieces {
                let m = 40_000;
                let h = (hi - lo) / m as f64;
                let f = |t: f64| {
                    let v = ya + (yb - ya) * (t - lo) / (hi - lo);
                    c64::new((omega * t).cos(), -(omega * t).sin()) * v
                };
                let mut sum = f(lo) + f(hi);
                for i in 1..m {
                    sum += f(lo + h * i as f64) * if i % 2 == 1 { 4.0 } else { 2.0 };
                }
                want += sum * (h / 3.0);
            }
            let got = table_transform(&shape, omega);
            assert!((got - want).norm() < 1e-10, "ω {omega}: {got} vs {want}");
        }
    }

    /// Transform and inverse transform give the table back: a triangle pulse (0 → 1 → 0 over
    /// 1 s) on frequencies 0–50 Hz by 0.05 Hz (period 20 s) comes back at t = 0 … 2 s within
    /// the truncation bound ∫_Ω^∞ |P| dω / π ≤ 4/(a π Ω) = 8.1e-3 (a = 0.5 s, Ω = 2π·50),
    /// by rectangles and by trapezoids (measured 4.1e-3 and 6.1e-3, both at the peak's kink).
    #[test]
    fn inverse_transform_returns_the_table() {
        let tri = table(&[(0.0, 0.0), (0.5, 1.0), (1.0, 0.0)]);
        let freqs: Vec<f64> = (0..=1000).map(|i| 0.05 * i as f64).collect();
        let y: Vec<c64> = freqs
            .iter()
            .map(|f| table_transform(&tri, 2.0 * std::f64::consts::PI * f))
            .collect();
        let times: Vec<f64> = (0..=40).map(|i| 0.05 * i as f64).collect();
        for method in [InverseTransform::Rectangles, InverseTransform::Trapezoids] {
            let back = inverse_transform(&freqs, &y, &times, method);
            let err = back
                .iter()
                .zip(&times)
                .map(|(v, &t)| (v - crate::nastran::response::table_value(&tri, t)).abs())
                .fold(0.0, f64::max);
            eprintln!("{method:?}: largest error {err:.3e}");
            assert!(err < 8.1e-3, "{method:?}: {err}");
        }
    }
}
