//! Every shipped study file loads and validates as its kind (validation is cheap: it builds no
//! aerodynamic model, so the CFD studies load in milliseconds too).

use gustkit::runner::LoadedStudy;

#[test]
fn every_shipped_study_loads() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("studies");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "json") {
            if let Err(e) = LoadedStudy::load(&path) {
                panic!("{}: {e:#}", path.display());
            }
            n += 1;
        }
    }
    assert!(n >= 13, "only {n} studies found");
}
