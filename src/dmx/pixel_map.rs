//! The GPU side of pixel mapping: a pass of the frame that averages each LED's box of an image
//! into 8 bytes, and the read back of only those bytes — blocking for renders, a ring of
//! buffers mapped in the background for the live show.

use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};

use crate::gpu::{ComputeKernel, ReadbackError, ShaderError, read_buffer};
use crate::graph::{FrameGraph, TextureHandle, next_resource_id};

use super::layout::PixelBox;

const SOURCE: &str = include_str!("../../shaders/pixel_map.wgsl");
/// Bytes per LED read back: red, green and blue as 16-bit unorms, and padding.
const PIXEL_BYTES: u64 = 8;
/// Readbacks in flight at once in the live show; a frame that finds none free sends nothing
/// new (the sender repeats the last) rather than wait.
const RING: usize = 3;

// A staging buffer's state, set by the render thread and by wgpu's map callback.
const FREE: u8 = 0;
const COPIED: u8 = 1;
const MAPPING: u8 = 2;
const MAPPED: u8 = 3;
const FAILED: u8 = 4;

/// One staging buffer of the ring.
struct Staging {
    buffer: wgpu::Buffer,
    state: Arc<AtomicU8>,
    frame: u64,
}

/// The pixel-map pass and its readback.
pub struct PixelMap {
    kernel: ComputeKernel,
    layout: wgpu::BindGroupLayout,
    boxes: wgpu::Buffer,
    pixels: wgpu::Buffer,
    pixels_id: u64,
    count: u32,
    ring: Vec<Staging>,
    skipped: u64,
}

impl PixelMap {
    /// Builds the pass for `boxes` (at least one).
    pub fn new(device: &wgpu::Device, boxes: &[PixelBox]) -> Result<Self, ShaderError> {
        use crate::gpu::{storage_entry, texture_entry};
        use wgpu::util::DeviceExt;
        assert!(!boxes.is_empty(), "a patch has at least one pixel");
        let stage = wgpu::ShaderStages::COMPUTE;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("pixel_map"),
            entries: &[texture_entry(0, stage), storage_entry(1, stage, true), storage_entry(2, stage, false)],
        });
        let kernel = ComputeKernel::new(device, "shaders/pixel_map.wgsl", SOURCE, "cs_main", &[&layout])?;
        let boxes_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("pixel_map_boxes"),
            contents: bytemuck::cast_slice(boxes),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let size = boxes.len() as u64 * PIXEL_BYTES;
        let pixels = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("pixel_map_pixels"),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let ring = (0..RING)
            .map(|_| Staging {
                buffer: device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("pixel_map_staging"),
                    size,
                    usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                    mapped_at_creation: false,
                }),
                state: Arc::new(AtomicU8::new(FREE)),
                frame: 0,
            })
            .collect();
        Ok(Self {
            kernel,
            layout,
            boxes: boxes_buffer,
            pixels,
            pixels_id: next_resource_id(),
            count: boxes.len() as u32,
            ring,
            skipped: 0,
        })
    }

    /// Adds this frame's pass: every LED's average of `source`.
    pub fn add_pass<'r>(&'r self, graph: &mut FrameGraph<'r>, source: TextureHandle) {
        let pixels = graph.import_buffer("dmx/pixels", &self.pixels, self.pixels_id);
        graph.add_pass("dmx/pixel_map").read(source).write_buffer(pixels).side_effect().record(move |ctx| {
            let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("pixel_map"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(ctx.view(source)) },
                    crate::gpu::buffer_entry(1, &self.boxes),
                    crate::gpu::buffer_entry(2, ctx.buffer(pixels)),
                ],
            });
            let mut pass = ctx
                .encoder
                .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("pixel_map"), timestamp_writes: None });
            // One workgroup of 64 per LED (the shader's layout).
            self.kernel.dispatch(&mut pass, &[&group], [self.count * 64, 1, 1]);
        });
    }

    /// Moves the LEDs' boxes (the panel dragged a fixture); as many boxes as before.
    pub fn set_boxes(&self, queue: &wgpu::Queue, boxes: &[PixelBox]) {
        debug_assert_eq!(boxes.len(), self.count as usize);
        queue.write_buffer(&self.boxes, 0, bytemuck::cast_slice(boxes));
    }

    /// Reads this frame's values now, waiting for the GPU (renders).
    pub fn read_now(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<Vec<[u16; 3]>, ReadbackError> {
        let bytes = read_buffer(device, queue, &self.pixels, 0, self.pixels.size())?;
        Ok(unpack(&bytes))
    }

    /// Copies frame `frame`'s values into a free staging buffer, after the pass in `encoder`;
    /// none free (the GPU is behind): this frame is not read back.
    pub fn copy_out(&mut self, encoder: &mut wgpu::CommandEncoder, frame: u64) {
        let Some(staging) = self.ring.iter_mut().find(|s| s.state.load(Ordering::Acquire) == FREE) else {
            self.skipped += 1;
            return;
        };
        encoder.copy_buffer_to_buffer(&self.pixels, 0, &staging.buffer, 0, self.pixels.size());
        staging.state.store(COPIED, Ordering::Release);
        staging.frame = frame;
    }

    /// After the submit holding [`PixelMap::copy_out`]'s copy: starts mapping it.
    pub fn after_submit(&mut self) {
        for staging in &self.ring {
            if staging.state.load(Ordering::Acquire) != COPIED {
                continue;
            }
            staging.state.store(MAPPING, Ordering::Release);
            let state = staging.state.clone();
            staging.buffer.slice(..).map_async(wgpu::MapMode::Read, move |result| {
                state.store(if result.is_ok() { MAPPED } else { FAILED }, Ordering::Release);
            });
        }
    }

    /// The newest frame whose values have come back, if any since the last call; never waits.
    pub fn take_newest(&mut self, device: &wgpu::Device) -> Option<(u64, Vec<[u16; 3]>)> {
        let _ = device.poll(wgpu::PollType::Poll);
        let mut newest: Option<(u64, Vec<[u16; 3]>)> = None;
        for staging in &mut self.ring {
            match staging.state.load(Ordering::Acquire) {
                MAPPED => {
                    if newest.as_ref().is_none_or(|(frame, _)| staging.frame > *frame)
                        && let Ok(view) = staging.buffer.slice(..).get_mapped_range()
                    {
                        newest = Some((staging.frame, unpack(&view)));
                    }
                    staging.buffer.unmap();
                    staging.state.store(FREE, Ordering::Release);
                }
                FAILED => staging.state.store(FREE, Ordering::Release),
                _ => {}
            }
        }
        newest
    }

    /// Frames not read back because every staging buffer was busy.
    pub fn skipped(&self) -> u64 {
        self.skipped
    }
}

/// The shader's packing: red | green << 16, blue | 1 << 16.
fn unpack(bytes: &[u8]) -> Vec<[u16; 3]> {
    bytes
        .chunks_exact(PIXEL_BYTES as usize)
        .map(|p| {
            let word = |i: usize| u16::from_le_bytes([p[i], p[i + 1]]);
            [word(0), word(2), word(4)]
        })
        .collect()
}
