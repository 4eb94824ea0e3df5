//! The text of every figure: fonts in px at the saved size (never below [`MIN_TEXT_PX`]), tick
//! labels without round-off, round ticks, titles that fit their strip, wrapped legend entries.

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// The smallest text of any figure [px at the saved size].
pub const MIN_TEXT_PX: u32 = 13;
/// The sans-serif font whose text is `px` px high in the saved SVG (plotters writes a size
/// `s` as `s / 1.24` px).
pub(crate) fn font(px: u32) -> FontDesc<'static> {
    ("sans-serif", px as f64 * 1.24).into_font()
}
/// Panel titles at most this size [px]; a long title is set smaller, down to [`MIN_TEXT_PX`].
pub(crate) const TITLE_PX: u32 = 19;
/// Tick labels [px].
pub(crate) const TICK_PX: u32 = 15;
/// Axis descriptions [px].
pub(crate) const DESC_PX: u32 = 16;
/// Legend entries [px].
pub(crate) const LEGEND_PX: u32 = 14;
/// Height of a panel's title strip [px].
pub(crate) const TITLE_STRIP: u32 = 34;
/// Average advance of a sans-serif character as a fraction of its size (for layout).
pub(crate) const CHAR_WIDTH: f64 = 0.56;

/// Compact tick labels: plain decimals for moderate magnitudes, else `1.5e-3`.
pub(crate) fn format_tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".to_string()
    } else if (1e-3..1e4).contains(&a) {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        let s = format!("{v:.2e}");
        match s.split_once('e') {
            Some((m, e)) => format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.')),
            None => s,
        }
    }
}

/// A tick label on a linear axis of width `span`: a value within 1e-9 `span` of 0 (the
/// round-off of a tick computed as a sum) is "0".
pub(crate) fn axis_tick(v: f64, span: f64) -> String {
    format_tick(if v.abs() <= 1e-9 * span.abs() { 0.0 } else { v })
}

/// About `n` round ticks (1, 2, 2.5 or 5 × 10^k apart) within `[lo, hi]`; `[lo]` for an empty range.
pub(crate) fn nice_ticks(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    if !lo.is_finite() || !hi.is_finite() || hi <= lo {
        return vec![lo];
    }
    let raw = (hi - lo) / n.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0].iter().map(|m| m * mag).find(|s| *s >= raw).unwrap_or(10.0 * mag);
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    (first..=last).map(|k| if k == 0 { 0.0 } else { k as f64 * step }).collect()
}

/// The largest font size ≤ `max` (and ≥ [`MIN_TEXT_PX`]) at which `text` fits in `width` px.
pub(crate) fn fit_font(text: &str, width: u32, max: u32) -> u32 {
    let chars = text.chars().count().max(1) as f64;
    ((width as f64 / (CHAR_WIDTH * chars)).floor() as u32).clamp(MIN_TEXT_PX, max)
}

/// `text` broken at spaces into lines of at most `chars` characters (a longer word is kept
/// whole).
pub(crate) fn wrap(text: &str, chars: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in text.split(' ') {
        match lines.last_mut() {
            Some(l) if l.chars().count() + 1 + word.chars().count() <= chars => {
                l.push(' ');
                l.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    lines
}

/// Left-aligned, vertically centred text of `px` px.
pub(crate) fn text_style(px: u32) -> TextStyle<'static> {
    TextStyle::from(font(px)).pos(Pos::new(HPos::Left, VPos::Center))
}
