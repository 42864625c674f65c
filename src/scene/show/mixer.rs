//! The passes a show draws between its clips and its layers: a layer in transition mixes its
//! outgoing and incoming clips with a transition shader. Every kind the show names is compiled
//! when the show is built, so a trigger never waits for a pipeline.
//!
//! A transition shader is `shaders/transition_<kind>.wgsl`, starting `// extends:
//! transition.wgsl`, and defines `fn transition(uv: vec2<f32>, progress: f32) -> vec4<f32>`:
//! the colour at `uv` (0–1 from the top left) when it is `progress` (0 → 1) of the way from the
//! outgoing clip (`from_color(uv)`) to the incoming one (`to_color(uv)`). The base declares the
//! bindings and helpers (see `shaders/transition.wgsl`); indra adds the entry point.
//!
//! A kind that is a path to an ISF transition (`shaders/isf/Directional Wipe.fs`: a shader with
//! `startImage`, `endImage` and `progress`) runs as an `isf` node per layer, its `progress` the
//! transition's and its `TIME` the seconds since the transition began.

use crate::assets::{AssetKind, Assets};
use crate::gpu::{Gpu, JoinedSource, ShaderError};
use crate::graph::{FrameGraph, TextureHandle};
use crate::params::{ParamSet, ParamValue, Text};
use crate::techniques::image_pass::{ImageKernel, ImagePass, PatternUniforms, pixel_entry_point};
use crate::techniques::{self, NodeSetup, Technique};
use crate::time::FrameTime;

use super::{LayerView, Show};

/// The file every transition extends.
pub const TRANSITION_BASE: &str = "transition.wgsl";

/// The file of transition kind `kind`.
pub fn transition_file(kind: &str) -> String {
    format!("transition_{kind}.wgsl")
}

/// The entry point indra appends to every transition.
fn entry_point() -> String {
    pixel_entry_point("transition_main", "transition(uv, clamp(u.progress, 0.0, 1.0))")
}

/// The base's uniform block (`progress` is its value).
pub type TransitionUniforms = PatternUniforms;

/// Whether transition kind `kind` is a shader file a technique plays (an ISF transition:
/// `startImage`, `endImage`, `progress`) rather than a WGSL transition's name.
pub fn is_isf(kind: &str) -> bool {
    techniques::file_technique(kind).is_some()
}

/// An ISF transition for one layer: the shader as a node, and its parameters (`progress` set
/// each frame).
struct IsfTransition {
    node: Box<dyn Technique>,
    params: ParamSet,
    progress: usize,
}

/// The show's transition pipelines, and one pass per layer.
pub struct Mixer {
    /// Per kind: its WGSL kernel (`None` for an ISF kind).
    kernels: Vec<Option<ImageKernel>>,
    passes: Vec<ImagePass>,
    /// Per kind: for an ISF kind, one node per layer.
    isf: Vec<Vec<IsfTransition>>,
    /// The kind that mixes an effect's dry and wet images, and one pass per effect.
    mix_kind: Option<usize>,
    fx: Vec<ImagePass>,
}

impl Mixer {
    /// Compiles every transition `show` names, with `assets`' shaders.
    pub fn new(gpu: &Gpu, assets: &Assets, show: &Show) -> Result<Self, ShaderError> {
        let device = &gpu.device;
        let load = |name: &str| assets.load(AssetKind::Shader, name).map(|a| (a.origin, a.source));
        let mut kernels = Vec::with_capacity(show.kinds.len());
        let mut isf = Vec::with_capacity(show.kinds.len());
        for kind in &show.kinds {
            if is_isf(kind) {
                let layers = (0..show.layers.len()).map(|l| isf_transition(gpu, assets, kind, l));
                isf.push(layers.collect::<Result<Vec<_>, _>>()?);
                kernels.push(None);
                continue;
            }
            isf.push(Vec::new());
            let file = transition_file(kind);
            let located = |message: String| ShaderError { origin: file.clone(), line: 1, column: 1, message };
            let (origin, source) = load(&file).map_err(located)?;
            let joined = JoinedSource::with_bases(&origin, &source, load).map_err(located)?;
            let text = format!("{}\n{}", joined.source, entry_point());
            let size = size_of::<TransitionUniforms>() as u64;
            let kernel = ImageKernel::new(device, (joined.origin(), &text), "transition_main", 2, size)
                .map_err(|e| joined.relocate(e))?;
            kernels.push(Some(kernel));
        }
        let passes = match kernels.iter().flatten().next() {
            Some(k) => show.layers.iter().map(|_| ImagePass::new(device, k)).collect(),
            None => Vec::new(),
        };
        let mix_kind = show.mix_kind.filter(|&k| matches!(kernels.get(k), Some(Some(_))));
        let fx = match mix_kind.and_then(|k| kernels[k].as_ref()) {
            Some(k) => show.effects.iter().map(|_| ImagePass::new(device, k)).collect(),
            None => Vec::new(),
        };
        Ok(Self { kernels, passes, isf, mix_kind, fx })
    }

    /// An empty mixer, to take the running show's with [`Mixer::take_from`]: a chain edit's,
    /// whose show plays the same transitions. Compiling them again cost the edit's build the
    /// time and the driver's memory, and the running show the drop of them.
    pub fn to_take_over() -> Self {
        Self { kernels: Vec::new(), passes: Vec::new(), isf: Vec::new(), mix_kind: None, fx: Vec::new() }
    }

    /// The shader files a mixer for `show` is built from (an edit of one rebuilds it).
    pub fn files_for(show: &Show) -> Vec<String> {
        let mut files: Vec<String> = show.kinds.iter().filter(|k| !is_isf(k)).map(|k| transition_file(k)).collect();
        files.push(TRANSITION_BASE.into());
        files
    }

    /// Takes `old`'s pipelines, passes and ISF transition nodes (it was built for the same
    /// transition kinds on as many layers), and makes or drops dry/wet passes to have one for
    /// each of `effects`. The objects that drew the frame before draw the next one with their
    /// bind groups and buffers in place; with fresh ones the edit frame's submit took 0.09–0.16
    /// ms more than its neighbours' on an H100 host (median of 11–14 edits), 0.01–0.02 ms with
    /// these.
    pub fn take_from(&mut self, old: &mut Mixer, device: &wgpu::Device, effects: usize) {
        *self = std::mem::replace(old, Self::to_take_over());
        // Dry/wet passes are alike: the effects there were keep theirs, a new one takes a new one.
        self.fx.truncate(effects);
        if let Some(kernel) = self.mix_kind.and_then(|k| self.kernels[k].as_ref()) {
            while self.fx.len() < effects {
                self.fx.push(ImagePass::new(device, kernel));
            }
        }
    }

    /// This frame's use of the mixer: each layer's pass lent out once.
    pub fn frame(&mut self) -> MixerFrame<'_> {
        MixerFrame {
            kernels: &self.kernels,
            passes: self.passes.iter_mut().map(Some).collect(),
            isf: self.isf.iter_mut().map(|layers| layers.iter_mut().map(Some).collect()).collect(),
            mix: self.mix_kind.and_then(|k| self.kernels[k].as_ref()),
            fx: self.fx.iter_mut().map(Some).collect(),
        }
    }
}

/// ISF transition `file` for layer `layer`, built as an `isf` node would be.
fn isf_transition(gpu: &Gpu, assets: &Assets, file: &str, layer: usize) -> Result<IsfTransition, ShaderError> {
    let located = |message: String| ShaderError { origin: file.to_string(), line: 1, column: 1, message };
    let (technique, declarer) =
        techniques::file_technique(file).ok_or_else(|| located("no technique plays this file".into()))?;
    let declared = (declarer.declare)(assets, file).map_err(located)?;
    let mut decls = (technique.params)();
    decls.extend(declared.params);
    let mut params = ParamSet::new(decls);
    let index = |name: &str| params.index(name).ok_or_else(|| located(format!("an ISF transition needs '{name}'")));
    let (file_param, progress) = (index(declarer.file_param)?, index("progress")?);
    params.set_at(file_param, ParamValue::Text(Text::new(file)));
    params.snap();
    let id = format!("show/layer{}/transition", layer + 1);
    let setup = NodeSetup { gpu, assets, id: &id, output_size: (1920, 1080), msaa: 1, params: &params, seed: 0 };
    let node = (technique.create)(&setup)?;
    Ok(IsfTransition { node, params, progress })
}

/// The mixer during one frame's declaration (see [`Mixer::frame`]).
pub struct MixerFrame<'r> {
    kernels: &'r [Option<ImageKernel>],
    passes: Vec<Option<&'r mut ImagePass>>,
    isf: Vec<Vec<Option<&'r mut IsfTransition>>>,
    mix: Option<&'r ImageKernel>,
    fx: Vec<Option<&'r mut ImagePass>>,
}

impl<'r> MixerFrame<'r> {
    /// Declares layer `layer`'s transition from `from` to `to` at `view`'s progress; returns the
    /// mixed image (`to` when no transition runs, or the layer's pass was used this frame).
    pub fn declare(
        &mut self,
        graph: &mut FrameGraph<'r>,
        layer: usize,
        view: &LayerView,
        from: TextureHandle,
        to: TextureHandle,
    ) -> TextureHandle {
        let Some(kind) = view.kind else { return to };
        if let Some(t) = self.isf.get_mut(kind).and_then(|layers| layers.get_mut(layer)).and_then(Option::take) {
            // The shader's own clock is the transition's: seconds since it began.
            t.params.set_at(t.progress, ParamValue::Float(view.progress.clamp(0.0, 1.0)));
            t.params.snap();
            let time = FrameTime { frame: 0, seconds: f64::from(view.seconds), dt: 0.0, seed: 0 };
            return t.node.add_passes(graph, &t.params, &time, &[from, to]);
        }
        let Some(Some(kernel)) = self.kernels.get(kind) else { return to };
        let Some(pass) = self.passes.get_mut(layer).and_then(Option::take) else { return to };
        let uniforms = TransitionUniforms::new(view.progress, view.seconds, graph.output_size());
        pass.declare(graph, "show/transition", kernel, uniforms, &[from, to])
    }

    /// Declares effect `slot`'s (see [`Show::effect_slot`]) dry/wet mix: `amount` of the way from
    /// `dry` to `wet` in linear light (`wet` if the pass was used this frame).
    pub fn mix(
        &mut self,
        graph: &mut FrameGraph<'r>,
        slot: usize,
        dry: TextureHandle,
        wet: TextureHandle,
        amount: f32,
    ) -> TextureHandle {
        let (Some(kernel), Some(pass)) = (self.mix, self.fx.get_mut(slot).and_then(Option::take)) else { return wet };
        let uniforms = TransitionUniforms::new(amount, 0.0, graph.output_size());
        pass.declare(graph, "show/fx_mix", kernel, uniforms, &[dry, wet])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_layout_matches_the_wgsl_struct() {
        let source = include_str!("../../../shaders/transition.wgsl");
        let size = crate::gpu::wgsl_struct_size(source, "TransitionUniforms");
        assert_eq!(size, Some(size_of::<TransitionUniforms>() as u32));
    }

    #[test]
    fn every_bundled_transition_validates_with_the_entry_point() {
        let base = include_str!("../../../shaders/transition.wgsl");
        for (name, source) in [
            ("crossfade", include_str!("../../../shaders/transition_crossfade.wgsl")),
            ("fade_black", include_str!("../../../shaders/transition_fade_black.wgsl")),
            ("wipe", include_str!("../../../shaders/transition_wipe.wgsl")),
            ("luma", include_str!("../../../shaders/transition_luma.wgsl")),
        ] {
            let text = format!("{base}\n{source}\n{}", entry_point());
            crate::gpu::validate_wgsl(name, &text).unwrap_or_else(|e| panic!("{name}: {e}"));
        }
    }
}
