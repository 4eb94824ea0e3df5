use super::*;
use crate::clip::MAX_LENGTH_DEVIATION;

/// SplitMix64 with Box–Muller: seeded standard normal numbers without a crate.
struct Normal(u64);

impl Normal {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn next(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * self.uniform()).cos()
    }

    fn vector(&mut self, sigma: f64) -> Vector3<f64> {
        Vector3::new(self.next(), self.next(), self.next()) * sigma
    }
}

/// Abramowitz & Stegun, Table 7.1 (10 digits), and erf(4) from 1 − erfc(4) = 1 − 1.541725790e-8.
#[test]
fn erf_matches_its_table() {
    for (x, v) in [
        (0.1, 0.112_462_916_0),
        (0.5, 0.520_499_877_8),
        (1.0, 0.842_700_792_9),
        (2.0, 0.995_322_265_0),
        (2.9, 0.999_958_902_2),
        (3.0, 0.999_977_909_5),
        (4.0, 1.0 - 1.541_725_790e-8),
    ] {
        assert!((erf(x) - v).abs() < 1e-10, "erf({x}) = {} against {v}", erf(x));
        assert_eq!(erf(-x), -erf(x));
    }
    assert_eq!(erf(0.0), 0.0);
    assert_eq!(erf(f64::INFINITY), 1.0);
    assert!(erf(f64::NAN).is_nan());
}

/// Eq. (1) against its limits (χ₃'s mean 2√(2/π) at λ = 0, λ + 1/λ for a large λ) and against
/// a Monte Carlo mean of |d + e| (2·10⁵ samples: the standard error is below 1/√(2·10⁵) =
/// 2.2e-3, since |d + e| has a variance below 3; tolerance 1e-2).
#[test]
fn noisy_chord_mean_is_the_mean_of_a_noisy_chord() {
    assert!((noisy_chord_mean(0.0) - 2.0 * (2.0 / std::f64::consts::PI).sqrt()).abs() < 1e-15);
    assert!((noisy_chord_mean(1e-6) - noisy_chord_mean(0.0)).abs() < 1e-11);
    for l in [10.0, 30.0] {
        assert!((noisy_chord_mean(l) - (l + 1.0 / l)).abs() < 1e-12 * l, "λ = {l}");
    }
    let mut g = Normal(3);
    for lambda in [0.0, 0.5, 1.0, 2.0, 5.0] {
        let d = Vector3::new(0.3, -0.4, 0.866_025_403_784_438_6).normalize() * lambda;
        let samples = 200_000;
        let mean = (0..samples).map(|_| (d + g.vector(1.0)).norm()).sum::<f64>() / samples as f64;
        assert!(
            (mean - noisy_chord_mean(lambda)).abs() < 1e-2,
            "λ = {lambda}: MC {mean}, eq. (1) {}",
            noisy_chord_mean(lambda)
        );
    }
    // m increases, so that eq. (2) has one root; denoised_chord inverts it
    let m: Vec<f64> = (0..200).map(|i| noisy_chord_mean(i as f64 * 0.05)).collect();
    assert!(m.windows(2).all(|w| w[1] > w[0]));
    // the slope of m, against central differences
    for lambda in [0.05, 0.5, 2.0, 7.0, 9.5] {
        let e = 1e-6 * lambda;
        let fd = (noisy_chord_mean(lambda + e) - noisy_chord_mean(lambda - e)) / (2.0 * e);
        assert!((noisy_chord_slope(lambda) - fd).abs() < 1e-7, "λ = {lambda}: {} vs {fd}", noisy_chord_slope(lambda));
    }
    // either side of the closed form's threshold (9) and far beyond it
    for lambda in [0.3, 1.0, 4.0, 8.9, 9.1, 12.0, 300.0] {
        let s = 2e-6;
        let l = denoised_chord(s * noisy_chord_mean(lambda), s);
        assert!((l / (lambda * s) - 1.0).abs() < 1e-12, "λ = {lambda}: {l:e}");
    }
    assert_eq!(denoised_chord(1.5e-6, 1e-6), 0.0, "shorter than noise alone");
    assert_eq!(denoised_chord(3e-5, 0.0), 3e-5);
}

/// A circular arc of 1 mm at curvature 6/mm (almost a full turn: more than the worm clips'
/// rms curvature, 9/mm at 33 nodes, sustained along the whole body), nodes equally spaced in
/// arc length.
fn arc(nodes: usize) -> Vec<Vector3<f64>> {
    let (l, r) = (1e-3, 1e-3 / 6.0);
    (0..nodes)
        .map(|i| {
            let t = l * i as f64 / (nodes - 1) as f64 / r;
            Vector3::new(r * (1.0 - t.cos()), 0.0, r * t.sin())
        })
        .collect()
}

/// Seeded noise of σ ∈ {0.3, 1, 3, 10} µm on the arc at 33 and 128 nodes (σ/h from 0.01 to
/// 1.27), 200 frames each. Measured (max over frames of |L/L_true − 1|; the raw polyline's mean
/// inflation against 2σ²/h² where σ/h < 0.35):
///
/// | nodes | σ [µm] | σ/h | raw max | mean inflation (2σ²/h²) | k | corrected max | mean | sd |
/// |---|---|---|---|---|---|---|---|---|
/// | 33 | 0.3 | 0.010 | 2.6e-3 | 1.5e-4 (1.8e-4) | 1 | 1.8e-3 | −5e-5 | 5.9e-4 |
/// | 33 | 1 | 0.032 | 6.1e-3 | 2.2e-3 (2.0e-3) | 1 | 6.4e-3 | 5e-5 | 1.9e-3 |
/// | 33 | 3 | 0.096 | 3.6e-2 | 1.95e-2 (1.84e-2) | 1 | 2.1e-2 | 1.4e-3 | 7.0e-3 |
/// | 33 | 10 | 0.32 | 3.2e-1 | 2.02e-1 (2.05e-1) | 3 | 6.0e-2 | −3e-4 | 1.6e-2 |
/// | 128 | 0.3 | 0.038 | 4.6e-3 | 3.0e-3 (2.9e-3) | 1 | 1.8e-3 | 2.5e-4 | 6.2e-4 |
/// | 128 | 1 | 0.13 | 4.2e-2 | 3.2e-2 (3.2e-2) | 2 | 1.2e-2 | 3.5e-4 | 2.3e-3 |
/// | 128 | 3 | 0.38 | 3.7e-1 | 2.8e-1 (2.9e-1) | 4 | 1.7e-2 | 4.4e-4 | 4.4e-3 |
/// | 128 | 10 | 1.27 | 2.3 | 2.0 (–) | 15 | 2.9e-2 | −9e-4 | 8.1e-3 |
///
/// The corrected length of every frame is within the band of the load check,
/// [`MAX_LENGTH_DEVIATION`], so that a recording of the rod's length passes it at any of these
/// noise levels, while the raw polyline at 10 µm is far outside; the mean over the frames is
/// within 1 % (the bias of the per-chord inversion is about `1/Λ⁴` = 4e-4). What is left is
/// the spread of one frame (sd), set by the noise: at 33 nodes and 10 µm the chords are 7 noise
/// levels long and only 10 of them span the body. Without noise the curvature correction of
/// step 3 makes the length exact to 1e-6 where the polyline is short by `h²κ²/24` (1.5e-3 at 33
/// nodes).
#[test]
fn corrected_length_removes_the_noise_inflation() {
    let mut g = Normal(11);
    for nodes in [33usize, 128] {
        let clean = arc(nodes);
        let h = 1e-3 / (nodes - 1) as f64;
        let exact = FrameLength::with_noise(&clean, 0.0);
        assert!((exact.corrected_m / 1e-3 - 1.0).abs() < 1e-6, "{nodes} nodes: {exact:?}");
        let chord_deficit = 1.0 - exact.polyline_m / 1e-3;
        assert!((chord_deficit / ((h * 6e3).powi(2) / 24.0) - 1.0).abs() < 1e-2, "{chord_deficit:e}");
        for sigma in [0.3e-6, 1e-6, 3e-6, 10e-6] {
            let frames: Vec<FrameLength> = (0..200)
                .map(|_| FrameLength::of(&clean.iter().map(|p| p + g.vector(sigma)).collect::<Vec<_>>()))
                .collect();
            let dev = |f: &FrameLength| f.corrected_m / 1e-3 - 1.0;
            let max = frames.iter().map(|f| dev(f).abs()).fold(0.0, f64::max);
            let mean = frames.iter().map(dev).sum::<f64>() / frames.len() as f64;
            let raw_max = frames.iter().map(|f| (f.polyline_m / 1e-3 - 1.0).abs()).fold(0.0, f64::max);
            let raw_mean = frames.iter().map(|f| f.polyline_m / 1e-3 - 1.0).sum::<f64>() / 200.0 + chord_deficit;
            let line = format!(
                "{nodes} nodes, σ = {sigma:e} m, σ/h = {:.3}: raw max {raw_max:.2e} (mean inflation {raw_mean:.2e}, \
                 2σ²/h² = {:.2e}), corrected max {max:.2e}, mean {mean:.1e}, k = {}",
                sigma / h,
                2.0 * (sigma / h).powi(2),
                frames[0].chord_nodes
            );
            let sd = (frames.iter().map(|f| (dev(f) - mean).powi(2)).sum::<f64>() / 199.0).sqrt();
            println!("{line}, sd {sd:.1e}");
            assert!(max < MAX_LENGTH_DEVIATION && mean.abs() < 1e-2, "{line}");
            if sigma == 10e-6 {
                assert!(raw_max > MAX_LENGTH_DEVIATION, "the raw polyline would be refused: {line}");
            }
            if sigma / h < 0.35 {
                // eq. (1) to first order: each chord gains 2σ²/h² on average
                let first_order = 2.0 * (sigma / h).powi(2);
                assert!((raw_mean / first_order - 1.0).abs() < 0.1 + 3e-4 / first_order, "{line}");
            }
        }
    }
}

/// The body length of a recording is the median over its frames; a few glitched frames do not
/// move it, and their spread shows.
#[test]
fn body_length_is_a_robust_median() {
    let mut g = Normal(5);
    let clean = arc(65);
    let mut frames: Vec<Vec<Vector3<f64>>> =
        (0..41).map(|_| clean.iter().map(|p| p + g.vector(2e-6)).collect()).collect();
    // three frames with a node 100 µm off (a tracking glitch)
    for f in frames.iter_mut().take(3) {
        f[30].x += 1e-4;
    }
    let b = BodyLength::estimate(&frames).unwrap();
    assert_eq!(b.frames, 41);
    assert!((b.length_m / 1e-3 - 1.0).abs() < 5e-3, "{b:?}");
    assert!(b.max_m > 1.1e-3 && b.spread_rel < 2e-2, "{b:?}");
    assert!((b.noise_m_median / 2e-6 - 1.0).abs() < 0.15, "{b:?}");
    assert_eq!(BodyLength::estimate(&[]), None);
    assert_eq!(BodyLength::estimate(&[vec![Vector3::zeros(); 4]]), None);
}

/// A planar recording's chords: noise in two coordinates. The mean of the corrected chord over
/// 20 000 noisy copies of a chord of λ = 3, 7 and 20 noise levels (the Rice mean's expansion,
/// inverted) is the true chord within 2 % at λ = 3 (measured 1.2 % short: the expansion's
/// neglected λ⁻³ term) and 0.3 % from λ = 7 (the shortest mean chord step 1 uses; the sampling
/// noise of the mean is 2e-4 of a chord there), where the 3D
/// inversion takes off about twice the excess.
#[test]
fn planar_chords_are_corrected_with_two_noisy_coordinates() {
    let mut g = Normal(17);
    let s = 1.0;
    for (lambda, tol) in [(3.0, 2e-2), (7.0, 3e-3), (20.0, 2e-3)] {
        let n = 20_000;
        let (mut planar, mut spatial) = (0.0, 0.0);
        for _ in 0..n {
            let c = Vector3::new(lambda + s * g.next(), s * g.next(), 0.0).norm();
            planar += denoised_planar_chord(c, s);
            spatial += denoised_chord(c, s);
        }
        let (planar, spatial) = (planar / n as f64 / lambda, spatial / n as f64 / lambda);
        println!("λ = {lambda}: planar {planar:.5}, 3D inversion {spatial:.5}");
        assert!((planar - 1.0).abs() < tol, "λ = {lambda}: planar {planar}");
        // (at λ = 20 the 3D bias, 1/(2λ²) = 1.3e-3, is within the sampling noise of the mean)
        assert!(lambda > 10.0 || spatial < 1.0 - 0.3 / (lambda * lambda), "λ = {lambda}: 3D {spatial}");
    }
}

/// A planar arc of 49 nodes, 1.1 mm, with 1 µm of noise in x and y: the length measured in its
/// plane is within 0.1 % of the arc, the 3D reading of the same frame (a third of its noise
/// estimate's coordinates empty) about 0.2 % off.
#[test]
fn a_planar_frame_is_measured_in_its_plane() {
    let mut g = Normal(5);
    let (n, l, r) = (49, 1.1e-3, 0.4e-3);
    let mut planar = Vec::new();
    let mut spatial = Vec::new();
    for _ in 0..50 {
        let x: Vec<Vector3<f64>> = (0..n)
            .map(|i| {
                let th = l / r * i as f64 / (n - 1) as f64;
                Vector3::new(r * th.sin() + 1e-6 * g.next(), r * (1.0 - th.cos()) + 1e-6 * g.next(), 0.0)
            })
            .collect();
        planar.push(FrameLength::of_in(&x, Some(&Vector3::z())).corrected_m / l - 1.0);
        spatial.push(FrameLength::of(&x).corrected_m / l - 1.0);
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    println!("planar {:.2e}, 3D reading {:.2e}", mean(&planar), mean(&spatial));
    assert!(mean(&planar).abs() < 1e-3, "{}", mean(&planar));
}
