//! `reference.csv`: a run's published values (`[[reference.values]]`) against what it
//! computed, one row per value ([`run_csv`]); `compare` writes both engines side by side
//! ([`compare_csv`]). Numbers at full precision; the verdict `true`/`false`.
use crate::engine::published::PublishedRow;

/// The columns of a run's `reference.csv` (the unit of each row is in `unit`).
pub const RUN_HEADER: [&str; 8] = ["quantity", "unit", "published", "computed", "error", "tolerance", "pass", "source"];

/// The columns of `compare`'s `reference.csv`: both engines' values, errors and verdicts.
pub const COMPARE_HEADER: [&str; 11] = [
    "quantity",
    "unit",
    "published",
    "tolerance",
    "rust",
    "rust_error",
    "rust_pass",
    "freefem",
    "freefem_error",
    "freefem_pass",
    "source",
];

fn number(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.17e}")
    } else {
        String::new()
    }
}

fn computed(r: &PublishedRow) -> String {
    r.computed.as_ref().map_or(String::new(), |c| number(*c))
}

/// CSV text of `header` and `rows` of fields (quoted where a field needs it).
fn csv(header: &[&str], rows: impl Iterator<Item = Vec<String>>) -> String {
    let mut w = csv::WriterBuilder::new().terminator(csv::Terminator::Any(b'\n')).from_writer(Vec::new());
    // writing to memory cannot fail
    let _ = w.write_record(header);
    for r in rows {
        let _ = w.write_record(&r);
    }
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

/// A run's `reference.csv`.
pub fn run_csv(rows: &[PublishedRow]) -> String {
    csv(
        &RUN_HEADER,
        rows.iter().map(|r| {
            vec![
                r.quantity.clone(),
                r.unit.to_string(),
                number(r.published),
                computed(r),
                number(r.error),
                number(r.tolerance),
                r.pass.to_string(),
                r.source.clone(),
            ]
        }),
    )
}

/// `compare`'s `reference.csv`: the rows of the Rust and the FreeFEM run, in the same order.
pub fn compare_csv(rust: &[PublishedRow], freefem: &[PublishedRow]) -> String {
    csv(
        &COMPARE_HEADER,
        rust.iter().zip(freefem).map(|(r, f)| {
            vec![
                r.quantity.clone(),
                r.unit.to_string(),
                number(r.published),
                number(r.tolerance),
                computed(r),
                number(r.error),
                r.pass.to_string(),
                computed(f),
                number(f.error),
                f.pass.to_string(),
                r.source.clone(),
            ]
        }),
    )
}
