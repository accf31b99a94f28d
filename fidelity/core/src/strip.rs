//! A reference aerodynamic model behind the shared trait: a 2-D section by Theodorsen (motion) and
//! Sears (gust) strip theory ([`crate::theory::strip_gafs`]), the rigid plunge and pitch of each
//! mode fitted from its displacements along the chord. It runs the same gust and flutter pipeline
//! as the DLM and the LFD, as the classical baseline of a typical section.

use crate::aero::check_request;
use crate::theory::strip_gafs;
use crate::{
    AeroError, AeroSurface, Aerodynamics, AerodynamicsReverse, FlightCondition, GafGradient,
    GafTable, ModalSurface,
};
use num_complex::Complex64;

/// Refuses a flight condition at or above Mach 1 (Prandtl–Glauert strip theory is subsonic).
fn subsonic(flight: &FlightCondition) -> Result<(), AeroError> {
    if !(flight.mach < 1.0) {
        return Err(AeroError::Input(format!(
            "mach: strip theory is subsonic (got {})",
            flight.mach
        )));
    }
    Ok(())
}

/// A flat-plate section of semichord `b` along x (mid-chord at x = `x_mid`), forces per `span`
/// metres of span.
#[derive(Clone, Debug)]
pub struct StripSection {
    pub b: f64,
    pub x_mid: f64,
    pub span: f64,
    surface: AeroSurface,
    /// Least-squares rows: (h, α) at the mid-chord = Σ_p fit[p] · dz_p.
    fit: Vec<[f64; 2]>,
}

impl StripSection {
    /// The section with `n_points` (≥ 2) chord points where it samples the modes.
    pub fn new(b: f64, x_mid: f64, span: f64, n_points: usize) -> Self {
        let n = n_points.max(2);
        let xs: Vec<f64> = (0..n)
            .map(|i| x_mid - b + 2.0 * b * i as f64 / (n - 1) as f64)
            .collect();
        // dz = h − α (x − x_mid): normal equations of the two unknowns
        let (s0, s1, s2) = xs.iter().fold((0.0, 0.0, 0.0), |(a, c, d), x| {
            let r = x - x_mid;
            (a + 1.0, c + r, d + r * r)
        });
        let det = s0 * s2 - s1 * s1;
        let fit = xs
            .iter()
            .map(|x| {
                let r = -(x - x_mid);
                // [h, α] = N⁻¹ [Σ dz, Σ r dz] with N = [[s0, −s1], [−s1, s2]]
                [(s2 + s1 * r) / det, (s1 + s0 * r) / det]
            })
            .collect();
        Self {
            b,
            x_mid,
            span,
            surface: AeroSurface {
                points: xs.iter().map(|&x| [x, 0.0, 0.0]).collect(),
                normals: vec![[0.0, 0.0, 1.0]; n],
            },
            fit,
        }
    }

    /// Plunge (up) and nose-up pitch about the mid-chord of each mode.
    fn rigid(&self, modes: &ModalSurface) -> Vec<[f64; 2]> {
        modes
            .disp
            .iter()
            .map(|d| {
                let mut a = [0.0; 2];
                for (f, v) in self.fit.iter().zip(d) {
                    a[0] += f[0] * v[2];
                    a[1] += f[1] * v[2];
                }
                a
            })
            .collect()
    }

    /// The 2 × 2 motion and the gust GAFs at the reference reduced frequency k = ω b_ref / U
    /// (the section's own is k b / b_ref) with the gust phase referred to `x_ref`.
    fn parts(&self, flight: &FlightCondition, k: f64) -> ([[Complex64; 2]; 2], [Complex64; 2]) {
        let (ss, gs) = strip_gafs(k * self.b / flight.b_ref, self.b, flight.mach);
        // the gust reaches the mid-chord with phase e^{−iω(x_mid − x_ref)/U}
        let phase = Complex64::new(0.0, -k * (self.x_mid - flight.x_ref) / flight.b_ref).exp();
        let scale = self.span;
        (
            ss.map(|row| row.map(|v| v * scale)),
            gs.map(|v| v * phase * scale),
        )
    }

    fn check(
        &self,
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: &[f64],
    ) -> Result<(), AeroError> {
        check_request(flight, modes, k, self.surface.points.len())?;
        if (flight.b_ref - self.b).abs() > 1e-9 * self.b {
            return Err(AeroError::Input(format!(
                "b_ref: the strip section's semichord is {} m, the flight condition's reference {} m",
                self.b, flight.b_ref
            )));
        }
        subsonic(flight)
    }
}

impl Aerodynamics for StripSection {
    fn surface(&self) -> &AeroSurface {
        &self.surface
    }

    fn geometry_names(&self) -> Vec<String> {
        Vec::new()
    }

    fn gafs(
        &self,
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: &[f64],
    ) -> Result<GafTable, AeroError> {
        self.check(flight, modes, k)?;
        Ok(self.table(flight, modes, k))
    }

    fn reverse(&self) -> Option<&dyn AerodynamicsReverse> {
        Some(self)
    }
}

impl StripSection {
    /// The GAF table of this section for modes sampled on its points (checked by the caller).
    fn table(&self, flight: &FlightCondition, modes: &ModalSurface, k: &[f64]) -> GafTable {
        let a = self.rigid(modes);
        let parts = k
            .iter()
            .map(|&kk| {
                let (ss, gs) = self.parts(flight, kk);
                // generalized force on mode m: L h_m + M α_m
                let force = |f: [Complex64; 2], m: usize| f[0] * a[m][0] + f[1] * a[m][1];
                let q_ss = (0..a.len())
                    .map(|m| {
                        (0..a.len())
                            .map(|n| {
                                let f = [
                                    ss[0][0] * a[n][0] + ss[0][1] * a[n][1],
                                    ss[1][0] * a[n][0] + ss[1][1] * a[n][1],
                                ];
                                force(f, m)
                            })
                            .collect()
                    })
                    .collect();
                let q_gs = (0..a.len()).map(|m| force(gs, m)).collect();
                (q_ss, q_gs)
            })
            .collect();
        GafTable::from_parts(flight, k, parts)
    }
}

impl AerodynamicsReverse for StripSection {
    /// Q_ss[m][n] = a_mᵀ S a_n and Q_gs[m] = a_mᵀ g with a = (h, α) linear in the displacements,
    /// so ∂J/∂a_m = Re(Σ_n conj(Q̄_mn) S a_n + Σ_n conj(Q̄_nm) Sᵀ a_n + conj(Q̄_g,m) g), pulled back
    /// through the fit.
    fn gafs_vjp(
        &self,
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: &[f64],
        seed: &GafTable,
    ) -> Result<GafGradient, AeroError> {
        self.check(flight, modes, k)?;
        Ok(GafGradient {
            modes: self.table_vjp(flight, modes, k, seed),
            geometry: Vec::new(),
        })
    }
}

impl StripSection {
    /// The reverse mode of [`StripSection::table`]: the seed pulled back to the mode samples.
    fn table_vjp(
        &self,
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: &[f64],
        seed: &GafTable,
    ) -> ModalSurface {
        let a = self.rigid(modes);
        let nm = a.len();
        let mut abar = vec![[0.0; 2]; nm];
        for (i, &kk) in k.iter().enumerate() {
            let (ss, gs) = self.parts(flight, kk);
            for m in 0..nm {
                for r in 0..2 {
                    let mut acc = seed.q_gs[i][m].conj() * gs[r];
                    for n in 0..nm {
                        let sa: Complex64 = (0..2).map(|c| ss[r][c] * a[n][c]).sum();
                        let sta: Complex64 = (0..2).map(|c| ss[c][r] * a[n][c]).sum();
                        acc += seed.q_ss[i][m][n].conj() * sa + seed.q_ss[i][n][m].conj() * sta;
                    }
                    abar[m][r] += acc.re;
                }
            }
        }
        let mut grad = ModalSurface::zeros(nm, self.surface.points.len());
        for m in 0..nm {
            for (p, f) in self.fit.iter().enumerate() {
                grad.disp[m][p][2] = abar[m][0] * f[0] + abar[m][1] * f[1];
            }
        }
        grad
    }
}

/// A strip of a wing: its spanwise station y (m), mid-chord x (m), semichord b (m) and width
/// (m of span its forces stand for).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StripStation {
    pub y: f64,
    pub x_mid: f64,
    pub b: f64,
    pub width: f64,
}

/// Strip theory on a wing: a streamwise Theodorsen/Sears section at each station, with its own
/// semichord (reduced frequency k b / b_ref), mid-chord and gust phase, its forces per its strip
/// width; the GAFs are the sum over the strips. No three-dimensional effects: no downwash from
/// the other strips, no tip loss, no sweep correction (the classical baseline that overestimates
/// a low-aspect-ratio wing's lift).
#[derive(Clone, Debug)]
pub struct StripWing {
    strips: Vec<StripSection>,
    surface: AeroSurface,
}

impl StripWing {
    /// The wing of these stations, each sampling the modes at `n_points` (≥ 2) chord points.
    pub fn new(stations: &[StripStation], n_points: usize) -> Self {
        let strips: Vec<StripSection> = stations
            .iter()
            .map(|s| StripSection::new(s.b, s.x_mid, s.width, n_points))
            .collect();
        let mut surface = AeroSurface {
            points: Vec::new(),
            normals: Vec::new(),
        };
        for (st, s) in strips.iter().zip(stations) {
            surface
                .points
                .extend(st.surface.points.iter().map(|p| [p[0], s.y, 0.0]));
            surface.normals.extend(&st.surface.normals);
        }
        Self { strips, surface }
    }

    /// The modes sampled on strip j's points (its slice of `modes`).
    fn slice(&self, modes: &ModalSurface, j: usize) -> ModalSurface {
        let n = self.strips[0].surface.points.len();
        let r = j * n..(j + 1) * n;
        ModalSurface {
            disp: modes.disp.iter().map(|d| d[r.clone()].to_vec()).collect(),
            disp_x: modes.disp_x.iter().map(|d| d[r.clone()].to_vec()).collect(),
        }
    }

    fn check(
        &self,
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: &[f64],
    ) -> Result<(), AeroError> {
        check_request(flight, modes, k, self.surface.points.len())?;
        subsonic(flight)
    }
}

impl Aerodynamics for StripWing {
    fn surface(&self) -> &AeroSurface {
        &self.surface
    }

    fn geometry_names(&self) -> Vec<String> {
        Vec::new()
    }

    fn gafs(
        &self,
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: &[f64],
    ) -> Result<GafTable, AeroError> {
        self.check(flight, modes, k)?;
        let mut total = GafTable::zeros(flight, k, modes.n_modes());
        for (j, strip) in self.strips.iter().enumerate() {
            let t = strip.table(flight, &self.slice(modes, j), k);
            for (i, (ss, gs)) in t.q_ss.iter().zip(&t.q_gs).enumerate() {
                for (m, row) in ss.iter().enumerate() {
                    for (n, v) in row.iter().enumerate() {
                        total.q_ss[i][m][n] += v;
                    }
                    total.q_gs[i][m] += gs[m];
                }
            }
        }
        Ok(total)
    }

    fn reverse(&self) -> Option<&dyn AerodynamicsReverse> {
        Some(self)
    }
}

impl AerodynamicsReverse for StripWing {
    /// The GAFs are a sum over the strips of functions of each strip's own samples: each
    /// strip's reverse mode with the whole seed gives its slice of the gradient.
    fn gafs_vjp(
        &self,
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: &[f64],
        seed: &GafTable,
    ) -> Result<GafGradient, AeroError> {
        self.check(flight, modes, k)?;
        let mut grad = ModalSurface::zeros(modes.n_modes(), 0);
        for (j, strip) in self.strips.iter().enumerate() {
            let g = strip.table_vjp(flight, &self.slice(modes, j), k, seed);
            for (m, (d, dx)) in g.disp.into_iter().zip(g.disp_x).enumerate() {
                grad.disp[m].extend(d);
                grad.disp_x[m].extend(dx);
            }
        }
        Ok(GafGradient {
            modes: grad,
            geometry: Vec::new(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flight() -> FlightCondition {
        FlightCondition {
            mach: 0.3,
            velocity: 100.0,
            density: 1.2,
            b_ref: 0.5,
            x_ref: -0.3,
        }
    }

    /// A rigid pitch about the quarter chord is recovered exactly by the fit, and the pitch GAF
    /// about another axis follows the transfer of the moment: M_qc = M_mid − (b/2)·L for the same
    /// lift; the gust GAF carries the phase of its reference.
    #[test]
    fn rigid_modes_and_gust_phase() {
        let s = StripSection::new(0.5, 0.0, 1.0, 11);
        let pts = &s.surface().points;
        let mut modes = ModalSurface::zeros(2, pts.len());
        for (i, p) in pts.iter().enumerate() {
            modes.disp[0][i] = [0.0, 0.0, 1.0];
            // nose-up pitch about the quarter chord x = −b/2: dz = −(x + b/2)
            modes.disp[1][i] = [0.0, 0.0, -(p[0] + 0.25)];
        }
        let a = s.rigid(&modes);
        assert!((a[0][0] - 1.0).abs() < 1e-14 && a[0][1].abs() < 1e-14);
        assert!((a[1][0] + 0.25).abs() < 1e-14 && (a[1][1] - 1.0).abs() < 1e-14);
        let f = flight();
        let t = s.gafs(&f, &modes, &[0.0, 0.4]).unwrap();
        // at k = 0 the quarter-chord pitch moment about the quarter chord vanishes
        assert!(t.q_ss[0][1][1].norm() < 1e-12, "{}", t.q_ss[0][1][1]);
        let (_, gs) = strip_gafs(0.4, 0.5, 0.3);
        let phase = Complex64::new(0.0, -0.4 * 0.3 / 0.5).exp();
        assert!((t.q_gs[1][0] - gs[0] * phase).norm() < 1e-12);
    }

    /// Dot-product test of the reverse mode: Re Σ conj(seed) · (dQ along a random displacement
    /// direction) equals Σ gradient · direction, to 1e-12.
    #[test]
    fn reverse_mode_dot_product() {
        dot_product_check(&StripSection::new(0.5, 0.1, 2.0, 9), &flight());
        // a wing of three strips of other semichords, stations and widths
        let stations = [
            (0.1, 0.0, 0.5, 0.2),
            (0.3, 0.15, 0.4, 0.2),
            (0.5, 0.3, 0.3, 0.1),
        ]
        .map(|(y, x_mid, b, width)| StripStation { y, x_mid, b, width });
        dot_product_check(&StripWing::new(&stations, 7), &flight());
    }

    /// Dot-product test of a model's reverse mode against central differences of its GAFs
    /// (exact up to round-off: the GAFs are quadratic in the mode samples).
    fn dot_product_check<A: Aerodynamics + AerodynamicsReverse>(s: &A, f: &FlightCondition) {
        let n = s.surface().points.len();
        let rnd = |i: usize| ((i as f64 * 12.9898).sin() * 43758.5453).fract();
        let mut modes = ModalSurface::zeros(3, n);
        let mut dir = ModalSurface::zeros(3, n);
        for m in 0..3 {
            for p in 0..n {
                modes.disp[m][p][2] = rnd(m * 97 + p);
                dir.disp[m][p][2] = rnd(m * 31 + p + 500);
            }
        }
        let k = [0.0, 0.3, 1.1];
        let t = s.gafs(f, &modes, &k).unwrap();
        let mut seed = t.clone();
        for (i, v) in seed.q_ss.iter_mut().flatten().flatten().enumerate() {
            *v = Complex64::new(rnd(i + 900), rnd(i + 1900));
        }
        for (i, v) in seed.q_gs.iter_mut().flatten().enumerate() {
            *v = Complex64::new(rnd(i + 2900), rnd(i + 3900));
        }
        // the map is quadratic in the modes: the directional derivative by central differences
        // is exact up to round-off
        let h = 1e-3;
        let shifted = |sign: f64| {
            let mut m = modes.clone();
            for (a, d) in m.values_mut().zip(dir.values()) {
                *a += sign * h * d;
            }
            s.gafs(f, &m, &k).unwrap()
        };
        let (tp, tm) = (shifted(1.0), shifted(-1.0));
        let mut dq = tp.clone();
        for (d, (p, q)) in dq.q_ss.iter_mut().flatten().flatten().zip(
            tp.q_ss
                .iter()
                .flatten()
                .flatten()
                .zip(tm.q_ss.iter().flatten().flatten()),
        ) {
            *d = (p - q) / (2.0 * h);
        }
        for (d, (p, q)) in dq
            .q_gs
            .iter_mut()
            .flatten()
            .zip(tp.q_gs.iter().flatten().zip(tm.q_gs.iter().flatten()))
        {
            *d = (p - q) / (2.0 * h);
        }
        let forward = seed.pair(&dq);
        let g = s.gafs_vjp(f, &modes, &k, &seed).unwrap();
        let reverse: f64 = g.modes.values().zip(dir.values()).map(|(a, b)| a * b).sum();
        assert!(
            (forward - reverse).abs() < 1e-10 * forward.abs(),
            "{forward} vs {reverse}"
        );
    }

    /// A wing of identical strips with a spanwise-uniform mode is the section of their total
    /// span (to round-off); a strip of another semichord than b_ref takes its own reduced
    /// frequency k b / b_ref and the gust phase of its mid-chord (Theodorsen/Sears directly).
    #[test]
    fn strip_wing_sums_its_sections() {
        let f = flight();
        let k = [0.0, 0.4, 1.3];
        let stations: Vec<StripStation> = (0..4)
            .map(|j| StripStation {
                y: 0.25 * j as f64,
                x_mid: 0.1,
                b: 0.5,
                width: 0.25,
            })
            .collect();
        let wing = StripWing::new(&stations, 9);
        let section = StripSection::new(0.5, 0.1, 1.0, 9);
        let shape = |x: f64| [[0.0, 0.0, 1.0], [0.0, 0.0, -(x - 0.1)]];
        let sample = |pts: &[[f64; 3]]| {
            let mut m = ModalSurface::zeros(2, pts.len());
            for (p, x) in pts.iter().enumerate() {
                let s = shape(x[0]);
                m.disp[0][p] = s[0];
                m.disp[1][p] = s[1];
            }
            m
        };
        let tw = wing.gafs(&f, &sample(&wing.surface().points), &k).unwrap();
        let ts = section
            .gafs(&f, &sample(&section.surface().points), &k)
            .unwrap();
        for i in 0..k.len() {
            for m in 0..2 {
                assert!((tw.q_gs[i][m] - ts.q_gs[i][m]).norm() < 1e-12 * ts.q_gs[i][0].norm());
                for n in 0..2 {
                    let (a, b) = (tw.q_ss[i][m][n], ts.q_ss[i][m][n]);
                    assert!((a - b).norm() <= 1e-12 * (1.0 + b.norm()), "{i} {m} {n}");
                }
            }
        }
        // one strip of semichord 0.3 m (b_ref 0.5 m) at x_mid 0.4, width 0.2: plunge lift
        let one = StripWing::new(
            &[StripStation {
                y: 0.0,
                x_mid: 0.4,
                b: 0.3,
                width: 0.2,
            }],
            5,
        );
        let mut plunge = ModalSurface::zeros(1, 5);
        for p in 0..5 {
            plunge.disp[0][p] = [0.0, 0.0, 1.0];
        }
        let t = one.gafs(&f, &plunge, &[0.8]).unwrap();
        let (ss, gs) = strip_gafs(0.8 * 0.3 / 0.5, 0.3, f.mach);
        let phase = Complex64::new(0.0, -0.8 * (0.4 - f.x_ref) / 0.5).exp();
        assert!((t.q_ss[0][0][0] - 0.2 * ss[0][0]).norm() < 1e-12 * ss[0][0].norm());
        assert!((t.q_gs[0][0] - 0.2 * gs[0] * phase).norm() < 1e-12 * gs[0].norm());
    }
}
