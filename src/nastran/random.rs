//! Random gust response of a Nastran model the way SOL 146 (NASTRAN-95's APP AERO SOL 11)
//! computes it: the modal frequency response to the GUST (`response.rs`) at the FREQ list's
//! frequencies, PSDs from RANDPS and TABRND1, RMS and zero-crossing rate N0 by the trapezoidal
//! rule over the frequency list, for grid displacements ("9T3"), accelerations ("ACCE 9T3"),
//! single-point constraint forces ("SPCF 11R3") and modal coordinates ("MODE 2"), in the
//! model's units.
//!
//! PSD_y = |y|² X · TABRND1(f); RMS = √∫PSD df, N0 = √(∫f²PSD df / ∫PSD df), the integrals
//! over the FREQ list with the PSD linear between its frequencies ([`spectral_moments`]).

use super::bulk::BulkData;
use super::response::{gust_frequency_response, table_value};
pub use super::response::{KInterpolation, Quantity};
use super::structure::{RealModes, Structure};
use super::{NastranError, Subcase};

type R<T> = Result<T, NastranError>;

/// One output's random response.
#[derive(Clone, Debug, PartialEq)]
pub struct RandomRow {
    /// Nastran's label: `9T3`, `SPCF 11R3`.
    pub label: String,
    pub rms: f64,
    pub n0_hz: f64,
    /// The PSD at the FREQ list's frequencies (`frequencies_hz`), per Hz.
    pub psd: Vec<f64>,
    pub frequencies_hz: Vec<f64>,
}

/// The spectral moments m₀ = ∫ PSD df and m₂ = ∫ f² PSD df over the frequency list the way
/// NASTRAN-95 integrates them (RAND3): the PSD linear between frequencies, so m₀ by trapezoids
/// and m₂ exact for f² times that line, per segment
///   Δf [S_a (3f_a² + 2f_a f_b + f_b²) + S_b (f_a² + 2f_a f_b + 3f_b²)] / 12.
/// (A trapezoid of f² PSD instead underweights a peak's upper neighbour: on D11-03-1A's 0.25 Hz
/// list it gave N0 6 % below NASTRAN-95's.)
pub fn spectral_moments(freqs: &[f64], psd: &[f64]) -> (f64, f64) {
    let (mut m0, mut m2) = (0.0, 0.0);
    for i in 1..freqs.len() {
        let (fa, fb) = (freqs[i - 1], freqs[i]);
        let (sa, sb) = (psd[i - 1], psd[i]);
        let h = fb - fa;
        m0 += 0.5 * h * (sa + sb);
        m2 += h
            * (sa * (3.0 * fa * fa + 2.0 * fa * fb + fb * fb)
                + sb * (fa * fa + 2.0 * fa * fb + 3.0 * fb * fb))
            / 12.0;
    }
    (m0, m2)
}

/// The random response of `requests` ((grid, component 1–6, quantity)) for subcase `sub`,
/// whose structure `s` and modes (`subcase_modes`) the caller has solved once; with the
/// warnings of the reading.
pub fn random_response(
    b: &BulkData,
    sub: &Subcase,
    s: &Structure,
    modes: &RealModes,
    requests: &[(u32, u8, Quantity)],
    interpolation: &KInterpolation,
) -> R<(Vec<RandomRow>, Vec<String>)> {
    let random_id = sub.selections.get("RANDOM").copied().ok_or_else(|| {
        NastranError::model(
            "case control",
            "selects no RANDOM: a random gust response needs GUST, FREQUENCY and RANDOM".into(),
        )
    })?;
    let psd = b
        .randps
        .iter()
        .filter(|r| r.sid == random_id)
        .collect::<Vec<_>>();
    let [psd] = psd.as_slice() else {
        return Err(NastranError::model(
            &format!("RANDOM = {random_id}"),
            format!("needs one RANDPS (found {})", psd.len()),
        ));
    };
    let psd_table = psd
        .tid
        .map(|t| {
            b.tables.get(&t).ok_or_else(|| {
                NastranError::model(
                    &format!("RANDPS {random_id}"),
                    format!("refers to TABRND1 {t}, which the model does not define"),
                )
            })
        })
        .transpose()?;
    let response = gust_frequency_response(b, sub, s, modes, interpolation)?;
    let rows = response.rows(b, sub, s, modes, requests)?;
    let freqs = &response.frequencies_hz;
    let out = rows
        .iter()
        .map(|row| {
            let psd_values: Vec<f64> = response
                .output(row)
                .iter()
                .zip(freqs)
                .map(|(y, &f)| y.norm_sqr() * psd.x * psd_table.map_or(1.0, |t| table_value(t, f)))
                .collect();
            let (m0, m2) = spectral_moments(freqs, &psd_values);
            RandomRow {
                label: row.label.clone(),
                rms: m0.sqrt(),
                n0_hz: if m0 > 0.0 { (m2 / m0).sqrt() } else { 0.0 },
                psd: psd_values,
                frequencies_hz: freqs.clone(),
            }
        })
        .collect();
    Ok((out, response.warnings))
}

#[cfg(test)]
mod tests {
    use super::spectral_moments;

    /// The moments are exact for a PSD linear between the frequencies: S = 2 − f/2 on an
    /// uneven list over [0.5, 3] against ∫S df = [2f − f²/4] and ∫f²S df = [2f³/3 − f⁴/8] to
    /// 1e-14; a PSD bent at a frequency (a peak) is integrated as the broken line through it.
    #[test]
    fn spectral_moments_are_exact_for_linear_psd() {
        let f = [0.5, 0.7, 1.3, 2.0, 2.2, 3.0];
        let s: Vec<f64> = f.iter().map(|x| 2.0 - 0.5 * x).collect();
        let (m0, m2) = spectral_moments(&f, &s);
        let p0 = |x: f64| 2.0 * x - x * x / 4.0;
        let p2 = |x: f64| 2.0 * x.powi(3) / 3.0 - x.powi(4) / 8.0;
        assert!((m0 - (p0(3.0) - p0(0.5))).abs() < 1e-14);
        assert!((m2 - (p2(3.0) - p2(0.5))).abs() < 1e-14 * p2(3.0));
        // a triangle peak at 1 Hz, by hand: [0, 1]: ∫ f²·f df = 1/4;
        // [1, 2]: ∫ f²(2 − f) df = 2(8 − 1)/3 − (16 − 1)/4 = 11/12
        let (m0, m2) = spectral_moments(&[0.0, 1.0, 2.0], &[0.0, 1.0, 0.0]);
        assert!((m0 - 1.0).abs() < 1e-15);
        assert!((m2 - (0.25 + 11.0 / 12.0)).abs() < 1e-14);
    }
}
