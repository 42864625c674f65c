//! Drawing the cloth: the lit two-sided surface and the sphere, or the debug view.

use super::Settings;
use super::state::State;
use crate::gpu::ShaderError;
use crate::graph::{PassContext, RasterTargets};
use crate::techniques::splat_draw::{self, SplatDraw};
use crate::techniques::visibility::PixelRays;
use crate::techniques::{NodeSetup, Rasterizer, linear_rgba};
use crate::time::FrameTime;
use std::cell::RefCell;

/// Depth format of the draw pass.
pub const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
const SPHERE_VERTICES: u32 = 32 * 16 * 6;

/// The render shader's uniform block.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ClothViewUniforms {
    /// Projection × view.
    pub view_proj: [[f32; 4]; 4],
    /// Camera position; w: half the cloth's rest width (scales the position inset).
    pub camera: [f32; 4],
    /// Towards the light, unit.
    pub light_dir: [f32; 4],
    /// Linear cloth colour.
    pub color: [f32; 4],
    /// Linear sphere colour; w: output aspect (sizes the debug insets).
    pub sphere_color: [f32; 4],
    /// Sphere centre and radius (0: not drawn).
    pub sphere: [f32; 4],
    /// The compute draw's ray through the image's top-left corner (from the camera).
    pub ray_origin: [f32; 4],
    /// The ray's change per pixel to the right.
    pub ray_x: [f32; 4],
    /// The ray's change per pixel down.
    pub ray_y: [f32; 4],
}

/// What one frame's draw needs from the parameters.
pub struct ClothView {
    /// The uniform block.
    pub uniforms: ClothViewUniforms,
    /// Linear clear colour.
    pub background: wgpu::Color,
}

impl ClothView {
    /// Camera at (0, 0, −distance) looking down +z, y up (the sample's camera at (0, 0, −10)).
    pub fn from_params(p: &Settings, time: &FrameTime, size: (u32, u32)) -> Self {
        let aspect = size.0 as f32 / size.1.max(1) as f32;
        let eye = glam::Vec3::new(0.0, 0.0, -p.camera_distance);
        let proj = glam::camera::lh::proj::directx::perspective(p.fov.to_radians(), aspect, 0.05, 500.0);
        let view = glam::camera::lh::view::look_to_mat4(eye, glam::Vec3::Z, glam::Vec3::Y);
        let light = glam::Vec3::from(p.light_dir).normalize_or(glam::Vec3::NEG_Z);
        let c = super::sphere_center(p, time.seconds);
        let radius = if p.sphere { p.sphere_radius } else { 0.0 };
        let b = linear_rgba(p.background);
        let half_width = (p.resolution.max(2) - 1) as f32 * p.rest_length / 2.0;
        let mut sphere_color = linear_rgba(p.sphere_color);
        sphere_color[3] = aspect;
        let rays = PixelRays::new(proj * view, eye, size);
        Self {
            uniforms: ClothViewUniforms {
                view_proj: (proj * view).to_cols_array_2d(),
                camera: [eye.x, eye.y, eye.z, half_width],
                light_dir: [light.x, light.y, light.z, 0.0],
                color: linear_rgba(p.color),
                sphere_color,
                sphere: [c[0], c[1], c[2], radius],
                ray_origin: PixelRays::vec4(rays.origin, 0.0),
                ray_x: PixelRays::vec4(rays.x, 0.0),
                ray_y: PixelRays::vec4(rays.y, 0.0),
            },
            background: wgpu::Color { r: f64::from(b[0]), g: f64::from(b[1]), b: f64::from(b[2]), a: 1.0 },
        }
    }
}

/// What one frame's draw shows.
#[derive(Clone, Copy, Debug)]
pub struct DrawMode {
    /// Linear clear colour.
    pub clear: wgpu::Color,
    /// Particles and springs instead of the lit surface.
    pub debug: bool,
    /// Draw the collision sphere.
    pub sphere: bool,
}

/// The draw pipelines and their uniform buffer.
pub struct Renderer {
    surface: wgpu::RenderPipeline,
    sphere: wgpu::RenderPipeline,
    lines: wgpu::RenderPipeline,
    points: wgpu::RenderPipeline,
    insets: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    uniform: wgpu::Buffer,
    /// Samples per pixel of the draw (the scene's `msaa`, as the adapter allows).
    pub samples: u32,
    /// The lit surface and sphere drawn in compute, where the adapter has 64-bit atomics (a
    /// cell: its passes keep bind groups while the graph holds the node shared).
    pub compute: Option<RefCell<SplatDraw>>,
    /// What `rasterizer: auto` takes on this adapter.
    pub tuned: Rasterizer,
}

impl Renderer {
    /// Builds the four pipelines from `cloth_render.wgsl`.
    pub fn new(setup: &NodeSetup<'_>) -> Result<Self, ShaderError> {
        let device = &setup.gpu.device;
        let (origin, source) =
            setup.shader_source("cloth_render.wgsl", &[("view", 0), ("positions", 1), ("normals", 2)])?;
        let (module, _) = crate::gpu::compile_wgsl(device, &origin, &source)?;
        // The compute draw binds the same group.
        let stages = wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let storage = |binding| crate::gpu::storage_entry(binding, stages, true);
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("cloth_draw_layout"),
            entries: &[crate::gpu::uniform_entry::<ClothViewUniforms>(0, stages), storage(1), storage(2)],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("cloth_draw_pipeline_layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let samples = setup.samples_for(&[super::FORMAT, DEPTH]);
        // The debug view (springs and particles adding up, insets drawn last over them) needs no
        // depth: its pipelines draw into targets without it, which at 4K on the H200 saves the
        // multisampled depth clear (cloth_debug 9.58 -> 7.2 ms).
        let pipeline = |vertex, fragment, topology, additive, depth: bool| {
            crate::gpu::raster_pipeline(
                device,
                &module,
                &pipeline_layout,
                &crate::gpu::RasterDesc {
                    vertex,
                    fragment,
                    buffers: &[],
                    topology,
                    color: super::FORMAT,
                    depth: depth.then_some((DEPTH, wgpu::CompareFunction::LessEqual)),
                    additive,
                    samples,
                },
            )
        };
        use wgpu::PrimitiveTopology as T;
        let (surface, sphere, lines, points, insets) = crate::gpu::validated(device, &origin, || {
            (
                pipeline("vs_surface", "fs_surface", T::TriangleList, false, true),
                pipeline("vs_sphere", "fs_sphere", T::TriangleList, false, true),
                // Springs and particles add up, as the book draws them: no kind hides another.
                pipeline("vs_debug", "fs_debug", T::LineList, true, false),
                pipeline("vs_debug", "fs_debug", T::PointList, true, false),
                pipeline("vs_inset", "fs_inset", T::TriangleList, false, false),
            )
        })?;
        let uniform = crate::gpu::uniform_buffer::<ClothViewUniforms>(device, "cloth_view");
        let compute = if device.features().contains(splat_draw::FEATURES) {
            let bindings = [("view", 0), ("positions", 1), ("normals", 2)];
            Some(RefCell::new(SplatDraw::new(setup, "cloth_raster.wgsl", &bindings, &layout, false)?))
        } else {
            None
        };
        let tuned = setup.tuned_rasterizer(super::INFO.name);
        Ok(Self { surface, sphere, lines, points, insets, layout, uniform, samples, compute, tuned })
    }

    /// Two triangles per grid cell, shared vertices: indices are particle numbers.
    pub fn surface_indices(&self, device: &wgpu::Device, res: u32) -> (wgpu::Buffer, u32) {
        let mut indices = Vec::with_capacity(((res - 1) * (res - 1) * 6) as usize);
        for j in 0..res - 1 {
            for i in 0..res - 1 {
                let a = j * res + i;
                indices.extend_from_slice(&[a, a + 1, a + res, a + 1, a + res + 1, a + res]);
            }
        }
        (index_buffer(device, "cloth_surface_indices", &indices), indices.len() as u32)
    }

    /// Writes this frame's view uniforms and makes the bind groups and buffers the draw needs.
    pub fn prepare(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        state: &mut State,
        view: &ClothView,
        debug: bool,
    ) {
        queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&view.uniforms));
        let cur = state.cur;
        let (buffer, normals) = (state.particles()[cur].clone(), state.normals.clone());
        state.draw_groups.get_or_create(cur, || {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("cloth_draw_bind_group"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: self.uniform.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: buffer.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 2, resource: normals.as_entire_binding() },
                ],
            })
        });
        if debug && state.lines.is_none() {
            state.lines = Some(spring_lines(device, state.res));
        }
    }

    /// Records the draw into `color` and `depth`.
    pub fn draw(&self, ctx: &mut PassContext<'_>, state: &State, targets: &RasterTargets, mode: DrawMode) {
        let mut pass = ctx.begin_draw(targets, mode.clear);
        pass.set_bind_group(0, &state.draw_groups[&state.cur], &[]);
        match (&state.lines, mode.debug) {
            (Some((lines, ranges)), true) => {
                pass.set_pipeline(&self.lines);
                pass.set_index_buffer(lines.slice(..), wgpu::IndexFormat::Uint32);
                for (kind, range) in ranges.iter().enumerate() {
                    pass.draw_indexed(range.clone(), 0, kind as u32..kind as u32 + 1);
                }
                pass.set_pipeline(&self.points);
                pass.draw(0..state.res * state.res, 3..4);
                // The position and normal buffers as images, drawn over everything.
                pass.set_pipeline(&self.insets);
                pass.draw(0..6, 0..2);
            }
            _ => {
                pass.set_pipeline(&self.surface);
                pass.set_index_buffer(state.surface_indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..state.surface_count, 0, 0..1);
                if mode.sphere {
                    pass.set_pipeline(&self.sphere);
                    pass.draw(0..SPHERE_VERTICES, 0..1);
                }
            }
        }
    }
}

fn index_buffer(device: &wgpu::Device, label: &str, indices: &[u32]) -> wgpu::Buffer {
    use wgpu::util::DeviceExt;
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::cast_slice(indices),
        usage: wgpu::BufferUsages::INDEX,
    })
}

/// Line indices of every spring, grouped by kind: structural, shear, bend (two along); each
/// spring once, all inside the grid (the sample's debug lists ran past the border).
fn spring_lines(device: &wgpu::Device, res: u32) -> (wgpu::Buffer, [std::ops::Range<u32>; 3]) {
    let kinds: [&[(i32, i32)]; 3] = [&[(1, 0), (0, 1)], &[(1, 1), (-1, 1)], &[(2, 0), (0, 2)]];
    let mut indices = Vec::new();
    let mut ranges: [std::ops::Range<u32>; 3] = Default::default();
    for (k, offsets) in kinds.iter().enumerate() {
        let start = indices.len() as u32;
        for j in 0..res as i32 {
            for i in 0..res as i32 {
                for &(dx, dy) in offsets.iter() {
                    let (ni, nj) = (i + dx, j + dy);
                    if ni >= 0 && nj >= 0 && ni < res as i32 && nj < res as i32 {
                        indices.extend_from_slice(&[(j * res as i32 + i) as u32, (nj * res as i32 + ni) as u32]);
                    }
                }
            }
        }
        ranges[k] = start..indices.len() as u32;
    }
    (index_buffer(device, "cloth_spring_lines", &indices), ranges)
}
