//! The transient pools: textures and storage buffers persist across frames and are handed out
//! again within a frame once their previous user's last reader has run (wgpu has no memory
//! aliasing; this reuse is how the graph saves memory).

use super::builder::ResolvedTexture;
use super::resource::next_resource_id;

/// What makes two transient textures interchangeable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PoolKey {
    /// Size in texels.
    pub size: (u32, u32),
    /// Texel format.
    pub format: wgpu::TextureFormat,
    /// Usage flags the user needs.
    pub usage: wgpu::TextureUsages,
    /// Array layers (`None`: plain 2-D).
    pub layers: Option<u32>,
    /// Samples per texel.
    pub samples: u32,
}

struct Entry {
    key: PoolKey,
    resolved: ResolvedTexture,
    in_use: bool,
    last_frame: u64,
}

/// Frames a pooled texture may sit unused before it is freed (after a resize, say).
const EVICT_AFTER_FRAMES: u64 = 120;

/// Owns the GPU textures behind transient graph resources.
#[derive(Default)]
pub struct TexturePool {
    entries: Vec<Entry>,
    frame: u64,
    created_this_frame: usize,
    /// Keep idle textures (a show: a clip that comes back finds its textures).
    hold: bool,
}

impl TexturePool {
    /// An empty pool.
    pub fn new() -> Self {
        Self::default()
    }

    /// A free texture matching `key` (same size and format, at least the usage), or a new one.
    pub(crate) fn acquire(&mut self, device: &wgpu::Device, key: PoolKey) -> (usize, ResolvedTexture) {
        let found = self.entries.iter().position(|e| {
            !e.in_use
                && e.key.size == key.size
                && e.key.format == key.format
                && e.key.layers == key.layers
                && e.key.samples == key.samples
                && e.key.usage.contains(key.usage)
        });
        let index = found.unwrap_or_else(|| {
            self.created_this_frame += 1;
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some("graph_transient"),
                size: wgpu::Extent3d {
                    width: key.size.0,
                    height: key.size.1,
                    depth_or_array_layers: key.layers.unwrap_or(1),
                },
                mip_level_count: 1,
                sample_count: key.samples,
                dimension: wgpu::TextureDimension::D2,
                format: key.format,
                usage: key.usage,
                view_formats: &[],
            });
            let dimension = key.layers.map(|_| wgpu::TextureViewDimension::D2Array);
            let view = texture.create_view(&wgpu::TextureViewDescriptor { dimension, ..Default::default() });
            let resolved = ResolvedTexture { texture, view, id: next_resource_id() };
            self.entries.push(Entry { key, resolved, in_use: false, last_frame: self.frame });
            self.entries.len() - 1
        });
        let entry = &mut self.entries[index];
        entry.in_use = true;
        entry.last_frame = self.frame;
        (index, entry.resolved.clone())
    }

    /// Returns a texture for later passes of this frame (its last reader has run).
    pub(crate) fn release(&mut self, index: usize) {
        self.entries[index].in_use = false;
    }

    /// Ends a frame: everything becomes free; textures idle for long are dropped.
    pub(crate) fn end_frame(&mut self) {
        end_frame(&mut self.entries, &mut self.frame, self.hold);
        self.created_this_frame = 0;
    }

    /// Whether idle textures stay (`true`: a show, whose clips come and go) or are dropped after
    /// two seconds unused (a scene: after a resize, the old sizes go).
    pub fn set_hold(&mut self, hold: bool) {
        self.hold = hold;
    }

    /// Textures created during the current frame (0 in a steady state).
    pub fn created_this_frame(&self) -> usize {
        self.created_this_frame
    }

    /// Textures the pool holds.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether the pool holds no texture.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Bytes of all pooled textures.
    pub fn bytes(&self) -> u64 {
        self.entries
            .iter()
            .map(|e| {
                texture_bytes(e.key.size, e.key.format)
                    * u64::from(e.key.layers.unwrap_or(1))
                    * u64::from(e.key.samples)
            })
            .sum()
    }
}

struct PooledBuffer {
    size: u64,
    buffer: wgpu::Buffer,
    id: u64,
    in_use: bool,
    last_frame: u64,
}

/// Owns the GPU buffers behind transient graph buffers (the compute draws' visibility buffers,
/// scratch), kept and dropped as the texture pool keeps its textures.
#[derive(Default)]
pub struct BufferPool {
    entries: Vec<PooledBuffer>,
    frame: u64,
    hold: bool,
}

impl BufferPool {
    /// A free buffer of exactly `size` bytes, or a new one; its index and id.
    pub(crate) fn acquire(&mut self, device: &wgpu::Device, size: u64) -> (usize, wgpu::Buffer, u64) {
        let index = self.entries.iter().position(|e| !e.in_use && e.size == size).unwrap_or_else(|| {
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("graph_transient_buffer"),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let id = next_resource_id();
            self.entries.push(PooledBuffer { size, buffer, id, in_use: false, last_frame: self.frame });
            self.entries.len() - 1
        });
        let entry = &mut self.entries[index];
        entry.in_use = true;
        entry.last_frame = self.frame;
        (index, entry.buffer.clone(), entry.id)
    }

    /// Returns a buffer for later passes of this frame (its last reader has run).
    pub(crate) fn release(&mut self, index: usize) {
        self.entries[index].in_use = false;
    }

    /// Ends a frame as [`TexturePool::end_frame`] does.
    pub(crate) fn end_frame(&mut self) {
        end_frame(&mut self.entries, &mut self.frame, self.hold);
    }

    /// Whether idle buffers stay, as [`TexturePool::set_hold`].
    pub fn set_hold(&mut self, hold: bool) {
        self.hold = hold;
    }

    /// Bytes of all pooled buffers.
    pub fn bytes(&self) -> u64 {
        self.entries.iter().map(|e| e.size).sum()
    }
}

/// What a pool's entry tells of its use.
trait Lendable {
    /// The last frame it was lent in.
    fn last_frame(&self) -> u64;
    /// Makes it free for the next frame.
    fn free(&mut self);
}

impl Lendable for Entry {
    fn last_frame(&self) -> u64 {
        self.last_frame
    }

    fn free(&mut self) {
        self.in_use = false;
    }
}

impl Lendable for PooledBuffer {
    fn last_frame(&self) -> u64 {
        self.last_frame
    }

    fn free(&mut self) {
        self.in_use = false;
    }
}

/// Ends a pool's `frame`: every entry free, those idle for [`EVICT_AFTER_FRAMES`] dropped unless
/// the pool `hold`s them.
fn end_frame<E: Lendable>(entries: &mut Vec<E>, frame: &mut u64, hold: bool) {
    if !hold {
        let now = *frame;
        entries.retain(|e| now.saturating_sub(e.last_frame()) < EVICT_AFTER_FRAMES);
    }
    entries.iter_mut().for_each(Lendable::free);
    *frame += 1;
}

/// Bytes a single-mip 2-D texture occupies.
pub fn texture_bytes(size: (u32, u32), format: wgpu::TextureFormat) -> u64 {
    u64::from(format.block_copy_size(None).unwrap_or(4)) * u64::from(size.0) * u64::from(size.1)
}
