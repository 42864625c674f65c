//! The visibility buffer of a draw done in compute: one 64-bit word per sample of the image,
//! (inverted depth, primitive + 1), filled with `atomicMax` so the nearest primitive wins in any
//! order, then shaded per pixel: the store of the compute draws (tessellation, space colonization,
//! Poisson).

use crate::graph::{BufferHandle, FrameGraph};

/// The visibility buffer a compute draw needs for one image size and sample count. The frame
/// graph lends it each frame from its pool of buffers, so nodes that draw one after another share
/// one, and a node off screen (a clip not playing) holds none: at 4K with 4 samples it is 265 MB.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VisibilityBuffer {
    /// (width, height, samples) it is for.
    key: (u32, u32, u32),
    /// Its size in bytes.
    bytes: u64,
}

impl VisibilityBuffer {
    /// Keeps `slot` for `size` × `samples` (checked against the device's buffer limits only
    /// when those change); false, and `slot` emptied, when the buffer would exceed them (the
    /// caller draws with the pipeline then).
    pub fn ensure(slot: &mut Option<Self>, device: &wgpu::Device, size: (u32, u32), samples: u32) -> bool {
        let key = (size.0, size.1, samples);
        if slot.is_some_and(|v| v.key == key) {
            return true;
        }
        let limits = device.limits();
        // One 64-bit word per sample.
        let bytes = u64::from(size.0) * u64::from(size.1) * u64::from(samples.max(1)) * 8;
        let fits = bytes <= limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        *slot = fits.then_some(Self { key, bytes: bytes.max(8) });
        fits
    }

    /// Declares this frame's buffer in `graph` as `name`.
    pub fn declare(&self, graph: &mut FrameGraph<'_>, name: &str) -> BufferHandle {
        graph.create_buffer(name, self.bytes)
    }

    /// (width, height, samples).
    pub fn key(&self) -> (u32, u32, u32) {
        self.key
    }
}

/// The rays of a perspective camera at `eye` seen through `view_proj` over a `size` image: the
/// ray through pixel position p (y down) is `origin + x p.x + y p.y`, not normalised (rays are
/// affine in the pixel position). In f64: the far plane may be 10⁴ near planes away, and the
/// rays are its points' differences.
pub struct PixelRays {
    /// The ray through the image's top-left corner.
    pub origin: glam::DVec3,
    /// The ray's change per pixel to the right.
    pub x: glam::DVec3,
    /// The ray's change per pixel down.
    pub y: glam::DVec3,
}

impl PixelRays {
    /// The rays of `view_proj` from `eye` over `size` pixels.
    pub fn new(view_proj: glam::Mat4, eye: glam::Vec3, size: (u32, u32)) -> Self {
        let inverse = view_proj.as_dmat4().inverse();
        let (width, height) = (f64::from(size.0.max(1)), f64::from(size.1.max(1)));
        let ray = |x: f64, y: f64| {
            let far = inverse * glam::DVec4::new(x / width * 2.0 - 1.0, 1.0 - y / height * 2.0, 1.0, 1.0);
            far.truncate() / far.w - eye.as_dvec3()
        };
        let origin = ray(0.0, 0.0);
        Self { origin, x: ray(1.0, 0.0) - origin, y: ray(0.0, 1.0) - origin }
    }

    /// `v` in f32 with `w` appended, as uniforms carry it.
    pub fn vec4(v: glam::DVec3, w: f64) -> [f32; 4] {
        [v.x as f32, v.y as f32, v.z as f32, w as f32]
    }
}
