//! Helpers shared by the integration tests: the AGARD study with edits, and its plate model.
#![allow(dead_code)]

use gustkit::structure::{airfoil_thickness, Clamp, Orthotropic, PlateMesh, PlateModel};
use gustkit::study::Study;
use gustkit::wing::{Airfoil, DesignVector, Planform};
use std::path::{Path, PathBuf};

/// The design variables (SI, the optimizer's order) of a design kept in `tests/data/<file>`.
pub fn fixture_design(file: &str) -> Vec<f64> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(file);
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    doc["design_variables"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect()
}

/// Path of the shipped AGARD study.
pub fn agard_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/agard445_dlm_analysis.json")
}

/// The AGARD study as JSON.
pub fn agard_json() -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(agard_path()).unwrap()).unwrap()
}

/// The AGARD study after `edit` (coarser boxes, fewer frequencies, …), loaded and validated.
pub fn agard_study(edit: impl FnOnce(&mut serde_json::Value)) -> Study {
    let mut v = agard_json();
    edit(&mut v);
    Study::from_str(Path::new("agard_edited.json"), &v.to_string()).unwrap()
}

/// Sets the DLM box layout of a study JSON.
pub fn set_boxes(v: &mut serde_json::Value, n_chord: usize, n_span: usize) {
    v["aero"]["fidelity"]["dlm"]["n_chord"] = n_chord.into();
    v["aero"]["fidelity"]["dlm"]["n_span"] = n_span.into();
}

/// The AGARD 445.6 mahogany with the grain along the 45° quarter-chord line.
pub fn mahogany() -> Orthotropic {
    Orthotropic {
        e1: 3.151e9,
        e2: 0.4162e9,
        g12: 0.4392e9,
        nu12: 0.31,
        density: 381.98,
        grain_angle: 45f64.to_radians(),
    }
}

/// The AGARD planform in SI.
pub fn agard_planform() -> Planform {
    Planform {
        span: 0.762,
        sweep_c4: 45f64.to_radians(),
        root_chord: 0.5587,
        tip_chord: 0.3682,
    }
}

/// The AGARD plate: 10 × 10 design patches split into refine² elements, NACA 65A004 thickness.
pub fn agard_plate(refine: usize, clamp: Clamp) -> PlateModel {
    let planform = agard_planform();
    let mesh = PlateMesh::new(10, 10, refine, &clamp).unwrap();
    let thickness = airfoil_thickness(&mesh, &planform, &Airfoil::naca65a004());
    PlateModel::new(
        mesh,
        mahogany(),
        DesignVector {
            thickness,
            planform,
        },
    )
    .unwrap()
}

/// The gustkit binary of this build.
pub fn gustkit() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_gustkit"))
}

/// A test's scratch folder, removed when the test ends well and kept (its path printed) when it
/// panics, so a passing test run leaves nothing in the temporary folder.
pub struct Scratch(PathBuf);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<std::ffi::OsStr> for Scratch {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.0.as_os_str()
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if std::thread::panicking() {
            eprintln!("scratch folder kept for inspection: {}", self.0.display());
        } else {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

/// An empty scratch folder `gustkit-<suite>-<name>-<pid>` in the temporary folder, removed when
/// the returned guard drops (kept when the test fails).
pub fn scratch(suite: &str, name: &str) -> Scratch {
    let d = std::env::temp_dir().join(format!("gustkit-{suite}-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    Scratch(d)
}

/// Asserts that a gustkit command succeeded, showing its error output when not.
pub fn assert_success(out: &std::process::Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Asserts that a gustkit command stopped on a user error (exit 1) whose message names `needle`.
pub fn assert_refused(out: &std::process::Output, needle: &str) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains(needle), "{err}");
}

/// gustkit's plate as Nastran bulk data, every point through `rot` (a rigid rotation of the
/// whole wing): the grain's CORD2R 9, MAT8 1, GRIDs (ids from 1 in the plate's node order), one
/// PSHELL a CQUAD4 with the element's thickness, SPC1 1 at the clamped nodes.
pub fn plate_bulk_data(plate: &PlateModel, rot: &dyn Fn([f64; 3]) -> [f64; 3]) -> String {
    let xy = plate.node_xy();
    let grain = mahogany().grain_angle;
    let mut deck = String::new();
    // the grain direction (sin g, cos g, 0) as the x axis of CORD2R 9
    let g_dir = rot([grain.sin(), grain.cos(), 0.0]);
    let normal = rot([0.0, 0.0, 1.0]);
    let cpt = [
        g_dir[0] + 0.3 * normal[0],
        g_dir[1] + 0.3 * normal[1],
        g_dir[2] + 0.3 * normal[2],
    ];
    deck.push_str(&format!(
        "CORD2R,9,,0.,0.,0.,{:.17e},{:.17e},{:.17e}\n,{:.17e},{:.17e},{:.17e}\n",
        normal[0], normal[1], normal[2], cpt[0], cpt[1], cpt[2]
    ));
    let m = mahogany();
    deck.push_str(&format!(
        "MAT8,1,{:e},{:e},{},{:e},,,{}\n",
        m.e1, m.e2, m.nu12, m.g12, m.density
    ));
    for (i, p) in xy.iter().enumerate() {
        let q = rot([p[0], p[1], 0.0]);
        deck.push_str(&format!(
            "GRID*,{},,{:.17e},{:.17e}\n*,{:.17e}\n",
            i + 1,
            q[0],
            q[1],
            q[2]
        ));
    }
    for (e, nodes) in plate.mesh.elements.iter().enumerate() {
        deck.push_str(&format!(
            "PSHELL*,{},1,{:.17e},1\n",
            e + 1,
            plate.element_thickness(e)
        ));
        deck.push_str(&format!(
            "CQUAD4,{},{},{},{},{},{},9\n",
            e + 1,
            e + 1,
            nodes[0] + 1,
            nodes[1] + 1,
            nodes[2] + 1,
            nodes[3] + 1
        ));
    }
    for (i, &c) in plate.mesh.clamped.iter().enumerate() {
        if c {
            deck.push_str(&format!("SPC1,1,123456,{}\n", i + 1));
        }
    }
    deck
}

/// A cantilever plate wing of 2 × 4 CQUAD4 (two PSHELLs, root and tip halves; chord 0.5 m,
/// semispan 2 m) with a tip mass, one CAERO1 of 4 × 4 boxes on an infinite-plate SPLINE1, a
/// random gust at M 0.3 on 0.1–19.85 Hz with 2 % modal damping: EIGRL keeps `modes`,
/// `half_wing` sets AERO's SYMXZ = 1, and everything moves by `dx` along the flow (grids, panel,
/// the gust's X0 = dx + `gust_x0`).
pub fn plate_wing_gust_deck(dx: f64, modes: usize, half_wing: bool, gust_x0: f64) -> String {
    let mut d = String::from(
        "SOL 146\nCEND\nSPC = 1\nMETHOD = 1\nFREQ = 40\nRANDOM = 31\nGUST = 32\nSDAMP = 20\nBEGIN BULK\n",
    );
    d.push_str(&format!(
        "EIGRL,1,,,{modes}\nMAT1,1,7.0e10,,0.3,2700.\nPSHELL,1,1,0.012,1\nPSHELL,2,1,0.008,1\n"
    ));
    for iy in 0..5 {
        for ix in 0..3 {
            d.push_str(&format!(
                "GRID,{},,{},{},0.\n",
                1 + ix + 3 * iy,
                dx + 0.25 * ix as f64,
                0.5 * iy as f64
            ));
        }
    }
    let mut e = 1;
    for iy in 0..4 {
        for ix in 0..2 {
            let g = 1 + ix + 3 * iy;
            let pid = if iy < 2 { 1 } else { 2 };
            d.push_str(&format!(
                "CQUAD4,{e},{pid},{g},{},{},{}\n",
                g + 1,
                g + 4,
                g + 3
            ));
            e += 1;
        }
    }
    d.push_str("CONM2,201,15,,0.5\nSPC1,1,123456,1,2,3\n");
    d.push_str(if half_wing {
        "AERO,0,100.,0.5,0.4,1\nPARAM,MACH,0.3\n"
    } else {
        "AERO,0,100.,0.5,0.4\nPARAM,MACH,0.3\n"
    });
    d.push_str(&format!(
        "CAERO1,1001,1000,,4,4,,,1,+CA\n+CA,{dx},0.,0.,0.5,{dx},2.,0.,0.5\nPAERO1,1000\n"
    ));
    d.push_str("SPLINE1,100,1001,1001,1016,10\nSET1,10,1,THRU,15\n");
    d.push_str("MKAERO1,0.3,,,,,,,,+MK\n+MK,0.01,0.1,0.5,1.0\n");
    d.push_str(&format!(
        "GUST,32,33,0.01,{},100.\nRLOAD1,33,34,,,35\nDAREA,34,1,3,1.\n",
        dx + gust_x0
    ));
    d.push_str("TABLED1,35,,,,,,,,+TB\n+TB,0.,1.,1000.,1.,ENDT\n");
    d.push_str("FREQ1,40,0.1,0.25,79\nRANDPS,31,1,1,1.,,36\n");
    d.push_str("TABRND1,36,,,,,,,,+TR\n+TR,0.,1.,1000.,1.,ENDT\n");
    d.push_str("TABDMP1,20,CRIT,,,,,,,+TD\n+TD,0.,0.02,1000.,0.02,ENDT\nENDDATA\n");
    d
}

/// The small built-in wing mesh of the LFD tests (768 cells: 16 around, 6 radial, 4 + 4 spanwise).
pub fn small_wing_mesh_spec() -> gustkit_cfd::wing_mesh::WingMeshSpec {
    gustkit_cfd::wing_mesh::WingMeshSpec {
        n_around: 16,
        n_radial: 6,
        n_span: 4,
        n_outboard: 4,
        far_field_chords: 15.0,
        first_spacing_chords: 0.02,
        tip_closure: 0.05,
    }
}
