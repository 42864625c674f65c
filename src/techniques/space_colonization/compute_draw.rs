//! The tubes drawn in compute (`space_colonization_raster.wgsl`): exact capsules found by a ray
//! per sample into a visibility buffer, then shaded once per pixel and edge; the skinned scene's
//! floor (a ray–plane test per sample, filling the buffer first) and the model's additive glow
//! (a ray per sample and mesh triangle, summed per pixel in integers) with them. Where the raster
//! path is narrow (the H100/H200) this replaces the instanced eight-sided tubes; the pipeline
//! stays for lines and for adapters without 64-bit atomics.

use crate::gpu::{
    BindGroupCache, ComputeKernel, JoinedSource, ShaderError, buffer_entry as entry, storage_entry as storage,
};
use crate::graph::{BufferHandle, FrameGraph, PassContext};
use crate::techniques::visibility::{PixelRays, VisibilityBuffer};

use super::FORMAT;

/// Features the compute draw needs.
pub const FEATURES: wgpu::Features = wgpu::Features::SHADER_INT64.union(wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX);

/// `Raster` in the shader.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct RasterUniforms {
    /// The ray through pixel position p (y down) is `ray_origin + ray_x p.x + ray_y p.y`, not
    /// normalised; `ray_origin[3]`: the widest angle one pixel spans (at the image's centre).
    pub ray_origin: [f32; 4],
    /// The ray's change per pixel to the right.
    pub ray_x: [f32; 4],
    /// The ray's change per pixel down.
    pub ray_y: [f32; 4],
    /// The view axis (unit).
    pub forward: [f32; 4],
    /// Linear background colour.
    pub background: [f32; 4],
    /// Image size in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel (the draw's multisampling).
    pub samples: u32,
    /// Edge slots (threads dispatched).
    pub capacity: u32,
    /// Boxes of more pixels go to the large edges' queue (32 lanes each), fewer to the medium
    /// edges' (a thread each).
    pub large_pixels: i32,
    /// 1: the floor is drawn.
    pub floor: u32,
    /// 1: the model's glow is drawn.
    pub glow: u32,
    /// The model's triangles (the glow's).
    pub triangles: u32,
    /// Boxes of more pixels go to the huge edges' queue (a workgroup each).
    pub huge_pixels: i32,
    /// Padding to the WGSL struct's 16-byte alignment.
    pub _pad: [u32; 3],
}

/// Edge slots that fill an H200 one thread each (132 SMs × 2,048 threads, rounded up): with fewer
/// edges, one thread per medium edge leaves the GPU idle and a workgroup per edge wins (measured:
/// `space_colonization_tubes`, 10⁴ edges at 1080p, 0.30 against 0.59 ms).
const EDGES_FOR_THREADS: u32 = 1 << 18;

/// With that many edges, boxes of 16–128 px go to a thread each, 128–1,024 px to 32 lanes each
/// and larger ones to a workgroup (64 lanes). Measured on the grown million, H200 (see
/// `raster_large` in the shader): small edges want a thread, large ones lanes, and the huge
/// edges of a camera inside the forest a whole workgroup.
const MANY_EDGES_LARGE_PIXELS: i32 = 128;
/// See [`MANY_EDGES_LARGE_PIXELS`].
const MANY_EDGES_HUGE_PIXELS: i32 = 1024;

impl RasterUniforms {
    /// The uniforms for a `size` image seen by `view_proj` from `eye` (a perspective camera),
    /// with `samples` per pixel, `capacity` edge slots and `background` (linear).
    pub fn new(
        view_proj: glam::Mat4,
        eye: glam::Vec3,
        size: (u32, u32),
        samples: u32,
        capacity: u32,
        background: [f32; 4],
    ) -> Self {
        let PixelRays { origin, x: ray_x, y: ray_y } = PixelRays::new(view_proj, eye, size);
        let (width, height) = (f64::from(size.0.max(1)), f64::from(size.1.max(1)));
        let centre = origin + ray_x * (width / 2.0) + ray_y * (height / 2.0);
        let angle = ray_x.length().max(ray_y.length()) / centre.length();
        let v = PixelRays::vec4;
        Self {
            ray_origin: v(origin, angle),
            ray_x: v(ray_x, 0.0),
            ray_y: v(ray_y, 0.0),
            forward: v(centre.normalize(), 0.0),
            background,
            width: size.0,
            height: size.1,
            samples,
            capacity,
            // With few edges every queued edge is huge (a workgroup each).
            large_pixels: if capacity >= EDGES_FOR_THREADS { MANY_EDGES_LARGE_PIXELS } else { 0 },
            huge_pixels: if capacity >= EDGES_FOR_THREADS { MANY_EDGES_HUGE_PIXELS } else { 0 },
            floor: 0,
            glow: 0,
            triangles: 0,
            _pad: [0; 3],
        }
    }

    /// These uniforms with the floor (`floor`) and the glow of a model of `triangles` (none: 0).
    pub fn with_extras(self, floor: bool, triangles: u32) -> Self {
        Self { floor: u32::from(floor), glow: u32::from(triangles > 0), triangles, ..self }
    }
}

/// Workgroups per glow triangle (`GLOW_CHUNKS` in the shader).
const GLOW_CHUNKS: u32 = 16;

/// The buffers the frame graph lends the compute draw each frame: as handles while the frame is
/// declared, as buffers and their ids while it is recorded.
#[derive(Clone, Copy, Debug)]
pub struct Lent<B> {
    /// One 64-bit word per sample (see [`VisibilityBuffer`]).
    pub visibility: B,
    /// The glow's sum per pixel, a u32 each, on frames that draw the glow.
    pub glow_sum: Option<B>,
}

impl Lent<BufferHandle> {
    /// The buffers behind the handles in a pass.
    pub fn in_pass(&self, ctx: &PassContext<'_>) -> Lent<(wgpu::Buffer, u64)> {
        Lent {
            visibility: ctx.buffer_and_id(self.visibility),
            glow_sum: self.glow_sum.map(|sums| ctx.buffer_and_id(sums)),
        }
    }
}

/// The kernels of the compute draw (its buffers are lent, see [`Lent`]).
pub struct ComputeDraw {
    device: wgpu::Device,
    raster: ComputeKernel,
    raster_medium: ComputeKernel,
    raster_large: ComputeKernel,
    raster_huge: ComputeKernel,
    floor_fill: ComputeKernel,
    glow: ComputeKernel,
    resolve: ComputeKernel,
    raster_layout: wgpu::BindGroupLayout,
    big_layout: wgpu::BindGroupLayout,
    floor_layout: wgpu::BindGroupLayout,
    glow_layout: wgpu::BindGroupLayout,
    resolve_layout: wgpu::BindGroupLayout,
    uniforms: wgpu::Buffer,
    visibility: Option<VisibilityBuffer>,
    /// Group 1 of the floor's fill, by the id of the visibility buffer the graph lent.
    floor_groups: BindGroupCache<u64>,
    /// Group 1 of the glow, by the ids of the lent visibility buffer and glow sums.
    glow_groups: BindGroupCache<(u64, u64)>,
    /// This frame's uniforms.
    frame: Option<RasterUniforms>,
    /// Edge slots this frame (the raster's threads).
    capacity: u32,
    /// The queue of medium and large edges (two counts, then up to `capacity` edges), by its
    /// capacity.
    big_queue: Option<(u32, wgpu::Buffer)>,
    /// The queue kernels' dispatches: (x, 1, 1) for the medium edges at byte 0, the large at 16.
    big_args: wgpu::Buffer,
    /// Group 1 of the raster and of the queue kernel, by the growth's argument buffer id and the
    /// lent visibility buffer's.
    raster_groups: BindGroupCache<(u64, u64), [wgpu::BindGroup; 2]>,
    /// Group 1 of the resolve, by the ids of the lent visibility buffer, the lent glow sums and
    /// the output texture.
    resolve_groups: BindGroupCache<(u64, u64, u64)>,
}

impl ComputeDraw {
    /// Builds the kernels from `space_colonization_raster.wgsl` (joined after the draw shader);
    /// `view_layout` is group 0 as the pipeline draw binds it.
    pub fn new(
        device: &wgpu::Device,
        shader: &JoinedSource,
        view_layout: &wgpu::BindGroupLayout,
    ) -> Result<Self, ShaderError> {
        let compute = wgpu::ShaderStages::COMPUTE;
        let uniforms_entry = crate::gpu::uniform_entry::<RasterUniforms>(0, compute);
        let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries })
        };
        let raster_layout = layout(
            "sc_raster_layout",
            &[
                uniforms_entry,
                storage(1, compute, false),
                storage(2, compute, true),
                storage(5, compute, false),
                storage(6, compute, false),
            ],
        );
        // The queue's kernel reads big_args as its dispatch, so it may not bind them too.
        let big_layout =
            layout("sc_raster_big_layout", &[uniforms_entry, storage(1, compute, false), storage(8, compute, true)]);
        let output = crate::gpu::output_image_entry(4, FORMAT);
        let resolve_layout = layout(
            "sc_resolve_layout",
            &[uniforms_entry, storage(3, compute, true), output, storage(10, compute, true)],
        );
        let floor_layout = layout("sc_floor_layout", &[uniforms_entry, storage(11, compute, false)]);
        let glow_layout =
            layout("sc_glow_layout", &[uniforms_entry, storage(3, compute, true), storage(9, compute, false)]);
        let kernel = |entry, group: &wgpu::BindGroupLayout| {
            ComputeKernel::new(device, shader.origin(), &shader.source, entry, &[view_layout, group])
                .map_err(|e| shader.relocate(e))
        };
        Ok(Self {
            device: device.clone(),
            raster: kernel("raster", &raster_layout)?,
            raster_medium: kernel("raster_medium", &big_layout)?,
            raster_large: kernel("raster_large", &big_layout)?,
            raster_huge: kernel("raster_huge", &big_layout)?,
            floor_fill: kernel("floor_fill", &floor_layout)?,
            glow: kernel("glow", &glow_layout)?,
            resolve: kernel("resolve", &resolve_layout)?,
            raster_layout,
            big_layout,
            floor_layout,
            glow_layout,
            resolve_layout,
            uniforms: crate::gpu::uniform_buffer::<RasterUniforms>(device, "sc_raster_uniforms"),
            visibility: None,
            floor_groups: BindGroupCache::default(),
            glow_groups: BindGroupCache::default(),
            frame: None,
            capacity: 0,
            big_queue: None,
            big_args: wgpu::util::DeviceExt::create_buffer_init(
                device,
                &wgpu::util::BufferInitDescriptor {
                    label: Some("sc_big_args"),
                    contents: bytemuck::cast_slice(&[0u32, 1, 1, 0, 0, 1, 1, 0, 0, 1, 1, 0]),
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
                },
            ),
            raster_groups: BindGroupCache::default(),
            resolve_groups: BindGroupCache::default(),
        })
    }

    /// Readies the visibility buffer for `u`'s size and samples and writes the uniforms; false
    /// when the buffer would exceed the device's limits (the caller draws with the pipeline).
    pub fn prepare(&mut self, queue: &wgpu::Queue, u: &RasterUniforms) -> bool {
        if !VisibilityBuffer::ensure(&mut self.visibility, &self.device, (u.width, u.height), u.samples) {
            return false;
        }
        if self.big_queue.as_ref().is_none_or(|(capacity, _)| *capacity < u.capacity) {
            let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("sc_big_queue"),
                // The counts, then the medium and large edges' region and the huge edges'.
                size: (2 * u64::from(u.capacity) + 4) * 4,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            self.big_queue = Some((u.capacity, buffer));
            self.raster_groups = BindGroupCache::default();
        }
        self.raster_groups.begin_frame();
        self.resolve_groups.begin_frame();
        self.floor_groups.begin_frame();
        self.glow_groups.begin_frame();
        self.capacity = u.capacity;
        self.frame = Some(*u);
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(u));
        true
    }

    /// Declares this frame's visibility buffer and, if it draws the `glow`, the glow's sums (a
    /// u32 per pixel) in `graph` (after a successful [`Self::prepare`]): the graph lends both
    /// from its pool.
    pub fn declare_buffers(&self, graph: &mut FrameGraph<'_>, glow: bool) -> Lent<BufferHandle> {
        let visibility = self.visibility.expect("prepared");
        let (width, height, _) = visibility.key();
        let sums = (u64::from(width) * u64::from(height) * 4).max(4);
        Lent {
            visibility: visibility.declare(graph, "space_colonization/visibility"),
            glow_sum: glow.then(|| graph.create_buffer("space_colonization/glow_sum", sums)),
        }
    }

    /// Records the coverage: the visibility buffer cleared, then one thread per edge slot
    /// (`view` is group 0; `args` the growth's indirect arguments, holding the grown count; the
    /// last the visibility buffer the graph lent and its id).
    pub fn record_raster(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        view: &wgpu::BindGroup,
        args: (&wgpu::Buffer, u64),
        (v, v_id): (&wgpu::Buffer, u64),
    ) {
        let (Some(visibility), Some((_, queue))) = (&self.visibility, &self.big_queue) else { return };
        let (device, uniforms, big_args) = (&self.device, &self.uniforms, &self.big_args);
        let (raster_layout, big_layout) = (&self.raster_layout, &self.big_layout);
        let groups = self.raster_groups.get_or_create((args.1, v_id), || {
            let group = |layout, entries: &[wgpu::BindGroupEntry]| {
                device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some("sc_raster_group"), layout, entries })
            };
            [
                group(
                    raster_layout,
                    &[entry(0, uniforms), entry(1, v), entry(2, args.0), entry(5, queue), entry(6, big_args)],
                ),
                group(big_layout, &[entry(0, uniforms), entry(1, v), entry(8, queue)]),
            ]
        });
        let floor = self.frame.is_some_and(|u| u.floor != 0);
        if !floor {
            encoder.clear_buffer(v, 0, None);
        }
        encoder.clear_buffer(queue, 0, Some(16));
        for offset in [0, 16, 32] {
            encoder.clear_buffer(big_args, offset, Some(4));
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("space_colonization/raster"),
            timestamp_writes: None,
        });
        if floor {
            let (floor_layout, floor_fill) = (&self.floor_layout, &self.floor_fill);
            let floor_group = self.floor_groups.get_or_create(v_id, || {
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("sc_floor_group"),
                    layout: floor_layout,
                    entries: &[entry(0, uniforms), entry(11, v)],
                })
            });
            // The floor writes every word: the clear's work, with the floor's hits.
            let (width, height, _) = visibility.key();
            floor_fill.dispatch(&mut pass, &[view, floor_group], [width, height, 1]);
        }
        // Rows of at most 65,535 workgroups; the shader numbers threads across them.
        let slots = self.capacity.max(1);
        let row = 65535 * 256;
        self.raster.dispatch(&mut pass, &[view, &groups[0]], [slots.min(row), slots.div_ceil(row), 1]);
        pass.set_bind_group(0, view, &[]);
        pass.set_bind_group(1, &groups[1], &[]);
        for (kernel, offset) in [(&self.raster_medium, 0), (&self.raster_large, 16), (&self.raster_huge, 32)] {
            pass.set_pipeline(&kernel.pipeline);
            pass.dispatch_workgroups_indirect(big_args, offset);
        }
    }

    /// Records the model's glow (`view` is group 0): its sums cleared, then a workgroup per
    /// triangle and chunk; nothing where this frame draws no glow.
    pub fn record_glow(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        view: &wgpu::BindGroup,
        lent: &Lent<(wgpu::Buffer, u64)>,
    ) {
        let (Some(u), (v, v_id), Some((sums, sums_id))) =
            (self.frame.filter(|u| u.glow != 0), &lent.visibility, &lent.glow_sum)
        else {
            return;
        };
        let (device, layout, uniforms) = (&self.device, &self.glow_layout, &self.uniforms);
        let group = self.glow_groups.get_or_create((*v_id, *sums_id), || {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("sc_glow_group"),
                layout,
                entries: &[entry(0, uniforms), entry(3, v), entry(9, sums)],
            })
        });
        encoder.clear_buffer(sums, 0, None);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("space_colonization/glow"),
            timestamp_writes: None,
        });
        // At most 65,535 workgroups in x: the shader loops over the triangles past them.
        self.glow.dispatch(&mut pass, &[view, group], [u.triangles.min(65535) * 256, GLOW_CHUNKS, 1]);
    }

    /// Records the shading of every pixel into `image` (its view and graph id).
    pub fn record_resolve(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        view: &wgpu::BindGroup,
        lent: &Lent<(wgpu::Buffer, u64)>,
        image: (&wgpu::TextureView, u64),
    ) {
        let Some(visibility) = &self.visibility else { return };
        // Without the glow the shader reads no sums: the visibility buffer stands in for them.
        let ((v, v_id), (sums, sums_id)) = (&lent.visibility, lent.glow_sum.as_ref().unwrap_or(&lent.visibility));
        let (device, layout, uniforms) = (&self.device, &self.resolve_layout, &self.uniforms);
        let group = self.resolve_groups.get_or_create((*v_id, *sums_id, image.1), || {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("sc_resolve_group"),
                layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: uniforms.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 3, resource: v.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::TextureView(image.0) },
                    entry(10, sums),
                ],
            })
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("space_colonization/resolve"),
            timestamp_writes: None,
        });
        let (width, height, _) = visibility.key();
        self.resolve.dispatch(&mut pass, &[view, group], [width, height, 1]);
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_uniform_block_and_the_argument_word_match_the_wgsl() {
        let source = [
            include_str!("../../../shaders/msaa_samples.wgsl"),
            include_str!("space_colonization_draw.wgsl"),
            include_str!("space_colonization_raster.wgsl"),
        ]
        .join("\n");
        assert_eq!(crate::gpu::wgsl_struct_size(&source, "Raster"), Some(size_of::<super::RasterUniforms>() as u32));
        let word = super::super::growth::TUBE_ARGS / 4 + 1;
        assert!(source.contains(&format!("const TUBE_INSTANCES: u32 = {word}u;")), "TUBE_INSTANCES must be {word}");
    }
}
