//! A GPU exclusive prefix sum over a u32 buffer, in place (`shaders/prefix_sum.wgsl`): the
//! primitive behind deterministic compaction (a flagged item's slot is its rank in index order,
//! never the order atomics happened to return) and counting sorts.

use super::{ComputeKernel, ShaderError, storage_entry, uniform_entry};

/// Values one `scan_blocks` workgroup scans (the shader's `BLOCK`).
pub const SCAN_BLOCK: u32 = 1024;

/// The shader's bindings, for [`super::check_bindings`].
pub const SCAN_BINDINGS: [(&str, u32); 3] = [("info", 0), ("data", 1), ("sums", 2)];

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ScanInfo {
    len: u32,
    blocks: u32,
    _pad: [u32; 2],
}

/// The three scan pipelines and their layout.
pub struct PrefixSum {
    blocks: ComputeKernel,
    sums: ComputeKernel,
    add: ComputeKernel,
    layout: wgpu::BindGroupLayout,
}

/// One buffer prepared for scanning: its length, block sums and bind group.
pub struct ScanTarget {
    len: u32,
    blocks: u32,
    group: wgpu::BindGroup,
}

impl PrefixSum {
    /// Builds the pipelines from the prefix-sum shader's `origin` and `source`.
    pub fn new(device: &wgpu::Device, origin: &str, source: &str) -> Result<Self, ShaderError> {
        let compute = wgpu::ShaderStages::COMPUTE;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("prefix_sum_layout"),
            entries: &[
                uniform_entry::<ScanInfo>(0, compute),
                storage_entry(1, compute, false),
                storage_entry(2, compute, false),
            ],
        });
        let kernel = |entry| ComputeKernel::new(device, origin, source, entry, &[&layout]);
        Ok(Self { blocks: kernel("scan_blocks")?, sums: kernel("scan_sums")?, add: kernel("scan_add")?, layout })
    }

    /// Prepares `data` (at least `len + 1` u32s: the total lands at `data[len]`) for scanning.
    pub fn target(&self, device: &wgpu::Device, data: &wgpu::Buffer, len: u32) -> ScanTarget {
        use wgpu::util::DeviceExt;
        let blocks = len.div_ceil(SCAN_BLOCK).max(1);
        let info = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("prefix_sum_info"),
            contents: bytemuck::bytes_of(&ScanInfo { len, blocks, _pad: [0; 2] }),
            usage: super::BLOCK_USAGE,
        });
        let sums = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("prefix_sum_block_sums"),
            size: u64::from(blocks + 1) * 4,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("prefix_sum_group"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: info.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: data.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: sums.as_entire_binding() },
            ],
        });
        ScanTarget { len, blocks, group }
    }

    /// Records the scan of `target` into `pass`.
    pub fn record(&self, pass: &mut wgpu::ComputePass<'_>, target: &ScanTarget) {
        let wg = self.blocks.workgroup_size[0];
        self.blocks.dispatch(pass, &[&target.group], [target.blocks * wg, 1, 1]);
        self.sums.dispatch(pass, &[&target.group], [1, 1, 1]);
        self.add.dispatch(pass, &[&target.group], [target.len.max(1), 1, 1]);
    }
}
