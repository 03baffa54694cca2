//! The information boundary (docs/architecture.md), checked: the knowledge side (`vmc-predict`:
//! predictors, controller, synthesis, datasets; `vmc-identify`: five-axis identification;
//! `vmc-dynamics`: milling dynamics and chatter control) cannot reach the machine's truth because
//! it depends neither on the machine crate (`vmc-machine`) nor on the application
//! (`vmc-twin`) — and cannot, since both depend on it (Cargo forbids cycles). This test fails
//! if someone adds such a dependency or names either crate in the knowledge side's sources.

use std::path::Path;

/// The crates of the knowledge side.
const KNOWLEDGE_CRATES: [&str; 4] = ["vmc-predict", "vmc-identify", "vmc-dynamics", "vmc-tables"];

/// The crates of the truth side and the application, which the knowledge side must not name.
const TRUTH_CRATES: [&str; 2] = ["vmc-machine", "vmc-twin"];

#[test]
fn the_identification_crate_depends_only_on_numerics() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let m = manifest(&root.join("crates/vmc-identify/Cargo.toml"));
    let deps = m["dependencies"].as_table().unwrap();
    let mut names: Vec<&String> = deps.keys().collect();
    names.sort();
    assert_eq!(names, ["nalgebra", "serde", "thiserror"]);
}

fn manifest(path: &Path) -> toml::Table {
    let text = std::fs::read_to_string(path).unwrap();
    toml::from_str(&text).unwrap()
}

fn dependency_names(t: &toml::Table) -> Vec<String> {
    let mut names = Vec::new();
    for section in ["dependencies", "dev-dependencies", "build-dependencies"] {
        if let Some(deps) = t.get(section).and_then(|d| d.as_table()) {
            names.extend(deps.keys().cloned());
        }
    }
    names
}

#[test]
fn the_knowledge_crates_do_not_depend_on_the_machine_or_the_application() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for krate in KNOWLEDGE_CRATES {
        let m = manifest(&root.join(format!("crates/{krate}/Cargo.toml")));
        let deps = dependency_names(&m);
        assert!(!deps.is_empty());
        for d in &deps {
            assert!(
                !TRUTH_CRATES.contains(&d.replace('_', "-").as_str()),
                "{krate} depends on {d}"
            );
        }
        // And the application depends on the knowledge crate (the only allowed direction).
        let twin = manifest(&root.join("Cargo.toml"));
        assert!(dependency_names(&twin).iter().any(|d| d == krate));
    }
}

#[test]
fn no_knowledge_side_source_names_the_twin() {
    fn walk(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    let mut files = Vec::new();
    for krate in KNOWLEDGE_CRATES {
        let before = files.len();
        walk(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("crates/{krate}/src")),
            &mut files,
        );
        assert!(files.len() - before > 5, "{krate}");
    }
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap();
        // Code lines only: documentation may mention the twin to explain the boundary.
        for (n, line) in text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim_start().starts_with("//"))
        {
            for forbidden in ["vmc_twin", "vmc_machine", "extern crate"] {
                assert!(
                    !line.contains(forbidden),
                    "{}:{} uses `{forbidden}`",
                    f.display(),
                    n + 1
                );
            }
        }
    }
}
