//! How well a clip frame's reconstruction follows its data, and the gate that flags frames that
//! do not (`docs/certificate.md`, C5).
//!
//! A frame can be solved (its certificate within tolerance) and still be a wrong reconstruction:
//! with a large Λω the frames lag behind the data and d3 leaves the tangent. Two measures,
//! both independent of where the recording sits in space:
//!
//! ```text
//!   position misfit   p = ( (1/L) ∫ |x − x_g|² )^½ / L          (RMS distance, in body lengths)
//!   tangent misfit    t = ( (1/L) ∫ |∂s x − d3|² )^½            (RMS, ≈ the angle between them [rad])
//! ```
//!
//! They are held against thresholds derived from the data. The noise level `σ` of a recorded
//! frame is estimated from its own positions ([`noise_level`]). A fit is expected to follow
//! the data to about `σ` and its tangent to about the noise of a difference tangent, `√2 σ/h`.
//! A frame is flagged when
//!
//! ```text
//!   p > max(k σ / L, p_min)    or    t > max(k √2 σ / h, t_min)
//! ```
//!
//! Here `k` is [`FitGate::noise_multiple`], and the floors are the misfits the model leaves on
//! clean data (C5 has the measured values).
use nalgebra::Vector3;

/// `1.4826`: the ratio of the standard deviation to the median absolute deviation of a
/// Gaussian.
const MAD_TO_SIGMA: f64 = 1.482_602_218_505_602;
/// `√70`: the norm of the fourth-difference stencil (1, −4, 6, −4, 1).
const FOURTH_DIFFERENCE_NORM: f64 = 8.366_600_265_340_756;

/// The noise level `σ` [m] of one recorded frame: the standard deviation of independent
/// Gaussian noise on each coordinate of each node, estimated from the fourth differences along
/// the rod, `Δ⁴x_i = x_{i−2} − 4 x_{i−1} + 6 x_i − 4 x_{i+1} + x_{i+2}`, as
/// `σ = 1.4826 median|Δ⁴x| / √70` over every coordinate and interior node. The fourth difference
/// of a smooth centreline is `h⁴ x''''`: on the worm clips (h ≈ 8 µm, bending waves of a few
/// body lengths) that is about 1e-18 m, far below any recorded noise. The median makes one
/// bad node, a tracking glitch, count for little. A frame of fewer than 5 nodes has no estimate
/// (0).
pub fn noise_level(x: &[Vector3<f64>]) -> f64 {
    noise_level_in(x, None)
}

/// [`noise_level`] of a frame whose data carry noise in the plane normal to `plane` only (a
/// planar recording, `clip::recording`): the fourth differences' two components in that plane
/// are pooled, not the third, which holds no noise (pooled, its zeros would put the median of
/// the absolute values at the 3/4 quantile of the noise's instead of the 1/2: a planar
/// recording's σ came out 0.46 σ). `None`: the three coordinates.
pub fn noise_level_in(x: &[Vector3<f64>], plane: Option<&Vector3<f64>>) -> f64 {
    if x.len() < 5 {
        return 0.0;
    }
    let basis = plane.map(plane_basis);
    let mut d: Vec<f64> = x
        .windows(5)
        .flat_map(|w| {
            let v = w[0] - w[1] * 4.0 + w[2] * 6.0 - w[3] * 4.0 + w[4];
            match &basis {
                Some((a, b)) => [v.dot(a).abs(), v.dot(b).abs(), f64::NAN],
                None => [v[0].abs(), v[1].abs(), v[2].abs()],
            }
        })
        .filter(|v| v.is_finite())
        .collect();
    if d.is_empty() {
        return 0.0;
    }
    let mid = d.len() / 2;
    let (_, median, _) = d.select_nth_unstable_by(mid, f64::total_cmp);
    MAD_TO_SIGMA * *median / FOURTH_DIFFERENCE_NORM
}

/// Two unit vectors spanning the plane normal to the unit vector `n`: `(e1, e2)` with
/// `e1 × e2 = n`. For `n = e3` they are exactly `(e1, e2)`.
pub fn plane_basis(n: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let k = n.iamax();
    let helper = if k == 0 { Vector3::y() } else { Vector3::x() };
    let mut a = helper - n * n.dot(&helper);
    a.iter_mut().for_each(|v| {
        if v.abs() < 1e-15 {
            *v = 0.0
        }
    });
    let a = a.normalize();
    (a, n.cross(&a))
}

/// The position misfit `p` of the module doc: `((1/L) ∫ |x − x_g|²)^½ / L` for P1 fields on a
/// uniform mesh of `x.len() − 1` elements of a rod of length `length_m` [m], integrated
/// exactly (`∫ |a(1 − ξ) + b ξ|² = h (|a|² + a·b + |b|²)/3` per element, `a, b` the nodal
/// differences). With `tracked` (`clip::missing`) the integral and the `1/L` run over the
/// elements whose two nodes were tracked; a frame without such an element is measured whole.
pub fn position_misfit(x: &[Vector3<f64>], x_g: &[Vector3<f64>], tracked: Option<&[bool]>, length_m: f64) -> f64 {
    let d: Vec<Vector3<f64>> = x.iter().zip(x_g).map(|(a, b)| a - b).collect();
    let h = length_m / (d.len().max(2) - 1) as f64;
    let both = |e: usize| tracked.is_none_or(|t| t[e] && t[e + 1]);
    let elements: Vec<usize> = (0..d.len().saturating_sub(1)).filter(|&e| both(e)).collect();
    // no element with two tracked nodes (a bridged frame): against the whole filled frame
    let elements = if elements.is_empty() { (0..d.len().saturating_sub(1)).collect() } else { elements };
    let integral: f64 =
        elements.iter().map(|&e| h * (d[e].norm_squared() + d[e].dot(&d[e + 1]) + d[e + 1].norm_squared()) / 3.0).sum();
    let measured = if elements.len() + 1 == d.len() { length_m } else { h * elements.len() as f64 };
    (integral / measured).sqrt() / length_m
}

/// The fit measures of one frame (module doc).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FrameFit {
    /// the noise level of the frame's data, [`noise_level`] [m]
    pub noise_m: f64,
    /// position misfit `p`, RMS of `|x − x_g|` over the rod in body lengths [–]
    pub position: f64,
    /// tangent misfit `t`, RMS of `|∂s x − d3|` over the rod [–]
    pub tangent: f64,
    /// largest `|κ|` over the element midpoints [1/m]
    #[serde(default)]
    pub curvature_max_per_m: f64,
    /// over the gate ([`FitGate::check`])
    pub flagged: bool,
    /// solved again from its data guess because its solution from the previous frame was over
    /// the gate (`solve::sequence`)
    #[serde(default)]
    pub resolved: bool,
}

/// Why a frame was flagged, for messages.
impl FrameFit {
    pub fn reason(&self, gate: &FitGate, length_m: f64, h_m: f64) -> String {
        let (p, t) = gate.thresholds(self.noise_m, length_m, h_m);
        format!(
            "position misfit {:.2e} L (gate {p:.2e} L), tangent misfit {:.2e} (gate {t:.2e}), largest curvature {:.3e} 1/m (bound {:.3e} 1/m), data noise {:.2e} m",
            self.position, self.tangent, self.curvature_max_per_m, gate.max_curvature_per_m, self.noise_m
        )
    }
}

/// The fit-quality gate of a clip (module doc): `clip.gate_noise_multiple`,
/// `clip.gate_position` and `clip.gate_tangent` of a case file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitGate {
    /// `k`: how many noise levels a misfit may reach
    pub noise_multiple: f64,
    /// `p_min`: the position misfit [body lengths] below which a frame is never flagged
    pub position_min: f64,
    /// `t_min`: the tangent misfit below which a frame is never flagged
    pub tangent_min: f64,
    /// the noise level σ per coordinate stated by the case (`clip.noise_m`) [m]; `None`: each
    /// frame's own estimate ([`noise_level_in`])
    pub noise_m: Option<f64>,
    /// `κ_max`: a frame whose curvature `|κ|` exceeds this anywhere is over the gate
    /// (`clip.max_curvature_per_m`, default [`FitGate::curvature_bound`]) [1/m]
    pub max_curvature_per_m: f64,
}

impl Default for FitGate {
    /// `k = 3`, `p_min = 1e-3` (1 µm on a 1 mm worm), `t_min = 0.1` (the paper's largest
    /// detachment of d3 from the tangent, §6 (ii)).
    fn default() -> Self {
        FitGate {
            noise_multiple: 3.0,
            position_min: 1e-3,
            tangent_min: 0.1,
            noise_m: None,
            max_curvature_per_m: f64::INFINITY,
        }
    }
}

impl FitGate {
    /// The physical bound on a rod's curvature: the inverse of the smallest half-width of its
    /// cross-section (a circle's radius). A centreline bent tighter than that would fold the
    /// body's inner side onto itself; a worm of radius 20 µm bends to at most 50 /mm, while
    /// the elegansbot kymograms never exceed 14 /mm and a wrong branch reaches 10³ /mm [1/m].
    pub fn curvature_bound(section: &crate::model::material::CrossSection) -> f64 {
        use crate::model::material::CrossSection;
        match *section {
            CrossSection::Circle { radius_m } => 1.0 / radius_m,
            CrossSection::Rectangle { width_m, height_m } => 2.0 / width_m.min(height_m),
        }
    }

    /// The noise level the gate holds a frame's misfits against: the stated one, else the
    /// frame's own estimate `estimated` [m].
    pub fn noise(&self, estimated: f64) -> f64 {
        self.noise_m.unwrap_or(estimated)
    }

    /// The thresholds `(p*, t*)` for data of noise level `noise_m` [m] on a rod of length
    /// `length_m` [m] with elements of `h_m` [m].
    pub fn thresholds(&self, noise_m: f64, length_m: f64, h_m: f64) -> (f64, f64) {
        let k = self.noise_multiple;
        (
            (k * noise_m / length_m).max(self.position_min),
            (k * std::f64::consts::SQRT_2 * noise_m / h_m).max(self.tangent_min),
        )
    }

    /// Is a frame with these measures over the gate (a non-finite measure is)?
    pub fn check(&self, fit: &FrameFit, length_m: f64, h_m: f64) -> bool {
        let (p, t) = self.thresholds(fit.noise_m, length_m, h_m);
        !(fit.position <= p && fit.tangent <= t && fit.curvature_max_per_m <= self.max_curvature_per_m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A planar arc of radius 1 mm sampled at 129 nodes over 1 mm, with seeded Gaussian noise
    /// of σ on every coordinate: the estimate is within 10 % of σ for σ from 0.1 to 10 µm, and
    /// below 1e-3 µm without noise.
    #[test]
    fn noise_level_recovers_gaussian_noise() {
        let n = 129;
        let arc = |i: usize| {
            let s = i as f64 / (n - 1) as f64 * 1e-3;
            let th = s / 1e-3;
            Vector3::new(1e-3 * (1.0 - th.cos()), 0.0, 1e-3 * th.sin())
        };
        let clean: Vec<Vector3<f64>> = (0..n).map(arc).collect();
        assert!(noise_level(&clean) < 1e-9, "{}", noise_level(&clean));
        // Box–Muller on a small LCG: reproducible without a crate
        let mut state: u64 = 0x2545_f491_4f6c_dd1d;
        let mut uniform = || {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        for sigma in [1e-7, 1e-6, 1e-5] {
            let mut gauss = || (-2.0 * uniform().ln()).sqrt() * (std::f64::consts::TAU * uniform()).cos();
            let noisy: Vec<Vector3<f64>> =
                clean.iter().map(|p| p + Vector3::new(gauss(), gauss(), gauss()) * sigma).collect();
            let est = noise_level(&noisy);
            assert!((est / sigma - 1.0).abs() < 0.1, "σ = {sigma:e}: estimated {est:e}");
        }
    }

    /// Noise of σ in x and y only (a planar recording at z = 0): pooled with the zero third
    /// coordinate, the median of |Δ⁴| is the 1/4 quantile of the noisy coordinates' |Δ⁴|
    /// (1/3 + (2/3)·1/4 = 1/2), 0.319 σ√70 instead of 0.674 σ√70: the estimate is 0.47 σ in
    /// expectation (0.47 σ on this frame of 1025 nodes; 0.46 σ on the recordings of the tracker trial); in the
    /// plane it is within 10 % of σ. The plane need not be a coordinate plane.
    #[test]
    fn planar_noise_is_estimated_in_its_plane() {
        let n = 1025;
        let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut uniform = || {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        let mut gauss = || (-2.0 * uniform().ln()).sqrt() * (std::f64::consts::TAU * uniform()).cos();
        let sigma = 1e-6;
        let frame: Vec<Vector3<f64>> = (0..n)
            .map(|i| {
                let th = i as f64 / (n - 1) as f64;
                Vector3::new(1e-3 * th.sin() + sigma * gauss(), 1e-3 * (1.0 - th.cos()) + sigma * gauss(), 0.0)
            })
            .collect();
        let pooled = noise_level(&frame);
        let planar = noise_level_in(&frame, Some(&Vector3::z()));
        assert!(pooled / sigma > 0.35 && pooled / sigma < 0.55, "pooled {pooled:e}");
        assert!((planar / sigma - 1.0).abs() < 0.1, "planar {planar:e}");
        // the same frame in a tilted plane
        let r = nalgebra::Rotation3::new(Vector3::new(0.4, -0.9, 0.3));
        let tilted: Vec<Vector3<f64>> = frame.iter().map(|p| r * p).collect();
        let est = noise_level_in(&tilted, Some(&(r * Vector3::z())));
        // (its in-plane basis differs by a turn within the plane: the same noise, other samples)
        assert!((est / sigma - 1.0).abs() < 0.1, "tilted {est:e} vs {planar:e}");
    }

    /// The curvature bound: a frame whose |κ| exceeds it is over the gate, whatever its fit;
    /// the bound of a circle is its inverse radius, of a rectangle the inverse half of its
    /// smaller side.
    #[test]
    fn the_curvature_bound_flags_a_frame() {
        use crate::model::material::CrossSection;
        let circle = FitGate::curvature_bound(&CrossSection::Circle { radius_m: 2e-5 });
        let rectangle = FitGate::curvature_bound(&CrossSection::Rectangle { width_m: 4e-5, height_m: 1e-4 });
        assert!((circle / 5e4 - 1.0).abs() < 1e-15 && (rectangle / 5e4 - 1.0).abs() < 1e-15, "{circle} {rectangle}");
        let g = FitGate { max_curvature_per_m: 5e4, ..FitGate::default() };
        let (l, h) = (1e-3, 1e-3 / 32.0);
        let fit = FrameFit { position: 5e-4, tangent: 0.05, curvature_max_per_m: 4.9e4, ..FrameFit::default() };
        assert!(!g.check(&fit, l, h));
        assert!(g.check(&FrameFit { curvature_max_per_m: 5.1e4, ..fit }, l, h));
        assert!(g.check(&FrameFit { curvature_max_per_m: f64::NAN, ..fit }, l, h));
        assert_eq!(g.noise(3e-7), 3e-7);
        assert_eq!(FitGate { noise_m: Some(1e-6), ..g }.noise(3e-7), 1e-6);
    }

    #[test]
    fn gate_thresholds_follow_the_noise_above_their_floors() {
        let g = FitGate::default();
        let (l, h) = (1e-3, 1e-3 / 32.0);
        assert_eq!(g.thresholds(0.0, l, h), (1e-3, 0.1));
        let (p, t) = g.thresholds(1e-5, l, h);
        assert!((p - 3e-2).abs() < 1e-15 && (t - 3.0 * 2f64.sqrt() * 1e-5 / h).abs() < 1e-12);
        let fit = FrameFit { noise_m: 0.0, position: 5e-4, tangent: 0.05, ..FrameFit::default() };
        assert!(!g.check(&fit, l, h));
        assert!(g.check(&FrameFit { tangent: 1.5, ..fit }, l, h));
        assert!(g.check(&FrameFit { position: f64::NAN, ..fit }, l, h));
    }
}
