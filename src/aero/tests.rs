//! The registry's contract: builders bind their models to the plate point for point, the
//! capability of a reverse mode is known before anything runs, and a model without one is
//! refused with its name instead of failing deep in a gradient.

use super::*;
use crate::aero::dlm::DlmSpec;
use crate::study::Study;
use gustkit_core::{AeroSurface, Aerodynamics, GafTable};
use std::path::Path;

fn agard() -> Study {
    Study::load(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/studies/agard445_dlm.json"
    )))
    .unwrap()
}

/// The DLM's binding: one plate point for each surface point, and the planform map of each
/// (ξ, η) is the surface point's (x, y) to round-off (the boxes lie on the plate's own map).
#[test]
fn dlm_binding_matches_its_surface() {
    let study = agard();
    let planform = study.planform().unwrap();
    let aero = study.spec.aero.as_ref().unwrap();
    let (airfoil, flight) = (study.airfoil().unwrap(), study.flight_condition().unwrap());
    let ctx = WingContext {
        planform: &planform,
        airfoil: &airfoil,
        flight: &flight,
        cache_dir: None,
        fixed_planform: false,
    };
    let built = aero.fidelity.builder().build(&ctx).unwrap();
    let pts = &built.model.surface().points;
    assert_eq!(built.binding.points.len(), pts.len());
    assert_eq!(
        built.binding.geometry_jacobian.len(),
        built.model.geometry_names().len()
    );
    let p = planform.to_array();
    for (xe, x) in built.binding.points.iter().zip(pts) {
        let q = crate::wing::planform_point(p, xe[0], xe[1]);
        assert!((q[0] - x[0]).abs() < 1e-12 && (q[1] - x[1]).abs() < 1e-12);
    }
}

/// A forward-only model: the DLM's GAFs without its reverse mode.
struct ForwardOnly(Box<dyn Aerodynamics>);

impl Aerodynamics for ForwardOnly {
    fn surface(&self) -> &AeroSurface {
        self.0.surface()
    }
    fn geometry_names(&self) -> Vec<String> {
        self.0.geometry_names()
    }
    fn gafs(
        &self,
        flight: &FlightCondition,
        modes: &ModalSurface,
        k: &[f64],
    ) -> Result<GafTable, AeroError> {
        self.0.gafs(flight, modes, k)
    }
}

/// A bound model without a reverse mode gives its GAFs, and a gradient request is the typed
/// `Unsupported` error naming the fidelity.
#[test]
fn model_without_reverse_mode_is_refused_by_name() {
    let study = agard();
    let plate = study.build_model().unwrap();
    let modes = study.solve_modes(&plate).unwrap();
    let aero = study.spec.aero.as_ref().unwrap();
    let (airfoil, flight) = (study.airfoil().unwrap(), study.flight_condition().unwrap());
    let ctx = WingContext {
        planform: plate.planform(),
        airfoil: &airfoil,
        flight: &flight,
        cache_dir: None,
        fixed_planform: false,
    };
    let mut built = aero.fidelity.builder().build(&ctx).unwrap();
    built.model = Box::new(ForwardOnly(built.model));
    let model = AeroModel::bind(
        "forward-only",
        built,
        study.flight_condition().unwrap(),
        aero.reduced_frequencies.clone(),
        &plate,
    );
    assert!(!model.has_reverse());
    let table = model.gafs(&plate, &modes).unwrap();
    let e = model.gafs_vjp(&plate, &modes, &table).unwrap_err();
    assert_eq!(
        e,
        AeroError::Unsupported {
            fidelity: "forward-only".into(),
            what: "supply gradients (it has no reverse mode)".into()
        }
    );
    assert!(e.to_string().contains("forward-only fidelity"), "{e}");
    assert!(study.aero_model(&plate).unwrap().has_reverse());
}

/// Capabilities come from the spec alone: the DLM, strip theory and the section LFD have a
/// reverse mode (the section has no planform); a use that needs gradients of a fidelity without
/// one, or the planform's of one whose reverse mode covers the mode shapes only, is refused with
/// the fidelity's name.
#[test]
fn capabilities_are_known_before_building() {
    let dlm = DlmSpec {
        n_chord: 4,
        n_span: 4,
        chord_spacing: Default::default(),
        span_spacing: Default::default(),
        symmetry: gustkit_dlm::Symmetry::Symmetric,
    };
    assert!(FidelitySpec::Dlm(dlm).builder().capabilities().reverse);
    let lfd = SectionFidelitySpec::Lfd(crate::aero::lfd::SectionLfdSpec {
        thickness: 0.1,
        mesh: crate::aero::lfd::OMeshSpec {
            n_around: 16,
            n_radial: 4,
            far_field_chords: 20.0,
            first_spacing_chords: 0.01,
        },
        order: crate::aero::lfd::OrderSpec::Second,
    });
    assert!(lfd.capabilities().require_reverse("lfd", "x").is_ok());
    let none = Capabilities {
        reverse: false,
        reverse_planform: false,
    };
    let e = none.require_reverse("fake", "optimization").unwrap_err();
    assert!(
        e.contains("optimization") && e.contains("fake fidelity has no reverse mode"),
        "{e}"
    );
    let shapes_only = Capabilities {
        reverse: true,
        reverse_planform: false,
    };
    assert!(shapes_only.require_reverse("lfd", "x").is_ok());
    let e = shapes_only
        .require_planform_reverse("lfd", "optimization")
        .unwrap_err();
    assert!(
        e.contains("optimization") && e.contains("thickness variables only"),
        "{e}"
    );
    let strip = SectionFidelitySpec::Strip(crate::aero::strip::StripSpec::default());
    assert!(strip.capabilities().require_reverse("strip", "x").is_ok());
}

/// Each builder owns its flight range and memory estimate: the DLM refuses M > 0.97 and sizes
/// its influence matrices (32 B per box pair per k, 100 with gradients) at the field that sizes
/// them; the LFD refuses a free stream at rest or sonic, and its estimate grows with the threads
/// it runs on (each frequency in flight holds a preconditioner and a Krylov basis).
#[test]
fn builders_own_their_flight_range_and_memory() {
    let dlm: DlmSpec =
        serde_json::from_value(serde_json::json!({"n_chord": 8, "n_span": 12})).unwrap();
    assert!(dlm.check_mach(0.9).is_ok());
    assert!(dlm.check_mach(0.98).unwrap_err().contains("0.97"));
    for gradients in [false, true] {
        let f = dlm
            .footprint(&Sizing {
                n_k: 11,
                gradients,
                threads: 2,
            })
            .unwrap();
        let per = if gradients { 100.0 } else { 32.0 };
        assert_eq!(f.bytes, per * 11.0 * 96.0 * 96.0);
        assert_eq!(f.path, "n_span");
    }
    let lfd: crate::aero::lfd::LfdWingSpec =
        serde_json::from_value(serde_json::json!({"mesh": "coarse"})).unwrap();
    assert!(lfd.check_mach(0.5).is_ok());
    for m in [0.0, 1.0] {
        assert!(lfd.check_mach(m).unwrap_err().contains("0 < M < 1"), "{m}");
    }
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| lfd.memory_estimate_gb())
    };
    assert!(
        on(4) > on(2) && on(2) > on(1),
        "{} {} {}",
        on(1),
        on(2),
        on(4)
    );
}

/// The strip builder's binding: each strip's chord points at the (ξ, η) whose planform map is
/// the point's (x, y) to round-off, strips at the centres of equal spanwise strips.
#[test]
fn strip_binding_matches_its_surface() {
    let study = agard();
    let planform = study.planform().unwrap();
    let (airfoil, flight) = (study.airfoil().unwrap(), study.flight_condition().unwrap());
    let ctx = WingContext {
        planform: &planform,
        airfoil: &airfoil,
        flight: &flight,
        cache_dir: None,
        fixed_planform: false,
    };
    let spec: FidelitySpec =
        serde_json::from_value(serde_json::json!({"strip": {"n_strips": 6, "points": 5}})).unwrap();
    let built = spec.builder().build(&ctx).unwrap();
    let pts = &built.model.surface().points;
    assert_eq!((built.binding.points.len(), pts.len()), (30, 30));
    let p = planform.to_array();
    for (xe, x) in built.binding.points.iter().zip(pts) {
        let q = crate::wing::planform_point(p, xe[0], xe[1]);
        assert!((q[0] - x[0]).abs() < 1e-12 && (q[1] - x[1]).abs() < 1e-12);
    }
    assert!((pts[5][1] - 1.5 * planform.span / 6.0).abs() < 1e-12);
    let zero: FidelitySpec =
        serde_json::from_value(serde_json::json!({"strip": {"n_strips": 0}})).unwrap();
    assert_eq!(zero.builder().validate(&ctx).unwrap_err().path, "n_strips");
}

/// Each fidelity's next resolution for the resolution check, in its own words: the DLM's lattice
/// doubled each way (its spacings named where not uniform), the LFD's next mesh level (coarse 7 168 → medium 57 344 cells; none above
/// the fine one), twice the strips.
#[test]
fn each_fidelity_refines_itself() {
    let spec = |v: serde_json::Value| -> FidelitySpec { serde_json::from_value(v).unwrap() };
    let (d, w) = spec(serde_json::json!({"dlm": {"n_chord": 8, "n_span": 12}}))
        .refined()
        .unwrap();
    assert_eq!((d.words(), w.as_str()), (w.clone(), "DLM 16 × 24 boxes"));
    // the spacings are part of the model: named where either is not uniform
    let (_, w) =
        spec(serde_json::json!({"dlm": {"n_chord": 8, "n_span": 12, "chord_spacing": "cosine"}}))
            .refined()
            .unwrap();
    assert_eq!(w, "DLM 16 × 24 boxes (chordwise cosine, spanwise uniform)");
    let (_, w) = spec(serde_json::json!({"lfd": {"mesh": "coarse"}}))
        .refined()
        .unwrap();
    assert_eq!(w, "LFD medium mesh (57344 cells)");
    let e = spec(serde_json::json!({"lfd": {"mesh": "fine"}}))
        .refined()
        .unwrap_err();
    assert!(e.contains("finest built-in level"), "{e}");
    let (s, w) = spec(serde_json::json!({"strip": {"n_strips": 10}}))
        .refined()
        .unwrap();
    assert_eq!(
        (w.as_str(), s.words()),
        ("strip theory, 20 strips", w.clone())
    );
}
