//! Copying a texture back to the CPU.

/// Reads any single-plane colour texture into tightly packed rows of its texel bytes (e.g. 8
/// bytes per texel for `Rgba16Float`). Blocks until the GPU is done; for tests, exports and
/// screenshots, not for the frame loop.
pub fn read_texture_bytes(device: &wgpu::Device, queue: &wgpu::Queue, texture: &wgpu::Texture) -> Vec<u8> {
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
    let slice = buffer.slice(..);
    slice.map_async(wgpu::MapMode::Read, |r| r.expect("readback buffer mapping failed"));
    device.poll(wgpu::PollType::wait_indefinitely()).expect("device lost during readback");
    let mapped = slice.get_mapped_range().expect("readback range is mapped");
    let mut out = Vec::with_capacity((tight * height) as usize);
    for row in mapped.chunks(padded as usize) {
        out.extend_from_slice(&row[..tight as usize]);
    }
    out
}

/// Reads an `Rgba8Unorm` (or `Bgra8Unorm`, returned as stored) texture into tightly packed rows.
pub fn read_texture_rgba8(device: &wgpu::Device, queue: &wgpu::Queue, texture: &wgpu::Texture) -> Vec<u8> {
    debug_assert_eq!(texture.format().block_copy_size(None), Some(4));
    read_texture_bytes(device, queue, texture)
}
