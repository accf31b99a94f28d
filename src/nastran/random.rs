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
use super::response::table_value;
pub use super::response::{KInterpolation, Quantity};
use super::structure::{RealModes, Structure};
use super::{NastranError, Subcase};

type R<T> = Result<T, NastranError>;

/// The LFD in place of the panels' DLM (shared: one model serves every design's response).
pub type Lfd = std::sync::Arc<super::lfd::NastranLfd>;

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

/// The weights of [`spectral_moments`]: m₀ = Σ w₀ᵢ PSDᵢ and m₂ = Σ w₂ᵢ PSDᵢ (the moments are
/// linear in the PSD), for the reverse mode.
pub fn spectral_moment_weights(freqs: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let n = freqs.len();
    let (mut w0, mut w2) = (vec![0.0; n], vec![0.0; n]);
    for i in 1..n {
        let (fa, fb) = (freqs[i - 1], freqs[i]);
        let h = fb - fa;
        w0[i - 1] += 0.5 * h;
        w0[i] += 0.5 * h;
        w2[i - 1] += h * (3.0 * fa * fa + 2.0 * fa * fb + fb * fb) / 12.0;
        w2[i] += h * (fa * fa + 2.0 * fa * fb + 3.0 * fb * fb) / 12.0;
    }
    (w0, w2)
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

/// The PSD |y|² X(f) of one output's complex response y(f) on the frequency list.
fn psd_of(ys: &[faer::c64], freqs: &[f64], input: &GustSpectrum) -> Vec<f64> {
    ys.iter()
        .zip(freqs)
        .map(|(y, &f)| y.norm_sqr() * input.at(f))
        .collect()
}

/// RMS = √m₀ and N0 = √(m₂/m₀) (0 where m₀ is).
fn rms_and_n0(m0: f64, m2: f64) -> (f64, f64) {
    (m0.sqrt(), if m0 > 0.0 { (m2 / m0).sqrt() } else { 0.0 })
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
    random_response_with(b, sub, s, modes, requests, interpolation, None)
}

/// [`random_response`] with the GAFs from the LFD in place of the panels' DLM.
pub fn random_response_with(
    b: &BulkData,
    sub: &Subcase,
    s: &Structure,
    modes: &RealModes,
    requests: &[(u32, u8, Quantity)],
    interpolation: &KInterpolation,
    lfd: Option<Lfd>,
) -> R<(Vec<RandomRow>, Vec<String>)> {
    let input = gust_spectrum(b, sub)?;
    let response =
        super::response::gust_frequency_solution_with(b, sub, s, modes, interpolation, lfd)?
            .response;
    let rows = response.rows(b, sub, s, modes, requests)?;
    let freqs = &response.frequencies_hz;
    let out = rows
        .iter()
        .map(|row| {
            let psd_values = psd_of(&response.output(row), freqs, &input);
            let (m0, m2) = spectral_moments(freqs, &psd_values);
            let (rms, n0_hz) = rms_and_n0(m0, m2);
            RandomRow {
                label: row.label.clone(),
                rms,
                n0_hz,
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
/// mode's frequency is refused. The model's monitor points follow the requests among the
/// outputs (their aerodynamic part through the box forces of ∂φ, their inertial part through
/// −lᵀ(∂M φ + M ∂φ)).
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
        None,
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
    lfd: Option<Lfd>,
    directions: &[ModeDirection],
) -> R<Vec<Vec<RandomDerivative>>> {
    let prepared = prepare(b, sub, s, modes, requests, (interpolation, lfd))?;
    directions
        .iter()
        .map(|d| derivative_along(b, sub, s, modes, requests, &prepared, d))
        .collect()
}

/// What both derivative modes start from: the input spectrum, the solved response, the rows
/// of the requests and monitor points, and the monitors as functionals.
struct Prepared<'a> {
    input: GustSpectrum<'a>,
    sol: super::response::GustSolution,
    rows: Vec<super::response::OutputRow>,
    monitors: Vec<super::response::MonitorFunctional>,
    /// Each row's complex response y(f) on the FREQ list.
    outputs: Vec<Vec<faer::c64>>,
    /// The modal problem's grid index of each FREQ-list frequency with a load.
    grid_index: Vec<Option<usize>>,
}

/// The response solved once for the derivatives, with their checks (flat modal damping, the
/// MASS normalization of modal coordinates).
fn prepare<'a>(
    b: &'a BulkData,
    sub: &Subcase,
    s: &Structure,
    modes: &RealModes,
    requests: &[(u32, u8, Quantity)],
    (interpolation, lfd): (&KInterpolation, Option<Lfd>),
) -> R<Prepared<'a>> {
    let input = gust_spectrum(b, sub)?;
    let sol = super::response::gust_frequency_solution_with(b, sub, s, modes, interpolation, lfd)?;
    let n = sol.response.n_modes;
    check_flat_damping(b, sub, modes, n)?;
    check_mode_norm(b, sub, requests)?;
    let mut rows = super::response::output_rows(b, sub, s, modes, n, requests)?;
    rows.extend(sol.response.monitor_rows.iter().cloned());
    let monitors = monitors_of(b, s, &sol)?;
    let outputs = rows.iter().map(|row| sol.response.output(row)).collect();
    let mut grid_index = vec![None; sol.response.frequencies_hz.len()];
    for (j, &i) in sol.live.iter().enumerate() {
        grid_index[i] = Some(j);
    }
    Ok(Prepared {
        input,
        sol,
        rows,
        monitors,
        outputs,
        grid_index,
    })
}

/// The model's monitor components as functionals (none without MONPNT1).
fn monitors_of(
    b: &BulkData,
    s: &Structure,
    sol: &super::response::GustSolution,
) -> R<Vec<super::response::MonitorFunctional>> {
    if b.monitors.is_empty() {
        return Ok(Vec::new());
    }
    super::response::monitor_functionals(b, s, &sol.rows, sol.surf.box_ids.len())
}

/// lᵀ A (A a g-set matrix, l a g-set vector, mostly zeros).
fn row_of(l: &[f64], a: &faer::Mat<f64>) -> Vec<f64> {
    let ng = a.nrows();
    (0..ng)
        .map(|j| {
            (0..ng)
                .filter(|&i| l[i] != 0.0)
                .map(|i| l[i] * a[(i, j)])
                .sum()
        })
        .collect()
}

/// lᵀ A φ_m for every mode m < n.
fn paired(l: &[f64], a: &faer::Mat<f64>, phi: &faer::Mat<f64>, n: usize) -> Vec<f64> {
    let ng = a.nrows();
    let la = row_of(l, a);
    (0..n)
        .map(|m| (0..ng).map(|j| la[j] * phi[(j, m)]).sum())
        .collect()
}

/// The derivatives of every output along one direction, from the solved response.
fn derivative_along(
    b: &BulkData,
    sub: &Subcase,
    s: &Structure,
    modes: &RealModes,
    requests: &[(u32, u8, Quantity)],
    prepared: &Prepared,
    direction: &ModeDirection,
) -> R<Vec<RandomDerivative>> {
    use faer::c64;
    let Prepared {
        input,
        sol,
        rows,
        monitors,
        outputs,
        grid_index,
    } = prepared;
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
    // the monitor rows' tangents: m_row = −lᵀ M φ, so −lᵀ (∂M φ + M ∂φ)
    for f in monitors {
        let (a, c) = (
            paired(&f.l, direction.dm, &modes.phi_g, n),
            paired(&f.l, &s.m_gg, &direction.d_phi_g, n),
        );
        d_rows.push(super::response::OutputRow {
            label: f.label.clone(),
            k_row: vec![0.0; n],
            m_row: a.iter().zip(&c).map(|(x, y)| -(x + y)).collect(),
            aero: f.aero.clone(),
        });
    }
    let ng = modes.phi_g.nrows();
    // the box forces of ∂φ (the monitors' aerodynamic loads are linear in the shapes)
    let d_forces = if monitors.is_empty() {
        Vec::new()
    } else {
        let moved_surface = super::aero::modal_surface(&sol.surf, &sol.rows, &moved, n);
        sol.box_forces_of(&moved_surface)?
    };
    // the GAF table's tangent from the table of [φ | ∂φ]
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
    let ms2 = sol.modal_surface(&both, 2 * n);
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
    rows.iter()
        .zip(&d_rows)
        .zip(outputs)
        .map(|((row, d_row), ys)| {
            // y(f) as the response gives it, and its tangent
            let (mut psd, mut d_psd) = (vec![0.0; freqs.len()], vec![0.0; freqs.len()]);
            for (i, &f) in freqs.iter().enumerate() {
                let (Some(eta), Some(j)) = (&r.eta[i], grid_index[i]) else {
                    continue;
                };
                let w2 = (2.0 * std::f64::consts::PI * f).powi(2);
                let mut dy = (0..n)
                    .map(|m| {
                        d_eta[j][m] * (row.k_row[m] - w2 * row.m_row[m])
                            + eta[m] * (d_row.k_row[m] - w2 * d_row.m_row[m])
                    })
                    .sum::<c64>();
                if !row.aero.is_empty() {
                    // q Σ_boxes aero (Σ_m ∂F η_m + F ∂η_m)
                    let forces = r.box_forces[i]
                        .as_ref()
                        .expect("box forces where the model has monitor points");
                    for (box_j, (wj, fj)) in row.aero.iter().zip(forces).enumerate() {
                        if *wj != 0.0 {
                            let dfj = &d_forces[j][box_j];
                            let load = (0..n)
                                .map(|m| dfj[m] * eta[m] + fj[m] * d_eta[j][m])
                                .sum::<c64>();
                            dy += load * (r.q * wj);
                        }
                    }
                }
                let dy = dy * r.load[i];
                let x = input.at(f);
                psd[i] = ys[i].norm_sqr() * x;
                d_psd[i] = 2.0 * (ys[i].conj() * dy).re * x;
            }
            let (m0, m2) = spectral_moments(freqs, &psd);
            let (dm0, dm2) = spectral_moments(freqs, &d_psd);
            let (rms, n0) = rms_and_n0(m0, m2);
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

/// Seeds on the modes of a functional of the random response (the reverse mode of
/// [`random_response`] up to the modes): ∂J/∂λ, ∂J/∂φ (g-set) and, for the rows that pair the
/// matrices with the shapes — lᵀ K φ and lᵀ M φ of the constraint forces (l a unit vector) and
/// the monitor points (l their force summation) — the seeds per mode, which a design
/// direction's ∂K and ∂M meet directly.
#[derive(Clone, Debug)]
pub struct ModeSeeds {
    pub lambda: Vec<f64>,
    pub phi_g: faer::Mat<f64>,
    /// (l over the g-set, seed on lᵀKφ_m, seed on lᵀMφ_m per mode) of every such row.
    pub direct: Vec<(Vec<f64>, Vec<f64>, Vec<f64>)>,
}

/// The reverse mode of the RMS and N0 of `requests`: for each functional J = Σ_y (r̄_y RMS_y +
/// n̄_y N0_y) (`functionals[f][y] = (r̄_y, n̄_y)`), the seeds on the modes ([`ModeSeeds`]),
/// sharing the response: the spectral moments' and the PSD's transposes, η̄ per frequency, the
/// modal problem's adjoint (`FrequencyResponse::eta_vjp`), the DLM's reverse mode through the
/// splines' transpose, and the rows' own seeds. The modal damping is held fixed, as in the
/// forward mode; modal coordinates are supported in the MASS normalization only (a MAX one
/// moves with the shape).
pub fn random_response_vjp(
    b: &BulkData,
    sub: &Subcase,
    s: &Structure,
    modes: &RealModes,
    requests: &[(u32, u8, Quantity)],
    interpolation: &KInterpolation,
    lfd: Option<Lfd>,
    functionals: &[Vec<(f64, f64)>],
) -> R<Vec<ModeSeeds>> {
    use faer::c64;
    let Prepared {
        input,
        sol,
        rows,
        monitors,
        outputs,
        grid_index,
    } = prepare(b, sub, s, modes, requests, (interpolation, lfd))?;
    let n = sol.response.n_modes;
    let r = &sol.response;
    let freqs = &r.frequencies_hz;
    let (w0, w2) = spectral_moment_weights(freqs);
    let n_boxes = sol.surf.box_ids.len();
    let ms = sol.modal_surface(modes, n);
    functionals
        .iter()
        .map(|seeds| {
            if seeds.len() != rows.len() {
                return Err(NastranError::model(
                    "reverse mode",
                    format!("{} seeds for {} outputs", seeds.len(), rows.len()),
                ));
            }
            let zero = c64::new(0.0, 0.0);
            let mut eta_bar = vec![vec![zero; n]; sol.live.len()];
            // seeds on the box forces' modal columns, where monitors have seeds
            let mut force_bar = vec![vec![vec![zero; n + 1]; n_boxes]; sol.live.len()];
            let mut any_force = false;
            let mut k_bar = vec![vec![0.0; n]; rows.len()];
            let mut m_bar = vec![vec![0.0; n]; rows.len()];
            for (y, row) in rows.iter().enumerate() {
                let (rms_bar, n0_bar) = seeds[y];
                if rms_bar == 0.0 && n0_bar == 0.0 {
                    continue;
                }
                let ys = &outputs[y];
                let (m0, m2) = spectral_moments(freqs, &psd_of(ys, freqs, &input));
                let (rms, n0) = rms_and_n0(m0, m2);
                // RMS = √m₀, N0 = √(m₂/m₀)
                let mut m0_bar = if rms > 0.0 {
                    rms_bar / (2.0 * rms)
                } else {
                    0.0
                };
                let mut m2_bar = 0.0;
                if n0 > 0.0 {
                    m0_bar -= n0_bar * m2 / (2.0 * n0 * m0 * m0);
                    m2_bar += n0_bar / (2.0 * n0 * m0);
                }
                for (i, &f) in freqs.iter().enumerate() {
                    let (Some(eta), Some(j)) = (&r.eta[i], grid_index[i]) else {
                        continue;
                    };
                    // PSD = |y|² X: ȳ = 2 X PSD̄ y (conjugate convention)
                    let psd_bar = m0_bar * w0[i] + m2_bar * w2[i];
                    let y_bar = ys[i] * (2.0 * input.at(f) * psd_bar);
                    let w2f = (2.0 * std::f64::consts::PI * f).powi(2);
                    for m in 0..n {
                        let c = r.load[i] * (row.k_row[m] - w2f * row.m_row[m]);
                        eta_bar[j][m] += c.conj() * y_bar;
                        let t = (y_bar.conj() * r.load[i] * eta[m]).re;
                        k_bar[y][m] += t;
                        m_bar[y][m] -= w2f * t;
                    }
                    if !row.aero.is_empty() {
                        // y += load q Σ_boxes aero (Σ_m F η_m + F_g)
                        let forces = r.box_forces[i]
                            .as_ref()
                            .expect("box forces where the model has monitor points");
                        for (box_j, (wj, fj)) in row.aero.iter().zip(forces).enumerate() {
                            if *wj == 0.0 {
                                continue;
                            }
                            let c = r.load[i] * (r.q * wj);
                            for m in 0..n {
                                eta_bar[j][m] += (c * fj[m]).conj() * y_bar;
                                force_bar[j][box_j][m] += (c * eta[m]).conj() * y_bar;
                            }
                            any_force = true;
                        }
                    }
                }
            }
            let g = sol.eta_vjp(&eta_bar)?;
            let mut surface_bar = sol.gafs_vjp_of(b, &ms, &g.table)?;
            if any_force {
                let from_forces = sol.box_forces_vjp_of(&ms, &force_bar)?;
                for (t, v) in surface_bar.values_mut().zip(from_forces.values()) {
                    *t += v;
                }
            }
            let mut phi_g = sol.modal_surface_vjp(&surface_bar);
            let mut direct = Vec::new();
            for (y, &(grid, comp, quantity)) in requests.iter().enumerate() {
                if k_bar[y].iter().chain(&m_bar[y]).all(|v| *v == 0.0) {
                    continue;
                }
                let dof = || s.dof(grid, comp).expect("output_rows checked the grid");
                match quantity {
                    Quantity::Displacement => {
                        for m in 0..n {
                            phi_g[(dof(), m)] += k_bar[y][m];
                        }
                    }
                    Quantity::Acceleration => {
                        for m in 0..n {
                            phi_g[(dof(), m)] += m_bar[y][m];
                        }
                    }
                    // the MASS normalization's scale is 1, whatever the shape
                    Quantity::Mode => {}
                    Quantity::SpcForce => {
                        let d = dof();
                        for m in 0..n {
                            for j in 0..phi_g.nrows() {
                                phi_g[(j, m)] +=
                                    k_bar[y][m] * s.k_gg[(d, j)] + m_bar[y][m] * s.m_gg[(d, j)];
                            }
                        }
                        let mut l = vec![0.0; phi_g.nrows()];
                        l[d] = 1.0;
                        direct.push((l, k_bar[y].clone(), m_bar[y].clone()));
                    }
                }
            }
            // the monitor rows: m_row = −lᵀ M φ
            for (f, y) in monitors.iter().zip(requests.len()..) {
                if m_bar[y].iter().all(|v| *v == 0.0) {
                    continue;
                }
                let ng = phi_g.nrows();
                let m_l = row_of(&f.l, &s.m_gg);
                for m in 0..n {
                    for j in 0..ng {
                        phi_g[(j, m)] -= m_bar[y][m] * m_l[j];
                    }
                }
                let minus: Vec<f64> = m_bar[y].iter().map(|v| -v).collect();
                direct.push((f.l.clone(), vec![0.0; n], minus));
            }
            Ok(ModeSeeds {
                lambda: g.lambda,
                phi_g,
                direct,
            })
        })
        .collect()
}

/// Refuses a derivative through an SDAMP table that is not flat at a retained mode's frequency
/// (the derivatives hold the modal damping fixed).
fn check_flat_damping(b: &BulkData, sub: &Subcase, modes: &RealModes, n: usize) -> R<()> {
    let Some(id) = sub.selections.get("SDAMPING") else {
        return Ok(());
    };
    let Some(t) = b.tables.get(id) else {
        return Ok(());
    };
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
    Ok(())
}

/// Refuses a derivative of modal coordinates in the MAX normalization (its scale, the shape's
/// largest component, moves with the design).
fn check_mode_norm(b: &BulkData, sub: &Subcase, requests: &[(u32, u8, Quantity)]) -> R<()> {
    let norm = sub
        .selections
        .get("METHOD")
        .and_then(|m| b.eigr.get(m))
        .map_or("MASS", |e| e.norm.as_str());
    if requests.iter().any(|r| r.2 == Quantity::Mode) && norm == "MAX" {
        return Err(NastranError::model(
            "SDISPLACEMENT",
            "derivatives of modal coordinates are taken in the MASS normalization: NORM MAX scales them by the shape's largest component, which moves with the design; give the EIGR/EIGRL NORM MASS".into(),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::spectral_moments;

    /// The weights reproduce the moments on an uneven list to 1e-14.
    #[test]
    fn moment_weights_match_the_moments() {
        let f = [0.5, 0.7, 1.3, 2.0, 2.2, 3.0];
        let s = [0.3, 1.7, 0.2, 4.0, 0.9, 0.1];
        let (m0, m2) = spectral_moments(&f, &s);
        let (w0, w2) = super::spectral_moment_weights(&f);
        let dot = |w: &[f64]| w.iter().zip(&s).map(|(a, b)| a * b).sum::<f64>();
        assert!((dot(&w0) - m0).abs() < 1e-14 * m0);
        assert!((dot(&w2) - m2).abs() < 1e-14 * m2);
    }

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
