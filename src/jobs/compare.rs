//! `cosserat compare`: a case in both engines at a well-defined point, with tolerances derived
//! from the case's measured conditioning (docs/decisions.md D14).
//!
//! - **Where.** Newton runs (static, dynamic, inverse) are compared at their converged roots;
//!   an inverse fixed point, which stops on a sublinear plateau (docs/inverse.md I9), is
//!   compared at the same iterate: FreeFEM runs exactly the iterations Rust needed
//!   (`exactIters`), and the iteration at which FreeFEM first met the tolerance is a row of
//!   its own. Clips: the first `frames` frames, consecutive, warm-started and re-based by
//!   both engines ([`crate::engine::run_freefem_clip`]).
//! - **Tolerances.** The Rust engine runs the case a second time with its input perturbed at
//!   [`PERTURBATION`] (relative): the data x_g of an inverse case or a clip, the stiffnesses
//!   and inertias of a forward case. For every compared quantity q, with σ_q the perturbed
//!   run's change and τ the solver's stopping tolerance (0 at an equal iteration count),
//!
//!   ```text
//!   field rows:     tol = S (σ + τ) + ε_f
//!   scalar metrics: tol = S (σ + τ |q|) + ε_f |q| + ε_a
//!   iterations:     tol = 1 + S σ
//!   ```
//!   with S = [`SAFETY`], ε_f = [`FLOOR_REL`], ε_a = ε_f × (L for lengths, 1 rad for angles).
//!   A `[compare]` value overrides its group (with the case's `reason`).
use std::path::{Path, PathBuf};

use nalgebra::Vector3;

use crate::case::{Analysis, Case, CompareOverrides};
use crate::engine::clip::solve_frames;
use crate::engine::frames::{SolvedFrame, SolvedFrames};
use crate::engine::input::clip_files::load_clip;
use crate::engine::input::data::write_data;
use crate::engine::metrics::{all_metrics, differences, ComparisonRow, Difference, Group, Iterations};
use crate::engine::{load_data, EngineError};
use crate::engine::{run_forward, run_inverse, NodalState, RunError, RunResult};
use crate::engine::{run_freefem, run_freefem_clip, run_freefem_inverse, FreeFemFrames, RunOptions};
use crate::io::files::{write_atomic, OutputError};
use crate::output::run_files::write_run;
use crate::solve::certificate::CERTIFICATE_FLOOR;
use crate::solve::{inverse::InverseMethod, sequence::ClipData, statics::Method, SolveError, PLATEAU_ITERATIONS};

/// Relative size of the input perturbation that measures a case's conditioning: 450 ulps, far
/// above the engines' own round-off and far below any physical change.
pub const PERTURBATION: f64 = 1e-13;
/// Safety factor on the measured sensitivity.
pub const SAFETY: f64 = 10.0;
/// Relative floor of every tolerance (a quantity that the perturbation does not move at all).
pub const FLOOR_REL: f64 = 1e-12;
/// Short horizon (`--short`): time steps of a dynamic case.
pub const SHORT_STEPS: usize = 200;
/// Short horizon: iterations of an inverse fixed point (both engines run exactly these).
pub const SHORT_ITERATIONS: usize = 40;
/// Short horizon: frames of a clip.
pub const SHORT_FRAMES: usize = 3;

/// How much of a case is compared.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Horizon {
    /// the whole run; a clip's `[compare] frames` (or `frames`)
    #[default]
    Full,
    /// [`SHORT_STEPS`] time steps, [`SHORT_ITERATIONS`] fixed-point iterations,
    /// [`SHORT_FRAMES`] clip frames: every case within seconds to a minute of FreeFEM
    Short,
}

/// Options of [`compare_case`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CompareOptions {
    pub horizon: Horizon,
    /// clip frames to compare: `None` the case's `[compare] frames` (or the short horizon's),
    /// `Some(usize::MAX)` the whole clip
    pub frames: Option<usize>,
}

/// One clip frame's cost in both engines.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameTime {
    pub frame: usize,
    /// wall time of the frame's solve [s]
    pub rust_s: f64,
    /// FreeFEM's CPU time of the frame [s]
    pub freefem_s: f64,
    pub rust_iterations: usize,
    pub freefem_iterations: usize,
}

/// The outcome of a comparison.
#[derive(Debug)]
pub struct CompareReport {
    pub case: String,
    pub rows: Vec<ComparisonRow>,
    /// what was compared, in words (iterations, steps, frames)
    pub what: String,
    pub rust_wall_s: f64,
    pub freefem_wall_s: f64,
    /// clip comparisons: per frame, both engines' time and iterations
    pub frame_times: Vec<FrameTime>,
    /// single runs: both results (for their output folders)
    pub runs: Option<(RunResult, RunResult)>,
}

impl CompareReport {
    pub fn failed(&self) -> usize {
        self.rows.iter().filter(|r| !r.passed()).count()
    }
}

/// Errors of a comparison.
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    #[error(transparent)]
    Engine(#[from] EngineError),
    #[error("rust engine on the perturbed input (conditioning run)")]
    Perturbed(#[source] EngineError),
    #[error("case `{0}` is not a clip case: `--frames` applies to clips only")]
    FramesWithoutClip(String),
}

impl From<RunError> for CompareError {
    fn from(e: RunError) -> Self {
        CompareError::Engine(e.into())
    }
}

/// Compare `case` in both engines in `dir` (`dir/data.csv`, `dir/freefem_work/`).
pub fn compare_case(case: &Case, dir: &Path, opts: &CompareOptions) -> Result<CompareReport, CompareError> {
    if case.clip().is_some() {
        compare_clip(case, dir, opts)
    } else if opts.frames.is_some() {
        Err(CompareError::FramesWithoutClip(case.name.clone()))
    } else {
        compare_single(case, dir, opts)
    }
}

/// Deterministic numbers in [−1, 1] (splitmix64): the perturbation's pattern.
fn pattern(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// Positions perturbed by [`PERTURBATION`] × their largest coordinate, node by node.
pub fn perturb_positions(x: &[Vector3<f64>], seed: u64) -> Vec<Vector3<f64>> {
    let scale = x.iter().fold(0.0_f64, |m, v| m.max(v.amax())) * PERTURBATION;
    let mut r = pattern(seed);
    x.iter().map(|v| v + Vector3::new(r(), r(), r()) * scale).collect()
}

/// The case with its stiffnesses, inertias and mass perturbed by [`PERTURBATION`] (relative).
pub fn perturb_material(case: &Case) -> Case {
    let mut c = case.clone();
    let mut r = pattern(7);
    let p = &mut c.props;
    for v in [&mut p.shear_stretch_n, &mut p.bend_twist_nm2, &mut p.rotary_inertia_kg_m] {
        for k in 0..3 {
            v[k] *= 1.0 + PERTURBATION * r();
        }
    }
    p.mass_per_length_kg_m *= 1.0 + PERTURBATION * r();
    c
}

/// The solver's stopping tolerance τ of a run compared at its converged point (relative
/// change of the unknowns, D5/I8); 0 for the inverse fixed point compared at an equal count.
pub fn stop_tolerance(case: &Case) -> f64 {
    match &case.analysis {
        Analysis::Static(p) => p.tolerance,
        Analysis::Dynamic(p) => p.newton_tolerance,
        Analysis::Inverse(inv) => match inv.params.method {
            InverseMethod::FixedPoint => 0.0,
            InverseMethod::Newton { .. } => inv.params.tolerance,
        },
    }
}

/// Whether the rows include the iteration count (the same algorithm and rule in both engines,
/// not compared at an equal count by construction).
fn counts_compared(case: &Case) -> Iterations {
    match &case.analysis {
        Analysis::Static(p) if matches!(p.method, Method::FixedPoint { .. }) => Iterations::Compared,
        Analysis::Inverse(inv) if matches!(inv.params.method, InverseMethod::Newton { .. }) => Iterations::Compared,
        Analysis::Static(_) | Analysis::Dynamic(_) | Analysis::Inverse(_) => Iterations::Ignored,
    }
}

fn is_fixed_point_inverse(case: &Case) -> bool {
    matches!(case.inverse().map(|i| i.params.method), Some(InverseMethod::FixedPoint))
}

/// The tolerance of one row and how it was found; `sens` the perturbed run's differences.
fn tolerance(d: &Difference, sens: &[Difference], tau: f64, case: &Case) -> (f64, String) {
    let o: &CompareOverrides = &case.checks.compare.overrides;
    let reason = || format!("override: {}", case.checks.compare.reason.as_deref().unwrap_or(""));
    let value = d.a.unwrap_or(0.0).abs();
    let over = match d.group {
        Group::Displacement => o.displacement_rel,
        Group::Angles => o.angles_rel,
        Group::Adjoint => o.adjoint_rel,
        Group::Iterations => o.iterations_abs,
        Group::Certificate => None,
        Group::Metric => match (o.metric_rel, o.metric_abs) {
            (None, None) => None,
            (r, a) => Some(r.unwrap_or(0.0) * value + a.unwrap_or(0.0)),
        },
    };
    if let Some(t) = over {
        return (t, reason());
    }
    let own = sens.iter().find(|s| s.name == d.name).map(|s| s.difference).filter(|s| s.is_finite());
    // A single perturbation can leave one scalar nearly unchanged by chance: the field row
    // that bounds it (a maximum over every node) gives the floor of its sensitivity.
    let via_field = d.bound.and_then(|(group, scale)| {
        let f = sens.iter().filter(|s| s.group == group && s.a.is_none()).map(|s| s.difference).fold(0.0, f64::max);
        (f * scale).is_finite().then_some(f * scale)
    });
    let sigma = match (own, via_field) {
        (Some(a), Some(b)) => a.max(b),
        (Some(a), None) | (None, Some(a)) => a,
        (None, None) => f64::INFINITY,
    };
    let t = match d.group {
        Group::Iterations => 1.0 + SAFETY * sigma,
        // A certificate is relative, like a relative change: two engines stopped by a change
        // within τ can differ by about τ in it (the residual of an iterate a change τ from the
        // root); below ten times the floor both have solved the same equations, whatever the
        // digits (docs/certificate.md)
        Group::Certificate => SAFETY * (sigma + tau) + 10.0 * CERTIFICATE_FLOOR,
        Group::Metric => {
            let abs = if d.name.ends_with("_m") {
                FLOOR_REL * case.mesh.length_m
            } else if d.name.ends_with("_rad") {
                FLOOR_REL
            } else {
                0.0
            };
            SAFETY * (sigma + tau * value) + FLOOR_REL * value + abs
        }
        _ => SAFETY * (sigma + tau) + FLOOR_REL,
    };
    (t, format!("derived: sigma {sigma:.1e}, tau {tau:.0e}"))
}

/// Rows of a comparison from the Rust–FreeFEM differences and the Rust–perturbed ones.
fn rows(case: &Case, tau: f64, diffs: &[Difference], sens: &[Difference]) -> Vec<ComparisonRow> {
    diffs
        .iter()
        .map(|d| {
            let (tol, basis) = tolerance(d, sens, tau, case);
            ComparisonRow {
                name: d.name.clone(),
                rust: d.a,
                freefem: d.b,
                difference: d.difference,
                tolerance: tol,
                basis,
            }
        })
        .collect()
}

/// The first iteration at which the relative change had met `tol` in
/// [`PLATEAU_ITERATIONS`] consecutive iterations (the fixed point's natural stop, C4), if any.
fn natural_stop(r: &RunResult, tol: f64) -> Option<usize> {
    let h = &r.inverse.as_ref()?.history;
    h.windows(PLATEAU_ITERATIONS).find(|w| w.iter().all(|r| r.rel_change <= tol)).map(|w| w[w.len() - 1].iteration)
}

/// Rust inverse run for exactly `n` fixed-point iterations (the tolerance ignored).
fn rust_exact(case: &Case, data: &NodalState, n: usize) -> Result<RunResult, RunError> {
    let mut c = case.clone();
    if let Analysis::Inverse(inv) = &mut c.analysis {
        inv.params.tolerance = -1.0;
        inv.params.max_iterations = n;
    }
    match run_inverse(&c, data, |_, _| {}) {
        Ok(r) => Ok(r),
        Err(RunError::Incomplete { partial, .. }) if partial.stats.iterations == n => Ok(*partial),
        Err(e) => Err(e),
    }
}

/// A Rust inverse run whose end is a result to compare: converged, or stalled (the paper's
/// fixed point at its stopping rule; its last iterate, which FreeFEM reaches too, with its
/// certificate, docs/certificate.md C4).
fn comparable(run: Result<RunResult, RunError>) -> Result<RunResult, RunError> {
    match run {
        Err(RunError::Incomplete { source: SolveError::Stalled(_), partial }) => Ok(*partial),
        other => other,
    }
}

fn compare_single(case: &Case, dir: &Path, opts: &CompareOptions) -> Result<CompareReport, CompareError> {
    let short = opts.horizon == Horizon::Short;
    let case = if short { case.time_prefix(SHORT_STEPS) } else { case.clone() };
    let work = dir.join("freefem_work");
    let tau = stop_tolerance(&case);
    let (rust, perturbed, ff, what) = if let Some(inv) = case.inverse() {
        let data = load_data(&case).map_err(CompareError::Engine)?;
        let path = dir.join("data.csv");
        write_data(&path, &data).map_err(EngineError::DataOutput)?;
        let pert = NodalState { x: perturb_positions(&data.x, 11), ..data.clone() };
        let fixed_point = is_fixed_point_inverse(&case);
        let (rust, perturbed, exact) = if fixed_point {
            let rust = if short {
                rust_exact(&case, &data, SHORT_ITERATIONS)?
            } else {
                comparable(run_inverse(&case, &data, |_, _| {}))?
            };
            let n = rust.stats.iterations;
            let p = rust_exact(&case, &pert, n).map_err(|e| CompareError::Perturbed(e.into()))?;
            (rust, p, Some(n))
        } else {
            let rust = comparable(run_inverse(&case, &data, |_, _| {}))?;
            let p = comparable(run_inverse(&case, &pert, |_, _| {})).map_err(|e| CompareError::Perturbed(e.into()))?;
            (rust, p, None)
        };
        let ro = RunOptions { exact_iterations: exact, clip: None };
        let ff = run_freefem_inverse(&case, data, &path, &work, &ro).map_err(EngineError::from)?;
        let what = match exact {
            Some(n) => format!("inverse fixed point, both engines at iteration {n}"),
            None => format!("inverse Newton (I8) to the root, tolerance {:e}", inv.params.tolerance),
        };
        (rust, perturbed, ff, what)
    } else {
        let rust = run_forward(&case, |_, _| {})?;
        let p = run_forward(&perturb_material(&case), |_, _| {}).map_err(|e| CompareError::Perturbed(e.into()))?;
        let ff = run_freefem(&case, &work).map_err(EngineError::from)?;
        let what = match &case.analysis {
            Analysis::Dynamic(p) => format!("dynamic, {} time steps", p.steps),
            Analysis::Static(p) if p.path.is_some() => "static arc-length path (D25), to the tolerance".to_string(),
            _ => "static, to the solver's tolerance".to_string(),
        };
        (rust, p, ff, what)
    };
    let counts = counts_compared(&case);
    let mut out = rows(&case, tau, &differences(&rust, &ff, counts), &differences(&rust, &perturbed, counts));
    // An inverse fixed point compared at an equal count: where would FreeFEM have stopped?
    if let (Some(inv), false) = (case.inverse().filter(|_| is_fixed_point_inverse(&case)), short) {
        let tol = inv.params.tolerance;
        let n = rust.stats.iterations;
        let f = natural_stop(&ff, tol).unwrap_or(n + 1);
        let p = natural_stop(&perturbed, tol).unwrap_or(n + 1);
        let d = Difference {
            name: "iterations_to_tolerance".into(),
            group: Group::Iterations,
            a: Some(n as f64),
            b: Some(f as f64),
            difference: (n as f64 - f as f64).abs(),
            bound: None,
        };
        let s = Difference { difference: (n as f64 - p as f64).abs(), ..d.clone() };
        out.extend(rows(&case, tau, &[d], &[s]));
    }
    Ok(CompareReport {
        case: case.name.clone(),
        rows: out,
        what,
        rust_wall_s: rust.stats.wall_time_s,
        freefem_wall_s: ff.stats.wall_time_s,
        frame_times: Vec::new(),
        runs: Some((rust, ff)),
    })
}

fn compare_clip(case: &Case, dir: &Path, opts: &CompareOptions) -> Result<CompareReport, CompareError> {
    let (clip, _) = load_clip(case).map_err(EngineError::from)?;
    // weights = "auto": λg chosen once (in Rust, docs/noise.md N2), then both engines use it
    let auto = crate::engine::weights::choose_weights(case, &clip.frames);
    let case = auto.as_ref().map_or(case, |a| &a.case);
    let default = match opts.horizon {
        Horizon::Full => case.checks.compare.frames,
        Horizon::Short => SHORT_FRAMES,
    };
    let n = opts.frames.unwrap_or(default).min(clip.frames.len()).max(1);
    let tracked = clip.tracked.as_deref().map(|t| &t[..n]);
    let runs = solve_clip_both(case, ClipData { positions: &clip.frames[..n], tracked }, dir)?;
    let tau = stop_tolerance(case);
    let fixed_point = is_fixed_point_inverse(case);
    // a fixed point's frames run the same count in both engines by construction
    let counts = if fixed_point { Iterations::Ignored } else { Iterations::Compared };
    let per_frame = compare_frames(case, tau, counts, &runs);
    let mut out = per_frame.worst;
    out.push(frames_solved_row(n, &runs));
    out.push(ComparisonRow {
        name: "restarted_frames_differing".into(),
        rust: None,
        freefem: None,
        difference: per_frame.restarts,
        tolerance: 0.0,
        basis: "restart from the data guess in one engine only".into(),
    });
    let first = runs.rust.frames.first().map_or(0, |f| f.frame);
    let what = format!(
        "clip frames {first}-{} ({n} frames), {}",
        first + n - 1,
        if fixed_point {
            "fixed point at Rust's iteration count per frame".to_string()
        } else {
            format!("Newton to tolerance {tau:e} per frame")
        }
    );
    Ok(CompareReport {
        case: case.name.clone(),
        rows: out,
        what,
        rust_wall_s: runs.rust.wall_time_s,
        freefem_wall_s: runs.freefem.wall_time_s,
        frame_times: per_frame.times,
        runs: None,
    })
}

/// A clip's frames solved by both engines, and by Rust again on perturbed data (the
/// sensitivity a difference is judged against).
struct ClipRuns {
    rust: SolvedFrames,
    perturbed: SolvedFrames,
    freefem: FreeFemFrames,
}

/// Solve `clip` in Rust, in Rust on perturbed positions, and in FreeFEM (in `dir/freefem_work`; a
/// fixed point at Rust's iteration count; restarted where Rust restarted, a branch too).
fn solve_clip_both(case: &Case, clip: ClipData<'_>, dir: &Path) -> Result<ClipRuns, CompareError> {
    let (frames, tracked) = (clip.positions, clip.tracked);
    let rust = solve_frames(case, ClipData { positions: frames, tracked })?;
    let pert: Vec<Vec<Vector3<f64>>> =
        frames.iter().enumerate().map(|(f, x)| perturb_positions(x, 1000 + f as u64)).collect();
    let perturbed =
        solve_frames(case, ClipData { positions: &pert, tracked }).map_err(|e| CompareError::Perturbed(e.into()))?;
    let n = |f: &SolvedFrame| if is_fixed_point_inverse(case) { f.result.stats.iterations } else { 0 };
    let exact: Option<Vec<(usize, bool)>> = Some(rust.frames.iter().map(|f| (n(f), f.restarted)).collect());
    let work = dir.join("freefem_work");
    let freefem = run_freefem_clip(case, ClipData { positions: frames, tracked }, exact.as_deref(), &work)
        .map_err(EngineError::from)?;
    Ok(ClipRuns { rust, perturbed, freefem })
}

/// The frames of both engines compared: per quantity the row of the frame with the largest
/// difference/tolerance ratio, the frames restarted in one engine only, each frame's cost.
struct FrameComparison {
    worst: Vec<ComparisonRow>,
    restarts: f64,
    times: Vec<FrameTime>,
}

/// Compare the frames of `runs` (their iteration counts as `counts` says).
fn compare_frames(case: &Case, tau: f64, counts: Iterations, runs: &ClipRuns) -> FrameComparison {
    let mut worst: Vec<(ComparisonRow, usize, f64)> = Vec::new();
    let mut restarts = 0.0;
    let mut times = Vec::new();
    for (r, f) in runs.rust.frames.iter().zip(&runs.freefem.frames) {
        let p: Option<&SolvedFrame> = runs.perturbed.frames.iter().find(|p| p.frame == r.frame);
        let sens = p.map(|p| differences(&r.result, &p.result, counts)).unwrap_or_default();
        for row in rows(case, tau, &differences(&r.result, &f.result, counts), &sens) {
            let ratio = if row.tolerance > 0.0 { row.difference / row.tolerance } else { f64::INFINITY };
            match worst.iter_mut().find(|w| w.0.name == row.name) {
                Some(w) if w.2 >= ratio => {}
                Some(w) => *w = (row, r.frame, ratio),
                None => worst.push((row, r.frame, ratio)),
            }
        }
        restarts += f64::from(u8::from(r.restarted != f.restarted));
        times.push(FrameTime {
            frame: r.frame,
            rust_s: r.result.stats.wall_time_s,
            freefem_s: f.result.stats.wall_time_s,
            rust_iterations: r.result.stats.iterations,
            freefem_iterations: f.result.stats.iterations,
        });
    }
    let worst = worst
        .into_iter()
        .map(|(mut row, frame, _)| {
            row.basis = format!("{} (worst: frame {frame})", row.basis);
            row
        })
        .collect();
    FrameComparison { worst, restarts, times }
}

/// The row `frames_solved`: every one of the `n` requested frames solved by both engines, else
/// why not.
fn frames_solved_row(n: usize, runs: &ClipRuns) -> ComparisonRow {
    let (a, b) = (runs.rust.frames.len(), runs.freefem.frames.len());
    let why = |e: Option<String>| e.unwrap_or_else(|| "all frames solved".into());
    ComparisonRow {
        name: "frames_solved".into(),
        rust: Some(a as f64),
        freefem: Some(b as f64),
        difference: (n - a.min(b)) as f64 + (a as f64 - b as f64).abs(),
        tolerance: 0.0,
        basis: format!(
            "rust: {}; freefem: {}",
            why(runs.rust.error.as_ref().map(|e| e.to_string())),
            why(runs.freefem.error.clone())
        ),
    }
}

/// `compare.csv` of a report: one row per compared quantity.
pub fn report_csv(report: &CompareReport) -> String {
    let mut s = String::from("quantity,rust,freefem,difference,tolerance,result,basis\n");
    let v = |x: Option<f64>| x.map(|x| format!("{x:e}")).unwrap_or_default();
    for r in &report.rows {
        s.push_str(&format!(
            "{},{},{},{:e},{:e},{},\"{}\"\n",
            r.name,
            v(r.rust),
            v(r.freefem),
            r.difference,
            r.tolerance,
            if r.passed() { "pass" } else { "FAIL" },
            r.basis.replace('"', "'")
        ));
    }
    s
}

/// `compare_frames.csv` of a clip comparison: per frame, both engines' time and iterations.
pub fn frames_csv(report: &CompareReport) -> String {
    let mut csv = String::from("frame,rust_wall_s,freefem_wall_s,rust_iterations,freefem_iterations\n");
    for t in &report.frame_times {
        csv.push_str(&format!(
            "{},{:e},{:e},{},{}\n",
            t.frame, t.rust_s, t.freefem_s, t.rust_iterations, t.freefem_iterations
        ));
    }
    csv
}

/// Where a comparison writes (`out/<case>` unless given).
pub fn default_dir(case: &Case) -> PathBuf {
    PathBuf::from("out").join(&case.name)
}

/// Write what `cosserat compare` keeps in `dir`: both engines' outputs (single runs),
/// `compare.csv` and, for clips, `compare_frames.csv`.
pub fn write_compare(case: &Case, report: &CompareReport, dir: &Path) -> Result<(), OutputError> {
    if let Some((rust, ff)) = &report.runs {
        let metrics = |r: &RunResult| {
            all_metrics(case, r).map_err(|e| OutputError::Invalid { path: dir.to_path_buf(), reason: e.to_string() })
        };
        write_run(case, rust, &metrics(rust)?, &dir.join("rust"))?;
        write_run(case, ff, &metrics(ff)?, &dir.join("freefem"))?;
    }
    write_atomic(&dir.join("compare.csv"), report_csv(report).as_bytes())?;
    if !report.frame_times.is_empty() {
        write_atomic(&dir.join("compare_frames.csv"), frames_csv(report).as_bytes())?;
    }
    Ok(())
}

/// The comparison as a table for the terminal: one line per row (values, difference,
/// tolerance, verdict, where the tolerance comes from), per-frame times of a clip, wall times.
pub fn report_table(case: &Case, report: &CompareReport) -> String {
    let mut out = format!("{}: {}\n", case.name, report.what);
    out += &format!(
        "{:<34} {:>15} {:>15} {:>11} {:>11}  result  tolerance from\n",
        "quantity", "rust", "freefem", "|diff|", "tolerance"
    );
    for r in &report.rows {
        let v = |x: Option<f64>| x.map(|x| format!("{x:.8e}")).unwrap_or_else(|| "-".into());
        out += &format!(
            "{:<34} {:>15} {:>15} {:>11.3e} {:>11.3e}  {:<6}  {}\n",
            r.name,
            v(r.rust),
            v(r.freefem),
            r.difference,
            r.tolerance,
            if r.passed() { "PASS" } else { "FAIL" },
            r.basis
        );
    }
    if !report.frame_times.is_empty() {
        let t = &report.frame_times;
        let n = t.len() as f64;
        let (r, f) = (t.iter().map(|t| t.rust_s).sum::<f64>(), t.iter().map(|t| t.freefem_s).sum::<f64>());
        out += &format!(
            "per frame: rust {:.1} ms, freefem {:.2} s (ratio {:.0}); iterations per frame rust {:.2}, freefem {:.2}\n",
            1e3 * r / n,
            f / n,
            f / r,
            t.iter().map(|t| t.rust_iterations).sum::<usize>() as f64 / n,
            t.iter().map(|t| t.freefem_iterations).sum::<usize>() as f64 / n
        );
    }
    out += &format!(
        "wall time: rust {:.3} s, freefem {:.3} s (ratio freefem/rust {:.1})\n",
        report.rust_wall_s,
        report.freefem_wall_s,
        report.freefem_wall_s / report.rust_wall_s
    );
    out
}
