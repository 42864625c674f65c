//! Limit sets of Kleinian groups: Jos Leys' escape-time membership test for the Maskit slice,
//! drawn full-screen by a compute shader, with jittered supersampling and circle inversion.
//!
//! Book: [UGP4 ch.2] "Limit sets of Kleinian groups" (fuqunaga). Reference: [Leys] J. Leys,
//! "A fast algorithm for limit sets of Kleinian groups with the Maskit parametrisation".
//! Shader: `kleinian.wgsl`. Goldens: `golden/`, made by `render_tests.rs`.

pub mod reference;

use crate::gpu::{BindGroupCache, ComputeKernel, ShaderError};
use crate::graph::{FrameGraph, TextureDesc, TextureHandle};
use crate::params::{ParamDecl, ParamSet, ParamValue};
use crate::time::FrameTime;

use super::{NodeSetup, Technique, TechniqueInfo, linear_rgba};

/// The registry entry.
pub const INFO: TechniqueInfo = TechniqueInfo {
    name: "kleinian",
    chapter: "2: Limit sets of Kleinian groups",
    summary: "Jos Leys' escape-time limit set of the Maskit slice, with circle inversion",
    params,
    inputs: &[],
    shaders: &["kleinian.wgsl"],
    create,
    check: None,
    stage: None,
    declare: None,
};

/// The output format: linear HDR so that post effects (StarGlow) can follow.
pub const OUTPUT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

crate::technique_params! {
    /// What a limit-set node reads each step, with the book sample's C# defaults
    /// (seed-reference §2).
    pub struct Settings {
        /// Maskit parameter t = (u, v); (2, 0) is the classic set, near (1.94, 0.02) it turns intricate
        t: [f32; 2] = |n, doc| ParamDecl::new(n, ParamValue::Vec2([2.0, 0.0]), Some((-2.5, 2.5)), doc),
        /// escape-time iteration cap per sample
        iterations: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(500), Some((1.0, 5000.0)), doc),
        /// fractal units per output height (zoom out)
        scale: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(1.0), Some((0.01, 50.0)), doc),
        /// fractal position of the bottom-left corner
        offset: [f32; 2] = |n, doc| ParamDecl::new(n, ParamValue::Vec2([0.0, 0.0]), Some((-20.0, 20.0)), doc),
        /// colour inside the limit set's disks
        hit_color: [f32; 4] = |n, doc| ParamDecl::new(n, ParamValue::Color([1.0, 0.0, 0.0, 1.0]), None, doc),
        /// background colour
        back_color: [f32; 4] = |n, doc| ParamDecl::new(n, ParamValue::Color([0.5, 0.5, 0.5, 1.0]), None, doc),
        /// jittered samples per pixel (anti-aliasing)
        samples: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(1), Some((1.0, 64.0)), doc),
        /// invert the plane in a circle before the test
        circle_inversion: bool = |n, doc| ParamDecl::new(n, ParamValue::Bool(false), None, doc),
        /// inversion circle centre
        circle_center: [f32; 2] = |n, doc| ParamDecl::new(n, ParamValue::Vec2([0.0, 0.0]), Some((-20.0, 20.0)), doc),
        /// inversion circle radius
        circle_radius: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(1.0), Some((0.01, 20.0)), doc),
    }
}

/// Parameters (see [`Settings`]).
pub fn params() -> Vec<ParamDecl> {
    Settings::decls()
}

/// The shader's uniform block; layout checked against naga's reflection in the tests.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct KleinianUniforms {
    /// (u, v).
    pub t: [f32; 2],
    /// Fractal units per output height.
    pub scale: f32,
    /// Iteration cap.
    pub iterations: u32,
    /// Bottom-left corner in fractal units.
    pub offset: [f32; 2],
    /// Samples per pixel.
    pub samples: u32,
    /// 1 when circle inversion is on.
    pub inversion: u32,
    /// Inversion centre.
    pub circle_center: [f32; 2],
    /// Inversion radius.
    pub circle_radius: f32,
    /// Jitter seed.
    pub seed: u32,
    /// Linear hit colour.
    pub hit_color: [f32; 4],
    /// Linear background colour.
    pub back_color: [f32; 4],
    /// Output size in pixels.
    pub size: [u32; 2],
    /// Padding to the WGSL struct's 16-byte alignment.
    pub _pad: [u32; 2],
}

impl KleinianUniforms {
    /// All per-frame precomputation: colours to linear, bools to flags.
    pub fn from_params(p: &ParamSet, time: &FrameTime, size: (u32, u32)) -> Self {
        let s = Settings::read(p);
        Self {
            t: s.t,
            scale: s.scale,
            // A scene's own range may reach below the declared one.
            iterations: s.iterations.max(1) as u32,
            offset: s.offset,
            samples: s.samples.max(1) as u32,
            inversion: u32::from(s.circle_inversion),
            circle_center: s.circle_center,
            circle_radius: s.circle_radius,
            seed: time.seed as u32,
            hit_color: linear_rgba(s.hit_color),
            back_color: linear_rgba(s.back_color),
            size: [size.0, size.1],
            _pad: [0; 2],
        }
    }
}

/// A Kleinian limit-set node.
pub struct Kleinian {
    kernel: ComputeKernel,
    layout: wgpu::BindGroupLayout,
    uniforms: wgpu::Buffer,
    /// Bind groups by output texture id: steady-state frames create none.
    bind_groups: BindGroupCache<u64>,
}

/// Bindings of `kleinian.wgsl` (checked against the WGSL by name at creation).
const PARAMS_BINDING: u32 = 0;
const OUTPUT_BINDING: u32 = 1;

fn create(setup: &NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError> {
    let device = &setup.gpu.device;
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("kleinian_layout"),
        entries: &[
            crate::gpu::uniform_entry::<KleinianUniforms>(PARAMS_BINDING, wgpu::ShaderStages::COMPUTE),
            wgpu::BindGroupLayoutEntry {
                binding: OUTPUT_BINDING,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::StorageTexture {
                    access: wgpu::StorageTextureAccess::WriteOnly,
                    format: OUTPUT_FORMAT,
                    view_dimension: wgpu::TextureViewDimension::D2,
                },
                count: None,
            },
        ],
    });
    let (origin, source) =
        setup.shader_source("kleinian.wgsl", &[("params", PARAMS_BINDING), ("output", OUTPUT_BINDING)])?;
    let kernel = ComputeKernel::new(device, &origin, &source, "render", &[&layout])?;
    let uniforms = crate::gpu::uniform_buffer::<KleinianUniforms>(device, "kleinian_uniforms");
    Ok(Box::new(Kleinian { kernel, layout, uniforms, bind_groups: BindGroupCache::default() }))
}

impl Technique for Kleinian {
    fn add_passes<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        params: &ParamSet,
        time: &FrameTime,
        _inputs: &[TextureHandle],
    ) -> TextureHandle {
        let output = graph.create_texture("kleinian/image", TextureDesc::full(OUTPUT_FORMAT));
        let size = graph.texture_size(output);
        let uniforms = KleinianUniforms::from_params(params, time, size);
        self.bind_groups.begin_frame();
        graph.add_pass("kleinian/limit_set").write(output).record(move |ctx| {
            ctx.queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
            let bind_group = self.bind_groups.get_or_create(ctx.texture_id(output), || {
                ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("kleinian_bind_group"),
                    layout: &self.layout,
                    entries: &[
                        wgpu::BindGroupEntry { binding: PARAMS_BINDING, resource: self.uniforms.as_entire_binding() },
                        wgpu::BindGroupEntry {
                            binding: OUTPUT_BINDING,
                            resource: wgpu::BindingResource::TextureView(ctx.view(output)),
                        },
                    ],
                })
            });
            let mut pass = ctx.encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("kleinian/limit_set"),
                timestamp_writes: None,
            });
            self.kernel.dispatch(&mut pass, &[bind_group], [size.0, size.1, 1]);
        });
        output
    }
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod render_tests;
