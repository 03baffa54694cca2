//! The shape of the house, checked on the sources: no import circles between the top-level
//! modules of either crate, one path for sensor readings from the twin to the predictor (through
//! `sim`), a thin binary and small files.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// Every `.rs` file under `dir`.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let p = entry.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|e| e == "rs") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// The names `crate::NAME` and `crate::{NAME, …}` refer to in `text`.
fn crate_refs(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect()
    };
    for (i, _) in text.match_indices("crate::") {
        let rest = &text[i + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let inner = &group[..group.find('}').unwrap_or(group.len())];
            for part in inner.split(',') {
                let name = ident(part.trim());
                if !name.is_empty() {
                    out.insert(name);
                }
            }
        } else {
            let name = ident(rest);
            if !name.is_empty() {
                out.insert(name);
            }
        }
    }
    out
}

/// Module → the other top-level modules it names, for the crate rooted at `src`.
fn module_graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for entry in std::fs::read_dir(src).unwrap() {
        let p = entry.unwrap().path();
        let name = p.file_stem().unwrap().to_string_lossy().to_string();
        if name == "lib" || name == "main" {
            continue;
        }
        let files = if p.is_dir() {
            rust_files(&p)
        } else if p.extension().is_some_and(|e| e == "rs") {
            vec![p.clone()]
        } else {
            continue;
        };
        let refs = graph.entry(name.clone()).or_default();
        for f in files {
            refs.extend(crate_refs(&std::fs::read_to_string(f).unwrap()));
        }
        refs.remove(&name);
    }
    let names: BTreeSet<String> = graph.keys().cloned().collect();
    for refs in graph.values_mut() {
        refs.retain(|r| names.contains(r));
    }
    graph
}

/// A circle of modules, if there is one (depth-first search for a back edge).
fn find_circle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) -> Option<Vec<String>> {
        if let Some(i) = path.iter().position(|p| p == node) {
            let mut circle = path[i..].to_vec();
            circle.push(node.to_string());
            return Some(circle);
        }
        if done.contains(node) {
            return None;
        }
        path.push(node.to_string());
        for next in &graph[node] {
            if let Some(c) = visit(next, graph, path, done) {
                return Some(c);
            }
        }
        path.pop();
        done.insert(node.to_string());
        None
    }
    let mut done = BTreeSet::new();
    for node in graph.keys() {
        if let Some(c) = visit(node, graph, &mut Vec::new(), &mut done) {
            return Some(c);
        }
    }
    None
}

#[test]
fn the_circle_finder_finds_a_circle() {
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    g.insert("a".into(), ["b".to_string()].into());
    g.insert("b".into(), ["c".to_string()].into());
    g.insert("c".into(), ["a".to_string()].into());
    assert_eq!(find_circle(&g).unwrap(), ["a", "b", "c", "a"]);
    g.get_mut("c").unwrap().clear();
    assert_eq!(find_circle(&g), None);
    assert_eq!(
        crate_refs("use crate::{a, b::C};\nlet x = crate::c::f();"),
        ["a", "b", "c"].map(String::from).into()
    );
}

#[test]
fn no_import_circles_between_top_level_modules() {
    for src in ["src", "crates/vmc-predict/src", "crates/vmc-dynamics/src"] {
        let graph = module_graph(&repo(src));
        assert!(graph.len() > 5, "{src}: {} modules found", graph.len());
        if let Some(c) = find_circle(&graph) {
            panic!("{src}: import circle {}", c.join(" → "));
        }
    }
}

#[test]
fn sensor_readings_reach_a_controller_through_sim_only() {
    // Outside `sim`, no library code hands readings to a controller or a predictor; the speed
    // benchmark, which times one query from fixed readings, is the one exception.
    for f in rust_files(&repo("src")) {
        let rel = f
            .strip_prefix(repo(""))
            .unwrap()
            .to_string_lossy()
            .to_string();
        if rel == "src/sim.rs" || rel == "src/benchmark.rs" {
            continue;
        }
        let text = std::fs::read_to_string(&f).unwrap();
        for (n, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            assert!(
                !code.contains(".on_readings(") && !code.contains(".observe_readings("),
                "{rel}:{}: readings passed to a controller outside sim: {line}",
                n + 1
            );
        }
    }
}

#[test]
fn the_binary_is_thin_and_no_source_file_is_large() {
    let main = std::fs::read_to_string(repo("src/main.rs")).unwrap();
    assert!(
        main.lines().count() <= 300,
        "src/main.rs has {} lines",
        main.lines().count()
    );
    for dir in [
        "src",
        "crates/vmc-predict/src",
        "crates/vmc-dynamics/src",
        "benches",
        "examples",
    ] {
        for f in rust_files(&repo(dir)) {
            let name = f.file_name().unwrap().to_string_lossy();
            if name == "tests.rs" || name.ends_with("_tests.rs") {
                continue;
            }
            let n = std::fs::read_to_string(&f).unwrap().lines().count();
            assert!(n <= 800, "{} has {n} lines (split it at ~800)", f.display());
        }
    }
}
