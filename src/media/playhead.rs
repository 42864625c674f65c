//! Where in a clip a node is: a position in seconds moved by the fixed clock, so that frame n of
//! a scene shows the same clip frame however it is reached (played, sought, split). Speed, pause,
//! loop mode, in and out points, scrubbing and restart are all changes to that one number, made
//! in the step, never from the wall clock.

/// A ten-thousandth of a frame: float error at frame boundaries (n / fps is frame n, and in
/// and out points come as `f32` shares) never shows the frame before.
const FRAME_EPSILON: f64 = 1e-4;

/// What happens at the out point (or the in point, playing backwards).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LoopMode {
    /// Jump back to the other end.
    Loop,
    /// Turn round and play the other way.
    PingPong,
    /// Stop and hold the last frame.
    Once,
}

/// How a clip is to play this step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaySettings {
    /// Whether it moves.
    pub playing: bool,
    /// Clip seconds per scene second; negative plays backwards.
    pub speed: f64,
    /// At the ends.
    pub mode: LoopMode,
    /// In point, a share of the clip (0–1).
    pub in_point: f64,
    /// Out point, a share of the clip (0–1); at or before `in_point` holds the in point.
    pub out_point: f64,
}

/// A clip's play position.
#[derive(Clone, Debug, PartialEq)]
pub struct Playhead {
    /// Seconds into the clip.
    seconds: f64,
    /// +1 or −1: ping-pong's current direction, times the speed's sign.
    bounce: f64,
}

impl Playhead {
    /// At `settings`' start: the in point, or the last frame for a clip playing backwards
    /// (a clip of `duration` seconds at `fps`).
    pub fn new(settings: &PlaySettings, duration: f64, fps: f64) -> Self {
        let mut head = Self { seconds: 0.0, bounce: 1.0 };
        head.restart(settings, duration, fps);
        head
    }

    /// Seconds into the clip.
    pub fn seconds(&self) -> f64 {
        self.seconds
    }

    /// The whole state — seconds into the clip and the ping-pong direction — for checkpoints.
    pub fn parts(&self) -> [f64; 2] {
        [self.seconds, self.bounce]
    }

    /// A playhead from [`Playhead::parts`]; `None` for parts no playhead has.
    pub fn from_parts([seconds, bounce]: [f64; 2]) -> Option<Self> {
        (seconds.is_finite() && bounce.is_finite()).then_some(Self { seconds, bounce })
    }

    /// The in and out points in seconds.
    fn range(settings: &PlaySettings, duration: f64) -> (f64, f64) {
        let start = settings.in_point.clamp(0.0, 1.0) * duration;
        let end = (settings.out_point.clamp(0.0, 1.0) * duration).max(start);
        (start, end)
    }

    /// Back to the start (the restart trigger): the in point, or playing backwards the start of
    /// the last frame before the out point — so backwards is forwards mirrored, frame for frame.
    pub fn restart(&mut self, settings: &PlaySettings, duration: f64, fps: f64) {
        let (start, end) = Self::range(settings, duration);
        self.seconds = if settings.speed < 0.0 { (end - 1.0 / fps.max(1e-9)).max(start) } else { start };
        self.bounce = 1.0;
    }

    /// To `share` (0–1) of the way from the in to the out point (scrubbing).
    pub fn scrub(&mut self, share: f64, settings: &PlaySettings, duration: f64) {
        let (start, end) = Self::range(settings, duration);
        self.seconds = start + share.clamp(0.0, 1.0) * (end - start);
    }

    /// Where the head is, as a share of the in–out range (what the position parameter shows).
    pub fn share(&self, settings: &PlaySettings, duration: f64) -> f64 {
        let (start, end) = Self::range(settings, duration);
        if end > start { ((self.seconds - start) / (end - start)).clamp(0.0, 1.0) } else { 0.0 }
    }

    /// One fixed step of `dt` scene seconds through a clip of `duration` seconds at `fps`.
    pub fn step(&mut self, settings: &PlaySettings, dt: f64, duration: f64, fps: f64) {
        let (start, end) = Self::range(settings, duration);
        if end <= start {
            self.seconds = start;
            return;
        }
        if !settings.playing {
            self.seconds = self.seconds.clamp(start, end);
            return;
        }
        // Out of range after an in/out change: back inside from the nearer end.
        let t = self.seconds.clamp(start, end) + dt * settings.speed * self.bounce;
        self.seconds = match settings.mode {
            LoopMode::Loop => {
                let into = (t - start).rem_euclid(end - start);
                // A step that lands on the out point but for float error wraps like one past it.
                if (end - start - into) * fps < FRAME_EPSILON { start } else { start + into }
            }
            LoopMode::Once => t.clamp(start, end),
            LoopMode::PingPong => {
                // Turning on the last frame's start, not the out point, so the end frames show
                // once per turn, as at every other frame (0 1 2 3 2 1 0 1 …).
                let turn = (end - 1.0 / fps.max(1e-9)).max(start);
                let length = turn - start;
                if length <= 0.0 {
                    start
                } else if t > turn || t < start {
                    let folded = (t - start).rem_euclid(2.0 * length);
                    if folded > length {
                        self.bounce = -self.bounce;
                        start + 2.0 * length - folded
                    } else {
                        start + folded
                    }
                } else {
                    t
                }
            }
        };
    }

    /// The frame to show: the last frame whose start is at or before the head, and at the out
    /// point of a clip the last frame before it (the out point itself is where the next begins).
    pub fn frame(&self, settings: &PlaySettings, fps: f64, frames: usize) -> usize {
        frame_at(self.seconds, settings, fps, frames)
    }

    /// The next `count` frames this head will show from now, one step of `dt` apart (for
    /// decoding ahead), current first.
    pub fn upcoming(&self, settings: &PlaySettings, dt: f64, fps: f64, frames: usize, count: usize) -> Vec<usize> {
        let duration = frames as f64 / fps.max(1e-9);
        let mut head = self.clone();
        let mut out = Vec::with_capacity(count);
        let mut guard = 0;
        while out.len() < count && guard < count * 64 {
            let f = head.frame(settings, fps, frames);
            if !out.contains(&f) {
                out.push(f);
            }
            if !settings.playing || settings.speed == 0.0 {
                break;
            }
            head.step(settings, dt, duration, fps);
            guard += 1;
        }
        out
    }
}

fn frame_at(seconds: f64, settings: &PlaySettings, fps: f64, frames: usize) -> usize {
    if frames == 0 {
        return 0;
    }
    let duration = frames as f64 / fps;
    let (start, end) = Playhead::range(settings, duration);
    let f = (seconds * fps + FRAME_EPSILON).floor().max(0.0) as usize;
    let last_in_range = if end > start { ((end * fps - FRAME_EPSILON).ceil() as usize).saturating_sub(1) } else { f };
    let first_in_range = (start * fps + FRAME_EPSILON).floor() as usize;
    f.clamp(first_in_range.min(last_in_range), last_in_range).min(frames - 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(speed: f64, mode: LoopMode) -> PlaySettings {
        PlaySettings { playing: true, speed, mode, in_point: 0.0, out_point: 1.0 }
    }

    /// The frames a clip of `frames` at 10 fps shows over `steps` steps of 0.1 s.
    fn play(s: &PlaySettings, frames: usize, steps: usize) -> Vec<usize> {
        let duration = frames as f64 / 10.0;
        let mut head = Playhead::new(s, duration, 10.0);
        let mut shown = vec![head.frame(s, 10.0, frames)];
        for _ in 0..steps {
            head.step(s, 0.1, duration, 10.0);
            shown.push(head.frame(s, 10.0, frames));
        }
        shown
    }

    #[test]
    fn loop_once_and_backwards_show_the_frames_in_order() {
        assert_eq!(play(&settings(1.0, LoopMode::Loop), 4, 9), [0, 1, 2, 3, 0, 1, 2, 3, 0, 1]);
        assert_eq!(play(&settings(1.0, LoopMode::Once), 4, 6), [0, 1, 2, 3, 3, 3, 3]);
        assert_eq!(play(&settings(-1.0, LoopMode::Loop), 4, 5), [3, 2, 1, 0, 3, 2]);
        assert_eq!(play(&settings(2.0, LoopMode::Loop), 4, 3), [0, 2, 0, 2]);
        let paused = PlaySettings { playing: false, ..settings(1.0, LoopMode::Loop) };
        assert_eq!(play(&paused, 4, 3), [0, 0, 0, 0]);
    }

    #[test]
    fn ping_pong_turns_at_each_end() {
        assert_eq!(play(&settings(1.0, LoopMode::PingPong), 4, 10), [0, 1, 2, 3, 2, 1, 0, 1, 2, 3, 2]);
    }

    #[test]
    fn in_and_out_points_bound_every_mode_and_scrub() {
        let s = PlaySettings { in_point: 0.25, out_point: 0.75, ..settings(1.0, LoopMode::Loop) };
        assert_eq!(play(&s, 8, 5), [2, 3, 4, 5, 2, 3]);
        let once = PlaySettings { mode: LoopMode::Once, ..s };
        assert_eq!(play(&once, 8, 5), [2, 3, 4, 5, 5, 5]);
        let mut head = Playhead::new(&s, 0.8, 10.0);
        head.scrub(0.5, &s, 0.8);
        assert_eq!(head.frame(&s, 10.0, 8), 4);
        assert!((head.share(&s, 0.8) - 0.5).abs() < 1e-9);
        let empty = PlaySettings { out_point: 0.1, ..s };
        assert_eq!(play(&empty, 8, 3), [2, 2, 2, 2], "an out point before the in point holds the in point");
    }

    #[test]
    fn upcoming_frames_follow_loops() {
        let s = settings(1.0, LoopMode::Loop);
        let mut head = Playhead::new(&s, 0.4, 10.0);
        head.step(&s, 0.1, 0.4, 10.0);
        head.step(&s, 0.1, 0.4, 10.0);
        assert_eq!(head.upcoming(&s, 0.1, 10.0, 4, 4), [2, 3, 0, 1]);
    }
}
