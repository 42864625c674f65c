//! The live sound input the control hub listens to: the device (behind the `audio` feature) and
//! its analysis, opened only when something listens.

use super::AudioFrame;

/// A live input with its analyzer and the time of its last frame.
pub struct LiveSound {
    #[cfg(feature = "audio")]
    input: super::live::LiveAudio,
    analyzer: super::Analyzer,
    started: std::time::Instant,
    last: f64,
}

impl LiveSound {
    /// Analyses what arrived since the last frame; with the real seconds it covered.
    pub fn analyse(&mut self) -> Option<(AudioFrame, f64)> {
        #[cfg(feature = "audio")]
        let samples = self.input.drain();
        #[cfg(not(feature = "audio"))]
        let samples: Vec<f32> = Vec::new();
        if samples.is_empty() {
            return None;
        }
        let now = self.started.elapsed().as_secs_f64();
        let dt = (now - self.last).max(1e-3);
        self.last = now;
        Some((self.analyzer.frame(&samples, now), dt))
    }
}

/// Opens the audio input `wanted` asks for (see [`ControlOptions::audio_in`]; the default device
/// only when `mapped`: some mapping listens). No device, or a build without the `audio` feature,
/// is a logged fact (a notice when a device was named).
pub fn open_audio(wanted: Option<&Option<String>>, mapped: bool, notices: &mut Vec<String>) -> Option<LiveSound> {
    let filter = match wanted {
        None => return None,
        Some(None) if !mapped => return None,
        Some(filter) => filter.as_deref(),
    };
    #[cfg(feature = "audio")]
    {
        match super::live::LiveAudio::open(filter) {
            Ok(input) => {
                let analyzer = super::Analyzer::new(input.rate);
                Some(LiveSound { input, analyzer, started: std::time::Instant::now(), last: 0.0 })
            }
            Err(e) => {
                log::info!("{e}; the scene's audio mappings stay still");
                if filter.is_some() {
                    notices.push(e);
                }
                None
            }
        }
    }
    #[cfg(not(feature = "audio"))]
    {
        let message = "this build has no live audio input (built without the `audio` feature)";
        log::info!("{message}");
        if filter.is_some() {
            notices.push(message.into());
        }
        None
    }
}
