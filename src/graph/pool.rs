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

/// Frames a pooled texture or buffer may sit unused before it is freed (after a resize, say).
const EVICT_AFTER_FRAMES: u64 = 120;

/// An item of a pool, with its use.
struct Loan<T> {
    item: T,
    /// Lent in this frame and not yet given back.
    in_use: bool,
    /// The last frame it was lent in.
    last_frame: u64,
}

/// The lending both pools share: a free item that fits, or a new one; given back once its last
/// reader has run; dropped after [`EVICT_AFTER_FRAMES`] idle unless the pool holds its items.
struct Lender<T> {
    loans: Vec<Loan<T>>,
    frame: u64,
    hold: bool,
}

impl<T> Default for Lender<T> {
    fn default() -> Self {
        Self { loans: Vec::new(), frame: 0, hold: false }
    }
}

impl<T> Lender<T> {
    /// Lends a free item that `fits`, or one `make` makes; its index, the item, and whether it
    /// was made.
    fn lend(&mut self, fits: impl Fn(&T) -> bool, make: impl FnOnce() -> T) -> (usize, &T, bool) {
        let found = self.loans.iter().position(|l| !l.in_use && fits(&l.item));
        let index = found.unwrap_or_else(|| {
            self.loans.push(Loan { item: make(), in_use: false, last_frame: self.frame });
            self.loans.len() - 1
        });
        let loan = &mut self.loans[index];
        loan.in_use = true;
        loan.last_frame = self.frame;
        (index, &loan.item, found.is_none())
    }

    fn give_back(&mut self, index: usize) {
        self.loans[index].in_use = false;
    }

    /// Ends a frame: everything free, items idle for long dropped unless held.
    fn end_frame(&mut self) {
        let now = self.frame;
        if !self.hold {
            self.loans.retain(|l| now.saturating_sub(l.last_frame) < EVICT_AFTER_FRAMES);
        }
        for loan in &mut self.loans {
            loan.in_use = false;
        }
        self.frame += 1;
    }

    fn items(&self) -> impl Iterator<Item = &T> {
        self.loans.iter().map(|l| &l.item)
    }
}

/// Owns the GPU textures behind transient graph resources.
#[derive(Default)]
pub struct TexturePool {
    /// Each texture with the key it was made for.
    lender: Lender<(PoolKey, ResolvedTexture)>,
    created_this_frame: usize,
}

impl TexturePool {
    /// An empty pool.
    pub fn new() -> Self {
        Self::default()
    }

    /// A free texture matching `key` (same size and format, at least the usage), or a new one.
    pub(crate) fn acquire(&mut self, device: &wgpu::Device, key: PoolKey) -> (usize, ResolvedTexture) {
        let fits = |(k, _): &(PoolKey, ResolvedTexture)| {
            k.size == key.size
                && k.format == key.format
                && k.layers == key.layers
                && k.samples == key.samples
                && k.usage.contains(key.usage)
        };
        let (index, (_, resolved), made) = self.lender.lend(fits, || (key, create_texture(device, key)));
        let resolved = resolved.clone();
        self.created_this_frame += usize::from(made);
        (index, resolved)
    }

    /// Returns a texture for later passes of this frame (its last reader has run).
    pub(crate) fn release(&mut self, index: usize) {
        self.lender.give_back(index);
    }

    /// Ends a frame: everything becomes free; textures idle for long are dropped.
    pub(crate) fn end_frame(&mut self) {
        self.lender.end_frame();
        self.created_this_frame = 0;
    }

    /// Whether idle textures stay (`true`: a show, whose clips come and go) or are dropped after
    /// two seconds unused (a scene: after a resize, the old sizes go).
    pub fn set_hold(&mut self, hold: bool) {
        self.lender.hold = hold;
    }

    /// Textures created during the current frame (0 in a steady state).
    pub fn created_this_frame(&self) -> usize {
        self.created_this_frame
    }

    /// Textures the pool holds.
    pub fn len(&self) -> usize {
        self.lender.loans.len()
    }

    /// Whether the pool holds no texture.
    pub fn is_empty(&self) -> bool {
        self.lender.loans.is_empty()
    }

    /// Bytes of all pooled textures.
    pub fn bytes(&self) -> u64 {
        self.lender
            .items()
            .map(|(k, _)| texture_bytes(k.size, k.format) * u64::from(k.layers.unwrap_or(1)) * u64::from(k.samples))
            .sum()
    }
}

/// A texture and its view for `key`.
fn create_texture(device: &wgpu::Device, key: PoolKey) -> ResolvedTexture {
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("graph_transient"),
        size: wgpu::Extent3d { width: key.size.0, height: key.size.1, depth_or_array_layers: key.layers.unwrap_or(1) },
        mip_level_count: 1,
        sample_count: key.samples,
        dimension: wgpu::TextureDimension::D2,
        format: key.format,
        usage: key.usage,
        view_formats: &[],
    });
    let dimension = key.layers.map(|_| wgpu::TextureViewDimension::D2Array);
    let view = texture.create_view(&wgpu::TextureViewDescriptor { dimension, ..Default::default() });
    ResolvedTexture { texture, view, id: next_resource_id() }
}

/// Owns the GPU buffers behind transient graph buffers (the compute draws' visibility buffers,
/// scratch), lent as the texture pool lends its textures.
#[derive(Default)]
pub struct BufferPool {
    /// Each buffer with its id.
    lender: Lender<(wgpu::Buffer, u64)>,
}

impl BufferPool {
    /// A free buffer of exactly `size` bytes, or a new one; its index and id.
    pub(crate) fn acquire(&mut self, device: &wgpu::Device, size: u64) -> (usize, wgpu::Buffer, u64) {
        let make = || {
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("graph_transient_buffer"),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            (buffer, next_resource_id())
        };
        let (index, (buffer, id), _) = self.lender.lend(|(b, _)| b.size() == size, make);
        (index, buffer.clone(), *id)
    }

    /// Returns a buffer for later passes of this frame (its last reader has run).
    pub(crate) fn release(&mut self, index: usize) {
        self.lender.give_back(index);
    }

    /// Ends a frame as [`TexturePool::end_frame`] does.
    pub(crate) fn end_frame(&mut self) {
        self.lender.end_frame();
    }

    /// Whether idle buffers stay, as [`TexturePool::set_hold`].
    pub fn set_hold(&mut self, hold: bool) {
        self.lender.hold = hold;
    }

    /// Bytes of all pooled buffers.
    pub fn bytes(&self) -> u64 {
        self.lender.items().map(|(b, _)| b.size()).sum()
    }
}

/// Bytes a single-mip 2-D texture occupies.
pub fn texture_bytes(size: (u32, u32), format: wgpu::TextureFormat) -> u64 {
    u64::from(format.block_copy_size(None).unwrap_or(4)) * u64::from(size.0) * u64::from(size.1)
}
