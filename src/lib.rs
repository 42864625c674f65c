//! indra — a real-time visual-art engine for live VJ sets and installations, rendering the
//! techniques of *Unity Graphics Programming vol.4* with wgpu.
//!
//! Layers, from the bottom (a module imports only lower layers; `docs/architecture.md` is the
//! map, and a test holds it to this crate): [`time`], [`timecode`], [`files`], [`atomic_file`] → [`assets`],
//! [`checkpoint`], [`geometry`], [`gpu`], [`graph`] → [`params`], [`dmx`] → [`techniques`] → [`scene`] → [`control`],
//! [`live`] → [`offscreen`] → [`app`]; `main.rs` is the command line only.

#![warn(missing_docs)]

pub mod app;
pub mod assets;
pub mod atomic_file;
pub mod checkpoint;
pub mod control;
pub mod dmx;
pub mod files;
pub mod geometry;
pub mod gpu;
pub mod graph;
pub mod live;
pub mod media;
pub mod offscreen;
pub mod params;
pub mod scene;
pub mod techniques;
pub mod time;
pub mod timecode;

// A technique's golden renders live in its folder (`techniques/<name>/render_tests.rs`) and run
// as this crate's tests, written as the integration tests are: against `indra::` and with the
// helpers of `tests/common`.
#[cfg(test)]
extern crate self as indra;
#[cfg(all(test, not(feature = "golden")))]
compile_error!("indra's own tests compare renders by FLIP: build them with the `golden` feature (on by default)");
#[cfg(test)]
#[path = "../tests/common/mod.rs"]
mod common;
