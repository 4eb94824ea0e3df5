//! Lines of many points drawn with a bounded number of them: min–max decimation. A curve of
//! one value per frame of an hour-long recording (108,000 points) would make an SVG of megabytes
//! whose every pixel column holds dozens of points; [`min_max`] keeps, of each run of
//! consecutive points, the lowest and the highest (in their order), so that the envelope and
//! every spike of the curve are drawn as the full curve draws them.

/// Most points of a line after [`min_max`].
pub const MAX_LINE_POINTS: usize = 2000;

/// The points `(x, y)` of a curve, at most about `max_points` of them: unchanged if there are no
/// more; else the points split into runs of `⌈2 n / max_points⌉` consecutive ones, each
/// represented by its smallest and its largest finite `y` (one point if they are the same, the
/// run's first if none is finite), in the order they come.
pub fn min_max(x: &[f64], y: &[f64], max_points: usize) -> (Vec<f64>, Vec<f64>) {
    let n = x.len().min(y.len());
    if n <= max_points.max(2) {
        return (x[..n].to_vec(), y[..n].to_vec());
    }
    let run = (2 * n).div_ceil(max_points.max(2));
    let (mut xs, mut ys) = (Vec::with_capacity(max_points + 2), Vec::with_capacity(max_points + 2));
    for start in (0..n).step_by(run) {
        let range = start..(start + run).min(n);
        let finite = || range.clone().filter(|&i| y[i].is_finite());
        let lo = finite().min_by(|&a, &b| y[a].total_cmp(&y[b]));
        let hi = finite().max_by(|&a, &b| y[a].total_cmp(&y[b]));
        let keep = match (lo, hi) {
            (Some(a), Some(b)) if a == b => vec![a],
            (Some(a), Some(b)) => vec![a.min(b), a.max(b)],
            _ => vec![start],
        };
        for i in keep {
            xs.push(x[i]);
            ys.push(y[i]);
        }
    }
    (xs, ys)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_curves_are_kept_and_long_ones_keep_their_extremes() {
        let x: Vec<f64> = (0..10).map(f64::from).collect();
        assert_eq!(min_max(&x, &x, 20), (x.clone(), x.clone()));
        // 10,000 points of a slow wave with one spike up and one down
        let n = 10_000;
        let x: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let mut y: Vec<f64> = x.iter().map(|t| (t * 1e-3).sin()).collect();
        y[4321] = 50.0;
        y[777] = -50.0;
        y[9000] = f64::NAN;
        let (xd, yd) = min_max(&x, &y, 200);
        assert!(xd.len() <= 202 && xd.len() >= 150, "{}", xd.len());
        assert!(xd.windows(2).all(|w| w[0] < w[1]), "in order");
        assert!(yd.contains(&50.0) && yd.contains(&-50.0), "spikes kept");
        let (lo, hi) = yd.iter().fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(*v), b.max(*v)));
        assert_eq!((lo, hi), (-50.0, 50.0));
        // each kept point is a point of the curve
        assert!(xd.iter().zip(&yd).all(|(a, b)| y[*a as usize] == *b));
    }
}
