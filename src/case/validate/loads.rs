//! `[loads]`: the load components, expressions of `s`, `t` and the constants (D7), parsed with
//! messages that name the key, the expression and the names it may use, and evaluated where
//! and when the engines will evaluate them: a component that is not finite there is refused
//! here, naming the key, the expression, `s` and `t`, instead of failing in the solver.
use super::super::raw::{RawAnalysis, RawFrame, RawLoads, Scalar};
use super::super::{Analysis, CaseError};
use super::Validator;
use crate::expr::Expr;
use crate::model::loads::{LoadFrame, Loads};
use crate::model::mesh::{Mesh, QuadratureScheme};

/// Evaluations of one component at most spent on checking it at every time step of a dynamic
/// analysis; beyond that it is checked at [`MIN_TIME_SAMPLES`] (or more) steps spread evenly
/// from `t = 0` to `t = T`. `cantilever_dynamic` (1000 steps, 100 elements: 301 points) takes
/// 3·10⁵, a few milliseconds.
const EVALUATION_BUDGET: usize = 2_000_000;
/// Fewest time steps (including `t = 0` and `t = T`) at which a component of `s` and `t` is
/// checked when every step would exceed [`EVALUATION_BUDGET`].
const MIN_TIME_SAMPLES: usize = 101;

/// Names that read as "not a number" or "infinity" (as the TOML and Rust float syntaxes spell
/// them), which the expression language does not have.
fn is_non_finite_word(name: &str) -> bool {
    ["nan", "inf", "infinity"].iter().any(|w| name.eq_ignore_ascii_case(w))
}

impl Validator<'_> {
    /// Why `var` (in `text`) is refused, and the names an expression of `vars` may use.
    pub(super) fn unknown_name(&self, var: &str, text: &str, vars: &[&str]) -> String {
        let why = if is_non_finite_word(var) {
            " (NaN and infinity are not numbers of the expression language: every value must be finite)"
        } else if var == "t" {
            " (t, the time [s], is defined in the loads of a dynamic analysis only)"
        } else if var == "s" {
            " (s, the arc length [m], is defined in distributed loads only: end loads act at s = L)"
        } else {
            ""
        };
        format!("unknown name `{var}` in {}{why}; allowed names: {}", super::quoted(text), self.allowed_names(vars))
    }

    /// The names an expression of the variables `vars` may use: `vars`, `pi` and the constants.
    pub(super) fn allowed_names(&self, vars: &[&str]) -> String {
        let names: Vec<&str> = vars.iter().copied().chain(["pi"]).collect();
        if self.constant_names.is_empty() {
            format!("{} (no [constants] are defined)", names.join(", "))
        } else {
            let constants: Vec<&str> = self.constant_names.iter().map(String::as_str).collect();
            format!("{} and the [constants] {}", names.join(", "), constants.join(", "))
        }
    }

    /// A load component: a number or an expression of `allowed` and the constants; with its
    /// text as written.
    pub(super) fn expr(&self, key: &str, v: &Scalar, allowed: &[&str]) -> Result<(Expr, String), CaseError> {
        let text = match v {
            Scalar::Number(x) if !x.is_finite() => {
                return Err(self.err(
                    key,
                    format!(
                        "{x} is not a number of the expression language (NaN and infinity are not: every load \
                         must be finite); write a finite number or an expression of {}",
                        self.allowed_names(allowed)
                    ),
                ))
            }
            Scalar::Number(x) => format!("{x:e}"),
            Scalar::Text(s) => s.clone(),
        };
        let e = Expr::parse(&text)
            .map_err(|e| self.err(key, format!("cannot parse {}", super::syntax_in_words(&text, &e))))?;
        if let Some(var) =
            e.variables().into_iter().find(|v| !allowed.contains(&v.as_str()) && !self.constants.contains_key(v))
        {
            return Err(self.err(key, self.unknown_name(&var, &text, allowed)));
        }
        Ok((e, text))
    }

    fn vector(
        &self,
        key: &str,
        v: &Option<[Scalar; 3]>,
        allowed: &[&str],
        texts: &mut Vec<String>,
    ) -> Result<[Expr; 3], CaseError> {
        let zero = Scalar::Number(0.0);
        let items = v.clone().unwrap_or([zero.clone(), zero.clone(), zero]);
        let mut out = Vec::with_capacity(3);
        for (i, item) in items.iter().enumerate() {
            let (e, text) = self.expr(&format!("{key}[{i}]"), item, allowed)?;
            out.push(e);
            texts.push(text);
        }
        Ok([out[0].clone(), out[1].clone(), out[2].clone()])
    }

    /// `[loads]`: expressions of `s` (and `t` in a dynamic analysis) and the constants, and the
    /// twelve components' texts as written (in the order of `Loads::exprs`).
    pub(super) fn loads(&self, l: &RawLoads, kind: RawAnalysis) -> Result<(Loads, Vec<String>), CaseError> {
        let (vars, end_vars): (&[&str], &[&str]) = match kind {
            RawAnalysis::Static | RawAnalysis::Inverse => (&["s"], &[]),
            RawAnalysis::Dynamic => (&["s", "t"], &["t"]),
        };
        let frame = match l.frame {
            RawFrame::Global => LoadFrame::Global,
            RawFrame::Local => LoadFrame::Local,
        };
        let mut texts = Vec::with_capacity(12);
        let loads = Loads::new(
            frame,
            self.vector(LOAD_KEYS[0], &l.force_n_per_m, vars, &mut texts)?,
            self.vector(LOAD_KEYS[1], &l.torque_nm_per_m, vars, &mut texts)?,
            self.vector(LOAD_KEYS[2], &l.end_force_n, end_vars, &mut texts)?,
            self.vector(LOAD_KEYS[3], &l.end_torque_nm, end_vars, &mut texts)?,
            &self.constants,
        )
        .map_err(|e| self.err("loads", e.to_string()))?;
        Ok((loads, texts))
    }

    /// Every load component is finite where and when the engines evaluate it: the distributed
    /// ones at the nodes and at the load quadrature points of every element (D4), the end loads
    /// at `s = L`; at `t = 0` in a static or inverse analysis, at every time step `t_n = n Δt`
    /// of a dynamic one (at ≥ [`MIN_TIME_SAMPLES`] of them, `t = 0` and `t = T` included, when
    /// every step would cost more than [`EVALUATION_BUDGET`] evaluations).
    pub(super) fn loads_are_finite(
        &self,
        loads: &Loads,
        texts: &[String],
        mesh: &Mesh,
        quadrature: QuadratureScheme,
        analysis: &Analysis,
    ) -> Result<(), CaseError> {
        let h = mesh.h();
        let mut points: Vec<f64> = Vec::with_capacity(mesh.nodes() * 3);
        for e in 0..mesh.elements {
            let s0 = mesh.node_s(e);
            points.push(s0);
            points.extend(quadrature.loads().points.iter().map(|xi| s0 + xi * h));
        }
        points.push(mesh.node_s(mesh.elements));
        let steps = match analysis {
            Analysis::Dynamic(p) => Some((p.steps, p.end_time_s / p.steps as f64)),
            _ => None,
        };
        let names: Vec<&str> = ["s", "t"].into_iter().chain(self.constants.keys().map(String::as_str)).collect();
        let mut slots: Vec<f64> = [0.0, 0.0].into_iter().chain(self.constants.values().copied()).collect();
        for (group, key) in LOAD_KEYS.iter().enumerate() {
            for (i, e) in loads.exprs[group].iter().enumerate() {
                let vars = e.variables();
                let compiled = e.compile(&names).map_err(|err| self.err(key, err.to_string()))?;
                // The end loads are evaluated with s = 0 (they take no s) and act at s = L.
                let at: &[f64] = if group >= 2 || !vars.contains("s") { &points[..1] } else { &points };
                let times = match steps {
                    Some((n, dt)) if vars.contains("t") => time_steps(n, dt, at.len()),
                    _ => vec![0.0],
                };
                for &t in &times {
                    for &s in at {
                        slots[0] = s;
                        slots[1] = t;
                        let v = compiled.eval(&slots);
                        if !v.is_finite() {
                            let text = &texts[3 * group + i];
                            let s_text =
                                if group >= 2 { format!("s = L = {} m", mesh.length_m) } else { format!("s = {s} m") };
                            return Err(self.err(
                                &format!("{key}[{i}]"),
                                format!(
                                    "`{text}` is not finite ({v}) at {s_text}, t = {t} s: a load must be finite at every node and \
                                     load quadrature point of the rod{}",
                                    if steps.is_some() { " and at every time step" } else { "" }
                                ),
                            ));
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

/// The case-file keys of the four load vectors, in the order of `Loads::exprs`.
const LOAD_KEYS: [&str; 4] =
    ["loads.force_n_per_m", "loads.torque_nm_per_m", "loads.end_force_n", "loads.end_torque_nm"];

/// Times `t_n = n Δt` (as the time stepping computes them, D6) at which a component evaluated
/// at `points` points per time is checked: every `n = 0 … steps` within the budget, else at
/// least [`MIN_TIME_SAMPLES`] steps spread evenly, `n = 0` and `n = steps` included.
fn time_steps(steps: usize, dt: f64, points: usize) -> Vec<f64> {
    let all = steps.saturating_add(1);
    let samples = (EVALUATION_BUDGET / points.max(1)).max(MIN_TIME_SAMPLES);
    if all <= samples {
        return (0..=steps).map(|n| n as f64 * dt).collect();
    }
    (0..samples)
        .map(|k| {
            let n = (k as u128 * steps as u128 / (samples - 1) as u128) as usize;
            n as f64 * dt
        })
        .collect()
}
