//! Lifting surfaces and their boxes, generic over the scalar so box geometry can carry derivatives
//! with respect to the surface parameters.

use gustkit_core::scalar::Scalar;
use gustkit_core::AeroError;
use serde::{Deserialize, Serialize};

/// Distribution of box edges along a direction.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Spacing {
    #[default]
    Uniform,
    /// Cosine spacing, clustered at both ends.
    Cosine,
    /// Given edge fractions in [0, 1], increasing (Nastran's AEFACT divisions of a CAERO1: the
    /// boxes may cover part of the panel, as when several CAERO1 share one planform).
    Fractions(Vec<f64>),
}

impl Spacing {
    /// The n + 1 edge fractions in [0, 1].
    pub fn edges(&self, n: usize) -> Vec<f64> {
        if let Spacing::Fractions(f) = self {
            return f.clone();
        }
        (0..=n)
            .map(|i| {
                let t = i as f64 / n as f64;
                match self {
                    Spacing::Cosine => 0.5 * (1.0 - (std::f64::consts::PI * t).cos()),
                    _ => t,
                }
            })
            .collect()
    }

    /// Checks given fractions against the box count `n`: n + 1 increasing values in [0, 1].
    pub fn validate(&self, n: usize) -> Result<(), String> {
        let Spacing::Fractions(f) = self else {
            return Ok(());
        };
        if f.len() != n + 1 {
            return Err(format!(
                "{} edge fractions for {n} boxes (need {})",
                f.len(),
                n + 1
            ));
        }
        if !(f[0] >= 0.0 && f[n] <= 1.0) || f.windows(2).any(|w| !(w[1] > w[0])) {
            return Err(format!(
                "edge fractions must increase within [0, 1] (got {f:?})"
            ));
        }
        Ok(())
    }
}

/// A trapezoidal lifting surface (like Nastran's CAERO1): root leading-edge point `p1`, streamwise
/// root chord `c1`, tip leading-edge point `p4`, streamwise tip chord `c4` (SI), divided into
/// `n_chord × n_span` boxes. Surfaces are defined root (left) to tip (right): p4.y > p1.y, or
/// p4.z > p1.z for a vertical surface.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceSpec {
    pub name: String,
    pub p1: [f64; 3],
    pub c1: f64,
    pub p4: [f64; 3],
    pub c4: f64,
    pub n_chord: usize,
    pub n_span: usize,
    #[serde(default)]
    pub chord_spacing: Spacing,
    #[serde(default)]
    pub span_spacing: Spacing,
}

/// Geometry parameters of a surface in [`SurfaceSpec::params`] order.
pub const SURFACE_PARAMS: [&str; 8] = ["p1.x", "p1.y", "p1.z", "c1", "p4.x", "p4.y", "p4.z", "c4"];

impl SurfaceSpec {
    /// The 8 geometry parameters (p1, c1, p4, c4).
    pub fn params(&self) -> [f64; 8] {
        [
            self.p1[0], self.p1[1], self.p1[2], self.c1, self.p4[0], self.p4[1], self.p4[2],
            self.c4,
        ]
    }

    /// Checks the surface; `idx` names it in messages.
    pub fn validate(&self, idx: usize) -> Result<(), AeroError> {
        let name = |f: &str| format!("surfaces[{idx}] ({}): {f}", self.name);
        if self.n_chord == 0 || self.n_span == 0 {
            return Err(AeroError::Input(name(
                "n_chord and n_span must be at least 1",
            )));
        }
        if !(self.c1 > 0.0 && self.c4 > 0.0) {
            return Err(AeroError::Input(name(&format!(
                "chords must be positive (c1 = {}, c4 = {}): a box of zero area",
                self.c1, self.c4
            ))));
        }
        for (what, spacing, n) in [
            ("chord_spacing", &self.chord_spacing, self.n_chord),
            ("span_spacing", &self.span_spacing, self.n_span),
        ] {
            spacing
                .validate(n)
                .map_err(|e| AeroError::Input(name(&format!("{what}: {e}"))))?;
        }
        if self.params().iter().any(|v| !v.is_finite()) {
            return Err(AeroError::Input(name("coordinates must be finite")));
        }
        let (dy, dz) = (self.p4[1] - self.p1[1], self.p4[2] - self.p1[2]);
        if dy.hypot(dz) <= 1e-12 * self.c1.max(self.c4) {
            return Err(AeroError::Input(name(
                "p1 and p4 coincide in the y-z plane: boxes of zero span",
            )));
        }
        if dy < 0.0 || (dy == 0.0 && dz < 0.0) {
            return Err(AeroError::Input(name(
                "boxes are defined right to left (p4 must lie at larger y than p1, or above it for a vertical surface)",
            )));
        }
        Ok(())
    }
}

/// One box: doublet line at its ¼-chord, control point at ¾-chord mid-span, all in SI.
#[derive(Clone, Copy, Debug)]
pub struct AeroBox<S> {
    /// Corners: inboard LE, inboard TE, outboard TE, outboard LE.
    pub corners: [[S; 3]; 4],
    /// Inboard and outboard ends of the doublet line (¼-chord of the box edges).
    pub line_a: [S; 3],
    pub line_b: [S; 3],
    /// Control (normalwash) point: ¾-chord at mid-span.
    pub cp: [S; 3],
    /// Doublet (force) point: ¼-chord at mid-span.
    pub dp: [S; 3],
    /// Streamwise box chord at mid-span.
    pub chord: S,
    /// Box area.
    pub area: S,
    /// Half-span e of the doublet line in the y-z plane.
    pub e: S,
    /// tan of the doublet line's sweep, Δx / (2e).
    pub tan_sweep: S,
    /// cos γ, sin γ of the dihedral γ = atan2(Δz, Δy).
    pub cos_g: S,
    pub sin_g: S,
}

impl<S: Scalar> AeroBox<S> {
    /// Unit normal (0, −sin γ, cos γ).
    pub fn normal(&self) -> [S; 3] {
        [S::zero(), -self.sin_g, self.cos_g]
    }

    /// The mirror image in the x-z plane (y → −y), itself defined left to right.
    pub fn mirrored(&self) -> Self {
        let m = |p: [S; 3]| [p[0], -p[1], p[2]];
        let c = self.corners;
        Self {
            corners: [m(c[3]), m(c[2]), m(c[1]), m(c[0])],
            line_a: m(self.line_b),
            line_b: m(self.line_a),
            cp: m(self.cp),
            dp: m(self.dp),
            tan_sweep: -self.tan_sweep,
            sin_g: -self.sin_g,
            ..*self
        }
    }
}

/// Parametric coordinates (ξ chord fraction, η span fraction) of a box's control point (¾-chord,
/// mid-span) and doublet point (¼-chord, mid-span), the same for any values of the surface
/// parameters; chordwise index fastest.
pub fn box_parametric_points(spec: &SurfaceSpec) -> Vec<([f64; 2], [f64; 2])> {
    let xi = spec.chord_spacing.edges(spec.n_chord);
    let eta = spec.span_spacing.edges(spec.n_span);
    let mut out = Vec::with_capacity(spec.n_chord * spec.n_span);
    for j in 0..spec.n_span {
        let em = 0.5 * (eta[j] + eta[j + 1]);
        for i in 0..spec.n_chord {
            let (xa, xb) = (xi[i], xi[i + 1]);
            out.push(([xa + 0.75 * (xb - xa), em], [xa + 0.25 * (xb - xa), em]));
        }
    }
    out
}

/// Boxes of a surface for parameters `q` (see [`SURFACE_PARAMS`]); chordwise index fastest.
pub fn surface_boxes<S: Scalar>(spec: &SurfaceSpec, q: [S; 8]) -> Vec<AeroBox<S>> {
    let p1 = [q[0], q[1], q[2]];
    let p4 = [q[4], q[5], q[6]];
    let (c1, c4) = (q[3], q[7]);
    let xi = spec.chord_spacing.edges(spec.n_chord);
    let eta = spec.span_spacing.edges(spec.n_span);
    let dy = p4[1] - p1[1];
    let dz = p4[2] - p1[2];
    let width = (dy * dy + dz * dz).sqrt();
    let (cos_g, sin_g) = (dy / width, dz / width);
    let point = |xi: f64, eta: f64| -> [S; 3] {
        let c = c1 + (c4 - c1) * eta;
        [
            p1[0] + (p4[0] - p1[0]) * eta + c * xi,
            p1[1] + dy * eta,
            p1[2] + dz * eta,
        ]
    };
    let params = box_parametric_points(spec);
    let mut boxes = Vec::with_capacity(spec.n_chord * spec.n_span);
    for j in 0..spec.n_span {
        let (ea, eb) = (eta[j], eta[j + 1]);
        let em = 0.5 * (ea + eb);
        for i in 0..spec.n_chord {
            let (xa, xb) = (xi[i], xi[i + 1]);
            let xq = xa + 0.25 * (xb - xa);
            let line_a = point(xq, ea);
            let line_b = point(xq, eb);
            let e = width * (0.5 * (eb - ea));
            let chord = (c1 + (c4 - c1) * em) * (xb - xa);
            let ([cx, ce], [dx, de]) = params[j * spec.n_chord + i];
            boxes.push(AeroBox {
                corners: [point(xa, ea), point(xb, ea), point(xb, eb), point(xa, eb)],
                line_a,
                line_b,
                cp: point(cx, ce),
                dp: point(dx, de),
                chord,
                area: chord * e * 2.0,
                e,
                tan_sweep: (line_b[0] - line_a[0]) / (e * 2.0),
                cos_g,
                sin_g,
            });
        }
    }
    boxes
}

/// Checks that coplanar surfaces share their strip edges where their spans overlap, as the DLM
/// requires for accurate interference (the doublet lines of one strip must not straddle another's).
pub fn check_strip_alignment(specs: &[SurfaceSpec]) -> Result<(), AeroError> {
    let tol = 1e-6;
    for a in 0..specs.len() {
        for b in a + 1..specs.len() {
            let (sa, sb) = (&specs[a], &specs[b]);
            let plane = |s: &SurfaceSpec| {
                let (dy, dz) = (s.p4[1] - s.p1[1], s.p4[2] - s.p1[2]);
                let g = dz.atan2(dy);
                // offset of the plane from the origin along its normal
                (g, s.p1[2] * g.cos() - s.p1[1] * g.sin())
            };
            let (ga, oa) = plane(sa);
            let (gb, ob) = plane(sb);
            if (ga - gb).abs() > 1e-9 || (oa - ob).abs() > tol {
                continue;
            }
            // spanwise coordinate along the plane
            let along = |s: &SurfaceSpec| -> Vec<f64> {
                let (y1, z1, y4, z4) = (s.p1[1], s.p1[2], s.p4[1], s.p4[2]);
                let (c, sn) = (ga.cos(), ga.sin());
                let (s1, s4) = (y1 * c + z1 * sn, y4 * c + z4 * sn);
                s.span_spacing
                    .edges(s.n_span)
                    .iter()
                    .map(|t| s1 + t * (s4 - s1))
                    .collect()
            };
            let (ea, eb) = (along(sa), along(sb));
            let lo = ea[0].max(eb[0]);
            let hi = ea[ea.len() - 1].min(eb[eb.len() - 1]);
            if hi - lo <= tol {
                continue;
            }
            let inside = |v: f64| v > lo + tol && v < hi - tol;
            for v in ea.iter().chain(&eb).copied().filter(|v| inside(*v)) {
                let on_a = ea.iter().any(|w| (w - v).abs() <= tol);
                let on_b = eb.iter().any(|w| (w - v).abs() <= tol);
                if !(on_a && on_b) {
                    return Err(AeroError::Input(format!(
                        "surfaces[{a}] ({}) and surfaces[{b}] ({}) lie in one plane but their strips do not line up (edge at {v:.6} m belongs to one only)",
                        sa.name, sb.name
                    )));
                }
            }
        }
    }
    Ok(())
}
