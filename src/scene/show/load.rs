//! Reading a show file into one flat [`Scene`]: each clip's scene loaded and validated on its
//! own, its nodes renamed `<clip>/<node>` and appended, then one `blend` node per layer and the
//! `master` fader. Errors are located in the show file (a broken clip's scene error is quoted
//! at the clip).

use std::collections::BTreeSet;
use std::path::Path;
use std::sync::Arc;

use super::effects::chain_nodes;
use super::file::{ClipFile, CueFile, EffectFile, Hold, ShowFile, TransitionFile};
use super::{
    Clip, Cue, CueNotes, Layer, Length, MAX_CLIPS_PER_LAYER, MAX_CUES, MAX_LAYERS, Show, ShowSource, Transition,
};
use crate::assets::{AssetKind, Assets};
use crate::params::{ParamSet, ParamValue, Target, coerce};
use crate::scene::error::{SceneError, SceneErrors, locate};
use crate::scene::load::{load_scene, names_a_show, read_ron};
use crate::scene::model::{MAX_NODES, MAX_REPORTED_ERRORS, Scene, SceneNode, resolve_target};
use crate::scene::validate::header_problems;
use crate::techniques::{blend, fader};

/// Ids a clip may not take: the show's own addresses start with them.
const RESERVED_IDS: [&str; 9] = ["layer", "master", "column", "cue", "output", "preset", "record", "tempo", "resume"];

/// The longest clip id.
const MAX_CLIP_ID_CHARS: usize = 32;

/// The longest transition, seconds or beats (an hour).
const MAX_TRANSITION: f64 = 3600.0;

/// Loads a show by name (`shows/`) or path. `lenient`: a clip whose scene is missing or broken
/// is left out with its reason in [`Show::broken`] (a running show plays the rest); otherwise it
/// is an error located at the clip.
pub fn load_show(assets: &Assets, name_or_path: &str, lenient: bool) -> Result<Scene, SceneErrors> {
    let path = Path::new(name_or_path);
    let one =
        |message: String| SceneErrors(vec![SceneError { origin: name_or_path.into(), line: 1, column: 1, message }]);
    let (origin, source) = if path.is_file() {
        let bytes = crate::files::read_limited(path, SHOW_FILE_LIMIT).map_err(|e| one(format!("cannot read {e}")))?;
        (path.display().to_string(), String::from_utf8_lossy(&bytes).into_owned())
    } else {
        let name = name_or_path.strip_prefix("shows/").unwrap_or(name_or_path);
        let asset = assets.load(AssetKind::Show, name).map_err(one)?;
        (asset.origin, asset.source)
    };
    parse_show(assets, &origin, &source, lenient)
}

/// The largest show file read.
const SHOW_FILE_LIMIT: u64 = 4 << 20;

/// Parses and validates show text; `origin` names it in errors and places relative clip paths.
pub fn parse_show(assets: &Assets, origin: &str, source: &str, lenient: bool) -> Result<Scene, SceneErrors> {
    build_show(assets, origin, source, read_ron(origin, source)?, lenient)
}

/// Validates a parsed show file (`source` is the text errors are located in; it may be older
/// than `file`, for a show edited live).
pub fn build_show(
    assets: &Assets,
    origin: &str,
    source: &str,
    file: ShowFile,
    lenient: bool,
) -> Result<Scene, SceneErrors> {
    let mut builder =
        Builder { assets, origin, source, errors: Vec::new(), lenient, kinds: Vec::new(), effects: Vec::new() };
    let scene = builder.build(file);
    match scene {
        Some(scene) if builder.errors.is_empty() => Ok(scene),
        _ => Err(SceneErrors(builder.errors)),
    }
}

struct Builder<'a> {
    assets: &'a Assets,
    origin: &'a str,
    source: &'a str,
    errors: Vec<SceneError>,
    lenient: bool,
    kinds: Vec<String>,
    /// Every effect node appended so far, ascending.
    effects: Vec<usize>,
}

impl Builder<'_> {
    fn error(&mut self, anchors: &[&str], message: String) {
        if self.errors.len() < MAX_REPORTED_ERRORS {
            let (line, column) = locate(self.source, anchors);
            self.errors.push(SceneError { origin: self.origin.into(), line, column, message });
        }
    }

    fn build(&mut self, file: ShowFile) -> Option<Scene> {
        self.check_header(&file);
        if file.layers.is_empty() || file.layers.len() > MAX_LAYERS {
            self.error(&["layers"], format!("{} layers; a show has 1 to {MAX_LAYERS}", file.layers.len()));
            return None;
        }
        let default = self.transition(&file.transition, &["transition"]).unwrap_or(Transition {
            kind: None,
            length: Length::Seconds(0.0),
            quantize: Default::default(),
        });
        let mut nodes: Vec<SceneNode> = Vec::new();
        let mut tracks = Vec::new();
        let mut lfos = Vec::new();
        let mut audio = Vec::new();
        let mut clips = Vec::new();
        let mut layers = Vec::new();
        let mut broken = Vec::new();
        let mut sources = vec![self.origin.to_string()];
        let mut ids = BTreeSet::new();
        for (l, layer) in file.layers.iter().enumerate() {
            let anchor = ["layers", "clips"];
            let name = if layer.name.is_empty() { format!("layer {}", l + 1) } else { layer.name.clone() };
            if layer.clips.len() > MAX_CLIPS_PER_LAYER {
                self.error(
                    &anchor,
                    format!("layer {} has {} clips; at most {MAX_CLIPS_PER_LAYER}", l + 1, layer.clips.len()),
                );
                // The layer stays, empty, so that every later index by layer holds.
                layers.push(Layer { name, node: usize::MAX, clips: Vec::new(), start: None, effects: Vec::new() });
                continue;
            }
            let layer_transition = match &layer.transition {
                Some(t) => self.transition(t, &["layers", "transition"]).unwrap_or(default),
                None => default,
            };
            let mut in_layer = Vec::new();
            for clip in &layer.clips {
                let scene_anchor = format!("\"{}\"", clip.scene);
                let id = clip_id(clip);
                if let Some(problem) = id_problem(&id) {
                    self.error(&[&scene_anchor], format!("clip '{id}': {problem}"));
                    continue;
                }
                if !ids.insert(id.clone()) {
                    self.error(
                        &[&scene_anchor, &scene_anchor],
                        format!("clip id '{id}' is used twice; give one clip an `id`"),
                    );
                    continue;
                }
                let transition = match &clip.transition {
                    Some(t) => self.transition(t, &[&scene_anchor, "transition"]).unwrap_or(layer_transition),
                    None => layer_transition,
                };
                if let Some(problem) = note_problem(clip) {
                    self.error(&[&scene_anchor, "note"], format!("clip '{id}': {problem}"));
                }
                let offset = nodes.len();
                let output = match self.clip_scene(clip) {
                    Ok(scene) => {
                        sources.push(scene.origin.clone());
                        for mut t in scene.tracks {
                            t.node += offset;
                            tracks.push(t);
                        }
                        for mut lfo in scene.lfos {
                            lfo.target.node += offset;
                            lfos.push(lfo);
                        }
                        for mut a in scene.audio {
                            a.target.node += offset;
                            audio.push(a);
                        }
                        for mut node in scene.nodes {
                            node.id = format!("{id}/{}", node.id);
                            node.inputs.iter_mut().for_each(|i| *i += offset);
                            nodes.push(node);
                        }
                        let chain = self.chain(&id, &clip.effects, &mut nodes, Some(offset + scene.output));
                        Some(chain.last().copied().unwrap_or(offset + scene.output))
                    }
                    Err(message) if self.lenient => {
                        broken.push((id.clone(), message));
                        None
                    }
                    Err(message) => {
                        self.error(&[&scene_anchor], format!("clip '{id}': {message}"));
                        None
                    }
                };
                in_layer.push(clips.len());
                clips.push(Clip {
                    id,
                    scene: clip.scene.clone(),
                    layer: l,
                    nodes: offset..nodes.len(),
                    output,
                    policy: clip.policy,
                    transition,
                    note: clip.note.map(|n| (clip.channel, n)),
                });
            }
            let start = match layer.start {
                Some(0) => None,
                Some(n) if n as usize <= in_layer.len() => Some(n as usize - 1),
                Some(n) => {
                    self.error(
                        &["start"],
                        format!("layer {}: start clip {n}, but it has {} clips", l + 1, in_layer.len()),
                    );
                    None
                }
                None if file.cues.is_empty() && !in_layer.is_empty() => Some(0),
                None => None,
            };
            layers.push(Layer { name, node: usize::MAX, clips: in_layer, start, effects: Vec::new() });
        }
        let chains = file.layers.iter().map(|l| l.effects.len()).sum::<usize>() + file.effects.len();
        if nodes.len() + chains + layers.len() + 1 > MAX_NODES {
            let message = format!("the clips have {} nodes in all; a show may have at most {MAX_NODES}", nodes.len());
            self.error(&["layers"], message);
            return None;
        }
        for (l, layer) in file.layers.iter().enumerate() {
            let mut params = ParamSet::new((blend::INFO.params)());
            let set = |params: &mut ParamSet, name: &str, value: ParamValue| {
                let index = params.index(name).expect("a blend node declares opacity and blend");
                set_start(params, index, Start::Value(value))
            };
            if !(0.0..=1.0).contains(&layer.opacity) {
                self.error(&["opacity"], format!("layer {}: opacity {} must be 0–1", l + 1, layer.opacity));
            }
            set(&mut params, "opacity", ParamValue::Float(layer.opacity));
            match blend::BlendMode::OPTIONS.iter().position(|o| o.eq_ignore_ascii_case(&layer.blend)) {
                Some(i) => {
                    set(&mut params, "blend", ParamValue::Enum(i as u32));
                }
                None => {
                    let options = blend::BlendMode::OPTIONS.join(", ");
                    self.error(
                        &[&format!("\"{}\"", layer.blend)],
                        format!("blend '{}' is not one of {options}", layer.blend),
                    );
                }
            }
            layers[l].effects = self.chain(&format!("layer/{}", l + 1), &layer.effects, &mut nodes, None);
            layers[l].node = nodes.len();
            nodes.push(SceneNode {
                id: format!("layer/{}", l + 1),
                technique: &blend::INFO,
                params,
                inputs: Vec::new(),
                slots: blend::INFO.inputs.iter().map(|s| s.to_string()).collect(),
                hears_audio: false,
            });
        }
        let mut master_params = ParamSet::new((fader::INFO.params)());
        if !(0.0..=1.0).contains(&file.master) {
            self.error(&["master"], format!("master {} must be 0–1", file.master));
        }
        set_start(&mut master_params, 0, Start::Value(ParamValue::Float(file.master)));
        let master_effects = self.chain("master", &file.effects, &mut nodes, None);
        let master = nodes.len();
        nodes.push(SceneNode {
            id: "master".into(),
            technique: &fader::INFO,
            params: master_params,
            inputs: Vec::new(),
            slots: fader::INFO.inputs.iter().map(|s| s.to_string()).collect(),
            hears_audio: false,
        });
        let columns = (0..layers.iter().map(|l| l.clips.len()).max().unwrap_or(0))
            .map(|i| file.columns.get(i).cloned().unwrap_or_else(|| format!("column {}", i + 1)))
            .collect();
        let mut show = Show {
            layers,
            clips,
            columns,
            cues: Vec::new(),
            loop_cues: file.loop_cues,
            cue_notes: CueNotes { go: file.go_note, back: file.back_note },
            master,
            effects: std::mem::take(&mut self.effects),
            master_effects,
            mix_kind: None,
            file: None,
            kinds: Vec::new(),
            sources,
            broken,
            timeline: Default::default(),
        };
        if [file.go_note, file.back_note].iter().flatten().any(|&n| n > 127) {
            self.error(&["go_note", "back_note"], "a cue note must be 0–127".into());
        }
        if file.cues.len() > MAX_CUES {
            self.error(&["cues"], format!("{} cues; at most {MAX_CUES}", file.cues.len()));
        } else {
            show.cues = file.cues.iter().enumerate().filter_map(|(i, c)| self.cue(&show, i, c)).collect();
        }
        let (lanes, timeline, problems) = super::timeline::build_timeline(&file.timeline, &nodes, &show, file.dt);
        problems.into_iter().for_each(|(anchor, message)| self.error(&[anchor.as_str()], message));
        tracks.extend(lanes);
        show.timeline = timeline;
        if !show.effects.is_empty() {
            // An effect's dry/wet mix is the crossfade transition at the mix amount.
            show.mix_kind = self.transition(&TransitionFile::default(), &["effects"]).and_then(|t| t.kind);
        }
        show.kinds = std::mem::take(&mut self.kinds);
        let size = self.assets.output_size().unwrap_or(file.size);
        let own_texture_bytes = crate::scene::model::own_texture_bytes(self.assets, &nodes, size);
        let mut scene = Scene {
            origin: self.origin.to_string(),
            name: file.name.clone(),
            description: file.description.clone(),
            size: file.size,
            seed: file.seed,
            dt: file.dt,
            bpm: file.bpm,
            lfos,
            audio,
            msaa: file.msaa,
            nodes,
            output: master,
            tracks,
            outputs: Vec::new(),
            dmx: file.dmx.clone(),
            dmx_in: file.dmx_in.clone(),
            osc_aliases: vec![("/indra/master".into(), Target { node: master, param: 0, component: None })],
            midi: Vec::new(),
            show: None,
            own_texture_bytes,
        };
        self.controls(&file, &mut scene);
        for output in &file.outputs {
            if let Err(e) = scene.attach_output(output) {
                self.error(&["outputs"], e);
            }
        }
        show.file = Some(Arc::new(ShowSource { file, text: self.source.into() }));
        scene.show = Some(Arc::new(show));
        if let Err(e) = super::budget::budget(&scene, size) {
            self.error(&["size"], e);
        }
        Some(scene)
    }

    fn check_header(&mut self, file: &ShowFile) {
        for (anchor, message) in header_problems(&file.name, file.size, file.msaa, file.dt, file.bpm) {
            self.error(&[anchor], message);
        }
    }

    /// The clip's scene, validated, with the clip's start values applied.
    fn clip_scene(&self, clip: &ClipFile) -> Result<Scene, String> {
        // A relative path is taken from the show file's folder first.
        let beside = Path::new(self.origin).parent().map(|d| d.join(&clip.scene)).filter(|p| p.is_file());
        let name = beside.map(|p| p.display().to_string()).unwrap_or_else(|| clip.scene.clone());
        if names_a_show(&name) {
            return Err(format!("'{}' is a show; a clip plays a scene", clip.scene));
        }
        let mut scene = load_scene(self.assets, &name).map_err(|e| e.to_string())?;
        for (target, raw) in &clip.params {
            let t = resolve_target(&scene.nodes, target).map_err(|e| format!("params: {e}"))?;
            let params = &mut scene.nodes[t.node].params;
            let decl = &params.decls()[t.param];
            let value = match (t.component, raw) {
                (Some(c), crate::params::RawValue::Number(x)) => Start::Component(c, *x as f32),
                (Some(_), other) => return Err(format!("params: {target}: {other:?} is not a number")),
                (None, raw) => Start::Value(
                    coerce(raw, decl.ty(), &decl.options)
                        .ok_or_else(|| format!("params: {target}: {raw:?} does not fit a {}", decl.ty()))?,
                ),
            };
            if !set_start(params, t.param, value) {
                return Err(format!("params: {target}: not a finite number"));
            }
        }
        Ok(scene)
    }

    /// Appends the nodes of `owner`'s effect chain (see [`chain_nodes`]); returns their indices
    /// in chain order.
    fn chain(
        &mut self,
        owner: &str,
        effects: &[EffectFile],
        nodes: &mut Vec<SceneNode>,
        input: Option<usize>,
    ) -> Vec<usize> {
        let (chain, errors) =
            chain_nodes((self.origin, self.source), self.assets, owner, effects, (nodes.len(), input));
        let room = MAX_REPORTED_ERRORS.saturating_sub(self.errors.len());
        self.errors.extend(errors.into_iter().take(room));
        let indices: Vec<usize> = (nodes.len()..nodes.len() + chain.len()).collect();
        self.effects.extend(&indices);
        nodes.extend(chain);
        indices
    }

    /// A transition, its shader kind registered; `None` after reporting what is wrong.
    fn transition(&mut self, t: &TransitionFile, anchors: &[&str]) -> Option<Transition> {
        let length = match (t.seconds, t.beats) {
            (Some(_), Some(_)) => {
                self.error(anchors, "give seconds or beats, not both".into());
                return None;
            }
            (_, Some(b)) => Length::Beats(b),
            (s, None) => Length::Seconds(s.unwrap_or(1.0)),
        };
        let (Length::Seconds(x) | Length::Beats(x)) = length;
        if !(0.0..=MAX_TRANSITION).contains(&x) {
            self.error(anchors, format!("a transition of {x} must last 0 to {MAX_TRANSITION}"));
            return None;
        }
        if t.kind == "cut" {
            return Some(Transition { kind: None, length: Length::Seconds(0.0), quantize: t.quantize });
        }
        let isf = super::mixer::is_isf(&t.kind);
        let named =
            !t.kind.is_empty() && t.kind.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_');
        if !(isf || named) {
            self.error(
                anchors,
                format!("transition kind '{}': use cut, a name of a-z, 0-9 and _, or an ISF transition's .fs", t.kind),
            );
            return None;
        }
        let kind = match self.kinds.iter().position(|k| *k == t.kind) {
            Some(i) => i,
            None => {
                let file = super::transition_file(&t.kind);
                let found = if isf {
                    isf_transition_problem(self.assets, &t.kind).map_or(Ok(()), Err)
                } else {
                    self.assets.load(AssetKind::Shader, &file).map(|_| ())
                };
                if let Err(e) = found {
                    let anchor = format!("\"{}\"", t.kind);
                    self.error(&[&anchor], format!("transition '{}': {e}", t.kind));
                    return None;
                }
                self.kinds.push(t.kind.clone());
                self.kinds.len() - 1
            }
        };
        Some(Transition { kind: Some(kind), length, quantize: t.quantize })
    }

    fn cue(&mut self, show: &Show, i: usize, cue: &CueFile) -> Option<Cue> {
        let anchor = if cue.name.is_empty() { "cues".to_string() } else { format!("\"{}\"", cue.name) };
        let at = |message: String| (anchor.clone(), format!("cue {}: {message}", i + 1));
        let mut problems = Vec::new();
        let column = match cue.column {
            Some(c) if c >= 1 && (c as usize) <= show.columns.len() => Some(c as usize - 1),
            Some(c) => {
                problems.push(at(format!("column {c}: the show has {} columns", show.columns.len())));
                None
            }
            None => None,
        };
        let mut clips = Vec::new();
        for &(layer, clip) in &cue.clips {
            let Some(l) = (layer as usize).checked_sub(1).filter(|&l| l < show.layers.len()) else {
                problems.push(at(format!("layer {layer}: the show has {} layers", show.layers.len())));
                continue;
            };
            match clip {
                0 => clips.push((l, None)),
                c if (c as usize) <= show.layers[l].clips.len() => clips.push((l, Some(c as usize - 1))),
                c => problems.push(at(format!("clip {c}: layer {layer} has {} clips", show.layers[l].clips.len()))),
            }
        }
        let hold = match cue.hold {
            None => None,
            Some(Hold::Seconds(s)) if s.is_finite() && s > 0.0 => Some(Length::Seconds(s)),
            Some(Hold::Beats(b)) if b.is_finite() && b > 0.0 => Some(Length::Beats(b)),
            Some(h) => {
                problems.push(at(format!("hold {h:?} must be a positive number")));
                None
            }
        };
        let transition = cue.transition.as_ref().and_then(|t| self.transition(t, &[&anchor, "transition"]));
        for (a, message) in problems {
            self.error(&[&a], message);
        }
        Some(Cue { name: cue.name.clone(), column, clips, transition, hold })
    }

    fn controls(&mut self, file: &ShowFile, scene: &mut Scene) {
        for (address, target) in &file.controls.osc {
            if !address.starts_with('/') {
                self.error(&[&format!("\"{address}\"")], format!("OSC alias '{address}' must start with /"));
                continue;
            }
            match resolve_target(&scene.nodes, target) {
                Ok(t) => scene.osc_aliases.push((address.clone(), t)),
                Err(e) => self.error(&[&format!("\"{target}\"")], format!("OSC alias {address}: {e}")),
            }
        }
        for m in &file.controls.midi {
            let anchor = format!("\"{}\"", m.target);
            if let Some(problem) = m.problem() {
                self.error(&[&anchor], format!("MIDI mapping: {problem}"));
                continue;
            }
            match resolve_target(&scene.nodes, &m.target) {
                Ok(t) => scene.midi.push((m.clone(), t)),
                Err(e) => self.error(&[&anchor], format!("MIDI mapping: {e}")),
            }
        }
        if !file.controls.lfo.is_empty() || !file.controls.audio.is_empty() {
            self.error(
                &["lfo", "audio"],
                "a show's controls take osc and midi; put LFOs and audio in the clips' scenes".into(),
            );
        }
    }
}

/// A start value the show gives a parameter: the whole value or one component.
enum Start {
    Value(ParamValue),
    Component(usize, f32),
}

/// Makes `value` parameter `index`'s start value — its declared default, as a scene file's
/// values are, so that a reload which changes it applies (clamped to its range). False if it is
/// not a finite number.
fn set_start(params: &mut ParamSet, index: usize, value: Start) -> bool {
    let mut probe = params.clone();
    let accepted = match value {
        Start::Value(v) => probe.set_at(index, v),
        Start::Component(c, x) => probe.set_component(index, c, x),
    };
    if !accepted {
        return false;
    }
    probe.snap();
    let mut decls = params.decls().to_vec();
    decls[index].default = probe.target_at(index);
    *params = ParamSet::new(decls);
    true
}

/// The clip's id: given, or the scene's file stem.
fn clip_id(clip: &ClipFile) -> String {
    clip.id.clone().unwrap_or_else(|| {
        Path::new(&clip.scene).file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
    })
}

fn id_problem(id: &str) -> Option<String> {
    if id.is_empty() || id.chars().count() > MAX_CLIP_ID_CHARS {
        return Some(format!("an id needs 1 to {MAX_CLIP_ID_CHARS} characters"));
    }
    if !id.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-') {
        return Some("an id is letters, digits, _ and - (it becomes an OSC address)".into());
    }
    RESERVED_IDS
        .contains(&id)
        .then(|| format!("'{id}' is reserved for the show's own addresses; give the clip an `id`"))
}

fn note_problem(clip: &ClipFile) -> Option<String> {
    if clip.note.is_some_and(|n| n > 127) {
        return Some("note must be 0–127".into());
    }
    if clip.channel.is_some_and(|c| !(1..=16).contains(&c)) {
        return Some("channel must be 1–16".into());
    }
    None
}

/// Why shader file `file` cannot be a transition (it does not load, or lacks the image inputs
/// `startImage` and `endImage` or a `progress`), if it cannot.
fn isf_transition_problem(assets: &Assets, file: &str) -> Option<String> {
    let (_, declarer) = crate::techniques::file_technique(file)?;
    match (declarer.declare)(assets, file) {
        Err(e) => Some(e),
        Ok(d) => {
            let has = |slot: &str| d.inputs.iter().any(|i| i == slot);
            let transition = has("startImage") && has("endImage") && d.params.iter().any(|p| p.name == "progress");
            (!transition).then(|| {
                format!("{file} is not an ISF transition: it needs image inputs startImage and endImage and a progress")
            })
        }
    }
}
