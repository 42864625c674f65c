//! Golden checkers with the bounds each test states, for references in `tests/golden/` or in a
//! technique's own folder.

use indra::offscreen::GoldenCheck;

/// The golden checker for `tests/golden/`, passing a picture whose FLIP error against the
/// reference is at most `max_mean` on average and `max_p99` at the 99th percentile. Each test
/// states its own bounds where it checks (0.01 and 0.3 tolerate rasterisation noise across
/// drivers but not a changed picture).
pub fn golden(max_mean: f32, max_p99: f32) -> GoldenCheck {
    golden_in(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/golden"), max_mean, max_p99)
}

/// The golden checker for the `golden/` folder beside `file` (a test's `file!()`: a technique's
/// references sit in its own folder), with the bounds of [`golden`].
pub fn golden_beside(file: &str, max_mean: f32, max_p99: f32) -> GoldenCheck {
    let folder = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(file);
    let dir = folder.parent().expect("a test file is in a folder").join("golden");
    golden_in(dir, max_mean, max_p99)
}

/// The golden checker for the references in `dir`, with the bounds of [`golden`].
pub fn golden_in(dir: impl Into<std::path::PathBuf>, max_mean: f32, max_p99: f32) -> GoldenCheck {
    GoldenCheck { max_mean, max_percentile: max_p99, percentile: 0.99, ..GoldenCheck::new(dir) }
}
