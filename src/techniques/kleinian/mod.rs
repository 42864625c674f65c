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
    params: Settings::decls,
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
        /// from 4 samples up, take them all only near an edge of the set (the pixel's 4 × 4 neighbouring corners not all one class, or its first sample disagreeing); elsewhere one
        adaptive: bool = |n, doc| ParamDecl::new(n, ParamValue::Bool(true), None, doc),
        /// invert the plane in a circle before the test
        circle_inversion: bool = |n, doc| ParamDecl::new(n, ParamValue::Bool(false), None, doc),
        /// inversion circle centre
        circle_center: [f32; 2] = |n, doc| ParamDecl::new(n, ParamValue::Vec2([0.0, 0.0]), Some((-20.0, 20.0)), doc),
        /// inversion circle radius
        circle_radius: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(1.0), Some((0.01, 20.0)), doc),
    }
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
        Self::from_settings(&Settings::read(p), time, size)
    }

    /// [`Self::from_params`] from settings already read.
    fn from_settings(s: &Settings, time: &FrameTime, size: (u32, u32)) -> Self {
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

/// Fewest samples per pixel that adaptive sampling serves: it costs about two samples a pixel
/// (the corners, the first sample) before the edges' own.
pub const ADAPTIVE_MIN_SAMPLES: i32 = 4;

/// Whether a frame samples adaptively.
fn samples_adaptively(s: &Settings) -> bool {
    s.adaptive && s.samples >= ADAPTIVE_MIN_SAMPLES
}

/// Bytes of the corner classes of a `size` image: (width + 3) × (height + 3) bits (the pixel
/// corners and a margin of one), each row padded to whole 32-bit words
/// (`kleinian.wgsl::corner_words`).
fn corner_bits_bytes(size: (u32, u32)) -> u64 {
    u64::from((size.0 + 34) / 32) * u64::from(size.1 + 3) * 4
}

/// A Kleinian limit-set node.
pub struct Kleinian {
    /// Every sample of every pixel.
    render: ComputeKernel,
    /// Adaptive sampling: the corner classes, then samples where they differ.
    corners: ComputeKernel,
    render_edges: ComputeKernel,
    /// (params, output), and the same with the corner classes.
    layout: wgpu::BindGroupLayout,
    adaptive_layout: wgpu::BindGroupLayout,
    uniforms: wgpu::Buffer,
    /// Bind groups by output texture id and, adaptive, corner buffer id: steady frames create none.
    bind_groups: BindGroupCache<(u64, Option<u64>)>,
}

/// Bindings of `kleinian.wgsl` (checked against the WGSL by name at creation).
const PARAMS_BINDING: u32 = 0;
const OUTPUT_BINDING: u32 = 1;
const CORNERS_BINDING: u32 = 2;

fn create(setup: &NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError> {
    let device = &setup.gpu.device;
    let params_entry = crate::gpu::uniform_entry::<KleinianUniforms>(PARAMS_BINDING, wgpu::ShaderStages::COMPUTE);
    let output_entry = crate::gpu::output_image_entry(OUTPUT_BINDING, OUTPUT_FORMAT);
    let corners_entry = crate::gpu::storage_entry(CORNERS_BINDING, wgpu::ShaderStages::COMPUTE, false);
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("kleinian_layout"),
        entries: &[params_entry, output_entry],
    });
    let adaptive_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("kleinian_adaptive_layout"),
        entries: &[params_entry, output_entry, corners_entry],
    });
    let (origin, source) = setup.shader_source(
        "kleinian.wgsl",
        &[("params", PARAMS_BINDING), ("output", OUTPUT_BINDING), ("corner_bits", CORNERS_BINDING)],
    )?;
    let kernel = |entry, layout| ComputeKernel::new(device, &origin, &source, entry, &[layout]);
    Ok(Box::new(Kleinian {
        render: kernel("render", &layout)?,
        corners: kernel("corners", &adaptive_layout)?,
        render_edges: kernel("render_edges", &adaptive_layout)?,
        layout,
        adaptive_layout,
        uniforms: crate::gpu::uniform_buffer::<KleinianUniforms>(device, "kleinian_uniforms"),
        bind_groups: BindGroupCache::default(),
    }))
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
        let settings = Settings::read(params);
        let uniforms = KleinianUniforms::from_settings(&settings, time, size);
        self.bind_groups.begin_frame();
        let corners =
            samples_adaptively(&settings).then(|| graph.create_buffer("kleinian/corner_bits", corner_bits_bytes(size)));
        let mut pass = graph.add_pass("kleinian/limit_set").write(output);
        if let Some(buffer) = corners {
            pass = pass.write_buffer(buffer);
        }
        pass.record(move |ctx| {
            ctx.queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
            let key = (ctx.texture_id(output), corners.map(|b| ctx.buffer_id(b)));
            let bind_group = self.bind_groups.get_or_create(key, || {
                let mut entries = vec![
                    wgpu::BindGroupEntry { binding: PARAMS_BINDING, resource: self.uniforms.as_entire_binding() },
                    wgpu::BindGroupEntry {
                        binding: OUTPUT_BINDING,
                        resource: wgpu::BindingResource::TextureView(ctx.view(output)),
                    },
                ];
                let layout = match corners {
                    Some(b) => {
                        let resource = ctx.buffer(b).as_entire_binding();
                        entries.push(wgpu::BindGroupEntry { binding: CORNERS_BINDING, resource });
                        &self.adaptive_layout
                    }
                    None => &self.layout,
                };
                ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("kleinian_bind_group"),
                    layout,
                    entries: &entries,
                })
            });
            let mut pass = ctx.encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("kleinian/limit_set"),
                timestamp_writes: None,
            });
            if corners.is_some() {
                // wgpu orders the two dispatches: the second reads what the first wrote.
                self.corners.dispatch(&mut pass, &[bind_group], [size.0 + 3, size.1 + 3, 1]);
                self.render_edges.dispatch(&mut pass, &[bind_group], [size.0, size.1, 1]);
            } else {
                self.render.dispatch(&mut pass, &[bind_group], [size.0, size.1, 1]);
            }
        });
        output
    }
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod render_tests;
