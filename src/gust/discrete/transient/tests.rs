use super::*;

/// One RK4 step of x'' + 2ζω_n x' + ω_n² x = f(t).
fn rk4(state: [f64; 2], t: f64, dt: f64, zeta: f64, wn: f64, f: &dyn Fn(f64) -> f64) -> [f64; 2] {
    let rhs = |s: [f64; 2], t: f64| [s[1], f(t) - 2.0 * zeta * wn * s[1] - wn * wn * s[0]];
    let add = |s: [f64; 2], d: [f64; 2], h: f64| [s[0] + h * d[0], s[1] + h * d[1]];
    let k1 = rhs(state, t);
    let k2 = rhs(add(state, k1, dt / 2.0), t + dt / 2.0);
    let k3 = rhs(add(state, k2, dt / 2.0), t + dt / 2.0);
    let k4 = rhs(add(state, k3, dt), t + dt);
    [
        state[0] + dt / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]),
        state[1] + dt / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]),
    ]
}

/// A damped oscillator (3 Hz, ζ = 0.05) forced by a 1-cos profile and by a table with a steep
/// ramp: the FFT's displacement and acceleration histories against RK4 time marching of the
/// same equation (40 steps per sample, error ~1e-10 of the peak). The span (16 s) leaves
/// e^{−ζω_n 15 s} = 7e-7 of the response to wrap around and the grid (to 600 rad/s) misses
/// below 1e-6 of the gust energy, so 1e-5 of the peak is the displacement's tolerance.
#[test]
fn oscillator_histories_match_time_marching() {
    let (wn, zeta) = (2.0 * std::f64::consts::PI * 3.0, 0.05);
    let profiles = [
        GustProfile::OneMinusCosine {
            gradient: 20.0,
            amplitude: 10.0,
            velocity: 100.0,
        },
        GustProfile::Tabulated {
            time: vec![0.0, 0.05, 0.6, 0.8],
            velocity: vec![0.0, 4.0, 4.0, 0.0],
        },
    ];
    let grid = TimeGrid::new(16.0, 600.0).unwrap();
    let mut syn = Synthesizer::new(&grid);
    let n = grid.time.len();
    for g in &profiles {
        assert!(
            truncated_energy(g, &grid) < 1e-6,
            "{}",
            truncated_energy(g, &grid)
        );
        let h = |w: f64| c64::new(1.0, 0.0) / c64::new(wn * wn - w * w, 2.0 * zeta * wn * w);
        let disp: Vec<c64> = grid.omega.iter().map(|&w| h(w) * g.spectrum(w)).collect();
        let acc: Vec<c64> = grid
            .omega
            .iter()
            .zip(&disp)
            .map(|(&w, x)| x * (-w * w))
            .collect();
        let (mut x, mut a) = (vec![0.0; n], vec![0.0; n]);
        syn.history(&disp, &mut x);
        syn.history(&acc, &mut a);
        // what is left at the window's end: the decay e^{−ζω_n t} for the displacement, the
        // ripple of the frequency cut on the force's corners for the acceleration
        assert!(wrap_fraction(&x) < 1e-5 && wrap_fraction(&a) < 1e-4);
        // marching from the window's start, at rest (the force is zero before t = 0)
        let dt = grid.time[1] - grid.time[0];
        let sub = 40;
        let f = |t: f64| g.value(t);
        let mut state = [0.0, 0.0];
        let (xpk, apk) = (
            x.iter().fold(0.0f64, |m, v| m.max(v.abs())),
            a.iter().fold(0.0f64, |m, v| m.max(v.abs())),
        );
        let (mut ex, mut ea) = (0.0f64, 0.0f64);
        for i in 0..n {
            let t = grid.time[i];
            let acc_march = f(t) - 2.0 * zeta * wn * state[1] - wn * wn * state[0];
            ex = ex.max((x[i] - state[0]).abs());
            ea = ea.max((a[i] - acc_march).abs());
            for s in 0..sub {
                state = rk4(
                    state,
                    t + s as f64 * dt / sub as f64,
                    dt / sub as f64,
                    zeta,
                    wn,
                    &f,
                );
            }
        }
        assert!(
            ex < 1e-5 * xpk,
            "{g:?}: displacement error {ex:.3e} of peak {xpk:.3e}"
        );
        // the acceleration holds the force itself, whose spectrum the cut at ω_M truncates:
        // 1e-3 of the peak for the smooth 1-cos (|W| ~ ω⁻³), and at a corner of the ramps,
        // where the slope jumps by Δḟ (|W| ~ ω⁻²), the cut's error ∫_{ω_M}^∞ Δḟ/(π ω²) dω
        // = Δḟ/(π ω_M) on top
        let corner = match g {
            GustProfile::Tabulated { time, velocity } => {
                let slope: Vec<f64> = std::iter::once(0.0)
                    .chain(
                        (1..time.len())
                            .map(|i| (velocity[i] - velocity[i - 1]) / (time[i] - time[i - 1])),
                    )
                    .chain(std::iter::once(0.0))
                    .collect();
                slope
                    .windows(2)
                    .fold(0.0f64, |m, w| m.max((w[1] - w[0]).abs()))
                    / (std::f64::consts::PI * grid.omega[grid.omega.len() - 1])
            }
            GustProfile::OneMinusCosine { .. } => 0.0,
        };
        assert!(
            ea < 1e-3 * apk + corner,
            "{g:?}: acceleration error {ea:.3e} of peak {apk:.3e}"
        );
    }
}

/// A peak between samples: cos(ω(t − t*)) sampled at 8 points a period, the refined maximum
/// within 1e-3 of 1 (the sample alone: up to 1 − cos(π/8) = 7.6e-2 off) and its time within
/// 1 % of a sample interval.
#[test]
fn extremes_refine_between_samples() {
    let (w, t_star) = (2.0 * std::f64::consts::PI, 0.37);
    let time: Vec<f64> = (0..40).map(|i| i as f64 / 8.0).collect();
    let y: Vec<f64> = time.iter().map(|t| (w * (t - t_star)).cos()).collect();
    let (max, min) = extremes(&time, &y);
    assert!((max.value - 1.0).abs() < 1e-2, "{max:?}");
    assert!((min.value + 1.0).abs() < 1e-2, "{min:?}");
    let period_offset = (max.time - t_star).rem_euclid(1.0);
    assert!(
        period_offset.min(1.0 - period_offset) < 0.02 / 8.0 * 8.0,
        "{max:?}"
    );
}

/// The energy left beyond the grid: nearly none for a 1-cos gust whose Ω lies far below ω_M,
/// a large share for a gust not much longer than the grid's shortest period.
#[test]
fn truncation_measures_the_gust_spectrum_left_out() {
    let g = GustProfile::OneMinusCosine {
        gradient: 30.0,
        amplitude: 1.0,
        velocity: 150.0,
    };
    let fine = TimeGrid::new(8.0, 2000.0).unwrap();
    assert!(truncated_energy(&g, &fine) < 1e-8);
    // Ω = 2π V/(2H) = 15.7 rad/s: a grid to 20 rad/s keeps the main lobe only in part
    let coarse = TimeGrid::new(8.0, 20.0).unwrap();
    let left = truncated_energy(&g, &coarse);
    assert!(left > 1e-3 && left < 0.5, "{left}");
    assert!(TimeGrid::new(0.1, 20.0).is_err());
}

/// Dot-product test of the inverse transform's adjoint: Σ ȳ_n y_n(Y) = Re Σ conj(Ȳ_j) Y_j for
/// random spectra and seeds on a short and a long grid, to 1e-12.
#[test]
fn history_adjoint_passes_the_dot_product_test() {
    for (span, omega_max) in [(3.0, 200.0), (40.0, 50.0)] {
        let grid = TimeGrid::new(span, omega_max).unwrap();
        let mut syn = Synthesizer::new(&grid);
        let (m, n) = (grid.omega.len(), grid.time.len());
        let r = gustkit_testkit::rand_vec(2 * m + n, 12345);
        let y_omega: Vec<c64> = r[..2 * m].chunks(2).map(|c| c64::new(c[0], c[1])).collect();
        let y_bar = &r[2 * m..];
        let mut y = vec![0.0; n];
        syn.history(&y_omega, &mut y);
        let mut spectrum_bar = vec![c64::new(0.0, 0.0); m];
        syn.history_adjoint(y_bar, &mut spectrum_bar);
        let lhs: f64 = y.iter().zip(y_bar).map(|(a, b)| a * b).sum();
        let rhs: f64 = spectrum_bar
            .iter()
            .zip(&y_omega)
            .map(|(a, b)| (a.conj() * b).re)
            .sum();
        assert!(
            (lhs - rhs).abs() <= 1e-12 * lhs.abs().max(1.0),
            "{lhs} against {rhs}"
        );
    }
}
