//! One decoded frame of a clip, a still or a camera, as a node uploads it: texture blocks or
//! pixels. Below every reader of pictures, so that none imports another for it.

use super::hap::HapFrame;

/// One decoded frame.
#[derive(Clone, Debug)]
pub enum Picture {
    /// HAP's texture blocks, for the GPU to sample (or the CPU to decode).
    Hap(HapFrame),
    /// RGBA8 pixels, sRGB-encoded, straight alpha, top row first.
    Rgba(Vec<u8>),
    /// Linear RGBA half floats (bits), straight alpha, top row first (OpenEXR).
    LinearHalf(Vec<u16>),
}

impl Picture {
    /// Bytes held.
    pub fn bytes(&self) -> usize {
        match self {
            Picture::Hap(f) => f.color.blocks.len() + f.alpha.as_ref().map_or(0, |a| a.blocks.len()),
            Picture::Rgba(p) => p.len(),
            Picture::LinearHalf(p) => p.len() * 2,
        }
    }
}
