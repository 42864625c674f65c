//! Running a compiled frame: resolve transients from the pool as their lifetimes begin, record
//! each pass between timestamps, release textures after their last reader.

use std::collections::BTreeSet;
use std::time::{Duration, Instant};

use super::builder::{Access, BufferOrigin, FrameGraph, PassContext, ResolvedTexture, Resource, TextureOrigin};
use super::compile::{GraphError, compile};
use super::pool::{BufferPool, PoolKey, TexturePool, texture_bytes};
use super::timing::{GpuTimer, PassTiming};

/// What the graph reports about one frame.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FrameStats {
    /// Passes the nodes declared.
    pub passes_declared: usize,
    /// Passes that ran after culling.
    pub passes_executed: usize,
    /// Bytes of every transient texture used this frame, as if each had its own.
    pub transient_bytes_requested: u64,
    /// Bytes of the distinct pool textures that served them.
    pub transient_bytes_allocated: u64,
    /// Pool textures created this frame (0 once the pool is warm).
    pub textures_created: usize,
    /// CPU time of compiling the graph.
    pub compile_time: Duration,
}

/// The frame's output texture (to encode for display or read back) and its stats.
pub struct FrameOutput {
    /// The output texture.
    pub texture: wgpu::Texture,
    /// Its view.
    pub view: wgpu::TextureView,
    /// The textures added with [`super::FrameGraph::add_extra_output`], in order (None: never
    /// written this frame).
    pub extras: Vec<Option<(wgpu::Texture, wgpu::TextureView)>>,
    /// Stats of this frame.
    pub stats: FrameStats,
}

/// What persists between frames for the graph: the texture pool, pooled buffers and the timer.
pub struct GraphRuntime {
    pool: TexturePool,
    buffers: BufferPool,
    timer: Option<GpuTimer>,
    /// Whether each pass is recorded inside a debug group of its name.
    debug_groups: bool,
}

impl GraphRuntime {
    /// A runtime that times passes when the device has `TIMESTAMP_QUERY_INSIDE_ENCODERS`, and
    /// encloses each pass in a debug group named like it (so a RenderDoc or Nsight capture reads
    /// like the frame graph) except on a CPU adapter: lavapipe (Mesa 22.3) crashes when a debug
    /// group encloses a render pass.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> Self {
        let timed = device.features().contains(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS);
        let debug_groups = device.adapter_info().device_type != wgpu::DeviceType::Cpu;
        Self {
            pool: TexturePool::new(),
            buffers: BufferPool::default(),
            timer: timed.then(|| GpuTimer::new(device, queue)),
            debug_groups,
        }
    }

    /// Whether passes are recorded inside debug groups of their names (see [`GraphRuntime::new`]).
    pub fn debug_groups(&self) -> bool {
        self.debug_groups
    }

    /// The transient texture pool.
    pub fn pool(&self) -> &TexturePool {
        &self.pool
    }

    /// The transient buffer pool.
    pub fn buffer_pool(&self) -> &BufferPool {
        &self.buffers
    }

    /// Keeps idle pool textures instead of dropping them after two seconds (see
    /// [`TexturePool::set_hold`]).
    pub fn hold_transients(&mut self, hold: bool) {
        self.pool.set_hold(hold);
        self.buffers.set_hold(hold);
    }

    /// Compiles and records `graph` into `encoder`. Submit the encoder, then call `after_submit`.
    pub fn execute(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        graph: FrameGraph<'_>,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<FrameOutput, GraphError> {
        let output = graph.output.ok_or(GraphError::NoOutput)?;
        let output_name = graph.textures[output.0 as usize].name.clone();
        let extra_outputs = graph.extra_outputs.clone();
        let (textures, stats) = self.record(device, queue, graph, encoder)?;
        let out = textures[output.0 as usize]
            .clone()
            .ok_or(GraphError::ReadOfUnwritten { pass: "<output>".into(), resource: output_name })?;
        let extras = extra_outputs
            .iter()
            .map(|t| textures[t.0 as usize].as_ref().map(|r| (r.texture.clone(), r.view.clone())))
            .collect();
        Ok(FrameOutput { texture: out.texture, view: out.view, extras, stats })
    }

    /// Compiles and records a [`FrameGraph::simulation_only`] frame: only the passes that write
    /// persistent state run. Submit the encoder, then call `after_submit`.
    pub fn simulate(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        graph: FrameGraph<'_>,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<FrameStats, GraphError> {
        debug_assert!(graph.simulation_only, "simulate takes a simulation-only graph");
        self.record(device, queue, graph, encoder).map(|(_, stats)| stats)
    }

    /// Records the live passes of `graph`; returns the resolved textures (the output's included).
    fn record(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        mut graph: FrameGraph<'_>,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(Vec<Option<ResolvedTexture>>, FrameStats), GraphError> {
        let started = Instant::now();
        let compiled = compile(&graph)?;
        let compile_time = started.elapsed();
        let usages = texture_usages(&graph);

        let mut textures: Vec<Option<ResolvedTexture>> = vec![None; graph.textures.len()];
        let mut pool_index: Vec<Option<usize>> = vec![None; graph.textures.len()];
        let mut buffers: Vec<Option<(wgpu::Buffer, u64)>> = vec![None; graph.buffers.len()];
        let mut buffer_index: Vec<Option<usize>> = vec![None; graph.buffers.len()];
        let mut stats = FrameStats {
            passes_declared: graph.passes.len(),
            passes_executed: compiled.executed(),
            compile_time,
            ..Default::default()
        };
        let mut used_pool_entries = BTreeSet::new();
        let timing = self.timer.as_mut().is_some_and(|t| t.begin_frame());

        for (position, &p) in compiled.order.iter().enumerate() {
            for (t, life) in compiled.texture_lifetimes.iter().enumerate() {
                if life.is_some_and(|(first, _)| first == position) {
                    let (resolved, pooled) = self.resolve_texture(device, &graph, t, usages[t]);
                    if let Some(i) = pooled {
                        let bytes = texture_bytes(size_of(&resolved), resolved.texture.format())
                            * u64::from(resolved.texture.depth_or_array_layers())
                            * u64::from(resolved.texture.sample_count());
                        stats.transient_bytes_requested += bytes;
                        if used_pool_entries.insert(i) {
                            stats.transient_bytes_allocated += bytes;
                        }
                    }
                    textures[t] = Some(resolved);
                    pool_index[t] = pooled;
                }
            }
            for (b, life) in compiled.buffer_lifetimes.iter().enumerate() {
                if life.is_some_and(|(first, _)| first == position) {
                    let (buffer, id, pooled) = self.resolve_buffer(device, &graph, b);
                    buffers[b] = Some((buffer, id));
                    buffer_index[b] = pooled;
                }
            }

            let pass = &mut graph.passes[p];
            if timing && let Some(t) = self.timer.as_mut() {
                t.begin_pass(encoder, position, &pass.name);
            }
            if self.debug_groups {
                encoder.push_debug_group(&pass.name);
            }
            if let Some(record) = pass.record.take() {
                let mut ctx = PassContext {
                    device,
                    queue,
                    encoder,
                    textures: &textures,
                    buffers: &buffers,
                    pass_name: &pass.name,
                };
                record(&mut ctx);
            }
            if self.debug_groups {
                encoder.pop_debug_group();
            }
            if timing && let Some(t) = self.timer.as_mut() {
                t.end_pass(encoder, position);
            }

            for (t, life) in compiled.texture_lifetimes.iter().enumerate() {
                if life.is_some_and(|(_, last)| last == position)
                    && let Some(i) = pool_index[t]
                {
                    self.pool.release(i);
                }
            }
            for (b, life) in compiled.buffer_lifetimes.iter().enumerate() {
                if life.is_some_and(|(_, last)| last == position)
                    && let Some(i) = buffer_index[b]
                {
                    self.buffers.release(i);
                }
            }
        }
        if timing && let Some(t) = self.timer.as_mut() {
            t.end_frame(encoder);
        }
        stats.textures_created = self.pool.created_this_frame();
        self.pool.end_frame();
        self.buffers.end_frame();
        Ok((textures, stats))
    }

    /// Call after the frame's encoder was submitted: starts reading back its timestamps.
    pub fn after_submit(&mut self) {
        if let Some(t) = self.timer.as_mut() {
            t.after_submit();
        }
    }

    /// Rolling medians per pass (empty without timestamp support).
    pub fn timings(&self) -> Vec<PassTiming> {
        self.timer.as_ref().map(|t| t.timings()).unwrap_or_default()
    }

    /// The passes of the latest frame whose timestamps were read back, with their GPU
    /// milliseconds (empty without timestamp support): waiting for a frame, then starting the
    /// next, reads it.
    pub fn latest_frame_timings(&self) -> Vec<(String, f64)> {
        self.timer.as_ref().map(|t| t.latest_frame()).unwrap_or_default()
    }

    /// Rolling median of the summed GPU pass time per frame, milliseconds.
    pub fn frame_gpu_median_ms(&self) -> Option<f64> {
        self.timer.as_ref().and_then(|t| t.frame_median_ms())
    }

    /// Rolling median of the span from the first pass's start to the last pass's end per frame
    /// (the pass time and the GPU's gaps between passes), milliseconds.
    pub fn frame_gpu_span_median_ms(&self) -> Option<f64> {
        self.timer.as_ref().and_then(|t| t.frame_span_median_ms())
    }

    /// Waits for outstanding timestamp readbacks and folds them into the medians.
    pub fn drain_timings(&mut self, device: &wgpu::Device) {
        if let Some(t) = self.timer.as_mut() {
            t.drain(device);
        }
    }

    /// Forgets the timings so far, so that later medians cover only what follows.
    pub fn reset_timings(&mut self) {
        if let Some(t) = self.timer.as_mut() {
            t.reset();
        }
    }

    fn resolve_texture(
        &mut self,
        device: &wgpu::Device,
        graph: &FrameGraph<'_>,
        t: usize,
        usage: wgpu::TextureUsages,
    ) -> (ResolvedTexture, Option<usize>) {
        match &graph.textures[t].origin {
            TextureOrigin::Imported(texture, view, id) => {
                (ResolvedTexture { texture: texture.clone(), view: view.clone(), id: *id }, None)
            }
            TextureOrigin::Transient(desc) => {
                let key = PoolKey {
                    size: desc.extent.resolve(graph.output_size),
                    format: desc.format,
                    usage,
                    layers: desc.layers,
                    samples: desc.samples,
                };
                let (index, resolved) = self.pool.acquire(device, key);
                (resolved, Some(index))
            }
        }
    }

    fn resolve_buffer(
        &mut self,
        device: &wgpu::Device,
        graph: &FrameGraph<'_>,
        b: usize,
    ) -> (wgpu::Buffer, u64, Option<usize>) {
        match &graph.buffers[b].origin {
            BufferOrigin::Imported(buffer, id) => (buffer.clone(), *id, None),
            BufferOrigin::Transient { size } => {
                let (index, buffer, id) = self.buffers.acquire(device, *size);
                (buffer, id, Some(index))
            }
        }
    }
}

fn size_of(t: &ResolvedTexture) -> (u32, u32) {
    (t.texture.width(), t.texture.height())
}

/// Usage flags of each texture, inferred from how passes access it.
fn texture_usages(graph: &FrameGraph<'_>) -> Vec<wgpu::TextureUsages> {
    let mut usages = vec![wgpu::TextureUsages::empty(); graph.textures.len()];
    for pass in &graph.passes {
        for &(res, access) in &pass.accesses {
            if let Resource::Texture(t) = res {
                usages[t as usize] |= match access {
                    Access::Read => wgpu::TextureUsages::TEXTURE_BINDING,
                    Access::Write => wgpu::TextureUsages::STORAGE_BINDING,
                    Access::RenderTarget => wgpu::TextureUsages::RENDER_ATTACHMENT,
                };
            }
        }
    }
    // Outputs are encoded for display (sampled) or copied for readback.
    for shown in graph.output.iter().chain(&graph.extra_outputs) {
        usages[shown.0 as usize] |= wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC;
    }
    usages
}
