//! Poisson disk samples growing step by step [UGP4 ch.7]: the 2-D set as flat discs seen from
//! above, the 3-D set as lit spheres seen by an orbiting camera, both coloured by insertion order
//! (first samples deep blue, through magenta, newest yellow). Sampling is [`crate::geometry::poisson`] on the CPU;
//! each fixed step runs `steps_per_step` sampler steps and only new samples are uploaded.
//! Changing dimensions, radius, attempts, extent or seed restarts the run (so does `restart`).
//! Shaders: `poisson.wgsl` (instanced quads: discs, or sphere impostors), `poisson_raster.wgsl`
//! (the same discs drawn in compute through `shaders/splat_draw.wgsl`),
//! `shaders/msaa_samples.wgsl`.

use crate::checkpoint::{CheckpointError, NodeState};
use crate::gpu::{Gpu, ShaderError};
use crate::graph::{FrameGraph, TextureDesc, TextureHandle};
use crate::params::{InputRole, ParamDecl, ParamSet, ParamValue};
use crate::time::FrameTime;
use std::cell::RefCell;

mod sampler;

use sampler::Sampler;

use super::splat_draw::{self, SplatDraw, SplatUniforms};
use super::{NodeSetup, Rasterizer, Technique, TechniqueInfo};

/// The registry entry.
pub const INFO: TechniqueInfo = TechniqueInfo {
    name: "poisson",
    chapter: "7: Fast Poisson disk sampling",
    summary: "Bridson Poisson disk samples in 2-D or 3-D, growing step by step",
    params: Settings::decls,
    inputs: &[],
    shaders: &["poisson.wgsl", "poisson_raster.wgsl", "splat_draw.wgsl", "msaa_samples.wgsl"],
    create,
    check: Some(check_settings),
    stage: None,
    declare: None,
};

const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

crate::param_enum! {
    /// Whether a rectangle or a box is sampled.
    pub enum Dimensions {
        /// A rectangle, drawn as discs.
        Two = "2d",
        /// A box, drawn as spheres.
        Three = "3d",
    }
}

crate::technique_params! {
    /// What a Poisson node reads each step; defaults are the sample's 2-D scene
    /// (seed-reference §7).
    pub struct Settings {
        /// sample a rectangle (discs) or a box (spheres)
        dimensions: Dimensions = |n, doc| ParamDecl::choice(n, Dimensions::OPTIONS, 0, doc),
        /// minimum distance between samples
        radius: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(5.0), Some((0.5, 100.0)), doc).with_unit("u"),
        /// candidates per active sample before it retires (k)
        attempts: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(30), Some((1.0, 200.0)), doc),
        /// size of the box (2-D uses x, y)
        extent: [f32; 3] = |n, doc| ParamDecl::new(n, ParamValue::Vec3([200.0; 3]), Some((1.0, 10000.0)), doc),
        /// seed of every random choice
        seed: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(1), Some((0.0, 1e9)), doc),
        /// sampler steps per fixed time step
        steps_per_step: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(2), Some((0.0, 100000.0)), doc),
        /// drawn radius = radius × draw_scale / 2
        draw_scale: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(1.0), Some((0.05, 2.0)), doc),
        /// 3-D camera orbit
        orbit_speed: f32 =
            |n, doc| ParamDecl::new(n, ParamValue::Float(10.0), Some((-360.0, 360.0)), doc).with_unit("°/s"),
        /// how discs are drawn — compute: found per sample in a visibility buffer (where the
        /// adapter has 64-bit atomics); pipeline: instanced quads through the hardware rasterizer
        rasterizer: Rasterizer = |n, doc| ParamDecl::choice(n, Rasterizer::OPTIONS, 0, doc),
        /// start sampling again from one seed point (R in the window)
        restart: bool = |n, doc| ParamDecl::trigger(n, doc).with_role(InputRole::Key('r')),
    }
}

/// The shader's uniform block.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PoissonUniforms {
    /// Projection × view.
    pub view_proj: [[f32; 4]; 4],
    /// Camera right (world, unit) — billboard axis.
    pub right: [f32; 4],
    /// Camera up (world, unit) — billboard axis.
    pub up: [f32; 4],
    /// Drawn radius of a sample.
    pub draw_radius: f32,
    /// Samples so far (for the colour ramp).
    pub count: f32,
    /// 0: flat discs, 1: lit spheres.
    pub spheres: u32,
    /// Samples per pixel of the draw (the shader cuts each disc's rim per sample).
    pub samples: u32,
}

/// What restarts a run when it changes.
#[derive(Clone, Debug, PartialEq)]
struct RunKey {
    three_d: bool,
    radius: f32,
    attempts: i32,
    extent: [f32; 3],
    seed: i32,
}

/// The most memory one run may take: its grid, and every sample it can hold on the CPU and the
/// GPU. Each setting's range alone allows 10⁴ × 10⁴ × 10⁴ at radius 0.5, 4·10¹³ grid cells.
pub const RUN_BUDGET: u64 = 512 << 20;

impl RunKey {
    fn of(p: &Settings) -> Self {
        Self {
            three_d: p.dimensions == Dimensions::Three,
            radius: p.radius,
            attempts: p.attempts,
            extent: p.extent,
            seed: p.seed,
        }
    }

    /// Whether a run of these settings fits [`RUN_BUDGET`].
    fn fits(&self) -> bool {
        self.cost() <= RUN_BUDGET as f64
    }

    /// The bytes a run of these settings may take at most: 4 per grid cell, and per sample its
    /// point (8 per dimension), its instance (16) and active-list entry (8), for the most samples
    /// r apart the box can hold (discs of radius r/2 packed into the box grown by r).
    fn cost(&self) -> f64 {
        let n: usize = if self.three_d { 3 } else { 2 };
        let r = f64::from(self.radius);
        let cell = r / (n as f64).sqrt();
        let extent = &self.extent[..n];
        let cells: f64 = extent.iter().map(|e| (f64::from(*e) / cell).ceil().max(1.0)).product();
        let ball = if n == 3 {
            4.0 / 3.0 * std::f64::consts::PI * (r / 2.0).powi(3)
        } else {
            std::f64::consts::PI * (r / 2.0).powi(2)
        };
        let samples = extent.iter().map(|e| f64::from(*e) + r).product::<f64>() / ball;
        cells * 4.0 + samples * (8.0 * n as f64 + 24.0)
    }

    /// These settings, or with the least radius that fits [`RUN_BUDGET`] (a message says so).
    fn within_budget(mut self) -> (Self, Option<String>) {
        if self.fits() {
            return (self, None);
        }
        let asked = self.radius;
        let (mut lo, mut hi) = (f64::from(asked), f64::from(self.extent.iter().copied().fold(1.0, f32::max)));
        for _ in 0..60 {
            let mid = (lo + hi) / 2.0;
            self.radius = mid as f32;
            if self.fits() { hi = mid } else { lo = mid }
        }
        self.radius = hi as f32;
        let message = format!(
            "poisson: radius {asked} in a box of {:?} would need {:.0} MiB; sampling at radius {:.3}, the least within the {} MiB budget",
            if self.three_d { &self.extent[..] } else { &self.extent[..2] },
            RunKey { radius: asked, ..self.clone() }.cost() / f64::from(1u32 << 20),
            self.radius,
            RUN_BUDGET >> 20
        );
        (self, Some(message))
    }
}

/// Refuses settings whose run would pass [`RUN_BUDGET`] (see [`TechniqueInfo::check`]).
fn check_settings(params: &ParamSet) -> Result<(), String> {
    let key = RunKey::of(&Settings::read(params));
    if key.fits() {
        return Ok(());
    }
    let cost = key.cost();
    Err(format!(
        "radius {} in a box of {:?} ({}) needs about {:.0} MiB, more than the {} MiB a Poisson run may take: raise the radius or shrink the extent",
        key.radius,
        key.extent,
        if key.three_d { "3-D" } else { "2-D" },
        cost / f64::from(1u32 << 20),
        RUN_BUDGET >> 20
    ))
}

/// A Poisson disk node.
pub struct Poisson {
    pipeline: wgpu::RenderPipeline,
    /// Samples per pixel of the draw (the scene's `msaa`, as the adapter allows).
    samples: u32,
    block: crate::gpu::UniformBlock,
    instances: crate::gpu::GrowableBuffer,
    /// Samples already in `instances`.
    uploaded: usize,
    /// The settings of the run.
    key: RunKey,
    /// The settings the sampler runs with: `key`, its radius raised to fit the budget.
    fitted: RunKey,
    sampler: Sampler,
    messages: Vec<String>,
    /// The first frame whose sampler steps have not run yet: frames skipped by a seek are caught
    /// up, so frame N renders the same whether reached by playing or by seeking.
    next_frame: u64,
    pending: Vec<[f32; 4]>,
    device: wgpu::Device,
    /// The compute draw, where the adapter has 64-bit atomics (a cell: its passes keep bind
    /// groups while the graph holds the node shared).
    compute: Option<(RefCell<SplatDraw>, wgpu::BindGroup)>,
    /// What `rasterizer: auto` takes on this adapter.
    tuned: Rasterizer,
}

/// Bytes of one instance: position and insertion index.
const INSTANCE: u64 = size_of::<[f32; 4]>() as u64;

fn create(setup: &NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError> {
    let device = &setup.gpu.device;
    let shader = setup.joined_shader_source("poisson.wgsl", &[("u", 0)])?;
    let origin = shader.origin().to_string();
    let (module, _) = crate::gpu::compile_wgsl(device, &origin, &shader.source).map_err(|e| shader.relocate(e))?;
    let block = crate::gpu::UniformBlock::new::<PoissonUniforms>(device, "poisson_uniforms");
    let samples = setup.samples_for(&[FORMAT, DEPTH]);
    let pipeline = crate::gpu::validated(device, &origin, || {
        crate::gpu::raster_pipeline(
            device,
            &module,
            &block.pipeline_layout,
            &crate::gpu::RasterDesc {
                vertex: "vs_main",
                fragment: "fs_main",
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: INSTANCE,
                    step_mode: wgpu::VertexStepMode::Instance,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x4],
                })],
                topology: wgpu::PrimitiveTopology::TriangleList,
                color: FORMAT,
                depth: Some((DEPTH, wgpu::CompareFunction::Less)),
                additive: false,
                samples,
            },
        )
    })?;
    let compute = if device.features().contains(splat_draw::FEATURES) {
        let (layout, view) = SplatDraw::uniform_view::<PoissonUniforms>(device, &block.buffer);
        let draw = SplatDraw::new(setup, "poisson_raster.wgsl", &[("u", 0)], &layout, true)?;
        Some((RefCell::new(draw), view))
    } else {
        None
    };
    let usage = wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::STORAGE;
    let instances = crate::gpu::GrowableBuffer::new(device, "poisson_instances", usage, 4096 * INSTANCE);
    // The scene's run starts at frame 0; later runs start in the frame that asks for them.
    let key = RunKey::of(&Settings::read(setup.params));
    let (fitted, message) = key.clone().within_budget();
    Ok(Box::new(Poisson {
        pipeline,
        samples,
        block,
        instances,
        uploaded: 0,
        sampler: Sampler::new(&fitted),
        key,
        fitted,
        messages: message.into_iter().collect(),
        next_frame: 0,
        pending: Vec::new(),
        device: device.clone(),
        compute,
        tuned: setup.tuned_rasterizer(INFO.name),
    }))
}

impl Poisson {
    /// Restarts the run if its settings changed or `restart` fired; it counts from this frame.
    fn sync(&mut self, settings: &Settings, time: &FrameTime) {
        let key = RunKey::of(settings);
        if self.key != key || settings.restart {
            let (fitted, message) = key.clone().within_budget();
            self.messages.extend(message);
            self.sampler = Sampler::new(&fitted);
            self.fitted = fitted;
            self.key = key;
            self.uploaded = 0;
            self.next_frame = time.frame;
        }
    }
}

impl Technique for Poisson {
    fn step(&mut self, params: &ParamSet, time: &FrameTime) {
        let settings = Settings::read(params);
        self.sync(&settings, time);
        let frames = (time.frame + 1).saturating_sub(self.next_frame);
        self.next_frame = time.frame + 1;
        for _ in 0..frames * settings.steps_per_step.max(0) as u64 {
            if !self.sampler.step() {
                break;
            }
        }
    }

    fn take_messages(&mut self) -> Vec<String> {
        std::mem::take(&mut self.messages)
    }

    fn save_state(&self, _gpu: &Gpu, state: &mut NodeState) -> Result<(), CheckpointError> {
        let (points, active, rng) = self.sampler.progress();
        state.put_pod("points", &points);
        state.put_pod("active", &active);
        state.put_u64("rng", rng);
        state.put_u64("next_frame", self.next_frame);
        Ok(())
    }

    fn load_state(
        &mut self,
        _gpu: &Gpu,
        params: &ParamSet,
        time: &FrameTime,
        state: &NodeState,
    ) -> Result<(), CheckpointError> {
        self.sync(&Settings::read(params), time);
        let (points, active) = (state.get_pod::<f64>("points")?, state.get_pod::<u64>("active")?);
        self.sampler = Sampler::resume(&self.fitted, &points, active, state.get_u64("rng")?)
            .ok_or_else(|| state.error("points", "are not a run of this node's settings".into()))?;
        self.next_frame = state.get_u64("next_frame")?;
        self.uploaded = 0;
        self.pending.clear();
        Ok(())
    }

    fn add_passes<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        params: &ParamSet,
        time: &FrameTime,
        _inputs: &[TextureHandle],
    ) -> TextureHandle {
        // Runs (and restarts) are decided in `step`.
        let settings = Settings::read(params);
        let key = self.fitted.clone();
        let sampler = &self.sampler;
        let count = sampler.len();
        let new_buffer = self.instances.reserve(&self.device, count as u64 * INSTANCE);
        if new_buffer {
            // A new buffer: everything is uploaded again.
            self.uploaded = 0;
        }
        self.pending.clear();
        let first_new = self.uploaded;
        sampler.instances_from(first_new, &key, &mut self.pending);
        self.uploaded = count;

        let (w, h) = graph.output_size();
        let uniforms = camera(&key, &settings, time, w as f32 / h as f32, count, self.samples);
        let in_compute = settings.rasterizer.in_compute(self.tuned)
            && self
                .compute
                .as_mut()
                .is_some_and(|c| c.0.get_mut().prepare((w, h), self.samples, count as u32, new_buffer));
        if in_compute {
            return self.add_compute_passes(graph, uniforms, first_new, count as u32);
        }
        let targets = graph.create_raster_targets("poisson", FORMAT, Some(DEPTH), self.samples);
        let this: &'r Poisson = self;
        graph.add_pass("poisson/draw").draws_into(&targets).record(move |ctx| {
            this.upload(ctx.queue, &uniforms, first_new);
            let mut pass = ctx.begin_draw(&targets, wgpu::Color::BLACK);
            pass.set_pipeline(&this.pipeline);
            pass.set_bind_group(0, &this.block.bind_group, &[]);
            pass.set_vertex_buffer(0, this.instances.buffer().slice(..));
            pass.draw(0..6, 0..count as u32);
        });
        targets.color
    }
}

impl Poisson {
    /// Writes this frame's uniforms and the samples new since `first_new`.
    fn upload(&self, queue: &wgpu::Queue, uniforms: &PoissonUniforms, first_new: usize) {
        queue.write_buffer(&self.block.buffer, 0, bytemuck::bytes_of(uniforms));
        if !self.pending.is_empty() {
            let offset = first_new as u64 * INSTANCE;
            queue.write_buffer(self.instances.buffer(), offset, bytemuck::cast_slice(&self.pending));
        }
    }

    /// The discs drawn in compute (after a successful `prepare`): coverage into the visibility
    /// buffer, then shading into a new image.
    fn add_compute_passes<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        uniforms: PoissonUniforms,
        first_new: usize,
        count: u32,
    ) -> TextureHandle {
        let this: &'r Poisson = self;
        let (compute, view) = this.compute.as_ref().expect("prepared");
        let visibility = compute.borrow().declare_visibility(graph, "poisson/visibility");
        let image = graph.create_texture("poisson/image", TextureDesc::full(FORMAT));
        let raster = SplatUniforms::new(graph.output_size(), count, uniforms.samples, [0.0, 0.0, 0.0, 1.0]);
        graph.add_pass("poisson/raster").write_buffer(visibility).record(move |ctx| {
            this.upload(ctx.queue, &uniforms, first_new);
            let lent = ctx.buffer_and_id(visibility);
            let instances = Some(this.instances.buffer());
            compute.borrow_mut().record_raster(ctx.encoder, ctx.queue, &raster, view, instances, &lent);
        });
        graph.add_pass("poisson/resolve").read_buffer(visibility).write(image).record(move |ctx| {
            // Views are shared handles: a clone frees the context for the encoder.
            let (image_view, id) = (ctx.view(image).clone(), ctx.texture_id(image));
            let lent = ctx.buffer_and_id(visibility);
            let instances = Some(this.instances.buffer());
            compute.borrow_mut().record_resolve(ctx.encoder, view, instances, &lent, (&image_view, id));
        });
        image
    }
}

/// 2-D: orthographic, top-down, the rectangle fitted with a 5% margin. 3-D: perspective (60°),
/// orbiting the box slightly from above, far enough that the box's bounding sphere (and the
/// spheres drawn at its corners) fits the narrower field of view at every angle.
fn camera(
    key: &RunKey,
    settings: &Settings,
    time: &FrameTime,
    aspect: f32,
    count: usize,
    samples: u32,
) -> PoissonUniforms {
    use glam::Vec3;
    let draw_radius = key.radius * settings.draw_scale / 2.0;
    let (view_proj, right, up) = if key.three_d {
        let diagonal = Vec3::from(key.extent).length();
        let angle = (settings.orbit_speed * time.seconds as f32).to_radians();
        let half_fov = 30f32.to_radians();
        let narrowest = half_fov.min((half_fov.tan() * aspect).atan());
        let distance = (diagonal / 2.0 + draw_radius) / narrowest.sin() * 1.02;
        let eye = Vec3::new(angle.sin(), 0.35, -angle.cos()).normalize() * distance;
        let view = glam::camera::lh::view::look_at_mat4(eye, Vec3::ZERO, Vec3::Y);
        let proj =
            glam::camera::lh::proj::directx::perspective(60f32.to_radians(), aspect, diagonal * 0.05, diagonal * 5.0);
        let inverse = view.inverse();
        (proj * view, inverse.x_axis.truncate(), inverse.y_axis.truncate())
    } else {
        let half = [key.extent[0] / 2.0 * 1.05, key.extent[1] / 2.0 * 1.05];
        let (hw, hh) =
            if half[0] / half[1] > aspect { (half[0], half[0] / aspect) } else { (half[1] * aspect, half[1]) };
        let proj = glam::camera::lh::proj::directx::orthographic(-hw, hw, -hh, hh, -1.0, 1.0);
        (proj, Vec3::X, Vec3::Y)
    };
    PoissonUniforms {
        view_proj: view_proj.to_cols_array_2d(),
        right: right.extend(0.0).into(),
        up: up.extend(0.0).into(),
        draw_radius,
        count: count as f32,
        spheres: u32::from(key.three_d),
        samples,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_whole_box_stays_in_view_at_every_orbit_angle() {
        let mut p = ParamSet::new(Settings::decls());
        p.set_at(p.index("dimensions").unwrap(), crate::params::ParamValue::Enum(1));
        p.set_at(p.index("extent").unwrap(), crate::params::ParamValue::Vec3([200.0, 200.0, 200.0]));
        let settings = Settings::read(&p);
        let key = RunKey::of(&settings);
        for aspect in [16.0 / 9.0, 1.0, 9.0 / 16.0] {
            for frame in (0..7200).step_by(50) {
                let time = FrameTime { frame, seconds: frame as f64 / 60.0, dt: 1.0 / 60.0, seed: 1 };
                let u = camera(&key, &settings, &time, aspect, 0, 1);
                let view_proj = glam::Mat4::from_cols_array_2d(&u.view_proj);
                for corner in 0..8 {
                    let c = glam::Vec3::new(
                        if corner & 1 == 0 { -100.0 } else { 100.0 },
                        if corner & 2 == 0 { -100.0 } else { 100.0 },
                        if corner & 4 == 0 { -100.0 } else { 100.0 },
                    );
                    let clip = view_proj * c.extend(1.0);
                    let (x, y) = (clip.x / clip.w, clip.y / clip.w);
                    assert!(
                        x.abs() <= 1.0 && y.abs() <= 1.0,
                        "aspect {aspect}, frame {frame}: corner {c} at ({x}, {y})"
                    );
                }
            }
        }
    }

    #[test]
    fn in_range_settings_too_large_for_memory_are_refused_by_check_and_fitted_live() {
        let mut p = ParamSet::new(Settings::decls());
        assert!(check_settings(&p).is_ok(), "the defaults fit");
        p.set_at(p.index("dimensions").unwrap(), crate::params::ParamValue::Enum(1));
        p.set_at(p.index("extent").unwrap(), crate::params::ParamValue::Vec3([10000.0; 3]));
        p.set_at(p.index("radius").unwrap(), crate::params::ParamValue::Float(0.5));
        p.snap();
        let e = check_settings(&p).unwrap_err();
        assert!(e.contains("MiB") && e.contains("raise the radius"), "{e}");
        let (fitted, message) = RunKey::of(&Settings::read(&p)).within_budget();
        assert!(message.is_some_and(|m| m.contains("least within")));
        assert!(fitted.cost() <= RUN_BUDGET as f64 && fitted.cost() > RUN_BUDGET as f64 * 0.99, "{}", fitted.radius);
        // The fitted run really is small: its grid allocates within the budget.
        let sampler = Sampler::new(&fitted);
        assert_eq!(sampler.len(), 1);
    }

    #[test]
    fn uniform_layout_matches_the_wgsl_struct() {
        let source = [include_str!("../../../shaders/msaa_samples.wgsl"), include_str!("poisson.wgsl")].join("\n");
        assert_eq!(crate::gpu::wgsl_struct_size(&source, "PoissonUniforms"), Some(size_of::<PoissonUniforms>() as u32));
    }
}

#[cfg(test)]
mod render_tests;
