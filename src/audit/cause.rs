//! The cause of a failed check, from the spec's `cause` text and the measured points: a cause
//! that names where along the grid the check starts to fail takes that point from the run,
//! not from a number written by hand, so it cannot contradict the row's numbers. The
//! placeholders, over the check's points in the order of the grid:
//! - `{first_failing}`: the first point where the check does not hold;
//! - `{last_holding}`: the last point before it where it holds;
//! - `{first_not_stalled}`: the first point that neither holds nor stalls at the paper's
//!   stopping rule (it runs to its iteration limit or diverges).

/// The placeholders a cause may hold.
pub const PLACEHOLDERS: [&str; 3] = ["{first_failing}", "{last_holding}", "{first_not_stalled}"];

/// One point of a check, for its cause.
#[derive(Clone, Debug, PartialEq)]
pub struct PointState {
    /// the point's grid value as the report writes it (`1e-6`)
    pub value: String,
    /// the check holds at this point
    pub holds: bool,
    /// it stopped at the paper's stopping rule without a certified solution
    pub stalled: bool,
}

/// What a placeholder stands for when no point of the grid is one.
pub const NONE_ON_GRID: &str = "(no point of this grid)";

/// `template` with its placeholders replaced by the grid values of `points`.
pub fn fill(template: &str, points: &[PointState]) -> String {
    let first_failing = points.iter().position(|p| !p.holds);
    let last_holding = points[..first_failing.unwrap_or(points.len())].iter().rev().find(|p| p.holds);
    let first_not_stalled = points.iter().find(|p| !p.holds && !p.stalled);
    let text = |p: Option<&PointState>| p.map_or(NONE_ON_GRID.to_string(), |p| p.value.clone());
    template
        .replace("{first_failing}", &text(first_failing.map(|i| &points[i])))
        .replace("{last_holding}", &text(last_holding))
        .replace("{first_not_stalled}", &text(first_not_stalled))
}

/// The first `{…}` of `text` that is not a placeholder, if any.
pub fn unknown_placeholder(text: &str) -> Option<String> {
    let mut rest = text;
    while let Some(i) = rest.find('{') {
        let end = rest[i..].find('}').map_or(rest.len(), |j| i + j + 1);
        let word = &rest[i..end];
        if !PLACEHOLDERS.contains(&word) {
            return Some(word.to_string());
        }
        rest = &rest[end..];
    }
    None
}

#[cfg(test)]
mod tests {
    use super::{fill, unknown_placeholder, PointState, NONE_ON_GRID};

    fn point(value: &str, holds: bool, stalled: bool) -> PointState {
        PointState { value: value.into(), holds, stalled }
    }

    #[test]
    fn the_cause_names_the_measured_points() {
        let pts = [point("1e-20", true, false), point("1e-3", true, false), point("1", false, false)];
        assert_eq!(
            fill("same up to {last_holding}, parts from {first_failing}", &pts),
            "same up to 1e-3, parts from 1"
        );
        // a stall is a failure, but not the first that runs to its limit
        let pts = [point("1e-15", false, true), point("1e-10", false, true), point("1e-8", false, false)];
        assert_eq!(fill("from {first_not_stalled} on", &pts), "from 1e-8 on");
        assert_eq!(fill("{last_holding}", &pts), NONE_ON_GRID);
        assert_eq!(unknown_placeholder("from {first_failing} on"), None);
        assert_eq!(unknown_placeholder("from {first_fail} on").as_deref(), Some("{first_fail}"));
    }
}
