//! Stochastic gust response, paper Eqs. 16–18, and its reverse mode.
//!
//! For each ω of a grid: k = ω b_ref / U, GAFs spline-interpolated in k, and
//!   [−ω² M̄ + iω C̄ + K̄ − q_inf Q_ss(ik)] η = q_inf Q_gs(ik)               (Eq. 16, per unit w_g/U)
//!   H_y(ω) = Sᵀ η / U  (response per unit gust velocity),   PSD_y = |H_y|² Φ_w(ω)   (Eq. 17)
//!   RMS_y = √(∫ PSD_y dω),   N0_y = (1/2π) √(∫ ω² PSD_y dω / ∫ PSD_y dω)          (Eq. 18)
//! with mass-normalized modes (M̄ = I, K̄ = diag ω_n², C̄ = diag 2ζω_n) and the trapezoidal rule on
//! the grid. With the mode-acceleration method (residual flexibility, see
//! `structure::residual`) an output adds the quasi-static response of the modes left out:
//!   H_y(ω) = [Sᵀ η + q_inf (Q_ws(ik) η + Q_wg(ik))] / U,
//! Q_ws, Q_wg the GAF rows of the output's residual shape w ([`ResidualGafs`]).
//!
//! Reverse mode (conjugate convention of gustkit_core::aero): for J = Σ_y RMS̄_y RMS_y,
//!   H̄_j = RMS̄ w_j Φ_j H_j / RMS,  η̄ = S H̄ / U,  solve Aᴴ λ = η̄,
//!   Q̄_gs(ω) = q λ,  Q̄_ss(ω) = q λ ηᴴ,  ω̄²_n,m = Re(−conj(λ_m) η_m (1 + iω ζ/ω_n,m)),
//!   S̄ = Re(conj(H̄) η) / U,
//! and with residual rows η̄ += q conj(Q_ws) H̄ / U, Q̄_ws = q H̄ conj(η) / U, Q̄_wg = q H̄ / U;
//! and the table seeds are the transposed spline weights applied to Q̄(ω).

use super::interp::SplineWeights;
use super::psd::Turbulence;
use super::small_lu::SmallLu;
use faer::c64;
use gustkit_core::GafTable;
use rayon::prelude::*;

/// Why a gust response cannot be computed.
#[derive(Clone, Debug, thiserror::Error, PartialEq)]
pub enum GustError {
    #[error("{0}")]
    Input(String),
    #[error(
        "the frequency grid ends at {omega_max:.3} rad/s (k = {k_max:.3}) and leaves up to {fraction:.2e} of {what} out (limit gust.max_tail = {limit:.0e}){note}: extend aero.reduced_frequencies to k ≈ {k_needed:.3} (enough whatever the response does) or raise gust.max_tail to {fraction:.2e}"
    )]
    GridTooShort {
        omega_max: f64,
        k_max: f64,
        fraction: f64,
        limit: f64,
        /// The reduced frequency up to which the grid would leave out no more than the limit of
        /// the gust variance itself.
        k_needed: f64,
        /// Whose variance: "the gust variance" or "the variance of output N".
        what: String,
        /// Why the gust variance decides, where it does ("" otherwise).
        note: String,
    },
    #[error("the aeroelastic system is singular at {omega:.4} rad/s")]
    Singular { omega: f64 },
}

/// A frequency grid with trapezoidal weights: ω = 0 followed by `n` log-spaced points on
/// [ω_min, ω_max].
#[derive(Clone, Debug)]
pub struct FrequencyGrid {
    pub omega: Vec<f64>,
    pub weights: Vec<f64>,
}

impl FrequencyGrid {
    pub fn log(omega_min: f64, omega_max: f64, n: usize) -> Result<Self, GustError> {
        if !(omega_min > 0.0 && omega_max > omega_min && n >= 2) {
            return Err(GustError::Input(format!(
                "frequency grid: need 0 < omega_min < omega_max and at least 2 points (got {omega_min}, {omega_max}, {n})"
            )));
        }
        let r = (omega_max / omega_min).ln();
        let mut omega = vec![0.0];
        omega.extend((0..n).map(|i| omega_min * (r * i as f64 / (n - 1) as f64).exp()));
        let m = omega.len();
        let mut weights = vec![0.0; m];
        for i in 0..m - 1 {
            let h = omega[i + 1] - omega[i];
            weights[i] += 0.5 * h;
            weights[i + 1] += 0.5 * h;
        }
        Ok(Self { omega, weights })
    }
}

/// The GAF rows of the outputs' residual shapes (mode acceleration): per table reduced frequency
/// and output, Q_ws (one entry a retained mode: the force on the residual shape w of each mode's
/// motion) and Q_wg (of the gust), in the normalization of the GAF table.
#[derive(Clone, Debug, PartialEq)]
pub struct ResidualGafs {
    pub q_ws: Vec<Vec<Vec<c64>>>,
    pub q_wg: Vec<Vec<c64>>,
}

impl ResidualGafs {
    /// Zero rows for `n_k` reduced frequencies, `n_outputs` outputs and `n_modes` modes.
    pub fn zeros(n_k: usize, n_outputs: usize, n_modes: usize) -> Self {
        let z = c64::new(0.0, 0.0);
        Self {
            q_ws: vec![vec![vec![z; n_modes]; n_outputs]; n_k],
            q_wg: vec![vec![z; n_outputs]; n_k],
        }
    }

    /// Splits a table of the modes followed by one residual shape an output into the modes' own
    /// table and the residual rows (the residual shapes' columns, their own motion, are not used).
    pub fn split(table: &GafTable, n_modes: usize) -> (GafTable, Self) {
        let n_out = table.n_modes() - n_modes;
        let mut modal = table.clone();
        let mut rows = Self::zeros(table.k.len(), n_out, n_modes);
        for i in 0..table.k.len() {
            modal.q_ss[i] = table.q_ss[i][..n_modes]
                .iter()
                .map(|row| row[..n_modes].to_vec())
                .collect();
            modal.q_gs[i] = table.q_gs[i][..n_modes].to_vec();
            for y in 0..n_out {
                rows.q_ws[i][y] = table.q_ss[i][n_modes + y][..n_modes].to_vec();
                rows.q_wg[i][y] = table.q_gs[i][n_modes + y];
            }
        }
        (modal, rows)
    }

    /// Reverse of [`ResidualGafs::split`]: seeds on the modes' table and on the rows as seeds on
    /// the whole table.
    pub fn join(modal: &GafTable, rows: &Self) -> GafTable {
        let n_modes = modal.n_modes();
        let n_out = rows.q_wg.first().map_or(0, Vec::len);
        let n = n_modes + n_out;
        let z = c64::new(0.0, 0.0);
        let mut t = modal.clone();
        for i in 0..modal.k.len() {
            t.q_ss[i] = (0..n)
                .map(|a| {
                    (0..n)
                        .map(|b| match (a < n_modes, b < n_modes) {
                            (true, true) => modal.q_ss[i][a][b],
                            (false, true) => rows.q_ws[i][a - n_modes][b],
                            _ => z,
                        })
                        .collect()
                })
                .collect();
            t.q_gs[i] = (0..n)
                .map(|a| {
                    if a < n_modes {
                        modal.q_gs[i][a]
                    } else {
                        rows.q_wg[i][a - n_modes]
                    }
                })
                .collect();
        }
        t
    }
}

/// Everything Eq. 16–18 needs, in SI.
#[derive(Clone, Debug)]
pub struct GustProblem<'a> {
    /// Natural circular frequencies ω_n of the retained (mass-normalized) modes.
    pub omega_n: Vec<f64>,
    pub damping_ratio: f64,
    pub table: &'a GafTable,
    pub q_inf: f64,
    pub velocity: f64,
    pub turbulence: Turbulence,
    pub grid: FrequencyGrid,
    /// Output vectors S (one row an output, one column a mode): y = S η.
    pub outputs: Vec<Vec<f64>>,
    /// The outputs' residual rows (mode acceleration), or none (mode displacement).
    pub residual: Option<&'a ResidualGafs>,
    /// Largest fraction of a response's variance the grid may leave out above its last
    /// frequency (of σ_w² itself where the response bound does not apply: see [`TAIL_BEYOND`]).
    pub max_tail: f64,
}

/// The grid's last frequency must lie this far beyond every natural frequency for the response
/// bound of the tail: there the inertia grows with ω², so |H_y(ω)| falls beyond the grid and
/// |H_y(ω_max)|² ∫_{ω_max}^∞ Φ_w dω bounds the variance left out from above. Closer to a
/// resonance the bound does not hold and the tail of the gust spectrum itself is limited.
pub const TAIL_BEYOND: f64 = 1.5;

/// The response: per output, RMS, N0 and the PSD on the grid; per ω, η.
#[derive(Clone, Debug, Default)]
pub struct GustResponse {
    pub rms: Vec<f64>,
    pub n0: Vec<f64>,
    pub psd: Vec<Vec<f64>>,
    /// Per output, the upper bound of the fraction of its variance beyond the grid (the gust
    /// spectrum's own tail fraction where the response bound does not apply).
    pub tail: Vec<f64>,
    pub eta: Vec<Vec<c64>>,
    h: Vec<Vec<c64>>,
    lus: Vec<SmallLu>,
}

/// Reverse-mode result of [`rms_vjp`].
#[derive(Clone, Debug)]
pub struct GustGradient {
    /// Seeds on the GAF table (conjugate convention).
    pub table: GafTable,
    /// ∂J/∂(ω_n²) per mode.
    pub lambda: Vec<f64>,
    /// ∂J/∂S.
    pub outputs: Vec<Vec<f64>>,
    /// Seeds on the residual rows (conjugate convention), where the problem has them.
    pub residual: Option<ResidualGafs>,
}

impl<'a> GustProblem<'a> {
    /// A problem for the discrete gust (transient) path only: its turbulence, frequency grid and
    /// tail limit are placeholders, which that path replaces (the grid) or never reads.
    pub fn for_transient(
        omega_n: Vec<f64>,
        damping_ratio: f64,
        table: &'a GafTable,
        q_inf: f64,
        velocity: f64,
        outputs: Vec<Vec<f64>>,
    ) -> Self {
        Self {
            omega_n,
            damping_ratio,
            table,
            q_inf,
            velocity,
            turbulence: Turbulence::Dryden {
                sigma_w_m_s: 1.0,
                scale_length_m: 100.0,
            },
            grid: FrequencyGrid {
                omega: vec![0.0],
                weights: vec![0.0],
            },
            outputs,
            residual: None,
            max_tail: 1.0,
        }
    }

    /// The circular frequency of the GAF table's highest reduced frequency, k_max U / b (rad/s):
    /// how far a frequency grid of this problem can reach.
    pub fn table_omega_max(&self) -> f64 {
        self.table.k.last().copied().unwrap_or(0.0) * self.velocity / self.table.b_ref
    }

    fn check(&self) -> Result<SplineWeights, GustError> {
        let nm = self.omega_n.len();
        if self.table.n_modes() != nm {
            return Err(GustError::Input(format!(
                "the GAF table has {} modes, the structure {nm}",
                self.table.n_modes()
            )));
        }
        if !(self.damping_ratio >= 0.0 && self.damping_ratio < 1.0) {
            return Err(GustError::Input(format!(
                "damping_ratio: must lie in [0, 1) (got {})",
                self.damping_ratio
            )));
        }
        self.turbulence.validate().map_err(GustError::Input)?;
        if self.outputs.iter().any(|s| s.len() != nm) {
            return Err(GustError::Input(
                "outputs: every S vector needs one entry a mode".into(),
            ));
        }
        if let Some(r) = self.residual {
            let ny = self.outputs.len();
            if r.q_wg.len() != self.table.k.len()
                || r.q_wg.iter().any(|v| v.len() != ny)
                || r.q_ws.len() != self.table.k.len()
                || r.q_ws.iter().flatten().any(|v| v.len() != nm)
            {
                return Err(GustError::Input(
                    "residual rows: one row an output, one entry a mode, at every reduced frequency"
                        .into(),
                ));
            }
        }
        let ks: Vec<f64> = self
            .grid
            .omega
            .iter()
            .map(|w| w * self.table.b_ref / self.velocity)
            .collect();
        SplineWeights::new(&self.table.k, &ks).map_err(GustError::Input)
    }

    /// The reduced frequency beyond which the gust spectrum itself holds no more than
    /// `max_tail` of σ_w² (bisection in log ω: the tail falls monotonically).
    fn k_needed(&self) -> f64 {
        let omega_max = *self.grid.omega.last().expect("grid has points");
        let (mut lo, mut hi) = (omega_max, omega_max);
        while self.turbulence.tail_fraction(hi, self.velocity) > self.max_tail && hi < 1e12 {
            lo = hi;
            hi *= 2.0;
        }
        for _ in 0..60 {
            let mid = (lo * hi).sqrt();
            if self.turbulence.tail_fraction(mid, self.velocity) > self.max_tail {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        hi * self.table.b_ref / self.velocity
    }

    /// Per output, the bound of the fraction of its variance beyond the grid, from the PSD on
    /// the grid (`m0`: its integral) and |H_y| at the last point; an error above `max_tail`.
    fn tail_check(&self, m0: &[f64], h_last: &[f64]) -> Result<Vec<f64>, GustError> {
        let omega_max = *self.grid.omega.last().expect("grid has points");
        let gust_tail = self.turbulence.tail_fraction(omega_max, self.velocity);
        let sigma2 = self.turbulence.sigma().powi(2);
        let bound_applies = self.omega_n.iter().all(|&wn| omega_max >= TAIL_BEYOND * wn);
        let fractions: Vec<f64> = m0
            .iter()
            .zip(h_last)
            .map(|(&m0, &h)| {
                if bound_applies {
                    let left_out = h * h * gust_tail * sigma2;
                    left_out / (m0 + left_out).max(f64::MIN_POSITIVE)
                } else {
                    gust_tail
                }
            })
            .collect();
        if let Some((y, &fraction)) = fractions
            .iter()
            .enumerate()
            .find(|(_, &f)| f > self.max_tail)
        {
            return Err(GustError::GridTooShort {
                omega_max,
                k_max: omega_max * self.table.b_ref / self.velocity,
                fraction,
                limit: self.max_tail,
                k_needed: self.k_needed(),
                what: if bound_applies {
                    format!("the variance of output {}", y + 1)
                } else {
                    "the gust variance".into()
                },
                note: if bound_applies {
                    String::new()
                } else {
                    format!(
                        "; the grid ends below {TAIL_BEYOND} × the highest natural frequency ({:.1} Hz), so the response's own tail cannot be bounded",
                        self.omega_n.iter().fold(0.0f64, |a, &b| a.max(b)) / (2.0 * std::f64::consts::PI)
                    )
                },
            });
        }
        Ok(fractions)
    }

    /// Output y's effective row S_y + q Q_ws,y(ω) into `row` (one entry a mode, a buffer the
    /// caller reuses across frequencies) and its offset q Q_wg,y(ω), at spline weights `w` (S_y
    /// and zero without residual rows).
    fn output_row(&self, w: &[f64], y: usize, row: &mut [c64]) -> c64 {
        for (rv, sv) in row.iter_mut().zip(&self.outputs[y]) {
            *rv = c64::new(*sv, 0.0);
        }
        let mut off = c64::new(0.0, 0.0);
        if let Some(r) = self.residual {
            for (i, wi) in w.iter().enumerate() {
                if *wi == 0.0 {
                    continue;
                }
                for (rv, q) in row.iter_mut().zip(&r.q_ws[i][y]) {
                    *rv += q * (self.q_inf * wi);
                }
                off += r.q_wg[i][y] * (self.q_inf * wi);
            }
        }
        off
    }

    /// The aeroelastic matrix A(ω) (row-major) and right-hand side q Q_gs at grid point j.
    fn system(&self, w: &[f64], omega: f64) -> (Vec<c64>, Vec<c64>) {
        let nm = self.omega_n.len();
        let interp = |f: &dyn Fn(usize) -> c64| -> c64 {
            w.iter().enumerate().map(|(i, wi)| f(i) * *wi).sum()
        };
        let mut a = Vec::with_capacity(nm * nm);
        for m in 0..nm {
            for n in 0..nm {
                let q = interp(&|i| self.table.q_ss[i][m][n]);
                let mut v = -q * self.q_inf;
                if m == n {
                    let wn = self.omega_n[m];
                    v += c64::new(
                        wn * wn - omega * omega,
                        2.0 * self.damping_ratio * wn * omega,
                    );
                }
                a.push(v);
            }
        }
        let g = (0..nm)
            .map(|m| interp(&|i| self.table.q_gs[i][m]) * self.q_inf)
            .collect();
        (a, g)
    }
}

/// The modal frequency response of Eq. 16 on a problem's grid: η per ω, H_y per output and ω
/// (per unit gust velocity), and the factorizations that the reverse mode reuses.
#[derive(Clone, Debug)]
pub struct FrequencyResponse {
    /// η(ω_j), one entry a mode.
    pub eta: Vec<Vec<c64>>,
    /// H_y(ω_j), `[output][j]`, in the output's SI unit per m/s of gust velocity.
    pub h: Vec<Vec<c64>>,
    lus: Vec<SmallLu>,
}

/// Solves Eq. 16 at every frequency of the problem's grid and forms the outputs' transfer
/// functions H_y (Eq. 17 without the spectrum): the part shared by the stochastic and the
/// discrete gust responses.
pub fn frequency_response(p: &GustProblem) -> Result<FrequencyResponse, GustError> {
    let weights = p.check()?;
    let nm = p.omega_n.len();
    let per: Vec<(Vec<c64>, SmallLu)> = p
        .grid
        .omega
        .par_iter()
        .zip(&weights.weights)
        .map(|(&omega, w)| {
            let (a, g) = p.system(w, omega);
            let lu = SmallLu::factor(nm, a).ok_or(GustError::Singular { omega })?;
            let eta = lu.solve(&g);
            if eta.iter().any(|v| !(v.re.is_finite() && v.im.is_finite())) {
                return Err(GustError::Singular { omega });
            }
            Ok((eta, lu))
        })
        .collect::<Result<_, _>>()?;
    let (eta, lus): (Vec<_>, Vec<_>) = per.into_iter().unzip();
    let mut row = vec![c64::new(0.0, 0.0); nm];
    let h = (0..p.outputs.len())
        .map(|y| {
            eta.iter()
                .zip(&weights.weights)
                .map(|(e, w)| {
                    let off = p.output_row(w, y, &mut row);
                    (e.iter().zip(&row).map(|(a, b)| a * b).sum::<c64>() + off) / p.velocity
                })
                .collect()
        })
        .collect();
    Ok(FrequencyResponse { eta, h, lus })
}

/// Solves Eqs. 16–18 on the grid.
pub fn solve(p: &GustProblem) -> Result<GustResponse, GustError> {
    let FrequencyResponse { eta, h, lus } = frequency_response(p)?;
    let mut rms = Vec::new();
    let mut n0 = Vec::new();
    let mut psd = Vec::new();
    let mut m0s = Vec::new();
    let mut h_last = Vec::new();
    for hy in &h {
        let py: Vec<f64> = hy
            .iter()
            .zip(&p.grid.omega)
            .map(|(hv, &w)| hv.norm_sqr() * p.turbulence.psd(w, p.velocity))
            .collect();
        let m0: f64 = py.iter().zip(&p.grid.weights).map(|(a, b)| a * b).sum();
        let m2: f64 = py
            .iter()
            .zip(&p.grid.weights)
            .zip(&p.grid.omega)
            .map(|((a, b), w)| a * b * w * w)
            .sum();
        rms.push(m0.sqrt());
        n0.push((m2 / m0).sqrt() / (2.0 * std::f64::consts::PI));
        m0s.push(m0);
        h_last.push(hy.last().map_or(0.0, |v| v.norm()));
        psd.push(py);
    }
    let tail = p.tail_check(&m0s, &h_last)?;
    Ok(GustResponse {
        rms,
        n0,
        psd,
        tail,
        eta,
        h,
        lus,
    })
}

/// Reverse mode of the RMS values: seeds `rms_bar` (one per output).
pub fn rms_vjp(
    p: &GustProblem,
    r: &GustResponse,
    rms_bar: &[f64],
) -> Result<GustGradient, GustError> {
    if rms_bar.len() != p.outputs.len() {
        return Err(GustError::Input(format!(
            "seeds: {} RMS seeds for {} outputs",
            rms_bar.len(),
            p.outputs.len()
        )));
    }
    // H̄_y(ω_j) = RMS̄_y w_j Φ_j H_y(ω_j) / RMS_y
    let hbar: Vec<Vec<c64>> = (0..p.outputs.len())
        .map(|y| {
            p.grid
                .omega
                .iter()
                .enumerate()
                .map(|(j, &omega)| {
                    if rms_bar[y] == 0.0 || r.rms[y] == 0.0 {
                        return c64::new(0.0, 0.0);
                    }
                    let phi = p.turbulence.psd(omega, p.velocity);
                    r.h[y][j] * (rms_bar[y] * p.grid.weights[j] * phi / r.rms[y])
                })
                .collect()
        })
        .collect();
    transfer_vjp(p, &r.eta, &r.lus, &hbar)
}

impl FrequencyResponse {
    /// Reverse mode of the transfer functions: seeds `hbar[y][j]` on H_y(ω_j) (conjugate
    /// convention, δJ = Re Σ conj(H̄) δH) to seeds on the GAF table, ω_n², S and the residual rows.
    pub fn vjp(&self, p: &GustProblem, hbar: &[Vec<c64>]) -> Result<GustGradient, GustError> {
        transfer_vjp(p, &self.eta, &self.lus, hbar)
    }
}

/// The reverse sweep shared by every functional of the transfer functions (module docs): per ω,
///   η̄ = Σ_y conj(S̃_y) H̄_y / U,  Aᴴ λ = η̄,  Q̄_gs = q λ,  Q̄_ss = q λ ηᴴ,
///   ω̄²_n,m = Re(−conj(λ_m) η_m (1 + iω ζ/ω_n,m)),  S̄ = Re(conj(H̄) η) / U,
/// and the residual rows' seeds, all mapped to the table's k by the transposed spline weights.
fn transfer_vjp(
    p: &GustProblem,
    eta_all: &[Vec<c64>],
    lus: &[SmallLu],
    hbar: &[Vec<c64>],
) -> Result<GustGradient, GustError> {
    let weights = p.check()?;
    if hbar.len() != p.outputs.len() || hbar.iter().any(|h| h.len() != p.grid.omega.len()) {
        return Err(GustError::Input(format!(
            "seeds: one transfer-function seed an output and grid frequency ({} outputs, {} frequencies)",
            p.outputs.len(),
            p.grid.omega.len()
        )));
    }
    let nm = p.omega_n.len();
    let nk = p.table.k.len();
    let mut table = seed_table(p);
    let mut lambda = vec![0.0; nm];
    let mut outputs = vec![vec![0.0; nm]; p.outputs.len()];
    let mut residual = p
        .residual
        .map(|_| ResidualGafs::zeros(nk, p.outputs.len(), nm));
    let mut row = vec![c64::new(0.0, 0.0); nm];
    for (j, &omega) in p.grid.omega.iter().enumerate() {
        let eta = &eta_all[j];
        // η̄ = Σ_y conj(S̃_y) H̄_y / U
        let mut eta_bar = vec![c64::new(0.0, 0.0); nm];
        let mut any = false;
        for y in 0..p.outputs.len() {
            let hb = hbar[y][j];
            if hb == c64::new(0.0, 0.0) {
                continue;
            }
            any = true;
            p.output_row(&weights.weights[j], y, &mut row);
            for m in 0..nm {
                eta_bar[m] += hb * row[m].conj() / p.velocity;
                outputs[y][m] += (hb.conj() * eta[m]).re / p.velocity;
            }
            if let Some(res) = residual.as_mut() {
                let s = hb * (p.q_inf / p.velocity);
                for (i, wi) in weights.weights[j].iter().enumerate() {
                    if *wi == 0.0 {
                        continue;
                    }
                    for m in 0..nm {
                        res.q_ws[i][y][m] += s * eta[m].conj() * *wi;
                    }
                    res.q_wg[i][y] += s * *wi;
                }
            }
        }
        if !any {
            continue;
        }
        let at = (omega, &weights.weights[j][..], &eta[..], &lus[j]);
        accumulate_eta_seed(p, at, &eta_bar, &mut table, &mut lambda);
    }
    debug_assert_eq!(table.k.len(), nk);
    Ok(GustGradient {
        table,
        lambda,
        outputs,
        residual,
    })
}

/// A zero table of seeds on the problem's GAF table (its k, Mach and reference values).
fn seed_table(p: &GustProblem) -> GafTable {
    let flight_like = gustkit_core::FlightCondition {
        mach: p.table.mach,
        velocity: p.velocity,
        density: 1.0,
        b_ref: p.table.b_ref,
        x_ref: p.table.x_ref,
    };
    GafTable::zeros(&flight_like, &p.table.k, p.omega_n.len())
}

/// One frequency's share of the reverse sweep from a seed η̄ on η(ω) (spline weights `w`,
/// factorization `lu` of A(ω)): Aᴴ λ = η̄, then Q̄_gs += q λ, Q̄_ss += q λ ηᴴ and
/// ω̄²_n,m += Re(−conj(λ_m) η_m (1 + iω ζ/ω_n,m)), spread to the table's k by the weights.
fn accumulate_eta_seed(
    p: &GustProblem,
    (omega, w, eta, lu): (f64, &[f64], &[c64], &SmallLu),
    eta_bar: &[c64],
    table: &mut GafTable,
    lambda: &mut [f64],
) {
    let nm = p.omega_n.len();
    let lam = lu.solve_adjoint(eta_bar);
    for m in 0..nm {
        let l = lam[m];
        // Ā_mn = −λ_m conj(η_n); Q̄_ss = −q Ā = q λ_m conj(η_n); Q̄_gs = q λ
        let wn = p.omega_n[m];
        // a rigid-body mode (ω_n = 0): its ω_n² stays zero under sizing, and its seed is not
        // formed (the damping term's derivative is not defined there)
        if wn > 0.0 {
            let dadl = c64::new(1.0, omega * p.damping_ratio / wn);
            lambda[m] += (-(l * eta[m].conj()).conj() * dadl).re;
        }
        for (i, wi) in w.iter().enumerate() {
            if *wi == 0.0 {
                continue;
            }
            table.q_gs[i][m] += l * (p.q_inf * wi);
            for n in 0..nm {
                table.q_ss[i][m][n] += l * eta[n].conj() * (p.q_inf * wi);
            }
        }
    }
}

/// The tangent of η at one frequency (spline weights `w`, factorization `lu` of A(ω)) along
/// perturbations of the GAF table and of ω_n² (the damping ratio fixed): from A η = q Q_gs,
/// dη = A⁻¹ (q dQ_gs + q dQ_ss η − (1 + i ω ζ/ω_n) dλ η), the last term the derivative of
/// ω_n² + 2iζω_nω along dλ = d(ω_n²).
fn eta_tangent(
    p: &GustProblem,
    w: &[f64],
    omega: f64,
    eta: &[c64],
    lu: &SmallLu,
    d_table: &GafTable,
    d_lambda: &[f64],
) -> Vec<c64> {
    let nm = p.omega_n.len();
    let interp =
        |f: &dyn Fn(usize) -> c64| -> c64 { w.iter().enumerate().map(|(i, wi)| f(i) * *wi).sum() };
    let rhs: Vec<c64> = (0..nm)
        .map(|m| {
            let mut v = interp(&|i| d_table.q_gs[i][m]) * p.q_inf;
            for n in 0..nm {
                v += interp(&|i| d_table.q_ss[i][m][n]) * p.q_inf * eta[n];
            }
            if d_lambda[m] == 0.0 {
                // a rigid-body mode (ω_n = 0) has no ∂(ω_n²): its damping term is not formed
                return v;
            }
            let wn = p.omega_n[m];
            v - c64::new(1.0, omega * p.damping_ratio / wn) * d_lambda[m] * eta[m]
        })
        .collect();
    lu.solve(&rhs)
}

impl FrequencyResponse {
    /// Forward mode of η(ω_j) along perturbations of the GAF table and of ω_n² (see
    /// [`eta_tangent`]): for a caller that integrates the response its own way (a Nastran
    /// model's RMS over its FREQ list), one vector a grid frequency.
    pub fn eta_jvp(
        &self,
        p: &GustProblem,
        d_table: &GafTable,
        d_lambda: &[f64],
    ) -> Result<Vec<Vec<c64>>, GustError> {
        let weights = p.check()?;
        if d_lambda.len() != p.omega_n.len() || d_table.n_modes() != p.omega_n.len() {
            return Err(GustError::Input(
                "tangents: one dλ a mode and a GAF table of the problem's modes".into(),
            ));
        }
        Ok(p.grid
            .omega
            .iter()
            .enumerate()
            .map(|(j, &omega)| {
                eta_tangent(
                    p,
                    &weights.weights[j],
                    omega,
                    &self.eta[j],
                    &self.lus[j],
                    d_table,
                    d_lambda,
                )
            })
            .collect())
    }
}

impl FrequencyResponse {
    /// Reverse mode of η(ω_j) (the adjoint of [`FrequencyResponse::eta_jvp`]): seeds
    /// `eta_bar[j]` on η at each grid frequency (conjugate convention, δJ = Re Σ conj(η̄)·δη) to
    /// seeds on the GAF table and on ω_n²; for a caller that integrates the response its own way.
    pub fn eta_vjp(
        &self,
        p: &GustProblem,
        eta_bar: &[Vec<c64>],
    ) -> Result<GustGradient, GustError> {
        let weights = p.check()?;
        let nm = p.omega_n.len();
        if eta_bar.len() != p.grid.omega.len() || eta_bar.iter().any(|e| e.len() != nm) {
            return Err(GustError::Input(
                "seeds: one η̄ of the problem's modes a grid frequency".into(),
            ));
        }
        let mut table = seed_table(p);
        let mut lambda = vec![0.0; nm];
        for (j, &omega) in p.grid.omega.iter().enumerate() {
            if eta_bar[j].iter().all(|e| *e == c64::new(0.0, 0.0)) {
                continue;
            }
            let at = (
                omega,
                &weights.weights[j][..],
                &self.eta[j][..],
                &self.lus[j],
            );
            accumulate_eta_seed(p, at, &eta_bar[j], &mut table, &mut lambda);
        }
        Ok(GustGradient {
            table,
            lambda,
            outputs: Vec::new(),
            residual: None,
        })
    }
}

/// Forward mode of the RMS values along perturbations of the GAF table, of ω_n², of S and of the
/// residual rows (where the problem has them).
pub fn rms_jvp(
    p: &GustProblem,
    r: &GustResponse,
    d_table: &GafTable,
    d_lambda: &[f64],
    d_outputs: &[Vec<f64>],
    d_residual: Option<&ResidualGafs>,
) -> Result<Vec<f64>, GustError> {
    let weights = p.check()?;
    let nm = p.omega_n.len();
    let mut d_ms = vec![0.0; p.outputs.len()];
    let mut row = vec![c64::new(0.0, 0.0); nm];
    for (j, &omega) in p.grid.omega.iter().enumerate() {
        let w = &weights.weights[j];
        let eta = &r.eta[j];
        let deta = eta_tangent(p, w, omega, eta, &r.lus[j], d_table, d_lambda);
        let phi = p.turbulence.psd(omega, p.velocity);
        for y in 0..p.outputs.len() {
            p.output_row(w, y, &mut row);
            let mut dh: c64 = (0..nm)
                .map(|m| deta[m] * row[m] + eta[m] * d_outputs[y][m])
                .sum::<c64>();
            if let Some(d) = d_residual {
                for (i, wi) in w.iter().enumerate() {
                    let dq: c64 =
                        (0..nm).map(|m| d.q_ws[i][y][m] * eta[m]).sum::<c64>() + d.q_wg[i][y];
                    dh += dq * (p.q_inf * wi);
                }
            }
            let dh = dh / p.velocity;
            d_ms[y] += p.grid.weights[j] * phi * 2.0 * (r.h[y][j].conj() * dh).re;
        }
    }
    Ok(d_ms
        .iter()
        .zip(&r.rms)
        .map(|(d, rms)| d / (2.0 * rms))
        .collect())
}

#[cfg(test)]
mod tests;
