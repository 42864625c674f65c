//! The GPU layer: adapter and device (headless or for a window surface), shader compilation with
//! naga validation and located errors, texture readback and the final display encode.
//! Knows nothing of scenes or techniques.

mod binding;
mod blit;
mod cache;
mod compute;
mod context;
mod prefix_sum;
mod raster;
mod readback;
mod reaper;
mod shader;
pub mod tuning;
mod watchdog;

pub use binding::{
    BLOCK_USAGE, block_binding, blocks_in_storage, buffer_entry, check_bindings, output_image_entry,
    sampled_texture_entries, storage_entry, texture_entry, uniform_buffer, uniform_entry, wgsl_struct_size,
    with_blocks_bound,
};
pub use blit::{Blit, BlitTarget, DISPLAY_FORMAT, display_target};
pub use cache::{BindGroupCache, DEFAULT_MAX_AGE};
pub use compute::ComputeKernel;
pub use context::{BackendChoice, Gpu, GpuError, GpuOptions, instance_descriptor};
pub use prefix_sum::{PrefixSum, SCAN_BINDINGS, SCAN_BLOCK, ScanTarget};
pub use raster::{GrowableBuffer, RasterDesc, UniformBlock, raster_pipeline};
pub use readback::{ReadbackError, read_buffer, read_texture_bytes, read_texture_rgba8};
pub use reaper::{drop_later, spawn_worker, wait_for_drops};
pub use shader::{
    JoinedSource, ShaderError, compile_wgsl, validate_as_used, validate_module, validate_wgsl, validated,
};
pub use watchdog::{DEFAULT_STALL_TIMEOUT, Stall, Watchdog};
