//! Checkers every derivative test in gustkit uses: finite differences at several steps (with
//! Richardson extrapolation) and dot-product tests, plus deterministic pseudo-random vectors.

/// Deterministic pseudo-random numbers in [-1, 1) (xorshift64), reproducible across platforms.
pub fn rand_vec(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        })
        .collect()
}

/// Euclidean inner product.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len(), "dot of vectors of different lengths");
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Central difference of f along variable k with absolute step h.
pub fn central_difference(f: &dyn Fn(&[f64]) -> f64, x: &[f64], k: usize, h: f64) -> f64 {
    let mut a = x.to_vec();
    let mut b = x.to_vec();
    a[k] += h;
    b[k] -= h;
    (f(&a) - f(&b)) / (2.0 * h)
}

/// One row of a finite-difference check.
#[derive(Clone, Debug)]
pub struct FdRow {
    /// Relative step (absolute step = rel_step · |x_k|, or rel_step where x_k = 0).
    pub rel_step: f64,
    /// Central difference.
    pub central: f64,
    /// Richardson extrapolation of the central differences at h and h/2 (error O(h⁴)).
    pub richardson: f64,
}

/// Result of checking one derivative against finite differences at several steps.
#[derive(Clone, Debug)]
pub struct FdReport {
    pub exact: f64,
    pub rows: Vec<FdRow>,
    /// Smallest |fd − exact| / scale over all steps and both estimates.
    pub best_rel_error: f64,
    /// The finite-difference value that achieved it.
    pub best: f64,
}

/// Relative steps used by [`fd_check`]: truncation error falls with h, round-off grows as ε/h, so
/// one of them reaches the floor set by the noise of the function itself.
pub const FD_STEPS: [f64; 5] = [1e-2, 1e-3, 1e-4, 1e-5, 1e-6];

/// Compares `exact` (an adjoint or forward derivative of f along x_k) with central differences
/// and their Richardson extrapolations at [`FD_STEPS`]; errors are taken relative to `scale`.
pub fn fd_check(
    f: &dyn Fn(&[f64]) -> f64,
    x: &[f64],
    k: usize,
    exact: f64,
    scale: f64,
) -> FdReport {
    let mut rows = Vec::new();
    let (mut best_rel_error, mut best) = (f64::INFINITY, f64::NAN);
    for &rel in &FD_STEPS {
        let h = rel * if x[k] == 0.0 { 1.0 } else { x[k].abs() };
        let d1 = central_difference(f, x, k, h);
        let d2 = central_difference(f, x, k, 0.5 * h);
        let r = (4.0 * d2 - d1) / 3.0;
        for v in [d1, r] {
            let e = (v - exact).abs() / scale;
            if e < best_rel_error {
                best_rel_error = e;
                best = v;
            }
        }
        rows.push(FdRow {
            rel_step: rel,
            central: d1,
            richardson: r,
        });
    }
    FdReport {
        exact,
        rows,
        best_rel_error,
        best,
    }
}

/// Dot-product test: relative mismatch |⟨w, J v⟩ − ⟨Jᵀ w, v⟩| / max(|⟨w, J v⟩|, tiny).
pub fn dot_product_mismatch(w: &[f64], jv: &[f64], jtw: &[f64], v: &[f64]) -> f64 {
    let forward = dot(w, jv);
    let reverse = dot(jtw, v);
    (forward - reverse).abs() / forward.abs().max(f64::MIN_POSITIVE)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The checker itself: on an analytic function it finds the derivative to ~1e-10 and it flags
    /// a wrong one.
    #[test]
    fn fd_check_on_analytic_function() {
        let f = |x: &[f64]| (x[0] * x[1]).sin() + x[1].exp();
        let x = [0.3f64, 1.7];
        let exact = x[0] * (x[0] * x[1]).cos() + x[1].exp();
        let rep = fd_check(&f, &x, 1, exact, exact.abs());
        assert!(rep.best_rel_error < 1e-10, "{rep:?}");
        let wrong = fd_check(&f, &x, 1, exact * 1.001, exact.abs());
        assert!(wrong.best_rel_error > 5e-4);
    }

    #[test]
    fn dot_product_of_transpose() {
        // J = [[1, 2], [3, 4], [5, 6]]
        let v = [0.5, -1.0];
        let w = [1.0, 2.0, -3.0];
        let jv = [1.0 * 0.5 - 2.0, 3.0 * 0.5 - 4.0, 5.0 * 0.5 - 6.0];
        let jtw = [1.0 + 6.0 - 15.0, 2.0 + 8.0 - 18.0];
        assert!(dot_product_mismatch(&w, &jv, &jtw, &v) < 1e-15);
        let r = rand_vec(1000, 5);
        assert!(r.iter().all(|v| (-1.0..1.0).contains(v)));
        assert!((r.iter().sum::<f64>() / 1000.0).abs() < 0.1);
    }
}

/// Bessel functions and the Theodorsen and Sears functions (they live in `gustkit-core`, where
/// the pipeline's reports use them too).
pub use gustkit_core::theory as bessel;

/// A fake aerodynamic model with closed-form GAFs and an exact reverse mode, for testing code that
/// consumes the [`gustkit_core::Aerodynamics`] trait without a real solver.
///
/// With h_m(p) = n_p · u_m(p) and s_m(p) = n_p · ∂u_m/∂x(p) at the surface points p (weights w_p),
///   Q_ss\[m\]\[n\](k) = Σ_p w_p h_m(p) [(a0 + i a1 k) s_n(p) + (i b1 k − b2 k²) h_n(p)],
///   Q_gs\[m\](k)     = Σ_p w_p h_m(p) g0 e^{−i k (x_p − x_ref)/b_ref},
/// a quasi-steady strip-like model: stiffness from slopes, damping and apparent mass from motion.
pub mod fake {
    use gustkit_core::{
        check_reduced_frequencies, AeroError, AeroSurface, Aerodynamics, AerodynamicsReverse,
        FlightCondition, GafGradient, GafTable, ModalSurface,
    };
    use num_complex::Complex64 as C;

    /// See the module documentation.
    pub struct FakeAero {
        pub surface: AeroSurface,
        pub weights: Vec<f64>,
        pub a0: f64,
        pub a1: f64,
        pub b1: f64,
        pub b2: f64,
        pub g0: f64,
    }

    fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }

    impl FakeAero {
        fn terms(&self, k: f64, x: f64, f: &FlightCondition) -> (C, C, C) {
            let i = C::new(0.0, 1.0);
            (
                C::new(self.a0, 0.0) + i * (self.a1 * k),
                i * (self.b1 * k) - self.b2 * k * k,
                self.g0 * (-i * k * (x - f.x_ref) / f.b_ref).exp(),
            )
        }
    }

    impl Aerodynamics for FakeAero {
        fn surface(&self) -> &AeroSurface {
            &self.surface
        }
        fn geometry_names(&self) -> Vec<String> {
            Vec::new()
        }
        fn gafs(
            &self,
            f: &FlightCondition,
            modes: &ModalSurface,
            k: &[f64],
        ) -> Result<GafTable, AeroError> {
            check_reduced_frequencies(k)?;
            modes.check(self.surface.points.len())?;
            let nm = modes.n_modes();
            let mut t = GafTable::zeros(f, k, nm);
            for (ik, &kk) in k.iter().enumerate() {
                for (p, (&w, nrm)) in self.weights.iter().zip(&self.surface.normals).enumerate() {
                    let (cs, ch, cg) = self.terms(kk, self.surface.points[p][0], f);
                    for m in 0..nm {
                        let hm = dot(*nrm, modes.disp[m][p]) * w;
                        for n in 0..nm {
                            let (hn, sn) =
                                (dot(*nrm, modes.disp[n][p]), dot(*nrm, modes.disp_x[n][p]));
                            t.q_ss[ik][m][n] += hm * (cs * sn + ch * hn);
                        }
                        t.q_gs[ik][m] += hm * cg;
                    }
                }
            }
            Ok(t)
        }

        fn reverse(&self) -> Option<&dyn AerodynamicsReverse> {
            Some(self)
        }
    }

    impl AerodynamicsReverse for FakeAero {
        fn gafs_vjp(
            &self,
            f: &FlightCondition,
            modes: &ModalSurface,
            k: &[f64],
            seed: &GafTable,
        ) -> Result<GafGradient, AeroError> {
            check_reduced_frequencies(k)?;
            modes.check(self.surface.points.len())?;
            let nm = modes.n_modes();
            let mut g = GafGradient {
                modes: ModalSurface::zeros(nm, self.surface.points.len()),
                geometry: Vec::new(),
            };
            for (ik, &kk) in k.iter().enumerate() {
                for (p, (&w, nrm)) in self.weights.iter().zip(&self.surface.normals).enumerate() {
                    let (cs, ch, cg) = self.terms(kk, self.surface.points[p][0], f);
                    for m in 0..nm {
                        let hm = dot(*nrm, modes.disp[m][p]);
                        // ∂J/∂h_m: Re Σ_n conj(Q̄_mn) w (cs s_n + ch h_n) + Re conj(Q̄_gs,m) w cg
                        let mut dhm = (seed.q_gs[ik][m].conj() * cg).re * w;
                        for n in 0..nm {
                            let (hn, sn) =
                                (dot(*nrm, modes.disp[n][p]), dot(*nrm, modes.disp_x[n][p]));
                            let qb = seed.q_ss[ik][m][n].conj();
                            dhm += (qb * (cs * sn + ch * hn)).re * w;
                            // ∂J/∂h_n and ∂J/∂s_n from this (m, n) term
                            let dhn = (qb * ch).re * w * hm;
                            let dsn = (qb * cs).re * w * hm;
                            for a in 0..3 {
                                g.modes.disp[n][p][a] += dhn * nrm[a];
                                g.modes.disp_x[n][p][a] += dsn * nrm[a];
                            }
                        }
                        for a in 0..3 {
                            g.modes.disp[m][p][a] += dhm * nrm[a];
                        }
                    }
                }
            }
            Ok(g)
        }
    }

    #[cfg(test)]
    mod tests {
        use super::*;
        use crate::rand_vec;

        /// The fake model's reverse mode against its exact forward product: GAFs are bilinear in
        /// the shapes, so the central difference with a unit step is exact.
        #[test]
        fn fake_model_dot_product_test() {
            let np = 7;
            let r = rand_vec(10 * np, 4);
            let surface = AeroSurface {
                points: (0..np).map(|p| [r[p], r[np + p], 0.0]).collect(),
                normals: (0..np).map(|_| [0.0, 0.0, 1.0]).collect(),
            };
            let fake = FakeAero {
                surface,
                weights: r[2 * np..3 * np].to_vec(),
                a0: 6.0,
                a1: 1.5,
                b1: 3.0,
                b2: 0.7,
                g0: 5.0,
            };
            let f = FlightCondition {
                mach: 0.3,
                velocity: 50.0,
                density: 1.2,
                b_ref: 0.4,
                x_ref: 0.1,
            };
            let k = [0.0, 0.4, 1.3];
            let shapes = |s: u64| {
                let v = rand_vec(2 * 3 * np * 3, s);
                let mut m = ModalSurface::zeros(3, np);
                for (x, vi) in m.values_mut().zip(&v) {
                    *x = *vi;
                }
                m
            };
            let (m0, dm) = (shapes(1), shapes(2));
            let mut seed = GafTable::zeros(&f, &k, 3);
            let sv = rand_vec(2 * 3 * 12, 3);
            let mut it = sv.chunks(2).map(|c| C::new(c[0], c[1]));
            for ik in 0..3 {
                for m in 0..3 {
                    for n in 0..3 {
                        seed.q_ss[ik][m][n] = it.next().unwrap();
                    }
                    seed.q_gs[ik][m] = it.next().unwrap();
                }
            }
            let pair = |t: &GafTable| seed.pair(t);
            let shift = |s: f64| {
                let mut m = m0.clone();
                for (a, b) in m.values_mut().zip(dm.values()) {
                    *a += s * b;
                }
                m
            };
            let forward = 0.5
                * (pair(&fake.gafs(&f, &shift(1.0), &k).unwrap())
                    - pair(&fake.gafs(&f, &shift(-1.0), &k).unwrap()));
            let g = fake.gafs_vjp(&f, &m0, &k, &seed).unwrap();
            let reverse: f64 = g.modes.values().zip(dm.values()).map(|(a, b)| a * b).sum();
            assert!(
                (forward - reverse).abs() < 1e-12 * forward.abs(),
                "{forward} {reverse}"
            );
        }
    }
}
