//! What the rasterising techniques build the same way: one uniform block bound at group 0
//! (layout, pipeline layout, buffer, bind group), and render pipelines that differ only in entry
//! points, vertex buffers, topology and depth test.

use super::{uniform_buffer, uniform_entry};

/// A uniform block of `T` at group 0, binding 0, seen by vertex and fragment stages.
pub struct UniformBlock {
    /// Its bind-group layout.
    pub layout: wgpu::BindGroupLayout,
    /// A pipeline layout with just that group.
    pub pipeline_layout: wgpu::PipelineLayout,
    /// The buffer, written with `queue.write_buffer`.
    pub buffer: wgpu::Buffer,
    /// The bind group of the buffer.
    pub bind_group: wgpu::BindGroup,
}

impl UniformBlock {
    /// Creates all four, labelled after `label`.
    pub fn new<T>(device: &wgpu::Device, label: &str) -> Self {
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(label),
            entries: &[uniform_entry::<T>(0, wgpu::ShaderStages::VERTEX_FRAGMENT)],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let buffer = uniform_buffer::<T>(device, label);
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: buffer.as_entire_binding() }],
        });
        Self { layout, pipeline_layout, buffer, bind_group }
    }
}

/// The parts of a render pipeline that differ between techniques.
pub struct RasterDesc<'a> {
    /// Vertex entry point (also the label).
    pub vertex: &'a str,
    /// Fragment entry point.
    pub fragment: &'a str,
    /// Vertex buffer layouts (empty when vertices come from indices and storage).
    pub buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    /// Primitive topology.
    pub topology: wgpu::PrimitiveTopology,
    /// Colour target format (no blending).
    pub color: wgpu::TextureFormat,
    /// Depth format and test, with depth writes; `None` for no depth.
    pub depth: Option<(wgpu::TextureFormat, wgpu::CompareFunction)>,
    /// Add to the target (one + one) without writing depth, so overlapping lines all show
    /// (debug views, the book's additive line looks); false: opaque with depth writes.
    pub additive: bool,
    /// Samples per pixel of the targets it draws into (1: no multisampling).
    pub samples: u32,
}

/// A render pipeline from `module` with `layout`. Call inside [`super::validated`] so that a
/// mismatch between shader and layout becomes a [`super::ShaderError`].
pub fn raster_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    layout: &wgpu::PipelineLayout,
    desc: &RasterDesc<'_>,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(desc.vertex),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(desc.vertex),
            compilation_options: Default::default(),
            buffers: desc.buffers,
        },
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(desc.fragment),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format: desc.color,
                blend: desc.additive.then_some(wgpu::BlendState {
                    color: wgpu::BlendComponent {
                        src_factor: wgpu::BlendFactor::One,
                        dst_factor: wgpu::BlendFactor::One,
                        operation: wgpu::BlendOperation::Add,
                    },
                    alpha: wgpu::BlendComponent::REPLACE,
                }),
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        primitive: wgpu::PrimitiveState { topology: desc.topology, ..Default::default() },
        depth_stencil: desc.depth.map(|(format, compare)| wgpu::DepthStencilState {
            format,
            depth_write_enabled: Some(!desc.additive),
            depth_compare: Some(compare),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: wgpu::MultisampleState { count: desc.samples, ..Default::default() },
        multiview_mask: None,
        cache: None,
    })
}

/// A vertex or index buffer that grows (to the next power of two) to fit what is written.
pub struct GrowableBuffer {
    buffer: wgpu::Buffer,
    usage: wgpu::BufferUsages,
    label: &'static str,
}

impl GrowableBuffer {
    /// An empty buffer of `initial` bytes for `usage` (COPY_DST is added).
    pub fn new(device: &wgpu::Device, label: &'static str, usage: wgpu::BufferUsages, initial: u64) -> Self {
        let usage = usage | wgpu::BufferUsages::COPY_DST;
        Self { buffer: Self::allocate(device, label, usage, initial), usage, label }
    }

    fn allocate(device: &wgpu::Device, label: &str, usage: wgpu::BufferUsages, size: u64) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: size.max(16).next_power_of_two(),
            usage,
            mapped_at_creation: false,
        })
    }

    /// Makes room for `bytes`; true if the buffer was replaced (its contents are gone).
    pub fn reserve(&mut self, device: &wgpu::Device, bytes: u64) -> bool {
        if bytes <= self.buffer.size() {
            return false;
        }
        self.buffer = Self::allocate(device, self.label, self.usage, bytes);
        true
    }

    /// Replaces the contents with `data` (growing if needed); returns the element count.
    pub fn write_all<T: bytemuck::Pod>(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, data: &[T]) -> u32 {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        self.reserve(device, bytes.len() as u64);
        queue.write_buffer(&self.buffer, 0, bytes);
        data.len() as u32
    }

    /// The buffer.
    pub fn buffer(&self) -> &wgpu::Buffer {
        &self.buffer
    }
}
