//! Typed parameters: values, declarations with ranges, the per-node parameter set, animation
//! tracks, values as files write them, and the address space live sources write through
//! (targets, control events, remapping across a reload). Knows nothing of where values come from
//! (UI, files, OSC).

mod address;
pub mod lfo;
mod morph;
mod raw;
mod set;
mod track;
mod typed;
mod value;
mod write;

pub use address::{
    Addressing, AudioSnapshot, ControlEvent, EffectEdit, Indexed, LaneKeys, NodeValues, Remap, ShowCommand, Target,
};
pub use lfo::{Lfo, LfoRate, LfoShape, TempoClock};
pub use morph::Morph;
pub use raw::{RawValue, coerce, raw_from_value, value_from_raw};
pub use set::ParamSet;
pub use track::{Interpolation, Key, LoopMode, Track, mix};
pub use typed::{FromValue, ParamEnum, doc_text, field, option_index};
pub use value::{Components, InputRole, ParamDecl, ParamType, ParamValue, Text};
pub use write::{ParamWrite, Source};
