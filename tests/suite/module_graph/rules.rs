//! The rules that src/ keeps: the import cycles allowed, the layers and the edges they forbid,
//! and what a crate using the library names of it.

use super::graph::src;
use super::reader::{paths_in, without_tests};

/// The groups of modules of one directory that use one another today (found when the scan
/// learnt to read a directory's mod.rs as a node of its own and to follow its re-exports), and
/// only these: the test fails on any other group, on a group that grows, and on an entry that
/// no longer is one as listed (then take it out, or shrink it, here). Each group is the set of
/// modules that reach one another; a failure names one cycle through it and where each step is.
///
/// Most go through a directory's mod.rs: it declares the types and calls what its files
/// implement, and the files use its types through `super::` (Rust's usual layout). The last
/// three are cycles between files of one directory, one way through a name that mod.rs
/// re-exports (`super::DeviceTraffic` is resident.rs's): they are what to untangle first.
pub const ALLOWED_CYCLES: &[&[&str]] = &[
    &["distributed/mod", "distributed/mpi"],
    &["kernels/by_rule", "kernels/mod"],
    &["mesh/graded", "mesh/mod"],
    &["scene/builtin", "scene/city", "scene/file", "scene/mod"],
    &["scene/file/builder", "scene/file/import", "scene/file/mod", "scene/file/schema"],
    &["solve/lu", "solve/mod", "solve/products"],
    // Between files: gpu/assembly.rs names resident.rs's `DeviceTraffic`, resident.rs
    // assembly.rs's `GpuAssembler`.
    &["gpu/assembly", "gpu/resident"],
    // Between files: occluders.rs builds solids.rs's `Solid`s, solids.rs names `Occluder`.
    &["visibility/occluders", "visibility/solids"],
];

// ---------------------------------------------------------------------------------------------
// Layers.

/// The layers of src/, lowest first: a module names only modules of lower layers
/// (ARCHITECTURE.md's table, which a test compares with this).
pub const LAYERS: &[&[&str]] = &[
    &["error", "progress", "distributed", "geometry", "quadrature"],
    &["vocabulary"],
    &["kernels", "scene"],
    &["visibility"],
    &["mesh"],
    &["discretization"],
    &["assembly"],
    &["gpu", "operator", "problems", "sun", "viewfactors"],
    &["solve", "solution", "surface_error"],
    &["pipeline", "shortwave"],
    &["bench", "study"],
    &["report"],
    &["cli"],
];

/// Edges that name what a layer must not know, and why (the layers forbid them too; these say
/// why in the failure).
pub const FORBIDDEN: &[(&str, &str, &str)] = &[
    ("operator", "gpu", "the operator asks for values through assembly's PairEvaluation"),
    ("visibility", "mesh", "the pair plan sees faces and points, not the mesh"),
    ("assembly", "gpu", "the GPU implements assembly's traits, not the other way round"),
];

/// The command line's module: the binary's alone.
pub const CLI: &str = "cli";

pub fn layer_of(module: &str) -> Option<usize> {
    LAYERS.iter().position(|layer| layer.contains(&module))
}

/// The modules that a crate root declares with `prefix` (`pub mod `), in order.
pub fn declared(root: &str, prefix: &str) -> Vec<String> {
    let text = std::fs::read_to_string(src().join(root)).unwrap();
    let names = text.lines().filter_map(|l| l.strip_prefix(prefix)?.strip_suffix(';'));
    names.map(str::to_string).collect()
}

/// What the files (path and text) of a crate that uses the library as `radiosity` name right
/// after `radiosity::` (a module, or a re-export of the root), and where (`lib.rs:19`).
pub fn library_uses(files: &[(String, String)]) -> Vec<(String, String)> {
    let mut used = Vec::new();
    for (file, text) in files {
        let code = without_tests(text);
        for (offset, path) in paths_in(&code.text, &["radiosity"]) {
            let line = code.text[..offset].matches('\n').count() + 1;
            if let Some(name) = path.get(1) {
                used.push((format!("{file}:{line}"), name.clone()));
            }
        }
    }
    used
}
