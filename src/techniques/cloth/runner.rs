//! A cloth node driven headless (see [`crate::techniques::runner`]) and the strain measure the
//! tests and `examples/cloth_strain` read from it.

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
