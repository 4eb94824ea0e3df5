//! The general rod of a forward case (`docs/decisions.md`, D20–D23): `[rod]`'s reference keys and
//! chart axis, `[ends]`, `[[loads.point]]`. Nothing here is given: `None`, the paper's rod
//! (straight along e3 from the origin, clamped at s = 0, free at s = L).
use nalgebra::{Matrix3, Vector3};

use super::super::raw::{
    RawAnalysis, RawCase, RawContinuation, RawEnd, RawEndKind, RawFrame, RawMethod, RawPointLoad, RawTwist, Scalar,
};
use super::super::CaseError;
use super::Validator;
use crate::expr::Expr;
use crate::model::chart::Chart;
use crate::model::ends::{free_rigid_motions, End, EndKind, Ends, Motion};
use crate::model::geometry::{RestShape, RestSpec, Rod};
use crate::model::loads::{LoadFrame, PointLoad, VectorExpr};
use crate::model::mesh::Mesh;
use crate::solve::arclength::ArcLengthParams;

/// Times at which a dynamic motion or point load is checked to be finite (besides t = 0).
const TIME_SAMPLES: usize = 101;

impl Validator<'_> {
    /// Three numbers (constants' expressions) of `key`, or `default`.
    fn triple(&self, key: &str, v: &Option<[Scalar; 3]>, default: [f64; 3]) -> Result<Vector3<f64>, CaseError> {
        match v {
            None => Ok(Vector3::from(default)),
            Some(items) => {
                let mut out = [0.0; 3];
                for (i, item) in items.iter().enumerate() {
                    out[i] = self.scalar(&format!("{key}[{i}]"), item)?;
                }
                Ok(Vector3::from(out))
            }
        }
    }

    /// Three expressions of `vars` and the constants, compiled; zero when absent.
    fn expr3(&self, key: &str, v: &Option<[Scalar; 3]>, vars: &[&str]) -> Result<VectorExpr, CaseError> {
        let Some(items) = v else { return Ok(VectorExpr::zero()) };
        let mut out: Vec<Expr> = Vec::with_capacity(3);
        for (i, item) in items.iter().enumerate() {
            out.push(self.expr(&format!("{key}[{i}]"), item, vars)?.0);
        }
        let [a, b, c] = <[Expr; 3]>::try_from(out).expect("three components");
        VectorExpr::new([a, b, c], &self.constants).map_err(|e| self.err(key, e.to_string()))
    }

    /// `key` finite at `s` for every time of `times`.
    fn finite_over(&self, key: &str, v: &VectorExpr, s: f64, times: &[f64]) -> Result<(), CaseError> {
        for &t in times {
            let x = v.at(s, t);
            if let Some(i) = (0..3).find(|&i| !x[i].is_finite()) {
                return Err(self.err(
                    &format!("{key}[{i}]"),
                    format!("`{}` is not finite ({}) at s = {s} m, t = {t} s", v.exprs[i], x[i]),
                ));
            }
        }
        Ok(())
    }

    /// The start frame of D20: rows d1, d2, d3 from `start_d3` and `start_d1` (Gram–Schmidt).
    fn start_frame(&self, raw: &RawCase) -> Result<Matrix3<f64>, CaseError> {
        let d3 = self.triple("rod.start_d3", &raw.rod.start_d3, [0.0, 0.0, 1.0])?;
        let d1 = self.triple("rod.start_d1", &raw.rod.start_d1, [1.0, 0.0, 0.0])?;
        let d3 = d3.try_normalize(0.0).ok_or_else(|| self.err("rod.start_d3", "must not be the zero vector"))?;
        let d1 = (d1 - d3 * d1.dot(&d3)).try_normalize(1e-9 * d1.norm().max(f64::MIN_POSITIVE)).ok_or_else(|| {
            self.err(
                "rod.start_d1",
                "must not be parallel to rod.start_d3 (d1 is the section's first axis, perpendicular to the tangent d3)",
            )
        })?;
        let d2 = d3.cross(&d1);
        Ok(Matrix3::from_rows(&[d1.transpose(), d2.transpose(), d3.transpose()]))
    }

    /// The general rod of a forward case, or `None` for the paper's.
    pub(super) fn general_rod(&self, raw: &RawCase, mesh: &Mesh) -> Result<Option<Rod>, CaseError> {
        let r = &raw.rod;
        let keys = [
            ("rod.start_position_m", r.start_position_m.is_some()),
            ("rod.start_d3", r.start_d3.is_some()),
            ("rod.start_d1", r.start_d1.is_some()),
            ("rod.intrinsic_curvature_per_m", r.intrinsic_curvature_per_m.is_some()),
            ("rod.chart_axis", r.chart_axis.is_some()),
            ("ends", raw.ends.start.is_some() || raw.ends.end.is_some()),
        ];
        let Some((first, _)) = keys.iter().find(|(_, given)| *given) else { return Ok(None) };
        let kind = raw.solver.analysis;
        if kind == RawAnalysis::Inverse {
            return Err(self.err(
                first,
                "an inverse case keeps the paper's straight rod clamped at s = 0: its reference is the data's (D20)",
            ));
        }
        let spec = RestSpec {
            start_position_m: self.triple("rod.start_position_m", &r.start_position_m, [0.0; 3])?,
            start_frame: self.start_frame(raw)?,
            curvature: self.expr3("rod.intrinsic_curvature_per_m", &r.intrinsic_curvature_per_m, &["s"])?,
        };
        for e in 0..=mesh.elements {
            self.finite_over("rod.intrinsic_curvature_per_m", &spec.curvature, mesh.node_s(e), &[0.0])?;
        }
        let chart = match &r.chart_axis {
            None => None,
            Some(_) => {
                let n = self.triple("rod.chart_axis", &r.chart_axis, [0.0; 3])?;
                let n =
                    n.try_normalize(0.0).ok_or_else(|| self.err("rod.chart_axis", "must not be the zero vector"))?;
                Some(Chart::with_axis(&n))
            }
        };
        let ends = Ends {
            start: self.end("ends.start", raw.ends.start.as_ref(), EndKind::Clamped, kind, mesh)?,
            end: self.end("ends.end", raw.ends.end.as_ref(), EndKind::Free, kind, mesh)?,
        };
        let rest = RestShape::new(mesh, &spec, chart);
        if kind == RawAnalysis::Static {
            self.rigid_modes_held(&ends, &rest, mesh)?;
            let clamped = [ends.start.kind, ends.end.kind].contains(&EndKind::Clamped);
            if raw.solver.method == RawMethod::FixedPoint && !clamped {
                // constant angles are a null vector of the fixed point's frozen operator (D22)
                return Err(self.err(
                    "solver.method",
                    "the fixed point needs a clamped end (its frozen operator leaves constant angles free): use method = \"newton\"",
                ));
            }
        }
        Ok(Some(Rod { rest, ends }))
    }

    /// One end (`table` = `ends.start` or `ends.end`), `default` when absent.
    fn end(
        &self,
        table: &str,
        e: Option<&RawEnd>,
        default: EndKind,
        kind: RawAnalysis,
        mesh: &Mesh,
    ) -> Result<End, CaseError> {
        let Some(e) = e else { return Ok(End { kind: default, motion: None }) };
        let end_kind = match (e.kind, e.twist) {
            (RawEndKind::Clamped, None) => EndKind::Clamped,
            (RawEndKind::Pinned, twist) => EndKind::Pinned { twist_held: twist == Some(RawTwist::Held) },
            (RawEndKind::Free, None) => EndKind::Free,
            (_, Some(_)) => {
                return Err(self.err(
                    &format!("{table}.twist"),
                    "only for kind = \"pinned\" (a clamp holds the twist, a free end does not)",
                ))
            }
        };
        if e.rotation_rad.is_some() && end_kind != EndKind::Clamped {
            return Err(self.err(
                &format!("{table}.rotation_rad"),
                "a prescribed rotation needs kind = \"clamped\" (a pinned end's rotation is free)",
            ));
        }
        if e.displacement_m.is_some() && end_kind == EndKind::Free {
            return Err(self.err(&format!("{table}.displacement_m"), "a free end cannot be moved: clamp or pin it"));
        }
        if e.displacement_m.is_none() && e.rotation_rad.is_none() {
            return Ok(End { kind: end_kind, motion: None });
        }
        let vars: &[&str] = if kind == RawAnalysis::Dynamic { &["t"] } else { &[] };
        let motion = Motion {
            displacement: self.expr3(&format!("{table}.displacement_m"), &e.displacement_m, vars)?,
            rotation: self.expr3(&format!("{table}.rotation_rad"), &e.rotation_rad, vars)?,
        };
        let times = self.check_times(kind);
        self.finite_over(&format!("{table}.displacement_m"), &motion.displacement, 0.0, &times)?;
        self.finite_over(&format!("{table}.rotation_rad"), &motion.rotation, 0.0, &times)?;
        if kind == RawAnalysis::Dynamic {
            let scale = mesh.length_m;
            let (u0, th0) = (motion.displacement.at(0.0, 0.0), motion.rotation.at(0.0, 0.0));
            if u0.amax() > 1e-12 * scale || th0.amax() > 1e-12 {
                return Err(self.err(
                    table,
                    format!(
                        "a moving end must start where the rod is at rest: displacement_m and rotation_rad must be 0 at t = 0 (they are {u0:?} m, {th0:?} rad)"
                    ),
                ));
            }
        }
        Ok(End { kind: end_kind, motion: Some(motion) })
    }

    /// Times at which expressions of t are checked: 0 and, in a dynamic case, samples up to T.
    fn check_times(&self, kind: RawAnalysis) -> Vec<f64> {
        match (kind, self.end_time_s) {
            (RawAnalysis::Dynamic, Some(end)) => {
                (0..TIME_SAMPLES).map(|k| end * k as f64 / (TIME_SAMPLES - 1) as f64).collect()
            }
            _ => vec![0.0],
        }
    }

    /// A static case must hold every rigid-body motion (D22).
    fn rigid_modes_held(&self, ends: &Ends, rest: &RestShape, mesh: &Mesh) -> Result<(), CaseError> {
        let (a, b) = (rest.end_reference(mesh, 0), rest.end_reference(mesh, mesh.nodes() - 1));
        let free = free_rigid_motions(ends, &a, &b, &rest.chart, mesh.length_m);
        if let Some(m) = free.first() {
            let hint = match (ends.start.kind, ends.end.kind) {
                (EndKind::Pinned { twist_held: false }, EndKind::Pinned { twist_held: false }) => {
                    "hold the twist at one end (ends.start.twist = \"held\")"
                }
                _ => "clamp an end (kind = \"clamped\"), pin both, or hold a pinned end's twist",
            };
            let all: Vec<String> = free.iter().map(|m| m.to_string()).collect();
            return Err(self.err(
                "ends",
                format!(
                    "a static problem needs every rigid-body motion held, but these ends leave {} free ({}{}): {hint}",
                    if free.len() == 1 { "one" } else { "several" },
                    m,
                    if all.len() > 1 { format!("; and {}", all[1..].join("; ")) } else { String::new() }
                ),
            ));
        }
        Ok(())
    }

    /// `solver.continuation` and `[arc_length]` of a static case (D25): the path's parameters,
    /// or `None` for load steps.
    pub(super) fn path(&self, raw: &RawCase) -> Result<Option<ArcLengthParams>, CaseError> {
        let s = &raw.solver;
        let arc = match (s.continuation, &raw.arc_length) {
            (None | Some(RawContinuation::LoadSteps), None) => return Ok(None),
            (None | Some(RawContinuation::LoadSteps), Some(_)) => {
                return Err(self.err("arc_length", "only used with solver.continuation = \"arc_length\""))
            }
            (Some(RawContinuation::ArcLength), None) => {
                return Err(self
                    .err("arc_length", "required by solver.continuation = \"arc_length\" (steps, initial_increment)"))
            }
            (Some(RawContinuation::ArcLength), Some(a)) => a,
        };
        if s.method != RawMethod::Newton {
            return Err(
                self.err("solver.method", "the arc-length continuation corrects by Newton: method = \"newton\"")
            );
        }
        if s.continuation_steps != 1 {
            return Err(self.err(
                "solver.continuation_steps",
                "not used by the arc-length continuation (its steps are arc_length.steps)",
            ));
        }
        let max = match &arc.max_load_factor {
            Some(v) => self.positive("arc_length.max_load_factor", v)?,
            None => 1.0,
        };
        let mut p = ArcLengthParams::new(self.count("arc_length.steps", arc.steps)?, arc.initial_increment, max);
        if !(arc.initial_increment > 0.0 && arc.initial_increment.is_finite()) {
            return Err(self.err("arc_length.initial_increment", format!("must be > 0, got {}", arc.initial_increment)));
        }
        p.min_increment = arc.min_increment.unwrap_or(p.min_increment);
        p.max_increment = arc.max_increment.unwrap_or(p.max_increment);
        if !(p.min_increment > 0.0 && p.min_increment <= p.initial_increment && p.initial_increment <= p.max_increment)
        {
            return Err(self.err(
                "arc_length.min_increment",
                format!(
                    "need 0 < min_increment ≤ initial_increment ≤ max_increment, got {} ≤ {} ≤ {}",
                    p.min_increment, p.initial_increment, p.max_increment
                ),
            ));
        }
        p.target_iterations = self.count("arc_length.target_iterations", arc.target_iterations.unwrap_or(5))?;
        Ok(Some(p))
    }

    /// `[[loads.point]]` (D23): each within the rod, components expressions of t in a dynamic
    /// case, finite.
    pub(super) fn point_loads(
        &self,
        raw: &[RawPointLoad],
        mesh: &Mesh,
        kind: RawAnalysis,
    ) -> Result<Vec<PointLoad>, CaseError> {
        let vars: &[&str] = if kind == RawAnalysis::Dynamic { &["t"] } else { &[] };
        let times = self.check_times(kind);
        let mut out = Vec::with_capacity(raw.len());
        for (k, p) in raw.iter().enumerate() {
            let key = format!("loads.point[{k}]");
            let s_m = self.scalar(&format!("{key}.s_m"), &p.s_m)?;
            if !(0.0..=mesh.length_m).contains(&s_m) {
                return Err(
                    self.err(&format!("{key}.s_m"), format!("{s_m} m lies outside the rod [0, {} m]", mesh.length_m))
                );
            }
            let frame = match p.frame.unwrap_or(RawFrame::Global) {
                RawFrame::Global => LoadFrame::Global,
                RawFrame::Local => LoadFrame::Local,
            };
            let force = self.expr3(&format!("{key}.force_n"), &p.force_n, vars)?;
            let torque = self.expr3(&format!("{key}.torque_nm"), &p.torque_nm, vars)?;
            self.finite_over(&format!("{key}.force_n"), &force, s_m, &times)?;
            self.finite_over(&format!("{key}.torque_nm"), &torque, s_m, &times)?;
            out.push(PointLoad { s_m, frame, force, torque });
        }
        Ok(out)
    }
}
