//! The RON file format, as serde types. Unknown fields are errors (with their position).
//!
//! ```ron
//! (
//!     name: "kleinian",
//!     size: (1280, 720),          // default render size
//!     seed: 1,                    // randomness = f(seed, frame)
//!     dt: 0.0166667,              // fixed simulation step, seconds
//!     nodes: [
//!         (id: "limit_set", technique: "kleinian",
//!          params: { "scale": 1.9, "t": (1.98795, 0.005859) },
//!          ranges: { "iterations": (1, 200) },
//!          inputs: {}),
//!     ],
//!     output: "limit_set",
//!     tracks: [
//!         (target: "limit_set.t.x", interpolation: Smooth, repeat: PingPong,
//!          keys: [(0.0016, 1.98795), (1.0, 1.93961)]),
//!     ],
//! )
//! ```

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::params::{Interpolation, LfoRate, LfoShape, LoopMode, RawValue};

/// A whole scene file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Display name.
    pub name: String,
    /// One line on what it shows.
    #[serde(default)]
    pub description: String,
    /// Default output size in pixels (the window and `--size` may override it).
    pub size: (u32, u32),
    /// Seed of all randomness.
    #[serde(default)]
    pub seed: u64,
    /// Fixed simulation step in seconds (default 1/60).
    #[serde(default = "default_dt")]
    pub dt: f32,
    /// The show's tempo at start, in beats per minute (default 120): what `Beats` LFOs follow
    /// until a tap, OSC or MIDI clock sets it.
    #[serde(default = "default_bpm")]
    pub bpm: f64,
    /// Samples per pixel of the rasterising nodes (1, 2, 4 or 8; default 4), resolved before
    /// any post effect sees the image. `run`, `render` and `bench` override it with `--msaa`.
    #[serde(default = "default_msaa")]
    pub msaa: u32,
    /// Technique instances and their wiring.
    pub nodes: Vec<NodeFile>,
    /// The node whose texture is shown (in the first window, with the panel).
    pub output: String,
    /// More outputs for the stage: each a window of its own (`run`) or a target of
    /// `render --output N`, numbered from 1.
    #[serde(default)]
    pub outputs: Vec<OutputFile>,
    /// OSC aliases and MIDI mappings.
    #[serde(default)]
    pub controls: ControlsFile,
    /// Animation tracks.
    #[serde(default)]
    pub tracks: Vec<TrackFile>,
    /// A DMX patch file (docs/lights.md) whose fixtures the show's pixels light.
    #[serde(default)]
    pub dmx: Option<String>,
    /// A DMX-in file (docs/lights.md): which desk channels drive which parameters.
    #[serde(default)]
    pub dmx_in: Option<String>,
}

/// One more output: a node's texture, optionally through a warp (projection mapping).
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputFile {
    /// The node whose texture it shows (default: the scene's output).
    #[serde(default)]
    pub source: Option<String>,
    /// A warp file: a `warp` node `output<n>` is added between the source and this output, its
    /// corners also at `/indra/output/<n>/corner/<0–3>` (clockwise from the top left).
    #[serde(default)]
    pub warp: Option<String>,
    /// Monitor index for its window (see the log for the list).
    #[serde(default)]
    pub monitor: Option<usize>,
    /// Open borderless fullscreen on that monitor.
    #[serde(default)]
    pub fullscreen: bool,
    /// Also send its image as an NDI source of this name (`run`).
    #[serde(default)]
    pub ndi: Option<String>,
    /// Also offer its image as a PipeWire video source of this name (`run`).
    #[serde(default)]
    pub pipewire: Option<String>,
    /// Open no window for it: the output only feeds its sends (`ndi`, `pipewire`).
    #[serde(default)]
    pub headless: bool,
}

/// How controllers reach parameters, besides the default `/indra/<node>/<param>` addresses.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControlsFile {
    /// OSC address → `node.param[.component]` (e.g. `"/1/fader1": "limit_set.scale"`).
    #[serde(default)]
    pub osc: BTreeMap<String, String>,
    /// MIDI controls bound to parameters.
    #[serde(default)]
    pub midi: Vec<MidiMapping>,
    /// LFOs moving parameters on the fixed clock.
    #[serde(default)]
    pub lfo: Vec<LfoFile>,
    /// Audio analysis moving parameters.
    #[serde(default)]
    pub audio: Vec<AudioFile>,
}

/// An audio mapping: `(source: Band(0), target: "limit_set.scale", range: (1.5, 3.0),
/// attack: 0.01, release: 0.3)`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct AudioFile {
    /// What it follows.
    pub source: AudioSource,
    /// `node.param` or `node.param.<component>`: a number, a bool, a trigger or a component.
    pub target: String,
    /// The values at silence and at full scale (default 0–1).
    #[serde(default = "unit_range")]
    pub range: (f32, f32),
    /// Seconds to rise (default 0.01).
    #[serde(default = "default_attack")]
    pub attack: f32,
    /// Seconds to fall (default 0.3).
    #[serde(default = "default_release")]
    pub release: f32,
}

/// Log-spaced bands the audio analysis measures.
pub const AUDIO_BANDS: usize = 16;

/// What an audio mapping follows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
pub enum AudioSource {
    /// RMS level (a full-scale sine is 0.707).
    Level,
    /// Peak sample.
    Peak,
    /// Bands below 250 Hz, 0–1 over −60…0 dBFS.
    Low,
    /// Bands 250 Hz – 4 kHz.
    Mid,
    /// Bands above 4 kHz.
    High,
    /// One of the 16 log-spaced bands (30 Hz – 16 kHz), 0 the lowest.
    Band(u8),
    /// 1 on an onset (a hit), then released; fires a trigger target.
    Onset,
    /// 1 on each beat of the music (onsets locked to the heard tempo, kept through a missed
    /// hit), then released; fires a trigger target.
    Beat,
}

fn unit_range() -> (f32, f32) {
    (0.0, 1.0)
}

fn default_attack() -> f32 {
    0.01
}

fn default_release() -> f32 {
    0.3
}

/// An LFO: `(target: "glow.angle", shape: Sine, rate: Beats(1.0), range: (0, 90), phase: 0.0)`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LfoFile {
    /// `node.param` or `node.param.<component>` (a number, or one component of a vector).
    pub target: String,
    /// Sine (default), Triangle, Saw, Square or Random (sample and hold).
    #[serde(default)]
    pub shape: LfoShape,
    /// `Beats(n)`: one cycle every n beats of the show's tempo; `Hz(f)`: f cycles a second.
    pub rate: LfoRate,
    /// The values at the bottom and the top of the wave.
    pub range: (f32, f32),
    /// Offset in cycles.
    #[serde(default)]
    pub phase: f64,
}

/// How every hand-editable RON file (scenes, MIDI learn files) is read: `implicit_some`, so
/// authors write `channel: 1`, not `channel: Some(1)`.
pub fn ron_options() -> ron::Options {
    ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
}

/// A MIDI control change (7-bit, or 14-bit when `fine`) or note bound to a parameter.
#[derive(Clone, Debug, PartialEq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct MidiMapping {
    /// MIDI channel 1–16; absent = any channel.
    #[serde(default)]
    pub channel: Option<u8>,
    /// Controller number 0–127 (0–31 for 14-bit pairs).
    #[serde(default)]
    pub cc: Option<u8>,
    /// Note number 0–127: note-on fires triggers / sets bools, velocity drives numbers.
    #[serde(default)]
    pub note: Option<u8>,
    /// `node.param[.component]`.
    pub target: String,
    /// Value range the control sweeps (default: the parameter's range).
    #[serde(default)]
    pub range: Option<(f32, f32)>,
    /// Linear or Exponential response.
    #[serde(default)]
    pub curve: MidiCurve,
    /// Reverse the direction.
    #[serde(default)]
    pub invert: bool,
    /// 14-bit: the controller's LSB comes on `cc + 32`.
    #[serde(default)]
    pub fine: bool,
}

impl MidiMapping {
    /// What is wrong with this mapping on its own (before its target is resolved), if anything:
    /// the same check for scene files and for the hand-editable MIDI learn file.
    pub fn problem(&self) -> Option<String> {
        match (self.cc, self.note) {
            _ if self.channel.is_some_and(|c| !(1..=16).contains(&c)) => Some("channel must be 1–16".to_string()),
            (Some(_), Some(_)) | (None, None) => Some("give exactly one of cc and note".into()),
            (Some(cc), None) if cc > 127 || (self.fine && cc > 31) => {
                Some(format!("cc {cc} out of range (0–127, or 0–31 for a 14-bit pair)"))
            }
            (None, Some(n)) if n > 127 => Some(format!("note {n} out of range (0–127)")),
            _ if self.range.is_some_and(|(lo, hi)| !lo.is_finite() || !hi.is_finite()) => {
                Some("range must be two finite numbers".into())
            }
            _ => None,
        }
    }
}

/// How a 0–1 control position maps onto a range.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, serde::Serialize)]
pub enum MidiCurve {
    /// Even steps.
    #[default]
    Linear,
    /// Fine control at the low end (for zoom, speed, frequency).
    Exponential,
}

pub(crate) fn default_msaa() -> u32 {
    4
}

pub(crate) fn default_bpm() -> f64 {
    crate::params::lfo::DEFAULT_BPM
}

pub(crate) fn default_dt() -> f32 {
    1.0 / 60.0
}

pub(crate) fn one() -> f32 {
    1.0
}

/// One technique instance.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodeFile {
    /// Unique id; also the `<node>` of OSC addresses.
    pub id: String,
    /// Registry name of the technique.
    pub technique: String,
    /// Start values that differ from the technique's defaults.
    #[serde(default)]
    pub params: BTreeMap<String, RawValue>,
    /// Narrower (or wider) slider ranges than the technique declares.
    #[serde(default)]
    pub ranges: BTreeMap<String, (f32, f32)>,
    /// Smoothing time constants in seconds (so a 20 Hz fader glides).
    #[serde(default)]
    pub smoothing: BTreeMap<String, f32>,
    /// Input slot → upstream node id.
    #[serde(default)]
    pub inputs: BTreeMap<String, String>,
}

/// One animation track.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrackFile {
    /// `node.param` or `node.param.x` (components x y z w or r g b a).
    pub target: String,
    /// Step, Linear or Smooth (default Smooth: zero-slope keys).
    #[serde(default)]
    pub interpolation: Interpolation,
    /// Once, Loop or PingPong after the last key (default Once).
    #[serde(default)]
    pub repeat: LoopMode,
    /// Clock multiplier (default 1).
    #[serde(default = "one")]
    pub time_scale: f32,
    /// Key times in beats of the show's tempo instead of seconds: the track runs on the beat
    /// position that tap, MIDI clock and Link move, so a 16-beat loop stays on the music.
    #[serde(default)]
    pub beats: bool,
    /// (time in seconds, or beats, value) pairs.
    pub keys: Vec<(f32, RawValue)>,
}
