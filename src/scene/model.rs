//! A validated scene, as the runtime instantiates it: its nodes with typed parameters, its
//! outputs, mappings and tracks, the limits a scene is held to, and what its textures cost.

use super::schema::{AUDIO_BANDS, AudioSource, MidiMapping};
use crate::assets::Assets;
use crate::params::{Lfo, ParamSet, ParamType, ParamValue, Target, Track};
use crate::techniques::TechniqueInfo;

/// The longest scene name (it becomes the window title).
pub const MAX_NAME_CHARS: usize = 200;

/// The longest node id (ids become OSC addresses and labels).
pub const MAX_ID_CHARS: usize = 64;

/// Errors located and reported per file; the rest are counted. Locating scans the source, so a
/// file with tens of thousands of mistakes would otherwise take quadratic time to check.
pub(crate) const MAX_REPORTED_ERRORS: usize = 50;
/// Most nodes a scene may have (each builds pipelines and textures): a bound that `check` reports,
/// rather than a render that runs out of memory.
pub const MAX_NODES: usize = 256;
/// Most texture memory a scene may ask for (see [`Scene::texture_bytes`]): a bound `check`
/// reports, rather than a render that exhausts the machine's memory.
pub const MAX_TEXTURE_BYTES: u64 = 8 << 30;

/// A validated scene: every name resolved, every value typed.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Where it was loaded from.
    pub origin: String,
    /// Display name.
    pub name: String,
    /// One line on what it shows.
    pub description: String,
    /// Default output size.
    pub size: (u32, u32),
    /// Seed of all randomness.
    pub seed: u64,
    /// Fixed step, seconds.
    pub dt: f32,
    /// Tempo at start, beats per minute.
    pub bpm: f64,
    /// LFOs bound to parameters.
    pub lfos: Vec<Lfo>,
    /// Audio analysis bound to parameters.
    pub audio: Vec<AudioMapping>,
    /// Samples per pixel wanted for rasterising nodes (1, 2, 4 or 8; the adapter may allow fewer).
    pub msaa: u32,
    /// Nodes in dependency order (inputs before their consumers).
    pub nodes: Vec<SceneNode>,
    /// Index of the output node in `nodes`.
    pub output: usize,
    /// Tracks bound to node parameters.
    pub tracks: Vec<BoundTrack>,
    /// More outputs (windows; `render --output N`), numbered from 1.
    pub outputs: Vec<SceneOutput>,
    /// The DMX patch file the scene names (`dmx:`), as written; `--dmx-out` overrides it.
    pub dmx: Option<String>,
    /// The DMX-in file the scene names (`dmx_in:`), as written; `--dmx-in` overrides it.
    pub dmx_in: Option<String>,
    /// OSC addresses declared in the scene's `controls`, besides `/indra/<node>/<param>`.
    pub osc_aliases: Vec<(String, Target)>,
    /// MIDI mappings declared in the scene's `controls`.
    pub midi: Vec<(MidiMapping, Target)>,
    /// For a show: its layers, clips, columns and cues over these nodes (`None`: a scene).
    pub show: Option<std::sync::Arc<super::show::Show>>,
    /// Texture bytes nodes keep beyond their outputs at the size the scene was loaded to render
    /// at (an ISF node's pass targets, as its file declares them), counted in
    /// [`Scene::texture_bytes`].
    pub own_texture_bytes: u64,
}

/// An audio mapping, resolved (see the scene file's `controls.audio`).
#[derive(Clone, Debug, PartialEq)]
pub struct AudioMapping {
    /// What it follows.
    pub source: AudioSource,
    /// The parameter it writes.
    pub target: Target,
    /// Values at silence and at full scale.
    pub range: (f32, f32),
    /// Rise time, seconds.
    pub attack: f32,
    /// Fall time, seconds.
    pub release: f32,
}

/// One more output of a scene, resolved.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneOutput {
    /// Index of the node it shows.
    pub node: usize,
    /// Monitor for its window.
    pub monitor: Option<usize>,
    /// Borderless fullscreen on that monitor.
    pub fullscreen: bool,
    /// The NDI source its image is also sent as.
    pub ndi: Option<String>,
    /// The PipeWire video source its image is also offered as.
    pub pipewire: Option<String>,
    /// No window: the output only feeds its sends.
    pub headless: bool,
}

/// The audio mapping `a` binds to `target` among `nodes`, or why it cannot (the target's type,
/// a band that does not exist, a range or time that is not a number).
pub fn check_audio(nodes: &[SceneNode], a: &super::schema::AudioFile, target: Target) -> Result<AudioMapping, String> {
    let ty = nodes[target.node].params.decls()[target.param].ty();
    if !(target.component.is_some() || ty.is_scalar()) {
        return Err(format!("'{}' is a {ty}: name a number, a bool, a trigger or one component", a.target));
    }
    if matches!(a.source, AudioSource::Band(b) if usize::from(b) >= AUDIO_BANDS) {
        return Err(format!("there are {AUDIO_BANDS} bands, Band(0) to Band({})", AUDIO_BANDS - 1));
    }
    if ![a.range.0, a.range.1, a.attack, a.release].iter().all(|v| v.is_finite()) || a.attack < 0.0 || a.release < 0.0 {
        return Err("range must be finite and attack and release 0 or more seconds".into());
    }
    Ok(AudioMapping { source: a.source, target, range: a.range, attack: a.attack, release: a.release })
}

/// Resolves `node.param` or `node.param.<x|y|z|w|r|g|b|a>` against validated nodes.
pub fn resolve_target(nodes: &[SceneNode], target: &str) -> Result<Target, String> {
    let mut parts = target.split('.');
    let (node_id, param, component) = (parts.next().unwrap_or(""), parts.next().unwrap_or(""), parts.next());
    if parts.next().is_some() {
        return Err(format!("'{target}' is not node.param or node.param.component"));
    }
    let node = nodes.iter().position(|n| n.id == node_id).ok_or_else(|| {
        let ids: Vec<&str> = nodes.iter().map(|n| n.id.as_str()).collect();
        format!("no node '{node_id}' (nodes: {})", ids.join(", "))
    })?;
    let params = &nodes[node].params;
    let index = params.index(param).ok_or_else(|| {
        let names: Vec<String> = params.decls().iter().map(|d| d.name.clone()).collect();
        unknown_param(nodes[node].technique, param, &names)
    })?;
    let ty = params.decls()[index].ty();
    let component = match component {
        None => None,
        Some(c) => Some(component_index(c, ty).ok_or_else(|| format!("'{target}': a {ty} has no component '{c}'"))?),
    };
    Ok(Target { node, param: index, component })
}

/// One technique instance of a validated scene.
#[derive(Clone)]
pub struct SceneNode {
    /// Unique id.
    pub id: String,
    /// The technique.
    pub technique: &'static TechniqueInfo,
    /// Declarations (with the scene's defaults and ranges) and start values.
    pub params: ParamSet,
    /// Upstream node indices, in the order of `slots`.
    pub inputs: Vec<usize>,
    /// The names of its texture inputs: the technique's, or what its file declares (ISF).
    pub slots: Vec<String>,
    /// Whether it samples sound (see [`techniques::Declared::hears_audio`]).
    pub hears_audio: bool,
}

/// A track resolved to a parameter (or one of its components).
#[derive(Clone, Debug)]
pub struct BoundTrack {
    /// The target as written (`node.param[.c]`).
    pub target: String,
    /// Node index.
    pub node: usize,
    /// Parameter index within the node.
    pub param: usize,
    /// Component index, for targets like `t.x`.
    pub component: Option<usize>,
    /// The keys.
    pub track: Track,
    /// Whether it runs on the show's clock (a timeline lane) rather than its node's (a clip's
    /// own track restarts with the clip).
    pub show_clock: bool,
    /// Whether its key times are beats of the show's tempo (read at the beat position) rather
    /// than seconds.
    pub beats: bool,
}

impl std::fmt::Debug for SceneNode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SceneNode")
            .field("id", &self.id)
            .field("technique", &self.technique.name)
            .field("params", &self.params)
            .field("inputs", &self.inputs)
            .field("slots", &self.slots)
            .field("hears_audio", &self.hears_audio)
            .finish()
    }
}

impl Scene {
    /// The timecode its show's timeline chases, if it says.
    pub fn chase(&self) -> Option<crate::timecode::chase::ChaseSettings> {
        self.show.as_ref().and_then(|show| show.timeline.chase)
    }

    /// Whether some node samples sound (the audio analysis runs for it).
    pub fn hears_audio(&self) -> bool {
        self.nodes.iter().any(|n| n.hears_audio)
    }

    /// Index of a node by id.
    pub fn node_index(&self, id: &str) -> Option<usize> {
        self.nodes.iter().position(|n| n.id == id)
    }

    /// An upper estimate of the texture memory the scene takes at `size` with its `msaa`: per
    /// node that can draw in one frame, its output and one working texture in HDR (8 bytes a
    /// pixel each); when multisampled, two sets of a colour and a depth target per sample (12
    /// bytes a pixel-sample) — a pass resolves its targets and gives them back to the frame's
    /// pool, so nodes drawing one after another share them; and what nodes keep (see
    /// [`Scene::own_texture_bytes`]). In a show only the clips that can be on screen at once
    /// draw ([`super::show::Show::nodes_drawn_at_once`]). Simulation buffers are bounded by each
    /// technique's parameter ranges instead.
    pub fn texture_bytes(&self, size: (u32, u32)) -> u64 {
        let drawn = self.show.as_deref().map_or(self.nodes.len(), |show| show.nodes_drawn_at_once(self.nodes.len()));
        self.texture_bytes_of(drawn, size).saturating_add(self.own_texture_bytes)
    }

    /// The per-frame texture bytes of `nodes` drawing nodes at `size` (without what nodes keep).
    pub fn texture_bytes_of(&self, nodes: usize, size: (u32, u32)) -> u64 {
        let pixels = u64::from(size.0) * u64::from(size.1);
        let multisampled = if self.msaa > 1 { 12 * u64::from(self.msaa) } else { 0 };
        let sets = nodes.min(2) as u64;
        (nodes as u64).saturating_mul(pixels * 16).saturating_add(sets * pixels * multisampled)
    }

    /// Whether the scene fits [`MAX_TEXTURE_BYTES`] at `size`; the error says what to lower.
    pub fn check_texture_budget(&self, size: (u32, u32)) -> Result<(), String> {
        let bytes = self.texture_bytes(size);
        if bytes <= MAX_TEXTURE_BYTES {
            return Ok(());
        }
        let gib = |b: u64| b as f64 / f64::from(1u32 << 30);
        Err(format!(
            "{} nodes at {}x{} with msaa {} need about {:.1} GiB of textures; a scene may use at most {:.0} GiB (lower the size, the msaa or the number of nodes)",
            self.nodes.len(),
            size.0,
            size.1,
            self.msaa,
            gib(bytes),
            gib(MAX_TEXTURE_BYTES)
        ))
    }
}

/// The texture bytes `nodes` keep beyond their outputs at `size` (see [`Scene::own_texture_bytes`]).
pub(crate) fn own_texture_bytes(assets: &Assets, nodes: &[SceneNode], size: (u32, u32)) -> u64 {
    let declared = |n: &SceneNode| {
        let declarer = n.technique.declare?;
        let index = n.params.index(declarer.file_param)?;
        let ParamValue::Text(file) = n.params.value_at(index) else { return None };
        Some((declarer.texture_bytes)(assets, file.as_str(), size))
    };
    nodes.iter().filter_map(declared).fold(0, u64::saturating_add)
}

/// `/indra/output/<n>/corner/<i>` for every output that shows a warp node: a controller can
/// drag corner i (clockwise from the top left) of output n without knowing node ids.
pub(super) fn corner_aliases(outputs: &[SceneOutput], nodes: &[SceneNode]) -> Vec<(String, Target)> {
    let mut aliases = Vec::new();
    for (i, output) in outputs.iter().enumerate() {
        let node = &nodes[output.node];
        let Some(edit) = node.technique.stage else { continue };
        for (c, name) in edit.corners.iter().enumerate() {
            if let Some(param) = node.params.index(name) {
                aliases.push((
                    format!("/indra/output/{}/corner/{c}", i + 1),
                    Target { node: output.node, param, component: None },
                ));
            }
        }
    }
    aliases
}

pub(super) fn unknown_param(technique: &TechniqueInfo, name: &str, known: &[String]) -> String {
    format!("technique '{}' has no parameter '{name}' (parameters: {})", technique.name, known.join(", "))
}

/// The index of component `c` (`x`/`r` … `w`/`a`) of a parameter of type `ty`, if it has one.
pub(super) fn component_index(c: &str, ty: ParamType) -> Option<usize> {
    let i = match c {
        "x" | "r" => 0,
        "y" | "g" => 1,
        "z" | "b" => 2,
        "w" | "a" => 3,
        _ => return None,
    };
    (ty.components() > 1 && i < ty.components()).then_some(i)
}
