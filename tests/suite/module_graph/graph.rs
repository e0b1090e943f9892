//! The module graph of a crate read from its files, and the cycles in it.

use std::collections::{BTreeMap, BTreeSet};
use std::ops::Range;
use std::path::{Path, PathBuf};

use super::reader::{Code, imports_in, is_ident, item_at, paths_in, without_tests};

/// Edges between modules: module (`mesh`, `mesh/constrained`, or `mesh/mod` for what the file
/// mesh/mod.rs itself holds) to the modules it names, each with the first place it names it
/// (`mesh/constrained.rs:12`) so that a failure can point there.
pub type Graph = BTreeMap<String, BTreeMap<String, String>>;

// ---------------------------------------------------------------------------------------------
// The module graph.

/// A module of the crate that a file holds, as the graph sees it.
struct Module {
    /// `[operator, stored]` for operator/stored.rs, `[operator]` for operator/mod.rs.
    path: Vec<String>,
    /// A module with files below it (operator/mod.rs, or x.rs beside x/): a node of its own
    /// among them (`operator/mod`), so that a cycle between it and them shows.
    is_dir: bool,
    /// Where it is (`operator/stored.rs`), for the failures.
    file: String,
    code: Code,
}

impl Module {
    /// The graph's node for this file: `operator/mod` for operator/mod.rs.
    fn node(&self) -> Vec<String> {
        let mut node = self.path.clone();
        if self.is_dir {
            node.push("mod".into());
        }
        node
    }

    /// Modules declared in this file (`mod x;`, `mod x { .. }`): a path may start with them.
    fn children(&self) -> Vec<&str> {
        let mut children = Vec::new();
        for (k, _) in self.code.text.match_indices("mod ") {
            let b = self.code.text.as_bytes();
            if k == 0 || !is_ident(b[k - 1]) {
                if let ["mod", name] = item_at(&self.code.text, k).words[..] {
                    children.push(name);
                }
            }
        }
        children
    }

    /// Inline modules of this file (`pub mod field { .. }`), where `super` and `self` mean
    /// something else: their spans and names, outermost first.
    fn inline_modules(&self) -> Vec<(Range<usize>, String)> {
        let text = &self.code.text;
        let b = text.as_bytes();
        let mut found = Vec::new();
        for (k, _) in text.match_indices("mod ") {
            if k > 0 && is_ident(b[k - 1]) {
                continue;
            }
            let item = item_at(text, k);
            if let (["mod", name], true) = (&item.words[..], text[..item.end].ends_with('}')) {
                found.push((k..item.end, name.to_string()));
            }
        }
        found
    }

    /// The crate path (from the root, without `crate`) that `path`, written at `offset` of this
    /// file, names; None where it leaves the crate.
    fn absolute(
        &self,
        offset: usize,
        path: &[String],
        inline: &[(Range<usize>, String)],
    ) -> Option<Vec<String>> {
        let mut base = self.path.clone();
        base.extend(
            inline.iter().filter(|(span, _)| span.contains(&offset)).map(|(_, n)| n.clone()),
        );
        let mut rest = path;
        match path.first().map(String::as_str) {
            Some("crate" | "$crate") => return Some(path[1..].to_vec()),
            Some("self") => rest = &path[1..],
            Some("super") => {
                while rest.first().is_some_and(|s| s == "super") {
                    base.pop()?;
                    rest = &rest[1..];
                }
            }
            _ => {} // a child module of this file
        }
        base.extend(rest.iter().cloned());
        Some(base)
    }
}

/// The modules of a crate, read: what each file compiles and where a path leads.
struct Crate {
    modules: Vec<Module>,
    /// Module path to its index in `modules`; the crate root (lib.rs) is `[]`.
    by_path: BTreeMap<Vec<String>, usize>,
    /// Names that each module imports, to the crate path they stand for: a child's
    /// `super::Precision` is operator/stored.rs's item where operator/mod.rs re-exports it.
    imports: BTreeMap<Vec<String>, BTreeMap<String, Vec<String>>>,
}

impl Crate {
    /// The crate of the source files given by path relative to src/ (`mesh/constrained.rs`,
    /// `lib.rs`) and text. main.rs, the binary's root, is no module of the library: its `cli`
    /// files are read as a top-level module of their own.
    fn new(files: impl IntoIterator<Item = (String, String)>) -> Crate {
        let mut modules = Vec::new();
        for (file, text) in files {
            let rel = Path::new(&file).with_extension("");
            let mut path: Vec<String> =
                rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
            let is_dir = path.last().is_some_and(|p| p == "mod");
            if is_dir || path == ["lib"] {
                path.pop();
            }
            if path == ["main"] {
                continue;
            }
            modules.push(Module { path, is_dir, file, code: without_tests(&text) });
        }
        // Files that a `#[cfg(test)] mod x;` declares, and everything under them, are tests.
        let test_files: Vec<Vec<String>> = modules
            .iter()
            .flat_map(|m| {
                m.code.test_files.iter().map(|t| [m.path.clone(), vec![t.clone()]].concat())
            })
            .collect();
        modules.retain(|m| !test_files.iter().any(|t| m.path.starts_with(t)));
        let parents: BTreeSet<Vec<String>> =
            modules.iter().filter_map(|m| Some(m.path.split_last()?.1.to_vec())).collect();
        for m in modules.iter_mut().filter(|m| !m.path.is_empty()) {
            m.is_dir |= parents.contains(&m.path);
        }
        modules.sort_by(|a, b| a.file.cmp(&b.file));
        let by_path = modules.iter().enumerate().map(|(k, m)| (m.path.clone(), k)).collect();
        let mut krate = Crate { modules, by_path, imports: BTreeMap::new() };
        for m in &krate.modules {
            let children = m.children();
            let imports = imports_in(&m.code.text)
                .into_iter()
                .filter(|(local, path)| {
                    local != "*"
                        && path
                            .first()
                            .is_some_and(|s| Self::starts(&children).contains(&s.as_str()))
                })
                .filter_map(|(local, path)| Some((local, m.absolute(0, &path, &[])?)))
                .collect();
            krate.imports.insert(m.path.clone(), imports);
        }
        krate
    }

    /// The names a path of a file with these child modules can start with and stay in the crate.
    fn starts<'a>(children: &[&'a str]) -> Vec<&'a str> {
        [&["crate", "$crate", "super", "self"][..], children].concat()
    }

    /// The node that a crate path names: the file that defines it (`operator/stored` for
    /// `operator::Precision`, which operator/mod.rs re-exports from stored.rs), `operator/mod`
    /// for what operator/mod.rs defines itself; the path itself where no file of the crate holds
    /// it.
    fn node_of(&self, path: &[String]) -> Vec<String> {
        let mut path = path.to_vec();
        // Re-exports of re-exports: a few steps at most (a bound against `use` loops).
        for _ in 0..8 {
            let Some(k) = (1..=path.len()).rev().find(|k| self.by_path.contains_key(&path[..*k]))
            else {
                // Only the crate root holds it, or nothing: lib.rs's re-exports, or the path.
                match path.first().and_then(|item| self.imports.get(&Vec::new())?.get(item)) {
                    Some(target) => {
                        path = [target.clone(), path[1..].to_vec()].concat();
                        continue;
                    }
                    None => return path,
                }
            };
            let imported = path.get(k).and_then(|item| self.imports.get(&path[..k])?.get(item));
            match imported {
                Some(target) => path = [target.clone(), path[k + 1..].to_vec()].concat(),
                None => return self.modules[self.by_path[&path[..k]]].node(),
            }
        }
        path
    }

    /// The module graph: an edge between two modules of one parent (two top-level modules, two
    /// files of one directory, or a directory's mod.rs and one of its files) wherever a file
    /// inside the first names the second, with the first place it does.
    fn graph(&self) -> Graph {
        let mut graph = Graph::new();
        for m in self.modules.iter().filter(|m| !m.path.is_empty()) {
            let from = m.node();
            let children = m.children();
            let inline = m.inline_modules();
            let line = |offset: usize| m.code.text[..offset].matches('\n').count() + 1;
            for (offset, path) in paths_in(&m.code.text, &Self::starts(&children)) {
                let Some(target) = m.absolute(offset, &path, &inline) else { continue };
                let to = self.node_of(&target);
                // The first module where the two paths part: siblings under their common parent.
                let common = from.iter().zip(&to).take_while(|(a, b)| a == b).count();
                if common < from.len() && common < to.len() && !to[common].is_empty() {
                    let key = |p: &[String]| p[..=common].join("/");
                    let site = format!("{}:{}", m.file, line(offset));
                    graph.entry(key(&from)).or_default().entry(key(&to)).or_insert(site);
                }
            }
        }
        graph
    }
}

/// The Rust files under `dir`, by path relative to it, and their text, in a stable order.
pub fn read_rust_files(dir: &Path) -> Vec<(String, String)> {
    fn collect(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                collect(&path, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path);
            }
        }
    }
    let mut files = Vec::new();
    collect(dir, &mut files);
    files.sort();
    files
        .into_iter()
        .map(|file| {
            let rel = file.strip_prefix(dir).unwrap().to_string_lossy().replace('\\', "/");
            (rel, std::fs::read_to_string(&file).unwrap())
        })
        .collect()
}

pub fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The module graph of the crate under `src`.
pub fn module_graph(src: &Path) -> Graph {
    Crate::new(read_rust_files(src)).graph()
}

/// The graph of test cases: files by path under src/ and their text.
pub fn graph_of(files: &[(&str, &str)]) -> Graph {
    Crate::new(files.iter().map(|(path, text)| (path.to_string(), text.to_string()))).graph()
}

// ---------------------------------------------------------------------------------------------
// Cycles.

/// A cycle of the graph, if there is one (depth-first search with colours).
pub fn find_cycle(graph: &Graph) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        graph: &Graph,
        state: &mut BTreeMap<String, bool>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(node.to_string(), false);
        stack.push(node.to_string());
        for next in graph.get(node).into_iter().flat_map(|targets| targets.keys()) {
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

/// The groups of modules that reach one another (strongly connected components of more than
/// one module): every cycle lies in one of them.
pub fn cyclic_groups(graph: &Graph) -> BTreeSet<BTreeSet<String>> {
    let reach = |from: &str, reverse: bool| {
        let mut seen = BTreeSet::from([from.to_string()]);
        let mut todo = vec![from.to_string()];
        while let Some(node) = todo.pop() {
            let next: Vec<&String> = if reverse {
                graph.iter().filter(|(_, t)| t.contains_key(&node)).map(|(f, _)| f).collect()
            } else {
                graph.get(&node).into_iter().flat_map(|t| t.keys()).collect()
            };
            for n in next {
                if seen.insert(n.clone()) {
                    todo.push(n.clone());
                }
            }
        }
        seen
    };
    let nodes: BTreeSet<&String> = graph
        .iter()
        .flat_map(|(from, targets)| std::iter::once(from).chain(targets.keys()))
        .collect();
    nodes
        .into_iter()
        .map(|node| &reach(node, false) & &reach(node, true))
        .filter(|group| group.len() > 1)
        .collect()
}

/// A cycle through `group`, with where each step is made (`a -> b (a.rs:3)`), for a failure.
pub fn describe(graph: &Graph, group: &BTreeSet<String>) -> String {
    let within: Graph = graph
        .iter()
        .filter(|(from, _)| group.contains(*from))
        .map(|(from, targets)| {
            let kept = targets.iter().filter(|(to, _)| group.contains(*to));
            (from.clone(), kept.map(|(to, site)| (to.clone(), site.clone())).collect())
        })
        .collect();
    let cycle = find_cycle(&within).expect("a group that reaches itself has a cycle");
    let steps: Vec<String> = cycle
        .windows(2)
        .map(|w| format!("{} -> {} ({})", w[0], w[1], graph[&w[0]][&w[1]]))
        .collect();
    format!("{{{}}}: {}", group.iter().cloned().collect::<Vec<_>>().join(", "), steps.join(", "))
}
