//! An image effect written in WGSL with the small interface of a show transition: a file under
//! `shaders/` that starts `// extends: effect.wgsl` and defines `fn effect(uv) -> vec4<f32>`
//! over `input_color(uv)`, with one `amount` parameter (0–1) to drive it. It is what a show's
//! effect chain takes besides ISF filters (`effect: "effect_mirror.wgsl"`), or a node of a scene.
//! Bundled: `effect_mirror.wgsl` and `effect_grade.wgsl`; the base is `shaders/effect.wgsl`.

use crate::assets::Assets;
use crate::gpu::ShaderError;
use crate::graph::{FrameGraph, TextureHandle};
use crate::params::{ParamDecl, ParamSet, ParamValue, Text};
use crate::time::FrameTime;

use super::image_pass::{ImageKernel, ImagePass, PatternUniforms, bindings, pixel_entry_point};
use super::{Declared, Declarer, NodeSetup, Technique, TechniqueInfo};

/// The registry entry.
pub const INFO: TechniqueInfo = TechniqueInfo {
    name: "wgsl_effect",
    chapter: "show: effects written in WGSL",
    summary: "an image changed by a WGSL effect file (extends effect.wgsl), driven by an amount",
    params: Settings::decls,
    inputs: &["image"],
    shaders: &[BASE],
    create,
    check: None,
    stage: None,
    declare: Some(Declarer { file_param: "file", extensions: &["wgsl"], declare, scene_for, texture_bytes }),
};

/// The file every effect extends.
pub const BASE: &str = "effect.wgsl";

crate::technique_params! {
    /// What an effect node reads each step.
    pub struct Settings {
        /// the effect: a WGSL file under shaders/ that extends effect.wgsl
        file: Text = |n, doc| ParamDecl::text(n, "effect_mirror.wgsl", doc),
        /// how strongly the effect applies, 0–1 (each effect says what it means)
        amount: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(1.0), Some((0.0, 1.0)), doc),
    }
}

/// The base's uniform block (`amount` is its value).
pub type EffectUniforms = PatternUniforms;

/// The entry point indra appends to every effect.
fn entry_point() -> String {
    pixel_entry_point("effect_main", "effect(uv)")
}

/// The asset name of effect file `file` (`shaders/effect_x.wgsl` or `effect_x.wgsl`).
fn asset_name(file: &str) -> &str {
    file.strip_prefix("shaders/").unwrap_or(file)
}

/// An effect file declares no parameters of its own: it is checked to extend the base.
fn declare(assets: &Assets, file: &str) -> Result<Declared, String> {
    let asset = assets.load(crate::assets::AssetKind::Shader, asset_name(file))?;
    if asset.source.lines().next().is_none_or(|l| l.trim() != format!("// extends: {BASE}")) {
        return Err(format!("{file}: a WGSL effect starts with `// extends: {BASE}`"));
    }
    Ok(Declared { params: Vec::new(), inputs: vec!["image".into()], hears_audio: false })
}

/// The effect over the bundled test pattern (`indra run shaders/effect_mirror.wgsl`).
fn scene_for(_assets: &Assets, file: &str) -> Result<String, ShaderError> {
    let file = file.replace('\\', "\\\\").replace('"', "\\\"");
    Ok(format!(
        "(\n    name: \"{file}\",\n    size: (1280, 720),\n    seed: 1,\n    nodes: [\n        (id: \"pattern\", \
         technique: \"isf\", params: {{ \"file\": \"shaders/isf/Test Pattern Generator.fs\" }}),\n        \
         (id: \"effect\", technique: \"wgsl_effect\", params: {{ \"file\": \"{file}\" }}, inputs: {{ \"image\": \
         \"pattern\" }}),\n    ],\n    output: \"effect\",\n)\n"
    ))
}

/// An effect keeps no images beyond its output.
fn texture_bytes(_assets: &Assets, _file: &str, _size: (u32, u32)) -> u64 {
    0
}

/// One effect: its kernel and its pass.
struct WgslEffect {
    kernel: ImageKernel,
    pass: ImagePass,
}

fn create(setup: &NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError> {
    let file = Settings::read(setup.params).file;
    let joined = setup.joined_shader_source(asset_name(file.as_str()), &bindings(1))?;
    let text = format!("{}\n{}", joined.source, entry_point());
    let size = size_of::<EffectUniforms>() as u64;
    let kernel = ImageKernel::new(&setup.gpu.device, (joined.origin(), &text), "effect_main", 1, size)
        .map_err(|e| joined.relocate(e))?;
    let pass = ImagePass::new(&setup.gpu.device, &kernel);
    Ok(Box::new(WgslEffect { kernel, pass }))
}

impl Technique for WgslEffect {
    fn add_passes<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        params: &ParamSet,
        time: &FrameTime,
        inputs: &[TextureHandle],
    ) -> TextureHandle {
        let Some(&image) = inputs.first() else { return super::image_pass::black(graph) };
        let uniforms = EffectUniforms::new(Settings::read(params).amount, time.seconds as f32, graph.output_size());
        self.pass.declare(graph, "wgsl_effect", &self.kernel, uniforms, &[image])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_layout_matches_the_wgsl_struct() {
        let source = include_str!("../../../shaders/effect.wgsl");
        assert_eq!(crate::gpu::wgsl_struct_size(source, "EffectUniforms"), Some(size_of::<EffectUniforms>() as u32));
    }

    #[test]
    fn every_bundled_effect_validates_with_the_entry_point() {
        let base = include_str!("../../../shaders/effect.wgsl");
        for (name, source) in [
            ("mirror", include_str!("../../../shaders/effect_mirror.wgsl")),
            ("grade", include_str!("../../../shaders/effect_grade.wgsl")),
        ] {
            let text = format!("{base}\n{source}\n{}", entry_point());
            crate::gpu::validate_wgsl(name, &text).unwrap_or_else(|e| panic!("{name}: {e}"));
        }
    }
}
