//! Typed parameters: values, declarations with ranges, the per-node parameter set, and animation
//! tracks. Knows nothing of where values come from (UI, files, OSC).

mod set;
mod track;
mod value;

pub use set::ParamSet;
pub use track::{Interpolation, Key, LoopMode, Track};
pub use value::{ParamDecl, ParamType, ParamValue};
