//! `run.json`, the manifest of an output folder (docs/decisions.md D16): what the folder
//! holds, its status and its inputs with their SHA-256, read and written here; and whether a
//! folder's run can be resumed by another. The folder contract itself is `super::run_folder`'s.
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

use crate::case::sweep::SweepValue;
use crate::clip::length::BodyLength;
use crate::io::files::{is_temporary, write_atomic};
use crate::solve::Outcome;

/// File name of the manifest in an output folder.
pub const MANIFEST: &str = "run.json";

/// The state of an output folder's run in its `run.json`: running, or how it ended. Not the
/// run's [`Outcome`] (the vocabulary of results, `solve::outcome`): a folder may still be
/// running, and a run that reached its iteration limit leaves a `failed` folder; its words
/// are `run.json`'s (`complete` where an outcome is `ok`). `Status::from(outcome)` is the one
/// mapping.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    Running,
    Complete,
    /// a clip solved whole with frames over the fit-quality gate (`solve::fit`): every frame is
    /// certified, but some do not follow their data
    CompleteWithWarnings,
    /// the run ended with a result that is not a solution: its iteration stopped moving with a
    /// residual certificate above the tolerance (`docs/certificate.md`)
    Stalled,
    Failed,
    Interrupted,
}

impl From<Outcome> for Status {
    fn from(outcome: Outcome) -> Self {
        match outcome {
            Outcome::Converged => Status::Complete,
            Outcome::IterationLimit | Outcome::Failed => Status::Failed,
            Outcome::Stalled => Status::Stalled,
            Outcome::CompleteWithWarnings => Status::CompleteWithWarnings,
            Outcome::Interrupted => Status::Interrupted,
        }
    }
}

impl Status {
    /// A whole result: complete, with or without warnings.
    pub fn is_complete(self) -> bool {
        matches!(self, Status::Complete | Status::CompleteWithWarnings)
    }

    pub fn as_str(self) -> &'static str {
        match self {
            Status::Running => "running",
            Status::Complete => "complete",
            Status::CompleteWithWarnings => "complete_with_warnings",
            Status::Stalled => "stalled",
            Status::Failed => "failed",
            Status::Interrupted => "interrupted",
        }
    }
}

/// An input file of a run and its SHA-256.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct InputFile {
    pub path: String,
    pub sha256: String,
}

/// The residual certificate of a run's result (`docs/certificate.md`) in its `run.json`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CertificateSummary {
    /// the certificate of the result (a dynamic run: the largest of its steps; a clip: the
    /// largest of its frames)
    pub value: f64,
    /// the tolerance a converged result meets (`solver.certificate_tolerance`)
    pub tolerance: f64,
    /// clips: the frames over the fit-quality gate (`solve::fit`, docs/certificate.md C5)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flagged_frames: Option<usize>,
}

/// `run.json`; the groups are flattened into it, so its keys keep their order: program,
/// version, command, case_name, case, inputs, settings, engine, status, frames_done,
/// frames_total, message, certificate, weights, body_length, pid, started_unix_s,
/// finished_unix_s, files.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Manifest {
    #[serde(flatten)]
    pub writer: Writer,
    #[serde(flatten)]
    pub input: RunInputs,
    pub status: Status,
    #[serde(flatten)]
    pub frames: FrameProgress,
    /// why the run failed or stopped
    pub message: Option<String>,
    /// the residual certificate of the result, where the run has one
    #[serde(default)]
    pub certificate: Option<CertificateSummary>,
    /// clips with `[inverse] weights = "auto"`: the noise level and the weights chosen
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weights: Option<crate::engine::weights::ChosenWeights>,
    /// what the recording said of itself and of its frames: its body length, its plane, its
    /// lost, filled and re-solved frames
    #[serde(flatten)]
    pub recording: RecordingNotes,
    #[serde(flatten)]
    pub process: Process,
    /// every file of the folder (relative paths, `/`-separated), `run.json` excepted
    pub files: Vec<String>,
}

/// What a clip's recording said of itself, in `run.json` (each key only where it applies).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RecordingNotes {
    /// `rod.length_m = "from_data"`: the body length estimated from the recording, with the
    /// spread and range of its frames (`clip::length`)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub body_length: Option<BodyLength>,
    /// a planar recording (`clip::recording`): its plane, and what its data cannot tell
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub planar: Option<PlanarNote>,
    /// clips: the frames whose data were lost or filled, and those re-solved from their data
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame_data: Option<FrameDataNote>,
}

/// What a planar recording cannot tell (`clip::recording`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PlanarNote {
    /// the unit normal of the data's plane, in space coordinates
    pub plane_normal: [f64; 3],
    /// in words: the twist and the roll are not observable
    pub twist: String,
}

/// The words of [`PlanarNote::twist`], also on stderr and in the figures' titles.
pub const PLANAR_TWIST: &str = "not observable: the data lie in one plane (one camera), so the rotation of the cross-section about the centreline is fixed by the gauge alpha(0) = 0 on every frame and kappa3 = 0 is the gauge's, not a measurement of no twist; the bending is kappa2, d2 normal to the plane";

impl PlanarNote {
    pub fn new(n: &nalgebra::Vector3<f64>) -> Self {
        PlanarNote { plane_normal: [n.x, n.y, n.z], twist: PLANAR_TWIST.into() }
    }
}

/// A clip's frames by their data (`frames.csv` has the same per frame: `nodes_tracked`,
/// `lost`, `filled`, `resolved`, `flagged`).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FrameDataNote {
    /// frames with fewer than 2 tracked nodes: bridged in time from their neighbours
    /// (`clip::missing`), their numbers
    pub lost: Vec<usize>,
    /// frames with some, not all, of their nodes filled
    pub filled: usize,
    /// frames solved again from their data guess because their solution from the previous
    /// frame was over the fit-quality gate (`solve::sequence`), their numbers
    pub resolved: Vec<usize>,
}

/// What wrote a run folder.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Writer {
    /// "cosserat"
    pub program: String,
    /// the program's version (Cargo.toml)
    pub version: String,
    /// the subcommand: run, sweep, compare, audit
    pub command: String,
}

/// What a run's results depend on, and the engine that made them.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RunInputs {
    /// the case's name and file (with its SHA-256), where the command has one
    pub case_name: Option<String>,
    pub case: Option<InputFile>,
    /// other inputs the results depend on (a clip's recording or kymogram)
    pub inputs: Vec<InputFile>,
    /// settings that differ from the case file (a sweep point)
    pub settings: BTreeMap<String, SweepValue>,
    pub engine: Option<String>,
}

/// Clips: converged frames written, and frames of the clip.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FrameProgress {
    pub frames_done: Option<usize>,
    pub frames_total: Option<usize>,
}

/// The process that wrote the folder, and when [s since the Unix epoch].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Process {
    pub pid: u32,
    pub started_unix_s: u64,
    pub finished_unix_s: Option<u64>,
}

/// Errors of the output-folder contract; each names the folder.
#[derive(Debug, thiserror::Error)]
pub enum FolderError {
    #[error("{path} is a file, not a folder")]
    NotAFolder { path: PathBuf },
    #[error(
        "{path} holds files ({examples}) but no run.json: it was not written by a cosserat run (or by an older version). Choose another --out, or pass --force to replace it whole"
    )]
    Foreign { path: PathBuf, examples: String },
    #[error("{path}: refusing to replace the working folder, one of its parents or the root; choose a folder for the results")]
    Dangerous { path: PathBuf },
    #[error(
        "{path} is being written by another cosserat process ({}): one run writes a folder at a time; wait for it to end, or choose another --out",
        pid.map_or("its pid not yet known".to_string(), |p| format!("pid {p}"))
    )]
    Busy { path: PathBuf, pid: Option<u32> },
    #[error("{path}: cannot resume: {reason}")]
    CannotResume { path: PathBuf, reason: ResumeRefusal },
    #[error("{path}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {reason}")]
    Manifest { path: PathBuf, reason: String },
    #[error(
        "{space}: `--resume` cannot continue the run of {path}: the {frames} frames already written are kept in {}{need}; free some space and run --resume again",
        kept.display()
    )]
    ResumeDiskFull {
        path: PathBuf,
        /// the disk and its free space ("the disk holding … is full (… free of …)")
        space: String,
        frames: usize,
        /// the folder that holds them
        kept: PathBuf,
        /// what the resume needs, where known ("; the copy … needs 3 MiB")
        need: String,
        #[source]
        source: Box<FolderError>,
    },
    #[error(transparent)]
    Input(#[from] crate::io::files::InputError),
}

pub(super) fn io_err(path: &Path) -> impl Fn(std::io::Error) -> FolderError + '_ {
    move |source| FolderError::Io { path: path.to_path_buf(), source }
}

/// SHA-256 of a file's bytes (hex), streamed.
pub fn sha256_file(path: &Path) -> std::io::Result<String> {
    let mut f = std::fs::File::open(path)?;
    let mut hasher = Sha256::new();
    std::io::copy(&mut f, &mut hasher)?;
    Ok(hasher.finalize().iter().map(|b| format!("{b:02x}")).collect())
}

/// An input file with its hash.
pub fn input_file(path: &Path) -> Result<InputFile, FolderError> {
    input_file_as(path, "input file")
}

/// The input file `path` (`what` names it in messages: "clip file", "recording") with its
/// hash; anything but a regular file is refused before it is opened (a pipe's open would
/// block: `crate::io::files::check_regular`).
pub fn input_file_as(path: &Path, what: &'static str) -> Result<InputFile, FolderError> {
    crate::io::files::check_regular(path, what)?;
    Ok(InputFile { path: path.display().to_string(), sha256: sha256_file(path).map_err(io_err(path))? })
}

pub(super) fn now_unix_s() -> u64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0)
}

impl Manifest {
    /// A running manifest of `command` in this process.
    pub fn new(command: &str) -> Self {
        Manifest {
            writer: Writer {
                program: "cosserat".into(),
                version: env!("CARGO_PKG_VERSION").into(),
                command: command.into(),
            },
            input: RunInputs {
                case_name: None,
                case: None,
                inputs: Vec::new(),
                settings: BTreeMap::new(),
                engine: None,
            },
            status: Status::Running,
            frames: FrameProgress { frames_done: None, frames_total: None },
            message: None,
            certificate: None,
            weights: None,
            recording: RecordingNotes::default(),
            process: Process { pid: std::process::id(), started_unix_s: now_unix_s(), finished_unix_s: None },
            files: Vec::new(),
        }
    }

    /// Read `dir/run.json`; `Ok(None)` if there is none.
    pub fn read(dir: &Path) -> Result<Option<Manifest>, FolderError> {
        let path = dir.join(MANIFEST);
        match std::fs::read(&path) {
            Ok(bytes) => serde_json::from_slice(&bytes)
                .map(Some)
                .map_err(|e| FolderError::Manifest { path, reason: format!("not a cosserat run.json: {e}") }),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(source) => Err(FolderError::Io { path, source }),
        }
    }

    /// Write `dir/run.json` (atomically).
    pub fn write(&self, dir: &Path) -> Result<(), FolderError> {
        let path = dir.join(MANIFEST);
        let text = serde_json::to_string_pretty(self)
            .map_err(|e| FolderError::Manifest { path: path.clone(), reason: e.to_string() })?;
        write_atomic(&path, format!("{text}\n").as_bytes()).map_err(|e| match e {
            // an I/O error keeps its cause (a full disk is recognised by it)
            crate::io::files::OutputError::Io { path, source } => FolderError::Io { path, source },
            e => {
                let cause = std::error::Error::source(&e).map(|c| format!(": {c}")).unwrap_or_default();
                FolderError::Manifest { path, reason: format!("{e}{cause}") }
            }
        })
    }

    /// End the run as `status` (with `message`), listing the files of `dir`, and write it there.
    pub fn finish(&mut self, dir: &Path, status: Status, message: Option<String>) -> Result<(), FolderError> {
        self.status = status;
        self.message = message;
        self.process.finished_unix_s = Some(now_unix_s());
        self.files = list_files(dir)?;
        self.write(dir)
    }
}

/// The files under `dir` (relative, sorted, `/`-separated), `run.json` and the hidden
/// temporaries of atomic writes excepted.
pub fn list_files(dir: &Path) -> Result<Vec<String>, FolderError> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<String>) -> Result<(), FolderError> {
        for entry in std::fs::read_dir(dir).map_err(io_err(dir))? {
            let entry = entry.map_err(io_err(dir))?;
            let p = entry.path();
            let name = entry.file_name().to_string_lossy().into_owned();
            if entry.file_type().map_err(io_err(&p))?.is_dir() {
                walk(root, &p, out)?;
            } else {
                let skip = (dir == root && name == MANIFEST) || is_temporary(&name);
                if skip {
                    continue;
                }
                let rel = p.strip_prefix(root).unwrap_or(&p);
                out.push(rel.iter().map(|c| c.to_string_lossy()).collect::<Vec<_>>().join("/"));
            }
        }
        Ok(())
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out)?;
    out.sort();
    Ok(out)
}

/// Why the run in a folder cannot be continued by `--resume` ([`check_resumable`]); the folder
/// is the caller's ([`FolderError::CannotResume`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ResumeRefusal {
    #[error("it holds no run.json (no run to resume)")]
    NoManifest,
    #[error("it holds a `{command}` run, not a clip run (only clips resume)")]
    NotClip { command: String },
    #[error("its run is complete; nothing to resume")]
    Complete,
    #[error("it was written by cosserat {previous}, this is {now}")]
    Version { previous: String, now: String },
    #[error(
        "its case file had SHA-256 {previous}, the case given now has {now}: a resumed clip must be the same case"
    )]
    CaseChanged { previous: String, now: String },
    #[error("its clip file has changed since (SHA-256 differs)")]
    InputsChanged,
    #[error("it was run by the {previous} engine")]
    Engine { previous: String },
}

/// Can the run of `previous` be continued by the run described by `new`? The same command
/// (`run`, or a batch's recording) on the same case file and inputs, a clip, not complete; or an audit (`audit
/// --resume`, `crate::audit::resume`) on the same specs, not complete.
pub(super) fn check_resumable(previous: &Manifest, new: &Manifest) -> Result<(), ResumeRefusal> {
    let clip = previous.writer.command == "run" && previous.frames.frames_done.is_some();
    let audit = previous.writer.command == "audit" && new.writer.command == "audit";
    // a batch's recording (its command names its format: the same one)
    let batch = previous.writer.command.starts_with("batch")
        && previous.writer.command == new.writer.command
        && previous.frames.frames_done.is_some();
    if !(clip || audit || batch) {
        return Err(ResumeRefusal::NotClip { command: previous.writer.command.clone() });
    }
    if previous.status.is_complete() {
        return Err(ResumeRefusal::Complete);
    }
    if previous.writer.version != new.writer.version {
        return Err(ResumeRefusal::Version {
            previous: previous.writer.version.clone(),
            now: new.writer.version.clone(),
        });
    }
    let hash = |f: &Option<InputFile>| f.as_ref().map(|f| f.sha256.clone());
    if hash(&previous.input.case) != hash(&new.input.case) {
        return Err(ResumeRefusal::CaseChanged {
            previous: hash(&previous.input.case).unwrap_or_default(),
            now: hash(&new.input.case).unwrap_or_default(),
        });
    }
    let hashes = |m: &Manifest| m.input.inputs.iter().map(|f| f.sha256.clone()).collect::<Vec<_>>();
    if hashes(previous) != hashes(new) {
        return Err(ResumeRefusal::InputsChanged);
    }
    if previous.input.engine != new.input.engine {
        return Err(ResumeRefusal::Engine { previous: previous.input.engine.clone().unwrap_or_default() });
    }
    Ok(())
}
