//! LTC out as live audio: indra as the timecode master of a sound desk on an audio output
//! (`run --ltc-out RATE`). The render thread reports the show's position after each frame
//! (never waiting for the lock); the audio callback writes the code for it on the output's
//! first channel (silence on the others) through [`LtcFollower`], which runs on the audio clock
//! and follows the reports. No device, or a build without the `audio` feature, is one message
//! and the show goes on.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use crate::timecode::Rate;
#[cfg(feature = "audio")]
use crate::timecode::ltc_follow::{LtcFollower, ShowPosition};

/// The code's level: −6 dBFS, a desk's usual line level for LTC.
#[cfg(feature = "audio")]
const LEVEL: f32 = 0.5;

/// What the render thread shares with the audio callback.
#[derive(Default)]
struct Shared {
    /// The show's position in code seconds, at an instant.
    position: Mutex<Option<(f64, Instant)>>,
    frames: AtomicU64,
    jumps: AtomicU64,
}

/// An open LTC output.
pub struct LtcOut {
    #[cfg(feature = "audio")]
    _stream: cpal::Stream,
    shared: Arc<Shared>,
    rate: Rate,
    name: String,
}

impl LtcOut {
    /// Sends LTC at `rate` on the default output, or the first whose name contains `filter`.
    pub fn open(filter: Option<&str>, rate: Rate) -> Result<Self, String> {
        #[cfg(feature = "audio")]
        return open(filter, rate);
        #[cfg(not(feature = "audio"))]
        {
            let _ = (filter, rate);
            Err("this build has no audio output for LTC (built without the `audio` feature)".into())
        }
    }

    /// The show is at `code_seconds` now (after a frame). Skipped when the callback holds the
    /// lock: the next frame reports again.
    pub fn report(&self, code_seconds: f64) {
        if let Ok(mut position) = self.shared.position.try_lock() {
            *position = Some((code_seconds, Instant::now()));
        }
    }

    /// The code's rate.
    pub fn rate(&self) -> Rate {
        self.rate
    }

    /// For the status line.
    pub fn status(&self) -> String {
        let (frames, jumps) = (self.shared.frames.load(Ordering::Relaxed), self.shared.jumps.load(Ordering::Relaxed));
        format!("LTC out {} on {}: {frames} frames, {jumps} jumps", self.rate, self.name)
    }
}

#[cfg(feature = "audio")]
fn open(filter: Option<&str>, rate: Rate) -> Result<LtcOut, String> {
    use cpal::traits::{DeviceTrait, HostTrait, StreamTrait};
    let host = super::audio::live::host()?;
    let device = match filter {
        None => host.default_output_device().ok_or("no default audio output device for LTC")?,
        Some(f) => host
            .output_devices()
            .map_err(|e| format!("no audio output devices: {e}"))?
            .find(|d| d.to_string().contains(f))
            .ok_or_else(|| format!("no audio output device name contains '{f}'"))?,
    };
    let name = device.to_string();
    let config = device.default_output_config().map_err(|e| format!("audio output {name}: {e}"))?;
    let channels = usize::from(config.channels().max(1));
    let mut follower = LtcFollower::new(config.sample_rate(), rate, LEVEL);
    let shared = Arc::new(Shared::default());
    let callback_shared = Arc::clone(&shared);
    let (mut last, mut code) = (None, Vec::new());
    let stream = device
        .build_output_stream::<f32, _, _>(
            config.config(),
            move |data, info| {
                if let Ok(position) = callback_shared.position.try_lock() {
                    last = *position;
                }
                // The block's first sample sounds the driver's latency after this call.
                let stamp = info.timestamp();
                let first = Instant::now() + stamp.playback.duration_since(stamp.callback);
                let show = last.map(|(seconds, at)| {
                    let age = first.saturating_duration_since(at).as_secs_f64();
                    ShowPosition { seconds: seconds + age, age }
                });
                code.resize(data.len() / channels, 0.0);
                follower.fill(&mut code, show);
                for (frame, sample) in data.chunks_mut(channels).zip(&code) {
                    frame.fill(0.0);
                    frame[0] = *sample;
                }
                callback_shared.frames.store(follower.frames, Ordering::Relaxed);
                callback_shared.jumps.store(follower.jumps, Ordering::Relaxed);
            },
            |e| log::warn!("LTC out: {e}"),
            None,
        )
        .map_err(|e| format!("cannot open audio output {name} for LTC: {e}"))?;
    stream.play().map_err(|e| format!("cannot start audio output {name} for LTC: {e}"))?;
    log::info!("LTC out at {rate} on {name}");
    Ok(LtcOut { _stream: stream, shared, rate, name })
}
