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

/// One row of the README's "Shipped studies" table: the study file, the command that runs it and
/// the exit status the README promises.
struct ShippedRow {
    study: String,
    command: String,
    exit: i32,
}

/// The rows of the README's "Shipped studies" table (between its heading and the next one).
fn shipped_rows() -> Vec<ShippedRow> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let start = readme
        .find("## Shipped studies")
        .expect("README has no Shipped studies section");
    let section = &readme[start + 3..];
    let section = &section[..section.find("\n## ").unwrap_or(section.len())];
    let mut rows = Vec::new();
    for line in section.lines().filter(|l| l.starts_with("| `")) {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        let unquote = |s: &str| s.trim_matches('`').to_string();
        let exit = cells[4]
            .split("exit ")
            .nth(1)
            .and_then(|s| s.chars().next())
            .and_then(|c| c.to_digit(10))
            .unwrap_or_else(|| panic!("no `exit N` in the row: {line}"));
        rows.push(ShippedRow {
            study: unquote(cells[1]),
            command: unquote(cells[2]),
            exit: exit as i32,
        });
    }
    rows
}

/// Runs one row's command on its study (reports in a scratch folder) and checks the exit status
/// the README promises.
fn run_row(row: &ShippedRow) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    // the flagship's report goes where the README's main command puts it: the warm-started LFD
    // study reads it from there
    let flagship = row.study == "studies/agard445_dlm.json";
    let dir = if flagship {
        root.join("reports")
    } else {
        std::env::temp_dir().join(format!(
            "gustkit-shipped-{}-{}",
            row.study.replace(['/', '.'], "_"),
            std::process::id()
        ))
    };
    if !flagship {
        let _ = std::fs::remove_dir_all(&dir);
    }
    let sub = row
        .command
        .strip_prefix("gustkit ")
        .unwrap_or_else(|| panic!("{}: command {}", row.study, row.command));
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_gustkit"))
        .arg(sub)
        .arg(root.join(&row.study))
        .arg("--reports")
        .arg(&dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    println!(
        "{} {}: exit {:?}",
        row.command,
        row.study,
        out.status.code()
    );
    assert_eq!(
        out.status.code(),
        Some(row.exit),
        "{} {}: the README says exit {}; stderr: {stderr}",
        row.command,
        row.study,
        row.exit
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    if !flagship {
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// Studies quick enough for every test run (DLM, a few seconds to a minute on 2 cores); the
/// others run in `shipped_studies_end_as_the_readme_says_all`.
const QUICK: [&str; 6] = [
    "studies/minimal_wing.json",
    "studies/nastran_bar_wing.json",
    "studies/agard445_dlm_analysis.json",
    "studies/agard445_flutter_m0901.json",
    "studies/agard445_dlm_sweep.json",
    "studies/transport_wing.json",
];

/// Every shipped study has a row in the README's table, and every row names a shipped study and
/// a command that exists; the quick ones end with the exit status the README promises.
#[test]
fn shipped_studies_end_as_the_readme_says() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let rows = shipped_rows();
    for entry in std::fs::read_dir(root.join("studies")).unwrap() {
        let name = format!("studies/{}", entry.unwrap().file_name().to_string_lossy());
        if name.ends_with(".json") {
            assert!(
                rows.iter().any(|r| r.study == name),
                "{name} has no row in the README's Shipped studies table"
            );
        }
    }
    for row in &rows {
        assert!(
            root.join(&row.study).exists(),
            "{}: no such file",
            row.study
        );
        assert!(
            [
                "gustkit run",
                "gustkit flutter",
                "gustkit sweep",
                "gustkit mesh-study",
            ]
            .contains(&row.command.as_str()),
            "{}: command {}",
            row.study,
            row.command
        );
    }
    for row in rows.iter().filter(|r| QUICK.contains(&r.study.as_str())) {
        run_row(row);
    }
}

/// Every row of the README's table, the long CFD ones included (hours on 2 cores:
/// `cargo test --release --test studies -- --ignored`). The warm-started LFD study needs the
/// flagship's run first, as the README says: this runs the rows in the table's order.
#[test]
#[ignore]
fn shipped_studies_end_as_the_readme_says_all() {
    for row in shipped_rows()
        .iter()
        .filter(|r| !QUICK.contains(&r.study.as_str()))
    {
        run_row(row);
    }
}

/// Every shipped reference report works with every command that takes a run folder: `gustkit
/// report` re-renders it (a copy, so the committed figures stay as they are), and one holding an
/// optimization goes into `gustkit compare`.
#[test]
fn shipped_reference_reports_are_accepted() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let scratch = std::env::temp_dir().join(format!("gustkit-reference-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&scratch);
    let mut reports = 0;
    for entry in std::fs::read_dir(root.join("reports/reference")).unwrap() {
        let dir = entry.unwrap().path();
        let results = ["results.json", "sweep_results.json"]
            .iter()
            .map(|f| dir.join(f))
            .find(|p| p.exists());
        let Some(results) = results else {
            continue; // a comparison report (compare.json): no command reads it back
        };
        let copy = scratch.join(dir.file_name().unwrap());
        std::fs::create_dir_all(&copy).unwrap();
        std::fs::copy(&results, copy.join(results.file_name().unwrap())).unwrap();
        let gustkit = || std::process::Command::new(env!("CARGO_BIN_EXE_gustkit"));
        let o = gustkit().arg("report").arg(&copy).output().unwrap();
        assert!(
            o.status.success(),
            "gustkit report {}: {}",
            dir.display(),
            String::from_utf8_lossy(&o.stderr)
        );
        reports += 1;
        let text = std::fs::read_to_string(&results).unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        if v.get("history").is_some() {
            let o = gustkit()
                .arg("compare")
                .arg(&dir)
                .arg("--out")
                .arg(scratch.join("compare"))
                .output()
                .unwrap();
            assert!(
                o.status.success(),
                "gustkit compare {}: {}",
                dir.display(),
                String::from_utf8_lossy(&o.stderr)
            );
        }
    }
    assert!(reports >= 4, "only {reports} reference reports");
    std::fs::remove_dir_all(&scratch).unwrap();
}
