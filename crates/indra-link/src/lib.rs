//! Ableton Link for indra, kept in its own crate because Link is GPL-2.0-or-later: indra links
//! it only when built with `--features link`.
//!
//! A [`LinkSession`] joins the Link session on the local network (peers are found by multicast;
//! none is a session of one), reads the shared tempo and the beat within a bar of `quantum`
//! beats, and proposes tempo changes, which every peer follows.

use rusty_link::{AblLink, SessionState};

/// Where the session stands at one moment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkBeat {
    /// The shared tempo.
    pub bpm: f64,
    /// The beat position on the session's timeline (its fraction: the phase within the beat).
    pub beat: f64,
    /// The beat within the bar, 0 up to `quantum`: what every peer agrees on.
    pub phase: f64,
    /// Other apps in the session.
    pub peers: u64,
}

/// A membership of the Link session; leaves it when dropped.
pub struct LinkSession {
    link: AblLink,
    state: SessionState,
    quantum: f64,
}

impl LinkSession {
    /// Joins the session, proposing `bpm` if there is nobody to follow yet; bars are `quantum`
    /// beats long (4 in 4/4).
    pub fn join(bpm: f64, quantum: f64) -> Self {
        let link = AblLink::new(bpm);
        link.enable(true);
        Self { link, state: SessionState::new(), quantum: quantum.max(1.0) }
    }

    /// The session now, `ahead_micros` into the future (the time until what is computed now is
    /// seen: a frame or two).
    pub fn now(&mut self, ahead_micros: i64) -> LinkBeat {
        self.link.capture_app_session_state(&mut self.state);
        let time = self.link.clock_micros() + ahead_micros;
        LinkBeat {
            bpm: self.state.tempo(),
            beat: self.state.beat_at_time(time, self.quantum),
            phase: self.state.phase_at_time(time, self.quantum),
            peers: self.link.num_peers(),
        }
    }

    /// Proposes `bpm` to the session: every peer follows it.
    pub fn set_tempo(&mut self, bpm: f64) {
        self.link.capture_app_session_state(&mut self.state);
        self.state.set_tempo(bpm, self.link.clock_micros());
        self.link.commit_app_session_state(&self.state);
    }

    /// Other apps in the session.
    pub fn peers(&self) -> u64 {
        self.link.num_peers()
    }
}

impl Drop for LinkSession {
    fn drop(&mut self) {
        self.link.enable(false);
    }
}

#[cfg(test)]
mod tests {
    use std::time::{Duration, Instant};

    use super::*;

    /// Waits up to 10 s for `done`.
    fn within(mut done: impl FnMut() -> bool) -> bool {
        let started = Instant::now();
        while started.elapsed() < Duration::from_secs(10) {
            if done() {
                return true;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        false
    }

    #[test]
    fn two_sessions_find_each_other_and_agree_on_tempo_and_phase() {
        let mut a = LinkSession::join(120.0, 4.0);
        let mut b = LinkSession::join(97.0, 4.0);
        assert!(within(|| a.peers() == 1 && b.peers() == 1), "the two never met");
        // One tempo for both, whoever proposed it.
        a.set_tempo(133.0);
        assert!(within(|| (b.now(0).bpm - 133.0).abs() < 1e-3), "b did not follow: {}", b.now(0).bpm);
        b.set_tempo(87.5);
        assert!(within(|| (a.now(0).bpm - 87.5).abs() < 1e-3), "a did not follow: {}", a.now(0).bpm);
        // The same place in the bar at the same moment (the two reads are microseconds apart).
        let (pa, pb) = (a.now(0).phase, b.now(0).phase);
        let apart = (pa - pb).rem_euclid(4.0).min((pb - pa).rem_euclid(4.0));
        assert!(apart < 0.01, "phases {pa} and {pb}");
        // Looking ahead moves the beat by the tempo.
        let now = a.now(0).beat;
        let later = a.now(1_000_000).beat;
        assert!((later - now - 87.5 / 60.0).abs() < 0.01, "{now} → {later}");
    }
}
