//! Driving one cloth node headless, step by step, the way the runtime does (step, add passes,
//! execute, submit) — for tests and measurement tools that need the particle positions.

use super::Cloth;
use crate::gpu::Gpu;
use crate::graph::{FrameGraph, GraphRuntime};
use crate::params::ParamSet;
use crate::techniques::{NodeSetup, Technique};
use crate::time::{FixedClock, FrameTime};

/// A cloth node with its own graph runtime and clock.
pub struct Runner {
    gpu: Gpu,
    /// The node.
    pub cloth: Cloth,
    /// Its parameters (change them between frames).
    pub params: ParamSet,
    runtime: GraphRuntime,
    clock: FixedClock,
}

impl Runner {
    /// A runner for `params` on `gpu`, stepping `dt` seconds per frame.
    pub fn new(
        gpu: Gpu,
        assets: &crate::assets::Assets,
        params: ParamSet,
        dt: f32,
    ) -> Result<Self, crate::gpu::ShaderError> {
        let cloth = Cloth::new(&NodeSetup { gpu: &gpu, assets, id: "cloth", output_size: (64, 64) })?;
        let runtime = GraphRuntime::new(&gpu.device, &gpu.queue);
        Ok(Self { gpu, cloth, params, runtime, clock: FixedClock::new(dt, 1) })
    }

    /// The time of the next frame.
    pub fn time(&self) -> FrameTime {
        self.clock.now()
    }

    /// Runs `frames` fixed steps, each recorded and submitted like a frame (64×64 image).
    pub fn run(&mut self, frames: u32) {
        for _ in 0..frames {
            let time = self.clock.now();
            self.cloth.step(&self.params, &time);
            self.params.end_step();
            let mut graph = FrameGraph::new((64, 64));
            let out = self.cloth.add_passes(&mut graph, &self.params, &time, &[]);
            graph.set_output(out);
            let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
            if let Err(e) = self.runtime.execute(&self.gpu.device, &self.gpu.queue, graph, &mut encoder) {
                log::error!("cloth frame: {e}");
            }
            self.gpu.queue.submit([encoder.finish()]);
            self.clock.step();
        }
    }
}

/// The largest strain of the vertical structural springs hanging from the top row.
pub fn top_row_strain(positions: &[[f32; 4]], res: usize, rest: f32) -> f32 {
    let distance =
        |a: [f32; 4], b: [f32; 4]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
    (0..res).map(|i| (distance(positions[i], positions[res + i]) - rest) / rest).fold(0.0, f32::max)
}
