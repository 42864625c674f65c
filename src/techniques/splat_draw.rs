//! A draw in compute of primitives that each cover a box of pixels on screen (the steps shared
//! in `shaders/splat_draw.wgsl`; the technique's raster shader extends it with what a primitive
//! covers and how it is shaded): coverage per sample into a visibility buffer, then
//! shading once per pixel and primitive. Where the raster path is narrow (the H100/H200) this
//! replaces instanced quads and meshes (Poisson's discs, the cube field's cubes, the cloth); the
//! pipeline stays for adapters without 64-bit atomics.

use crate::gpu::{BindGroupCache, ComputeKernel, ShaderError, buffer_entry as entry, storage_entry as storage};
use crate::graph::{BufferHandle, FrameGraph};
use crate::techniques::NodeSetup;
use crate::techniques::visibility::VisibilityBuffer;

/// Features the compute draw needs.
pub const FEATURES: wgpu::Features = wgpu::Features::SHADER_INT64.union(wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX);

/// `Splat` in the shader.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SplatUniforms {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Primitives drawn.
    pub count: u32,
    /// Samples per pixel.
    pub samples: u32,
    /// Linear colour where nothing is drawn.
    pub background: [f32; 4],
}

impl SplatUniforms {
    /// `count` primitives into a `size` image of `samples` per pixel over `background` (linear).
    pub fn new(size: (u32, u32), count: u32, samples: u32, background: [f32; 4]) -> Self {
        Self { width: size.0, height: size.1, count, samples: samples.max(1), background }
    }
}

/// The kernels, as keys of their bind groups.
const RASTER: u8 = 0;
const RASTER_BIG: u8 = 1;
const RESOLVE: u8 = 2;

/// Threads per row of the raster's dispatch (the most workgroups one dimension may hold, of 64).
const THREADS_PER_ROW: u32 = 65535 * 64;

/// The kernels, uniforms, visibility buffer and queue of one node's compute draw.
pub struct SplatDraw {
    device: wgpu::Device,
    raster: ComputeKernel,
    raster_big: ComputeKernel,
    resolve: ComputeKernel,
    raster_layout: wgpu::BindGroupLayout,
    big_layout: wgpu::BindGroupLayout,
    resolve_layout: wgpu::BindGroupLayout,
    uniforms: wgpu::Buffer,
    visibility: Option<VisibilityBuffer>,
    /// The large primitives' queue (its length, then one slot each), by its capacity.
    big_queue: Option<(u32, wgpu::Buffer)>,
    /// The large primitives' dispatch (queued, chunks of the largest, rows), written by the raster.
    big_args: wgpu::Buffer,
    /// Group 1 by kernel (`RASTER`, `RASTER_BIG`, `RESOLVE`), the id of the visibility buffer
    /// the graph lent, and the output texture's id (0 for the raster kernels); dropped when a
    /// buffer they bind is made anew.
    groups: BindGroupCache<(u8, u64, u64)>,
}

impl SplatDraw {
    /// Group 0 for a node whose kernels see only its uniform block of `T` in `buffer`.
    pub fn uniform_view<T>(device: &wgpu::Device, buffer: &wgpu::Buffer) -> (wgpu::BindGroupLayout, wgpu::BindGroup) {
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("splat_view"),
            entries: &[crate::gpu::uniform_entry::<T>(0, wgpu::ShaderStages::COMPUTE)],
        });
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("splat_view"),
            layout: &layout,
            entries: &[entry(0, buffer)],
        });
        (layout, group)
    }

    /// Builds the kernels from the technique's raster shader `file` (with the files it extends,
    /// `splat_draw.wgsl` among them; each group-0 binding of `bindings` checked); group 0 (the
    /// node's own) has `view_layout`; `primitives` says whether group 1 binds a buffer of them
    /// (binding 1) or the shader finds them itself.
    pub fn new(
        setup: &NodeSetup<'_>,
        file: &str,
        bindings: &[(&str, u32)],
        view_layout: &wgpu::BindGroupLayout,
        primitives: bool,
    ) -> Result<Self, ShaderError> {
        let device = &setup.gpu.device;
        let shader = setup.joined_shader_source(file, bindings)?;
        let compute = wgpu::ShaderStages::COMPUTE;
        let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries })
        };
        let uniforms_entry = crate::gpu::uniform_entry::<SplatUniforms>(0, compute);
        let first: Vec<_> =
            [Some(uniforms_entry), primitives.then(|| storage(1, compute, true))].into_iter().flatten().collect();
        let with = |more: &[wgpu::BindGroupLayoutEntry]| [&first[..], more].concat();
        let visibility = storage(2, compute, false);
        let (queue, args) = (storage(5, compute, false), storage(6, compute, false));
        let raster_layout = layout("splat_raster_layout", &with(&[visibility, queue, args]));
        // The large primitives' kernel reads big_args as its dispatch, so it may not bind them too.
        let big_layout = layout("splat_big_layout", &with(&[visibility, storage(7, compute, true)]));
        let output = crate::gpu::output_image_entry(4, wgpu::TextureFormat::Rgba16Float);
        let resolve_layout = layout("splat_resolve_layout", &with(&[storage(3, compute, true), output]));
        let kernel = |entry, group: &wgpu::BindGroupLayout| {
            ComputeKernel::new(device, shader.origin(), &shader.source, entry, &[view_layout, group])
                .map_err(|e| shader.relocate(e))
        };
        Ok(Self {
            device: device.clone(),
            raster: kernel("raster", &raster_layout)?,
            raster_big: kernel("raster_big", &big_layout)?,
            resolve: kernel("resolve", &resolve_layout)?,
            raster_layout,
            big_layout,
            resolve_layout,
            uniforms: crate::gpu::uniform_buffer::<SplatUniforms>(device, "splat_uniforms"),
            visibility: None,
            big_queue: None,
            big_args: wgpu::util::DeviceExt::create_buffer_init(
                device,
                &wgpu::util::BufferInitDescriptor {
                    label: Some("splat_big_args"),
                    contents: bytemuck::cast_slice(&[0u32, 0, 0]),
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
                },
            ),
            groups: BindGroupCache::default(),
        })
    }

    /// Readies the visibility buffer for a `size` image of `samples` per pixel and the queue
    /// for `count` primitives; `primitives_made` says their buffer was made anew since the last
    /// frame. False when the buffer would exceed the device's limits (the caller draws with the
    /// pipeline).
    pub fn prepare(&mut self, size: (u32, u32), samples: u32, count: u32, primitives_made: bool) -> bool {
        if !VisibilityBuffer::ensure(&mut self.visibility, &self.device, size, samples) {
            return false;
        }
        let mut made = false;
        if self.big_queue.as_ref().is_none_or(|(capacity, _)| *capacity < count) {
            // Room to grow into, so that a growing set does not make a queue every frame.
            let capacity = count.max(1024).next_power_of_two();
            let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("splat_big_queue"),
                size: (u64::from(capacity) + 1) * 4,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            self.big_queue = Some((capacity, buffer));
            made = true;
        }
        if made || primitives_made {
            self.groups = BindGroupCache::default();
        }
        self.groups.begin_frame();
        true
    }

    /// Declares this frame's visibility buffer in `graph` as `name` (after a successful
    /// [`Self::prepare`]): the raster writes it, the resolve reads it.
    pub fn declare_visibility(&self, graph: &mut FrameGraph<'_>, name: &str) -> BufferHandle {
        self.visibility.expect("prepared").declare(graph, name)
    }

    /// Records the coverage of `u.count` primitives (from `primitives`, where group 1 binds
    /// them): the visibility buffer cleared, then one thread per primitive and one workgroup per
    /// large one, into the visibility buffer the graph lent (with its id); `view` is group 0.
    pub fn record_raster(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        queue: &wgpu::Queue,
        u: &SplatUniforms,
        view: &wgpu::BindGroup,
        primitives: Option<&wgpu::Buffer>,
        (v, v_id): &(wgpu::Buffer, u64),
    ) {
        let Some((_, big_queue)) = &self.big_queue else { return };
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(u));
        let (device, uniforms, args) = (&self.device, &self.uniforms, &self.big_args);
        for (kernel, layout) in [(RASTER, &self.raster_layout), (RASTER_BIG, &self.big_layout)] {
            self.groups.get_or_create((kernel, *v_id, 0), || {
                let own = if kernel == RASTER {
                    vec![entry(5, big_queue), entry(6, args)]
                } else {
                    vec![entry(7, big_queue)]
                };
                let first = [Some(entry(0, uniforms)), primitives.map(|p| entry(1, p))].into_iter().flatten();
                let entries = [first.collect(), vec![entry(2, v)], own].concat();
                let label = Some("splat_raster_group");
                device.create_bind_group(&wgpu::BindGroupDescriptor { label, layout, entries: &entries })
            });
        }
        let (Some(small), Some(big)) = (self.groups.get(&(RASTER, *v_id, 0)), self.groups.get(&(RASTER_BIG, *v_id, 0)))
        else {
            return;
        };
        encoder.clear_buffer(v, 0, None);
        encoder.clear_buffer(big_queue, 0, Some(4));
        encoder.clear_buffer(args, 0, Some(12));
        let mut pass = encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("splat/raster"), timestamp_writes: None });
        let threads = u.count.max(1);
        let rows = [threads.min(THREADS_PER_ROW), threads.div_ceil(THREADS_PER_ROW), 1];
        self.raster.dispatch(&mut pass, &[view, small], rows);
        pass.set_pipeline(&self.raster_big.pipeline);
        pass.set_bind_group(0, view, &[]);
        pass.set_bind_group(1, big, &[]);
        pass.dispatch_workgroups_indirect(args, 0);
    }

    /// Records the shading of every pixel into `image` (its view and graph id); `view`,
    /// `primitives` and the lent visibility buffer as for [`Self::record_raster`].
    pub fn record_resolve(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        view: &wgpu::BindGroup,
        primitives: Option<&wgpu::Buffer>,
        (v, v_id): &(wgpu::Buffer, u64),
        image: (&wgpu::TextureView, u64),
    ) {
        let Some(visibility) = &self.visibility else { return };
        let (device, layout, uniforms) = (&self.device, &self.resolve_layout, &self.uniforms);
        let group = self.groups.get_or_create((RESOLVE, *v_id, image.1), || {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("splat_resolve_group"),
                layout,
                entries: &[
                    [Some(entry(0, uniforms)), primitives.map(|p| entry(1, p))].into_iter().flatten().collect(),
                    vec![
                        entry(3, v),
                        wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::TextureView(image.0) },
                    ],
                ]
                .concat(),
            })
        });
        let mut pass = encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("splat/resolve"), timestamp_writes: None });
        let (width, height, _) = visibility.key();
        self.resolve.dispatch(&mut pass, &[view, group], [width, height, 1]);
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_uniform_block_matches_the_wgsl() {
        // As the Poisson discs join it (the shared file alone leaves the technique's part open).
        let source = [
            include_str!("../../shaders/splat_draw.wgsl"),
            include_str!("../../shaders/msaa_samples.wgsl"),
            include_str!("poisson/poisson.wgsl"),
            include_str!("poisson/poisson_raster.wgsl"),
        ]
        .join("\n");
        assert_eq!(crate::gpu::wgsl_struct_size(&source, "Splat"), Some(size_of::<super::SplatUniforms>() as u32));
    }
}
