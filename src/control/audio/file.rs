//! Audio files for deterministic renders: a WAV file (8–32-bit integer or float, any channel
//! count, mixed to mono) decoded with `hound`, or any other format (MP3, FLAC, Ogg, AAC, the sound
//! of a video) decoded by the `ffmpeg` program that video export uses and then read the same way.
//! The samples are cut into the hops that the fixed clock's frames cover, so
//! frame n always hears the audio up to (n + 1) × dt.

use std::path::Path;
use std::process::Command;

/// A decoded file: mono samples at their own rate.
#[derive(Clone, Debug)]
pub struct AudioFile {
    /// Samples per second.
    pub rate: u32,
    /// Mono samples, −1 to 1.
    pub samples: Vec<f32>,
}

impl AudioFile {
    /// Reads a WAV file, or has ffmpeg decode any other; every failure is one sentence naming the
    /// file.
    pub fn open(path: &Path) -> Result<Self, String> {
        Self::open_as(path, None)
    }

    /// Reads channel `channel` (from 1) alone, as [`AudioFile::open`] reads the mix: a
    /// timecode track beside the music is read unmixed.
    pub fn open_channel(path: &Path, channel: u16) -> Result<Self, String> {
        Self::open_as(path, Some(channel))
    }

    fn open_as(path: &Path, channel: Option<u16>) -> Result<Self, String> {
        match hound::WavReader::open(path) {
            Ok(reader) => read_wav(reader, channel).map_err(|e| format!("{}: {e}", path.display())),
            Err(hound::Error::IoError(io)) => Err(format!("cannot read audio file {}: {io}", path.display())),
            Err(_) => decode_with_ffmpeg(path, channel),
        }
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

/// The samples of an open WAV file (8–32-bit integer or float), mixed to mono by the mean of
/// the channels or only `channel` (from 1); a damaged file or a missing channel says why.
fn read_wav<R: std::io::Read>(reader: hound::WavReader<R>, channel: Option<u16>) -> Result<AudioFile, String> {
    let spec = reader.spec();
    let channels = usize::from(spec.channels.max(1));
    if let Some(c) = channel.filter(|c| *c == 0 || usize::from(*c) > channels) {
        return Err(format!("no channel {c}: the file has {channels} (numbered from 1)"));
    }
    let interleaved: Vec<f32> = match spec.sample_format {
        hound::SampleFormat::Float => reader.into_samples::<f32>().collect::<Result<_, _>>(),
        hound::SampleFormat::Int => {
            let scale = 1.0 / (1i64 << (spec.bits_per_sample.clamp(1, 32) - 1)) as f32;
            reader.into_samples::<i32>().map(|s| s.map(|v| v as f32 * scale)).collect::<Result<_, _>>()
        }
    }
    .map_err(|e| format!("damaged audio data ({e})"))?;
    let samples = match channel {
        Some(c) => {
            interleaved.chunks(channels).map(|frame| frame.get(usize::from(c) - 1).copied().unwrap_or(0.0)).collect()
        }
        None => interleaved.chunks(channels).map(|c| c.iter().sum::<f32>() / channels as f32).collect(),
    };
    Ok(AudioFile { rate: spec.sample_rate, samples })
}

/// Decodes a file that is not WAV with ffmpeg (`INDRA_FFMPEG`, as for video export, or `ffmpeg`
/// on the PATH) into a temporary 32-bit float WAV at the file's own rate and channels, then reads
/// that like any WAV file (ffmpeg's own downmix would not be the plain mean the WAV path takes).
fn decode_with_ffmpeg(path: &Path, channel: Option<u16>) -> Result<AudioFile, String> {
    let name = path.display();
    let program = std::env::var_os("INDRA_FFMPEG").unwrap_or_else(|| "ffmpeg".into());
    let decoded = tempfile_path();
    let output = Command::new(&program)
        .args(["-nostdin", "-v", "error", "-y", "-i"])
        .arg(path)
        .args(["-vn", "-c:a", "pcm_f32le", "-f", "wav"])
        .arg(&decoded)
        .output();
    let result = match output {
        Err(e) => Err(format!(
            "{name} is not a WAV file, and other formats are decoded by ffmpeg, which was not found ({e}): \
             install it (`apt-get install ffmpeg`) or convert the file to WAV"
        )),
        Ok(o) if !o.status.success() => {
            let said = String::from_utf8_lossy(&o.stderr);
            let last = said.lines().rev().find(|l| !l.trim().is_empty()).unwrap_or("no audio stream");
            Err(format!("{name} is neither a WAV file nor audio ffmpeg can decode ({})", last.trim()))
        }
        Ok(_) => hound::WavReader::open(&decoded)
            .map_err(|e| e.to_string())
            .and_then(|reader| read_wav(reader, channel))
            .map_err(|e| format!("{name}: ffmpeg's decoding cannot be read ({e})")),
    };
    let _ = std::fs::remove_file(&decoded);
    result
}

/// A fresh path in the temporary folder for a decoded file.
fn tempfile_path() -> std::path::PathBuf {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    std::env::temp_dir().join(format!("indra-decoded-{}-{n}.wav", std::process::id()))
}
