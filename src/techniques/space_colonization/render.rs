//! Drawing the forest: instanced lines or capsules, one instance per edge, sized by the indirect
//! arguments the growth step wrote (free slots cost nothing), multisampled and resolved — or the
//! tubes as exact capsules in compute (`compute_draw`), where the adapter has 64-bit atomics.

use std::cell::RefCell;

use super::compute_draw::{self, ComputeDraw, Lent, RasterUniforms};
use super::growth::{GrowthState, LINE_ARGS, TUBE_ARGS};
use super::params::ViewUniforms;
use crate::gpu::{BindGroupCache, RasterDesc, ShaderError, raster_pipeline};
use crate::graph::{BufferHandle, FrameGraph, PassContext, RasterTargets, TextureHandle};
use crate::techniques::NodeSetup;

/// Vertices around a tube (the draw shader's `SIDES`).
pub const TUBE_SIDES: u32 = 8;
/// Rings of the tip's hemispherical cap (the draw shader's `CAP_ROWS`).
pub const TUBE_CAP_ROWS: u32 = 3;
/// The draw shader's bindings, in the order of the draw group's entries.
const DRAW_BINDINGS: [(&str, u32); 6] =
    [("view", 0), ("posed", 1), ("nodes", 2), ("mesh_positions", 3), ("vertex_skins", 4), ("joint_matrices", 5)];
/// Depth format of the draw.
pub const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Indices of one capsule: quads between consecutive rings (two rings and the cap's).
pub fn tube_indices() -> Vec<u32> {
    let rows = 2 + TUBE_CAP_ROWS;
    let mut indices = Vec::new();
    for row in 0..rows - 1 {
        for side in 0..TUBE_SIDES {
            let next = (side + 1) % TUBE_SIDES;
            let (a, b) = (row * TUBE_SIDES + side, row * TUBE_SIDES + next);
            let (c, d) = (a + TUBE_SIDES, b + TUBE_SIDES);
            indices.extend_from_slice(&[a, b, c, b, d, c]);
        }
    }
    indices
}

/// What is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Style {
    /// Additive lines.
    Lines,
    /// Opaque capsules.
    Tubes,
    /// The floor (opaque).
    Floor,
    /// The model's skin (additive, depth-tested).
    Mesh,
}

/// What one frame draws besides the branches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Extras {
    /// Draw the floor first.
    pub floor: bool,
    /// Draw the model's glow last.
    pub mesh: bool,
}

impl Extras {
    /// Whether a frame of `style` with these extras needs a depth buffer: lines alone add up
    /// whatever their depth, and at 4K a multisampled depth buffer costs ~2.4 ms to clear on the
    /// H200 (examples/raster_floor).
    pub fn need_depth(self, style: Style) -> bool {
        style != Style::Lines || self.floor || self.mesh
    }
}

/// The draw pipelines (lines, tubes, floor and model, at 1 sample and the scene's).
pub struct Renderer {
    /// [lines, tubes, floor, mesh, lines without a depth buffer] × [1 sample, `samples`].
    pipelines: [[wgpu::RenderPipeline; 2]; 5],
    layout: wgpu::BindGroupLayout,
    uniform: wgpu::Buffer,
    indices: wgpu::Buffer,
    /// Indices per tube.
    pub index_count: u32,
    /// Samples per pixel with `msaa` on (the scene's, as the adapter allows).
    pub samples: u32,
    groups: BindGroupCache<(u64, u64)>,
    /// The tubes' compute draw, where the adapter has 64-bit atomics (it keeps bind groups as
    /// it records, from the shared borrow the frame graph's passes get).
    compute: Option<RefCell<ComputeDraw>>,
}

impl Renderer {
    /// Builds the pipelines from `space_colonization_draw.wgsl` for `format`.
    pub fn new(setup: &NodeSetup<'_>, format: wgpu::TextureFormat) -> Result<Self, ShaderError> {
        let device = &setup.gpu.device;
        let shader = setup.joined_shader_source("space_colonization_draw.wgsl", &DRAW_BINDINGS)?;
        let origin = shader.origin().to_string();
        let (module, _) = crate::gpu::compile_wgsl(device, &origin, &shader.source).map_err(|e| shader.relocate(e))?;
        // Group 0 serves both draws: the vertex and fragment stages, and the compute kernels.
        let stages = wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let readers = wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::COMPUTE;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("sc_draw_layout"),
            entries: &[
                crate::gpu::uniform_entry::<ViewUniforms>(0, stages),
                crate::gpu::storage_entry(1, readers, true),
                crate::gpu::storage_entry(2, readers, true),
                crate::gpu::storage_entry(3, readers, true),
                crate::gpu::storage_entry(4, readers, true),
                crate::gpu::storage_entry(5, readers, true),
                // The model's triangles, for the compute draw's glow.
                crate::gpu::storage_entry(6, wgpu::ShaderStages::COMPUTE, true),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("sc_draw_pipeline_layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let samples = setup.samples_for(&[format, DEPTH]);
        let pipeline = |style: Style, samples, with_depth: bool| {
            let (vertex, fragment, topology, depth, additive) = match style {
                // Lines add up regardless of depth, as the book draws them.
                Style::Lines => {
                    ("vs_line", "fs_line", wgpu::PrimitiveTopology::LineList, wgpu::CompareFunction::Always, true)
                }
                Style::Tubes => {
                    ("vs_tube", "fs_tube", wgpu::PrimitiveTopology::TriangleList, wgpu::CompareFunction::Less, false)
                }
                Style::Floor => {
                    ("vs_floor", "fs_floor", wgpu::PrimitiveTopology::TriangleList, wgpu::CompareFunction::Less, false)
                }
                // The glow adds where nothing nearer hides it.
                Style::Mesh => {
                    ("vs_mesh", "fs_mesh", wgpu::PrimitiveTopology::TriangleList, wgpu::CompareFunction::Less, true)
                }
            };
            let desc = RasterDesc {
                vertex,
                fragment,
                buffers: &[],
                topology,
                color: format,
                depth: with_depth.then_some((DEPTH, depth)),
                additive,
                samples,
            };
            raster_pipeline(device, &module, &pipeline_layout, &desc)
        };
        let pipelines = crate::gpu::validated(device, &origin, || {
            [
                (Style::Lines, true),
                (Style::Tubes, true),
                (Style::Floor, true),
                (Style::Mesh, true),
                (Style::Lines, false),
            ]
            .map(|(s, depth)| [pipeline(s, 1, depth), pipeline(s, samples, depth)])
        })?;
        let compute = if device.features().contains(compute_draw::FEATURES) {
            let shader = setup.joined_shader_source("space_colonization_raster.wgsl", &DRAW_BINDINGS)?;
            Some(RefCell::new(ComputeDraw::new(device, &shader, &layout)?))
        } else {
            None
        };
        let index_data = tube_indices();
        use wgpu::util::DeviceExt;
        let indices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("sc_tube_indices"),
            contents: bytemuck::cast_slice(&index_data),
            usage: wgpu::BufferUsages::INDEX,
        });
        Ok(Self {
            pipelines,
            layout,
            uniform: crate::gpu::uniform_buffer::<ViewUniforms>(device, "sc_view"),
            indices,
            index_count: index_data.len() as u32,
            samples,
            groups: BindGroupCache::default(),
            compute,
        })
    }

    /// Writes the view uniforms and makes the bind group for `state`'s buffers.
    pub fn prepare(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, state: &GrowthState, view: &ViewUniforms) {
        queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(view));
        self.groups.begin_frame();
        let (layout, uniform) = (&self.layout, &self.uniform);
        self.groups.get_or_create((state.posed.id, state.nodes.id), || {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("sc_draw_group"),
                layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: state.posed.buffer.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 2, resource: state.nodes.buffer.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 3, resource: state.mesh.positions.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 4, resource: state.skins.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 5, resource: state.joints.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 6, resource: state.mesh.indices.as_entire_binding() },
                ],
            })
        });
    }

    /// Readies the compute draw for a frame with `u`; false where there is none (no 64-bit
    /// atomics) or its visibility buffer would exceed the device's limits.
    pub fn prepare_compute(&mut self, queue: &wgpu::Queue, u: &RasterUniforms) -> bool {
        self.compute.as_mut().is_some_and(|c| c.get_mut().prepare(queue, u))
    }

    /// Declares the buffers the graph lends the compute draw this frame (after
    /// [`Self::prepare_compute`]).
    pub fn declare_compute_buffers(&self, graph: &mut FrameGraph<'_>, glow: bool) -> Option<Lent<BufferHandle>> {
        Some(self.compute.as_ref()?.borrow().declare_buffers(graph, glow))
    }

    /// The compute draw and the view group of `state`'s buffers, where both exist.
    fn compute_and_group(&self, state: &GrowthState) -> Option<(std::cell::RefMut<'_, ComputeDraw>, &wgpu::BindGroup)> {
        let compute = self.compute.as_ref()?;
        let group = self.groups.get(&(state.posed.id, state.nodes.id))?;
        Some((compute.borrow_mut(), group))
    }

    /// Records the compute draw's coverage of every grown edge.
    pub fn record_compute_raster(&self, ctx: &mut PassContext<'_>, state: &GrowthState, lent: Lent<BufferHandle>) {
        let Some((mut compute, group)) = self.compute_and_group(state) else { return };
        let (visibility, id) = ctx.buffer_and_id(lent.visibility);
        compute.record_raster(ctx.encoder, group, (&state.args.buffer, state.args.id), (&visibility, id));
    }

    /// Records the compute draw's glow of the model's mesh over what the raster kept.
    pub fn record_compute_glow(&self, ctx: &mut PassContext<'_>, state: &GrowthState, lent: Lent<BufferHandle>) {
        let Some((mut compute, group)) = self.compute_and_group(state) else { return };
        compute.record_glow(ctx.encoder, group, &lent.in_pass(ctx));
    }

    /// Records the compute draw's shading into `image` (its view and graph id).
    pub fn record_compute_resolve(
        &self,
        ctx: &mut PassContext<'_>,
        state: &GrowthState,
        lent: Lent<BufferHandle>,
        image: TextureHandle,
    ) {
        let Some((mut compute, group)) = self.compute_and_group(state) else { return };
        // Views are shared handles: a clone frees the context for the encoder.
        let (view, id) = (ctx.view(image).clone(), ctx.texture_id(image));
        compute.record_resolve(ctx.encoder, group, &lent.in_pass(ctx), (&view, id));
    }

    /// Records the draw of every grown edge into `targets` (resolved if multisampled).
    pub fn draw(
        &self,
        ctx: &mut PassContext<'_>,
        state: &GrowthState,
        targets: &RasterTargets,
        style: Style,
        extras: Extras,
        clear: wgpu::Color,
    ) {
        let Some(group) = self.groups.get(&(state.posed.id, state.nodes.id)) else { return };
        let mut pass = ctx.begin_draw(targets, clear);
        let samples = usize::from(targets.msaa.is_some());
        pass.set_bind_group(0, group, &[]);
        if extras.floor {
            pass.set_pipeline(&self.pipelines[2][samples]);
            pass.draw(0..6, 0..1);
        }
        match style {
            Style::Lines => {
                pass.set_pipeline(&self.pipelines[if targets.depth.is_some() { 0 } else { 4 }][samples]);
                pass.draw_indirect(&state.args.buffer, LINE_ARGS);
            }
            Style::Tubes => {
                pass.set_pipeline(&self.pipelines[1][samples]);
                pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed_indirect(&state.args.buffer, TUBE_ARGS);
            }
            Style::Floor | Style::Mesh => {}
        }
        if extras.mesh && state.mesh.index_count > 0 {
            pass.set_pipeline(&self.pipelines[3][samples]);
            pass.set_index_buffer(state.mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..state.mesh.index_count, 0, 0..1);
        }
    }
}
