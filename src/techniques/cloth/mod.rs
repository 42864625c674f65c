//! GPU cloth: a grid of particles with 12 springs each, the book's mass-spring Verlet model or
//! small-step XPBD, colliding with an oscillating sphere; drawn lit and two-sided, or as particles
//! and springs. Simulation state lives in node-owned storage buffers imported into the graph;
//! `step` queues fixed steps and `add_passes` records them, so all GPU work is timed by the graph.
//!
//! Book: [UGP4 ch.3] "GPU-Based Cloth Simulation" (oishi); [Macklin 2019] "Small Steps in Physics
//! Simulation". Shaders: `cloth.wgsl`, `cloth_render.wgsl`.
//! Goldens: `golden/`, made by `render_tests.rs`.

mod params;
pub mod reference;
mod render;
pub mod runner;
mod state;

pub use params::{ClothUniforms, Pin, Settings, Solver, View, rest_pose, sphere_center, wind_force};
use render::{ClothView, Renderer};
use state::State;

use crate::checkpoint::{CheckpointError, NodeState};
use crate::gpu::{ComputeKernel, Gpu, ShaderError};
use crate::graph::{FrameGraph, TextureDesc, TextureHandle};
use crate::params::ParamSet;
use crate::time::{FrameTime, MAX_CATCH_UP_STEPS};

use super::splat_draw::SplatUniforms;
use super::{NodeSetup, Technique, TechniqueInfo};

/// The registry entry.
pub const INFO: TechniqueInfo = TechniqueInfo {
    name: "cloth",
    chapter: "3: GPU-Based Cloth Simulation",
    summary: "mass-spring (Verlet) or XPBD cloth on the GPU with a colliding sphere",
    params: Settings::decls,
    inputs: &[],
    shaders: &["cloth.wgsl", "cloth_render.wgsl", "cloth_raster.wgsl", "splat_draw.wgsl", "msaa_samples.wgsl"],
    create,
    check: None,
    stage: None,
    declare: None,
};

/// The colour target format.
pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The simulation pipelines and the layout they share.
struct Kernels {
    verlet: ComputeKernel,
    xpbd: ComputeKernel,
    normals: ComputeKernel,
    layout: wgpu::BindGroupLayout,
}

/// A cloth node.
pub struct Cloth {
    device: wgpu::Device,
    queue: wgpu::Queue,
    kernels: Kernels,
    renderer: Renderer,
    /// One uniform buffer per clock step a frame may run.
    uniforms: Vec<wgpu::Buffer>,
    state: State,
    /// Steps queued by `step`, recorded by the next `add_passes`.
    pending: Vec<ClothUniforms>,
    messages: Vec<String>,
}

fn create(setup: &NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError> {
    Ok(Box::new(Cloth::new(setup)?))
}

impl Cloth {
    /// Builds the pipelines and the cloth at rest, at the resolution and pinning asked for.
    pub fn new(setup: &NodeSetup<'_>) -> Result<Self, ShaderError> {
        let device = &setup.gpu.device;
        let storage = |binding, read_only| crate::gpu::storage_entry(binding, wgpu::ShaderStages::COMPUTE, read_only);
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("cloth_sim_layout"),
            entries: &[
                crate::gpu::uniform_entry::<ClothUniforms>(0, wgpu::ShaderStages::COMPUTE),
                storage(1, true),
                storage(2, true),
                storage(3, false),
                storage(4, false),
                storage(5, false),
            ],
        });
        // Binding order = the order of `State::bind_group`'s entries and of the layout above.
        let bindings = [("u", 0), ("prev", 1), ("cur", 2), ("next", 3), ("status", 4), ("normals", 5)];
        let (origin, source) = setup.shader_source("cloth.wgsl", &bindings)?;
        let kernel = |entry| ComputeKernel::new(device, &origin, &source, entry, &[&layout]);
        let kernels =
            Kernels { verlet: kernel("verlet")?, xpbd: kernel("xpbd")?, normals: kernel("compute_normals")?, layout };
        let renderer = Renderer::new(setup)?;
        let uniforms = (0..MAX_CATCH_UP_STEPS.max(1))
            .map(|_| crate::gpu::uniform_buffer::<ClothUniforms>(device, "cloth_uniforms"))
            .collect();
        let settings = Settings::read(setup.params);
        let state = at_rest(device, &setup.gpu.queue, &renderer, &settings);
        Ok(Self {
            device: device.clone(),
            queue: setup.gpu.queue.clone(),
            kernels,
            renderer,
            uniforms,
            state,
            pending: Vec::new(),
            messages: Vec::new(),
        })
    }

    /// Reads the current particle positions back (blocking; for tests and tools).
    pub fn positions(&self) -> Vec<[f32; 4]> {
        self.state.read_positions(&self.device, &self.queue)
    }

    /// Reads the previous positions back (blocking; for tests and tools).
    pub fn previous_positions(&self) -> Vec<[f32; 4]> {
        self.state.read_previous(&self.device, &self.queue)
    }

    /// Reads the normals back (blocking; for tests and tools).
    pub fn normals(&self) -> Vec<[f32; 4]> {
        self.state.read_normals(&self.device, &self.queue)
    }

    /// Recreates the cloth at rest if the resolution or pinning changed, and puts it back to
    /// rest if a reset was asked for.
    fn ensure_state(&mut self, p: &Settings) {
        let res = p.resolution.clamp(4, 1024) as u32;
        if self.state.res != res || self.state.pin != p.pin.index() {
            self.state = at_rest(&self.device, &self.queue, &self.renderer, p);
        } else if p.reset {
            let pose = rest_pose(res, p.rest_length, p.mass, self.state.pin);
            self.state.reset(&self.queue, &pose);
        }
    }
}

/// A cloth of `p`'s resolution and pinning, at rest.
fn at_rest(device: &wgpu::Device, queue: &wgpu::Queue, renderer: &Renderer, p: &Settings) -> State {
    let (res, pin) = (p.resolution.clamp(4, 1024) as u32, p.pin.index());
    let mut state = State::new(device, res, pin, renderer.surface_indices(device, res));
    state.reset(queue, &rest_pose(res, p.rest_length, p.mass, pin));
    state
}

impl Technique for Cloth {
    fn step(&mut self, params: &ParamSet, time: &FrameTime) {
        let settings = Settings::read(params);
        self.ensure_state(&settings);
        let state = &mut self.state;
        if state.nan.poll(&state.status_readback) {
            self.messages.push("cloth: the simulation blew up (a position became NaN or infinite); reset to the rest pose — lower the time step or stiffness, or add substeps".into());
            let pose = rest_pose(state.res, settings.rest_length, settings.mass, state.pin);
            state.reset(&self.queue, &pose);
            self.pending.clear();
        }
        if self.pending.len() == self.uniforms.len() {
            self.pending.remove(0);
        }
        self.pending.push(ClothUniforms::from_params(&settings, time, state.res));
    }

    fn simulates_on_gpu(&self) -> bool {
        true
    }

    fn take_messages(&mut self) -> Vec<String> {
        std::mem::take(&mut self.messages)
    }

    fn save_state(&self, gpu: &Gpu, state: &mut NodeState) -> Result<(), CheckpointError> {
        self.state.save(gpu, state)
    }

    fn load_state(
        &mut self,
        gpu: &Gpu,
        params: &ParamSet,
        _time: &FrameTime,
        state: &NodeState,
    ) -> Result<(), CheckpointError> {
        self.ensure_state(&Settings::read(params));
        self.state.load(gpu, state)
    }

    fn add_passes<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        params: &ParamSet,
        time: &FrameTime,
        _inputs: &[TextureHandle],
    ) -> TextureHandle {
        let settings = Settings::read(params);
        self.ensure_state(&settings);
        // CPU work first: buffer rotation, bind groups and uniforms for every substep.
        let substeps = settings.substeps.clamp(1, 64) as u32;
        let steps = std::mem::take(&mut self.pending);
        for (slot, u) in steps.iter().enumerate() {
            self.queue.write_buffer(&self.uniforms[slot], 0, bytemuck::bytes_of(u));
        }
        let state = &mut self.state;
        let dispatches = state.plan(&self.device, &self.kernels.layout, &self.uniforms, &steps, substeps);
        let (w, h) = graph.output_size();
        let view = ClothView::from_params(&settings, time, (w, h));
        let debug = settings.view == View::Debug;
        self.renderer.prepare(&self.device, &self.queue, state, &view, debug);
        let this: &'r Cloth = self;
        let state = &this.state;

        let particles = state.import(graph);
        let count = state.res * state.res;
        let mut sim = graph.add_pass("cloth/simulate").side_effect();
        for &b in &particles {
            sim = sim.write_buffer(b);
        }
        sim.record(move |ctx| {
            let mut pass = ctx.encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("cloth/simulate"),
                timestamp_writes: None,
            });
            // Both solvers run one tiled dispatch per substep over the 2-D grid.
            let grid = [state.res, state.res, 1];
            for d in &dispatches {
                let kernel = match d.kernel {
                    state::Kernel::Verlet => &this.kernels.verlet,
                    state::Kernel::Xpbd => &this.kernels.xpbd,
                };
                kernel.dispatch(&mut pass, &[&state.bind_groups[&d.key]], grid);
            }
        });
        let normals = graph.import_buffer("cloth/normals", &state.normals, state.normals_id);
        let cur = particles[state.cur];
        graph.add_pass("cloth/normals").read_buffer(cur).write_buffer(normals).record(move |ctx| {
            let mut pass = ctx.encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("cloth/normals"),
                timestamp_writes: None,
            });
            this.kernels.normals.dispatch(&mut pass, &[&state.bind_groups[&state.normals_key()]], [count, 1, 1]);
            drop(pass);
            // The normals pass is also where the positions are checked for a blow-up.
            state.nan.after_check(ctx.encoder, &state.status, &state.status_readback);
        });
        let triangles = state.triangles(view.uniforms.sphere[3] > 0.0);
        let in_compute = !debug
            && settings.rasterizer.in_compute(this.renderer.tuned)
            && this
                .renderer
                .compute
                .as_ref()
                .is_some_and(|c| c.borrow_mut().prepare((w, h), this.renderer.samples, triangles, false));
        if in_compute {
            let compute = this.renderer.compute.as_ref().expect("prepared");
            let visibility = compute.borrow().declare_visibility(graph, "cloth/visibility");
            let image = graph.create_texture("cloth/image", TextureDesc::full(FORMAT));
            let b = view.background;
            let background = [b.r as f32, b.g as f32, b.b as f32, 1.0];
            let splat = SplatUniforms::new((w, h), triangles, this.renderer.samples, background);
            let group = &state.draw_groups[&state.cur];
            graph.add_pass("cloth/raster").read_buffer(cur).read_buffer(normals).write_buffer(visibility).record(
                move |ctx| {
                    let lent = ctx.buffer_and_id(visibility);
                    compute.borrow_mut().record_raster(ctx.encoder, ctx.queue, &splat, group, None, &lent);
                },
            );
            graph
                .add_pass("cloth/resolve")
                .read_buffer(cur)
                .read_buffer(normals)
                .read_buffer(visibility)
                .write(image)
                .record(move |ctx| {
                    // Views are shared handles: a clone frees the context for the encoder.
                    let (image_view, id) = (ctx.view(image).clone(), ctx.texture_id(image));
                    let lent = ctx.buffer_and_id(visibility);
                    compute.borrow_mut().record_resolve(ctx.encoder, group, None, &lent, (&image_view, id));
                });
            return image;
        }
        // The debug view draws without depth (see `render::Renderer::new`).
        let depth = (!debug).then_some(render::DEPTH);
        let targets = graph.create_raster_targets("cloth", FORMAT, depth, this.renderer.samples);
        let mode = render::DrawMode { clear: view.background, debug, sphere: view.uniforms.sphere[3] > 0.0 };
        graph
            .add_pass("cloth/draw")
            .read_buffer(cur)
            .read_buffer(normals)
            .draws_into(&targets)
            .record(move |ctx| this.renderer.draw(ctx, state, &targets, mode));
        targets.color
    }
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod render_tests;
