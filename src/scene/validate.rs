//! Validation of a parsed scene file: every name resolved, every value typed, each mistake
//! located at its line and column, and the settings a scene and a show share checked alike.

use std::collections::{BTreeMap, BTreeSet};

use super::error::{SceneError, SceneErrors, locate};
use super::model::{
    AudioMapping, BoundTrack, MAX_ID_CHARS, MAX_NAME_CHARS, MAX_NODES, MAX_REPORTED_ERRORS, Scene, SceneNode,
    check_audio, own_texture_bytes, resolve_target, unknown_param,
};
use super::schema::{MidiMapping, SceneFile, TrackFile};
use crate::assets::Assets;
use crate::params::{Key, Lfo, ParamDecl, ParamSet, ParamType, ParamValue, RawValue, Target, Track, coerce};
use crate::techniques;

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

/// One node built as a scene file's `node` would be — technique, the parameters its file
/// declares, start values, ranges — with its errors located in `source`; its input slots are
/// the caller's to wire (a show's effects are nodes wired by the show).
pub(super) fn build_node(
    (origin, source): (&str, &str),
    assets: &Assets,
    node: &super::schema::NodeFile,
    anchor: &str,
) -> Result<SceneNode, Vec<SceneError>> {
    let mut validator = Validator::new(origin, source, assets);
    match validator.node(node, anchor) {
        Some(built) if validator.errors.is_empty() => Ok(built),
        _ => Err(validator.failure().0),
    }
}

/// A scene's OSC aliases and MIDI mappings, resolved.
type ControlMaps = (Vec<(String, Target)>, Vec<(MidiMapping, Target)>);

/// Collects every semantic error of one file, each located by anchors.
pub(super) struct Validator<'a> {
    origin: &'a str,
    source: &'a str,
    /// Where files that declare a node's parameters are read from.
    assets: &'a Assets,
    errors: Vec<SceneError>,
    /// Errors past [`MAX_REPORTED_ERRORS`], counted only.
    more: usize,
}

impl<'a> Validator<'a> {
    /// A validator of `source` (called `origin` in errors), reading the files nodes declare their
    /// parameters from through `assets`.
    pub(super) fn new(origin: &'a str, source: &'a str, assets: &'a Assets) -> Self {
        Self { origin, source, assets, errors: Vec::new(), more: 0 }
    }

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

    /// The scene `file` describes, or every error found in it.
    pub(super) fn validate(mut self, file: SceneFile) -> Result<Scene, SceneErrors> {
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
                self.check_wiring(node, &built, &anchor);
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
        let size = self.assets.output_size().unwrap_or(file.size);
        let own_texture_bytes = own_texture_bytes(self.assets, &ordered, size);
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
            dmx: file.dmx.clone(),
            dmx_in: file.dmx_in.clone(),
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
        if let Err(message) = scene.check_texture_budget(size) {
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
        let params = ParamSet::new(decls);
        Some(SceneNode { id: node.id.clone(), technique, params, inputs: Vec::new(), slots, hears_audio })
    }

    /// Checks that `node` wires exactly the input slots `built` has.
    fn check_wiring(&mut self, node: &super::schema::NodeFile, built: &SceneNode, anchor: &str) {
        for slot in node.inputs.keys() {
            if !built.slots.contains(slot) {
                let key = format!("\"{slot}\"");
                self.error(
                    &[anchor, "inputs", &key],
                    format!("technique '{}' has no input '{slot}' (inputs: {:?})", built.technique.name, built.slots),
                );
            }
        }
        for slot in &built.slots {
            if !node.inputs.contains_key(slot) {
                self.error(&[anchor], format!("node '{}' needs its input '{slot}' wired to a node", node.id));
            }
        }
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
            match bind_track(nodes, t, false) {
                Ok(track) => out.push(track),
                Err(problems) => problems.into_iter().for_each(|p| self.error(&["tracks", anchor.as_str()], p)),
            }
        }
        out
    }
}

/// Resolves a track's target among `nodes` and types its keys; `show_clock`: it runs on the
/// show's clock (a timeline lane), not its node's. What is wrong, one sentence each.
pub(crate) fn bind_track(nodes: &[SceneNode], t: &TrackFile, show_clock: bool) -> Result<BoundTrack, Vec<String>> {
    let Target { node, param: pi, component } =
        resolve_target(nodes, &t.target).map_err(|e| vec![format!("track target {e}")])?;
    let params = &nodes[node].params;
    let ty = params.decls()[pi].ty();
    let key_type = if component.is_some() { ParamType::Float } else { ty };
    let options = params.decls()[pi].options.clone();
    if t.keys.is_empty() || t.time_scale.is_nan() || t.time_scale <= 0.0 {
        return Err(vec![format!("track '{}' needs at least one key and a positive time_scale", t.target)]);
    }
    let mut keys = Vec::new();
    let mut problems = Vec::new();
    for (time, raw) in &t.keys {
        match coerce(raw, key_type, &options) {
            Some(value) if time.is_finite() => keys.push(Key { time: *time, value }),
            Some(_) => problems.push(format!("track '{}': a key's time is {time}, not a number", t.target)),
            None => problems.push(format!(
                "track '{}': key at {time} s is {}, expected a {key_type}",
                t.target,
                describe(raw)
            )),
        }
    }
    if !problems.is_empty() {
        return Err(problems);
    }
    let track = Track::new(keys, t.interpolation, t.repeat, t.time_scale);
    Ok(BoundTrack { target: t.target.clone(), node, param: pi, component, track, show_clock, beats: t.beats })
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
