//! Virtual resources: descriptors, handles, and the persistent textures nodes own across frames.

use std::sync::atomic::{AtomicU64, Ordering};

/// A texture size: fixed, or a fraction of the frame's output size (rounded up, at least 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Extent {
    /// Exactly this many texels.
    Absolute(u32, u32),
    /// `output × num / den` on each axis, e.g. `Relative(1, 3)` for StarGlow's third size.
    Relative(u32, u32),
}

impl Extent {
    /// The size in texels for a given output size.
    pub fn resolve(self, output: (u32, u32)) -> (u32, u32) {
        match self {
            Extent::Absolute(w, h) => (w.max(1), h.max(1)),
            Extent::Relative(num, den) => {
                let scale = |x: u32| (u64::from(x) * u64::from(num)).div_ceil(u64::from(den.max(1))).max(1) as u32;
                (scale(output.0), scale(output.1))
            }
        }
    }
}

/// What a transient texture must be; the graph infers usage flags from the declared accesses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextureDesc {
    /// Size, absolute or relative to the output.
    pub extent: Extent,
    /// Texel format.
    pub format: wgpu::TextureFormat,
    /// `None`: a plain 2-D texture. `Some(n)`: a 2-D array of `n` layers, viewed as `D2Array`
    /// even when `n` is 1 (so shaders declaring arrays bind it whatever `n` is).
    pub layers: Option<u32>,
    /// Samples per texel: more than 1 for a multisampled render target, which a pass resolves
    /// into a single-sample texture (see `PassContext::begin_resolved_pass`).
    pub samples: u32,
}

impl TextureDesc {
    /// A texture the size of the output.
    pub fn full(format: wgpu::TextureFormat) -> Self {
        Self { extent: Extent::Relative(1, 1), format, layers: None, samples: 1 }
    }

    /// A texture `num/den` of the output size.
    pub fn scaled(format: wgpu::TextureFormat, num: u32, den: u32) -> Self {
        Self { extent: Extent::Relative(num, den), format, layers: None, samples: 1 }
    }

    /// The same size and format with `samples` samples per texel (a render target only).
    #[must_use]
    pub fn multisampled(self, samples: u32) -> Self {
        Self { samples: samples.max(1), ..self }
    }

    /// The same size and format as a 2-D array of `layers` layers.
    #[must_use]
    pub fn with_layers(self, layers: u32) -> Self {
        Self { layers: Some(layers.max(1)), ..self }
    }
}

/// A texture declared in this frame's graph.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct TextureHandle(pub(crate) u32);

/// A buffer declared in this frame's graph.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct BufferHandle(pub(crate) u32);

static NEXT_ID: AtomicU64 = AtomicU64::new(1);

/// A process-unique id for a GPU resource, stable for its lifetime: techniques key cached bind
/// groups by it, so steady-state frames create none.
pub fn next_resource_id() -> u64 {
    NEXT_ID.fetch_add(1, Ordering::Relaxed)
}

/// A texture a node owns across frames (simulation state, history) and imports each frame.
pub struct PersistentTexture {
    /// The texture.
    pub texture: wgpu::Texture,
    /// Its default view.
    pub view: wgpu::TextureView,
    /// Stable id (see [`next_resource_id`]).
    pub id: u64,
}

impl PersistentTexture {
    /// Creates a texture usable as storage, sampled, render target and copy source/destination.
    pub fn new(device: &wgpu::Device, label: &str, size: (u32, u32), format: wgpu::TextureFormat) -> Self {
        let usage = wgpu::TextureUsages::STORAGE_BINDING
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::COPY_DST
            | wgpu::TextureUsages::RENDER_ATTACHMENT;
        Self::with_usage(device, label, size, format, usage)
    }

    /// A texture only written by the queue and sampled — what block-compressed formats allow
    /// (a clip's uploaded frame).
    pub fn sampled(device: &wgpu::Device, label: &str, size: (u32, u32), format: wgpu::TextureFormat) -> Self {
        let usage = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST;
        Self::with_usage(device, label, size, format, usage)
    }

    fn with_usage(
        device: &wgpu::Device,
        label: &str,
        size: (u32, u32),
        format: wgpu::TextureFormat,
        usage: wgpu::TextureUsages,
    ) -> Self {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        Self { texture, view, id: next_resource_id() }
    }
}

/// Two persistent textures that swap roles each step: one holds the last state (read), the other
/// receives the next (write).
pub struct PingPong {
    textures: [PersistentTexture; 2],
    current: usize,
}

impl PingPong {
    /// Two textures of the same size and format, named `<label>.a` and `<label>.b`.
    pub fn new(device: &wgpu::Device, label: &str, size: (u32, u32), format: wgpu::TextureFormat) -> Self {
        let a = PersistentTexture::new(device, &format!("{label}.a"), size, format);
        let b = PersistentTexture::new(device, &format!("{label}.b"), size, format);
        Self { textures: [a, b], current: 0 }
    }

    /// (the texture to write this step, the texture holding the previous state).
    pub fn write_and_history(&self) -> (&PersistentTexture, &PersistentTexture) {
        (&self.textures[1 - self.current], &self.textures[self.current])
    }

    /// The latest state.
    pub fn current(&self) -> &PersistentTexture {
        &self.textures[self.current]
    }

    /// Makes the texture just written the current state.
    pub fn swap(&mut self) {
        self.current = 1 - self.current;
    }

    /// Both textures, and which of them is the current state (for checkpoints).
    pub fn sides(&self) -> (&[PersistentTexture; 2], usize) {
        (&self.textures, self.current)
    }

    /// Makes texture `side` (0 or 1) the current state (a checkpoint's).
    pub fn set_current(&mut self, side: usize) {
        self.current = side.min(1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_extent_rounds_up_and_never_hits_zero() {
        assert_eq!(Extent::Relative(1, 3).resolve((1920, 1080)), (640, 360));
        assert_eq!(Extent::Relative(1, 7).resolve((256, 256)), (37, 37));
        assert_eq!(Extent::Relative(1, 20).resolve((4, 4)), (1, 1));
        assert_eq!(Extent::Absolute(0, 5).resolve((4, 4)), (1, 5));
    }
}
