//! The inputs of `tests/fuzz.rs`: mutations of the committed case files, well-formed
//! expressions, valid recordings and `.npy` files and the edits applied to them.
use std::path::Path;
use std::sync::OnceLock;

use cosserat::engine::input::clip_files::RECORDING_HEADER;
use cosserat::io::npy::npy_bytes;
use proptest::prelude::*;
use proptest::sample::Index;
use toml::{Table, Value};

// ------------------------------------------------------------------------------ case files

/// The committed cases, as TOML tables.
pub fn committed_cases() -> &'static Vec<(String, Table)> {
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
pub enum Generated {
    Float(f64),
    Int(i64),
    Str(String),
    Bool(bool),
    Array(Vec<Generated>),
    Table,
}

pub fn float() -> impl Strategy<Value = f64> {
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

pub fn int() -> impl Strategy<Value = i64> {
    prop_oneof![
        any::<i64>(),
        0..2_000i64,
        prop::sample::select(vec![0, 1, 2, 3, 10, 11, -1, i64::MAX, i64::MIN, 5_000, 1_000_001, 1 << 40]),
    ]
}

pub fn text() -> impl Strategy<Value = String> {
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

pub fn generated() -> impl Strategy<Value = Generated> {
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
pub enum Mutation {
    /// replace a scalar by one of the same TOML type (most reach the validator: a value of
    /// another type is mostly refused by the serde layer already)
    SameType(Index, f64, i64, String, bool),
    /// replace the value (scalar, array or table) at a path
    Replace(Index, Generated),
    /// remove the entry at a path
    Delete(Index),
    /// add a key to a table (the key often an existing one of another table)
    Add(Index, String, Generated),
}

pub fn mutation() -> impl Strategy<Value = Mutation> {
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
        12 => (any::<Index>(), float(), int(), text(), any::<bool>())
            .prop_map(|(i, x, n, t, b)| Mutation::SameType(i, x, n, t, b)),
        4 => (any::<Index>(), generated()).prop_map(|(i, g)| Mutation::Replace(i, g)),
        2 => any::<Index>().prop_map(Mutation::Delete),
        2 => (any::<Index>(), key, generated()).prop_map(|(i, k, g)| Mutation::Add(i, k, g)),
    ]
}

/// A path into a TOML value: table keys and array indices.
#[derive(Clone, Debug)]
pub enum Seg {
    Key(String),
    At(usize),
}

/// Every path below `v` (tables, arrays and scalars), depth first.
pub fn paths(v: &Value, prefix: &mut Vec<Seg>, out: &mut Vec<Vec<Seg>>) {
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

pub fn get_mut<'a>(v: &'a mut Value, path: &[Seg]) -> Option<&'a mut Value> {
    path.iter().try_fold(v, |v, seg| match (seg, v) {
        (Seg::Key(k), Value::Table(t)) => t.get_mut(k),
        (Seg::At(i), Value::Array(a)) => a.get_mut(*i),
        _ => None,
    })
}

pub fn apply(root: &mut Value, m: &Mutation) {
    let mut all = Vec::new();
    paths(root, &mut Vec::new(), &mut all);
    if all.is_empty() {
        return;
    }
    match m {
        Mutation::SameType(i, x, n, t, b) => {
            let scalars: Vec<&Vec<Seg>> =
                all.iter().filter(|p| matches!(get_mut(root, p), Some(v) if !v.is_table() && !v.is_array())).collect();
            if scalars.is_empty() {
                return;
            }
            let path = scalars[i.index(scalars.len())].clone();
            if let Some(v) = get_mut(root, &path) {
                *v = match v {
                    Value::Float(_) => Value::Float(*x),
                    Value::Integer(_) => Value::Integer(*n),
                    Value::Boolean(_) => Value::Boolean(*b),
                    _ => Value::String(t.clone()),
                };
            }
        }
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

/// Well-formed expressions of s, t, two constants, pi and every function.
pub fn expression() -> impl Strategy<Value = String> {
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

/// A valid recording: `frames` × `nodes` rows, in a shuffled order.
pub fn recording_text(frames: usize, nodes: usize, order: &[Index]) -> String {
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
pub enum Edit {
    Replace(Index, String),
    Insert(Index, String),
    Delete(Index, usize),
    DuplicateLine(Index),
    DropLine(Index),
}

pub fn edit() -> impl Strategy<Value = Edit> {
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
pub fn edited(text: &str, edits: &[Edit]) -> String {
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

/// Edits of a valid `.npy` file: its bytes, its header text, its shape, its header length.
#[derive(Clone, Debug)]
pub enum NpyEdit {
    Byte(Index, u8),
    Truncate(Index),
    Append(Vec<u8>),
    Shape(Vec<u64>),
    HeaderText(String),
    HeaderLen(u32),
    Version(u8),
}

pub fn npy_edit() -> impl Strategy<Value = NpyEdit> {
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
pub fn npy_raw(major: u8, header: &str, data: &[u8], header_len: Option<u32>) -> Vec<u8> {
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

pub fn npy_edited(frames: usize, cols: usize, e: &NpyEdit) -> Vec<u8> {
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
