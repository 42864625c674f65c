//! The display encode: any float texture → an 8-bit, sRGB-encoded target (window or PNG).

use std::collections::HashMap;

/// The format of the image that off-screen renders read back and write as PNG.
pub const DISPLAY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

const SOURCE: &str = include_str!("../../shaders/display.wgsl");

/// A texture of [`DISPLAY_FORMAT`] that a blit draws into and that can be copied out (the
/// image a render or a recording reads back).
pub fn display_target(device: &wgpu::Device, label: &str, size: (u32, u32)) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: DISPLAY_FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::STORAGE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

/// Where a blit draws: a render-target view of `format` and `size`.
pub struct BlitTarget<'a> {
    /// The view to draw into.
    pub view: &'a wgpu::TextureView,
    /// Its format (picks the pipeline).
    pub format: wgpu::TextureFormat,
    /// Its size in pixels.
    pub size: (u32, u32),
}

/// Draws a texture into a render target, converting linear colour to sRGB bytes.
pub struct Blit {
    layout: wgpu::BindGroupLayout,
    module: wgpu::ShaderModule,
    pipelines: HashMap<wgpu::TextureFormat, wgpu::RenderPipeline>,
    uniform: wgpu::Buffer,
    /// The compute encode into a [`display_target`] (made on first use).
    compute: Option<(wgpu::BindGroupLayout, wgpu::ComputePipeline)>,
}

impl Blit {
    /// Builds the shader module and layout; pipelines are made per target format on first use.
    pub fn new(device: &wgpu::Device) -> Self {
        let (module, _) =
            super::compile_wgsl(device, "<engine>/display.wgsl", SOURCE).expect("built-in display shader is valid");
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("display_layout"),
            entries: &[
                source_entry(wgpu::ShaderStages::FRAGMENT),
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: super::block_binding(false, None),
                    count: None,
                },
            ],
        });
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("display_uniform"),
            size: 16,
            usage: super::BLOCK_USAGE,
            mapped_at_creation: false,
        });
        Self { layout, module, pipelines: HashMap::new(), uniform, compute: None }
    }

    /// Records the same encode as [`Blit::record`] as a compute pass into `target` (a storage
    /// view of [`DISPLAY_FORMAT`], `size` pixels): off-screen renders and recordings. On the H200
    /// the raster pass cost ~2 ms at 4K; this one a tenth of that.
    pub fn record_compute(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        source: &wgpu::TextureView,
        target: &wgpu::TextureView,
        size: (u32, u32),
    ) {
        let (layout, pipeline) = self.compute.get_or_insert_with(|| compute_pipeline(device, &self.module));
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("display_compute_bind_group"),
            layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(source) },
                wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(target) },
            ],
        });
        let mut pass = encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("display_encode"), timestamp_writes: None });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        // `cs_main`'s workgroup is 16×16.
        pass.dispatch_workgroups(size.0.div_ceil(16), size.1.div_ceil(16), 1);
    }

    /// Records a pass that draws `source` over the whole of `target`.
    pub fn record(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        source: &wgpu::TextureView,
        target: BlitTarget<'_>,
    ) {
        let BlitTarget { view: target, format, size } = target;
        queue.write_buffer(&self.uniform, 0, bytemuck::cast_slice(&[size.0, size.1, 0, 0]));
        let pipeline = self.pipeline(device, format).clone();
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("display_bind_group"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(source) },
                wgpu::BindGroupEntry { binding: 1, resource: self.uniform.as_entire_binding() },
            ],
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("display_pass"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
            })],
            ..Default::default()
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.draw(0..3, 0..1);
    }

    fn pipeline(&mut self, device: &wgpu::Device, format: wgpu::TextureFormat) -> &wgpu::RenderPipeline {
        let (layout, module) = (&self.layout, &self.module);
        self.pipelines.entry(format).or_insert_with(|| {
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("display_pipeline_layout"),
                bind_group_layouts: &[Some(layout)],
                immediate_size: 0,
            });
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("display_pipeline"),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                fragment: Some(wgpu::FragmentState {
                    module,
                    entry_point: Some("fs_main"),
                    compilation_options: Default::default(),
                    targets: &[Some(format.into())],
                }),
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: None,
                multisample: wgpu::MultisampleState::default(),
                multiview_mask: None,
                cache: None,
            })
        })
    }
}

/// The compute encode's layout and pipeline (entry `cs_main` of the display shader).
fn compute_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
) -> (wgpu::BindGroupLayout, wgpu::ComputePipeline) {
    let stage = wgpu::ShaderStages::COMPUTE;
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("display_compute_layout"),
        entries: &[
            source_entry(stage),
            wgpu::BindGroupLayoutEntry {
                binding: 2,
                visibility: stage,
                ty: wgpu::BindingType::StorageTexture {
                    access: wgpu::StorageTextureAccess::WriteOnly,
                    format: DISPLAY_FORMAT,
                    view_dimension: wgpu::TextureViewDimension::D2,
                },
                count: None,
            },
        ],
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("display_compute_pipeline_layout"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("display_compute"),
        layout: Some(&pipeline_layout),
        module,
        entry_point: Some("cs_main"),
        compilation_options: Default::default(),
        cache: None,
    });
    (layout, pipeline)
}

/// Binding 0 of both display encoders: the linear HDR image read texel by texel.
fn source_entry(visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding: 0,
        visibility,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}
