//! Where the show's tempo comes from besides the scene: tap tempo (key T, the panel, OSC
//! `/indra/tempo/tap`), a set BPM (OSC `/indra/tempo/bpm f`), MIDI clock, and a shared session
//! (Ableton Link, see [`SessionFollower`]). Each becomes a [`ControlEvent::Tempo`] (or
//! [`ControlEvent::Phase`]), applied on the fixed clock and recorded like any other event, so a
//! replay follows the same tempo.

use std::time::Instant;

use crate::params::ControlEvent;
use crate::params::lfo::{TempoClock, clamp_bpm, phase_offset};

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

/// A shared session's tempo differences smaller than this are not followed.
const SESSION_FOLLOW_BPM: f64 = 0.005;
/// A shared session's phase is followed once the show drifts this many beats from it (10 ms at
/// 120 bpm): closer, the jump would be invisible and only fill the recording.
const SESSION_FOLLOW_BEATS: f64 = 0.02;

/// Keeps the show's tempo clock with a shared session (Ableton Link): the session's tempo and
/// phase become events, and a tempo set here (a tap, OSC, MIDI clock, the scene) is proposed to
/// the session instead of being overridden by it.
#[derive(Debug, Default)]
pub struct SessionFollower {
    /// The tempo the show's clock had after the last follow.
    known: Option<f64>,
}

/// What following the session asks for this frame.
#[derive(Debug, Default, PartialEq)]
pub struct Follow {
    /// Events that bring the show's clock to the session.
    pub events: Vec<ControlEvent>,
    /// A tempo to propose to the session (the show's tempo was changed here).
    pub propose: Option<f64>,
}

impl SessionFollower {
    /// Compares the show's `clock` with the session's tempo and its phase within a bar of
    /// `quantum` beats (taken at the moment the events will apply).
    pub fn follow(&mut self, clock: &TempoClock, session_bpm: f64, session_phase: f64, quantum: f64) -> Follow {
        if let Some(known) = self.known
            && (clock.bpm - known).abs() > 1e-9
        {
            self.known = Some(clock.bpm);
            return Follow { events: Vec::new(), propose: Some(clock.bpm) };
        }
        let mut events = Vec::new();
        let bpm = clamp_bpm(session_bpm).unwrap_or(clock.bpm);
        if (bpm - clock.bpm).abs() > SESSION_FOLLOW_BPM {
            events.push(ControlEvent::Tempo { bpm, resync: false });
        }
        self.known = Some(if events.is_empty() { clock.bpm } else { bpm });
        if session_phase.is_finite() && phase_offset(clock.beats, session_phase, quantum).abs() > SESSION_FOLLOW_BEATS {
            events.push(ControlEvent::Phase { phase: session_phase, quantum });
        }
        Follow { events, propose: None }
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
    fn a_session_is_followed_and_a_tempo_set_here_is_proposed_to_it() {
        let mut clock = TempoClock::new(120.0);
        let mut follower = SessionFollower::default();
        // Joining: the session's tempo and phase are taken.
        let follow = follower.follow(&clock, 128.0, 1.5, 4.0);
        assert_eq!(
            follow.events,
            [ControlEvent::Tempo { bpm: 128.0, resync: false }, ControlEvent::Phase { phase: 1.5, quantum: 4.0 }]
        );
        clock.set(128.0, false);
        clock.align(1.5, 4.0);
        // In step: nothing; a small drift is left alone, a larger one is followed.
        assert_eq!(follower.follow(&clock, 128.0, 1.51, 4.0), Follow::default());
        assert_eq!(follower.follow(&clock, 128.0, 1.6, 4.0).events, [ControlEvent::Phase { phase: 1.6, quantum: 4.0 }]);
        // A tap here sets 100 bpm: proposed to the session, not undone by it.
        clock.set(100.0, true);
        assert_eq!(follower.follow(&clock, 128.0, 1.6, 4.0), Follow { events: Vec::new(), propose: Some(100.0) });
        // A session tempo outside indra's range is followed as far as the range goes, once.
        let out_of_range = follower.follow(&clock, 999.0, 0.0, 4.0);
        let clamped = clamp_bpm(999.0).unwrap();
        assert_eq!(out_of_range.events[0], ControlEvent::Tempo { bpm: clamped, resync: false });
        clock.set(clamped, false);
        assert_eq!(follower.follow(&clock, 999.0, clock.beats.rem_euclid(4.0), 4.0), Follow::default());
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
