//! The show file format (`shows/<name>.ron`), as serde types. Unknown fields are errors.
//!
//! ```ron
//! (
//!     name: "set",
//!     size: (1920, 1080),
//!     layers: [
//!         (name: "background", clips: [
//!             (scene: "kleinian"),
//!             (scene: "tessellation_fluid", note: 37),
//!         ]),
//!         (name: "glow", blend: "add", opacity: 0.8, clips: [(scene: "star_glow", policy: Continue)]),
//!     ],
//!     transition: (kind: "crossfade", beats: 4, quantize: Bar),
//!     cues: [
//!         (name: "intro", clips: [(1, 1)], hold: Seconds(20)),
//!         (name: "drop", column: 2),
//!     ],
//! )
//! ```

use std::collections::BTreeMap;

use serde::Deserialize;

use crate::params::RawValue;
use crate::scene::schema::{ControlsFile, OutputFile, default_bpm, default_dt, default_msaa, one};

/// A whole show file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShowFile {
    /// Display name.
    pub name: String,
    /// One line on what it is.
    #[serde(default)]
    pub description: String,
    /// The composition's size in pixels; every clip renders at it.
    pub size: (u32, u32),
    /// Seed of all randomness (every clip's).
    #[serde(default)]
    pub seed: u64,
    /// Fixed simulation step in seconds (default 1/60), for every clip.
    #[serde(default = "default_dt")]
    pub dt: f32,
    /// Tempo at start, beats per minute (default 120).
    #[serde(default = "default_bpm")]
    pub bpm: f64,
    /// Samples per pixel of rasterising nodes, for every clip (default 4).
    #[serde(default = "default_msaa")]
    pub msaa: u32,
    /// Layers, bottom first (at most 8).
    pub layers: Vec<LayerFile>,
    /// Names of the columns (column n triggers clip n of every layer); optional.
    #[serde(default)]
    pub columns: Vec<String>,
    /// The transition clips use unless their clip, layer or cue names another (default: a
    /// one-second crossfade).
    #[serde(default)]
    pub transition: TransitionFile,
    /// The cue list, in order.
    #[serde(default)]
    pub cues: Vec<CueFile>,
    /// After the last cue, GO goes to the first (default true).
    #[serde(default = "yes")]
    pub loop_cues: bool,
    /// A MIDI note (0–127, any channel) that is GO.
    #[serde(default)]
    pub go_note: Option<u8>,
    /// A MIDI note that goes back a cue.
    #[serde(default)]
    pub back_note: Option<u8>,
    /// The master fader at start, 0 (black) to 1.
    #[serde(default = "one")]
    pub master: f32,
    /// The master's effect chain, in order: over the composited layers, before the fader.
    #[serde(default)]
    pub effects: Vec<EffectFile>,
    /// Output windows of the composition (sources default to the master).
    #[serde(default)]
    pub outputs: Vec<OutputFile>,
    /// A DMX patch file (docs/lights.md) whose fixtures the show's pixels light.
    #[serde(default)]
    pub dmx: Option<String>,
    /// A DMX-in file (docs/lights.md): which desk channels drive which parameters.
    #[serde(default)]
    pub dmx_in: Option<String>,
    /// OSC aliases and MIDI mappings; targets as `layer/1.opacity`, `master.level` or
    /// `<clip>/<node>.<param>`.
    #[serde(default)]
    pub controls: ControlsFile,
    /// Lanes, markers and the timecode chased (see [`super::timeline`]).
    #[serde(default)]
    pub timeline: super::timeline::TimelineFile,
}

/// One layer of the composition.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LayerFile {
    /// A name for the panel (default "layer n").
    #[serde(default)]
    pub name: String,
    /// normal, add, screen, multiply, difference or lighten (default normal).
    #[serde(default = "normal")]
    pub blend: String,
    /// 0–1 (default 1).
    #[serde(default = "one")]
    pub opacity: f32,
    /// The layer's transition (default: the show's).
    #[serde(default)]
    pub transition: Option<TransitionFile>,
    /// The clip playing at start, numbered from 1 (default: clip 1 when the show has no cues,
    /// none when it has: the first cue starts it). 0: none.
    #[serde(default)]
    pub start: Option<u32>,
    /// The layer's clips.
    pub clips: Vec<ClipFile>,
    /// The layer's effect chain, in order: after its transition, before its blend.
    #[serde(default)]
    pub effects: Vec<EffectFile>,
}

/// A clip: a scene and how it plays.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClipFile {
    /// A scene name (`scenes/`) or a path to a scene file.
    pub scene: String,
    /// The clip's id in addresses (`/indra/<id>/<node>/<param>`); default the scene's file name.
    #[serde(default)]
    pub id: Option<String>,
    /// Start values: `"node.param": value`, over the scene's own.
    #[serde(default)]
    pub params: BTreeMap<String, RawValue>,
    /// Restart (default: from its first frame when triggered; costs nothing while hidden) or
    /// Continue (keeps running while hidden, and costs its time).
    #[serde(default)]
    pub policy: ClipPolicy,
    /// The clip's transition (default: its layer's).
    #[serde(default)]
    pub transition: Option<TransitionFile>,
    /// A MIDI note (0–127) that triggers it.
    #[serde(default)]
    pub note: Option<u8>,
    /// The note's MIDI channel, 1–16 (default any).
    #[serde(default)]
    pub channel: Option<u8>,
    /// The clip's effect chain, in order: over the scene's output, before the transition.
    #[serde(default)]
    pub effects: Vec<EffectFile>,
}

/// One effect of a chain: an image filter with a bypass switch and a dry/wet mix.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EffectFile {
    /// An ISF filter file (`shaders/isf/Kaleidoscope.fs`, or the performer's own) or a technique
    /// that takes one image (`star_glow`, `warp`).
    pub effect: String,
    /// Start values of its parameters, over their defaults.
    #[serde(default)]
    pub params: BTreeMap<String, RawValue>,
    /// Dry/wet at start, 0 (the input only) to 1 (the effect only; default).
    #[serde(default = "one")]
    pub mix: f32,
    /// Bypassed at start: the input passes through and the effect costs no GPU time.
    #[serde(default)]
    pub bypass: bool,
}

/// What a clip does while it is not shown.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum ClipPolicy {
    /// Starts again from its first frame when triggered; hidden, it costs no time.
    #[default]
    Restart,
    /// Keeps stepping while hidden (its simulation goes on; it costs GPU time).
    Continue,
}

/// How a clip replaces the one before it.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransitionFile {
    /// `cut`, or a transition shader `shaders/transition_<kind>.wgsl`: bundled are crossfade,
    /// fade_black, wipe and luma (default crossfade).
    #[serde(default = "crossfade")]
    pub kind: String,
    /// Length in seconds (default 1 when no beats are given).
    #[serde(default)]
    pub seconds: Option<f64>,
    /// Length in beats of the show's tempo.
    #[serde(default)]
    pub beats: Option<f64>,
    /// Wait for the next beat or bar of the tempo clock before starting (default Off).
    #[serde(default)]
    pub quantize: Quantize,
}

impl Default for TransitionFile {
    fn default() -> Self {
        Self { kind: crossfade(), seconds: None, beats: None, quantize: Quantize::Off }
    }
}

/// When a trigger takes effect.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, serde::Serialize)]
pub enum Quantize {
    /// At once.
    #[default]
    Off,
    /// On the next beat.
    Beat,
    /// On the next bar (4 beats).
    Bar,
}

/// One cue: clips to trigger, then how long to hold.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CueFile {
    /// A name (for `/indra/cue/goto s` and the panel).
    #[serde(default)]
    pub name: String,
    /// (layer, clip) pairs numbered from 1; clip 0 empties the layer.
    #[serde(default)]
    pub clips: Vec<(u32, u32)>,
    /// A column to trigger (numbered from 1), before `clips`.
    #[serde(default)]
    pub column: Option<u32>,
    /// The transition for this cue's triggers (default: each clip's own).
    #[serde(default)]
    pub transition: Option<TransitionFile>,
    /// How long the cue holds before the next one goes; absent: wait for GO.
    #[serde(default)]
    pub hold: Option<Hold>,
}

/// A cue's hold time.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
pub enum Hold {
    /// Seconds of the fixed clock.
    Seconds(f64),
    /// Beats of the show's tempo.
    Beats(f64),
}

fn yes() -> bool {
    true
}

fn normal() -> String {
    "normal".into()
}

fn crossfade() -> String {
    "crossfade".into()
}

/// Whether RON text is a show rather than a scene: its top-level struct has `layers`.
pub fn is_show(source: &str) -> bool {
    #[derive(Deserialize)]
    struct Probe {
        #[serde(default)]
        layers: Option<serde::de::IgnoredAny>,
    }
    crate::scene::ron_options().from_str::<Probe>(source).is_ok_and(|p| p.layers.is_some())
}
