//! Scenes: the RON schema, validation with file:line:column errors, and turning a validated
//! scene into live nodes that add passes to a frame graph. Knows nothing of windows or UI.

mod edit;
mod error;
mod instance;
mod load;
mod model;
mod player;
mod schema;
pub mod show;
mod validate;

pub use edit::parse_value_override;
pub use error::{SceneError, SceneErrors};
pub use instance::{NodeRebuild, Outdated, Replacement, SceneInstance, SceneSnapshot, SceneView, Transitions};
pub use load::{load_scene, names_a_show, parse_scene, parse_scene_with};
pub use model::{AudioMapping, BoundTrack, MAX_NAME_CHARS, Scene, SceneNode, SceneOutput, check_audio, resolve_target};
pub use player::{Player, SeekError};
pub use schema::{
    AUDIO_BANDS, AudioFile, AudioSource, ControlsFile, MidiCurve, MidiMapping, NodeFile, SceneFile, TrackFile,
    ron_options,
};
// The address space lives in `params/`; re-exported for code that reaches it through scenes.
pub use crate::params::{ControlEvent, NodeValues, RawValue, Target, raw_from_value, value_from_raw};
