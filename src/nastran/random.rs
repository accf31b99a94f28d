//! Random gust response of a Nastran model the way SOL 146 (NASTRAN-95's APP AERO SOL 11)
//! computes it: the modal frequency response to the GUST (`response.rs`) at the FREQ list's
//! frequencies, PSDs from RANDPS and TABRND1, RMS and zero-crossing rate N0 by the trapezoidal
//! rule over the frequency list, for grid displacements ("9T3"), accelerations ("ACCE 9T3"),
//! single-point constraint forces ("SPCF 11R3") and modal coordinates ("MODE 2"), in the
//! model's units.
//!
//! PSD_y = |y|² X · TABRND1(f); RMS = √∫PSD df, N0 = √(∫f²PSD df / ∫PSD df).

use super::bulk::BulkData;
use super::response::{gust_frequency_response, output_rows, table_value};
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
    let rows = output_rows(b, sub, s, modes, response.n_modes, requests)?;
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
            let (mut m0, mut m2) = (0.0, 0.0);
            for i in 1..freqs.len() {
                let h = freqs[i] - freqs[i - 1];
                m0 += 0.5 * h * (psd_values[i] + psd_values[i - 1]);
                m2 += 0.5
                    * h
                    * (freqs[i].powi(2) * psd_values[i] + freqs[i - 1].powi(2) * psd_values[i - 1]);
            }
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
