//! Audio analysis for modulation: level (RMS, peak), log-spaced bands from a real FFT, onsets by
//! spectral flux against an adaptive threshold, and a tempo estimate from the onset strength's
//! autocorrelation, with a beat tracker that locks to the onsets on that tempo's grid and keeps
//! the beat through a missed hit. It sees audio in hops (whatever arrived since the last frame) and keeps the
//! last [`FFT_SIZE`] samples for the spectrum, so a file analysed hop by hop on the fixed clock
//! gives the same numbers every time.

use std::collections::VecDeque;
use std::sync::Arc;

use realfft::RealToComplex;

pub use crate::params::AudioSnapshot;

/// Samples per spectrum (≈ 43 ms at 48 kHz).
pub const FFT_SIZE: usize = 2048;

/// Log-spaced bands from [`LOWEST_HZ`] to [`HIGHEST_HZ`].
pub const BANDS: usize = crate::scene::AUDIO_BANDS;
/// Lower edge of the first band.
pub const LOWEST_HZ: f32 = 30.0;
/// Upper edge of the last band.
pub const HIGHEST_HZ: f32 = 16_000.0;

/// Samples in an [`AudioSnapshot`]'s waveform.
pub const SNAPSHOT_SAMPLES: usize = 256;
/// Bins in an [`AudioSnapshot`]'s spectrum (each four FFT bins, up to half the sample rate).
pub const SNAPSHOT_BINS: usize = 256;

/// Band values are dB above this floor, scaled to 0–1 at 0 dBFS.
const FLOOR_DB: f32 = -60.0;

/// Seconds of flux history for the onset threshold, and of onset strength for the tempo.
const FLUX_SECONDS: f64 = 1.0;
const TEMPO_SECONDS: f64 = 8.0;
/// Tempi the estimate considers.
const TEMPO_BPM: (f64, f64) = (60.0, 180.0);
/// The tempo the estimate leans to when a period and its multiples match equally.
const TEMPO_PRIOR_BPM: f64 = 120.0;
/// Onsets closer than this are one.
const REFRACTORY_SECONDS: f64 = 0.1;
/// An onset this close to the predicted beat (a share of the beat period) is the beat.
const BEAT_WINDOW: f64 = 0.2;

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
    /// A beat of the music falls in this hop: an onset on the tempo's grid, or the grid's beat
    /// when the hit is missing. Before a tempo is heard, every onset is a beat.
    pub beat: bool,
    /// The tempo the onsets suggest, once a few seconds were heard.
    pub bpm: Option<f64>,
    /// What shaders sample (ISF `audio` and `audioFFT` inputs): the newest samples and the
    /// spectrum in linear bins.
    pub snapshot: AudioSnapshot,
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
    /// The beat tracker: when the next beat is due, and when the last one fell.
    next_beat: Option<f64>,
    last_beat: Option<f64>,
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
            next_beat: None,
            last_beat: None,
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
        let snapshot = self.snapshot(&magnitudes);
        self.previous = magnitudes;
        let bpm = self.tempo();
        let beat = self.beat(onset, bpm, seconds);
        AudioFrame { level, peak, bands, low, mid, high, onset, beat, bpm, snapshot }
    }

    /// Whether a beat falls at `seconds`: an onset near (or past) the predicted beat is the beat
    /// and sets the phase; a predicted beat with no onset near it still beats (the flywheel); an
    /// onset just after a flywheel beat moves the phase to it without beating twice; an onset
    /// between beats (an off-beat hit) is not a beat. No tempo: every onset beats.
    fn beat(&mut self, onset: bool, bpm: Option<f64>, seconds: f64) -> bool {
        let Some(bpm) = bpm else {
            self.next_beat = None;
            return onset;
        };
        let period = 60.0 / bpm;
        let window = BEAT_WINDOW * period;
        let just_beat = self.last_beat.is_some_and(|t| seconds - t <= window);
        if onset && just_beat {
            self.next_beat = Some(seconds + period);
            return false;
        }
        let due = self.next_beat.is_none_or(|next| seconds >= next - window);
        if onset && due {
            self.next_beat = Some(seconds + period);
        } else if let Some(next) = self.next_beat.filter(|&next| seconds >= next) {
            self.next_beat = Some(next + period);
        } else {
            return false;
        }
        self.last_beat = Some(seconds);
        true
    }

    /// The newest [`SNAPSHOT_SAMPLES`] samples and [`SNAPSHOT_BINS`] spectrum bins, each the
    /// mean of four FFT bins (about 94 Hz wide at 48 kHz), 0 (−60 dBFS or less) to 1 (0 dBFS)
    /// as the bands are.
    fn snapshot(&self, magnitudes: &[f32]) -> AudioSnapshot {
        let wave = self.history.iter().skip(FFT_SIZE - SNAPSHOT_SAMPLES).copied().collect();
        let per_bin = (FFT_SIZE / 2) / SNAPSHOT_BINS;
        let spectrum = (0..SNAPSHOT_BINS)
            .map(|b| {
                let bins = &magnitudes[b * per_bin..(b + 1) * per_bin];
                let mean = bins.iter().sum::<f32>() / per_bin as f32;
                ((20.0 * mean.max(1e-9).log10() - FLOOR_DB) / -FLOOR_DB).clamp(0.0, 1.0)
            })
            .collect();
        AudioSnapshot { wave, spectrum }
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

    /// The beat period between 60 and 180 bpm at which the onset strength best matches itself,
    /// refined to a fraction of a frame over several periods.
    fn tempo(&self) -> Option<f64> {
        let (first, last) = (self.strength.front()?.0, self.strength.back()?.0);
        let n = self.strength.len();
        if last - first < 4.0 || n < 32 {
            return None;
        }
        let frame = (last - first) / (n - 1) as f64;
        let values: Vec<f32> = self.strength.iter().map(|s| s.1).collect();
        let matched = |lag: usize| {
            if lag == 0 || lag >= n {
                return 0.0;
            }
            values.iter().zip(&values[lag..]).map(|(a, b)| a * b).sum::<f32>() / (n - lag) as f32
        };
        // Beat periods from 1/3 s (180 bpm) to 1 s (60 bpm), in frames.
        let (min_lag, max_lag) =
            ((60.0 / TEMPO_BPM.1 / frame).ceil() as usize, (60.0 / TEMPO_BPM.0 / frame).floor() as usize);
        // Every lag the search below looks at, matched once (this runs every frame).
        let table: Vec<f32> = (0..=max_lag + 2).map(matched).collect();
        let at = |lag: usize| table.get(lag).copied().unwrap_or_else(|| matched(lag));
        // A period that is not a whole number of frames splits its match over two lags.
        let near = |lag: usize| at(lag.saturating_sub(1)).max(at(lag)).max(at(lag + 1));
        // A pulse matches itself at every multiple of its period too. A tempo prior (an
        // octave-wide log-normal around 120 bpm, as in Ellis's beat tracker) leans to the middle,
        // and a lag whose half matches well is taken at its half.
        let prior = |lag: usize| {
            let octaves = (60.0 / (lag as f64 * frame) / TEMPO_PRIOR_BPM).log2();
            (-0.5 * octaves * octaves).exp() as f32
        };
        let best = (min_lag.max(1)..=max_lag.min(n - 1))
            .map(|lag| (lag, near(lag) * prior(lag)))
            .max_by(|a, b| a.1.total_cmp(&b.1))?
            .0;
        if near(best) <= 0.0 {
            return None;
        }
        // The prior must not pull the period off its own peak within the tolerance.
        let best = (best.saturating_sub(1).max(1)..=best + 1).max_by(|&a, &b| at(a).total_cmp(&at(b)))?;
        let half = best / 2;
        let mut period = best as f64;
        if half + 1 >= min_lag && near(half).max(near(half + 1)) >= 0.5 * near(best) {
            period /= 2.0;
        }
        // Refine over as many periods as half the history holds: the peak of the match near k
        // periods, interpolated by a parabola, divided by k.
        let k = ((n / 2) as f64 / period).floor().max(1.0);
        let around = (k * period).round() as usize;
        let reach = (k / 2.0).ceil() as usize + 1;
        let peak = (around.saturating_sub(reach).max(1)..=(around + reach).min(n - 2))
            .map(|lag| (lag, at(lag)))
            .max_by(|a, b| a.1.total_cmp(&b.1))?
            .0;
        let (l, c, r) = (at(peak - 1), at(peak), at(peak + 1));
        let curvature = l - 2.0 * c + r;
        let offset = if curvature < 0.0 { (0.5 * (l - r) / curvature).clamp(-0.5, 0.5) } else { 0.0 };
        let refined = (peak as f64 + f64::from(offset)) / k;
        Some(60.0 / (refined * frame))
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

    /// `seconds` of 60 Hz kicks (80 ms) at `bpm`, leaving out the kicks for which `missing` holds.
    fn kicks(rate: u32, bpm: f32, seconds: usize, missing: impl Fn(usize) -> bool) -> Vec<f32> {
        let period = 60.0 / bpm;
        (0..seconds * rate as usize)
            .map(|i| {
                let t = i as f32 / rate as f32;
                let (k, in_beat) = ((t / period) as usize, t % period);
                let on = !missing(k) && in_beat < 0.08;
                if on { 0.8 * (std::f32::consts::TAU * 60.0 * t).sin() * (1.0 - in_beat / 0.08) } else { 0.0 }
            })
            .collect()
    }

    /// Analyses `samples` in 60 Hz frames; the frames' results.
    fn frames(rate: u32, samples: &[f32]) -> Vec<AudioFrame> {
        let mut a = Analyzer::new(rate);
        let hop = rate as usize / 60;
        (0..samples.len() / hop).map(|f| a.frame(&samples[f * hop..(f + 1) * hop], (f + 1) as f64 / 60.0)).collect()
    }

    #[test]
    fn beats_lock_to_the_kicks_and_carry_on_through_missing_ones() {
        // 120 bpm; from 6 s on every fourth kick is missing.
        let rate = 48_000;
        let heard = frames(rate, &kicks(rate, 120.0, 12, |k| k >= 12 && k % 4 == 3));
        let beats: Vec<usize> = (0..heard.len()).filter(|&f| heard[f].beat).collect();
        // Every half second from 1 s on is a beat, within a frame of the grid, missing kicks
        // included; nothing else is.
        let late: Vec<usize> = beats.iter().copied().filter(|&f| f >= 60).collect();
        assert_eq!(late.len(), 22, "{beats:?}");
        for (i, f) in late.iter().enumerate() {
            assert!(f.abs_diff(60 + 30 * i) <= 1, "beat {i} at frame {f}: {beats:?}");
        }
    }

    #[test]
    fn slow_and_fast_tempi_are_heard_as_themselves_not_as_their_octaves() {
        let rate = 48_000;
        for bpm in [72.0, 100.0, 150.0, 175.0] {
            let heard = frames(rate, &kicks(rate, bpm, 9, |_| false));
            let estimate = heard.last().unwrap().bpm.expect("a tempo after 9 s");
            assert!((estimate - f64::from(bpm)).abs() < 1.0, "{bpm} heard as {estimate}");
        }
    }
}
