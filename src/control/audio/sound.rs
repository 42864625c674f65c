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

    /// The timecode channel's samples since the last call (see [`open_audio`]'s `code`): the
    /// samples, their rate, and when the first was captured.
    pub fn code(&mut self) -> Option<(Vec<f32>, u32, std::time::Instant)> {
        #[cfg(feature = "audio")]
        return self.input.drain_code().map(|(samples, first)| (samples, self.input.rate, first));
        #[cfg(not(feature = "audio"))]
        None
    }
}

/// Opens the audio input `wanted` asks for (see [`ControlOptions::audio_in`]; the default device
/// only when `mapped`: some mapping listens, or `code` asks for a timecode's channel, from 1 or
/// `None` for the mix). No device, or a build without the `audio` feature, is a logged fact (a
/// notice when a device was named or a code is chased).
///
/// [`ControlOptions::audio_in`]: crate::control::hub::ControlOptions::audio_in
pub fn open_audio(
    wanted: Option<&Option<String>>,
    mapped: bool,
    code: Option<Option<u16>>,
    notices: &mut Vec<String>,
) -> Option<LiveSound> {
    let filter = match wanted {
        None if code.is_some() => {
            notices.push("LTC is chased from the audio input, which is off: no code will come".into());
            return None;
        }
        None => return None,
        Some(None) if !mapped && code.is_none() => return None,
        Some(filter) => filter.as_deref(),
    };
    let told = filter.is_some() || code.is_some();
    #[cfg(feature = "audio")]
    {
        match super::live::LiveAudio::open(filter, code) {
            Ok(input) => {
                let analyzer = super::Analyzer::new(input.rate);
                Some(LiveSound { input, analyzer, started: std::time::Instant::now(), last: 0.0 })
            }
            Err(e) => {
                log::info!("{e}; the scene's audio mappings stay still");
                if told {
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
        if told {
            notices.push(message.into());
        }
        None
    }
}
