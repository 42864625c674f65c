//! The surface drawn in compute (`tessellation_raster.wgsl`): a visibility buffer of
//! one 64-bit word per sample (inverted depth, triangle), filled by one thread per refined
//! triangle with `atomicMax` and shaded once per pixel and triangle. On GPUs whose raster path is
//! narrow (the H100/H200, where clearing and resolving a 4× multisampled 4K target alone takes
//! ~6 ms) this replaces the draw; the pipeline draw stays for adapters without 64-bit atomics.

use crate::gpu::{BindGroupCache, ComputeKernel, JoinedSource, ShaderError, storage_entry as storage};

use super::FORMAT;
use crate::graph::{BufferHandle, FrameGraph};
use crate::techniques::visibility::VisibilityBuffer;

/// Features the compute draw needs.
pub const FEATURES: wgpu::Features = wgpu::Features::SHADER_INT64.union(wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX);

/// Large triangles the queue holds per frame; more are covered by their own thread.
const BIG_CAPACITY: u32 = 16384;
/// Bytes of one queued triangle (`BigTriangle`).
const BIG_TRIANGLE_BYTES: u64 = 48;
/// Bytes of one triangle's kept corners (six vec4).
const CORNER_BYTES: u64 = 96;
/// The most memory kept corners may take (grid 10 at level 64 everywhere: 79 MB; grid 36: 1 GiB);
/// beyond it the resolve evaluates corners again.
const CORNER_BUDGET: u64 = 1 << 30;

/// `Raster` in the shader.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct RasterUniforms {
    width: u32,
    height: u32,
    samples: u32,
    big_capacity: u32,
    cached: u32,
    _pad: [u32; 3],
}

/// Room for every triangle's corners at one grid size (or a stand-in when over the budget).
struct Corners {
    grid: u32,
    buffer: wgpu::Buffer,
    cached: bool,
}

/// The kernels and buffers of the compute draw.
pub struct ComputeRaster {
    device: wgpu::Device,
    raster: ComputeKernel,
    raster_big: ComputeKernel,
    resolve: ComputeKernel,
    raster_layout: wgpu::BindGroupLayout,
    big_layout: wgpu::BindGroupLayout,
    resolve_layout: wgpu::BindGroupLayout,
    uniforms: wgpu::Buffer,
    big_triangles: wgpu::Buffer,
    /// The queue's dispatch arguments and length (x, y, z, count).
    big_args: wgpu::Buffer,
    visibility: Option<VisibilityBuffer>,
    corners: Option<Corners>,
    /// Group 2 of the raster kernels (with and without the queue's arguments, which the second
    /// reads as its dispatch), with the id of the visibility buffer they bind.
    raster_groups: Option<(u64, [wgpu::BindGroup; 2])>,
    /// Group 2 of the resolve by (visibility buffer id, output texture id); cleared with the
    /// corners.
    resolve_groups: BindGroupCache<(u64, u64)>,
}

/// What one frame's compute draw binds.
pub struct DrawBindings<'a> {
    /// Group 0: the tessellation uniforms.
    pub uniforms: &'a wgpu::BindGroup,
    /// Group 1: the height map and the refined mesh's tables.
    pub mesh: &'a wgpu::BindGroup,
    /// The draw arguments, with the raster dispatch at byte 20.
    pub args: &'a wgpu::Buffer,
}

impl ComputeRaster {
    /// Builds the kernels from `tessellation.wgsl` joined with `tessellation_raster.wgsl`;
    /// `layouts` are groups 0 and 1 as the pipeline draw binds them.
    pub fn new(
        device: &wgpu::Device,
        shader: &JoinedSource,
        layouts: [&wgpu::BindGroupLayout; 2],
    ) -> Result<Self, ShaderError> {
        let compute = wgpu::ShaderStages::COMPUTE;
        // Group 2 of each kernel: the raster uniforms at binding 0, then `entries`.
        let group_layout = |label: &str, entries: &[wgpu::BindGroupLayoutEntry]| {
            let uniforms = crate::gpu::uniform_entry::<RasterUniforms>(0, compute);
            let entries: Vec<_> = std::iter::once(uniforms).chain(entries.iter().copied()).collect();
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries: &entries })
        };
        let raster_layout = group_layout(
            "tessellation_raster_layout",
            &[
                storage(1, compute, false),
                storage(2, compute, false),
                storage(3, compute, false),
                storage(6, compute, false),
            ],
        );
        // The queue's kernel reads big_args as its dispatch, so it may not bind them too.
        let big_layout =
            group_layout("tessellation_raster_big_layout", &[storage(1, compute, false), storage(2, compute, false)]);
        let output = crate::gpu::output_image_entry(5, FORMAT);
        let resolve_layout = group_layout(
            "tessellation_resolve_layout",
            &[storage(4, compute, true), storage(7, compute, true), output],
        );
        let kernel = |entry, group: &wgpu::BindGroupLayout| {
            ComputeKernel::new(device, shader.origin(), &shader.source, entry, &[layouts[0], layouts[1], group])
                .map_err(|e| shader.relocate(e))
        };
        let raster = kernel("raster", &raster_layout)?;
        let raster_big = kernel("raster_big", &big_layout)?;
        let resolve = kernel("resolve", &resolve_layout)?;
        let big_triangles = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("tessellation_big_triangles"),
            size: u64::from(BIG_CAPACITY) * BIG_TRIANGLE_BYTES,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        // (x, y, z, count): y and z stay 1; x and the count are zeroed before each frame.
        let big_args = wgpu::util::DeviceExt::create_buffer_init(
            device,
            &wgpu::util::BufferInitDescriptor {
                label: Some("tessellation_big_args"),
                contents: bytemuck::cast_slice(&[0u32, 1, 1, 0]),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
            },
        );
        Ok(Self {
            device: device.clone(),
            raster,
            raster_big,
            resolve,
            raster_layout,
            big_layout,
            resolve_layout,
            uniforms: crate::gpu::uniform_buffer::<RasterUniforms>(device, "tessellation_raster_uniforms"),
            big_triangles,
            big_args,
            visibility: None,
            corners: None,
            raster_groups: None,
            resolve_groups: BindGroupCache::default(),
        })
    }

    /// Readies the visibility buffer for `size` × `samples` and the corners for `grid`, and
    /// writes the uniforms; false when the visibility buffer would exceed the device's limits
    /// (the caller draws with the pipeline then).
    pub fn prepare(&mut self, queue: &wgpu::Queue, size: (u32, u32), samples: u32, grid: u32) -> bool {
        if !VisibilityBuffer::ensure(&mut self.visibility, &self.device, size, samples) {
            return false;
        }
        let limits = self.device.limits();
        let largest = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        if self.corners.as_ref().is_none_or(|c| c.grid != grid) {
            // At most level 64 (4,096 triangles) in each of the 2 grid² patches.
            let bytes = 2 * u64::from(grid * grid) * 4096 * CORNER_BYTES;
            let cached = bytes <= CORNER_BUDGET.min(largest);
            let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("tessellation_corners"),
                size: if cached { bytes } else { CORNER_BYTES },
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            });
            self.corners = Some(Corners { grid, buffer, cached });
            self.forget_groups();
        }
        self.resolve_groups.begin_frame();
        let cached = u32::from(self.corners.as_ref().is_some_and(|c| c.cached));
        let u =
            RasterUniforms { width: size.0, height: size.1, samples, big_capacity: BIG_CAPACITY, cached, _pad: [0; 3] };
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&u));
        true
    }

    /// Drops the bind groups: they bind a buffer just replaced.
    fn forget_groups(&mut self) {
        self.raster_groups = None;
        self.resolve_groups = BindGroupCache::default();
    }

    /// Group 2 of `raster` and of `raster_big` (which reads the queue's arguments as its
    /// dispatch, so it may not bind them too).
    fn make_raster_groups(&self, visibility: &wgpu::Buffer, corners: &wgpu::Buffer) -> [wgpu::BindGroup; 2] {
        let group = |layout, first_only: Option<&wgpu::Buffer>| {
            let mut entries = vec![
                wgpu::BindGroupEntry { binding: 0, resource: self.uniforms.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: visibility.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: self.big_triangles.as_entire_binding() },
            ];
            if let Some(args) = first_only {
                entries.push(wgpu::BindGroupEntry { binding: 3, resource: args.as_entire_binding() });
                entries.push(wgpu::BindGroupEntry { binding: 6, resource: corners.as_entire_binding() });
            }
            self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("tessellation_raster_group"),
                layout,
                entries: &entries,
            })
        };
        [group(&self.raster_layout, Some(&self.big_args)), group(&self.big_layout, None)]
    }

    /// Declares this frame's visibility buffer in `graph` as `name` (after a successful
    /// [`Self::prepare`]): the raster writes it, the resolve reads it.
    pub fn declare_visibility(&self, graph: &mut FrameGraph<'_>, name: &str) -> BufferHandle {
        self.visibility.expect("prepared").declare(graph, name)
    }

    /// Records the coverage into the visibility buffer the graph lent (with its id): clear it,
    /// then cover every refined triangle (the dispatch the scan wrote) and the queued large ones.
    pub fn record_raster(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        b: &DrawBindings<'_>,
        (visibility, v_id): &(wgpu::Buffer, u64),
    ) {
        let Some(corners) = &self.corners else { return };
        if self.raster_groups.as_ref().is_none_or(|(id, _)| id != v_id) {
            self.raster_groups = Some((*v_id, self.make_raster_groups(visibility, &corners.buffer)));
        }
        let (_, groups) = self.raster_groups.as_ref().expect("made above");
        encoder.clear_buffer(visibility, 0, None);
        encoder.clear_buffer(&self.big_args, 0, Some(4));
        encoder.clear_buffer(&self.big_args, 12, Some(4));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("tessellation/raster"),
            timestamp_writes: None,
        });
        pass.set_bind_group(0, b.uniforms, &[]);
        pass.set_bind_group(1, b.mesh, &[]);
        pass.set_bind_group(2, &groups[0], &[]);
        pass.set_pipeline(&self.raster.pipeline);
        pass.dispatch_workgroups_indirect(b.args, 20);
        pass.set_bind_group(2, &groups[1], &[]);
        pass.set_pipeline(&self.raster_big.pipeline);
        pass.dispatch_workgroups_indirect(&self.big_args, 0);
    }

    /// Records the shading from the lent visibility buffer: each pixel's distinct triangles
    /// shaded and averaged into `image`.
    pub fn record_resolve(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        b: &DrawBindings<'_>,
        (v, v_id): &(wgpu::Buffer, u64),
        image: (&wgpu::TextureView, u64),
    ) {
        let (Some(visibility), Some(corners)) = (&self.visibility, &self.corners) else { return };
        let (device, uniforms) = (&self.device, &self.uniforms);
        let entry = |binding, resource| wgpu::BindGroupEntry { binding, resource };
        let group = self.resolve_groups.get_or_create((*v_id, image.1), || {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("tessellation_resolve_group"),
                layout: &self.resolve_layout,
                entries: &[
                    entry(0, uniforms.as_entire_binding()),
                    entry(4, v.as_entire_binding()),
                    entry(7, corners.buffer.as_entire_binding()),
                    entry(5, wgpu::BindingResource::TextureView(image.0)),
                ],
            })
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("tessellation/resolve"),
            timestamp_writes: None,
        });
        let (width, height, _) = visibility.key();
        self.resolve.dispatch(&mut pass, &[b.uniforms, b.mesh, group], [width, height, 1]);
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_uniform_block_matches_the_wgsl_struct() {
        let source = [
            include_str!("../../../shaders/msaa_samples.wgsl"),
            include_str!("tessellation.wgsl"),
            include_str!("tessellation_raster.wgsl"),
        ]
        .join("\n");
        assert_eq!(crate::gpu::wgsl_struct_size(&source, "Raster"), Some(size_of::<super::RasterUniforms>() as u32));
        assert_eq!(crate::gpu::wgsl_struct_size(&source, "BigTriangle"), Some(super::BIG_TRIANGLE_BYTES as u32));
    }
}
