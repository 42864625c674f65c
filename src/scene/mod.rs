//! Scenes: the RON schema, validation with file:line:column errors, and turning a validated
//! scene into live nodes that add passes to a frame graph. Knows nothing of windows or UI.

mod error;
mod instance;
mod load;
mod schema;

pub use error::{SceneError, SceneErrors};
pub use instance::{ControlEvent, NodeValues, SceneInstance};
pub use load::{
    BoundTrack, Scene, SceneNode, Target, load_scene, parse_scene, parse_value_override, raw_from_value,
    resolve_target, value_from_raw,
};
pub use schema::{ControlsFile, MidiCurve, MidiMapping, NodeFile, RawValue, SceneFile, TrackFile};
