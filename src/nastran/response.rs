//! The modal frequency response of a Nastran model to its GUST card: what SOL 146 (NASTRAN-95's
//! APP AERO SOL 11) solves before it forms PSDs (RANDOM, `random.rs`) or time histories by the
//! inverse Fourier transform (TSTEP, `transient.rs`).
//!
//! Per frequency f of the FREQ list (ω = 2πf, k = ω REFC / 2V):
//!   [−ω² + iω 2ζᵢωᵢ + ωᵢ² − q Q_hh(ik)] η = q Q_hg(ik) α(f)
//! with mass-normalized modes, ζᵢ = g(fᵢ)/2 from TABDMP1 (SDAMP) and α the gust angle w_g/V at X0:
//!   RLOAD1:  α(f) = WG · C(f) e^{iD(f)}          (tables TC and TD, D in degrees)
//!   TLOAD1:  α(f) = WG · ∫ T(t) e^{−iωt} dt · e^{−iωτ}   (table TID, exact for its segments)
//! The DAREA that the load names is not a gust's scale: NASTRAN-95 sets its amplitude to 1 for a
//! gust load (FRLGA), and so does gustkit (a value other than 1 is reported in a warning). The
//! transform takes the table as zero outside its range, as NASTRAN-95's TAB1 does. Outputs:
//! displacements u = Φ η, accelerations −ω² u, constraint forces K_sg u − ω² M_sg u (the rows of
//! the constrained components) and modal coordinates.

use super::aero::{lifting_surfaces, modal_surface, spline_rows};
use super::bulk::{BulkData, DynamicLoad, Table};
use super::structure::{constrained, RealModes, Structure};
use super::{NastranError, Subcase};
use faer::c64;
use gustkit_core::{Aerodynamics, FlightCondition};

type R<T> = Result<T, NastranError>;

/// What to report: a grid component's displacement, acceleration or constraint force, or a
/// modal coordinate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Quantity {
    Displacement,
    Acceleration,
    SpcForce,
    /// The modal coordinate of a mode (1-based; the request's grid field holds it, the
    /// component is unused).
    Mode,
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

impl KInterpolation {
    /// The reduced frequencies the GAF table is sampled on.
    pub fn reduced_frequencies(&self) -> &[f64] {
        match self {
            KInterpolation::Dense(k) | KInterpolation::LinearOnMkaero(k) => k,
        }
    }
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

/// G(θ) = ∫₀¹ (1 − u) e^{−iθu} du = (1 − iθ − e^{−iθ}) / θ²: the weight of a segment's left end
/// in the exact transform of a linear piece (its series below |θ| = 1e-2, where the closed form
/// cancels).
pub fn hat_weight(theta: f64) -> c64 {
    if theta.abs() < 1e-2 {
        let t2 = theta * theta;
        // 1/2 − iθ/6 − θ²/24 + iθ³/120 + θ⁴/720 (next term θ⁵/5040 < 2e-14)
        c64::new(
            0.5 - t2 / 24.0 + t2 * t2 / 720.0,
            -theta / 6.0 + theta * t2 / 120.0,
        )
    } else {
        let e = c64::new(theta.cos(), -theta.sin());
        (c64::new(1.0, -theta) - e) / (theta * theta)
    }
}

/// ∫ T(t) e^{−iωt} dt of a piecewise-linear table, zero outside its range: exact per segment,
///   h [T_a e^{−iωt_a} G(ωh) + T_b e^{−iωt_b} conj G(ωh)].
pub fn table_transform(t: &Table, omega: f64) -> c64 {
    let mut sum = c64::new(0.0, 0.0);
    for w in t.points.windows(2) {
        let ((xa, ya), (xb, yb)) = (w[0], w[1]);
        let h = xb - xa;
        if h <= 0.0 {
            continue;
        }
        let g = hat_weight(omega * h);
        let ea = c64::new((omega * xa).cos(), -(omega * xa).sin());
        let eb = c64::new((omega * xb).cos(), -(omega * xb).sin());
        sum += (ea * g * ya + eb * g.conj() * yb) * h;
    }
    sum
}

/// The component label of Nastran's printouts: T1–T3, R1–R3.
fn component_label(c: u8) -> String {
    if c <= 3 {
        format!("T{c}")
    } else {
        format!("R{}", c - 3)
    }
}

/// One output as a row over the modes and the boxes:
///   y(ω) = Σₘ (k_row[m] − ω² m_row[m]) ηₘ(ω) + q Σⱼ aero[j] (Σₘ F_jm(k) ηₘ + F_jg(k)),
/// F the boxes' normal forces per unit q (`Dlm::box_forces`); `aero` is empty but for monitor
/// points.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputRow {
    /// Nastran's label: `9T3`, `ACCE 9T3`, `SPCF 11R3`, `MODE 2`, `ROOT CMX`.
    pub label: String,
    pub k_row: Vec<f64>,
    pub m_row: Vec<f64>,
    pub aero: Vec<f64>,
}

/// The modal response to the subcase's gust on its FREQ list.
#[derive(Clone, Debug)]
pub struct GustFrequencyResponse {
    /// The FREQ list, sorted, without repeats (Hz).
    pub frequencies_hz: Vec<f64>,
    /// The gust angle α(f) at each frequency.
    pub load: Vec<c64>,
    /// η per unit gust angle at each frequency (None where α = 0: no response to solve).
    pub eta: Vec<Option<Vec<c64>>>,
    /// The modes kept (PARAM LMODES).
    pub n_modes: usize,
    /// The dynamic pressure.
    pub q: f64,
    /// The boxes' normal forces per unit q at each frequency with a load (`[box][column]`,
    /// modes then the gust), where the model has monitor points.
    pub box_forces: Vec<Option<Vec<Vec<c64>>>>,
    /// One row a component of every MONPNT1 of the model.
    pub monitor_rows: Vec<OutputRow>,
    /// What the reading noticed and let pass (one line each).
    pub warnings: Vec<String>,
}

impl GustFrequencyResponse {
    /// The rows of `requests` (`output_rows`) followed by the model's monitor points.
    pub fn rows(
        &self,
        b: &BulkData,
        sub: &Subcase,
        s: &Structure,
        modes: &RealModes,
        requests: &[(u32, u8, Quantity)],
    ) -> R<Vec<OutputRow>> {
        let mut rows = output_rows(b, sub, s, modes, self.n_modes, requests)?;
        rows.extend(self.monitor_rows.iter().cloned());
        Ok(rows)
    }

    /// The output's complex response y(f) at every frequency (zero where there is no load).
    pub fn output(&self, row: &OutputRow) -> Vec<c64> {
        self.frequencies_hz
            .iter()
            .zip(&self.eta)
            .zip(&self.load)
            .enumerate()
            .map(|(i, ((&f, eta), &a))| match eta {
                None => c64::new(0.0, 0.0),
                Some(eta) => {
                    let w2 = (2.0 * std::f64::consts::PI * f).powi(2);
                    let mut y = eta
                        .iter()
                        .zip(row.k_row.iter().zip(&row.m_row))
                        .map(|(e, (k, m))| e * (k - w2 * m))
                        .sum::<c64>();
                    if !row.aero.is_empty() {
                        let forces = self.box_forces[i]
                            .as_ref()
                            .expect("box forces where the model has monitor points");
                        for (wj, fj) in row.aero.iter().zip(forces) {
                            if *wj != 0.0 {
                                let (modal, gust) = fj.split_at(self.n_modes);
                                let load = modal.iter().zip(eta).map(|(f, e)| f * e).sum::<c64>()
                                    + gust[0];
                                y += load * (self.q * wj);
                            }
                        }
                    }
                    y * a
                }
            })
            .collect()
    }
}

/// A real PARAM, or None where the model does not give it.
fn real_param(b: &BulkData, name: &str) -> R<Option<f64>> {
    b.params
        .get(name)
        .map(|v| {
            super::field::parse_real(v).ok_or_else(|| {
                NastranError::model(
                    &format!("PARAM {name}"),
                    format!("must be a real number (got '{v}')"),
                )
            })
        })
        .transpose()
}

/// Solves the subcase's gust response on its FREQ list: GUST → DLOAD (RLOAD1 for a frequency
/// or random response, TLOAD1 for a transient one) → α(f); the GAFs of the model's CAERO1
/// surfaces through its splines; η at every frequency with a load.
pub fn gust_frequency_response(
    b: &BulkData,
    sub: &Subcase,
    s: &Structure,
    modes: &RealModes,
    interpolation: &KInterpolation,
) -> R<GustFrequencyResponse> {
    Ok(gust_frequency_solution(b, sub, s, modes, interpolation)?.response)
}

/// What [`gust_frequency_response`] solved, kept for the response's derivatives: the lifting
/// surfaces and their spline rows, the GAF table and the modal problem with its factorizations.
pub struct GustSolution {
    pub response: GustFrequencyResponse,
    pub surf: super::aero::LiftingSurfaces,
    pub rows: super::spline::SplineRows,
    flight: FlightCondition,
    mach: f64,
    interpolation: KInterpolation,
    table: gustkit_core::GafTable,
    omega_n: Vec<f64>,
    zeta: f64,
    velocity: f64,
    grid: crate::gust::FrequencyGrid,
    /// The FREQ list's indices of the grid's frequencies (those with a load).
    pub live: Vec<usize>,
    fr: crate::gust::response::FrequencyResponse,
    /// The LFD in place of the panels' DLM, if the study asks for it.
    pub lfd: Option<std::sync::Arc<super::lfd::NastranLfd>>,
}

impl GustSolution {
    /// The modal problem solved (Eq. 16 on the FREQ list's loaded frequencies).
    pub fn problem(&self) -> crate::gust::GustProblem<'_> {
        modal_problem(
            self.omega_n.clone(),
            self.zeta,
            &self.table,
            (self.response.q, self.velocity),
            self.grid.clone(),
        )
    }

    /// The modes on the surface of the fidelity the GAFs come from (the DLM's points, or the
    /// LFD's wall points).
    pub fn modal_surface(&self, modes: &RealModes, n_modes: usize) -> gustkit_core::ModalSurface {
        match &self.lfd {
            Some(l) => l.modal_surface(modes, n_modes),
            None => super::aero::modal_surface(&self.surf, &self.rows, modes, n_modes),
        }
    }

    /// The transpose of [`GustSolution::modal_surface`].
    pub fn modal_surface_vjp(&self, seed: &gustkit_core::ModalSurface) -> faer::Mat<f64> {
        match &self.lfd {
            Some(l) => l.modal_surface_vjp(seed),
            None => super::aero::modal_surface_vjp(&self.surf, &self.rows, seed),
        }
    }

    /// The GAF table of any modal surface of this model on the solution's reduced frequencies
    /// (the same k interpolation).
    pub fn gafs_of(
        &self,
        b: &BulkData,
        ms: &gustkit_core::ModalSurface,
    ) -> R<gustkit_core::GafTable> {
        gaf_table(
            b,
            (&self.surf, self.lfd.as_deref()),
            &self.flight,
            ms,
            &self.interpolation,
            self.mach,
        )
    }

    /// The reverse mode of [`GustSolution::gafs_of`]: seeds on the table to seeds on the modal
    /// surface.
    pub fn gafs_vjp_of(
        &self,
        b: &BulkData,
        ms: &gustkit_core::ModalSurface,
        seed: &gustkit_core::GafTable,
    ) -> R<gustkit_core::ModalSurface> {
        gaf_table_vjp(
            b,
            (&self.surf, self.lfd.as_deref()),
            &self.flight,
            ms,
            (&self.interpolation, self.mach),
            seed,
        )
    }

    /// The reduced frequencies of the loaded frequencies (`live`), where the box forces are
    /// taken.
    fn live_k(&self) -> Vec<f64> {
        self.live
            .iter()
            .map(|&i| {
                2.0 * std::f64::consts::PI * self.response.frequencies_hz[i] * self.surf.b_ref
                    / self.velocity
            })
            .collect()
    }

    /// The boxes' forces per unit q of any modal surface of this model at each loaded
    /// frequency (`[live][box][column]`, the modes then the gust).
    pub fn box_forces_of(&self, ms: &gustkit_core::ModalSurface) -> R<Vec<Vec<Vec<c64>>>> {
        self.surf
            .dlm
            .box_forces(&self.flight, ms, &self.live_k())
            .map_err(|e| NastranError::model("DLM", e.to_string()))
    }

    /// The reverse mode of [`GustSolution::box_forces_of`]: seeds on the forces (one a loaded
    /// frequency) to seeds on the modal surface.
    pub fn box_forces_vjp_of(
        &self,
        ms: &gustkit_core::ModalSurface,
        seeds: &[Vec<Vec<c64>>],
    ) -> R<gustkit_core::ModalSurface> {
        self.surf
            .dlm
            .box_forces_vjp(&self.flight, ms, &self.live_k(), seeds)
            .map_err(|e| NastranError::model("DLM", e.to_string()))
    }

    /// The reverse mode of η at the grid's frequencies (one seed a grid frequency, conjugate
    /// convention) to seeds on the GAF table and ω_n².
    pub fn eta_vjp(&self, eta_bar: &[Vec<c64>]) -> R<crate::gust::GustGradient> {
        self.fr
            .eta_vjp(&self.problem(), eta_bar)
            .map_err(|e| NastranError::model("frequency response", e.to_string()))
    }

    /// The forward mode of η at the grid's frequencies along the GAF table and ω_n².
    pub fn eta_jvp(&self, d_table: &gustkit_core::GafTable, d_lambda: &[f64]) -> R<Vec<Vec<c64>>> {
        self.fr
            .eta_jvp(&self.problem(), d_table, d_lambda)
            .map_err(|e| NastranError::model("frequency response", e.to_string()))
    }
}

/// Eq. 16 on a grid of loaded frequencies: the modes' ω_n and damping ratio, the GAF table,
/// (q, V); no outputs (the Nastran rows are applied to η by their own rule).
fn modal_problem(
    omega_n: Vec<f64>,
    zeta: f64,
    table: &gustkit_core::GafTable,
    (q, velocity): (f64, f64),
    grid: crate::gust::FrequencyGrid,
) -> crate::gust::GustProblem<'_> {
    let n_modes = omega_n.len();
    crate::gust::GustProblem {
        grid,
        max_tail: 1.0,
        ..crate::gust::GustProblem::for_transient(
            omega_n,
            zeta,
            table,
            q,
            velocity,
            vec![vec![0.0; n_modes]],
        )
    }
}

/// The GAF table of modal surface `ms` on the reduced frequencies of `interpolation`: the DLM
/// there (dense), or at MKAERO's k at `mach` and linear in k between them.
fn gaf_table(
    b: &BulkData,
    (surf, lfd): (
        &super::aero::LiftingSurfaces,
        Option<&super::lfd::NastranLfd>,
    ),
    flight: &FlightCondition,
    ms: &gustkit_core::ModalSurface,
    interpolation: &KInterpolation,
    mach: f64,
) -> R<gustkit_core::GafTable> {
    let dlm_error = |e: gustkit_core::AeroError| NastranError::model("DLM", e.to_string());
    // the panels' DLM, or the LFD in its mesh's frame (the table keeps the model's x_ref)
    let gafs = |k: &[f64]| -> R<gustkit_core::GafTable> {
        match lfd {
            None => surf.dlm.gafs(flight, ms, k).map_err(dlm_error),
            Some(l) => {
                let mut t = l
                    .model
                    .gafs(&l.flight(flight), ms, k)
                    .map_err(|e| NastranError::model("LFD", e.to_string()))?;
                t.x_ref = flight.x_ref;
                Ok(t)
            }
        }
    };
    Ok(match interpolation {
        KInterpolation::Dense(k) => gafs(k)?,
        KInterpolation::LinearOnMkaero(k) => {
            let ks = mkaero_k(b, mach)?;
            let coarse = gafs(&ks)?;
            // every entry comes from the MKAERO table: no DLM solve at the fine k
            gustkit_core::aero::check_reduced_frequencies(k).map_err(dlm_error)?;
            let mut t = gustkit_core::GafTable::zeros(flight, k, ms.n_modes());
            for (i, &kk) in k.iter().enumerate() {
                let (a, bb, u) = mkaero_segment(&ks, kk);
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
    })
}

/// The MKAERO reduced frequencies at `mach`, sorted, without repeats.
fn mkaero_k(b: &BulkData, mach: f64) -> R<Vec<f64>> {
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
    Ok(ks)
}

/// Where k lies on the sorted MKAERO list `ks`: the two entries it is linear between and its
/// fraction u of the way (beyond the ends, the end segments' lines, extrapolated).
fn mkaero_segment(ks: &[f64], kk: f64) -> (usize, usize, f64) {
    let seg = ks.windows(2).position(|w| kk >= w[0] && kk <= w[1]);
    let last = ks.len() - 1;
    match seg {
        Some(j) => (j, j + 1, (kk - ks[j]) / (ks[j + 1] - ks[j])),
        None if ks.len() == 1 => (0, 0, 0.0),
        None if kk < ks[0] => (0, 1, (kk - ks[0]) / (ks[1] - ks[0])),
        None => (
            last - 1,
            last,
            (kk - ks[last - 1]) / (ks[last] - ks[last - 1]),
        ),
    }
}

/// The reverse mode of [`gaf_table`]: seeds on the table (its reduced frequencies, conjugate
/// convention) to seeds on the modal surface's displacements and slopes, through the DLM's
/// reverse mode (and, on MKAERO's k, the transposed linear interpolation).
fn gaf_table_vjp(
    b: &BulkData,
    (surf, lfd): (
        &super::aero::LiftingSurfaces,
        Option<&super::lfd::NastranLfd>,
    ),
    flight: &FlightCondition,
    ms: &gustkit_core::ModalSurface,
    (interpolation, mach): (&KInterpolation, f64),
    seed: &gustkit_core::GafTable,
) -> R<gustkit_core::ModalSurface> {
    use gustkit_core::AerodynamicsReverse;
    let dlm_error = |e: gustkit_core::AeroError| NastranError::model("DLM", e.to_string());
    let vjp = |k: &[f64], seed: &gustkit_core::GafTable| match lfd {
        None => surf.dlm.gafs_vjp(flight, ms, k, seed),
        Some(l) => {
            let reverse = l.model.reverse().ok_or_else(|| {
                gustkit_core::AeroError::Input("the LFD model has no reverse mode".into())
            })?;
            reverse.gafs_vjp(&l.flight(flight), ms, k, seed)
        }
    };
    let g = match interpolation {
        KInterpolation::Dense(k) => vjp(k, seed),
        KInterpolation::LinearOnMkaero(k) => {
            let ks = mkaero_k(b, mach)?;
            let n = ms.n_modes();
            let mut coarse = gustkit_core::GafTable::zeros(flight, &ks, n);
            for (i, &kk) in k.iter().enumerate() {
                let (a, bb, u) = mkaero_segment(&ks, kk);
                for r in 0..n {
                    for c in 0..n {
                        coarse.q_ss[a][r][c] += seed.q_ss[i][r][c] * (1.0 - u);
                        coarse.q_ss[bb][r][c] += seed.q_ss[i][r][c] * u;
                    }
                    coarse.q_gs[a][r] += seed.q_gs[i][r] * (1.0 - u);
                    coarse.q_gs[bb][r] += seed.q_gs[i][r] * u;
                }
            }
            vjp(&ks, &coarse)
        }
    };
    Ok(g.map_err(dlm_error)?.modes)
}

/// The flight condition of a subcase's gust response: Mach (PARAM MACH, else the first
/// MKAERO's), the GUST's velocity and X0, AERO's reference density and semichord.
pub fn subcase_flight(b: &BulkData, sub: &Subcase) -> R<FlightCondition> {
    let gust_id = sub.selections.get("GUST").copied().ok_or_else(|| {
        NastranError::model(
            "case control",
            "selects no GUST: a gust response needs GUST and FREQUENCY".into(),
        )
    })?;
    let gust = b.gusts.get(&gust_id).ok_or_else(|| {
        NastranError::model(
            &format!("GUST = {gust_id}"),
            "no GUST card has this id".into(),
        )
    })?;
    let aero = b
        .aero
        .as_ref()
        .ok_or_else(|| NastranError::model("bulk data", "has no AERO card".into()))?;
    Ok(FlightCondition {
        mach: real_param(b, "MACH")?.unwrap_or_else(|| b.mkaero.first().map_or(0.0, |m| m.0)),
        velocity: gust.v,
        density: aero.rhoref,
        b_ref: 0.5 * aero.refc,
        x_ref: gust.x0,
    })
}

/// [`gust_frequency_response`] with what it solved kept ([`GustSolution`]).
pub fn gust_frequency_solution(
    b: &BulkData,
    sub: &Subcase,
    s: &Structure,
    modes: &RealModes,
    interpolation: &KInterpolation,
) -> R<GustSolution> {
    gust_frequency_solution_with(b, sub, s, modes, interpolation, None)
}

/// [`gust_frequency_solution`] with the GAFs from `lfd` in place of the panels' DLM (built for
/// this model by [`super::lfd::NastranLfd::build`]).
pub fn gust_frequency_solution_with(
    b: &BulkData,
    sub: &Subcase,
    s: &Structure,
    modes: &RealModes,
    interpolation: &KInterpolation,
    lfd: Option<std::sync::Arc<super::lfd::NastranLfd>>,
) -> R<GustSolution> {
    let sel = |name: &str| -> R<u32> {
        sub.selections.get(name).copied().ok_or_else(|| {
            NastranError::model(
                "case control",
                format!("selects no {name}: a gust response needs GUST and FREQUENCY"),
            )
        })
    };
    let (gust_id, freq_id) = (sel("GUST")?, sel("FREQUENCY")?);
    let n_modes = b
        .params
        .get("LMODES")
        .and_then(|v| v.parse::<usize>().ok())
        .unwrap_or(modes.lambda.len())
        .min(modes.lambda.len());
    if n_modes == 0 {
        return Err(NastranError::model(
            "PARAM LMODES",
            "keeps no mode (or the eigenvalue method found none): a gust response needs at least one"
                .into(),
        ));
    }
    let surf = lifting_surfaces(b, s)?;
    let (rows, _unmoved) = spline_rows(b, s, &surf)?;
    let ms = match &lfd {
        Some(l) => l.modal_surface(modes, n_modes),
        None => modal_surface(&surf, &rows, modes, n_modes),
    };
    let gust = b.gusts.get(&gust_id).ok_or_else(|| {
        NastranError::model(
            &format!("GUST = {gust_id}"),
            "no GUST card has this id".into(),
        )
    })?;
    let load = b.dynamic_loads.get(&gust.dload).ok_or_else(|| {
        NastranError::model(
            &format!("GUST {gust_id}"),
            format!("its DLOAD {} is no RLOAD1 or TLOAD1", gust.dload),
        )
    })?;
    let table = |id: u32, card: &str| -> R<&Table> {
        b.tables.get(&id).ok_or_else(|| {
            NastranError::model(
                &format!("{card} {}", gust.dload),
                format!("refers to table {id}, which the model does not define"),
            )
        })
    };
    let mut warnings = Vec::new();
    let mut darea_note = |excite: u32, card: &str| {
        if let Some(v) = b.darea.get(&excite) {
            if v.iter().any(|e| e.2 != 1.0) {
                warnings.push(format!(
                    "{card} {}: the amplitude of its DAREA {excite} ({}) is not applied to the gust: a gust load's scale is the GUST card's WG (NASTRAN-95 sets the DAREA amplitude of a gust load to 1)",
                    gust.dload, v[0].2
                ));
            }
        }
    };
    // α(f) / WG
    let shape: Box<dyn Fn(f64) -> c64> = match load {
        DynamicLoad::Rload1 {
            excite,
            tc,
            td,
            delay,
            dphase,
            ..
        } => {
            if delay.is_some() || dphase.is_some() {
                return Err(NastranError::model(
                    &format!("RLOAD1 {}", gust.dload),
                    "DELAY and DPHASE are not read (the gust's phase comes from X0 and the box positions)"
                        .into(),
                ));
            }
            darea_note(*excite, "RLOAD1");
            let c_table = tc.map(|t| table(t, "RLOAD1")).transpose()?;
            let d_table = td.map(|t| table(t, "RLOAD1")).transpose()?;
            Box::new(move |f| {
                let c = c_table.map_or(1.0, |t| table_value(t, f));
                let phase = d_table.map_or(0.0, |t| table_value(t, f)).to_radians();
                c64::new(phase.cos(), phase.sin()) * c
            })
        }
        DynamicLoad::Tload1 {
            excite,
            delay,
            kind,
            tid,
            ..
        } => {
            if *kind != 0 {
                return Err(NastranError::model(
                    &format!("TLOAD1 {}", gust.dload),
                    format!("TYPE {kind} (an enforced motion) cannot drive a gust: leave TYPE blank or 0 (a load)"),
                ));
            }
            if delay.is_some() {
                return Err(NastranError::model(
                    &format!("TLOAD1 {}", gust.dload),
                    "DELAY is not read (the gust's timing comes from X0 and its table)".into(),
                ));
            }
            darea_note(*excite, "TLOAD1");
            let t = table(*tid, "TLOAD1")?;
            if t.card != "TABLED1" || t.x_axis != "LINEAR" || t.y_axis != "LINEAR" {
                return Err(NastranError::model(
                    &format!("TLOAD1 {}", gust.dload),
                    format!("its table {tid} must be a TABLED1 with linear axes (its transform is exact for linear segments)"),
                ));
            }
            Box::new(move |f| table_transform(t, 2.0 * std::f64::consts::PI * f))
        }
    };
    let freqs = b.freq.get(&freq_id).ok_or_else(|| {
        NastranError::model(
            &format!("FREQUENCY = {freq_id}"),
            "no FREQ, FREQ1 or FREQ2 card has this id".into(),
        )
    })?;
    let mut freqs = freqs.clone();
    freqs.sort_by(f64::total_cmp);
    freqs.dedup();
    let flight = subcase_flight(b, sub)?;
    let (velocity, mach) = (flight.velocity, flight.mach);
    let q = real_param(b, "Q")?.unwrap_or(0.5 * flight.density * velocity * velocity);
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
    let dlm_error = |e: gustkit_core::AeroError| NastranError::model("DLM", e.to_string());
    if let Some(l) = &lfd {
        if (l.mach - mach).abs() > 1e-9 * mach.max(1.0) {
            return Err(NastranError::model(
                "PARAM MACH",
                format!("the subcase's Mach number {mach} is not the {} the LFD's steady state was converged at", l.mach),
            ));
        }
        if !b.monitors.is_empty() {
            return Err(NastranError::model(
                "MONPNT1",
                "monitor loads sum the DLM's box forces; with the LFD fidelity they are not available: remove the monitor points or use the DLM".into(),
            ));
        }
    }
    let table_gaf = gaf_table(
        b,
        (&surf, lfd.as_deref()),
        &flight,
        &ms,
        interpolation,
        mach,
    )?;
    let omega_n: Vec<f64> = modes.lambda[..n_modes]
        .iter()
        .map(|l| l.max(0.0).sqrt())
        .collect();
    let alpha: Vec<c64> = freqs.iter().map(|&f| shape(f) * gust.wg).collect();
    // the frequencies with a load (a zero α, as at f = 0 for a load without mean, needs no solve)
    let live: Vec<usize> = (0..freqs.len())
        .filter(|&i| alpha[i].norm() > 0.0)
        .collect();
    if let Some(&i) = live.iter().find(|&&i| freqs[i] == 0.0) {
        if let Some(m) = omega_n
            .iter()
            .position(|&w| w < 1e-6 * omega_n[n_modes - 1].max(1.0))
        {
            return Err(NastranError::model(
                &format!("FREQUENCY = {freq_id}"),
                format!(
                    "starts at 0 Hz, where the gust load is not zero (|α| = {:.4e}), and mode {} is a rigid-body mode: a free body's steady response to a load with a mean is unbounded; start the list above 0 Hz or give a load without mean",
                    alpha[i].norm(),
                    m + 1
                ),
            ));
        }
    }
    let grid = crate::gust::FrequencyGrid {
        omega: live
            .iter()
            .map(|&i| 2.0 * std::f64::consts::PI * freqs[i])
            .collect(),
        weights: vec![0.0; live.len()],
    };
    let problem = modal_problem(
        omega_n,
        zetas.first().copied().unwrap_or(0.0),
        &table_gaf,
        (q, velocity),
        grid,
    );
    let fr = crate::gust::response::frequency_response(&problem)
        .map_err(|e| NastranError::model("frequency response", e.to_string()))?;
    let mut eta = vec![None; freqs.len()];
    for (e, &i) in fr.eta.iter().zip(&live) {
        eta[i] = Some(e.clone());
    }
    // monitor points: the boxes' forces at each loaded frequency's k, the rows of the stations
    let mut box_forces = vec![None; freqs.len()];
    let mut monitors = Vec::new();
    if !b.monitors.is_empty() {
        let k: Vec<f64> = live
            .iter()
            .map(|&i| 2.0 * std::f64::consts::PI * freqs[i] * surf.b_ref / velocity)
            .collect();
        let forces = surf.dlm.box_forces(&flight, &ms, &k).map_err(dlm_error)?;
        for (f, &i) in forces.into_iter().zip(&live) {
            box_forces[i] = Some(f);
        }
        monitors = monitor_rows(b, s, modes, n_modes, &rows, surf.box_ids.len())?;
    }
    let crate::gust::GustProblem {
        grid,
        omega_n,
        damping_ratio: zeta,
        ..
    } = problem;
    Ok(GustSolution {
        response: GustFrequencyResponse {
            frequencies_hz: freqs,
            load: alpha,
            eta,
            n_modes,
            q,
            box_forces,
            monitor_rows: monitors,
            warnings,
        },
        surf,
        rows,
        flight,
        mach,
        interpolation: interpolation.clone(),
        table: table_gaf,
        omega_n,
        zeta,
        velocity,
        grid,
        live,
        fr,
        lfd,
    })
}

/// Per mode, the factor c that takes a mass-normalized modal coordinate to the one of the
/// subcase's eigenvalue method (η = c η_mass): 1 for NORM MASS (EIGR's and EIGRL's default),
/// φ_mass at the a-set's largest component for NORM MAX (that component becomes +1).
fn modal_coordinate_scale(
    b: &BulkData,
    sub: &Subcase,
    modes: &RealModes,
    n_modes: usize,
) -> R<Vec<f64>> {
    let norm = sub
        .selections
        .get("METHOD")
        .and_then(|m| b.eigr.get(m))
        .map_or("MASS", |e| e.norm.as_str());
    match norm {
        "" | "MASS" => Ok(vec![1.0; n_modes]),
        "MAX" => Ok((0..n_modes)
            .map(|m| {
                modes
                    .phi_a
                    .col(m)
                    .iter()
                    .fold(0.0, |a: f64, &v| if v.abs() > a.abs() { v } else { a })
            })
            .collect()),
        other => Err(NastranError::model(
            "SDISPLACEMENT",
            format!("modal coordinates are given in the MASS or MAX normalization of the eigenvalue method; NORM {other} is not"),
        )),
    }
}

/// The rows of `requests` ((grid or mode, component 1–6, quantity)), checked against the model:
/// grids it defines, SPC forces only of constrained components, modes among the `n_modes` kept
/// (modal coordinates in the normalization the eigenvalue method names).
pub fn output_rows(
    b: &BulkData,
    sub: &Subcase,
    s: &Structure,
    modes: &RealModes,
    n_modes: usize,
    requests: &[(u32, u8, Quantity)],
) -> R<Vec<OutputRow>> {
    let spc: std::collections::BTreeSet<usize> =
        constrained(s, b, sub.selections.get("SPC").copied())?;
    let modal_scale = if requests.iter().any(|r| r.2 == Quantity::Mode) {
        modal_coordinate_scale(b, sub, modes, n_modes)?
    } else {
        Vec::new()
    };
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
                Quantity::Mode if m + 1 == grid_id as usize => (modal_scale[m], 0.0),
                Quantity::Mode => (0.0, 0.0),
                Quantity::SpcForce => {
                    let n = s.k_gg.nrows();
                    let kp: f64 = (0..n).map(|j| s.k_gg[(dof, j)] * modes.phi_g[(j, m)]).sum();
                    let mp: f64 = (0..n).map(|j| s.m_gg[(dof, j)] * modes.phi_g[(j, m)]).sum();
                    (kp, mp)
                }
            })
            .unzip();
        let label = match quantity {
            Quantity::Displacement => format!("{grid_id}{}", component_label(comp)),
            Quantity::Acceleration => format!("ACCE {grid_id}{}", component_label(comp)),
            Quantity::Mode => format!("MODE {grid_id}"),
            Quantity::SpcForce => format!("SPCF {grid_id}{}", component_label(comp)),
        };
        out.push(OutputRow {
            label,
            k_row,
            m_row,
            aero: Vec::new(),
        });
    }
    Ok(out)
}

/// One output's complex frequency response on the FREQ list (the model's units per unit gust
/// angle's scale as the GUST card gives it), for SOL 146 without RANDOM or TSTEP.
#[derive(Clone, Debug, PartialEq)]
pub struct FrequencyRow {
    pub label: String,
    pub values: Vec<c64>,
}

/// The frequency response of `requests` to the subcase's gust (GUST → RLOAD1), with the
/// frequencies (Hz) and the warnings of the reading.
pub fn frequency_rows(
    b: &BulkData,
    sub: &Subcase,
    s: &Structure,
    modes: &RealModes,
    requests: &[(u32, u8, Quantity)],
    interpolation: &KInterpolation,
) -> R<(Vec<f64>, Vec<FrequencyRow>, Vec<String>)> {
    let response = gust_frequency_response(b, sub, s, modes, interpolation)?;
    let rows = response
        .rows(b, sub, s, modes, requests)?
        .iter()
        .map(|row| FrequencyRow {
            label: row.label.clone(),
            values: response.output(row),
        })
        .collect();
    Ok((response.frequencies_hz, rows, response.warnings))
}

/// One MONPNT1 component as a functional of the g-set loads: its label, the weights `l` that sum
/// the grids' forces and moments at the point along the component's axis, and those weights
/// carried to the boxes' doublet points through the splines (`aero`, one a box).
#[derive(Clone, Debug)]
pub struct MonitorFunctional {
    pub label: String,
    pub l: Vec<f64>,
    pub aero: Vec<f64>,
}

/// The rows of every MONPNT1's components: the aerodynamic and inertial loads on its AECOMP's
/// grids summed at its point (force summation),
///   F = Σᵢ fᵢ,   M = Σᵢ (xᵢ − x₀) × fᵢ + mᵢ,   (fᵢ, mᵢ) = q Gᵢᵀ F_boxes + ω² (M Φ η)ᵢ,
/// in basic and then along CD's axes; G the spline's rows at the doublet points. Labels are
/// Nastran's: `NAME CX` … `NAME CMZ`.
pub fn monitor_rows(
    b: &BulkData,
    s: &Structure,
    modes: &RealModes,
    n_modes: usize,
    rows: &super::spline::SplineRows,
    n_boxes: usize,
) -> R<Vec<OutputRow>> {
    let ng = s.k_gg.nrows();
    // M Φ, the inertial loads of the modes
    let m_phi: Vec<Vec<f64>> = (0..n_modes)
        .map(|m| {
            (0..ng)
                .map(|i| (0..ng).map(|j| s.m_gg[(i, j)] * modes.phi_g[(j, m)]).sum())
                .collect()
        })
        .collect();
    Ok(monitor_functionals(b, s, rows, n_boxes)?
        .into_iter()
        .map(|f| OutputRow {
            m_row: m_phi
                .iter()
                .map(|mp| -(0..ng).map(|g| f.l[g] * mp[g]).sum::<f64>())
                .collect(),
            label: f.label,
            k_row: vec![0.0; n_modes],
            aero: f.aero,
        })
        .collect())
}

/// Every MONPNT1 component of the model as a [`MonitorFunctional`], in the order of
/// [`monitor_rows`].
pub fn monitor_functionals(
    b: &BulkData,
    s: &Structure,
    rows: &super::spline::SplineRows,
    n_boxes: usize,
) -> R<Vec<MonitorFunctional>> {
    let frame = |id: u32, what: &str| -> R<super::structure::Frame> {
        s.frames.get(&id).copied().ok_or_else(|| {
            NastranError::model(what, format!("coordinate system {id} is not defined"))
        })
    };
    let ng = s.k_gg.nrows();
    let names = ["CX", "CY", "CZ", "CMX", "CMY", "CMZ"];
    let mut out = Vec::new();
    for mon in b.monitors.values() {
        let what = format!("MONPNT1 {}", mon.name);
        let comp = b.aecomps.get(&mon.comp).ok_or_else(|| {
            NastranError::model(&what, format!("its AECOMP {} is not defined", mon.comp))
        })?;
        let mut grids = std::collections::BTreeSet::new();
        for sid in &comp.sets {
            let set = b.set1.get(sid).ok_or_else(|| {
                NastranError::model(
                    &format!("AECOMP {}", comp.name),
                    format!("its SET1 {sid} is not defined"),
                )
            })?;
            for g in set {
                let i = *s.index.get(g).ok_or_else(|| {
                    NastranError::model(
                        &format!("SET1 {sid}"),
                        format!("names grid {g}, which the model does not define"),
                    )
                })?;
                grids.insert(i);
            }
        }
        let cp = frame(mon.cp, &what)?;
        let cd = frame(mon.cd, &what)?;
        let x0 = cp.to_basic(mon.point);
        for &axis in &mon.axes {
            let a = (axis - 1) as usize;
            let e = cd.axes[a % 3];
            // the functional over the g-set loads
            let mut l = vec![0.0; ng];
            for &i in &grids {
                let r = s.cd[i];
                let d = [
                    s.position[i][0] - x0[0],
                    s.position[i][1] - x0[1],
                    s.position[i][2] - x0[2],
                ];
                for c in 0..3 {
                    let ax = r.axes[c];
                    let dot = |u: [f64; 3]| e[0] * u[0] + e[1] * u[1] + e[2] * u[2];
                    if a < 3 {
                        l[6 * i + c] = dot(ax);
                    } else {
                        let cross = [
                            d[1] * ax[2] - d[2] * ax[1],
                            d[2] * ax[0] - d[0] * ax[2],
                            d[0] * ax[1] - d[1] * ax[0],
                        ];
                        l[6 * i + c] = dot(cross);
                        l[6 * i + 3 + c] = dot(ax);
                    }
                }
            }
            let aero: Vec<f64> = (0..n_boxes)
                .map(|j| (0..ng).map(|g| l[g] * rows.value[(n_boxes + j, g)]).sum())
                .collect();
            out.push(MonitorFunctional {
                label: format!("{} {}", mon.name, names[a]),
                l,
                aero,
            });
        }
    }
    Ok(out)
}
