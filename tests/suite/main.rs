//! The integration tests, one binary: each module was its own test binary once, but every binary
//! links all of indra, wgpu and naga (~50 MB and ~2 s of linking each), which on CI cost a gigabyte
//! of disk and most of a minute. `cargo test --test suite kleinian::` runs one module. `cli.rs` stays
//! apart: it also runs against the build without default features (tools/test-render-node).

mod architecture;
mod audio;
mod browser;
mod chase_in;
mod checkpoints;
#[path = "../support/chromium.rs"]
mod chromium;
#[path = "../common/mod.rs"]
mod common;
mod control;
mod controllers;
mod effects;
mod errors;
mod farm;
mod file_imports;
mod flood;
mod gl_transitions;
mod graph_gpu;
mod isf_reference;
mod lights;
mod live;
#[path = "../support/live_show.rs"]
mod live_show;
mod media;
mod midi_out;
mod msaa;
mod ndi;
mod osc;
#[cfg(target_os = "linux")]
mod pipewire;
mod recovery;
mod seek;
mod show;
mod show_memory;
#[cfg(target_os = "linux")]
mod slurm;
mod timecode;
mod timeline;
mod triangulate;
mod tune;
mod video;
mod window;
