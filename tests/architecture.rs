//! The module structure of `src/` (see the layers in `src/lib.rs`): every `crate::`, `super::`
//! and (in `main.rs`) `cosserat::` path is resolved to the module it names; the resulting graph
//! has no cycle, no module imports a module of a higher layer ([`LAYERS`]) or of a higher
//! sub-layer of its own folder ([`SUBLAYERS`]), no source file is longer than 600 lines, no
//! function outside tests longer than 80 and no `pub struct` outside tests with more than 10
//! named fields. `cargo test --test architecture -- --nocapture` prints the graph's size.
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Layers, lowest first; a module may use its own top-level module and those of lower layers.
const LAYERS: &[&[&str]] = &[
    &["expr", "linalg", "reference", "interrupt", "file_kind"],
    &["figures"],
    &["io"],
    &["model"],
    &["assemble"],
    &["solve"],
    &["clip"],
    &["case"],
    &["engine"],
    &["output"],
    &["jobs"],
    &["audit", "study"],
    &["main", "cli"],
];

/// The same rule inside a folder, between its sub-folders (lowest first; a module in none of
/// them is its folder's top): the Rust engine knows neither FreeFEM nor the files the engines
/// read; the FreeFEM engine gives the Rust engine's results; `engine` itself (`run_case`) is
/// the interface above both.
const SUBLAYERS: &[&[&str]] = &[&["engine::rust"], &["engine::input"], &["engine::freefem"], &["engine"]];

/// Longest source file allowed [lines].
const MAX_LINES: usize = 600;

fn layer(module: &str) -> usize {
    let top = module.split("::").next().unwrap_or(module);
    LAYERS.iter().position(|l| l.contains(&top)).unwrap_or_else(|| panic!("module `{module}` is in no layer"))
}

/// The sub-layer of `module` in [`SUBLAYERS`], if its folder has them.
fn sublayer(module: &str) -> Option<usize> {
    SUBLAYERS.iter().position(|l| l.iter().any(|p| module == *p || module.starts_with(&format!("{p}::"))))
}

/// Does an import `from` → `to` go up: to a higher layer, or to a higher sub-layer of the same
/// folder?
fn goes_up(from: &str, to: &str) -> bool {
    let sub_up = matches!((sublayer(from), sublayer(to)), (Some(f), Some(t)) if t > f);
    layer(to) > layer(from) || (layer(to) == layer(from) && sub_up)
}

/// Module path of a source file: `src/a/b.rs` and `src/a/b/mod.rs` are `a::b`; `main.rs` is `main`.
fn module_of(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).expect("under src");
    let mut parts: Vec<String> = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    let last = parts.pop().expect("file name");
    let stem = last.trim_end_matches(".rs");
    if stem != "mod" && stem != "lib" {
        parts.push(stem.to_string());
    }
    parts.join("::")
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("read_dir") {
        let p = entry.expect("entry").path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// The code of a Rust file without comments and string literals (paths in docs and messages
/// are not imports).
fn code_only(text: &str) -> String {
    let b: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == '/' && b.get(i + 1) == Some(&'/') {
            while i < b.len() && b[i] != '\n' {
                i += 1;
            }
        } else if b[i] == '/' && b.get(i + 1) == Some(&'*') {
            i += 2;
            while i + 1 < b.len() && !(b[i] == '*' && b[i + 1] == '/') {
                if b[i] == '\n' {
                    out.push('\n'); // keep line numbers
                }
                i += 1;
            }
            i += 2;
        } else if b[i] == '"' {
            i += 1;
            let mut newlines = 0;
            while i < b.len() && b[i] != '"' {
                newlines += usize::from(b[i] == '\n');
                i += if b[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("\"\"");
            out.extend(std::iter::repeat_n('\n', newlines));
        } else if b[i] == '\'' && b.get(i + 2) == Some(&'\'') {
            i += 3; // a char literal such as '"'
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    out
}

/// Every path that starts with `crate`, `super`, `self` or `cosserat` in `code`, with `use`
/// groups `a::{b, c::d}` expanded.
fn paths(code: &str) -> Vec<Vec<String>> {
    let chars: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    let mut i = 0;
    while i < chars.len() {
        if ident(chars[i]) && (i == 0 || !(ident(chars[i - 1]) || chars[i - 1] == ':')) {
            let start = i;
            while i < chars.len() && ident(chars[i]) {
                i += 1;
            }
            let word: String = chars[start..i].iter().collect();
            if matches!(word.as_str(), "crate" | "super" | "self" | "cosserat") && chars.get(i) == Some(&':') {
                let mut prefix = vec![word];
                i = read_path(&chars, i, &mut prefix, &mut out);
            }
        } else {
            i += 1;
        }
    }
    out
}

/// Continue a path after `prefix` at `i` (which points at `::`), pushing complete paths.
fn read_path(chars: &[char], mut i: usize, prefix: &mut Vec<String>, out: &mut Vec<Vec<String>>) -> usize {
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    while chars.get(i) == Some(&':') && chars.get(i + 1) == Some(&':') {
        i += 2;
        while chars.get(i).is_some_and(|c| c.is_whitespace()) {
            i += 1;
        }
        if chars.get(i) == Some(&'{') {
            i += 1;
            loop {
                while chars.get(i).is_some_and(|c| c.is_whitespace() || *c == ',') {
                    i += 1;
                }
                match chars.get(i) {
                    None => return i,
                    Some('}') => return i + 1,
                    _ => {}
                }
                let start = i;
                while chars.get(i).is_some_and(|c| ident(*c) || *c == '*') {
                    i += 1;
                }
                let mut p = prefix.clone();
                p.push(chars[start..i].iter().collect());
                i = read_path(chars, i, &mut p, out);
                // skip `as name`
                while chars.get(i).is_some_and(|c| *c != ',' && *c != '}') {
                    i += 1;
                }
            }
        }
        let start = i;
        while chars.get(i).is_some_and(|c| ident(*c) || *c == '*') {
            i += 1;
        }
        if start == i {
            break;
        }
        prefix.push(chars[start..i].iter().collect());
    }
    out.push(prefix.clone());
    i
}

/// The module a path in `from` refers to: the longest prefix that is a known module.
fn resolve(from: &str, path: &[String], modules: &BTreeSet<String>) -> Option<String> {
    let mut base: Vec<String> = match path[0].as_str() {
        "crate" | "cosserat" => Vec::new(),
        "self" | "super" => {
            // `self` is the file's module, `super` its parent (inline `mod tests` blocks use
            // `super` for their file: an edge to the parent, which is not counted)
            let mut b: Vec<String> =
                if from.is_empty() { Vec::new() } else { from.split("::").map(String::from).collect() };
            if path[0] == "super" {
                b.pop();
            }
            b
        }
        _ => return None,
    };
    let mut rest = &path[1..];
    while rest.first().is_some_and(|s| s == "super") {
        base.pop();
        rest = &rest[1..];
    }
    let mut best = None;
    let mut cur = base.clone();
    if !cur.is_empty() && modules.contains(&cur.join("::")) {
        best = Some(cur.join("::"));
    }
    for seg in rest {
        cur.push(seg.clone());
        let name = cur.join("::");
        if modules.contains(&name) {
            best = Some(name);
        }
    }
    best
}

/// Strongly connected components with more than one module (Tarjan).
fn cycles(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct T<'a> {
        g: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on: BTreeSet<&'a str>,
        next: usize,
        out: Vec<Vec<String>>,
    }
    fn visit<'a>(t: &mut T<'a>, v: &'a str) {
        t.index.insert(v, t.next);
        t.low.insert(v, t.next);
        t.next += 1;
        t.stack.push(v);
        t.on.insert(v);
        for w in t.g.get(v).into_iter().flatten() {
            let w = w.as_str();
            if !t.index.contains_key(w) {
                visit(t, w);
                let lw = t.low[w];
                let lv = t.low.get_mut(v).expect("low");
                *lv = (*lv).min(lw);
            } else if t.on.contains(w) {
                let iw = t.index[w];
                let lv = t.low.get_mut(v).expect("low");
                *lv = (*lv).min(iw);
            }
        }
        if t.low[v] == t.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = t.stack.pop() {
                t.on.remove(w);
                comp.push(w.to_string());
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                comp.sort();
                t.out.push(comp);
            }
        }
    }
    let mut t = T {
        g: graph,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        next: 0,
        out: Vec::new(),
    };
    for v in graph.keys() {
        if !t.index.contains_key(v.as_str()) {
            visit(&mut t, v);
        }
    }
    t.out
}

#[test]
fn layers_are_imported_downward_only_without_cycles_and_files_are_short() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let src = root.join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let modules: BTreeSet<String> =
        files.iter().map(|f| module_of(&src, f)).filter(|m| !m.is_empty() && m != "main").collect();
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut upward = Vec::new();
    let mut long = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).expect("source");
        let from = module_of(&src, f);
        if text.lines().count() > MAX_LINES {
            long.push(format!("{} ({} lines)", f.display(), text.lines().count()));
        }
        if from.is_empty() {
            continue; // lib.rs declares the modules
        }
        for p in paths(&code_only(&text)) {
            let Some(to) = resolve(&from, &p, &modules) else { continue };
            if to == from || to.starts_with(&format!("{from}::")) || from.starts_with(&format!("{to}::")) {
                continue; // a module and its own submodules
            }
            graph.entry(from.clone()).or_default().insert(to.clone());
            if goes_up(&from, &to) {
                upward.push(format!("{from} → {to} ({})", p.join("::")));
            }
        }
    }
    for m in &modules {
        graph.entry(m.clone()).or_default();
    }
    let edges: usize = graph.values().map(BTreeSet::len).sum();
    let cyc = cycles(&graph);
    let largest = files
        .iter()
        .map(|f| (std::fs::read_to_string(f).map(|t| t.lines().count()).unwrap_or(0), f))
        .max()
        .map(|(n, f)| format!("{} ({n} lines)", f.strip_prefix(root).unwrap_or(f).display()))
        .unwrap_or_default();
    println!(
        "{} modules, {edges} imports between modules, {} cycles, {} upward imports; largest file {largest}",
        modules.len() + 1,
        cyc.len(),
        upward.len()
    );
    assert!(cyc.is_empty(), "import cycles: {cyc:?}");
    assert!(upward.is_empty(), "imports from a lower layer to a higher one:\n{}", upward.join("\n"));
    let mut test_files = Vec::new();
    rust_files(&root.join("tests"), &mut test_files);
    rust_files(&root.join("examples"), &mut test_files);
    for f in test_files {
        let n = std::fs::read_to_string(&f).expect("source").lines().count();
        if n > MAX_LINES {
            long.push(format!("{} ({n} lines)", f.display()));
        }
    }
    assert!(long.is_empty(), "files over {MAX_LINES} lines: {long:?}");
}

/// Longest function allowed outside tests [lines, from `fn` to its closing brace].
const MAX_FN_LINES: usize = 80;

/// Every function of `code` (as given by [`code_only`]) outside `#[cfg(test)]` items: its name,
/// first line (1-based) and length in lines from the line of `fn` to that of its closing brace.
fn functions(code: &str) -> Vec<(String, usize, usize)> {
    let chars: Vec<char> = code.chars().collect();
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    let line_at = |i: usize| 1 + chars[..i].iter().filter(|c| **c == '\n').count();
    // the closing brace matching the opening one at `open`
    let close = |open: usize| block_end(chars.iter().copied().enumerate().skip(open)).unwrap_or(chars.len() - 1);
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        if chars[i..].starts_with(&['#', '[', 'c', 'f', 'g', '(', 't', 'e', 's', 't', ')', ']']) {
            // skip the item that follows up to its block (a `mod tests { .. }` or a function)
            let mut k = i;
            while k < chars.len() && chars[k] != '{' && chars[k] != ';' {
                k += 1;
            }
            i = if chars.get(k) == Some(&'{') { close(k) + 1 } else { k + 1 };
            continue;
        }
        let word_start = ident(chars[i]) && (i == 0 || !ident(chars[i - 1]));
        if word_start && chars[i..].starts_with(&['f', 'n']) && chars.get(i + 2).is_some_and(|c| c.is_whitespace()) {
            let mut k = i + 2;
            while chars.get(k).is_some_and(|c| c.is_whitespace()) {
                k += 1;
            }
            let start = k;
            while chars.get(k).is_some_and(|c| ident(*c)) {
                k += 1;
            }
            let name: String = chars[start..k].iter().collect();
            // the body: the first `{` at bracket depth 0 before any `;` (a declaration has none)
            let mut depth = 0i32;
            while k < chars.len() {
                match chars[k] {
                    '(' | '[' | '<' => depth += 1,
                    ')' | ']' => depth -= 1,
                    '>' if chars[k - 1] != '-' => depth -= 1,
                    '{' if depth <= 0 => break,
                    ';' if depth <= 0 => break,
                    _ => {}
                }
                k += 1;
            }
            if chars.get(k) == Some(&'{') {
                let end = close(k);
                let first = line_at(i);
                out.push((name, first, line_at(end) - first + 1));
            }
            i += 2; // nested functions are counted too
            continue;
        }
        i += 1;
    }
    out
}

/// Functions still over [`MAX_FN_LINES`] (`file:name`), to be split: the list may only shrink
/// (a listed function that became short must leave it).
const LONG_FUNCTIONS_LEFT: &[&str] = &[];

/// The items that `items` finds (name, line, size) in the source files of `src/` outside
/// tests and whose size is over `max`, against a may-only-shrink list `left` of `file:name`
/// keys: the unlisted ones (largest first, `"file:line `name` (size unit)"`), and the listed
/// ones that are no longer over (or gone).
fn over_limit(
    items: fn(&str) -> Vec<(String, usize, usize)>,
    max: usize,
    left: &[&str],
    unit: &str,
) -> (Vec<String>, Vec<String>) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let src = root.join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut over = Vec::new();
    let mut still: BTreeSet<String> = BTreeSet::new();
    for f in &files {
        if module_of(&src, f).rsplit("::").next() == Some("tests") {
            continue;
        }
        let text = std::fs::read_to_string(f).expect("source");
        let rel = f.strip_prefix(root).unwrap_or(f).display().to_string();
        for (name, line, n) in items(&code_only(&text)) {
            let key = format!("{rel}:{name}");
            if n > max && left.contains(&key.as_str()) {
                still.insert(key);
            } else if n > max {
                over.push((n, format!("{rel}:{line} `{name}` ({n} {unit})")));
            }
        }
    }
    over.sort_by_key(|b| std::cmp::Reverse(b.0));
    let done = left.iter().filter(|k| !still.contains(**k)).map(|k| k.to_string()).collect();
    (over.into_iter().map(|(_, s)| s).collect(), done)
}

#[test]
fn no_function_is_longer_than_80_lines_outside_tests() {
    let (long, done) = over_limit(functions, MAX_FN_LINES, LONG_FUNCTIONS_LEFT, "lines");
    assert!(long.is_empty(), "{} functions over {MAX_FN_LINES} lines:\n{}", long.len(), long.join("\n"));
    assert!(done.is_empty(), "now short (or gone), remove from LONG_FUNCTIONS_LEFT: {done:?}");
}

/// Most named fields a `pub struct` outside tests may have.
const MAX_STRUCT_FIELDS: usize = 10;

/// Structs still over [`MAX_STRUCT_FIELDS`] (`file:name`): the list may only shrink (a listed
/// struct that became small must leave it). Each mirrors a file format field by field, where
/// grouping its fields into typed parts would change the format or how it is read (the comment
/// of each says how).
const LARGE_STRUCTS_LEFT: &[&str] = &[
    // the case file's top-level tables as written: `deny_unknown_fields`, which `flatten` breaks
    "src/case/raw.rs:RawCase",
    // the case file's `[clip]` table as written: `deny_unknown_fields`, which `flatten` breaks
    "src/case/raw.rs:RawClip",
    // the case file's `[solver]` table as written: `deny_unknown_fields`, which `flatten` breaks
    "src/case/raw.rs:RawSolver",
    // a recording's row of summary.csv (SUMMARY_COLUMNS, a field per column) and batch_row.json
    "src/jobs/batch.rs:BatchRow",
    // a row of noise_study.csv written by the csv crate's `serialize`, which refuses `flatten`
    "src/study/mod.rs:StudyRow",
];

/// Every `pub struct` with named fields in `code` (as given by [`code_only`]) outside
/// `#[cfg(test)]` items: its name, line (1-based) and number of named fields (the commas at
/// the top level of its braces, plus one for a last field without a trailing comma).
fn pub_structs(code: &str) -> Vec<(String, usize, usize)> {
    let mut out = Vec::new();
    let mut skip_to = 0;
    for (i, _) in code.char_indices() {
        if i < skip_to {
            continue;
        }
        let rest = &code[i..];
        if rest.starts_with("#[cfg(test)]") {
            // skip the item that follows up to the end of its block
            let open = rest.find(['{', ';']).unwrap_or(rest.len());
            skip_to = i + if rest[open..].starts_with('{') {
                block_end(rest.char_indices()).unwrap_or(rest.len())
            } else {
                open
            };
            continue;
        }
        let word_start = code[..i].chars().next_back().is_none_or(|c| !(c.is_alphanumeric() || c == '_'));
        if !word_start || !rest.starts_with("pub") {
            continue;
        }
        let after_vis = rest[3..].trim_start();
        let after_vis = if after_vis.starts_with('(') {
            after_vis[after_vis.find(')').map_or(0, |k| k + 1)..].trim_start()
        } else {
            after_vis
        };
        let Some(decl) = after_vis.strip_prefix("struct ") else { continue };
        let name: String = decl.trim_start().chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
        // named fields: a `{` before any `;` or `(` (a unit or tuple struct has none)
        let Some(open) = decl.find(['{', ';', '(']).filter(|&k| decl[k..].starts_with('{')) else { continue };
        let body = &decl[open + 1..block_end(decl.char_indices().skip_while(|&(k, _)| k < open)).unwrap_or(decl.len())];
        let (mut depth, mut commas, mut prev) = (0i32, 0, ' ');
        for c in body.chars() {
            match c {
                '(' | '[' | '{' | '<' => depth += 1,
                ')' | ']' | '}' => depth -= 1,
                '>' if prev != '-' => depth -= 1,
                ',' if depth == 0 => commas += 1,
                _ => {}
            }
            prev = c;
        }
        let trailing = body.trim_end().ends_with(',') || body.trim().is_empty();
        let line = 1 + code[..i].matches('\n').count();
        out.push((name, line, commas + usize::from(!trailing)));
    }
    out
}

/// The position (as `chars` numbers it) of the `}` that closes the first `{` of `chars`, if any.
fn block_end(chars: impl Iterator<Item = (usize, char)>) -> Option<usize> {
    let mut depth = 0usize;
    for (k, c) in chars {
        match c {
            '{' => depth += 1,
            '}' => {
                depth -= 1;
                if depth == 0 {
                    return Some(k);
                }
            }
            _ => {}
        }
    }
    None
}

#[test]
fn no_pub_struct_has_more_than_10_fields_outside_tests() {
    let (large, done) = over_limit(pub_structs, MAX_STRUCT_FIELDS, LARGE_STRUCTS_LEFT, "fields");
    assert!(large.is_empty(), "{} pub structs over {MAX_STRUCT_FIELDS} fields:\n{}", large.len(), large.join("\n"));
    assert!(done.is_empty(), "now small (or gone), remove from LARGE_STRUCTS_LEFT: {done:?}");
}

/// The checker itself: it finds a cycle and an upward import when there is one, and reads
/// grouped imports, `super` and paths inside code but not inside comments or strings.
#[test]
fn the_checker_sees_imports_and_cycles() {
    let code = code_only(
        "use crate::io::{files::write_atomic, plot::{render_svg, Series}};\n// crate::run::X\nlet s = \"crate::case\"; super::kkt::X; crate::model::mesh::Field::X",
    );
    let p = paths(&code);
    let modules: BTreeSet<String> = [
        "io",
        "io::files",
        "io::plot",
        "model",
        "model::mesh",
        "run",
        "case",
        "solve",
        "solve::inverse",
        "solve::inverse::kkt",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let resolved: BTreeSet<String> = p.iter().filter_map(|p| resolve("solve::inverse::newton", p, &modules)).collect();
    let expected: BTreeSet<String> =
        ["io::files", "io::plot", "solve::inverse::kkt", "model::mesh"].iter().map(|s| s.to_string()).collect();
    assert_eq!(resolved, expected, "{p:?}");
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    g.entry("a".into()).or_default().insert("b".into());
    g.entry("b".into()).or_default().insert("c".into());
    g.entry("c".into()).or_default().insert("a".into());
    g.entry("d".into()).or_default().insert("a".into());
    assert_eq!(cycles(&g), vec![vec!["a".to_string(), "b".to_string(), "c".to_string()]]);
    assert!(layer("output::journal") > layer("engine::rust::clip") && layer("model::mesh") < layer("assemble"));
    assert!(
        goes_up("engine::rust::clip", "engine::freefem") && !goes_up("engine::freefem::clip", "engine::rust::frames")
    );
    assert!(goes_up("engine::input::data", "engine") && !goes_up("engine", "engine::input::data"));
    let f = functions(&code_only(
        "fn a() {\n}\n#[cfg(test)]\nmod tests {\n    fn b() {\n    }\n}\nfn c(x: Vec<u8>) -> Result<(), ()> {\n    let s = \"}\n\";\n}\ntrait T { fn d(&self); }",
    ));
    assert_eq!(f, vec![("a".to_string(), 1, 2), ("c".to_string(), 8, 4)]);
    let s = pub_structs(&code_only(
        "pub struct A {\n    pub x: fn(u8) -> u8,\n    /// a, b\n    y: Vec<(u8, u8)>,\n    z: [f64; 2]\n}\npub(crate) struct B { f: HashMap<K, V>, }\npub struct U;\npub struct T(u8, u8);\n#[cfg(test)]\nmod tests {\n    pub struct C { a: u8 }\n}",
    ));
    assert_eq!(s, vec![("A".to_string(), 1, 3), ("B".to_string(), 7, 1)]);
}
