//! A fader to black: the image's colour times a level. A show's master (`master`) is one, so the
//! whole composition can be taken down to black from the panel, OSC or a MIDI fader.
//!
//! Shader: `fader.wgsl`.

use crate::gpu::ShaderError;
use crate::graph::{FrameGraph, TextureHandle};
use crate::params::{ParamDecl, ParamSet, ParamValue};
use crate::time::FrameTime;

use super::image_pass::ImageNode;
use super::{NodeSetup, Technique, TechniqueInfo};

/// The registry entry.
pub const INFO: TechniqueInfo = TechniqueInfo {
    name: "fader",
    chapter: "show: master fader",
    summary: "the image faded towards black by a level",
    params: Settings::decls,
    inputs: &["image"],
    shaders: &["fader.wgsl"],
    create,
    check: None,
    stage: None,
    declare: None,
};

crate::technique_params! {
    /// What a fader reads each step.
    pub struct Settings {
        /// 1 shows the image, 0 is black
        level: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(1.0), Some((0.0, 1.0)), doc),
    }
}

/// The shader's uniform block.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FaderUniforms {
    /// 0–1.
    pub level: f32,
    /// Padding to 16 bytes.
    pub pad: [f32; 3],
}

fn create(setup: &NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError> {
    Ok(Box::new(ImageNode::<FaderUniforms>::new(setup, "fader.wgsl", "fader", 1)?))
}

impl Technique for ImageNode<FaderUniforms> {
    fn add_passes<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        params: &ParamSet,
        _time: &FrameTime,
        inputs: &[TextureHandle],
    ) -> TextureHandle {
        let level = Settings::read(params).level;
        match inputs.first() {
            Some(&image) => self.declare(graph, FaderUniforms { level, pad: [0.0; 3] }, &[image]),
            None => super::image_pass::black(graph),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_layout_matches_the_wgsl_struct() {
        let source = include_str!("fader.wgsl");
        assert_eq!(crate::gpu::wgsl_struct_size(source, "FaderUniforms"), Some(size_of::<FaderUniforms>() as u32));
    }
}
