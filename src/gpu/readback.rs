//! Copying a texture back to the CPU.

/// Why a frame could not be read back: the device was lost (driver reset, GPU removed, out of
/// memory) while waiting for it. A render ends with this sentence, never a panic.
#[derive(Debug, thiserror::Error)]
#[error(
    "the GPU was lost while reading a frame back ({0}); the render stopped — check the driver (e.g. `dmesg`), free GPU memory, and render again from this frame with --start"
)]
pub struct ReadbackError(pub String);

/// Reads any single-plane colour texture into tightly packed rows of its texel bytes (e.g. 8
/// bytes per texel for `Rgba16Float`). Blocks until the GPU is done; for tests, exports and
/// screenshots, not for the frame loop.
pub fn read_texture_bytes(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
) -> Result<Vec<u8>, ReadbackError> {
    let (width, height) = (texture.width(), texture.height());
    let texel = texture.format().block_copy_size(None).expect("a colour format with a fixed texel size");
    let tight = width * texel;
    let padded = tight.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback_buffer"),
        size: u64::from(padded) * u64::from(height),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder =
        device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("readback_encoder") });
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(height),
            },
        },
        texture.size(),
    );
    queue.submit([encoder.finish()]);
    let mapped = map_read(device, &buffer)?;
    let mut out = Vec::with_capacity((tight * height) as usize);
    for row in mapped.chunks(padded as usize) {
        out.extend_from_slice(&row[..tight as usize]);
    }
    Ok(out)
}

/// Reads `size` bytes of `buffer` from `offset` (it needs COPY_SRC). Blocks until the GPU is
/// done; for tests and tools.
pub fn read_buffer(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
    offset: u64,
    size: u64,
) -> Result<Vec<u8>, ReadbackError> {
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback_staging"),
        size,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("readback_copy") });
    encoder.copy_buffer_to_buffer(buffer, offset, &staging, 0, size);
    queue.submit([encoder.finish()]);
    Ok(map_read(device, &staging)?.to_vec())
}

/// Maps a MAP_READ buffer after the submitted work that fills it, or says the device is lost.
fn map_read(device: &wgpu::Device, buffer: &wgpu::Buffer) -> Result<wgpu::BufferView, ReadbackError> {
    let slice = buffer.slice(..);
    let (sender, mapped) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| drop(sender.send(r)));
    device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| ReadbackError(e.to_string()))?;
    match mapped.try_recv() {
        Ok(Ok(())) => {}
        Ok(Err(e)) => return Err(ReadbackError(e.to_string())),
        Err(_) => return Err(ReadbackError("the mapping never completed".into())),
    }
    slice.get_mapped_range().map_err(|e| ReadbackError(e.to_string()))
}

/// Reads an `Rgba8Unorm` (or `Bgra8Unorm`, returned as stored) texture into tightly packed rows.
pub fn read_texture_rgba8(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
) -> Result<Vec<u8>, ReadbackError> {
    debug_assert_eq!(texture.format().block_copy_size(None), Some(4));
    read_texture_bytes(device, queue, texture)
}
