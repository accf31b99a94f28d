use super::*;
use faer::c64;
use gustkit_core::GafTable;

/// A 2 Hz oscillator (ζ = 0.02) driven by a force proportional to the gust velocity (no
/// aerodynamic lag): its response peaks at an interior gust gradient (the 1-cos duration 2H/V
/// near the natural period), so the search has something to find.
fn oscillator_table() -> GafTable {
    let k: Vec<f64> = (0..=40).map(|i| 0.1 * i as f64).collect();
    GafTable {
        mach: 0.0,
        b_ref: 1.0,
        x_ref: 0.0,
        q_ss: vec![vec![vec![c64::new(0.0, 0.0)]]; k.len()],
        q_gs: vec![vec![c64::new(1.0, 0.0)]; k.len()],
        k,
    }
}

/// The refined critical gradients against a brute-force scan of 400 gradients on the same
/// model: the golden section finds a peak at least as large as the scan's best (the scan's
/// spacing of 0.24 m misses the top by up to ~1e-4) and no more than 1e-3 above it, for both
/// signs; the envelope holds the grid and the refinement points in increasing H.
#[test]
fn refinement_finds_the_scan_maximum() {
    let table = oscillator_table();
    let velocity = 150.0;
    let p = GustProblem::for_transient(
        vec![2.0 * std::f64::consts::PI * 2.0],
        0.02,
        &table,
        1000.0,
        velocity,
        vec![vec![1.0]],
    );
    let s = TransientSettings {
        span: None,
        omega_max: 4.0 * velocity,
        derivative: vec![0],
        keep_histories: false,
        max_bytes: 1e9,
    };
    let amplitude = |h: f64| 10.0 * (h / 106.68).powf(1.0 / 6.0);
    let range = [9.144, 106.68];
    let r = tuned_search(&p, &s, range, 20, &amplitude, velocity).unwrap();
    assert!(r
        .envelope
        .windows(2)
        .all(|w| w[0].gradient <= w[1].gradient));
    assert_eq!(r.envelope.iter().filter(|e| !e.refined).count(), 20);
    let span = r.response.grid.span;
    let mut model = TransientModel::new(&p, &[0], r.response.grid.clone()).unwrap();
    let (mut scan_max, mut scan_min) = (f64::MIN, f64::MAX);
    for i in 0..400 {
        let h = range[0] + (range[1] - range[0]) * i as f64 / 399.0;
        let g = GustProfile::OneMinusCosine {
            gradient: h,
            amplitude: amplitude(h),
            velocity,
        };
        let pk = model.respond(&g, false).peaks[0];
        scan_max = scan_max.max(pk.0.value);
        scan_min = scan_min.min(pk.1.value);
    }
    let (hi, lo) = r.critical[0];
    assert!(
        hi.peak.value >= scan_max * (1.0 - 1e-9) && hi.peak.value <= scan_max * (1.0 + 1e-3),
        "{hi:?} against {scan_max}"
    );
    assert!(
        lo.peak.value <= scan_min * (1.0 - 1e-9) && lo.peak.value >= scan_min * (1.0 + 1e-3),
        "{lo:?} against {scan_min}"
    );
    // an interior maximum (the search did not just pick an end of the range)
    assert!(
        hi.gradient > range[0] + 1.0 && hi.gradient < range[1] - 1.0,
        "{hi:?}"
    );
    assert!(r.wrap_max <= WRAP_TOLERANCE && span > 0.0);
    assert_eq!(r.histories[0].0.len(), r.response.grid.time.len());
}
