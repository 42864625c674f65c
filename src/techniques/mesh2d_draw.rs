//! Drawing a triangulated 2-D mesh, shared by chapter 5's two techniques (`polygon_draw` and
//! `text_mesh`): the textured fill, the wireframe (line list over the same vertices) and the
//! open loop being drawn (line strip), with `polygon_draw/polygon_draw.wgsl`.

use crate::geometry::triangulate::Mesh2D;
use crate::gpu::{GrowableBuffer, RasterDesc, ShaderError, UniformBlock};
use crate::graph::{FrameGraph, PassContext, RasterTargets, TextureHandle};
use crate::time::FrameTime;

use super::NodeSetup;

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

/// How a triangulated mesh is drawn: what the drawing and text nodes pass the renderer from
/// their own settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrawStyle {
    /// Draw the triangle edges over the fill.
    pub wireframe: bool,
    /// Checker cells across the UV range.
    pub checker: i32,
    /// Half the view height in world units.
    pub view_size: f32,
}

impl PolygonUniforms {
    /// The sample's orthographic camera of half-height `view_size`, centred on the origin.
    pub fn new(style: &DrawStyle, time: &FrameTime, aspect: f32) -> Self {
        let half = style.view_size;
        let proj = glam::camera::lh::proj::directx::orthographic(-half * aspect, half * aspect, -half, half, -1.0, 1.0);
        // Hue = sin(0.5 t) mapped to [0, 1], full saturation.
        let hue = ((0.5 * time.seconds).sin() as f32 + 1.0) / 2.0;
        let channel = |shift: f32| (((hue + shift) * 6.0).rem_euclid(6.0) - 3.0).abs().clamp(1.0, 2.0) - 1.0;
        let rgb = [channel(0.0), channel(2.0 / 3.0), channel(1.0 / 3.0)].map(|c| 1.0 - c);
        Self {
            view_proj: proj.to_cols_array_2d(),
            loop_color: [rgb[0], rgb[1], rgb[2], 1.0],
            checker: style.checker as f32,
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

/// Draws a triangulated polygon set.
pub struct Renderer {
    fill: wgpu::RenderPipeline,
    wire: wgpu::RenderPipeline,
    open_loop: wgpu::RenderPipeline,
    block: UniformBlock,
    /// Samples per pixel of the draw (the scene's `msaa`, as the adapter allows).
    samples: u32,
    vertices: GrowableBuffer,
    triangles: GrowableBuffer,
    edges: GrowableBuffer,
    loop_vertices: GrowableBuffer,
    /// Element counts last uploaded: triangle indices, edge indices, loop vertices.
    counts: [u32; 3],
    device: wgpu::Device,
    queue: wgpu::Queue,
}

impl Renderer {
    /// Builds the three pipelines from `polygon_draw.wgsl`.
    pub fn new(setup: &NodeSetup<'_>) -> Result<Self, ShaderError> {
        let device = &setup.gpu.device;
        let (origin, source) = setup.shader_source("polygon_draw.wgsl", &[("u", 0)])?;
        let (module, _) = crate::gpu::compile_wgsl(device, &origin, &source)?;
        let block = UniformBlock::new::<PolygonUniforms>(device, "polygon_draw_uniforms");
        let samples = setup.samples_for(&[FORMAT]);
        let pipeline = |fragment: &str, topology| {
            crate::gpu::raster_pipeline(
                device,
                &module,
                &block.pipeline_layout,
                &RasterDesc {
                    vertex: "vs_main",
                    fragment,
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: size_of::<Vertex>() as u64,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &wgpu::vertex_attr_array![0 => Float32x2, 1 => Float32x2],
                    })],
                    topology,
                    color: FORMAT,
                    depth: None,
                    additive: false,
                    samples,
                },
            )
        };
        let (fill, wire, open_loop) = crate::gpu::validated(device, &origin, || {
            (
                pipeline("fs_fill", wgpu::PrimitiveTopology::TriangleList),
                pipeline("fs_wire", wgpu::PrimitiveTopology::LineList),
                pipeline("fs_loop", wgpu::PrimitiveTopology::LineStrip),
            )
        })?;
        use wgpu::BufferUsages as U;
        let buffer = |label, usage| GrowableBuffer::new(device, label, usage, 1024);
        Ok(Self {
            fill,
            wire,
            open_loop,
            block,
            samples,
            vertices: buffer("polygon_draw_vertices", U::VERTEX),
            triangles: buffer("polygon_draw_triangles", U::INDEX),
            edges: buffer("polygon_draw_edges", U::INDEX),
            loop_vertices: buffer("polygon_draw_loop", U::VERTEX),
            counts: [0; 3],
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
        let (device, queue) = (&self.device, &self.queue);
        self.vertices.write_all(device, queue, &vertices);
        self.counts = [
            self.triangles.write_all(device, queue, &mesh.indices),
            self.edges.write_all(device, queue, &edges),
            self.loop_vertices.write_all(device, queue, &open),
        ];
    }

    /// Adds pass `name` drawing the fill, the wireframe (if `style` asks) and the open loop
    /// into a new colour target, which it returns.
    pub fn add_pass<'r>(
        &'r self,
        graph: &mut FrameGraph<'r>,
        name: &str,
        style: &DrawStyle,
        time: &FrameTime,
    ) -> TextureHandle {
        let targets = graph.create_raster_targets(name, FORMAT, None, self.samples);
        let (w, h) = graph.texture_size(targets.color);
        let uniforms = PolygonUniforms::new(style, time, w as f32 / h as f32);
        let wireframe = style.wireframe;
        graph.add_pass(format!("{name}/draw")).draws_into(&targets).record(move |ctx| {
            self.record(ctx, &targets, &uniforms, wireframe);
        });
        targets.color
    }

    fn record(&self, ctx: &mut PassContext<'_>, targets: &RasterTargets, uniforms: &PolygonUniforms, wireframe: bool) {
        let [triangles, edges, open] = self.counts;
        ctx.queue.write_buffer(&self.block.buffer, 0, bytemuck::bytes_of(uniforms));
        let mut pass = ctx.begin_draw(targets, wgpu::Color::BLACK);
        pass.set_bind_group(0, &self.block.bind_group, &[]);
        if triangles > 0 {
            pass.set_vertex_buffer(0, self.vertices.buffer().slice(..));
            pass.set_pipeline(&self.fill);
            pass.set_index_buffer(self.triangles.buffer().slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..triangles, 0, 0..1);
            if wireframe {
                pass.set_pipeline(&self.wire);
                pass.set_index_buffer(self.edges.buffer().slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..edges, 0, 0..1);
            }
        }
        if open > 1 {
            pass.set_pipeline(&self.open_loop);
            pass.set_vertex_buffer(0, self.loop_vertices.buffer().slice(..));
            pass.draw(0..open, 0..1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_layout_matches_the_wgsl_struct() {
        let source = include_str!("polygon_draw/polygon_draw.wgsl");
        assert_eq!(crate::gpu::wgsl_struct_size(source, "PolygonUniforms"), Some(size_of::<PolygonUniforms>() as u32));
    }
}
