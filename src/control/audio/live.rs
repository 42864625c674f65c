//! Live audio input through cpal (ALSA on Linux, or JACK in builds with the `jack` feature): the
//! default input device, or the first whose name contains a filter. The driver's callback only
//! mixes to mono and appends to a bounded buffer (and, for a timecode chase, the code's channel
//! to a second one, stamped with when its first sample was captured); the analysis runs on the
//! render thread from what the buffers hold. No device, or no sound system at all, is a logged
//! fact and the show goes on (as with MIDI).

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use cpal::traits::{DeviceTrait, HostTrait, StreamTrait};

/// Most samples the buffer holds between frames (≈ 1 s at 48 kHz): a stalled render loop never
/// grows memory; the oldest samples go.
const MAX_BUFFERED: usize = 48_000;

/// The samples of the channel that carries a timecode, and when the first was captured.
#[derive(Default)]
struct CodeBuffer {
    samples: VecDeque<f32>,
    first: Option<Instant>,
}

/// An open input stream.
pub struct LiveAudio {
    _stream: cpal::Stream,
    buffer: Arc<Mutex<VecDeque<f32>>>,
    code: Option<Arc<Mutex<CodeBuffer>>>,
    /// Samples per second.
    pub rate: u32,
    /// The device's name.
    pub name: String,
}

/// Names of the input devices, default first.
pub fn list_devices() -> Result<Vec<String>, String> {
    let host = host()?;
    let devices = host.input_devices().map_err(|e| format!("no audio input devices: {e}"))?;
    Ok(devices.map(|d| d.to_string()).collect())
}

/// The sound system: JACK in builds with the `jack` feature, else the platform's default.
pub fn host() -> Result<cpal::Host, String> {
    #[cfg(feature = "jack")]
    return cpal::host_from_id(cpal::HostId::Jack).map_err(|e| format!("no JACK server for audio input: {e}"));
    #[cfg(not(feature = "jack"))]
    Ok(cpal::default_host())
}

impl LiveAudio {
    /// Opens the default input, or the first input whose name contains `filter`; with `code`,
    /// also keeps a timecode's channel (from 1, or `None` for the mix) for
    /// [`LiveAudio::drain_code`].
    pub fn open(filter: Option<&str>, code: Option<Option<u16>>) -> Result<Self, String> {
        let host = host()?;
        let device = match filter {
            None => host.default_input_device().ok_or("no default audio input device")?,
            Some(f) => host
                .input_devices()
                .map_err(|e| format!("no audio input devices: {e}"))?
                .find(|d| d.to_string().contains(f))
                .ok_or_else(|| {
                    format!("no audio input device name contains '{f}' (`indra --list-audio` lists them)")
                })?,
        };
        let name = device.to_string();
        let config = device.default_input_config().map_err(|e| format!("audio input {name}: {e}"))?;
        let channels = usize::from(config.channels().max(1));
        let rate = config.sample_rate();
        let code_channel = match code {
            Some(Some(c)) if c == 0 || usize::from(c) > channels => {
                return Err(format!(
                    "audio input {name} has {channels} channels: there is no channel {c} for the code"
                ));
            }
            Some(c) => Some(c.map(|c| usize::from(c) - 1)),
            None => None,
        };
        let buffer = Arc::new(Mutex::new(VecDeque::with_capacity(MAX_BUFFERED)));
        let code = code_channel.map(|_| Arc::new(Mutex::new(CodeBuffer::default())));
        let (sink, code_sink) = (buffer.clone(), code.clone());
        let stream = device
            .build_input_stream::<f32, _, _>(
                config.config(),
                move |data, info| {
                    let mix = |c: &[f32]| c.iter().sum::<f32>() / channels as f32;
                    if let Ok(mut b) = sink.lock() {
                        b.extend(data.chunks(channels).map(mix));
                        let excess = b.len().saturating_sub(MAX_BUFFERED);
                        b.drain(..excess);
                    }
                    if let (Some(code), Some(channel)) = (code_sink.as_ref(), code_channel)
                        && let Ok(mut code) = code.lock()
                    {
                        // The first sample was captured the driver's latency before this call.
                        let stamp = info.timestamp();
                        let latency = stamp.callback.duration_since(stamp.capture);
                        let first = Instant::now().checked_sub(latency).unwrap_or_else(Instant::now);
                        code.first.get_or_insert(first);
                        let frames = data.chunks(channels);
                        match channel {
                            Some(c) => code.samples.extend(frames.map(|f| f[c])),
                            None => code.samples.extend(frames.map(mix)),
                        }
                        let excess = code.samples.len().saturating_sub(MAX_BUFFERED);
                        code.samples.drain(..excess);
                        if excess > 0 {
                            code.first =
                                code.first.map(|t| t + Duration::from_secs_f64(excess as f64 / f64::from(rate)));
                        }
                    }
                },
                |e| log::warn!("audio input: {e}"),
                None,
            )
            .map_err(|e| format!("cannot open audio input {name}: {e}"))?;
        stream.play().map_err(|e| format!("cannot start audio input {name}: {e}"))?;
        log::info!("audio input: {name} at {rate} Hz");
        Ok(Self { _stream: stream, buffer, code, rate, name })
    }

    /// The samples that arrived since the last call.
    pub fn drain(&self) -> Vec<f32> {
        self.buffer.lock().map(|mut b| b.drain(..).collect()).unwrap_or_default()
    }

    /// The code channel's samples that arrived since the last call, and when the first of them
    /// was captured; `None` when none came (or no code channel was asked for).
    pub fn drain_code(&self) -> Option<(Vec<f32>, Instant)> {
        let mut code = self.code.as_ref()?.lock().ok()?;
        let first = code.first.take()?;
        Some((code.samples.drain(..).collect(), first))
    }
}
