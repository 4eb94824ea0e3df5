//! The parameters of a static case's path following (D25), apart from the method
//! (`solve::arclength`) so that the static solver's parameters can name them.

/// Parameters of the arc-length continuation (`[arc_length]` of a case, D25).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArcLengthParams {
    /// most path steps
    pub steps: usize,
    /// arc length of the first step, in the scaled norm `‖·‖_w` of the module doc [-]
    pub initial_increment: f64,
    /// bounds of the adapted arc length [-]
    pub min_increment: f64,
    pub max_increment: f64,
    /// the path stops when λ reaches this (the case's loads are λ = 1)
    pub max_load_factor: f64,
    /// Newton iterations a step aims at (the arc length adapts to it)
    pub target_iterations: usize,
}

impl ArcLengthParams {
    /// Defaults for a path to λ = `max_load_factor` in about `steps`/2 steps.
    pub fn new(steps: usize, initial_increment: f64, max_load_factor: f64) -> Self {
        ArcLengthParams {
            steps,
            initial_increment,
            min_increment: initial_increment * 1e-4,
            max_increment: initial_increment * 10.0,
            max_load_factor,
            target_iterations: 5,
        }
    }
}
