//! MTC out: indra as the timecode master. The MIDI out thread sends quarter frames at the code's
//! rate for the show's position on its timeline (its first frame labelled as the timeline's chase
//! start says, else 00:00:00:00), and a full-frame message when the code starts or the show's
//! position jumps. Like the MIDI clock, the code runs on real time and is pulled gently toward
//! the positions the frames report: each report is late by its frame's render time, and
//! following each one would send quarter frames in bursts or twice.

use std::time::{Duration, Instant};

use crate::scene::SceneView;
use crate::timecode::Rate;
use crate::timecode::mtc::{full_frame, quarter_frame};

/// The share of the gap to the reported position closed each millisecond (about half a
/// second's time constant, as the clock's).
const PULL: f64 = 0.002;
/// A reported position this many code frames or more from the code's own is a jump (a seek, a
/// stall): a full-frame message locates the receiver there.
const JUMP_FRAMES: f64 = 2.0;
/// A show that has reported nothing for this long has stopped (closed, or stalled past a jump):
/// the code stops, and starts again with a full frame.
const STALE: Duration = Duration::from_millis(250);

/// The code's own position, following the show's.
#[derive(Clone, Debug)]
pub struct MtcFollower {
    rate: Rate,
    /// The code's position, in frames counted from 00:00:00:00, at an instant.
    own: Option<(f64, Instant)>,
    /// The next quarter frame to send, counted from 00:00:00:00.
    next_quarter: u64,
}

impl MtcFollower {
    /// A code at `rate` that has not started.
    pub fn new(rate: Rate) -> Self {
        MtcFollower { rate, own: None, next_quarter: 0 }
    }

    /// The code's rate.
    pub fn rate(&self) -> Rate {
        self.rate
    }

    /// Moves the code to `now`, the show having been at `seconds` of code time (its timeline's
    /// seconds plus its start label's) at `at`; `send` gets each message due.
    pub fn advance(&mut self, seconds: f64, at: Instant, now: Instant, mut send: impl FnMut(&[u8])) {
        let since_report = now.saturating_duration_since(at);
        if since_report > STALE || !seconds.is_finite() || seconds < 0.0 {
            self.own = None;
            return;
        }
        let fps = self.rate.fps();
        let reported = (seconds + since_report.as_secs_f64()) * fps;
        let own = match self.own {
            Some((frames, then)) => {
                let elapsed = now.saturating_duration_since(then).as_secs_f64();
                let own = frames + elapsed * fps;
                let gap = reported - own;
                (gap.abs() < JUMP_FRAMES).then(|| own + gap * (PULL * elapsed * 1000.0).min(1.0))
            }
            None => None,
        };
        let Some(own) = own else {
            // Started, resumed or jumped: locate the receiver, then run on from there.
            self.own = Some((reported, now));
            send(&full_frame(reported as u64, self.rate));
            self.next_quarter = (reported * 4.0).floor() as u64 + 1;
            return;
        };
        self.own = Some((own, now));
        // Pulled back a little, the quarters already sent are not sent twice.
        let due = (own * 4.0).floor() as u64;
        while self.next_quarter <= due {
            send(&quarter_frame(self.next_quarter, self.rate));
            self.next_quarter += 1;
        }
    }
}

/// The code time at `rate` of the show's `seconds`: its timeline's first frame carries its chase
/// start's label, when it has one (else 00:00:00:00). What MTC and LTC out send.
pub fn code_seconds(view: &SceneView<'_>, seconds: f64, rate: Rate) -> f64 {
    let start = view.show.and_then(|(show, _)| show.timeline.chase).map(|c| c.start);
    let start = start.and_then(|label| rate.count(label).ok()).unwrap_or(0);
    start as f64 / rate.fps() + seconds
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::timecode::mtc::{MtcEvent, MtcReader};

    /// Frames at 60 Hz reporting their step's time, each late by a render time of 0–40 ms; the
    /// thread wakes every millisecond. Read back by the MTC reader.
    fn play(from: f64, ms: u64, mut follower: MtcFollower, start: Instant) -> Vec<(u64, MtcEvent)> {
        let mut reader = MtcReader::new();
        let mut heard = Vec::new();
        let mut report = (from, start);
        for t in 0..ms {
            let now = start + Duration::from_millis(t);
            if t % 16 == 0 {
                let late = (t * 7919 % 41) as f64 / 1000.0;
                report = (from + (t as f64 / 1000.0 - late).max(0.0), now);
            }
            follower.advance(report.0, report.1, now, |m| heard.extend(reader.message(m).map(|e| (t, e))));
        }
        heard
    }

    #[test]
    fn the_code_follows_late_reports_a_quarter_frame_at_a_time_at_every_rate() {
        for rate in Rate::ALL {
            let from = 3600.0 - 1.0; // across the hour, where drop-frame skips labels
            let heard = play(from, 4000, MtcFollower::new(rate), Instant::now());
            let Some((0, MtcEvent::Located { frame, .. })) = heard.first().copied() else {
                panic!("{rate}: no full frame first: {:?}", heard.first());
            };
            assert_eq!(frame, (from * rate.fps()) as u64, "{rate}");
            let running: Vec<(u64, f64)> = heard
                .iter()
                .filter_map(|(t, e)| match e {
                    MtcEvent::Running { frame, rate: r } if *r == rate => Some((*t, *frame)),
                    _ => None,
                })
                .collect();
            // Every quarter frame in order, none twice, none skipped.
            for pair in running.windows(2) {
                assert_eq!(pair[1].1 - pair[0].1, 0.25, "{rate}: {pair:?}");
            }
            // Each arrives within 1.5 frames of the show's real position (reports lag by up
            // to 40 ms, and the pull halves a gap in about 350 ms).
            for (t, frame) in &running {
                let truth = (from + *t as f64 / 1000.0) * rate.fps();
                assert!((frame - truth).abs() < 1.5, "{rate}: at {t} ms code {frame}, show {truth}");
            }
            assert!(running.len() > 4 * 3 * 24, "{rate}: {} quarter frames in 4 s", running.len());
        }
    }

    #[test]
    fn a_jump_locates_and_a_stopped_show_stops_the_code() {
        let rate = Rate::Fps25;
        let start = Instant::now();
        let mut follower = MtcFollower::new(rate);
        let mut sent = Vec::new();
        follower.advance(10.0, start, start, |m| sent.push(m.to_vec()));
        follower.advance(10.1, start + Duration::from_millis(100), start + Duration::from_millis(100), |m| {
            sent.push(m.to_vec())
        });
        assert_eq!(sent[0], full_frame(250, rate));
        assert!(sent[1..].iter().all(|m| m[0] == 0xF1) && sent.len() > 8, "{sent:?}");
        // A seek back five seconds: a full frame at the new place, no run of quarters.
        sent.clear();
        let at = start + Duration::from_millis(116);
        follower.advance(5.0, at, at, |m| sent.push(m.to_vec()));
        assert_eq!(sent, vec![full_frame(125, rate).to_vec()]);
        // No report for a second: nothing sent; the next report locates again.
        sent.clear();
        follower.advance(5.0, at, at + Duration::from_secs(1), |m| sent.push(m.to_vec()));
        assert!(sent.is_empty());
        let later = at + Duration::from_secs(2);
        follower.advance(5.0, later, later, |m| sent.push(m.to_vec()));
        assert_eq!(sent, vec![full_frame(125, rate).to_vec()]);
    }
}
