//! Golden-image checks with the FLIP metric (Andersson et al. 2020, nv-flip crate): a mean and a
//! percentile threshold per test. A mismatch writes `<name>-actual.png` and `<name>-diff.png`
//! next to the reference and says where; `INDRA_BLESS=1` rewrites references. A missing
//! reference fails unless blessing — a test that passes on nothing cannot fail.

use std::path::{Path, PathBuf};

/// FLIP error statistics of one comparison (0 = identical, 1 = maximal).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlipScore {
    /// Mean FLIP error over all pixels.
    pub mean: f32,
    /// The given percentile of the per-pixel error.
    pub percentile: f32,
}

/// Compares two RGBA8 images of `size` (alpha ignored); returns the score and a colour-mapped
/// error image (RGB8).
pub fn flip_score(reference: &[u8], test: &[u8], size: (u32, u32), percentile: f32) -> (FlipScore, Vec<u8>) {
    let rgb = |rgba: &[u8]| rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect::<Vec<u8>>();
    let r = nv_flip::FlipImageRgb8::with_data(size.0, size.1, &rgb(reference));
    let t = nv_flip::FlipImageRgb8::with_data(size.0, size.1, &rgb(test));
    let error = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    let mut pool = nv_flip::FlipPool::from_image(&error);
    let score = FlipScore { mean: pool.mean(), percentile: pool.get_percentile(percentile, true) };
    (score, error.apply_color_lut(&nv_flip::magma_lut()).to_vec())
}

/// A golden check: where references live and how close is close enough.
#[derive(Clone, Debug)]
pub struct GoldenCheck {
    /// Folder of reference PNGs (e.g. `tests/golden`).
    pub dir: PathBuf,
    /// Largest mean FLIP error that passes.
    pub max_mean: f32,
    /// Which percentile to bound (e.g. 0.99).
    pub percentile: f32,
    /// Largest error at that percentile that passes.
    pub max_percentile: f32,
}

impl GoldenCheck {
    /// Thresholds that tolerate rasterisation noise across drivers but not a changed picture.
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        Self { dir: dir.into(), max_mean: 0.01, percentile: 0.99, max_percentile: 0.3 }
    }

    /// Checks `rgba` against `<dir>/<name>.png`. With `INDRA_BLESS=1` it writes the reference
    /// instead and passes. The error message names the files written.
    pub fn check(&self, name: &str, size: (u32, u32), rgba: &[u8]) -> Result<FlipScore, String> {
        let reference_path = self.dir.join(format!("{name}.png"));
        if std::env::var("INDRA_BLESS").is_ok_and(|v| v == "1") {
            std::fs::create_dir_all(&self.dir).map_err(|e| e.to_string())?;
            super::write_png(&reference_path, size, rgba)?;
            return Ok(FlipScore { mean: 0.0, percentile: 0.0 });
        }
        let reference = load_rgba(&reference_path).map_err(|e| {
            format!("{e}\n  no reference for '{name}': run the test with INDRA_BLESS=1 to create it, then look at it")
        })?;
        let actual_path = self.dir.join(format!("{name}-actual.png"));
        let diff_path = self.dir.join(format!("{name}-diff.png"));
        if reference.1 != size {
            super::write_png(&actual_path, size, rgba)?;
            return Err(format!(
                "'{name}': size {:?} differs from the reference's {:?}; wrote {}",
                size,
                reference.1,
                actual_path.display()
            ));
        }
        let (score, diff) = flip_score(&reference.0, rgba, size, self.percentile);
        if score.mean <= self.max_mean && score.percentile <= self.max_percentile {
            let _ = std::fs::remove_file(&actual_path);
            let _ = std::fs::remove_file(&diff_path);
            return Ok(score);
        }
        super::write_png(&actual_path, size, rgba)?;
        image::save_buffer(&diff_path, &diff, size.0, size.1, image::ExtendedColorType::Rgb8)
            .map_err(|e| e.to_string())?;
        Err(format!(
            "'{name}' differs from {}: FLIP mean {:.4} (max {}), p{} {:.4} (max {})\n  actual: {}\n  diff:   {}\n  if the change is intended: INDRA_BLESS=1",
            reference_path.display(),
            score.mean,
            self.max_mean,
            self.percentile * 100.0,
            score.percentile,
            self.max_percentile,
            actual_path.display(),
            diff_path.display()
        ))
    }
}

/// Loads a PNG as RGBA8 with its size.
pub fn load_rgba(path: &Path) -> Result<(Vec<u8>, (u32, u32)), String> {
    let img = image::open(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?.to_rgba8();
    let size = img.dimensions();
    Ok((img.into_raw(), size))
}
