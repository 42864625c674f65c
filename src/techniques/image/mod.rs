//! A still image (PNG, JPEG) as a node: as a picture (sRGB to linear light, alpha premultiplied,
//! fitted into the node's size like a clip's frame — any node's input), or as data (the values
//! as stored, at the image's own size — the height map of a tessellated surface). A path that
//! cannot be read is one message, and the last good image (or a flat black one) stays, so the
//! show goes on; fixing the path (a `--set`, OSC, a scene edit) loads it. Numbered sequences
//! play as clips in the `video` node (`frames/shot_%04d.png`).
//!
//! Relative paths are looked up beside `scenes/` and `shaders/` (the asset root), then in the
//! current folder, under the file rules of [`crate::files`]; the bundled height maps are built
//! into the binary as a fallback. An image is read and decoded off the render thread, and its
//! size is checked against the device and a memory budget before it is decoded.

#[cfg(test)]
mod render_tests;

use crate::assets::Assets;

use crate::files::Loader;
use crate::gpu::ShaderError;
use crate::graph::{FrameGraph, TextureHandle};
use crate::params::{ParamDecl, ParamSet, Text};
use crate::time::FrameTime;

use super::image_pass;
use super::picture_pass::{Fit, PicturePass};
use super::{NodeSetup, Technique, TechniqueInfo};
use crate::media::picture::Picture;
use crate::media::still::Still;

/// The registry entry.
pub const INFO: TechniqueInfo = TechniqueInfo {
    name: "image",
    chapter: "media: stills (and ch. 6's height maps)",
    summary: "a PNG or JPEG: a picture fitted into the image, or its values as data (a height map)",
    params: Settings::decls,
    inputs: &[],
    shaders: &["picture.wgsl"],
    create,
    check: None,
    stage: None,
    declare: None,
};

/// The bundled height maps, by the path scenes use.
const BUNDLED: &[(&str, &[u8])] =
    &[("assets/heightmaps/ridges.png", include_bytes!("../../../assets/heightmaps/ridges.png"))];

/// The largest image file read.
const IMAGE_FILE_LIMIT: u64 = 64 << 20;

crate::param_enum! {
    /// What the image's values are.
    pub enum Values {
        /// Colours: sRGB to linear light, alpha premultiplied, fitted into the node's size.
        Picture = "picture",
        /// Numbers, as stored, at the image's own size (a height map).
        Data = "data",
    }
}

crate::technique_params! {
    /// What an image node reads each step.
    pub struct Settings {
        /// image file (PNG, JPEG); relative to the folder holding scenes/, or the current folder
        path: Text = |n, doc| ParamDecl::text(n, "assets/heightmaps/ridges.png", doc),
        /// colours (a picture) or numbers as stored (data, e.g. heights)
        values: Values = |n, doc| ParamDecl::choice(n, Values::OPTIONS, 0, doc),
        /// how a picture of another shape fills the image
        fit: Fit = |n, doc| ParamDecl::choice(n, Fit::OPTIONS, 0, doc),
    }
}

/// An image node.
pub struct Image {
    /// The image as a picture.
    picture: PicturePass,
    device: wgpu::Device,
    assets: Assets,
    /// Images being read and decoded off the render thread.
    loader: Loader<Still>,
    /// The path last asked for (loaded or not), so a bad path is reported once.
    requested: Option<String>,
    messages: Vec<String>,
}

fn create(setup: &NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError> {
    Ok(Box::new(Image::new(setup)?))
}

impl Image {
    /// A node showing its path's image, read and decoded now (a show prepares clips on a worker
    /// thread, so a triggered clip has its image before its first frame); a 1×1 black image and
    /// a message when it cannot be read. Later paths load in the background.
    pub fn new(setup: &NodeSetup<'_>) -> Result<Self, ShaderError> {
        let device = &setup.gpu.device;
        let path = Settings::read(setup.params).path.as_str().trim().to_string();
        let max_side = device.limits().max_texture_dimension_2d;
        let (image, mut messages) = match read_image(setup.assets, &path, max_side) {
            Ok(image) => (image, Vec::new()),
            Err(e) => (Still { size: (1, 1), picture: Picture::Rgba(vec![0; 4]) }, vec![e]),
        };
        let mut picture = PicturePass::new(setup, true)?;
        show(&mut picture, &image, &mut messages);
        Ok(Self {
            picture,
            device: device.clone(),
            assets: setup.assets.clone(),
            loader: Loader::new(setup.assets.load_wait()),
            requested: Some(path),
            messages,
        })
    }
}

/// Reads image `name` under the file rules, or says why not. The bundled height maps answer
/// for their paths when no file is there.
fn read_image(assets: &Assets, name: &str, max_side: u32) -> Result<Still, String> {
    let bundled = BUNDLED.iter().find(|(bundled, _)| *bundled == name).map(|(_, bytes)| *bytes);
    let read = assets.read_file(name, IMAGE_FILE_LIMIT, bundled).map_err(|e| format!("cannot read image: {e}"))?;
    decode_bounded(&read.bytes, &read.origin, max_side)
}

/// Decodes `bytes` within the device's side and this node's memory budget (see
/// [`crate::media::still::decode`]).
pub fn decode_bounded(bytes: &[u8], name: &str, max_side: u32) -> Result<Still, String> {
    crate::media::still::decode(bytes, name, max_side, crate::media::DECODED_LIMIT)
}

/// Makes `image` the picture shown.
fn show(picture: &mut PicturePass, image: &Still, messages: &mut Vec<String>) {
    if let Err(e) = picture.upload(&image.picture, image.size) {
        messages.push(e);
    }
}

impl Technique for Image {
    fn step(&mut self, params: &ParamSet, _time: &FrameTime) {
        let path = Settings::read(params).path.as_str().trim().to_string();
        if self.requested.as_deref() != Some(path.as_str()) {
            let (assets, name) = (self.assets.clone(), path.clone());
            let max_side = self.device.limits().max_texture_dimension_2d;
            self.loader.request(&path, move || read_image(&assets, &name, max_side));
            self.requested = Some(path);
        }
        match self.loader.poll() {
            Some((_, Ok(image))) => show(&mut self.picture, &image, &mut self.messages),
            Some((_, Err(e))) => self.messages.push(format!("{e}; keeping the last image")),
            None => {}
        }
    }

    fn take_messages(&mut self) -> Vec<String> {
        std::mem::take(&mut self.messages)
    }

    fn add_passes<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        params: &ParamSet,
        _time: &FrameTime,
        _inputs: &[TextureHandle],
    ) -> TextureHandle {
        let settings = Settings::read(params);
        match settings.values {
            // The picture's upload is the values as stored, at the image's own size: RGBA8, or
            // half floats for OpenEXR (heights above 1 stay above 1).
            Values::Data => match self.picture.uploaded() {
                Some(texture) => graph.import_texture("image/data", texture),
                None => image_pass::black(graph),
            },
            Values::Picture => self.picture.declare(graph, "image", settings.fit),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A PNG chunk: length, type, data and CRC.
    fn chunk(kind: &[u8; 4], data: &[u8]) -> Vec<u8> {
        let body: Vec<u8> = kind.iter().chain(data).copied().collect();
        let mut crc = !0u32;
        for byte in &body {
            crc ^= u32::from(*byte);
            for _ in 0..8 {
                crc = if crc & 1 == 1 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
            }
        }
        let mut out = (data.len() as u32).to_be_bytes().to_vec();
        out.extend(body);
        out.extend((!crc).to_be_bytes());
        out
    }

    /// A PNG claiming `width` × `height` grey pixels, with no pixel data behind the claim.
    fn png_header(width: u32, height: u32) -> Vec<u8> {
        let mut header = width.to_be_bytes().to_vec();
        header.extend(height.to_be_bytes());
        header.extend([8, 0, 0, 0, 0]);
        let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
        png.extend(chunk(b"IHDR", &header));
        png.extend(chunk(b"IDAT", &[]));
        png.extend(chunk(b"IEND", &[]));
        png
    }

    #[test]
    fn an_image_too_large_for_the_device_or_the_budget_is_refused_before_decoding() {
        let e = decode_bounded(&png_header(16385, 8), "wide.png", 16384).unwrap_err();
        assert!(e.contains("16385×8") && e.contains("at most 16384"), "{e}");
        let e = decode_bounded(&png_header(11000, 11000), "huge.png", 16384).unwrap_err();
        assert!(e.contains("MiB"), "{e}");
        let e = decode_bounded(b"not an image", "junk.png", 16384).unwrap_err();
        assert!(e.contains("junk.png"), "{e}");
        let bundled = decode_bounded(BUNDLED[0].1, "ridges.png", 16384).unwrap();
        assert!(bundled.size.0 > 1, "a real image still decodes");
    }
}
