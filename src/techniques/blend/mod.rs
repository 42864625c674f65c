//! Blending one image over another, as a VJ mixer's layers do: Normal (alpha over), Add, Screen,
//! Multiply, Difference and Lighten, in linear HDR, at an opacity. A show composites its layers
//! with one `blend` node each (`layer/<n>`); a scene may use it to mix any two nodes.
//!
//! Shader: `blend.wgsl`. Tests: `tests/suite/show.rs` (each mode against a CPU reference).

use crate::gpu::ShaderError;
use crate::graph::{FrameGraph, TextureHandle};
use crate::params::{ParamDecl, ParamSet, ParamValue};
use crate::time::FrameTime;

use super::image_pass::ImageNode;
use super::{NodeSetup, Technique, TechniqueInfo};

/// The registry entry.
pub const INFO: TechniqueInfo = TechniqueInfo {
    name: "blend",
    chapter: "show: layer compositing",
    summary: "one image over another: normal, add, screen, multiply, difference or lighten, at an opacity",
    params: Settings::decls,
    inputs: &["below", "over"],
    shaders: &["blend.wgsl"],
    create,
    check: None,
    stage: None,
    declare: None,
};

crate::param_enum! {
    /// How a layer's colour meets the image below (in linear light).
    pub enum BlendMode {
        /// The layer over the image, by its alpha.
        Normal = "normal",
        /// Sum: light adds up (glows, particles).
        Add = "add",
        /// 1 − (1 − a)(1 − b): brightens without blowing out as fast as add.
        Screen = "screen",
        /// Product: darkens, white is neutral.
        Multiply = "multiply",
        /// |a − b|.
        Difference = "difference",
        /// The brighter of the two, per channel.
        Lighten = "lighten",
    }
}

crate::technique_params! {
    /// What a blend node reads each step.
    pub struct Settings {
        /// how much of the layer shows, 0 (none) to 1 (all)
        opacity: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(1.0), Some((0.0, 1.0)), doc),
        /// how the layer's colour meets the image below
        blend: BlendMode = |n, doc| ParamDecl::choice(n, BlendMode::OPTIONS, 0, doc),
    }
}

/// The shader's uniform block.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BlendUniforms {
    /// The mode's option index.
    pub mode: u32,
    /// 0–1.
    pub opacity: f32,
    /// Padding to 16 bytes.
    pub pad: [u32; 2],
}

fn create(setup: &NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError> {
    Ok(Box::new(ImageNode::<BlendUniforms>::new(setup, "blend.wgsl", "blend", 2)?))
}

impl Technique for ImageNode<BlendUniforms> {
    fn add_passes<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        params: &ParamSet,
        _time: &FrameTime,
        inputs: &[TextureHandle],
    ) -> TextureHandle {
        let s = Settings::read(params);
        let uniforms = BlendUniforms { mode: s.blend.index(), opacity: s.opacity, pad: [0; 2] };
        match inputs {
            [below, over, ..] => self.declare(graph, uniforms, &[*below, *over]),
            // A node missing an input shows what it has (scene validation wires both).
            [only] => *only,
            [] => super::image_pass::black(graph),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_layout_matches_the_wgsl_struct() {
        let source = include_str!("blend.wgsl");
        assert_eq!(crate::gpu::wgsl_struct_size(source, "BlendUniforms"), Some(size_of::<BlendUniforms>() as u32));
    }
}
