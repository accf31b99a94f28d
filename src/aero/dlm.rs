//! The DLM's builder: a CAERO1-like lifting surface on the wing planform (root LE at the origin),
//! boxes laid on the plate's own (ξ, η) parametrization, and the derivatives of the surface's
//! eight geometry parameters with respect to the planform variables (dual numbers through the
//! planform map).

use super::contract::{
    BuildError, Capabilities, ModelFootprint, Sizing, SurfaceBinding, WingBuilder, WingContext,
    WingFidelity,
};
use crate::wing::{planform_point, Planform, N_PLANFORM};
use gustkit_core::scalar::Dual;
use gustkit_dlm::{Dlm, Spacing, SurfaceSpec};
use serde::{Deserialize, Serialize};

/// Box layout of the DLM on the planform.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DlmSpec {
    pub n_chord: usize,
    pub n_span: usize,
    #[serde(default)]
    pub chord_spacing: gustkit_dlm::Spacing,
    #[serde(default)]
    pub span_spacing: gustkit_dlm::Spacing,
    /// `"symmetric"` (a wall-mounted half wing, the default), `"antisymmetric"` or `"none"`.
    #[serde(default = "default_symmetry")]
    pub symmetry: gustkit_dlm::Symmetry,
}

fn default_symmetry() -> gustkit_dlm::Symmetry {
    gustkit_dlm::Symmetry::Symmetric
}

/// The DLM lifting surface of a planform (a CAERO1 from root LE (0, 0, 0) to tip LE) and the
/// derivatives of its 8 parameters with respect to the planform variables.
pub fn dlm_surface(planform: &Planform, spec: &DlmSpec) -> (SurfaceSpec, Vec<[f64; N_PLANFORM]>) {
    let p = planform.to_array();
    let pd: [Dual<N_PLANFORM>; N_PLANFORM] = std::array::from_fn(|k| Dual::var(p[k], k));
    let tip = planform_point(pd, 0.0, 1.0);
    let zero = [0.0; N_PLANFORM];
    let unit = |k: usize| {
        let mut v = zero;
        v[k] = 1.0;
        v
    };
    let jac = vec![
        zero,     // p1.x
        zero,     // p1.y
        zero,     // p1.z
        unit(2),  // c1 = root chord
        tip[0].d, // p4.x = tip LE x
        tip[1].d, // p4.y = span
        zero,     // p4.z
        unit(3),  // c4 = tip chord
    ];
    let surface = SurfaceSpec {
        name: "wing".into(),
        p1: [0.0, 0.0, 0.0],
        c1: planform.root_chord,
        p4: [tip[0].v, tip[1].v, 0.0],
        c4: planform.tip_chord,
        n_chord: spec.n_chord,
        n_span: spec.n_span,
        chord_spacing: spec.chord_spacing.clone(),
        span_spacing: spec.span_spacing.clone(),
    };
    (surface, jac)
}

impl DlmSpec {
    /// The next resolution for the resolution check (twice the boxes each way) and its words.
    pub fn refined(&self) -> (Self, String) {
        let mut d = self.clone();
        d.n_chord *= 2;
        d.n_span *= 2;
        let words = d.words();
        (d, words)
    }

    /// The model in words: its lattice, and its spacings where either is not uniform (two
    /// lattices of the same box counts are different models when their spacings differ).
    pub fn words(&self) -> String {
        let lattice = format!("DLM {} × {} boxes", self.n_chord, self.n_span);
        let name = |s: &Spacing| match s {
            Spacing::Uniform => "uniform",
            Spacing::Cosine => "cosine",
            Spacing::Fractions(_) => "given divisions",
        };
        if self.chord_spacing == Spacing::Uniform && self.span_spacing == Spacing::Uniform {
            return lattice;
        }
        format!(
            "{lattice} (chordwise {}, spanwise {})",
            name(&self.chord_spacing),
            name(&self.span_spacing)
        )
    }

    /// The lattice on a planform (boxes only; influence matrices come with the first GAFs).
    pub fn lattice(&self, planform: &Planform) -> Result<Dlm, BuildError> {
        let (surface, _) = dlm_surface(planform, self);
        Dlm::new(vec![surface], self.symmetry).map_err(|e| BuildError {
            path: String::new(),
            reason: e.to_string(),
        })
    }
}

/// Largest Mach number of the doublet-lattice method: linear subsonic theory, whose kernel
/// (and compressibility factor β = √(1 − M²)) loses meaning as M → 1; transonic flow needs the
/// LFD.
pub const DLM_MAX_MACH: f64 = 0.97;

/// Bytes of the DLM influence matrices of `boxes` boxes at `n_k` reduced frequencies: 32 bytes
/// per (box pair) per reduced frequency for an analysis (the complex AIC and its LU), 100 with
/// gradients (the geometry derivatives; measured 0.79 GB at 864 boxes × 11 k). The matrices of
/// every reduced frequency are alive at once whatever the thread count.
pub fn dlm_bytes(boxes: usize, n_k: usize, gradients: bool) -> f64 {
    let per = if gradients { 100.0 } else { 32.0 };
    per * n_k.max(1) as f64 * (boxes as f64).powi(2)
}

impl WingBuilder for DlmSpec {
    fn name(&self) -> &'static str {
        "dlm"
    }

    fn check_mach(&self, mach: f64) -> Result<(), String> {
        if mach > DLM_MAX_MACH && mach < 1.0 {
            return Err(format!(
                "the doublet-lattice method is linear subsonic theory, valid up to M = {DLM_MAX_MACH} here (got {}); transonic flow needs the lfd fidelity",
                crate::units::show(mach)
            ));
        }
        Ok(())
    }

    fn footprint(&self, sizing: &Sizing) -> Option<ModelFootprint> {
        let boxes = self.n_chord.saturating_mul(self.n_span);
        Some(ModelFootprint {
            what: format!(
                "the DLM's influence matrices of {boxes} boxes ({} × {}) at {} reduced frequencies",
                self.n_chord, self.n_span, sizing.n_k
            ),
            path: if self.n_chord >= self.n_span {
                "n_chord"
            } else {
                "n_span"
            }
            .into(),
            bytes: dlm_bytes(boxes, sizing.n_k, sizing.gradients),
        })
    }

    fn capabilities(&self) -> Capabilities {
        Capabilities {
            reverse: true,
            reverse_planform: true,
        }
    }

    fn validate(&self, wing: &WingContext) -> Result<(), BuildError> {
        let (surface, _) = dlm_surface(wing.planform, self);
        surface.validate(0).map_err(|e| BuildError {
            path: String::new(),
            reason: e.to_string(),
        })
    }

    fn build(&self, wing: &WingContext) -> Result<WingFidelity, BuildError> {
        let planform = wing.planform;
        let (_, jac) = dlm_surface(planform, self);
        let mut dlm = self.lattice(planform)?;
        // only the parameters the planform moves need reverse-mode work
        let active: Vec<usize> = (0..jac.len())
            .filter(|&i| jac[i].iter().any(|v| *v != 0.0))
            .collect();
        dlm.set_active_geometry(0, &active);
        let points = dlm
            .parametric_points()
            .into_iter()
            .map(|(_, p)| p)
            .collect();
        Ok(WingFidelity {
            model: Box::new(dlm),
            binding: SurfaceBinding {
                points,
                geometry_jacobian: jac,
            },
        })
    }
}

/// Boxes per wavelength the doublet-lattice needs: the box chord at most 0.08 V/f, the rule of
/// MSC Nastran's aeroelastic guide (about 12.5 boxes a wavelength of the highest frequency f
/// analysed at speed V), so the downwash of the highest retained mode is resolved.
pub const BOX_PER_WAVELENGTH: f64 = 0.08;

/// The lattice rule checked on a study's DLM: its longest box against 0.08 V/f.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
pub struct LatticeRule {
    /// The longest chordwise box (at the longer of the root and tip chords), m.
    pub box_length_m: f64,
    /// 0.08 V/f, m.
    pub limit_m: f64,
    /// The highest frequency the lattice must resolve (the mode cutoff, or the highest retained
    /// mode), Hz, and what it is.
    pub frequency_hz: f64,
    pub frequency_is: String,
    /// The speed it is resolved at (the flight speed), m/s.
    pub velocity_m_s: f64,
    pub n_chord: usize,
    /// The fewest chordwise boxes (same spacing) that meet the rule.
    pub n_chord_needed: usize,
}

impl LatticeRule {
    pub fn met(&self) -> bool {
        self.box_length_m <= self.limit_m * (1.0 + 1e-9)
    }
}

/// The longest box of `n` chordwise boxes of a chord `c` with this spacing.
fn longest_box(spacing: &gustkit_dlm::Spacing, n: usize, c: f64) -> f64 {
    spacing
        .edges(n)
        .windows(2)
        .map(|w| (w[1] - w[0]) * c)
        .fold(0.0, f64::max)
}

/// The lattice rule of `spec` on `planform` for frequency `f_hz` (what it is: `f_is`) at speed
/// `velocity`.
pub fn lattice_rule(
    spec: &DlmSpec,
    planform: &Planform,
    velocity: f64,
    f_hz: f64,
    f_is: &str,
) -> LatticeRule {
    let c = planform.root_chord.max(planform.tip_chord);
    let limit = BOX_PER_WAVELENGTH * velocity / f_hz;
    let needed = (1..=100_000)
        .find(|&n| longest_box(&spec.chord_spacing, n, c) <= limit)
        .unwrap_or(100_000);
    LatticeRule {
        box_length_m: longest_box(&spec.chord_spacing, spec.n_chord, c),
        limit_m: limit,
        frequency_hz: f_hz,
        frequency_is: f_is.to_string(),
        velocity_m_s: velocity,
        n_chord: spec.n_chord,
        n_chord_needed: needed,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The flagship: 16 boxes on the 0.5587 m root chord are 0.0349 m, within 0.08 × 172.8 /
    /// 226.4 = 0.0611 m (10 boxes would do); the transport wing's 8 boxes on 5 m are 0.625 m
    /// against 0.321 m at 58 Hz and 233 m/s (16 needed). Cosine spacing's longest box is at
    /// mid-chord, sin(π/n)/2 of the chord.
    #[test]
    fn the_rule_on_the_flagship_and_the_transport_wing() {
        let spec = |n: usize, spacing| DlmSpec {
            n_chord: n,
            n_span: 24,
            chord_spacing: spacing,
            span_spacing: gustkit_dlm::Spacing::Uniform,
            symmetry: gustkit_dlm::Symmetry::Symmetric,
        };
        let agard = Planform {
            span: 0.762,
            sweep_c4: 45f64.to_radians(),
            root_chord: 0.558_698_4,
            tip_chord: 0.368_198_4,
        };
        let r = lattice_rule(
            &spec(16, Default::default()),
            &agard,
            172.8,
            226.4,
            "cutoff",
        );
        assert!((r.box_length_m - 0.558_698_4 / 16.0).abs() < 1e-12);
        assert!((r.limit_m - 0.08 * 172.8 / 226.4).abs() < 1e-12);
        assert!(r.met());
        assert_eq!(r.n_chord_needed, 10);
        let transport = Planform {
            span: 15.0,
            sweep_c4: 28f64.to_radians(),
            root_chord: 5.0,
            tip_chord: 1.6,
        };
        let t = lattice_rule(
            &spec(8, Default::default()),
            &transport,
            233.0,
            58.0,
            "cutoff",
        );
        assert!(!t.met());
        assert_eq!(t.n_chord_needed, 16);
        let cosine = lattice_rule(
            &spec(40, gustkit_dlm::Spacing::Cosine),
            &transport,
            233.0,
            58.0,
            "cutoff",
        );
        // exactly c sin(π/n)/2 at mid-chord
        let exact = 0.5 * (std::f64::consts::PI / 40.0).sin() * 5.0;
        assert!((cosine.box_length_m - exact).abs() < 1e-12);
    }
}
