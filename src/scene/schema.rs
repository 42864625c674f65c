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

use serde::Deserialize;

use crate::params::{Interpolation, LoopMode};

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
    /// Technique instances and their wiring.
    pub nodes: Vec<NodeFile>,
    /// The node whose texture is shown.
    pub output: String,
    /// Animation tracks.
    #[serde(default)]
    pub tracks: Vec<TrackFile>,
}

fn default_dt() -> f32 {
    1.0 / 60.0
}

fn one() -> f32 {
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
    /// (time in seconds, value) pairs.
    pub keys: Vec<(f32, RawValue)>,
}

/// A value as written in a file, before the declared type gives it meaning.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum RawValue {
    /// `true` / `false`.
    Bool(bool),
    /// `1.9` or `50`.
    Number(f64),
    /// `(1.0, 0.5)` or `[1.0, 0.5]`.
    List(Vec<f64>),
    /// `"Additive"`: an enum option by name.
    Text(String),
}

impl RawValue {
    /// The numbers it holds (bools as 0/1).
    pub fn numbers(&self) -> Vec<f64> {
        match self {
            RawValue::Bool(b) => vec![if *b { 1.0 } else { 0.0 }],
            RawValue::Number(x) => vec![*x],
            RawValue::List(v) => v.clone(),
            RawValue::Text(_) => Vec::new(),
        }
    }
}
