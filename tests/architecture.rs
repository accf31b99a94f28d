//! The module graph has no import cycles: in the root package (top-level modules, and the
//! submodules of every folder module, found on disk: the registry ⇄ builders circle inside `aero`
//! was one) and in each fidelity crate (its modules). The evaluation layer never reads a study.
//! A reference `crate::m` or `super::m` in code (comments and unit-test modules excluded) is an edge; the test finds
//! strongly connected components of more than one module (Tarjan) and names them.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every `.rs` file below `dir`.
fn sources(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(sources(&p));
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
    out
}

/// The code of a file without line comments and without its `#[cfg(test)] mod tests` block.
fn code(text: &str) -> String {
    let text = match text.find("#[cfg(test)]\nmod tests") {
        Some(i) => &text[..i],
        None => text,
    };
    text.lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Identifiers following each occurrence of `prefix` in `text`.
fn paths_after(text: &str, prefix: &str) -> Vec<(String, Option<String>)> {
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find(prefix) {
        let before = rest[..i].chars().last();
        rest = &rest[i + prefix.len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let first = ident(rest);
        let second = rest[first.len()..]
            .strip_prefix("::")
            .map(ident)
            .filter(|s| !s.is_empty());
        if !first.is_empty() {
            out.push((first, second));
        }
    }
    out
}

/// The module graph of a crate's `src`; modules in `split` are graphed by their submodules.
fn graph(src: &Path, split: &[&str]) -> BTreeMap<String, BTreeSet<String>> {
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for file in sources(src) {
        let rel = file.strip_prefix(src).unwrap().with_extension("");
        let mut parts: Vec<String> = rel
            .iter()
            .map(|s| s.to_string_lossy().into_owned())
            .collect();
        if parts.last().is_some_and(|p| p == "mod") {
            parts.pop();
        }
        if parts.is_empty()
            || ["lib", "main"].contains(&parts[0].as_str())
            || parts.last().is_some_and(|p| p == "tests")
        {
            continue;
        }
        let node_of = |first: &str, second: Option<&str>| -> String {
            match second {
                Some(s) if split.contains(&first) && is_module(&src.join(first), s) => {
                    format!("{first}/{s}")
                }
                _ => first.to_string(),
            }
        };
        let node = node_of(&parts[0], parts.get(1).map(String::as_str));
        let text = code(&std::fs::read_to_string(&file).unwrap());
        let entry = g.entry(node.clone()).or_default();
        for (a, b) in paths_after(&text, "crate::") {
            let t = node_of(&a, b.as_deref());
            if t != node {
                entry.insert(t);
            }
        }
        if split.contains(&parts[0].as_str()) && parts.len() > 1 {
            for (a, _) in paths_after(&text, "super::") {
                let t = format!("{}/{a}", parts[0]);
                if is_module(&src.join(&parts[0]), &a) && t != node {
                    entry.insert(t);
                }
            }
        }
    }
    g
}

/// Strongly connected components with more than one module.
fn cycles(g: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct Tarjan<'a> {
        g: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<String, usize>,
        low: BTreeMap<String, usize>,
        stack: Vec<String>,
        on: BTreeSet<String>,
        out: Vec<Vec<String>>,
    }
    impl Tarjan<'_> {
        fn visit(&mut self, v: &str) {
            let i = self.index.len();
            self.index.insert(v.into(), i);
            self.low.insert(v.into(), i);
            self.stack.push(v.into());
            self.on.insert(v.into());
            for w in self.g.get(v).into_iter().flatten() {
                if !self.index.contains_key(w) {
                    self.visit(w);
                    let l = self.low[v].min(self.low[w]);
                    self.low.insert(v.into(), l);
                } else if self.on.contains(w) {
                    let l = self.low[v].min(self.index[w]);
                    self.low.insert(v.into(), l);
                }
            }
            if self.low[v] == self.index[v] {
                let mut comp = Vec::new();
                loop {
                    let w = self.stack.pop().unwrap();
                    self.on.remove(&w);
                    let done = w == v;
                    comp.push(w);
                    if done {
                        break;
                    }
                }
                if comp.len() > 1 {
                    self.out.push(comp);
                }
            }
        }
    }
    let mut t = Tarjan {
        g,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in g.keys() {
        if !t.index.contains_key(v) {
            t.visit(v);
        }
    }
    t.out
}

/// Whether `name` is a module of folder `dir` (a file, or a folder with its `mod.rs`).
fn is_module(dir: &Path, name: &str) -> bool {
    dir.join(format!("{name}.rs")).is_file() || dir.join(name).join("mod.rs").is_file()
}

/// The folder modules of a crate's `src` (those graphed by their submodules).
fn folder_modules(src: &Path) -> Vec<String> {
    let mut out: Vec<String> = std::fs::read_dir(src)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    out.sort();
    out
}

/// No import cycle among the modules of the root package or of any fidelity crate (every
/// crate under `fidelity/` found on disk), each folder module graphed by its submodules.
#[test]
fn no_import_cycles() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut crates = vec![root.join("src")];
    let mut fidelities: Vec<PathBuf> = std::fs::read_dir(root.join("fidelity"))
        .unwrap()
        .map(|e| e.unwrap().path().join("src"))
        .filter(|p| p.is_dir())
        .collect();
    fidelities.sort();
    assert!(fidelities.len() >= 3, "fidelity crates not found");
    crates.extend(fidelities);
    for src in &crates {
        let split = folder_modules(src);
        let split: Vec<&str> = split.iter().map(String::as_str).collect();
        if sources(src).len() == 1 {
            continue; // a one-file crate (the test kit) has no modules to form a cycle
        }
        let g = graph(src, &split);
        assert!(g.len() > 3, "{}: no modules found", src.display());
        let c = cycles(&g);
        assert!(c.is_empty(), "{}: import cycles {c:?}", src.display());
    }
}

/// The checker itself finds a cycle where there is one.
#[test]
fn cycle_checker_finds_a_cycle() {
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    g.entry("a".into()).or_default().insert("b".into());
    g.entry("b".into()).or_default().insert("c".into());
    g.entry("c".into()).or_default().insert("a".into());
    g.entry("d".into()).or_default().insert("a".into());
    let c = cycles(&g);
    assert_eq!(c.len(), 1);
    assert_eq!(c[0].len(), 3);
    assert_eq!(
        paths_after("use crate::report::figures; xcrate::no", "crate::"),
        vec![("report".to_string(), Some("figures".to_string()))]
    );
}

/// The evaluation layer (the pipeline, the design problem, the optimizer and everything they
/// call) works on the resolved case (`gustkit::case::Case`) and never on a study file: no
/// reference to `crate::study` or `crate::runner` in its code, so that a new structure source
/// (a Nastran model) or study schema cannot leak rules into it.
#[test]
fn evaluation_layer_reads_no_study() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    for m in ["pipeline.rs", "problem.rs", "case.rs", "units.rs"] {
        files.push(src.join(m));
    }
    for d in [
        "optim",
        "gust",
        "flutter",
        "structure",
        "transfer",
        "wing",
        "aero",
    ] {
        files.extend(sources(&src.join(d)));
    }
    assert!(files.len() > 20, "too few files found: {}", files.len());
    let mut found = Vec::new();
    for f in files.iter().filter(|f| !f.ends_with("tests.rs")) {
        let text = code(&std::fs::read_to_string(f).unwrap());
        for layer in ["study", "runner"] {
            if !paths_after(&text, "crate::")
                .iter()
                .all(|(first, _)| first != layer)
            {
                found.push(format!("{} uses crate::{layer}", f.display()));
            }
        }
    }
    assert!(found.is_empty(), "{found:#?}");
}

/// Builders leave no files for a person (the run folder writes a model's artifacts, SU2's
/// lesson: solvers keep out of output): inside `src/aero` only the steady-state cache and the
/// LFD's scratch files (forward solutions in `TMPDIR`, deleted with their table) write to disk,
/// and the fidelity crates write nothing. Any file write (`fs::write`, `File::create`,
/// `atomic::write`) elsewhere fails this test.
#[test]
fn fidelities_write_no_files() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = sources(&root.join("src/aero"));
    for krate in std::fs::read_dir(root.join("fidelity")).unwrap() {
        files.extend(sources(&krate.unwrap().path().join("src")));
    }
    assert!(files.len() > 20, "too few files found: {}", files.len());
    let mut found = Vec::new();
    for f in &files {
        if f.ends_with("src/aero/lfd/steady_cache.rs")
            || f.ends_with("src/aero/lfd/scratch.rs")
            || f.ends_with("tests.rs")
        {
            continue;
        }
        let text = code(&std::fs::read_to_string(f).unwrap());
        for call in [
            "fs::write(",
            "File::create(",
            "atomic::write(",
            "OpenOptions",
        ] {
            if text.contains(call) {
                found.push(format!("{} calls {call}", f.display()));
            }
        }
    }
    assert!(found.is_empty(), "{found:#?}");
}
