//! The peak of an output over a set of discrete gusts as one smooth function, for constraints:
//! the Kreisselmeier–Steinhauser aggregate of ±y(t_n)/y_ref over every time sample and gust,
//!   KS = m + (1/ρ) ln Σ e^{ρ(v − m)},  v ∈ {±y_h(t_n)/y_ref},  m = max v,
//! which bounds max |y|/y_ref from above by at most ln(2 N n_gusts)/ρ. Its reverse mode runs
//! back through the inverse FFT (an FFT of the seeds ∂KS/∂y) to seeds on the transfer function
//! H_y(ω_j), then through Eq. 16 as every gust functional does ([`FrequencyResponse::vjp`]).

use super::analysis::TransientModel;
use super::profile::GustProfile;
use crate::gust::response::{GustError, GustGradient, GustProblem};
use faer::c64;

/// The KS aggregate's allowance: ρ = ln(n)/PEAK_KS_GAP over the n values it aggregates, so KS
/// exceeds the largest |y|/y_ref by at most this (0.5 % of the reference).
pub const PEAK_KS_GAP: f64 = 0.005;

/// The aggregate of one output's peak over a set of gusts, with what its reverse mode needs.
#[derive(Clone, Debug)]
pub struct PeakKs {
    pub output: usize,
    /// The reference y_ref the values are divided by (the constraint's limit).
    pub scale: f64,
    pub rho: f64,
    /// KS of ±y/y_ref.
    pub ks: f64,
    /// The largest |y|/y_ref on the samples (KS − this is the aggregate's gap).
    pub peak: f64,
    /// ∂KS/∂y_h(t_n), `[gust][n]`.
    y_bar: Vec<Vec<f64>>,
}

impl PeakKs {
    /// KS of output `y` over `gusts`, values divided by `scale`; ρ from [`PEAK_KS_GAP`].
    pub fn evaluate(
        model: &mut TransientModel,
        gusts: &[GustProfile],
        y: usize,
        scale: f64,
    ) -> Self {
        let n = model.grid.time.len();
        let count = 2 * n * gusts.len();
        let rho = (count as f64).ln() / PEAK_KS_GAP;
        let mut hist = vec![vec![0.0; n]; gusts.len()];
        for (g, h) in gusts.iter().zip(hist.iter_mut()) {
            model.history(g, y, h);
        }
        let m = hist.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs())) / scale;
        let mut sum = 0.0;
        for v in hist.iter().flatten() {
            let v = v / scale;
            sum += (rho * (v - m)).exp() + (rho * (-v - m)).exp();
        }
        let ks = m + sum.ln() / rho;
        // ∂KS/∂y = (e^{ρ(v−m)} − e^{ρ(−v−m)}) / (Σ y_ref)
        let y_bar = hist
            .iter()
            .map(|h| {
                h.iter()
                    .map(|v| {
                        let v = v / scale;
                        ((rho * (v - m)).exp() - (rho * (-v - m)).exp()) / (sum * scale)
                    })
                    .collect()
            })
            .collect();
        Self {
            output: y,
            scale,
            rho,
            ks,
            peak: m,
            y_bar,
        }
    }

    /// Reverse mode: the seeds `ks_bar` × ∂KS on the GAF table, ω_n², S and the residual rows of
    /// `p` (the problem the model was made from).
    pub fn vjp(
        &self,
        model: &mut TransientModel,
        p: &GustProblem,
        gusts: &[GustProfile],
        ks_bar: f64,
    ) -> Result<GustGradient, GustError> {
        let m = model.grid.omega.len();
        let d = model.derivative[self.output];
        let mut spectrum_bar = vec![c64::new(0.0, 0.0); m];
        let mut h_bar = vec![c64::new(0.0, 0.0); m];
        let mut scaled = vec![0.0; model.grid.time.len()];
        for (g, yb) in gusts.iter().zip(&self.y_bar) {
            for (s, v) in scaled.iter_mut().zip(yb) {
                *s = v * ks_bar;
            }
            model
                .synthesizer()
                .history_adjoint(&scaled, &mut spectrum_bar);
            // Y = (iω)^d H W: H̄ += conj((iω)^d W) Ȳ
            for ((hb, yb), &w) in h_bar.iter_mut().zip(&spectrum_bar).zip(&model.grid.omega) {
                *hb += (c64::new(0.0, w).powu(d) * g.spectrum(w)).conj() * yb;
            }
        }
        let mut hbar = vec![vec![c64::new(0.0, 0.0); m]; p.outputs.len()];
        hbar[self.output] = h_bar;
        model.response.vjp(&model.on_grid(p), &hbar)
    }
}

#[cfg(test)]
mod tests;
