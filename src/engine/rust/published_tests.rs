//! Tests of the published values' evaluator (`crate::engine::common::published`) on Rust engine runs: interpolation against an analytic linear field, verdicts, the
//! metrics.json entries, and the list of metric keys against what a run writes.
use std::path::Path;

use nalgebra::Vector3;

use super::{run_forward, run_inverse, RunError};
use crate::case::published::{Axis, NodeField, PublishedValue, Quantity, Tolerance};
use crate::case::{Analysis, Case};
use crate::engine::common::metrics::{all_metrics, Metric, Metrics};
use crate::engine::common::published::*;
use crate::engine::common::result::{Engine, SolverStats};
use crate::engine::common::result::{NodalState, RunResult};
use crate::model::chart::Chart;

/// A state whose every field is linear in s on uneven nodes: x = a + b s, α = c + d s.
fn linear_state() -> (NodalState, [Vector3<f64>; 4]) {
    let (a, b) = (Vector3::new(0.3, -1.2, 0.05), Vector3::new(2.0, 0.7, -0.4));
    let (c, d) = (Vector3::new(0.1, -0.2, 0.3), Vector3::new(-1.5, 0.25, 4.0));
    let s = vec![0.0, 0.1, 0.35, 0.6, 1.0];
    let state = NodalState {
        x: s.iter().map(|s| a + b * *s).collect(),
        alpha: s.iter().map(|s| c + d * *s).collect(),
        s,
        chart: Chart::default(),
        reference_x: None,
    };
    (state, [a, b, c, d])
}

fn result(nodes: NodalState) -> RunResult {
    RunResult {
        engine: Engine::Rust,
        nodes,
        history: Vec::new(),
        tip: Vec::new(),
        stats: SolverStats::default(),
        inverse: None,
        path: None,
        stability: None,
    }
}

/// A P1 field is exact between its nodes: the interpolated value at any s equals the linear
/// field there, for positions, displacements (x − (0, 0, s)) and angles.
#[test]
fn node_interpolation_is_exact_on_a_linear_field() {
    let (n, [a, b, c, d]) = linear_state();
    for s in [0.0, 0.05, 0.1, 0.2999, 0.35, 0.77, 0.999_999, 1.0] {
        for axis in Axis::ALL {
            let k = axis.index();
            let x = at_arc_length(&n, NodeField::Position(axis), s).unwrap();
            assert!((x - (a[k] + b[k] * s)).abs() < 1e-15, "x_{k}({s}) = {x}");
            let u = at_arc_length(&n, NodeField::Displacement(axis), s).unwrap();
            let reference = if k == 2 { s } else { 0.0 };
            assert!((u - (a[k] + b[k] * s - reference)).abs() < 1e-15, "u_{k}({s}) = {u}");
            let t = at_arc_length(&n, NodeField::Angle(k), s).unwrap();
            assert!((t - (c[k] + d[k] * s)).abs() < 1e-15, "alpha_{k}({s}) = {t}");
        }
    }
    let r = result(n.clone());
    let tip = value(&Quantity::Tip(NodeField::Angle(2)), &r, &Metrics::new()).unwrap();
    assert!((tip - (c[2] + d[2])).abs() < 1e-15);
    let e = at_arc_length(&n, NodeField::Position(Axis::X), 1.5).unwrap_err().to_string();
    assert!(e.contains("outside the rod's nodes"), "{e}");
    assert!(at_arc_length(&n, NodeField::Position(Axis::X), -1e-9).is_err());
}

fn published(text: &str, value: f64, tolerance: Tolerance) -> PublishedValue {
    PublishedValue { quantity: Quantity::parse(text).unwrap(), value, tolerance, source: "test".into(), note: None }
}

/// A row passes within its tolerance and misses outside it; a NaN or a missing value misses.
#[test]
fn rows_pass_within_their_tolerance_only() {
    let (n, [a, b, ..]) = linear_state();
    let r = result(n);
    let mut m = Metrics::new();
    m.insert(Metric::Iterations, 7.0);
    m.insert_named("odd", f64::NAN);
    let tip_y = a[1] + b[1];
    let cases = [
        (published("tip.y_m", tip_y + 0.9e-3, Tolerance::Absolute(1e-3)), true),
        (published("tip.y_m", tip_y + 1.1e-3, Tolerance::Absolute(1e-3)), false),
        (published("node(s=0.5).x_m", (a[0] + b[0] * 0.5) * 1.009, Tolerance::Relative(1e-2)), true),
        (published("node(s=0.5).x_m", (a[0] + b[0] * 0.5) * 1.011, Tolerance::Relative(1e-2)), false),
        (published("metric.iterations", 7.0, Tolerance::Absolute(0.5)), true),
        (published("metric.odd", 0.0, Tolerance::Absolute(1e300)), false),
        (published("metric.absent", 0.0, Tolerance::Absolute(1e300)), false),
    ];
    for (v, pass) in &cases {
        let row = PublishedRow::new(v, value(&v.quantity, &r, &m));
        assert_eq!(row.pass, *pass, "{}", row.summary());
        assert!(row.summary().ends_with(if *pass { "pass" } else { "MISS" }), "{}", row.summary());
    }
    let missing = PublishedRow::new(&cases[6].0, value(&cases[6].0.quantity, &r, &m));
    assert!(missing.summary().contains("not computed (absent is not in this run's metrics.json)"));
    let rows: Vec<PublishedRow> =
        cases[..2].iter().map(|(v, _)| PublishedRow::new(v, value(&v.quantity, &r, &m))).collect();
    let e = metric_entries(&rows);
    assert_eq!(e.named("reference.tip.y_m.pass").unwrap(), 0.0, "the last row of a quantity is the one kept: {e:?}");
    assert_eq!((e.named("reference.rows").unwrap(), e.named("reference.missed").unwrap()), (2.0, 1.0));
    assert!((e.named("reference.tip.y_m.error").unwrap() + 1.1e-3).abs() < 1e-12, "computed − published");
    assert!(metric_entries(&[]).is_empty());
}

fn case(name: &str) -> Case {
    Case::from_file(&Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("cases/{name}.toml"))).expect("case")
}

/// Every key a run writes to metrics.json is one that a `metric.KEY` row may name: a static
/// case with a `[reference]` theory, a dynamic case, an inverse case.
#[test]
fn metric_keys_cover_what_runs_write() {
    let statics = case("timoshenko_5pct");
    let dynamic = case("cantilever_dynamic").time_prefix(2);
    let mut inverse = case("inverse_bend");
    let data = run_forward(&inverse.data_case().expect("forward data"), |_, _| {}).expect("data").nodes;
    if let Analysis::Inverse(s) = &mut inverse.analysis {
        s.params.max_iterations = 3;
    }
    let inverse_run = match run_inverse(&inverse, &data, |_, _| {}) {
        Ok(r) => r,
        Err(RunError::Incomplete { partial, .. }) => *partial,
        Err(e) => panic!("{e}"),
    };
    for (c, r) in [
        (&statics, run_forward(&statics, |_, _| {}).expect("static")),
        (&dynamic, run_forward(&dynamic, |_, _| {}).expect("dynamic")),
        (&inverse, inverse_run),
    ] {
        let keys = metric_keys(c);
        let written = all_metrics(c, &r).expect("metrics");
        let unlisted: Vec<&str> = written.names().filter(|k| !keys.iter().any(|n| n == k)).collect();
        assert!(unlisted.is_empty(), "{}: metrics.json keys missing from metric_keys: {unlisted:?}", c.name);
        // a dynamic run without trailing unloaded steps writes none of the four `unloaded_*`
        let optional = if c.is_dynamic() { 4 } else { 0 };
        assert!(written.len() + 3 + optional >= keys.len(), "{}: {written:?} against {keys:?}", c.name);
    }
}

/// A metric that the case's run never writes is refused before the run, naming the row and
/// listing the metrics there are.
#[test]
fn an_unknown_metric_is_refused_before_the_run() {
    let mut c = case("timoshenko_5pct");
    assert_eq!(unavailable(&c), None);
    c.checks.published.values.push(published("metric.reissner_rel_error", 0.0, Tolerance::Absolute(1e-3)));
    assert_eq!(unavailable(&c), None);
    c.checks.published.values.push(published("metric.tip_max_abs_y_m", 0.0, Tolerance::Absolute(1e-3)));
    let e = unavailable(&c).expect("a dynamic metric on a static case");
    assert!(
        e.contains("reference.values[1]") && e.contains("tip_max_abs_y_m") && e.contains("elastica_rel_error"),
        "{e}"
    );
}
