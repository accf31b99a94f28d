//! p-k flutter analysis (as Nastran's PK) from a GAF table.
//!
//! At speed V (Mach and density fixed) the modal equations with the aerodynamic matrix split into
//! its real and imaginary parts at k = ω b_ref / V,
//!   [p² I + p (C̄ − q (b_ref/V) Q_I(k)/k) + (K̄ − q Q_R(k))] η = 0,   q = ½ ρ V²,
//! are solved as a real 2n × 2n eigenproblem; for each mode the root whose frequency matches the
//! k it was evaluated at is found by fixed-point iteration on k. Damping g = 2 Re p / Im p, frequency
//! Im p / 2π. An aperiodic root (Im p = 0, k = 0: a divergence or an overdamped branch) has
//! frequency 0 and reports g = 2 b_ref Re p / V (its decay per half-chord of travel, same sign).
//!
//! Branch identity: at every k the roots are assigned to all modes at once (each mode to its own
//! root, nearest pairs of the previous speed's roots first), so two modes never settle on one root,
//! also where frequencies coalesce. Flutter is the lowest speed where a mode's g crosses zero upward, refined by the
//! secant method. Beyond the table's largest k the GAFs are held at that k (only low speeds reach
//! it, where q is small) and the curve point is flagged.

use crate::gust::interp::SplineBasis;
use faer::Mat;
use gustkit_core::GafTable;
use num_complex::Complex64;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// A damping g at or below this is the round-off of a root without aerodynamic damping (a
/// Nastran model's in-plane mode, which the lattice does not see: g = ±1e-15 from one speed
/// to the next), not a crossing into flutter. Physical damping is ten million times larger.
pub const G_ROUNDOFF: f64 = 1e-9;

/// Why a flutter analysis failed.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FlutterError {
    #[error("{0}")]
    Input(String),
    #[error("the p-k iteration for mode {mode} (counted from 1) at V = {velocity:.2} m/s did not converge in {} steps; its last reduced frequencies: {}", history.len(), last_k(history))]
    NoConvergence {
        mode: usize,
        velocity: f64,
        history: Vec<f64>,
    },
    #[error("the eigensolver failed at V = {velocity:.3} m/s")]
    Eigen { velocity: f64 },
}

/// The last four values of a k history, for an error message.
fn last_k(history: &[f64]) -> String {
    let tail = &history[history.len().saturating_sub(4)..];
    tail.iter()
        .map(|k| format!("{k:.10}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Damping and frequency of one mode against speed.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ModeCurve {
    pub mode: usize,
    pub velocity_m_s: Vec<f64>,
    pub damping_g: Vec<f64>,
    pub frequency_hz: Vec<f64>,
    pub k: Vec<f64>,
    /// Whether k exceeded the GAF table (aerodynamics held at the largest k).
    pub extrapolated: Vec<bool>,
    /// Whether the root is aperiodic (real: frequency 0, g = 2 b_ref Re p / V).
    #[serde(default)]
    pub aperiodic: Vec<bool>,
}

/// The result of a p-k sweep.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct FlutterResult {
    pub flutter_speed_m_s: Option<f64>,
    pub flutter_frequency_hz: Option<f64>,
    pub flutter_mode: Option<usize>,
    pub curves: Vec<ModeCurve>,
}

/// Weights of the GAF table entries for the real and imaginary parts of Q(ik) and their slopes
/// ([`PkProblem::aero_weights`]).
pub(crate) struct AeroWeights {
    pub re: Vec<f64>,
    pub d_re: Vec<f64>,
    pub im: Vec<f64>,
    pub d_im: Vec<f64>,
}

/// The structural and aerodynamic data of a p-k analysis.
pub struct PkProblem<'a> {
    pub omega_n: Vec<f64>,
    pub damping_ratio: f64,
    pub table: &'a GafTable,
    pub density: f64,
    /// The table's spline, built at the first query and shared by every p-k iteration after.
    spline: std::sync::OnceLock<Result<SplineBasis, String>>,
}

/// Reduced frequency below which the Q_I/k damping term is held at its value at this k.
pub(crate) const K_HOLD: f64 = 1e-6;

/// A root with |Im p| at most this fraction of |p| counts as aperiodic (real).
const APERIODIC_TOL: f64 = 1e-12;

/// Whether root `p` is aperiodic (real).
pub(crate) fn is_aperiodic(p: Complex64) -> bool {
    p.im.abs() <= APERIODIC_TOL * p.norm()
}

/// The damping g of root `p` at speed `v`: 2 Re p / Im p, or 2 b_ref Re p / V when aperiodic.
pub(crate) fn damping_of(p: Complex64, v: f64, b_ref: f64) -> f64 {
    if is_aperiodic(p) {
        2.0 * b_ref * p.re / v
    } else {
        2.0 * p.re / p.im
    }
}

/// The eigenvalues of a small dense real matrix (a p-k state matrix, 2 × modes): nalgebra's
/// real Schur form, about 2.5 times faster than faer's general solver at this size (12 × 12:
/// 7 µs against 17 µs here), with faer's as the fallback should the QR iteration not converge
/// in 100 n sweeps.
pub(crate) fn eigenvalues(a: &Mat<f64>) -> Option<Vec<Complex64>> {
    let n = a.nrows();
    let m = nalgebra::DMatrix::from_fn(n, n, |i, j| a[(i, j)]);
    match nalgebra::linalg::Schur::try_new(m, f64::EPSILON, 100 * n) {
        Some(schur) => Some(schur.complex_eigenvalues().iter().copied().collect()),
        None => a.eigenvalues().ok(),
    }
}

/// Assigns each of the `refs` (one per mode) its own root among `roots` (those with Im p ≥ 0),
/// nearest pairs first; a mode left over when there are fewer roots than modes takes its nearest.
/// Returns the root index of each mode.
fn assign_roots(refs: &[Complex64], roots: &[Complex64]) -> Vec<usize> {
    let mut pairs: Vec<(f64, usize, usize)> = Vec::with_capacity(refs.len() * roots.len());
    for (m, r) in refs.iter().enumerate() {
        for (j, p) in roots.iter().enumerate() {
            pairs.push(((*p - *r).norm(), m, j));
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut of_mode = vec![usize::MAX; refs.len()];
    let mut taken = vec![false; roots.len()];
    for &(_, m, j) in &pairs {
        if of_mode[m] == usize::MAX && !taken[j] {
            of_mode[m] = j;
            taken[j] = true;
        }
    }
    for &(_, m, j) in &pairs {
        if of_mode[m] == usize::MAX {
            of_mode[m] = j;
        }
    }
    of_mode
}

pub(crate) struct Root {
    g: f64,
    p: Complex64,
    k: f64,
    extrapolated: bool,
}

/// The root among `roots` with Im p ≥ 0 (or aperiodic) nearest `q`.
fn nearest_root(roots: &[Complex64], q: Complex64) -> Option<Complex64> {
    roots
        .iter()
        .filter(|p| p.im > 0.0 || is_aperiodic(**p))
        .min_by(|a, c| (**a - q).norm().total_cmp(&(**c - q).norm()))
        .copied()
}

/// Iterations of the all-modes assignment after which a mode that has not converged follows its
/// own branch by continuity instead ([`track_root`]).
const FREEZE_AFTER: usize = 30;

/// Converges mode `mode`'s p-k root at speed `v` (reference semichord `b`, table's largest k
/// `kmax`) from the roots `refs` of every mode at the previous speed; `roots_at(k)` gives the
/// eigenvalues at reduced frequency k.
///
/// At each k the roots are assigned to all modes at once ([`assign_roots`]) and `mode` follows
/// its own, so modes that coalesce in frequency stay apart by their damping and no two modes share
/// a root. The fixed point k = φ(k) is found by safeguarded secant steps. Where two roots trade
/// places in that assignment as k moves (φ jumps between two branches and the iteration cycles
/// between them), after [`FREEZE_AFTER`] iterations the mode keeps the branch it is on, followed
/// by continuity in k (marched in small steps from one iterate to the next): a continuous φ,
/// whose fixed point is bracketed and found by secant steps kept inside the bracket (bisection
/// where a step leaves it).
pub(crate) fn track_root(
    mode: usize,
    v: f64,
    b: f64,
    kmax: f64,
    refs: &[Complex64],
    mut roots_at: impl FnMut(f64) -> Result<Vec<Complex64>, FlutterError>,
) -> Result<Root, FlutterError> {
    let mut k = refs[mode].im.max(0.0) * b / v;
    let mut history = vec![k];
    let mut last_step = f64::INFINITY;
    // the previous iterate and its residual φ(k) − k, for the secant step
    let mut previous: Option<(f64, f64)> = None;
    // the previous iterate's k and root; after FREEZE_AFTER iterations, the branch followed
    let mut followed: Option<(f64, Complex64)> = None;
    // once frozen: the largest k with φ(k) > k and the smallest with φ(k) < k seen since
    let (mut below, mut above) = (f64::NEG_INFINITY, f64::INFINITY);
    for iteration in 0..200 {
        let frozen = iteration >= FREEZE_AFTER;
        if iteration == FREEZE_AFTER {
            previous = None;
            last_step = f64::INFINITY;
        }
        let p = match followed.filter(|_| frozen) {
            // the branch marched from the k of its last root to this k in small steps, each
            // step's root the nearest to the one before: continuity even where k jumps
            Some((k_from, mut q)) => {
                let h = 2e-3 * k.max(k_from).max(0.05);
                let steps = ((k - k_from).abs() / h).ceil().clamp(1.0, 400.0) as usize;
                for s in 1..=steps {
                    let ks = k_from + (k - k_from) * s as f64 / steps as f64;
                    match nearest_root(&roots_at(ks)?, q) {
                        Some(r) => q = r,
                        None => break,
                    }
                }
                q
            }
            None => {
                let roots: Vec<Complex64> = roots_at(k)?
                    .into_iter()
                    .filter(|p| p.im > 0.0 || is_aperiodic(*p))
                    .collect();
                if roots.is_empty() {
                    break;
                }
                roots[assign_roots(refs, &roots)[mode]]
            }
        };
        followed = Some((k, p));
        let k_new = if is_aperiodic(p) { 0.0 } else { p.im * b / v };
        history.push(k_new);
        // converged to round-off, or at the eigensolver's noise floor (the step has stopped
        // shrinking once below 1e-10): the damping derivatives need the root that tight. The
        // noise of Im p scales with |p| (a heavily damped root has |p| ≫ Im p), so does the
        // tolerance
        let step = (k_new - k).abs();
        let scale = k.max(p.norm() * b / v).max(1e-8);
        if step <= 1e-13 * scale || (step <= 1e-10 * scale && step >= last_step) {
            return Ok(Root {
                g: damping_of(p, v, b),
                p,
                k: k_new,
                extrapolated: k_new > kmax,
            });
        }
        // the fixed point k = φ(k) by the secant method on φ(k) − k, which converges
        // superlinearly where the plain iteration shrinks the error by |φ'| a step; a secant
        // step further from φ(k) than the plain step itself is not taken
        let residual = k_new - k;
        let mut next = k_new;
        let secant = previous
            .filter(|_| !is_aperiodic(p))
            .map(|(k_prev, r_prev)| k - residual * (k - k_prev) / (residual - r_prev))
            .filter(|s| s.is_finite() && *s > 0.0);
        if frozen {
            // on one branch φ is continuous: keep the root bracketed
            if residual > 0.0 {
                below = below.max(k);
            } else {
                above = above.min(k);
            }
            let inside = |x: f64| x > below && x < above;
            next = match secant {
                Some(s) if inside(s) => s,
                _ if inside(k_new) => k_new,
                _ => 0.5 * (below + above),
            };
        } else if let Some(s) = secant.filter(|s| (s - k_new).abs() <= step) {
            next = s;
        }
        previous = Some((k, residual));
        k = next;
        last_step = step;
    }
    Err(FlutterError::NoConvergence {
        mode: mode + 1,
        velocity: v,
        history,
    })
}

impl<'a> PkProblem<'a> {
    /// The p-k problem of a modal model with the GAF table of its modes, at air density `density`.
    pub fn new(modes: &crate::structure::Modes, table: &'a GafTable, density: f64) -> Self {
        Self::from_parts(modes.omega(), modes.damping_ratio, table, density)
    }

    /// The p-k problem of natural circular frequencies `omega_n` (rad/s) with modal damping ratio
    /// `damping_ratio`, GAF table `table` and air density `density`.
    pub fn from_parts(
        omega_n: Vec<f64>,
        damping_ratio: f64,
        table: &'a GafTable,
        density: f64,
    ) -> Self {
        Self {
            omega_n,
            damping_ratio,
            table,
            density,
            spline: std::sync::OnceLock::new(),
        }
    }
}

impl PkProblem<'_> {
    fn check(&self) -> Result<(), FlutterError> {
        if self.table.n_modes() != self.omega_n.len() {
            return Err(FlutterError::Input(format!(
                "the GAF table has {} modes, the structure {}",
                self.table.n_modes(),
                self.omega_n.len()
            )));
        }
        if !(self.density > 0.0) {
            return Err(FlutterError::Input(format!(
                "density: must be positive (got {})",
                self.density
            )));
        }
        if !(self.damping_ratio >= 0.0) {
            return Err(FlutterError::Input(format!(
                "damping_ratio: must be non-negative (got {})",
                self.damping_ratio
            )));
        }
        Ok(())
    }

    /// Q(k) by the table's spline (clamped to its range) as (real part, imaginary part), and the
    /// slope dQ/dk the same way (zero outside the table, where Q is held).
    /// The slopes only when `slope` (else empty matrices: the roots alone need none).
    fn q_at_with(&self, k: f64, slope: bool) -> Result<[Mat<f64>; 4], FlutterError> {
        let w = self.aero_weights(k)?;
        let n = self.omega_n.len();
        let q = |w: &[f64], m: usize, j: usize| -> Complex64 {
            w.iter()
                .enumerate()
                .map(|(i, wi)| self.table.q_ss[i][m][j] * *wi)
                .sum()
        };
        let ns = if slope { n } else { 0 };
        Ok([
            Mat::from_fn(n, n, |m, j| q(&w.re, m, j).re),
            Mat::from_fn(n, n, |m, j| q(&w.im, m, j).im),
            Mat::from_fn(ns, ns, |m, j| q(&w.d_re, m, j).re),
            Mat::from_fn(ns, ns, |m, j| q(&w.d_im, m, j).im),
        ])
    }

    /// The weights of the table entries that give the real and imaginary parts of the GAFs at k,
    /// and of their slopes d/dk. Inside the table: the spline. Below k = 1e-6 the imaginary part
    /// is taken at that k (the Q_I/k damping term held at its steady limit). Beyond the table's
    /// last k (k_n): the high-frequency asymptote of unsteady aerodynamics, Q ≈ A₀ + i k A₁ − k² A₂
    /// (apparent stiffness, damping and mass), joined to the spline with its value and slope at
    /// k_n: Re Q(k) = Re Q(k_n) + (k² − k_n²) Re Q'(k_n) / (2 k_n), Im Q(k) = Im Q(k_n) + (k − k_n)
    /// Im Q'(k_n). Holding the GAFs at k_n instead made the aerodynamic damping Q_I/k vanish as
    /// 1/k, and high modes at low speeds (k ≈ 15 for the AGARD wing's 20th mode at a fifth of the
    /// flight speed) came out spuriously undamped.
    pub(crate) fn aero_weights(&self, k: f64) -> Result<AeroWeights, FlutterError> {
        let kmax = *self.table.k.last().expect("table has k");
        let (w, dw) = self.spline_at(k.min(kmax))?;
        let (w_im, dw_im) = if k < K_HOLD {
            self.spline_at(K_HOLD)?
        } else {
            (w.clone(), dw.clone())
        };
        if k <= kmax {
            return Ok(AeroWeights {
                re: w,
                d_re: dw,
                im: w_im,
                d_im: dw_im,
            });
        }
        let c = (k * k - kmax * kmax) / (2.0 * kmax);
        Ok(AeroWeights {
            re: w.iter().zip(&dw).map(|(w, d)| w + c * d).collect(),
            d_re: dw.iter().map(|d| k / kmax * d).collect(),
            im: w.iter().zip(&dw).map(|(w, d)| w + (k - kmax) * d).collect(),
            d_im: dw,
        })
    }

    /// Spline weights of the table at k clamped to its range, and the weights of its slope d/dk
    /// (at the clamped k).
    fn spline_at(&self, k: f64) -> Result<(Vec<f64>, Vec<f64>), FlutterError> {
        let kmax = *self.table.k.last().expect("table has k");
        let kk = k.clamp(self.table.k[0], kmax);
        let basis = self
            .spline
            .get_or_init(|| SplineBasis::new(&self.table.k))
            .as_ref()
            .map_err(|e| FlutterError::Input(e.clone()))?;
        let n = self.table.k.len();
        let (mut w, mut dw) = (vec![0.0; n], vec![0.0; n]);
        basis
            .weights_at(kk, &mut w, &mut dw)
            .map_err(FlutterError::Input)?;
        Ok((w, dw))
    }

    /// The first-order state matrix of the p-k equation at speed `v` with the aerodynamics at `k`,
    /// and its derivative with respect to k.
    fn state_matrix(&self, v: f64, k: f64) -> Result<(Mat<f64>, Mat<f64>), FlutterError> {
        self.state_matrix_with(v, k, true)
    }

    /// [`Self::state_matrix`], the derivative only when `slope` (else an empty matrix).
    fn state_matrix_with(
        &self,
        v: f64,
        k: f64,
        slope: bool,
    ) -> Result<(Mat<f64>, Mat<f64>), FlutterError> {
        let n = self.omega_n.len();
        let beta = self.table.b_ref / v;
        let qd = 0.5 * self.density * v * v;
        let [qr, qi, dqr, dqi] = self.q_at_with(k, slope)?;
        // below k = 1e-6 the Q_I/k term is held, as the steady limit of the damping
        let (kk, dkk) = if k >= K_HOLD { (k, 1.0) } else { (K_HOLD, 0.0) };
        let mut a = Mat::<f64>::zeros(2 * n, 2 * n);
        let ns = if slope { 2 * n } else { 0 };
        let mut a_k = Mat::<f64>::zeros(ns, ns);
        for i in 0..n {
            a[(i, n + i)] = 1.0;
            for j in 0..n {
                let kstiff = if i == j { self.omega_n[i].powi(2) } else { 0.0 } - qd * qr[(i, j)];
                let cdamp = if i == j {
                    2.0 * self.damping_ratio * self.omega_n[i]
                } else {
                    0.0
                } - qd * beta * qi[(i, j)] / kk;
                a[(n + i, j)] = -kstiff;
                a[(n + i, n + j)] = -cdamp;
                if slope {
                    a_k[(n + i, j)] = qd * dqr[(i, j)];
                    a_k[(n + i, n + j)] =
                        qd * beta * (dqi[(i, j)] / kk - dkk * qi[(i, j)] / (kk * kk));
                }
            }
        }
        Ok((a, a_k))
    }

    /// Roots p of the p-k equation at speed `v` with the aerodynamics evaluated at `k`.
    fn roots(&self, v: f64, k: f64) -> Result<Vec<Complex64>, FlutterError> {
        let (mut a, _) = self.state_matrix_with(v, k, false)?;
        // the similarity D⁻¹ A D with D = diag(I, s I), s the largest natural frequency, brings
        // the stiffness block (ω², up to 1e6 and more) and the identity block to one scale: the
        // eigenvalues are the same, their rounding errors those of a balanced matrix
        let n = self.omega_n.len();
        let s = self.omega_n.iter().copied().fold(0.0, f64::max);
        if s > 0.0 && s.is_finite() {
            for i in 0..n {
                for j in 0..n {
                    a[(i, n + j)] *= s;
                    a[(n + i, j)] /= s;
                }
            }
        }
        eigenvalues(&a).ok_or(FlutterError::Eigen { velocity: v })
    }

    /// Converges mode `mode`'s root at speed `v` from the roots `refs` of every mode at the
    /// previous speed ([`track_root`] on this problem's eigenvalues).
    fn track(&self, mode: usize, v: f64, refs: &[Complex64]) -> Result<Root, FlutterError> {
        let b = self.table.b_ref;
        let kmax = *self.table.k.last().expect("table has k");
        track_root(mode, v, b, kmax, refs, |k| self.roots(v, k))
    }

    /// The largest damping g over every consistent p-k root at speed `v`: for each k at which a
    /// mode converged, any root whose own k matches the one it was computed at. Positive means the
    /// system is unstable at `v`, whichever branch the tracking followed.
    pub fn max_damping(&self, v: f64, ks: &[f64]) -> Result<f64, FlutterError> {
        let b = self.table.b_ref;
        let mut gmax = f64::NEG_INFINITY;
        for &k in ks {
            for p in self.roots(v, k)? {
                if p.im > 0.0 && ((p.im * b / v) - k).abs() <= 1e-6 * k.max(1e-8) {
                    gmax = gmax.max(2.0 * p.re / p.im);
                }
            }
        }
        Ok(gmax)
    }

    /// p-k sweep over `velocities` (increasing) with the flutter crossing refined.
    pub fn sweep(&self, velocities: &[f64]) -> Result<FlutterResult, FlutterError> {
        Ok(self.sweep_roots(velocities)?.0)
    }

    /// The p-k sweep and every curve point's root p (rad/s), per mode and speed.
    pub(crate) fn sweep_roots(
        &self,
        velocities: &[f64],
    ) -> Result<(FlutterResult, Vec<Vec<Complex64>>), FlutterError> {
        self.check()?;
        if velocities.is_empty()
            || velocities.iter().any(|v| !(*v > 0.0))
            || velocities.windows(2).any(|w| !(w[1] > w[0]))
        {
            return Err(FlutterError::Input(
                "velocities: must be positive and increasing".into(),
            ));
        }
        let n = self.omega_n.len();
        let mut curves: Vec<ModeCurve> = (0..n)
            .map(|m| ModeCurve {
                mode: m + 1,
                velocity_m_s: Vec::new(),
                damping_g: Vec::new(),
                frequency_hz: Vec::new(),
                k: Vec::new(),
                extrapolated: Vec::new(),
                aperiodic: Vec::new(),
            })
            .collect();
        let mut roots: Vec<Vec<Complex64>> = vec![Vec::with_capacity(velocities.len()); n];
        let mut p_prev: Vec<Complex64> = self
            .omega_n
            .iter()
            .map(|w| Complex64::new(0.0, *w))
            .collect();
        let mut flutter: Option<(f64, f64, usize)> = None;
        for (iv, &v) in velocities.iter().enumerate() {
            // every mode starts from the previous speed's roots of all modes, so the modes are
            // independent at one speed: tracked in parallel (results in mode order)
            let mut p_now = p_prev.clone();
            let tracked: Vec<Root> = (0..n)
                .into_par_iter()
                .map(|m| self.track(m, v, &p_prev))
                .collect::<Result<_, _>>()?;
            for (m, r) in tracked.into_iter().enumerate() {
                p_now[m] = r.p;
                let c = &mut curves[m];
                if iv > 0 && flutter.is_none() {
                    let (g0, v0) = (
                        *c.damping_g.last().expect("previous point"),
                        velocities[iv - 1],
                    );
                    if g0 < 0.0 && r.g > G_ROUNDOFF {
                        flutter = Some(self.refine(m, (v0, g0), (v, r.g), &p_prev)?);
                    }
                }
                c.velocity_m_s.push(v);
                c.damping_g.push(r.g);
                c.frequency_hz
                    .push(r.p.im.max(0.0) / (2.0 * std::f64::consts::PI));
                c.k.push(r.k);
                c.extrapolated.push(r.extrapolated);
                c.aperiodic.push(is_aperiodic(r.p));
                roots[m].push(r.p);
            }
            p_prev = p_now;
        }
        Ok((
            FlutterResult {
                flutter_speed_m_s: flutter.map(|f| f.0),
                flutter_frequency_hz: flutter.map(|f| f.1),
                flutter_mode: flutter.map(|f| f.2 + 1),
                curves,
            },
            roots,
        ))
    }

    /// Secant refinement of g(V) = 0 between two bracketing speeds, every mode's branch followed
    /// from the roots `refs` at the lower speed.
    fn refine(
        &self,
        mode: usize,
        lo: (f64, f64),
        hi: (f64, f64),
        refs: &[Complex64],
    ) -> Result<(f64, f64, usize), FlutterError> {
        let (mut a, mut b) = (lo, hi);
        let mut best = (b.0, 0.0);
        for _ in 0..60 {
            let v = a.0 - a.1 * (b.0 - a.0) / (b.1 - a.1);
            let r = self.track(mode, v, refs)?;
            best = (v, r.p.im.max(0.0) / (2.0 * std::f64::consts::PI));
            if r.g.abs() < 1e-10 || (b.0 - a.0).abs() < 1e-10 * v {
                break;
            }
            // keep the bracket (Illinois-free regula falsi is fine for this smooth g)
            if r.g < 0.0 {
                a = (v, r.g);
            } else {
                b = (v, r.g);
            }
        }
        Ok((best.0, best.1, mode))
    }
}

pub mod margin;
pub mod stability;
pub mod verdict;

pub use stability::check_stability;
pub use verdict::Verdict;

#[cfg(test)]
mod tests;
