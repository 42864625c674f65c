//! Live audio input through cpal: the default input device, or the first whose name contains a
//! filter. The driver's callback only mixes to mono and appends to a bounded buffer; the
//! analysis runs on the render thread from what the buffer holds. No device, or no sound system
//! at all, is a logged fact and the show goes on (as with MIDI).

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

use cpal::traits::{DeviceTrait, HostTrait, StreamTrait};

/// Most samples the buffer holds between frames (≈ 1 s at 48 kHz): a stalled render loop never
/// grows memory; the oldest samples go.
const MAX_BUFFERED: usize = 48_000;

/// An open input stream.
pub struct LiveAudio {
    _stream: cpal::Stream,
    buffer: Arc<Mutex<VecDeque<f32>>>,
    /// Samples per second.
    pub rate: u32,
    /// The device's name.
    pub name: String,
}

/// Names of the input devices, default first.
pub fn list_devices() -> Result<Vec<String>, String> {
    let host = cpal::default_host();
    let devices = host.input_devices().map_err(|e| format!("no audio input devices: {e}"))?;
    Ok(devices.map(|d| d.to_string()).collect())
}

impl LiveAudio {
    /// Opens the default input, or the first input whose name contains `filter`.
    pub fn open(filter: Option<&str>) -> Result<Self, String> {
        let host = cpal::default_host();
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
        let buffer = Arc::new(Mutex::new(VecDeque::with_capacity(MAX_BUFFERED)));
        let sink = buffer.clone();
        let stream = device
            .build_input_stream::<f32, _, _>(
                config.config(),
                move |data, _| {
                    if let Ok(mut b) = sink.lock() {
                        b.extend(data.chunks(channels).map(|c| c.iter().sum::<f32>() / channels as f32));
                        let excess = b.len().saturating_sub(MAX_BUFFERED);
                        b.drain(..excess);
                    }
                },
                |e| log::warn!("audio input: {e}"),
                None,
            )
            .map_err(|e| format!("cannot open audio input {name}: {e}"))?;
        stream.play().map_err(|e| format!("cannot start audio input {name}: {e}"))?;
        log::info!("audio input: {name} at {rate} Hz");
        Ok(Self { _stream: stream, buffer, rate, name })
    }

    /// The samples that arrived since the last call.
    pub fn drain(&self) -> Vec<f32> {
        self.buffer.lock().map(|mut b| b.drain(..).collect()).unwrap_or_default()
    }
}
