//! Typed parameters: values, declarations with ranges, the per-node parameter set, and animation
//! tracks. Knows nothing of where values come from (UI, files, OSC).

mod morph;
mod set;
mod track;
mod value;
mod write;

pub use morph::Morph;
pub use set::ParamSet;
pub use track::{Interpolation, Key, LoopMode, Track, mix};
pub use value::{ParamDecl, ParamType, ParamValue, Text};
pub use write::{ParamWrite, Source};
