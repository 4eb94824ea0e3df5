//! TOML and type errors of a case file in the user's words: which key (with its table), what
//! was expected (an integer, a number or an expression), an empty file, and where an unclosed
//! array opened. The `toml` crate reports serde's types (`usize`, `untagged enum Scalar`) and
//! the position where parsing failed; this adds what a user needs to find the mistake, and
//! keeps the crate's own excerpt of the line below.

/// The message of `err`, raised while parsing `text` (a case or spec file).
pub fn describe(text: &str, err: &toml::de::Error) -> String {
    if is_empty(text) {
        return "the file is empty: a case needs at least `description`, [rod], [material], [cross_section] and [solver]"
            .to_string();
    }
    let message = rephrase(err.message());
    let Some(span) = err.span() else { return format!("{message}\n{err}") };
    let line = text[..span.start.min(text.len())].matches('\n').count() + 1;
    let mut head = String::new();
    let missing = err.message().starts_with("missing field");
    if let Some(key) = key_at(text, line).filter(|_| !missing) {
        head += &format!("key `{key}` (line {line}): ");
    }
    head += &message;
    if let Some(open) = unclosed_array(text, line) {
        head += &format!(" (the array that opens at line {open} is not closed with `]`)");
    }
    format!("{head}\n{err}")
}

/// No table and no key: only blanks and comments.
fn is_empty(text: &str) -> bool {
    text.lines().all(|l| {
        let t = l.trim();
        t.is_empty() || t.starts_with('#')
    })
}

/// serde's type words in the user's.
fn rephrase(message: &str) -> String {
    let mut m = message.trim().lines().map(str::trim).collect::<Vec<_>>().join("; ");
    for t in ["usize", "u64", "u32", "u16", "u8", "i64", "i32"] {
        m = m.replace(&format!("expected {t}"), "expected a non-negative integer (no decimal point, no quotes)");
    }
    m = m.replace("expected f64", "expected a number");
    if m.contains("untagged enum Scalar") {
        m = "expected a number or an expression in quotes (e.g. 1e-3 or \"L/2\")".to_string();
    }
    if let Some(field) = m.strip_prefix("missing field `").and_then(|r| r.strip_suffix('`')) {
        m = format!("missing key or table `{field}` (a table is written [{field}] on its own line)");
    }
    m
}

/// `table.key` of the key on line `line` (1-based), if the line assigns one.
fn key_at(text: &str, line: usize) -> Option<String> {
    let lines: Vec<&str> = text.lines().collect();
    let this = lines.get(line.checked_sub(1)?)?;
    let key = this.split_once('=')?.0.trim();
    if key.is_empty() || key.starts_with('#') || key.starts_with('[') {
        return None;
    }
    let table = lines[..line - 1].iter().rev().find_map(|l| {
        let t = l.trim();
        (t.starts_with('[') && !t.contains('=')).then(|| t.trim_matches(|c| c == '[' || c == ']').trim().to_string())
    });
    Some(match table {
        Some(t) if !t.is_empty() => format!("{t}.{key}"),
        _ => key.to_string(),
    })
}

/// The line (1-based) where an array opened before line `line` is still open there.
fn unclosed_array(text: &str, line: usize) -> Option<usize> {
    let mut depth = 0i64;
    let mut opened = None;
    for (i, l) in text.lines().take(line.saturating_sub(1)).enumerate() {
        let code = strip_strings_and_comment(l);
        let value = if depth == 0 {
            match code.split_once('=') {
                Some((_, v)) => v.to_string(),
                None => continue, // a table header or a blank line
            }
        } else {
            code
        };
        for c in value.chars() {
            match c {
                '[' => {
                    if depth == 0 {
                        opened = Some(i + 1);
                    }
                    depth += 1;
                }
                ']' => depth = (depth - 1).max(0),
                _ => {}
            }
        }
        if depth == 0 {
            opened = None;
        }
    }
    opened
}

/// A line without its string literals and its comment.
fn strip_strings_and_comment(line: &str) -> String {
    let mut out = String::new();
    let mut quote: Option<char> = None;
    for c in line.chars() {
        match quote {
            Some(q) if c == q => quote = None,
            Some(_) => {}
            None if c == '"' || c == '\'' => quote = Some(c),
            None if c == '#' => break,
            None => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn error_of(text: &str) -> String {
        #[derive(serde::Deserialize, Debug)]
        #[allow(dead_code)]
        struct Rod {
            elements: usize,
            frames: Option<Vec<usize>>,
        }
        #[derive(serde::Deserialize, Debug)]
        #[allow(dead_code)]
        struct File {
            description: String,
            rod: Rod,
        }
        let e = toml::from_str::<File>(text).expect_err("must fail");
        describe(text, &e)
    }

    #[test]
    fn names_the_key_its_table_and_the_integer() {
        let m = error_of("description = \"a\"\n[rod]\nelements = 20.5\n");
        assert!(m.starts_with("key `rod.elements` (line 3): "), "{m}");
        assert!(m.contains("non-negative integer"), "{m}");
        assert!(m.contains("20.5"), "{m}");
    }

    #[test]
    fn finds_where_an_unclosed_array_opens() {
        let m = error_of("description = \"a\"\n[rod]\nframes = [0,\n  2\nelements = 3\n[x]\n");
        assert!(m.contains("opens at line 3"), "{m}");
        // a closed array before the error is not blamed
        let m = error_of("description = \"a # [\"\n[rod]\nframes = [0, 2] # [\nelements = 2.5\n");
        assert!(!m.contains("opens at line"), "{m}");
    }

    #[test]
    fn an_empty_file_is_called_empty() {
        let m = error_of("# only a comment\n\n");
        assert!(m.starts_with("the file is empty"), "{m}");
        assert!(error_of("description = \"a\"\n").contains("missing key or table `rod`"));
    }
}
