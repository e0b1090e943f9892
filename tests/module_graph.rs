//! The library's modules import one another in one direction only (ARCHITECTURE.md): each
//! top-level module of src/ lies in a layer and names only modules of lower layers, and the
//! modules of one directory have no cycle among themselves (results flow from the layers that
//! compute them to `report`, which only formats them). Test code is left out: tests may use
//! anything.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Edges between modules: module path (`mesh`, `mesh/constrained`) to the modules it names.
type Graph = BTreeMap<String, BTreeSet<String>>;

/// The source without its test modules (`#[cfg(test)]` and everything after it, which is where
/// this crate keeps them).
fn without_tests(text: &str) -> &str {
    text.find("#[cfg(test)]").map_or(text, |k| &text[..k])
}

/// Module paths named after `prefix` (`crate::` or `super::`) in `text`, including the members of
/// braced groups such as `crate::{a, b::c}`.
fn named_after(text: &str, prefix: &str) -> Vec<Vec<String>> {
    let mut found = Vec::new();
    for (k, _) in text.match_indices(prefix) {
        let rest = &text[k + prefix.len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            for item in group[..end].split(',') {
                found.push(item.trim().split("::").map(|s| s.trim().to_string()).collect());
            }
        } else {
            let end = rest.find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'));
            found.push(rest[..end.unwrap_or(rest.len())].split("::").map(String::from).collect());
        }
    }
    found
}

/// The module graph of the crate under `src`: top-level modules, and the children of each
/// directory module among themselves.
fn module_graph(src: &Path) -> Graph {
    let mut files = Vec::new();
    collect_rust_files(src, &mut files);
    graph_of(files.iter().map(|file| {
        let rel = file.strip_prefix(src).unwrap().to_string_lossy().into_owned();
        (rel, std::fs::read_to_string(file).unwrap())
    }))
}

/// The module graph of source files given by path relative to src/ (`mesh/constrained.rs`) and
/// text: an edge between two modules of one parent (two top-level modules, or two files of one
/// directory) wherever a file inside the first names the second.
fn graph_of(files: impl IntoIterator<Item = (String, String)>) -> Graph {
    let mut graph = Graph::new();
    let mut edge = |from: &[String], to: &[String]| {
        // The first module where the two paths part: siblings under their common parent.
        let common = from.iter().zip(to).take_while(|(a, b)| a == b).count();
        if common < from.len() && common < to.len() && !to[common].is_empty() {
            let key = |p: &[String]| p[..=common].join("/");
            graph.entry(key(from)).or_default().insert(key(to));
        }
    };
    for (rel, text) in files {
        let rel = Path::new(&rel).with_extension("");
        let parts: Vec<String> =
            rel.iter().map(|p| p.to_string_lossy().into_owned()).filter(|p| p != "mod").collect();
        let is_mod = rel.file_name().is_some_and(|n| n == "mod");
        let Some(top) = parts.first() else { continue };
        if top == "main" || top == "lib" || parts.last().is_some_and(|p| p == "tests") {
            continue;
        }
        let code = without_tests(&text);
        for path in named_after(code, "crate::") {
            edge(&parts, &path);
        }
        // `super::x` names x in the parent of the file's module (a directory's mod.rs is that
        // directory's module, so its `super` is one level further up).
        let parent = &parts[..parts.len() - 1];
        if parent.is_empty() || (is_mod && parts.len() < 2) {
            continue;
        }
        for path in named_after(code, "super::") {
            let target: Vec<String> = parent.iter().cloned().chain(path).collect();
            edge(&parts, &target);
        }
    }
    graph
}

fn collect_rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            collect_rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// A cycle of the graph, if there is one (depth-first search with colours).
fn find_cycle(graph: &Graph) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        graph: &Graph,
        state: &mut BTreeMap<String, bool>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(node.to_string(), false);
        stack.push(node.to_string());
        for next in graph.get(node).into_iter().flatten() {
            match state.get(next) {
                Some(false) => {
                    let start = stack.iter().position(|n| n == next).unwrap();
                    let mut cycle = stack[start..].to_vec();
                    cycle.push(next.clone());
                    return Some(cycle);
                }
                Some(true) => {}
                None => {
                    if let Some(c) = visit(next, graph, state, stack) {
                        return Some(c);
                    }
                }
            }
        }
        stack.pop();
        state.insert(node.to_string(), true);
        None
    }
    let mut state = BTreeMap::new();
    for node in graph.keys() {
        if !state.contains_key(node) {
            if let Some(c) = visit(node, graph, &mut state, &mut Vec::new()) {
                return Some(c);
            }
        }
    }
    None
}

#[test]
fn the_modules_of_src_import_each_other_without_a_cycle() {
    let graph = module_graph(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"));
    assert!(graph.len() > 10, "the scan found too few modules: {graph:?}");
    assert!(graph["report"].contains("study"), "the scan must see report's imports: {graph:?}");
    if let Some(cycle) = find_cycle(&graph) {
        panic!("import cycle: {}", cycle.join(" -> "));
    }
}

/// The layers of src/, lowest first: a module names only modules of lower layers.
const LAYERS: &[&[&str]] = &[
    &["error", "progress", "distributed", "geometry", "quadrature"],
    &["kernels", "scene"],
    &["visibility"],
    &["mesh"],
    &["discretization"],
    &["assembly"],
    &["gpu", "operator", "problems", "viewfactors"],
    &["solve", "solution", "surface_error"],
    &["pipeline"],
    &["bench", "study"],
    &["report"],
    &["cli"],
];

/// Edges that name what a layer must not know, and why (the layers forbid them too; these say
/// why in the failure).
const FORBIDDEN: &[(&str, &str, &str)] = &[
    ("operator", "gpu", "the operator asks for values through assembly's PairEvaluation"),
    ("visibility", "mesh", "the pair plan sees faces and points, not the mesh"),
    ("assembly", "gpu", "the GPU implements assembly's traits, not the other way round"),
];

fn layer_of(module: &str) -> Option<usize> {
    LAYERS.iter().position(|layer| layer.contains(&module))
}

#[test]
fn each_module_names_only_lower_layers() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let graph = module_graph(&src);
    for (from, targets) in graph.iter().filter(|(from, _)| !from.contains('/')) {
        let own = layer_of(from).unwrap_or_else(|| {
            panic!("module {from} is in no layer of LAYERS: place it there and in ARCHITECTURE.md")
        });
        for to in targets {
            if let Some((_, _, why)) = FORBIDDEN.iter().find(|(a, b, _)| a == from && b == to) {
                panic!("{from} must not use {to}: {why}");
            }
            assert!(to != "cli", "{from} uses cli: the command line is the binary's only");
            let below = layer_of(to).is_some_and(|layer| layer < own);
            assert!(below, "{from} (layer {own}) uses {to} (layer {:?})", layer_of(to));
        }
    }
    let text = |file: &str| std::fs::read_to_string(src.join(file)).unwrap_or_default();
    for (file, module) in [("lib.rs", "pub mod "), ("main.rs", "mod ")] {
        for line in text(file).lines().filter_map(|l| l.strip_prefix(module)) {
            let name = line.trim_end_matches(';');
            assert!(layer_of(name).is_some(), "module {name} ({file}) is in no layer of LAYERS");
        }
    }
}

#[test]
fn the_layer_check_sees_a_forbidden_edge() {
    let graph = graph_of([("operator/mod.rs".to_string(), "use crate::gpu::X;".to_string())]);
    assert!(graph["operator"].contains("gpu"));
    assert!(FORBIDDEN.iter().any(|(a, b, _)| *a == "operator" && *b == "gpu"));
    assert!(layer_of("gpu") >= layer_of("operator"), "the layers forbid it as well");
}

#[test]
fn the_cycle_check_finds_cycles() {
    let edges = |list: &[(&str, &str)]| -> Graph {
        let mut g = Graph::new();
        for (a, b) in list {
            g.entry(a.to_string()).or_default().insert(b.to_string());
        }
        g
    };
    let cyclic = edges(&[("report", "study"), ("study", "pipeline"), ("pipeline", "report")]);
    let cycle = find_cycle(&cyclic).expect("a cycle");
    assert_eq!(cycle.first(), cycle.last());
    assert_eq!(cycle.len(), 4);
    assert!(find_cycle(&edges(&[("report", "study"), ("study", "pipeline")])).is_none());
    // The scan reads braced groups and sibling imports.
    let named = named_after("use crate::{mesh::Mesh, scene};", "crate::");
    assert_eq!(named, vec![vec!["mesh".to_string(), "Mesh".into()], vec!["scene".to_string()]]);
}

#[test]
fn the_scan_finds_the_cycles_of_a_cyclic_crate() {
    let crate_of = |files: &[(&str, &str)]| {
        graph_of(files.iter().map(|(path, text)| (path.to_string(), text.to_string())))
    };
    // The cycle this crate once had, through a braced group and a path in an expression.
    let cyclic = crate_of(&[
        ("report/mod.rs", "use crate::{error::Result, study::StudyResult};"),
        ("study/mod.rs", "fn run() { crate::pipeline::run(); }"),
        ("pipeline.rs", "use crate::report::SolutionField;"),
        ("error.rs", ""),
    ]);
    let cycle = find_cycle(&cyclic).expect("the scan must find the cycle");
    assert_eq!(cycle.len(), 4, "{cycle:?}");
    for module in ["report", "study", "pipeline"] {
        assert!(cycle.contains(&module.to_string()), "{cycle:?}");
    }
    // Two files of one directory that import each other.
    let siblings = crate_of(&[
        ("mesh/constrained.rs", "use super::shadow_lines::Segment;"),
        ("mesh/shadow_lines.rs", "use super::constrained::triangulate;"),
    ]);
    assert!(find_cycle(&siblings).is_some(), "{siblings:?}");
    // Two files of a nested directory, through `super::`, and a parent's mod.rs naming one.
    let nested = crate_of(&[
        ("scene/file/mod.rs", "use builder::Builder;"),
        ("scene/file/builder.rs", "use super::schema::Properties;"),
        ("scene/file/schema.rs", "use super::builder::Rules;"),
    ]);
    assert!(find_cycle(&nested).is_some(), "{nested:?}");
    assert!(nested["scene/file/builder"].contains("scene/file/schema"), "{nested:?}");
    // Imports in test modules, and the crate root, are left out; one-way imports are no cycle.
    let acyclic = crate_of(&[
        ("report/mod.rs", "use crate::study::StudyResult;"),
        ("study/mod.rs", "use crate::pipeline::run;\n#[cfg(test)]\nuse crate::report::x;"),
        ("pipeline.rs", "use crate::solution::SolutionField;"),
        ("solution.rs", ""),
        ("lib.rs", "pub mod report; use crate::pipeline::run;"),
        ("main.rs", "use crate::report::x;"),
    ]);
    assert_eq!(find_cycle(&acyclic), None, "{acyclic:?}");
}
