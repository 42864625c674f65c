//! LTC as live audio for a show's position: indra as the timecode master of a sound desk. The
//! code runs on the audio clock, a whole frame at a time, and follows the positions the show
//! reports: smoothed (each report is late by its frame's render time, which varies), the code
//! played up to 2 % fast or slow to keep to them as the audio clock drifts from the system's
//! (as a tape's vari-speed; readers follow a code's speed), a jump when the show seeks, and
//! silence when the show stops reporting.

use std::collections::VecDeque;

use super::Rate;
use super::ltc::LtcEncoder;

/// The share of the gap to the reported position closed each millisecond of code (about half
/// a second's time constant, as MTC out's).
const PULL: f64 = 0.002;
/// A reported position this many frames or more from the code's own is a jump (a seek): the
/// next frame carries the new label.
const JUMP_FRAMES: f64 = 2.0;
/// How fast the labels close on the show's position: the speed is off normal by this share of
/// the gap in frames (a gap closes over about 25 frames).
const CATCH_UP: f64 = 0.04;
/// The most the speed is off normal.
const MAX_SPEED_CHANGE: f64 = 0.02;
/// A report older than this (the show closed or hung) stops the code: silence until the next.
/// A second, not a frame or two: a window that stalls for a moment on a busy machine (a build,
/// a slow frame) must not cut the code a desk is chasing.
pub const STALE_SECONDS: f64 = 1.0;

/// Where the show is for [`LtcFollower::fill`]: its position in code seconds (the timeline's
/// seconds plus its start label's) when the block's first sample sounds, and how old the
/// report it comes from is then.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShowPosition {
    /// Code seconds at the block's first sample.
    pub seconds: f64,
    /// Seconds since the show reported, at the block's first sample.
    pub age: f64,
}

/// Writes LTC for a show's reported position, block by block as an audio callback asks.
#[derive(Clone, Debug)]
pub struct LtcFollower {
    encoder: LtcEncoder,
    rate: Rate,
    sample_rate: f64,
    /// Samples of the frame being sent.
    pending: VecDeque<f32>,
    /// The encoder's output, kept to reuse its memory.
    scratch: Vec<f32>,
    /// The show's position (frames from 00:00:00:00, smoothed) where the next frame begins.
    own: Option<f64>,
    /// The label of the next frame.
    next: u64,
    /// The length of the frame being sent, in seconds.
    length: f64,
    /// Frames sent, and the labels that jumped (a seek).
    pub frames: u64,
    /// See [`LtcFollower::frames`].
    pub jumps: u64,
}

impl LtcFollower {
    /// A code at `rate` on audio at `sample_rate`, its square wave at ±`level`.
    pub fn new(sample_rate: u32, rate: Rate, level: f32) -> Self {
        LtcFollower {
            encoder: LtcEncoder::new(sample_rate, rate, level),
            rate,
            sample_rate: f64::from(sample_rate),
            pending: VecDeque::new(),
            scratch: Vec::new(),
            own: None,
            next: 0,
            length: 0.0,
            frames: 0,
            jumps: 0,
        }
    }

    /// Fills `out` (one channel) with the code for a show at `show` (`None`: no report yet).
    pub fn fill(&mut self, out: &mut [f32], show: Option<ShowPosition>) {
        for (i, sample) in out.iter_mut().enumerate() {
            if self.pending.is_empty() {
                let offset = i as f64 / self.sample_rate;
                let live = show.filter(|s| s.age + offset <= STALE_SECONDS);
                match live {
                    Some(s) => self.begin_frame((s.seconds + offset) * self.rate.fps()),
                    None => self.own = None,
                }
            }
            *sample = self.pending.pop_front().unwrap_or(0.0);
        }
    }

    /// Encodes the next frame, the show being at `wanted` frames as it begins.
    fn begin_frame(&mut self, wanted: f64) {
        let fps = self.rate.fps();
        // Where the show is now by the code's own count, pulled toward the report.
        let own = self.own.map(|own| own + self.length * fps).filter(|own| (wanted - own).abs() < JUMP_FRAMES);
        let own = match own {
            Some(own) => own + (wanted - own) * (PULL * self.length * 1000.0).min(1.0),
            None => {
                // Started, resumed or jumped: the label the show is nearest to.
                self.jumps += u64::from(self.own.is_some());
                self.next = wanted.round().max(0.0) as u64;
                wanted
            }
        };
        // Labels behind the show play a little fast, ahead a little slow.
        let speed = 1.0 + ((own - self.next as f64) * CATCH_UP).clamp(-MAX_SPEED_CHANGE, MAX_SPEED_CHANGE);
        self.encoder.set_speed(speed);
        self.scratch.clear();
        self.encoder.frame(self.rate.timecode(self.next), 0, &mut self.scratch);
        self.pending.extend(self.scratch.iter().copied());
        self.length = self.scratch.len() as f64 / self.sample_rate;
        self.own = Some(own);
        self.next += 1;
        self.frames += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::timecode::ltc::{LtcDecoder, LtcFrame};

    /// The code for a show at 60 Hz from `from` code seconds for `seconds`, whose reports are
    /// late by a render time of 0–40 ms, written in blocks of 256 samples at 48 kHz; with the
    /// show jumping to `jump.1` at `jump.0` seconds in, and its clock running `drift` faster than
    /// the audio's. Read back by indra's decoder.
    fn play(rate: Rate, from: f64, seconds: f64, jump: Option<(f64, f64)>, drift: f64) -> (Vec<LtcFrame>, LtcFollower) {
        let mut follower = LtcFollower::new(48_000, rate, 0.5);
        let (mut decoder, mut frames) = (LtcDecoder::new(48_000), Vec::new());
        let mut block = vec![0.0; 256];
        let mut report: (f64, f64) = (from, 0.0);
        let blocks = (seconds * 48_000.0 / 256.0) as u64;
        for b in 0..blocks {
            let t = b as f64 * 256.0 / 48_000.0;
            let show = |t: f64| match jump {
                Some((at, to)) if t >= at => to + (t - at),
                _ => from + t * (1.0 + drift),
            };
            // A frame's report every 1/60 s, of where its step was up to 40 ms before.
            if (t * 60.0).floor() > (report.1 * 60.0).floor() || b == 0 {
                let late = (b * 7919 % 41) as f64 / 1000.0;
                report = (show((t - late).max(0.0)), t);
            }
            let position = ShowPosition { seconds: report.0 + (t - report.1), age: t - report.1 };
            follower.fill(&mut block, Some(position));
            decoder.write(&block, &mut frames);
        }
        (frames, follower)
    }

    #[test]
    fn the_code_follows_late_reports_and_a_drifting_clock_frame_after_frame_at_every_rate() {
        for (rate, drift) in Rate::ALL.into_iter().zip([0.0, 0.005, -0.005, 0.0]) {
            let from = 3600.0 - 2.0; // across the hour, where drop-frame skips labels
            let (frames, follower) = play(rate, from, 4.0, None, drift);
            assert!(frames.len() as f64 > 3.8 * rate.fps(), "{rate}: {} frames", frames.len());
            assert!(frames.iter().all(|f| f.rate == rate && !f.reverse), "{rate}");
            let counts: Vec<u64> = frames.iter().map(|f| rate.count(f.timecode).unwrap()).collect();
            assert!(counts.windows(2).all(|w| w[1] == w[0] + 1), "{rate}: {counts:?}");
            assert_eq!(follower.jumps, 0, "{rate}");
            // Each frame ends within a frame of where the show was then; past the first second,
            // within 0.75 frames (the reports lag by 20 ms on average: half a frame at 25 fps).
            for (frame, count) in frames.iter().zip(&counts) {
                let seconds = frame.end / 48_000.0;
                let show = (from + seconds * (1.0 + drift)) * rate.fps();
                let off = (*count as f64 + 1.0 - show).abs();
                assert!(off < 1.0 && (seconds < 1.0 || off < 0.75), "{rate}: frame {count} ended at show {show}");
            }
        }
    }

    #[test]
    fn a_seek_jumps_the_label_and_a_stopped_show_goes_silent() {
        let rate = Rate::Fps25;
        let (frames, follower) = play(rate, 100.0, 3.0, Some((1.5, 10.0)), 0.0);
        let counts: Vec<u64> = frames.iter().map(|f| rate.count(f.timecode).unwrap()).collect();
        let back = counts.windows(2).filter(|w| w[1] != w[0] + 1).collect::<Vec<_>>();
        assert_eq!(back.len(), 1, "{counts:?}");
        assert!(back[0][0] >= 2536 && back[0][1].abs_diff(251) <= 2, "{back:?}");
        assert_eq!(follower.jumps, 1);
        // No report for longer than the stale time: silence.
        let mut follower = LtcFollower::new(48_000, rate, 0.5);
        let mut block = vec![1.0; 48_000];
        follower.fill(&mut block, Some(ShowPosition { seconds: 10.0, age: STALE_SECONDS + 0.05 }));
        assert!(block.iter().all(|&s| s == 0.0));
        follower.fill(&mut block, None);
        assert!(block.iter().all(|&s| s == 0.0) && follower.frames == 0);
    }
}
