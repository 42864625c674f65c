//! Pipelines and buffers of the drawing node: the textured fill, the wireframe (line list over
//! the same vertices) and the open loop being drawn (line strip).

use crate::geometry::triangulate::Mesh2D;
use crate::gpu::ShaderError;
use crate::graph::{PassContext, TextureHandle};
use crate::params::ParamSet;
use crate::time::FrameTime;

use super::super::NodeSetup;

/// Colour target format: linear HDR like every node.
pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The shader's uniform block.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PolygonUniforms {
    /// World → clip (orthographic).
    pub view_proj: [[f32; 4]; 4],
    /// Colour of the loop being drawn (linear), hue cycling with time as in the sample.
    pub loop_color: [f32; 4],
    /// Checker cells across the UV range.
    pub checker: f32,
    /// Padding.
    pub _pad: [f32; 3],
}

impl PolygonUniforms {
    /// The sample's orthographic camera of half-height `view_size`, centred on the origin.
    pub fn new(params: &ParamSet, time: &FrameTime, aspect: f32) -> Self {
        let half = params.float("view_size");
        let proj = glam::camera::lh::proj::directx::orthographic(-half * aspect, half * aspect, -half, half, -1.0, 1.0);
        // Hue = sin(0.5 t) mapped to [0, 1], full saturation.
        let hue = ((0.5 * time.seconds).sin() as f32 + 1.0) / 2.0;
        let channel = |shift: f32| (((hue + shift) * 6.0).rem_euclid(6.0) - 3.0).abs().clamp(1.0, 2.0) - 1.0;
        let rgb = [channel(0.0), channel(2.0 / 3.0), channel(1.0 / 3.0)].map(|c| 1.0 - c);
        Self {
            view_proj: proj.to_cols_array_2d(),
            loop_color: [rgb[0], rgb[1], rgb[2], 1.0],
            checker: params.int("checker") as f32,
            _pad: [0.0; 3],
        }
    }
}

/// A vertex: position (world) and UV.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct Vertex {
    position: [f32; 2],
    uv: [f32; 2],
}

/// A buffer that grows (by doubling) to fit what is written into it.
struct Growable {
    buffer: wgpu::Buffer,
    usage: wgpu::BufferUsages,
    label: &'static str,
    /// Elements written last.
    len: u32,
}

impl Growable {
    fn new(device: &wgpu::Device, label: &'static str, usage: wgpu::BufferUsages) -> Self {
        Self { buffer: Self::allocate(device, label, usage, 1024), usage, label, len: 0 }
    }

    fn allocate(device: &wgpu::Device, label: &str, usage: wgpu::BufferUsages, size: u64) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: usage | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    fn write<T: bytemuck::Pod>(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, data: &[T]) {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        if bytes.len() as u64 > self.buffer.size() {
            self.buffer = Self::allocate(device, self.label, self.usage, (bytes.len() as u64).next_power_of_two());
        }
        queue.write_buffer(&self.buffer, 0, bytes);
        self.len = data.len() as u32;
    }
}

/// Draws a triangulated polygon set.
pub struct Renderer {
    fill: wgpu::RenderPipeline,
    wire: wgpu::RenderPipeline,
    open_loop: wgpu::RenderPipeline,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    vertices: Growable,
    triangles: Growable,
    edges: Growable,
    loop_vertices: Growable,
    device: wgpu::Device,
    queue: wgpu::Queue,
}

impl Renderer {
    /// Builds the three pipelines from `polygon_draw.wgsl`.
    pub fn new(setup: &NodeSetup<'_>) -> Result<Self, ShaderError> {
        let device = &setup.gpu.device;
        let (origin, source) = setup.shader_source("polygon_draw.wgsl")?;
        let (module, _) = crate::gpu::compile_wgsl(device, &origin, &source)?;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("polygon_draw_layout"),
            entries: &[crate::gpu::uniform_entry::<PolygonUniforms>(0, wgpu::ShaderStages::VERTEX_FRAGMENT)],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("polygon_draw_pipeline_layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let pipeline = |fragment: &str, topology: wgpu::PrimitiveTopology| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(fragment),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: size_of::<Vertex>() as u64,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &wgpu::vertex_attr_array![0 => Float32x2, 1 => Float32x2],
                    })],
                },
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fragment),
                    compilation_options: Default::default(),
                    targets: &[Some(FORMAT.into())],
                }),
                primitive: wgpu::PrimitiveState { topology, ..Default::default() },
                depth_stencil: None,
                multisample: wgpu::MultisampleState::default(),
                multiview_mask: None,
                cache: None,
            })
        };
        let fill = pipeline("fs_fill", wgpu::PrimitiveTopology::TriangleList);
        let wire = pipeline("fs_wire", wgpu::PrimitiveTopology::LineList);
        let open_loop = pipeline("fs_loop", wgpu::PrimitiveTopology::LineStrip);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(ShaderError { origin, line: 1, column: 1, message: e.to_string() });
        }
        let uniforms = crate::gpu::uniform_buffer::<PolygonUniforms>(device, "polygon_draw_uniforms");
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("polygon_draw_bind_group"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: uniforms.as_entire_binding() }],
        });
        use wgpu::BufferUsages as U;
        Ok(Self {
            fill,
            wire,
            open_loop,
            uniforms,
            bind_group,
            vertices: Growable::new(device, "polygon_draw_vertices", U::VERTEX),
            triangles: Growable::new(device, "polygon_draw_triangles", U::INDEX),
            edges: Growable::new(device, "polygon_draw_edges", U::INDEX),
            loop_vertices: Growable::new(device, "polygon_draw_loop", U::VERTEX),
            device: device.clone(),
            queue: setup.gpu.queue.clone(),
        })
    }

    /// Uploads a mesh and the open loop being drawn.
    pub fn upload(&mut self, mesh: &Mesh2D, drawing: &[[f64; 2]]) {
        let vertices: Vec<Vertex> = mesh
            .positions
            .iter()
            .zip(&mesh.uvs)
            .map(|(p, &uv)| Vertex { position: [p[0] as f32, p[1] as f32], uv })
            .collect();
        let edges: Vec<u32> = mesh.indices.chunks_exact(3).flat_map(|t| [t[0], t[1], t[1], t[2], t[2], t[0]]).collect();
        let open: Vec<Vertex> =
            drawing.iter().map(|p| Vertex { position: [p[0] as f32, p[1] as f32], uv: [0.0; 2] }).collect();
        self.vertices.write(&self.device, &self.queue, &vertices);
        self.triangles.write(&self.device, &self.queue, &mesh.indices);
        self.edges.write(&self.device, &self.queue, &edges);
        self.loop_vertices.write(&self.device, &self.queue, &open);
    }

    /// Records the fill, the wireframe (if on) and the open loop into `color`.
    pub fn record(&self, ctx: &mut PassContext<'_>, color: TextureHandle, uniforms: &PolygonUniforms, wireframe: bool) {
        ctx.queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(uniforms));
        let mut pass = ctx.begin_color_pass(color, wgpu::Color::BLACK);
        pass.set_bind_group(0, &self.bind_group, &[]);
        if self.triangles.len > 0 {
            pass.set_vertex_buffer(0, self.vertices.buffer.slice(..));
            pass.set_pipeline(&self.fill);
            pass.set_index_buffer(self.triangles.buffer.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..self.triangles.len, 0, 0..1);
            if wireframe {
                pass.set_pipeline(&self.wire);
                pass.set_index_buffer(self.edges.buffer.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..self.edges.len, 0, 0..1);
            }
        }
        if self.loop_vertices.len > 1 {
            pass.set_pipeline(&self.open_loop);
            pass.set_vertex_buffer(0, self.loop_vertices.buffer.slice(..));
            pass.draw(0..self.loop_vertices.len, 0..1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_layout_matches_the_wgsl_struct() {
        let source = include_str!("../../../shaders/polygon_draw.wgsl");
        assert_eq!(crate::gpu::wgsl_struct_size(source, "PolygonUniforms"), Some(size_of::<PolygonUniforms>() as u32));
    }
}
