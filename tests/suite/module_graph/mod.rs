//! The library's modules import one another in one direction only (ARCHITECTURE.md): each
//! top-level module of src/ lies in a layer and names only modules of lower layers (results
//! flow from the layers that compute them to `report`, which only formats them), and the
//! modules of one directory, its mod.rs among them, have no cycle among themselves but those
//! `ALLOWED_CYCLES` lists. The Python bindings (python/src) may use any module of the library
//! but not the command line's.
//!
//! Every line of every file is read; what is left out is what a build without `cfg(test)` does
//! not compile (test modules, inline or in their own files, and single test-only items), and
//! comments and literals, which name modules without using them. A test-only item is one
//! marked `#[cfg(test)]` exactly; other conditions (`cfg(all(test, ..))`) are read as code.
//!
//! The tests are here: `reader` reads a file as code, `graph` builds the module graph and finds
//! its cycles, `rules` holds `ALLOWED_CYCLES`, `LAYERS` and the edges they forbid.

mod graph;
mod reader;
mod rules;

use std::collections::BTreeSet;
use std::path::Path;

use graph::{
    Graph, cyclic_groups, describe, find_cycle, graph_of, module_graph, read_rust_files, src,
};
use reader::{code_only, imports_in, paths_in, without_tests};
use rules::{ALLOWED_CYCLES, CLI, FORBIDDEN, LAYERS, declared, layer_of, library_uses};

// ---------------------------------------------------------------------------------------------
// Cycles.

#[test]
fn the_modules_of_src_import_each_other_without_a_cycle() {
    let graph = module_graph(&src());
    assert!(graph.len() > 10, "the scan found too few modules: {graph:?}");
    assert!(graph["report"].contains_key("study"), "the scan must see report's imports: {graph:?}");
    assert!(
        graph.keys().any(|node| node.ends_with("/mod")),
        "the scan must see what a directory's mod.rs names of its files: {graph:?}"
    );
    let found = cyclic_groups(&graph);
    let allowed: BTreeSet<BTreeSet<String>> =
        ALLOWED_CYCLES.iter().map(|group| group.iter().map(|m| m.to_string()).collect()).collect();
    let new: Vec<String> = found.difference(&allowed).map(|g| describe(&graph, g)).collect();
    assert!(new.is_empty(), "import cycles not in ALLOWED_CYCLES:\n  {}", new.join("\n  "));
    let gone: Vec<&BTreeSet<String>> = allowed.difference(&found).collect();
    assert!(
        gone.is_empty(),
        "entries of ALLOWED_CYCLES that are no longer cycles as listed, to remove: {gone:?}"
    );
}

// ---------------------------------------------------------------------------------------------
// Layers.

#[test]
fn each_module_names_only_lower_layers() {
    let graph = module_graph(&src());
    for (from, targets) in graph.iter().filter(|(from, _)| !from.contains('/')) {
        let own = layer_of(from).unwrap_or_else(|| {
            panic!("module {from} is in no layer of LAYERS: place it there and in ARCHITECTURE.md")
        });
        for (to, site) in targets {
            if let Some((_, _, why)) = FORBIDDEN.iter().find(|(a, b, _)| a == from && b == to) {
                panic!("{from} must not use {to} ({site}): {why}");
            }
            assert!(to != CLI, "{from} uses cli ({site}): the command line is the binary's only");
            let below = layer_of(to).is_some_and(|layer| layer < own);
            assert!(below, "{from} (layer {own}) uses {to} (layer {:?}) at {site}", layer_of(to));
        }
    }
    for (root, prefix) in [("lib.rs", "pub mod "), ("main.rs", "mod ")] {
        for name in declared(root, prefix) {
            assert!(layer_of(&name).is_some(), "module {name} ({root}) is in no layer of LAYERS");
        }
    }
}

#[test]
fn lib_rs_lists_its_modules_in_layer_order() {
    let modules = declared("lib.rs", "pub mod ");
    // Every module of LAYERS but the binary's is the library's, so that the order says all.
    for module in LAYERS.iter().flat_map(|layer| layer.iter()).filter(|m| **m != CLI) {
        assert!(modules.iter().any(|m| m == module), "{module} is in LAYERS but not in lib.rs");
    }
    let layers: Vec<Option<usize>> = modules.iter().map(|m| layer_of(m)).collect();
    for (pair, layer) in modules.windows(2).zip(layers.windows(2)) {
        assert!(
            layer[0] <= layer[1],
            "lib.rs lists {} (layer {:?}) before {} (layer {:?}): list the modules lowest layer \
             first, as LAYERS and ARCHITECTURE.md do",
            pair[0],
            layer[0],
            pair[1],
            layer[1]
        );
    }
}

#[test]
fn architecture_md_has_the_layers_of_this_test() {
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("ARCHITECTURE.md"))
            .unwrap();
    // Rows of the module table: `| 3 | `mesh` | ... |`.
    let mut table: Vec<Vec<String>> = Vec::new();
    for row in text.lines().filter_map(|l| l.strip_prefix("| ")) {
        let mut cells = row.split('|').map(str::trim);
        let (Some(layer), Some(module)) = (cells.next(), cells.next()) else { continue };
        let (Ok(layer), Some(module)) = (layer.parse::<usize>(), module.strip_prefix('`')) else {
            continue;
        };
        table.resize(table.len().max(layer + 1), Vec::new());
        table[layer].push(module.trim_end_matches('`').to_string());
    }
    let ours: Vec<Vec<String>> =
        LAYERS.iter().map(|l| l.iter().map(|m| m.to_string()).collect()).collect();
    assert_eq!(table, ours, "ARCHITECTURE.md's module table and LAYERS disagree");
}

#[test]
fn the_python_bindings_use_the_library_but_not_the_command_line() {
    let python = Path::new(env!("CARGO_MANIFEST_DIR")).join("python/src");
    let library: BTreeSet<String> = declared("lib.rs", "pub mod ").into_iter().collect();
    let used = library_uses(&read_rust_files(&python));
    for (site, name) in &used {
        assert!(
            name != CLI,
            "python/src/{site} uses radiosity::cli: the command line is the binary's only"
        );
        // Lower case: a module, which must be the library's (upper case: a re-export).
        let is_module = name.starts_with(|c: char| c.is_ascii_lowercase());
        assert!(
            !is_module || library.contains(name),
            "python/src/{site} uses radiosity::{name}, which lib.rs does not declare"
        );
    }
    assert!(
        used.iter().any(|(_, name)| name == "pipeline"),
        "the scan must see the bindings' imports: {used:?}"
    );
}

// ---------------------------------------------------------------------------------------------
// The checks themselves.

#[test]
fn the_layer_check_sees_a_forbidden_edge() {
    let graph = graph_of(&[("operator/mod.rs", "use crate::gpu::X;"), ("gpu/mod.rs", "")]);
    assert!(graph["operator"].contains_key("gpu"));
    assert!(FORBIDDEN.iter().any(|(a, b, _)| *a == "operator" && *b == "gpu"));
    assert!(layer_of("gpu") >= layer_of("operator"), "the layers forbid it as well");
}

#[test]
fn the_cycle_check_finds_cycles() {
    let edges = |list: &[(&str, &str)]| -> Graph {
        let mut g = Graph::new();
        for (a, b) in list {
            g.entry(a.to_string()).or_default().insert(b.to_string(), String::new());
        }
        g
    };
    let cyclic = edges(&[("report", "study"), ("study", "pipeline"), ("pipeline", "report")]);
    let cycle = find_cycle(&cyclic).expect("a cycle");
    assert_eq!(cycle.first(), cycle.last());
    assert_eq!(cycle.len(), 4);
    assert!(find_cycle(&edges(&[("report", "study"), ("study", "pipeline")])).is_none());
    // Two cycles apart, and a module that only leads into one: two groups, without it.
    let groups =
        cyclic_groups(&edges(&[("a", "b"), ("b", "a"), ("c", "d"), ("d", "c"), ("e", "a")]));
    let names = |g: &[&str]| g.iter().map(|s| s.to_string()).collect::<BTreeSet<_>>();
    assert_eq!(groups, BTreeSet::from([names(&["a", "b"]), names(&["c", "d"])]));
}

#[test]
fn paths_are_read_with_their_groups() {
    let paths = |code: &str, starts: &[&str]| -> Vec<Vec<String>> {
        paths_in(code, starts).into_iter().map(|(_, p)| p).collect()
    };
    let p = |s: &[&str]| s.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    assert_eq!(
        paths("use crate::{mesh::Mesh, scene::{self, Face as F}};", &["crate"]),
        vec![p(&["crate", "mesh", "Mesh"]), p(&["crate", "scene"]), p(&["crate", "scene", "Face"])]
    );
    // `super::super` is one path; `a::crate` or `x.crate` no start; a turbofish ends a path.
    assert_eq!(
        paths("super::super::far_field::X", &["super"]),
        vec![p(&["super", "super", "far_field", "X"])]
    );
    assert_eq!(
        paths("f::<T>(); stored::Data::<f32>::new()", &["stored"]),
        vec![p(&["stored", "Data"])]
    );
    assert!(paths("other::crate::x; y.crate::z", &["crate"]).is_empty());
    let imports = imports_in("pub use stored::{Precision, F32 as Single};\nuse std::ops::*;");
    assert_eq!(imports[1], ("Single".to_string(), p(&["stored", "F32"])));
    assert_eq!(imports[2], ("*".to_string(), p(&["std", "ops"])));
}

#[test]
fn comments_and_literals_are_no_code() {
    let text = "a /* b /* nested */ c */ d // e {\nf \"g { \\\" }\" r#\"h \"{\"# 'i' '{' '\\'' 'a x b'\"≤\"";
    let code = code_only(text);
    assert_eq!(code.len(), text.len());
    let words: Vec<&str> = code.split_whitespace().collect();
    // `'a` is a lifetime, so it stays, as does the rest of that line's code.
    assert_eq!(words, ["a", "d", "f", "'a", "x", "b'"]);
    assert_eq!(code.lines().count(), text.lines().count());
}

#[test]
fn test_code_is_skipped_by_its_scope() {
    let text = r#"use crate::before::A;
#[cfg(test)]
mod tests {
    use crate::tested::B;
    fn f() { let s = "}}}"; let c = '}'; if true { { } } } // }
    /* } */
}
use crate::after::C;
#[cfg(test)]
#[allow(dead_code)]
pub(super) fn only_in_tests() -> Vec<u8> { crate::helper::h() }
fn kept<T, U>() { crate::kept::k() }
#[cfg(test)]
impl<'a> Among<'a> { fn g() { crate::among::x() } }
#[cfg(test)]
use crate::{test_a, test_b};
struct S {
    #[cfg(test)]
    field: crate::field::F,
    other: crate::other::O,
}
#[cfg(test)]
mod file_tests;
#[cfg(test)]
pub(crate) mod threads {
    use crate::threads::T;
}
fn last() { crate::last::l() }
"#;
    let code = without_tests(text);
    let named: Vec<String> =
        paths_in(&code.text, &["crate"]).into_iter().map(|(_, p)| p[1].clone()).collect();
    assert_eq!(named, ["before", "after", "kept", "other", "last"]);
    assert_eq!(code.test_files, ["file_tests"]);
    assert_eq!(code.text.lines().count(), text.lines().count(), "lines are kept");
}

#[test]
fn the_scan_finds_the_cycles_of_a_cyclic_crate() {
    // The cycle this crate once had, through a braced group and a path in an expression.
    let cyclic = graph_of(&[
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
    let siblings = graph_of(&[
        ("mesh/mod.rs", "mod constrained; mod shadow_lines;"),
        ("mesh/constrained.rs", "use super::shadow_lines::Segment;"),
        ("mesh/shadow_lines.rs", "use super::constrained::triangulate;"),
    ]);
    assert!(find_cycle(&siblings).is_some(), "{siblings:?}");
    // Two files of a nested directory, through `super::`, and a parent's mod.rs naming one.
    let nested = graph_of(&[
        ("scene/mod.rs", "mod file;"),
        ("scene/file/mod.rs", "mod builder; mod schema; use builder::Builder;"),
        ("scene/file/builder.rs", "use super::schema::Properties;"),
        ("scene/file/schema.rs", "use super::builder::Rules;"),
    ]);
    assert!(find_cycle(&nested).is_some(), "{nested:?}");
    assert!(nested["scene/file/builder"].contains_key("scene/file/schema"), "{nested:?}");
    assert!(nested["scene/file/mod"].contains_key("scene/file/builder"), "{nested:?}");
    // Imports in test modules, and the crate root, are left out; one-way imports are no cycle.
    let acyclic = graph_of(&[
        ("report/mod.rs", "use crate::study::StudyResult;"),
        ("study/mod.rs", "use crate::pipeline::run;\n#[cfg(test)]\nuse crate::report::x;"),
        ("pipeline.rs", "use crate::solution::SolutionField;"),
        ("solution.rs", "#[cfg(test)]\nmod tests;"),
        ("solution/tests.rs", "use crate::report::x;"),
        ("lib.rs", "pub mod report; use crate::pipeline::run;"),
        ("main.rs", "use crate::report::x;"),
    ]);
    assert_eq!(find_cycle(&acyclic), None, "{acyclic:?}");
}

#[test]
fn a_directory_and_its_files_are_nodes_of_their_own() {
    // mod.rs uses what a file implements; the file uses a type that mod.rs defines: a cycle.
    let cyclic = graph_of(&[
        ("operator/mod.rs", "mod stored; pub struct Block; fn f() { stored::apply() }"),
        ("operator/stored.rs", "use super::Block; pub fn apply() {}"),
    ]);
    assert_eq!(cyclic["operator/mod"]["operator/stored"], "operator/mod.rs:1");
    assert!(cyclic["operator/stored"].contains_key("operator/mod"), "{cyclic:?}");
    assert!(find_cycle(&cyclic).is_some());
    // A name that mod.rs re-exports from a file belongs to that file: no edge to mod.rs.
    let reexport = graph_of(&[
        ("operator/mod.rs", "mod aca; mod stored;\npub use stored::{Precision as P};"),
        ("operator/aca.rs", "use super::P;"),
        ("operator/stored.rs", "use crate::operator::aca::x;"),
    ]);
    assert_eq!(reexport["operator/aca"].keys().collect::<Vec<_>>(), ["operator/stored"]);
    assert!(find_cycle(&reexport).is_some(), "aca and stored use each other: {reexport:?}");
    // mod.rs's `super` is the crate root; `crate::Error` is lib.rs's re-export of error's.
    let root = graph_of(&[
        ("lib.rs", "pub mod error; pub mod operator; pub use error::Error;"),
        ("error.rs", "pub struct Error;"),
        ("operator/mod.rs", "use super::error::Result; fn f() -> crate::Error {}"),
    ]);
    assert_eq!(root["operator"].keys().collect::<Vec<_>>(), ["error"]);
    assert!(!root.contains_key("operator/mod"), "{root:?}");
    // A module's file beside its directory (gpu.rs and gpu/) is a node of its own as mod.rs is.
    let beside = graph_of(&[
        ("gpu.rs", "mod pairs; pub struct Gpu; fn f() { pairs::run() }"),
        ("gpu/pairs.rs", "use super::Gpu; pub fn run() {}"),
    ]);
    assert!(find_cycle(&beside).is_some(), "{beside:?}");
    assert!(beside["gpu/mod"].contains_key("gpu/pairs"), "{beside:?}");
}

#[test]
fn the_bindings_scan_sees_what_they_name() {
    let file = |text: &str| vec![("lib.rs".to_string(), text.to_string())];
    let used = library_uses(&file(
        "use radiosity::{pipeline, cli::Cli};\n// radiosity::cli\n#[cfg(test)]\nmod t {\n    \
         use radiosity::report;\n}\nfn f() -> radiosity::Error { radiosity::cli::run() }",
    ));
    let named = |site: &str, name: &str| (site.to_string(), name.to_string());
    assert_eq!(
        used,
        [
            named("lib.rs:1", "pipeline"),
            named("lib.rs:1", "cli"),
            named("lib.rs:7", "Error"),
            named("lib.rs:7", "cli")
        ]
    );
}
