//! Audio analysis for modulation: level (RMS, peak), log-spaced bands from a real FFT, onsets by
//! spectral flux against an adaptive threshold, and a tempo estimate from the onset strength's
//! autocorrelation. It sees audio in hops (whatever arrived since the last frame) and keeps the
//! last [`FFT_SIZE`] samples for the spectrum, so a file analysed hop by hop on the fixed clock
//! gives the same numbers every time.

use std::collections::VecDeque;
use std::sync::Arc;

use realfft::RealToComplex;

/// Samples per spectrum (≈ 43 ms at 48 kHz).
pub const FFT_SIZE: usize = 2048;

/// Log-spaced bands from [`LOWEST_HZ`] to [`HIGHEST_HZ`].
pub const BANDS: usize = crate::scene::AUDIO_BANDS;
/// Lower edge of the first band.
pub const LOWEST_HZ: f32 = 30.0;
/// Upper edge of the last band.
pub const HIGHEST_HZ: f32 = 16_000.0;

/// Band values are dB above this floor, scaled to 0–1 at 0 dBFS.
const FLOOR_DB: f32 = -60.0;

/// Seconds of flux history for the onset threshold, and of onset strength for the tempo.
const FLUX_SECONDS: f64 = 1.0;
const TEMPO_SECONDS: f64 = 8.0;
/// Tempi the estimate considers.
const TEMPO_BPM: (f64, f64) = (60.0, 180.0);
/// Onsets closer than this are one.
const REFRACTORY_SECONDS: f64 = 0.1;

/// What one frame of audio measures.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AudioFrame {
    /// RMS of the hop (a full-scale sine: 0.707).
    pub level: f32,
    /// Largest absolute sample of the hop.
    pub peak: f32,
    /// [`BANDS`] log-spaced bands, 0 (−60 dBFS or less) to 1 (0 dBFS).
    pub bands: Vec<f32>,
    /// Mean of the bands below 250 Hz, 250 Hz–4 kHz, above 4 kHz.
    pub low: f32,
    /// See `low`.
    pub mid: f32,
    /// See `low`.
    pub high: f32,
    /// An onset (a hit, a note) started in this hop.
    pub onset: bool,
    /// The tempo the onsets suggest, once a few seconds were heard.
    pub bpm: Option<f64>,
}

/// Running analysis state.
pub struct Analyzer {
    rate: u32,
    fft: Arc<dyn RealToComplex<f32>>,
    window: Vec<f32>,
    history: VecDeque<f32>,
    previous: Vec<f32>,
    /// Spectral flux per frame, for the adaptive threshold, and its frame times.
    flux: VecDeque<(f64, f32)>,
    last_onset: Option<f64>,
    /// (time, onset strength) for the tempo estimate.
    strength: VecDeque<(f64, f32)>,
    /// Band edges as FFT bin ranges.
    band_bins: Vec<(usize, usize)>,
}

impl Analyzer {
    /// An analyzer for mono audio at `rate` samples per second.
    pub fn new(rate: u32) -> Self {
        let fft = realfft::RealFftPlanner::<f32>::new().plan_fft_forward(FFT_SIZE);
        // Hann window.
        let window =
            (0..FFT_SIZE).map(|i| 0.5 - 0.5 * (std::f32::consts::TAU * i as f32 / FFT_SIZE as f32).cos()).collect();
        let bin_hz = rate as f32 / FFT_SIZE as f32;
        let nyquist_bin = FFT_SIZE / 2;
        let band_bins = (0..BANDS)
            .map(|b| {
                let edge = |i: usize| LOWEST_HZ * (HIGHEST_HZ / LOWEST_HZ).powf(i as f32 / BANDS as f32);
                let lo = ((edge(b) / bin_hz).floor() as usize).clamp(1, nyquist_bin);
                let hi = ((edge(b + 1) / bin_hz).ceil() as usize).clamp(lo + 1, nyquist_bin + 1);
                (lo, hi)
            })
            .collect();
        Self {
            rate,
            fft,
            window,
            history: VecDeque::from(vec![0.0; FFT_SIZE]),
            previous: vec![0.0; FFT_SIZE / 2 + 1],
            flux: VecDeque::new(),
            last_onset: None,
            strength: VecDeque::new(),
            band_bins,
        }
    }

    /// The sample rate.
    pub fn rate(&self) -> u32 {
        self.rate
    }

    /// Analyses `hop` (the samples since the last frame), heard up to `seconds`.
    pub fn frame(&mut self, hop: &[f32], seconds: f64) -> AudioFrame {
        // A broken driver or file may hand over NaN: it counts as silence.
        let hop: Vec<f32> = hop.iter().map(|&s| if s.is_finite() { s } else { 0.0 }).collect();
        let peak = hop.iter().fold(0.0f32, |m, s| m.max(s.abs()));
        let level =
            if hop.is_empty() { 0.0 } else { (hop.iter().map(|s| s * s).sum::<f32>() / hop.len() as f32).sqrt() };
        self.history.extend(&hop);
        let excess = self.history.len().saturating_sub(FFT_SIZE);
        self.history.drain(..excess);
        let magnitudes = self.spectrum();
        // Band value: mean magnitude in dB over the floor, 0–1.
        let bands: Vec<f32> = self
            .band_bins
            .iter()
            .map(|&(lo, hi)| {
                let mean = magnitudes[lo..hi].iter().sum::<f32>() / (hi - lo) as f32;
                let db = 20.0 * mean.max(1e-9).log10();
                ((db - FLOOR_DB) / -FLOOR_DB).clamp(0.0, 1.0)
            })
            .collect();
        let centre = |b: usize| LOWEST_HZ * (HIGHEST_HZ / LOWEST_HZ).powf((b as f32 + 0.5) / BANDS as f32);
        let mean_of = |range: std::ops::Range<f32>| {
            let picked: Vec<f32> = (0..BANDS).filter(|&b| range.contains(&centre(b))).map(|b| bands[b]).collect();
            picked.iter().sum::<f32>() / picked.len().max(1) as f32
        };
        let (low, mid, high) = (mean_of(0.0..250.0), mean_of(250.0..4000.0), mean_of(4000.0..f32::MAX));
        let onset = self.onset(&magnitudes, seconds);
        self.previous = magnitudes;
        AudioFrame { level, peak, bands, low, mid, high, onset, bpm: self.tempo() }
    }

    /// Magnitudes of the last [`FFT_SIZE`] samples, scaled so a full-scale sine peaks at 1.
    fn spectrum(&self) -> Vec<f32> {
        let mut input: Vec<f32> = self.history.iter().zip(&self.window).map(|(s, w)| s * w).collect();
        let mut output = self.fft.make_output_vec();
        if self.fft.process(&mut input, &mut output).is_err() {
            return vec![0.0; FFT_SIZE / 2 + 1];
        }
        // A Hann-windowed sine of amplitude 1 gives |X| = N/4 at its bin.
        let scale = 4.0 / FFT_SIZE as f32;
        output.iter().map(|c| c.norm() * scale).collect()
    }

    /// Spectral flux (the rise of every bin since the last frame) against the mean plus twice
    /// the deviation of the last second: a hit stands out of steady music.
    fn onset(&mut self, magnitudes: &[f32], seconds: f64) -> bool {
        let flux: f32 = magnitudes.iter().zip(&self.previous).map(|(m, p)| (m - p).max(0.0)).sum();
        while self.flux.front().is_some_and(|&(t, _)| t < seconds - FLUX_SECONDS) {
            self.flux.pop_front();
        }
        let n = self.flux.len().max(1) as f32;
        let mean = self.flux.iter().map(|f| f.1).sum::<f32>() / n;
        let deviation = (self.flux.iter().map(|f| (f.1 - mean).powi(2)).sum::<f32>() / n).sqrt();
        self.flux.push_back((seconds, flux));
        let clear = self.last_onset.is_none_or(|t| seconds - t >= REFRACTORY_SECONDS);
        let onset = clear && self.flux.len() > 3 && flux > mean + 2.0 * deviation + 0.05;
        if onset {
            self.last_onset = Some(seconds);
        }
        while self.strength.front().is_some_and(|&(t, _)| t < seconds - TEMPO_SECONDS) {
            self.strength.pop_front();
        }
        self.strength.push_back((seconds, (flux - mean).max(0.0)));
        onset
    }

    /// The lag between 60 and 180 bpm at which the onset strength best matches itself.
    fn tempo(&self) -> Option<f64> {
        let (first, last) = (self.strength.front()?.0, self.strength.back()?.0);
        let n = self.strength.len();
        if last - first < 4.0 || n < 32 {
            return None;
        }
        let frame = (last - first) / (n - 1) as f64;
        let values: Vec<f32> = self.strength.iter().map(|s| s.1).collect();
        // Beat periods from 1/3 s (180 bpm) to 1 s (60 bpm), in frames.
        let (min_lag, max_lag) =
            ((60.0 / TEMPO_BPM.1 / frame).ceil() as usize, (60.0 / TEMPO_BPM.0 / frame).floor() as usize);
        let score = |lag: usize| values.iter().zip(&values[lag..]).map(|(a, b)| a * b).sum::<f32>() / (n - lag) as f32;
        let best = (min_lag.max(1)..=max_lag.min(n - 1)).max_by(|&a, &b| score(a).total_cmp(&score(b)))?;
        (score(best) > 0.0).then(|| 60.0 / (best as f64 * frame))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sine(rate: u32, hz: f32, amplitude: f32, samples: usize, from: usize) -> Vec<f32> {
        (from..from + samples)
            .map(|i| amplitude * (std::f32::consts::TAU * hz * i as f32 / rate as f32).sin())
            .collect()
    }

    #[test]
    fn a_sine_lands_in_its_band_with_its_level() {
        let rate = 48_000;
        let mut a = Analyzer::new(rate);
        let hop = rate as usize / 60;
        let mut frame = AudioFrame::default();
        for i in 0..10 {
            frame = a.frame(&sine(rate, 100.0, 0.5, hop, i * hop), (i + 1) as f64 / 60.0);
        }
        assert!((frame.level - 0.5 / 2f32.sqrt()).abs() < 0.01, "{}", frame.level);
        assert!((frame.peak - 0.5).abs() < 0.01);
        assert!(frame.low > 0.3 && frame.mid < 0.05 && frame.high < 0.05, "{frame:?}");
        let loudest = (0..BANDS).max_by(|&a, &b| frame.bands[a].total_cmp(&frame.bands[b])).unwrap();
        let hz = |i: usize| LOWEST_HZ * (HIGHEST_HZ / LOWEST_HZ).powf(i as f32 / BANDS as f32);
        assert!(hz(loudest) <= 100.0 && 100.0 <= hz(loudest + 1), "band {loudest}");
        // −6 dBFS is 0.9 on the 60 dB scale; the band's mean spreads it a little.
        assert!(frame.bands[loudest] > 0.7, "{}", frame.bands[loudest]);
    }

    #[test]
    fn silence_is_zero_and_nan_samples_do_not_poison_the_spectrum() {
        let mut a = Analyzer::new(44_100);
        let f = a.frame(&[0.0; 735], 1.0 / 60.0);
        assert_eq!((f.level, f.low, f.onset), (0.0, 0.0, false));
        let f = a.frame(&[f32::NAN; 735], 2.0 / 60.0);
        assert!(f.level == 0.0 && f.bands.iter().all(|b| b.is_finite()));
    }
}
