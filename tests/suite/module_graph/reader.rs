//! Reading a source file as a build without `cfg(test)` compiles it: comments and literals
//! blanked, test-only items left out, and the paths and imports that the code names.

use std::ops::Range;

// ---------------------------------------------------------------------------------------------
// Reading a file: what a build compiles, as code.

pub fn is_ident(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

/// Turns `text[range]` into spaces, keeping its newlines (and so every line number and offset).
pub fn blank(text: &mut [u8], range: Range<usize>) {
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
pub fn code_only(text: &str) -> String {
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
pub fn after_close(b: &[u8], open: usize) -> usize {
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

pub fn skip_space(b: &[u8], mut i: usize) -> usize {
    while i < b.len() && b[i].is_ascii_whitespace() {
        i += 1;
    }
    i
}

/// An item of code (as `code_only` leaves it), such as the one an attribute stands on.
pub struct Item<'a> {
    /// Its leading words past further attributes and without `pub` (`mod tests`, `fn f`,
    /// `impl`, `use crate`).
    pub words: Vec<&'a str>,
    /// Where it ends: after its closing brace, `;` or `,`, or at the brace that closes the
    /// block around it.
    pub end: usize,
}

pub fn item_at(code: &str, at: usize) -> Item<'_> {
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
pub struct Code {
    /// The file as code (`code_only`) with every `#[cfg(test)]` item blanked: an inline test
    /// module to its closing brace, a single test-only fn, impl, use or field; offsets and lines
    /// are the file's.
    pub text: String,
    /// Modules in files of their own that the file declares under `#[cfg(test)]` (`mod tests;`):
    /// those files are test code as a whole.
    pub test_files: Vec<String>,
}

/// The file `text` without its test code, by the scope of each `#[cfg(test)]`: the code after
/// a test module, wherever the module stands, is read.
pub fn without_tests(text: &str) -> Code {
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
pub fn use_tree(b: &[u8], i: &mut usize) -> Vec<(Vec<String>, String)> {
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
pub fn paths_in(code: &str, starts: &[&str]) -> Vec<(usize, Vec<String>)> {
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
pub fn imports_in(code: &str) -> Vec<(String, Vec<String>)> {
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
