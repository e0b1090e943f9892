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

use std::collections::{BTreeMap, BTreeSet};
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Edges between modules: module (`mesh`, `mesh/constrained`, or `mesh/mod` for what the file
/// mesh/mod.rs itself holds) to the modules it names, each with the first place it names it
/// (`mesh/constrained.rs:12`) so that a failure can point there.
type Graph = BTreeMap<String, BTreeMap<String, String>>;

// ---------------------------------------------------------------------------------------------
// Reading a file: what a build compiles, as code.

fn is_ident(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

/// Turns `text[range]` into spaces, keeping its newlines (and so every line number and offset).
fn blank(text: &mut [u8], range: Range<usize>) {
    for c in &mut text[range] {
        if *c != b'\n' {
            *c = b' ';
        }
    }
}

/// `text` with its comments and literals (strings, raw and byte strings, chars) blanked: what
/// is left is code, at the same offsets, in which braces and paths can be counted without
/// counting those a string or a comment holds. Multi-byte characters only occur inside what is
/// blanked (byte by byte, so the result stays UTF-8) or in identifiers, which no rule here reads.
fn code_only(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = b.to_vec();
    // The end of a string whose contents start at `i` (escapes skipped).
    let string_end = |mut i: usize| {
        while i < b.len() && b[i] != b'"' {
            i += if b[i] == b'\\' { 2 } else { 1 };
        }
        (i + 1).min(b.len())
    };
    let mut i = 0;
    while i < b.len() {
        let at_token = i == 0 || !is_ident(b[i - 1]);
        let next = b.get(i + 1).copied();
        let end = match b[i] {
            b'/' if next == Some(b'/') => {
                Some(b[i..].iter().position(|&c| c == b'\n').map_or(b.len(), |k| i + k))
            }
            b'/' if next == Some(b'*') => {
                // Block comments nest.
                let (mut j, mut depth) = (i + 2, 1);
                while j < b.len() && depth > 0 {
                    if b[j..].starts_with(b"/*") {
                        (depth, j) = (depth + 1, j + 2);
                    } else if b[j..].starts_with(b"*/") {
                        (depth, j) = (depth - 1, j + 2);
                    } else {
                        j += 1;
                    }
                }
                Some(j)
            }
            b'"' => Some(string_end(i + 1)),
            b'b' if at_token && next == Some(b'"') => Some(string_end(i + 2)),
            b'b' if at_token && next == Some(b'\'') => char_end(text, i + 1),
            b'r' | b'b' if at_token => raw_string_end(b, i),
            // None: a lifetime or a label, which is code.
            b'\'' => char_end(text, i),
            _ => None,
        };
        match end {
            Some(end) => {
                blank(&mut out, i..end);
                i = end;
            }
            None => i += 1,
        }
    }
    String::from_utf8(out).expect("only whole characters are blanked")
}

/// The end of a raw string (`r"…"`, `r#"…"#`, `br"…"`) that starts at `i`, if one does.
fn raw_string_end(b: &[u8], i: usize) -> Option<usize> {
    let mut j = i + usize::from(b[i] == b'b');
    if b.get(j) != Some(&b'r') {
        return None;
    }
    j += 1;
    let hashes = b[j..].iter().take_while(|&&c| c == b'#').count();
    j += hashes;
    if b.get(j) != Some(&b'"') {
        return None;
    }
    let close: Vec<u8> = std::iter::once(b'"').chain(std::iter::repeat_n(b'#', hashes)).collect();
    let k = b[j + 1..].windows(close.len()).position(|w| w == close.as_slice());
    Some(k.map_or(b.len(), |k| j + 1 + k + close.len()))
}

/// The end of a char literal whose quote is at `q`, or None where the quote opens a lifetime
/// (`'a`) or a label.
fn char_end(text: &str, q: usize) -> Option<usize> {
    let b = text.as_bytes();
    if b.get(q + 1) == Some(&b'\\') {
        // An escape: `'\n'`, `'\''`, `'\u{7f}'`; the closing quote comes after its first char.
        let k = b.get(q + 3..)?.iter().position(|&c| c == b'\'')?;
        return Some(q + 3 + k + 1);
    }
    let c = text.get(q + 1..)?.chars().next()?;
    (b.get(q + 1 + c.len_utf8()) == Some(&b'\'')).then_some(q + 2 + c.len_utf8())
}

/// Where `b[open]`'s bracket closes (the index after it), brackets of all kinds counted.
fn after_close(b: &[u8], open: usize) -> usize {
    let mut depth = 0i64;
    for (k, &c) in b.iter().enumerate().skip(open) {
        match c {
            b'(' | b'[' | b'{' => depth += 1,
            b')' | b']' | b'}' => {
                depth -= 1;
                if depth == 0 {
                    return k + 1;
                }
            }
            _ => {}
        }
    }
    b.len()
}

fn skip_space(b: &[u8], mut i: usize) -> usize {
    while i < b.len() && b[i].is_ascii_whitespace() {
        i += 1;
    }
    i
}

/// An item of code (as `code_only` leaves it), such as the one an attribute stands on.
struct Item<'a> {
    /// Its leading words past further attributes and without `pub` (`mod tests`, `fn f`,
    /// `impl`, `use crate`).
    words: Vec<&'a str>,
    /// Where it ends: after its closing brace, `;` or `,`, or at the brace that closes the
    /// block around it.
    end: usize,
}

fn item_at(code: &str, at: usize) -> Item<'_> {
    let b = code.as_bytes();
    let mut i = skip_space(b, at);
    while b[i..].starts_with(b"#[") {
        i = skip_space(b, after_close(b, i + 1));
    }
    let start = i;
    let mut words = Vec::new();
    loop {
        let j = skip_space(b, i);
        let word_end = j + b[j..].iter().take_while(|&&c| is_ident(c)).count();
        if word_end == j {
            break;
        }
        words.push(&code[j..word_end]);
        i = word_end;
        // `pub(crate)`, `pub(in path)`
        let k = skip_space(b, i);
        if words.last() == Some(&"pub") && b.get(k) == Some(&b'(') {
            i = after_close(b, k);
        }
    }
    words.retain(|w| *w != "pub");
    // How far an item reaches: items with a body (`fn`, `mod`, `impl`, ...) end at the brace
    // that closes it or at a `;`; `use`, `const`, `static`, `let` and `type` at the `;` (braces
    // inside them, `use a::{b, c};`, `const S: T = T { .. };`, do not end them); anything else
    // (a field, a variant, a match arm, a statement) at a `,` or `;` or where its block closes.
    // Generic arguments are not counted as brackets, so a test-only field of type `Map<A, B>`
    // ends at the first comma: reading too much of the rest as code errs on the safe side.
    let first = words.first().copied().unwrap_or("");
    let second = words.get(1).copied().unwrap_or("");
    let to_semicolon = matches!(first, "use" | "static" | "let" | "type")
        || (first == "const" && !matches!(second, "fn" | "unsafe" | "async" | "extern"));
    let item = to_semicolon
        || matches!(
            first,
            "fn" | "impl"
                | "trait"
                | "struct"
                | "enum"
                | "union"
                | "mod"
                | "macro_rules"
                | "extern"
                | "unsafe"
                | "async"
                | "const"
        );
    let mut depth = 0i64;
    for (k, &c) in b.iter().enumerate().skip(start) {
        match c {
            b'(' | b'[' | b'{' => depth += 1,
            b')' | b']' | b'}' => {
                depth -= 1;
                if depth < 0 {
                    // The enclosing block closes: the item (a last field or arm) ended before.
                    return Item { words, end: k };
                }
                if depth == 0 && c == b'}' && !to_semicolon {
                    return Item { words, end: k + 1 };
                }
            }
            b';' if depth == 0 => return Item { words, end: k + 1 },
            b',' if depth == 0 && !item => return Item { words, end: k + 1 },
            _ => {}
        }
    }
    Item { words, end: b.len() }
}

/// What a build without `cfg(test)` compiles of a source file.
struct Code {
    /// The file as code (`code_only`) with every `#[cfg(test)]` item blanked: an inline test
    /// module to its closing brace, a single test-only fn, impl, use or field; offsets and lines
    /// are the file's.
    text: String,
    /// Modules in files of their own that the file declares under `#[cfg(test)]` (`mod tests;`):
    /// those files are test code as a whole.
    test_files: Vec<String>,
}

/// The file `text` without its test code, by the scope of each `#[cfg(test)]`: the code after
/// a test module, wherever the module stands, is read.
fn without_tests(text: &str) -> Code {
    const TEST: &str = "#[cfg(test)]";
    let mut code = code_only(text);
    let mut test_files = Vec::new();
    let mut from = 0;
    while let Some(k) = code[from..].find(TEST).map(|k| from + k) {
        let item = item_at(&code, k + TEST.len());
        if let ["mod", name] = item.words[..] {
            if code[..item.end].ends_with(';') {
                test_files.push(name.to_string());
            }
        }
        let end = item.end;
        let mut bytes = std::mem::take(&mut code).into_bytes();
        blank(&mut bytes, k..end);
        code = String::from_utf8(bytes).expect("blanking keeps UTF-8");
        from = end;
    }
    Code { text: code, test_files }
}

// ---------------------------------------------------------------------------------------------
// Paths in code.

/// The paths of a use tree or path that starts at `b[*i]` (`a::{b, c::{self, d as e}}`), each
/// with the name it goes by where it is imported (`e` for `c::d as e`; `*` for a glob).
fn use_tree(b: &[u8], i: &mut usize) -> Vec<(Vec<String>, String)> {
    *i = skip_space(b, *i);
    match b.get(*i) {
        Some(b'{') => {
            *i += 1;
            let mut all = Vec::new();
            loop {
                *i = skip_space(b, *i);
                match b.get(*i) {
                    None => break,
                    Some(b'}') => {
                        *i += 1;
                        break;
                    }
                    Some(b',') => *i += 1,
                    Some(_) => {
                        let before = *i;
                        all.extend(use_tree(b, i));
                        if *i == before {
                            *i += 1; // not a path: step over it
                        }
                    }
                }
            }
            return all;
        }
        Some(b'*') => {
            *i += 1;
            return vec![(Vec::new(), "*".to_string())];
        }
        _ => {}
    }
    let start = *i;
    while *i < b.len() && (is_ident(b[*i]) || b[*i] == b'$') {
        *i += 1;
    }
    let name = String::from_utf8_lossy(&b[start..*i]).into_owned();
    if name.is_empty() {
        return Vec::new();
    }
    // `a::b` goes on; `a::<T>` (turbofish) ends the path at a.
    if b[*i..].starts_with(b"::") && b.get(*i + 2) != Some(&b'<') {
        *i += 2;
        return use_tree(b, i)
            .into_iter()
            .map(|(mut path, local)| {
                path.insert(0, name.clone());
                (path, if local == "self" { name.clone() } else { local })
            })
            .collect();
    }
    if name == "self" {
        return vec![(Vec::new(), name)]; // `a::{self, b}`: a itself
    }
    let j = skip_space(b, *i);
    if b[j..].starts_with(b"as") && b.get(j + 2).is_some_and(|c| c.is_ascii_whitespace()) {
        let k = skip_space(b, j + 2);
        let alias = b[k..].iter().take_while(|&&c| is_ident(c)).count();
        if alias > 0 {
            *i = k + alias;
            let alias = String::from_utf8_lossy(&b[k..k + alias]).into_owned();
            return vec![(vec![name], alias)];
        }
    }
    vec![(vec![name.clone()], name)]
}

/// Every path in `code` that starts with one of `starts` (`crate`, `super`, a child module),
/// with the offset where it starts; braced groups give one path per member. A name after `::`
/// or `.` continues another path or names a field, and is no start.
fn paths_in(code: &str, starts: &[&str]) -> Vec<(usize, Vec<String>)> {
    let b = code.as_bytes();
    let mut found = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if !(is_ident(b[i]) || b[i] == b'$') || (i > 0 && is_ident(b[i - 1])) {
            i += 1;
            continue;
        }
        let end = i + 1 + b[i + 1..].iter().take_while(|&&c| is_ident(c)).count();
        let after_path = i > 0 && matches!(b[i - 1], b':' | b'.');
        if !after_path && starts.contains(&&code[i..end]) && b[end..].starts_with(b"::") {
            let mut j = i;
            found.extend(use_tree(b, &mut j).into_iter().map(|(path, _)| (i, path)));
            // Past the whole tree: a member of a group (`crate::{stored::X}`) is no start.
            i = j.max(end);
            continue;
        }
        i = end;
    }
    found
}

/// The `use` declarations of `code`: each imported name and the path it stands for.
fn imports_in(code: &str) -> Vec<(String, Vec<String>)> {
    let b = code.as_bytes();
    let mut found = Vec::new();
    for (k, _) in code.match_indices("use") {
        let token = (k == 0 || !is_ident(b[k - 1])) && b.get(k + 3).is_some_and(|c| *c == b' ');
        if token {
            let mut j = k + 3;
            for (path, local) in use_tree(b, &mut j) {
                found.push((local, path));
            }
        }
    }
    found
}

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
fn read_rust_files(dir: &Path) -> Vec<(String, String)> {
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

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The module graph of the crate under `src`.
fn module_graph(src: &Path) -> Graph {
    Crate::new(read_rust_files(src)).graph()
}

/// The graph of test cases: files by path under src/ and their text.
fn graph_of(files: &[(&str, &str)]) -> Graph {
    Crate::new(files.iter().map(|(path, text)| (path.to_string(), text.to_string()))).graph()
}

// ---------------------------------------------------------------------------------------------
// Cycles.

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
fn cyclic_groups(graph: &Graph) -> BTreeSet<BTreeSet<String>> {
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
fn describe(graph: &Graph, group: &BTreeSet<String>) -> String {
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
const ALLOWED_CYCLES: &[&[&str]] = &[
    &["cli/mod", "cli/solve"],
    &["distributed/mod", "distributed/mpi"],
    &["kernels/by_rule", "kernels/mod"],
    &["mesh/graded", "mesh/mod"],
    &["scene/builtin", "scene/city", "scene/file", "scene/mod"],
    &["scene/file/builder", "scene/file/import", "scene/file/mod", "scene/file/schema"],
    &["solve/lu", "solve/mod", "solve/products"],
    // Between files: gpu/assembly.rs names resident.rs's `DeviceTraffic`, resident.rs
    // assembly.rs's `GpuAssembler`.
    &["gpu/assembly", "gpu/resident"],
    // Between files: operator.rs names report.rs's `peak_rss_bytes` and saved.rs, which names
    // operator.rs's `TimedAssembly`, as report.rs names its `DeviceTransfers`.
    &["pipeline/operator", "pipeline/report", "pipeline/saved"],
    // Between files: occluders.rs builds solids.rs's `Solid`s, solids.rs names `Occluder`.
    &["visibility/occluders", "visibility/solids"],
];

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

/// The layers of src/, lowest first: a module names only modules of lower layers
/// (ARCHITECTURE.md's table, which a test compares with this).
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

/// The command line's module: the binary's alone.
const CLI: &str = "cli";

fn layer_of(module: &str) -> Option<usize> {
    LAYERS.iter().position(|layer| layer.contains(&module))
}

/// The modules that a crate root declares with `prefix` (`pub mod `), in order.
fn declared(root: &str, prefix: &str) -> Vec<String> {
    let text = std::fs::read_to_string(src().join(root)).unwrap();
    let names = text.lines().filter_map(|l| l.strip_prefix(prefix)?.strip_suffix(';'));
    names.map(str::to_string).collect()
}

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

/// What the files (path and text) of a crate that uses the library as `radiosity` name right
/// after `radiosity::` (a module, or a re-export of the root), and where (`lib.rs:19`).
fn library_uses(files: &[(String, String)]) -> Vec<(String, String)> {
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
