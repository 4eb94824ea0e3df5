//! FreeFEM runner: writes the case as a FreeFEM include file (`case.idp`), runs
//! `freefem/forward.edp` headless in a work directory and reads its CSV output back into a
//! [`RunResult`]. The scripts hold no physical constant: everything comes from `case.idp`.
//!
//! The scripts compute the residual certificate of `docs/certificate.md` as the Rust engine does
//! (`freefem/certificate.idp`) and end a run whose stopping rule was met but whose certificate is
//! above `solver.certificate_tolerance` with exit status 3 and `STALLED: …`, a static or inverse
//! run at its iteration limit with 4; both are read back as [`FreeFemError::Incomplete`] with the
//! error the Rust engine gives ([`SolveError::Stalled`], `…NotConverged`) and the last iterate
//! (`crate::engine` turns it into `RunError::Incomplete`).
pub mod clip;
pub mod include;
pub mod info;
pub mod modes;
pub mod path;
pub mod progress;
pub mod stability;

use std::path::{Path, PathBuf};
use std::process::Command;

use nalgebra::Vector3;

pub use self::include::{include_file, ClipInclude, RunOptions};
use self::info::FfInfo;
use self::progress::Watch;
use crate::case::{Analysis, Case};
use crate::engine::common::angles_known;
use crate::engine::common::result::{Engine, InverseOutput, NodalState, RunResult, SolverStats};
use crate::io::files::{csv_reader, InputError};
use crate::model::balance::Balance;
use crate::model::chart::Chart;
use crate::solve::certificate::{Certificate, System};
use crate::solve::dynamics::TipRecord;
use crate::solve::inverse::{InverseRecord, ObjectiveTerms};
use crate::solve::statics::{IterationRecord, Method};
use crate::solve::{SolveError, Step, Stop};

/// Environment variable pointing at the `freefem/` script directory (default: the crate's).
pub const SCRIPT_DIR_ENV: &str = "COSSERAT_FREEFEM_DIR";
/// Executable name.
pub const EXECUTABLE: &str = "FreeFem++";
/// How to install FreeFEM on Debian.
pub const INSTALL_HINT: &str = "install it with: apt-get update && apt-get install -y freefem++ libfreefem++";

/// Errors at the FreeFEM boundary.
#[derive(Debug, thiserror::Error)]
pub enum FreeFemError {
    #[error("`{EXECUTABLE}` was not found on PATH; {INSTALL_HINT}")]
    NotInstalled,
    #[error("FreeFEM script directory {0} does not contain forward.edp (set {SCRIPT_DIR_ENV})")]
    MissingScripts(PathBuf),
    #[error("I/O error on {path}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("FreeFEM failed (exit status {status}) in {workdir}:\n{output}")]
    Failed { status: i32, workdir: PathBuf, output: String },
    #[error("{0}")]
    Unsupported(&'static str),
    #[error("case `{0}` is not an inverse case")]
    NotInverse(String),

    #[error("FreeFEM was stopped by a signal (interrupted) in {workdir}")]
    Interrupted { workdir: PathBuf },
    #[error("FreeFEM output {path}: {reason}")]
    BadOutput { path: PathBuf, reason: String },
    #[error("cannot read FreeFEM output")]
    Read(#[from] InputError),
    /// FreeFEM met its stopping rule but the certificate of its result is above the tolerance
    /// (exit status [`STALLED_STATUS`]), or it reached its iteration limit
    /// ([`ITERATION_LIMIT_STATUS`]): `source` is the error the Rust engine gives for it,
    /// `partial` the last iterate and its history.
    #[error("freefem engine stopped without a certified result")]
    Incomplete { source: SolveError, partial: Box<RunResult> },
}

/// Exit status of a FreeFEM script whose result is stalled (`STALLED: …`, docs/certificate.md C4).
pub const STALLED_STATUS: i32 = 3;
/// Exit status of a static or single-frame inverse FreeFEM run that reached its iteration limit
/// (`FAILED: …`); its outputs hold the last iterate.
pub const ITERATION_LIMIT_STATUS: i32 = 4;
/// Exit status of a FreeFEM script that failed after writing what it had (`FAILED: …`; the
/// clip script: the frames before its failed frame, and that frame's code in `ff_info.csv`).
pub const FAILED_STATUS: i32 = 2;

/// A certificate column of FreeFEM's inverse histories: −1 marks a record without one.
fn optional_certificate(v: f64) -> Option<f64> {
    (v >= 0.0).then_some(v)
}

/// Run `script`: how it ended when its outputs hold a result (the last iterate when not
/// converged), as the Rust engine's solvers say it ([`Stop`]: exit status 0 converged,
/// [`STALLED_STATUS`] stalled, [`ITERATION_LIMIT_STATUS`] the iteration limit), else the error.
fn execute_to_end(
    case: &Case,
    workdir: &Path,
    script: &str,
    outputs: &[&str],
    opts: &RunOptions,
) -> Result<Stop, FreeFemError> {
    match execute(case, workdir, script, outputs, opts) {
        Ok(()) => Ok(Stop::Converged),
        Err(FreeFemError::Failed { status: STALLED_STATUS, .. }) => Ok(Stop::Stalled),
        Err(FreeFemError::Failed { status: ITERATION_LIMIT_STATUS, .. }) => Ok(Stop::MaxIterations),
        Err(e) => Err(e),
    }
}

/// The I/O error on `path`, for `map_err`.
pub(super) fn io(path: &Path) -> impl FnOnce(std::io::Error) -> FreeFemError {
    let path = path.to_path_buf();
    move |source| FreeFemError::Io { path, source }
}

/// Directory holding `forward.edp` and `rotation.idp`.
pub fn script_dir() -> PathBuf {
    std::env::var_os(SCRIPT_DIR_ENV)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/freefem")))
}

/// Path of the FreeFEM executable, if installed.
pub fn find_executable() -> Result<PathBuf, FreeFemError> {
    let path = std::env::var_os("PATH").ok_or(FreeFemError::NotInstalled)?;
    std::env::split_paths(&path).map(|d| d.join(EXECUTABLE)).find(|p| p.is_file()).ok_or(FreeFemError::NotInstalled)
}

/// The outputs of `inverse.edp`.
const INVERSE_OUTPUTS: [&str; 3] = ["ff_inverse_nodes.csv", "ff_inverse_history.csv", "ff_info.csv"];

/// Run `freefem/inverse.edp` on an inverse case with the data file `data_path` (copied into
/// `workdir` as `data.csv` unless it is already there). `data` is the parsed content of that file.
pub fn run_inverse(
    case: &Case,
    data: NodalState,
    data_path: &Path,
    workdir: &Path,
    opts: &RunOptions,
) -> Result<RunResult, FreeFemError> {
    let inv = case.inverse().ok_or_else(|| FreeFemError::NotInverse(case.name.clone()))?;
    stage_data(data_path, workdir)?;
    let end = execute_to_end(case, workdir, "inverse.edp", &INVERSE_OUTPUTS, opts)?;
    let nodes = read_inverse_nodes(case, workdir)?;
    let history = read_inverse_history(workdir)?;
    let (stats, certificate) = read_inverse_info(workdir)?;
    let stop = inverse_stop(end, &history, certificate, inv.params.certificate_tolerance);
    let w = inv.params.weights;
    let result = RunResult {
        engine: Engine::Freefem,
        nodes: nodes.state,
        history: Vec::new(),
        tip: Vec::new(),
        stats,
        inverse: Some(InverseOutput {
            data,
            angles_known: angles_known(case),
            xhat: nodes.xhat,
            ahat: nodes.ahat,
            history,
            kappa_err: Vec::new(),
            lambda_f: w.lambda_f,
            lambda_l: w.lambda_l,
        }),
        path: None,
        stability: None,
    };
    match stop {
        Some(source) => Err(FreeFemError::Incomplete { source, partial: Box::new(result) }),
        None => Ok(result),
    }
}

/// Copy the data file `data_path` into `workdir` as `data.csv` (which `inverse.edp` reads),
/// unless it is that file already.
fn stage_data(data_path: &Path, workdir: &Path) -> Result<(), FreeFemError> {
    std::fs::create_dir_all(workdir).map_err(io(workdir))?;
    let target = workdir.join("data.csv");
    let same = std::fs::canonicalize(data_path)
        .ok()
        .zip(std::fs::canonicalize(&target).ok())
        .map(|(a, b)| a == b)
        .unwrap_or(false);
    if !same {
        std::fs::copy(data_path, &target).map_err(io(&target))?;
    }
    Ok(())
}

/// The node table of `inverse.edp`: the state and the adjoints `x̂`, `α̂` per node.
struct InverseNodes {
    state: NodalState,
    xhat: Vec<Vector3<f64>>,
    ahat: Vec<Vector3<f64>>,
}

/// Read `ff_inverse_nodes.csv` of `workdir`, one row per node of the case's mesh.
fn read_inverse_nodes(case: &Case, workdir: &Path) -> Result<InverseNodes, FreeFemError> {
    let nodes_path = workdir.join("ff_inverse_nodes.csv");
    let mut header = vec!["s_m", "x_m", "y_m", "z_m", "alpha_rad", "beta_rad", "gamma_rad"];
    header.extend(["xhat_1", "xhat_2", "xhat_3", "ahat_1", "ahat_2", "ahat_3"]);
    let rows = read_table(&nodes_path, &header)?;
    if rows.len() != case.mesh.nodes() {
        return Err(FreeFemError::BadOutput {
            path: nodes_path,
            reason: format!("{} rows, expected {}", rows.len(), case.mesh.nodes()),
        });
    }
    let v3 = |k: usize| rows.iter().map(|r| Vector3::new(r[k], r[k + 1], r[k + 2])).collect();
    let state = NodalState {
        s: rows.iter().map(|r| r[0]).collect(),
        x: v3(1),
        alpha: v3(4),
        chart: Chart::default(),
        reference_x: None,
    };
    Ok(InverseNodes { state, xhat: v3(7), ahat: v3(10) })
}

/// The columns of `ff_tip.csv` (a dynamic run: the tip and the balance per time step, forward.edp).
const TIP_COLUMNS: [&str; 18] = [
    "time_s",
    "x_m",
    "y_m",
    "z_m",
    "alpha_rad",
    "beta_rad",
    "gamma_rad",
    "newton_iterations",
    "certificate",
    "kinetic_j",
    "elastic_j",
    "px",
    "py",
    "pz",
    "hx",
    "hy",
    "hz",
    "loaded",
];

/// Read the iteration history `ff_inverse_history.csv` of `workdir`.
fn read_inverse_history(workdir: &Path) -> Result<Vec<InverseRecord>, FreeFemError> {
    let mut header = vec!["iteration", "rel_change", "x_err_rel", "tangent_misfit"];
    header.extend(ObjectiveTerms::NAMES);
    header.extend(["newton_residual", "certificate"]);
    let rows = read_table(&workdir.join("ff_inverse_history.csv"), &header)?;
    Ok(rows
        .into_iter()
        .map(|r| InverseRecord {
            iteration: r[0] as usize,
            rel_change: r[1],
            x_err_rel: r[2],
            tangent_misfit: r[3],
            objective: ObjectiveTerms {
                tracking: r[4],
                force: r[5],
                torque: r[6],
                shear: r[7],
                bending: r[8],
                angular: r[9],
            },
            // −1 marks a fixed-point iteration (no Newton residual)
            residual: (r[11] >= 0.0).then_some(r[11]),
            certificate: optional_certificate(r[12]),
        })
        .collect())
}

/// The solver statistics and the certificate of an inverse run from `ff_info.csv` of `workdir`.
fn read_inverse_info(workdir: &Path) -> Result<(SolverStats, Option<Certificate>), FreeFemError> {
    let info = FfInfo::read(&workdir.join("ff_info.csv"))?;
    let certificate = info.certificate();
    let stats = SolverStats {
        iterations: info.iterations(),
        last_change: info.solve.rel_change,
        residual: None,
        max_newton_iterations: None,
        certificate: certificate.map(|c| c.value),
        wall_time_s: info.wall_time_s(),
    };
    Ok((stats, certificate))
}

/// The error the Rust engine gives for a frame that did not converge
/// (`InverseSolution::converged`), from how `inverse.edp` ended and its history; `None`:
/// converged and certified.
fn inverse_stop(
    end: Stop,
    history: &[InverseRecord],
    certificate: Option<Certificate>,
    tolerance: f64,
) -> Option<SolveError> {
    let last = history.last();
    let iterations = last.map_or(0, |r| r.iteration);
    let rel_change = last.map_or(f64::NAN, |r| r.rel_change);
    let newton = history.iter().any(|r| r.residual.is_some());
    let c = certificate.unwrap_or(Certificate { value: f64::NAN, blocks: [f64::NAN; 4] });
    match (end, last.and_then(|r| r.residual)) {
        (Stop::Converged, _) => None,
        (Stop::Stalled, _) => Some(SolveError::Stalled(Box::new(crate::solve::Stall {
            solver: format!("inverse {} of frame 0", if newton { "Newton" } else { "fixed point" }),
            iterations,
            rel_change,
            certificate: c.value,
            tolerance,
            block: c.worst_block(System::Kkt),
        }))),
        (Stop::MaxIterations, Some(residual)) => {
            Some(SolveError::InverseNewtonNotConverged { frame: 0, iterations, residual, certificate: c.value })
        }
        (Stop::MaxIterations, None) if newton => Some(SolveError::InverseNewtonNotConverged {
            frame: 0,
            iterations,
            residual: f64::NAN,
            certificate: c.value,
        }),
        (Stop::MaxIterations, None) => Some(SolveError::InverseNotConverged { frame: 0, iterations, rel_change }),
    }
}

/// Run the FreeFEM engine on `case` inside `workdir` (created if needed).
/// A static run that ends stalled or at its iteration limit is [`FreeFemError::Incomplete`] with
/// the Rust engine's error (`StaticSolution::converged`) and the last iterate.
pub fn run(case: &Case, workdir: &Path) -> Result<RunResult, FreeFemError> {
    let mut outputs = vec!["ff_nodes.csv", "ff_info.csv", "ff_history.csv", "ff_tip.csv", "ff_charts.csv"];
    outputs.extend(path::PATH_OUTPUTS);
    outputs.push(stability::BUCKLING_OUTPUT);
    let end = execute_to_end(case, workdir, "forward.edp", &outputs, &RunOptions::default())?;
    let (result, certificate) = read_outputs(case, workdir)?;
    let newton = matches!(&case.analysis, Analysis::Static(p) if p.method == Method::Newton);
    let last = result.history.last();
    let (step, iterations, change) =
        last.map(|r| (r.step, r.iteration, r.change)).unwrap_or((1, result.stats.iterations, f64::NAN));
    let c = certificate.unwrap_or(Certificate { value: f64::NAN, blocks: [f64::NAN; 4] });
    let source = match (end, newton) {
        (Stop::Converged, _) => return Ok(result),
        (Stop::Stalled, _) => SolveError::Stalled(Box::new(crate::solve::Stall {
            solver: if newton { "static Newton" } else { "static fixed point" }.to_string(),
            iterations: result.stats.iterations,
            rel_change: change,
            certificate: c.value,
            tolerance: case.certificate_tolerance(),
            block: c.worst_block(System::Forward),
        })),
        (Stop::MaxIterations, false) => SolveError::FixedPointNotConverged { step, iterations, rel_change: change },
        (Stop::MaxIterations, true) => {
            SolveError::NewtonNotConverged { step: Some(Step::Continuation(step)), iterations, increment: change }
        }
    };
    Err(FreeFemError::Incomplete { source, partial: Box::new(result) })
}

/// Write `case.idp` into `workdir`, remove stale `outputs`, run `script` headless there.
pub(super) fn execute(
    case: &Case,
    workdir: &Path,
    script: &str,
    outputs: &[&str],
    opts: &RunOptions,
) -> Result<(), FreeFemError> {
    let exe = find_executable()?;
    let scripts = script_dir();
    let script_name = script;
    let script = scripts.join(script);
    if !script.is_file() {
        return Err(FreeFemError::MissingScripts(scripts));
    }
    std::fs::create_dir_all(workdir).map_err(io(workdir))?;
    let include = workdir.join("case.idp");
    std::fs::write(&include, include_file(case, opts)).map_err(io(&include))?;
    for stale in outputs {
        let _ = std::fs::remove_file(workdir.join(stale));
    }
    let mut cmd = Command::new(exe);
    cmd.arg("-nw").arg("-v").arg("0").arg(&script).current_dir(workdir);
    if std::env::var_os("FF_LOADPATH").is_none() {
        cmd.env("FF_LOADPATH", "/usr/lib/freefem++");
    }
    // Output to a file (no pipe to drain), the child polled so that a requested stop
    // (`crate::interrupt`) kills it instead of waiting for it.
    let log = workdir.join("freefem_output.txt");
    let log_file = std::fs::File::create(&log).map_err(io(&log))?;
    cmd.stdout(log_file.try_clone().map_err(io(&log))?).stderr(log_file);
    let mut child = cmd.spawn().map_err(io(&script))?;
    let mut watch = Watch::new(case, script_name, workdir, opts);
    let status = loop {
        if let Some(status) = child.try_wait().map_err(io(&script))? {
            if let Some(w) = watch.as_mut() {
                w.read();
            }
            break status;
        }
        if let Some(w) = watch.as_mut() {
            w.poll();
        }
        if crate::interrupt::requested() {
            let _ = child.kill();
            let _ = child.wait();
            return Err(FreeFemError::Interrupted { workdir: workdir.to_path_buf() });
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    if !status.success() {
        if crate::interrupt::requested() {
            return Err(FreeFemError::Interrupted { workdir: workdir.to_path_buf() });
        }
        return Err(FreeFemError::Failed {
            status: status.code().unwrap_or(-1),
            workdir: workdir.to_path_buf(),
            output: std::fs::read_to_string(&log).unwrap_or_default(),
        });
    }
    Ok(())
}

impl FreeFemError {
    /// Was FreeFEM stopped because a stop was requested?
    pub fn is_interrupted(&self) -> bool {
        matches!(self, FreeFemError::Interrupted { .. })
    }
}

pub(super) fn read_table(path: &Path, expected: &[&str]) -> Result<Vec<Vec<f64>>, FreeFemError> {
    let bad = |reason: String| FreeFemError::BadOutput { path: path.to_path_buf(), reason };
    let mut rdr = csv_reader(path, expected)?;
    let mut rows = Vec::new();
    for (i, rec) in rdr.records().enumerate() {
        let rec = rec.map_err(|source| InputError::Csv { path: path.to_path_buf(), source })?;
        let row: Result<Vec<f64>, _> = rec.iter().map(|v| v.parse::<f64>()).collect();
        let row = row.map_err(|e| bad(format!("row {}: {e}", i + 1)))?;
        if row.iter().any(|v| !v.is_finite()) {
            return Err(bad(format!("row {}: non-finite value", i + 1)));
        }
        rows.push(row);
    }
    Ok(rows)
}

/// The charts of a dynamic run (`ff_charts.csv`, D32): the first step in each and its base `B`;
/// only `initial` where the script wrote none.
fn read_charts(path: &Path, initial: Chart) -> Result<Vec<(usize, Chart)>, FreeFemError> {
    if !path.exists() {
        return Ok(vec![(0, initial)]);
    }
    let columns = ["step", "time_s", "b11", "b12", "b13", "b21", "b22", "b23", "b31", "b32", "b33"];
    let rows = read_table(path, &columns)?;
    Ok(rows.iter().map(|r| (r[0] as usize, Chart { base: nalgebra::Matrix3::from_row_slice(&r[2..11]) })).collect())
}

/// The result of `forward.edp` in `dir`, and its certificate with the blocks.
fn read_outputs(case: &Case, dir: &Path) -> Result<(RunResult, Option<Certificate>), FreeFemError> {
    let nodes_path = dir.join("ff_nodes.csv");
    let rows = read_table(&nodes_path, &["s_m", "x_m", "y_m", "z_m", "alpha_rad", "beta_rad", "gamma_rad"])?;
    if rows.len() != case.mesh.nodes() {
        return Err(FreeFemError::BadOutput {
            path: nodes_path,
            reason: format!("{} rows, expected {}", rows.len(), case.mesh.nodes()),
        });
    }
    let nodes = NodalState {
        s: rows.iter().map(|r| r[0]).collect(),
        x: rows.iter().map(|r| Vector3::new(r[1], r[2], r[3])).collect(),
        alpha: rows.iter().map(|r| Vector3::new(r[4], r[5], r[6])).collect(),
        chart: case.rod.general.as_ref().map(|g| g.rest.chart).unwrap_or_default(),
        reference_x: case.rod.general.as_ref().map(|g| g.rest.positions.clone()),
    };
    let info = FfInfo::read(&dir.join("ff_info.csv"))?;
    let certificate = info.certificate();
    let stats = SolverStats {
        iterations: info.iterations(),
        last_change: info.solve.rel_change,
        residual: info.solve.residual,
        max_newton_iterations: info.solve.max_newton_iterations.map(|v| v as usize),
        certificate: certificate.map(|c| c.value),
        wall_time_s: info.wall_time_s(),
    };
    let mut history = Vec::new();
    let mut tip = Vec::new();
    let mut nodes = nodes;
    if case.is_dynamic() {
        // the charts of the run (D32): each record's, and the final state's
        let initial = nodes.chart;
        let charts = read_charts(&dir.join("ff_charts.csv"), initial)?;
        let chart_at = |k: usize| charts.iter().rev().find(|(step, _)| *step <= k).map(|c| c.1).unwrap_or(initial);
        nodes.chart = charts.last().map(|c| c.1).unwrap_or(initial);
        for r in read_table(&dir.join("ff_tip.csv"), &TIP_COLUMNS)? {
            tip.push(TipRecord {
                time_s: r[0],
                position_m: Vector3::new(r[1], r[2], r[3]),
                angles_rad: Vector3::new(r[4], r[5], r[6]),
                newton_iterations: r[7] as usize,
                certificate: r[8],
                balance: Balance {
                    kinetic_j: r[9],
                    elastic_j: r[10],
                    momentum_n_s: Vector3::new(r[11], r[12], r[13]),
                    angular_momentum_n_m_s: Vector3::new(r[14], r[15], r[16]),
                },
                loaded: r[17] != 0.0,
                chart: chart_at(tip.len()),
            });
        }
    } else {
        for r in read_table(&dir.join("ff_history.csv"), &["iteration", "rel_change", "certificate"])? {
            let iteration = r[0] as usize;
            let step = history
                .last()
                .map(|h: &IterationRecord| if iteration <= h.iteration { h.step + 1 } else { h.step })
                .unwrap_or(1);
            history.push(IterationRecord { step, iteration, change: r[1], certificate: r[2] });
        }
    }
    let followed = matches!(&case.analysis, Analysis::Static(p) if p.path.is_some());
    let path = if followed { Some(path::read_path(case, dir, &info)?) } else { None };
    let stability = stability::read_stability(case, dir)?;
    Ok((RunResult { engine: Engine::Freefem, nodes, history, tip, stats, inverse: None, path, stability }, certificate))
}
