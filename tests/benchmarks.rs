//! The benchmark library `cases/benchmarks/`: every case there carries its published values
//! (`[[reference.values]]`), and here every one of them is run in both engines (its
//! `[reference.short]` variant where it has one) with every published value within its
//! tolerance in each. Beside it, the checks of the mechanism itself: a published value checked
//! against an independent elliptic-integral evaluation, a deliberately wrong value reported as
//! missed (`run --strict` exits 1), `compare` reporting both engines, a metric the run does not
//! write refused before the run, and the vocabulary documented where the users read it.
//!
//! FreeFEM must be installed; `COSSERAT_SKIP_FREEFEM=1` runs the Rust engine only.
mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use cosserat::case::published::{Axis, NodeField, Quantity, VOCABULARY};
use cosserat::case::{case_files, Analysis, Case};
use cosserat::engine::metrics::all_metrics;
use cosserat::engine::published::{evaluate, unavailable};
use cosserat::engine::run_case;
use cosserat::engine::{Engine, RunResult};
use cosserat::jobs::compare::{compare_case, CompareOptions, Horizon};
use cosserat::reference::{tip_loaded_cantilever, PlanarRod};

fn benchmarks_dir() -> PathBuf {
    common::cases_dir().join("benchmarks")
}

/// Every case of `cases/benchmarks/` in both engines: each has published values, each with a
/// source, and each value is within its tolerance in the Rust and in the FreeFEM engine.
/// Every benchmark meets its published values in each engine, and the engines agree as every
/// case of `cases/` does (`compare` with its derived tolerances: the Rust engine perturbed by
/// 1e-13 gives each quantity's spread). A static benchmark's published values are read from the
/// two runs that `compare` made, so FreeFEM solves it once; `compare` runs a dynamic one over its
/// first time steps only, so the published values at its end need both engines' whole runs.
#[test]
fn every_benchmark_meets_its_published_values_in_both_engines_which_agree() {
    let files = case_files(&benchmarks_dir()).expect("cases/benchmarks");
    assert!(!files.is_empty(), "no benchmark in {}", benchmarks_dir().display());
    let mut failures = Vec::new();
    for f in &files {
        let full = Case::from_file(f).unwrap_or_else(|e| panic!("{e}"));
        assert!(!full.checks.published.values.is_empty(), "{}: a benchmark needs [[reference.values]]", f.display());
        assert_eq!(unavailable(&full), None);
        let case =
            full.short_variant().unwrap_or_else(|e| panic!("{}: [reference.short]: {e}", f.display())).unwrap_or(full);
        for (engine, r) in benchmark_runs(&case, &mut failures) {
            let metrics = all_metrics(&case, &r).expect("metrics");
            for row in evaluate(&case, &r, &metrics) {
                eprintln!("{} [{engine}] {}", case.name, row.summary());
                if !row.pass {
                    failures.push(format!("{} [{engine}] {}", case.name, row.summary()));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The runs of a benchmark whose published values are checked: both engines' where FreeFEM is
/// required (after `compare`, whose disagreements are added to `failures`), the Rust engine's
/// alone otherwise.
fn benchmark_runs(case: &Case, failures: &mut Vec<String>) -> Vec<(Engine, RunResult)> {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut engines = vec![Engine::Rust];
    if common::freefem_required() {
        let opts = CompareOptions { horizon: Horizon::Short, frames: None };
        match compare_case(case, dir.path(), &opts) {
            Ok(report) => {
                common::report_failures(&report, failures);
                let static_case = !matches!(case.analysis, Analysis::Dynamic(_));
                if let (true, Some((rust, freefem))) = (static_case, report.runs) {
                    return vec![(Engine::Rust, rust), (Engine::Freefem, freefem)];
                }
            }
            Err(e) => failures.push(format!("{}: {}", case.name, common::error_chain(&e))),
        }
        engines.push(Engine::Freefem);
    }
    let mut runs = Vec::new();
    for engine in engines {
        let dir = tempfile::tempdir().expect("tempdir");
        match run_case(case, engine, dir.path(), |_, _| {}) {
            Ok(r) => runs.push((engine, r)),
            Err(e) => failures.push(format!("{} [{engine}]: {}", case.name, common::error_chain(&e))),
        }
    }
    runs
}

// ------------------------------------------------ an independent elliptic-integral evaluation

/// Carlson's symmetric integral R_F(x, y, z) by duplication (B. C. Carlson, Numer. Algorithms
/// 10 (1995) 13–26, §2): relative error below 1e-16 once every deviation is below 1e-3.
fn carlson_rf(mut x: f64, mut y: f64, mut z: f64) -> f64 {
    loop {
        let (sx, sy, sz) = (x.sqrt(), y.sqrt(), z.sqrt());
        let l = sx * (sy + sz) + sy * sz;
        (x, y, z) = ((x + l) / 4.0, (y + l) / 4.0, (z + l) / 4.0);
        let a = (x + y + z) / 3.0;
        let (dx, dy, dz) = ((a - x) / a, (a - y) / a, (a - z) / a);
        if dx.abs().max(dy.abs()).max(dz.abs()) < 1e-3 {
            let (e2, e3) = (dx * dy - dz * dz, dx * dy * dz);
            return (1.0 + (e2 / 24.0 - 0.1 - 3.0 * e3 / 44.0) * e2 + e3 / 14.0) / a.sqrt();
        }
    }
}

/// Carlson's R_D(x, y, z) by duplication (ibid., §3).
fn carlson_rd(mut x: f64, mut y: f64, mut z: f64) -> f64 {
    let (mut sum, mut fac) = (0.0, 1.0);
    loop {
        let (sx, sy, sz) = (x.sqrt(), y.sqrt(), z.sqrt());
        let l = sx * (sy + sz) + sy * sz;
        sum += fac / (sz * (z + l));
        fac /= 4.0;
        (x, y, z) = ((x + l) / 4.0, (y + l) / 4.0, (z + l) / 4.0);
        let a = (x + y + 3.0 * z) / 5.0;
        let (dx, dy, dz) = ((a - x) / a, (a - y) / a, (a - z) / a);
        if dx.abs().max(dy.abs()).max(dz.abs()) < 1e-3 {
            let (ea, eb) = (dx * dy, dz * dz);
            let (ec, ed) = (ea - eb, ea - 6.0 * eb);
            let ee = ed + 2.0 * ec;
            let (c1, c2, c3, c4) = (3.0 / 14.0, 1.0 / 6.0, 9.0 / 22.0, 3.0 / 26.0);
            let series = 1.0
                + ed * (-c1 + 0.25 * c3 * ed - 1.5 * c4 * dz * ee)
                + dz * (c2 * ee + dz * (-c3 * ec + dz * c4 * ea));
            return 3.0 * sum + fac * series / (a * a.sqrt());
        }
    }
}

/// Incomplete elliptic integrals of the first and second kind, F(φ, k) and E(φ, k).
fn elliptic_f_e(phi: f64, k: f64) -> (f64, f64) {
    let (s, c) = phi.sin_cos();
    let q = 1.0 - k * k * s * s;
    let rf = carlson_rf(c * c, q, 1.0);
    (s * rf, s * rf - k * k * s * s * s * carlson_rd(c * c, q, 1.0) / 3.0)
}

/// The Bisshopp–Drucker elastica at load parameter `a` = PL²/EI: with the tip angle θ₀,
/// k = √((1 + sin θ₀)/2) and sin φ₁ = 1/(k√2),
/// √a = K(k) − F(φ₁, k), δ/L = 1 − 2 (E(k) − E(φ₁, k))/√a, (L − Δ)/L = 1 − √(2 sin θ₀ / a).
/// Returns (θ₀ [rad], δ/L, (L − Δ)/L).
fn bisshopp_drucker(a: f64) -> (f64, f64, f64) {
    let parts = |theta0: f64| {
        let k = ((1.0 + theta0.sin()) / 2.0).sqrt();
        let phi1 = (1.0 / (k * 2f64.sqrt())).asin();
        let (kk, ek) = elliptic_f_e(std::f64::consts::FRAC_PI_2, k);
        let (f1, e1) = elliptic_f_e(phi1, k);
        (kk - f1, ek - e1)
    };
    let (mut lo, mut hi) = (1e-12, std::f64::consts::FRAC_PI_2 - 1e-12);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if parts(mid).0 < a.sqrt() {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let theta0 = 0.5 * (lo + hi);
    let (_, de) = parts(theta0);
    (theta0, 1.0 - 2.0 * de / a.sqrt(), 1.0 - (2.0 * theta0.sin() / a).sqrt())
}

/// The elliptic integrals against closed forms at k = 1/√2 (K = Γ(1/4)²/(4√π), and E from
/// Legendre's relation 2EK − K² = π/2) and the elastica against the shooting solution of
/// `cosserat::reference` (RK4 and Brent, no elliptic integral).
#[test]
fn elliptic_integral_elastica_is_independent_and_exact() {
    use std::f64::consts::{FRAC_1_SQRT_2, FRAC_PI_2, PI};
    const GAMMA_QUARTER: f64 = 3.625_609_908_221_908; // Γ(1/4)
    let (kk, ek) = elliptic_f_e(FRAC_PI_2, FRAC_1_SQRT_2);
    let k_exact = GAMMA_QUARTER * GAMMA_QUARTER / (4.0 * PI.sqrt());
    assert!((kk - k_exact).abs() < 1e-14, "K(1/√2) = {kk}, exact {k_exact}");
    assert!((ek - (FRAC_PI_2 + k_exact * k_exact) / (2.0 * k_exact)).abs() < 1e-14, "E(1/√2) = {ek}");
    for a in [0.5, 1.0, 2.0, 5.0, 10.0] {
        let (theta0, delta, shortening) = bisshopp_drucker(a);
        let rod =
            PlanarRod { length_m: 1.0, bending_stiffness_nm2: 1.0, shear_stiffness_n: None, axial_stiffness_n: None };
        let s = tip_loaded_cantilever(&rod, a).expect("elastica by shooting");
        assert!((delta + s.tip_y_m).abs() < 1e-9, "a = {a}: delta/L {delta} against {}", -s.tip_y_m);
        assert!((shortening - (1.0 - s.tip_z_m)).abs() < 1e-9, "a = {a}: {shortening} against {}", 1.0 - s.tip_z_m);
        assert!((theta0 - s.tip_angle_rad).abs() < 1e-9, "a = {a}: {theta0} against {}", s.tip_angle_rad);
    }
}

/// The published numbers of the Bisshopp–Drucker benchmark are the elastica's at the case's
/// own PL²/EI, to every printed digit (within half a unit of the fifth decimal): the case's
/// value is the published number, checked here independently of the solver.
#[test]
fn bisshopp_drucker_published_digits_are_the_elastica() {
    let case = Case::from_file(&benchmarks_dir().join("bisshopp_drucker.toml")).unwrap_or_else(|e| panic!("{e}"));
    let (l, p) = (case.mesh.length_m, case.origin.constants["P"]);
    let a = p * l * l / case.props.bend_twist_nm2[0];
    assert!((a - 2.0).abs() < 1e-12, "PL^2/EI = {a}");
    let (_, delta, shortening) = bisshopp_drucker(a);
    let published = |axis: Axis| {
        let q = Quantity::Tip(NodeField::Displacement(axis));
        case.checks.published.values.iter().find(|v| v.quantity == q).map(|v| v.value / l).expect("published value")
    };
    assert!((-published(Axis::Y) - delta).abs() <= 5e-6, "delta/L: published {} against {delta}", -published(Axis::Y));
    assert!(
        (-published(Axis::Z) - shortening).abs() <= 5e-6,
        "(L - Delta)/L: {} against {shortening}",
        -published(Axis::Z)
    );
}

/// The post-buckled elastica's published row (top slope 100°) is the elliptic-integral
/// solution to its printed digits: with p = sin(α/2), √(P/P_cr) = 2K/π, x/L = 2E/K − 1,
/// y/L = 2p/K; and the case loads the column at that ratio.
#[test]
fn postbuckled_elastica_published_digits_are_the_elliptic_solution() {
    use std::f64::consts::{FRAC_PI_2, PI};
    let p = (100f64.to_radians() / 2.0).sin();
    let (kk, ek) = elliptic_f_e(FRAC_PI_2, p);
    let (ratio, x, y) = ((2.0 * kk / PI).powi(2), 2.0 * ek / kk - 1.0, 2.0 * p / kk);
    let case = Case::from_file(&benchmarks_dir().join("postbuckled_elastica.toml")).unwrap_or_else(|e| panic!("{e}"));
    assert!((case.origin.constants["ratio"] - ratio).abs() <= 5e-5, "P/Pcr: {ratio}");
    let l = case.mesh.length_m;
    let published = |axis: Axis| {
        let q = Quantity::Tip(NodeField::Position(axis));
        case.checks.published.values.iter().find(|v| v.quantity == q).map(|v| v.value / l).expect("published value")
    };
    assert!((published(Axis::X) - y).abs() <= 5e-5, "y/L: {} against {y}", published(Axis::X));
    assert!((published(Axis::Z) - x).abs() <= 5e-5, "x/L: {} against {x}", published(Axis::Z));
}

// ------------------------------------------------------ the localised helix of a twisted rod

/// The end conditions of the localised helix (Neukirch, van der Heijden & Thompson 2002, J.
/// Mech. Phys. Solids 50, Eqs. 14–15) in m = M L/B, τ = T L²/B: the shortening
/// `D/L = √(16/τ (1 − m²/(4τ)))` and the end rotation `R = m/γ + 4 acos(m/(2√τ))`, γ = C/B.
fn helix_end_conditions(m: f64, tau: f64, gamma: f64) -> (f64, f64) {
    ((16.0 / tau * (1.0 - m * m / (4.0 * tau))).sqrt(), m / gamma + 4.0 * (m / (2.0 * tau.sqrt())).acos())
}

/// (m, τ) with the given slack ratio D/L and end rotation R [rad], by Newton from (R γ, R²γ²/3)
/// (the pure twist's moment and a tension a little above the straight rod's limit m²/4);
/// the Jacobian by central differences.
fn helix_loads(d_over_l: f64, rotation: f64, gamma: f64) -> (f64, f64) {
    let (mut m, mut tau) = (rotation * gamma, (rotation * gamma).powi(2) / 3.0);
    for _ in 0..60 {
        let (f0, f1) = helix_end_conditions(m, tau, gamma);
        let (r0, r1) = (f0 - d_over_l, f1 - rotation);
        let (hm, ht) = (1e-6 * m, 1e-6 * tau);
        let (mp, mm) = (helix_end_conditions(m + hm, tau, gamma), helix_end_conditions(m - hm, tau, gamma));
        let (tp, tm) = (helix_end_conditions(m, tau + ht, gamma), helix_end_conditions(m, tau - ht, gamma));
        let (j00, j10) = ((mp.0 - mm.0) / (2.0 * hm), (mp.1 - mm.1) / (2.0 * hm));
        let (j01, j11) = ((tp.0 - tm.0) / (2.0 * ht), (tp.1 - tm.1) / (2.0 * ht));
        let det = j00 * j11 - j01 * j10;
        m -= (r0 * j11 - r1 * j01) / det;
        tau -= (j00 * r1 - j10 * r0) / det;
    }
    (m, tau)
}

/// The helical-buckling benchmark's constants m, τ solve its end conditions (to 1e-12
/// relative), the envelope's largest distance from the axis a/k is half the slack, and its
/// published rows are the localised helix of van der Heijden et al. (2003), Eqs. 27, 52:
/// `1 − cos θ = a sech²(kσ)` integrated to `x + iy = (a/k) sech(kσ) e^{iωσ}`,
/// `z = σ − (a/k) tanh(kσ)`, plus the imperfection's tent `F/(2T) (L/2 − |σ|)` along x.
#[test]
fn helical_buckling_published_values_are_the_localised_helix() {
    let case = Case::from_file(&benchmarks_dir().join("helical_buckling.toml")).unwrap_or_else(|e| panic!("{e}"));
    let c = &case.origin.constants;
    let (l, b, cc, d, r, f) = (c["L"], c["B"], c["C"], c["D"], c["R"], c["F"]);
    assert!((r - 27.0 * std::f64::consts::TAU).abs() < 1e-12, "27 turns");
    let (m, tau) = helix_loads(d / l, r, cc / b);
    let (fd, fr) = helix_end_conditions(m, tau, cc / b);
    assert!((fd - d / l).abs() < 1e-13 && (fr - r).abs() < 1e-10, "Newton: {fd} {fr}");
    assert!((c["m"] - m).abs() <= 1e-12 * m && (c["tau"] - tau).abs() <= 1e-12 * tau, "m {m}, tau {tau}");
    let (moment, tension) = (m * b / l, tau * b / (l * l));
    let k = (4.0 * b * tension - moment * moment).sqrt() / (2.0 * b);
    let a = 2.0 - moment * moment / (2.0 * b * tension);
    let omega = moment / (2.0 * b);
    assert!((a / k - d / 2.0).abs() < 1e-12, "a/k = {} against D/2", a / k);
    // the integrated centreline is a unit-speed curve whose tangent makes 1 − cos θ = a sech²
    let position = |sigma: f64| {
        let rho = a / k / (k * sigma).cosh();
        [rho * (omega * sigma).cos(), rho * (omega * sigma).sin(), sigma - a / k * (k * sigma).tanh()]
    };
    for sigma in [-7.0, -1.0, 0.3, 2.0, 9.0] {
        let h = 1e-5;
        let (p, q) = (position(sigma + h), position(sigma - h));
        let t: Vec<f64> = (0..3).map(|i| (p[i] - q[i]) / (2.0 * h)).collect();
        let speed = t.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!((speed - 1.0).abs() < 1e-9, "sigma {sigma}: |x'| = {speed}");
        assert!((1.0 - t[2] - a / (k * sigma).cosh().powi(2)).abs() < 1e-9, "sigma {sigma}: 1 - cos theta");
    }
    let published = |q: &Quantity| {
        case.checks.published.values.iter().find(|v| &v.quantity == q).map(|v| v.value).expect("published value")
    };
    let node = |sigma: f64, axis: Axis| Quantity::Node { s_m: l / 2.0 + sigma, field: NodeField::Position(axis) };
    let tent = |sigma: f64| f / (2.0 * tension) * (l / 2.0 - sigma.abs());
    assert!((published(&node(0.0, Axis::X)) - (position(0.0)[0] + tent(0.0))).abs() < 1e-12);
    assert!((published(&node(1.0 / k, Axis::Y)) - position(1.0 / k)[1]).abs() < 1e-12);
    assert!((published(&node(1.0 / k, Axis::Z)) - position(1.0 / k)[2]).abs() < 1e-12);
}

// ------------------------------------------------------------------------------ the command line

/// The benchmark written to `dir` with `edits` (each pattern once) and its data-free paths.
fn benchmark_with(dir: &Path, edits: &[(&str, &str)]) -> PathBuf {
    let mut text = std::fs::read_to_string(benchmarks_dir().join("bisshopp_drucker.toml")).expect("case");
    for (from, to) in edits {
        text = common::edit(&text, from, to);
    }
    let path = dir.join("bd.toml");
    std::fs::write(&path, text).expect("write case");
    path
}

fn cosserat(args: &[&str], case: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_cosserat")).args(args).arg(case).output().expect("cosserat")
}

/// The fields of `reference.csv` by column name, one map per row.
fn reference_csv(path: &Path) -> Vec<std::collections::BTreeMap<String, String>> {
    let mut r = csv::Reader::from_path(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let header: Vec<String> = r.headers().expect("header").iter().map(String::from).collect();
    r.records().map(|rec| header.iter().cloned().zip(rec.expect("row").iter().map(String::from)).collect()).collect()
}

/// A published value 0.5 % off (−0.49346 L written as −0.49 L) misses: `run` writes it as
/// missed in `reference.csv` and `metrics.json`, says so on stderr, exits 0, and 1 with
/// `--strict`; the right value beside it passes.
#[test]
fn a_wrong_published_value_is_reported_and_strict_exits_1() {
    let dir = tempfile::tempdir().expect("tempdir");
    let case = benchmark_with(
        dir.path(),
        &[("value = \"-0.49346*L\"", "value = \"-0.49*L\""), ("elements = 200", "elements = 100")],
    );
    let out = dir.path().join("out");
    let run = cosserat(&["run", "--quiet", "--out", out.to_str().unwrap()], &case);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "without --strict a miss is reported, not an error: {stderr}");
    assert!(stderr.contains("published tip.displacement_y_m: computed") && stderr.contains("MISS"), "{stderr}");
    assert!(stderr.contains("1 of 2 published values missed"), "{stderr}");
    assert!(stderr.contains("source: Mattiasson (1981)"), "{stderr}");
    let rows = reference_csv(&out.join("reference.csv"));
    assert_eq!(rows.len(), 2);
    assert_eq!((rows[0]["quantity"].as_str(), rows[0]["unit"].as_str()), ("tip.displacement_y_m", "m"));
    assert_eq!((rows[0]["pass"].as_str(), rows[1]["pass"].as_str()), ("false", "true"));
    let (published, computed): (f64, f64) =
        (rows[0]["published"].parse().unwrap(), rows[0]["computed"].parse().unwrap());
    assert_eq!(published, -0.49);
    assert!((computed + 0.49346).abs() < 1.5e-5, "the rod's deflection: {computed}");
    assert!((rows[0]["error"].parse::<f64>().unwrap() - (computed - published)).abs() < 1e-15);
    let metrics: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("metrics.json")).unwrap()).unwrap();
    assert_eq!(metrics["reference.missed"], 1.0);
    assert_eq!(metrics["reference.tip.displacement_y_m.pass"], 0.0);
    let manifest: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("run.json")).unwrap()).unwrap();
    assert_eq!(manifest["status"], "complete");
    assert!(manifest["files"].as_array().unwrap().iter().any(|f| f == "reference.csv"), "{manifest}");

    let strict = cosserat(&["run", "--quiet", "--strict", "--force", "--out", out.to_str().unwrap()], &case);
    assert_eq!(strict.status.code(), Some(1), "{}", String::from_utf8_lossy(&strict.stderr));
    let right = benchmark_with(dir.path(), &[("elements = 200", "elements = 100")]);
    let ok = cosserat(&["run", "--quiet", "--strict", "--force", "--out", out.to_str().unwrap()], &right);
    assert!(ok.status.success(), "{}", String::from_utf8_lossy(&ok.stderr));
    assert!(reference_csv(&out.join("reference.csv")).iter().all(|r| r["pass"] == "true"));
}

/// `compare` evaluates the published values on both engines' results: a table with both, the
/// top folder's `reference.csv` with both values and verdicts, each engine's own
/// `reference.csv`, and exit status 1 when a value misses.
#[test]
fn compare_reports_the_published_values_of_both_engines() {
    if !common::freefem_required() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let case = benchmark_with(
        dir.path(),
        &[("value = \"-0.16064*L\"", "value = \"-0.17*L\""), ("elements = 200", "elements = 100")],
    );
    let out = dir.path().join("cmp");
    let run = cosserat(&["compare", "--out", out.to_str().unwrap()], &case);
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert_eq!(run.status.code(), Some(1), "a missed value fails the comparison: {stdout}");
    assert!(stdout.contains("published values:") && stdout.contains("tip.displacement_z_m [m]"), "{stdout}");
    assert!(String::from_utf8_lossy(&run.stderr).contains("1 of 2 published values MISSED"));
    let rows = reference_csv(&out.join("reference.csv"));
    assert_eq!(rows.len(), 2);
    for (row, pass) in rows.iter().zip(["true", "false"]) {
        assert_eq!((row["rust_pass"].as_str(), row["freefem_pass"].as_str()), (pass, pass), "{row:?}");
        let (r, f): (f64, f64) = (row["rust"].parse().unwrap(), row["freefem"].parse().unwrap());
        assert!((r - f).abs() < 1e-10, "the engines agree: {r} against {f}");
    }
    for engine in ["rust", "freefem"] {
        let own = reference_csv(&out.join(engine).join("reference.csv"));
        assert_eq!(own[1]["pass"], "false", "{engine}: {own:?}");
    }
}

/// A `metric.KEY` that the case's run never writes is refused before anything runs, naming the
/// row and listing the metrics there are; a typo in a quantity names the vocabulary.
#[test]
fn a_quantity_the_run_cannot_compute_is_refused_before_the_run() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let case =
        benchmark_with(dir.path(), &[("quantity = \"tip.displacement_z_m\"", "quantity = \"metric.tip_max_abs_y_m\"")]);
    let run = cosserat(&["run", "--quiet", "--out", out.to_str().unwrap()], &case);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("reference.values[1]")
            && stderr.contains("tip_max_abs_y_m")
            && stderr.contains("reissner_rel_error"),
        "{stderr}"
    );
    assert!(!out.exists(), "nothing is written");
    let compare = cosserat(&["compare", "--out", out.to_str().unwrap()], &case);
    assert_eq!(compare.status.code(), Some(1));
    assert!(!out.exists(), "nothing is written");
    let typo =
        benchmark_with(dir.path(), &[("quantity = \"tip.displacement_z_m\"", "quantity = \"tip.displacment_z_m\"")]);
    let run = cosserat(&["run", "--quiet", "--out", out.to_str().unwrap()], &typo);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    for w in
        ["reference.values[1].quantity", "displacment_z_m", "tip.displacement_x_m", "node(s=S).FIELD", "metric.KEY"]
    {
        assert!(stderr.contains(w), "`{w}` missing from: {stderr}");
    }
}

/// Every form of the vocabulary is documented where a user writing a benchmark reads: the
/// README's table and `docs/benchmarks.md`.
#[test]
fn the_vocabulary_is_documented() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for doc in ["README.md", "docs/benchmarks.md"] {
        let text = std::fs::read_to_string(root.join(doc)).expect(doc);
        for form in VOCABULARY {
            for pattern in form.pattern.split(", ") {
                assert!(text.contains(pattern), "{doc} does not mention `{pattern}`");
            }
        }
    }
}
