//! Smooth resampling of a centreline: a not-a-knot cubic spline through the given points,
//! re-parametrised by its own arc length, sampled at equal arc-length steps.
//!
//! Knots `t_i` are the cumulative chord lengths of the points. Each coordinate is the cubic
//! spline with second derivatives `M_i` from the standard system
//!
//! ```text
//! h_{i-1} M_{i-1} + 2 (h_{i-1} + h_i) M_i + h_i M_{i+1} = 6 [ (y_{i+1} - y_i)/h_i - (y_i - y_{i-1})/h_{i-1} ],
//! ```
//!
//! `i = 1 … n-2`, closed by the not-a-knot conditions (third derivative continuous at `t_1` and
//! `t_{n-2}`). Not-a-knot rather than natural ends: a natural spline forces zero curvature at
//! the head and tail, which the worm does not have. The arc length `S(t) = ∫ |r'(t)| dt` is
//! integrated with 5-point Gauss–Legendre on `SUBDIVISIONS` sub-intervals per knot interval and
//! inverted by safeguarded Newton, so the returned points are equally spaced in the spline's
//! arc length to about 1e-13 relative.
use nalgebra::Vector3;

/// Sub-intervals per knot interval of the arc-length table.
const SUBDIVISIONS: usize = 8;
/// Relative tolerance of the arc-length inversion.
const ARC_TOL: f64 = 1e-14;

/// Gauss–Legendre nodes on [0, 1] and weights (5 points, exact for degree 9).
const GAUSS: [(f64, f64); 5] = [
    (0.046_910_077_030_668_004, 0.118_463_442_528_094_54),
    (0.230_765_344_947_158_45, 0.239_314_335_249_683_23),
    (0.5, 0.284_444_444_444_444_45),
    (0.769_234_655_052_841_6, 0.239_314_335_249_683_23),
    (0.953_089_922_969_332, 0.118_463_442_528_094_54),
];

/// Not-a-knot cubic spline through points in 3D, parametrised by cumulative chord length.
#[derive(Debug, Clone)]
pub struct Spline {
    t: Vec<f64>,
    y: Vec<Vector3<f64>>,
    /// second derivatives at the knots
    m: Vec<Vector3<f64>>,
}

impl Spline {
    /// Spline through `points` (at least 2, consecutive points distinct). With 2 points it is
    /// the segment, with 3 the parabola through them.
    pub fn through(points: &[Vector3<f64>]) -> Self {
        let n = points.len();
        assert!(n >= 2, "a spline needs two points");
        let mut t = vec![0.0; n];
        for i in 1..n {
            let h = (points[i] - points[i - 1]).norm();
            assert!(h > 0.0, "coincident consecutive points {} and {i}", i - 1);
            t[i] = t[i - 1] + h;
        }
        let m = second_derivatives(&t, points);
        Spline { t, y: points.to_vec(), m }
    }

    /// Parameter range `[0, t_end]` (total chord length).
    pub fn t_end(&self) -> f64 {
        *self.t.last().expect("non-empty")
    }

    fn interval(&self, t: f64) -> usize {
        let k = self.t.partition_point(|&ti| ti <= t);
        k.clamp(1, self.t.len() - 1) - 1
    }

    /// Point r(t).
    pub fn point(&self, t: f64) -> Vector3<f64> {
        let i = self.interval(t);
        let h = self.t[i + 1] - self.t[i];
        let (a, b) = ((self.t[i + 1] - t) / h, (t - self.t[i]) / h);
        self.y[i] * a
            + self.y[i + 1] * b
            + (self.m[i] * (a * a * a - a) + self.m[i + 1] * (b * b * b - b)) * (h * h / 6.0)
    }

    /// Derivative r'(t).
    pub fn derivative(&self, t: f64) -> Vector3<f64> {
        let i = self.interval(t);
        let h = self.t[i + 1] - self.t[i];
        let (a, b) = ((self.t[i + 1] - t) / h, (t - self.t[i]) / h);
        (self.y[i + 1] - self.y[i]) / h
            + (self.m[i + 1] * (3.0 * b * b - 1.0) - self.m[i] * (3.0 * a * a - 1.0)) * (h / 6.0)
    }

    /// Arc length between parameters `t0 < t1` inside one knot interval (Gauss–Legendre).
    fn arc(&self, t0: f64, t1: f64) -> f64 {
        GAUSS.iter().map(|&(x, w)| w * self.derivative(t0 + x * (t1 - t0)).norm()).sum::<f64>() * (t1 - t0)
    }

    /// `n ≥ 2` points equally spaced in the spline's arc length, from the first to the last
    /// point, and the spline's total arc length.
    pub fn resample_by_arc_length(&self, n: usize) -> (Vec<Vector3<f64>>, f64) {
        assert!(n >= 2, "resampling needs two points");
        // Arc-length table on a fine grid of parameters.
        let mut grid = vec![0.0];
        for i in 0..self.t.len() - 1 {
            let h = (self.t[i + 1] - self.t[i]) / SUBDIVISIONS as f64;
            for k in 1..=SUBDIVISIONS {
                grid.push(if k == SUBDIVISIONS { self.t[i + 1] } else { self.t[i] + k as f64 * h });
            }
        }
        let mut cumulative = vec![0.0; grid.len()];
        for g in 1..grid.len() {
            cumulative[g] = cumulative[g - 1] + self.arc(grid[g - 1], grid[g]);
        }
        let total = *cumulative.last().expect("non-empty");
        let mut out = Vec::with_capacity(n);
        out.push(self.y[0]);
        for k in 1..n - 1 {
            let target = total * k as f64 / (n - 1) as f64;
            let g = cumulative.partition_point(|&c| c <= target).clamp(1, grid.len() - 1) - 1;
            let (lo, hi) = (grid[g], grid[g + 1]);
            let remaining = target - cumulative[g];
            // Newton on S(t) - S(lo) = remaining inside [lo, hi] (S is monotone), bisection fallback.
            let (mut a, mut b) = (lo, hi);
            let mut t = lo + (hi - lo) * remaining / (cumulative[g + 1] - cumulative[g]);
            for _ in 0..60 {
                let f = self.arc(lo, t) - remaining;
                if f.abs() <= ARC_TOL * total {
                    break;
                }
                if f > 0.0 {
                    b = t;
                } else {
                    a = t;
                }
                let next = t - f / self.derivative(t).norm();
                t = if next > a && next < b { next } else { 0.5 * (a + b) };
            }
            out.push(self.point(t));
        }
        out.push(*self.y.last().expect("non-empty"));
        (out, total)
    }
}

/// Second derivatives of the not-a-knot spline, per coordinate (tridiagonal after eliminating
/// `M_0` and `M_{n-1}` with the not-a-knot conditions; Thomas algorithm).
fn second_derivatives(t: &[f64], y: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    let n = t.len();
    let h: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    let r = |i: usize| ((y[i + 1] - y[i]) / h[i] - (y[i] - y[i - 1]) / h[i - 1]) * 6.0;
    match n {
        2 => return vec![Vector3::zeros(); 2],
        3 => {
            let m = r(1) / (3.0 * (h[0] + h[1]));
            return vec![m; 3];
        }
        _ => {}
    }
    // Unknowns M_1 … M_{n-2}; row k ↔ i = k + 1.
    let size = n - 2;
    let (mut lower, mut diag, mut upper) = (vec![0.0; size], vec![0.0; size], vec![0.0; size]);
    let mut rhs: Vec<Vector3<f64>> = (1..n - 1).map(r).collect();
    for k in 0..size {
        let i = k + 1;
        lower[k] = h[i - 1];
        diag[k] = 2.0 * (h[i - 1] + h[i]);
        upper[k] = h[i];
    }
    // M_0 = ((h0 + h1) M_1 - h0 M_2) / h1
    diag[0] += h[0] * (h[0] + h[1]) / h[1];
    upper[0] -= h[0] * h[0] / h[1];
    // M_{n-1} = ((h_{n-3} + h_{n-2}) M_{n-2} - h_{n-2} M_{n-3}) / h_{n-3}
    let (ha, hb) = (h[n - 3], h[n - 2]);
    diag[size - 1] += hb * (ha + hb) / ha;
    lower[size - 1] -= hb * hb / ha;
    // Thomas algorithm.
    for k in 1..size {
        let w = lower[k] / diag[k - 1];
        diag[k] -= w * upper[k - 1];
        let prev = rhs[k - 1];
        rhs[k] -= prev * w;
    }
    let mut inner = vec![Vector3::zeros(); size];
    inner[size - 1] = rhs[size - 1] / diag[size - 1];
    for k in (0..size - 1).rev() {
        inner[k] = (rhs[k] - inner[k + 1] * upper[k]) / diag[k];
    }
    let mut m = Vec::with_capacity(n);
    // size ≥ 2 here (n ≥ 4).
    m.push((inner[0] * (h[0] + h[1]) - inner[1] * h[0]) / h[1]);
    m.extend_from_slice(&inner);
    m.push((inner[size - 1] * (ha + hb) - inner[size - 2] * hb) / ha);
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spline_reproduces_a_cubic_exactly() {
        // Not-a-knot reproduces a cubic polynomial of the parameter, also on uneven knots.
        let g = |c: f64| Vector3::new(1.0 - c, c * c * 0.5, 0.2 * c * c * c - c);
        let cs = [0.0, 0.5, 0.7, 1.4, 2.0, 2.1];
        let pts: Vec<_> = cs.iter().map(|&c| g(c)).collect();
        let mut s = Spline::through(&pts);
        s.t = cs.to_vec();
        s.m = second_derivatives(&s.t, &pts);
        for k in 0..=50 {
            let c = 2.1 * k as f64 / 50.0;
            assert!((s.point(c) - g(c)).norm() < 1e-12, "c = {c}: {}", (s.point(c) - g(c)).norm());
        }
    }

    #[test]
    fn straight_points_resample_to_equal_steps() {
        let pts: Vec<_> = [0.0, 0.1, 0.35, 0.4, 1.0].iter().map(|&z| Vector3::new(0.0, 0.0, z)).collect();
        let (out, total) = Spline::through(&pts).resample_by_arc_length(11);
        assert!((total - 1.0).abs() < 1e-14);
        for (k, p) in out.iter().enumerate() {
            assert!((p - Vector3::new(0.0, 0.0, k as f64 / 10.0)).norm() < 1e-13, "{k}: {p}");
        }
    }
}
