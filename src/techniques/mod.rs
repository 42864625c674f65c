//! One module per book chapter. A technique declares its parameters and inputs, builds its
//! pipelines once, steps its simulation on the fixed clock and adds passes to the frame graph.
//! It never owns the frame: no encoders, no submits, no windows, no files beyond its shader.
//!
//! A technique is one folder, `src/techniques/<name>/`: its Rust (`mod.rs` with its `INFO`), its
//! shaders (`*.wgsl`, embedded by `build.rs` and loaded by file name, so a performer's file of
//! that name in `shaders/` overrides one), its render tests (`render_tests.rs`, golden renders
//! and invariants through the whole engine, `#[cfg(test)] mod render_tests;`) and their
//! references (`golden/`). Its demo scenes are `scenes/<name>*.ron`. To add one, write the folder
//! and register it here — `pub mod <name>;` and its `INFO` in [`REGISTRY`]. Nothing else (a test
//! checks that every folder is registered and its shaders are built in).

pub mod blend;
pub mod camera;
pub mod cloth;
pub mod cube_field;
pub mod fader;
pub mod grid_fluid;
pub mod image;
pub mod image_pass;
pub mod isf;
pub mod kleinian;
pub mod mesh2d_draw;
pub mod ndi;
pub mod picture_pass;
pub mod poisson;
pub mod polygon_draw;
pub mod runner;
pub mod saved;
pub mod space_colonization;
pub mod splat_draw;
pub mod star_glow;
pub mod tessellation;
pub mod text_mesh;
pub mod video;
pub mod visibility;
pub mod warp;
pub mod wgsl_effect;

use crate::assets::{AssetKind, Assets};
use crate::checkpoint::{CheckpointError, NodeState};
use crate::gpu::{Gpu, ShaderError};
use crate::graph::{FrameGraph, TextureHandle};
use crate::params::{AudioSnapshot, ParamDecl, ParamSet, ParamValue};
use crate::time::FrameTime;

/// Every technique indra knows, by scene name.
pub const REGISTRY: &[TechniqueInfo] = &[
    kleinian::INFO,
    star_glow::INFO,
    cube_field::INFO,
    cloth::INFO,
    poisson::INFO,
    polygon_draw::INFO,
    text_mesh::INFO,
    grid_fluid::INFO,
    tessellation::INFO,
    image::INFO,
    space_colonization::INFO,
    warp::INFO,
    blend::INFO,
    fader::INFO,
    video::INFO,
    camera::INFO,
    ndi::INFO,
    isf::INFO,
    wgsl_effect::INFO,
];

/// Finds a technique by the name scenes use.
pub fn find(name: &str) -> Option<&'static TechniqueInfo> {
    REGISTRY.iter().find(|t| t.name == name)
}

/// What a technique is, before any instance exists.
pub struct TechniqueInfo {
    /// The name scenes use (`technique: "kleinian"`).
    pub name: &'static str,
    /// The book chapter it implements.
    pub chapter: &'static str,
    /// One sentence on what it draws.
    pub summary: &'static str,
    /// Its parameters with defaults and ranges.
    pub params: fn() -> Vec<ParamDecl>,
    /// Names of the textures it takes from upstream nodes, in order.
    pub inputs: &'static [&'static str],
    /// Shader files it loads (checked by `indra check`).
    pub shaders: &'static [&'static str],
    /// Builds an instance (pipelines, persistent resources).
    pub create: fn(&NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError>,
    /// Refuses settings that are each in range but together too costly (a memory budget), in
    /// one sentence; `indra check` and scene loading apply it, and the node keeps to the same
    /// rule when such values arrive live.
    pub check: Option<SettingsCheck>,
    /// For a stage output (a projection-mapping warp): the parameters the scene loader and the
    /// output windows work through — so neither knows a technique by name.
    pub stage: Option<StageEdit>,
    /// For a technique whose parameters and inputs come from a file the node names (an ISF
    /// shader's inputs): the scene loader reads them through it, after `params`.
    pub declare: Option<Declarer>,
}

/// See [`TechniqueInfo::declare`].
#[derive(Clone, Copy)]
pub struct Declarer {
    /// The text parameter naming the file.
    pub file_param: &'static str,
    /// The extensions of such files (`fs`, `glsl`): a file of one named on the command line
    /// plays as a scene of its own, and names a show transition.
    pub extensions: &'static [&'static str],
    /// Reads the file a node names: its parameters and input slots, or one located sentence.
    pub declare: fn(&Assets, &str) -> Result<Declared, String>,
    /// The scene text that plays such a file on its own (inputs wired to default sources).
    pub scene_for: fn(&Assets, &str) -> Result<String, ShaderError>,
    /// The texture bytes a node of the file renders into at a render size, with the file's
    /// defaults (an ISF shader's pass targets, persistent ones twice): counted in the scene's
    /// texture budget.
    pub texture_bytes: fn(&Assets, &str, (u32, u32)) -> u64,
}

/// The technique that plays files like `path` (by extension; see [`Declarer`]).
pub fn file_technique(path: &str) -> Option<(&'static TechniqueInfo, Declarer)> {
    let ext = std::path::Path::new(path).extension()?.to_str()?;
    REGISTRY.iter().find_map(|t| t.declare.filter(|d| d.extensions.contains(&ext)).map(|d| (t, d)))
}

/// What a file declares for a node (see [`Declarer`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Declared {
    /// Parameters, after the technique's own.
    pub params: Vec<ParamDecl>,
    /// Texture inputs, in order (the node's input slots).
    pub inputs: Vec<String>,
    /// Whether the node samples sound ([`Technique::hear`]): the scene then runs the audio
    /// analysis even where no parameter is mapped to it.
    pub hears_audio: bool,
}

/// The parameters, by name, of a technique that maps an image onto a wall: what an output's
/// `warp: FILE` sets, what `/indra/output/<n>/corner/<i>` drives, what an output window's edit
/// mode drags, shows and saves.
#[derive(Clone, Copy, Debug)]
pub struct StageEdit {
    /// The text parameter naming the file it reads its settings from.
    pub file: &'static str,
    /// The four corner parameters (`vec2`, view units), clockwise from the top left.
    pub corners: [&'static str; 4],
    /// A `vec3` parameter (index, x, y) moving one mesh point (see [`Technique::handles`]).
    pub mesh_point: &'static str,
    /// A bool parameter showing the mesh.
    pub grid: &'static str,
    /// A trigger parameter saving the file.
    pub save: &'static str,
}

/// The technique that maps a scene's outputs onto walls, and its parameters (see [`StageEdit`]).
pub fn stage_output() -> Option<(&'static TechniqueInfo, StageEdit)> {
    REGISTRY.iter().find_map(|t| t.stage.map(|edit| (t, edit)))
}

/// See [`TechniqueInfo::check`]: `Err` says in one sentence what does not fit.
pub type SettingsCheck = fn(&ParamSet) -> Result<(), String>;

/// What a technique gets when an instance is created.
pub struct NodeSetup<'a> {
    /// The device.
    pub gpu: &'a Gpu,
    /// Where to load shaders from.
    pub assets: &'a Assets,
    /// The node's id in the scene (for labels).
    pub id: &'a str,
    /// The scene's output size.
    pub output_size: (u32, u32),
    /// Samples per pixel the scene asks rasterising nodes for (see [`NodeSetup::samples_for`]).
    pub msaa: u32,
    /// The node's parameters now: a node builds its state from them, so that state exists from
    /// the start (later changes reach it in `step`).
    pub params: &'a ParamSet,
    /// The scene seed (what [`FrameTime::seed`] will be).
    pub seed: u64,
}

impl NodeSetup<'_> {
    /// What `rasterizer: auto` takes in `technique` on this adapter (see [`NodeSetup::tuned`]).
    pub fn tuned_rasterizer(&self, technique: &str) -> Rasterizer {
        self.tuned(technique, "rasterizer").unwrap_or(Rasterizer::Auto)
    }

    /// The option of `technique`'s enum parameter `param` that `indra tune` measured fastest on
    /// this adapter (what the parameter's `auto` takes), if it measured one.
    pub fn tuned<E: crate::params::ParamEnum>(&self, technique: &str, param: &str) -> Option<E> {
        let name = self.gpu.tuning.choice(technique, param)?;
        let index = E::OPTIONS.iter().position(|option| *option == name)?;
        Some(E::from_index(index as u32))
    }

    /// The scene's sample count, lowered to the largest this adapter can render and resolve for
    /// every format in `formats` (colour targets and depth), at least 1.
    pub fn samples_for(&self, formats: &[wgpu::TextureFormat]) -> u32 {
        // Without the adapter-specific feature the device allows WebGPU's guaranteed counts only.
        let specific = self.gpu.device.features().contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES);
        let supported = |n: u32| {
            (specific || n == 4)
                && formats.iter().all(|f| {
                    let features = self.gpu.adapter.get_texture_format_features(*f);
                    let resolvable = f.is_depth_stencil_format()
                        || features.flags.contains(wgpu::TextureFormatFeatureFlags::MULTISAMPLE_RESOLVE);
                    features.flags.sample_count_supported(n) && resolvable
                })
        };
        [8, 4, 2].into_iter().find(|&n| n <= self.msaa && supported(n)).unwrap_or(1)
    }

    /// Loads a shader file's text and origin, turning a missing file into a located error, and
    /// checks that each `(name, binding)` the technique binds in group 0 is where the WGSL
    /// declares it (naga reflection): layouts and shaders cannot drift apart, also when a shader
    /// is edited live — a mismatch is a located error and the last good version keeps running.
    pub fn shader_source(&self, file: &str, bindings: &[(&str, u32)]) -> Result<(String, String), ShaderError> {
        let (origin, source) = self.load_shader(file)?;
        crate::gpu::check_bindings(&origin, &source, bindings)?;
        Ok((origin, source))
    }

    /// A shader joined after the files it extends (`// extends: NAME` at its top), checked like
    /// [`Self::shader_source`]; errors are located in the file they come from.
    pub fn joined_shader_source(
        &self,
        file: &str,
        bindings: &[(&str, u32)],
    ) -> Result<crate::gpu::JoinedSource, ShaderError> {
        let (origin, source) = self.load_shader(file)?;
        let joined = crate::gpu::JoinedSource::with_bases(&origin, &source, |base| {
            self.load_shader(base).map_err(|e| e.message)
        })
        .map_err(|message| ShaderError { origin: origin.clone(), line: 1, column: 1, message })?;
        crate::gpu::check_bindings(joined.origin(), &joined.source, bindings).map_err(|e| joined.relocate(e))?;
        Ok(joined)
    }

    fn load_shader(&self, file: &str) -> Result<(String, String), ShaderError> {
        self.assets.load(AssetKind::Shader, file).map(|a| (a.origin, a.source)).map_err(|message| ShaderError {
            origin: file.into(),
            line: 1,
            column: 1,
            message,
        })
    }
}

/// A live instance of a technique inside a scene.
pub trait Technique: Send {
    /// Advances the simulation by one fixed step (no-op for stateless techniques).
    fn step(&mut self, _params: &ParamSet, _time: &FrameTime) {}

    /// Whether `add_passes` records simulation work that every fixed step needs (state on the
    /// GPU, like cloth). Frames skipped by a seek then still build a simulation-only graph, so
    /// frame N is the same bytes played or sought. CPU state advanced in `step` needs nothing.
    fn simulates_on_gpu(&self) -> bool {
        false
    }

    /// Where a pointer at `view` (0–1 on the output, y up) lands in this node's input texture
    /// (UV 0–1, y up), if the node draws its input on a surface — so that a cursor-driven
    /// upstream node (a fluid) is stirred under the pointer. `None`: not such a node, or a miss.
    fn map_pointer(&self, _view: [f32; 2]) -> Option<[f32; 2]> {
        None
    }

    /// Figures for `indra bench` to print after measuring (e.g. triangles generated). May read
    /// back from the GPU: never called in the frame loop.
    fn bench_report(&mut self) -> Vec<String> {
        Vec::new()
    }

    /// Parameter values the node read from a file since the last call (a warp file's corners):
    /// the scene sets them after the step, as a preset recall would, so the panel, OSC feedback
    /// and saves see them.
    fn take_loaded_values(&mut self) -> Vec<(&'static str, ParamValue)> {
        Vec::new()
    }

    /// Points of this node a performer may drag in an output window (a warp's mesh control
    /// points), in view units; their order is the index the node's edit parameters take.
    fn handles(&self) -> Vec<[f32; 2]> {
        Vec::new()
    }

    /// A line the panel shows under the node's name while it runs (a clip's codec, frame and
    /// late frames), or `None`.
    fn status(&self) -> Option<String> {
        None
    }

    /// What the audio analysis heard this frame (only nodes that sample sound use it; the
    /// scene asks for it through [`Declared::hears_audio`]).
    fn hear(&mut self, _audio: &AudioSnapshot) {}

    /// Things to tell the performer since the last call (e.g. "the cloth blew up and was reset").
    fn take_messages(&mut self) -> Vec<String> {
        Vec::new()
    }

    /// Writes what survives a frame — GPU buffers and textures read back, CPU simulation state —
    /// into `state`, for a checkpoint. Called between frames with every step recorded and the GPU
    /// idle. The default saves nothing: the node is a function of its parameters and the time.
    fn save_state(&self, _gpu: &Gpu, _state: &mut NodeState) -> Result<(), CheckpointError> {
        Ok(())
    }

    /// Puts back what [`Technique::save_state`] wrote, into a node just created for the same
    /// scene; `params` and `time` are the checkpoint's (its last step), so a node sized by its
    /// parameters is first brought to that size.
    fn load_state(
        &mut self,
        _gpu: &Gpu,
        _params: &ParamSet,
        _time: &FrameTime,
        _state: &NodeState,
    ) -> Result<(), CheckpointError> {
        Ok(())
    }

    /// Adds this frame's passes; returns the texture downstream nodes (or the output) see.
    fn add_passes<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        params: &ParamSet,
        time: &FrameTime,
        inputs: &[TextureHandle],
    ) -> TextureHandle;
}

/// Converts one sRGB-encoded channel (as colour pickers and scene files give) to linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

crate::param_enum! {
    /// An `msaa` parameter: whether a node draws at the scene's sample count or at one sample
    /// (faster where fill is slow).
    pub enum Msaa {
        /// One sample.
        Off = "off",
        /// The scene's samples.
        On = "on",
    }
}

impl Msaa {
    /// The samples a draw uses: `scene_samples` when on, else 1.
    pub fn samples(self, scene_samples: u32) -> u32 {
        if self == Msaa::On { scene_samples } else { 1 }
    }
}

crate::param_enum! {
    /// A `rasterizer` parameter: how a node that draws geometry fills its pixels.
    pub enum Rasterizer {
        /// What `indra tune` measured fastest on this adapter; compute where it measured nothing.
        Auto = "auto",
        /// In compute, through a visibility buffer (64-bit atomics), where the adapter allows:
        /// on GPUs whose raster path is narrow (the H100/H200) a multisampled 4K target costs
        /// ~6 ms to clear and resolve before anything is drawn.
        Compute = "compute",
        /// The hardware rasterizer.
        Pipeline = "pipeline",
    }
}

impl Rasterizer {
    /// Whether a node draws in compute (where it can): `auto` stands for `tuned`, what the
    /// node took from [`NodeSetup::tuned`] when it was made.
    pub fn in_compute(self, tuned: Rasterizer) -> bool {
        match self {
            Rasterizer::Auto => tuned != Rasterizer::Pipeline,
            Rasterizer::Compute => true,
            Rasterizer::Pipeline => false,
        }
    }
}

/// An sRGB-encoded colour (as colour pickers and scene files give) in linear light; alpha as is.
pub fn linear_rgba(c: [f32; 4]) -> [f32; 4] {
    [srgb_to_linear(c[0]), srgb_to_linear(c[1]), srgb_to_linear(c[2]), c[3]]
}
