//! The published values of a case (`[[reference.values]]`) in both engines of `cosserat
//! compare`: each value evaluated on the Rust and on the FreeFEM result
//! (`engine::published`), reported side by side (a table, `reference.csv`) and counted
//! in the comparison's exit status.
use super::compare::{CompareReport, Horizon, SHORT_STEPS};
use crate::case::{Analysis, Case};
use crate::engine::metrics::all_metrics;
use crate::engine::published::{evaluate, sources, PublishedRow};
use crate::reference::ReferenceError;
use crate::solve::inverse::InverseMethod;

/// A case's published values in both engines.
#[derive(Clone, Debug, PartialEq)]
pub struct PublishedComparison {
    pub rust: Vec<PublishedRow>,
    pub freefem: Vec<PublishedRow>,
    /// the comparison ran a shorter problem than the case (`--short`): its values are not
    /// those the case publishes, so the rows are shown but not counted
    pub cut_short: bool,
}

impl PublishedComparison {
    /// The published values of `case` on both runs of `report`; `None` for a case without
    /// published values or a comparison without single runs (a clip).
    pub fn of(case: &Case, report: &CompareReport, horizon: Horizon) -> Result<Option<Self>, ReferenceError> {
        let Some((rust, freefem)) = &report.runs else { return Ok(None) };
        if case.checks.published.values.is_empty() {
            return Ok(None);
        }
        let rows = |r| all_metrics(case, r).map(|m| evaluate(case, r, &m));
        Ok(Some(PublishedComparison {
            rust: rows(rust)?,
            freefem: rows(freefem)?,
            cut_short: cut_short(case, horizon),
        }))
    }

    /// Values missed by either engine (0 for a comparison cut short).
    pub fn missed(&self) -> usize {
        if self.cut_short {
            return 0;
        }
        self.rust.iter().zip(&self.freefem).filter(|(r, f)| !(r.pass && f.pass)).count()
    }

    /// The table for the terminal: per value, the published number, each engine's value and
    /// error, the tolerance and each engine's verdict, then the sources.
    pub fn table(&self) -> String {
        let mut out = String::from("published values:\n");
        out += &format!(
            "{:<34} {:>15} {:>15} {:>10} {:>15} {:>10} {:>10}  rust  freefem\n",
            "quantity", "published", "rust", "error", "freefem", "error", "tolerance"
        );
        let value = |r: &PublishedRow| r.computed.as_ref().map_or("-".to_string(), |c| format!("{c:.8e}"));
        let verdict = |r: &PublishedRow| if r.pass { "pass" } else { "MISS" };
        for (r, f) in self.rust.iter().zip(&self.freefem) {
            out += &format!(
                "{:<34} {:>15.8e} {:>15} {:>10.2e} {:>15} {:>10.2e} {:>10.2e}  {:<4}  {}\n",
                format!("{} [{}]", r.quantity, r.unit),
                r.published,
                value(r),
                r.error,
                value(f),
                f.error,
                r.tolerance,
                verdict(r),
                verdict(f)
            );
        }
        for s in sources(&self.rust) {
            out += &format!("  source: {s}\n");
        }
        if self.cut_short {
            out += "  (--short ran fewer steps or iterations than the case: the published values are of the whole run and not counted)\n";
        }
        out
    }

    /// `reference.csv` of the comparison.
    pub fn csv(&self) -> String {
        crate::output::reference_file::compare_csv(&self.rust, &self.freefem)
    }
}

/// Does the horizon run a shorter problem than `case`: a dynamic case beyond
/// [`SHORT_STEPS`], or an inverse fixed point (cut at `compare::SHORT_ITERATIONS`)?
fn cut_short(case: &Case, horizon: Horizon) -> bool {
    horizon == Horizon::Short
        && match &case.analysis {
            Analysis::Dynamic(p) => p.steps > SHORT_STEPS,
            Analysis::Inverse(s) => s.params.method == InverseMethod::FixedPoint,
            Analysis::Static(_) => false,
        }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn case(name: &str) -> Case {
        Case::from_file(&Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("cases/{name}.toml"))).expect("case")
    }

    /// `--short` cuts a dynamic case beyond its 200 steps and an inverse fixed point, whose
    /// results are then not the published ones; a static case, a short dynamic one and Newton
    /// run whole.
    #[test]
    fn the_short_horizon_is_known_to_cut() {
        let dynamic = case("cantilever_dynamic");
        assert!(cut_short(&dynamic, Horizon::Short) && !cut_short(&dynamic, Horizon::Full));
        assert!(!cut_short(&dynamic.time_prefix(SHORT_STEPS), Horizon::Short));
        assert!(!cut_short(&case("timoshenko_5pct"), Horizon::Short));
        assert!(cut_short(&case("inverse_bend"), Horizon::Short));
        assert!(!cut_short(&case("inverse_bend_twist_newton"), Horizon::Short));
    }
}
