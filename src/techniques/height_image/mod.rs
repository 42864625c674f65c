//! A PNG (or any image the `image` crate reads) as a texture in the frame graph: the height map
//! of a tessellated surface, or any node's input. A path that cannot be read is one message, and
//! the last good image (or a flat black one) stays, so the show goes on; fixing the path (a
//! `--set`, OSC, a scene edit) loads it.
//!
//! Relative paths are looked up beside `scenes/` and `shaders/` (the asset root), then in the
//! current folder; the bundled height maps are built into the binary as a fallback.

use crate::gpu::ShaderError;
use crate::graph::{FrameGraph, PersistentTexture, TextureHandle};
use crate::params::{ParamDecl, ParamSet, ParamValue, Text};
use crate::time::FrameTime;

use super::{NodeSetup, Technique, TechniqueInfo};

/// The registry entry.
pub const INFO: TechniqueInfo = TechniqueInfo {
    name: "height_image",
    chapter: "6: Tessellation & Displacement (height map)",
    summary: "an image file as a texture (a height map for the tessellated surface)",
    params,
    inputs: &[],
    shaders: &[],
    create,
};

/// The bundled height maps, by the path scenes use.
const BUNDLED: &[(&str, &[u8])] =
    &[("assets/heightmaps/ridges.png", include_bytes!("../../../assets/heightmaps/ridges.png"))];

/// Parameters.
pub fn params() -> Vec<ParamDecl> {
    vec![ParamDecl::new(
        "path",
        ParamValue::Text(Text::new("assets/heightmaps/ridges.png")),
        None,
        "image file (PNG); relative to the folder holding scenes/, or the current folder",
    )]
}

/// An image node.
pub struct HeightImage {
    device: wgpu::Device,
    queue: wgpu::Queue,
    root: Option<std::path::PathBuf>,
    /// The path last asked for (loaded or not), so a bad path is reported once.
    requested: Option<String>,
    texture: PersistentTexture,
    messages: Vec<String>,
}

fn create(setup: &NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError> {
    Ok(Box::new(HeightImage::new(setup)))
}

impl HeightImage {
    /// A node showing a 1×1 black image until its path loads.
    pub fn new(setup: &NodeSetup<'_>) -> Self {
        let device = &setup.gpu.device;
        let texture = upload(device, &setup.gpu.queue, &image::RgbaImage::new(1, 1));
        Self {
            device: device.clone(),
            queue: setup.gpu.queue.clone(),
            root: setup.assets.root().map(std::path::Path::to_path_buf),
            requested: None,
            texture,
            messages: Vec::new(),
        }
    }

    /// The loaded image's size.
    pub fn size(&self) -> (u32, u32) {
        (self.texture.texture.width(), self.texture.texture.height())
    }

    /// Reads `path` as RGBA8, or says why not.
    fn read(&self, path: &str) -> Result<image::RgbaImage, String> {
        let candidates = [self.root.as_ref().map(|r| r.join(path)), Some(std::path::PathBuf::from(path))];
        let found = candidates.into_iter().flatten().find(|p| p.is_file());
        let decoded = match (found, BUNDLED.iter().find(|(name, _)| *name == path)) {
            (Some(file), _) => image::open(&file).map_err(|e| format!("cannot read {}: {e}", file.display()))?,
            (None, Some((_, bytes))) => image::load_from_memory(bytes).map_err(|e| format!("bundled {path}: {e}"))?,
            (None, None) => {
                return Err(format!("no image at '{path}' (looked beside scenes/ and in the current folder)"));
            }
        };
        Ok(decoded.to_rgba8())
    }
}

fn upload(device: &wgpu::Device, queue: &wgpu::Queue, image: &image::RgbaImage) -> PersistentTexture {
    let size = (image.width().max(1), image.height().max(1));
    let texture = PersistentTexture::new(device, "height_image", size, wgpu::TextureFormat::Rgba8Unorm);
    queue.write_texture(
        texture.texture.as_image_copy(),
        image.as_raw(),
        wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(4 * size.0), rows_per_image: Some(size.1) },
        wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
    );
    texture
}

impl Technique for HeightImage {
    fn step(&mut self, params: &ParamSet, _time: &FrameTime) {
        let ParamValue::Text(path) = params.get("path") else { return };
        let path = path.as_str().trim().to_string();
        if self.requested.as_deref() == Some(path.as_str()) {
            return;
        }
        match self.read(&path) {
            Ok(image) => self.texture = upload(&self.device, &self.queue, &image),
            Err(e) => self.messages.push(format!("{e}; keeping the last image")),
        }
        self.requested = Some(path);
    }

    fn take_messages(&mut self) -> Vec<String> {
        std::mem::take(&mut self.messages)
    }

    fn add_passes<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        params: &ParamSet,
        time: &FrameTime,
        _inputs: &[TextureHandle],
    ) -> TextureHandle {
        // A frame drawn before any step still shows the image.
        if self.requested.is_none() {
            self.step(params, time);
        }
        graph.import_texture("height_image/image", &self.texture)
    }
}
