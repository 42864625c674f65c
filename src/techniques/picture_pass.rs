//! A decoded picture — a clip's frame, a camera's, a still — as a node's image: uploaded (HAP's
//! blocks as BC textures where the adapter has `TEXTURE_COMPRESSION_BC`, so the GPU decodes them
//! as it samples, otherwise decoded on the CPU to BGRA8; RGBA as RGBA8), then one compute pass
//! (`shaders/picture.wgsl`) fits it into the node's size (contain, cover, stretch), turns HAP Q's
//! YCoCg into RGB, takes sRGB to linear light and premultiplies alpha — what every node's image
//! is. Shared by the `video`, `camera` and `image` nodes.

use super::NodeSetup;
use super::image_pass::{self, ImageKernel, ImagePass};
use crate::gpu::ShaderError;
use crate::graph::{FrameGraph, PersistentTexture, TextureHandle};
use crate::media::hap::{self, BlockFormat, Channels, HapTexture};
use crate::media::picture::Picture;

crate::param_enum! {
    /// How a picture of another shape fills the node's image.
    pub enum Fit {
        /// All of the picture, bars where the shapes differ.
        Contain = "contain",
        /// All of the image, the picture cropped.
        Cover = "cover",
        /// Both, the picture stretched.
        Stretch = "stretch",
    }
}

/// The shader's uniform block.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PictureUniforms {
    /// 0 RGB, 1 RGBA, 2 scaled YCoCg, 3 alpha only.
    pub channels: u32,
    /// The [`Fit`] option index.
    pub fit: u32,
    /// 1 when the second texture holds the alpha.
    pub separate_alpha: u32,
    /// 0 sRGB-encoded (to be linearised, within 0–1), 1 linear already (OpenEXR, HDR kept).
    pub linear_values: u32,
    /// The picture's size in pixels.
    pub size: [f32; 2],
    /// The picture's share of its texture.
    pub uv_scale: [f32; 2],
}

/// A node's picture: its textures and the pass that makes its image.
pub struct PicturePass {
    kernel: ImageKernel,
    pass: ImagePass,
    textures: FrameTextures,
    device: wgpu::Device,
    queue: wgpu::Queue,
}

impl PicturePass {
    /// Builds the pass; with `allow_blocks` false, HAP is decoded on the CPU even where the GPU
    /// could (the fallback path, for tests).
    pub fn new(setup: &NodeSetup<'_>, allow_blocks: bool) -> Result<Self, ShaderError> {
        let (origin, source) = setup.shader_source("picture.wgsl", &image_pass::bindings(2))?;
        let device = &setup.gpu.device;
        let kernel = ImageKernel::new(device, (&origin, &source), "picture", 2, size_of::<PictureUniforms>() as u64)?;
        let pass = ImagePass::new(device, &kernel);
        let textures = FrameTextures::new(device, &setup.gpu.queue, allow_blocks);
        Ok(Self { kernel, pass, textures, device: device.clone(), queue: setup.gpu.queue.clone() })
    }

    /// Whether HAP blocks go to the GPU as they are.
    pub fn uploads_blocks(&self) -> bool {
        self.textures.uploads_blocks()
    }

    /// The picture's texture as uploaded: its values as stored, at its own size (what an
    /// image node shows as data). `None` before any picture came.
    pub fn uploaded(&self) -> Option<&PersistentTexture> {
        self.textures.color.as_ref()
    }

    /// Makes `picture` (of `size` pixels) the one shown.
    pub fn upload(&mut self, picture: &Picture, size: (u32, u32)) -> Result<(), String> {
        self.textures.upload(&self.device, &self.queue, picture, size)
    }

    /// Makes RGBA8 `pixels` (sRGB, top row first) of `size` the picture shown, straight from a
    /// live source's shared frame (no copy into a [`Picture`] first).
    pub fn upload_rgba(&mut self, pixels: &[u8], size: (u32, u32)) -> Result<(), String> {
        self.textures.upload_rgba(&self.device, &self.queue, pixels, size)
    }

    /// Declares this frame's pass (named `name`): the picture fitted by `fit`, or a black image
    /// before any picture came.
    pub fn declare<'r>(&'r mut self, graph: &mut FrameGraph<'r>, name: &str, fit: Fit) -> TextureHandle {
        let Self { kernel, pass, textures, .. } = self;
        let Some((color, alpha, layout)) = textures.current() else { return image_pass::black(graph) };
        let uniforms = PictureUniforms {
            channels: layout.channels,
            fit: fit.index(),
            separate_alpha: u32::from(layout.separate_alpha),
            linear_values: u32::from(layout.linear),
            size: [layout.size.0 as f32, layout.size.1 as f32],
            uv_scale: layout.uv_scale,
        };
        let inputs = [
            graph.import_texture(format!("{name}/picture"), color),
            graph.import_texture(format!("{name}/alpha"), alpha),
        ];
        pass.declare(graph, name, kernel, uniforms, &inputs)
    }
}

/// What the shader must do with the uploaded texture(s) (see `video.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Layout {
    /// 0 RGB, 1 RGBA, 2 scaled YCoCg, 3 alpha only.
    pub channels: u32,
    /// Whether the second texture holds the alpha.
    pub separate_alpha: bool,
    /// The picture's size in pixels.
    pub size: (u32, u32),
    /// The picture's share of its texture (BC textures are padded to whole blocks).
    pub uv_scale: [f32; 2],
    /// Whether the values are linear already.
    pub linear: bool,
}

/// The textures a video node samples.
struct FrameTextures {
    /// Whether BC textures may be made.
    block_upload: bool,
    color: Option<PersistentTexture>,
    alpha: Option<PersistentTexture>,
    /// A 1×1 white texture standing in for a missing alpha.
    white: PersistentTexture,
    layout: Option<Layout>,
}

impl FrameTextures {
    /// Empty textures; BC uploads when `device` has `TEXTURE_COMPRESSION_BC` and `allow_blocks`.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, allow_blocks: bool) -> Self {
        let white = PersistentTexture::sampled(device, "video/white", (1, 1), wgpu::TextureFormat::Rgba8Unorm);
        queue.write_texture(
            white.texture.as_image_copy(),
            &[255; 4],
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(4), rows_per_image: Some(1) },
            white.texture.size(),
        );
        let block_upload = allow_blocks && device.features().contains(wgpu::Features::TEXTURE_COMPRESSION_BC);
        Self { block_upload, color: None, alpha: None, white, layout: None }
    }

    /// Whether HAP blocks go to the GPU as they are.
    pub fn uploads_blocks(&self) -> bool {
        self.block_upload
    }

    /// The textures to sample (colour, alpha) and how, once a picture was uploaded.
    pub fn current(&self) -> Option<(&PersistentTexture, &PersistentTexture, Layout)> {
        let layout = self.layout?;
        let color = self.color.as_ref()?;
        Some((color, self.alpha.as_ref().filter(|_| layout.separate_alpha).unwrap_or(&self.white), layout))
    }

    /// Uploads `picture` of `size`.
    pub fn upload(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        picture: &Picture,
        size: (u32, u32),
    ) -> Result<(), String> {
        let (w, h) = size;
        match picture {
            Picture::Rgba(pixels) => self.upload_rgba(device, queue, pixels, size)?,
            Picture::LinearHalf(texels) => {
                let bytes: &[u8] = bytemuck::cast_slice(texels);
                write_pixels(device, queue, &mut self.color, wgpu::TextureFormat::Rgba16Float, size, bytes)?;
                self.layout =
                    Some(Layout { channels: 1, separate_alpha: false, size, uv_scale: [1.0, 1.0], linear: true });
            }
            Picture::Hap(frame) => {
                let uv_scale = self.write_hap(device, queue, &frame.color, size, false)?;
                if let Some(alpha) = &frame.alpha {
                    self.write_hap(device, queue, alpha, size, true)?;
                }
                let channels = match frame.color.channels {
                    Channels::Rgb => 0,
                    Channels::Rgba => 1,
                    Channels::ScaledYCoCg => 2,
                    Channels::Alpha => 3,
                };
                let separate_alpha = frame.alpha.is_some();
                self.layout = Some(Layout { channels, separate_alpha, size: (w, h), uv_scale, linear: false });
            }
        }
        Ok(())
    }

    /// Uploads RGBA8 `pixels` of `size`.
    pub fn upload_rgba(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        pixels: &[u8],
        size: (u32, u32),
    ) -> Result<(), String> {
        write_pixels(device, queue, &mut self.color, wgpu::TextureFormat::Rgba8Unorm, size, pixels)?;
        self.layout = Some(Layout { channels: 1, separate_alpha: false, size, uv_scale: [1.0, 1.0], linear: false });
        Ok(())
    }

    /// Writes one HAP texture; returns the picture's share of the texture.
    fn write_hap(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        texture: &HapTexture,
        (w, h): (u32, u32),
        alpha: bool,
    ) -> Result<[f32; 2], String> {
        let slot = if alpha { &mut self.alpha } else { &mut self.color };
        if !self.block_upload {
            let pixels = hap::decode_to_bgra(texture, w, h)?;
            write_pixels(device, queue, slot, wgpu::TextureFormat::Bgra8Unorm, (w, h), bytemuck::cast_slice(&pixels))?;
            return Ok([1.0, 1.0]);
        }
        let format = match texture.format {
            BlockFormat::Bc1 => wgpu::TextureFormat::Bc1RgbaUnorm,
            BlockFormat::Bc3 => wgpu::TextureFormat::Bc3RgbaUnorm,
            BlockFormat::Bc4 => wgpu::TextureFormat::Bc4RUnorm,
            BlockFormat::Bc7 => wgpu::TextureFormat::Bc7RgbaUnorm,
        };
        let padded = (w.div_ceil(4) * 4, h.div_ceil(4) * 4);
        let target = reuse(device, slot, format, padded);
        queue.write_texture(
            target.texture.as_image_copy(),
            &texture.blocks,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(w.div_ceil(4) * texture.format.block_bytes() as u32),
                rows_per_image: Some(h.div_ceil(4)),
            },
            target.texture.size(),
        );
        Ok([w as f32 / padded.0 as f32, h as f32 / padded.1 as f32])
    }
}

/// Writes pixels (of `format`'s texel size) into `slot` (made or remade at `size` and `format`).
fn write_pixels(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    slot: &mut Option<PersistentTexture>,
    format: wgpu::TextureFormat,
    size: (u32, u32),
    pixels: &[u8],
) -> Result<(), String> {
    let texel = format.block_copy_size(None).unwrap_or(4);
    if pixels.len() != size.0 as usize * size.1 as usize * texel as usize {
        return Err(format!("a frame of {} bytes does not fit {}×{}", pixels.len(), size.0, size.1));
    }
    let target = reuse(device, slot, format, size);
    queue.write_texture(
        target.texture.as_image_copy(),
        pixels,
        wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(texel * size.0), rows_per_image: Some(size.1) },
        target.texture.size(),
    );
    Ok(())
}

/// The texture in `slot` if it has `format` and `size`, else a new one put there.
fn reuse<'a>(
    device: &wgpu::Device,
    slot: &'a mut Option<PersistentTexture>,
    format: wgpu::TextureFormat,
    size: (u32, u32),
) -> &'a PersistentTexture {
    let fits =
        slot.as_ref().is_some_and(|t| t.texture.format() == format && (t.texture.width(), t.texture.height()) == size);
    if !fits {
        *slot = Some(PersistentTexture::sampled(device, "video/frame", size, format));
    }
    slot.as_ref().expect("made above")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_layout_matches_the_wgsl_struct() {
        let source = include_str!("../../shaders/picture.wgsl");
        assert_eq!(crate::gpu::wgsl_struct_size(source, "PictureUniforms"), Some(size_of::<PictureUniforms>() as u32));
    }
}
