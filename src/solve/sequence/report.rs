//! The report of one frame of a clip ([`FrameReport`]), grouped by what each number says: how
//! the solve ended, how the solution meets the data, how well-posed the frame is.
//!
//! The groups are `#[serde(flatten)]`ed: a report is one flat JSON object (the resume journal,
//! `crate::output::journal`), its keys in the order of the fields here, as before the grouping.
use nalgebra::Vector3;

use crate::recorded::fit::FrameFit;
use crate::solve::inverse::{InverseRecord, ObjectiveTerms};

/// Per-frame report.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
pub struct FrameReport {
    pub frame: usize,
    /// how the frame's solve ended
    #[serde(flatten)]
    pub convergence: FrameConvergence,
    /// how the solution meets the frame's data
    #[serde(flatten)]
    pub misfit: DataMisfit,
    /// how close the frame comes to the angle chart's singularity, and how far its data
    /// stretches
    #[serde(flatten)]
    pub conditioning: FrameConditioning,
    /// the frame failed from the previous frame's solution and was solved from the data guess
    pub restarted: bool,
    /// singular axis `n = Bᵀ e2` of the frame's chart (e2 for the global chart)
    pub chart_axis: Vector3<f64>,
    /// wall-clock time of the frame's solve [s]
    pub wall_time_s: f64,
    /// the residual certificate of the frame's solution (`inverse::kkt::certificate`)
    pub certificate: f64,
    /// how well the frame follows its data, and whether it is over the gate (`solve::fit`)
    pub fit: FrameFit,
    /// nodes of the frame that were tracked (`clip::missing`; all of them without missing data)
    #[serde(default)]
    pub nodes_tracked: usize,
}

/// How the solve of a frame ended: its last iteration.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
pub struct FrameConvergence {
    /// iterations of the frame's solve (the number of its last iteration)
    pub iterations: usize,
    /// relative change of (x, α) of the last iteration (D5) [–]
    pub last_change: f64,
}

impl FrameConvergence {
    /// The end of a solve whose last iteration is `last`.
    pub fn at(last: &InverseRecord) -> Self {
        FrameConvergence { iterations: last.iteration, last_change: last.rel_change }
    }
}

/// How the solution of a frame meets its data, at the last iteration.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
pub struct DataMisfit {
    /// relative position error ‖x − x_g‖/‖x_g‖ (L² norms) [–]
    pub x_err_rel: f64,
    /// ‖∂s x − d3‖ (L² norm) [m^½]
    pub tangent_misfit: f64,
    /// the terms of the objective (41)
    pub objective: ObjectiveTerms,
}

impl DataMisfit {
    /// The misfit of a solve whose last iteration is `last`.
    pub fn at(last: &InverseRecord) -> Self {
        DataMisfit { x_err_rel: last.x_err_rel, tangent_misfit: last.tangent_misfit, objective: last.objective }
    }
}

/// How well-posed a frame is: the angle chart's distance from its singularity (eq. 1,
/// det A = −cos β) and the stretch of the frame's data.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
pub struct FrameConditioning {
    /// smallest |cos β| over the nodes [–]
    pub min_cos_beta: f64,
    /// the node of the smallest |cos β|
    pub min_cos_beta_node: usize,
    /// max over elements of |j − 1|, j = |Δx_g|/h the data's stretch (Remark 9) [–]
    pub max_stretch_deviation: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The groups are flattened: a report is the flat JSON object of the journal, its keys in
    /// the order they had before the grouping, and it reads back as it was written.
    #[test]
    fn a_report_is_one_flat_json_object_in_the_journal_order() {
        let report = FrameReport {
            frame: 3,
            convergence: FrameConvergence { iterations: 4, last_change: 1.5e-9 },
            misfit: DataMisfit { x_err_rel: 2e-3, tangent_misfit: 0.25, objective: ObjectiveTerms::default() },
            conditioning: FrameConditioning { min_cos_beta: 0.5, min_cos_beta_node: 7, max_stretch_deviation: 0.01 },
            restarted: true,
            chart_axis: Vector3::new(0.0, 1.0, 0.0),
            wall_time_s: 0.125,
            certificate: 3e-12,
            fit: FrameFit::default(),
            nodes_tracked: 20,
        };
        let json = serde_json::to_string(&report).expect("serialises");
        let keys = [
            "frame",
            "iterations",
            "last_change",
            "x_err_rel",
            "tangent_misfit",
            "objective",
            "min_cos_beta",
            "min_cos_beta_node",
            "max_stretch_deviation",
            "restarted",
            "chart_axis",
            "wall_time_s",
            "certificate",
            "fit",
            "nodes_tracked",
        ];
        let at: Vec<usize> =
            keys.iter().map(|k| json.find(&format!("\"{k}\":")).unwrap_or_else(|| panic!("{k} in {json}"))).collect();
        assert!(at.windows(2).all(|w| w[0] < w[1]), "{json}");
        assert!(json.starts_with("{\"frame\":3,\"iterations\":4,"), "{json}");
        let back: FrameReport = serde_json::from_str(&json).expect("reads back");
        assert_eq!(serde_json::to_string(&back).expect("serialises"), json);
        let old = json.replace(",\"nodes_tracked\":20", "");
        let back: FrameReport = serde_json::from_str(&old).expect("reads a report without nodes_tracked");
        assert_eq!(back.nodes_tracked, 0);
    }
}
