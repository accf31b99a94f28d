//! The aerodynamic contract shared by every fidelity (DLM, LFD).
//!
//! # Conventions (stated once; every fidelity follows them)
//! - Harmonic time dependence `exp(+i ω t)`.
//! - Reduced frequency `k = ω b_ref / U` with the reference **semichord** `b_ref` of
//!   [`FlightCondition`] (Nastran's convention).
//! - Gust: vertical (+z), unit amplitude `w_g / U = 1`, convecting with the flow, phase
//!   `exp(-i ω (x - x_ref) / U) = exp(-i k (x - x_ref) / b_ref)` at streamwise station x, with the
//!   stated `x_ref`.
//! - Generalized aerodynamic forces: the modal force is `q_inf · Q_ss(ik) · η + q_inf · Q_gs(ik) · w_g/U`
//!   (paper Eq. 16), `q_inf = ½ ρ U²`, η the generalized displacements of mass-normalized or any
//!   other modes: Q_ss\[m\]\[n\] is the force on mode m from unit motion of mode n.
//! - Mode shapes reach a fidelity sampled at its [`AeroSurface`] points: displacement vectors and
//!   their streamwise derivatives ∂/∂x (SI, m and m/m).
//! - Reverse mode with complex quantities (paper Sec. III): for a real output J and a complex
//!   Q = a + i b the seed is `Q̄ = ∂J/∂a + i ∂J/∂b`, so that `dJ = Re(conj(Q̄) dQ)`; for real inputs
//!   x, `∂J/∂x = Re(conj(Q̄) ∂Q/∂x)`. A linear map Q = A z then pulls back as z̄ = Aᴴ Q̄.

use num_complex::Complex64;
use serde::{Deserialize, Serialize};

/// Flight condition and the reference values that define k and the gust phase.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FlightCondition {
    /// Free-stream Mach number.
    pub mach: f64,
    /// Free-stream speed U, m/s.
    pub velocity: f64,
    /// Air density ρ, kg/m³.
    pub density: f64,
    /// Reference semichord b_ref of k = ω b_ref / U, m.
    pub b_ref: f64,
    /// Streamwise station where the gust phase is zero, m.
    pub x_ref: f64,
}

impl FlightCondition {
    /// Dynamic pressure q_inf = ½ ρ U², Pa.
    pub fn q_inf(&self) -> f64 {
        0.5 * self.density * self.velocity * self.velocity
    }
    /// Circular frequency of reduced frequency k, rad/s.
    pub fn omega(&self, k: f64) -> f64 {
        k * self.velocity / self.b_ref
    }
    /// Checks the condition is physical.
    pub fn validate(&self) -> Result<(), AeroError> {
        for (name, v) in [
            ("velocity", self.velocity),
            ("density", self.density),
            ("b_ref", self.b_ref),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(AeroError::Input(format!(
                    "{name}: must be positive (got {v})"
                )));
            }
        }
        if !(self.mach >= 0.0 && self.mach.is_finite()) {
            return Err(AeroError::Input(format!(
                "mach: must be non-negative (got {})",
                self.mach
            )));
        }
        if !self.x_ref.is_finite() {
            return Err(AeroError::Input(format!(
                "x_ref: must be finite (got {})",
                self.x_ref
            )));
        }
        Ok(())
    }
}

/// Points where a fidelity wants structural displacements, with the unit normals there.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct AeroSurface {
    pub points: Vec<[f64; 3]>,
    pub normals: Vec<[f64; 3]>,
}

/// Mode shapes sampled on an [`AeroSurface`]: `disp[m][p]` and `disp_x[m][p]` (∂/∂x) for mode m at
/// point p.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ModalSurface {
    pub disp: Vec<Vec<[f64; 3]>>,
    pub disp_x: Vec<Vec<[f64; 3]>>,
}

impl ModalSurface {
    /// Zero shapes for `n_modes` modes on `n_points` points.
    pub fn zeros(n_modes: usize, n_points: usize) -> Self {
        Self {
            disp: vec![vec![[0.0; 3]; n_points]; n_modes],
            disp_x: vec![vec![[0.0; 3]; n_points]; n_modes],
        }
    }
    pub fn n_modes(&self) -> usize {
        self.disp.len()
    }
    /// Every value (displacements, then slopes) in a fixed order, for dot products in tests and
    /// checkers.
    pub fn values(&self) -> impl Iterator<Item = &f64> {
        self.disp.iter().chain(&self.disp_x).flatten().flatten()
    }
    /// Mutable access to every value in the order of [`ModalSurface::values`].
    pub fn values_mut(&mut self) -> impl Iterator<Item = &mut f64> {
        self.disp
            .iter_mut()
            .chain(self.disp_x.iter_mut())
            .flatten()
            .flatten()
    }
    /// Checks the shapes fit a surface of `n_points` points.
    pub fn check(&self, n_points: usize) -> Result<(), AeroError> {
        if self.disp.len() != self.disp_x.len() {
            return Err(AeroError::Input(format!(
                "modes: {} displacement sets but {} slope sets",
                self.disp.len(),
                self.disp_x.len()
            )));
        }
        for (m, (d, dx)) in self.disp.iter().zip(&self.disp_x).enumerate() {
            if d.len() != n_points || dx.len() != n_points {
                return Err(AeroError::Input(format!(
                    "modes: mode {} has {} points, the aerodynamic surface has {n_points}",
                    m + 1,
                    d.len()
                )));
            }
            if d.iter().chain(dx).flatten().any(|v| !v.is_finite()) {
                return Err(AeroError::Input(format!(
                    "modes: mode {} is not finite",
                    m + 1
                )));
            }
        }
        Ok(())
    }
}

/// Whether two reduced frequencies are the same GAF-table row: equal to round-off of their
/// JSON round trip (relative 1e-12, absolute near k = 0).
pub fn same_k(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * b.abs().max(1.0)
}

/// Generalized aerodynamic forces at a list of reduced frequencies (see the module conventions).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GafTable {
    pub mach: f64,
    pub b_ref: f64,
    pub x_ref: f64,
    /// Reduced frequencies.
    pub k: Vec<f64>,
    /// `q_ss[i][m][n]`: structure-on-structure GAFs at k\[i\].
    pub q_ss: Vec<Vec<Vec<Complex64>>>,
    /// `q_gs[i][m]`: gust-on-structure GAFs at k\[i\].
    pub q_gs: Vec<Vec<Complex64>>,
}

impl GafTable {
    /// A table of zeros with the given shape (used for seeds).
    pub fn zeros(flight: &FlightCondition, k: &[f64], n_modes: usize) -> Self {
        Self {
            mach: flight.mach,
            b_ref: flight.b_ref,
            x_ref: flight.x_ref,
            k: k.to_vec(),
            q_ss: vec![vec![vec![Complex64::new(0.0, 0.0); n_modes]; n_modes]; k.len()],
            q_gs: vec![vec![Complex64::new(0.0, 0.0); n_modes]; k.len()],
        }
    }
    pub fn n_modes(&self) -> usize {
        self.q_gs.first().map_or(0, Vec::len)
    }

    /// A table from its per-frequency parts (Q_ss, Q_gs), in the order of `k`.
    pub fn from_parts(
        flight: &FlightCondition,
        k: &[f64],
        parts: Vec<(Vec<Vec<Complex64>>, Vec<Complex64>)>,
    ) -> Self {
        let (q_ss, q_gs) = parts.into_iter().unzip();
        Self {
            mach: flight.mach,
            b_ref: flight.b_ref,
            x_ref: flight.x_ref,
            k: k.to_vec(),
            q_ss,
            q_gs,
        }
    }

    /// Re Σ conj(self) · other over every entry: the real pairing of a seed table with a GAF table
    /// (dJ = seed.pair(dQ) in the conjugate convention).
    pub fn pair(&self, other: &GafTable) -> f64 {
        let ss: f64 = self
            .q_ss
            .iter()
            .flatten()
            .flatten()
            .zip(other.q_ss.iter().flatten().flatten())
            .map(|(a, b)| (a.conj() * b).re)
            .sum();
        let gs: f64 = self
            .q_gs
            .iter()
            .flatten()
            .zip(other.q_gs.iter().flatten())
            .map(|(a, b)| (a.conj() * b).re)
            .sum();
        ss + gs
    }
}

/// Reverse-mode result: gradients with respect to the sampled mode shapes and to the fidelity's
/// geometry parameters (see [`Aerodynamics::geometry_names`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GafGradient {
    pub modes: ModalSurface,
    pub geometry: Vec<f64>,
}

/// One row of a fidelity's linearization checks (paper Table 3): a linearization's product
/// paired with a random vector in forward mode, the same pairing from its reverse-mode
/// (transposed) product where it has one, and real finite differences of the underlying
/// nonlinear function at several steps (step, value).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LinearizationCheck {
    pub name: String,
    pub forward: f64,
    pub reverse: Option<f64>,
    pub fd: Vec<(f64, f64)>,
}

/// Why a fidelity's solver failed: its own words and, for iterative solvers, the residual
/// history (so a stalled solve can be diagnosed from the error alone).
#[derive(Clone, Debug, PartialEq)]
pub struct SolverFailure {
    pub reason: String,
    /// Residual norms of the iterations, where the solver is iterative (relative or absolute,
    /// as the solver states in `reason`).
    pub history: Vec<f64>,
}

impl std::fmt::Display for SolverFailure {
    /// The reason and a one-line digest of the history (the whole history stays in the value).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.reason)?;
        if let (Some(first), Some(last)) = (self.history.first(), self.history.last()) {
            write!(
                f,
                " (residual history: {} values, {first:.3e} first, {last:.3e} last)",
                self.history.len()
            )?;
        }
        Ok(())
    }
}

impl std::error::Error for SolverFailure {}

/// Errors of an aerodynamic model: bad input, a singular system, a solver that failed at a
/// reduced frequency and right-hand side, or a capability the fidelity lacks.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum AeroError {
    #[error("{0}")]
    Input(String),
    #[error("the aerodynamic influence matrix is singular at k = {k}")]
    Singular { k: f64 },
    /// A solver failed (a Krylov solve that stalled, a factorization that broke down). The
    /// failure is part of the message, not a separate source (an error chain printed whole would
    /// repeat it); its residual history stays in the value for a caller that downcasts.
    #[error("solver failed at k = {k} ({rhs}): {failure}")]
    Solver {
        /// The reduced frequency.
        k: f64,
        /// Which right-hand side: "mode 3", "gust", "preconditioner", ….
        rhs: String,
        failure: SolverFailure,
    },
    /// The fidelity has no such capability (e.g. no reverse mode).
    #[error("the {fidelity} fidelity cannot {what}")]
    Unsupported { fidelity: String, what: String },
}

/// Checks a reduced-frequency list: finite, non-negative, no duplicates.
pub fn check_reduced_frequencies(k: &[f64]) -> Result<(), AeroError> {
    if k.is_empty() {
        return Err(AeroError::Input(
            "k: the reduced-frequency list is empty".into(),
        ));
    }
    for (i, &ki) in k.iter().enumerate() {
        if !(ki >= 0.0 && ki.is_finite()) {
            return Err(AeroError::Input(format!(
                "k[{i}]: reduced frequencies must be finite and non-negative (got {ki})"
            )));
        }
        if k[..i].contains(&ki) {
            return Err(AeroError::Input(format!(
                "k[{i}]: duplicate reduced frequency {ki}"
            )));
        }
    }
    Ok(())
}

/// The checks every GAF request shares: a physical flight condition, a valid reduced-frequency
/// list and mode shapes sampled on all `n_points` surface points.
pub fn check_request(
    flight: &FlightCondition,
    modes: &ModalSurface,
    k: &[f64],
    n_points: usize,
) -> Result<(), AeroError> {
    flight.validate()?;
    check_reduced_frequencies(k)?;
    modes.check(n_points)
}

/// Checks reverse-mode seeds against the GAF table they seed: `n_k` frequencies, `n_modes`
/// modes, every row of Q_ss and Q_gs complete.
pub fn check_seeds(seeds: &[GafTable], n_k: usize, n_modes: usize) -> Result<(), AeroError> {
    let fits = |s: &GafTable| {
        s.k.len() == n_k
            && s.q_ss.len() == n_k
            && s.q_gs.len() == n_k
            && s.q_gs.iter().all(|q| q.len() == n_modes)
            && s.q_ss
                .iter()
                .all(|q| q.len() == n_modes && q.iter().all(|r| r.len() == n_modes))
    };
    if seeds.iter().all(fits) {
        Ok(())
    } else {
        Err(AeroError::Input(
            "seed: its shape does not match the GAF table".into(),
        ))
    }
}

/// An aerodynamic model that supplies GAFs. Its reverse mode is a separate capability
/// ([`AerodynamicsReverse`], reached through [`Aerodynamics::reverse`]), so a caller that needs
/// gradients asks for it once, up front, instead of failing at the first gradient.
pub trait Aerodynamics: Send + Sync {
    /// Points where this model wants structural displacements.
    fn surface(&self) -> &AeroSurface;
    /// Names of the geometry parameters that [`GafGradient::geometry`] refers to.
    fn geometry_names(&self) -> Vec<String>;
    /// GAFs at each reduced frequency for modes sampled on [`Aerodynamics::surface`].
    fn gafs(
        &self,
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: &[f64],
    ) -> Result<GafTable, AeroError>;
    /// Does ahead what the GAFs at (`flight`, `k`) need but the modes do not (a DLM's influence
    /// matrices), so that a caller can run it beside the modal analysis; [`Aerodynamics::gafs`]
    /// then reuses it. The default: nothing. Errors are left to `gafs`, which checks its inputs.
    fn prepare(&self, flight: &FlightCondition, k: &[f64]) {
        let _ = (flight, k);
    }
    /// The model's reverse mode, if it has one (the default: none).
    fn reverse(&self) -> Option<&dyn AerodynamicsReverse> {
        None
    }
    /// Checks of the model's linearizations against their transposes and finite differences
    /// (the default: none to show).
    fn linearization_checks(&self) -> Vec<LinearizationCheck> {
        Vec::new()
    }
    /// Flow-field amplitudes of the last GAF table at reduced frequency `k` for a field viewer:
    /// (file stem, legacy-VTK text) per mode column and the gust (the default: none; a model
    /// without a flow field has none to show).
    fn amplitude_fields(&self, k: f64, title: &str) -> Vec<(String, String)> {
        let _ = (k, title);
        Vec::new()
    }
    /// Files a person reads about the model's own state (a CFD model's steady flow field and
    /// surface pressures): (file name, text) for the caller's run folder; a model writes no
    /// file itself (the default: none).
    fn artifacts(&self, title: &str) -> Vec<(String, String)> {
        let _ = title;
        Vec::new()
    }
}

/// The reverse mode of an [`Aerodynamics`] model.
pub trait AerodynamicsReverse: Aerodynamics {
    /// Reverse mode: for seeds on Q_ss and Q_gs (conjugate convention above), the gradient with
    /// respect to the sampled mode shapes and the geometry parameters.
    fn gafs_vjp(
        &self,
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: &[f64],
        seed: &GafTable,
    ) -> Result<GafGradient, AeroError>;
    /// Reverse mode for several seeds at once, one gradient each (none for no seeds). Models
    /// that share work between seeds (factorizations, geometry passes) override it.
    fn gafs_vjp_many(
        &self,
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: &[f64],
        seeds: &[GafTable],
    ) -> Result<Vec<GafGradient>, AeroError> {
        seeds
            .iter()
            .map(|s| self.gafs_vjp(flight, modes, k, s))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reduced_frequency_checks() {
        assert!(check_reduced_frequencies(&[0.0, 0.1, 2.0]).is_ok());
        assert!(check_reduced_frequencies(&[]).is_err());
        let e = check_reduced_frequencies(&[0.1, -0.2]).unwrap_err();
        assert!(e.to_string().contains("k[1]"));
        let e = check_reduced_frequencies(&[0.1, 0.5, 0.1]).unwrap_err();
        assert!(e.to_string().contains("duplicate"));
        assert!(check_reduced_frequencies(&[f64::NAN]).is_err());
    }

    /// The trap of the two reduced-frequency conventions: k = ω b / U uses the semichord, so
    /// ω for k = 1 at U = 100 m/s and b = 0.5 m is 200 rad/s (not 100).
    #[test]
    fn reduced_frequency_uses_semichord() {
        let f = FlightCondition {
            mach: 0.5,
            velocity: 100.0,
            density: 1.2,
            b_ref: 0.5,
            x_ref: 0.0,
        };
        assert_eq!(f.omega(1.0), 200.0);
        assert_eq!(f.q_inf(), 6000.0);
        let mut bad = f;
        bad.mach = -0.1;
        assert!(bad.validate().unwrap_err().to_string().starts_with("mach:"));
        // a bad gust reference station is named as such, not as the Mach number
        let mut bad = f;
        bad.x_ref = f64::NAN;
        assert!(bad
            .validate()
            .unwrap_err()
            .to_string()
            .starts_with("x_ref:"));
    }

    #[test]
    fn modal_surface_shape_check() {
        let m = ModalSurface::zeros(2, 3);
        assert!(m.check(3).is_ok());
        let e = m.check(4).unwrap_err();
        assert!(e.to_string().contains("mode 1 has 3 points"));
    }
}
