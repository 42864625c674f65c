//! A scene made live: one technique instance per node, current parameter values, and the
//! per-frame work of applying tracks, stepping simulations and declaring the frame graph.

use super::load::Scene;
use crate::assets::Assets;
use crate::gpu::{Gpu, ShaderError};
use crate::graph::{FrameGraph, FrameOutput, GraphError, GraphRuntime};
use crate::params::ParamSet;
use crate::techniques::{NodeSetup, Technique};
use crate::time::FrameTime;

/// The running form of a [`Scene`].
pub struct SceneInstance {
    scene: Scene,
    params: Vec<ParamSet>,
    nodes: Vec<Box<dyn Technique>>,
    /// When false, tracks leave parameters alone (the performer has taken over).
    pub animate: bool,
}

impl SceneInstance {
    /// Creates every node's technique (pipelines, persistent resources) for `output_size`.
    pub fn new(gpu: &Gpu, assets: &Assets, scene: Scene, output_size: (u32, u32)) -> Result<Self, ShaderError> {
        let nodes = scene
            .nodes
            .iter()
            .map(|n| (n.technique.create)(&NodeSetup { gpu, assets, id: &n.id, output_size }))
            .collect::<Result<Vec<_>, _>>()?;
        let params = scene.nodes.iter().map(|n| n.params.clone()).collect();
        Ok(Self { scene, params, nodes, animate: true })
    }

    /// The validated scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Current parameters of node `i`.
    pub fn params(&self, node: usize) -> &ParamSet {
        &self.params[node]
    }

    /// Mutable parameters of node `i` (UI, control input).
    pub fn params_mut(&mut self, node: usize) -> &mut ParamSet {
        &mut self.params[node]
    }

    /// Whether a track drives parameter `param` of node `node`.
    pub fn is_animated(&self, node: usize, param: usize) -> bool {
        self.animate && self.scene.tracks.iter().any(|t| t.node == node && t.param == param)
    }

    /// Sets every tracked parameter to its value at `time`.
    pub fn apply_tracks(&mut self, time: &FrameTime) {
        if !self.animate {
            return;
        }
        for bound in &self.scene.tracks {
            let value = bound.track.sample(time.seconds);
            let params = &mut self.params[bound.node];
            match bound.component {
                Some(c) => params.set_component(bound.param, c, value.components()[0]),
                None => params.set_at(bound.param, value),
            }
        }
    }

    /// Advances every node's simulation by one fixed step.
    pub fn step(&mut self, time: &FrameTime) {
        for (node, params) in self.nodes.iter_mut().zip(&self.params) {
            node.step(params, time);
        }
    }

    /// Declares this frame: every node adds its passes, the output node's texture is the output.
    pub fn build_graph(&mut self, output_size: (u32, u32), time: &FrameTime) -> FrameGraph<'_> {
        let mut graph = FrameGraph::new(output_size);
        let mut outputs = Vec::with_capacity(self.nodes.len());
        for (i, node) in self.nodes.iter_mut().enumerate() {
            let inputs: Vec<_> = self.scene.nodes[i].inputs.iter().map(|&j| outputs[j]).collect();
            outputs.push(node.add_passes(&mut graph, &self.params[i], time, &inputs));
        }
        graph.set_output(outputs[self.scene.output]);
        graph
    }

    /// Applies tracks, builds and records the frame into `encoder`; the caller encodes the
    /// output for display and submits.
    pub fn encode(
        &mut self,
        gpu: &Gpu,
        runtime: &mut GraphRuntime,
        encoder: &mut wgpu::CommandEncoder,
        output_size: (u32, u32),
        time: &FrameTime,
    ) -> Result<FrameOutput, GraphError> {
        self.apply_tracks(time);
        let graph = self.build_graph(output_size, time);
        runtime.execute(&gpu.device, &gpu.queue, graph, encoder)
    }
}
