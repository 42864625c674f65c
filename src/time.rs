//! Simulation time: a fixed-dt clock. The window accumulates real time and runs whole steps;
//! the off-screen runner advances exactly one step per frame. Below every other layer.

/// The time of one frame as every node sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameTime {
    /// Frame index since start (0-based).
    pub frame: u64,
    /// Seconds since start: `frame × dt`, in f64 so that weeks of running stay exact.
    pub seconds: f64,
    /// The fixed step, seconds.
    pub dt: f32,
    /// The scene seed; randomness derives from it and the frame index.
    pub seed: u64,
}

impl FrameTime {
    /// This time on a clock that started at frame `start` (a show's clip, restarted when
    /// triggered): frame and seconds counted from there, the same step and seed.
    pub fn since(&self, start: u64) -> FrameTime {
        let frame = self.frame.saturating_sub(start);
        FrameTime { frame, seconds: frame as f64 * f64::from(self.dt), ..*self }
    }
}

/// A fixed-step clock.
#[derive(Clone, Debug)]
pub struct FixedClock {
    dt: f32,
    seed: u64,
    frame: u64,
    pending: f64,
}

/// Most steps a window frame may run to catch up, so a stall never snowballs.
pub const MAX_CATCH_UP_STEPS: u32 = 4;

impl FixedClock {
    /// A clock at frame 0.
    pub fn new(dt: f32, seed: u64) -> Self {
        Self { dt: dt.max(1e-6), seed, frame: 0, pending: 0.0 }
    }

    /// The current frame's time.
    pub fn now(&self) -> FrameTime {
        FrameTime { frame: self.frame, seconds: self.frame as f64 * f64::from(self.dt), dt: self.dt, seed: self.seed }
    }

    /// Advances exactly one step (off-screen rendering).
    pub fn step(&mut self) {
        self.frame += 1;
    }

    /// Adds real elapsed seconds and returns how many whole steps to run now (window).
    pub fn accumulate(&mut self, elapsed: f64) -> u32 {
        self.pending += elapsed;
        let steps = (self.pending / f64::from(self.dt)).floor();
        self.pending -= steps * f64::from(self.dt);
        let steps = steps as u32;
        if steps > MAX_CATCH_UP_STEPS {
            self.pending = 0.0;
        }
        steps.min(MAX_CATCH_UP_STEPS)
    }

    /// Jumps to `frame` (replay, scrubbing).
    pub fn seek(&mut self, frame: u64) {
        self.frame = frame;
        self.pending = 0.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accumulates_whole_steps_and_caps_catch_up() {
        let mut c = FixedClock::new(0.01, 7);
        assert_eq!(c.accumulate(0.025), 2);
        assert_eq!(c.accumulate(0.006), 1); // 0.005 left over + 0.006
        assert_eq!(c.accumulate(10.0), MAX_CATCH_UP_STEPS);
        assert_eq!(c.accumulate(0.0), 0, "a long stall is dropped, not replayed");
    }

    #[test]
    fn off_screen_time_is_frame_times_dt() {
        let mut c = FixedClock::new(0.5, 1);
        for _ in 0..3 {
            c.step();
        }
        assert_eq!(c.now(), FrameTime { frame: 3, seconds: 1.5, dt: 0.5, seed: 1 });
    }
}
