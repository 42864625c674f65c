//! Live control: OSC in and out (with OSCQuery discovery and the browser surface), MIDI with
//! learn and controllers that light up, presets, and the
//! recording and replay of control streams. Everything becomes [`ControlEvent`]s that the
//! running scene applies before its next fixed step. Knows nothing of rendering.
//!
//! [`ControlEvent`]: crate::scene::ControlEvent

pub mod address;
pub mod audio;
pub mod controller;
pub mod discovery;
pub mod dmx_in;
pub mod feedback;
pub mod http;
pub mod hub;
#[cfg(feature = "link")]
pub mod link;
pub mod listen;
pub mod ltc_out;
pub mod midi;
pub mod midi_commands;
pub mod midi_out;
pub mod mtc_out;
pub mod osc;
mod osc_guard;
pub mod osc_route;
pub mod oscquery;
pub mod presets;
pub mod record;
pub mod site;
pub mod tempo;
pub mod timecode_in;
pub mod web;

pub use address::{AddressMap, Route};
pub use hub::{ControlHub, ControlOptions};
pub use osc_route::RecordRequest;
