//! The shape every compositing step shares — blends, faders, transitions: a compute kernel that
//! samples a few same-sized images and writes one linear-HDR image of the output's size, driven
//! by one small uniform block. A kernel is built once per shader entry; each place that runs it
//! in a frame owns an [`ImagePass`] (its own uniform buffer: writes land before the submit, so two
//! passes of one frame cannot share one).
//!
//! Bindings (checked against the WGSL by name): `u` (0) the uniform block, `linear_clamp` (1) a
//! linear sampler, `src0`… (2…) the inputs, `dst` (8) the `rgba16float` storage output.

use super::NodeSetup;
use crate::gpu::{BindGroupCache, ComputeKernel, DEFAULT_MAX_AGE, ShaderError};
use crate::graph::{FrameGraph, PassContext, TextureDesc, TextureHandle};

/// The output format of every image pass: linear HDR, like every node's image.
pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The most inputs one kernel samples.
pub const MAX_INPUTS: usize = 4;

/// Binding of the storage output.
const DST_BINDING: u32 = 8;

/// The bindings an image kernel with `inputs` inputs declares, by name, for
/// [`crate::gpu::check_bindings`].
pub fn bindings(inputs: usize) -> Vec<(&'static str, u32)> {
    const SOURCES: [&str; MAX_INPUTS] = ["src0", "src1", "src2", "src3"];
    let mut names = vec![("u", 0), ("linear_clamp", 1)];
    names.extend(SOURCES.iter().take(inputs).enumerate().map(|(i, n)| (*n, 2 + i as u32)));
    names.push(("dst", DST_BINDING));
    names
}

/// The uniform block of the kernels a performer writes (show transitions, WGSL effects): one
/// value (a transition's progress, an effect's amount), the clock, and the output's shape.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PatternUniforms {
    /// The kernel's one value, 0–1.
    pub value: f32,
    /// Seconds of its clock.
    pub seconds: f32,
    /// Width / height of the output.
    pub aspect: f32,
    /// Padding.
    pub pad: f32,
    /// Output size in pixels.
    pub size: [f32; 2],
    /// Padding to 32 bytes.
    pub pad2: [f32; 2],
}

impl PatternUniforms {
    /// The block for `value` at `seconds`, over an output of `size`.
    pub fn new(value: f32, seconds: f32, (w, h): (u32, u32)) -> Self {
        let aspect = w as f32 / h.max(1) as f32;
        Self { value, seconds, aspect, pad: 0.0, size: [w as f32, h as f32], pad2: [0.0; 2] }
    }
}

/// The compute entry point `name` that indra appends to a performer's kernel: one invocation
/// per output pixel, writing `color` (a WGSL expression of `uv`, 0–1 from the top left) to `dst`.
pub fn pixel_entry_point(name: &str, color: &str) -> String {
    format!(
        "
@compute @workgroup_size(8, 8)
fn {name}(@builtin(global_invocation_id) id: vec3<u32>) {{
    let size = textureDimensions(dst);
    if id.x >= size.x || id.y >= size.y {{
        return;
    }}
    let uv = (vec2<f32>(id.xy) + 0.5) / vec2<f32>(size);
    textureStore(dst, vec2<i32>(id.xy), {color});
}}
"
    )
}

/// A compiled image kernel: pipeline, layout and sampler.
pub struct ImageKernel {
    compute: ComputeKernel,
    layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    inputs: usize,
    uniform_size: u64,
    /// Tells kernels apart in bind-group keys (one pass may run several kernels).
    id: u64,
}

impl ImageKernel {
    /// Builds entry `entry` of validated WGSL `source` taking `inputs` images (≤ [`MAX_INPUTS`])
    /// and a uniform block of `uniform_size` bytes.
    pub fn new(
        device: &wgpu::Device,
        (origin, source): (&str, &str),
        entry: &str,
        inputs: usize,
        uniform_size: u64,
    ) -> Result<Self, ShaderError> {
        crate::gpu::check_bindings(origin, source, &bindings(inputs))?;
        let stage = wgpu::ShaderStages::COMPUTE;
        let mut entries = vec![
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: stage,
                ty: crate::gpu::block_binding(false, wgpu::BufferSize::new(uniform_size)),
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: stage,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                count: None,
            },
        ];
        entries.extend((0..inputs.min(MAX_INPUTS)).map(|i| crate::gpu::texture_entry(2 + i as u32, stage)));
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: DST_BINDING,
            visibility: stage,
            ty: wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::WriteOnly,
                format: FORMAT,
                view_dimension: wgpu::TextureViewDimension::D2,
            },
            count: None,
        });
        let layout =
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(entry), entries: &entries });
        let compute = ComputeKernel::new(device, origin, source, entry, &[&layout])?;
        // Clamp to edge: an input of another size is stretched, never wrapped.
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("image_pass_sampler"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        Ok(Self { compute, layout, sampler, inputs, uniform_size, id: crate::graph::next_resource_id() })
    }
}

/// One use of a kernel in a frame: its uniform buffer and its cached bind groups.
pub struct ImagePass {
    uniforms: wgpu::Buffer,
    groups: BindGroupCache<Vec<u64>>,
}

impl ImagePass {
    /// A pass for `kernel`'s uniform size.
    pub fn new(device: &wgpu::Device, kernel: &ImageKernel) -> Self {
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("image_pass_uniforms"),
            size: kernel.uniform_size,
            usage: crate::gpu::BLOCK_USAGE,
            mapped_at_creation: false,
        });
        Self { uniforms, groups: BindGroupCache::new(DEFAULT_MAX_AGE) }
    }

    /// Declares pass `name`: `kernel` reads `inputs` with `uniforms` and writes a new full-size
    /// image, which it returns. Call at most once per frame per `ImagePass`.
    pub fn declare<'r, U: bytemuck::Pod>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        name: &str,
        kernel: &'r ImageKernel,
        uniforms: U,
        inputs: &[TextureHandle],
    ) -> TextureHandle {
        debug_assert_eq!(inputs.len(), kernel.inputs, "{name}: inputs");
        debug_assert_eq!(size_of::<U>() as u64, kernel.uniform_size, "{name}: uniform size");
        self.groups.begin_frame();
        let out = graph.create_texture(name.to_string(), TextureDesc::full(FORMAT));
        let size = graph.texture_size(out);
        let mut pass = graph.add_pass(name.to_string());
        for &input in inputs {
            pass = pass.read(input);
        }
        let inputs = inputs.to_vec();
        pass.write(out).record(move |ctx| {
            ctx.queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
            let group = self.bind_group(ctx, kernel, &inputs, out);
            let mut compute = ctx
                .encoder
                .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("image_pass"), timestamp_writes: None });
            kernel.compute.dispatch(&mut compute, &[&group], [size.0, size.1, 1]);
        });
        out
    }

    fn bind_group(
        &mut self,
        ctx: &PassContext<'_>,
        kernel: &ImageKernel,
        inputs: &[TextureHandle],
        out: TextureHandle,
    ) -> wgpu::BindGroup {
        let mut key = vec![kernel.id];
        key.extend(inputs.iter().chain([&out]).map(|&t| ctx.texture_id(t)));
        let uniforms = &self.uniforms;
        self.groups
            .get_or_create(key, || {
                let mut entries = vec![
                    wgpu::BindGroupEntry { binding: 0, resource: uniforms.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&kernel.sampler) },
                ];
                for (i, &t) in inputs.iter().enumerate() {
                    entries.push(wgpu::BindGroupEntry {
                        binding: 2 + i as u32,
                        resource: wgpu::BindingResource::TextureView(ctx.view(t)),
                    });
                }
                entries.push(wgpu::BindGroupEntry {
                    binding: DST_BINDING,
                    resource: wgpu::BindingResource::TextureView(ctx.view(out)),
                });
                ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("image_pass_group"),
                    layout: &kernel.layout,
                    entries: &entries,
                })
            })
            .clone()
    }
}

/// A node that is one image pass: its kernel and its pass (a blend, a fader).
pub struct ImageNode<U> {
    kernel: ImageKernel,
    pass: ImagePass,
    name: &'static str,
    uniforms: std::marker::PhantomData<U>,
}

impl<U: bytemuck::Pod> ImageNode<U> {
    /// Entry `entry` of shader `file` (checked against its bindings), taking `inputs` images and
    /// uniforms `U`; its pass is named after the entry.
    pub fn new(setup: &NodeSetup<'_>, file: &str, entry: &'static str, inputs: usize) -> Result<Self, ShaderError> {
        let (origin, source) = setup.shader_source(file, &bindings(inputs))?;
        let device = &setup.gpu.device;
        let kernel = ImageKernel::new(device, (&origin, &source), entry, inputs, size_of::<U>() as u64)?;
        let pass = ImagePass::new(device, &kernel);
        Ok(Self { kernel, pass, name: entry, uniforms: std::marker::PhantomData })
    }

    /// Declares this frame's pass over `inputs`; returns its image.
    pub fn declare<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        uniforms: U,
        inputs: &[TextureHandle],
    ) -> TextureHandle {
        self.pass.declare(graph, self.name, &self.kernel, uniforms, inputs)
    }
}

/// A new full-size transparent black image: what an empty layer shows.
pub fn black<'r>(graph: &mut FrameGraph<'r>) -> TextureHandle {
    let out = graph.create_texture("black", TextureDesc::full(FORMAT));
    graph.add_pass("black").render_target(out).record(move |ctx| {
        drop(ctx.begin_color_pass(out, wgpu::Color::TRANSPARENT));
    });
    out
}
