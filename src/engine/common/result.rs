//! What a run produces, the same for both engines: [`RunResult`] with its nodal state, the
//! histories and, for inverse runs, the data and controls.
use nalgebra::{DVector, Vector3};

use crate::model::chart::Chart;
use crate::model::element::{midpoint_curvatures, ElementRest};
use crate::model::material::RodProperties;
use crate::model::mesh::{Field, Mesh, QuadratureScheme};
use crate::model::resultants::{element_resultants, Resultants};
use crate::solve::dynamics::TipRecord;
use crate::solve::inverse::InverseRecord;
use crate::solve::statics::IterationRecord;

/// Which implementation produced a result.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Engine {
    Rust,
    Freefem,
}

impl std::fmt::Display for Engine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Engine::Rust => "rust",
            Engine::Freefem => "freefem",
        })
    }
}

/// Nodal fields of a state.
#[derive(Clone, Debug, PartialEq)]
pub struct NodalState {
    /// reference arc length [m]
    pub s: Vec<f64>,
    /// position [m]
    pub x: Vec<Vector3<f64>>,
    /// angles (α, β, γ) [rad] in `chart`
    pub alpha: Vec<Vector3<f64>>,
    /// the angles' chart (`crate::model::chart`; the paper's global chart unless a clip was
    /// rebased or a forward case has a chart of its own, D21)
    pub chart: Chart,
    /// the reference positions [m] of a rod with a reference configuration of its own (D20);
    /// `None`: the paper's straight rod `(0, 0, s)`
    pub reference_x: Option<Vec<Vector3<f64>>>,
}

impl NodalState {
    /// The nodal fields of a state `u` (forward layout) on `mesh`, in the global chart.
    pub fn from_vector(mesh: &Mesh, u: &DVector<f64>) -> Self {
        let dofs = mesh.dofs();
        NodalState {
            s: (0..mesh.nodes()).map(|i| mesh.node_s(i)).collect(),
            x: dofs.field(u, Field::X),
            alpha: dofs.field(u, Field::Alpha),
            chart: Chart::default(),
            reference_x: None,
        }
    }

    /// The nodal fields of a forward case's state `u` (chart coordinates, D21): positions in
    /// space, angles in the case's chart, the case's reference positions.
    pub fn of_forward(case: &crate::case::Case, u: &DVector<f64>) -> Self {
        let mut n = NodalState::from_vector(&case.mesh, u);
        if let Some(rod) = &case.rod.general {
            let chart = rod.rest.chart;
            if !chart.is_identity() {
                n.x.iter_mut().for_each(|x| *x = chart.to_space(x));
            }
            n.chart = chart;
            n.reference_x = Some(rod.rest.positions.clone());
        }
        n
    }
    /// [`NodalState::of_forward`] for a state in `chart`, which may differ from the case's
    /// (a dynamic run that changed its chart, D32): positions in space, angles in `chart`.
    pub fn of_forward_in(case: &crate::case::Case, u: &DVector<f64>, chart: Chart) -> Self {
        let mut n = NodalState::of_forward(case, u);
        let case_chart = case.rod.general.as_ref().map(|g| g.rest.chart).unwrap_or_default();
        if chart != case_chart {
            let from_case = chart.base.transpose() * case_chart.base;
            n.x.iter_mut().for_each(|x| *x = from_case * *x);
            n.chart = chart;
        }
        n
    }
    /// Element-midpoint curvature `κˡ = A(α) ∂s α` [1/m] with the midpoint arc length [m]
    /// (eq. 28, [`midpoint_curvatures`]).
    pub fn element_curvature(&self) -> Vec<(f64, Vector3<f64>)> {
        midpoint_curvatures(&self.s, &self.alpha)
    }
    /// The internal force `n` [N] and moment `m` [N m] of every element (eqs. 13, 15, 28),
    /// the means of `scheme`'s rules ([`crate::model::resultants::resultants`]), their global
    /// components in space coordinates (the state is solved in its chart, R3: the resultants
    /// are rotated back), their local ones on the directors.
    /// `rest`: the reference strains per element of a rod with a reference of its own (D20).
    pub fn resultants(
        &self,
        props: &RodProperties,
        scheme: QuadratureScheme,
        rest: Option<&[ElementRest]>,
    ) -> Vec<Resultants> {
        if self.chart.is_identity() {
            return element_resultants(props, scheme, (&self.s, &self.x, &self.alpha), rest);
        }
        let x: Vec<Vector3<f64>> = self.x.iter().map(|v| self.chart.to_chart(v)).collect();
        let mut r = element_resultants(props, scheme, (&self.s, &x, &self.alpha), rest);
        for e in &mut r {
            e.n = self.chart.to_space(&e.n);
            e.m = self.chart.to_space(&e.m);
        }
        r
    }
    /// Directors `d1, d2, d3` per node (rows of Q, eq. 2).
    pub fn directors(&self) -> Vec<[Vector3<f64>; 3]> {
        self.alpha
            .iter()
            .map(|a| {
                let q = self.chart.rotation(a);
                [q.row(0).transpose(), q.row(1).transpose(), q.row(2).transpose()]
            })
            .collect()
    }
    /// Displacement from the reference configuration [m]: the rod's (D20), or `(0, 0, s)`.
    pub fn displacement(&self) -> Vec<Vector3<f64>> {
        match &self.reference_x {
            Some(x0) => self.x.iter().zip(x0).map(|(x, x0)| x - x0).collect(),
            None => self.x.iter().zip(&self.s).map(|(x, s)| x - Vector3::new(0.0, 0.0, *s)).collect(),
        }
    }
}

/// Solver statistics.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SolverStats {
    /// static: iterations of the nonlinear solver; dynamic: total Newton iterations
    pub iterations: usize,
    /// static: last relative change (fixed point) or increment (Newton)
    pub last_change: Option<f64>,
    /// static: ‖R‖∞/‖F‖∞ at the solution
    pub residual: Option<f64>,
    /// dynamic: largest Newton iteration count of a step
    pub max_newton_iterations: Option<usize>,
    /// the residual certificate of the result (`solve::certificate`, `docs/certificate.md`):
    /// static and inverse at the returned state, dynamic the largest of its steps
    pub certificate: Option<f64>,
    /// wall-clock time of the solve (engine-internal) [s]
    pub wall_time_s: f64,
}

/// Result of running a case in one engine.
#[derive(Clone, Debug)]
pub struct RunResult {
    pub engine: Engine,
    /// final state; for an inverse case the recovered `(x, α)`
    pub nodes: NodalState,
    /// static iteration history
    pub history: Vec<IterationRecord>,
    /// dynamic tip history (including t = 0)
    pub tip: Vec<TipRecord>,
    pub stats: SolverStats,
    /// inverse cases: data, adjoint (controls) and per-iteration history
    pub inverse: Option<InverseOutput>,
    /// a static case followed by arc length (D25): its path
    pub path: Option<PathOutput>,
    /// a static case: the stability of its state and its buckling modes (D27)
    pub stability: Option<StabilityOutput>,
}

/// The stability of a static result, the case's linearised buckling (D27) and the rod's
/// natural frequencies about its rest state (D28), the same for both engines.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StabilityOutput {
    /// `min Re ω²` of the rod linearised about the result [1/s²] (≤ 0 unstable; unit inertias
    /// where the case has none: then its sign only); `None` above the dense limit
    /// (`solve::stability::DENSE_LIMIT`) and in the FreeFEM engine (which has no mass-matrix
    /// eigen-analysis of a static state)
    pub smallest_eigenvalue_per_s2: Option<f64>,
    /// every load is a dead force, so that the sign of `smallest_eigenvalue_per_s2` says stable or not
    /// (`solve::stability::Stability::conservative`); follower loads: `false`
    pub conservative: bool,
    /// the lowest critical load factors about the reference (`solver.buckling_modes`), ascending
    pub modes: Vec<BucklingRecord>,
    /// the lowest natural frequencies ω [rad/s] of the rod about its rest state
    /// (`solver.vibration_modes`, D28), ascending, each multiple one repeated
    pub omegas_rad_per_s: Vec<f64>,
}

/// One buckling mode: its critical load factor and its shape at the nodes.
#[derive(Clone, Debug, PartialEq)]
pub struct BucklingRecord {
    /// critical load factor λ_cr [-]
    pub load_factor: f64,
    /// the mode's displacement per node in space, scaled so that `‖φ‖_w = 1` (D27) [m per m of
    /// rod length]
    pub displacement: Vec<Vector3<f64>>,
}

/// The path of an arc-length continuation (D25), the same for both engines.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PathOutput {
    /// arc lengths [m] whose displacements each point records: the point loads' and s = L
    pub record_s_m: Vec<f64>,
    pub points: Vec<PathRecord>,
    /// limit and bifurcation points (`solve::arclength::Critical`)
    pub critical: Vec<crate::solve::arclength::Critical>,
    /// whether λ reached the case's `max_load_factor`
    pub reached_end: bool,
}

/// One converged point of a path.
#[derive(Clone, Debug, PartialEq)]
pub struct PathRecord {
    pub step: usize,
    /// load factor λ [-]
    pub load_factor: f64,
    /// arc length travelled in the scaled norm of D25 [-]
    pub arc_length: f64,
    /// sign of the tangent's determinant relative to the reference's
    pub determinant_sign: i8,
    pub iterations: usize,
    pub certificate: f64,
    /// displacement [m] (space components) at each of `PathOutput::record_s_m`
    pub displacements: Vec<Vector3<f64>>,
}

/// What an inverse run adds to its [`RunResult`].
#[derive(Clone, Debug)]
pub struct InverseOutput {
    /// the data read from `data.csv` (x_g and the forward angles α_f, I7)
    pub data: NodalState,
    /// whether `data.alpha` holds true angles (synthetic data) or zeros (a recorded clip,
    /// whose frame is unknown): curvature errors are only reported in the first case
    pub angles_known: bool,
    /// adjoint x̂ per node; the force control is f = x̂/λf [N/m] (eq. 54)
    pub xhat: Vec<Vector3<f64>>,
    /// adjoint α̂ per node; the torque control is l = α̂/λl [N] (eq. 54)
    pub ahat: Vec<Vector3<f64>>,
    /// one record per iteration (relative change, fit measures, objective terms of (41))
    pub history: Vec<InverseRecord>,
    /// per iteration: curvature error against the data's `[all elements, inner]`
    /// (`metrics::inverse_metrics`); empty when the engine does not report it (FreeFEM)
    pub kappa_err: Vec<[f64; 2]>,
    pub lambda_f: f64,
    pub lambda_l: f64,
}

impl InverseOutput {
    /// Force control f = x̂/λf per node [N/m].
    pub fn force(&self) -> Vec<Vector3<f64>> {
        self.xhat.iter().map(|v| v / self.lambda_f).collect()
    }
    /// Torque control l = α̂/λl per node [N·m/m].
    pub fn torque(&self) -> Vec<Vector3<f64>> {
        self.ahat.iter().map(|v| v / self.lambda_l).collect()
    }
}
