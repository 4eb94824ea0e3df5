//! Property-based fuzzing of every reader of user input (issue 15, "runs that never lie"): the
//! case parser, the expression language, the CSV recording reader, the `data.csv` reader and
//! the `.npy` reader. Each target runs [`CASES`] generated inputs, arbitrary ones and mutations
//! of real, valid inputs; the property is always the same: no panic (proptest reports one as a
//! failure), and an error is an `Err` whose message is not empty. Where a reader accepts the
//! input, what it promises is checked too (finite values, sizes that match the file).
//!
//! Failures are not persisted (`failure_persistence: None`): a failing input is printed,
//! shrunk, and goes into a unit test next to the code it breaks.
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use cosserat::case::{Case, MAX_ELEMENTS};
use cosserat::clip::MIN_CLIP_ELEMENTS;
use cosserat::expr::Expr;
use cosserat::io::clip_files::{kymogram_rows, read_recording, RECORDING_HEADER};
use cosserat::io::data::{read_data, DATA_HEADER};
use cosserat::io::npy::{npy_bytes, parse_npy};
use cosserat::model::mesh::Mesh;
use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::{Config, RngSeed};
use toml::{Table, Value};

/// Generated inputs per target (`PROPTEST_CASES` overrides).
const CASES: u32 = 10_000;
/// The seed of every target (`PROPTEST_RNG_SEED` overrides): `cargo test` draws the same inputs
/// each time; other seeds explore further.
const SEED: u64 = 15;

fn config() -> Config {
    let mut c = Config { failure_persistence: None, ..Config::default() };
    if std::env::var_os("PROPTEST_CASES").is_none() {
        c.cases = CASES;
    }
    if matches!(c.rng_seed, RngSeed::Random) {
        c.rng_seed = RngSeed::Fixed(SEED);
    }
    c
}

/// An error's message is not empty.
fn says_something(e: &dyn std::error::Error) -> Result<(), TestCaseError> {
    prop_assert!(!e.to_string().trim().is_empty(), "empty message: {e:?}");
    Ok(())
}

/// A scratch directory for the readers that take a path, one file per target; in memory
/// (`/dev/shm`) where there is one: rewriting a small file on a disk can cost milliseconds
/// (measured: 2.8 ms per rewrite on the ext4 disk of the development machine, 30–50 s per
/// target of 10⁴ inputs; 0.05 ms on tmpfs).
fn scratch(name: &str) -> PathBuf {
    static DIR: OnceLock<tempfile::TempDir> = OnceLock::new();
    DIR.get_or_init(|| {
        let shm = Path::new("/dev/shm");
        let in_memory =
            if shm.is_dir() { tempfile::Builder::new().prefix("cosserat-fuzz").tempdir_in(shm).ok() } else { None };
        in_memory.unwrap_or_else(|| tempfile::tempdir().expect("temporary directory"))
    })
    .path()
    .join(name)
}

// ------------------------------------------------------------------------------ case files

/// The committed cases, as TOML tables.
fn committed_cases() -> &'static Vec<(String, Table)> {
    static CASES_: OnceLock<Vec<(String, Table)>> = OnceLock::new();
    CASES_.get_or_init(|| {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases");
        cosserat::case::case_files(&dir)
            .expect("cases/")
            .into_iter()
            .map(|p| {
                let text = std::fs::read_to_string(&p).expect("case file");
                (p.file_stem().unwrap().to_string_lossy().into_owned(), text.parse::<Table>().expect("TOML"))
            })
            .collect()
    })
}

/// A generated TOML value: numbers near every boundary the validator has, expression-like
/// and keyword strings, arrays of them, booleans and tables.
#[derive(Clone, Debug)]
enum Generated {
    Float(f64),
    Int(i64),
    Str(String),
    Bool(bool),
    Array(Vec<Generated>),
    Table,
}

fn float() -> impl Strategy<Value = f64> {
    prop_oneof![
        any::<f64>(),
        -1e3..1e3f64,
        prop::sample::select(vec![
            0.0,
            -0.0,
            0.5,
            1.0,
            -1.0,
            1e-300,
            1e308,
            -1e308,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MIN_POSITIVE,
            1.0 - f64::EPSILON,
        ]),
    ]
}

fn int() -> impl Strategy<Value = i64> {
    prop_oneof![
        any::<i64>(),
        0..2_000i64,
        prop::sample::select(vec![0, 1, 2, 3, 10, 11, -1, i64::MAX, i64::MIN, 5_000, 1_000_001, 1 << 40]),
    ]
}

fn text() -> impl Strategy<Value = String> {
    prop_oneof![
        "[-+*/^() .,0-9a-zA-Z_]{0,24}",
        prop::sample::select(vec![
            "nan",
            "NaN",
            "inf",
            "-inf",
            "1/(s-s)",
            "1/s",
            "s*t",
            "pi",
            "",
            "1e999",
            "((((((1))))))",
            "sqrt(-1)",
            "log(0)",
            "L",
            "E/(2*(1 + 0.4))",
            "static",
            "dynamic",
            "inverse",
            "newton",
            "fixed_point",
            "kymogram",
            "recording",
            "roll_3d",
            "local",
            "global",
            "circle",
            "rectangle",
            "xy",
            "xz",
            "data_guess",
            "rebased",
            "global_euler",
            "selective",
            "full",
            "reduced",
            "tip_loaded_cantilever",
        ])
        .prop_map(String::from),
        any::<String>(),
    ]
}

fn generated() -> impl Strategy<Value = Generated> {
    let leaf = prop_oneof![
        3 => float().prop_map(Generated::Float),
        3 => int().prop_map(Generated::Int),
        3 => text().prop_map(Generated::Str),
        1 => any::<bool>().prop_map(Generated::Bool),
        1 => Just(Generated::Table),
    ];
    leaf.prop_recursive(2, 12, 5, |inner| prop::collection::vec(inner, 0..5).prop_map(Generated::Array))
}

impl Generated {
    fn value(&self) -> Value {
        match self {
            Generated::Float(x) => Value::Float(*x),
            Generated::Int(i) => Value::Integer(*i),
            Generated::Str(s) => Value::String(s.clone()),
            Generated::Bool(b) => Value::Boolean(*b),
            Generated::Array(a) => Value::Array(a.iter().map(Generated::value).collect()),
            Generated::Table => Value::Table(Table::new()),
        }
    }
}

#[derive(Clone, Debug)]
enum Mutation {
    /// replace the value (scalar, array or table) at a path
    Replace(Index, Generated),
    /// remove the entry at a path
    Delete(Index),
    /// add a key to a table (the key often an existing one of another table)
    Add(Index, String, Generated),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let key = prop_oneof![
        prop::sample::select(vec![
            "elements",
            "length_m",
            "frames",
            "kind",
            "file",
            "steps",
            "end_s",
            "gauge",
            "orientation",
            "clip_frames",
            "substeps",
            "force_n_per_m",
            "end_force_n",
            "frame",
            "lambda_omega",
            "frame_interval_s",
            "relaxation",
            "method",
            "analysis",
            "warm_start_tolerance",
            "reason",
            "x",
            "s",
            "pi",
            "sin",
        ])
        .prop_map(String::from),
        "[a-z_]{1,12}",
    ];
    prop_oneof![
        4 => (any::<Index>(), generated()).prop_map(|(i, g)| Mutation::Replace(i, g)),
        2 => any::<Index>().prop_map(Mutation::Delete),
        2 => (any::<Index>(), key, generated()).prop_map(|(i, k, g)| Mutation::Add(i, k, g)),
    ]
}

/// A path into a TOML value: table keys and array indices.
#[derive(Clone, Debug)]
enum Seg {
    Key(String),
    At(usize),
}

/// Every path below `v` (tables, arrays and scalars), depth first.
fn paths(v: &Value, prefix: &mut Vec<Seg>, out: &mut Vec<Vec<Seg>>) {
    match v {
        Value::Table(t) => {
            for (k, x) in t {
                prefix.push(Seg::Key(k.clone()));
                out.push(prefix.clone());
                paths(x, prefix, out);
                prefix.pop();
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                prefix.push(Seg::At(i));
                out.push(prefix.clone());
                paths(x, prefix, out);
                prefix.pop();
            }
        }
        _ => {}
    }
}

fn get_mut<'a>(v: &'a mut Value, path: &[Seg]) -> Option<&'a mut Value> {
    path.iter().try_fold(v, |v, seg| match (seg, v) {
        (Seg::Key(k), Value::Table(t)) => t.get_mut(k),
        (Seg::At(i), Value::Array(a)) => a.get_mut(*i),
        _ => None,
    })
}

fn apply(root: &mut Value, m: &Mutation) {
    let mut all = Vec::new();
    paths(root, &mut Vec::new(), &mut all);
    if all.is_empty() {
        return;
    }
    match m {
        Mutation::Replace(i, g) => {
            if let Some(v) = get_mut(root, &all[i.index(all.len())]) {
                *v = g.value();
            }
        }
        Mutation::Delete(i) => {
            let path = &all[i.index(all.len())];
            let (last, parent) = path.split_last().expect("non-empty path");
            match (get_mut(root, parent), last) {
                (Some(Value::Table(t)), Seg::Key(k)) => {
                    t.remove(k);
                }
                (Some(Value::Array(a)), Seg::At(j)) if *j < a.len() => {
                    a.remove(*j);
                }
                _ => {}
            }
        }
        Mutation::Add(i, key, g) => {
            let mut tables: Vec<Vec<Seg>> = vec![Vec::new()];
            tables.extend(all.into_iter().filter(|p| matches!(get_mut(root, p), Some(Value::Table(_)))));
            if let Some(Value::Table(t)) = get_mut(root, &tables[i.index(tables.len())]) {
                t.insert(key.clone(), g.value());
            }
        }
    }
}

/// What a validated case promises: a bounded mesh, finite loads, a clip on a mesh fine enough.
fn check_case(text: &str, name: &str) -> Result<(), TestCaseError> {
    // Clip files resolve against `cases/`; nothing is read at validation.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases").join(format!("{name}.toml"));
    match Case::from_toml(text, name, &path) {
        Ok(case) => {
            prop_assert!((2..=MAX_ELEMENTS).contains(&case.mesh.elements));
            prop_assert!(case.mesh.length_m.is_finite() && case.mesh.length_m > 0.0);
            let (f, l) = case.loads.distributed(case.mesh.length_m / 2.0, 0.0);
            let (fe, le) = case.loads.end(0.0);
            prop_assert!([f, l, fe, le].iter().all(|v| v.iter().all(|c| c.is_finite())), "loads {f} {l} {fe} {le}");
            if case.clip().is_some() {
                prop_assert!(case.mesh.elements >= MIN_CLIP_ELEMENTS);
            }
            Ok(())
        }
        Err(e) => says_something(&e),
    }
}

proptest! {
    #![proptest_config(config())]

    /// Arbitrary text, TOML-like text and arbitrary bytes.
    #[test]
    fn case_parser_takes_any_text(
        text in prop_oneof![
            any::<String>(),
            "[a-z_\\[\\]=\"'0-9., \n#{}+*/()-]{0,300}",
            prop::collection::vec(any::<u8>(), 0..512).prop_map(|b| String::from_utf8_lossy(&b).into_owned()),
        ]
    ) {
        check_case(&text, "fuzz")?;
    }

    /// The committed cases with one to four values replaced, deleted or added.
    #[test]
    fn case_parser_takes_mutated_cases(
        which in any::<Index>(),
        mutations in prop::collection::vec(mutation(), 1..5),
    ) {
        let cases = committed_cases();
        let (name, table) = &cases[which.index(cases.len())];
        let mut root = Value::Table(table.clone());
        for m in &mutations {
            apply(&mut root, m);
        }
        let Value::Table(t) = root else { unreachable!("the root stays a table") };
        if let Ok(text) = toml::to_string(&t) {
            check_case(&text, name)?;
        }
    }
}

// ------------------------------------------------------------------------------ expressions

/// Well-formed expressions of s, t, two constants, pi and every function.
fn expression() -> impl Strategy<Value = String> {
    let leaf = prop_oneof![
        prop::sample::select(vec!["s", "t", "k", "omega0", "pi"]).prop_map(String::from),
        (0.0..1e6f64).prop_map(|x| format!("{x}")),
        (0u32..1000).prop_map(|x| x.to_string()),
        (1e-300..1e300f64).prop_map(|x| format!("{x:e}")),
    ];
    leaf.prop_recursive(6, 64, 2, |inner| {
        prop_oneof![
            (inner.clone(), prop::sample::select(vec!["+", "-", "*", "/", "^"]), inner.clone())
                .prop_map(|(a, op, b)| format!("{a}{op}{b}")),
            inner.clone().prop_map(|a| format!("({a})")),
            inner.clone().prop_map(|a| format!("-{a}")),
            (
                prop::sample::select(vec![
                    "sin", "cos", "tan", "exp", "log", "sqrt", "abs", "sinh", "cosh", "tanh", "atan", "asin", "acos"
                ]),
                inner.clone()
            )
                .prop_map(|(f, a)| format!("{f}({a})")),
            (prop::sample::select(vec!["pow", "atan2", "min", "max"]), inner.clone(), inner)
                .prop_map(|(f, a, b)| format!("{f}({a}, {b})")),
        ]
    })
}

/// Same value, NaN included.
fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// Parse, evaluate with `vars`, compile, print for FreeFEM, re-parse the print: no panic, and
/// every form of the expression gives the same value.
fn check_expr(src: &str, vars: &BTreeMap<String, f64>) -> Result<(), TestCaseError> {
    let e = match Expr::parse(src) {
        Ok(e) => e,
        Err(err) => return says_something(&err),
    };
    let lookup = |n: &str| vars.get(n).copied();
    let names: Vec<String> = e.variables().into_iter().collect();
    let all_known = names.iter().all(|n| vars.contains_key(n));
    match e.eval(&lookup) {
        Ok(v) => {
            prop_assert!(all_known);
            let slots: Vec<&str> = names.iter().map(String::as_str).collect();
            let values: Vec<f64> = names.iter().map(|n| vars[n]).collect();
            let c = e.compile(&slots).expect("every variable has a slot");
            prop_assert!(same(c.eval(&values), v), "compiled {} vs {v} for {src}", c.eval(&values));
            let again = Expr::parse(&e.to_string());
            prop_assert!(again.is_ok(), "print of {src} does not re-parse: {}: {:?}", e, again);
            let w = again.expect("checked").eval(&lookup).expect("same variables");
            prop_assert!(same(w, v), "re-parsed {w} vs {v} for {src}");
        }
        Err(err) => {
            prop_assert!(!all_known);
            says_something(&err)?;
        }
    }
    let ff = e.to_freefem(&|n| format!("v{}", n.len()));
    prop_assert!(!ff.is_empty());
    Ok(())
}

fn variables() -> impl Strategy<Value = BTreeMap<String, f64>> {
    prop::collection::btree_map(
        prop::sample::select(vec!["s", "t", "k", "omega0", "x", "nan"]).prop_map(String::from),
        float(),
        0..6,
    )
}

proptest! {
    #![proptest_config(config())]

    /// Arbitrary strings, strings of the language's characters, and deep nesting (up to 2·10⁴
    /// levels, far beyond the parser's bound; without it, 2·10³ nested parentheses overflowed
    /// the 2 MiB stack of a test thread).
    #[test]
    fn expressions_take_any_text(
        src in prop_oneof![
            2 => any::<String>(),
            2 => "[-+*/^(),. 0-9eEsSt_a-z]{0,80}",
            1 => (prop::sample::select(vec!["(", "-", "+", "sin(", "1+", "2^", "max(1,"]), 1usize..20_000, any::<bool>())
                .prop_map(|(open, n, close)| {
                    let closing = if close && open.ends_with('(') { ")".repeat(n) } else { String::new() };
                    format!("{}s{closing}", open.repeat(n))
                }),
        ],
        vars in variables(),
    ) {
        check_expr(&src, &vars)?;
    }

    /// Well-formed expressions: they parse, and every form evaluates alike.
    #[test]
    fn expressions_generated_well_formed(src in expression(), vars in variables()) {
        prop_assert!(Expr::parse(&src).is_ok() || src.len() > 400, "{src}: {:?}", Expr::parse(&src));
        check_expr(&src, &vars)?;
    }
}

// ------------------------------------------------------------------------------ CSV readers

/// A valid recording: `frames` × `nodes` rows, in a shuffled order.
fn recording_text(frames: usize, nodes: usize, order: &[Index]) -> String {
    let mut rows: Vec<String> = (0..frames)
        .flat_map(|f| (0..nodes).map(move |i| format!("{f},{i},{:e},{:e},{:e}", 1e-5 * f as f64, 0.0, 1e-4 * i as f64)))
        .collect();
    let n = rows.len();
    for (k, ix) in order.iter().enumerate() {
        rows.swap(k % n, ix.index(n));
    }
    format!("{}\n{}\n", RECORDING_HEADER.join(","), rows.join("\n"))
}

/// Text edits: replace, insert or delete a short run of characters, duplicate or drop a line.
#[derive(Clone, Debug)]
enum Edit {
    Replace(Index, String),
    Insert(Index, String),
    Delete(Index, usize),
    DuplicateLine(Index),
    DropLine(Index),
}

fn edit() -> impl Strategy<Value = Edit> {
    let piece = prop_oneof![
        "[-0-9,.eE\n ]{0,6}",
        prop::sample::select(vec![
            "18446744073709551615",
            "18446744073709551616",
            "1000000000000",
            "-1",
            "nan",
            "inf",
            "1e999",
            ",",
            "\n",
            "\"",
            "0,0,0,0,0",
        ])
        .prop_map(String::from),
        any::<String>(),
    ];
    prop_oneof![
        (any::<Index>(), piece.clone()).prop_map(|(i, s)| Edit::Replace(i, s)),
        (any::<Index>(), piece).prop_map(|(i, s)| Edit::Insert(i, s)),
        (any::<Index>(), 1usize..8).prop_map(|(i, n)| Edit::Delete(i, n)),
        any::<Index>().prop_map(Edit::DuplicateLine),
        any::<Index>().prop_map(Edit::DropLine),
    ]
}

/// `text` with `edits` applied (on character boundaries).
fn edited(text: &str, edits: &[Edit]) -> String {
    let mut s = text.to_string();
    for e in edits {
        let chars: Vec<char> = s.chars().collect();
        let at = |i: &Index| i.index(chars.len() + 1);
        let join =
            |a: &[char], mid: &str, b: &[char]| a.iter().collect::<String>() + mid + &b.iter().collect::<String>();
        s = match e {
            Edit::Replace(i, p) => {
                let k = at(i);
                let end = (k + p.chars().count().max(1)).min(chars.len());
                join(&chars[..k], p, &chars[end..])
            }
            Edit::Insert(i, p) => join(&chars[..at(i)], p, &chars[at(i)..]),
            Edit::Delete(i, n) => {
                let k = at(i);
                join(&chars[..k], "", &chars[(k + n).min(chars.len())..])
            }
            Edit::DuplicateLine(i) | Edit::DropLine(i) => {
                let mut lines: Vec<&str> = s.lines().collect();
                if lines.is_empty() {
                    continue;
                }
                let k = i.index(lines.len());
                if matches!(e, Edit::DuplicateLine(_)) {
                    lines.insert(k, lines[k]);
                } else {
                    lines.remove(k);
                }
                lines.join("\n")
            }
        };
    }
    s
}

fn write(path: &Path, bytes: &[u8]) {
    std::fs::write(path, bytes).expect("scratch file");
}

proptest! {
    #![proptest_config(config())]

    /// Valid recordings edited, and arbitrary text under a valid header.
    #[test]
    fn recording_csv_reader_takes_any_file(
        (frames, nodes) in (1usize..5, 1usize..6),
        order in prop::collection::vec(any::<Index>(), 0..6),
        edits in prop::collection::vec(edit(), 0..4),
        raw in prop_oneof![Just(None), any::<String>().prop_map(Some)],
    ) {
        let text = match raw {
            Some(body) => format!("{}\n{body}", RECORDING_HEADER.join(",")),
            None => edited(&recording_text(frames, nodes, &order), &edits),
        };
        let path = scratch("rec.csv");
        write(&path, text.as_bytes());
        match read_recording(&path, 0.04) {
            Ok(clip) => {
                // CSV ends a record at \n, \r or both: at most this many data rows.
                let rows = text.split(['\n', '\r']).count().saturating_sub(1);
                prop_assert!(clip.frame_count() * clip.node_count() <= rows);
                prop_assert!(clip.frames.iter().all(|f| f.len() == clip.node_count() && f.len() >= 3));
                prop_assert!(clip.frames.iter().flatten().all(|p| p.iter().all(|c| c.is_finite())));
                prop_assert!(clip.length_m > 0.0);
            }
            Err(e) => says_something(&e)?,
        }
    }

    /// `data.csv` of a small mesh, edited, and arbitrary bytes.
    #[test]
    fn data_csv_reader_takes_any_file(
        elements in 2usize..6,
        edits in prop::collection::vec(edit(), 0..4),
        raw in prop_oneof![3 => Just(None), 1 => prop::collection::vec(any::<u8>(), 0..300).prop_map(Some)],
    ) {
        let mesh = Mesh::new(1e-3, elements);
        let good: String = std::iter::once(DATA_HEADER.join(","))
            .chain((0..mesh.nodes()).map(|i| {
                let s = mesh.node_s(i);
                format!("{s:.16e},{:.16e},0,{s:.16e},0,{:.16e},0", 1e-5 * i as f64, 0.1 * i as f64)
            }))
            .collect::<Vec<_>>()
            .join("\n");
        let bytes = raw.unwrap_or_else(|| edited(&good, &edits).into_bytes());
        let path = scratch("data.csv");
        write(&path, &bytes);
        match read_data(&path, &mesh) {
            Ok(d) => {
                prop_assert_eq!(d.s.len(), mesh.nodes());
                prop_assert!(d.x.iter().chain(&d.alpha).all(|v| v.iter().all(|c| c.is_finite())));
            }
            Err(e) => says_something(&e)?,
        }
    }
}

// ------------------------------------------------------------------------------ NPY

/// Edits of a valid `.npy` file: its bytes, its header text, its shape, its header length.
#[derive(Clone, Debug)]
enum NpyEdit {
    Byte(Index, u8),
    Truncate(Index),
    Append(Vec<u8>),
    Shape(Vec<u64>),
    HeaderText(String),
    HeaderLen(u32),
    Version(u8),
}

fn npy_edit() -> impl Strategy<Value = NpyEdit> {
    let dim = prop_oneof![0u64..8, any::<u64>(), Just(u64::MAX), Just(1 << 32), Just(1_000_000_000_000)];
    prop_oneof![
        (any::<Index>(), any::<u8>()).prop_map(|(i, b)| NpyEdit::Byte(i, b)),
        any::<Index>().prop_map(NpyEdit::Truncate),
        prop::collection::vec(any::<u8>(), 0..24).prop_map(NpyEdit::Append),
        prop::collection::vec(dim, 0..5).prop_map(NpyEdit::Shape),
        prop_oneof![
            "\\{[ 'a-z_:,()0-9<>fTrueFals]{0,80}\\}",
            Just("{'descr': '<f8', 'fortran_order': True, 'shape': (2, 3), }".to_string()),
            Just("{'descr': '>f8', 'fortran_order': False, 'shape': (2, 3), }".to_string()),
            Just("{'descr': '<f8', 'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }".to_string()),
            any::<String>(),
        ]
        .prop_map(NpyEdit::HeaderText),
        any::<u32>().prop_map(NpyEdit::HeaderLen),
        any::<u8>().prop_map(NpyEdit::Version),
    ]
}

/// A version `major` file with `header` and `data` bytes as given (no checks).
fn npy_raw(major: u8, header: &str, data: &[u8], header_len: Option<u32>) -> Vec<u8> {
    let mut b = b"\x93NUMPY".to_vec();
    b.extend_from_slice(&[major, 0]);
    let len = header_len.unwrap_or(header.len() as u32);
    if major == 1 {
        b.extend_from_slice(&(len as u16).to_le_bytes());
    } else {
        b.extend_from_slice(&len.to_le_bytes());
    }
    b.extend_from_slice(header.as_bytes());
    b.extend_from_slice(data);
    b
}

fn npy_edited(frames: usize, cols: usize, e: &NpyEdit) -> Vec<u8> {
    let data: Vec<f64> = (0..frames * cols).map(|i| 0.01 * i as f64).collect();
    let mut b = npy_bytes(&[frames, cols], &data);
    let body: Vec<u8> = data.iter().flat_map(|v| v.to_le_bytes()).collect();
    let good_header = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': ({frames}, {cols}), }}\n");
    match e {
        NpyEdit::Byte(i, v) => {
            let k = i.index(b.len());
            b[k] = *v;
        }
        NpyEdit::Truncate(i) => b.truncate(i.index(b.len() + 1)),
        NpyEdit::Append(extra) => b.extend_from_slice(extra),
        NpyEdit::Shape(dims) => {
            let dims: Vec<String> = dims.iter().map(u64::to_string).collect();
            let h = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': ({},), }}\n", dims.join(", "));
            b = npy_raw(1, &h, &body, None);
        }
        NpyEdit::HeaderText(h) => b = npy_raw(3, h, &body, None),
        NpyEdit::HeaderLen(n) => b = npy_raw(2, &good_header, &body, Some(*n)),
        NpyEdit::Version(v) => b = npy_raw(*v, &good_header, &body, None),
    }
    b
}

proptest! {
    #![proptest_config(config())]

    /// Random bytes, and valid files with one edit: parsed from memory, and read from a file as
    /// a kymogram and as a recording.
    #[test]
    fn npy_reader_takes_any_bytes(
        (frames, cols) in (0usize..4, 0usize..7),
        edit in npy_edit(),
        raw in prop_oneof![3 => Just(None), 1 => prop::collection::vec(any::<u8>(), 0..200).prop_map(Some)],
    ) {
        let bytes = raw.unwrap_or_else(|| npy_edited(frames, cols, &edit));
        match parse_npy(&bytes) {
            Ok(a) => {
                let count = a.shape.iter().try_fold(1usize, |p, &n| p.checked_mul(n));
                prop_assert_eq!(count, Some(a.data.len()));
                prop_assert!(a.data.len() * 8 <= bytes.len());
            }
            Err(reason) => prop_assert!(!reason.is_empty()),
        }
        let path = scratch("k.npy");
        write(&path, &bytes);
        match kymogram_rows(&path) {
            Ok(rows) => prop_assert!(rows.iter().flatten().all(|a| a.is_finite()) && !rows.is_empty()),
            Err(e) => says_something(&e)?,
        }
        let path = scratch("rec.npy");
        write(&path, &bytes);
        match read_recording(&path, 0.04) {
            Ok(clip) => prop_assert!(clip.node_count() >= 3 && clip.length_m > 0.0),
            Err(e) => says_something(&e)?,
        }
    }
}
