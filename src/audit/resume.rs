//! `cosserat audit --resume`: an audit continues the interrupted or failed one in its folder.
//! A spec whose points all finished wrote its judged claims and figures to [`JUDGED`]; the
//! resumed audit takes them from there and runs only the other specs, whose folders it
//! empties first (a spec is judged on points of one audit, never a mix).
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::spec::Spec;
use super::{ClaimResult, Verdict};
use crate::io::OutputError;
use crate::jobs::depth::Depth;

/// The record of a spec judged whole, in its folder.
pub const JUDGED: &str = "judged.json";

#[derive(Serialize, Deserialize)]
struct Judged {
    quick: bool,
    claims: Vec<Stored>,
    figures: Vec<String>,
}

#[derive(Serialize, Deserialize)]
struct Stored {
    id: String,
    verdict: Verdict,
    ours: String,
    /// a convergence claim's column of our standard
    #[serde(default)]
    standard: Option<String>,
    /// the cause of a failed check, as judged
    cause: Option<String>,
    /// the check in the other engine and readings, where it was rerun
    #[serde(default)]
    engines: Option<String>,
}

/// Record `spec`'s claims (every one judged) and the figures written, relative to the audit
/// folder `out`.
pub fn store(
    spec: &Spec,
    claims: &[ClaimResult],
    figures: &[String],
    depth: Depth,
    out: &Path,
) -> Result<(), OutputError> {
    let claims = claims
        .iter()
        .filter(|c| c.spec == spec.name)
        .map(|c| {
            c.verdict.map(|verdict| Stored {
                id: c.claim.id.clone(),
                verdict,
                ours: c.ours.clone(),
                standard: c.standard.clone(),
                cause: c.cause.clone(),
                engines: c.engines.clone(),
            })
        })
        .collect::<Option<Vec<_>>>();
    let Some(claims) = claims else { return Ok(()) };
    let prefix = format!("{}/", spec.name);
    let figures = figures.iter().filter(|f| f.starts_with(&prefix)).cloned().collect();
    let path = out.join(&spec.name).join(JUDGED);
    let text = serde_json::to_string_pretty(&Judged { quick: depth.is_quick(), claims, figures })
        .map_err(|e| OutputError::Invalid { path: path.clone(), reason: e.to_string() })?;
    crate::io::files::write_atomic(&path, text.as_bytes())
}

/// The claims and figures of `spec` from the audit being resumed: `None` unless it judged
/// every claim the spec has now, at the same `depth`.
pub fn load(spec: &Spec, depth: Depth, out: &Path) -> Option<(Vec<ClaimResult>, Vec<String>)> {
    let text = std::fs::read_to_string(out.join(&spec.name).join(JUDGED)).ok()?;
    let judged: Judged = serde_json::from_str(&text).ok()?;
    if judged.quick != depth.is_quick() || judged.claims.len() != spec.claims.len() {
        return None;
    }
    let claims = spec
        .claims
        .iter()
        .map(|claim| {
            let s = judged.claims.iter().find(|s| s.id == claim.id)?;
            Some(ClaimResult {
                spec: spec.name.clone(),
                claim: claim.clone(),
                verdict: Some(s.verdict),
                ours: s.ours.clone(),
                standard: s.standard.clone(),
                cause: s.cause.clone(),
                figure: claim.figure.clone(),
                engines: s.engines.clone(),
            })
        })
        .collect::<Option<Vec<_>>>()?;
    Some((claims, judged.figures))
}
