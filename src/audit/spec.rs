//! Audit specs (`cases/paper/*.toml`): TOML → serde structs (`deny_unknown_fields`) → one
//! validated [`Spec`] whose runs hold validated cases. One spec per figure, table or group of
//! claims of §5–6 of the paper:
//!
//! ```toml
//! title = "Findings (1)-(5) of §5.2 on the data of eq. (64)"
//! section = "§5.2"
//! paper_figures = "Figs. 9-11"
//!
//! [runs.ld]                                   # a run: a case, fixed overrides, a grid
//! case = "../inverse_bend.toml"               # relative to this file
//! set = { "solver.max_iterations" = 3000 }    # dotted keys of the case file
//! grid = { lambda_d = [1e-10, 1e-6, 1e-2, 1, 10] }   # `cosserat sweep --set` keys
//! quick_grid = { lambda_d = [1e-2, 10] }      # `--quick` (default: grid)
//! quick_set = { "clip.frames" = [0, 40] }     # `--quick` only, after `set`
//!
//! [[claims]]
//! id = "eq64-3"
//! where = "§5.2 (64), finding (3); Fig. 10"
//! statement = "converge stably with the regularisation parameter λd varying from 10¹ to 10⁻¹⁰"
//! paper = "converges for λd = 1e-10 … 1e1"
//! check = { kind = "converges", run = "ld" }
//! expect = "reproduced"
//! cause = "…"                                 # shown when the check fails (`{first_failing}` …: audit::cause)
//!
//! [[figures]]
//! file = "fig10.svg"
//! title = "Fig. 10: convergence against λd"
//! show = { kind = "convergence", run = "ld" }
//! ```
use crate::jobs::depth::Depth;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::Verdict;
use crate::case::sweep::{known_keys, SweepParam, SweepValue};
use crate::case::Case;
use crate::io::files::{read_capped_text, InputError};

/// Largest audit spec read [bytes]: 1 MiB, as a case file (`case::CASE_FILE_CAP_BYTES`); the
/// committed specs are 7–11 KiB.
pub const SPEC_FILE_CAP_BYTES: u64 = 1 << 20;

/// Errors at the spec-file boundary; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum SpecError {
    #[error(transparent)]
    Input(#[from] InputError),
    #[error("{path}: {message}")]
    Syntax { path: PathBuf, message: String },
    #[error("{path}: {what}: {reason}")]
    Invalid { path: PathBuf, what: String, reason: String },
    #[error("{path}: run `{run}`: case {case}")]
    Case {
        path: PathBuf,
        run: String,
        case: PathBuf,
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSpec {
    title: String,
    section: String,
    #[serde(default)]
    paper_figures: String,
    runs: BTreeMap<String, RawRun>,
    claims: Vec<RawClaim>,
    #[serde(default)]
    figures: Vec<PlotSpec>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRun {
    case: PathBuf,
    #[serde(default)]
    set: toml::Table,
    #[serde(default)]
    quick_set: toml::Table,
    #[serde(default)]
    grid: BTreeMap<String, Vec<f64>>,
    quick_grid: Option<BTreeMap<String, Vec<f64>>>,
    /// frames of a clip run kept in memory for posture figures
    #[serde(default)]
    keep_frames: Vec<usize>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawClaim {
    id: String,
    #[serde(rename = "where")]
    location: String,
    statement: String,
    paper: String,
    check: Check,
    expect: Verdict,
    #[serde(default)]
    if_fails: Option<Verdict>,
    #[serde(default)]
    if_partly: Option<Verdict>,
    cause: Option<String>,
    not_computable: Option<String>,
    substitute: Option<String>,
    figure: Option<String>,
    /// the check is weaker than the paper's words: why (the verdict is at best "differs")
    partial: Option<String>,
    /// a check of ours, not a claim of the paper (e.g. second order in time): its own table
    #[serde(default)]
    ours: bool,
}

/// A grid point by its values (`{ lambda_d = 1e-2 }`); empty: the run's only point.
pub type Selector = BTreeMap<String, f64>;

/// A run's point, or every point of the run when `at` is empty.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Ref {
    pub run: String,
    #[serde(default)]
    pub at: Selector,
}

/// The relation a claim checks on the runs' metrics.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Check {
    /// every point of `run` meets its stopping rule (partly: some points do)
    Converges { run: String },
    /// no point of `run` converges (the paper says the scheme fails there)
    /// (and of each run `with`: every weight the paper calls necessary, removed in turn)
    DoesNotConverge {
        run: String,
        #[serde(default)]
        with: Vec<String>,
    },
    /// `metric ≤ limit` at every selected point (of `run`, and every point of the runs `with`)
    Below {
        run: String,
        metric: String,
        limit: f64,
        #[serde(default)]
        at: Selector,
        #[serde(default)]
        with: Vec<String>,
    },
    /// `metric ≥ limit` at every selected point (of `run`, and every point of the runs `with`)
    Above {
        run: String,
        metric: String,
        limit: f64,
        #[serde(default)]
        at: Selector,
        #[serde(default)]
        with: Vec<String>,
    },
    /// `metric` increases (strictly) along the run's single grid key
    Increasing { run: String, metric: String },
    /// `metric(numerator) / metric(denominator) ≥ limit`
    RatioAbove { metric: String, numerator: Ref, denominator: Ref, limit: f64 },
    /// `metric(numerator) / metric(denominator) ≤ limit`
    RatioBelow { metric: String, numerator: Ref, denominator: Ref, limit: f64 },
    /// `max / min` of `metric` over the points of `run` and of the runs `with` ≤ `factor`
    /// (the same value everywhere), and so of each metric of `also`; at least two points
    WithinFactor {
        run: String,
        metric: String,
        factor: f64,
        #[serde(default)]
        with: Vec<String>,
        #[serde(default)]
        also: Vec<String>,
    },
    /// `metric` has the order of magnitude of `value` at every selected point:
    /// |log10(|metric| / value)| ≤ `orders`
    Magnitude {
        run: String,
        metric: String,
        value: f64,
        orders: f64,
        #[serde(default)]
        at: Selector,
    },
    /// the histories of `history` (an inverse run's per-iteration record) agree with the
    /// reference point's to a relative spread ≤ `limit` over their common iterations
    SameHistories { run: String, history: String, reference: Selector, limit: f64 },
    /// every check of `checks` holds (partly: some do): a sentence with several parts
    All { checks: Vec<Check> },
    /// some metric of `metrics` changes by more than `factor` (max/min) over the points of `run`
    /// and of the runs `with` (the converse of `within_factor`)
    Varies {
        run: String,
        #[serde(default)]
        with: Vec<String>,
        metrics: Vec<String>,
        factor: f64,
    },
    /// `check`, with every point of the runs `runs` (clips with a ground truth) measured against
    /// the truth (`audit::truth`); with `bending_below`, `twist_below` the check holds only where
    /// those errors are within them (the sentence is about recovering the worm's state)
    WithTruth {
        check: Box<Check>,
        runs: Vec<String>,
        #[serde(default)]
        bending_below: Option<f64>,
        #[serde(default)]
        twist_below: Option<f64>,
    },
}

impl Check {
    /// The metric the check reads, if any.
    pub fn metric(&self) -> Option<&str> {
        match self {
            Check::Below { metric, .. }
            | Check::Above { metric, .. }
            | Check::Increasing { metric, .. }
            | Check::RatioAbove { metric, .. }
            | Check::RatioBelow { metric, .. }
            | Check::WithinFactor { metric, .. }
            | Check::Magnitude { metric, .. } => Some(metric),
            Check::WithTruth { check, .. } => check.metric(),
            Check::Converges { .. }
            | Check::DoesNotConverge { .. }
            | Check::SameHistories { .. }
            | Check::All { .. }
            | Check::Varies { .. } => None,
        }
    }

    /// The runs the check reads.
    pub fn runs(&self) -> Vec<&str> {
        match self {
            Check::Below { run, with, .. } | Check::Above { run, with, .. } | Check::DoesNotConverge { run, with } => {
                std::iter::once(run).chain(with).map(|s| s.as_str()).collect()
            }
            Check::Converges { run }
            | Check::Increasing { run, .. }
            | Check::Magnitude { run, .. }
            | Check::SameHistories { run, .. } => vec![run],
            Check::WithinFactor { run, with, .. } => std::iter::once(run).chain(with).map(|s| s.as_str()).collect(),
            Check::RatioAbove { numerator, denominator, .. } | Check::RatioBelow { numerator, denominator, .. } => {
                vec![&numerator.run, &denominator.run]
            }
            Check::All { checks } => checks.iter().flat_map(|c| c.runs()).collect(),
            Check::Varies { run, with, .. } => std::iter::once(run).chain(with).map(|s| s.as_str()).collect(),
            // the truth's runs give numbers only: the scheme and the stopped points are the check's
            Check::WithTruth { check, .. } => check.runs(),
        }
    }
}

/// A figure of the audit, laid out like the paper's panels.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PlotSpec {
    /// file name in the spec's output folder (`.svg`)
    pub file: String,
    pub title: String,
    pub show: PlotKind,
}

/// What a figure shows.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum PlotKind {
    /// log-log histories of every point of an inverse run (Figs. 9–11, 13)
    Convergence { run: String },
    /// recovered x and κ against the data along the rod (Figs. 8, 12, 14)
    Recovered {
        run: String,
        #[serde(default)]
        at: Selector,
    },
    /// the controls f and l along the rod against the loads that made the data (Fig. 15)
    Controls {
        run: String,
        #[serde(default)]
        at: Selector,
    },
    /// tip history of a dynamic run with the modal solution overlaid (Fig. 5)
    TipHistory { run: String },
    /// tip-loaded cantilevers against eq. (63), the elastica and the Reissner rod (Fig. 7)
    Deflection { runs: Vec<String> },
    /// κ1, κ2, κ3 of a clip run over frames and arc length (Figs. 17, 23, 25)
    Kymograph {
        run: String,
        #[serde(default)]
        at: Selector,
    },
    /// the objective's terms per frame, one curve per point of each run (Figs. 18–20); `at`
    /// keeps, of a run it names, the points of its selector (`at = { ll = { lambda_l = 1e-10 } }`)
    Objectives {
        runs: Vec<String>,
        #[serde(default)]
        at: BTreeMap<String, Selector>,
    },
    /// the angular velocity ω per frame, max over the body, one curve per point of each run
    /// (Fig. 24)
    Omega { runs: Vec<String> },
    /// accuracy per second: a metric (an error) against the solve's wall time over the grid
    /// points of a run, log-log, each point labelled with its grid values
    Tradeoff { run: String, metric: String },
    /// rendered postures of chosen frames (among the run's `keep_frames`) of a clip run
    /// (Figs. 16, 21, 22)
    Postures {
        run: String,
        frames: Vec<usize>,
        #[serde(default)]
        at: Selector,
    },
}

impl PlotKind {
    /// The runs the figure reads.
    pub fn runs(&self) -> Vec<&str> {
        match self {
            PlotKind::Convergence { run }
            | PlotKind::Recovered { run, .. }
            | PlotKind::Controls { run, .. }
            | PlotKind::TipHistory { run }
            | PlotKind::Kymograph { run, .. }
            | PlotKind::Tradeoff { run, .. }
            | PlotKind::Postures { run, .. } => vec![run],
            PlotKind::Deflection { runs } | PlotKind::Omega { runs } => runs.iter().map(|s| s.as_str()).collect(),
            PlotKind::Objectives { runs, at } => runs.iter().chain(at.keys()).map(|s| s.as_str()).collect(),
        }
    }
}

/// A run of a spec: a validated case and its grid.
#[derive(Clone, Debug)]
pub struct RunSpec {
    pub name: String,
    /// the case with `set` applied (and `quick_set` in quick mode)
    pub case: Case,
    /// the grid (`quick_grid` in quick mode); empty: one point
    pub grid: Vec<SweepParam>,
    /// clip runs: frames kept for posture figures
    pub keep_frames: Vec<usize>,
}

/// One claim of the paper and how it is judged.
#[derive(Clone, Debug)]
pub struct Claim {
    pub id: String,
    /// where the paper makes the claim, its words and its number
    pub cited: Citation,
    pub check: Check,
    /// the verdict this project established (asserted by the quick audit in `cargo test`)
    pub expect: Verdict,
    /// the verdicts when the check does not hold on every point
    pub fallback: FallbackVerdicts,
    /// why the verdict may be other than "reproduced", and what the check runs on instead
    pub caveats: Caveats,
    /// a figure file of the spec illustrating the claim
    pub figure: Option<String>,
    /// a check of ours, not a claim of the paper: reported in its own table, counted apart
    pub ours: bool,
}

/// What the paper says: the claim as cited in the report's `where`, `statement` and `paper`
/// columns.
#[derive(Clone, Debug)]
pub struct Citation {
    /// section, equation, figure
    pub location: String,
    /// the paper's words (a short quote)
    pub statement: String,
    /// the paper's number or range
    pub paper: String,
}

/// A claim's verdicts when its check does not hold on every point of the paper's range.
#[derive(Clone, Copy, Debug)]
pub struct FallbackVerdicts {
    /// the verdict when the check fails outright (default: differs)
    pub if_fails: Verdict,
    /// the verdict when the check holds on some points of the paper's range only (default:
    /// differs; "refuted" is not a fallback: the audit gives it from its reruns in both
    /// engines and readings, `super::engines`)
    pub if_partly: Verdict,
}

/// The reservations of a claim's verdict, each reported with it.
#[derive(Clone, Debug)]
pub struct Caveats {
    /// why the check fails, reported only when it does; its placeholders (`{first_failing}`,
    /// `super::cause`) are filled in from the measured points
    pub cause: Option<String>,
    /// what of the paper is not available here (its data, its code): the check runs on the
    /// `substitute` and the verdict is "not computable here" when it holds there
    pub not_computable: Option<String>,
    /// the data the check runs on when it is not the paper's
    pub substitute: Option<String>,
    /// the check is weaker than the paper's words: why. Such a claim is at best "differs".
    pub partial: Option<String>,
}

/// A validated audit spec.
#[derive(Clone, Debug)]
pub struct Spec {
    /// file stem (output folder name)
    pub name: String,
    pub path: PathBuf,
    pub title: String,
    pub section: String,
    /// the paper's figures and tables the spec covers
    pub paper_figures: String,
    pub runs: Vec<RunSpec>,
    pub claims: Vec<Claim>,
    pub plots: Vec<PlotSpec>,
}

impl Spec {
    /// The run named `name`.
    pub fn run(&self, name: &str) -> Option<&RunSpec> {
        self.runs.iter().find(|r| r.name == name)
    }
}

/// Read and validate a spec; at [`Depth::Quick`], with the runs' `quick_set` and `quick_grid`.
pub fn read_spec(path: &Path, depth: Depth) -> Result<Spec, SpecError> {
    let text = read_capped_text(path, SPEC_FILE_CAP_BYTES, "audit spec")?;
    let raw: RawSpec = toml::from_str(&text).map_err(|e| SpecError::Syntax {
        path: path.to_path_buf(),
        message: match crate::case::is_case_text(&text) {
            true => format!(
                "this is a case file ([rod], [solver]), not an audit spec: `cosserat run {}` runs it; `cosserat \
                 audit` takes specs of claims and runs (cases/paper/*.toml)",
                path.display()
            ),
            false => e.to_string(),
        },
    })?;
    let runs = raw.runs.into_iter().map(|(name, r)| read_run(path, name, r, depth)).collect::<Result<Vec<_>, _>>()?;
    let mut claims: Vec<Claim> = Vec::new();
    for c in raw.claims {
        let claim = read_claim(path, c, &claims, &runs)?;
        claims.push(claim);
    }
    for p in &raw.figures {
        names_runs(path, &runs, p.show.runs(), format!("figure `{}`", p.file))?;
        if !p.file.ends_with(".svg") || p.file.contains('/') {
            return Err(invalid(path, format!("figure `{}`", p.file), "must be a file name ending in .svg".into()));
        }
    }
    let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("spec").to_string();
    Ok(Spec {
        name,
        path: path.to_path_buf(),
        title: raw.title,
        section: raw.section,
        paper_figures: raw.paper_figures,
        runs,
        claims,
        plots: raw.figures,
    })
}

/// The error of a spec at `path`: `what` (a run, claim or figure) and why.
fn invalid(path: &Path, what: String, reason: String) -> SpecError {
    SpecError::Invalid { path: path.to_path_buf(), what, reason }
}

/// The run `name` of the spec at `path`: its case file (relative to the spec) with the run's
/// `set` (and, at [`Depth::Quick`], `quick_set`), and its grid of known keys and finite values.
fn read_run(path: &Path, name: String, r: RawRun, depth: Depth) -> Result<RunSpec, SpecError> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let case_path = dir.join(&r.case);
    let boxed = |e: Box<dyn std::error::Error + Send + Sync>| SpecError::Case {
        path: path.to_path_buf(),
        run: name.clone(),
        case: case_path.clone(),
        source: e,
    };
    let mut case = Case::from_file(&case_path).map_err(|e| boxed(Box::new(e)))?;
    let mut set: Vec<(String, toml::Value)> = r.set.into_iter().collect();
    if depth.is_quick() {
        set.extend(r.quick_set);
    }
    if !set.is_empty() {
        case = case.with_overrides(&set).map_err(|e| boxed(Box::new(e)))?;
    }
    let grid_table = if depth.is_quick() { r.quick_grid.unwrap_or(r.grid) } else { r.grid };
    let known = known_keys(&case);
    let mut grid = Vec::new();
    for (key, values) in grid_table {
        if !known.contains(&key.as_str()) {
            return Err(invalid(
                path,
                format!("run `{name}` grid"),
                format!("unknown key `{key}` (known: {})", known.join(", ")),
            ));
        }
        if values.is_empty() || values.iter().any(|v| !v.is_finite()) {
            return Err(invalid(path, format!("run `{name}` grid `{key}`"), "needs finite values".into()));
        }
        grid.push(SweepParam { key, values: values.into_iter().map(SweepValue::Number).collect() });
    }
    if !r.keep_frames.is_empty() && case.clip().is_none() {
        return Err(invalid(path, format!("run `{name}`"), "keep_frames needs a clip case".into()));
    }
    Ok(RunSpec { name, case, grid, keep_frames: r.keep_frames })
}

/// `Err` naming `what` when one of `names` is not a run of `runs`.
fn names_runs(path: &Path, runs: &[RunSpec], names: Vec<&str>, what: String) -> Result<(), SpecError> {
    match names.iter().find(|n| !runs.iter().any(|r| r.name == **n)) {
        Some(n) => Err(invalid(path, what, format!("names no run `{n}`"))),
        None => Ok(()),
    }
}

/// A claim of the spec at `path`, checked against the claims before it (`earlier`) and the
/// runs: runs it names, a unique id, a cause for any verdict but reproduced, what is missing
/// for not computable, no partial check that expects reproduced, no words of ours in the
/// statement.
fn read_claim(path: &Path, c: RawClaim, earlier: &[Claim], runs: &[RunSpec]) -> Result<Claim, SpecError> {
    names_runs(path, runs, c.check.runs(), format!("claim `{}`", c.id))?;
    if earlier.iter().any(|o| o.id == c.id) {
        return Err(invalid(path, format!("claim `{}`", c.id), "id given twice".into()));
    }
    if !matches!(c.expect, Verdict::Reproduced | Verdict::NotComputable) && c.cause.is_none() {
        return Err(invalid(path, format!("claim `{}`", c.id), "a verdict other than reproduced needs a cause".into()));
    }
    if let Some(word) = c.cause.as_deref().and_then(super::cause::unknown_placeholder) {
        let known = super::cause::PLACEHOLDERS.join(", ");
        return Err(invalid(path, format!("claim `{}`", c.id), format!("the cause's `{word}` is none of {known}")));
    }
    if c.expect == Verdict::NotComputable && (c.not_computable.is_none() || c.substitute.is_none()) {
        return Err(invalid(
            path,
            format!("claim `{}`", c.id),
            "expect = \"not_computable\" needs not_computable = \"<what is missing>\" and substitute = \"<what ran instead>\""
                .into(),
        ));
    }
    if c.partial.is_some() && matches!(c.expect, Verdict::Reproduced | Verdict::NotComputable) {
        return Err(invalid(
            path,
            format!("claim `{}`", c.id),
            "a partial check (weaker than the paper's words) yields at best \"differs\": expect cannot be reproduced or not computable".into(),
        ));
    }
    // "refuted" needs the failure in the paper's scheme under both one-rule readings and in
    // both engines (docs/audit.md): the audit decides it from its reruns (`super::engines`), a
    // spec may expect it but not declare it as a fallback.
    let rerun = !c.ours && c.partial.is_none() && c.substitute.is_none();
    if [c.if_fails, c.if_partly].contains(&Some(Verdict::Refuted)) || (c.expect == Verdict::Refuted && !rerun) {
        return Err(invalid(
            path,
            format!("claim `{}`", c.id),
            "\"refuted\" is not a fallback, nor for a check of ours, a partial one or one on a substitute: the audit gives it when the check of the paper's claim fails under both one-rule readings and in both engines (Rust and FreeFEM, docs/audit.md)".into(),
        ));
    }
    if let Some(q) = ["(here", "(ours", "(our "].iter().find(|q| c.statement.contains(*q)) {
        return Err(invalid(
            path,
            format!("claim `{}`", c.id),
            format!("the statement quotes the paper verbatim; `{q}…` is ours: put it in `paper` or `partial`"),
        ));
    }
    Ok(Claim {
        id: c.id,
        cited: Citation { location: c.location, statement: c.statement, paper: c.paper },
        check: c.check,
        expect: c.expect,
        fallback: FallbackVerdicts {
            if_fails: c.if_fails.unwrap_or(Verdict::Differs),
            if_partly: c.if_partly.unwrap_or(Verdict::Differs),
        },
        caveats: Caveats {
            cause: c.cause,
            not_computable: c.not_computable,
            substitute: c.substitute,
            partial: c.partial,
        },
        figure: c.figure,
        ours: c.ours,
    })
}
