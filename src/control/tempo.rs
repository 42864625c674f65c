//! Where the show's tempo comes from besides the scene: tap tempo (key T, the panel, OSC
//! `/indra/tempo/tap`), a set BPM (OSC `/indra/tempo/bpm f`) and MIDI clock. Each becomes a
//! [`ControlEvent::Tempo`], applied on the fixed clock and recorded like any other event, so a
//! replay follows the same tempo.

use std::time::Instant;

use crate::params::ControlEvent;

/// Taps further apart than this start a new count.
const TAP_TIMEOUT_SECONDS: f64 = 2.0;

/// Intervals averaged (the last four taps' spacing, so a late tap moves the tempo a little).
const TAP_INTERVALS: usize = 4;

/// MIDI clock tempo changes smaller than this are not followed (its jitter would otherwise flood
/// the recording with tempo events).
const CLOCK_FOLLOW_BPM: f64 = 0.5;

/// Tap tempo: the mean interval of the last few taps.
#[derive(Debug, Default)]
pub struct TapTempo {
    taps: Vec<f64>,
}

impl TapTempo {
    /// A tap at `seconds` (any monotonic clock). From the second tap on, the tempo the taps give,
    /// with the beat put on this tap.
    pub fn tap(&mut self, seconds: f64) -> Option<ControlEvent> {
        if self.taps.last().is_some_and(|&last| !(seconds - last > 0.0 && seconds - last <= TAP_TIMEOUT_SECONDS)) {
            self.taps.clear();
        }
        self.taps.push(seconds);
        if self.taps.len() > TAP_INTERVALS + 1 {
            self.taps.remove(0);
        }
        let (first, last) = (self.taps.first()?, self.taps.last()?);
        let intervals = (self.taps.len() - 1) as f64;
        (intervals > 0.0).then(|| ControlEvent::Tempo { bpm: 60.0 * intervals / (last - first), resync: true })
    }
}

/// Everything that sets the tempo live.
#[derive(Debug)]
pub struct TempoInput {
    tap: TapTempo,
    started: Instant,
    /// The MIDI clock tempo last followed.
    followed: Option<f64>,
}

impl Default for TempoInput {
    fn default() -> Self {
        Self { tap: TapTempo::default(), started: Instant::now(), followed: None }
    }
}

impl TempoInput {
    /// A tap now.
    pub fn tap(&mut self) -> Option<ControlEvent> {
        self.tap.tap(self.started.elapsed().as_secs_f64())
    }

    /// The event that follows the MIDI clock's tempo, when it moved enough since last time.
    pub fn follow_clock(&mut self, bpm: Option<f64>) -> Option<ControlEvent> {
        let bpm = bpm.filter(|b| b.is_finite())?;
        if self.followed.is_some_and(|f| (f - bpm).abs() < CLOCK_FOLLOW_BPM) {
            return None;
        }
        self.followed = Some(bpm);
        Some(ControlEvent::Tempo { bpm, resync: false })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bpm(event: Option<ControlEvent>) -> Option<f64> {
        match event {
            Some(ControlEvent::Tempo { bpm, resync: true }) => Some(bpm),
            _ => None,
        }
    }

    #[test]
    fn taps_half_a_second_apart_are_120_bpm_and_a_pause_starts_over() {
        let mut taps = TapTempo::default();
        assert_eq!(bpm(taps.tap(10.0)), None, "one tap is no tempo");
        assert!((bpm(taps.tap(10.5)).unwrap() - 120.0).abs() < 1e-9);
        for t in [11.0, 11.5, 12.0, 12.5] {
            assert!((bpm(taps.tap(t)).unwrap() - 120.0).abs() < 1e-9);
        }
        // After a pause, two taps 0.4 s apart: 150 bpm, nothing of the old count.
        assert_eq!(bpm(taps.tap(20.0)), None);
        assert!((bpm(taps.tap(20.4)).unwrap() - 150.0).abs() < 1e-9);
    }

    #[test]
    fn the_midi_clock_is_followed_past_its_jitter_only() {
        let mut input = TempoInput::default();
        assert!(input.follow_clock(None).is_none());
        assert_eq!(input.follow_clock(Some(128.0)), Some(ControlEvent::Tempo { bpm: 128.0, resync: false }));
        assert!(input.follow_clock(Some(128.3)).is_none());
        assert!(input.follow_clock(Some(126.0)).is_some());
    }
}
