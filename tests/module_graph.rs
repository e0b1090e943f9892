//! The library's modules import one another in one direction only: no cycle among the top-level
//! modules of src/, nor among the sibling modules of one directory (results flow from the layers
//! that compute them to `report`, which only formats them). Test code is left out: tests may use
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
/// text.
fn graph_of(files: impl IntoIterator<Item = (String, String)>) -> Graph {
    let mut graph = Graph::new();
    for (rel, text) in files {
        let rel = Path::new(&rel).with_extension("");
        let parts: Vec<String> =
            rel.iter().map(|p| p.to_string_lossy().into_owned()).filter(|p| p != "mod").collect();
        let Some(top) = parts.first().cloned() else { continue };
        if top == "main" || top == "lib" || parts.last().is_some_and(|p| p == "tests") {
            continue;
        }
        let code = without_tests(&text);
        for path in named_after(code, "crate::") {
            let Some(target) = path.first().filter(|t| !t.is_empty()) else { continue };
            if *target != top {
                graph.entry(top.clone()).or_default().insert(target.clone());
            } else if parts.len() >= 2 && path.len() >= 2 && path[1] != parts[1] {
                let (from, to) = (format!("{top}/{}", parts[1]), format!("{top}/{}", path[1]));
                graph.entry(from).or_default().insert(to);
            }
        }
        // `super::x` from a file of directory module `top` names its sibling `top/x`.
        if parts.len() == 2 {
            for path in named_after(code, "super::") {
                if let Some(sibling) = path.first().filter(|s| !s.is_empty() && **s != parts[1]) {
                    let from = format!("{top}/{}", parts[1]);
                    graph.entry(from).or_default().insert(format!("{top}/{sibling}"));
                }
            }
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
