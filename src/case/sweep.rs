//! Parameter sweeps (`cosserat sweep`): `--set key=v1,v2,…` specifications and their
//! cartesian product of cases. Each value is written into the case file's own table (e.g.
//! `lambda_d` → `inverse.lambda_d`, `elements` → `rod.elements`) and the whole case is
//! validated again, so a swept value meets exactly the rules, and reaches the solvers by
//! exactly the path, of a value written in the file.
use super::published::Setting;
use super::raw::RawCase;
use super::validate::Validator;
use super::{Analysis, Case, CaseError, RodLength};

/// Errors of sweep specifications.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    #[error("--set `{0}`: expected key=value[,value…]")]
    Syntax(String),
    #[error("--set {key}: `{value}` is not a number")]
    NotANumber { key: String, value: String },
    #[error("--set {key}: {reason}")]
    Invalid { key: String, reason: String },
    #[error("--set {key}: unknown parameter for case `{case}` (known: {known})")]
    UnknownKey { key: String, case: String, known: String },
    #[error("--set {0} given twice")]
    Duplicate(String),
    /// `value`: the value as given the second time, with the first spelling when it differs
    #[error("--set {key}: value {value} given twice: both runs would write one folder")]
    DuplicateValue { key: String, value: String },
}

/// One swept parameter and its values.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepParam {
    pub key: String,
    pub values: Vec<SweepValue>,
}

/// A swept value: a number, or a word of a key that takes one of a few words
/// (`quadrature = selective|full|reduced|midpoint|gauss2`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(untagged)]
pub enum SweepValue {
    Number(f64),
    Word(String),
}

impl SweepValue {
    /// The number, if it is one.
    pub fn number(&self) -> Option<f64> {
        match self {
            SweepValue::Number(v) => Some(*v),
            SweepValue::Word(_) => None,
        }
    }
}

impl std::fmt::Display for SweepValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SweepValue::Number(v) => f.write_str(&fmt_value(*v)),
            SweepValue::Word(w) => f.write_str(w),
        }
    }
}

impl From<f64> for SweepValue {
    fn from(v: f64) -> Self {
        SweepValue::Number(v)
    }
}

/// A parameter a sweep can set: its name on the command line, its table and key in the case
/// file (`index`: the entry of an array), and whether it is a count.
struct Key {
    name: &'static str,
    table: &'static str,
    key: &'static str,
    index: Option<usize>,
    count: bool,
    /// a key that takes one of these words instead of a number
    words: Option<&'static [&'static str]>,
}

const fn key(name: &'static str, table: &'static str, key: &'static str) -> Key {
    Key { name, table, key, index: None, count: false, words: None }
}
const fn count(name: &'static str, table: &'static str, key: &'static str) -> Key {
    Key { name, table, key, index: None, count: true, words: None }
}
const fn entry(name: &'static str, key: &'static str, index: usize) -> Key {
    Key { name, table: "inverse", key, index: Some(index), count: false, words: None }
}
/// The quadrature scheme (`solver.quadrature`, D4): ours, or the paper's scheme with one rule.
const QUADRATURE: Key = Key {
    name: "quadrature",
    table: "solver",
    key: "quadrature",
    index: None,
    count: false,
    words: Some(&["selective", "full", "reduced", "midpoint", "gauss2"]),
};
/// `solver.certificate_tolerance` (docs/certificate.md).
const CERTIFICATE_TOLERANCE: Key = key("certificate_tolerance", "solver", "certificate_tolerance");

const INVERSE_KEYS: &[Key] = &[
    key("lambda_g", "inverse", "lambda_g"),
    key("lambda_f", "inverse", "lambda_f"),
    key("lambda_l", "inverse", "lambda_l"),
    key("lambda_d", "inverse", "lambda_d"),
    entry("lambda_kappa1", "lambda_kappa", 0),
    entry("lambda_kappa2", "lambda_kappa", 1),
    entry("lambda_kappa3", "lambda_kappa", 2),
    entry("lambda_omega1", "lambda_omega", 0),
    entry("lambda_omega2", "lambda_omega", 1),
    entry("lambda_omega3", "lambda_omega", 2),
    key("relaxation", "solver", "relaxation"),
    key("warm_start_tolerance", "solver", "warm_start_tolerance"),
    key("tolerance", "solver", "tolerance"),
    count("max_iterations", "solver", "max_iterations"),
    count("elements", "rod", "elements"),
    key("stabilisation", "inverse", "stabilisation"),
    QUADRATURE,
    CERTIFICATE_TOLERANCE,
];
const STATIC_KEYS: &[Key] = &[
    key("relaxation", "solver", "relaxation"),
    key("tolerance", "solver", "tolerance"),
    count("max_iterations", "solver", "max_iterations"),
    count("continuation_steps", "solver", "continuation_steps"),
    count("elements", "rod", "elements"),
    QUADRATURE,
    CERTIFICATE_TOLERANCE,
];
const DYNAMIC_KEYS: &[Key] = &[
    key("tolerance", "solver", "tolerance"),
    count("max_iterations", "solver", "max_iterations"),
    count("steps", "time", "steps"),
    count("elements", "rod", "elements"),
    QUADRATURE,
    CERTIFICATE_TOLERANCE,
];

fn keys(case: &Case) -> &'static [Key] {
    match case.analysis {
        Analysis::Inverse(_) => INVERSE_KEYS,
        Analysis::Static(_) => STATIC_KEYS,
        Analysis::Dynamic(_) => DYNAMIC_KEYS,
    }
}

/// Parameters a sweep can set on `case`.
pub fn known_keys(case: &Case) -> Vec<&'static str> {
    keys(case).iter().map(|k| k.name).collect()
}

/// Parse `key=v1,v2,…`; each value once (equal numbers, e.g. `10` and `1e1`, are one value).
/// A value that is not a number is a word (`quadrature=midpoint`), checked against the key
/// when the grid is applied to a case.
pub fn parse_set(spec: &str) -> Result<SweepParam, SweepError> {
    let (key, values) = spec.split_once('=').ok_or_else(|| SweepError::Syntax(spec.into()))?;
    let key = key.trim().to_string();
    if key.is_empty() || values.trim().is_empty() {
        return Err(SweepError::Syntax(spec.into()));
    }
    let mut parsed: Vec<(SweepValue, &str)> = Vec::new();
    for v in values.split(',').map(str::trim) {
        let x = match v.parse::<f64>() {
            Ok(x) if x.is_finite() => SweepValue::Number(x),
            Ok(_) => return Err(SweepError::NotANumber { key: key.clone(), value: v.into() }),
            Err(_) if !v.is_empty() && v.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') => {
                SweepValue::Word(v.to_string())
            }
            Err(_) => return Err(SweepError::NotANumber { key: key.clone(), value: v.into() }),
        };
        if let Some((_, first)) = parsed.iter().find(|(y, _)| *y == x) {
            let value = if *first == v { format!("`{v}`") } else { format!("`{v}` (= `{first}`)") };
            return Err(SweepError::DuplicateValue { key, value });
        }
        parsed.push((x, v));
    }
    Ok(SweepParam { key, values: parsed.into_iter().map(|p| p.0).collect() })
}

impl Case {
    /// The case with the given parameters set (command-line names, see [`known_keys`]),
    /// validated again as a whole.
    pub fn with_values(&self, values: &[(&str, SweepValue)]) -> Result<Case, SweepError> {
        let label = values.iter().map(|v| v.0).collect::<Vec<_>>().join(", ");
        self.revalidated(&label, |table| {
            for (name, v) in values {
                let name = *name;
                let k = keys(self).iter().find(|k| k.name == name).ok_or_else(|| SweepError::UnknownKey {
                    key: name.into(),
                    case: self.name.clone(),
                    known: known_keys(self).join(", "),
                })?;
                set(table, k, v)?;
            }
            Ok(())
        })
    }

    /// The case with any keys of its file set, by dotted path (`"clip.frames"`,
    /// `"inverse.lambda_omega"`, `"solver.max_iterations"`) to TOML values, validated again
    /// as a whole. Missing tables are created; a path through a non-table is an error.
    /// `solver.method = "fixed_point"` drops the case's Newton-only `solver.warm_start_tolerance`.
    pub fn with_overrides(&self, overrides: &[(String, toml::Value)]) -> Result<Case, SweepError> {
        let label = overrides.iter().map(|o| o.0.as_str()).collect::<Vec<_>>().join(", ");
        self.revalidated(&label, |table| {
            for (path, value) in overrides {
                let parts: Vec<&str> = path.split('.').collect();
                let (last, tables) = parts
                    .split_last()
                    .filter(|(l, _)| !l.is_empty())
                    .ok_or_else(|| SweepError::Invalid { key: path.clone(), reason: "empty key".into() })?;
                let mut t = &mut *table;
                for part in tables {
                    t = t
                        .entry(part.to_string())
                        .or_insert_with(|| toml::Value::Table(toml::Table::new()))
                        .as_table_mut()
                        .ok_or_else(|| SweepError::Invalid {
                            key: path.clone(),
                            reason: format!("`{part}` is not a table"),
                        })?;
                }
                t.insert(last.to_string(), value.clone());
            }
            // `solver.method = "fixed_point"` over a Newton case: its warm start (used by Newton
            // only, and refused with the fixed point) goes with it, unless set here too.
            let to_fixed_point =
                overrides.iter().any(|(k, v)| k == "solver.method" && v.as_str() == Some("fixed_point"));
            if to_fixed_point && !overrides.iter().any(|(k, _)| k == "solver.warm_start_tolerance") {
                if let Some(s) = table.get_mut("solver").and_then(|s| s.as_table_mut()) {
                    s.remove("warm_start_tolerance");
                }
            }
            Ok(())
        })
    }

    /// The shorter variant of a benchmark that `cargo test` runs (`[reference.short]`, keys of
    /// [`known_keys`]), validated as a whole; `None` when the case has none.
    pub fn short_variant(&self) -> Result<Option<Case>, SweepError> {
        let short = &self.checks.published.short;
        if short.is_empty() {
            return Ok(None);
        }
        let values: Vec<(&str, SweepValue)> = short
            .iter()
            .map(|(k, v)| {
                let v = match v {
                    Setting::Number(x) => SweepValue::Number(*x),
                    Setting::Word(w) => SweepValue::Word(w.clone()),
                };
                (k.as_str(), v)
            })
            .collect();
        let mut c = self.with_values(&values)?;
        c.name = format!("{} (short)", self.name);
        Ok(Some(c))
    }

    /// `[reference.short]` names keys of [`known_keys`] for this case's analysis (checked when
    /// the file is read; the values when the variant is made, [`Case::short_variant`]).
    pub(super) fn short_variant_keys(&self, path: &std::path::Path) -> Result<(), CaseError> {
        let known = known_keys(self);
        match self.checks.published.short.iter().find(|(k, _)| !known.contains(&k.as_str())) {
            Some((k, _)) => Err(CaseError::Invalid {
                path: path.to_path_buf(),
                key: format!("reference.short.{k}"),
                reason: format!(
                    "not a setting of this case's shorter variant (the keys of `cosserat sweep --set`: {})",
                    known.join(", ")
                ),
            }),
            None => Ok(()),
        }
    }

    /// Apply `edit` to a copy of the case file's tables and validate the result (errors name
    /// `label`).
    fn revalidated(
        &self,
        label: &str,
        edit: impl FnOnce(&mut toml::Table) -> Result<(), SweepError>,
    ) -> Result<Case, SweepError> {
        let (mut table, path) = self.origin.raw.clone().ok_or_else(|| SweepError::Invalid {
            key: label.to_string(),
            reason: format!("case `{}` was not read from TOML", self.name),
        })?;
        edit(&mut table)?;
        let invalid = |reason: String| SweepError::Invalid { key: label.to_string(), reason };
        let raw: RawCase =
            toml::Value::Table(table.clone()).try_into().map_err(|e: toml::de::Error| invalid(e.to_string()))?;
        let mut case = Validator::new(&path).case(raw, &self.name).map_err(|e| match e {
            CaseError::Invalid { key, reason, .. } => invalid(format!("{reason} (case file key `{key}`)")),
            other => invalid(other.to_string()),
        })?;
        case.origin.source = self.origin.source.clone();
        case.origin.raw = Some((table, path));
        // a body length estimated from the recording stays with the case while its length does
        // (`rod.length_m = "from_data"` resolved: the tables hold the estimate as a number)
        if case.rod.length == RodLength::Given && case.mesh.length_m == self.mesh.length_m {
            if let RodLength::FromData(Some(b)) = self.rod.length {
                case.rod.length = RodLength::FromData(Some(b));
            }
        }
        Ok(case)
    }
}

/// Write `v` at `k` in the case file's tables (an integer for a count, a string for a word).
fn set(table: &mut toml::Table, k: &Key, v: &SweepValue) -> Result<(), SweepError> {
    let invalid = |reason: String| SweepError::Invalid { key: k.name.into(), reason };
    let value = match (v, k.words) {
        (SweepValue::Word(w), Some(words)) if words.contains(&w.as_str()) => toml::Value::String(w.clone()),
        (_, Some(words)) => return Err(invalid(format!("must be one of {}, got {v}", words.join(", ")))),
        (SweepValue::Word(w), None) => return Err(invalid(format!("`{w}` is not a number"))),
        (SweepValue::Number(v), None) if k.count => {
            if !(*v >= 1.0 && v.fract() == 0.0 && *v < 1e9) {
                return Err(invalid(format!("must be a positive integer, got {v}")));
            }
            toml::Value::Integer(*v as i64)
        }
        (SweepValue::Number(v), None) => toml::Value::Float(*v),
    };
    let t =
        table.entry(k.table).or_insert_with(|| toml::Value::Table(toml::Table::new())).as_table_mut().ok_or_else(
            || SweepError::Invalid { key: k.name.into(), reason: format!("[{}] is not a table", k.table) },
        )?;
    match k.index {
        None => {
            t.insert(k.key.into(), value);
        }
        Some(i) => {
            let zeros = || toml::Value::Array(vec![toml::Value::Float(0.0); 3]);
            let a = t.entry(k.key).or_insert_with(zeros).as_array_mut().ok_or_else(|| SweepError::Invalid {
                key: k.name.into(),
                reason: format!("{}.{} is not an array", k.table, k.key),
            })?;
            match a.get_mut(i) {
                Some(slot) => *slot = value,
                None => {
                    return Err(SweepError::Invalid {
                        key: k.name.into(),
                        reason: format!("{}.{} has no entry {i}", k.table, k.key),
                    })
                }
            }
        }
    }
    Ok(())
}

/// One point of the cartesian product: `(key, value)` in the order of the `--set` options.
pub type Point = Vec<(String, SweepValue)>;

/// The cartesian product of the specifications (first key varies slowest), each point
/// applied to `case` and validated.
pub fn product(case: &Case, params: &[SweepParam]) -> Result<Vec<(Point, Case)>, SweepError> {
    for (i, p) in params.iter().enumerate() {
        if params[..i].iter().any(|q| q.key == p.key) {
            return Err(SweepError::Duplicate(p.key.clone()));
        }
        if !known_keys(case).contains(&p.key.as_str()) {
            return Err(SweepError::UnknownKey {
                key: p.key.clone(),
                case: case.name.clone(),
                known: known_keys(case).join(", "),
            });
        }
    }
    let mut points: Vec<Point> = vec![Vec::new()];
    for p in params {
        points = points
            .into_iter()
            .flat_map(|pt| {
                p.values.iter().map(move |v| {
                    let mut q = pt.clone();
                    q.push((p.key.clone(), v.clone()));
                    q
                })
            })
            .collect();
    }
    points
        .into_iter()
        .map(|pt| {
            let values: Vec<(&str, SweepValue)> = pt.iter().map(|(k, v)| (k.as_str(), v.clone())).collect();
            let mut c = case.with_values(&values)?;
            c.name = run_name(case, &pt);
            Ok((pt, c))
        })
        .collect()
}

/// Folder name of a run: `<key>=<value>` joined with `_`, e.g. `lambda_l=1e-20`.
pub fn run_name(case: &Case, point: &Point) -> String {
    if point.is_empty() {
        return case.name.clone();
    }
    point.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join("_")
}

/// Shortest exact decimal of a value (`1e-20`, `0.5`, `100`).
pub fn fmt_value(v: f64) -> String {
    let plain = format!("{v}");
    let sci = format!("{v:e}");
    if sci.len() < plain.len() {
        sci
    } else {
        plain
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn case(name: &str) -> Case {
        Case::from_file(&Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("cases/{name}.toml"))).expect("case")
    }

    #[test]
    fn product_is_cartesian_and_applied() {
        let params = vec![parse_set("lambda_l=1e-20,1e3").unwrap(), parse_set("lambda_kappa3=0,1e-10,1").unwrap()];
        let pts = product(&case("inverse_bend"), &params).unwrap();
        assert_eq!(pts.len(), 6);
        assert_eq!(pts[0].1.name, "lambda_l=1e-20_lambda_kappa3=0");
        let Analysis::Inverse(ref s) = pts[5].1.analysis else { panic!() };
        let w = s.params.weights;
        assert_eq!((w.lambda_l, w.lambda_kappa[2], w.lambda_kappa[1]), (1e3, 1.0, 0.0));
    }

    /// A swept value takes the path of a value in the file: the whole case is derived again.
    #[test]
    fn swept_values_are_validated_and_derived_like_the_file() {
        let c = case("worm_roll_3d");
        let (_, c63) = product(&c, &[parse_set("elements=63").unwrap()]).unwrap().remove(0);
        assert_eq!((c63.mesh.nodes(), c63.roll_clip_params().unwrap().nodes), (64, 64));
        let (_, d) = product(&case("cantilever_dynamic"), &[parse_set("steps=10").unwrap()]).unwrap().remove(0);
        let Analysis::Dynamic(p) = d.analysis else { panic!() };
        assert_eq!(p.steps, 10);
    }

    /// Dotted overrides reach the same validator: a clip's frame range and a weight vector.
    #[test]
    fn overrides_by_dotted_path() {
        let c = case("inverse_bend_twist");
        let v = |x: f64| toml::Value::Float(x);
        let o = c
            .with_overrides(&[("inverse.lambda_kappa".into(), toml::Value::Array(vec![v(0.0), v(1e-3), v(2.0)]))])
            .unwrap();
        assert_eq!(o.inverse().unwrap().params.weights.lambda_kappa, nalgebra::Vector3::new(0.0, 1e-3, 2.0));
        let e = c.with_overrides(&[("inverse.lambda_kappa".into(), v(1.0))]).unwrap_err();
        assert!(e.to_string().contains("inverse.lambda_kappa"), "{e}");
        let e = c.with_overrides(&[("description.x".into(), v(1.0))]).unwrap_err();
        assert!(e.to_string().contains("not a table"), "{e}");
    }

    #[test]
    fn bad_specifications_are_errors() {
        assert!(matches!(parse_set("lambda_l"), Err(SweepError::Syntax(_))));
        assert!(matches!(parse_set("lambda_l=1,x-y"), Err(SweepError::NotANumber { .. })));
        // a word is taken by a key of words only
        let e = product(&case("inverse_bend"), &[parse_set("lambda_l=1,x").unwrap()]).unwrap_err();
        assert!(e.to_string().contains("`x` is not a number"), "{e}");
        let e = product(&case("inverse_bend"), &[parse_set("quadrature=gauss3").unwrap()]).unwrap_err();
        assert!(e.to_string().contains("must be one of selective, full, reduced, midpoint, gauss2"), "{e}");
        let q = product(&case("inverse_bend"), &[parse_set("quadrature=gauss2").unwrap()]).unwrap();
        assert_eq!(q[0].1.quadrature, crate::model::mesh::QuadratureScheme::Gauss2);
        assert_eq!(q[0].1.inverse().unwrap().params.stabilisation, 0.0);
        assert!(matches!(parse_set("lambda_l=nan"), Err(SweepError::NotANumber { .. })));
        let c = case("inverse_bend");
        assert!(matches!(product(&c, &[parse_set("lambda_q=1").unwrap()]), Err(SweepError::UnknownKey { .. })));
        let e = product(&c, &[parse_set("lambda_f=0").unwrap()]).unwrap_err();
        assert!(e.to_string().contains("must be > 0, got 0") && e.to_string().contains("inverse.lambda_f"), "{e}");
        assert!(matches!(product(&c, &[parse_set("elements=2.5").unwrap()]), Err(SweepError::Invalid { .. })));
        assert!(matches!(
            product(&c, &[parse_set("warm_start_tolerance=1e-3").unwrap()]),
            Err(SweepError::Invalid { .. })
        ));
        let twice = [parse_set("lambda_f=1").unwrap(), parse_set("lambda_f=2").unwrap()];
        assert!(matches!(product(&c, &twice), Err(SweepError::Duplicate(_))));
    }

    /// One value twice would run two points into one folder.
    #[test]
    fn a_value_given_twice_is_refused() {
        let e = parse_set("elements=10,10").unwrap_err();
        assert_eq!(e.to_string(), "--set elements: value `10` given twice: both runs would write one folder");
        let e = parse_set("lambda_l=1e-20, 5, 1.0e-20").unwrap_err();
        assert_eq!(
            e.to_string(),
            "--set lambda_l: value `1.0e-20` (= `1e-20`) given twice: both runs would write one folder"
        );
        assert_eq!(parse_set("elements=10,20").unwrap().values, vec![10.0.into(), 20.0.into()]);
    }
}
