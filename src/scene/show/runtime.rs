//! A show running inside a scene instance: the play state, the transition mixer and the fresh
//! copies of restarting clips, and the rules that tie them to the flat scene's nodes — which
//! nodes step and draw (a hidden restart clip does neither), on which clock (a restart clip's
//! own, from its trigger), and how the layers composite.

use std::sync::Arc;

use super::spares::{Build, Finished};
use super::state::Clock;
use super::{ClipPolicy, Mixer, MixerFrame, Show, ShowState, Spares, effects};
use crate::assets::Assets;
use crate::gpu::{Gpu, ShaderError};
use crate::graph::{FrameGraph, GraphError, GraphRuntime, PersistentTexture, TextureHandle};
use crate::params::{ParamSet, ShowCommand};
use crate::scene::Scene;
use crate::techniques::Technique;
use crate::time::FrameTime;

/// The running part of a show.
pub struct ShowRuntime {
    plan: Arc<Show>,
    state: ShowState,
    mixer: Mixer,
    spares: Spares,
    /// The clip each node belongs to.
    node_clip: Vec<Option<usize>>,
    gpu: Gpu,
    assets: Assets,
    output_size: (u32, u32),
    /// A 1×1 transparent black image: what an empty layer, or the side of a transition that
    /// has no clip, is sampled from (the passes sample with clamped UVs, so one texel covers any
    /// size). A clear of a full-size texture was a raster pass of 0.3 ms at 1080p on the H200.
    black: PersistentTexture,
}

impl ShowRuntime {
    /// The runtime of `scene`'s show (`None` for a plain scene), its transitions compiled.
    pub fn new(
        gpu: &Gpu,
        assets: &Assets,
        scene: &Scene,
        output_size: (u32, u32),
    ) -> Result<Option<Self>, ShaderError> {
        let Some(plan) = scene.show.clone() else { return Ok(None) };
        let mixer = Mixer::new(gpu, assets, &plan)?;
        Ok(Some(Self::with_mixer(gpu, assets, scene, output_size, plan, mixer)))
    }

    /// The runtime of `scene`'s show with no transitions of its own: it takes the running
    /// show's in [`ShowRuntime::take_transitions`], which must play the same transitions (see
    /// [`Show::plays_same_transitions`]; a chain edit's).
    pub fn taking_transitions(gpu: &Gpu, assets: &Assets, scene: &Scene, output_size: (u32, u32)) -> Option<Self> {
        let plan = scene.show.clone()?;
        Some(Self::with_mixer(gpu, assets, scene, output_size, plan, Mixer::to_take_over()))
    }

    fn with_mixer(
        gpu: &Gpu,
        assets: &Assets,
        scene: &Scene,
        output_size: (u32, u32),
        plan: Arc<Show>,
        mixer: Mixer,
    ) -> Self {
        Self {
            node_clip: (0..scene.nodes.len()).map(|n| plan.clip_of(n)).collect(),
            state: ShowState::new(&plan),
            spares: Spares::new(plan.clips.len()),
            plan,
            mixer,
            black: PersistentTexture::new(&gpu.device, "show/black", (1, 1), crate::techniques::image_pass::FORMAT),
            gpu: gpu.clone(),
            assets: assets.clone(),
            output_size,
        }
    }

    /// The plan.
    pub fn plan(&self) -> &Show {
        &self.plan
    }

    /// What the show builds with: the device, the assets and the output size.
    pub fn context(&self) -> (&Gpu, &Assets, (u32, u32)) {
        (&self.gpu, &self.assets, self.output_size)
    }

    /// The play state.
    pub fn state(&self) -> &ShowState {
        &self.state
    }

    /// Takes over the play state of the show this one replaces (a hot reload, a chain edit);
    /// clips whose nodes ran before are no longer fresh, and hidden ones get fresh copies — but a
    /// clip whose nodes were all kept in place (`kept_in_place`, by node) keeps its slot (fresh,
    /// or a copy on its way): an effect added to a layer rebuilds no clip.
    pub fn carry_over(
        &mut self,
        old: &mut ShowRuntime,
        scene: &Scene,
        params: &[ParamSet],
        nodes: &mut [Box<dyn Technique>],
        kept_in_place: &dyn Fn(usize) -> bool,
    ) -> Vec<String> {
        self.state = old.state.carried(&old.plan, &self.plan);
        self.spares.continue_from(&old.spares);
        let mut messages = Vec::new();
        for c in 0..self.plan.clips.len() {
            let clip = &self.plan.clips[c];
            let untouched = old.plan.clips.get(c).is_some_and(|o| o.id == clip.id && o.nodes == clip.nodes)
                && clip.nodes.clone().all(kept_in_place);
            // A copy on its way stays on its way: building it again would clone the clip's nodes
            // on the render thread and throw a build away.
            if untouched && self.spares.take_slot(&mut old.spares, c) {
                continue;
            }
            self.spares.mark_stale(c);
            if self.plan.clips[c].policy == ClipPolicy::Restart && !self.state.visible(c) {
                self.prepare(c, scene, params, nodes, &mut messages);
            }
        }
        messages
    }

    /// Takes `old`'s transitions and shared image (see [`Mixer::take_from`]): this runtime was
    /// made by [`ShowRuntime::taking_transitions`] for a show that plays the same ones.
    pub fn take_transitions(&mut self, old: &mut ShowRuntime) {
        debug_assert!(self.plan.plays_same_transitions(&old.plan), "a chain edit's show changed its transitions");
        self.mixer.take_from(&mut old.mixer, &self.gpu.device, self.plan.effects.len());
        std::mem::swap(&mut self.black, &mut old.black);
    }

    /// After every node was rebuilt on a new device: the play state stays; clips on screen run
    /// on from their fresh state.
    pub fn keep_state(&mut self, old: ShowRuntime) {
        self.state = old.state;
        for c in 0..self.plan.clips.len() {
            if self.state.visible(c) {
                self.spares.mark_stale(c);
            }
        }
    }

    /// Takes the play state of a checkpoint: the clips on screen ran, so they are not fresh
    /// (their nodes get the checkpoint's state); hidden restart clips stay fresh copies.
    pub fn restore_state(&mut self, state: ShowState) {
        self.state = state;
        for c in 0..self.plan.clips.len() {
            if self.state.visible(c) || self.plan.clips[c].policy != ClipPolicy::Restart {
                self.spares.mark_stale(c);
            }
        }
    }

    /// Takes transitions rebuilt with `assets` (a shader edit) in place of the old ones.
    pub fn install_mixer(&mut self, mixer: Mixer, assets: &Assets) {
        self.mixer = mixer;
        self.assets = assets.clone();
    }

    /// Queues a command for the next step.
    pub fn request(&mut self, command: ShowCommand) -> Result<(), String> {
        self.state.request(&self.plan, command)
    }

    /// The time node `node` runs at, or `None` while it idles (a hidden restart clip).
    pub fn node_time(&self, node: usize, time: &FrameTime) -> Option<FrameTime> {
        clip_time(&self.plan, &self.state, self.node_clip.get(node).copied().flatten(), time)
    }

    /// The show's part of a step at `time` (before the nodes step): commands, triggers, cues;
    /// clips that start get fresh nodes, clips that leave get fresh copies prepared. Returns
    /// what to tell the performer.
    pub fn step(
        &mut self,
        time: &FrameTime,
        beats: f64,
        scene: &Scene,
        params: &[ParamSet],
        nodes: &mut [Box<dyn Technique>],
    ) -> Vec<String> {
        let mut messages = Vec::new();
        for done in self.spares.finished() {
            self.install(done, nodes, &mut messages);
        }
        // The timeline's markers ask at their frame, as a performer's commands do (so a seek
        // passes through them all).
        for marker in self.plan.markers_at(time.frame) {
            if let Err(e) = self.state.request(&self.plan, marker.command) {
                messages.push(format!("marker '{}' at frame {}: {e}", marker.name, marker.frame));
            }
        }
        let clock = Clock { frame: time.frame, seconds: time.seconds, beats };
        let changes = self.state.step(&self.plan, clock);
        messages.extend(changes.messages);
        for &(layer, clip) in &changes.switched {
            let name = &self.plan.layers[layer].name;
            match clip.map(|c| &self.plan.clips[c]) {
                Some(c) => log::info!("frame {}: layer {} '{name}' plays clip '{}'", time.frame, layer + 1, c.id),
                None => log::info!("frame {}: layer {} '{name}' is empty", time.frame, layer + 1),
            }
        }
        let wait = self.assets.load_wait();
        for &c in &changes.started {
            let (plan, gpu, assets, size) = (&self.plan, &self.gpu, &self.assets, self.output_size);
            let result = self.spares.take_for_start(c, wait, || clip_build(plan, gpu, assets, size, c, scene, params));
            match result {
                Ok(Some(fresh)) => self.swap_in(c, fresh, nodes),
                Ok(None) => {}
                Err(e) => messages.push(format!("clip '{}' restarts from where it was: {e}", self.plan.clips[c].id)),
            }
        }
        for c in changes.hidden {
            if self.plan.clips[c].policy == ClipPolicy::Restart {
                self.prepare(c, scene, params, nodes, &mut messages);
            }
        }
        messages
    }

    /// Draws one throwaway frame of every hidden restart clip, then gives each a fresh copy:
    /// afterwards `runtime`'s texture pool holds the textures every clip needs (and keeps them),
    /// and the driver has seen each pipeline run, so no trigger allocates or compiles on stage.
    /// Measured on the H200 at 1080p, a clip's first frame cost up to 9 ms of allocation without
    /// this, against 5 ms for a whole frame.
    pub fn warm_up(
        &mut self,
        runtime: &mut GraphRuntime,
        scene: &Scene,
        params: &[ParamSet],
        nodes: &mut [Box<dyn Technique>],
    ) -> Result<Vec<String>, GraphError> {
        runtime.hold_transients(true);
        let mut messages = Vec::new();
        let start = FrameTime { frame: 0, seconds: 0.0, dt: scene.dt, seed: scene.seed };
        let (device, queue) = (self.gpu.device.clone(), self.gpu.queue.clone());
        for c in 0..self.plan.clips.len() {
            let clip = &self.plan.clips[c];
            let Some(output) = clip.output.filter(|_| clip.policy == ClipPolicy::Restart && !self.state.visible(c))
            else {
                continue;
            };
            let range = clip.nodes.clone();
            let mut graph = FrameGraph::new(self.output_size);
            let mut outputs: Vec<Option<TextureHandle>> = vec![None; nodes.len()];
            for (i, node) in nodes[range.clone()].iter_mut().enumerate().map(|(k, n)| (range.start + k, n)) {
                node.step(&params[i], &start);
                let inputs: Vec<TextureHandle> = scene.nodes[i].inputs.iter().filter_map(|&j| outputs[j]).collect();
                outputs[i] = Some(node.add_passes(&mut graph, &params[i], &start, &inputs));
            }
            if let Some(image) = outputs[output] {
                graph.set_output(image);
            }
            let mut encoder =
                device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("clip_warm_up") });
            runtime.execute(&device, &queue, graph, &mut encoder)?;
            queue.submit([encoder.finish()]);
            runtime.after_submit();
            self.spares.mark_stale(c);
            self.prepare(c, scene, params, nodes, &mut messages);
        }
        Ok(messages)
    }

    /// Starts a fresh copy of clip `clip` (its nodes ran): built now in renders, on a worker
    /// thread in a live show; one built now is swapped in at once.
    fn prepare(
        &mut self,
        clip: usize,
        scene: &Scene,
        params: &[ParamSet],
        nodes: &mut [Box<dyn Technique>],
        messages: &mut Vec<String>,
    ) {
        let build = self.build(clip, scene, params);
        if let Some(result) = self.spares.prepare(clip, build, self.assets.load_wait()) {
            self.install(Finished { clip, result, restart: false }, nodes, messages);
        }
    }

    fn install(&mut self, done: Finished, nodes: &mut [Box<dyn Technique>], messages: &mut Vec<String>) {
        let clip = done.clip;
        match done.result {
            Ok(fresh) if !self.state.visible(clip) => {
                self.swap_in(clip, fresh, nodes);
                self.spares.mark_fresh(clip);
            }
            // Retriggered while it was built: it restarts on these nodes from now (its clock
            // restarted at the trigger); they run, so the slot stays stale.
            Ok(fresh) if done.restart => self.swap_in(clip, fresh, nodes),
            // Shown again while it was built, without a restart: it plays on.
            Ok(fresh) => crate::gpu::drop_later(fresh),
            Err(e) => messages.push(format!("clip '{}' could not be prepared: {e}", self.plan.clips[clip].id)),
        }
    }

    fn swap_in(&mut self, clip: usize, fresh: Vec<Box<dyn Technique>>, nodes: &mut [Box<dyn Technique>]) {
        let range = self.plan.clips[clip].nodes.clone();
        let old: Vec<Box<dyn Technique>> =
            nodes[range].iter_mut().zip(fresh).map(|(slot, node)| std::mem::replace(slot, node)).collect();
        // The clip's old nodes hold its pipelines, buffers and textures: dropped here they took
        // 0.03–25 ms of a frame on lavapipe (book.ron, a copy swapped in every half second).
        crate::gpu::drop_later(old);
    }

    fn build(&self, clip: usize, scene: &Scene, params: &[ParamSet]) -> Build {
        clip_build(&self.plan, &self.gpu, &self.assets, self.output_size, clip, scene, params)
    }

    /// Declares this frame of the show: every running clip's passes (and its effects), each
    /// layer's transition, effects and blend, the master's effects and fader. Returns each node's
    /// image (a hidden clip's: none).
    pub fn declare<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        scene: &Scene,
        params: &[ParamSet],
        nodes: &'r mut [Box<dyn Technique>],
        time: &FrameTime,
    ) -> Vec<Option<TextureHandle>> {
        let mut outputs: Vec<Option<TextureHandle>> = vec![None; nodes.len()];
        let black = graph.import_texture("show/black", &self.black);
        let mut below = black;
        let Self { plan, state, mixer, node_clip, .. } = self;
        // Nodes are lent out one at a time: a layer's effects are drawn when its blend is.
        let mut lent = Lent { plan, mixer: mixer.frame(), slots: nodes.iter_mut().map(Some).collect() };
        for i in 0..outputs.len() {
            if plan.is_chain_effect(i) {
                continue;
            }
            let Some(node) = lent.slots[i].take() else { continue };
            outputs[i] = if let Some(l) = plan.layer_of_node(i) {
                let image_of = |clip: Option<usize>, outputs: &[Option<TextureHandle>]| {
                    clip.and_then(|c| plan.clips[c].output).and_then(|n| outputs[n])
                };
                let view = state.view(l);
                let to = image_of(view.to, &outputs);
                let image = if view.fading() {
                    let from = image_of(view.from, &outputs).unwrap_or(black);
                    Some(lent.mixer.declare(graph, l, &view, from, to.unwrap_or(black)))
                } else {
                    to
                };
                // An empty layer leaves the image below as it is.
                if let Some(image) = image {
                    let image = lent.chain(graph, &plan.layers[l].effects, image, (params, time), &mut outputs);
                    below = node.add_passes(graph, &params[i], time, &[below, image]);
                }
                Some(below)
            } else if i == plan.master {
                let image = lent.chain(graph, &plan.master_effects, below, (params, time), &mut outputs);
                Some(node.add_passes(graph, &params[i], time, &[image]))
            } else {
                clip_time(plan, state, node_clip[i], time).map(|t| {
                    let inputs: Vec<TextureHandle> =
                        scene.nodes[i].inputs.iter().map(|&j| outputs[j].unwrap_or(black)).collect();
                    match inputs.first() {
                        Some(&dry) if plan.effect_slot(i).is_some() => {
                            lent.effect(node, graph, (&params[i], &t), dry, i)
                        }
                        _ => node.add_passes(graph, &params[i], &t, &inputs),
                    }
                })
            };
        }
        outputs
    }
}

/// One frame's declaration: the nodes and the mixer's passes, each lent out once.
struct Lent<'a, 'r> {
    plan: &'a Show,
    mixer: MixerFrame<'r>,
    slots: Vec<Option<&'r mut Box<dyn Technique>>>,
}

impl<'r> Lent<'_, 'r> {
    /// Declares the effects `chain` (node indices, in order) over `image`; returns the result.
    fn chain(
        &mut self,
        graph: &mut FrameGraph<'r>,
        chain: &[usize],
        mut image: TextureHandle,
        (params, time): (&[ParamSet], &FrameTime),
        outputs: &mut [Option<TextureHandle>],
    ) -> TextureHandle {
        for &e in chain {
            let Some(node) = self.slots.get_mut(e).and_then(Option::take) else { continue };
            image = self.effect(node, graph, (&params[e], time), image, e);
            outputs[e] = Some(image);
        }
        image
    }

    /// Declares effect node `index` over `dry`, with its bypass and dry/wet mix.
    fn effect(
        &mut self,
        node: &'r mut Box<dyn Technique>,
        graph: &mut FrameGraph<'r>,
        (params, time): (&ParamSet, &FrameTime),
        dry: TextureHandle,
        index: usize,
    ) -> TextureHandle {
        let slot = self.plan.effect_slot(index).unwrap_or(usize::MAX);
        let mixer = &mut self.mixer;
        effects::declare(node, graph, params, time, dry, |graph, dry, wet, amount| {
            mixer.mix(graph, slot, dry, wet, amount)
        })
    }
}

/// The time a node of `clip` (none: a layer, the master, an output) runs at, or `None` while
/// it idles: a restart clip runs on its own clock from its trigger, and only while shown.
fn clip_time(plan: &Show, state: &ShowState, clip: Option<usize>, time: &FrameTime) -> Option<FrameTime> {
    let Some(c) = clip else { return Some(*time) };
    match plan.clips[c].policy {
        ClipPolicy::Continue => Some(*time),
        ClipPolicy::Restart => state.visible(c).then(|| time.since(state.started(c))),
    }
}

/// What building clip `clip`'s nodes afresh takes, with their parameters now.
fn clip_build(
    plan: &Show,
    gpu: &Gpu,
    assets: &Assets,
    output_size: (u32, u32),
    clip: usize,
    scene: &Scene,
    params: &[ParamSet],
) -> Build {
    Build {
        gpu: gpu.clone(),
        assets: assets.clone(),
        nodes: plan.clips[clip].nodes.clone().map(|n| (scene.nodes[n].clone(), params[n].clone())).collect(),
        output_size,
        msaa: scene.msaa,
        seed: scene.seed,
    }
}
