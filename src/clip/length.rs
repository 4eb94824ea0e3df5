//! The length of a recorded centreline, corrected for the position noise of the recording, and
//! the body length estimated from a whole recording (`rod.length_m = "from_data"`). The data
//! give the body's current arc length (Remark 9 of [R1], the stretch `j`); a recording whose
//! frames are far from the rod length is in the wrong unit or of another body
//! (`crate::clip::MAX_LENGTH_DEVIATION`). Decisions: `docs/decisions.md` D18.
//!
//! ## Why a noisy polyline is too long
//! A recorded node is `y_i = x_i + e_i`, with independent Gaussian noise of standard deviation
//! `σ` on each coordinate. A chord `c_i = y_{i+1} − y_i = d_i + (e_{i+1} − e_i)` is its true
//! chord `d_i` plus a Gaussian vector of `s² = 2σ²` per coordinate, so `|c_i|/s` is a
//! non-central χ variable with 3 degrees of freedom and non-centrality `λ = |d_i|/s`, whose mean
//! is, in closed form for 3 degrees of freedom (integrate `r` over the Gaussian shell about `d`;
//! checked against a Monte Carlo mean in the tests):
//!
//! ```text
//!   E|c_i| = s m(|d_i|/s),   m(λ) = √(2/π) e^{−λ²/2} + (λ + 1/λ) erf(λ/√2)        (1)
//! ```
//!
//! `m(λ) ≥ λ`, `m(0) = 2√(2/π)` (the mean of a χ₃ variable) and `m(λ) = λ + 1/λ + O(e^{−λ²/2})`
//! for a large `λ`: each chord gains `s²/|d| = 2σ²/h` on average, a relative `2σ²/h²` at node
//! spacing `h` (≈ 20 % for σ = 10 µm at h = 31 µm). The expectation of a sum is the sum of the
//! expectations, so that adjacent chords share a node does not change it.
//!
//! ## The correction
//! Per frame, with the noise level `σ̂` of its nodes ([`crate::recorded::fit::noise_level`], from
//! the data) and `s = √2 σ̂`:
//!
//! 1. **Chords long against the noise.** At `σ/h` near or above 1 (10 µm of noise at 128 nodes
//!    on 1 mm) a chord holds more noise than length, and its fluctuation, not its mean, decides:
//!    the relative spread of a sum of `n` chords is about `1/(λ² √n)`, `λ = h/s`. So the frame
//!    is measured with chords of `k` node spacings, `k` the smallest whose mean chord
//!    `|x_{i+k} − x_i|` over every start node `i` is at least `Λ s` ([`MIN_CHORD_OVER_NOISE`],
//!    `Λ = 7`). Each offset `o < k` gives the polyline through the nodes `o, o + k, …`, whose
//!    corrected length (steps 2, 3) is scaled by `(N − 1)/(k m_o)` to the whole rod (`m_o` its
//!    chords; the nodes are equally spaced in arc length, as the rod's mesh is), and the `k`
//!    offsets, which share no node, are averaged. Without noise `k = 1`: every node.
//! 2. **Noise.** Each chord `c_j` joins two nodes of independent noise, so (1) holds for it
//!    with `s`, and its length is corrected by inverting (1),
//!
//!    ```text
//!      ℓ_j = s m⁻¹(|c_j|/s)                                                              (2)
//!    ```
//!
//!    (bisection: `m` increases and `m(λ) ≥ λ`; `ℓ_j = 0` where `|c_j| ≤ s m(0)`, no longer
//!    than noise alone makes it). For `λ ≥ Λ` the inverse is nearly linear,
//!    `m⁻¹(q) ≈ q − 1/q`, and inverting a noisy `|c_j|` chord by chord is biased by about
//!    `1/λ⁴` (4e-4 at `Λ`).
//! 3. **Curvature.** A chord is shorter than the arc it spans: for an arc of curvature `κ`,
//!    `arc/chord = (θ/2)/sin(θ/2) ≈ 1 + θ²/24`, `θ = κ ℓ` the turning angle. The turning angle
//!    `θ_j` between chords `j − 1` and `j` is measured and its noise removed:
//!
//!    ```text
//!      θ̃_j² = max(0, θ_j² − 2σ̂² (a² + (a + b)² + b²)),    a = 1/ℓ_j, b = 1/ℓ_{j−1}       (3)
//!    ```
//!
//!    (the two components of the nodes' noise across the chords, each of variance σ̂², move the
//!    chords' directions by `e⊥/ℓ`). Chord `j` then counts `ℓ_j (θ̄_j/2)/sin(θ̄_j/2)`, `θ̄_j²`
//!    the mean of `θ̃²` at its ends (its one end for the first and last chord of the polyline).
//!
//! The corrected length is `Σ_j ℓ_j (θ̄_j/2)/sin(θ̄_j/2)`. With `k = 1` and no noise it is the
//! polyline length with the chord-to-arc excess of a bent centreline added back (3.2e-3 of the
//! body on the 33-node synthetic recordings, 2e-4 on 128 nodes).
//!
//! ## Body length from the data
//! [`BodyLength::estimate`]: the median of the corrected lengths over the frames, with their
//! spread (the scaled median absolute deviation relative to the median) and their range.
use nalgebra::Vector3;

use super::polyline_length;
use crate::recorded::fit::{noise_level, noise_level_in};

/// `√(2/π)`.
const SQRT_2_OVER_PI: f64 = 0.797_884_560_802_865_4;
/// `1.4826`: the standard deviation over the median absolute deviation of a Gaussian.
const MAD_TO_SIGMA: f64 = 1.482_602_218_505_602;
/// Below this `λ`, `m(λ)` of eq. (1) is its limit `2√(2/π)` to within `λ²/3 < 4e-17`.
const SMALL_LAMBDA: f64 = 1e-8;
/// Most steps of eq. (2)'s safeguarded Newton: bisection alone shrinks the bracket `[0, q]` by
/// 2⁻⁶⁴ in as many, below round-off.
const BISECTION_STEPS: usize = 64;
/// Where `erf` switches from its Maclaurin series to the asymptotic series of `erfc`.
const ERF_SERIES_LIMIT: f64 = 4.0;

/// The error function for `x ≥ 0` (odd: `erf(−x) = −erf(x)`), to about 1e-12: the Maclaurin
/// series `erf x = (2/√π) Σ (−1)ⁿ x^{2n+1} / (n! (2n + 1))` below 4 (Abramowitz & Stegun
/// 7.1.5; its largest term, ~1e5 at x = 4, costs 5 of the 16 digits), and
/// `erfc x = e^{−x²}/(x√π) Σ (−1)ⁿ (2n − 1)!! / (2x²)ⁿ` (7.1.23), summed to its smallest
/// term, above (where `erfc x < 1.6e-8`).
pub fn erf(x: f64) -> f64 {
    if x < 0.0 {
        return -erf(-x);
    }
    if !x.is_finite() {
        return if x.is_nan() { x } else { 1.0 };
    }
    if x < ERF_SERIES_LIMIT {
        let (mut term, mut sum, x2) = (x, x, x * x);
        for n in 1..200 {
            term *= -x2 / n as f64;
            let add = term / (2 * n + 1) as f64;
            sum += add;
            if add.abs() < 1e-17 * sum.abs() {
                break;
            }
        }
        return std::f64::consts::FRAC_2_SQRT_PI * sum;
    }
    let inv = 1.0 / (2.0 * x * x);
    let (mut term, mut sum) = (1.0f64, 1.0f64);
    for n in 1..40 {
        let next = -term * (2 * n - 1) as f64 * inv;
        if next.abs() >= term.abs() {
            break;
        }
        term = next;
        sum += term;
    }
    1.0 - (-x * x).exp() / (x * std::f64::consts::PI.sqrt()) * sum
}

/// `m(λ)` of eq. (1) of the module doc: the mean of `|d + e|` in units of `s`, for a vector `d`
/// of length `λ s` and Gaussian `e` of `s²` per coordinate.
pub fn noisy_chord_mean(lambda: f64) -> f64 {
    if lambda < SMALL_LAMBDA {
        return 2.0 * SQRT_2_OVER_PI;
    }
    SQRT_2_OVER_PI * (-0.5 * lambda * lambda).exp() + (lambda + 1.0 / lambda) * erf(lambda / std::f64::consts::SQRT_2)
}

/// Shortest chord used, in units of the chord noise `s = √2 σ̂`: `Λ` of step 1 of the module
/// doc.
pub const MIN_CHORD_OVER_NOISE: f64 = 7.0;

/// `m'(λ) = (1 − 1/λ²) erf(λ/√2) + √(2/π) e^{−λ²/2}/λ`, the slope of [`noisy_chord_mean`]
/// (positive for `λ > 0`).
pub fn noisy_chord_slope(lambda: f64) -> f64 {
    let l = lambda.max(SMALL_LAMBDA);
    (1.0 - 1.0 / (l * l)) * erf(l / std::f64::consts::SQRT_2) + SQRT_2_OVER_PI * (-0.5 * l * l).exp() / l
}

/// From this `λ` on, `m(λ) = λ + 1/λ` in double precision (the rest is below `e^{−λ²/2}`,
/// 2.6e-18 at 9), and eq. (2) is solved in closed form.
const CLOSED_FORM_LAMBDA: f64 = 9.0;

/// `ℓ = s m⁻¹(c/s)` of eq. (2) of the module doc [m]: the chord whose expected noisy length
/// is `c` [m] under noise `s` [m] per coordinate of the chord (`s = 0`: `c`). A chord long
/// against the noise has the closed form `λ = (q + √(q² − 4))/2` of `λ + 1/λ = q`, `q = c/s`;
/// a shorter one is solved by Newton's method kept inside a bisection bracket (`m` increases,
/// `m(λ) ≥ λ`: the root lies in `[0, q]`).
pub fn denoised_chord(c: f64, s: f64) -> f64 {
    if !(s > 0.0 && s.is_finite() && c.is_finite()) {
        return c;
    }
    let q = c / s;
    if q <= noisy_chord_mean(0.0) {
        return 0.0;
    }
    let asymptotic = (q > 2.0).then(|| 0.5 * (q + (q * q - 4.0).sqrt()));
    if let Some(l) = asymptotic.filter(|l| *l >= CLOSED_FORM_LAMBDA) {
        return s * l;
    }
    let (mut lo, mut hi) = (0.0, q);
    let mut l = asymptotic.unwrap_or(0.5 * q);
    for _ in 0..BISECTION_STEPS {
        let f = noisy_chord_mean(l) - q;
        if f < 0.0 {
            lo = l;
        } else {
            hi = l;
        }
        let newton = l - f / noisy_chord_slope(l);
        let next = if newton > lo && newton < hi { newton } else { 0.5 * (lo + hi) };
        let done = (next - l).abs() <= 1e-15 * l || hi - lo <= 1e-15 * hi;
        l = next;
        if done {
            break;
        }
    }
    s * l
}

/// The length of one recorded frame, measured and corrected for its noise.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FrameLength {
    /// polyline length of the nodes [m]
    pub polyline_m: f64,
    /// the frame's noise level `σ̂` (`solve::fit::noise_level`) [m]
    pub noise_m: f64,
    /// node spacings per chord, `k` of step 1 of the module doc
    pub chord_nodes: usize,
    /// the corrected length of the module doc [m]
    pub corrected_m: f64,
}

/// The coordinates a recording's noise lies in: three (a 3D recording) or the two of its plane
/// (a planar recording, `crate::clip::recording`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Noisy {
    /// noise in all three coordinates
    Spatial,
    /// noise in the two coordinates of the recording's plane
    Planar,
}

impl FrameLength {
    /// The lengths of the frame `x` (nodes in order, [m]).
    pub fn of(x: &[Vector3<f64>]) -> FrameLength {
        FrameLength::with_noise(x, noise_level(x))
    }

    /// The lengths of the frame `x` of a recording whose noise lies in the plane normal to
    /// `plane` (a planar recording, `crate::clip::recording`), or in all three coordinates
    /// (`None`). Planar noise has two components: a chord gains half the length a 3D chord
    /// does, and a turning angle carries one component of noise across each chord, not two.
    pub fn of_in(x: &[Vector3<f64>], plane: Option<&Vector3<f64>>) -> FrameLength {
        match plane {
            None => FrameLength::of(x),
            Some(n) => FrameLength::measured(x, noise_level_in(x, Some(n)), Noisy::Planar),
        }
    }

    /// The lengths of the frame `x` with the noise level `noise_m` [m] per coordinate.
    pub fn with_noise(x: &[Vector3<f64>], noise_m: f64) -> FrameLength {
        FrameLength::measured(x, noise_m, Noisy::Spatial)
    }

    /// The lengths of the frame `x` with the noise level `noise_m` [m] per coordinate, in two
    /// or three coordinates (`noisy`).
    fn measured(x: &[Vector3<f64>], noise_m: f64, noisy: Noisy) -> FrameLength {
        let polyline_m = polyline_length(x);
        let n = x.len().saturating_sub(1);
        let s = std::f64::consts::SQRT_2 * noise_m.max(0.0);
        if n == 0 || !polyline_m.is_finite() || !s.is_finite() {
            return FrameLength { polyline_m, noise_m, chord_nodes: 1, corrected_m: polyline_m };
        }
        let k = chord_step(x, s);
        // every offset's chords, scaled to the whole rod (nodes equally spaced in arc length)
        let estimates: Vec<f64> = (0..k)
            .filter(|o| (n - o) / k >= 1)
            .map(|o| {
                let m = (n - o) / k;
                let nodes: Vec<Vector3<f64>> = (0..=m).map(|j| x[o + j * k]).collect();
                curvature_corrected(&nodes, noise_m, noisy) * n as f64 / (m * k) as f64
            })
            .collect();
        let corrected_m = estimates.iter().sum::<f64>() / estimates.len().max(1) as f64;
        FrameLength { polyline_m, noise_m, chord_nodes: k, corrected_m }
    }
}

/// `(θ/2)/sin(θ/2)`: the arc of a circle over its chord, `θ` the arc's turning angle
/// (`1 + θ²/24` below 1e-4 rad, where the next term is < 1e-18); capped at θ = π (a half
/// circle: π/2).
fn arc_over_chord(theta: f64) -> f64 {
    let half = 0.5 * theta.min(std::f64::consts::PI);
    if half < 1e-4 {
        1.0 + theta * theta / 24.0
    } else {
        half / half.sin()
    }
}

/// Mean length of the chords `x_{i+k} − x_i` [m].
fn mean_chord(x: &[Vector3<f64>], k: usize) -> f64 {
    let n = x.len() - k;
    x.windows(k + 1).map(|w| (w[k] - w[0]).norm()).sum::<f64>() / n as f64
}

/// `k` of step 1 of the module doc: the smallest node step whose mean chord (noisy, over every
/// start node) is at least `Λ s`, found by doubling and then bisection; 1 without noise, at
/// most `x.len() − 1`.
fn chord_step(x: &[Vector3<f64>], s: f64) -> usize {
    let n = x.len() - 1;
    let long = |k: usize| mean_chord(x, k) >= MIN_CHORD_OVER_NOISE * s;
    if s.is_nan() || s <= 0.0 || long(1) {
        return 1;
    }
    let mut hi = 2;
    while hi < n && !long(hi) {
        hi = (2 * hi).min(n);
    }
    // long(lo) is false, long(hi) true (or hi = n)
    let mut lo = hi / 2;
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if long(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

/// Steps 2 and 3 of the module doc on the chords of `nodes` (the nodes kept) with noise
/// `noise_m` [m] per coordinate, in three coordinates or two (`noisy`,
/// [`FrameLength::of_in`]):
/// `Σ_j ℓ_j (θ̄_j/2)/sin(θ̄_j/2)` [m].
fn curvature_corrected(nodes: &[Vector3<f64>], noise_m: f64, noisy: Noisy) -> f64 {
    let planar = noisy == Noisy::Planar;
    let s = std::f64::consts::SQRT_2 * noise_m;
    let chords: Vec<Vector3<f64>> = nodes.windows(2).map(|w| w[1] - w[0]).collect();
    let l: Vec<f64> = chords
        .iter()
        .map(|c| if planar { denoised_planar_chord(c.norm(), s) } else { denoised_chord(c.norm(), s) })
        .collect();
    // components of a node's noise across a chord: two in space, one in the plane
    let across = if planar { 1.0 } else { 2.0 };
    // θ̃² at the vertex between chords j − 1 and j, eq. (3)
    let theta2: Vec<f64> = (1..chords.len())
        .map(|j| {
            let (u, v) = (chords[j - 1], chords[j]);
            let (nu, nv) = (u.norm(), v.norm());
            if !(nu > 0.0 && nv > 0.0 && l[j] > 0.0 && l[j - 1] > 0.0) {
                return 0.0;
            }
            let theta = u.cross(&v).norm().atan2(u.dot(&v));
            let (a, b) = (1.0 / l[j], 1.0 / l[j - 1]);
            (theta * theta - across * noise_m * noise_m * (a * a + (a + b) * (a + b) + b * b)).max(0.0)
        })
        .collect();
    let end = |j: usize| -> Option<f64> { j.checked_sub(1).and_then(|i| theta2.get(i)).copied() };
    l.iter()
        .enumerate()
        .map(|(j, lj)| {
            // the vertices at the chord's ends: before it (j) and after it (j + 1)
            let ends: Vec<f64> = [end(j), end(j + 1)].into_iter().flatten().collect();
            let t2 = if ends.is_empty() { 0.0 } else { ends.iter().sum::<f64>() / ends.len() as f64 };
            lj * arc_over_chord(t2.sqrt())
        })
        .sum()
}

/// `ℓ = s m₂⁻¹(c/s)` [m]: eq. (2) of the module doc for a planar recording
/// ([`FrameLength::of_in`]), whose
/// chord noise has two components of `s²` each; `|c|/s` is then a Rice variable, whose mean
/// is `m₂(λ) = λ + 1/(2λ) + O(λ⁻³)` (each chord gains `s²/(2|d|) = σ²/h`, half the 3D
/// excess). Inverted in closed form, `λ = (q + √(q² − 2))/2`; a chord no longer than the mean of
/// noise alone (`√(π/2) s`, the Rayleigh mean) is 0, and between that and `√2 s`, where the
/// expansion has no root, `λ = q/√2` (chords there are shorter than `Λ s`/5, which step 1 keeps
/// rare: the expansion's error at `Λ` is 3e-4 of a chord).
pub fn denoised_planar_chord(c: f64, s: f64) -> f64 {
    if !(s > 0.0 && s.is_finite() && c.is_finite()) {
        return c;
    }
    let q = c / s;
    if q <= (std::f64::consts::PI / 2.0).sqrt() {
        return 0.0;
    }
    if q < std::f64::consts::SQRT_2 {
        return s * q / std::f64::consts::SQRT_2;
    }
    s * 0.5 * (q + (q * q - 2.0).sqrt())
}

/// A body length estimated from the frames of a recording (module doc).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BodyLength {
    /// the median over the frames of the corrected length [m]
    pub length_m: f64,
    /// the frames' spread: `1.4826 median|L_f − L| / L` [–]
    pub spread_rel: f64,
    /// the shortest and the longest corrected frame length [m]
    pub min_m: f64,
    pub max_m: f64,
    /// the median noise level of the frames [m]
    pub noise_m_median: f64,
    /// frames used
    pub frames: usize,
}

impl BodyLength {
    /// The estimate from `frames` (each a centreline, [m]); `None` without a frame of positive
    /// finite corrected length.
    pub fn estimate(frames: &[Vec<Vector3<f64>>]) -> Option<BodyLength> {
        BodyLength::estimate_in(frames, None)
    }

    /// [`BodyLength::estimate`] of a recording whose noise lies in the plane normal to `plane`
    /// ([`FrameLength::of_in`]).
    pub fn estimate_in(frames: &[Vec<Vector3<f64>>], plane: Option<&Vector3<f64>>) -> Option<BodyLength> {
        BodyLength::of_lengths(&frames.iter().map(|f| FrameLength::of_in(f, plane)).collect::<Vec<_>>())
    }

    /// [`BodyLength::estimate_in`] of the frames' lengths (each [`FrameLength::of_in`]), taken
    /// as the frames were read.
    pub fn of_lengths(lengths: &[FrameLength]) -> Option<BodyLength> {
        let mut l: Vec<f64> = lengths.iter().map(|f| f.corrected_m).filter(|v| v.is_finite()).collect();
        let length_m = median(&mut l)?;
        if length_m.is_nan() || length_m <= 0.0 {
            return None;
        }
        let mut dev: Vec<f64> = l.iter().map(|v| (v - length_m).abs()).collect();
        let mut noise: Vec<f64> = lengths.iter().map(|f| f.noise_m).collect();
        Some(BodyLength {
            length_m,
            spread_rel: MAD_TO_SIGMA * median(&mut dev).unwrap_or(0.0) / length_m,
            min_m: l.iter().copied().fold(f64::INFINITY, f64::min),
            max_m: l.iter().copied().fold(0.0, f64::max),
            noise_m_median: median(&mut noise).unwrap_or(0.0),
            frames: l.len(),
        })
    }
}

/// The median of `v` (mean of the middle two for an even count); `None` when empty.
fn median(v: &mut [f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) })
}

#[cfg(test)]
mod tests;
