//! How a run ended: the one vocabulary of outcomes of a forward or inverse run, a clip, the
//! points of a sweep or an audit and the recordings of a batch, with one serialisation (serde,
//! [`Display`](std::fmt::Display) and [`FromStr`] give the same words: the `status` column of
//! `summary.csv` of a sweep or a batch, `batch_row.json`, the audit's point tables).
//!
//! A solver's own stop ([`super::Stop`]) is the part of it an iteration decides
//! (`From<Stop>`); the rest is decided by the run around it (an error, a signal, the
//! fit-quality gate or the stability of a static state). The state of an output folder in its
//! `run.json` is another thing (`output::manifest::Status`: it may still be running, and its
//! words are that file's), derived from an outcome in one place.
use std::fmt;
use std::str::FromStr;

use super::Stop;

/// How one run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum Outcome {
    /// converged and certified (`ok`)
    #[serde(rename = "ok")]
    Converged,
    /// a whole result with a warning (`complete_with_warnings`): a clip solved whole with
    /// frames over the fit-quality gate (`solve::fit`: every frame is certified, but some do not
    /// follow their data), or a static state that is certified but not stable (D27)
    #[serde(rename = "complete_with_warnings")]
    CompleteWithWarnings,
    /// the iteration stopped moving but its residual certificate is above the tolerance
    /// ([`Stop::Stalled`], `stalled`); the metrics are those of the last iterate
    #[serde(rename = "stalled")]
    Stalled,
    /// the iteration limit was reached first ([`Stop::MaxIterations`], `not_converged`); the
    /// metrics are those of the last iterate
    #[serde(rename = "not_converged")]
    IterationLimit,
    /// no result: an error (`failed`)
    #[serde(rename = "failed")]
    Failed,
    /// stopped by a signal, or not started because of one (`interrupted`)
    #[serde(rename = "interrupted")]
    Interrupted,
}

impl Outcome {
    /// Every outcome, in the order above.
    pub const ALL: [Outcome; 6] = [
        Outcome::Converged,
        Outcome::CompleteWithWarnings,
        Outcome::Stalled,
        Outcome::IterationLimit,
        Outcome::Failed,
        Outcome::Interrupted,
    ];

    /// The word of the outcome in every file (the serde name).
    pub fn as_str(self) -> &'static str {
        match self {
            Outcome::Converged => "ok",
            Outcome::CompleteWithWarnings => "complete_with_warnings",
            Outcome::Stalled => "stalled",
            Outcome::IterationLimit => "not_converged",
            Outcome::Failed => "failed",
            Outcome::Interrupted => "interrupted",
        }
    }

    /// A result whole: converged, or complete with warnings.
    pub fn is_complete(self) -> bool {
        matches!(self, Outcome::Converged | Outcome::CompleteWithWarnings)
    }
}

impl From<Stop> for Outcome {
    fn from(stop: Stop) -> Self {
        match stop {
            Stop::Converged => Outcome::Converged,
            Stop::Stalled => Outcome::Stalled,
            Stop::MaxIterations => Outcome::IterationLimit,
        }
    }
}

impl fmt::Display for Outcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A word that is not an [`Outcome`]'s.
#[derive(Debug, thiserror::Error)]
#[error("`{0}` is not an outcome (ok, complete_with_warnings, stalled, not_converged, failed, interrupted)")]
pub struct UnknownOutcome(pub String);

impl FromStr for Outcome {
    type Err = UnknownOutcome;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Outcome::ALL.into_iter().find(|o| o.as_str() == s).ok_or_else(|| UnknownOutcome(s.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// serde, `Display` and `FromStr` give the same word, and it reads back.
    #[test]
    fn one_serialisation() {
        for o in Outcome::ALL {
            let json = serde_json::to_string(&o).unwrap();
            assert_eq!(json, format!("\"{o}\""));
            assert_eq!(serde_json::from_str::<Outcome>(&json).unwrap(), o);
            assert_eq!(o.to_string().parse::<Outcome>().unwrap(), o);
        }
        assert!("converged".parse::<Outcome>().is_err());
    }

    #[test]
    fn a_stop_is_an_outcome() {
        assert_eq!(Outcome::from(Stop::Converged), Outcome::Converged);
        assert_eq!(Outcome::from(Stop::Stalled), Outcome::Stalled);
        assert_eq!(Outcome::from(Stop::MaxIterations), Outcome::IterationLimit);
    }
}
