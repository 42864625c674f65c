//! Hot reload while the show runs: the `shaders/` and `scenes/` folders are watched (not single
//! files, so editors' atomic saves and renames count), changes are debounced and re-read until
//! stable, and applied only if they validate — otherwise the last good version keeps running and
//! the error (file:line:col) is reported once, until the next save fixes it. A lost or stuck GPU
//! moves the show to a new device built from the last good shaders.

mod chase_seek;
mod prepare;
mod recovery;
mod reload;
mod seek_checkpoints;
mod watcher;

pub use chase_seek::{BackgroundSeek, HAND_OVER_WITHIN, Sought};
pub use recovery::{GpuGuard, GpuState, GpuTrouble, recover, roll_back_stall};
pub use reload::{LiveReload, ReloadReport, RolledBack};
pub use seek_checkpoints::SeekCheckpoints;
pub use watcher::{Watcher, read_stable};
