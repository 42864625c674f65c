//! Sound as a control source: analysis (level, bands, onsets, tempo), the mapping of it to
//! parameters, WAV files for deterministic renders, and live input (cpal, behind the `audio`
//! feature). Every value reaches the scene as a parameter write, recorded and replayed like OSC.

pub mod analysis;
pub mod file;
pub mod learn;
#[cfg(feature = "audio")]
pub mod live;
pub mod mapping;
pub mod sound;

pub use analysis::{Analyzer, AudioFrame};
pub use file::AudioFile;
pub use learn::AudioLearn;
pub use mapping::AudioMapper;

use crate::params::ControlEvent;
use crate::scene::Scene;

/// What frames 0 up to (not including) `frames` at step `dt` hear of `file`: frame n analyses
/// the file up to (n + 1) × dt. Frames past the file's end hear silence.
pub fn analyse_file(file: &AudioFile, frames: u64, dt: f64) -> Vec<AudioFrame> {
    let mut analyzer = Analyzer::new(file.rate);
    (0..frames).map(|f| analyzer.frame(file.hop(f, dt), (f + 1) as f64 * dt)).collect()
}

/// The writes that `file` makes through `scene`'s audio mappings for frames 0 up to (not
/// including) `frames` at step `dt`, by frame — what `render --audio` schedules.
pub fn file_script(file: &AudioFile, scene: &Scene, frames: u64, dt: f64) -> Vec<(u64, Vec<ControlEvent>)> {
    let mut mapper = AudioMapper::new(scene);
    (0u64..).zip(analyse_file(file, frames, dt)).map(|(f, frame)| (f, mapper.events(&frame, dt, scene))).collect()
}
