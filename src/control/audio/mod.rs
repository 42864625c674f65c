//! Sound as a control source: analysis (level, bands, onsets, tempo), the mapping of it to
//! parameters, WAV files for deterministic renders, and live input (cpal, behind the `audio`
//! feature). Every value reaches the scene as a parameter write, recorded and replayed like OSC.

pub mod analysis;
pub mod file;
pub mod learn;
#[cfg(feature = "audio")]
pub mod live;
pub mod mapping;

pub use analysis::{Analyzer, AudioFrame};
pub use file::AudioFile;
pub use learn::AudioLearn;
pub use mapping::AudioMapper;

use crate::params::ControlEvent;
use crate::scene::Scene;

/// The writes that `file` makes through `scene`'s audio mappings for frames 0 up to (not
/// including) `frames` at step `dt`, by frame — what `render --audio` schedules. Frames past the
/// file's end hear silence.
pub fn file_script(file: &AudioFile, scene: &Scene, frames: u64, dt: f64) -> Vec<(u64, Vec<ControlEvent>)> {
    let mut analyzer = Analyzer::new(file.rate);
    let mut mapper = AudioMapper::new(scene);
    (0..frames)
        .map(|f| {
            let frame = analyzer.frame(file.hop(f, dt), (f + 1) as f64 * dt);
            (f, mapper.events(&frame, dt, scene))
        })
        .collect()
}
