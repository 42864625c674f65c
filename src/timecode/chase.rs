//! Chasing a desk's timecode: where the timeline should be now, from the code heard so far, and
//! how the fixed-step show gets there — run a few steps, wait, or seek.
//!
//! The code is heard as positions stamped with the local clock (an LTC frame's end in the audio
//! input's time, an MTC quarter frame's arrival). Between two, the timeline runs on at the
//! code's speed (one second a second); when the code stops it keeps running for the freewheel
//! time, then stops where it got to. A desk that jumps, backwards or forwards, is a seek, and
//! seeks in indra are exact (frame n is the same bytes however it is reached).

use super::{Rate, Timecode};

/// How a show chases a code.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChaseSettings {
    /// The label at the timeline's start: code before it holds the timeline's first frame.
    pub start: Timecode,
    /// Seconds the timeline runs on after the code stops.
    pub freewheel: f64,
}

impl Default for ChaseSettings {
    fn default() -> Self {
        ChaseSettings { start: Timecode::default(), freewheel: 2.0 }
    }
}

/// The longest freewheel a show or the command line may ask for, seconds.
pub const MAX_FREEWHEEL: f64 = 3600.0;

/// Chase settings given on the command line over a show's own (each `None`: the show's, else
/// the default).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ChaseOverrides {
    /// The label at the timeline's first frame.
    pub start: Option<Timecode>,
    /// Seconds the timeline runs on when the code drops out.
    pub freewheel: Option<f64>,
}

impl ChaseOverrides {
    /// These over `own` (a show's `timeline.chase`), over the defaults.
    pub fn over(self, own: Option<ChaseSettings>) -> ChaseSettings {
        let own = own.unwrap_or_default();
        ChaseSettings { start: self.start.unwrap_or(own.start), freewheel: self.freewheel.unwrap_or(own.freewheel) }
    }
}

/// The code last heard.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Heard {
    /// The timeline's seconds the code said.
    seconds: f64,
    /// When, on the local clock (seconds).
    at: f64,
    /// The code's frame length, seconds.
    frame: f64,
    /// Whether the desk was running (a full-frame locate says it stands).
    running: bool,
}

/// Where the chase stands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Chasing {
    /// No code heard yet.
    NoCode,
    /// The code is coming in: the timeline is at `seconds`.
    Locked {
        /// The timeline's position, seconds.
        seconds: f64,
    },
    /// The code stopped `for_seconds` ago; the timeline runs on at `seconds`.
    Freewheel {
        /// The timeline's position, seconds.
        seconds: f64,
        /// Seconds since the code was last heard.
        for_seconds: f64,
    },
    /// The code stopped longer ago than the freewheel time (or the desk located and stands):
    /// the timeline holds `seconds`.
    Stopped {
        /// The timeline's position, seconds.
        seconds: f64,
    },
}

impl Chasing {
    /// The timeline's position, if any code was heard.
    pub fn seconds(self) -> Option<f64> {
        match self {
            Chasing::NoCode => None,
            Chasing::Locked { seconds } | Chasing::Freewheel { seconds, .. } | Chasing::Stopped { seconds } => {
                Some(seconds)
            }
        }
    }
}

/// Follows a code.
#[derive(Clone, Debug)]
pub struct Chase {
    settings: ChaseSettings,
    heard: Option<Heard>,
}

impl Chase {
    /// A chase that has heard nothing.
    pub fn new(settings: ChaseSettings) -> Self {
        Chase { settings, heard: None }
    }

    /// The settings.
    pub fn settings(&self) -> ChaseSettings {
        self.settings
    }

    /// The code was at frame count `frame` (with a fraction) of `rate` at local time `at`,
    /// running.
    pub fn heard(&mut self, frame: f64, rate: Rate, at: f64) {
        self.hear(frame, rate, at, true);
    }

    /// The desk located to frame count `frame` and stands there (MTC's full frame).
    pub fn located(&mut self, frame: u64, rate: Rate, at: f64) {
        self.hear(frame as f64, rate, at, false);
    }

    fn hear(&mut self, frame: f64, rate: Rate, at: f64, running: bool) {
        // The start's label at this code's rate; one that does not exist at it (a drop-frame
        // label) counts as the frame after.
        let start = rate.count(self.settings.start).unwrap_or_else(|_| {
            let mut next = self.settings.start;
            next.frames = 2;
            rate.count(next).unwrap_or(0)
        });
        let seconds = (frame - start as f64) / rate.fps();
        self.heard = Some(Heard { seconds, at, frame: 1.0 / rate.fps(), running });
    }

    /// Where the timeline is at local time `now`.
    pub fn at(&self, now: f64) -> Chasing {
        let Some(h) = self.heard else { return Chasing::NoCode };
        if !h.running {
            return Chasing::Stopped { seconds: h.seconds };
        }
        let since = (now - h.at).max(0.0);
        // Code comes a frame at a time (LTC) or a quarter frame (MTC): two frames' silence
        // and some for the audio or MIDI buffer is a dropout.
        let locked = 2.0 * h.frame + 0.05;
        if since <= locked {
            Chasing::Locked { seconds: h.seconds + since }
        } else if since <= self.settings.freewheel {
            Chasing::Freewheel { seconds: h.seconds + since, for_seconds: since }
        } else {
            // Stops where it got to, never back to where the code was last heard.
            Chasing::Stopped { seconds: h.seconds + self.settings.freewheel.max(locked) }
        }
    }
}

/// The show's frame for a timeline position: ⌊seconds / dt⌋, before the start the first frame.
pub fn frame_at(seconds: f64, dt: f64) -> u64 {
    // A thousandth of a frame of slack, so that N frames' worth of seconds is frame N even
    // after rounding (dt is an f32 in scenes).
    (seconds / dt + 1e-3).floor().max(0.0) as u64
}

/// What the fixed-step show does to show the frame the code wants.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Follow {
    /// Keep the frame on screen (the code is there, or a frame or two behind).
    Hold,
    /// Run this many steps, as a window catching up does.
    Step(u32),
    /// Go to this frame (the desk jumped, or the show fell too far behind).
    Seek(u64),
}

/// How to get from `drawn` (the frame on screen, `None` before the first) to `wanted`, running
/// at most `max_steps` steps in one go. A code up to `jitter` frames behind is waited for
/// rather than sought (a live input's timing; 0 in a render, where the code is exact).
pub fn follow(wanted: u64, drawn: Option<u64>, max_steps: u32, jitter: u64) -> Follow {
    let Some(drawn) = drawn else { return Follow::Seek(wanted) };
    if wanted <= drawn {
        return if drawn - wanted <= jitter { Follow::Hold } else { Follow::Seek(wanted) };
    }
    match u32::try_from(wanted - drawn) {
        Ok(steps) if steps <= max_steps => Follow::Step(steps),
        _ => Follow::Seek(wanted),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chase(start: &str, freewheel: f64) -> Chase {
        Chase::new(ChaseSettings { start: Timecode::parse(start).unwrap(), freewheel })
    }

    #[test]
    fn the_timeline_follows_the_code_from_its_start_label() {
        let mut c = chase("01:00:00:00", 2.0);
        assert_eq!(c.at(0.0), Chasing::NoCode);
        let rate = Rate::Fps25;
        let one_hour = rate.count(Timecode::parse("01:00:10:00").unwrap()).unwrap() as f64;
        c.heard(one_hour, rate, 5.0);
        assert_eq!(c.at(5.0), Chasing::Locked { seconds: 10.0 });
        assert_eq!(c.at(5.04), Chasing::Locked { seconds: 10.04 });
        assert_eq!(frame_at(c.at(5.04).seconds().unwrap(), 1.0 / 25.0), 251);
        // Code before the start holds the first frame.
        c.heard(rate.count(Timecode::parse("00:59:59:00").unwrap()).unwrap() as f64, rate, 6.0);
        assert_eq!(frame_at(c.at(6.0).seconds().unwrap(), 1.0 / 60.0), 0);
    }

    #[test]
    fn a_dropout_freewheels_then_stops_and_the_code_relocks() {
        let mut c = chase("00:00:00:00", 1.0);
        let rate = Rate::Fps30;
        c.heard(300.0, rate, 0.0);
        assert!(matches!(c.at(0.05), Chasing::Locked { .. }));
        assert_eq!(c.at(0.5), Chasing::Freewheel { seconds: 10.5, for_seconds: 0.5 });
        assert_eq!(c.at(3.0), Chasing::Stopped { seconds: 11.0 });
        c.heard(390.0, rate, 3.0);
        assert_eq!(c.at(3.0), Chasing::Locked { seconds: 13.0 });
        c.located(30, rate, 4.0);
        assert_eq!(c.at(9.0), Chasing::Stopped { seconds: 1.0 }, "a located desk stands");
    }

    #[test]
    fn drop_frame_code_keeps_to_the_clock() {
        let mut c = chase("00:00:00:00", 2.0);
        let rate = Rate::Fps2997Drop;
        // An hour of drop-frame labels is an hour of real time, less 3.6 ms.
        c.heard(rate.count(Timecode::parse("01:00:00:00").unwrap()).unwrap() as f64, rate, 0.0);
        let seconds = c.at(0.0).seconds().unwrap();
        assert!((seconds - 3600.0).abs() < 0.004, "{seconds}");
    }

    #[test]
    fn steps_waits_and_seeks_are_chosen_by_the_distance() {
        assert_eq!(follow(10, None, 4, 2), Follow::Seek(10));
        assert_eq!(follow(10, Some(10), 4, 2), Follow::Hold);
        assert_eq!(follow(10, Some(12), 4, 2), Follow::Hold, "jitter is waited for");
        assert_eq!(follow(10, Some(11), 4, 0), Follow::Seek(10), "not in a render");
        assert_eq!(follow(10, Some(13), 4, 2), Follow::Seek(10), "a jump back");
        assert_eq!(follow(14, Some(10), 4, 2), Follow::Step(4));
        assert_eq!(follow(15, Some(10), 4, 2), Follow::Seek(15), "a jump ahead");
        assert_eq!(frame_at(100.0 * f64::from(0.04f32), f64::from(0.04f32)), 100);
        assert_eq!(frame_at(-3.0, 0.04), 0);
    }
}
