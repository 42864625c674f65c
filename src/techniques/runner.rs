//! Driving one node headless, step by step, the way the runtime does (step, add passes, execute,
//! submit) — for tests and measurement tools that need a technique's concrete state (particle
//! positions, fluid fields) rather than only its image.

use super::{NodeSetup, Technique};
use crate::assets::Assets;
use crate::gpu::{Gpu, ShaderError};
use crate::graph::{FrameGraph, GraphRuntime};
use crate::params::ParamSet;
use crate::time::{FixedClock, FrameTime};

/// The output size the runner's frames use.
pub const RUNNER_SIZE: (u32, u32) = (64, 64);

/// A node with its own graph runtime and clock.
pub struct NodeRunner<T: Technique> {
    gpu: Gpu,
    /// The node.
    pub node: T,
    /// Its parameters (change them between frames).
    pub params: ParamSet,
    runtime: GraphRuntime,
    clock: FixedClock,
}

impl<T: Technique> NodeRunner<T> {
    /// Builds the node with `create` and runs it on `gpu` at `dt` seconds per frame.
    pub fn new(
        gpu: Gpu,
        assets: &Assets,
        params: ParamSet,
        dt: f32,
        create: impl FnOnce(&NodeSetup<'_>) -> Result<T, ShaderError>,
    ) -> Result<Self, ShaderError> {
        let setup =
            NodeSetup { gpu: &gpu, assets, id: "node", output_size: RUNNER_SIZE, msaa: 1, params: &params, seed: 1 };
        let node = create(&setup)?;
        let runtime = GraphRuntime::new(&gpu.device, &gpu.queue);
        Ok(Self { gpu, node, params, runtime, clock: FixedClock::new(dt, 1) })
    }

    /// The device.
    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    /// The time of the next frame.
    pub fn time(&self) -> FrameTime {
        self.clock.now()
    }

    /// Runs `frames` fixed steps, each recorded and submitted like a frame.
    pub fn run(&mut self, frames: u32) {
        for _ in 0..frames {
            let time = self.clock.now();
            self.node.step(&self.params, &time);
            self.params.end_step();
            let mut graph = FrameGraph::new(RUNNER_SIZE);
            let out = self.node.add_passes(&mut graph, &self.params, &time, &[]);
            graph.set_output(out);
            let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
            if let Err(e) = self.runtime.execute(&self.gpu.device, &self.gpu.queue, graph, &mut encoder) {
                log::error!("runner frame: {e}");
            }
            self.gpu.queue.submit([encoder.finish()]);
            self.clock.step();
        }
    }
}
