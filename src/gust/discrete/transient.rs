//! Time histories through the frequency response (Nastran SOL 146's way with a transient gust):
//! the response y(t) = (1/2π) ∫ H_y(ω) W(ω) e^{iωt} dω of every output, by an inverse FFT of the
//! product on a uniform frequency grid.
//!
//! On the grid ω_j = j Δω (j = 0 … M, Δω = 2π/T) the sum
//!   y(t_n) = (Δω/π) Re[½ Y_0 + Σ_{j≥1} Y_j e^{iω_j t_n}],  Y_j = (iω_j)^d H_y(ω_j) W(ω_j),
//! is exactly the response periodized with the span T (Poisson's summation) and cut at ω_M.
//! Hence the two checks every result passes: the response must have decayed by the end of the
//! window (what it still holds there wraps onto the start: [`WRAP_TOLERANCE`]) and the gust's
//! spectrum must hold almost none of its energy beyond ω_M ([`TRUNCATION_TOLERANCE`]). The time
//! window starts a little before the gust reaches the reference point (a fraction
//! [`PRE_WINDOW`] of T), where a causal response shows zero.

use super::profile::GustProfile;
use faer::c64;
use rustfft::{Fft, FftPlanner};
use std::sync::Arc;

/// The largest |y| in the last tenth of the window, as a fraction of the peak |y|, that a
/// response may keep: what is left there is added to the start of the next period, so it bounds
/// the wrap-around error of the peaks (the tail of a decaying response is below its last tenth).
pub const WRAP_TOLERANCE: f64 = 1e-3;

/// The largest fraction of the gust's energy ∫ w² dt that may lie beyond the grid's last
/// frequency (the amplitude left out is about its square root, 1 %, and falls where the
/// structure's response is small: beyond the retained modes and the GAF table).
pub const TRUNCATION_TOLERANCE: f64 = 1e-4;

/// The part of the window before t = 0 (the gust front at the reference point).
pub const PRE_WINDOW: f64 = 0.05;

/// A uniform frequency grid and the time grid its inverse transform samples.
#[derive(Clone, Debug)]
pub struct TimeGrid {
    /// The span T (s): the period of the computed (periodized) response.
    pub span: f64,
    /// Δω = 2π/T (rad/s).
    pub d_omega: f64,
    /// ω_j = j Δω, j = 0 … M (rad/s), M Δω ≤ the largest frequency asked for.
    pub omega: Vec<f64>,
    /// Time samples t_n = t_0 + n T/N, t_0 = −PRE_WINDOW T (s).
    pub time: Vec<f64>,
}

impl TimeGrid {
    /// The grid of span `span` (s) up to `omega_max` (rad/s), sampled in time at least four times
    /// per period of ω_max (a power of two points, at least 256).
    pub fn new(span: f64, omega_max: f64) -> Result<Self, String> {
        if !(span > 0.0 && span.is_finite() && omega_max > 0.0 && omega_max.is_finite()) {
            return Err(format!(
                "a time grid needs a positive span and largest frequency (got {span} s, {omega_max} rad/s)"
            ));
        }
        let d_omega = 2.0 * std::f64::consts::PI / span;
        let m = (omega_max / d_omega).floor() as usize;
        if m < 8 {
            return Err(format!(
                "the time span {span} s resolves only {m} frequencies below {omega_max:.4} rad/s; it needs at least 8 (span ≥ {:.4} s)",
                16.0 * std::f64::consts::PI / omega_max
            ));
        }
        let n = (4 * (m + 1)).next_power_of_two().max(256);
        let dt = span / n as f64;
        let t0 = -PRE_WINDOW * span;
        Ok(Self {
            span,
            d_omega,
            omega: (0..=m).map(|j| j as f64 * d_omega).collect(),
            time: (0..n).map(|i| t0 + i as f64 * dt).collect(),
        })
    }

    /// Bytes that a grid of span `span` up to `omega_max` and the histories of `n_outputs`
    /// outputs take: per frequency ω, W and one transfer function an output (8 + 16 + 16 per
    /// output), per time sample t, the FFT buffer and one history an output (8 + 16 + 8 per
    /// output); for the memory estimate before a large grid is made.
    pub fn bytes(span: f64, omega_max: f64, n_outputs: usize) -> f64 {
        let m = (omega_max * span / (2.0 * std::f64::consts::PI)).floor() + 1.0;
        let n = ((4.0 * m) as usize).next_power_of_two().max(256) as f64;
        let k = n_outputs as f64;
        m * (24.0 + 16.0 * k) + n * (24.0 + 8.0 * k)
    }
}

/// The inverse transform of one grid, planned once and used for every profile and output.
pub struct Synthesizer {
    fft: Arc<dyn Fft<f64>>,
    buffer: Vec<c64>,
    scratch: Vec<c64>,
    /// e^{iω_j t_0}: the window's start shift.
    shift: Vec<c64>,
    scale: f64,
}

impl Synthesizer {
    pub fn new(grid: &TimeGrid) -> Self {
        let n = grid.time.len();
        let fft = FftPlanner::<f64>::new().plan_fft_inverse(n);
        let t0 = grid.time[0];
        Self {
            scratch: vec![c64::new(0.0, 0.0); fft.get_inplace_scratch_len()],
            fft,
            buffer: vec![c64::new(0.0, 0.0); n],
            shift: grid
                .omega
                .iter()
                .map(|w| c64::new((w * t0).cos(), (w * t0).sin()))
                .collect(),
            scale: grid.d_omega / std::f64::consts::PI,
        }
    }

    /// y(t_n) for the spectrum `y_omega` (one value per grid frequency) into `out` (one value
    /// per time sample).
    pub fn history(&mut self, y_omega: &[c64], out: &mut [f64]) {
        let n = self.buffer.len();
        self.buffer.iter_mut().for_each(|b| *b = c64::new(0.0, 0.0));
        for (j, (y, s)) in y_omega.iter().zip(&self.shift).enumerate() {
            let c = if j == 0 { 0.5 } else { 1.0 };
            // frequencies beyond the time grid's Nyquist fold onto their alias: the sum above
            // is evaluated exactly at the samples whatever N is
            self.buffer[j % n] += y * s * c;
        }
        self.fft
            .process_with_scratch(&mut self.buffer, &mut self.scratch);
        for (o, b) in out.iter_mut().zip(&self.buffer) {
            *o = b.re * self.scale;
        }
    }
}

impl Synthesizer {
    /// The adjoint of [`Synthesizer::history`]: for seeds ȳ_n on the samples, the seeds on the
    /// spectrum in the conjugate convention (δJ = Re Σ conj(Ȳ_j) δY_j, J = Σ ȳ_n y_n):
    /// Ȳ_j = conj[(Δω/π) c_j e^{iω_j t_0} Σ_n ȳ_n e^{2πi jn/N}], one forward-direction FFT.
    pub fn history_adjoint(&mut self, y_bar: &[f64], out: &mut [c64]) {
        let n = self.buffer.len();
        for (b, y) in self.buffer.iter_mut().zip(y_bar) {
            *b = c64::new(*y, 0.0);
        }
        self.fft
            .process_with_scratch(&mut self.buffer, &mut self.scratch);
        for (j, (o, s)) in out.iter_mut().zip(&self.shift).enumerate() {
            let c = if j == 0 { 0.5 } else { 1.0 };
            *o = (self.buffer[j % n] * s * (c * self.scale)).conj();
        }
    }
}

/// The fraction of the gust's energy that the grid up to its last frequency misses:
/// 1 − (1/π) ∫₀^{ω_M} |W|² dω / ∫ w² dt, the integral by the trapezoidal rule on the grid
/// (negative values, the rule's own error, reported as zero).
pub fn truncated_energy(profile: &GustProfile, grid: &TimeGrid) -> f64 {
    let m = grid.omega.len();
    let kept: f64 = grid
        .omega
        .iter()
        .enumerate()
        .map(|(j, &w)| {
            let c = if j == 0 || j == m - 1 { 0.5 } else { 1.0 };
            c * profile.spectrum(w).norm_sqr()
        })
        .sum::<f64>()
        * grid.d_omega
        / std::f64::consts::PI;
    (1.0 - kept / profile.energy()).max(0.0)
}

/// A peak of a time history: the extreme sample refined by the parabola through it and its
/// neighbours.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Peak {
    pub value: f64,
    pub time: f64,
}

/// The largest and the smallest value of `y` on the samples `time` (each refined by a parabola
/// through the extreme sample and its neighbours: the sampling error of a peak falls from
/// O(dt²) to O(dt⁴)).
pub fn extremes(time: &[f64], y: &[f64]) -> (Peak, Peak) {
    let refine = |i: usize| -> Peak {
        if i == 0 || i + 1 >= y.len() {
            return Peak {
                value: y[i],
                time: time[i],
            };
        }
        let (a, b, c) = (y[i - 1], y[i], y[i + 1]);
        let den = a - 2.0 * b + c;
        if den == 0.0 {
            return Peak {
                value: b,
                time: time[i],
            };
        }
        let s = (0.5 * (a - c) / den).clamp(-0.5, 0.5);
        let dt = time[i + 1] - time[i];
        Peak {
            value: b - 0.25 * (a - c) * s,
            time: time[i] + s * dt,
        }
    };
    let (mut imax, mut imin) = (0, 0);
    for (i, v) in y.iter().enumerate() {
        if *v > y[imax] {
            imax = i;
        }
        if *v < y[imin] {
            imin = i;
        }
    }
    (refine(imax), refine(imin))
}

/// The largest |y| in the last tenth of the window over the largest |y| anywhere: how much of
/// the response has not decayed within the span (see [`WRAP_TOLERANCE`]).
pub fn wrap_fraction(y: &[f64]) -> f64 {
    let peak = y.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    if peak == 0.0 {
        return 0.0;
    }
    let tail_start = y.len() - y.len() / 10;
    y[tail_start..].iter().fold(0.0f64, |a, v| a.max(v.abs())) / peak
}

#[cfg(test)]
mod tests;
