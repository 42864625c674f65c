//! Ableton Link as a tempo source (feature `link`; Link is GPL-2.0-or-later, so this build is
//! too): the show joins the session on the local network, follows its tempo and phase, and
//! proposes tempo changes made here (see [`super::tempo::SessionFollower`]).

use indra_link::LinkSession;

use super::tempo::SessionFollower;
use crate::params::ControlEvent;
use crate::params::lfo::TempoClock;

/// Beats per bar: the phase every peer agrees on (4/4).
pub const QUANTUM: f64 = 4.0;

/// The show's membership of the Link session.
pub struct LinkInput {
    session: LinkSession,
    follower: SessionFollower,
}

impl LinkInput {
    /// Joins the session, proposing `bpm` if nobody is there yet.
    pub fn join(bpm: f64) -> Self {
        log::info!("joined the Ableton Link session");
        Self { session: LinkSession::join(bpm, QUANTUM), follower: SessionFollower::default() }
    }

    /// The events that keep `clock` with the session, read `ahead` seconds from now (when they
    /// apply); a tempo set here is proposed to the session.
    pub fn poll(&mut self, clock: &TempoClock, ahead: f64) -> Vec<ControlEvent> {
        let now = self.session.now((ahead * 1e6) as i64);
        let follow = self.follower.follow(clock, now.bpm, now.phase, QUANTUM);
        if let Some(bpm) = follow.propose {
            self.session.set_tempo(bpm);
        }
        follow.events
    }

    /// Other apps in the session.
    pub fn peers(&self) -> u64 {
        self.session.peers()
    }
}

#[cfg(test)]
mod tests {
    use std::time::{Duration, Instant};

    use super::*;

    /// Polls `input` into `clock` (as the scene applies the events) until `done` or 10 s pass.
    fn follow_until(input: &mut LinkInput, clock: &mut TempoClock, done: impl Fn(&TempoClock) -> bool) -> bool {
        let started = Instant::now();
        while started.elapsed() < Duration::from_secs(10) {
            for event in input.poll(clock, 0.0) {
                match event {
                    ControlEvent::Tempo { bpm, resync } => clock.set(bpm, resync),
                    ControlEvent::Phase { phase, quantum } => clock.align(phase, quantum),
                    other => panic!("{other:?}"),
                }
            }
            if done(clock) {
                return true;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        false
    }

    #[test]
    fn the_show_follows_a_peer_and_the_peer_follows_the_show() {
        let mut peer = LinkSession::join(140.0, QUANTUM);
        let mut show = LinkInput::join(120.0);
        let mut clock = TempoClock::new(120.0);
        assert!(follow_until(&mut show, &mut clock, |_| peer.peers() == 1), "the two never met");
        // The peer was first: its 140 bpm is the session's, and the show takes it and its phase.
        peer.set_tempo(140.0);
        assert!(follow_until(&mut show, &mut clock, |c| (c.bpm - 140.0).abs() < 1e-3), "tempo {}", clock.bpm);
        let apart = phase_offset_now(&mut peer, &clock);
        assert!(apart.abs() < 0.03, "the show is {apart} beats off the peer");
        // A tap here: the peer follows the show.
        clock.set(100.0, true);
        let _ = show.poll(&clock, 0.0);
        let started = Instant::now();
        while (peer.now(0).bpm - 100.0).abs() > 1e-3 {
            assert!(started.elapsed() < Duration::from_secs(10), "the peer stayed at {}", peer.now(0).bpm);
            std::thread::sleep(Duration::from_millis(10));
        }
    }

    /// How far the peer's phase is ahead of the show's clock, in beats.
    fn phase_offset_now(peer: &mut LinkSession, clock: &TempoClock) -> f64 {
        crate::params::lfo::phase_offset(clock.beats, peer.now(0).phase, QUANTUM)
    }
}
