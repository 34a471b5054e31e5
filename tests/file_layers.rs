//! Layers inside each crate, checked from the source files themselves (std only, no build):
//!
//! * no circle of imports between the files of a crate: a file's `use` and inline paths
//!   (`crate::…`, `super::…`, `self::…`) are resolved to the file that defines what they name,
//!   through the `pub use` re-exports of `lib.rs` and `mod.rs` files (a re-export is a crate's
//!   face, not a dependency of its own); test modules (`#[cfg(test)]`) are left out;
//! * the mission library's files stay under [`MAX_MISSION_FILE_LINES`] lines, and no function
//!   of the mission and tactile crates is longer than [`MAX_FUNCTION_LINES`].
//!
//! `cargo test --test file_layers`, or without cargo: `rustc --edition 2021 --test
//! tests/file_layers.rs -o /tmp/file_layers && /tmp/file_layers` from the workspace root.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Longest file of `crates/mission/src`, lines.
const MAX_MISSION_FILE_LINES: usize = 500;
/// Longest function of the mission and tactile crates, lines (its signature to its closing
/// brace).
const MAX_FUNCTION_LINES: usize = 100;

/// Circles that remain, by crate and the files in them (sorted), with why. None today.
const KNOWN_CIRCLES: &[(&str, &[&str], &str)] = &[];

/// The workspace's root (this file's package is the root package).
fn root() -> PathBuf {
    option_env!("CARGO_MANIFEST_DIR").map_or_else(|| PathBuf::from("."), PathBuf::from)
}

/// Every `.rs` file under `dir`, sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// The crates' source folders: `crates/*/src` and `firmware/src`.
fn crate_sources() -> Vec<(String, PathBuf)> {
    let mut out = Vec::new();
    let crates = root().join("crates");
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(&crates)
        .expect("crates/")
        .flatten()
        .map(|e| e.path())
        .collect();
    dirs.push(root().join("firmware"));
    dirs.sort();
    for d in dirs {
        let src = d.join("src");
        if src.is_dir() {
            let name = d
                .file_name()
                .expect("a crate folder")
                .to_string_lossy()
                .into_owned();
            out.push((name, src));
        }
    }
    out
}

/// The module path of `file` inside a crate whose sources are in `src` (`lib.rs`, `main.rs`
/// and `mod.rs` name their folder's module; `bin/x.rs` is a crate of its own, `[bin:x]`).
fn module_of(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).expect("a file of the crate");
    let mut parts: Vec<String> = rel
        .iter()
        .map(|s| s.to_string_lossy().into_owned())
        .collect();
    let last = parts.pop().expect("a file name");
    let stem = last.trim_end_matches(".rs").to_string();
    if parts.first().is_some_and(|p| p == "bin") {
        return vec![format!("[bin:{}]", stem)];
    }
    if !matches!(stem.as_str(), "lib" | "main" | "mod") {
        parts.push(stem);
    }
    parts
}

/// `text` without comments, string and char literals (their contents blanked), and without
/// `#[cfg(test)]` items: what its code names.
fn code_of(text: &str) -> String {
    let b: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        let next = b.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < b.len() && b[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            i += 2;
            while i + 1 < b.len() && !(b[i] == '*' && b[i + 1] == '/') {
                i += 1;
            }
            i += 2;
        } else if c == '"' || (c == 'r' && (next == Some('"') || next == Some('#'))) {
            // A string (raw ones with their hashes).
            let mut hashes = 0;
            let raw = c == 'r';
            if raw {
                i += 1;
                while i < b.len() && b[i] == '#' {
                    hashes += 1;
                    i += 1;
                }
                if i >= b.len() || b[i] != '"' {
                    out.push('r');
                    continue;
                }
            }
            i += 1;
            while i < b.len() {
                if !raw && b[i] == '\\' {
                    i += 2;
                    continue;
                }
                if b[i] == '"' && (0..hashes).all(|k| b.get(i + 1 + k) == Some(&'#')) {
                    i += 1 + hashes;
                    break;
                }
                if b[i] == '\n' {
                    out.push('\n');
                }
                i += 1;
            }
            out.push_str("\"\"");
        } else if c == '\'' && next.is_some() && b.get(i + 2) == Some(&'\'') {
            out.push_str("' '");
            i += 3;
        } else if c == '\'' && next == Some('\\') {
            i += 2;
            while i < b.len() && b[i] != '\'' {
                i += 1;
            }
            i += 1;
            out.push_str("' '");
        } else {
            out.push(c);
            i += 1;
        }
    }
    strip_test_items(&out)
}

/// Where the first `#[cfg(…)]` that holds `test` (`#[cfg(test)]`, `#[cfg(all(test, …))]`)
/// stands in `code`.
fn test_attribute(code: &str) -> Option<usize> {
    let mut from = 0;
    while let Some(k) = code[from..].find("#[cfg(") {
        let at = from + k;
        let end = code[at..].find(']').map_or(code.len(), |e| at + e);
        let attr = &code[at..end];
        if attr
            .split(|c: char| !c.is_alphanumeric() && c != '_')
            .any(|w| w == "test")
        {
            return Some(at);
        }
        from = at + 6;
    }
    None
}

/// `code` without the items that follow a `#[cfg(test)]` (to the end of their braces).
fn strip_test_items(code: &str) -> String {
    let mut out = String::new();
    let mut rest = code;
    while let Some(at) = test_attribute(rest) {
        out.push_str(&rest[..at]);
        let after = &rest[at..];
        // The item ends at the `;` or the `}` closing its first `{`.
        let mut depth = 0i32;
        let mut end = after.len();
        for (k, ch) in after.char_indices() {
            match ch {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        end = k + 1;
                        break;
                    }
                }
                ';' if depth == 0 => {
                    end = k + 1;
                    break;
                }
                _ => {}
            }
        }
        rest = &after[end..];
    }
    out.push_str(rest);
    out
}

/// The `use` declarations of `code`: (public, each path they import, braces expanded).
fn uses(code: &str) -> Vec<(bool, Vec<String>)> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(at) = find_keyword(rest, "use") {
        let before = rest[..at].trim_end();
        let public = before.ends_with("pub") || before.ends_with(')') && before.contains("pub(");
        let after = &rest[at + 3..];
        let end = after.find(';').unwrap_or(after.len());
        let tree: String = after[..end]
            .chars()
            .filter(|c| !c.is_whitespace())
            .collect();
        let mut paths = Vec::new();
        expand(&tree, "", &mut paths);
        out.push((public, paths));
        rest = &after[end.min(after.len())..];
    }
    out
}

/// Where the keyword `kw` stands as a word in `s`.
fn find_keyword(s: &str, kw: &str) -> Option<usize> {
    let bytes = s.as_bytes();
    let mut from = 0;
    while let Some(k) = s[from..].find(kw) {
        let at = from + k;
        let before_ok =
            at == 0 || !(bytes[at - 1].is_ascii_alphanumeric() || bytes[at - 1] == b'_');
        let after = at + kw.len();
        let after_ok = after < bytes.len() && bytes[after].is_ascii_whitespace();
        if before_ok && after_ok {
            return Some(at);
        }
        from = after;
    }
    None
}

/// A use tree (`a::{b, c::{d, e}}`, whitespace removed) as whole paths, each after `prefix`.
fn expand(tree: &str, prefix: &str, out: &mut Vec<String>) {
    match tree.find('{') {
        None => out.push(format!("{prefix}{tree}")),
        Some(open) => {
            let head = &tree[..open];
            let inner = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
            let mut depth = 0;
            let mut start = 0;
            for (k, ch) in inner.char_indices() {
                match ch {
                    '{' => depth += 1,
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        if k > start {
                            expand(&inner[start..k], &format!("{prefix}{head}"), out);
                        }
                        start = k + 1;
                    }
                    _ => {}
                }
            }
            if inner.len() > start {
                expand(&inner[start..], &format!("{prefix}{head}"), out);
            }
        }
    }
}

/// The paths that start with `crate::`, `super::` or `self::` anywhere in `code` (outside `use`
/// declarations too: `crate::inspect::report::Evidence { … }`).
fn inline_paths(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let chars: Vec<char> = code.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        let word_start = i == 0
            || !(chars[i - 1].is_alphanumeric() || chars[i - 1] == '_' || chars[i - 1] == ':');
        if word_start {
            for head in ["crate::", "super::", "self::"] {
                let h: Vec<char> = head.chars().collect();
                if chars[i..].starts_with(&h) {
                    let mut j = i;
                    while j < chars.len()
                        && (chars[j].is_alphanumeric() || chars[j] == '_' || chars[j] == ':')
                    {
                        j += 1;
                    }
                    let path: String = chars[i..j].iter().collect();
                    out.push(path.trim_end_matches(':').to_string());
                    i = j;
                    break;
                }
            }
        }
        i += 1;
    }
    out
}

/// One crate's files: module path → (file, its code).
struct Crate {
    files: BTreeMap<Vec<String>, (PathBuf, String)>,
}

impl Crate {
    fn load(src: &Path) -> Crate {
        let mut files = BTreeMap::new();
        for f in rust_files(src) {
            let text = std::fs::read_to_string(&f).expect("a readable source file");
            files.insert(module_of(src, &f), (f, code_of(&text)));
        }
        Crate { files }
    }

    /// The module path `path` names, from the module `at` (`crate::`, `super::`, `self::` or a
    /// child module's name), as absolute segments; `None` for another crate's path.
    fn absolute(&self, at: &[String], path: &str) -> Option<Vec<String>> {
        let segs: Vec<&str> = path.split("::").filter(|s| !s.is_empty()).collect();
        let mut base: Vec<String>;
        let mut rest = &segs[..];
        match segs.first() {
            Some(&"crate") => {
                base = Vec::new();
                rest = &segs[1..];
            }
            Some(&"super" | &"self") => {
                base = at.to_vec();
                while let Some(&s) = rest.first() {
                    match s {
                        "super" => {
                            base.pop();
                        }
                        "self" => {}
                        _ => break,
                    }
                    rest = &rest[1..];
                }
            }
            Some(first) => {
                // A child module of this one, named bare.
                let mut child = at.to_vec();
                child.push(first.to_string());
                if self.files.contains_key(&child) {
                    base = at.to_vec();
                } else {
                    return None;
                }
            }
            None => return None,
        }
        base.extend(rest.iter().map(std::string::ToString::to_string));
        Some(base)
    }

    /// The file that defines what the absolute `path` names: its longest prefix that is a file,
    /// followed through that file's `pub use` re-exports when it is a `lib.rs` or `mod.rs`
    /// (`depth` bounds the chain).
    fn defining_file(&self, path: &[String], depth: usize) -> Option<Vec<String>> {
        let mut k = path.len();
        while !self.files.contains_key(&path[..k]) {
            if k == 0 {
                return None;
            }
            k -= 1;
        }
        let module = path[..k].to_vec();
        let item = path.get(k);
        let (file, code) = &self.files[&module];
        let hub = file
            .file_name()
            .is_some_and(|n| n == "mod.rs" || n == "lib.rs" || n == "main.rs");
        if let (true, Some(item), true) = (hub, item, depth < 8) {
            for (public, paths) in uses(code) {
                if !public {
                    continue;
                }
                for p in paths {
                    let (target, alias) = match p.split_once("as") {
                        Some((t, a)) if p.contains("::") && !a.contains("::") => {
                            (t.to_string(), a.to_string())
                        }
                        _ => (p.clone(), p.rsplit("::").next().unwrap_or("").to_string()),
                    };
                    if &alias == item {
                        if let Some(abs) = self.absolute(&module, &target) {
                            return self.defining_file(&abs, depth + 1);
                        }
                    }
                }
            }
        }
        Some(module)
    }

    /// The import graph: file → the files it imports from (re-exports left out).
    fn graph(&self) -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
        let mut g: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
        for (module, (_, code)) in &self.files {
            let mut named: Vec<String> = Vec::new();
            for (public, paths) in uses(code) {
                if !public {
                    named.extend(paths);
                }
            }
            // Inline paths, outside the `pub use` lines (already left out above).
            let without_pub_uses = remove_pub_uses(code);
            named.extend(inline_paths(&without_pub_uses));
            let edges = g.entry(module.clone()).or_default();
            for p in named {
                let Some(abs) = self.absolute(module, &p) else {
                    continue;
                };
                if let Some(file) = self.defining_file(&abs, 0) {
                    if &file != module {
                        edges.insert(file);
                    }
                }
            }
        }
        g
    }
}

/// `code` without its `pub use …;` declarations.
fn remove_pub_uses(code: &str) -> String {
    let mut out = String::new();
    let mut rest = code;
    while let Some(at) = find_keyword(rest, "use") {
        let before = rest[..at].trim_end();
        let public = before.ends_with("pub") || before.ends_with(')') && before.contains("pub(");
        let end = rest[at..].find(';').map_or(rest.len(), |e| at + e + 1);
        out.push_str(&rest[..at]);
        if !public {
            out.push_str(&rest[at..end]);
        }
        rest = &rest[end..];
    }
    out.push_str(rest);
    out
}

/// The strongly connected components of more than one file (Tarjan's algorithm).
fn circles(g: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>) -> Vec<Vec<Vec<String>>> {
    struct State<'a> {
        g: &'a BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
        index: BTreeMap<&'a Vec<String>, usize>,
        low: BTreeMap<&'a Vec<String>, usize>,
        stack: Vec<&'a Vec<String>>,
        on: BTreeSet<&'a Vec<String>>,
        next: usize,
        out: Vec<Vec<Vec<String>>>,
    }
    fn visit<'a>(s: &mut State<'a>, v: &'a Vec<String>) {
        s.index.insert(v, s.next);
        s.low.insert(v, s.next);
        s.next += 1;
        s.stack.push(v);
        s.on.insert(v);
        if let Some(ws) = s.g.get(v) {
            for w in ws {
                let Some((w, _)) = s.g.get_key_value(w) else {
                    continue;
                };
                if !s.index.contains_key(w) {
                    visit(s, w);
                    let lw = s.low[w];
                    let lv = s.low[v];
                    s.low.insert(v, lv.min(lw));
                } else if s.on.contains(w) {
                    let iw = s.index[w];
                    let lv = s.low[v];
                    s.low.insert(v, lv.min(iw));
                }
            }
        }
        if s.low[v] == s.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on.remove(w);
                comp.push(w.clone());
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                comp.sort();
                s.out.push(comp);
            }
        }
    }
    let mut s = State {
        g,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        next: 0,
        out: Vec::new(),
    };
    for v in g.keys() {
        if !s.index.contains_key(v) {
            visit(&mut s, v);
        }
    }
    s.out
}

/// A module path as a file-like name for messages (`inspect/steps/judge`, `lib`).
fn shown(m: &[String]) -> String {
    if m.is_empty() {
        "lib".into()
    } else {
        m.join("/")
    }
}

#[test]
fn no_crate_has_a_circle_of_imports_between_its_files() {
    let mut found = Vec::new();
    for (name, src) in crate_sources() {
        let c = Crate::load(&src);
        for comp in circles(&c.graph()) {
            let files: Vec<String> = comp.iter().map(|m| shown(m)).collect();
            let known = KNOWN_CIRCLES.iter().any(|(k, f, _)| {
                *k == name
                    && f.iter()
                        .map(std::string::ToString::to_string)
                        .collect::<Vec<_>>()
                        == files
            });
            if !known {
                found.push(format!("{name}: {}", files.join(" ↔ ")));
            }
        }
    }
    if let Ok(name) = std::env::var("FILE_LAYERS_SHOW") {
        for (n, src) in crate_sources().into_iter().filter(|(n, _)| *n == name) {
            for (from, to) in Crate::load(&src).graph() {
                let to: Vec<String> = to.iter().map(|m| shown(m)).collect();
                eprintln!("{n}: {} -> {}", shown(&from), to.join(", "));
            }
        }
    }
    assert!(
        found.is_empty(),
        "circles of imports:\n{}",
        found.join("\n")
    );
}

#[test]
fn the_checker_sees_a_circle_through_a_re_export_and_not_one_in_tests() {
    let mut c = Crate {
        files: BTreeMap::new(),
    };
    let put = |c: &mut Crate, m: &[&str], code: &str| {
        let hub = if m.is_empty() {
            "lib".to_string()
        } else {
            m.join("/")
        };
        c.files.insert(
            m.iter().map(std::string::ToString::to_string).collect(),
            (PathBuf::from(format!("{hub}.rs")), code_of(code)),
        );
    };
    put(&mut c, &[], "mod a;\nmod b;\npub use a::Alpha;\n");
    put(&mut c, &["a"], "use crate::b::beta;\npub struct Alpha;\n");
    put(&mut c, &["b"], "// use crate::a::Alpha;\nlet s = \"crate::a::x\";\npub fn beta() {}\n#[cfg(test)]\nmod tests { use crate::Alpha; }\n");
    assert!(circles(&c.graph()).is_empty(), "{:?}", c.graph());
    put(
        &mut c,
        &["b"],
        "pub fn beta() -> crate::Alpha { crate::Alpha }\n",
    );
    assert_eq!(circles(&c.graph()).len(), 1, "{:?}", c.graph());
    let mut tree = Vec::new();
    expand("super::{a::{B,C},d}", "", &mut tree);
    assert_eq!(tree, ["super::a::B", "super::a::C", "super::d"]);
}

/// The functions of `text` longer than `max` lines: (first line, name, lines).
fn long_functions(text: &str, max: usize) -> Vec<(usize, String, usize)> {
    // Test modules are left out.
    let code = &text[..test_attribute(text).unwrap_or(text.len())];
    let lines: Vec<&str> = code.lines().collect();
    let mut out = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        let t = l.trim_start();
        let indent = l.len() - t.len();
        let is_fn = (t.starts_with("fn ")
            || t.starts_with("pub fn ")
            || t.starts_with("pub(crate) fn ")
            || t.starts_with("pub(super) fn ")
            || t.starts_with("async fn ")
            || t.starts_with("pub async fn ")
            || t.starts_with("const fn ")
            || t.starts_with("pub const fn "))
            && !t.ends_with(';');
        if !is_fn {
            continue;
        }
        let close = " ".repeat(indent) + "}";
        if let Some(end) = (i + 1..lines.len()).find(|&j| lines[j] == close) {
            let n = end - i + 1;
            if n > max {
                let name = t[t.find("fn ").map_or(0, |k| k + 3)..]
                    .split(['(', '<'])
                    .next()
                    .unwrap_or(t)
                    .to_string();
                out.push((i + 1, name, n));
            }
        }
    }
    out
}

#[test]
fn the_mission_library_keeps_its_files_and_functions_short() {
    let mut found = Vec::new();
    for f in rust_files(&root().join("crates/mission/src")) {
        let n = std::fs::read_to_string(&f)
            .expect("a readable source file")
            .lines()
            .count();
        if n > MAX_MISSION_FILE_LINES {
            found.push(format!("{}: {n} lines", f.display()));
        }
    }
    for dir in ["crates/mission/src", "crates/tactile/src"] {
        for f in rust_files(&root().join(dir)) {
            let text = std::fs::read_to_string(&f).expect("a readable source file");
            for (line, name, n) in long_functions(&text, MAX_FUNCTION_LINES) {
                found.push(format!("{}:{line}: {name}: {n} lines", f.display()));
            }
        }
    }
    assert!(found.is_empty(), "too long:\n{}", found.join("\n"));
}

/// The `…` spans of `text` that name a file or folder of the mission library (`steps/x.rs`,
/// `rig/`, `mod.rs`).
fn named_paths(text: &str) -> BTreeSet<String> {
    text.split('`')
        .skip(1)
        .step_by(2)
        .filter(|s| s.ends_with(".rs") || s.ends_with('/'))
        .filter(|s| !s.contains(' ') && !s.starts_with("crates/") && !s.starts_with("tests/"))
        .map(str::to_string)
        .collect()
}

#[test]
fn the_architectures_mission_tables_name_every_file_of_the_mission_library_and_no_other() {
    let arch = std::fs::read_to_string(root().join("ARCHITECTURE.md")).expect("ARCHITECTURE.md");
    let section = arch
        .split("## A mission, step by step")
        .nth(1)
        .expect("ARCHITECTURE.md has the section \"A mission, step by step\"");
    let named = named_paths(section);
    let inspect = root().join("crates/mission/src/inspect");
    // Every name is a file or folder there.
    let missing: Vec<&String> = named
        .iter()
        .filter(|n| {
            let n = n.trim_end_matches('/');
            // The rig's files are named bare in its row.
            !(inspect.join(n).exists() || inspect.join("rig").join(n).exists())
        })
        .collect();
    assert!(missing.is_empty(), "named but not there: {missing:?}");
    // Every file of the report layer, the rig and the steps is named (a folder's own files
    // through the folder).
    let mut unnamed = Vec::new();
    for f in rust_files(&inspect) {
        let rel = f
            .strip_prefix(&inspect)
            .expect("a file of the mission library")
            .to_string_lossy()
            .replace('\\', "/");
        let folder = rel.rsplit_once('/').map(|(d, _)| format!("{d}/"));
        let in_named_folder = folder
            .as_ref()
            .is_some_and(|d| named.contains(d) && d.matches('/').count() > 1);
        let bare = rel.rsplit('/').next().unwrap_or(&rel).to_string();
        let listed = named.contains(&rel)
            || in_named_folder
            || (rel.starts_with("rig/") && named.contains(&bare))
            || (rel.starts_with("steps/") && !rel.contains("/mod.rs") && named.contains(&rel));
        if !listed && rel != "steps/mod.rs" && rel != "rig/mod.rs" {
            unnamed.push(rel);
        }
    }
    assert!(
        unnamed.is_empty(),
        "files the tables do not name: {unnamed:?}"
    );
}
