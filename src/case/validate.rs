//! Raw case tables → the typed [`Case`]: one function per table, each building the solver's
//! own params type directly, every rule in one place (a sweep's values go through these same
//! functions, `case::sweep`). Errors name the file and the key.
//!
//! The tables of loads ([`loads`]) and of clips ([`clip`]) are validated in submodules.
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use nalgebra::Vector3;

use super::raw::*;
use super::{
    Analysis, Case, CaseChecks, CaseError, CaseOrigin, CompareOverrides, CompareSpec, DataSource, InverseSettings,
    Reference, RodGiven, RodLength, Section, WeightsRule, DEFAULT_COMPARE_FRAMES,
};
use crate::expr::{Expr, ExprError, Node};
use crate::model::material::RodProperties;
use crate::model::mesh::{Mesh, QuadratureScheme};
use crate::solve::certificate::{CERTIFICATE_FLOOR, DEFAULT_CERTIFICATE_TOLERANCE};
use crate::solve::dynamics::DynamicParams;
use crate::solve::inverse::{default_stabilisation, InverseMethod, InverseParams, Weights};
use crate::solve::statics::{Method, StaticParams};

mod clip;
mod general;
mod loads;
mod modes;
mod published;
mod rod;

/// Most elements of a mesh: 10⁶. The cases use 10–400 (the Timoshenko convergence study of
/// `cases/paper/fig07_timoshenko.toml` goes to 400); a mesh beyond this would not fit the
/// solvers' memory (the inverse KKT system holds 12 unknowns per node in a band of 24) and a
/// count read from a file must not decide an allocation unchecked.
pub const MAX_ELEMENTS: usize = 1_000_000;

/// The validator of one case file: its path (for messages) and its evaluated constants.
pub(super) struct Validator<'a> {
    pub(super) path: &'a Path,
    constants: BTreeMap<String, f64>,
    /// the names of `[constants]` (known before they are evaluated, for messages)
    constant_names: BTreeSet<String>,
    /// `time.end_s` of a dynamic case, once known (the times at which expressions of t are checked)
    end_time_s: Option<f64>,
}

impl<'a> Validator<'a> {
    pub(super) fn new(path: &'a Path) -> Self {
        Validator { path, constants: BTreeMap::new(), constant_names: BTreeSet::new(), end_time_s: None }
    }

    fn err(&self, key: &str, reason: impl Into<String>) -> CaseError {
        CaseError::Invalid { path: self.path.to_path_buf(), key: key.to_string(), reason: reason.into() }
    }

    /// A finite number (a TOML number or an expression of the constants).
    fn scalar(&self, key: &str, v: &Scalar) -> Result<f64, CaseError> {
        let x = match v {
            Scalar::Number(x) => *x,
            Scalar::Text(s) => crate::expr::eval_const(s, &self.constants).map_err(|e| match e {
                ExprError::UnknownVariable { name } => self.err(key, self.unknown_name(&name, s, &[])),
                e => self.err(key, syntax_in_words(s, &e)),
            })?,
        };
        if !x.is_finite() {
            return Err(self.err(key, format!("value is not finite ({x})")));
        }
        Ok(x)
    }

    fn positive(&self, key: &str, v: &Scalar) -> Result<f64, CaseError> {
        let x = self.scalar(key, v)?;
        if x <= 0.0 {
            return Err(self.err(key, format!("must be > 0, got {x}")));
        }
        Ok(x)
    }

    fn nonnegative(&self, key: &str, v: &Scalar) -> Result<f64, CaseError> {
        let x = self.scalar(key, v)?;
        if x < 0.0 {
            return Err(self.err(key, format!("must be ≥ 0, got {x}")));
        }
        Ok(x)
    }

    /// A tolerance or other number in (0, 1).
    fn unit_open(&self, key: &str, v: f64) -> Result<f64, CaseError> {
        if !(v > 0.0 && v < 1.0) {
            return Err(self.err(key, format!("must lie in (0, 1), got {v}")));
        }
        Ok(v)
    }

    /// `solver.certificate_tolerance` (or `data.…`): in `[CERTIFICATE_FLOOR, 1)`, default
    /// [`DEFAULT_CERTIFICATE_TOLERANCE`] (docs/certificate.md).
    fn certificate_tolerance(&self, key: &str, v: Option<f64>) -> Result<f64, CaseError> {
        match v {
            None => Ok(DEFAULT_CERTIFICATE_TOLERANCE),
            Some(v) if (CERTIFICATE_FLOOR..1.0).contains(&v) => Ok(v),
            Some(v) => Err(self.err(
                key,
                format!(
                    "must lie in [{CERTIFICATE_FLOOR:e}, 1), got {v}: below {CERTIFICATE_FLOOR:e} the certificate is round-off (docs/certificate.md)"
                ),
            )),
        }
    }

    /// A count ≥ 1.
    fn count(&self, key: &str, v: usize) -> Result<usize, CaseError> {
        if v == 0 {
            return Err(self.err(key, "must be ≥ 1"));
        }
        Ok(v)
    }

    /// The whole case.
    pub(super) fn case(mut self, mut raw: RawCase, name: &str) -> Result<Case, CaseError> {
        self.constants(std::mem::take(&mut raw.constants))?;
        let (mesh, rod_length) = self.mesh(&raw.rod)?;
        let kind = raw.solver.analysis;
        self.end_time_s = raw.time.as_ref().and_then(|t| self.scalar("time.end_s", &t.end_s).ok());
        let (section, material, props, density_given) = self.section_and_material(&raw, kind, &mesh, rod_length)?;
        if rod_length == RodLength::Given {
            // a length from the data is checked when it is known (the case is validated again)
            self.slenderness(&mesh, &section)?;
        }
        let (loads, load_texts) = self.loads(&raw.loads, kind)?;
        let loads = loads.with_point_loads(self.point_loads(&raw.loads.point, &mesh, kind)?);
        let general = self.general_rod(&raw, &mesh)?;
        self.tables_of_other_analyses(&raw, kind)?;
        let quadrature = match raw.solver.quadrature {
            RawQuadrature::Selective => QuadratureScheme::Selective,
            RawQuadrature::Full => QuadratureScheme::Full,
            RawQuadrature::Reduced => QuadratureScheme::Reduced,
            RawQuadrature::Midpoint => QuadratureScheme::Midpoint,
            RawQuadrature::Gauss2 => QuadratureScheme::Gauss2,
        };
        if quadrature == QuadratureScheme::Midpoint && kind == RawAnalysis::Dynamic {
            return Err(self.err(
                "solver.quadrature",
                "\"midpoint\" integrates the mass matrix with one point, which is singular for P1 elements: a dynamic case needs \"selective\", \"full\", \"reduced\" or \"gauss2\"",
            ));
        }
        let vibration_modes = self.vibration_modes(&raw, &mesh, density_given, general.is_some())?;
        let analysis = match kind {
            RawAnalysis::Static => Analysis::Static(StaticParams {
                path: self.path(&raw)?,
                buckling_modes: self.buckling_modes(raw.solver.buckling_modes, &mesh)?,
                vibration_modes,
                ..self.static_solve("solver", &raw.solver)?
            }),
            RawAnalysis::Dynamic => Analysis::Dynamic(self.dynamic(&raw.solver, raw.time.as_ref())?),
            RawAnalysis::Inverse => Analysis::Inverse(self.inverse(&raw, (&mesh, &section), &props)?),
        };
        self.loads_are_finite(&loads, &load_texts, &mesh, quadrature, &analysis)?;
        self.length_from_data(rod_length, &analysis)?;
        let compare = self.compare(&raw.compare)?;
        let reference = self.reference(raw.reference.as_ref(), kind, &loads)?;
        let published = self.published(raw.reference.as_ref(), &mesh, &analysis)?;
        Ok(Case {
            name: name.to_string(),
            origin: CaseOrigin {
                description: raw.description,
                source: None,
                source_sha256: None,
                constants: self.constants,
                raw: None,
            },
            mesh,
            props,
            rod: RodGiven { length: rod_length, material, density_given, general },
            section,
            quadrature,
            loads,
            analysis,
            checks: CaseChecks { compare, reference, published },
        })
    }

    /// `[constants]`: each may use the others, in any order: evaluated in the order of their
    /// dependencies (the first ready name first), so that each is evaluated once; constants
    /// that depend on each other are refused.
    fn constants(&mut self, raw: BTreeMap<String, Scalar>) -> Result<(), CaseError> {
        for k in raw.keys() {
            // A name is an identifier that parses to itself: not s, t, pi or a function.
            if matches!(k.as_str(), "s" | "t") || Expr::parse(k).map(|e| e.root != Node::Var(k.clone())).unwrap_or(true)
            {
                return Err(
                    self.err(&format!("constants.{k}"), "not a valid constant name (identifier other than s, t, pi)")
                );
            }
        }
        self.constant_names = raw.keys().cloned().collect();
        // Dependencies on other constants (a text that does not parse has none: its evaluation
        // reports the parse error).
        let deps: BTreeMap<&str, BTreeSet<String>> = raw
            .iter()
            .map(|(k, v)| {
                let vars = match v {
                    Scalar::Text(t) => Expr::parse(t).map(|e| e.variables()).unwrap_or_default(),
                    Scalar::Number(_) => BTreeSet::new(),
                };
                (k.as_str(), vars.into_iter().filter(|d| raw.contains_key(d)).collect())
            })
            .collect();
        let mut users: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
        for (k, ds) in &deps {
            for d in ds {
                users.entry(d.as_str()).or_default().push(k);
            }
        }
        let mut waiting: BTreeMap<&str, usize> = deps.iter().map(|(k, ds)| (*k, ds.len())).collect();
        let mut ready: BTreeSet<&str> = waiting.iter().filter(|(_, n)| **n == 0).map(|(k, _)| *k).collect();
        while let Some(k) = ready.pop_first() {
            waiting.remove(k);
            let x = self.scalar(&format!("constants.{k}"), &raw[k])?;
            self.constants.insert(k.to_string(), x);
            for u in users.get(k).into_iter().flatten() {
                if let Some(n) = waiting.get_mut(u) {
                    *n -= 1;
                    if *n == 0 {
                        ready.insert(u);
                    }
                }
            }
        }
        if let Some(k) = waiting.keys().next() {
            let cycle: Vec<&str> = waiting.keys().copied().collect();
            return Err(self.err(
                &format!("constants.{k}"),
                format!(
                    "cannot be evaluated: the constants {} refer to themselves or to one another in a cycle",
                    cycle.join(", ")
                ),
            ));
        }
        Ok(())
    }

    /// Tables and `[solver]` keys that belong to another analysis are refused.
    fn tables_of_other_analyses(&self, raw: &RawCase, kind: RawAnalysis) -> Result<(), CaseError> {
        let s = &raw.solver;
        self.unit_open("solver.tolerance", s.tolerance)?;
        self.count("solver.max_iterations", s.max_iterations)?;
        if kind != RawAnalysis::Inverse {
            for (present, key) in
                [(raw.data.is_some(), "data"), (raw.clip.is_some(), "clip"), (raw.inverse.is_some(), "inverse")]
            {
                if present {
                    return Err(self.err(key, "only allowed when solver.analysis = \"inverse\""));
                }
            }
            if s.warm_start_tolerance.is_some() {
                return Err(self.err("solver.warm_start_tolerance", "only used by an inverse analysis"));
            }
        }
        if kind != RawAnalysis::Dynamic && raw.time.is_some() {
            return Err(self.err("time", "only allowed when solver.analysis = \"dynamic\""));
        }
        Ok(())
    }

    /// `method` (+ `relaxation`) of a static solve in table `table`.
    fn static_method(&self, table: &str, method: RawMethod, relaxation: Option<f64>) -> Result<Method, CaseError> {
        match method {
            RawMethod::FixedPoint => Ok(Method::FixedPoint { relaxation: self.relaxation(table, relaxation)? }),
            RawMethod::Newton => {
                if relaxation.is_some() {
                    return Err(self.err(&format!("{table}.relaxation"), "not used by method = \"newton\""));
                }
                Ok(Method::Newton)
            }
        }
    }

    /// `relaxation` of table `table`, required, in (0, 1].
    fn relaxation(&self, table: &str, relaxation: Option<f64>) -> Result<f64, CaseError> {
        let key = format!("{table}.relaxation");
        let w = relaxation.ok_or_else(|| self.err(&key, "required by method = \"fixed_point\""))?;
        if !(w > 0.0 && w <= 1.0) {
            return Err(self.err(&key, format!("must lie in (0, 1], got {w}")));
        }
        Ok(w)
    }

    /// A static solve: `[solver]` of a static analysis (`table = "solver"`), or `[data]`.
    fn static_solve(&self, table: &str, s: &RawSolver) -> Result<StaticParams, CaseError> {
        Ok(StaticParams {
            method: self.static_method(table, s.method, s.relaxation)?,
            tolerance: self.unit_open(&format!("{table}.tolerance"), s.tolerance)?,
            max_iterations: self.count(&format!("{table}.max_iterations"), s.max_iterations)?,
            continuation_steps: self.count(&format!("{table}.continuation_steps"), s.continuation_steps)?,
            certificate_tolerance: self
                .certificate_tolerance(&format!("{table}.certificate_tolerance"), s.certificate_tolerance)?,
            path: None,
            buckling_modes: 0,
            vibration_modes: 0,
        })
    }

    /// `solver.buckling_modes` of a static analysis (D27): at least 1 when given, on a mesh
    /// the dense eigen-analysis takes.
    fn buckling_modes(&self, modes: Option<usize>, mesh: &crate::model::mesh::Mesh) -> Result<usize, CaseError> {
        let Some(n) = modes else { return Ok(0) };
        let key = "solver.buckling_modes";
        if n == 0 {
            return Err(self.err(key, "must be at least 1 (leave it out for no buckling analysis)"));
        }
        let unknowns = mesh.dofs().len();
        let limit = crate::solve::stability::DENSE_LIMIT;
        if unknowns > limit {
            return Err(self.err(
                key,
                format!("the buckling analysis is dense (D27): at most {limit} unknowns (300 elements), this rod has {unknowns}"),
            ));
        }
        Ok(n)
    }

    /// `[solver]` and `[time]` of a dynamic analysis.
    fn dynamic(&self, s: &RawSolver, time: Option<&RawTime>) -> Result<DynamicParams, CaseError> {
        if s.method != RawMethod::Newton {
            return Err(self.err("solver.method", "a dynamic analysis is solved by \"newton\" per step (D6)"));
        }
        if s.relaxation.is_some() {
            return Err(self.err("solver.relaxation", "not used by a dynamic analysis"));
        }
        if s.continuation_steps != 1 {
            return Err(self.err("solver.continuation_steps", "only for a static analysis"));
        }
        if s.buckling_modes.is_some() {
            return Err(self.err("solver.buckling_modes", "only for a static analysis (D27)"));
        }
        let t = time.ok_or_else(|| self.err("time", "required when solver.analysis = \"dynamic\""))?;
        Ok(DynamicParams {
            end_time_s: self.positive("time.end_s", &t.end_s)?,
            steps: self.count("time.steps", t.steps)?,
            newton_tolerance: s.tolerance,
            newton_max_iterations: s.max_iterations,
            certificate_tolerance: self
                .certificate_tolerance("solver.certificate_tolerance", s.certificate_tolerance)?,
        })
    }

    /// The method of an inverse analysis (`solver.method`, with its warm start for Newton).
    fn inverse_method(&self, s: &RawSolver) -> Result<InverseMethod, CaseError> {
        Ok(match s.method {
            RawMethod::FixedPoint => {
                if s.warm_start_tolerance.is_some() {
                    return Err(self.err("solver.warm_start_tolerance", "only used by method = \"newton\""));
                }
                InverseMethod::FixedPoint
            }
            RawMethod::Newton => {
                let w = s.warm_start_tolerance.ok_or_else(|| {
                    self.err(
                        "solver.warm_start_tolerance",
                        "required by method = \"newton\" (Newton starts from the fixed point's iterate at this relative change, I8)",
                    )
                })?;
                InverseMethod::Newton { warm_start_tolerance: self.unit_open("solver.warm_start_tolerance", w)? }
            }
        })
    }

    /// Where an inverse analysis's data come from: `[data]` (a forward solve) or `[clip]`.
    fn data_source(&self, raw: &RawCase, mesh: &Mesh, section: &Section) -> Result<DataSource, CaseError> {
        Ok(match (&raw.data, &raw.clip) {
            (Some(d), None) => DataSource::Forward(self.data(d)?),
            (None, Some(cl)) => DataSource::Clip(Box::new(self.clip(cl, mesh, section)?)),
            (Some(_), Some(_)) => {
                return Err(self.err("clip", "give either [data] (synthetic) or [clip] (recorded), not both"))
            }
            (None, None) => return Err(self.err(
                "data",
                "an inverse case needs [data] (a forward solve generating the centreline) or [clip] (a recorded clip)",
            )),
        })
    }

    /// `[solver]`, `[inverse]` and `[data]` or `[clip]` of an inverse analysis.
    fn inverse(
        &self,
        raw: &RawCase,
        (mesh, section): (&Mesh, &Section),
        props: &RodProperties,
    ) -> Result<InverseSettings, CaseError> {
        let s = &raw.solver;
        // Both methods need the relaxation: Newton starts from the fixed point (I8).
        let relaxation = self.relaxation("solver", s.relaxation)?;
        let method = self.inverse_method(s)?;
        if s.continuation_steps != 1 {
            return Err(self.err("solver.continuation_steps", "not used by an inverse analysis"));
        }
        if s.buckling_modes.is_some() {
            return Err(self.err("solver.buckling_modes", "only for a static analysis (D27)"));
        }
        let data = self.data_source(raw, mesh, section)?;
        let inv = raw.inverse.as_ref().ok_or_else(|| {
            self.err("inverse", "required when solver.analysis = \"inverse\" (the weights of eq. 41)")
        })?;
        let weights = self.weights(inv)?;
        let frame_interval_s = match (&inv.frame_interval_s, &raw.clip) {
            (Some(_), Some(_)) => {
                return Err(self.err("inverse.frame_interval_s", "a clip case takes Δt from clip.frame_interval_s"))
            }
            (Some(v), None) => self.positive("inverse.frame_interval_s", v)?,
            (None, Some(cl)) => self.positive("clip.frame_interval_s", &cl.frame_interval_s)?,
            (None, None) if weights.lambda_omega.iter().any(|&w| w > 0.0) => {
                return Err(self.err("inverse.frame_interval_s", "required when lambda_omega is non-zero"));
            }
            (None, None) => 1.0,
        };
        let alpha0_rad =
            inv.alpha0_rad.as_ref().map(|v| self.scalar("inverse.alpha0_rad", v)).transpose()?.unwrap_or(0.0);
        let one_rule = matches!(s.quadrature, RawQuadrature::Midpoint | RawQuadrature::Gauss2);
        let stabilisation = match &inv.stabilisation {
            Some(v) => {
                let e = self.scalar("inverse.stabilisation", v)?;
                if !(0.0..=1.0).contains(&e) {
                    return Err(self.err("inverse.stabilisation", format!("must lie in [0, 1], got {e}")));
                }
                if one_rule && e != 0.0 {
                    return Err(self.err(
                        "inverse.stabilisation",
                        "blends two rules in the λd term (I11), but solver.quadrature = \"midpoint\" or \"gauss2\" applies one rule to every integral: leave it out",
                    ));
                }
                e
            }
            None if one_rule => 0.0,
            None => default_stabilisation(&weights, &props.bend_twist_nm2, mesh.length_m),
        };
        let params = InverseParams {
            weights,
            frame_interval_s,
            alpha0_rad,
            stabilisation,
            relaxation,
            method,
            tolerance: s.tolerance,
            max_iterations: s.max_iterations,
            certificate_tolerance: self
                .certificate_tolerance("solver.certificate_tolerance", s.certificate_tolerance)?,
        };
        if inv.weights == WeightsRule::Auto && !matches!(data, DataSource::Clip(_)) {
            return Err(self.err(
                "inverse.weights",
                "\"auto\" chooses λg from a recording's noise: only a clip case has one (use the default, \"fixed\")",
            ));
        }
        Ok(InverseSettings { params, data, weights_rule: inv.weights })
    }

    /// `[inverse]`: the weights of eq. (41).
    fn weights(&self, inv: &RawInverse) -> Result<Weights, CaseError> {
        let diag = |key: &str, v: &Option<[Scalar; 3]>| -> Result<Vector3<f64>, CaseError> {
            let mut out = Vector3::zeros();
            for (i, item) in v.iter().flatten().enumerate() {
                out[i] = self.nonnegative(&format!("{key}[{i}]"), item)?;
            }
            Ok(out)
        };
        Ok(Weights {
            lambda_g: self.positive("inverse.lambda_g", &inv.lambda_g)?,
            lambda_f: self.positive("inverse.lambda_f", &inv.lambda_f)?,
            lambda_l: self.positive("inverse.lambda_l", &inv.lambda_l)?,
            lambda_d: self.nonnegative("inverse.lambda_d", &inv.lambda_d)?,
            lambda_kappa: diag("inverse.lambda_kappa", &Some(inv.lambda_kappa.clone()))?,
            lambda_omega: diag("inverse.lambda_omega", &inv.lambda_omega)?,
        })
    }

    /// `[data]`: the static forward solve that generates an inverse case's data (I7).
    fn data(&self, d: &RawData) -> Result<StaticParams, CaseError> {
        if d.max_iterations == 0 || d.continuation_steps == 0 {
            return Err(self.err("data.max_iterations", "max_iterations and continuation_steps must be ≥ 1"));
        }
        Ok(StaticParams {
            method: self.static_method("data", d.method, d.relaxation)?,
            tolerance: self.unit_open("data.tolerance", d.tolerance)?,
            max_iterations: d.max_iterations,
            continuation_steps: d.continuation_steps,
            certificate_tolerance: self.certificate_tolerance("data.certificate_tolerance", d.certificate_tolerance)?,
            path: None,
            buckling_modes: 0,
            vibration_modes: 0,
        })
    }

    /// `[compare]`: the frames of a clip comparison and the overrides of the derived
    /// tolerances (D14), each with the `reason` they need.
    fn compare(&self, rc: &RawCompare) -> Result<CompareSpec, CaseError> {
        let o = CompareOverrides {
            displacement_rel: rc.displacement_rel,
            angles_rel: rc.angles_rel,
            metric_rel: rc.metric_rel,
            metric_abs: rc.metric_abs,
            iterations_abs: rc.iterations_abs,
            adjoint_rel: rc.adjoint_rel,
        };
        let given = [
            ("compare.displacement_rel", o.displacement_rel),
            ("compare.angles_rel", o.angles_rel),
            ("compare.metric_rel", o.metric_rel),
            ("compare.metric_abs", o.metric_abs),
            ("compare.iterations_abs", o.iterations_abs),
            ("compare.adjoint_rel", o.adjoint_rel),
        ];
        for (k, v) in given {
            if let Some(v) = v {
                if !(v >= 0.0 && v.is_finite()) {
                    return Err(self.err(k, format!("must be a finite number ≥ 0, got {v}")));
                }
            }
        }
        let reason = rc.reason.as_ref().map(|r| r.trim().to_string()).filter(|r| !r.is_empty());
        if let (Some((k, _)), None) = (given.iter().find(|(_, v)| v.is_some()), &reason) {
            return Err(self.err(
                k,
                "overrides the tolerance derived from the case's conditioning (docs/decisions.md D14): say why in compare.reason = \"…\", or remove it",
            ));
        }
        let frames = rc.frames.unwrap_or(DEFAULT_COMPARE_FRAMES);
        if frames == 0 {
            return Err(self.err("compare.frames", "must be ≥ 1"));
        }
        Ok(CompareSpec { frames, overrides: o, reason })
    }

    /// `[reference]`: the theory a static case is checked against.
    fn reference(
        &self,
        r: Option<&RawReference>,
        kind: RawAnalysis,
        loads: &crate::model::loads::Loads,
    ) -> Result<Option<Reference>, CaseError> {
        match r.map(|r| (r.kind, r.force_n.as_ref())) {
            None | Some((None, None)) => Ok(None),
            Some((None, Some(_))) => Err(self.err("reference.force_n", "only with kind = \"tip_loaded_cantilever\"")),
            Some((Some(RawReferenceKind::TipLoadedCantilever), force_n)) => {
                if kind != RawAnalysis::Static {
                    return Err(self.err("reference.kind", "\"tip_loaded_cantilever\" needs a static analysis"));
                }
                let force_n = force_n
                    .ok_or_else(|| self.err("reference.force_n", "required by kind = \"tip_loaded_cantilever\""))?;
                let force_n = self.positive("reference.force_n", force_n)?;
                // the theories (elastica, Reissner) are of the case's own tip force
                // scaled, so that a 5e300 N force does not overflow to an infinite norm
                let end = loads.end(0.0).0;
                let big = end.amax();
                let tip = if big > 0.0 { big * (end / big).norm() } else { 0.0 };
                if (force_n - tip).abs() > 1e-9 * force_n.max(tip) {
                    return Err(self.err(
                        "reference.force_n",
                        format!(
                            "{force_n:e} N, but the case's tip force loads.end_force_n has magnitude {tip:e} N: the \
                             reference solutions would be of another load (give the same force, or drop [reference])"
                        ),
                    ));
                }
                Ok(Some(Reference::TipLoadedCantilever { force_n }))
            }
        }
    }
}

/// A syntax error of the expression `text`, quoting it, with a hint for the two mistakes a
/// number in a case file invites: a decimal comma, and a unit after the value.
pub(super) fn syntax_in_words(text: &str, e: &ExprError) -> String {
    let hint = match e {
        ExprError::Unexpected { found, .. } if found.starts_with("','") || found.contains(',') => {
            " (a decimal comma? numbers take a point: 2.5e-5)"
        }
        ExprError::Unexpected { found, .. } if found.starts_with("identifier") => {
            " (a unit after the value? expressions take no units: give SI values, e.g. 1e-3 for 1 mm)"
        }
        _ => "",
    };
    format!("{}: {e}{hint}", quoted(text))
}

/// Longest expression quoted whole in a message [characters]; a longer one is quoted by its
/// start and its length (a generated expression can be megabytes: its error stays a line).
const QUOTE_CHARS: usize = 120;

/// `text` in backquotes for a message: whole up to [`QUOTE_CHARS`] characters, else its first
/// ones, an ellipsis and its length.
pub(super) fn quoted(text: &str) -> String {
    let n = text.chars().count();
    if n <= QUOTE_CHARS {
        return format!("`{text}`");
    }
    let head: String = text.chars().take(QUOTE_CHARS / 2).collect();
    format!("`{head}…` (an expression of {n} characters)")
}
