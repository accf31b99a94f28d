//! Airfoil sections for the built-in meshes: the NACA 64A010 from its published 6A-series
//! ordinates (NACA Report 903; not the 4-digit thickness formula), as a closed curve.

/// NACA 64A010 upper-surface ordinates, percent chord: (x, y). Symmetric section; the trailing
/// edge is blunt (y = 0.021 % at x = 100 %), and aft of 80 % chord the surface is straight (the
/// "A" modification).
pub const NACA64A010: [(f64, f64); 26] = [
    (0.0, 0.0),
    (0.5, 0.804),
    (0.75, 0.969),
    (1.25, 1.225),
    (2.5, 1.688),
    (5.0, 2.327),
    (7.5, 2.805),
    (10.0, 3.199),
    (15.0, 3.813),
    (20.0, 4.272),
    (25.0, 4.606),
    (30.0, 4.837),
    (35.0, 4.968),
    (40.0, 4.995),
    (45.0, 4.894),
    (50.0, 4.684),
    (55.0, 4.388),
    (60.0, 4.021),
    (65.0, 3.597),
    (70.0, 3.127),
    (75.0, 2.623),
    (80.0, 2.103),
    (85.0, 1.582),
    (90.0, 1.062),
    (95.0, 0.541),
    (100.0, 0.021),
];

/// A symmetric section given by half-thickness ordinates, interpolated by a natural cubic spline
/// of y in s = √x (y grows like √x at a round leading edge, so y(s) is smooth there).
#[derive(Clone, Debug)]
pub struct AirfoilShape {
    s: Vec<f64>,
    y: Vec<f64>,
    /// Second derivatives d²y/ds² at the nodes.
    m: Vec<f64>,
}

impl AirfoilShape {
    /// From (x, y) pairs in fractions of the chord, x increasing from 0 to 1.
    pub fn new(xy: &[(f64, f64)]) -> Self {
        let s: Vec<f64> = xy.iter().map(|p| p.0.sqrt()).collect();
        let y: Vec<f64> = xy.iter().map(|p| p.1).collect();
        let n = s.len();
        // natural spline: tridiagonal system for the second derivatives (Thomas algorithm)
        let h: Vec<f64> = s.windows(2).map(|w| w[1] - w[0]).collect();
        let mut a = vec![0.0; n];
        let mut b = vec![1.0; n];
        let mut c = vec![0.0; n];
        let mut d = vec![0.0; n];
        for i in 1..n - 1 {
            a[i] = h[i - 1];
            b[i] = 2.0 * (h[i - 1] + h[i]);
            c[i] = h[i];
            d[i] = 6.0 * ((y[i + 1] - y[i]) / h[i] - (y[i] - y[i - 1]) / h[i - 1]);
        }
        for i in 1..n {
            let w = a[i] / b[i - 1];
            b[i] -= w * c[i - 1];
            d[i] -= w * d[i - 1];
        }
        let mut m = vec![0.0; n];
        m[n - 1] = d[n - 1] / b[n - 1];
        for i in (0..n - 1).rev() {
            m[i] = (d[i] - c[i] * m[i + 1]) / b[i];
        }
        Self { s, y, m }
    }

    /// The NACA 64A010 (chord 1).
    pub fn naca64a010() -> Self {
        let xy: Vec<(f64, f64)> = NACA64A010
            .iter()
            .map(|(x, y)| (x / 100.0, y / 100.0))
            .collect();
        Self::new(&xy)
    }

    /// Half thickness at chord fraction x ∈ [0, 1].
    pub fn half_thickness(&self, x: f64) -> f64 {
        let sx = x.clamp(0.0, 1.0).sqrt();
        let n = self.s.len();
        let i = self.s.partition_point(|&v| v <= sx).clamp(1, n - 1) - 1;
        let h = self.s[i + 1] - self.s[i];
        let (t, u) = ((sx - self.s[i]) / h, (self.s[i + 1] - sx) / h);
        u * self.y[i]
            + t * self.y[i + 1]
            + ((u * u * u - u) * self.m[i] + (t * t * t - t) * self.m[i + 1]) * h * h / 6.0
    }

    /// The built-in O-mesh around the section (chord 1, mid-chord at the origin; see
    /// [`crate::mesh::o_mesh`] for the other arguments): its `n_around` wall points run from the
    /// upper to the lower trailing-edge corner, so the blunt base is one face (a sharp section:
    /// from the trailing-edge node round to it), and the mesh is symmetric about the chord line (a
    /// symmetric section has no lift at zero incidence).
    pub fn o_mesh(
        &self,
        n_around: usize,
        n_radial: usize,
        r_far: f64,
        first: f64,
        dz: f64,
    ) -> crate::mesh::Mesh {
        // blunt: the last point is the lower corner (the base is one face); sharp: the trailing
        // edge is one node and the contour closes on it
        let stretch = if self.half_thickness(1.0) == 0.0 {
            1.0
        } else {
            n_around as f64 / (n_around - 1) as f64
        };
        crate::mesh::o_mesh(
            &|t| {
                let p = self.contour(t * stretch);
                [p[0] - 0.5, p[1]]
            },
            n_around,
            n_radial,
            r_far,
            first,
            dz,
        )
    }

    /// The section closed to a sharp trailing edge: the linear ramp x · y(1) taken off every
    /// ordinate (exact on the spline in s = √x, since s² is a quadratic), which changes the
    /// 64A010 by at most its 0.021 % base half-thickness.
    pub fn sharp(&self) -> Self {
        let y_te = *self.y.last().expect("a section has ordinates");
        Self {
            s: self.s.clone(),
            y: self
                .s
                .iter()
                .zip(&self.y)
                .map(|(s, y)| y - s * s * y_te)
                .collect(),
            m: self.m.iter().map(|m| m - 2.0 * y_te).collect(),
        }
    }

    /// The same section with every ordinate scaled by `factor` (e.g. 0.4: a 4 %-thick NACA
    /// 64A004-like section from the 64A010 ordinates, for thin-airfoil comparisons).
    pub fn scaled(&self, factor: f64) -> Self {
        Self {
            s: self.s.clone(),
            y: self.y.iter().map(|v| v * factor).collect(),
            m: self.m.iter().map(|v| v * factor).collect(),
        }
    }

    /// The closed contour, counter-clockwise from the upper trailing edge: τ ∈ [0, ½] runs over
    /// the upper surface from the trailing edge to the leading edge, (½, 1) back along the lower
    /// one; chordwise positions x = (1 + cos 2πτ)/2 cluster points at both edges.
    pub fn contour(&self, tau: f64) -> [f64; 2] {
        let x = 0.5 * (1.0 + (2.0 * std::f64::consts::PI * tau).cos());
        let y = self.half_thickness(x);
        if tau <= 0.5 {
            [x, y]
        } else {
            [x, -y]
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The spline passes through every published ordinate, the maximum thickness is 10 % at 40 %
    /// chord, and the aft 20 % is straight (the 6A-series modification) to 1e-5 of the chord.
    #[test]
    fn naca64a010_shape() {
        let sec = AirfoilShape::naca64a010();
        for (x, y) in NACA64A010 {
            assert!((sec.half_thickness(x / 100.0) - y / 100.0).abs() < 1e-14);
        }
        let tmax = (0..=1000)
            .map(|i| sec.half_thickness(i as f64 / 1000.0))
            .fold(0.0, f64::max);
        assert!((2.0 * tmax - 0.1).abs() < 2e-4, "{tmax}");
        for i in 0..=20 {
            let x = 0.8 + 0.2 * i as f64 / 20.0;
            let line = 0.02103 + (x - 0.8) / 0.2 * (0.00021 - 0.02103);
            assert!((sec.half_thickness(x) - line).abs() < 1e-5, "{x}");
        }
        // the contour is closed up to the blunt trailing edge and runs counter-clockwise
        let (a, b) = (sec.contour(0.0), sec.contour(1.0 - 1e-12));
        assert!((a[1] - 0.00021).abs() < 1e-12 && (b[1] + 0.00021).abs() < 1e-9);
        let n = 400;
        let area: f64 = (0..n)
            .map(|i| {
                let p = sec.contour(i as f64 / n as f64);
                let q = sec.contour((i + 1) as f64 / n as f64);
                0.5 * (p[0] * q[1] - q[0] * p[1])
            })
            .sum();
        assert!(area > 0.0);
    }

    /// The sharp variant closes the trailing edge exactly, differs from the published ordinates
    /// by at most the 0.021 % base half-thickness (times x), and its O-mesh (the trailing edge one
    /// node) is valid and symmetric about the chord line.
    #[test]
    fn sharp_trailing_edge() {
        let sec = AirfoilShape::naca64a010();
        let sharp = sec.sharp();
        assert_eq!(sharp.half_thickness(1.0), 0.0);
        for i in 0..=200 {
            let x = i as f64 / 200.0;
            let d = sec.half_thickness(x) - sharp.half_thickness(x);
            assert!((d - 0.00021 * x).abs() < 1e-15, "x = {x}: {d}");
        }
        let m = sharp.o_mesh(32, 8, 20.0, 0.01, 1.0);
        assert!(m.check().is_ok());
        let wall: Vec<[f64; 3]> = m
            .faces
            .iter()
            .filter(|f| f.right == crate::mesh::Side::Boundary(crate::mesh::Boundary::Wall))
            .flat_map(|f| f.nodes.iter().map(|&n| m.nodes[n]))
            .collect();
        for p in &wall {
            assert!(wall
                .iter()
                .any(|q| (q[0] - p[0]).abs() < 1e-12 && (q[1] + p[1]).abs() < 1e-12));
        }
    }
}
