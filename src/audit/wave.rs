//! The propagation of a curvature wave along the body (§6, Figs. 17, 23, 25: "a bending (κ1
//! and κ2) wave can be seen propagating from the worm's head to the tail"), measured on a
//! kymograph `k(s, t)` (frames × positions along the body, s = 0 the head) in time windows, so
//! that a reversal of the wave counts.
//!
//! In each window of [`WINDOW_FRAMES`] frames, neighbouring probes `s_j` and `s_j + Δs`
//! (`Δs` = [`PROBE_SPACING`] body lengths, from [`PROBE_FIRST`] to [`PROBE_LAST`], values
//! interpolated linearly between the kymograph's positions) give, after removing each probe's
//! mean over the window, the normalised cross-correlation
//!
//! ```text
//! c_j(τ) = Σ_t k(s_j, t) k(s_j + Δs, t + τ) / √(Σ_t k(s_j, t)² Σ_t k(s_j + Δs, t + τ)²)
//! ```
//!
//! over the frames where both are in the window, averaged over the pairs: `C(τ)`, for
//! `|τ| ≤ W/4`. The lag `τ*` is the maximum of `C` nearest to τ = 0 among those within
//! [`PEAK_TOLERANCE`] of the largest (a periodic wave has a peak every period: the nearest one
//! is the wave's, as long as a wave crosses `Δs` in less than half a period), refined by the
//! parabola through its neighbours. The window's **coherence** is `C(τ*)`: 1 for a wave that
//! keeps its shape between neighbouring probes, near 0 for none. Its **direction** is head → tail
//! when `τ* > 0` (the probe further from the head sees the shape later), tail → head when
//! `τ* < 0`, and none when the coherence is below [`MIN_COHERENCE`] (no clear wave) or
//! `|τ*| <` [`MIN_LAG_FRAMES`] (the probes move together: a standing wave, or one faster than
//! the frames resolve). Its **speed** is `Δs / τ*` body lengths per frame.
//!
//! The clip's **clarity** is the mean over its windows of the coherence of the windows with a
//! direction (0 for a window without one): 1 for a wave that propagates clearly in every
//! window, 0 when none does (§6: "the wave propagation is clearer", "no longer apparent").
//!
//! ## References
//! [R1] of the crate docs: §6, Figs. 17, 23, 25.

/// Frames of a time window (4.64 s at the substitute's 0.04 s; a clip shorter than two windows
/// is one window).
pub const WINDOW_FRAMES: usize = 116;
/// Fewest frames a window may have: shorter clips give no windows.
pub const MIN_WINDOW_FRAMES: usize = 16;
/// Distance between neighbouring probes [body lengths].
pub const PROBE_SPACING: f64 = 0.05;
/// First probe [body lengths from the head]: the curvature of the first elements is the
/// least reliable part of a reconstruction (the end elements of `engine::metrics::INNER_SKIP_ELEMENTS`).
pub const PROBE_FIRST: f64 = 0.1;
/// Last probe [body lengths from the head].
pub const PROBE_LAST: f64 = 0.9;
/// Peaks of `C` within this of the largest count as the wave's (the one nearest τ = 0 wins).
pub const PEAK_TOLERANCE: f64 = 0.1;
/// Coherence below which a window has no clear wave (the bar of a "clear" wave).
pub const MIN_COHERENCE: f64 = 0.5;
/// Lags below this [frames] are no propagation.
pub const MIN_LAG_FRAMES: f64 = 0.5;

/// Which way a window's wave runs along the body.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    /// from s = 0 (the head) towards s = L
    HeadToTail,
    TailToHead,
    /// no clear wave, or the probes move together
    None,
}

impl Direction {
    pub fn as_str(&self) -> &'static str {
        match self {
            Direction::HeadToTail => "head→tail",
            Direction::TailToHead => "tail→head",
            Direction::None => "none",
        }
    }
}

/// The wave of one time window.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WindowWave {
    /// first frame of the window (index into the kymograph) and its number of frames
    pub first: usize,
    pub frames: usize,
    /// τ* [frames]: > 0 when the wave runs from the head towards the tail
    pub lag_frames: f64,
    /// C(τ*) in [−1, 1]
    pub coherence: f64,
    pub direction: Direction,
}

impl WindowWave {
    /// Speed [body lengths per frame], > 0 from the head to the tail; `None` without a direction.
    pub fn speed_body_per_frame(&self) -> Option<f64> {
        (self.direction != Direction::None).then(|| PROBE_SPACING / self.lag_frames)
    }
}

/// The wave of a kymograph in its windows (module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct Propagation {
    pub windows: Vec<WindowWave>,
}

impl Propagation {
    /// Share of the windows whose wave runs `d`.
    pub fn share(&self, d: Direction) -> f64 {
        let n = self.windows.iter().filter(|w| w.direction == d).count();
        n as f64 / self.windows.len().max(1) as f64
    }
    /// Mean over the windows of the coherence of those with a direction (0 for the others).
    pub fn clarity(&self) -> f64 {
        let sum: f64 = self.windows.iter().filter(|w| w.direction != Direction::None).map(|w| w.coherence).sum();
        sum / self.windows.len().max(1) as f64
    }
    /// Median speed magnitude over the windows with a direction [body lengths per frame].
    pub fn median_speed_body_per_frame(&self) -> Option<f64> {
        let mut v: Vec<f64> = self.windows.iter().filter_map(|w| w.speed_body_per_frame()).map(f64::abs).collect();
        v.sort_by(f64::total_cmp);
        (!v.is_empty()).then(|| v[v.len() / 2])
    }
    /// Share of the windows whose direction is that of `other`'s window at the same frames
    /// (over the windows both have).
    pub fn agreement(&self, other: &Propagation) -> f64 {
        let n = self.windows.len().min(other.windows.len());
        let same = self.windows.iter().zip(&other.windows).filter(|(a, b)| a.direction == b.direction).count();
        same as f64 / n.max(1) as f64
    }
    /// The directions of the windows, one letter each: `>` head→tail, `<` tail→head, `.` none.
    pub fn letters(&self) -> String {
        self.windows
            .iter()
            .map(|w| match w.direction {
                Direction::HeadToTail => '>',
                Direction::TailToHead => '<',
                Direction::None => '.',
            })
            .collect()
    }
}

/// The windows of a clip of `nf` frames: [`WINDOW_FRAMES`] each, the last one taking the rest
/// when it is shorter than half a window; a clip of fewer than two windows is one window;
/// none below [`MIN_WINDOW_FRAMES`].
pub fn windows(nf: usize) -> Vec<(usize, usize)> {
    if nf < MIN_WINDOW_FRAMES {
        return Vec::new();
    }
    if nf < 2 * WINDOW_FRAMES {
        return vec![(0, nf)];
    }
    let mut out: Vec<(usize, usize)> = (0..nf / WINDOW_FRAMES).map(|i| (i * WINDOW_FRAMES, WINDOW_FRAMES)).collect();
    let rest = nf % WINDOW_FRAMES;
    if rest >= WINDOW_FRAMES / 2 {
        out.push((nf - rest, rest));
    } else if let Some(last) = out.last_mut() {
        last.1 += rest;
    }
    out
}

/// The kymograph `k[frame][position]` at body position `p` [body lengths], linear between the
/// positions `s` [body lengths, increasing]; `None` outside them.
fn probe(k: &[Vec<f64>], s: &[f64], p: f64) -> Option<Vec<f64>> {
    let i = s.windows(2).position(|w| w[0] <= p && p <= w[1])?;
    let u = (p - s[i]) / (s[i + 1] - s[i]);
    Some(k.iter().map(|row| row[i] * (1.0 - u) + row[i + 1] * u).collect())
}

/// Normalised cross-correlation of the centred `a` and `b` at lag `tau` over their overlap
/// (`Σ a(t) b(t + τ)`); 0 when either is flat there.
fn correlation(a: &[f64], b: &[f64], tau: i64) -> f64 {
    let (mut ab, mut aa, mut bb) = (0.0, 0.0, 0.0);
    for (t, x) in a.iter().enumerate() {
        let u = t as i64 + tau;
        if u < 0 || u >= b.len() as i64 {
            continue;
        }
        let y = b[u as usize];
        ab += x * y;
        aa += x * x;
        bb += y * y;
    }
    if aa > 0.0 && bb > 0.0 {
        ab / (aa * bb).sqrt()
    } else {
        0.0
    }
}

fn centred(v: &[f64]) -> Vec<f64> {
    let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
    v.iter().map(|x| x - mean).collect()
}

/// The wave of one window: `probes` are the probe signals over the window.
fn window_wave(probes: &[Vec<f64>], first: usize) -> WindowWave {
    let frames = probes.first().map_or(0, Vec::len);
    let max_lag = (frames / 4) as i64;
    let centred: Vec<Vec<f64>> = probes.iter().map(|p| centred(p)).collect();
    let pairs = centred.len().saturating_sub(1).max(1) as f64;
    let c: Vec<f64> = (-max_lag..=max_lag)
        .map(|tau| centred.windows(2).map(|w| correlation(&w[0], &w[1], tau)).sum::<f64>() / pairs)
        .collect();
    let top = c.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    // local maxima within the tolerance of the largest, the one nearest τ = 0
    let peak = (0..c.len())
        .filter(|&i| c[i] >= top - PEAK_TOLERANCE)
        .filter(|&i| (i == 0 || c[i] >= c[i - 1]) && (i + 1 == c.len() || c[i] >= c[i + 1]))
        .min_by_key(|&i| (i as i64 - max_lag).abs())
        .unwrap_or(max_lag as usize);
    // the parabola through the peak and its neighbours
    let shift = if peak > 0 && peak + 1 < c.len() {
        let (l, m, r) = (c[peak - 1], c[peak], c[peak + 1]);
        let d = l - 2.0 * m + r;
        if d < 0.0 {
            (0.5 * (l - r) / d).clamp(-0.5, 0.5)
        } else {
            0.0
        }
    } else {
        0.0
    };
    let lag = peak as f64 - max_lag as f64 + shift;
    let coherence = c.get(peak).copied().unwrap_or(0.0).min(1.0);
    let direction = if coherence < MIN_COHERENCE || lag.abs() < MIN_LAG_FRAMES {
        Direction::None
    } else if lag > 0.0 {
        Direction::HeadToTail
    } else {
        Direction::TailToHead
    };
    WindowWave { first, frames, lag_frames: lag, coherence, direction }
}

/// The wave of the kymograph `k[frame][position]` at the positions `s` [body lengths from the
/// head, increasing], in the windows of [`windows`] (module documentation).
pub fn propagation(k: &[Vec<f64>], s: &[f64]) -> Propagation {
    let mut probes: Vec<Vec<f64>> = Vec::new();
    let mut p = PROBE_FIRST;
    while p <= PROBE_LAST + 1e-9 {
        if let Some(v) = probe(k, s, p) {
            probes.push(v);
        }
        p += PROBE_SPACING;
    }
    let windows = windows(k.len())
        .into_iter()
        .map(|(first, n)| {
            let cut: Vec<Vec<f64>> = probes.iter().map(|v| v[first..first + n].to_vec()).collect();
            window_wave(&cut, first)
        })
        .collect();
    Propagation { windows }
}
