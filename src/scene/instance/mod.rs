//! A scene made live: one technique instance per node, current parameter values, and the
//! per-step work of applying control events, tracks, preset morphs and smoothing.
//!
//! Order within one fixed step (documented precedence): control events that arrived since the
//! last step, in arrival order (the last write to a parameter wins) → animation tracks, except on
//! parameters a live source has taken over → a running preset morph → smoothing → simulation.
//! A live write (UI, OSC, MIDI) to a parameter a track drives stops that track for that parameter
//! until `resume_tracks`, so a performer's fader is never yanked back by automation.

mod chain;
mod checkpoint;
mod rebuild;

use std::collections::BTreeSet;

use super::model::Scene;
use super::show::{Show, ShowRuntime, ShowState};
use crate::assets::Assets;
use crate::gpu::{Gpu, ShaderError};
use crate::graph::{FrameGraph, FrameOutput, GraphError, GraphRuntime};
use crate::params::{
    ControlEvent, InputRole, Morph, NodeValues, ParamSet, ParamValue, ParamWrite, Remap, Source, TempoClock,
};
use crate::techniques::{NodeSetup, Technique};
use crate::time::FrameTime;
pub use rebuild::{NodeRebuild, Outdated, Replacement, SceneSnapshot, Transitions};

/// What the control layer reads of a running show: the scene, every node's parameters and the
/// tempo clock — not its GPU nodes, so protocol code (and its tests) needs no device.
#[derive(Clone, Copy)]
pub struct SceneView<'a> {
    /// The validated scene.
    pub scene: &'a Scene,
    /// Each node's parameters, in node order.
    pub params: &'a [ParamSet],
    /// The show's tempo and beat position.
    pub tempo: TempoClock,
    /// A show's plan and play state (`None` for a scene).
    pub show: Option<(&'a Show, &'a ShowState)>,
}

impl<'a> SceneView<'a> {
    /// The parameters of node `node`.
    pub fn params(&self, node: usize) -> &'a ParamSet {
        &self.params[node]
    }
}

/// The running form of a [`Scene`].
pub struct SceneInstance {
    scene: Scene,
    params: Vec<ParamSet>,
    nodes: Vec<Box<dyn Technique>>,
    /// When false, tracks leave parameters alone (the performer has taken over everything).
    pub animate: bool,
    overridden: BTreeSet<(usize, usize)>,
    morph: Option<Morph>,
    pending_morph: Option<(NodeValues, f64)>,
    /// The show's tempo and beat position (what `Beats` LFOs follow).
    tempo: TempoClock,
    /// Parameters a non-finite value was refused for (each told once), and the messages.
    refused: BTreeSet<(usize, usize)>,
    messages: Vec<String>,
    /// A show's clips, transitions and cues (`None` for a scene).
    show: Option<ShowRuntime>,
    /// Counts the changes of scene and nodes (reloads, a new device): what a rebuild made ahead
    /// checks before it is installed.
    revision: u64,
    /// A chain edit built ahead, installed when its event is applied.
    prepared: Option<(crate::params::ShowCommand, Replacement)>,
    /// Where parameters went since the last look, when chain edits replaced the scene.
    replaced: Option<Remap>,
}

impl SceneInstance {
    /// Creates every node's technique (pipelines, persistent resources) for `output_size`.
    pub fn new(gpu: &Gpu, assets: &Assets, scene: Scene, output_size: (u32, u32)) -> Result<Self, ShaderError> {
        let params: Vec<ParamSet> = scene.nodes.iter().map(|n| n.params.clone()).collect();
        let nodes = create_nodes(&scene, &params, gpu, assets, output_size)?;
        let tempo = TempoClock::new(scene.bpm);
        let show = ShowRuntime::new(gpu, assets, &scene, output_size)?;
        let mut messages = Vec::new();
        for (clip, why) in scene.show.iter().flat_map(|s| &s.broken) {
            messages.push(format!("clip '{clip}' is left out: {why}"));
        }
        Ok(Self {
            show,
            tempo,
            scene,
            params,
            nodes,
            animate: true,
            overridden: BTreeSet::new(),
            morph: None,
            pending_morph: None,
            refused: BTreeSet::new(),
            messages,
            revision: 0,
            prepared: None,
            replaced: None,
        })
    }

    /// What the control layer reads (see [`SceneView`]).
    pub fn view(&self) -> SceneView<'_> {
        let show = self.show.as_ref().map(|s| (s.plan(), s.state()));
        SceneView { scene: &self.scene, params: &self.params, tempo: self.tempo, show }
    }

    /// A show's plan and play state (`None` for a scene).
    pub fn show(&self) -> Option<(&Show, &ShowState)> {
        self.show.as_ref().map(|s| (s.plan(), s.state()))
    }

    /// A show's source as edited live (its lanes, its chains) and the file it was read from:
    /// what saving the lanes writes (the play state's plan keeps the source it was built with).
    pub fn show_source(&self) -> Option<(&super::show::ShowSource, &str)> {
        let show = self.scene.show.as_deref()?;
        Some((show.file.as_deref()?, show.sources.first()?.as_str()))
    }

    /// The validated scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Current parameters of node `i`.
    pub fn params(&self, node: usize) -> &ParamSet {
        &self.params[node]
    }

    /// Where parameter `target` (`node.param` or `node.param.x`) stands in its range, 0–1 (what
    /// a DMX lamp channel follows); `None` for a parameter the scene lacks.
    pub fn position_of(&self, target: &str) -> Option<f32> {
        let t = crate::scene::resolve_target(&self.scene.nodes, target).ok()?;
        let value = self.params[t.node].value_at(t.param).components();
        let x = *value.get(t.component.unwrap_or(0))?;
        let (lo, hi) = self.scene.nodes[t.node].params.decls()[t.param].range.unwrap_or((0.0, 1.0));
        Some(if hi > lo { ((x - lo) / (hi - lo)).clamp(0.0, 1.0) } else { 0.0 })
    }

    /// Every node's parameters.
    pub fn all_params(&self) -> &[ParamSet] {
        &self.params
    }

    /// Whether a track currently drives parameter `param` of node `node`.
    pub fn is_animated(&self, node: usize, param: usize) -> bool {
        self.animate && !self.overridden.contains(&(node, param)) && self.has_track(node, param)
    }

    /// Whether a live source took parameter `param` of `node` over from its track.
    pub fn is_overridden(&self, node: usize, param: usize) -> bool {
        self.overridden.contains(&(node, param))
    }

    /// Whether a track or an LFO drives the parameter (a live write then takes it over).
    fn has_track(&self, node: usize, param: usize) -> bool {
        self.scene.tracks.iter().any(|t| t.node == node && t.param == param)
            || self.scene.lfos.iter().any(|l| l.target.node == node && l.target.param == param)
    }

    /// The show's tempo and beat position.
    pub fn tempo(&self) -> TempoClock {
        self.tempo
    }

    /// Points of node `node` a performer may drag (see [`Technique::handles`]).
    pub fn handles(&self, node: usize) -> Vec<[f32; 2]> {
        self.nodes.get(node).map_or_else(Vec::new, |n| n.handles())
    }

    /// Applies control events in order; they take effect from the next step. A chain edit
    /// changes the scene: the events after it name parameters where they are after it (a
    /// replay reads them so; a live source's are moved with [`Self::take_replaced`]).
    pub fn apply(&mut self, events: &[ControlEvent]) {
        for event in events {
            match event {
                ControlEvent::Show(command @ crate::params::ShowCommand::Effect { .. }) => {
                    self.edit_chain(*command);
                }
                ControlEvent::Write(w) => self.write(w),
                ControlEvent::Morph { values, seconds } => self.pending_morph = Some((values.clone(), *seconds)),
                ControlEvent::ResumeTracks => self.overridden.clear(),
                ControlEvent::Tempo { bpm, resync } => self.tempo.set(*bpm, *resync),
                ControlEvent::Phase { phase, quantum } => self.tempo.align(*phase, *quantum),
                ControlEvent::Show(command) => {
                    let refused = match &mut self.show {
                        Some(show) => show.request(*command).err(),
                        None => Some(format!("{command:?}: '{}' is a scene, not a show", self.scene.name)),
                    };
                    self.messages.extend(refused);
                }
                ControlEvent::Audio(snapshot) => self.nodes.iter_mut().for_each(|n| n.hear(snapshot)),
                ControlEvent::Lane(lane) => match super::show::apply_lane(&mut self.scene, lane) {
                    // The edited lane plays at once: a take recorded into it is heard back.
                    // A chain edit built ahead from the show before this edit would lose it.
                    Ok(driven) => {
                        self.overridden.remove(&driven);
                        self.revision += 1;
                    }
                    Err(e) => self.messages.push(e),
                },
            }
        }
    }

    fn write(&mut self, w: &ParamWrite) {
        let Some(params) = self.params.get_mut(w.node) else { return };
        if w.param >= params.decls().len() {
            return;
        }
        let accepted = match w.component {
            Some(c) => params.set_component(w.param, c, w.value.components().first().copied().unwrap_or(f32::NAN)),
            None => params.set_at(w.param, w.value),
        };
        if !accepted {
            if self.refused.insert((w.node, w.param)) {
                let (node, decl) = (&self.scene.nodes[w.node].id, &params.decls()[w.param].name);
                self.messages
                    .push(format!("{node}.{decl}: a value that is not a finite number was refused ({:?})", w.source));
            }
            return;
        }
        let live =
            matches!(w.source, Source::Ui | Source::Osc | Source::Midi | Source::Replay | Source::Audio | Source::Dmx);
        if live && self.has_track(w.node, w.param) {
            self.overridden.insert((w.node, w.param));
        }
    }

    /// Runs one fixed step at `time`: tracks, preset morph, smoothing, simulation.
    pub fn advance(&mut self, time: &FrameTime) {
        if let Some(show) = &mut self.show {
            let messages = show.step(time, self.tempo.beats, &self.scene, &self.params, &mut self.nodes);
            self.messages.extend(messages);
        }
        if self.animate {
            for bound in &self.scene.tracks {
                if self.overridden.contains(&(bound.node, bound.param)) {
                    continue;
                }
                let local = if bound.show_clock { Some(*time) } else { self.node_time(bound.node, time) };
                let Some(local) = local else { continue };
                let value = bound.track.sample(if bound.beats { self.tempo.beats } else { local.seconds });
                let params = &mut self.params[bound.node];
                // Track values come from validated keys: always finite.
                let _ = match bound.component {
                    Some(c) => params.set_component(bound.param, c, value.components()[0]),
                    None => params.set_at(bound.param, value),
                };
            }
        }
        // LFOs after tracks: a modulated parameter follows its LFO unless a live source took it.
        for (i, lfo) in self.scene.lfos.iter().enumerate() {
            let (node, param) = (lfo.target.node, lfo.target.param);
            if self.overridden.contains(&(node, param)) {
                continue;
            }
            let Some(local) = self.node_time(node, time) else { continue };
            let key = time.seed ^ (i as u64 + 1).wrapping_mul(0xA24B_AED4_963E_E407);
            let value = lfo.value(local.seconds, self.tempo.beats, key);
            let params = &mut self.params[node];
            // LFO values come from validated, finite ranges.
            let _ = match lfo.target.component {
                Some(c) => params.set_component(param, c, value),
                None => params.set_at(param, ParamValue::Float(value)),
            };
        }
        if let Some((values, seconds)) = self.pending_morph.take() {
            let entries = values.iter().map(|&(n, p, to)| (n, p, self.params[n].target_at(p), to)).collect();
            // Every source refuses a non-finite duration; one that slipped through is instant
            // rather than a morph that pins its parameters for ever.
            let duration = if seconds.is_finite() { seconds.max(0.0) } else { 0.0 };
            self.morph = Some(Morph { entries, start: time.seconds, duration });
        }
        if let Some(morph) = &self.morph {
            let (values, done) = morph.sample(time.seconds);
            for (n, p, v) in values {
                self.params[n].set_at(p, v);
                // A recalled value replaces what a track or a live source had.
                self.overridden.remove(&(n, p));
            }
            if done {
                self.morph = None;
            }
        }
        for params in &mut self.params {
            params.advance(time.dt);
        }
        for (i, (node, params)) in self.nodes.iter_mut().zip(&mut self.params).enumerate() {
            let Some(local) = self.show.as_ref().map_or(Some(*time), |s| s.node_time(i, time)) else { continue };
            node.step(params, &local);
            for (name, value) in node.take_loaded_values() {
                if let Some(i) = params.index(name) {
                    params.set_at(i, value);
                    params.snap_at(i);
                }
            }
        }
        // A trigger fires for exactly one fixed step, however many steps a frame runs.
        for params in &mut self.params {
            params.end_step();
        }
        self.tempo.step(f64::from(time.dt));
    }

    /// The time node `node` runs at (a show's restart clip: its own clock), or `None` while it
    /// idles (a hidden restart clip).
    fn node_time(&self, node: usize, time: &FrameTime) -> Option<FrameTime> {
        self.show.as_ref().map_or(Some(*time), |s| s.node_time(node, time))
    }

    /// Prepares a show's clips before the show starts (see [`ShowRuntime::warm_up`]): one
    /// throwaway frame of each drawn through `runtime`, then fresh copies. Nothing for a scene.
    pub fn warm_up(&mut self, runtime: &mut GraphRuntime) -> Result<(), GraphError> {
        if let Some(show) = &mut self.show {
            let messages = show.warm_up(runtime, &self.scene, &self.params, &mut self.nodes)?;
            self.messages.extend(messages);
        }
        Ok(())
    }

    /// Whether any node records simulation work in its passes that every fixed step needs
    /// (GPU state). Seeking builds a simulation-only frame for each skipped step only then.
    pub fn simulates_on_gpu(&self) -> bool {
        self.nodes.iter().any(|n| n.simulates_on_gpu())
    }

    /// Recreates every node whose technique loads shader file `name` (after an edit), at once
    /// (see [`NodeRebuild`] for building them ahead). Either all of them build and are swapped
    /// in, or none is and the error is returned. Returns whether anything uses the shader.
    pub fn rebuild_nodes_using(
        &mut self,
        name: &str,
        gpu: &Gpu,
        assets: &Assets,
        output_size: (u32, u32),
    ) -> Result<bool, ShaderError> {
        let rebuild = NodeRebuild::prepare(&self.snapshot(), name, gpu, assets, output_size)?;
        let used = !rebuild.is_empty();
        self.install_nodes(rebuild).expect("built from this revision");
        Ok(used)
    }

    /// Recreates every node on `gpu` (a new device after the old one was lost or hung).
    /// Parameters, overrides, morphs and messages are kept; simulations start again from their
    /// initial state, since their state lived on the old device. Either every node builds or
    /// nothing changes and the error is returned.
    pub fn rebuild_all(&mut self, gpu: &Gpu, assets: &Assets, output_size: (u32, u32)) -> Result<(), ShaderError> {
        let nodes = create_nodes(&self.scene, &self.params, gpu, assets, output_size)?;
        let show = ShowRuntime::new(gpu, assets, &self.scene, output_size)?;
        self.nodes = nodes;
        if let (Some(mut show), Some(old)) = (show, self.show.take()) {
            show.keep_state(old);
            self.show = Some(show);
        }
        self.revision += 1;
        Ok(())
    }

    /// Switches to an edited version of the scene. Nodes whose id and technique are unchanged
    /// keep their instance (and simulation state); parameters keep their live values unless the
    /// file changed their default; new nodes are created. If any new node fails to build, the
    /// running scene stays as it was. Returns where each old parameter is now, for everything
    /// that holds parameter positions across the reload (queued events, scripts, MIDI learn).
    pub fn replace_scene(
        &mut self,
        scene: Scene,
        gpu: &Gpu,
        assets: &Assets,
        output_size: (u32, u32),
    ) -> Result<Remap, ShaderError> {
        self.replace_scene_rebuilding(scene, gpu, assets, output_size, &|_| false)
    }

    /// [`Self::replace_scene`], creating anew the nodes `rebuild` picks even where they are
    /// unchanged (their file changed: an ISF shader). See [`Replacement`] for building ahead.
    pub fn replace_scene_rebuilding(
        &mut self,
        scene: Scene,
        gpu: &Gpu,
        assets: &Assets,
        output_size: (u32, u32),
        rebuild: &dyn Fn(&super::SceneNode) -> bool,
    ) -> Result<Remap, ShaderError> {
        let replacement =
            Replacement::prepare(&self.snapshot(), scene, gpu, assets, output_size, (rebuild, Transitions::Compile))?;
        Ok(self.install(replacement).expect("built from this revision"))
    }

    /// Node `node`'s status line for the panel (see [`Technique::status`]).
    pub fn status(&self, node: usize) -> Option<String> {
        self.nodes.get(node).and_then(|n| n.status())
    }

    /// Every node's figures for `indra bench`, prefixed by node id.
    pub fn bench_reports(&mut self) -> Vec<String> {
        let ids = self.scene.nodes.iter().map(|n| n.id.as_str());
        self.nodes
            .iter_mut()
            .zip(ids)
            .flat_map(|(n, id)| n.bench_report().into_iter().map(move |r| format!("{id}: {r}")))
            .collect()
    }

    /// What the techniques want the performer to know since the last call, prefixed by node id.
    pub fn take_messages(&mut self) -> Vec<String> {
        let ids = self.scene.nodes.iter().map(|n| n.id.as_str());
        let mut messages = std::mem::take(&mut self.messages);
        messages.extend(
            self.nodes
                .iter_mut()
                .zip(ids)
                .flat_map(|(n, id)| n.take_messages().into_iter().map(move |m| format!("{id}: {m}"))),
        );
        messages
    }

    /// Writes for a key press: every trigger declared with [`InputRole::Key`] for this letter
    /// fires (R resets a cloth and restarts a Poisson run; U and C undo and clear a drawing).
    pub fn key(&self, key: char, source: Source) -> Vec<ControlEvent> {
        let key = key.to_ascii_lowercase();
        self.writes_for(source, |_, role| (role == InputRole::Key(key)).then_some(ParamValue::Trigger(true)))
    }

    /// Writes for a click at `position` (view units 0–1, y up): every parameter declared as
    /// [`InputRole::Pointer`] gets the position, then the triggers declared for that button
    /// fire. This is how the window's mouse draws, through the same parameters OSC and
    /// recordings use.
    pub fn pointer(&self, position: [f32; 2], primary: bool, source: Source) -> Vec<ControlEvent> {
        let click = if primary { InputRole::PrimaryClick } else { InputRole::SecondaryClick };
        let mut events = self.writes_for(source, |node, role| {
            (role == InputRole::Pointer).then(|| ParamValue::Vec2(self.pointer_for(node, position)))
        });
        events.extend(self.writes_for(source, |_, role| (role == click).then_some(ParamValue::Trigger(true))));
        events
    }

    /// Writes for the primary button going down (`held`) or up: every [`InputRole::Drag`] bool
    /// follows it, and pointer parameters get `position`.
    pub fn drag(&self, position: [f32; 2], held: bool, source: Source) -> Vec<ControlEvent> {
        let mut events = self.pointer_moved(position, source);
        events.extend(self.writes_for(source, |_, role| (role == InputRole::Drag).then_some(ParamValue::Bool(held))));
        events
    }

    /// Writes for the pointer moving while the primary button is held: pointer parameters of
    /// nodes that declare a [`InputRole::Drag`] follow it (a drawing's cursor does not move
    /// without a click).
    pub fn pointer_moved(&self, position: [f32; 2], source: Source) -> Vec<ControlEvent> {
        let mut events = Vec::new();
        for (node, params) in self.params.iter().enumerate() {
            if !params.decls().iter().any(|d| d.role == Some(InputRole::Drag)) {
                continue;
            }
            for (param, decl) in params.decls().iter().enumerate() {
                if decl.role == Some(InputRole::Pointer) {
                    let value = ParamValue::Vec2(self.pointer_for(node, position));
                    events.push(ControlEvent::Write(ParamWrite { node, param, component: None, value, source }));
                }
            }
        }
        events
    }

    /// Where a pointer at `view` (0–1 on the output, y up) points for node `node`: if a node that
    /// takes `node`'s texture draws it on a surface, the point of that texture under the pointer
    /// (a stroke lands under the cursor on the tessellated plane); else `view` itself.
    fn pointer_for(&self, node: usize, view: [f32; 2]) -> [f32; 2] {
        self.scene
            .nodes
            .iter()
            .enumerate()
            .filter(|(_, n)| n.inputs.contains(&node))
            .find_map(|(consumer, _)| self.nodes[consumer].map_pointer(view))
            .unwrap_or(view)
    }

    /// A write of `value(node, role)` to every parameter whose declared role gives a value.
    fn writes_for(&self, source: Source, value: impl Fn(usize, InputRole) -> Option<ParamValue>) -> Vec<ControlEvent> {
        let mut events = Vec::new();
        for (node, params) in self.params.iter().enumerate() {
            for (param, decl) in params.decls().iter().enumerate() {
                if let Some(value) = decl.role.and_then(|role| value(node, role)) {
                    events.push(ControlEvent::Write(ParamWrite { node, param, component: None, value, source }));
                }
            }
        }
        events
    }

    /// Declares this frame: every node adds its passes, the output node's texture is the output.
    pub fn build_graph(&mut self, output_size: (u32, u32), time: &FrameTime) -> FrameGraph<'_> {
        self.declare(FrameGraph::new(output_size), time)
    }

    fn declare<'r>(&'r mut self, mut graph: FrameGraph<'r>, time: &FrameTime) -> FrameGraph<'r> {
        let outputs = match &mut self.show {
            Some(show) => show.declare(&mut graph, &self.scene, &self.params, &mut self.nodes, time),
            None => {
                let mut outputs = Vec::with_capacity(self.nodes.len());
                for (i, node) in self.nodes.iter_mut().enumerate() {
                    let inputs: Vec<_> = self.scene.nodes[i].inputs.iter().map(|&j| outputs[j]).collect();
                    outputs.push(node.add_passes(&mut graph, &self.params[i], time, &inputs));
                }
                outputs.into_iter().map(Some).collect()
            }
        };
        // The output and every extra output always run (a show's master, its output warps).
        if let Some(output) = outputs[self.scene.output] {
            graph.set_output(output);
        }
        for extra in &self.scene.outputs {
            if let Some(texture) = outputs[extra.node] {
                graph.add_extra_output(texture);
            }
        }
        graph
    }

    /// Records the simulation work of a step that is not drawn (a seek): every node adds its
    /// passes to a [`FrameGraph::simulation_only`] graph, which runs only what changes
    /// persistent state. The caller submits.
    pub fn encode_simulation(
        &mut self,
        gpu: &Gpu,
        runtime: &mut GraphRuntime,
        encoder: &mut wgpu::CommandEncoder,
        output_size: (u32, u32),
        time: &FrameTime,
    ) -> Result<(), GraphError> {
        let graph = self.declare(FrameGraph::simulation_only(output_size), time);
        runtime.simulate(&gpu.device, &gpu.queue, graph, encoder).map(|_| ())
    }

    /// Builds and records the frame into `encoder`, after `finish` added its passes to the
    /// declared frame (a display encode, timed with the rest); the caller submits.
    pub fn encode<'r>(
        &'r mut self,
        gpu: &Gpu,
        runtime: &mut GraphRuntime,
        encoder: &mut wgpu::CommandEncoder,
        output_size: (u32, u32),
        time: &FrameTime,
        finish: impl FnOnce(&mut FrameGraph<'r>),
    ) -> Result<FrameOutput, GraphError> {
        let mut graph = self.build_graph(output_size, time);
        finish(&mut graph);
        runtime.execute(&gpu.device, &gpu.queue, graph, encoder)
    }
}

/// Every node's technique instance for `scene`, in node order.
fn create_nodes(
    scene: &Scene,
    params: &[ParamSet],
    gpu: &Gpu,
    assets: &Assets,
    output_size: (u32, u32),
) -> Result<Vec<Box<dyn Technique>>, ShaderError> {
    params.iter().enumerate().map(|(i, params)| create_node(scene, i, params, gpu, assets, output_size)).collect()
}

/// Creates node `i` of `scene` from `params` (its values now).
fn create_node(
    scene: &Scene,
    i: usize,
    params: &ParamSet,
    gpu: &Gpu,
    assets: &Assets,
    output_size: (u32, u32),
) -> Result<Box<dyn Technique>, ShaderError> {
    let n = &scene.nodes[i];
    let (msaa, seed) = (scene.msaa, scene.seed);
    (n.technique.create)(&NodeSetup { gpu, assets, id: &n.id, output_size, msaa, params, seed })
}
