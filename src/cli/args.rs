//! The command line: [`Cli`] and its subcommands ([`Command`]), parsed by clap.
use std::path::PathBuf;

use clap::{Parser, Subcommand};

use cosserat::engine::Engine;
use cosserat::io::compact::OutputFormat;

/// Forward Cosserat rods after Wang et al. (Comput. Mech. 71, 2023), in Rust and FreeFEM.
#[derive(Parser, Debug)]
#[command(name = "cosserat", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Run a case and write fields (CSV), metrics.json and plot.svg.
    ///
    /// A case with published values ([[reference.values]]) also writes reference.csv (published,
    /// computed, error, tolerance, pass, source per value), adds them to metrics.json and prints
    /// one line per value on stderr.
    ///
    /// Exit status: 0 the run is complete; 1 it failed, did not converge or stalled (the folder's
    /// run.json says which), or, with --strict, a published value missed its tolerance or a
    /// clip has frames over the fit-quality gate; 130 stopped by a signal.
    Run(RunArgs),
    /// Run both engines and compare them; exit status 1 if any row fails.
    ///
    /// Newton runs are compared at their roots, an inverse fixed point at the same iteration
    /// (FreeFEM runs exactly the iterations Rust needed), a clip frame by frame over its first
    /// frames. Each tolerance is derived from the case's conditioning: the Rust engine runs the
    /// case again with its input perturbed by 1e-13 (relative), and a row passes when the
    /// engines differ by less than 10 x (that change + the solver tolerance) + 1e-12. Values in
    /// the case's [compare] table override them (with a `reason`). Writes compare.csv, the
    /// engines' outputs (single runs) and FreeFEM's work folder to --out. A case with published
    /// values ([[reference.values]]) has them checked in both engines: a second table, and
    /// reference.csv with both engines' values, errors and verdicts; a value missed in either
    /// engine is exit status 1 too.
    Compare(CompareArgs),
    /// Run a case for every point of a parameter grid (in parallel) and summarise.
    ///
    /// Writes one folder per run (the files of `run`), `summary.csv` (one row per run: the swept
    /// values, status, iterations, recovery errors, objective, wall time, error message) and
    /// `convergence.svg` (log-log histories, one curve per run; Figs. 9-11 of the paper). A run
    /// that reaches its iteration limit is `not_converged`: its folder holds the last iterate
    /// with a run.json saying failed, and its curve is plotted. A clip case solves its whole clip for every
    /// point (the folder holds the files of `run` on the clip; the summary has one row per
    /// point: frames, iterations, worst fit, tangent misfit, |j - 1|, objective). Exit status 1
    /// if any run failed or did not converge (after writing everything).
    Sweep(SweepArgs),
    /// Audit the paper: regenerate its figures and judge its claims (§5-6).
    ///
    /// Reads the audit specs (default: every *.toml of cases/paper/), runs every point of every
    /// run in parallel (one folder per point, the files of `run`/`sweep`), draws the paper's
    /// figures and writes REPORT.md (one row per claim: the paper's words and number, ours, the
    /// verdict - reproduced, differs, refuted, not computable here - and its cause) and
    /// report.csv. `--quick` runs the specs' short grids and clip excerpts (the subset asserted by
    /// `cargo test`). Exit status 1 if a claim's verdict is not the one its spec expects (the
    /// report is written first).
    Audit(AuditArgs),
    /// Run a clip case over many recordings (here, or as a Slurm job array with --slurm).
    Batch(super::BatchArgs),
    /// Run one task of a batch's Slurm job array (called by the job script).
    #[command(hide = true)]
    BatchTask(super::TaskArgs),
    /// Write OUT/summary.csv from the recordings' folders of a batch (after a Slurm job array).
    Gather {
        /// Output folder of the batch (`--out` of `cosserat batch`: holds batch.json and one
        /// folder per recording); summary.csv is written there
        out: PathBuf,
    },
    /// Write a corpus of synthetic 3D recordings with their ground truth.
    Synth(super::synth::SynthArgs),
    /// Reconstruct synthetic recordings at several noise levels beside a smoothing spline.
    NoiseStudy(super::noise_study::NoiseStudyArgs),
    /// List the cases of a directory with their descriptions.
    List {
        /// Directory holding *.toml case files
        #[arg(default_value = "cases")]
        dir: PathBuf,
    },
    /// Critical load factors of a static case's loads (linearised buckling about the reference).
    ///
    /// Each with the arc length where its mode moves most (docs/decisions.md D27). Computed for
    /// loads that compress or stretch the rod without turning its sections (columns); others are
    /// refused with the arc-length path to take. `solver.buckling_modes` in the case writes the
    /// same from `run`, in both engines, with the modes in buckling.csv.
    Buckling {
        /// Static case file (TOML): its loads are scaled by the factors printed
        case: PathBuf,
        /// How many critical load factors to print (at least 1)
        #[arg(long, default_value_t = 6, allow_hyphen_values = true, value_parser = super::parse_count)]
        count: usize,
    },
    /// Natural frequencies of the rod linearised about its rest state (clamped at s = 0).
    Modes {
        /// Case file (TOML); loads and time settings are ignored
        case: PathBuf,
        /// How many modes to print (at least 1)
        #[arg(long, default_value_t = 10, allow_hyphen_values = true, value_parser = super::parse_count)]
        count: usize,
        #[command(flatten)]
        limits: Limits,
    },
}

/// Resource limits of a run.
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct Limits {
    /// Refuse a run whose estimated memory exceeds this [GiB] [default: half the machine's
    /// memory]
    #[arg(long, value_name = "GIB")]
    pub max_memory_gib: Option<f64>,
}

/// The options of `cosserat compare` (its help is the `Compare` command's).
#[derive(clap::Args, Debug)]
pub struct CompareArgs {
    /// Case file (TOML)
    pub case: PathBuf,
    /// Directory for both engines' outputs [default: out/<case name>]
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Short horizon: 200 time steps, 40 fixed-point iterations, 3 clip frames
    #[arg(long)]
    pub short: bool,
    /// Clip cases: frames to compare, a number or `all` [default: the case's
    /// `[compare] frames`, 10]
    #[arg(long, value_parser = super::parse_frames)]
    pub frames: Option<usize>,
    /// Replace the output directory even if it holds files but no run.json, or a complete
    /// run with one that fails or is interrupted
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub limits: Limits,
}

/// The options of `cosserat sweep` (its help is the `Sweep` command's).
#[derive(clap::Args, Debug)]
pub struct SweepArgs {
    /// Case file (TOML)
    pub case: PathBuf,
    /// Parameter and values, e.g. `--set lambda_d=1e-6,1e-4`; repeat for a cartesian
    /// product. Each value is set in the case file's table and the case validated again.
    /// Inverse cases: lambda_g, lambda_f, lambda_l, lambda_d, lambda_kappa1..3,
    /// lambda_omega1..3, relaxation, warm_start_tolerance, tolerance, max_iterations,
    /// elements, stabilisation. Static: relaxation, tolerance, max_iterations,
    /// continuation_steps, elements. Dynamic: tolerance, max_iterations, steps, elements
    #[arg(long = "set", value_name = "KEY=V1,V2,...", required = true)]
    pub set: Vec<String>,
    /// Output directory [default: out/<case name>/sweep]
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Replace the output directory even if it holds files but no run.json, or a complete run
    /// with one that fails or is interrupted (which otherwise is kept beside it)
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub limits: Limits,
    /// Parallel runs, 1 to 256 [default: number of cores; never more than the runs]
    #[arg(long, value_parser = super::parse_jobs)]
    pub jobs: Option<usize>,
    /// Do not show progress (a bar on a terminal, else a line every 10 s)
    #[arg(long)]
    pub quiet: bool,
}

/// The options of `cosserat audit` (its help is the `Audit` command's).
#[derive(clap::Args, Debug)]
pub struct AuditArgs {
    /// Audit specs (TOML) or folders of them [default: cases/paper]
    pub specs: Vec<PathBuf>,
    /// Short grids and clip excerpts (`quick_grid`, `quick_set` of the specs)
    #[arg(long)]
    pub quick: bool,
    /// Output directory [default: out/audit, out/audit-quick with --quick]; replaced whole
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Replace the output directory even if it holds files but no run.json, or a complete run
    /// with one that fails or is interrupted (which otherwise is kept beside it)
    #[arg(long)]
    pub force: bool,
    /// Parallel runs, 1 to 256 [default: number of cores; never more than the runs]
    #[arg(long, value_parser = super::parse_jobs)]
    pub jobs: Option<usize>,
    /// Do not show progress (a bar on a terminal, else a line every 10 s)
    #[arg(long)]
    pub quiet: bool,
    /// Clip points keep compact fields.npz and figures [default: tables only, ≤ 200 MB]
    #[arg(long, conflicts_with = "vtk")]
    pub fields: bool,
    /// Clip points keep fields.csv, curvature.csv, VTK and figures (GBs for the full audit)
    #[arg(long)]
    pub vtk: bool,
    /// Continue the unfinished audit of --out: keep the specs it judged whole, rerun the rest
    #[arg(long, conflicts_with = "force")]
    pub resume: bool,
    /// Rerun the failing rows of the printed scheme in FreeFEM and the other one-rule reading,
    /// so that a row can be judged refuted (docs/audit.md; long: FreeFEM's fixed point)
    #[arg(long)]
    pub engines: bool,
}

/// The options of `cosserat run` (its help is the `Run` command's).
#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// Case file (TOML), e.g. cases/timoshenko_10pct.toml
    pub case: PathBuf,
    /// Which engine to run
    #[arg(long, value_enum, default_value_t = EngineArg::Rust)]
    pub engine: EngineArg,
    /// Output directory [default: out/<case name>/<engine>]. The run writes into a staging
    /// folder beside it that replaces it whole at the end; run.json says what it holds
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Replace the output directory even if it holds files but no run.json, or a complete run
    /// with one that fails or is interrupted (which otherwise is kept beside it)
    #[arg(long)]
    pub force: bool,
    /// Continue the interrupted, failed or killed clip of the output directory from its
    /// last converged frame (same case file and clip file), in a staging folder of its own;
    /// the CSVs are then byte for byte those of an uninterrupted run
    #[arg(long, conflicts_with = "force")]
    pub resume: bool,
    /// Clips: per-node fields as CSV + ParaView VTK, or all in one fields.npz (docs/output.md)
    #[arg(long, value_enum, default_value_t = OutputFormatArg::Csv)]
    pub output_format: OutputFormatArg,
    #[command(flatten)]
    pub limits: Limits,
    /// Do not show progress (a bar on a terminal, else a line every 10 s)
    #[arg(long)]
    pub quiet: bool,
    /// Exit with status 1 when a published value ([[reference.values]]) misses its
    /// tolerance, or a clip has frames over the fit-quality gate (run.json says complete,
    /// or complete_with_warnings, either way)
    #[arg(long)]
    pub strict: bool,
}

impl RunArgs {
    /// What a missed published value or a flagged frame does: `--strict` makes it fail.
    pub fn strictness(&self) -> super::outcome::Strictness {
        use super::outcome::Strictness;
        if self.strict {
            Strictness::Fail
        } else {
            Strictness::Warn
        }
    }
}

impl AuditArgs {
    /// The grids to run: `--quick`'s or the full ones.
    pub fn depth(&self) -> cosserat::audit::Depth {
        use cosserat::audit::Depth;
        if self.quick {
            Depth::Quick
        } else {
            Depth::Full
        }
    }

    /// What the clip points keep, from `--fields` and `--vtk`.
    pub fn point_fields(&self) -> cosserat::audit::PointFields {
        use cosserat::audit::PointFields;
        match (self.fields, self.vtk) {
            (_, true) => PointFields::Vtk,
            (true, _) => PointFields::Compact,
            _ => PointFields::Tables,
        }
    }
}

/// `--engine` as the command line spells it (the library's [`Engine`] knows no command line).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum EngineArg {
    Rust,
    Freefem,
}

impl From<EngineArg> for Engine {
    fn from(e: EngineArg) -> Self {
        match e {
            EngineArg::Rust => Engine::Rust,
            EngineArg::Freefem => Engine::Freefem,
        }
    }
}

/// `--output-format` as the command line spells it ([`OutputFormat`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum OutputFormatArg {
    /// `fields.csv`, `curvature.csv` and ParaView `vtk/frame_NNNNN.vtp` + `clip.pvd`
    Csv,
    /// one `fields.npz` (NumPy) with every per-node field at full precision, 4-6x smaller
    Compact,
}

impl From<OutputFormatArg> for OutputFormat {
    fn from(f: OutputFormatArg) -> Self {
        match f {
            OutputFormatArg::Csv => OutputFormat::Csv,
            OutputFormatArg::Compact => OutputFormat::Compact,
        }
    }
}
