//! External loads of eq. (40): distributed force `f(s,t)` [N/m] and torque `l(s,t)` [N m/m]
//! (global frame), dead end loads at `s = L`: force [N] and torque [N m], and point loads at any
//! `s` (D23). Components are expressions compiled once; evaluation does no string lookups.
use std::collections::BTreeMap;

use nalgebra::Vector3;

use crate::expr::{Compiled, Expr, ExprError};

/// Slot layout of compiled load expressions: `s`, `t`, then the constants in name order.
const FIXED: [&str; 2] = ["s", "t"];

/// Frame of the distributed load components (end loads are always global dead loads).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LoadFrame {
    /// components along e1, e2, e3
    Global,
    /// components along d1, d2, d3 (follower load, `fᵍ = Qᵀ fˡ`, eqs. 4, 64, 65)
    Local,
}

/// Three components, each an expression of the reference arc length `s` [m], the time `t` [s]
/// and the case's constants, compiled once (a point load's force, an end's motion, the
/// intrinsic curvature of D20).
#[derive(Clone, Debug)]
pub struct VectorExpr {
    /// the source expressions, kept for the FreeFEM include file
    pub exprs: [Expr; 3],
    compiled: [Compiled; 3],
    /// slot values: s, t, constants...
    slots: Vec<f64>,
}

impl VectorExpr {
    /// Compile the three components against `s`, `t` and the constants.
    pub fn new(exprs: [Expr; 3], constants: &BTreeMap<String, f64>) -> Result<Self, ExprError> {
        let names: Vec<&str> = FIXED.iter().copied().chain(constants.keys().map(|k| k.as_str())).collect();
        let compiled = [exprs[0].compile(&names)?, exprs[1].compile(&names)?, exprs[2].compile(&names)?];
        let slots = [0.0, 0.0].into_iter().chain(constants.values().copied()).collect();
        Ok(VectorExpr { exprs, compiled, slots })
    }

    /// The zero vector (three literal zeros).
    pub fn zero() -> Self {
        let z = || Expr::parse("0").expect("the literal 0 parses");
        VectorExpr::new([z(), z(), z()], &BTreeMap::new()).expect("the literal 0 compiles")
    }

    /// The value at `(s, t)`.
    pub fn at(&self, s: f64, t: f64) -> Vector3<f64> {
        let mut slots = self.slots.clone();
        slots[0] = s;
        slots[1] = t;
        Vector3::new(self.compiled[0].eval(&slots), self.compiled[1].eval(&slots), self.compiled[2].eval(&slots))
    }

    /// True when every component is the literal zero.
    pub fn is_zero(&self) -> bool {
        self.compiled.iter().all(|c| c.as_constant() == Some(0.0))
    }
}

/// A force [N] and a torque [N m] at one arc length `s_m` [m] (D23): dead (global components)
/// or following the section (components along d1, d2, d3, `Qᵀ(α_h(s_m))` applied).
#[derive(Clone, Debug)]
pub struct PointLoad {
    /// where the load acts [m], in `[0, L]`
    pub s_m: f64,
    pub frame: LoadFrame,
    /// force [N], expressions of `t` and the constants
    pub force: VectorExpr,
    /// torque [N m]
    pub torque: VectorExpr,
}

/// Parsed and compiled load expressions of a case.
#[derive(Clone, Debug)]
pub struct Loads {
    /// frame of the distributed components
    pub frame: LoadFrame,
    /// Source expressions, kept for the FreeFEM include file: force, torque, end force, end torque.
    pub exprs: [[Expr; 3]; 4],
    compiled: Vec<Compiled>,
    /// slot values: s, t, constants...
    slots: Vec<f64>,
    /// point loads at any s (`[[loads.point]]`, D23), besides the end loads
    pub point: Vec<PointLoad>,
}

impl Loads {
    /// Every load a dead force (global frame, no applied moment): conservative (D27). A
    /// follower load is not, nor is a moment: one of fixed axis (an axial vector) is not the
    /// gradient of a potential for finite rotations in 3D (Ziegler, Principles of Structural
    /// Stability, 1977, §2.6).
    pub fn conservative(&self) -> bool {
        // compiled in the order of `exprs`: force, torque, end force, end torque, 3 each
        let zero = |group: usize| self.compiled[3 * group..3 * group + 3].iter().all(|c| c.as_constant() == Some(0.0));
        self.frame == LoadFrame::Global
            && zero(1)
            && zero(3)
            && self.point.iter().all(|p| p.frame == LoadFrame::Global && p.torque.is_zero())
    }

    pub fn new(
        frame: LoadFrame,
        force: [Expr; 3],
        torque: [Expr; 3],
        end_force: [Expr; 3],
        end_torque: [Expr; 3],
        constants: &BTreeMap<String, f64>,
    ) -> Result<Self, ExprError> {
        let names: Vec<&str> = FIXED.iter().copied().chain(constants.keys().map(|k| k.as_str())).collect();
        let exprs = [force, torque, end_force, end_torque];
        let mut compiled = Vec::with_capacity(12);
        for group in &exprs {
            for e in group {
                compiled.push(e.compile(&names)?);
            }
        }
        let slots = [0.0, 0.0].into_iter().chain(constants.values().copied()).collect();
        Ok(Loads { frame, exprs, compiled, slots, point: Vec::new() })
    }

    /// The same loads with point loads (D23).
    pub fn with_point_loads(mut self, point: Vec<PointLoad>) -> Self {
        self.point = point;
        self
    }

    fn eval3(&self, group: usize, s: f64, t: f64) -> Vector3<f64> {
        let mut slots = self.slots.clone();
        slots[0] = s;
        slots[1] = t;
        Vector3::new(
            self.compiled[3 * group].eval(&slots),
            self.compiled[3 * group + 1].eval(&slots),
            self.compiled[3 * group + 2].eval(&slots),
        )
    }

    /// Distributed force [N/m] and torque [N m/m] at `(s, t)`.
    pub fn distributed(&self, s: f64, t: f64) -> (Vector3<f64>, Vector3<f64>) {
        (self.eval3(0, s, t), self.eval3(1, s, t))
    }

    /// End force [N] and end torque [N m] at time `t`.
    pub fn end(&self, t: f64) -> (Vector3<f64>, Vector3<f64>) {
        (self.eval3(2, 0.0, t), self.eval3(3, 0.0, t))
    }

    /// Case-file keys of the load groups, in the order of [`Loads::exprs`].
    pub const KEYS: [&'static str; 4] =
        ["loads.force_n_per_m", "loads.torque_nm_per_m", "loads.end_force_n", "loads.end_torque_nm"];

    /// The load component of largest magnitude over the arc lengths `s` [m] at time `t` [s]:
    /// its key and component (`loads.end_force_n[1]`), expression and value.
    pub fn largest(&self, s: &[f64], t: f64) -> Option<(String, String, f64)> {
        let mut best: Option<(String, String, f64)> = None;
        for (g, key) in Self::KEYS.iter().enumerate() {
            let at: Vec<f64> = if g < 2 { s.to_vec() } else { vec![0.0] };
            for c in 0..3 {
                for &si in &at {
                    let v = self.eval3(g, si, t)[c];
                    if best.as_ref().is_none_or(|b| v.abs() > b.2.abs() || (v.is_nan() && !b.2.is_nan())) {
                        best = Some((format!("{key}[{c}]"), self.exprs[g][c].to_string(), v));
                    }
                }
            }
        }
        best
    }

    /// True when all distributed components are the literal zero (skip their quadrature).
    pub fn has_distributed(&self) -> bool {
        let zero = |e: &Expr| e.variables().is_empty() && e.eval(&|_| None).map(|v| v == 0.0).unwrap_or(false);
        self.exprs[0].iter().chain(self.exprs[1].iter()).any(|e| !zero(e))
    }
}
