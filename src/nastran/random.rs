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

/// The gust's input spectrum of a RANDOM set: RANDPS's X times its TABRND1 (1 without one).
struct GustSpectrum<'a> {
    x: f64,
    table: Option<&'a super::bulk::Table>,
}

impl GustSpectrum<'_> {
    /// The input PSD at frequency f (Hz).
    fn at(&self, f: f64) -> f64 {
        self.x * self.table.map_or(1.0, |t| table_value(t, f))
    }
}

/// The RANDPS of the subcase's RANDOM set (exactly one) and its TABRND1.
fn gust_spectrum<'a>(b: &'a BulkData, sub: &Subcase) -> R<GustSpectrum<'a>> {
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
    let table = psd
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
    Ok(GustSpectrum { x: psd.x, table })
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
    let input = gust_spectrum(b, sub)?;
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
                .map(|(y, &f)| y.norm_sqr() * input.at(f))
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

/// A design direction of the modes: ∂λ and ∂φ (g-set, one column a mode, as
/// [`super::structure::mode_derivatives`] gives them) and the ∂K, ∂M they come from (the
/// constraint forces' rows need them).
pub struct ModeDirection<'a> {
    pub d_lambda: Vec<f64>,
    pub d_phi_g: faer::Mat<f64>,
    pub dk: &'a faer::Mat<f64>,
    pub dm: &'a faer::Mat<f64>,
}

/// One output's random response and its derivative along a [`ModeDirection`].
#[derive(Clone, Debug, PartialEq)]
pub struct RandomDerivative {
    pub label: String,
    pub rms: f64,
    pub n0_hz: f64,
    pub d_rms: f64,
    pub d_n0_hz: f64,
}

/// The derivatives of the RMS and N0 of `requests` along a design direction of the modes
/// (exact, forward mode): the GAF table's tangent from one table of the 2n shapes [φ | ∂φ]
/// (the DLM's GAFs are bilinear in the projecting and the moving shape, so
/// dQ_ss[m][n] = Q[n+m][n] + Q[m][n+n] and dQ_gs[m] = Q_gs[n+m]), dη from the modal problem's
/// factorizations, the rows' tangents (φ rows; the constraint forces' add ∂K φ and ∂M φ), and
/// the spectral moments' (linear in the PSD): dRMS = dm₀/(2 RMS), dN0 = (dm₂/m₀ − m₂ dm₀/m₀²)
/// /(2 N0). The modal damping is held fixed: an SDAMP table that is not flat at a retained
/// mode's frequency is refused. Monitor points are not among its outputs yet (their
/// aerodynamic part would need the box forces' tangent).
pub fn random_response_derivative(
    b: &BulkData,
    sub: &Subcase,
    s: &Structure,
    modes: &RealModes,
    requests: &[(u32, u8, Quantity)],
    interpolation: &KInterpolation,
    direction: &ModeDirection,
) -> R<Vec<RandomDerivative>> {
    let mut all = random_response_derivatives(
        b,
        sub,
        s,
        modes,
        requests,
        interpolation,
        std::slice::from_ref(direction),
    )?;
    Ok(all.remove(0))
}

/// [`random_response_derivative`] along several directions (one a design variable), the
/// response, the output rows and the input spectrum solved once for all of them.
pub fn random_response_derivatives(
    b: &BulkData,
    sub: &Subcase,
    s: &Structure,
    modes: &RealModes,
    requests: &[(u32, u8, Quantity)],
    interpolation: &KInterpolation,
    directions: &[ModeDirection],
) -> R<Vec<Vec<RandomDerivative>>> {
    let input = gust_spectrum(b, sub)?;
    let sol = super::response::gust_frequency_solution(b, sub, s, modes, interpolation)?;
    let n = sol.response.n_modes;
    if let Some(id) = sub.selections.get("SDAMPING") {
        if let Some(t) = b.tables.get(id) {
            for f in &modes.freq_hz()[..n] {
                let v = table_value(t, *f);
                let flat = [0.999_999, 1.000_001]
                    .iter()
                    .all(|c| (table_value(t, f * c) - v).abs() <= 1e-12 * v.abs());
                if !flat {
                    return Err(NastranError::model(
                        &format!("SDAMP = {id}"),
                        format!("its damping changes with frequency at {f:.4} Hz (a retained mode's): the derivative holds the modal damping fixed; give a table flat over the modes' frequencies"),
                    ));
                }
            }
        }
    }
    let rows = super::response::output_rows(b, sub, s, modes, n, requests)?;
    directions
        .iter()
        .map(|d| derivative_along(b, sub, s, modes, requests, (&input, &sol, &rows), d))
        .collect()
}

/// The derivatives of every output along one direction, from the solved response.
fn derivative_along(
    b: &BulkData,
    sub: &Subcase,
    s: &Structure,
    modes: &RealModes,
    requests: &[(u32, u8, Quantity)],
    (input, sol, rows): (
        &GustSpectrum,
        &super::response::GustSolution,
        &[super::response::OutputRow],
    ),
    direction: &ModeDirection,
) -> R<Vec<RandomDerivative>> {
    use faer::c64;
    let n = sol.response.n_modes;
    if direction.d_lambda.len() < n || direction.d_phi_g.ncols() < n {
        return Err(NastranError::model(
            "design direction",
            format!(
                "gives {} mode derivatives; the response keeps {n} modes",
                direction.d_lambda.len().min(direction.d_phi_g.ncols())
            ),
        ));
    }
    // the rows' tangents
    let moved = RealModes {
        phi_g: direction.d_phi_g.clone(),
        ..modes.clone()
    };
    let mut d_rows = super::response::output_rows(b, sub, s, &moved, n, requests)?;
    for (r, &(grid, comp, quantity)) in d_rows.iter_mut().zip(requests) {
        match quantity {
            Quantity::Mode => {
                r.k_row.iter_mut().for_each(|v| *v = 0.0);
            }
            Quantity::SpcForce => {
                let dof = s.dof(grid, comp).expect("output_rows checked the grid");
                let ng = s.k_gg.nrows();
                for m in 0..n {
                    r.k_row[m] += (0..ng)
                        .map(|j| direction.dk[(dof, j)] * modes.phi_g[(j, m)])
                        .sum::<f64>();
                    r.m_row[m] += (0..ng)
                        .map(|j| direction.dm[(dof, j)] * modes.phi_g[(j, m)])
                        .sum::<f64>();
                }
            }
            _ => {}
        }
    }
    // the GAF table's tangent from the table of [φ | ∂φ]
    let ng = modes.phi_g.nrows();
    let both = RealModes {
        phi_g: faer::Mat::from_fn(ng, 2 * n, |i, c| {
            if c < n {
                modes.phi_g[(i, c)]
            } else {
                direction.d_phi_g[(i, c - n)]
            }
        }),
        ..modes.clone()
    };
    let ms2 = super::aero::modal_surface(&sol.surf, &sol.rows, &both, 2 * n);
    let t2 = sol.gafs_of(b, &ms2)?;
    let mut d_table = t2.clone();
    for i in 0..t2.k.len() {
        d_table.q_ss[i] = (0..n)
            .map(|m| {
                (0..n)
                    .map(|c| t2.q_ss[i][n + m][c] + t2.q_ss[i][m][n + c])
                    .collect()
            })
            .collect();
        d_table.q_gs[i] = (0..n).map(|m| t2.q_gs[i][n + m]).collect();
    }
    let d_eta = sol.eta_jvp(&d_table, &direction.d_lambda[..n])?;
    let r = &sol.response;
    let freqs = &r.frequencies_hz;
    let mut grid_index = vec![None; freqs.len()];
    for (j, &i) in sol.live.iter().enumerate() {
        grid_index[i] = Some(j);
    }
    rows.iter()
        .zip(&d_rows)
        .map(|(row, d_row)| {
            // y(f) as the response gives it, and its tangent
            let ys = r.output(row);
            let (mut psd, mut d_psd) = (vec![0.0; freqs.len()], vec![0.0; freqs.len()]);
            for (i, &f) in freqs.iter().enumerate() {
                let (Some(eta), Some(j)) = (&r.eta[i], grid_index[i]) else {
                    continue;
                };
                let w2 = (2.0 * std::f64::consts::PI * f).powi(2);
                let dy = (0..n)
                    .map(|m| {
                        d_eta[j][m] * (row.k_row[m] - w2 * row.m_row[m])
                            + eta[m] * (d_row.k_row[m] - w2 * d_row.m_row[m])
                    })
                    .sum::<c64>()
                    * r.load[i];
                let x = input.at(f);
                psd[i] = ys[i].norm_sqr() * x;
                d_psd[i] = 2.0 * (ys[i].conj() * dy).re * x;
            }
            let (m0, m2) = spectral_moments(freqs, &psd);
            let (dm0, dm2) = spectral_moments(freqs, &d_psd);
            let rms = m0.sqrt();
            let n0 = if m0 > 0.0 { (m2 / m0).sqrt() } else { 0.0 };
            Ok(RandomDerivative {
                label: row.label.clone(),
                rms,
                n0_hz: n0,
                d_rms: if rms > 0.0 { dm0 / (2.0 * rms) } else { 0.0 },
                d_n0_hz: if n0 > 0.0 {
                    (dm2 / m0 - m2 * dm0 / (m0 * m0)) / (2.0 * n0)
                } else {
                    0.0
                },
            })
        })
        .collect()
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
