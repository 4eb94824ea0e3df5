//! The module structure of `src/` (see the layers in `src/lib.rs`): every `crate::`, `super::`
//! and (in `main.rs`) `cosserat::` path is resolved to the module it names; the resulting graph
//! has no cycle, no module imports a module of a higher layer ([`LAYERS`]) or of a higher
//! sub-layer of its own folder ([`SUBLAYERS`]), no source file is longer than 600 lines, no
//! function outside tests longer than 80 and no `pub struct` outside tests with more than 10
//! named fields. `cargo test --test architecture -- --nocapture` prints the graph's size.
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

#[path = "architecture/source.rs"]
mod source;
use source::{code_only, cycles, functions, paths, pub_structs, resolve};

/// Layers, lowest first; a module may use its own top-level module and those of lower layers.
const LAYERS: &[&[&str]] = &[
    &["expr", "linalg", "reference", "interrupt", "file_kind"],
    &["figures"],
    &["io"],
    &["model"],
    &["recorded"],
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
/// them is its folder's top): what both engines give (`engine::common`: results, metrics, clip
/// frames) below the files they read (`engine::input`), below the two engines side by side,
/// below `engine` itself (`run_case`), the interface above both.
const SUBLAYERS: &[&[&str]] =
    &[&["engine::common"], &["engine::input"], &["engine::rust", "engine::freefem"], &["engine"]];

/// Sub-folders of one sub-layer that import each other in neither direction: the engines.
const SIBLINGS: &[(&str, &str)] = &[("engine::rust", "engine::freefem")];

/// Folders whose sub-folders the layers above reach only through the folder's own module (its
/// `mod.rs`, the interface): above `engine`, `crate::engine::RunResult`, never
/// `crate::engine::rust::…`; except the sub-folders of [`OPEN`].
const SEALED: &[&str] = &["engine"];

/// Sub-folders of a [`SEALED`] folder that are part of its interface: the files the engines
/// read (`engine::input`: data files, recordings, their ground truth, the synthetic corpora).
const OPEN: &[&str] = &["engine::input"];

fn within(module: &str, folder: &str) -> bool {
    module == folder || module.starts_with(&format!("{folder}::"))
}

/// Does an import `from` → `to` break a [`SIBLINGS`] or a [`SEALED`] rule? Its reason.
fn crosses_seam(from: &str, to: &str) -> Option<&'static str> {
    if SIBLINGS.iter().any(|(a, b)| (within(from, a) && within(to, b)) || (within(from, b) && within(to, a))) {
        return Some("the engines import each other");
    }
    let open = OPEN.iter().any(|o| within(to, o));
    if !open && SEALED.iter().any(|f| !within(from, f) && within(to, f) && to != *f) {
        return Some("past the engine's interface");
    }
    None
}

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
    let mut seams = Vec::new();
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
            if let Some(why) = crosses_seam(&from, &to) {
                seams.push(format!("{from} → {to} ({}): {why}", p.join("::")));
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
    // who imports each part of `engine/`: modules above it, and the engines themselves
    let importers = |e: &str, from: &dyn Fn(&str) -> bool| {
        graph.iter().filter(|(f, to)| from(f) && !within(f, e) && to.iter().any(|t| within(t, e))).count()
    };
    let engines = |f: &str| within(f, "engine::rust") || within(f, "engine::freefem");
    for e in ["engine::rust", "engine::freefem", "engine::common", "engine::input"] {
        let above = importers(e, &|f| !within(f, "engine"));
        println!("{e}: imported by {above} modules above engine/, {} modules of the engines", importers(e, &engines));
    }
    let interface = graph.iter().filter(|(f, to)| !within(f, "engine") && to.contains("engine")).count();
    println!("engine (the interface, engine/mod.rs): imported by {interface} modules above engine/");
    assert!(seams.is_empty(), "imports across the engine seam:\n{}", seams.join("\n"));
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
    "src/jobs/batch_summary.rs:BatchRow",
    // a row of noise_study.csv written by the csv crate's `serialize`, which refuses `flatten`
    "src/study/mod.rs:StudyRow",
];

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
        goes_up("engine::common::frames", "engine::freefem") && !goes_up("engine::freefem::clip", "engine::common")
    );
    assert!(!goes_up("engine::rust::clip", "engine::freefem") && !goes_up("engine::freefem", "engine::rust::frames"));
    assert!(crosses_seam("engine::rust::clip", "engine::freefem").is_some());
    assert!(crosses_seam("engine::freefem::clip", "engine::rust::frames").is_some());
    assert!(crosses_seam("output::clip_run", "engine::rust::clip").is_some());
    assert!(
        crosses_seam("output::clip_run", "engine").is_none()
            && crosses_seam("engine::rust", "engine::common").is_none()
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
