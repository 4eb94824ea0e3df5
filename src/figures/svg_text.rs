//! The text of an SVG as plotters writes it, each element with the box it covers (estimated
//! from its anchor, its size and [`CHAR_WIDTH`]): for the tests of the figures' layout (no text
//! runs into another, none is cut off at the figure's edge).

use super::figure_text::CHAR_WIDTH;

/// One text element: its text and the box it covers [px], `x = (left, right)`,
/// `y = (top, bottom)`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TextBox {
    pub text: String,
    pub x: (f64, f64),
    pub y: (f64, f64),
}

/// The value of attribute `name` in the tag `tag`.
fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    tag.split(&format!(" {name}=\"")).nth(1)?.split('"').next()
}

/// Every horizontal text element of `svg` with its box (rotated ones, the axis descriptions,
/// are left out).
pub(crate) fn texts(svg: &str) -> Vec<TextBox> {
    let mut out = Vec::new();
    for part in svg.split("<text").skip(1) {
        let Some((tag, rest)) = part.split_once('>') else { continue };
        if tag.contains("transform=") {
            continue;
        }
        let raw = rest.split("</text>").next().unwrap_or("").trim();
        let text = [("&lt;", "<"), ("&gt;", ">"), ("&quot;", "\""), ("&apos;", "'"), ("&amp;", "&")]
            .iter()
            .fold(raw.to_string(), |t, (entity, c)| t.replace(entity, c));
        let num = |n: &str| attr(tag, n).and_then(|v| v.parse::<f64>().ok());
        let (Some(x), Some(y), Some(size)) = (num("x"), num("y"), num("font-size")) else { continue };
        let width = text.chars().count() as f64 * CHAR_WIDTH * size;
        let left = match attr(tag, "text-anchor") {
            Some("middle") => x - width / 2.0,
            Some("end") => x - width,
            _ => x,
        };
        let top = match attr(tag, "dy") {
            Some("0.76em") => y,
            Some("-0.5ex") => y - size,
            _ => y - size / 2.0,
        };
        out.push(TextBox { text, x: (left, left + width), y: (top, top + size) });
    }
    out
}

/// The pairs of texts of `svg` whose boxes overlap by more than a pixel each way.
pub(crate) fn overlaps(svg: &str) -> Vec<(String, String)> {
    let boxes = texts(svg);
    let mut pairs = Vec::new();
    for (i, a) in boxes.iter().enumerate() {
        for b in &boxes[i + 1..] {
            let cross = |p: (f64, f64), q: (f64, f64)| p.0.max(q.0) + 1.0 < p.1.min(q.1);
            if cross(a.x, b.x) && cross(a.y, b.y) {
                pairs.push((a.text.clone(), b.text.clone()));
            }
        }
    }
    pairs
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn boxes_follow_the_anchor_and_overlaps_are_found() {
        let svg = "<svg><text x=\"100\" y=\"50\" dy=\"0.76em\" text-anchor=\"middle\" font-size=\"10\">\nabcd\n</text>\
                   <text x=\"110\" y=\"55\" dy=\"0.5ex\" text-anchor=\"start\" font-size=\"10\">\nxy\n</text>\
                   <text x=\"300\" y=\"55\" dy=\"0.5ex\" text-anchor=\"end\" font-size=\"10\">\nf&apos;r\n</text>\
                   <text x=\"0\" y=\"0\" dy=\"0.5ex\" text-anchor=\"start\" font-size=\"10\" transform=\"rotate(270, 0, 0)\">\nr\n</text></svg>";
        let t = texts(svg);
        assert_eq!(t.len(), 3, "the rotated text is left out");
        let w = 4.0 * CHAR_WIDTH * 10.0;
        assert_eq!(t[0], TextBox { text: "abcd".into(), x: (100.0 - w / 2.0, 100.0 + w / 2.0), y: (50.0, 60.0) });
        assert_eq!(t[1].y, (50.0, 60.0));
        assert_eq!((t[2].text.as_str(), t[2].x.1), ("f'r", 300.0), "entities read back");
        assert_eq!(overlaps(svg), vec![("abcd".to_string(), "xy".to_string())]);
    }
}
