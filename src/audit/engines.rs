//! The check of a claim in both engines and both one-rule readings, so that the audit itself can
//! say *refuted*: a row about the paper's scheme as printed (the relaxed fixed point of (61),
//! w = 0.5, Remark 10, the λd term without blend) whose check does not hold in the Rust engine
//! is run again on every point of its runs in the three other combinations of engine (Rust,
//! FreeFEM: `freefem/`, written separately from the paper) and one-rule reading (`gauss2`: every
//! integral by the 2-point rule; `midpoint`: by the 1-point rule). The row's verdict is
//! *refuted* when the check fails in all four: the failure is the printed scheme's, not one
//! engine's or one reading's (`docs/audit.md`).
//!
//! A row is rerun when it is a claim of the paper (not `ours`), its check is complete (not
//! `partial`), on the paper's own data (no substitute), its runs are single frames of the
//! printed scheme (no scheme deviation, `check::scheme_deviations`) in one of the two readings,
//! and its check fails in Rust. Each run is rerun once per combination, shared by the rows of
//! its spec that read it; a point runs in `out/<spec>/engines/<engine>_<reading>/<run>/<point>`.
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::check::{evaluate, scheme_deviations, stopped, Holding};
use super::measures::derived_metrics;
use super::spec::{Claim, Spec};
use super::{ClaimResult, PointResult, RunResults, Verdict};
use crate::case::sweep::{product, Point};
use crate::case::Case;
use crate::engine::Engine;
use crate::jobs::sweep::{point_manifest, run_point_in};
use crate::model::mesh::QuadratureScheme;

/// An engine and a one-rule reading of the printed scheme.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Variant {
    pub engine: Engine,
    pub quadrature: QuadratureScheme,
}

impl Variant {
    /// `FreeFEM gauss2` style, for the row.
    pub fn label(&self) -> String {
        let engine = if self.engine == Engine::Rust { "Rust" } else { "FreeFEM" };
        format!("{engine} {}", self.quadrature.name())
    }
    /// The folder name, `freefem_midpoint`.
    fn folder(&self) -> String {
        format!("{}_{}", self.engine, self.quadrature.name())
    }
}

/// The three combinations beside the spec's own (Rust in `reading`), in the order of the row.
pub fn others(reading: QuadratureScheme) -> Vec<Variant> {
    let other = if reading == QuadratureScheme::Gauss2 { QuadratureScheme::Midpoint } else { QuadratureScheme::Gauss2 };
    vec![
        Variant { engine: Engine::Freefem, quadrature: reading },
        Variant { engine: Engine::Rust, quadrature: other },
        Variant { engine: Engine::Freefem, quadrature: other },
    ]
}

/// The one-rule reading of a claim's runs, if the claim is rerun (module documentation):
/// every run a single frame of the printed scheme in the same reading.
pub fn reading(spec: &Spec, claim: &Claim) -> Option<QuadratureScheme> {
    let c = &claim.caveats;
    if claim.ours || c.partial.is_some() || c.substitute.is_some() || !scheme_deviations(spec, &claim.check).is_empty()
    {
        return None;
    }
    let runs: Vec<_> = claim.check.runs().iter().map(|r| spec.run(r)).collect::<Option<_>>()?;
    let q = runs.first()?.case.quadrature;
    let printed =
        |r: &&super::spec::RunSpec| r.case.quadrature == q && r.case.inverse().is_some() && r.case.clip().is_none();
    (matches!(q, QuadratureScheme::Gauss2 | QuadratureScheme::Midpoint) && runs.iter().all(printed)).then_some(q)
}

/// One point to rerun.
pub struct Rerun<'a> {
    spec: usize,
    run: &'a str,
    variant: Variant,
    point: Point,
    case: Case,
    dir: PathBuf,
}

/// The reruns of every spec: per spec, the variants' runs.
pub type Reruns = Vec<Vec<(Variant, Vec<RunResults>)>>;

/// The points to rerun: the runs of every claim of `specs` that is rerun and whose check does
/// not hold on `results` (the Rust runs), once per run and variant.
pub fn plan<'a>(specs: &'a [Spec], results: &[Vec<RunResults>], out: &Path) -> Vec<Rerun<'a>> {
    let mut jobs: Vec<Rerun> = Vec::new();
    for (i, (spec, runs)) in specs.iter().zip(results).enumerate() {
        for claim in &spec.claims {
            let Some(q) = reading(spec, claim) else { continue };
            if runs.iter().all(|r| r.points.is_empty()) || evaluate(&claim.check, runs).0 == Holding::Holds {
                continue;
            }
            for name in claim.check.runs() {
                let Some(run) = spec.run(name) else { continue };
                for variant in others(q) {
                    if jobs.iter().any(|j| j.spec == i && j.run == name && j.variant == variant) {
                        continue;
                    }
                    let set = [("solver.quadrature".to_string(), toml::Value::from(variant.quadrature.name()))];
                    let Ok(case) = run.case.with_overrides(&set) else { continue };
                    let Ok(points) = product(&case, &run.grid) else { continue };
                    for (point, case) in points {
                        let label = if point.is_empty() { "run".to_string() } else { case.name.clone() };
                        let dir = out.join(&spec.name).join("engines").join(variant.folder()).join(name).join(label);
                        jobs.push(Rerun { spec: i, run: &run.name, variant, point, case, dir });
                    }
                }
            }
        }
    }
    jobs
}

/// Run the points of `jobs` in parallel (in the caller's thread pool) and group them per spec,
/// variant and run.
pub fn run(specs: &[Spec], jobs: &[Rerun]) -> Reruns {
    let finished: Vec<(usize, Variant, &str, PointResult)> = jobs
        .par_iter()
        .map(|j| {
            let template = point_manifest("audit point", &j.case, &j.point);
            let mut outcome = run_point_in(&j.case, j.variant.engine, &j.dir, &template);
            if let Some(m) = outcome.metrics.as_mut() {
                m.extend(derived_metrics(&j.case, outcome.single.as_ref(), None));
            }
            let label = j.dir.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default();
            (j.spec, j.variant, j.run, PointResult { point: j.point.clone(), label, outcome, series: None })
        })
        .collect();
    let mut out: Reruns = specs.iter().map(|_| Vec::new()).collect();
    for (spec, variant, run, p) in finished {
        let groups = &mut out[spec];
        let g = match groups.iter().position(|(v, _)| *v == variant) {
            Some(g) => g,
            None => {
                groups.push((variant, Vec::new()));
                groups.len() - 1
            }
        };
        let runs = &mut groups[g].1;
        match runs.iter_mut().find(|r| r.name == run) {
            Some(r) => r.points.push(p),
            None => runs.push(RunResults { name: run.to_string(), points: vec![p], case_name: String::new() }),
        }
    }
    out
}

/// The claim's check in the other engine and readings (`c.engines`), and *refuted* when it
/// fails in all of them and in Rust (module documentation). `reruns`: the spec's.
pub fn apply(spec: &Spec, claim: &Claim, c: &mut ClaimResult, reruns: &[(Variant, Vec<RunResults>)]) {
    let Some(q) = reading(spec, claim) else { return };
    // a check that holds in Rust is not rerun
    if matches!(c.verdict, None | Some(Verdict::Reproduced | Verdict::NotComputable)) {
        return;
    }
    let mut texts = Vec::new();
    let mut all_fail = true;
    for variant in others(q) {
        let Some((_, runs)) = reruns.iter().find(|(v, _)| *v == variant) else { return };
        // every run of the claim rerun whole: a point stopped by a signal refutes nothing
        let whole = |name: &&str| {
            runs.iter().find(|r| r.name == *name).is_some_and(|r| !r.points.is_empty() && !r.points.iter().any(stopped))
        };
        if !claim.check.runs().iter().all(whole) {
            return;
        }
        let (o, text) = evaluate(&claim.check, runs);
        // a check that could not be evaluated there refutes nothing
        all_fail &= o != Holding::Holds && !text.starts_with("not evaluated");
        texts.push(format!("{}: {}", variant.label(), text));
    }
    c.engines = Some(format!("rerun in {}", texts.join("; ")));
    if all_fail {
        c.verdict = Some(Verdict::Refuted);
    }
}
