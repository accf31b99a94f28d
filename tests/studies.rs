//! Every shipped study file loads and validates as its kind (validation is cheap: it builds no
//! aerodynamic model, so the CFD studies load in milliseconds too); a warm-started study whose
//! source run has not been made yet is refused with the command that makes it.

use gustkit::runner::LoadedStudy;

#[test]
fn every_shipped_study_loads() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("studies");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "json") {
            if let Err(e) = LoadedStudy::load(&path) {
                // a warm start reads the results of another run, which a fresh checkout does not
                // have yet (the README's main command writes reports/agard445_dlm)
                let text = format!("{e:#}");
                let waits_for_a_run = text.contains("optimization.warm_start.from")
                    && text.contains("cannot read")
                    && text.contains("gustkit run");
                if !waits_for_a_run {
                    panic!("{}: {text}", path.display());
                }
            }
            n += 1;
        }
    }
    assert!(n >= 13, "only {n} studies found");
}
