//! Parameter sweeps (`cosserat sweep`): `--set key=v1,v2,…` specifications, their cartesian
//! product, applied to a validated [`Case`] (typed, never through TOML text), and the summary
//! table of the runs. The CLI runs the product in parallel and writes one folder per run.
use crate::case::{Analysis, Case, InverseMethod, StaticMethod};
use crate::mesh::Mesh;
use crate::metrics::Metrics;

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
}

/// One swept parameter and its values.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepParam {
    pub key: String,
    pub values: Vec<f64>,
}

/// Parse `key=v1,v2,…`.
pub fn parse_set(spec: &str) -> Result<SweepParam, SweepError> {
    let (key, values) = spec.split_once('=').ok_or_else(|| SweepError::Syntax(spec.into()))?;
    let key = key.trim().to_string();
    if key.is_empty() || values.trim().is_empty() {
        return Err(SweepError::Syntax(spec.into()));
    }
    let values = values
        .split(',')
        .map(|v| {
            let v = v.trim();
            v.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| SweepError::NotANumber { key: key.clone(), value: v.into() })
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(SweepParam { key, values })
}

/// Parameters a sweep can set, by analysis.
pub fn known_keys(case: &Case) -> &'static [&'static str] {
    match case.analysis {
        Analysis::Inverse(_) => &[
            "lambda_g",
            "lambda_f",
            "lambda_l",
            "lambda_d",
            "lambda_kappa1",
            "lambda_kappa2",
            "lambda_kappa3",
            "lambda_omega1",
            "lambda_omega2",
            "lambda_omega3",
            "relaxation",
            "warm_start_tolerance",
            "tolerance",
            "max_iterations",
            "elements",
            "stabilisation",
        ],
        Analysis::Static { .. } => &["relaxation", "tolerance", "max_iterations", "continuation_steps", "elements"],
        Analysis::Dynamic { .. } => &["tolerance", "max_iterations", "steps", "elements"],
    }
}

fn count(key: &str, v: f64) -> Result<usize, SweepError> {
    if v >= 1.0 && v.fract() == 0.0 && v < 1e9 {
        Ok(v as usize)
    } else {
        Err(SweepError::Invalid { key: key.into(), reason: format!("must be a positive integer, got {v}") })
    }
}

/// Set one parameter on a case, with the validation of the case file for that key.
pub fn apply(case: &mut Case, key: &str, v: f64) -> Result<(), SweepError> {
    let invalid = |reason: String| SweepError::Invalid { key: key.into(), reason };
    if !known_keys(case).contains(&key) {
        return Err(SweepError::UnknownKey {
            key: key.into(),
            case: case.name.clone(),
            known: known_keys(case).join(", "),
        });
    }
    if key == "elements" {
        let n = count(key, v)?;
        if n < 2 {
            return Err(invalid(format!("need at least 2 elements, got {n}")));
        }
        case.mesh = Mesh::new(case.mesh.length_m, n);
        return Ok(());
    }
    let positive = |x: f64| if x > 0.0 { Ok(x) } else { Err(invalid(format!("must be > 0, got {x}"))) };
    let nonneg = |x: f64| if x >= 0.0 { Ok(x) } else { Err(invalid(format!("must be ≥ 0, got {x}"))) };
    let unit = |x: f64| if x > 0.0 && x < 1.0 { Ok(x) } else { Err(invalid(format!("must lie in (0, 1), got {x}"))) };
    let relax = |x: f64| if x > 0.0 && x <= 1.0 { Ok(x) } else { Err(invalid(format!("must lie in (0, 1], got {x}"))) };
    match &mut case.analysis {
        Analysis::Inverse(s) => match key {
            "lambda_g" => s.weights.lambda_g = positive(v)?,
            "lambda_f" => s.weights.lambda_f = positive(v)?,
            "lambda_l" => s.weights.lambda_l = positive(v)?,
            "lambda_d" => s.weights.lambda_d = nonneg(v)?,
            "lambda_kappa1" | "lambda_kappa2" | "lambda_kappa3" => {
                s.weights.lambda_kappa[key.as_bytes()[12] as usize - b'1' as usize] = nonneg(v)?
            }
            "lambda_omega1" | "lambda_omega2" | "lambda_omega3" => {
                s.weights.lambda_omega[key.as_bytes()[12] as usize - b'1' as usize] = nonneg(v)?
            }
            "relaxation" => match &mut s.method {
                InverseMethod::FixedPoint { relaxation } | InverseMethod::Newton { relaxation, .. } => {
                    *relaxation = relax(v)?
                }
            },
            "warm_start_tolerance" => match &mut s.method {
                InverseMethod::Newton { warm_start_tolerance, .. } => *warm_start_tolerance = unit(v)?,
                InverseMethod::FixedPoint { .. } => return Err(invalid("only used by method = \"newton\"".into())),
            },
            "tolerance" => s.tolerance = unit(v)?,
            "max_iterations" => s.max_iterations = count(key, v)?,
            "stabilisation" => {
                s.stabilisation = if (0.0..=1.0).contains(&v) {
                    v
                } else {
                    return Err(invalid(format!("must lie in [0, 1], got {v}")));
                }
            }
            _ => unreachable!("checked against known_keys"),
        },
        Analysis::Static { method, tolerance, max_iterations, continuation_steps } => match key {
            "relaxation" => match method {
                StaticMethod::FixedPoint { relaxation } => *relaxation = relax(v)?,
                StaticMethod::Newton => return Err(invalid("not used by method = \"newton\"".into())),
            },
            "tolerance" => *tolerance = unit(v)?,
            "max_iterations" => *max_iterations = count(key, v)?,
            "continuation_steps" => *continuation_steps = count(key, v)?,
            _ => unreachable!("checked against known_keys"),
        },
        Analysis::Dynamic { end_time_s: _, steps, tolerance, max_iterations } => match key {
            "tolerance" => *tolerance = unit(v)?,
            "max_iterations" => *max_iterations = count(key, v)?,
            "steps" => *steps = count(key, v)?,
            _ => unreachable!("checked against known_keys"),
        },
    }
    Ok(())
}

/// One point of the cartesian product: `(key, value)` in the order of the `--set` options.
pub type Point = Vec<(String, f64)>;

/// The cartesian product of the specifications (first key varies slowest). Checks every key
/// against the case and every point by applying it.
pub fn product(case: &Case, params: &[SweepParam]) -> Result<Vec<(Point, Case)>, SweepError> {
    for (i, p) in params.iter().enumerate() {
        if params[..i].iter().any(|q| q.key == p.key) {
            return Err(SweepError::Duplicate(p.key.clone()));
        }
    }
    let mut points: Vec<Point> = vec![Vec::new()];
    for p in params {
        points = points
            .into_iter()
            .flat_map(|pt| {
                p.values.iter().map(move |&v| {
                    let mut q = pt.clone();
                    q.push((p.key.clone(), v));
                    q
                })
            })
            .collect();
    }
    points
        .into_iter()
        .map(|pt| {
            let mut c = case.clone();
            for (k, v) in &pt {
                apply(&mut c, k, *v)?;
            }
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
    point.iter().map(|(k, v)| format!("{k}={}", fmt_value(*v))).collect::<Vec<_>>().join("_")
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

/// Columns of the summary table after the swept keys.
pub const SUMMARY_METRICS: [&str; 11] = [
    "iterations",
    "x_err_rel",
    "kappa_err_rel",
    "kappa_err_rel_inner",
    "tangent_misfit_m05",
    "j_tracking",
    "j_total",
    "force_l2_n_per_m05",
    "torque_l2_n_m05",
    "tip_y_m",
    "wall_time_s",
];

/// One row of the summary: the point, its status, its metrics (also those of the last iterate
/// of a run that did not converge) and its error message.
#[derive(Clone, Debug)]
pub struct SummaryRow {
    pub point: Point,
    pub status: RunStatus,
    pub metrics: Option<Metrics>,
    pub error: Option<String>,
}

/// Outcome of one run of a sweep.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunStatus {
    Ok,
    /// iteration limit reached; the metrics are those of the last iterate
    NotConverged,
    Failed,
}

impl RunStatus {
    pub fn as_str(&self) -> &'static str {
        match self {
            RunStatus::Ok => "ok",
            RunStatus::NotConverged => "not_converged",
            RunStatus::Failed => "failed",
        }
    }
}

/// CSV text of the summary (header: swept keys, `status` (`ok`, `not_converged`, `failed`),
/// [`SUMMARY_METRICS`], `error`).
pub fn summary_csv(keys: &[String], rows: &[SummaryRow]) -> Result<String, csv::Error> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut header: Vec<String> = keys.to_vec();
    header.push("status".into());
    header.extend(SUMMARY_METRICS.iter().map(|s| s.to_string()));
    header.push("error".into());
    w.write_record(&header)?;
    for r in rows {
        let mut rec: Vec<String> = r.point.iter().map(|(_, v)| fmt_value(*v)).collect();
        rec.push(r.status.as_str().into());
        rec.extend(
            SUMMARY_METRICS
                .iter()
                .map(|k| r.metrics.as_ref().and_then(|m| m.get(*k)).map(|v| format!("{v:.10e}")).unwrap_or_default()),
        );
        rec.push(r.error.as_deref().unwrap_or("").replace('\n', " "));
        w.write_record(&rec)?;
    }
    let bytes = w.into_inner().map_err(|e| csv::Error::from(e.into_error()))?;
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn case() -> Case {
        let text =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/cases/inverse_bend.toml")).expect("case");
        Case::from_toml(&text, "inverse_bend", std::path::Path::new("inverse_bend.toml")).expect("case")
    }

    #[test]
    fn product_is_cartesian_and_applied() {
        let params = vec![parse_set("lambda_l=1e-20,1e3").unwrap(), parse_set("lambda_kappa3=0,1e-10,1").unwrap()];
        let pts = product(&case(), &params).unwrap();
        assert_eq!(pts.len(), 6);
        assert_eq!(pts[0].1.name, "lambda_l=1e-20_lambda_kappa3=0");
        let Analysis::Inverse(ref s) = pts[5].1.analysis else { panic!() };
        assert_eq!((s.weights.lambda_l, s.weights.lambda_kappa[2], s.weights.lambda_kappa[1]), (1e3, 1.0, 0.0));
    }

    #[test]
    fn bad_specifications_are_errors() {
        assert!(matches!(parse_set("lambda_l"), Err(SweepError::Syntax(_))));
        assert!(matches!(parse_set("lambda_l=1,x"), Err(SweepError::NotANumber { .. })));
        assert!(matches!(parse_set("lambda_l=nan"), Err(SweepError::NotANumber { .. })));
        let c = case();
        assert!(matches!(product(&c, &[parse_set("lambda_q=1").unwrap()]), Err(SweepError::UnknownKey { .. })));
        assert!(matches!(product(&c, &[parse_set("lambda_f=0").unwrap()]), Err(SweepError::Invalid { .. })));
        assert!(matches!(product(&c, &[parse_set("elements=2.5").unwrap()]), Err(SweepError::Invalid { .. })));
        let twice = [parse_set("lambda_f=1").unwrap(), parse_set("lambda_f=2").unwrap()];
        assert!(matches!(product(&c, &twice), Err(SweepError::Duplicate(_))));
    }

    #[test]
    fn summary_has_header_and_failures() {
        let mut m = Metrics::new();
        m.insert("iterations".into(), 12.0);
        let rows = vec![
            SummaryRow {
                point: vec![("lambda_l".into(), 1e-20)],
                status: RunStatus::Ok,
                metrics: Some(m.clone()),
                error: None,
            },
            SummaryRow {
                point: vec![("lambda_l".into(), 1e3)],
                status: RunStatus::NotConverged,
                metrics: Some(m),
                error: Some("did not converge,\nat all".into()),
            },
            SummaryRow {
                point: vec![("lambda_l".into(), 1.0)],
                status: RunStatus::Failed,
                metrics: None,
                error: Some("bad".into()),
            },
        ];
        let text = summary_csv(&["lambda_l".into()], &rows).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert!(lines[0].starts_with("lambda_l,status,iterations,x_err_rel"));
        assert!(lines[1].starts_with("1e-20,ok,1.2000000000e1"));
        assert!(
            lines[2].starts_with("1e3,not_converged,1.2000000000e1")
                && lines[2].ends_with("\"did not converge, at all\""),
            "{}",
            lines[2]
        );
        assert!(lines[3].starts_with("1,failed,,") && lines[3].ends_with(",bad"), "{}", lines[3]);
    }
}
