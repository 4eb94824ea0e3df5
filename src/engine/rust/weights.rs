//! `[inverse] weights = "auto"`: the tracking weight λg of eq. (41) chosen from the recording
//! (`docs/noise.md`, N2).
//!
//! The recording's noise level is `σ̂ = median over frames of fit::noise_level_in(frame)` (per
//! coordinate [m]). λg is then set by Morozov's discrepancy principle: the fit's RMS distance
//! to the data per coordinate on the clip's first [`CALIBRATION_FRAMES`] frames,
//!
//! ```text
//!   r(λg) = ( (1/3K) Σ_frames (1/L) ∫ |x − x_g|² )^½ ,
//! ```
//!
//! equals `σ̂`. `r` falls as λg grows (the other weights fixed); λg is searched in `ln λg`
//! from [`START_RATIO`]`·λg_max` (the case's `lambda_g` is the largest allowed): down by 10
//! while the fit follows the noise, up by 100 while it is smoother, then by the Illinois
//! variant of regula falsi on `ln r − ln σ̂`, until `r` is within [`MATCH`] of `σ̂` (while
//! bracketing, only from the smooth side: `σ̂ ≤ r < MATCH σ̂`, Morozov's smoothest fit within
//! the noise). Where `r(λg_max) ≥ σ̂` (the model cannot follow the data more closely than the
//! noise even at the cap, e.g. clean data) λg is the cap. Each calibration solve starts frame 0
//! from the previous solve's frame 0 (continuation in λg). A calibration solve that fails after
//! the first success counts as a fit that follows the noise (`r < σ̂`); where the start fails,
//! the search starts again at the smooth end ([`SMOOTH_START_RATIO`]), and one that fails there
//! too (too little tracking to hold frame 0: λg = 1e3 on a 3 µm recording of 33 nodes) moves
//! that start up by 10, and the search then never goes below it.
use nalgebra::{DVector, Vector3};

use crate::case::{Analysis, Case, WeightsRule};
pub use crate::engine::common::clip_summary::ChosenWeights;
use crate::recorded::noise::recording_noise_in;
use crate::solve::sequence::{solve_sequence, FirstStart, SequenceParams};

/// Frames of the clip's start on which `r(λg)` is measured (a recording streamed from its file
/// keeps these for the search).
pub use crate::engine::input::recording_stream::CALIBRATION_FRAMES;
/// `r` within this factor of `σ̂` ends the search.
pub const MATCH: f64 = 1.1;
/// Largest number of calibration solves.
pub const MAX_SOLVES: usize = 12;
/// The search's floor: `λg_max · MIN_RATIO`.
pub const MIN_RATIO: f64 = 1e-12;
/// The search's first λg: `λg_max · START_RATIO` (1e6 for the paper's 1e9), the middle of the
/// λg chosen on the recordings we measured (1e4–5e6 on noisy ones, 1e7–1e9 on clean ones):
/// its frame 0 starts from the data guess, which lies close to a fit of that weight.
pub const START_RATIO: f64 = 1e-3;
/// The search's start where the first one fails: `λg_max · SMOOTH_START_RATIO` (1e3 for the
/// paper's 1e9), a fit far smoother than the noise of any recording we measured, which every
/// frame 0 solves from the data guess (at a higher cost: 13–44 ms of the 30–60 ms of a search
/// on 3 frames of 33 nodes started there).
pub const SMOOTH_START_RATIO: f64 = 1e-6;

/// The stabilisation ε of the λd term's quadrature (I11) that automatic weights use at least
/// (`docs/noise.md` N10, N13).
pub const AUTO_STABILISATION: f64 = 0.1;

/// The stabilisation ε of the λd term's quadrature (I11) for a recording reconstructed with
/// automatic weights, when the case asks for `case_eps`: `max(case_eps, 0.1)` (`docs/noise.md`
/// N10). The one-point rule leaves a zig-zag mode of the angles that only ε·λd holds (I13).
/// Noise excites it, and Newton then crawls along it with damped steps (3 µm on 33 nodes: 10.5
/// iterations per frame at ε = 1e-3, 5.4 at 0.1); so do smooth changes of shape that stretch
/// the centreline from frame to frame, which the noise estimate does not see (N13: at ε = 1e-3
/// the frame's curvature was 1.4–2× the spline's error, at 0.1 at the spline's level). An
/// earlier rule, `max(case_eps, min(σ̂/h, 0.1))`, left clean recordings at the case's ε.
pub fn auto_stabilisation(case_eps: f64) -> f64 {
    case_eps.max(AUTO_STABILISATION)
}

/// The case with λg chosen for `frames` when its weights are `"auto"`, the choice, and frame 0's
/// solution at that λg in its chart (the clip's frame 0 starts there), else `None`.
pub fn choose_weights(case: &Case, frames: &[Vec<Vector3<f64>>]) -> Option<Auto> {
    let plane = case.sequence_params()?.plane;
    let calib = &frames[..CALIBRATION_FRAMES.min(frames.len())];
    choose_weights_on(case, calib, || recording_noise_in(frames, plane.as_ref()))
}

/// [`choose_weights`] of a clip known by its first [`CALIBRATION_FRAMES`] frames `calib` (or all
/// of a shorter clip) and, where the case states no noise level, the recording's
/// ([`recording_noise_in`], asked for only then): what a clip streamed from its file gives.
pub fn choose_weights_on(
    case: &Case,
    calib: &[Vec<Vector3<f64>>],
    recording_noise_m: impl FnOnce() -> f64,
) -> Option<Auto> {
    let rule = case.inverse().map(|s| s.weights_rule)?;
    let sp = case.sequence_params()?;
    if rule != WeightsRule::Auto || calib.is_empty() {
        return None;
    }
    // the noise the case states, else the recording's (in its plane, for planar data)
    let sigma = sp.gate.noise_m.unwrap_or_else(recording_noise_m);
    let cap = sp.inverse.weights.lambda_g;
    let mut sp = sp;
    let eps = auto_stabilisation(sp.inverse.stabilisation);
    sp.inverse.stabilisation = eps;
    let calib = &calib[..CALIBRATION_FRAMES.min(calib.len())];
    let mut search = Search { case, sp, calib, states: Vec::new(), solves: 0 };
    let (lambda_g, r) = search_lambda_g(&mut search, sigma, cap);
    let chosen = ChosenWeights {
        noise_m: sigma,
        lambda_g,
        lambda_g_max: cap,
        fit_residual_m: r,
        calibration_frames: calib.len(),
        solves: search.solves,
        stabilisation: eps,
    };
    let mut out = case.clone();
    if let Analysis::Inverse(s) = &mut out.analysis {
        s.params.weights.lambda_g = lambda_g;
        s.params.stabilisation = eps;
    }
    let start = search.states.into_iter().find(|(g, _)| *g == lambda_g).map(|(_, u)| u);
    Some(Auto { case: out, chosen, start })
}

/// What [`choose_weights`] gives.
pub struct Auto {
    /// the case with the chosen λg
    pub case: Case,
    pub chosen: ChosenWeights,
    /// frame 0's solution at the chosen λg, in frame 0's chart
    pub start: Option<DVector<f64>>,
}

/// The state of the λg search.
struct Search<'a> {
    case: &'a Case,
    sp: SequenceParams,
    calib: &'a [Vec<Vector3<f64>>],
    /// every successful solve's λg and frame 0's state; the last starts the next solve
    /// (continuation)
    states: Vec<(f64, DVector<f64>)>,
    solves: usize,
}

impl Search<'_> {
    /// `r(λg)` [m], 0 when the solve fails. The solve continues from the last successful
    /// one's frame 0; where that fails, it is solved once more from the data guess (a
    /// continuation start from another λg can lead Newton astray on noisy frames, 10 µm on 128
    /// nodes, where the guess does not). After a requested stop no solve runs (the clip's own
    /// solve then stops at its first frame) and the search ends.
    fn residual(&mut self, lambda_g: f64) -> f64 {
        if crate::interrupt::requested() {
            self.solves = MAX_SOLVES;
            return 0.0;
        }
        self.solves += 1;
        let last = self.states.last().map(|(_, u)| u.clone());
        match self.attempt(lambda_g, last.as_ref()) {
            Some(r) => r,
            None if last.is_some() => self.attempt(lambda_g, None).unwrap_or(0.0),
            None => 0.0,
        }
    }

    /// One calibration solve at `lambda_g` from `u0` (`None`: the data guess): `r(λg)`, or
    /// `None` when it fails; a success's frame 0 is kept for the next.
    fn attempt(&mut self, lambda_g: f64, u0: Option<&DVector<f64>>) -> Option<f64> {
        let mut sp = self.sp;
        sp.inverse.weights.lambda_g = lambda_g;
        let problem = self.case.problem();
        let length = self.case.mesh.length_m;
        let mut first: Option<DVector<f64>> = None;
        let solved = solve_sequence(
            &problem,
            &sp,
            self.calib,
            u0.map_or(FirstStart::DataGuess, FirstStart::Near),
            |_, _| {},
            |rep, sol| {
                if rep.frame == sp.frame_offset {
                    first = Some(sol.state.clone());
                }
                Ok(())
            },
        );
        let reports = solved.ok().filter(|r| !r.is_empty())?;
        if let Some(u) = first {
            self.states.push((lambda_g, u));
        }
        let mean_p2 = reports.iter().map(|r| r.fit.position.powi(2)).sum::<f64>() / reports.len() as f64;
        Some(mean_p2.sqrt() * length / 3f64.sqrt())
    }
}

/// `r(λg)` [m] of the λg search (0 when the solve fails) and the solves spent so far.
trait Residual {
    fn residual(&mut self, lambda_g: f64) -> f64;
    fn solves(&self) -> usize;
}

impl Residual for Search<'_> {
    fn residual(&mut self, lambda_g: f64) -> f64 {
        Search::residual(self, lambda_g)
    }
    fn solves(&self) -> usize {
        self.solves
    }
}

/// `(λg, r(λg))` by the module doc's rule, `r` measured by `search`.
fn search_lambda_g(search: &mut impl Residual, sigma: f64, cap: f64) -> (f64, f64) {
    let f = |r: f64| if r > 0.0 { (r / sigma).ln() } else { f64::NEG_INFINITY };
    let floor = cap * MIN_RATIO;
    if sigma.is_nan() || sigma <= 0.0 {
        return (cap, search.residual(cap));
    }
    // the smoothest fit within MATCH of the noise is Morozov's choice: a λg whose fit is
    // smoother than the noise (r ≥ σ̂) and within MATCH of it ends the search
    let smooth_enough = |r: f64| f(r) >= 0.0 && f(r) < MATCH.ln();
    // the start: the middle of the measured choices; where it fails, the smooth end, and a
    // failure there too (too little tracking to hold the frame): up by 10
    let mut lo = cap * START_RATIO;
    let mut r_lo = search.residual(lo);
    if r_lo == 0.0 {
        lo = cap * SMOOTH_START_RATIO;
        r_lo = search.residual(lo);
    }
    let raised = r_lo == 0.0;
    while r_lo == 0.0 && lo < cap && search.solves() < MAX_SOLVES {
        lo = (lo * 10.0).min(cap);
        r_lo = search.residual(lo);
    }
    // bracket r(lo) ≥ σ̂ > r(hi), each solve continuing from the last: down by 10 while the
    // fit follows the noise (only where the start itself solved: below a start that failed
    // lie only failures), the last such λg the bracket's upper end ...
    let mut above: Option<(f64, f64)> = None;
    while !raised && r_lo > 0.0 && f(r_lo) < 0.0 && lo > floor && search.solves() < MAX_SOLVES {
        above = Some((lo, r_lo));
        lo = (lo * 0.1).max(floor);
        r_lo = search.residual(lo);
    }
    if f(r_lo) < 0.0 {
        // at the floor or out of solves; a failed solve gives way to the last success
        return above.filter(|_| r_lo == 0.0).unwrap_or((lo, r_lo));
    }
    // ... else up by 100 while the fit is smoother than the noise
    let (hi, r_hi) = match above {
        Some(p) => p,
        None => {
            let (mut hi, mut r_hi) = (lo, r_lo);
            // a failed solve below the cap says nothing of r: the search steps over it (a
            // frame can stall in a band of λg where its twist changes branch, with a fit
            // smoother than the noise on both sides: `docs/noise.md` N13); only where every
            // solve above fails is the first failure the bracket's upper end
            let mut first_failure = None;
            while f(r_hi) >= 0.0 || (r_hi == 0.0 && hi < cap) {
                if search.solves() >= MAX_SOLVES {
                    break;
                }
                if r_hi > 0.0 {
                    if smooth_enough(r_hi) || hi >= cap {
                        return (hi, r_hi);
                    }
                    (lo, r_lo) = (hi, r_hi);
                } else {
                    first_failure = first_failure.or(Some(hi));
                }
                hi = (hi * 1e2).min(cap);
                r_hi = search.residual(hi);
            }
            match (r_hi > 0.0, first_failure) {
                (false, Some(first)) => (first, 0.0),
                _ => (hi, r_hi),
            }
        }
    };
    if smooth_enough(r_lo) {
        return (lo, r_lo);
    }
    regula_falsi(search, sigma, (lo, r_lo), (hi, r_hi))
}

/// Illinois regula falsi in ln λg on ln r − ln σ̂ (decreasing) between the bracket's ends
/// `(λg, r)` `lo` (r ≥ σ̂) and `hi` (r < σ̂): the first λg within MATCH of the noise, or the
/// closest one when the solves run out.
fn regula_falsi(search: &mut impl Residual, sigma: f64, (lo, r_lo): (f64, f64), (hi, r_hi): (f64, f64)) -> (f64, f64) {
    let f = |r: f64| if r > 0.0 { (r / sigma).ln() } else { f64::NEG_INFINITY };
    let (mut a, mut fa, mut b, mut fb) = (lo.ln(), f(r_lo), hi.ln(), f(r_hi));
    let mut best = (lo, r_lo);
    let mut side = 0;
    while search.solves() < MAX_SOLVES {
        let c = if fb.is_finite() { b - fb * (b - a) / (fb - fa) } else { 0.5 * (a + b) };
        let r = search.residual(c.exp());
        let fc = f(r);
        if fc.abs() < f(best.1).abs() {
            best = (c.exp(), r);
        }
        if fc.abs() < MATCH.ln() {
            return (c.exp(), r);
        }
        if fc > 0.0 {
            (a, fa) = (c, fc);
            if side == 1 {
                fb *= 0.5;
            }
            side = 1;
        } else {
            (b, fb) = (c, fc);
            if side == -1 {
                fa *= 0.5;
            }
            side = -1;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A residual `r(λg)` given as a function, with every λg asked for recorded.
    struct Model<F: Fn(f64) -> f64> {
        r: F,
        asked: Vec<f64>,
    }

    impl<F: Fn(f64) -> f64> Residual for Model<F> {
        fn residual(&mut self, lambda_g: f64) -> f64 {
            self.asked.push(lambda_g);
            (self.r)(lambda_g)
        }
        fn solves(&self) -> usize {
            self.asked.len()
        }
    }

    const CAP: f64 = 1e9;
    const SIGMA: f64 = 3e-6;

    fn run<F: Fn(f64) -> f64>(r: F) -> ((f64, f64), Vec<f64>) {
        let mut m = Model { r, asked: Vec::new() };
        let out = search_lambda_g(&mut m, SIGMA, CAP);
        (out, m.asked)
    }

    fn within_match(r: f64) -> bool {
        (r / SIGMA).ln().abs() < MATCH.ln()
    }

    /// `r ∝ λg^(−1/2)` through σ̂ at λg = 3e5: the search ends within MATCH of σ̂ near 3e5,
    /// starting at the middle and never visiting the smooth end.
    #[test]
    fn a_power_law_residual_is_matched_from_the_middle() {
        let ((lg, r), asked) = run(|l: f64| SIGMA * (l / 3e5).powf(-0.5));
        assert_eq!(asked[0], CAP * START_RATIO);
        assert!(within_match(r), "r = {r:e} at λg = {lg:e}, asked {asked:?}");
        assert!((lg / 3e5).ln().abs() < 2.0 * MATCH.ln() + 1e-9, "λg = {lg:e}");
        assert!(asked.iter().all(|&l| l > CAP * SMOOTH_START_RATIO), "{asked:?}");
        assert!(asked.len() <= 5, "{asked:?}");
    }

    /// A residual flat over a decade just below σ̂ (0.93 σ̂ from 1e5.5 up, as on 10 µm of noise
    /// on 128 nodes): the start's r(1e6) = 0.93 σ̂ is within MATCH but follows the noise, so the
    /// search goes on from the smooth side and ends below 1e6.
    #[test]
    fn a_flat_residual_is_approached_from_the_smooth_side() {
        let ((lg, r), asked) = run(|l: f64| SIGMA * (l / 3e5).powf(-0.5).max(0.93));
        assert!(asked.len() > 1, "{asked:?}");
        assert!(lg < CAP * START_RATIO, "λg = {lg:e}, asked {asked:?}");
        assert!(within_match(r), "r = {r:e}");
    }

    /// A start that fails (r = 0 from 1e5 up: too much tracking for the frame) sends the search
    /// to the smooth end; it ends on a solved λg within MATCH of σ̂, below the failures.
    #[test]
    fn a_failed_start_falls_back_to_the_smooth_end() {
        let ((lg, r), asked) = run(|l: f64| if l >= 1e5 { 0.0 } else { SIGMA * (l / 2e4).powf(-0.5) });
        assert_eq!(&asked[..2], &[CAP * START_RATIO, CAP * SMOOTH_START_RATIO]);
        assert!(r > 0.0 && lg < 1e5, "λg = {lg:e}, r = {r:e}, asked {asked:?}");
        assert!(within_match(r), "r = {r:e}, asked {asked:?}");
    }

    /// A band of λg where the solves fail (3e7–3e8: a frame's twist changing branch) on data
    /// the fit stays smoother than everywhere (smooth changes of shape): the search steps over
    /// the band to the cap, the failure telling nothing of `r`. (Taking the failure as a fit that
    /// follows the noise squeezed λg into the band's lower edge, 9.96e7, on such a recording.)
    #[test]
    fn a_band_of_failures_below_the_cap_is_stepped_over() {
        let ((lg, r), asked) = run(|l: f64| if (3e7..=3e8).contains(&l) { 0.0 } else { 2.0 * SIGMA * (1.0 + 1e6 / l) });
        assert!(asked.contains(&1e8), "the band is visited: {asked:?}");
        assert_eq!(lg, CAP, "{asked:?}");
        assert!(r > SIGMA);
    }

    /// Clean data: the fit stays smoother than σ̂ up to the cap, which is the choice.
    #[test]
    fn a_residual_above_the_noise_everywhere_gives_the_cap() {
        let ((lg, r), asked) = run(|l: f64| 2.0 * SIGMA * (1.0 + 1e6 / l));
        assert_eq!(lg, CAP, "{asked:?}");
        assert!(r > SIGMA);
    }
}
