//! A change to one parameter from a live source: what UI, OSC, MIDI, presets and replays all
//! produce, and what the control stream records.

/// Where a write came from. Within a frame writes apply in arrival order and the last one wins;
/// any live write to a parameter a track drives stops that track for it until resumed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum Source {
    /// The window's panel.
    Ui,
    /// An OSC message.
    Osc,
    /// A MIDI control change or note.
    Midi,
    /// A preset recall or morph.
    Preset,
    /// A recorded control stream played back.
    Replay,
    /// Audio analysis (a band, the level, an onset) through the scene's audio mappings.
    Audio,
    /// A DMX channel from a lighting desk (Art-Net or sACN in).
    Dmx,
}

/// Set parameter `param` (or one `component` of it) of node `node` to `value`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamWrite {
    /// Node index in the scene.
    pub node: usize,
    /// Parameter index in the node.
    pub param: usize,
    /// One float component (`/t/x`), or the whole value.
    pub component: Option<usize>,
    /// The new value (converted and clamped on application).
    pub value: super::ParamValue,
    /// Who wrote it.
    pub source: Source,
}
