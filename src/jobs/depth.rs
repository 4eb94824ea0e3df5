//! How far an audit or a study runs: its full grids, or the short ones of `--quick`.

/// The grids an audit ([`crate::audit`]) or a study ([`crate::study`]) runs: a spec's full
/// grid, or its smaller one (`quick_grid`, `quick_set`, `[quick]`) that `--quick` asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Depth {
    /// every point of the spec's grids
    #[default]
    Full,
    /// the spec's short grids and clip excerpts (`--quick`, the subset `cargo test` asserts)
    Quick,
}

impl Depth {
    /// Is this the short run of `--quick`?
    pub fn is_quick(self) -> bool {
        self == Depth::Quick
    }
}
