//! The rows of a batch's `summary.csv` (`super::batch`): one [`BatchRow`] per recording and
//! the columns they are written in ([`SUMMARY_COLUMNS`]).
use crate::solve::Outcome;

/// The `status` of a recording gathered before its task ran (it has no outcome).
pub const MISSING: &str = "missing";
/// The summary table in the output folder.
pub const SUMMARY: &str = "summary.csv";

/// A column of `summary.csv`: its name and its text of a row.
pub type SummaryColumn = (&'static str, fn(&BatchRow) -> String);

/// Columns of `summary.csv`, each with its text of a row. `fit_position_rel_length_max` is the worst frame's position
/// misfit in body lengths, `((1/L) ∫ |x − x_g|²)^½ / L` (`solve::fit`): unlike `‖x − x_g‖/‖x_g‖`
/// it does not depend on where the recording sits in space. `curvature_err_rel_max` is the
/// worst frame's relative L² error of the bending `κ1² + κ2²` against the ground truth [–]
/// (empty without a truth sidecar). `length_m` is the rod length the recording was solved with
/// [m], and `length_spread_rel` the spread of its frames' corrected lengths about it (`1.4826`
/// median absolute deviation over the median, `clip::length`), where `rod.length_m =
/// "from_data"` estimated it (empty otherwise). `wall_time_s` comes last: it is the only column
/// that differs between two runs of the same batch. `noise_m` [m] and `lambda_g` are the noise
/// level and tracking weight `[inverse] weights = "auto"` chose (empty with fixed weights;
/// `docs/noise.md`).
pub const SUMMARY_COLUMNS: [SummaryColumn; 14] = [
    ("recording", |r| r.recording.clone()),
    ("folder", |r| r.folder.clone()),
    ("status", |r| r.status_word().into()),
    ("frames", |r| r.frames.map(|f| f.to_string()).unwrap_or_default()),
    ("newton_iterations_per_frame", |r| number(r.newton_iterations_per_frame)),
    ("certificate_max", |r| number(r.certificate_max)),
    ("fit_position_rel_length_max", |r| number(r.fit_position_rel_length_max)),
    ("curvature_err_rel_max", |r| number(r.curvature_err_rel_max)),
    ("length_m", |r| number(r.length_m)),
    ("length_spread_rel", |r| number(r.length_spread_rel)),
    ("noise_m", |r| number(r.noise_m)),
    ("lambda_g", |r| number(r.lambda_g)),
    ("reason", |r| r.reason.as_deref().unwrap_or("").replace('\n', " ")),
    ("wall_time_s", |r| format!("{:.3}", r.wall_time_s)),
];

/// A number of the summary: 10 significant digits, empty where it does not apply.
fn number(v: Option<f64>) -> String {
    v.map(|v| crate::io::number::exp(v, 10)).unwrap_or_default()
}

/// The summary row of one recording.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BatchRow {
    pub recording: String,
    pub folder: String,
    /// how the recording's run ended; `None`: `missing` in the summary (gathered before its
    /// task ran; never in a `batch_row.json`)
    pub status: Option<Outcome>,
    /// converged frames
    pub frames: Option<usize>,
    pub newton_iterations_per_frame: Option<f64>,
    /// the largest residual certificate of the frames (`docs/certificate.md`)
    #[serde(default)]
    pub certificate_max: Option<f64>,
    /// the worst frame's position misfit in body lengths (`solve::fit`)
    #[serde(default)]
    pub fit_position_rel_length_max: Option<f64>,
    pub curvature_err_rel_max: Option<f64>,
    /// `weights = "auto"`: the recording's noise level per coordinate [m] and the λg chosen
    #[serde(default)]
    pub noise_m: Option<f64>,
    #[serde(default)]
    pub lambda_g: Option<f64>,
    /// the rod length solved with [m]
    #[serde(default)]
    pub length_m: Option<f64>,
    /// `rod.length_m = "from_data"`: the spread of the frames' lengths (`clip::length`)
    #[serde(default)]
    pub length_spread_rel: Option<f64>,
    /// why it failed (the error and its causes)
    pub reason: Option<String>,
    /// this recording's wall time [s]
    pub wall_time_s: f64,
}

impl BatchRow {
    /// The word of the summary's `status` column: the outcome's, or `missing`.
    pub fn status_word(&self) -> &'static str {
        self.status.map_or(MISSING, Outcome::as_str)
    }

    pub fn is_ok(&self) -> bool {
        self.status.is_some_and(Outcome::is_complete)
    }
}

/// CSV text of the summary ([`SUMMARY_COLUMNS`]); numbers with 10 significant digits, empty
/// where a value does not apply.
pub fn summary_csv(rows: &[BatchRow]) -> Result<String, csv::Error> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(SUMMARY_COLUMNS.map(|(name, _)| name))?;
    for r in rows {
        w.write_record(SUMMARY_COLUMNS.map(|(_, text)| text(r)))?;
    }
    let bytes = w.into_inner().map_err(|e| csv::Error::from(e.into_error()))?;
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}
