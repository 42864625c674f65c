//! Scenes: the RON schema, validation with file:line:column errors, and turning a validated
//! scene into live nodes that add passes to a frame graph. Knows nothing of windows or UI.

mod error;
mod instance;
mod load;
mod schema;

pub use error::{SceneError, SceneErrors};
pub use instance::SceneInstance;
pub use load::{BoundTrack, Scene, SceneNode, load_scene, parse_scene, parse_value_override};
pub use schema::{NodeFile, RawValue, SceneFile, TrackFile};
