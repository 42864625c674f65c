//! Parsing and validating a scene file into a [`Scene`] the runtime can instantiate.

use std::collections::{BTreeMap, BTreeSet};

use super::error::{SceneError, SceneErrors, locate};
use super::schema::{AUDIO_BANDS, AudioSource, MidiMapping, OutputFile, SceneFile};
use crate::assets::{AssetKind, Assets};
use crate::params::{Key, Lfo, ParamDecl, ParamSet, ParamType, ParamValue, RawValue, Target, Track, coerce};
use crate::techniques::{self, TechniqueInfo};

/// A validated scene: every name resolved, every value typed.
#[derive(Clone)]
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
    /// OSC addresses declared in the scene's `controls`, besides `/indra/<node>/<param>`.
    pub osc_aliases: Vec<(String, Target)>,
    /// MIDI mappings declared in the scene's `controls`.
    pub midi: Vec<(MidiMapping, Target)>,
    /// For a show: its layers, clips, columns and cues over these nodes (`None`: a scene).
    pub show: Option<std::sync::Arc<super::show::Show>>,
    /// Texture bytes nodes keep beyond their outputs at the scene's size (an ISF node's pass
    /// targets, as its file declares them), counted in [`Scene::texture_bytes`].
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

/// A scene's OSC aliases and MIDI mappings, resolved.
type ControlMaps = (Vec<(String, Target)>, Vec<(MidiMapping, Target)>);

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
}

impl std::fmt::Debug for SceneNode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SceneNode").field("id", &self.id).field("technique", &self.technique.name).finish()
    }
}

impl Scene {
    /// Whether some node samples sound (the audio analysis runs for it).
    pub fn hears_audio(&self) -> bool {
        self.nodes.iter().any(|n| n.hears_audio)
    }

    /// Index of a node by id.
    pub fn node_index(&self, id: &str) -> Option<usize> {
        self.nodes.iter().position(|n| n.id == id)
    }

    /// An upper estimate of the texture memory the scene takes at `size` with its `msaa`: per
    /// node, its output and one working texture in HDR (8 bytes a pixel each) and, when
    /// multisampled, a colour and depth target per sample (12 bytes a pixel-sample). Simulation
    /// buffers are bounded by each technique's parameter ranges instead.
    pub fn texture_bytes(&self, size: (u32, u32)) -> u64 {
        let pixels = u64::from(size.0) * u64::from(size.1);
        let multisampled = if self.msaa > 1 { 12 * u64::from(self.msaa) } else { 0 };
        (self.nodes.len() as u64 * pixels * (16 + multisampled)).saturating_add(self.own_texture_bytes)
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

    /// Adds an output from the command line (`run --output-window`): `source=NODE` (default the
    /// scene's output), `warp=FILE.ron` (a warp node `output<n>` in between, with its corner
    /// addresses), `monitor=N`, `fullscreen`, `ndi=NAME`, `pipewire=NAME`, `headless` — separated
    /// by commas, as a scene's `outputs` has.
    pub fn add_output(&mut self, spec: &str) -> Result<(), String> {
        let mut output = OutputFile::default();
        for part in spec.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            match part.split_once('=').map(|(k, v)| (k.trim(), v.trim().to_string())) {
                Some(("source", v)) => output.source = Some(v),
                Some(("warp", v)) => output.warp = Some(v),
                Some(("monitor", v)) => {
                    output.monitor = Some(v.parse::<usize>().map_err(|_| format!("monitor '{v}' is not a number"))?);
                }
                Some(("ndi", v)) => output.ndi = Some(v),
                Some(("pipewire", v)) => output.pipewire = Some(v),
                None if part == "fullscreen" => output.fullscreen = true,
                None if part == "headless" => output.headless = true,
                _ => {
                    return Err(format!(
                        "'{part}' in output '{spec}': use source=NODE, warp=FILE.ron, monitor=N, fullscreen, ndi=NAME, pipewire=NAME and headless"
                    ));
                }
            }
        }
        self.attach_output(&output)
    }

    /// Adds output `output` (from the scene file's `outputs` or the command line): resolves its
    /// source, puts a warp node `output<n>` in between when it names a warp file, and gives
    /// warped outputs their corner addresses.
    pub(crate) fn attach_output(&mut self, output: &OutputFile) -> Result<(), String> {
        let number = self.outputs.len() + 1;
        let main = &self.nodes[self.output].id;
        let source_id = output.source.clone().unwrap_or_else(|| main.clone());
        let mut node = self
            .node_index(&source_id)
            .ok_or_else(|| format!("output {number}: '{source_id}' is not a node of scene '{}'", self.name))?;
        if let Some(file) = &output.warp {
            let id = format!("output{number}");
            if self.node_index(&id).is_some() {
                return Err(format!("output {number}: the scene already has a node '{id}'"));
            }
            let (technique, edit) = techniques::stage_output()
                .ok_or_else(|| format!("output {number}: this build has no warp technique"))?;
            let mut params = ParamSet::new((technique.params)());
            let index =
                params.index(edit.file).ok_or_else(|| format!("output {number}: the warp has no file parameter"))?;
            params.set_at(index, ParamValue::Text(crate::params::Text::new(file)));
            params.snap();
            let slots = technique.inputs.iter().map(|s| s.to_string()).collect();
            self.nodes.push(SceneNode { id, technique, params, inputs: vec![node], slots, hears_audio: false });
            node = self.nodes.len() - 1;
        }
        if output.headless && output.ndi.is_none() && output.pipewire.is_none() {
            return Err(format!("output {number} is headless and sends nowhere: give it ndi=NAME or pipewire=NAME"));
        }
        self.outputs.push(SceneOutput {
            node,
            monitor: output.monitor,
            fullscreen: output.fullscreen,
            ndi: output.ndi.clone(),
            pipewire: output.pipewire.clone(),
            headless: output.headless,
        });
        self.osc_aliases.retain(|(a, _)| !a.starts_with("/indra/output/"));
        self.osc_aliases.extend(corner_aliases(&self.outputs, &self.nodes));
        Ok(())
    }

    /// Applies `node.param=value` (value: numbers separated by commas, or true/false), as the
    /// CLI's `--set` does. The value is typed and clamped like any other, and it holds: the
    /// scene's tracks, LFOs and sound mappings on that parameter (or on that component, or on the
    /// whole of the vector it is part of) are dropped. MIDI and OSC can still move it.
    pub fn set_from_str(&mut self, assignment: &str) -> Result<(), String> {
        let (target, value) =
            assignment.split_once('=').ok_or_else(|| format!("'{assignment}' is not of the form node.param=value"))?;
        let t = resolve_target(&self.nodes, target).map_err(|e| format!("scene '{}': {e}", self.name))?;
        let params = &mut self.nodes[t.node].params;
        let accepted = match t.component {
            Some(c) => {
                let x = value
                    .trim()
                    .parse::<f32>()
                    .map_err(|_| format!("'{value}' is not a number (a component takes one)"))?;
                params.set_component(t.param, c, x)
            }
            None => {
                let typed = parse_value_override(value, &params.decls()[t.param])?;
                params.set_at(t.param, typed)
            }
        };
        if !accepted {
            return Err(format!("'{value}' is not a finite number ({target})"));
        }
        params.snap();
        // Otherwise an LFO or a track overwrites the value from the first frame on, silently.
        let moves_it = |node: usize, param: usize, component: Option<usize>| {
            node == t.node
                && param == t.param
                && (component.is_none() || t.component.is_none() || component == t.component)
        };
        self.tracks.retain(|b| !moves_it(b.node, b.param, b.component));
        self.lfos.retain(|l| !moves_it(l.target.node, l.target.param, l.target.component));
        self.audio.retain(|a| !moves_it(a.target.node, a.target.param, a.target.component));
        Ok(())
    }
}

/// Parses a command-line value for `decl`: `1.5`; a vector as `1.0,0.3,0.1` or as the tuple
/// a scene file uses, `(1.0, 0.3, 0.1)` or `[1.0, 0.3, 0.1]`; `true`/`false`; an enum option
/// name (quoted or not); any text for text parameters.
pub fn parse_value_override(text: &str, decl: &ParamDecl) -> Result<ParamValue, String> {
    let ty = decl.ty();
    if ty == ParamType::Text {
        // Text is taken as written (`--set title.text=HELLO WORLD`).
        return Ok(ParamValue::Text(crate::params::Text::new(text)));
    }
    let trimmed = text.trim();
    let unwrapped = [('(', ')'), ('[', ']'), ('"', '"')]
        .iter()
        .find_map(|&(open, close)| trimmed.strip_prefix(open)?.strip_suffix(close))
        .unwrap_or(trimmed)
        .trim();
    let raw = match unwrapped {
        "true" => RawValue::Bool(true),
        "false" => RawValue::Bool(false),
        name if ty == ParamType::Enum && decl.option_index(name).is_some() => RawValue::Text(name.into()),
        name if ty == ParamType::Enum && name.parse::<f64>().is_err() => {
            return Err(format!("'{name}' is not one of {}", decl.options.join(", ")));
        }
        list => RawValue::List(
            list.trim_end_matches(',')
                .split(',')
                .map(|x| {
                    x.trim().parse::<f64>().map_err(|_| {
                        format!("'{}' in '{text}' is not a number (write 0.5, 1,0.5 or (1.0, 0.5))", x.trim())
                    })
                })
                .collect::<Result<_, _>>()?,
        ),
    };
    let raw = match raw {
        RawValue::List(v) if v.len() == 1 => RawValue::Number(v[0]),
        other => other,
    };
    coerce(&raw, ty, &decl.options).ok_or_else(|| match ty {
        ParamType::Enum => format!("'{text}' is not one of {}", decl.options.join(", ")),
        _ => format!("'{text}' is not a {ty}"),
    })
}

/// Loads a scene by name or path: an existing file path is read directly, anything else is
/// looked up in `scenes/` (disk first, then the built-in copies).
///
/// A show (`shows/<name>`, or a file whose top level has `layers`) loads as the flat scene of
/// all its clips (see [`super::show`]): every command takes shows where it takes scenes. A file a
/// technique plays (an ISF shader, `.fs`) loads as a scene of its own (see
/// [`techniques::Declarer::scene_for`]).
pub fn load_scene(assets: &Assets, name_or_path: &str) -> Result<Scene, SceneErrors> {
    if names_a_show(name_or_path) {
        return super::show::load_show(assets, name_or_path, false);
    }
    if let Some((_, declarer)) = techniques::file_technique(name_or_path) {
        // A bare shader file (ISF) plays as a generated scene (a filter over a default input).
        let text = (declarer.scene_for)(assets, name_or_path).map_err(|e| {
            SceneErrors(vec![SceneError {
                origin: e.origin,
                line: e.line as usize,
                column: e.column as usize,
                message: e.message,
            }])
        })?;
        return parse_scene_with(assets, name_or_path, &text);
    }
    let path = std::path::Path::new(name_or_path);
    let (origin, source) = if path.is_file() {
        std::fs::read_to_string(path)
            .map(|s| (path.display().to_string(), s))
            .map_err(|e| one_error(name_or_path, format!("cannot read the file: {e}")))?
    } else {
        let asset = assets.load(AssetKind::Scene, name_or_path).map_err(|m| one_error(name_or_path, m))?;
        (asset.origin, asset.source)
    };
    parse_scene_with(assets, &origin, &source)
}

/// Whether `name_or_path` is a show: under `shows/`, or a file whose top level has `layers`.
pub fn names_a_show(name_or_path: &str) -> bool {
    let path = std::path::Path::new(name_or_path);
    if path.is_file() {
        return crate::files::read_limited(path, 4 << 20)
            .is_ok_and(|bytes| super::show::is_show(&String::from_utf8_lossy(&bytes)));
    }
    name_or_path.starts_with("shows/")
}

fn one_error(origin: &str, message: String) -> SceneErrors {
    SceneErrors(vec![SceneError { origin: origin.into(), line: 1, column: 1, message }])
}

/// Parses and validates scene text; `origin` names it in errors. Files that nodes declare their
/// parameters from (ISF shaders) are found through [`Assets::discover`].
pub fn parse_scene(origin: &str, source: &str) -> Result<Scene, SceneErrors> {
    parse_scene_with(&Assets::discover(), origin, source)
}

/// [`parse_scene`] with the files nodes name found through `assets`.
pub fn parse_scene_with(assets: &Assets, origin: &str, source: &str) -> Result<Scene, SceneErrors> {
    let file: SceneFile = read_ron(origin, source)?;
    Validator { origin, source, assets, errors: Vec::new(), more: 0 }.validate(file)
}

/// RON text as `T` (a scene or a show file), a syntax or schema error located in `origin`.
pub(crate) fn read_ron<T: serde::de::DeserializeOwned>(origin: &str, source: &str) -> Result<T, SceneErrors> {
    super::schema::ron_options().from_str(source).map_err(|e| {
        SceneErrors(vec![SceneError {
            origin: origin.into(),
            line: e.span.start.line.max(1),
            column: e.span.start.col.max(1),
            message: e.code.to_string(),
        }])
    })
}

/// What is wrong with the settings a scene and a show both have (each with the field it is
/// at): the size, the name's length (it reaches the window title, which the display server
/// bounds), the sample count, the step and the tempo.
pub(crate) fn header_problems(
    name: &str,
    size: (u32, u32),
    msaa: u32,
    dt: f32,
    bpm: f64,
) -> Vec<(&'static str, String)> {
    let mut problems = Vec::new();
    if size.0 == 0 || size.1 == 0 || size.0 > 16384 || size.1 > 16384 {
        problems.push(("size", format!("size {size:?} must be between 1 and 16384 on each axis")));
    }
    if name.chars().count() > MAX_NAME_CHARS {
        problems.push(("name", format!("the name has {} characters; at most {MAX_NAME_CHARS}", name.chars().count())));
    }
    if ![1, 2, 4, 8].contains(&msaa) {
        problems.push(("msaa", format!("msaa {msaa} must be 1, 2, 4 or 8 samples per pixel")));
    }
    if !(dt > 0.0 && dt <= 1.0) {
        problems.push(("dt", format!("dt {dt} must be in (0, 1] seconds")));
    }
    let (lo, hi) = crate::params::lfo::BPM_RANGE;
    if !(bpm >= lo && bpm <= hi) {
        problems.push(("bpm", format!("bpm {bpm} must be between {lo} and {hi}")));
    }
    problems
}

/// `/indra/output/<n>/corner/<i>` for every output that shows a warp node: a controller can
/// drag corner i (clockwise from the top left) of output n without knowing node ids.
fn corner_aliases(outputs: &[SceneOutput], nodes: &[SceneNode]) -> Vec<(String, Target)> {
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

/// Collects every semantic error of one file, each located by anchors.
struct Validator<'a> {
    origin: &'a str,
    source: &'a str,
    /// Where files that declare a node's parameters are read from.
    assets: &'a Assets,
    errors: Vec<SceneError>,
    /// Errors past [`MAX_REPORTED_ERRORS`], counted only.
    more: usize,
}

impl Validator<'_> {
    fn error(&mut self, anchors: &[&str], message: String) {
        if self.errors.len() >= MAX_REPORTED_ERRORS {
            self.more += 1;
            return;
        }
        let (line, column) = locate(self.source, anchors);
        self.errors.push(SceneError { origin: self.origin.into(), line, column, message });
    }

    /// The errors found, with a last line counting those not reported.
    fn failure(mut self) -> SceneErrors {
        if self.more > 0 {
            let message = format!("… and {} more errors (fix these first)", self.more);
            self.errors.push(SceneError { origin: self.origin.into(), line: 1, column: 1, message });
        }
        SceneErrors(self.errors)
    }

    fn validate(mut self, file: SceneFile) -> Result<Scene, SceneErrors> {
        for (anchor, message) in header_problems(&file.name, file.size, file.msaa, file.dt, file.bpm) {
            self.error(&[anchor], message);
        }
        if file.nodes.len() > MAX_NODES {
            let message = format!("{} nodes; a scene may have at most {MAX_NODES}", file.nodes.len());
            self.error(&["nodes"], message);
            return Err(self.failure());
        }
        let mut nodes = Vec::new();
        let mut seen = BTreeSet::new();
        for node in &file.nodes {
            let anchor = format!("\"{}\"", node.id);
            if !seen.insert(node.id.clone()) {
                self.error(&[&anchor, &anchor], format!("node id '{}' is used twice", node.id));
            }
            if node.id.chars().count() > MAX_ID_CHARS {
                // Ids become OSC addresses, panel labels and GPU labels.
                let length = node.id.chars().count();
                self.error(&[&anchor], format!("a node id of {length} characters; at most {MAX_ID_CHARS}"));
            }
            if let Some(built) = self.node(node, &anchor) {
                if let Some(Err(e)) = built.technique.check.map(|check| check(&built.params)) {
                    self.error(&[&anchor], format!("node '{}': {e}", node.id));
                }
                nodes.push(built);
            }
        }
        let order = self.order_nodes(&file, &mut nodes);
        let output = file.nodes.iter().position(|n| n.id == file.output);
        if output.is_none() {
            let anchor = format!("\"{}\"", file.output);
            self.error(&["output", &anchor], format!("output '{}' is not a node of this scene", file.output));
        }
        if !self.errors.is_empty() || nodes.len() != file.nodes.len() {
            return Err(self.failure());
        }
        // Reorder so that inputs come first; remap input and output indices.
        let position: BTreeMap<usize, usize> = order.iter().enumerate().map(|(new, &old)| (old, new)).collect();
        let mut ordered: Vec<SceneNode> = order.iter().map(|&i| nodes[i].clone()).collect();
        for n in &mut ordered {
            n.inputs = n.inputs.iter().map(|i| position[i]).collect();
        }
        let output = position[&output.expect("checked above")];
        let tracks = self.tracks(&file, &ordered);
        let (osc_aliases, midi) = self.controls(&file, &ordered);
        let lfos = self.lfos(&file, &ordered);
        let audio = self.audio(&file, &ordered);
        if !self.errors.is_empty() {
            return Err(self.failure());
        }
        let own_texture_bytes = own_texture_bytes(self.assets, &ordered, file.size);
        let mut scene = Scene {
            origin: self.origin.into(),
            name: file.name,
            description: file.description,
            size: file.size,
            seed: file.seed,
            dt: file.dt,
            bpm: file.bpm,
            lfos,
            audio,
            msaa: file.msaa,
            nodes: ordered,
            output,
            outputs: Vec::new(),
            tracks,
            osc_aliases,
            midi,
            show: None,
            own_texture_bytes,
        };
        for o in &file.outputs {
            if let Err(e) = scene.attach_output(o) {
                let anchor = format!("\"{}\"", o.source.as_deref().unwrap_or_default());
                self.error(&["outputs", &anchor], e);
            }
        }
        if !self.errors.is_empty() {
            return Err(self.failure());
        }
        if let Err(message) = scene.check_texture_budget(scene.size) {
            self.error(&["size"], message);
            return Err(self.failure());
        }
        Ok(scene)
    }

    /// Binds the LFOs to numeric parameters (or components) with finite ranges and rates.
    fn lfos(&mut self, file: &SceneFile, nodes: &[SceneNode]) -> Vec<Lfo> {
        let mut lfos = Vec::new();
        for l in &file.controls.lfo {
            let anchor = format!("\"{}\"", l.target);
            let anchors = ["lfo", anchor.as_str()];
            let target = match resolve_target(nodes, &l.target) {
                Ok(t) => t,
                Err(e) => {
                    self.error(&anchors, format!("LFO target {e}"));
                    continue;
                }
            };
            let ty = nodes[target.node].params.decls()[target.param].ty();
            if target.component.is_none() && !matches!(ty, ParamType::Float | ParamType::Int) {
                self.error(&anchors, format!("LFO target '{}' is a {ty}: name a number or one component", l.target));
                continue;
            }
            if !(l.range.0.is_finite() && l.range.1.is_finite() && l.phase.is_finite() && l.rate.is_valid()) {
                self.error(
                    &anchors,
                    format!("LFO on '{}' needs a finite range and phase and a positive rate", l.target),
                );
                continue;
            }
            lfos.push(Lfo { target, shape: l.shape, rate: l.rate, range: l.range, phase: l.phase });
        }
        lfos
    }

    /// Binds the audio mappings to numbers, bools, triggers or components.
    fn audio(&mut self, file: &SceneFile, nodes: &[SceneNode]) -> Vec<AudioMapping> {
        let mut out = Vec::new();
        for a in &file.controls.audio {
            let anchor = format!("\"{}\"", a.target);
            let anchors = ["audio", anchor.as_str()];
            let target = match resolve_target(nodes, &a.target) {
                Ok(t) => t,
                Err(e) => {
                    self.error(&anchors, format!("audio mapping {e}"));
                    continue;
                }
            };
            match check_audio(nodes, a, target) {
                Err(p) => self.error(&anchors, format!("audio mapping to '{}': {p}", a.target)),
                Ok(m) => out.push(m),
            }
        }
        out
    }

    /// Resolves OSC aliases and MIDI mappings to parameters.
    fn controls(&mut self, file: &SceneFile, nodes: &[SceneNode]) -> ControlMaps {
        let mut aliases = Vec::new();
        for (address, target) in &file.controls.osc {
            let anchor = format!("\"{address}\"");
            if !address.starts_with('/') {
                self.error(&["controls", &anchor], format!("OSC address '{address}' must start with '/'"));
                continue;
            }
            match resolve_target(nodes, target) {
                Ok(t) => aliases.push((address.clone(), t)),
                Err(e) => self.error(&["controls", &anchor], format!("OSC alias '{address}': {e}")),
            }
        }
        let mut midi = Vec::new();
        for m in &file.controls.midi {
            let anchors = ["controls", "midi", m.target.as_str()];
            let problem = m.problem();
            match (problem, resolve_target(nodes, &m.target)) {
                (Some(p), _) => self.error(&anchors, format!("MIDI mapping to '{}': {p}", m.target)),
                (None, Err(e)) => self.error(&anchors, format!("MIDI mapping: {e}")),
                (None, Ok(t)) => midi.push((m.clone(), t)),
            }
        }
        (aliases, midi)
    }

    /// Checks one node's technique, params, ranges and input names; input indices refer to the
    /// file's node order.
    fn node(&mut self, node: &super::schema::NodeFile, anchor: &str) -> Option<SceneNode> {
        let Some(technique) = techniques::find(&node.technique) else {
            let known: Vec<&str> = techniques::REGISTRY.iter().map(|t| t.name).collect();
            let t_anchor = format!("\"{}\"", node.technique);
            self.error(
                &[anchor, &t_anchor],
                format!("unknown technique '{}' (known: {})", node.technique, known.join(", ")),
            );
            return None;
        };
        let mut decls = (technique.params)();
        let mut slots: Vec<String> = technique.inputs.iter().map(|s| s.to_string()).collect();
        let mut hears_audio = false;
        if let Some(declarer) = technique.declare {
            let file = match node.params.get(declarer.file_param) {
                Some(RawValue::Text(file)) => Some(file.clone()),
                _ => decls.iter().find(|d| d.name == declarer.file_param).and_then(|d| match d.default {
                    ParamValue::Text(t) => Some(t.as_str().to_string()),
                    _ => None,
                }),
            };
            let key = format!("\"{}\"", declarer.file_param);
            match file.map(|f| (declarer.declare)(self.assets, &f)) {
                Some(Ok(declared)) => {
                    decls.extend(declared.params);
                    slots = declared.inputs;
                    hears_audio = declared.hears_audio;
                }
                Some(Err(message)) => {
                    self.error(&[anchor, "params", &key], message);
                    return None;
                }
                None => {
                    self.error(&[anchor], format!("node '{}' needs its '{}' parameter", node.id, declarer.file_param));
                    return None;
                }
            }
        }
        let names: Vec<String> = decls.iter().map(|d| d.name.clone()).collect();
        for (name, (lo, hi)) in &node.ranges {
            let key = format!("\"{name}\"");
            match decls.iter_mut().find(|d| &d.name == name) {
                None => self.error(&[anchor, "ranges", &key], unknown_param(technique, name, &names)),
                Some(_) if !lo.is_finite() || !hi.is_finite() => self.error(
                    &[anchor, "ranges", &key],
                    format!("range of '{name}' must be two finite numbers: ({lo}, {hi})"),
                ),
                Some(_) if lo >= hi => {
                    self.error(&[anchor, "ranges", &key], format!("range of '{name}' is empty: ({lo}, {hi})"))
                }
                Some(d) => d.range = Some((*lo, *hi)),
            }
        }
        for (name, seconds) in &node.smoothing {
            let key = format!("\"{name}\"");
            match decls.iter_mut().find(|d| &d.name == name) {
                None => self.error(&[anchor, "smoothing", &key], unknown_param(technique, name, &names)),
                Some(_) if !(0.0..=60.0).contains(seconds) => self.error(
                    &[anchor, "smoothing", &key],
                    format!("smoothing of '{name}' must be 0–60 s, not {seconds}"),
                ),
                Some(d) => d.smoothing = *seconds,
            }
        }
        for (name, raw) in &node.params {
            let key = format!("\"{name}\"");
            let Some(d) = decls.iter_mut().find(|d| &d.name == name) else {
                self.error(&[anchor, "params", &key], unknown_param(technique, name, &names));
                continue;
            };
            match coerce(raw, d.ty(), &d.options) {
                None => self.error(&[anchor, "params", &key], mismatch(name, d, raw)),
                Some(v) if v.clamped(d.range) != v => self.error(
                    &[anchor, "params", &key],
                    format!("'{name}' = {} is outside its range {:?}", describe(raw), d.range.unwrap_or_default()),
                ),
                Some(v) => d.default = v,
            }
        }
        for slot in node.inputs.keys() {
            if !slots.contains(slot) {
                let key = format!("\"{slot}\"");
                self.error(
                    &[anchor, "inputs", &key],
                    format!("technique '{}' has no input '{slot}' (inputs: {slots:?})", technique.name),
                );
            }
        }
        for slot in &slots {
            if !node.inputs.contains_key(slot) {
                self.error(&[anchor], format!("node '{}' needs its input '{slot}' wired to a node", node.id));
            }
        }
        let params = ParamSet::new(decls);
        Some(SceneNode { id: node.id.clone(), technique, params, inputs: Vec::new(), slots, hears_audio })
    }

    /// Resolves input wiring into each node's `inputs` (file indices) and returns the node
    /// indices in dependency order.
    fn order_nodes(&mut self, file: &SceneFile, nodes: &mut [SceneNode]) -> Vec<usize> {
        let identity: Vec<usize> = (0..file.nodes.len()).collect();
        if nodes.len() != file.nodes.len() {
            return identity;
        }
        let index: BTreeMap<&str, usize> = file.nodes.iter().enumerate().map(|(i, n)| (n.id.as_str(), i)).collect();
        for (i, node) in file.nodes.iter().enumerate() {
            for slot in &nodes[i].slots {
                let Some(source) = node.inputs.get(slot) else {
                    continue;
                };
                match index.get(source.as_str()) {
                    Some(&j) if j != i => nodes[i].inputs.push(j),
                    _ => {
                        let (anchor, s_anchor) = (format!("\"{}\"", node.id), format!("\"{source}\""));
                        let message = format!("input '{slot}' names '{source}', which is not another node");
                        self.error(&[&anchor, "inputs", &s_anchor], message);
                    }
                }
            }
        }
        let mut order = Vec::new();
        let mut placed = vec![false; nodes.len()];
        while order.len() < nodes.len() {
            let ready = (0..nodes.len()).find(|&i| !placed[i] && nodes[i].inputs.iter().all(|&d| placed[d]));
            let Some(next) = ready else {
                let stuck: Vec<&str> = (0..nodes.len()).filter(|&i| !placed[i]).map(|i| nodes[i].id.as_str()).collect();
                self.error(&["nodes"], format!("the wiring of nodes {} forms a cycle", stuck.join(", ")));
                return identity;
            };
            placed[next] = true;
            order.push(next);
        }
        order
    }

    fn tracks(&mut self, file: &SceneFile, nodes: &[SceneNode]) -> Vec<BoundTrack> {
        let mut out = Vec::new();
        for t in &file.tracks {
            let anchor = format!("\"{}\"", t.target);
            let anchors = ["tracks", anchor.as_str()];
            let Target { node, param: pi, component } = match resolve_target(nodes, &t.target) {
                Ok(target) => target,
                Err(e) => {
                    self.error(&anchors, format!("track target {e}"));
                    continue;
                }
            };
            let params = &nodes[node].params;
            let ty = params.decls()[pi].ty();
            let key_type = if component.is_some() { ParamType::Float } else { ty };
            let options = params.decls()[pi].options.clone();
            if t.keys.is_empty() || t.time_scale.is_nan() || t.time_scale <= 0.0 {
                self.error(&anchors, format!("track '{}' needs at least one key and a positive time_scale", t.target));
                continue;
            }
            let mut keys = Vec::new();
            for (time, raw) in &t.keys {
                match coerce(raw, key_type, &options) {
                    Some(value) => keys.push(Key { time: *time, value }),
                    None => self.error(
                        &anchors,
                        format!("track '{}': key at {time} s is {}, expected a {key_type}", t.target, describe(raw)),
                    ),
                }
            }
            let track = Track::new(keys, t.interpolation, t.repeat, t.time_scale);
            out.push(BoundTrack { target: t.target.clone(), node, param: pi, component, track });
        }
        out
    }
}

fn unknown_param(technique: &TechniqueInfo, name: &str, known: &[String]) -> String {
    format!("technique '{}' has no parameter '{name}' (parameters: {})", technique.name, known.join(", "))
}

fn component_index(c: &str, ty: ParamType) -> Option<usize> {
    let i = match c {
        "x" | "r" => 0,
        "y" | "g" => 1,
        "z" | "b" => 2,
        "w" | "a" => 3,
        _ => return None,
    };
    (ty.components() > 1 && i < ty.components()).then_some(i)
}

fn mismatch(name: &str, decl: &ParamDecl, raw: &RawValue) -> String {
    match decl.ty() {
        ParamType::Enum => format!("'{name}' is one of {}, not {}", decl.options.join(", "), describe(raw)),
        ty => format!("'{name}' is a {ty}, not {}", describe(raw)),
    }
}

fn describe(raw: &RawValue) -> String {
    match raw {
        RawValue::Bool(b) => format!("the bool {b}"),
        RawValue::Number(x) => format!("the number {x}"),
        RawValue::List(v) => format!("a list of {} numbers", v.len()),
        RawValue::Text(t) => format!("the text \"{t}\""),
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

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"(
    name: "test",
    size: (64, 32),
    nodes: [
        (id: "k", technique: "kleinian", params: { "scale": 2.0, "t": (1.9, 0.1) }),
    ],
    output: "k",
    tracks: [
        (target: "k.t.y", interpolation: Linear, repeat: Loop, keys: [(0.0, 0.0), (1.0, 0.2)]),
    ],
)"#;

    fn first_error(src: &str) -> SceneError {
        parse_scene("test.ron", src).map(|_| ()).unwrap_err().0.remove(0)
    }

    #[test]
    fn a_valid_scene_resolves_params_and_tracks() {
        let scene = parse_scene("test.ron", GOOD).unwrap();
        assert_eq!(scene.nodes[0].params.get("scale"), ParamValue::Float(2.0));
        assert_eq!(scene.tracks[0].component, Some(1));
        assert_eq!(scene.dt, 1.0 / 60.0);
    }

    #[test]
    fn unknown_field_is_located_by_ron() {
        let e = first_error(&GOOD.replace("size: (64, 32),", "size: (64, 32),\n    colour: 3,"));
        assert_eq!(e.line, 4, "{e}");
        assert!(e.message.contains("colour"), "{e}");
    }

    #[test]
    fn syntax_error_is_located() {
        let e = first_error(&GOOD.replace("output: \"k\",", "output: \"k\""));
        assert!(e.line >= 7, "{e}");
    }

    #[test]
    fn unknown_param_names_the_param_and_its_line() {
        let e = first_error(&GOOD.replace("\"scale\": 2.0", "\"zoom\": 2.0"));
        assert_eq!((e.line, e.column), (5, 52), "{e}");
        assert!(e.message.contains("no parameter 'zoom'") && e.message.contains("scale"), "{e}");
    }

    #[test]
    fn type_mismatch_is_an_error_not_a_default() {
        let e = first_error(&GOOD.replace("\"scale\": 2.0", "\"scale\": (2.0, 1.0)"));
        assert!(e.message.contains("'scale' is a float, not a list of 2 numbers"), "{e}");
        let e = first_error(&GOOD.replace("\"scale\": 2.0", "\"scale\": true"));
        assert!(e.message.contains("float"), "{e}");
        let e = first_error(&GOOD.replace("\"scale\": 2.0", "\"iterations\": 2.5"));
        assert!(e.message.contains("int"), "{e}");
    }

    #[test]
    fn a_range_with_nan_or_infinity_is_a_located_error_not_a_panic() {
        for bad in ["(NaN, 3.0)", "(0.1, inf)", "(-inf, 3.0)"] {
            let src = GOOD.replace(
                "params: { \"scale\": 2.0,",
                &format!("ranges: {{ \"scale\": {bad} }}, params: {{ \"scale\": 2.0,"),
            );
            let e = first_error(&src);
            assert!(e.message.contains("two finite numbers") && e.line > 1, "{bad}: {e}");
        }
    }

    #[test]
    fn thousands_of_mistakes_report_fifty_and_count_the_rest() {
        let params: Vec<String> = (0..5000).map(|i| format!("\"nope_{i}\": 1.0")).collect();
        let src =
            GOOD.replace("params: { \"scale\": 2.0,", &format!("params: {{ {}, \"scale\": 2.0,", params.join(", ")));
        let errors = parse_scene("test.ron", &src).map(|_| ()).unwrap_err().0;
        assert_eq!(errors.len(), MAX_REPORTED_ERRORS + 1);
        assert!(errors.last().unwrap().message.contains("4950 more"), "{}", errors.last().unwrap());
    }

    #[test]
    fn a_scene_with_too_many_nodes_is_refused_at_check_time() {
        let nodes: Vec<String> = (0..=MAX_NODES).map(|i| format!("(id: \"k{i}\", technique: \"kleinian\")")).collect();
        let src = format!("(name: \"many\", size: (64, 64), nodes: [{}], output: \"k0\")", nodes.join(", "));
        let e = first_error(&src);
        assert!(e.message.contains("at most 256"), "{e}");
    }

    #[test]
    fn a_scene_asking_for_too_much_texture_memory_is_refused_at_check_time() {
        let nodes: Vec<String> = (0..100).map(|i| format!("(id: \"k{i}\", technique: \"kleinian\")")).collect();
        let scene = |size: &str, msaa: u32| {
            format!("(name: \"big\", size: {size}, msaa: {msaa}, nodes: [{}], output: \"k0\")", nodes.join(", "))
        };
        // 100 nodes at 4K: 100 × 8.3 Mpx × 16 B = 12.4 GiB without multisampling.
        let e = first_error(&scene("(3840, 2160)", 1));
        assert!(e.message.contains("12.4 GiB") && e.message.contains("at most 8 GiB"), "{e}");
        assert!(parse_scene("ok.ron", &scene("(1920, 1080)", 1)).is_ok(), "100 nodes at 1080p fit (3.1 GiB)");
        let e = first_error(&scene("(1920, 1080)", 8));
        assert!(e.message.contains("msaa 8"), "{e}");
        let one = parse_scene("one.ron", &scene("(64, 64)", 1)).unwrap();
        assert!(one.check_texture_budget((16384, 16384)).is_err(), "an override of the size is checked too");
    }

    #[test]
    fn an_unknown_option_lists_the_options() {
        let decl = ParamDecl::choice("solver", &["verlet", "xpbd"], 0, "");
        assert_eq!(parse_value_override("Bogus", &decl).unwrap_err(), "'Bogus' is not one of verlet, xpbd");
        assert_eq!(parse_value_override("xpbd", &decl), Ok(ParamValue::Enum(1)));
    }

    #[test]
    fn out_of_range_default_is_an_error() {
        let e = first_error(&GOOD.replace("\"scale\": 2.0", "\"scale\": 500.0"));
        assert!(e.message.contains("outside its range"), "{e}");
    }

    #[test]
    fn unknown_technique_output_and_track_targets_are_errors() {
        assert!(
            first_error(&GOOD.replace("\"kleinian\"", "\"kleinain\"")).message.contains("unknown technique 'kleinain'")
        );
        assert!(first_error(&GOOD.replace("output: \"k\"", "output: \"q\"")).message.contains("output 'q'"));
        let e = first_error(&GOOD.replace("k.t.y", "k.scale.y"));
        assert!(e.message.contains("no component 'y'"), "{e}");
        assert_eq!(e.line, 9, "{e}");
        assert!(first_error(&GOOD.replace("k.t.y", "k.tt")).message.contains("no parameter 'tt'"));
    }

    #[test]
    fn every_error_is_reported_not_just_the_first() {
        let src = GOOD.replace("\"scale\": 2.0", "\"zoom\": 2.0").replace("output: \"k\"", "output: \"q\"");
        assert_eq!(parse_scene("test.ron", &src).map(|_| ()).unwrap_err().0.len(), 2);
    }

    #[test]
    fn cli_overrides_are_typed_and_clamped() {
        let mut scene = parse_scene("test.ron", GOOD).unwrap();
        scene.set_from_str("k.samples=10").unwrap();
        scene.set_from_str("k.t=1.5,0.25").unwrap();
        scene.set_from_str("k.iterations=99999").unwrap();
        let p = &scene.nodes[0].params;
        assert_eq!((p.int("samples"), p.vec2("t"), p.int("iterations")), (10, [1.5, 0.25], 5000));
        assert!(scene.set_from_str("k.samples=lots").unwrap_err().contains("not a number"));
        assert!(scene.set_from_str("k.t=1").unwrap_err().contains("vec2"));
        assert!(scene.set_from_str("x.t=1").unwrap_err().contains("no node 'x'"));
    }

    #[test]
    fn every_bundled_scene_is_valid() {
        let assets = Assets::new(None);
        for name in assets.names(AssetKind::Scene) {
            load_scene(&assets, &name).unwrap_or_else(|e| panic!("{e}"));
        }
    }
}
