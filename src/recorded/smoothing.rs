//! The generic baseline a reconstruction of noisy data must beat: a cubic smoothing spline of
//! each coordinate against arc length (the nodes' equal spacing, [`SmoothingSpline::fit_uniform`],
//! or the chord length of the noisy points, [`SmoothingSpline::fit`]), its smoothing chosen
//! by generalised cross-validation (GCV), no physics, no time coupling (`docs/noise.md`, N4).
//!
//! For knots `t_0 < … < t_{n−1}` (the cumulative chord lengths of the points) and values `y_i`
//! of one coordinate, the smoothing spline `g` minimises (Reinsch 1967; Green & Silverman 1994,
//! §2.3)
//!
//! ```text
//!   Σ_i (y_i − g(t_i))² + p ∫ g''(t)² dt,
//! ```
//!
//! a natural cubic spline whose knot values are `ĝ = (I + p K)⁻¹ y`, `K = Q R⁻¹ Qᵀ`, with `Q`
//! (n × (n−2)) the second-difference matrix `Q_{i−1,i} = 1/h_{i−1}`, `Q_{i,i} = −1/h_{i−1} − 1/h_i`,
//! `Q_{i+1,i} = 1/h_i` and `R` ((n−2) × (n−2)) tridiagonal, `R_{ii} = (h_{i−1} + h_i)/3`,
//! `R_{i,i+1} = h_i/6`; its second derivatives at the interior knots are `γ = R⁻¹ Qᵀ ĝ`. With
//! `K = U D Uᵀ` (once per frame) and `z = Uᵀ y`, every `p` costs O(n):
//!
//! ```text
//!   RSS(p) = Σ_k (p d_k / (1 + p d_k))² z_k²,   tr(I − A(p)) = Σ_k p d_k / (1 + p d_k),
//!   GCV(p) = n RSS(p) / tr(I − A(p))²,
//! ```
//!
//! minimised over `log p` on a grid and refined by golden section. Each coordinate gets its own
//! `p` (the smoothing is chosen per coordinate, as a generic tool would).
use nalgebra::{DMatrix, DVector, SymmetricEigen, Vector3};

/// Grid points of the GCV search in `log p`.
const GRID: usize = 121;
/// Golden-section refinements after the grid.
const GOLDEN_STEPS: usize = 40;

/// A natural cubic spline in 3D: knot values and second derivatives per coordinate.
#[derive(Debug, Clone)]
pub struct SmoothingSpline {
    t: Vec<f64>,
    g: Vec<Vector3<f64>>,
    gamma: Vec<Vector3<f64>>,
    /// the chosen smoothing parameter per coordinate [m³]
    pub p: Vector3<f64>,
}

/// The eigen-decomposition of `K` for one set of knots, shared by the three coordinates.
struct Smoother {
    h: Vec<f64>,
    u: DMatrix<f64>,
    d: DVector<f64>,
}

impl Smoother {
    fn new(t: &[f64]) -> Self {
        let n = t.len();
        let h: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        let m = n - 2;
        let mut q = DMatrix::zeros(n, m);
        let mut r = DMatrix::zeros(m, m);
        for j in 0..m {
            let i = j + 1;
            q[(i - 1, j)] = 1.0 / h[i - 1];
            q[(i, j)] = -1.0 / h[i - 1] - 1.0 / h[i];
            q[(i + 1, j)] = 1.0 / h[i];
            r[(j, j)] = (h[i - 1] + h[i]) / 3.0;
            if j + 1 < m {
                r[(j, j + 1)] = h[i] / 6.0;
                r[(j + 1, j)] = h[i] / 6.0;
            }
        }
        // R is symmetric positive definite (diagonally dominant): Cholesky.
        let rinv_qt = r.cholesky().expect("R is diagonally dominant").solve(&q.transpose());
        let k = &q * rinv_qt;
        let k = (&k + k.transpose()) * 0.5;
        let eig = SymmetricEigen::new(k);
        let d = eig.eigenvalues.map(|v| v.max(0.0));
        Smoother { h, u: eig.eigenvectors, d }
    }

    /// [`Smoother::new`] of the knots `t`, kept per thread for the last knots asked for: the
    /// frames of one recording share their knots ([`SmoothingSpline::fit_uniform`]), so the
    /// O(n³) eigen-decomposition runs once per recording, not once per frame (the same numbers).
    fn cached(t: &[f64]) -> std::rc::Rc<Smoother> {
        thread_local! {
            static LAST: std::cell::RefCell<Option<(Vec<f64>, std::rc::Rc<Smoother>)>> = const { std::cell::RefCell::new(None) };
        }
        LAST.with(|last| {
            let mut last = last.borrow_mut();
            if let Some((_, s)) = last.as_ref().filter(|(knots, _)| knots.as_slice() == t) {
                return s.clone();
            }
            let s = std::rc::Rc::new(Smoother::new(t));
            *last = Some((t.to_vec(), s.clone()));
            s
        })
    }

    fn gcv(&self, z: &DVector<f64>, p: f64) -> f64 {
        let (mut rss, mut tr) = (0.0, 0.0);
        for (dk, zk) in self.d.iter().zip(z.iter()) {
            let a = p * dk / (1.0 + p * dk);
            rss += a * a * zk * zk;
            tr += a;
        }
        self.d.len() as f64 * rss / (tr * tr)
    }

    /// The GCV-optimal `p` for the values whose projection is `z`.
    fn choose(&self, z: &DVector<f64>) -> f64 {
        let positive: Vec<f64> = self.d.iter().copied().filter(|&v| v > 1e-12 * self.d.max()).collect();
        let (dmin, dmax) = positive.iter().fold((f64::INFINITY, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
        let (lo, hi) = ((1e-4 / dmax).ln(), (1e4 / dmin).ln());
        let at = |k: usize| lo + (hi - lo) * k as f64 / (GRID - 1) as f64;
        let best =
            (0..GRID).min_by(|&a, &b| self.gcv(z, at(a).exp()).total_cmp(&self.gcv(z, at(b).exp()))).unwrap_or(0);
        let (mut a, mut b) = (at(best.saturating_sub(1)), at((best + 1).min(GRID - 1)));
        let phi = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..GOLDEN_STEPS {
            let (c, d) = (b - phi * (b - a), a + phi * (b - a));
            if self.gcv(z, c.exp()) < self.gcv(z, d.exp()) {
                b = d;
            } else {
                a = c;
            }
        }
        (0.5 * (a + b)).exp()
    }

    /// Knot values `ĝ` and interior second derivatives for the values `y` at smoothing `p`.
    fn smooth(&self, y: &DVector<f64>, p: f64) -> (DVector<f64>, Vec<f64>) {
        let z = self.u.transpose() * y;
        let scaled = DVector::from_iterator(z.len(), z.iter().zip(self.d.iter()).map(|(zk, dk)| zk / (1.0 + p * dk)));
        let g = &self.u * scaled;
        // γ from the natural-spline system R γ = Qᵀ g (interior knots), γ = 0 at the ends
        let n = g.len();
        let h = &self.h;
        let m = n - 2;
        let mut diag: Vec<f64> = (1..=m).map(|i| (h[i - 1] + h[i]) / 3.0).collect();
        let mut rhs: Vec<f64> = (1..=m).map(|i| (g[i + 1] - g[i]) / h[i] - (g[i] - g[i - 1]) / h[i - 1]).collect();
        for j in 1..m {
            let w = (h[j] / 6.0) / diag[j - 1];
            diag[j] -= w * h[j] / 6.0;
            rhs[j] -= w * rhs[j - 1];
        }
        let mut gamma = vec![0.0; n];
        for j in (0..m).rev() {
            let upper = if j + 1 < m { h[j + 1] / 6.0 * gamma[j + 2] } else { 0.0 };
            gamma[j + 1] = (rhs[j] - upper) / diag[j];
        }
        (g, gamma)
    }
}

impl SmoothingSpline {
    /// The GCV smoothing spline of `points` (at least 4, finite) parametrised by their
    /// cumulative chord length (consecutive points distinct). `None` when the points do not
    /// allow one.
    pub fn fit(points: &[Vector3<f64>]) -> Option<Self> {
        let mut t = vec![0.0; points.len()];
        for i in 1..points.len() {
            t[i] = t[i - 1] + (points[i] - points[i - 1]).norm();
        }
        Self::fit_at(points, t)
    }

    /// The GCV smoothing spline of `points` at nodes equally spaced in arc length over a body
    /// of length `length_m` [m] (a tracker's output: knots `t_i = i L/(n − 1)`). Noise of the
    /// order of the node spacing makes the chord-length parameter of [`Self::fit`] a poor arc
    /// length (σ = 3 µm on 128 nodes of a 1 mm body: curvature errors of 20–30 against 0.3
    /// with these knots).
    pub fn fit_uniform(points: &[Vector3<f64>], length_m: f64) -> Option<Self> {
        let n = points.len().max(2);
        Self::fit_at(points, (0..points.len()).map(|i| length_m * i as f64 / (n - 1) as f64).collect())
    }

    fn fit_at(points: &[Vector3<f64>], t: Vec<f64>) -> Option<Self> {
        let n = points.len();
        if n < 4
            || points.iter().any(|p| !p.iter().all(|v| v.is_finite()))
            || t.windows(2).any(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
        {
            return None;
        }
        let s = Smoother::cached(&t);
        let mut g = vec![Vector3::zeros(); n];
        let mut gamma = vec![Vector3::zeros(); n];
        let mut p = Vector3::zeros();
        for c in 0..3 {
            let y = DVector::from_iterator(n, points.iter().map(|q| q[c]));
            let pc = s.choose(&(s.u.transpose() * &y));
            let (gc, gam) = s.smooth(&y, pc);
            for i in 0..n {
                g[i][c] = gc[i];
                gamma[i][c] = gam[i];
            }
            p[c] = pc;
        }
        Some(SmoothingSpline { t, g, gamma, p })
    }

    /// The smoothed points (the spline at its knots) [m].
    pub fn knot_values(&self) -> &[Vector3<f64>] {
        &self.g
    }

    /// Parameter range `[0, t_end]` (the chord length of the noisy points) [m].
    pub fn t_end(&self) -> f64 {
        *self.t.last().unwrap_or(&0.0)
    }

    /// First and second derivatives with respect to the parameter at `t`.
    pub fn derivatives(&self, t: f64) -> (Vector3<f64>, Vector3<f64>) {
        let i = match self.t.partition_point(|&k| k <= t) {
            0 => 0,
            k => (k - 1).min(self.t.len() - 2),
        };
        let h = self.t[i + 1] - self.t[i];
        let (a, b) = ((self.t[i + 1] - t) / h, (t - self.t[i]) / h);
        let (m0, m1) = (self.gamma[i], self.gamma[i + 1]);
        let d1 = (self.g[i + 1] - self.g[i]) / h - m0 * ((3.0 * a * a - 1.0) * h / 6.0)
            + m1 * ((3.0 * b * b - 1.0) * h / 6.0);
        let d2 = m0 * a + m1 * b;
        (d1, d2)
    }

    /// The curvature `|r' × r''| / |r'|³` of the spline at `t` [1/m].
    pub fn curvature(&self, t: f64) -> f64 {
        let (d1, d2) = self.derivatives(t);
        d1.cross(&d2).norm() / d1.norm().powi(3)
    }

    /// The curvature at the midpoints of `elements` equal parameter intervals of `[0, t_end]`
    /// (the mesh's element midpoints, the parameter standing in for the arc length) [1/m].
    pub fn element_curvatures(&self, elements: usize) -> Vec<f64> {
        let h = self.t_end() / elements as f64;
        (0..elements).map(|e| self.curvature((e as f64 + 0.5) * h)).collect()
    }
}

/// A frame's noise level over its node spacing above which its chart axis and its data guess
/// are taken from its smoothed centreline ([`frame_geometry`], `docs/noise.md` N8).
pub const NOISY_GEOMETRY: f64 = 0.1;

/// The centreline a frame's chart axis (`sequence::frame_chart`) and data guess (`sequence::data_frame_guess`)
/// are taken from (`docs/noise.md` N8): the data `x`, or, where their noise level
/// ([`crate::recorded::fit::noise_level`]) exceeds [`NOISY_GEOMETRY`] times the node spacing of a
/// rod of `length_m`, the knot values of their GCV smoothing spline (`solve::smoothing`). A
/// noisy chord's direction is noise: at σ = 10 µm on 128 nodes of 1 mm (h = 7.9 µm) the raw
/// tangents point anywhere, no chart axis keeps away from all of them, and the guess's angles
/// are noise. The tracking term of (41) still sees the data themselves.
pub fn frame_geometry(x: &[Vector3<f64>], length_m: f64) -> std::borrow::Cow<'_, [Vector3<f64>]> {
    let h = length_m / (x.len().max(2) - 1) as f64;
    if super::fit::noise_level(x) <= NOISY_GEOMETRY * h {
        return std::borrow::Cow::Borrowed(x);
    }
    match SmoothingSpline::fit_uniform(x, length_m) {
        Some(s) => std::borrow::Cow::Owned(s.knot_values().to_vec()),
        None => std::borrow::Cow::Borrowed(x),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(n: usize, radius: f64, arc: f64) -> Vec<Vector3<f64>> {
        (0..n)
            .map(|i| {
                let th = arc * i as f64 / (n - 1) as f64 / radius;
                Vector3::new(radius * th.sin(), radius * (1.0 - th.cos()), 0.0)
            })
            .collect()
    }

    /// Exact data on a circle: the GCV choice smooths little, and the curvature away from the
    /// natural ends (where g'' = 0 is imposed) is the circle's 1/R to discretisation accuracy.
    #[test]
    fn recovers_the_curvature_of_a_circle() {
        let pts = circle(65, 0.5e-3, 1e-3);
        let s = SmoothingSpline::fit(&pts).expect("fit");
        let k = s.element_curvatures(64);
        for (e, v) in k.iter().enumerate().skip(10).take(44) {
            assert!((v * 0.5e-3 - 1.0).abs() < 2e-3, "element {e}: {v}");
        }
    }

    /// Noisy straight line: the GCV choice removes the noise, the residual of the knot values
    /// is about the noise level and the curvature is far below that of the noise polyline.
    #[test]
    fn smooths_noise_on_a_line() {
        let n = 129;
        let sigma = 1e-6;
        let mut state = 12345u64;
        let mut gauss = || {
            // Box–Muller on a xorshift stream
            let mut u = || {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                (state >> 11) as f64 / (1u64 << 53) as f64
            };
            let (a, b) = (u().max(1e-300), u());
            (-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos()
        };
        let pts: Vec<Vector3<f64>> =
            (0..n).map(|i| Vector3::new(1e-3 * i as f64 / (n - 1) as f64, sigma * gauss(), sigma * gauss())).collect();
        let s = SmoothingSpline::fit(&pts).expect("fit");
        let worst = s.element_curvatures(n - 1).into_iter().fold(0.0, f64::max);
        // the noise polyline's turning angle per node is ~ 2σ/h = 0.26 rad over h = 7.8 µm
        let h = 1e-3 / (n - 1) as f64;
        assert!(worst < 0.01 * 2.0 * sigma / (h * h), "worst curvature {worst}");
    }
}
