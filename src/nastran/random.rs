//! Random gust response of a Nastran model the way SOL 146 (NASTRAN-95's APP AERO SOL 11)
//! computes it: the modal frequency response to the GUST's downwash at the FREQ list's
//! frequencies, PSDs from RANDPS and TABRND1, RMS and zero-crossing rate N0 by the trapezoidal
//! rule over the frequency list, for grid displacements ("9T3"), accelerations ("ACCE 9T3")
//! and single-point constraint forces ("SPCF 11R3"), in the model's units.
//!
//! Per frequency f (ω = 2πf, k = ω REFC / 2V):
//!   [−ω² + iω 2ζᵢωᵢ + ωᵢ² − q Q_hh(ik)] η = q Q_hg(ik) α(f),   α(f) = WG · A · C(f) e^{iφ(f)}
//! with mass-normalized modes, ζᵢ = g(fᵢ)/2 from TABDMP1 (SDAMP), α the gust angle w_g/V that
//! the GUST card scales from its RLOAD1 (DAREA scale A, TABLED1 C(f), phase table D(f) in
//! degrees); displacements u = Φ η and constraint forces K_sg u − ω² M_sg u (the rows of the
//! constrained components). PSD_y = |y|² X · TABRND1(f); RMS = √∫PSD df, N0 = √(∫f²PSD df /
//! ∫PSD df).

use super::aero::{lifting_surfaces, modal_surface, spline_rows};
use super::bulk::{BulkData, DynamicLoad, Table};
use super::structure::{constrained, RealModes, Structure};
use super::{NastranError, Subcase};
use faer::c64;
use gustkit_core::{Aerodynamics, FlightCondition};

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

/// What to report: a grid component's displacement or constraint force.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Quantity {
    Displacement,
    Acceleration,
    SpcForce,
    /// The modal coordinate of a mode (1-based; the request's grid field holds it, the
    /// component is unused).
    Mode,
}

/// A table's value at x, linear between points and constant beyond the ends.
pub fn table_value(t: &Table, x: f64) -> f64 {
    let p = &t.points;
    if x <= p[0].0 {
        return p[0].1;
    }
    if x >= p[p.len() - 1].0 {
        return p[p.len() - 1].1;
    }
    let i = p
        .windows(2)
        .position(|w| x >= w[0].0 && x <= w[1].0)
        .unwrap_or(0);
    let (a, b) = (p[i], p[i + 1]);
    if b.0 == a.0 {
        return b.1;
    }
    a.1 + (b.1 - a.1) * (x - a.0) / (b.0 - a.0)
}

/// The component label of Nastran's printouts: T1–T3, R1–R3.
fn component_label(c: u8) -> String {
    if c <= 3 {
        format!("T{c}")
    } else {
        format!("R{}", c - 3)
    }
}

/// How the GAFs reach the frequencies of the response.
#[derive(Clone, Debug, PartialEq)]
pub enum KInterpolation {
    /// The DLM evaluated on these reduced frequencies (dense enough for the FREQ list's range)
    /// and spline-interpolated in k: gustkit's way.
    Dense(Vec<f64>),
    /// The DLM at MKAERO's reduced frequencies only, linear in k between them and the end
    /// segments' lines beyond (a linear interpolation of the aerodynamic matrix list), sampled
    /// on these reduced frequencies.
    LinearOnMkaero(Vec<f64>),
}

/// The random response of `requests` ((grid, component 1–6, quantity)) for subcase `sub`,
/// whose structure `s` and modes (`subcase_modes`) the caller has solved once.
pub fn random_response(
    b: &BulkData,
    sub: &Subcase,
    s: &Structure,
    modes: &RealModes,
    requests: &[(u32, u8, Quantity)],
    interpolation: &KInterpolation,
) -> R<Vec<RandomRow>> {
    let sel = |name: &str| -> R<u32> {
        sub.selections.get(name).copied().ok_or_else(|| {
            NastranError::model(
                "case control",
                format!(
                    "selects no {name}: a random gust response needs GUST, FREQUENCY and RANDOM"
                ),
            )
        })
    };
    let (gust_id, freq_id, random_id) = (sel("GUST")?, sel("FREQUENCY")?, sel("RANDOM")?);
    let n_modes = b
        .params
        .get("LMODES")
        .and_then(|v| v.parse::<usize>().ok())
        .unwrap_or(modes.lambda.len())
        .min(modes.lambda.len());
    let surf = lifting_surfaces(b, s)?;
    let (rows, _unmoved) = spline_rows(b, s, &surf)?;
    let ms = modal_surface(&surf, &rows, modes, n_modes);
    let gust = b.gusts.get(&gust_id).ok_or_else(|| {
        NastranError::model(
            &format!("GUST = {gust_id}"),
            "no GUST card has this id".into(),
        )
    })?;
    let load = b.dynamic_loads.get(&gust.dload).ok_or_else(|| {
        NastranError::model(
            &format!("GUST {gust_id}"),
            format!("its DLOAD {} is no RLOAD1", gust.dload),
        )
    })?;
    let DynamicLoad::Rload1 {
        excite,
        tc,
        td,
        delay,
        dphase,
        ..
    } = load
    else {
        return Err(NastranError::model(
            &format!("GUST {gust_id}"),
            "a random response needs an RLOAD1 for its DLOAD (TLOAD1 is for transient response)"
                .into(),
        ));
    };
    if delay.is_some() || dphase.is_some() {
        return Err(NastranError::model(
            &format!("RLOAD1 {}", gust.dload),
            "DELAY and DPHASE are not read (the gust's phase comes from X0 and the box positions)"
                .into(),
        ));
    }
    // the gust's scale A: one DAREA value (its point does not matter, the load is the gust's)
    let area = match b.darea.get(excite).map(|v| v.as_slice()) {
        None | Some([]) => 1.0,
        Some([(_, _, a)]) => *a,
        Some(v) => {
            if v.iter().any(|e| e.2 != v[0].2) {
                return Err(NastranError::model(
                    &format!("DAREA {excite}"),
                    "a GUST's load takes one scale factor: its DAREA entries give different ones"
                        .into(),
                ));
            }
            v[0].2
        }
    };
    let table = |id: &Option<u32>| -> R<Option<&Table>> {
        id.map(|t| {
            b.tables.get(&t).ok_or_else(|| {
                NastranError::model(
                    &format!("RLOAD1 {}", gust.dload),
                    format!("refers to table {t}, which the model does not define"),
                )
            })
        })
        .transpose()
    };
    let (c_table, d_table) = (table(tc)?, table(td)?);
    let freqs = b.freq.get(&freq_id).ok_or_else(|| {
        NastranError::model(
            &format!("FREQUENCY = {freq_id}"),
            "no FREQ, FREQ1 or FREQ2 card has this id".into(),
        )
    })?;
    let mut freqs = freqs.clone();
    freqs.sort_by(f64::total_cmp);
    freqs.dedup();
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
    let aero = b.aero.as_ref().expect("lifting_surfaces checked AERO");
    let velocity = gust.v;
    let q = match b.params.get("Q") {
        Some(v) => super::field::parse_real(v).ok_or_else(|| {
            NastranError::model("PARAM Q", format!("must be a real number (got '{v}')"))
        })?,
        None => 0.5 * aero.rhoref * velocity * velocity,
    };
    let mach = match b.params.get("MACH") {
        Some(v) => super::field::parse_real(v).ok_or_else(|| {
            NastranError::model("PARAM MACH", format!("must be a real number (got '{v}')"))
        })?,
        None => b.mkaero.first().map_or(0.0, |m| m.0),
    };
    // modal damping ζ = g(f_n)/2 from the SDAMP table
    let g_of = |f: f64| -> R<f64> {
        match sub.selections.get("SDAMPING") {
            None => Ok(0.0),
            Some(id) => {
                let t = b
                    .tables
                    .get(id)
                    .filter(|t| t.card == "TABDMP1")
                    .ok_or_else(|| {
                        NastranError::model(
                            &format!("SDAMP = {id}"),
                            "no TABDMP1 has this id".into(),
                        )
                    })?;
                let v = table_value(t, f);
                Ok(match t.damping_type.as_str() {
                    "CRIT" => 2.0 * v,
                    "Q" => 1.0 / v,
                    _ => v,
                })
            }
        }
    };
    let freq_hz = modes.freq_hz();
    let zetas: Vec<f64> = (0..n_modes)
        .map(|m| g_of(freq_hz[m]).map(|g| 0.5 * g))
        .collect::<R<_>>()?;
    if zetas.windows(2).any(|w| (w[1] - w[0]).abs() > 1e-12) {
        return Err(NastranError::model("SDAMP", "modal damping that differs between modes is not read yet: give one value over the modes' frequencies".into()));
    }
    let flight = FlightCondition {
        mach,
        velocity,
        density: aero.rhoref,
        b_ref: surf.b_ref,
        x_ref: gust.x0,
    };
    let dlm_error = |e: gustkit_core::AeroError| NastranError::model("DLM", e.to_string());
    let table_gaf = match interpolation {
        KInterpolation::Dense(k) => surf.dlm.gafs(&flight, &ms, k).map_err(dlm_error)?,
        KInterpolation::LinearOnMkaero(k) => {
            let mut ks: Vec<f64> = b
                .mkaero
                .iter()
                .filter(|m| (m.0 - mach).abs() < 1e-9)
                .map(|m| m.1)
                .collect();
            ks.sort_by(f64::total_cmp);
            ks.dedup();
            if ks.is_empty() {
                return Err(NastranError::model(
                    "MKAERO1",
                    format!("has no reduced frequency at Mach {mach}"),
                ));
            }
            let coarse = surf.dlm.gafs(&flight, &ms, &ks).map_err(dlm_error)?;
            let mut t = surf.dlm.gafs(&flight, &ms, k).map_err(dlm_error)?;
            for (i, &kk) in k.iter().enumerate() {
                let seg = ks.windows(2).position(|w| kk >= w[0] && kk <= w[1]);
                let last = ks.len() - 1;
                let (a, bb, u) = match seg {
                    Some(j) => (j, j + 1, (kk - ks[j]) / (ks[j + 1] - ks[j])),
                    // beyond the ends: the end segments' lines, extrapolated
                    None if ks.len() == 1 => (0, 0, 0.0),
                    None if kk < ks[0] => (0, 1, (kk - ks[0]) / (ks[1] - ks[0])),
                    None => (
                        last - 1,
                        last,
                        (kk - ks[last - 1]) / (ks[last] - ks[last - 1]),
                    ),
                };
                let mix = |x: c64, y: c64| x * (1.0 - u) + y * u;
                for r in 0..t.q_ss[i].len() {
                    for c in 0..t.q_ss[i][r].len() {
                        t.q_ss[i][r][c] = mix(coarse.q_ss[a][r][c], coarse.q_ss[bb][r][c]);
                    }
                    t.q_gs[i][r] = mix(coarse.q_gs[a][r], coarse.q_gs[bb][r]);
                }
            }
            t
        }
    };
    let omega_n: Vec<f64> = modes.lambda[..n_modes]
        .iter()
        .map(|l| l.max(0.0).sqrt())
        .collect();
    // the frequencies with a load (a zero C(f), as at f = 0 for a free body, gives no response)
    let alpha = |f: f64| -> c64 {
        let c = c_table.map_or(1.0, |t| table_value(t, f));
        let phase = d_table.map_or(0.0, |t| table_value(t, f)).to_radians();
        c64::new(phase.cos(), phase.sin()) * (gust.wg * area * c)
    };
    let live: Vec<usize> = (0..freqs.len())
        .filter(|&i| alpha(freqs[i]).norm() > 0.0)
        .collect();
    let grid = crate::gust::FrequencyGrid {
        omega: live
            .iter()
            .map(|&i| 2.0 * std::f64::consts::PI * freqs[i])
            .collect(),
        weights: vec![0.0; live.len()],
    };
    let problem = crate::gust::GustProblem {
        grid,
        max_tail: 1.0,
        ..crate::gust::GustProblem::for_transient(
            omega_n,
            zetas.first().copied().unwrap_or(0.0),
            &table_gaf,
            q,
            velocity,
            vec![vec![0.0; n_modes]],
        )
    };
    let response = crate::gust::response::frequency_response(&problem)
        .map_err(|e| NastranError::model("frequency response", e.to_string()))?;
    let spc: std::collections::BTreeSet<usize> =
        constrained(s, b, sub.selections.get("SPC").copied())?;
    let mut out = Vec::new();
    for &(grid_id, comp, quantity) in requests {
        if quantity == Quantity::Mode && !(1..=n_modes).contains(&(grid_id as usize)) {
            return Err(NastranError::model(
                "SDISPLACEMENT",
                format!("asks for mode {grid_id}; the analysis keeps modes 1–{n_modes}"),
            ));
        }
        let dof = match quantity {
            Quantity::Mode => 0,
            _ => s.dof(grid_id, comp).ok_or_else(|| {
                NastranError::model(
                    "output request",
                    format!("names grid {grid_id}, which the model does not define"),
                )
            })?,
        };
        if quantity == Quantity::SpcForce && !spc.contains(&dof) {
            return Err(NastranError::model(
                "SPCFORCES",
                format!("component {comp} of grid {grid_id} is not constrained"),
            ));
        }
        // the output's row over the modes at ω: φ_dof, or (K − ω² M)[dof, :] Φ
        let (k_row, m_row): (Vec<f64>, Vec<f64>) = (0..n_modes)
            .map(|m| match quantity {
                Quantity::Displacement => (modes.phi_g[(dof, m)], 0.0),
                // ü = −ω² u
                Quantity::Acceleration => (0.0, modes.phi_g[(dof, m)]),
                Quantity::Mode => (if m + 1 == grid_id as usize { 1.0 } else { 0.0 }, 0.0),
                Quantity::SpcForce => {
                    let n = s.k_gg.nrows();
                    let kp: f64 = (0..n).map(|j| s.k_gg[(dof, j)] * modes.phi_g[(j, m)]).sum();
                    let mp: f64 = (0..n).map(|j| s.m_gg[(dof, j)] * modes.phi_g[(j, m)]).sum();
                    (kp, mp)
                }
            })
            .unzip();
        let mut psd_values = vec![0.0; freqs.len()];
        for (j, &i) in live.iter().enumerate() {
            let f = freqs[i];
            let w = 2.0 * std::f64::consts::PI * f;
            let y: c64 = (0..n_modes)
                .map(|m| response.eta[j][m] * (k_row[m] - w * w * m_row[m]))
                .sum::<c64>()
                * alpha(f);
            let s_in = psd.x * psd_table.map_or(1.0, |t| table_value(t, f));
            psd_values[i] = y.norm_sqr() * s_in;
        }
        let (mut m0, mut m2) = (0.0, 0.0);
        for i in 1..freqs.len() {
            let h = freqs[i] - freqs[i - 1];
            m0 += 0.5 * h * (psd_values[i] + psd_values[i - 1]);
            m2 += 0.5
                * h
                * (freqs[i].powi(2) * psd_values[i] + freqs[i - 1].powi(2) * psd_values[i - 1]);
        }
        let label = match quantity {
            Quantity::Displacement => format!("{grid_id}{}", component_label(comp)),
            Quantity::Acceleration => format!("ACCE {grid_id}{}", component_label(comp)),
            Quantity::Mode => format!("MODE {grid_id}"),
            Quantity::SpcForce => format!("SPCF {grid_id}{}", component_label(comp)),
        };
        out.push(RandomRow {
            label,
            rms: m0.sqrt(),
            n0_hz: if m0 > 0.0 { (m2 / m0).sqrt() } else { 0.0 },
            psd: psd_values,
            frequencies_hz: freqs.clone(),
        });
    }
    Ok(out)
}
