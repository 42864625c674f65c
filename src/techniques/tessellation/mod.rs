//! Chapter 6: tessellation and displacement. wgpu has no hull or domain stage, so the book's
//! pipeline is rebuilt from compute and an indirect draw: per-edge factors with the book's
//! edge-length formula and culling, a level per patch, a GPU prefix sum, and a vertex shader that
//! evaluates the refined lattice, displaced by any texture of the frame graph (the grid fluid, an
//! image, the Kleinian limit set). Edges shared by two patches are subdivided once, and boundary
//! points are placed from the edge's own integers, so displaced neighbours never open a crack.
//!
//! Fixes of the sample (seed-reference §9 items 20–24): outward or inward displacement is a
//! parameter; normals come from the height field's gradient (the flat normal is wrong once
//! displaced); the height is sampled with filtering in the plane's own UV.
//!
//! Integer spacing with geomorphing: levels change by whole steps, vertices glide between them.
//!
//! The draw: in compute where the adapter has 64-bit atomics (a visibility buffer, see
//! `compute_raster`; the `rasterizer` parameter), else by the raster pipeline (`draw_indirect`).
//! Both give the same image within multisampling's differences (a test compares them).
//!
//! Book: [UGP4 ch.6] "Tessellation & Displacement" (sakota). Shader: `tessellation.wgsl`.

mod compute_raster;
mod params;
pub mod reference;

pub use params::{
    Channel, PLANE_SIZE, Rasterizer, Settings, TessUniforms, View, camera, edge_count, frustum_planes, model,
};

use std::cell::RefCell;

use crate::gpu::{BindGroupCache, ComputeKernel, ShaderError, storage_entry as storage};
use crate::graph::{BufferHandle, FrameGraph, PassBuilder, PassContext, RasterTargets, TextureDesc, TextureHandle};
use crate::params::ParamSet;
use crate::time::FrameTime;

use super::{NodeSetup, Technique, TechniqueInfo};
use compute_raster::{ComputeRaster, DrawBindings};

/// The registry entry.
pub const INFO: TechniqueInfo = TechniqueInfo {
    name: "tessellation",
    chapter: "6: Tessellation & Displacement",
    summary: "a plane tessellated on the GPU by screen-space edge length and displaced by an input texture",
    params: Settings::decls,
    inputs: &["height"],
    shaders: &["tessellation.wgsl", "tessellation_raster.wgsl", "msaa_samples.wgsl"],
    create,
    check: None,
    stage: None,
    declare: None,
};

/// The colour format.
pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The per-frame buffers for one grid size.
struct Buffers {
    grid: u32,
    factors: (wgpu::Buffer, u64),
    levels: (wgpu::Buffer, u64),
    offsets: (wgpu::Buffer, u64),
    /// Indirect draw arguments, then the triangle total.
    args: (wgpu::Buffer, u64),
    compute_group: wgpu::BindGroup,
}

/// A tessellation node.
pub struct Tessellation {
    device: wgpu::Device,
    queue: wgpu::Queue,
    uniforms: wgpu::Buffer,
    /// The uniforms alone (group 0 of the draw and of the boundary test).
    uniform_group: wgpu::BindGroup,
    compute_layout: wgpu::BindGroupLayout,
    draw_layout: wgpu::BindGroupLayout,
    boundary_layout: wgpu::BindGroupLayout,
    edges: ComputeKernel,
    patches: ComputeKernel,
    scan: ComputeKernel,
    boundaries: ComputeKernel,
    /// The draw pipeline for 1 sample and for `samples`.
    draw: [wgpu::RenderPipeline; 2],
    /// Samples per pixel with `msaa` on (the scene's, as the adapter allows; resolved before
    /// anything downstream sees the image).
    samples: u32,
    sampler: wgpu::Sampler,
    buffers: Buffers,
    /// The output size of the last frame added (for the bench report).
    output_size: (u32, u32),
    /// Draw bind groups by height texture id.
    draw_groups: RefCell<BindGroupCache<u64>>,
    /// The draw in compute, where the adapter has 64-bit atomics.
    compute_raster: Option<RefCell<ComputeRaster>>,
    /// Whether the last frame was drawn in compute.
    drew_in_compute: bool,
    /// What `rasterizer: auto` takes on this adapter.
    tuned: Rasterizer,
    /// The last frame's uniforms (tests compare against the CPU reference with them).
    last: Option<TessUniforms>,
}

fn create(setup: &NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError> {
    Ok(Box::new(Tessellation::new(setup)?))
}

impl Tessellation {
    /// Builds the pipelines; buffers follow the grid size, targets the output size.
    pub fn new(setup: &NodeSetup<'_>) -> Result<Self, ShaderError> {
        let device = &setup.gpu.device;
        let compute = wgpu::ShaderStages::COMPUTE;
        let all = compute | wgpu::ShaderStages::VERTEX_FRAGMENT;
        let compute_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("tessellation_compute_layout"),
            entries: &[
                crate::gpu::uniform_entry::<TessUniforms>(0, all),
                storage(1, compute, false),
                storage(2, compute, false),
                storage(3, compute, false),
                storage(4, compute, false),
            ],
        });
        // What the draw (and the boundary test) bind in group 0: the uniforms alone, since the
        // same buffers are bound read-only in group 1 (read-write and read-only may not meet).
        let uniform_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("tessellation_uniform_layout"),
            entries: &[crate::gpu::uniform_entry::<TessUniforms>(0, all)],
        });
        let read = wgpu::ShaderStages::VERTEX | compute;
        let [texture, sampler] = crate::gpu::sampled_texture_entries(0, read);
        let draw_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("tessellation_draw_layout"),
            entries: &[texture, sampler, storage(2, read, true), storage(3, read, true), storage(4, read, true)],
        });
        let boundary_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("tessellation_boundary_layout"),
            entries: &[storage(0, compute, false)],
        });
        let bindings = [("u", 0), ("edge_factors", 1), ("patch_levels", 2), ("offsets", 3), ("draw_args", 4)];
        let (origin, source) = setup.shader_source("tessellation.wgsl", &bindings)?;
        let kernel =
            |entry, layouts: &[&wgpu::BindGroupLayout]| ComputeKernel::new(device, &origin, &source, entry, layouts);
        let edges = kernel("edges", &[&compute_layout])?;
        let patches = kernel("patches", &[&compute_layout])?;
        let scan = kernel("scan", &[&compute_layout])?;
        let boundaries = kernel("evaluate_boundaries", &[&uniform_layout, &draw_layout, &boundary_layout])?;
        let compute_raster = if device.features().contains(compute_raster::FEATURES) {
            let joined = setup.joined_shader_source("tessellation_raster.wgsl", &bindings)?;
            Some(RefCell::new(ComputeRaster::new(device, &joined, [&uniform_layout, &draw_layout])?))
        } else {
            None
        };
        let (module, _) = crate::gpu::compile_wgsl(device, &origin, &source)?;
        let pipeline = |samples: u32| {
            crate::gpu::validated(device, &origin, || {
                let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some("tessellation_draw_pipeline_layout"),
                    bind_group_layouts: &[Some(&uniform_layout), Some(&draw_layout)],
                    immediate_size: 0,
                });
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some("tessellation/draw"),
                    layout: Some(&layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_main"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some("fs_main"),
                        compilation_options: Default::default(),
                        targets: &[Some(FORMAT.into())],
                    }),
                    primitive: wgpu::PrimitiveState::default(),
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: DEPTH,
                        depth_write_enabled: Some(true),
                        depth_compare: Some(wgpu::CompareFunction::Less),
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                    multisample: wgpu::MultisampleState { count: samples, ..Default::default() },
                    multiview_mask: None,
                    cache: None,
                })
            })
        };
        let samples = setup.samples_for(&[FORMAT, DEPTH]);
        let draw = [pipeline(1)?, pipeline(samples)?];
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("tessellation_height_sampler"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let uniforms = crate::gpu::uniform_buffer::<TessUniforms>(device, "tessellation_uniforms");
        let grid = Settings::read(setup.params).grid.clamp(1, 64) as u32;
        let buffers = make_buffers(device, &compute_layout, &uniforms, grid);
        let uniform_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("tessellation_uniform_group"),
            layout: &uniform_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: uniforms.as_entire_binding() }],
        });
        Ok(Self {
            device: device.clone(),
            queue: setup.gpu.queue.clone(),
            uniforms,
            uniform_group,
            compute_layout,
            draw_layout,
            boundary_layout,
            edges,
            patches,
            scan,
            boundaries,
            draw,
            samples,
            sampler,
            buffers,
            output_size: (0, 0),
            draw_groups: RefCell::default(),
            compute_raster,
            drew_in_compute: false,
            tuned: setup.tuned_rasterizer(INFO.name),
            last: None,
        })
    }

    /// The uniforms of the last frame added (None before the first).
    pub fn uniforms(&self) -> Option<TessUniforms> {
        self.last
    }

    /// Every edge's factor as the GPU computed it in the last submitted frame (blocking).
    pub fn read_factors(&self) -> Vec<f32> {
        self.read(|b| &b.factors.0).map(|b| bytemuck::cast_slice(&b).to_vec()).unwrap_or_default()
    }

    /// Every patch's level (0: culled) from the last submitted frame (blocking).
    pub fn read_levels(&self) -> Vec<u32> {
        self.read(|b| &b.levels.0).map(|b| bytemuck::cast_slice(&b).to_vec()).unwrap_or_default()
    }

    /// Triangles the last submitted frame drew (blocking).
    pub fn read_triangles(&self) -> u32 {
        self.read(|b| &b.args.0).map(|b| bytemuck::cast_slice::<u8, u32>(&b)[4]).unwrap_or(0)
    }

    fn read(&self, which: impl Fn(&Buffers) -> &wgpu::Buffer) -> Option<Vec<u8>> {
        let buffer = which(&self.buffers);
        crate::gpu::read_buffer(&self.device, &self.queue, buffer, 0, buffer.size()).ok()
    }

    /// The displaced position of every boundary lattice point of every patch, as the vertex
    /// shader places it, for the last submitted frame and `height`: (patch · 3 + edge) · 65 +
    /// index, w = 1 where a point exists (blocking; the crack test).
    pub fn boundary_points(&self, height: &wgpu::TextureView) -> Vec<[f32; 4]> {
        let b = &self.buffers;
        let patches = 2 * b.grid * b.grid;
        let out = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("tessellation_boundaries"),
            size: u64::from(patches) * 3 * 65 * 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("tessellation_boundary_group"),
            layout: &self.boundary_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: out.as_entire_binding() }],
        });
        let draw_group = self.make_draw_group(height, b);
        let mut encoder = self.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.boundaries.pipeline);
            pass.set_bind_group(0, &self.uniform_group, &[]);
            pass.set_bind_group(1, &draw_group, &[]);
            pass.set_bind_group(2, &group, &[]);
            pass.dispatch_workgroups(patches * 3, 1, 1);
        }
        self.queue.submit([encoder.finish()]);
        crate::gpu::read_buffer(&self.device, &self.queue, &out, 0, out.size())
            .map(|bytes| bytemuck::cast_slice(&bytes).to_vec())
            .unwrap_or_default()
    }

    /// Recreates the per-frame buffers if `grid` changed.
    fn ensure_buffers(&mut self, grid: u32) {
        if self.buffers.grid == grid {
            return;
        }
        self.buffers = make_buffers(&self.device, &self.compute_layout, &self.uniforms, grid);
        // Old draw groups bind the old buffers.
        *self.draw_groups.get_mut() = BindGroupCache::default();
    }

    fn make_draw_group(&self, height: &wgpu::TextureView, b: &Buffers) -> wgpu::BindGroup {
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("tessellation_draw_group"),
            layout: &self.draw_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(height) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&self.sampler) },
                wgpu::BindGroupEntry { binding: 2, resource: b.factors.0.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: b.levels.0.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: b.offsets.0.as_entire_binding() },
            ],
        })
    }

    /// Group 1 of the draw for the height texture `height`.
    fn draw_group(&self, ctx: &PassContext<'_>, height: TextureHandle, b: &Buffers) -> wgpu::BindGroup {
        self.draw_groups
            .borrow_mut()
            .get_or_create(ctx.texture_id(height), || self.make_draw_group(ctx.view(height), b))
            .clone()
    }

    /// Records the draw into `targets`: multisampled and resolved, or directly.
    fn record_draw(&self, ctx: &mut PassContext<'_>, height: TextureHandle, targets: &RasterTargets, clear: [f32; 4]) {
        let b = &self.buffers;
        let group = self.draw_group(ctx, height, b);
        let clear = wgpu::Color { r: f64::from(clear[0]), g: f64::from(clear[1]), b: f64::from(clear[2]), a: 1.0 };
        let mut pass = ctx.begin_draw(targets, clear);
        pass.set_pipeline(&self.draw[usize::from(targets.msaa.is_some())]);
        pass.set_bind_group(0, &self.uniform_group, &[]);
        pass.set_bind_group(1, &group, &[]);
        pass.draw_indirect(&b.args.0, 0);
    }

    /// Records the compute draw's coverage (`image` None) or its shading into `image`.
    fn record_compute_draw(
        &self,
        ctx: &mut PassContext<'_>,
        height: TextureHandle,
        visibility: BufferHandle,
        image: Option<TextureHandle>,
    ) {
        let (b, Some(raster)) = (&self.buffers, &self.compute_raster) else { return };
        let mesh = self.draw_group(ctx, height, b);
        let bindings = DrawBindings { uniforms: &self.uniform_group, mesh: &mesh, args: &b.args.0 };
        let lent = ctx.buffer_and_id(visibility);
        match image {
            None => raster.borrow_mut().record_raster(ctx.encoder, &bindings, &lent),
            Some(image) => {
                // Views are shared handles: a clone frees the context for the encoder.
                let (view, id) = (ctx.view(image).clone(), ctx.texture_id(image));
                raster.borrow_mut().record_resolve(ctx.encoder, &bindings, &lent, (&view, id));
            }
        }
    }
}

/// The per-frame buffers of a `grid`² plane: edge factors, patch levels, their prefix sums and
/// the indirect arguments, bound for the compute pass.
fn make_buffers(device: &wgpu::Device, layout: &wgpu::BindGroupLayout, uniforms: &wgpu::Buffer, grid: u32) -> Buffers {
    let patches = u64::from(2 * grid * grid);
    let make = |label, bytes: u64, usage| {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: bytes.max(16),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | usage,
            mapped_at_creation: false,
        });
        (buffer, crate::graph::next_resource_id())
    };
    let none = wgpu::BufferUsages::empty();
    let factors = make("tessellation_edge_factors", u64::from(edge_count(grid)) * 4, none);
    let levels = make("tessellation_patch_levels", patches * 4, none);
    let offsets = make("tessellation_offsets", (patches + 1) * 4, none);
    // The draw, the triangle total and the compute rasterizer's dispatch.
    let args = make("tessellation_draw_args", 8 * 4, wgpu::BufferUsages::INDIRECT);
    let compute_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("tessellation_compute_group"),
        layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: uniforms.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 1, resource: factors.0.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 2, resource: levels.0.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 3, resource: offsets.0.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 4, resource: args.0.as_entire_binding() },
        ],
    });
    Buffers { grid, factors, levels, offsets, args, compute_group }
}

impl Technique for Tessellation {
    fn add_passes<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        params: &ParamSet,
        _time: &FrameTime,
        inputs: &[TextureHandle],
    ) -> TextureHandle {
        let height = inputs[0];
        // Nothing here is state: a frame that is only stepped (a seek) needs none of it.
        if graph.is_simulation_only() {
            return height;
        }
        let size = graph.output_size();
        let u = TessUniforms::from_params(params, size);
        self.ensure_buffers(u.grid);
        self.output_size = size;
        self.queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&u));
        self.last = Some(u);
        self.draw_groups.get_mut().begin_frame();
        let settings = Settings::read(params);
        let samples = settings.msaa.samples(self.samples);
        self.drew_in_compute = settings.rasterizer.in_compute(self.tuned)
            && self.compute_raster.as_mut().is_some_and(|r| r.get_mut().prepare(&self.queue, size, samples, u.grid));

        let this: &'r Tessellation = self;
        let b = &this.buffers;
        let import = |graph: &mut FrameGraph<'r>, name: &str, (buffer, id): &(wgpu::Buffer, u64)| -> BufferHandle {
            graph.import_buffer(name, buffer, *id)
        };
        let factors = import(graph, "tessellation/edge_factors", &b.factors);
        let levels = import(graph, "tessellation/patch_levels", &b.levels);
        let offsets = import(graph, "tessellation/offsets", &b.offsets);
        let args = import(graph, "tessellation/draw_args", &b.args);
        let (edges, patches) = (u.edge_count, u.patch_count);
        graph
            .add_pass("tessellation/refine")
            .write_buffer(factors)
            .write_buffer(levels)
            .write_buffer(offsets)
            .write_buffer(args)
            .record(move |ctx| {
                let mut pass = ctx.encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("tessellation/refine"),
                    timestamp_writes: None,
                });
                this.edges.dispatch(&mut pass, &[&b.compute_group], [edges, 1, 1]);
                this.patches.dispatch(&mut pass, &[&b.compute_group], [patches, 1, 1]);
                this.scan.dispatch(&mut pass, &[&b.compute_group], [256, 1, 1]);
            });
        // Both draws read the input and the refined mesh's tables.
        let mesh = [factors, levels, offsets, args];
        if this.drew_in_compute {
            let raster = this.compute_raster.as_ref().expect("drawn in compute").borrow();
            let visibility = raster.declare_visibility(graph, "tessellation/visibility");
            drop(raster);
            let image = graph.create_texture("tessellation/image", TextureDesc::full(FORMAT));
            reading_mesh(graph.add_pass("tessellation/raster"), height, mesh)
                .write_buffer(visibility)
                .record(move |ctx| this.record_compute_draw(ctx, height, visibility, None));
            graph
                .add_pass("tessellation/resolve")
                .read(height)
                .read_buffer(visibility)
                .write(image)
                .record(move |ctx| this.record_compute_draw(ctx, height, visibility, Some(image)));
            return image;
        }
        let targets = graph.create_raster_targets("tessellation", FORMAT, Some(DEPTH), samples);
        let clear = u.background;
        reading_mesh(graph.add_pass("tessellation/draw"), height, mesh)
            .draws_into(&targets)
            .record(move |ctx| this.record_draw(ctx, height, &targets, clear));
        targets.color
    }

    fn map_pointer(&self, view: [f32; 2]) -> Option<[f32; 2]> {
        self.last.and_then(|u| pick(&u, view))
    }

    fn bench_report(&mut self) -> Vec<String> {
        let Some(u) = self.last else { return Vec::new() };
        vec![format!(
            "{} triangles from {} patches (grid {}, edge target {} px, {}×{} output), drawn by {}",
            self.read_triangles(),
            u.patch_count,
            u.grid,
            u.edge_px,
            self.output_size.0,
            u.screen_height,
            if self.drew_in_compute { "compute (visibility buffer)" } else { "the raster pipeline" }
        )]
    }
}

/// `pass` reading the input `height` and the refined mesh's tables, as both draws do.
fn reading_mesh<'g, 'r>(
    pass: PassBuilder<'g, 'r>,
    height: TextureHandle,
    mesh: [BufferHandle; 4],
) -> PassBuilder<'g, 'r> {
    mesh.into_iter().fold(pass.read(height), PassBuilder::read_buffer)
}

/// The UV (0–1, y up) of the undisplaced plane under a pointer at `view` (0–1 on the output, y
/// up) for the camera of `u`, if the ray through it hits the plane inside its bounds.
pub fn pick(u: &TessUniforms, view: [f32; 2]) -> Option<[f32; 2]> {
    use glam::{Mat4, Vec3, Vec4};
    let inverse = Mat4::from_cols_array_2d(&u.view_proj).inverse();
    let (x, y) = (view[0] * 2.0 - 1.0, view[1] * 2.0 - 1.0);
    let unproject = |z: f32| {
        let p = inverse * Vec4::new(x, y, z, 1.0);
        p.truncate() / p.w
    };
    let (near, far) = (unproject(0.0), unproject(1.0));
    let model = Mat4::from_cols_array_2d(&u.model);
    let (origin, normal) = (model.transform_point3(Vec3::ZERO), model.transform_vector3(Vec3::Y));
    let direction = far - near;
    let along = normal.dot(direction);
    if along.abs() < 1e-9 {
        return None;
    }
    let t = normal.dot(origin - near) / along;
    let local = model.inverse().transform_point3(near + direction * t);
    let uv = [local.x / u.plane_size + 0.5, local.z / u.plane_size + 0.5];
    ((0.0..=1.0).contains(&t) && uv.iter().all(|c| (0.0..=1.0).contains(c))).then_some(uv)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pointer_over_a_plane_point_picks_that_points_uv() {
        let mut params = ParamSet::new(super::Settings::decls());
        params.set_at(params.index("camera_yaw").unwrap(), crate::params::ParamValue::Float(25.0));
        params.snap();
        let u = TessUniforms::from_params(&params, (640, 360));
        let (model, view_proj) =
            (glam::Mat4::from_cols_array_2d(&u.model), glam::Mat4::from_cols_array_2d(&u.view_proj));
        for uv in [[0.3f32, 0.6], [0.5, 0.5], [0.9, 0.1]] {
            let local = glam::Vec3::new((uv[0] - 0.5) * PLANE_SIZE, 0.0, (uv[1] - 0.5) * PLANE_SIZE);
            let clip = view_proj * model.transform_point3(local).extend(1.0);
            let view = [(clip.x / clip.w + 1.0) / 2.0, (clip.y / clip.w + 1.0) / 2.0];
            let picked = pick(&u, view).expect("the point is on screen");
            assert!((picked[0] - uv[0]).abs() < 1e-4 && (picked[1] - uv[1]).abs() < 1e-4, "{uv:?} → {picked:?}");
        }
        assert_eq!(pick(&u, [0.5, 0.999]), None, "above the plane: a miss");
    }

    #[test]
    fn the_uniform_block_matches_the_wgsl_struct() {
        let source = include_str!("tessellation.wgsl");
        assert_eq!(crate::gpu::wgsl_struct_size(source, "Tess"), Some(size_of::<TessUniforms>() as u32));
    }

    #[test]
    fn the_mesh_numbering_covers_every_edge_twice_inside_and_once_on_the_border() {
        for grid in [1, 3, 10] {
            let mut uses = vec![0u32; edge_count(grid) as usize];
            for p in 0..2 * grid * grid {
                let (v, e) = reference::patch(grid, p);
                for k in 0..3 {
                    let (a, b) = reference::edge_vertices(grid, e[k]);
                    let (x, y) = (v[k].min(v[(k + 1) % 3]), v[k].max(v[(k + 1) % 3]));
                    assert_eq!((a, b), (x, y), "grid {grid} patch {p} edge {k}");
                    uses[e[k] as usize] += 1;
                }
            }
            let border = 4 * grid as usize;
            assert_eq!(uses.iter().filter(|&&n| n == 1).count(), border);
            assert!(uses.iter().all(|&n| n == 1 || n == 2));
        }
    }
}

#[cfg(test)]
mod render_tests;
