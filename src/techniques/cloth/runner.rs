//! A cloth node driven headless (see [`crate::techniques::runner`]) and the strain and roughness
//! measures the tests, `examples/cloth_strain` and `examples/cloth_roughness` read from it.

use super::Cloth;
use crate::gpu::{Gpu, ShaderError};
use crate::params::ParamSet;
use crate::techniques::runner::NodeRunner;

/// A cloth node with its own graph runtime and clock.
pub type Runner = NodeRunner<Cloth>;

/// A runner for `params` on `gpu`, stepping `dt` seconds per frame.
pub fn runner(gpu: Gpu, assets: &crate::assets::Assets, params: ParamSet, dt: f32) -> Result<Runner, ShaderError> {
    NodeRunner::new(gpu, assets, params, dt, Cloth::new)
}

/// The largest strain of the vertical structural springs hanging from the top row.
pub fn top_row_strain(positions: &[[f32; 4]], res: usize, rest: f32) -> f32 {
    let distance =
        |a: [f32; 4], b: [f32; 4]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
    (0..res).map(|i| (distance(positions[i], positions[res + i]) - rest) / rest).fold(0.0, f32::max)
}

/// RMS over the particles of rows `rows` of |p − mean of its 4 neighbours| / rest: 0 for a flat
/// or evenly curved sheet, large for wrinkles a few particles wide.
pub fn roughness(p: &[[f32; 4]], res: usize, rest: f32, rows: std::ops::Range<usize>) -> f32 {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for j in rows.start.max(1)..rows.end.min(res - 1) {
        for i in 1..res - 1 {
            let at = |i: usize, j: usize| p[j * res + i];
            let (c, l, r, u, d) = (at(i, j), at(i - 1, j), at(i + 1, j), at(i, j - 1), at(i, j + 1));
            let dev: f32 = (0..3).map(|k| (c[k] - (l[k] + r[k] + u[k] + d[k]) / 4.0).powi(2)).sum::<f32>().sqrt();
            sum += f64::from(dev / rest).powi(2);
            n += 1;
        }
    }
    (sum / n as f64).sqrt() as f32
}
