//! Reading Rust source as the architecture test needs it: comments and strings blanked
//! ([`code_only`]), the `crate::`/`super::` paths of a file ([`paths`]) resolved to the modules
//! they name ([`resolve`]), the cycles of the import graph ([`cycles`]), and the functions and
//! `pub struct`s outside tests with their sizes ([`functions`], [`pub_structs`]).
use std::collections::{BTreeMap, BTreeSet};

/// The code of a Rust file without comments and string literals (paths in docs and messages
/// are not imports).
pub fn code_only(text: &str) -> String {
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
pub fn paths(code: &str) -> Vec<Vec<String>> {
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
pub fn resolve(from: &str, path: &[String], modules: &BTreeSet<String>) -> Option<String> {
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
pub fn cycles(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
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

/// Every function of `code` (as given by [`code_only`]) outside `#[cfg(test)]` items: its name,
/// first line (1-based) and length in lines from the line of `fn` to that of its closing brace.
pub fn functions(code: &str) -> Vec<(String, usize, usize)> {
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

/// Every `pub struct` with named fields in `code` (as given by [`code_only`]) outside
/// `#[cfg(test)]` items: its name, line (1-based) and number of named fields (the commas at
/// the top level of its braces, plus one for a last field without a trailing comma).
pub fn pub_structs(code: &str) -> Vec<(String, usize, usize)> {
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
