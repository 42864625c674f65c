//! Audio files for deterministic renders: a WAV file (8–32-bit integer or float, any channel
//! count, mixed to mono) decoded with `hound`, cut into the hops that the fixed clock's frames
//! cover, so frame n always hears the audio up to (n + 1) × dt.

use std::path::Path;

/// A decoded file: mono samples at their own rate.
#[derive(Clone, Debug)]
pub struct AudioFile {
    /// Samples per second.
    pub rate: u32,
    /// Mono samples, −1 to 1.
    pub samples: Vec<f32>,
}

impl AudioFile {
    /// Reads a WAV file; every failure is one sentence naming the file.
    pub fn open(path: &Path) -> Result<Self, String> {
        let name = path.display();
        let reader = hound::WavReader::open(path).map_err(|e| match e {
            hound::Error::IoError(io) => format!("cannot read audio file {name}: {io}"),
            other => format!(
                "{name} is not a WAV file indra can read ({other}); convert it, e.g. `ffmpeg -i in.mp3 out.wav`"
            ),
        })?;
        let spec = reader.spec();
        let channels = usize::from(spec.channels.max(1));
        let interleaved: Vec<f32> = match spec.sample_format {
            hound::SampleFormat::Float => reader.into_samples::<f32>().collect::<Result<_, _>>(),
            hound::SampleFormat::Int => {
                let scale = 1.0 / (1i64 << (spec.bits_per_sample.clamp(1, 32) - 1)) as f32;
                reader.into_samples::<i32>().map(|s| s.map(|v| v as f32 * scale)).collect::<Result<_, _>>()
            }
        }
        .map_err(|e| format!("{name}: damaged audio data ({e})"))?;
        let samples = interleaved.chunks(channels).map(|c| c.iter().sum::<f32>() / channels as f32).collect();
        Ok(Self { rate: spec.sample_rate, samples })
    }

    /// Seconds of audio.
    pub fn seconds(&self) -> f64 {
        self.samples.len() as f64 / f64::from(self.rate.max(1))
    }

    /// The samples of frame `frame` at step `dt`: from frame × dt to (frame + 1) × dt (empty
    /// past the end: silence).
    pub fn hop(&self, frame: u64, dt: f64) -> &[f32] {
        let at = |f: u64| ((f as f64 * dt * f64::from(self.rate)).round() as usize).min(self.samples.len());
        &self.samples[at(frame)..at(frame + 1)]
    }
}
