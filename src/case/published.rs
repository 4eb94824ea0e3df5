//! Published values a case is checked against (`[[reference.values]]`): what is measured (a
//! [`Quantity`] of the vocabulary, parsed once here), the published number, the tolerance and
//! the source. `run` evaluates every row on its result (`engine::published`) and writes
//! them beside its metrics; `compare` does so for both engines; `tests/benchmarks.rs` runs every
//! case of `cases/benchmarks/` and asserts every row.
//!
//! The vocabulary is open: a family of quantities (`tip.…`, `node(s=…).…`, `metric.…`) is a
//! variant of [`Quantity`], a branch of [`Quantity::parse`], a row of [`VOCABULARY`] and a branch
//! of the evaluator (`engine::published::value`). A new family (a buckling load factor, a
//! natural frequency, a limit load) adds exactly these four.
use std::fmt;

/// The published values of a case and the shorter variant its test runs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Published {
    pub values: Vec<PublishedValue>,
    /// `[reference.short]`: settings (the keys of `cosserat sweep --set`) of the shorter
    /// variant `cargo test` runs (`Case::short_variant`); every row must pass there too
    /// (empty: the case itself)
    pub short: Vec<(String, Setting)>,
}

/// The value of a setting of `[reference.short]`: a number, or a word of a key that takes
/// words (`quadrature = "midpoint"`).
#[derive(Clone, Debug, PartialEq, serde::Deserialize)]
#[serde(untagged)]
pub enum Setting {
    Number(f64),
    Word(String),
}

/// One published value (`[[reference.values]]`).
#[derive(Clone, Debug, PartialEq)]
pub struct PublishedValue {
    pub quantity: Quantity,
    /// the published number, in the quantity's SI unit
    pub value: f64,
    pub tolerance: Tolerance,
    /// where the number is published (authors, year, journal, table or equation)
    pub source: String,
    pub note: Option<String>,
}

/// How far a computed value may lie from the published one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Tolerance {
    /// `|computed − published| ≤ tol`, in the quantity's unit (`tolerance_abs`)
    Absolute(f64),
    /// `|computed − published| ≤ tol · |published|` (`tolerance_rel`)
    Relative(f64),
}

impl Tolerance {
    /// The largest `|computed − published|` allowed, in the quantity's unit.
    pub fn bound(&self, published: f64) -> f64 {
        match *self {
            Tolerance::Absolute(t) => t,
            Tolerance::Relative(t) => t * published.abs(),
        }
    }
}

/// A Cartesian axis of the global frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    X,
    Y,
    Z,
}

impl Axis {
    pub const ALL: [Axis; 3] = [Axis::X, Axis::Y, Axis::Z];

    pub fn index(self) -> usize {
        self as usize
    }

    pub fn name(self) -> &'static str {
        ["x", "y", "z"][self.index()]
    }
}

/// A nodal field component: position, displacement from the reference configuration, or one
/// of the frame angles (α, β, γ) of eq. (1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeField {
    /// `x_m`, `y_m`, `z_m` [m]
    Position(Axis),
    /// `displacement_x_m`, … [m]
    Displacement(Axis),
    /// `alpha_rad`, `beta_rad`, `gamma_rad`: the angle of index 0, 1, 2 [rad]
    Angle(usize),
}

const ANGLES: [&str; 3] = ["alpha", "beta", "gamma"];

impl NodeField {
    /// Every field, in the order of the vocabulary.
    fn all() -> impl Iterator<Item = NodeField> {
        let pos = Axis::ALL.into_iter().map(NodeField::Position);
        let disp = Axis::ALL.into_iter().map(NodeField::Displacement);
        pos.chain(disp).chain((0..3).map(NodeField::Angle))
    }

    fn name(self) -> String {
        match self {
            NodeField::Position(a) => format!("{}_m", a.name()),
            NodeField::Displacement(a) => format!("displacement_{}_m", a.name()),
            NodeField::Angle(k) => format!("{}_rad", ANGLES[k]),
        }
    }

    fn parse(text: &str) -> Option<NodeField> {
        NodeField::all().find(|f| f.name() == text)
    }

    pub fn unit(self) -> &'static str {
        match self {
            NodeField::Angle(_) => "rad",
            _ => "m",
        }
    }
}

/// What a published value measures.
#[derive(Clone, Debug, PartialEq)]
pub enum Quantity {
    /// a field at the tip, s = L: `tip.y_m`, `tip.displacement_z_m`, `tip.beta_rad`
    Tip(NodeField),
    /// a field at reference arc length `s_m` [m], linearly interpolated between the nodes
    /// around it: `node(s=0.5).x_m`
    Node { s_m: f64, field: NodeField },
    /// a numeric key of `metrics.json`: `metric.elastica_rel_error`
    Metric(String),
}

/// One form of the vocabulary: how it is written, its unit and what it means (for error
/// messages, `--help`-like listings and the documentation, which a test keeps in step).
#[derive(Clone, Copy, Debug)]
pub struct Form {
    pub pattern: &'static str,
    pub unit: &'static str,
    pub meaning: &'static str,
}

/// Every family of quantities a published value may name.
pub const VOCABULARY: &[Form] = &[
    Form { pattern: "tip.x_m, tip.y_m, tip.z_m", unit: "m", meaning: "position of the tip (s = L)" },
    Form {
        pattern: "tip.displacement_x_m, tip.displacement_y_m, tip.displacement_z_m",
        unit: "m",
        meaning: "displacement of the tip from its reference position",
    },
    Form {
        pattern: "tip.alpha_rad, tip.beta_rad, tip.gamma_rad",
        unit: "rad",
        meaning: "frame angles (α, β, γ) of eq. (1) at the tip",
    },
    Form {
        pattern: "node(s=S).FIELD",
        unit: "m or rad",
        meaning: "any tip field at reference arc length S [m] (0 ≤ S ≤ L), linear between the nodes around it",
    },
    Form {
        pattern: "metric.KEY",
        unit: "as KEY",
        meaning: "any numeric key of the run's metrics.json (a single run, not a clip)",
    },
];

/// Why the text of a quantity is not one ([`Quantity::parse`]); each message ends with the
/// vocabulary.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum QuantityError {
    #[error("`{text}`: unknown field `{field}` (fields: {fields}); a quantity is one of: {}", vocabulary_in_words())]
    UnknownField { text: String, field: String, fields: String },
    #[error("`{text}`: write node(s=S).FIELD, S in metres; a quantity is one of: {}", vocabulary_in_words())]
    NodeSyntax { text: String },
    #[error(
        "`{text}`: the arc length `{s}` is not a number in metres; a quantity is one of: {}",
        vocabulary_in_words()
    )]
    ArcLength { text: String, s: String },
    #[error(
        "`{text}`: `{key}` is not a key of metrics.json (letters, digits, _); a quantity is one of: {}",
        vocabulary_in_words()
    )]
    MetricKey { text: String, key: String },
    #[error("`{text}` is not a quantity; a quantity is one of: {}", vocabulary_in_words())]
    NotAQuantity { text: String },
}

/// The vocabulary in one line, for error messages.
pub fn vocabulary_in_words() -> String {
    VOCABULARY.iter().map(|f| f.pattern).collect::<Vec<_>>().join("; ")
}

impl Quantity {
    /// Parse a quantity as written in a case file; `Err` says what is wrong and lists the
    /// vocabulary.
    pub fn parse(text: &str) -> Result<Quantity, QuantityError> {
        let t = text.trim();
        let family_end = t.find(['.', '(']).unwrap_or(t.len());
        let text = || t.to_string();
        let field = |f: &str| {
            NodeField::parse(f).ok_or_else(|| {
                let all: Vec<String> = NodeField::all().map(NodeField::name).collect();
                QuantityError::UnknownField { text: text(), field: f.to_string(), fields: all.join(", ") }
            })
        };
        match &t[..family_end] {
            "tip" if t[family_end..].starts_with('.') => Ok(Quantity::Tip(field(&t[family_end + 1..])?)),
            "node" => {
                let rest = &t[family_end..];
                let inner = rest.strip_prefix("(s=").and_then(|r| r.split_once(")."));
                let (s, f) = inner.ok_or_else(|| QuantityError::NodeSyntax { text: text() })?;
                let s_m = s
                    .trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| QuantityError::ArcLength { text: text(), s: s.to_string() })?;
                Ok(Quantity::Node { s_m, field: field(f)? })
            }
            "metric" if t[family_end..].starts_with('.') => {
                let key = &t[family_end + 1..];
                if key.is_empty() || !key.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                    return Err(QuantityError::MetricKey { text: text(), key: key.to_string() });
                }
                Ok(Quantity::Metric(key.to_string()))
            }
            _ => Err(QuantityError::NotAQuantity { text: text() }),
        }
    }

    /// The SI unit of the quantity (a metric's: from its key's suffix, `"1"` for a number).
    pub fn unit(&self) -> &'static str {
        match self {
            Quantity::Tip(f) | Quantity::Node { field: f, .. } => f.unit(),
            Quantity::Metric(key) => metric_unit(key),
        }
    }
}

/// The unit a metric's name carries (`_m`, `_rad`, `_s`, `_rad_per_s`; a count or ratio has none).
fn metric_unit(key: &str) -> &'static str {
    const SUFFIXES: [(&str, &str); 6] = [
        ("_m", "m"),
        ("_rad", "rad"),
        ("_s", "s"),
        ("_m05", "m^0.5"),
        ("_n_per_m05", "N/m^0.5"),
        ("_rad_per_s", "rad/s"),
    ];
    SUFFIXES.iter().rev().find(|(suffix, _)| key.ends_with(suffix)).map_or("1", |(_, unit)| unit)
}

impl fmt::Display for Quantity {
    /// The canonical text of the quantity (what [`Quantity::parse`] reads back).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Quantity::Tip(field) => write!(f, "tip.{}", field.name()),
            Quantity::Node { s_m, field } => write!(f, "node(s={s_m}).{}", field.name()),
            Quantity::Metric(key) => write!(f, "metric.{key}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_form_parses_and_prints_back() {
        for text in [
            "tip.x_m",
            "tip.displacement_z_m",
            "tip.gamma_rad",
            "node(s=0.5).y_m",
            "node(s=0.001).beta_rad",
            "metric.elastica_rel_error",
        ] {
            let q = Quantity::parse(text).unwrap_or_else(|e| panic!("{text}: {e}"));
            assert_eq!(q.to_string(), text);
        }
        assert_eq!(Quantity::parse("tip.y_m").unwrap(), Quantity::Tip(NodeField::Position(Axis::Y)));
        assert_eq!(
            Quantity::parse(" node(s=2.5e-1).displacement_x_m ").unwrap(),
            Quantity::Node { s_m: 0.25, field: NodeField::Displacement(Axis::X) }
        );
        assert_eq!(Quantity::parse("tip.alpha_rad").unwrap(), Quantity::Tip(NodeField::Angle(0)));
    }

    /// A typo names what is wrong and lists the vocabulary.
    #[test]
    fn typos_are_refused_with_the_vocabulary() {
        for (text, words) in [
            ("tip.y", &["unknown field `y`", "displacement_x_m", "tip.x_m"][..]),
            ("tips.y_m", &["`tips.y_m` is not a quantity", "node(s=S).FIELD", "metric.KEY"]),
            ("node(0.5).x_m", &["node(s=S).FIELD"]),
            ("node(s=half).x_m", &["`half` is not a number"]),
            ("node(s=0.5)", &["node(s=S).FIELD"]),
            ("metric.", &["is not a key of metrics.json"]),
            ("metric.tip y", &["is not a key"]),
            ("tip", &["is not a quantity"]),
            ("", &["is not a quantity"]),
        ] {
            let e = Quantity::parse(text).unwrap_err().to_string();
            for w in words {
                assert!(e.contains(w), "{text}: `{e}` lacks `{w}`");
            }
        }
    }

    #[test]
    fn units_follow_the_quantity() {
        let unit = |t: &str| Quantity::parse(t).unwrap().unit();
        assert_eq!(unit("tip.z_m"), "m");
        assert_eq!(unit("node(s=0).gamma_rad"), "rad");
        assert_eq!(unit("metric.tip_max_abs_beta_rad"), "rad");
        assert_eq!(unit("metric.wall_time_s"), "s");
        assert_eq!(unit("metric.iterations"), "1");
        assert_eq!(unit("metric.tangent_misfit_m05"), "m^0.5");
        assert_eq!(unit("metric.force_l2_n_per_m05"), "N/m^0.5");
        assert_eq!(unit("metric.omega_1_rad_per_s"), "rad/s");
    }

    #[test]
    fn tolerance_bounds() {
        assert_eq!(Tolerance::Absolute(1e-3).bound(-5.0), 1e-3);
        assert_eq!(Tolerance::Relative(1e-2).bound(-5.0), 5e-2);
    }
}
