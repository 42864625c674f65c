//! Modulators on the fixed clock: LFOs (sine, triangle, saw, square, random) that move a
//! parameter through a range, at a rate in hertz or in beats of the show's tempo — and the tempo
//! clock itself, whose beat position advances by bpm / 60 · dt each step. Both step with the
//! fixed clock, so a render with the same control stream (tempo changes included) is the same
//! bytes, and a seek passes every beat.

use serde::Deserialize;

use crate::geometry::SplitMix64;

/// The tempo a scene starts at unless it says otherwise.
pub const DEFAULT_BPM: f64 = 120.0;

/// The tempo range accepted from any source (taps, OSC, MIDI clock, scenes).
pub const BPM_RANGE: (f64, f64) = (20.0, 400.0);

/// The waveform of an LFO, as a value in [0, 1] over one cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum LfoShape {
    /// 0.5 + 0.5·sin(2πx): starts at the middle, rising.
    #[default]
    Sine,
    /// 0 → 1 → 0, peak at half a cycle.
    Triangle,
    /// 0 → 1, then back to 0 at once.
    Saw,
    /// 1 for the first half cycle, 0 for the second.
    Square,
    /// A new random value each cycle, held (sample and hold), from the scene seed.
    Random,
}

/// How fast an LFO cycles.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
pub enum LfoRate {
    /// One cycle every this many beats of the show's tempo.
    Beats(f64),
    /// Cycles per second.
    Hz(f64),
}

impl LfoRate {
    /// Whether the rate is a positive, finite number.
    pub fn is_valid(&self) -> bool {
        let (LfoRate::Beats(x) | LfoRate::Hz(x)) = *self;
        x.is_finite() && x > 0.0
    }
}

/// The shape's value at cycle position `x` (any real; the integer part counts cycles). `key`
/// seeds the random shape (scene seed and the LFO's place), so each LFO has its own sequence.
pub fn shape_value(shape: LfoShape, x: f64, key: u64) -> f64 {
    let f = x - x.floor();
    match shape {
        LfoShape::Sine => 0.5 + 0.5 * (std::f64::consts::TAU * f).sin(),
        LfoShape::Triangle => 1.0 - (2.0 * f - 1.0).abs(),
        LfoShape::Saw => f,
        LfoShape::Square => {
            if f < 0.5 {
                1.0
            } else {
                0.0
            }
        }
        LfoShape::Random => {
            let cycle = x.floor() as i64 as u64;
            let mut rng = SplitMix64::new(key ^ cycle.wrapping_mul(0x9E37_79B9_7F4A_7C15));
            rng.unit()
        }
    }
}

/// An LFO bound to a parameter (or one component of it).
#[derive(Clone, Debug, PartialEq)]
pub struct Lfo {
    /// The parameter it moves.
    pub target: super::Target,
    /// The waveform.
    pub shape: LfoShape,
    /// How fast.
    pub rate: LfoRate,
    /// The values at the shape's 0 and 1.
    pub range: (f32, f32),
    /// Offset in cycles (0.25: a quarter cycle ahead).
    pub phase: f64,
}

impl Lfo {
    /// The value at `seconds` on the clock and `beats` of the tempo clock; `key` seeds Random.
    pub fn value(&self, seconds: f64, beats: f64, key: u64) -> f32 {
        let cycles = match self.rate {
            LfoRate::Hz(hz) => seconds * hz,
            LfoRate::Beats(n) => beats / n,
        } + self.phase;
        let (lo, hi) = self.range;
        (f64::from(lo) + (f64::from(hi) - f64::from(lo)) * shape_value(self.shape, cycles, key)) as f32
    }
}

/// The show's tempo and beat position, advanced on the fixed clock.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TempoClock {
    /// Beats per minute.
    pub bpm: f64,
    /// Beats since frame 0 (fractional part: the phase within the beat).
    pub beats: f64,
}

impl TempoClock {
    /// A clock at beat 0 and `bpm` (clamped to [`BPM_RANGE`]).
    pub fn new(bpm: f64) -> Self {
        Self { bpm: clamp_bpm(bpm).unwrap_or(DEFAULT_BPM), beats: 0.0 }
    }

    /// Advances by one step of `dt` seconds.
    pub fn step(&mut self, dt: f64) {
        self.beats += self.bpm / 60.0 * dt;
    }

    /// Sets the tempo; with `resync` the beat position snaps to the nearest whole beat (a tap
    /// lands on the beat). A non-finite tempo is ignored.
    pub fn set(&mut self, bpm: f64, resync: bool) {
        if let Some(bpm) = clamp_bpm(bpm) {
            self.bpm = bpm;
        }
        if resync {
            self.beats = self.beats.round();
        }
    }
}

impl TempoClock {
    /// Moves the beat position by the shortest way (at most half a bar) to `phase` within a bar
    /// of `quantum` beats. Anything not finite, or a bar shorter than a beat, is ignored.
    pub fn align(&mut self, phase: f64, quantum: f64) {
        if !(phase.is_finite() && quantum.is_finite() && quantum >= 1.0) {
            return;
        }
        self.beats += phase_offset(self.beats, phase, quantum);
    }
}

/// How far (in beats, −quantum/2 up to quantum/2) `phase` within a bar of `quantum` beats is
/// ahead of the beat position `beats`.
pub fn phase_offset(beats: f64, phase: f64, quantum: f64) -> f64 {
    let half = quantum / 2.0;
    (phase - beats.rem_euclid(quantum) + half).rem_euclid(quantum) - half
}

/// `bpm` within [`BPM_RANGE`], or None when it is not a finite number.
pub fn clamp_bpm(bpm: f64) -> Option<f64> {
    bpm.is_finite().then(|| bpm.clamp(BPM_RANGE.0, BPM_RANGE.1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_take_their_values_at_the_quarter_cycles() {
        let at = |shape, x| shape_value(shape, x, 7);
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        assert!(close(at(LfoShape::Sine, 0.0), 0.5) && close(at(LfoShape::Sine, 0.25), 1.0));
        assert!(close(at(LfoShape::Sine, 0.75), 0.0) && close(at(LfoShape::Sine, 3.25), 1.0));
        assert!(close(at(LfoShape::Triangle, 0.0), 0.0) && close(at(LfoShape::Triangle, 0.5), 1.0));
        assert!(close(at(LfoShape::Triangle, 0.25), 0.5) && close(at(LfoShape::Triangle, -0.25), 0.5));
        assert!(close(at(LfoShape::Saw, 0.3), 0.3) && close(at(LfoShape::Saw, 2.7), 0.7));
        assert!(close(at(LfoShape::Square, 0.49), 1.0) && close(at(LfoShape::Square, 0.5), 0.0));
    }

    #[test]
    fn random_holds_within_a_cycle_changes_between_and_repeats_exactly() {
        let values: Vec<f64> = (0..64).map(|c| shape_value(LfoShape::Random, c as f64 + 0.1, 99)).collect();
        for (c, v) in values.iter().enumerate() {
            assert!((0.0..1.0).contains(v));
            assert_eq!(*v, shape_value(LfoShape::Random, c as f64 + 0.9, 99), "held through cycle {c}");
        }
        let distinct: std::collections::BTreeSet<u64> = values.iter().map(|v| v.to_bits()).collect();
        assert_eq!(distinct.len(), 64);
        assert_ne!(values[3], shape_value(LfoShape::Random, 3.5, 100), "another key, another sequence");
    }

    #[test]
    fn beats_follow_the_tempo_and_a_resync_lands_on_the_beat() {
        let mut clock = TempoClock::new(120.0);
        for _ in 0..60 {
            clock.step(1.0 / 60.0);
        }
        assert!((clock.beats - 2.0).abs() < 1e-9, "120 bpm: 2 beats a second");
        clock.set(90.0, false);
        for _ in 0..40 {
            clock.step(1.0 / 60.0);
        }
        assert!((clock.beats - 3.0).abs() < 1e-9, "the phase carries over a tempo change");
        clock.beats = 7.4;
        clock.set(f64::NAN, true);
        assert_eq!((clock.bpm, clock.beats), (90.0, 7.0));
        clock.set(10_000.0, false);
        assert_eq!(clock.bpm, BPM_RANGE.1);
    }

    #[test]
    fn align_takes_the_shortest_way_to_the_phase_and_ignores_nonsense() {
        let mut clock = TempoClock { bpm: 120.0, beats: 9.5 };
        clock.align(3.25, 4.0);
        assert!((clock.beats - 11.25).abs() < 1e-12, "9.5 is 1.5 in the bar: 1.75 ahead → {}", clock.beats);
        clock.align(0.0, 4.0);
        assert!((clock.beats - 12.0).abs() < 1e-12, "3.25 → 0 goes forward 0.75 → {}", clock.beats);
        clock.align(3.5, 4.0);
        assert!((clock.beats - 11.5).abs() < 1e-12, "0 → 3.5 goes back 0.5 → {}", clock.beats);
        for (phase, quantum) in [(f64::NAN, 4.0), (1.0, 0.0), (1.0, f64::INFINITY)] {
            clock.align(phase, quantum);
            assert_eq!(clock.beats, 11.5);
        }
    }

    #[test]
    fn an_lfo_in_beats_cycles_with_the_tempo() {
        let target = super::super::Target { node: 0, param: 0, component: None };
        let lfo = Lfo { target, shape: LfoShape::Saw, rate: LfoRate::Beats(4.0), range: (10.0, 20.0), phase: 0.0 };
        assert_eq!(lfo.value(0.0, 1.0, 0), 12.5);
        let hz = Lfo { rate: LfoRate::Hz(0.5), phase: 0.25, ..lfo };
        assert_eq!(hz.value(1.0, 0.0, 0), 17.5);
    }
}
