//! Chapter 1: space colonization (Runions, Lane & Prusinkiewicz 2007) grown on the GPU. Branches
//! grow from seeds towards a cloud of attractions; each growth step is Search → Attract → Connect
//! → Remove → Grow (see `space_colonization.wgsl`), entirely on the GPU with indirect
//! dispatches and draws — no count is read back.
//!
//! Changes from the book's sample (seed-reference §1, §9 items 1–7), and why:
//! 1. Frames between growth updates (`update_every` > 1) still draw and still grow t (the sample
//!    returned before drawing: flicker).
//! 2. The growth direction is the normalised mean of the unit vectors (the sample's unnormalised
//!    mean gave short or zero steps and stacked nodes when attractions surround a node); a mean
//!    shorter than 1e-3 gives no candidate.
//! 3. Tubes are an instanced capsule mesh with a round cross-section and a whole hemispherical
//!    cap (the sample's geometry stage made pentagons and cut the cap short).
//! 4. Tubes are built in world space from posed end points, so the radius is the thickness in
//!    world units whatever the object's scale or skinning.
//! 5. Search and Remove visit a uniform grid over the nodes (a counting sort by cell, rebuilt on
//!    the GPU after every Connect) instead of every node; `search: BruteForce` keeps the
//!    sample's way for comparison. Counts and sizes stay on the GPU (indirect dispatch and
//!    draw; free slots cost nothing).
//! 6. Skinned nodes are posed with the full 4-weight linear blend of the vertex they took their
//!    skin from, every frame on the GPU (the sample used one rigid bone: tearing at joints).
//! 7. Growth and kill distances default to 0.25, inside their own range (the sample's 0.2 was not).
//!
//! Determinism: an attraction's nearest node is the lowest index among the closest; direction
//! sums are 16.16 fixed-point integers (atomic adds commute); a candidate's slot is its rank
//! among the flagged nodes in node order (a prefix sum), never the order atomics returned; the
//! mass hash is integer-only. The same scene, seed and frame give the same bytes.
//!
//! Slots: nodes occupy slots `0..count` and never die, so the free pool is `count..capacity`
//! (the sample's append/consume buffer, without the order a consume buffer would randomise).
//!
//! Book: [UGP4 ch.1] "GPU-Based Space Colonization Algorithm" (nakamura). Shaders:
//! `space_colonization.wgsl`, `space_colonization_draw.wgsl`, `space_colonization_raster.wgsl`
//! (the tubes in compute), `shaders/prefix_sum.wgsl`, `shaders/msaa_samples.wgsl`.

mod cloud;
mod compute_draw;
mod growth;
mod model;
mod params;
pub mod reference;
mod render;

pub use cloud::{Attraction, Cloud, NONE, Node};
pub use growth::{SkinData, VertexSkin};
pub use model::{Sampling, load as load_model};
pub use params::{GridLayout, GrowthUniforms, MAX_CELLS, PoseUniforms, Search, Settings, Source, View, ViewUniforms};
pub use render::{TUBE_CAP_ROWS, TUBE_SIDES, tube_indices};

use std::sync::Arc;

use growth::{BLOCK, GrowthState, Kernels};
use render::{Extras, Renderer, Style};

use crate::checkpoint::{CheckpointError, NodeState};
use crate::geometry::skinned::SkinnedMesh;
use crate::gpu::{Gpu, ShaderError};
use crate::graph::{FrameGraph, TextureDesc, TextureHandle};
use crate::params::ParamSet;
use crate::time::FrameTime;

use super::{NodeSetup, Rasterizer, Technique, TechniqueInfo, linear_rgba};

/// The registry entry.
pub const INFO: TechniqueInfo = TechniqueInfo {
    name: "space_colonization",
    chapter: "1: GPU-Based Space Colonization",
    summary: "branches grow towards a cloud of attractions, grid-accelerated on the GPU, drawn as lines or tubes",
    params: Settings::decls,
    inputs: &[],
    shaders: &[
        "space_colonization.wgsl",
        "space_colonization_draw.wgsl",
        "space_colonization_raster.wgsl",
        "msaa_samples.wgsl",
        "prefix_sum.wgsl",
    ],
    create,
    check: None,
    stage: None,
    declare: None,
};

/// The colour format.
pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// What the cloud was built from: a change restarts the growth.
#[derive(Clone, Debug, PartialEq)]
struct CloudKey {
    source: u32,
    side: i32,
    seed_count: i32,
    variation: i32,
    seed: u64,
    /// The model's path, voxels and spacing (Model source only).
    model: Option<(String, i32, u32)>,
}

impl CloudKey {
    fn of(p: &Settings, seed: u64) -> Self {
        Self {
            source: p.source.index(),
            side: p.side,
            seed_count: p.seed_count,
            variation: p.variation,
            seed,
            model: (p.source == Source::Model)
                .then(|| (p.model.as_str().trim().to_string(), p.voxels, p.spacing.to_bits())),
        }
    }

    /// The random seed of the jitter, the seeds and the masses.
    fn rng_seed(&self) -> u64 {
        self.seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ self.variation as u64
    }
}

/// A space colonization node.
pub struct SpaceColonization {
    device: wgpu::Device,
    queue: wgpu::Queue,
    kernels: Kernels,
    renderer: Renderer,
    /// One 256-byte growth uniform block per queued frame, bound at a dynamic offset.
    uniforms: wgpu::Buffer,
    state: GrowthState,
    /// What `state` was built from (a newer key waits while its model is read).
    key: CloudKey,
    /// Frames queued by `step` (uniforms, grid, growth steps), recorded by `add_passes`.
    pending: Vec<(GrowthUniforms, GridLayout, u32)>,
    frames_since_reset: u64,
    last: Option<GrowthUniforms>,
    messages: Vec<String>,
    /// Models read for the Model source.
    models: Models,
    /// The model the cloud was sampled from (it poses the nodes), if any.
    mesh: Option<Arc<SkinnedMesh>>,
    /// Whether the last frame's tubes were drawn in compute.
    drew_in_compute: bool,
    /// What `rasterizer: auto` takes on this adapter.
    tuned: Rasterizer,
}

/// The models a node reads: loaded off the render thread, the last one kept by path (a restart
/// does not read the file again).
struct Models {
    /// Where model paths are looked up, under the file rules.
    assets: crate::assets::Assets,
    /// Models being read and parsed off the render thread.
    loader: crate::files::Loader<SkinnedMesh>,
    /// The model path being loaded, if any.
    loading: Option<String>,
    /// The last model loaded, by path.
    loaded: Option<(String, Arc<SkinnedMesh>)>,
}

fn create(setup: &NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError> {
    Ok(Box::new(SpaceColonization::new(setup)?))
}

fn uniform_blocks(device: &wgpu::Device, blocks: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("sc_growth_uniforms"),
        size: blocks.max(1) * BLOCK,
        usage: crate::gpu::BLOCK_USAGE,
        mapped_at_creation: false,
    })
}

impl SpaceColonization {
    /// Builds the pipelines and the cloud the parameters ask for.
    pub fn new(setup: &NodeSetup<'_>) -> Result<Self, ShaderError> {
        let device = &setup.gpu.device;
        let (kernels, renderer) = (Kernels::new(setup)?, Renderer::new(setup, FORMAT)?);
        let mut models = Models {
            assets: setup.assets.clone(),
            loader: crate::files::Loader::new(setup.assets.load_wait()),
            loading: None,
            loaded: None,
        };
        let key = CloudKey::of(&Settings::read(setup.params), setup.seed);
        let mut messages = Vec::new();
        // A node's first load is waited for, so the scene's model is there from the start.
        let (cloud, skin, mesh) = models.cloud(&key, &mut messages).unwrap_or_else(|| sphere(&key));
        let growth = Growth { device, queue: &setup.gpu.queue, kernels: &kernels, index_count: renderer.index_count };
        let state = growth.state(&key, &cloud, &skin, mesh.is_some());
        Ok(Self {
            device: device.clone(),
            queue: setup.gpu.queue.clone(),
            kernels,
            renderer,
            uniforms: uniform_blocks(device, 8),
            state,
            key,
            pending: Vec::new(),
            frames_since_reset: 0,
            last: None,
            messages,
            models,
            mesh,
            drew_in_compute: false,
            tuned: setup.tuned_rasterizer(INFO.name),
        })
    }

    /// The attractions and the nodes in use, as the GPU holds them after the last submitted
    /// frame (blocking; for tests and tools).
    pub fn read(&self) -> (Vec<Attraction>, Vec<Node>) {
        self.state.read(&self.device, &self.queue)
    }

    /// Every node's drawn position (world, w = t) from the last drawn frame (blocking; tests).
    pub fn read_posed(&self) -> Vec<[f32; 4]> {
        let state = &self.state;
        let count = u64::from(state.node_count(&self.device, &self.queue));
        crate::gpu::read_buffer(&self.device, &self.queue, &state.posed.buffer, 0, count.max(1) * 16)
            .map(|b| bytemuck::pod_collect_to_vec(&b))
            .map(|v: Vec<[f32; 4]>| v[..count as usize].to_vec())
            .unwrap_or_default()
    }

    /// The model the attractions were sampled from (None for the sphere, or a model that failed).
    pub fn model(&self) -> Option<&SkinnedMesh> {
        self.mesh.as_deref()
    }

    /// Node slots (the attraction count, as in the book).
    pub fn capacity(&self) -> u32 {
        self.state.capacity
    }

    /// The uniforms of the last queued frame (its growth settings in local units).
    pub fn last_uniforms(&self) -> Option<GrowthUniforms> {
        self.last
    }

    /// Builds the cloud and seeds again if the source changed or a reset was asked for. While a
    /// new model is being read the last cloud keeps growing.
    fn ensure_state(&mut self, p: &Settings, seed: u64) {
        let key = CloudKey::of(p, seed);
        if self.key == key && !p.reset {
            return;
        }
        let Some((cloud, skin, mesh)) = self.models.cloud(&key, &mut self.messages) else { return };
        let growth = Growth {
            device: &self.device,
            queue: &self.queue,
            kernels: &self.kernels,
            index_count: self.renderer.index_count,
        };
        self.state = growth.state(&key, &cloud, &skin, mesh.is_some());
        self.mesh = mesh;
        self.key = key;
        self.pending.clear();
        self.frames_since_reset = 0;
    }
}

/// What a growth state is made with.
struct Growth<'a> {
    device: &'a wgpu::Device,
    queue: &'a wgpu::Queue,
    kernels: &'a Kernels,
    index_count: u32,
}

impl Growth<'_> {
    /// Seeds `cloud` and makes the GPU state growing in it, for `key`.
    fn state(&self, key: &CloudKey, cloud: &Cloud, skin: &SkinData, model: bool) -> GrowthState {
        let count = key.seed_count.clamp(1, 64) as usize;
        // The sphere keeps the book's random seeds; a model's limbs each need one.
        let seeds = if model { cloud.spread_seeds(count, key.rng_seed()) } else { cloud.seeds(count, key.rng_seed()) };
        GrowthState::new(self.device, self.queue, self.kernels, cloud, &seeds, skin, self.index_count)
    }
}

/// The key's lattice sphere.
fn sphere(key: &CloudKey) -> (Cloud, SkinData, Option<Arc<SkinnedMesh>>) {
    (Cloud::lattice_sphere(key.side.clamp(2, 128) as u32, key.rng_seed()), SkinData::default(), None)
}

/// Where the cloud of a step comes from.
enum ModelCloudLoad {
    /// The source is the sphere.
    Sphere,
    /// The model's cloud, sampled.
    Ready(ModelCloud),
    /// The model could not be read or sampled.
    Failed(String),
    /// The model is still being read.
    Pending,
}

/// A cloud sampled inside a model, its skins and the model.
type ModelCloud = (Cloud, SkinData, Arc<SkinnedMesh>);

impl Models {
    /// The cloud the key asks for: the sphere, or inside its model (a model that fails is one
    /// message and the sphere); `None` while the model is still being read.
    fn cloud(
        &mut self,
        key: &CloudKey,
        messages: &mut Vec<String>,
    ) -> Option<(Cloud, SkinData, Option<Arc<SkinnedMesh>>)> {
        match self.model_cloud(key) {
            ModelCloudLoad::Ready((cloud, skin, mesh)) => Some((cloud, skin, Some(mesh))),
            ModelCloudLoad::Failed(e) => {
                messages.push(format!("space_colonization: {e}; growing in the sphere instead"));
                Some(sphere(key))
            }
            ModelCloudLoad::Sphere => Some(sphere(key)),
            ModelCloudLoad::Pending => None,
        }
    }

    /// The cloud inside the key's model, if the source is a model: loaded (or reused) and sampled.
    /// The file is read and parsed off the render thread; sampling is bounded by the clamped
    /// voxel count.
    fn model_cloud(&mut self, key: &CloudKey) -> ModelCloudLoad {
        let Some((path, voxels, spacing)) = key.model.as_ref() else { return ModelCloudLoad::Sphere };
        let mesh = match &self.loaded {
            Some((loaded, mesh)) if loaded == path => mesh.clone(),
            _ => {
                if self.loading.as_deref() != Some(path.as_str()) {
                    let (assets, name) = (self.assets.clone(), path.clone());
                    self.loader.request(path, move || model::load(&assets, &name));
                    self.loading = Some(path.clone());
                }
                let Some((loaded, result)) = self.loader.poll() else { return ModelCloudLoad::Pending };
                if self.loading.as_deref() == Some(loaded.as_str()) {
                    self.loading = None;
                }
                match result {
                    Ok(mesh) => {
                        let mesh = Arc::new(mesh);
                        self.loaded = Some((loaded.clone(), mesh.clone()));
                        if loaded != *path {
                            return ModelCloudLoad::Pending;
                        }
                        mesh
                    }
                    Err(e) if loaded == *path => return ModelCloudLoad::Failed(e),
                    Err(_) => return ModelCloudLoad::Pending,
                }
            }
        };
        let sampling = Sampling {
            voxels: (*voxels).clamp(8, 256) as u32,
            spacing: f32::from_bits(*spacing),
            seed: key.rng_seed(),
        };
        let (cloud, skins) = model::cloud(&mesh, sampling);
        if cloud.attractions.is_empty() {
            return ModelCloudLoad::Failed(format!("{path}: no volume inside the mesh (is it closed?)"));
        }
        let skin = SkinData { skins, positions: mesh.positions.clone(), triangles: mesh.triangles.clone() };
        ModelCloudLoad::Ready((cloud, skin, mesh))
    }
}

impl SpaceColonization {
    /// The distance unit of the growth parameters: the sphere's 2 / side, or the model's voxel
    /// times `unit_scale`.
    fn unit(&self, params: &Settings) -> f32 {
        let base = self.state.unit;
        if self.mesh.is_some() { base * params.unit_scale } else { base }
    }

    /// The pose uniforms and joint matrices of this frame.
    fn pose(&self, params: &Settings, seconds: f64) -> (PoseUniforms, Vec<[[f32; 4]; 4]>) {
        let model = params::model(params, seconds);
        let joints = match &self.mesh {
            Some(mesh) => {
                let time = mesh.ping_pong(seconds, params.animation_speed);
                mesh.joint_matrices(time).iter().map(|m| m.to_cols_array_2d()).collect()
            }
            None => Vec::new(),
        };
        let skinned = u32::from(self.mesh.is_some());
        (PoseUniforms { model: model.to_cols_array_2d(), skinned, _pad: [0; 3] }, joints)
    }
}

impl Technique for SpaceColonization {
    fn simulates_on_gpu(&self) -> bool {
        true
    }

    fn step(&mut self, params: &ParamSet, time: &FrameTime) {
        let params = &Settings::read(params);
        self.ensure_state(params, time.seed);
        let state = &self.state;
        let every = params.update_every.clamp(1, 5) as u64;
        let steps = if self.frames_since_reset.is_multiple_of(every) { params.steps.clamp(1, 16) as u32 } else { 0 };
        let key = &self.key;
        let hash_seed = (key.rng_seed() ^ (key.rng_seed() >> 32)) as u32;
        let u = params::growth_uniforms(params, self.unit(params), time.dt);
        let (u, layout) = state.complete(u, hash_seed, self.renderer.index_count);
        self.pending.push((u, layout, steps));
        self.last = Some(u);
        self.frames_since_reset += 1;
    }

    fn take_messages(&mut self) -> Vec<String> {
        std::mem::take(&mut self.messages)
    }

    fn save_state(&self, gpu: &Gpu, state: &mut NodeState) -> Result<(), CheckpointError> {
        // Growth runs every `update_every` frames counted from the last reset.
        state.put_u64("frames_since_reset", self.frames_since_reset);
        self.state.save(gpu, state)
    }

    fn load_state(
        &mut self,
        gpu: &Gpu,
        params: &ParamSet,
        time: &FrameTime,
        state: &NodeState,
    ) -> Result<(), CheckpointError> {
        self.ensure_state(&Settings::read(params), time.seed);
        self.frames_since_reset = state.get_u64("frames_since_reset")?;
        self.state.load(gpu, &self.kernels, state)
    }

    fn bench_report(&mut self) -> Vec<String> {
        let (attractions, nodes) = self.read();
        let alive = attractions.iter().filter(|a| a.alive != 0).count();
        vec![format!(
            "{} nodes of {} slots, {} of {} attractions alive, drawn by {}",
            nodes.len(),
            self.capacity(),
            alive,
            attractions.len(),
            if self.drew_in_compute { "compute (exact capsules)" } else { "the raster pipeline" }
        )]
    }

    fn add_passes<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        params: &ParamSet,
        time: &FrameTime,
        _inputs: &[TextureHandle],
    ) -> TextureHandle {
        let params = &Settings::read(params);
        self.ensure_state(params, time.seed);
        let frames = std::mem::take(&mut self.pending);
        let blocks = frames.len().max(1) as u64;
        if self.uniforms.size() < blocks * BLOCK {
            self.uniforms = uniform_blocks(&self.device, blocks.next_power_of_two());
        }
        let mut bytes = vec![0u8; (blocks * BLOCK) as usize];
        for (i, (u, _, _)) in frames.iter().enumerate() {
            let at = i * BLOCK as usize;
            bytes[at..at + size_of::<GrowthUniforms>()].copy_from_slice(bytemuck::bytes_of(u));
        }
        self.queue.write_buffer(&self.uniforms, 0, &bytes);
        let cells = frames.iter().map(|f| f.1.cells()).max().unwrap_or(1);
        let state = &mut self.state;
        state.prepare(&self.device, &self.kernels, &self.uniforms, cells);
        let ops = state.plan(&frames);

        let (w, h) = graph.output_size();
        let (pose, joints) = self.pose(params, time.seconds);
        let state = &self.state;
        state.set_pose(&self.queue, &pose, &joints);
        let (eye, view_proj) = params::view_proj(params, w as f32 / h.max(1) as f32);
        let light = glam::Vec3::from(params.light_dir).normalize_or(glam::Vec3::Y);
        let view = ViewUniforms {
            view_proj: view_proj.to_cols_array_2d(),
            camera: [eye.x, eye.y, eye.z, 1.0],
            color: linear_rgba(params.color),
            light: [light.x, light.y, light.z, params.emission],
            thickness: params.thickness,
            seed_count: state.seed_count,
            lit: u32::from(params.view == View::TubesLit),
            ghost: if params.show_model && self.mesh.is_some() { 0.6 } else { 0.0 },
            model: pose.model,
            floor: {
                let c = linear_rgba(params.floor_color);
                [c[0], c[1], c[2], if params.floor { 12.0 } else { 0.0 }]
            },
        };
        let extras = Extras { floor: view.floor[3] > 0.0, mesh: view.ghost > 0.0 };
        let samples = params.msaa.samples(self.renderer.samples);
        self.renderer.prepare(&self.device, &self.queue, &self.state, &view);
        let b = linear_rgba(params.background);
        let clear = wgpu::Color { r: f64::from(b[0]), g: f64::from(b[1]), b: f64::from(b[2]), a: 1.0 };
        let style = if params.view == View::Lines { Style::Lines } else { Style::Tubes };
        // Tubes go to the compute draw with the floor and the glow; lines (added up whatever
        // their depth) stay with the pipeline.
        let glow_triangles = if extras.mesh { self.state.mesh.index_count / 3 } else { 0 };
        let in_compute = style == Style::Tubes && params.rasterizer.in_compute(self.tuned) && {
            let u = compute_draw::RasterUniforms::new(view_proj, eye, (w, h), samples, self.state.capacity, b)
                .with_extras(extras.floor, glow_triangles);
            self.renderer.prepare_compute(&self.queue, &u)
        };
        self.drew_in_compute = in_compute;

        let this: &'r SpaceColonization = self;
        let state = &this.state;
        let nodes = graph.import_buffer("space_colonization/nodes", &state.nodes.buffer, state.nodes.id);
        let attractions =
            graph.import_buffer("space_colonization/attractions", &state.attractions.buffer, state.attractions.id);
        let args = graph.import_buffer("space_colonization/args", &state.args.buffer, state.args.id);
        let posed = graph.import_buffer("space_colonization/posed", &state.posed.buffer, state.posed.id);
        graph
            .add_pass("space_colonization/grow")
            .write_buffer(nodes)
            .write_buffer(attractions)
            .write_buffer(args)
            .record(move |ctx| {
                let mut pass = ctx.encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("space_colonization/grow"),
                    timestamp_writes: None,
                });
                state.record(&mut pass, &this.kernels, &ops);
            });
        if graph.is_simulation_only() {
            return graph.create_texture("space_colonization/image", TextureDesc::full(FORMAT));
        }
        graph.add_pass("space_colonization/pose").read_buffer(nodes).read_buffer(args).write_buffer(posed).record(
            move |ctx| {
                let mut pass = ctx.encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("space_colonization/pose"),
                    timestamp_writes: None,
                });
                state.record_pose(&mut pass, &this.kernels);
            },
        );
        if in_compute {
            let lent = this.renderer.declare_compute_buffers(graph, glow_triangles > 0).expect("prepared");
            let visibility = lent.visibility;
            let image = graph.create_texture("space_colonization/image", TextureDesc::full(FORMAT));
            graph
                .add_pass("space_colonization/raster")
                .read_buffer(posed)
                .read_buffer(nodes)
                .read_buffer(args)
                .write_buffer(visibility)
                .record(move |ctx| this.renderer.record_compute_raster(ctx, state, lent));
            if let Some(glow) = lent.glow_sum {
                graph
                    .add_pass("space_colonization/glow")
                    .read_buffer(visibility)
                    .write_buffer(glow)
                    .record(move |ctx| this.renderer.record_compute_glow(ctx, state, lent));
            }
            let resolve = graph.add_pass("space_colonization/resolve");
            let resolve = match lent.glow_sum {
                Some(glow) => resolve.read_buffer(glow),
                None => resolve,
            };
            resolve
                .read_buffer(posed)
                .read_buffer(nodes)
                .read_buffer(visibility)
                .write(image)
                .record(move |ctx| this.renderer.record_compute_resolve(ctx, state, lent, image));
            return image;
        }
        // The pipeline's targets only where it draws: the compute draw needs none of them.
        let depth = extras.need_depth(style).then_some(render::DEPTH);
        let targets = graph.create_raster_targets("space_colonization", FORMAT, depth, samples);
        graph
            .add_pass("space_colonization/draw")
            .read_buffer(posed)
            .read_buffer(nodes)
            .read_buffer(args)
            .draws_into(&targets)
            .record(move |ctx| this.renderer.draw(ctx, state, &targets, style, extras, clear));
        targets.color
    }
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod render_tests;
