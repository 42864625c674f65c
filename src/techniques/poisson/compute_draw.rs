//! The discs and spheres drawn in compute (`poisson_raster.wgsl`): each sample's disc found per
//! sample position into a visibility buffer, then shaded once per pixel and disc. Where the
//! raster path is narrow (the H100/H200) this replaces the instanced quads; the pipeline stays
//! for adapters without 64-bit atomics.

use crate::gpu::{
    BindGroupCache, ComputeKernel, JoinedSource, ShaderError, buffer_entry as entry, storage_entry as storage,
};
use crate::techniques::visibility::VisibilityBuffer;

use super::{FORMAT, PoissonUniforms};

/// Features the compute draw needs.
pub const FEATURES: wgpu::Features = wgpu::Features::SHADER_INT64.union(wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX);

/// `Raster` in the shader.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct RasterUniforms {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Discs drawn.
    pub count: u32,
    _pad: u32,
}

impl RasterUniforms {
    /// `count` discs into a `size` image.
    pub fn new(size: (u32, u32), count: u32) -> Self {
        Self { width: size.0, height: size.1, count, _pad: 0 }
    }
}

/// Threads per row of the raster's dispatch (the most workgroups one dimension may hold, of 64).
const THREADS_PER_ROW: u32 = 65535 * 64;

/// The kernels, uniforms and visibility buffer of the compute draw.
pub struct ComputeDraw {
    device: wgpu::Device,
    raster: ComputeKernel,
    raster_big: ComputeKernel,
    resolve: ComputeKernel,
    raster_layout: wgpu::BindGroupLayout,
    big_layout: wgpu::BindGroupLayout,
    resolve_layout: wgpu::BindGroupLayout,
    /// Group 0: the node's uniform block, seen from compute.
    view_group: wgpu::BindGroup,
    uniforms: wgpu::Buffer,
    visibility: Option<VisibilityBuffer>,
    /// The large discs' queue (its length, then one slot per disc), by its capacity in discs.
    big_queue: Option<(u32, wgpu::Buffer)>,
    /// The large discs' dispatch (x, y, 1), written by the raster.
    big_args: wgpu::Buffer,
    /// Group 1 of the raster (key 0), of the large discs' kernel (key 1) and of the resolve
    /// (key: the output texture id); dropped when a buffer they bind is made anew.
    groups: BindGroupCache<u64>,
}

impl ComputeDraw {
    /// Builds the kernels from `poisson_raster.wgsl` (joined after `poisson.wgsl`); `block` is
    /// the node's uniform buffer (group 0).
    pub fn new(device: &wgpu::Device, shader: &JoinedSource, block: &wgpu::Buffer) -> Result<Self, ShaderError> {
        let compute = wgpu::ShaderStages::COMPUTE;
        let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries })
        };
        let view_layout = layout("poisson_compute_view", &[crate::gpu::uniform_entry::<PoissonUniforms>(0, compute)]);
        let uniforms_entry = crate::gpu::uniform_entry::<RasterUniforms>(0, compute);
        let (discs, visibility) = (storage(1, compute, true), storage(2, compute, false));
        let queue = storage(5, compute, false);
        let raster_layout =
            layout("poisson_raster_layout", &[uniforms_entry, discs, visibility, queue, storage(6, compute, false)]);
        // The large discs' kernel reads big_args as its dispatch, so it may not bind them too.
        let big_layout = layout("poisson_big_layout", &[uniforms_entry, discs, visibility, storage(7, compute, true)]);
        let output = crate::gpu::output_image_entry(4, FORMAT);
        let resolve_layout = layout(
            "poisson_resolve_layout",
            &[uniforms_entry, storage(1, compute, true), storage(3, compute, true), output],
        );
        let kernel = |entry, group: &wgpu::BindGroupLayout| {
            ComputeKernel::new(device, shader.origin(), &shader.source, entry, &[&view_layout, group])
                .map_err(|e| shader.relocate(e))
        };
        let view_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("poisson_compute_view"),
            layout: &view_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: block.as_entire_binding() }],
        });
        Ok(Self {
            device: device.clone(),
            raster: kernel("raster", &raster_layout)?,
            raster_big: kernel("raster_big", &big_layout)?,
            resolve: kernel("resolve", &resolve_layout)?,
            raster_layout,
            big_layout,
            resolve_layout,
            view_group,
            uniforms: crate::gpu::uniform_buffer::<RasterUniforms>(device, "poisson_raster_uniforms"),
            visibility: None,
            big_queue: None,
            big_args: wgpu::util::DeviceExt::create_buffer_init(
                device,
                &wgpu::util::BufferInitDescriptor {
                    label: Some("poisson_big_args"),
                    contents: bytemuck::cast_slice(&[0u32, 0, 1]),
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
                },
            ),
            groups: BindGroupCache::default(),
        })
    }

    /// Readies the visibility buffer for a `size` image of `samples` per pixel and the queue
    /// for `count` discs; `discs_made` says the disc buffer was made anew since the last frame.
    /// False when the buffer would exceed the device's limits (the caller draws with the
    /// pipeline).
    pub fn prepare(&mut self, size: (u32, u32), samples: u32, count: u32, discs_made: bool) -> bool {
        let made = VisibilityBuffer::ensure(&mut self.visibility, &self.device, "poisson_visibility", size, samples);
        let Some(mut made) = made else { return false };
        if self.big_queue.as_ref().is_none_or(|(capacity, _)| *capacity < count) {
            // Room to grow into, so that a growing set does not make a queue every frame.
            let capacity = count.max(1024).next_power_of_two();
            let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("poisson_big_queue"),
                size: (u64::from(capacity) + 1) * 4,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            self.big_queue = Some((capacity, buffer));
            made = true;
        }
        if made || discs_made {
            self.groups = BindGroupCache::default();
        }
        self.groups.begin_frame();
        true
    }

    /// The visibility buffer and its graph id (after a successful [`Self::prepare`]).
    pub fn visibility(&self) -> Option<(&wgpu::Buffer, u64)> {
        self.visibility.as_ref().map(|v| (&v.buffer, v.id))
    }

    /// Records the coverage of `u.count` discs from `discs`: the visibility buffer cleared, then
    /// one workgroup per disc.
    pub fn record_raster(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        queue: &wgpu::Queue,
        u: &RasterUniforms,
        discs: &wgpu::Buffer,
    ) {
        let (Some(visibility), Some((_, big_queue))) = (&self.visibility, &self.big_queue) else { return };
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(u));
        let (device, uniforms, args) = (&self.device, &self.uniforms, &self.big_args);
        let v = &visibility.buffer;
        for (key, layout) in [(0, &self.raster_layout), (1, &self.big_layout)] {
            self.groups.get_or_create(key, || {
                let own = if key == 0 { vec![entry(5, big_queue), entry(6, args)] } else { vec![entry(7, big_queue)] };
                let entries = [vec![entry(0, uniforms), entry(1, discs), entry(2, v)], own].concat();
                let label = Some("poisson_raster_group");
                device.create_bind_group(&wgpu::BindGroupDescriptor { label, layout, entries: &entries })
            });
        }
        let (Some(small), Some(big)) = (self.groups.get(&0), self.groups.get(&1)) else { return };
        encoder.clear_buffer(v, 0, None);
        encoder.clear_buffer(big_queue, 0, Some(4));
        encoder.clear_buffer(args, 0, Some(8));
        let mut pass = encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("poisson/raster"), timestamp_writes: None });
        let threads = u.count.max(1);
        self.raster.dispatch(
            &mut pass,
            &[&self.view_group, small],
            [threads.min(THREADS_PER_ROW), threads.div_ceil(THREADS_PER_ROW), 1],
        );
        pass.set_pipeline(&self.raster_big.pipeline);
        pass.set_bind_group(0, &self.view_group, &[]);
        pass.set_bind_group(1, big, &[]);
        pass.dispatch_workgroups_indirect(args, 0);
    }

    /// Records the shading of every pixel into `image` (its view and graph id).
    pub fn record_resolve(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        discs: &wgpu::Buffer,
        image: (&wgpu::TextureView, u64),
    ) {
        let Some(visibility) = &self.visibility else { return };
        let (device, layout, uniforms) = (&self.device, &self.resolve_layout, &self.uniforms);
        // Texture ids are never 0 (the raster's key).
        let group = self.groups.get_or_create(image.1, || {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("poisson_resolve_group"),
                layout,
                entries: &[
                    entry(0, uniforms),
                    entry(1, discs),
                    entry(3, &visibility.buffer),
                    wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::TextureView(image.0) },
                ],
            })
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("poisson/resolve"),
            timestamp_writes: None,
        });
        let (width, height, _) = visibility.key();
        self.resolve.dispatch(&mut pass, &[&self.view_group, group], [width, height, 1]);
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_uniform_block_matches_the_wgsl() {
        let source = [
            include_str!("../../../shaders/msaa_samples.wgsl"),
            include_str!("poisson.wgsl"),
            include_str!("poisson_raster.wgsl"),
        ]
        .join("\n");
        assert_eq!(crate::gpu::wgsl_struct_size(&source, "Raster"), Some(size_of::<super::RasterUniforms>() as u32));
    }
}
