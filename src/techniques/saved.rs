//! A node's GPU state in a checkpoint: whole buffers and 2D textures, read back between frames
//! (the GPU idle) and written back into a freshly created node before its first step.

use crate::checkpoint::{CheckpointError, NodeState};
use crate::gpu::Gpu;

/// Saves all of `buffer` (it needs `COPY_SRC`) as blob `name`.
pub fn save_buffer(gpu: &Gpu, state: &mut NodeState, name: &str, buffer: &wgpu::Buffer) -> Result<(), CheckpointError> {
    let bytes = crate::gpu::read_buffer(&gpu.device, &gpu.queue, buffer, 0, buffer.size())
        .map_err(|e| state.error(name, format!("could not be read back: {e}")))?;
    state.put(name, bytes);
    Ok(())
}

/// Writes blob `name` back into `buffer`, which must be its size.
pub fn load_buffer(gpu: &Gpu, state: &NodeState, name: &str, buffer: &wgpu::Buffer) -> Result<(), CheckpointError> {
    gpu.queue.write_buffer(buffer, 0, state.get_exact(name, buffer.size())?);
    Ok(())
}

/// Saves mip 0 of a 2D `texture` (it needs `COPY_SRC`) as blob `name`, its rows packed.
pub fn save_texture(
    gpu: &Gpu,
    state: &mut NodeState,
    name: &str,
    texture: &wgpu::Texture,
) -> Result<(), CheckpointError> {
    let bytes = crate::gpu::read_texture_bytes(&gpu.device, &gpu.queue, texture)
        .map_err(|e| state.error(name, format!("could not be read back: {e}")))?;
    state.put(name, bytes);
    Ok(())
}

/// Writes blob `name` back into mip 0 of a 2D `texture` of the size it was saved from.
pub fn load_texture(gpu: &Gpu, state: &NodeState, name: &str, texture: &wgpu::Texture) -> Result<(), CheckpointError> {
    let texel = texture.format().block_copy_size(None).unwrap_or(4);
    let (width, height) = (texture.width(), texture.height());
    let bytes = state.get_exact(name, u64::from(width) * u64::from(height) * u64::from(texel))?;
    gpu.queue.write_texture(
        texture.as_image_copy(),
        bytes,
        wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(width * texel), rows_per_image: Some(height) },
        wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
    );
    Ok(())
}
