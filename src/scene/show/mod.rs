//! A show: layers of clips composited live, transitions between clips, columns and a cue list.
//! A show is loaded into one flat [`Scene`](super::Scene) — every clip's nodes, renamed
//! `<clip>/<node>`, plus a `blend` node per layer (`layer/<n>`) and a `fader` (`master`) — so
//! parameters, OSC, OSCQuery, MIDI, presets, recordings and seeking work on a show as on a scene.
//! What is a show's own lives here: the plan ([`Show`]), its play state ([`ShowState`]: which
//! clip each layer plays, running transitions, pending quantized triggers, the cue), the
//! transition passes ([`Mixer`]) and the fresh copies of restarting clips ([`Spares`]).

mod budget;
pub mod chain_edit;
pub mod effects;
mod file;
pub mod lane_file;
pub mod lanes;
mod load;
mod mixer;
mod runtime;
mod spares;
mod state;
pub mod timeline;

pub use file::{
    ClipFile, ClipPolicy, CueFile, EffectFile, Hold, LayerFile, Quantize, ShowFile, TransitionFile, is_show,
};
pub use lanes::{LaneTake, MAX_LANE_KEYS, apply_lane, raw_keys, scalar_keys};
pub use load::{build_show, load_show, parse_show};
pub use mixer::{Mixer, MixerFrame, TRANSITION_BASE, TransitionUniforms, transition_file};
pub use runtime::ShowRuntime;
pub use spares::Spares;
pub use state::{BEATS_PER_BAR, Clock, LayerView, ShowState, StepChanges};
pub use timeline::{Marker, Timeline, TimelineFile};

use std::ops::Range;
use std::sync::Arc;

/// The most layers a show may have.
pub const MAX_LAYERS: usize = 8;
/// The most clips on one layer.
pub const MAX_CLIPS_PER_LAYER: usize = 64;
/// The most cues.
pub const MAX_CUES: usize = 1024;

/// A validated show: what the flat scene's nodes mean.
#[derive(Clone, Debug)]
pub struct Show {
    /// Layers, bottom first.
    pub layers: Vec<Layer>,
    /// Every clip of every layer.
    pub clips: Vec<Clip>,
    /// Column names (column n triggers clip n of each layer); as many as the longest layer.
    pub columns: Vec<String>,
    /// The cue list.
    pub cues: Vec<Cue>,
    /// After the last cue, GO goes to the first.
    pub loop_cues: bool,
    /// MIDI notes (any channel) for GO and back.
    pub cue_notes: CueNotes,
    /// Index of the master fader node.
    pub master: usize,
    /// The master's effect nodes, in chain order (before the fader).
    pub master_effects: Vec<usize>,
    /// Every effect node (clips', layers' and the master's), ascending: the position of a node
    /// here is its dry/wet pass.
    pub effects: Vec<usize>,
    /// The transition kind that mixes an effect's dry and wet images (the crossfade, in linear
    /// light), when the show has effects.
    pub mix_kind: Option<usize>,
    /// The file it was built from, as edited live since (effect chains), to rebuild it from.
    pub file: Option<Arc<ShowSource>>,
    /// Transition shader kinds in use (`crossfade` → `transition_crossfade.wgsl`), by index.
    pub kinds: Vec<String>,
    /// Every file the show was built from (the show file and its clips' scenes), for reload.
    pub sources: Vec<String>,
    /// Clips that could not be loaded (a lenient load, for a running show): clip id and why.
    pub broken: Vec<(String, String)>,
    /// The timeline's markers and chase.
    pub timeline: Timeline,
}

/// A show file as parsed (and edited live since), and the text errors are located in.
#[derive(Clone, Debug)]
pub struct ShowSource {
    /// The file.
    pub file: ShowFile,
    /// The text it was read from.
    pub text: String,
}

/// MIDI notes that move through the cue list.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CueNotes {
    /// The next cue.
    pub go: Option<u8>,
    /// The previous cue.
    pub back: Option<u8>,
}

/// One layer.
#[derive(Clone, Debug)]
pub struct Layer {
    /// Its name.
    pub name: String,
    /// Index of its `blend` node.
    pub node: usize,
    /// Its clips (indices into [`Show::clips`]).
    pub clips: Vec<usize>,
    /// The clip within the layer playing at start.
    pub start: Option<usize>,
    /// Its effect nodes, in chain order (after the transition, before the blend).
    pub effects: Vec<usize>,
}

/// One clip: a scene's nodes in the flat scene.
#[derive(Clone, Debug)]
pub struct Clip {
    /// Its id (`/indra/<id>/<node>/<param>`).
    pub id: String,
    /// The scene it plays.
    pub scene: String,
    /// Its layer.
    pub layer: usize,
    /// Its nodes in the flat scene (empty for a broken clip).
    pub nodes: Range<usize>,
    /// The node whose image is the clip's.
    pub output: Option<usize>,
    /// Restart or continue.
    pub policy: ClipPolicy,
    /// Its transition.
    pub transition: Transition,
    /// The MIDI note (and channel) that triggers it.
    pub note: Option<(Option<u8>, u8)>,
}

/// A transition, resolved.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Transition {
    /// Index into [`Show::kinds`]; `None`: a cut.
    pub kind: Option<usize>,
    /// How long it lasts.
    pub length: Length,
    /// When it starts.
    pub quantize: Quantize,
}

/// A length on the fixed clock or the tempo.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Length {
    /// Seconds.
    Seconds(f64),
    /// Beats.
    Beats(f64),
}

/// One cue, resolved.
#[derive(Clone, Debug, PartialEq)]
pub struct Cue {
    /// Its name.
    pub name: String,
    /// Column to trigger first.
    pub column: Option<usize>,
    /// (layer, clip within the layer or none) triggers.
    pub clips: Vec<(usize, Option<usize>)>,
    /// Its transition, over the clips' own.
    pub transition: Option<Transition>,
    /// How long it holds; `None`: until GO.
    pub hold: Option<Length>,
}

impl Show {
    /// The clip node `node` belongs to, if any.
    pub fn clip_of(&self, node: usize) -> Option<usize> {
        self.clips.iter().position(|c| c.nodes.contains(&node))
    }

    /// Whether `other` plays the same transitions: the same kinds, dry/wet mix and number of
    /// layers (a mixer built for one serves the other).
    pub fn plays_same_transitions(&self, other: &Show) -> bool {
        self.kinds == other.kinds && self.mix_kind == other.mix_kind && self.layers.len() == other.layers.len()
    }

    /// Effect node `node`'s place among [`Show::effects`] (its dry/wet pass), if it is one.
    pub fn effect_slot(&self, node: usize) -> Option<usize> {
        self.effects.binary_search(&node).ok()
    }

    /// Whether `node` is an effect of a layer's or the master's chain (drawn with its owner).
    pub fn is_chain_effect(&self, node: usize) -> bool {
        self.master_effects.contains(&node) || self.layers.iter().any(|l| l.effects.contains(&node))
    }

    /// The layer whose `blend` node is `node`, if any.
    pub fn layer_of_node(&self, node: usize) -> Option<usize> {
        self.layers.iter().position(|l| l.node == node)
    }

    /// How many of the flat scene's `total` nodes can draw in one frame: all but those of clips
    /// that cannot be on screen. A layer shows one clip, two during a transition; its clips that
    /// restart when triggered draw only then, so all but its two largest are left out. Clips
    /// that keep running while hidden draw always.
    pub fn nodes_drawn_at_once(&self, total: usize) -> usize {
        let mut hidden = 0;
        for layer in &self.layers {
            let clips = layer.clips.iter().map(|&c| &self.clips[c]);
            let mut restarting: Vec<usize> =
                clips.filter(|c| c.policy == ClipPolicy::Restart).map(|c| c.nodes.len()).collect();
            restarting.sort_unstable_by(|a, b| b.cmp(a));
            hidden += restarting.iter().skip(2).sum::<usize>();
        }
        total.saturating_sub(hidden)
    }

    /// Clip `clip` of layer `layer` as an index into [`Show::clips`].
    pub fn clip_at(&self, layer: usize, clip: usize) -> Option<usize> {
        self.layers.get(layer)?.clips.get(clip).copied()
    }

    /// The cue named `name`, or numbered `name` from 1.
    pub fn cue_named(&self, name: &str) -> Option<usize> {
        self.cues
            .iter()
            .position(|c| c.name == name)
            .or_else(|| name.parse::<usize>().ok().filter(|n| (1..=self.cues.len()).contains(n)).map(|n| n - 1))
    }
}
