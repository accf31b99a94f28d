//! The LFD fidelity on a Nastran model (issue 29): the wing mesh about the model's CAERO1
//! panel, its wall points moved by the model's spline, the random gust response and its exact
//! design derivatives through the LFD's reverse mode.

use gustkit::nastran::aero::lifting_surfaces;
use gustkit::nastran::bulk::BulkData;
use gustkit::nastran::design::{parse_output, DesignModel, PropertyRelation};
use gustkit::nastran::lfd::NastranLfd;
use gustkit::nastran::random::{random_response_with, KInterpolation};
use gustkit::nastran::response::subcase_flight;
use gustkit::nastran::structure::subcase_modes;
use gustkit::nastran::Input;
use std::sync::Arc;

mod common;

/// The plate wing (`common::plate_wing_gust_deck`) as a half wing (AERO SYMXZ = 1) with 4
/// modes, the gust's X0 0.3 m ahead of the panel, everything moved by `dx` along the flow.
fn plate_wing_deck(dx: f64) -> String {
    common::plate_wing_gust_deck(dx, 4, true, -0.3)
}

/// The small built-in wing mesh (768 cells) with LFD solves to 1e-12.
fn small_lfd() -> gustkit::aero::FidelitySpec {
    serde_json::from_value(serde_json::json!({"lfd": {"gmres_tolerance": 1e-12, "mesh_sizes": {
        "n_around": 16, "n_radial": 6, "n_span": 4, "n_outboard": 4, "first_spacing_chords": 0.02
    }}}))
    .unwrap()
}

/// The reduced frequencies of the LFD table: to 0.35, beyond the FREQ list's 0.312.
fn table_k() -> Vec<f64> {
    vec![0.0, 0.05, 0.1, 0.2, 0.35]
}

/// The deck read, and its LFD.
fn read_with_lfd(dir: &std::path::Path, dx: f64) -> (Input, BulkData, NastranLfd) {
    let path = dir.join(format!("plate_{dx}.bdf"));
    std::fs::write(&path, plate_wing_deck(dx)).unwrap();
    let input = Input::read(&path).unwrap();
    let b = BulkData::from_cards(&input.deck.bulk).unwrap();
    let sub = input.case_control.subcase(1).unwrap();
    let (s, _) = subcase_modes(&b, &sub).unwrap();
    let surf = lifting_surfaces(&b, &s).unwrap();
    let flight = subcase_flight(&b, &sub).unwrap();
    let airfoil = gustkit::wing::Airfoil::naca65a004();
    let lfd = NastranLfd::build(&b, &s, &surf, (&small_lfd(), &airfoil), &flight, None).unwrap();
    (input, b, lfd)
}

/// The wall points lie on the panel and cover it (x from the leading to the trailing edge,
/// y from the symmetry plane to the tip, on its plane), each moved by the panel's spline; and
/// the model moved along the flow by 0.37 m with its gust's X0 gives the same random response
/// (the mesh's origin is the panel's root leading edge, the gust's phase reference moves with
/// it): RMS and N0 of the tip's displacement and the root's constraint moment equal to 1e-10
/// (round-off of the shifted coordinates). The LFD's RMS stands beside the DLM's.
#[test]
fn lfd_on_a_nastran_model_follows_its_panel_and_splines() {
    let dir = common::scratch("nastran", "lfd-placed");
    let requests: Vec<_> = ["15T3", "SPCF 1R1"]
        .iter()
        .map(|l| parse_output(l).unwrap())
        .collect();
    let mut results = Vec::new();
    for dx in [0.0, 0.37] {
        let (input, b, lfd) = read_with_lfd(&dir, dx);
        let (lo, hi) =
            lfd.points
                .iter()
                .fold(([f64::MAX; 3], [f64::MIN; 3]), |(mut lo, mut hi), p| {
                    for i in 0..3 {
                        lo[i] = lo[i].min(p[i]);
                        hi[i] = hi[i].max(p[i]);
                    }
                    (lo, hi)
                });
        let want = ([dx, 0.0, 0.0], [dx + 0.5, 2.0, 0.0]);
        for i in 0..3 {
            assert!(
                (lo[i] - want.0[i]).abs() < 1e-12 && (hi[i] - want.1[i]).abs() < 1e-12,
                "{lo:?} {hi:?}"
            );
        }
        assert!(lfd.unmoved.is_empty(), "{:?}", lfd.unmoved);
        let sub = input.case_control.subcase(1).unwrap();
        let (s, modes) = subcase_modes(&b, &sub).unwrap();
        let how = KInterpolation::Dense(table_k());
        let (rows, _) =
            random_response_with(&b, &sub, &s, &modes, &requests, &how, Some(Arc::new(lfd)))
                .unwrap();
        let (dlm, _) = random_response_with(&b, &sub, &s, &modes, &requests, &how, None).unwrap();
        for (l, d) in rows.iter().zip(&dlm) {
            eprintln!(
                "dx {dx}: {} RMS {:.6e} (DLM {:.6e}), N0 {:.4} Hz (DLM {:.4})",
                l.label, l.rms, d.rms, l.n0_hz, d.n0_hz
            );
            assert!(l.rms > 0.0 && l.rms.is_finite());
        }
        results.push(rows);
    }
    for (a, b) in results[0].iter().zip(&results[1]) {
        assert!(
            (a.rms / b.rms - 1.0).abs() < 1e-10 && (a.n0_hz / b.n0_hz - 1.0).abs() < 1e-10,
            "{}: {} {} / {} {}",
            a.label,
            a.rms,
            b.rms,
            a.n0_hz,
            b.n0_hz
        );
    }
}

/// The design derivatives with the LFD (the root and tip PSHELL thicknesses): the forward mode
/// (mode derivatives → the LFD's GAF table of [φ | ∂φ]) against central differences at
/// relative steps 1e-3 and 1e-4 (≥ 6 digits), and the reverse mode (the LFD's adjoint through
/// the spline's transpose) against the forward mode.
#[test]
fn lfd_design_derivatives_match_differences() {
    let dir = common::scratch("nastran", "lfd-design");
    let (input, base, lfd) = read_with_lfd(&dir, 0.0);
    let sub = input.case_control.subcase(1).unwrap();
    let relations = vec![
        PropertyRelation::new(&base, "PSHELL", 1, "T", 0.0, vec![(0, 0.012)]).unwrap(),
        PropertyRelation::new(&base, "PSHELL", 2, "T", 0.0, vec![(1, 0.008)]).unwrap(),
    ];
    let (_, modes) = subcase_modes(&base, &sub).unwrap();
    let labels = ["15T3", "SPCF 1R1"];
    let m = DesignModel {
        n_modes: modes.lambda.len(),
        base,
        sub,
        relations,
        requests: labels.iter().map(|l| parse_output(l).unwrap()).collect(),
        interpolation: KInterpolation::Dense(table_k()),
        n_variables: 2,
        lfd: Some(Arc::new(lfd)),
    };
    let x0 = [1.0, 1.0];
    let p = m.analyse(&x0).unwrap();
    let g = m.gradients(&p).unwrap();
    let n_rows = p.rows.len();
    let mut worst = 0.0f64;
    for v in 0..2 {
        for (y, row) in p.rows.iter().enumerate() {
            for (what, value, exact) in [
                ("RMS", row.rms, g.outputs[v][y].d_rms),
                ("N0", row.n0_hz, g.outputs[v][y].d_n0_hz),
            ] {
                let mut best = f64::MAX;
                for rel in [1e-3, 1e-4] {
                    let at = |sign: f64| {
                        let mut x = x0;
                        x[v] += sign * rel;
                        let q = m.analyse(&x).unwrap();
                        match what {
                            "RMS" => q.rows[y].rms,
                            _ => q.rows[y].n0_hz,
                        }
                    };
                    let fd = (at(1.0) - at(-1.0)) / (2.0 * rel);
                    let err = (fd - exact).abs() / value.abs();
                    eprintln!(
                        "x{v} {} {what}: exact {exact:.10e}, central {fd:.10e} at {rel:e}: {err:.1e}",
                        row.label
                    );
                    best = best.min(err);
                }
                worst = worst.max(best);
            }
        }
    }
    assert!(worst < 1e-6, "worst {worst:e}");
    // reverse: the functional Σ (RMS + N0) of every row against the forward mode's sum
    let functional = vec![vec![(1.0, 1.0); n_rows]];
    let r = m.gradients_reverse(&p, &functional).unwrap();
    for v in 0..2 {
        let forward: f64 = g.outputs[v].iter().map(|o| o.d_rms + o.d_n0_hz).sum();
        let rev = r.functionals[0][v];
        eprintln!("x{v}: reverse {rev:.12e}, forward {forward:.12e}");
        assert!(
            (rev - forward).abs() < 1e-10 * forward.abs(),
            "{rev} {forward}"
        );
    }
}

/// The shipped study (`studies/nastran_plate_wing_lfd.json`) through `gustkit run`: it
/// converges (exit 0) with the tip's RMS on its limit, results.json says where the GAFs came
/// from; and what a Nastran model cannot take is refused at load or when the model is read,
/// naming the JSON path or the card: a DLM fidelity (the model has its own), a table that ends
/// below the FREQ list's highest reduced frequency, a model without AERO's symmetry.
#[test]
fn lfd_nastran_study_runs_and_bad_input_is_named() {
    let dir = common::scratch("nastran", "lfd-study");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut v: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root.join("studies/nastran_plate_wing_lfd.json")).unwrap(),
    )
    .unwrap();
    v["model"]["nastran"] = root
        .join("studies/nastran/plate_wing_gust.bdf")
        .display()
        .to_string()
        .into();
    let run = |name: &str, v: &serde_json::Value| {
        let file = dir.join(format!("{name}.json"));
        std::fs::write(&file, v.to_string()).unwrap();
        common::gustkit()
            .arg("run")
            .arg(&file)
            .arg("--reports")
            .arg(dir.join("reports"))
            .output()
            .unwrap()
    };
    let out = run("whole", &v);
    common::assert_success(&out);
    let r: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("reports/nastran_plate_wing_lfd/results.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(r["converged"], true);
    let c = &r["constraints"][0];
    assert!(
        (c["final"].as_f64().unwrap() / 0.15 - 1.0).abs() < 1e-6,
        "{c}"
    );
    assert!(r["mass_change_percent"].as_f64().unwrap() < 0.0);
    let words = r["aerodynamics"].as_str().unwrap();
    assert!(words.contains("LFD given mesh (768 cells)"), "{words}");
    let summary =
        std::fs::read_to_string(dir.join("reports/nastran_plate_wing_lfd/summary.md")).unwrap();
    assert!(summary.contains("Aerodynamics: the LFD"), "{summary}");
    // bad input
    let refused = |name: &str, v: &serde_json::Value, words: &[&str]| {
        let out = run(name, v);
        for w in words {
            common::assert_refused(&out, w);
        }
        assert!(!String::from_utf8_lossy(&out.stderr).contains("backtrace"));
    };
    let mut dlm = v.clone();
    dlm["aero"]["fidelity"] = serde_json::json!({"dlm": {"n_chord": 4, "n_span": 4}});
    refused("dlm", &dlm, &["aero.fidelity", "CAERO1"]);
    let mut short = v.clone();
    short["aero"]["reduced_frequencies"] = serde_json::json!([0.0, 0.1]);
    refused("short", &short, &["aero", "reduced_frequencies", "0.31"]);
    let deck = std::fs::read_to_string(root.join("studies/nastran/plate_wing_gust.bdf")).unwrap();
    assert!(deck.contains("AERO,0,100.,0.5,0.4,1\n"));
    let plain = dir.join("no_symmetry.bdf");
    std::fs::write(
        &plain,
        deck.replace("AERO,0,100.,0.5,0.4,1\n", "AERO,0,100.,0.5,0.4\n"),
    )
    .unwrap();
    let mut asym = v.clone();
    asym["model"]["nastran"] = plain.display().to_string().into();
    refused("asym", &asym, &["AERO", "SYMXZ = 1"]);
    // a mesh file in another unit than the model's
    let mut inches = v.clone();
    inches["aero"]["fidelity"] = serde_json::json!({"lfd": {"mesh_file": {"path": "wing.su2",
        "markers": {"wall": "wall"}, "length_unit": "in"}}});
    refused(
        "inches",
        &inches,
        &[
            "aero.fidelity.lfd.mesh_file.length_unit",
            "model's own units",
        ],
    );
}

/// An external mesh (`aero.fidelity.lfd.mesh_file`) on a Nastran model: the small built-in
/// wing mesh about the panel written as SU2 in the model's units (metres here), in the LFD's
/// frame (x downstream from the panel's root leading edge, y up, z spanwise), gives the built-in
/// mesh's random response: RMS and N0 to 1e-8 (the same cells; the wall points' planform
/// coordinates recovered from their positions; the steady state from the free stream instead
/// of mesh sequencing, both converged).
#[test]
fn external_mesh_on_a_nastran_model_gives_the_built_in_response() {
    let dir = common::scratch("nastran", "lfd-mesh-file");
    let (input, b, lfd) = read_with_lfd(&dir, 0.0);
    let sub = input.case_control.subcase(1).unwrap();
    let (s, modes) = subcase_modes(&b, &sub).unwrap();
    let requests: Vec<_> = ["15T3", "SPCF 1R1"]
        .iter()
        .map(|l| parse_output(l).unwrap())
        .collect();
    let how = KInterpolation::Dense(table_k());
    let planform = lfd.planform.to_array();
    let (built_in, _) =
        random_response_with(&b, &sub, &s, &modes, &requests, &how, Some(Arc::new(lfd))).unwrap();
    let spec = common::small_wing_mesh_spec();
    let airfoil = gustkit::wing::Airfoil::naca65a004();
    let mesh =
        gustkit_cfd::wing_mesh::WingMesh::new(planform, &|x| airfoil.half_thickness(x), &spec).mesh;
    let file = dir.join("wing.su2");
    std::fs::write(&file, gustkit_cfd::readers::write_su2(&mesh)).unwrap();
    let external: gustkit::aero::FidelitySpec = serde_json::from_value(serde_json::json!({
        "lfd": {"gmres_tolerance": 1e-12, "mesh_file": {"path": file.to_string_lossy(),
            "markers": {"wall": "wall", "farfield": "far_field", "symmetry": "symmetry"}}}
    }))
    .unwrap();
    let surf = lifting_surfaces(&b, &s).unwrap();
    let flight = subcase_flight(&b, &sub).unwrap();
    let lfd = NastranLfd::build(&b, &s, &surf, (&external, &airfoil), &flight, None).unwrap();
    let (from_file, _) =
        random_response_with(&b, &sub, &s, &modes, &requests, &how, Some(Arc::new(lfd))).unwrap();
    for (a, f) in built_in.iter().zip(&from_file) {
        eprintln!(
            "{}: RMS {:.12e} / {:.12e}, N0 {:.12e} / {:.12e}",
            a.label, a.rms, f.rms, a.n0_hz, f.n0_hz
        );
        assert!(
            (a.rms / f.rms - 1.0).abs() < 1e-8 && (a.n0_hz / f.n0_hz - 1.0).abs() < 1e-8,
            "{}",
            a.label
        );
    }
}
