//! The shape of the house (docs/architecture.md), checked: the crate graph from `cargo
//! metadata`, no import circles inside any crate at any level of its module tree (from the
//! sources), one path for sensor readings from the twin to the predictor (through `sim`), a
//! thin binary, a small application root and small files.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// The workspace's crates, each with the workspace crates it may depend on (normal
/// dependencies) — the drawing of docs/architecture.md.
const CRATE_GRAPH: [(&str, &[&str]); 8] = [
    ("vmc-gcode", &[]),
    ("vmc-predict", &[]),
    ("vmc-identify", &[]),
    ("vmc-dynamics", &[]),
    (
        "vmc-machine",
        &["vmc-dynamics", "vmc-gcode", "vmc-identify", "vmc-predict"],
    ),
    ("vmc-tables", &["vmc-predict"]),
    ("vmc-rtcomp", &["vmc-predict"]),
    (
        "vmc-twin",
        &[
            "vmc-dynamics",
            "vmc-gcode",
            "vmc-identify",
            "vmc-machine",
            "vmc-predict",
            "vmc-tables",
        ],
    ),
];

/// The crates only the application may pull in: the viewer, the terminal, the command line.
const APPLICATION_ONLY: [&str; 4] = ["rerun", "clap", "indicatif", "png"];

/// Source folders of every crate, for the module checks.
fn crate_sources() -> Vec<(String, PathBuf)> {
    let mut out = vec![("vmc-twin".to_string(), repo("src"))];
    for entry in std::fs::read_dir(repo("crates")).unwrap() {
        let dir = entry.unwrap().path();
        if dir.join("Cargo.toml").is_file() {
            let name = dir.file_name().unwrap().to_string_lossy().to_string();
            out.push((name, dir.join("src")));
        }
    }
    out.sort();
    out
}

/// `cargo metadata` of the workspace (resolved, with the lock file).
fn metadata() -> serde_json::Value {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args(["metadata", "--format-version", "1", "--locked", "--offline"])
        .current_dir(repo(""))
        .output()
        .expect("cargo metadata runs");
    assert!(
        out.status.success(),
        "cargo metadata: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// Package id → (name, [(dependency id, kinds)]) from the resolve graph.
type Resolve = BTreeMap<String, (String, Vec<(String, Vec<String>)>)>;

fn resolve(meta: &serde_json::Value) -> Resolve {
    let names: BTreeMap<&str, &str> = meta["packages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| (p["id"].as_str().unwrap(), p["name"].as_str().unwrap()))
        .collect();
    meta["resolve"]["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| {
            let id = n["id"].as_str().unwrap().to_string();
            let deps = n["deps"]
                .as_array()
                .unwrap()
                .iter()
                .map(|d| {
                    let kinds = d["dep_kinds"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .map(|k| k["kind"].as_str().unwrap_or("normal").to_string())
                        .collect();
                    (d["pkg"].as_str().unwrap().to_string(), kinds)
                })
                .collect();
            (id.clone(), (names[id.as_str()].to_string(), deps))
        })
        .collect()
}

/// Every package a build of `name`'s tests compiles: its normal and dev dependencies, then
/// their normal dependencies, transitively (build scripts' dependencies included).
fn built_for_tests_of(graph: &Resolve, name: &str) -> BTreeSet<String> {
    let start = graph
        .iter()
        .find(|(_, (n, _))| n == name)
        .unwrap()
        .0
        .clone();
    let mut seen = BTreeSet::new();
    let mut stack = vec![(start, true)];
    while let Some((id, root)) = stack.pop() {
        if !seen.insert(id.clone()) {
            continue;
        }
        for (dep, kinds) in &graph[&id].1 {
            if root || kinds.iter().any(|k| k != "dev") {
                stack.push((dep.clone(), false));
            }
        }
    }
    seen.into_iter().map(|id| graph[&id].0.clone()).collect()
}

#[test]
fn the_crates_depend_on_each_other_as_drawn() {
    let meta = metadata();
    let members: BTreeSet<String> = meta["workspace_members"]
        .as_array()
        .unwrap()
        .iter()
        .map(|id| {
            let id = id.as_str().unwrap();
            let p = meta["packages"]
                .as_array()
                .unwrap()
                .iter()
                .find(|p| p["id"] == id)
                .unwrap();
            p["name"].as_str().unwrap().to_string()
        })
        .collect();
    let drawn: BTreeSet<String> = CRATE_GRAPH.iter().map(|(n, _)| n.to_string()).collect();
    assert_eq!(members, drawn, "workspace members against the drawing");
    let doc = std::fs::read_to_string(repo("docs/architecture.md")).unwrap();
    for package in meta["packages"].as_array().unwrap() {
        let name = package["name"].as_str().unwrap();
        if !members.contains(name) {
            continue;
        }
        assert!(
            doc.contains(&format!("`{name}`")),
            "docs/architecture.md does not draw {name}"
        );
        let allowed = CRATE_GRAPH.iter().find(|(n, _)| *n == name).unwrap().1;
        let mut internal: Vec<&str> = package["dependencies"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|d| d["kind"].is_null())
            .map(|d| d["name"].as_str().unwrap())
            .filter(|d| members.contains(*d))
            .collect();
        internal.sort_unstable();
        assert_eq!(internal, allowed, "{name}'s workspace dependencies");
    }
}

#[test]
fn the_interpreter_builds_without_the_viewer_or_linear_algebra() {
    let graph = resolve(&metadata());
    let built = built_for_tests_of(&graph, "vmc-gcode");
    for heavy in ["rerun", "nalgebra", "parry3d-f64", "serde_json"] {
        assert!(!built.contains(heavy), "vmc-gcode's tests build {heavy}");
    }
    assert!(built.contains("thiserror") && built.contains("proptest"));
}

#[test]
fn only_the_application_knows_the_viewer_and_the_terminal() {
    let meta = metadata();
    for package in meta["packages"].as_array().unwrap() {
        let name = package["name"].as_str().unwrap();
        if !name.starts_with("vmc-") || name == "vmc-twin" {
            continue;
        }
        for d in package["dependencies"].as_array().unwrap() {
            let dep = d["name"].as_str().unwrap();
            assert!(
                !APPLICATION_ONLY.contains(&dep),
                "{name} depends on {dep}, which only the application may use"
            );
        }
    }
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

/// A module's path in its crate: `src/a/b.rs` and `src/a/b/mod.rs` are `["a", "b"]`, the
/// crate root (`lib.rs`, `main.rs`) is `[]`.
fn module_path(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().to_string())
        .collect();
    if parts.last().is_some_and(|l| l == "mod") {
        parts.pop();
    }
    if parts.len() == 1 && (parts[0] == "lib" || parts[0] == "main") {
        parts.clear();
    }
    parts
}

/// The module paths a file's code names: `crate::a::b…` and `super::…::x` (comments left out),
/// each as the path of segments (resolved against `me` for `super`).
fn named_paths(text: &str, me: &[String]) -> Vec<Vec<String>> {
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect()
    };
    let segments = |mut rest: &str| -> Vec<String> {
        let mut out = Vec::new();
        loop {
            let id = ident(rest);
            if id.is_empty() {
                break;
            }
            rest = &rest[id.len()..];
            out.push(id);
            match rest.strip_prefix("::") {
                Some(r) => rest = r,
                None => break,
            }
        }
        out
    };
    let mut out = Vec::new();
    for line in text.lines() {
        let code = line.split("//").next().unwrap_or("");
        for (i, _) in code.match_indices("crate::") {
            let before = code[..i].chars().next_back();
            if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == '$') {
                continue;
            }
            out.push(segments(&code[i + "crate::".len()..]));
        }
        for (i, _) in code.match_indices("super::") {
            let before = code[..i].chars().next_back();
            if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == ':') {
                continue;
            }
            let mut rest = &code[i..];
            let mut up = 0;
            while let Some(r) = rest.strip_prefix("super::") {
                up += 1;
                rest = r;
            }
            if up <= me.len() {
                let mut path = me[..me.len() - up].to_vec();
                path.extend(segments(rest));
                out.push(path);
            }
        }
    }
    out
}

/// For each module with children: child → the siblings it names (a child's whole subtree
/// counts as the child). Parents and descendants naming each other are not edges: a module
/// re-exports its children's items and its children use them.
fn sibling_graphs(src: &Path) -> BTreeMap<Vec<String>, BTreeMap<String, BTreeSet<String>>> {
    let files = rust_files(src);
    let modules: BTreeSet<Vec<String>> = files.iter().map(|f| module_path(src, f)).collect();
    let mut graphs: BTreeMap<Vec<String>, BTreeMap<String, BTreeSet<String>>> = BTreeMap::new();
    for f in &files {
        let me = module_path(src, f);
        let text = std::fs::read_to_string(f).unwrap();
        for named in named_paths(&text, &me) {
            // The longest prefix that is a module of the crate.
            let Some(target) = (0..=named.len())
                .rev()
                .map(|k| named[..k].to_vec())
                .find(|p| modules.contains(p))
            else {
                continue;
            };
            let common = me.iter().zip(&target).take_while(|(a, b)| a == b).count();
            if common >= me.len() || common >= target.len() {
                continue;
            }
            graphs
                .entry(me[..common].to_vec())
                .or_default()
                .entry(me[common].clone())
                .or_default()
                .insert(target[common].clone());
        }
    }
    graphs
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
        for next in graph.get(node).into_iter().flatten() {
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
fn the_circle_finder_finds_circles_among_siblings_at_any_depth() {
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    g.insert("a".into(), ["b".to_string()].into());
    g.insert("b".into(), ["c".to_string()].into());
    g.insert("c".into(), ["a".to_string()].into());
    assert_eq!(find_circle(&g).unwrap(), ["a", "b", "c", "a"]);
    g.get_mut("c").unwrap().clear();
    assert_eq!(find_circle(&g), None);
    let me = ["x".to_string(), "y".to_string()];
    assert_eq!(
        named_paths(
            "use crate::a::B;\nlet v = super::z::f(); // crate::c\n",
            &me
        ),
        [vec!["a", "B"], vec!["x", "z", "f"]]
    );
    // Two sibling files naming each other, two levels down: a circle under `p::q`.
    let dir = std::env::temp_dir().join(format!("vmc-arch-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("p/q")).unwrap();
    std::fs::write(dir.join("lib.rs"), "pub mod p;").unwrap();
    std::fs::write(dir.join("p/mod.rs"), "pub mod q;").unwrap();
    std::fs::write(dir.join("p/q/mod.rs"), "mod r; mod s;").unwrap();
    std::fs::write(dir.join("p/q/r.rs"), "use super::s::S;").unwrap();
    std::fs::write(dir.join("p/q/s.rs"), "use crate::p::q::r::R;").unwrap();
    let graphs = sibling_graphs(&dir);
    let under_q = &graphs[&vec!["p".to_string(), "q".to_string()]];
    assert_eq!(find_circle(under_q).unwrap(), ["r", "s", "r"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn no_import_circles_in_any_crate_at_any_depth() {
    let mut modules_seen = 0;
    for (name, src) in crate_sources() {
        let graphs = sibling_graphs(&src);
        modules_seen += graphs.values().map(BTreeMap::len).sum::<usize>();
        for (parent, graph) in &graphs {
            if let Some(c) = find_circle(graph) {
                panic!(
                    "{name}: import circle under `{}`: {}",
                    if parent.is_empty() {
                        "crate".to_string()
                    } else {
                        parent.join("::")
                    },
                    c.join(" → ")
                );
            }
        }
    }
    assert!(
        modules_seen > 100,
        "{modules_seen} modules with edges found"
    );
}

#[test]
fn sensor_readings_reach_a_controller_through_sim_only() {
    // Outside `sim`, no code of the machine or the application hands readings to a controller
    // or a predictor; the speed benchmark, which times one query from fixed readings, is the
    // one exception.
    let mut files = rust_files(&repo("src"));
    files.extend(rust_files(&repo("crates/vmc-machine/src")));
    for f in files {
        let rel = f
            .strip_prefix(repo(""))
            .unwrap()
            .to_string_lossy()
            .to_string();
        if rel == "crates/vmc-machine/src/sim.rs" || rel == "src/benchmark.rs" {
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
fn the_binary_is_thin_the_application_root_small_and_no_source_file_large() {
    let main = std::fs::read_to_string(repo("src/main.rs")).unwrap();
    assert!(
        main.lines().count() <= 300,
        "src/main.rs has {} lines",
        main.lines().count()
    );
    let entries = std::fs::read_dir(repo("src")).unwrap().count();
    assert!(entries <= 12, "src/ has {entries} entries");
    let mut dirs: Vec<PathBuf> = crate_sources().into_iter().map(|(_, s)| s).collect();
    dirs.extend(["benches", "examples"].map(repo));
    for dir in dirs {
        for f in rust_files(&dir) {
            let name = f.file_name().unwrap().to_string_lossy();
            if name == "tests.rs" || name.ends_with("_tests.rs") {
                continue;
            }
            let n = std::fs::read_to_string(&f).unwrap().lines().count();
            assert!(n <= 800, "{} has {n} lines (split it at ~800)", f.display());
        }
    }
}
