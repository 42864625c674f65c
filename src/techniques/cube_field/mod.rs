//! A field of small white cubes emitted from a rectangle, drifting towards the camera and
//! spinning, lit by a directional light with Blinn-Phong so that specular glints exceed 1.0 —
//! the HDR source of the book's StarGlow demo.
//!
//! Book: [UGP4 ch.4] sample scene (a Unity particle system; seed-reference §4). Here the particles
//! are a pure function of time and seed (no simulation state), so any frame renders alone and
//! identically. Shaders: `cube_field.wgsl`, and `cube_field_raster.wgsl` for the cubes drawn in
//! compute through `shaders/splat_draw.wgsl`.

mod particles;
#[cfg(test)]
mod render_tests;

use crate::gpu::ShaderError;
use crate::graph::{FrameGraph, TextureDesc, TextureHandle};
use crate::params::{ParamDecl, ParamSet, ParamValue};
use crate::time::FrameTime;
use std::cell::RefCell;

pub use particles::{CubeInstance, MAX_CUBES, cubes_at};

use super::splat_draw::{self, SplatDraw, SplatUniforms};
use super::visibility::PixelRays;
use super::{NodeSetup, Rasterizer, Technique, TechniqueInfo, srgb_to_linear};

/// The registry entry.
pub const INFO: TechniqueInfo = TechniqueInfo {
    name: "cube_field",
    chapter: "4: StarGlow (demo scene)",
    summary: "instanced spinning cubes with HDR specular glints",
    params: Settings::decls,
    inputs: &[],
    shaders: &["cube_field.wgsl", "cube_field_raster.wgsl", "splat_draw.wgsl", "msaa_samples.wgsl"],
    create,
    check: None,
    stage: None,
    declare: None,
};

/// Colour target format: linear HDR.
pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

crate::technique_params! {
    /// What a cube field reads each frame.
    pub struct Settings {
        /// cubes emitted per second
        rate: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(100.0), Some((0.0, 400.0)), doc).with_unit("/s"),
        /// seconds each cube lives
        life: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(10.0), Some((0.1, 30.0)), doc).with_unit("s"),
        /// drift towards the camera
        speed: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(1.0), Some((0.0, 10.0)), doc).with_unit("u/s"),
        /// rotation about each axis
        spin: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(100.0), Some((0.0, 720.0)), doc).with_unit("°/s"),
        /// edge length
        cube_size: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.1), Some((0.01, 1.0)), doc).with_unit("u"),
        /// width and height of the emitting rectangle
        emitter_size: [f32; 2] = |n, doc| ParamDecl::new(n, ParamValue::Vec2([5.0, 10.0]), Some((0.1, 50.0)), doc),
        /// distance of the emitter in front of the camera
        emitter_distance: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(12.0), Some((1.0, 50.0)), doc),
        /// vertical field of view
        fov: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(30.0), Some((5.0, 120.0)), doc).with_unit("°"),
        /// direction towards the light
        light_dir: [f32; 3] = |n, doc| ParamDecl::new(n, ParamValue::Vec3([-0.4, 0.5, -0.75]), Some((-1.0, 1.0)), doc),
        /// light intensity
        light_intensity: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.87), Some((0.0, 10.0)), doc),
        /// specular strength; above ~1.2 glints exceed 1.0
        // Narrow, strong highlights: single glints cross StarGlow's threshold of 1, faces do not.
        specular: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(2.0), Some((0.0, 20.0)), doc),
        /// Blinn-Phong exponent
        shininess: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(128.0), Some((1.0, 512.0)), doc),
        /// cube colour
        color: [f32; 4] = |n, doc| ParamDecl::new(n, ParamValue::Color([1.0, 1.0, 1.0, 1.0]), None, doc),
        /// how cubes are drawn — compute: found by a ray per sample into a visibility buffer
        /// (where the adapter has 64-bit atomics); pipeline: 12 triangles each through the
        /// hardware rasterizer
        rasterizer: Rasterizer = |n, doc| ParamDecl::choice(n, Rasterizer::OPTIONS, 0, doc),
    }
}

/// The shader's uniform block.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CubeFieldUniforms {
    /// Projection × view.
    pub view_proj: [[f32; 4]; 4],
    /// Towards the light, unit.
    pub light_dir: [f32; 4],
    /// Linear light colour × intensity.
    pub light_color: [f32; 4],
    /// Linear albedo.
    pub albedo: [f32; 4],
    /// Constant fill light.
    pub ambient: f32,
    /// Specular strength.
    pub specular: f32,
    /// Blinn-Phong exponent.
    pub shininess: f32,
    /// Padding.
    pub _pad: f32,
    /// The compute draw's ray through the image's top-left corner (from the camera at the origin).
    pub ray_origin: [f32; 4],
    /// The ray's change per pixel to the right.
    pub ray_x: [f32; 4],
    /// The ray's change per pixel down.
    pub ray_y: [f32; 4],
}

impl CubeFieldUniforms {
    /// Camera at the origin looking down +z, y up, wgpu's [0, 1] depth.
    pub fn from_params(p: &Settings, size: (u32, u32)) -> Self {
        let aspect = size.0 as f32 / size.1.max(1) as f32;
        // wgpu's clip space is DirectX's: z in [0, 1], y up.
        let proj = glam::camera::lh::proj::directx::perspective(p.fov.to_radians(), aspect, 0.1, 100.0);
        let view = glam::camera::lh::view::look_to_mat4(glam::Vec3::ZERO, glam::Vec3::Z, glam::Vec3::Y);
        let light = glam::Vec3::from(p.light_dir).normalize_or(glam::Vec3::NEG_Z);
        let c = p.color;
        let i = p.light_intensity;
        let rays = PixelRays::new(proj * view, glam::Vec3::ZERO, size);
        Self {
            view_proj: (proj * view).to_cols_array_2d(),
            light_dir: [light.x, light.y, light.z, 0.0],
            light_color: [i, i, i, 1.0],
            albedo: [srgb_to_linear(c[0]), srgb_to_linear(c[1]), srgb_to_linear(c[2]), 1.0],
            ambient: 0.08,
            specular: p.specular,
            shininess: p.shininess,
            _pad: 0.0,
            ray_origin: PixelRays::vec4(rays.origin, 0.0),
            ray_x: PixelRays::vec4(rays.x, 0.0),
            ray_y: PixelRays::vec4(rays.y, 0.0),
        }
    }
}

/// A cube field node.
pub struct CubeField {
    pipeline: wgpu::RenderPipeline,
    /// Samples per pixel of the draw (the scene's `msaa`, as the adapter allows).
    samples: u32,
    block: crate::gpu::UniformBlock,
    instances: wgpu::Buffer,
    scratch: Vec<CubeInstance>,
    /// The compute draw, where the adapter has 64-bit atomics (a cell: its passes keep bind
    /// groups while the graph holds the node shared).
    compute: Option<(RefCell<SplatDraw>, wgpu::BindGroup)>,
    /// What `rasterizer: auto` takes on this adapter.
    tuned: Rasterizer,
}

fn create(setup: &NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError> {
    let device = &setup.gpu.device;
    let shader = setup.joined_shader_source("cube_field.wgsl", &[("u", 0)])?;
    let origin = shader.origin().to_string();
    let (module, _) = crate::gpu::compile_wgsl(device, &origin, &shader.source).map_err(|e| shader.relocate(e))?;
    let block = crate::gpu::UniformBlock::new::<CubeFieldUniforms>(device, "cube_field_uniforms");
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
                    array_stride: size_of::<CubeInstance>() as u64,
                    step_mode: wgpu::VertexStepMode::Instance,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x4, 1 => Float32x4],
                })],
                topology: wgpu::PrimitiveTopology::TriangleList,
                color: FORMAT,
                depth: Some((DEPTH, wgpu::CompareFunction::Less)),
                additive: false,
                samples,
            },
        )
    })?;
    let instances = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("cube_field_instances"),
        size: (MAX_CUBES * size_of::<CubeInstance>()) as u64,
        usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let compute = if device.features().contains(splat_draw::FEATURES) {
        let (layout, view) = SplatDraw::uniform_view::<CubeFieldUniforms>(device, &block.buffer);
        let draw = SplatDraw::new(setup, "cube_field_raster.wgsl", &[("u", 0)], &layout, true)?;
        Some((RefCell::new(draw), view))
    } else {
        None
    };
    let scratch = Vec::with_capacity(MAX_CUBES);
    let tuned = setup.tuned_rasterizer(INFO.name);
    Ok(Box::new(CubeField { pipeline, samples, block, instances, scratch, compute, tuned }))
}

impl Technique for CubeField {
    fn add_passes<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        params: &ParamSet,
        time: &FrameTime,
        _inputs: &[TextureHandle],
    ) -> TextureHandle {
        let size = graph.output_size();
        let settings = Settings::read(params);
        let uniforms = CubeFieldUniforms::from_params(&settings, size);
        cubes_at(&settings, time, &mut self.scratch);
        let count = self.scratch.len() as u32;
        let in_compute = settings.rasterizer.in_compute(self.tuned)
            && self.compute.as_mut().is_some_and(|c| c.0.get_mut().prepare(size, self.samples, count, false));
        let this: &'r CubeField = self;
        if in_compute {
            return this.add_compute_passes(graph, uniforms, count);
        }
        let targets = graph.create_raster_targets("cube_field", FORMAT, Some(DEPTH), self.samples);
        graph.add_pass("cube_field/draw").draws_into(&targets).record(move |ctx| {
            ctx.queue.write_buffer(&this.block.buffer, 0, bytemuck::bytes_of(&uniforms));
            ctx.queue.write_buffer(&this.instances, 0, bytemuck::cast_slice(&this.scratch));
            let mut pass = ctx.begin_draw(&targets, wgpu::Color::BLACK);
            pass.set_pipeline(&this.pipeline);
            pass.set_bind_group(0, &this.block.bind_group, &[]);
            pass.set_vertex_buffer(0, this.instances.slice(..));
            pass.draw(0..36, 0..count);
        });
        targets.color
    }
}

impl CubeField {
    /// The cubes drawn in compute (after a successful `prepare`): coverage into the visibility
    /// buffer, then shading into a new image.
    fn add_compute_passes<'r>(
        &'r self,
        graph: &mut FrameGraph<'r>,
        uniforms: CubeFieldUniforms,
        count: u32,
    ) -> TextureHandle {
        let (compute, view) = self.compute.as_ref().expect("prepared");
        let visibility = compute.borrow().declare_visibility(graph, "cube_field/visibility");
        let image = graph.create_texture("cube_field/image", TextureDesc::full(FORMAT));
        let splat = SplatUniforms::new(graph.output_size(), count, self.samples, [0.0, 0.0, 0.0, 1.0]);
        graph.add_pass("cube_field/raster").write_buffer(visibility).record(move |ctx| {
            ctx.queue.write_buffer(&self.block.buffer, 0, bytemuck::bytes_of(&uniforms));
            ctx.queue.write_buffer(&self.instances, 0, bytemuck::cast_slice(&self.scratch));
            let lent = ctx.buffer_and_id(visibility);
            compute.borrow_mut().record_raster(ctx.encoder, ctx.queue, &splat, view, Some(&self.instances), &lent);
        });
        graph.add_pass("cube_field/resolve").read_buffer(visibility).write(image).record(move |ctx| {
            // Views are shared handles: a clone frees the context for the encoder.
            let (image_view, id) = (ctx.view(image).clone(), ctx.texture_id(image));
            let lent = ctx.buffer_and_id(visibility);
            compute.borrow_mut().record_resolve(ctx.encoder, view, Some(&self.instances), &lent, (&image_view, id));
        });
        image
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_layout_matches_the_wgsl_struct() {
        let source = include_str!("cube_field.wgsl");
        assert_eq!(
            crate::gpu::wgsl_struct_size(source, "CubeFieldUniforms"),
            Some(size_of::<CubeFieldUniforms>() as u32)
        );
    }
}
