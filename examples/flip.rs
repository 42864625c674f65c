//! The mean FLIP difference between two images of the same size (NVIDIA's perceptual metric, as
//! the golden tests use it): how the docs' "image held" figures are measured.
//!
//! `cargo run --release --example flip -- REFERENCE.png TEST.png`

fn main() -> Result<(), String> {
    let paths: Vec<String> = std::env::args().skip(1).collect();
    let [reference, test] = paths.as_slice() else {
        return Err("usage: flip REFERENCE.png TEST.png".into());
    };
    let load = |path: &str| image::open(path).map(|i| i.to_rgba8()).map_err(|e| format!("{path}: {e}"));
    let (a, b) = (load(reference)?, load(test)?);
    if a.dimensions() != b.dimensions() {
        return Err(format!("sizes differ: {:?} and {:?}", a.dimensions(), b.dimensions()));
    }
    let (score, _) = indra::offscreen::flip_score(a.as_raw(), b.as_raw(), a.dimensions(), 0.99);
    println!("mean FLIP {:.4}  ({}×{})", score.mean, a.width(), a.height());
    Ok(())
}
