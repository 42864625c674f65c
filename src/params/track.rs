//! Animation tracks: keyframes over time with step, linear or smooth (zero-slope Hermite)
//! interpolation and once / loop / ping-pong repetition — what the book's Unity curves do.

use super::value::{ParamType, ParamValue};

/// How values between two keys are found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
pub enum Interpolation {
    /// Hold the earlier key's value.
    Step,
    /// Straight line.
    Linear,
    /// Cubic Hermite with zero slope at every key (ease in and out), like Unity's flat tangents.
    #[default]
    Smooth,
}

/// What happens after the last key. Before the first key the first value holds, as Unity's
/// clamped pre-infinity does.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
pub enum LoopMode {
    /// Hold the last value.
    #[default]
    Once,
    /// Jump back to the first key.
    Loop,
    /// Play backwards, then forwards again.
    PingPong,
}

/// One keyframe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Key {
    /// Time in seconds (after the track's time scale).
    pub time: f32,
    /// The value at that time.
    pub value: ParamValue,
}

/// Keys for one parameter (or one component of it).
#[derive(Clone, Debug, PartialEq)]
pub struct Track {
    /// Keys sorted by time; at least one.
    pub keys: Vec<Key>,
    /// Interpolation between keys.
    pub interpolation: Interpolation,
    /// Repetition after the last key.
    pub repeat: LoopMode,
    /// Multiplies the clock before lookup (the sample's `timeScale`).
    pub time_scale: f32,
}

impl Track {
    /// A track over `keys` (sorted here by time).
    pub fn new(mut keys: Vec<Key>, interpolation: Interpolation, repeat: LoopMode, time_scale: f32) -> Self {
        keys.sort_by(|a, b| a.time.total_cmp(&b.time));
        Self { keys, interpolation, repeat, time_scale }
    }

    /// The track's value at clock time `seconds`.
    pub fn sample(&self, seconds: f64) -> ParamValue {
        let (first, last) = (&self.keys[0], &self.keys[self.keys.len() - 1]);
        let t = self.local_time(seconds * f64::from(self.time_scale), f64::from(first.time), f64::from(last.time));
        // Keys are sorted: a binary search, as tracks are sampled every step and a recorded
        // lane holds thousands of keys.
        let next = self.keys.partition_point(|k| f64::from(k.time) <= t);
        if next == 0 {
            return first.value;
        }
        if next == self.keys.len() {
            return last.value;
        }
        let (a, b) = (&self.keys[next - 1], &self.keys[next]);
        let s = ((t - f64::from(a.time)) / f64::from(b.time - a.time)) as f32;
        let w = match self.interpolation {
            Interpolation::Step => 0.0,
            Interpolation::Linear => s,
            Interpolation::Smooth => s * s * (3.0 - 2.0 * s),
        };
        mix(a.value, b.value, w)
    }

    /// Maps clock time into the key span according to the loop mode (f64: shows run for weeks).
    fn local_time(&self, t: f64, start: f64, end: f64) -> f64 {
        let span = end - start;
        if t <= start || span <= 0.0 {
            return t.min(end);
        }
        let phase = t - start;
        match self.repeat {
            LoopMode::Once => t.min(end),
            LoopMode::Loop => start + phase.rem_euclid(span),
            LoopMode::PingPong => {
                let p = phase.rem_euclid(2.0 * span);
                start + if p <= span { p } else { 2.0 * span - p }
            }
        }
    }
}

/// Component-wise blend (`w` = 0 gives `a`); discrete types switch only at `w` = 1.
pub fn mix(a: ParamValue, b: ParamValue, w: f32) -> ParamValue {
    if matches!(a.ty(), ParamType::Bool | ParamType::Enum | ParamType::Trigger) {
        return if w >= 1.0 { b } else { a };
    }
    let c: Vec<f32> = a.components().iter().zip(b.components()).map(|(x, y)| x + (y - x) * w).collect();
    ParamValue::from_components(a.ty(), &c)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f(time: f32, v: f32) -> Key {
        Key { time, value: ParamValue::Float(v) }
    }

    fn value(track: &Track, t: f64) -> f32 {
        match track.sample(t) {
            ParamValue::Float(x) => x,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn interpolations_between_two_keys() {
        let keys = vec![f(0.0, 0.0), f(1.0, 10.0)];
        let step = Track::new(keys.clone(), Interpolation::Step, LoopMode::Once, 1.0);
        let linear = Track::new(keys.clone(), Interpolation::Linear, LoopMode::Once, 1.0);
        let smooth = Track::new(keys, Interpolation::Smooth, LoopMode::Once, 1.0);
        assert_eq!(value(&step, 0.75), 0.0);
        assert!((value(&linear, 0.25) - 2.5).abs() < 1e-6);
        assert!((value(&smooth, 0.25) - 1.5625).abs() < 1e-5); // 3s²−2s³ at s=¼ = 0.15625
        assert!((value(&smooth, 0.5) - 5.0).abs() < 1e-5);
        // Zero slope at keys: tiny steps near a key barely move the value.
        assert!(value(&smooth, 0.001) < 1e-4);
    }

    #[test]
    fn loop_modes_after_the_last_key() {
        let keys = vec![f(0.0, 0.0), f(2.0, 2.0)];
        let once = Track::new(keys.clone(), Interpolation::Linear, LoopMode::Once, 1.0);
        let looped = Track::new(keys.clone(), Interpolation::Linear, LoopMode::Loop, 1.0);
        let ping = Track::new(keys, Interpolation::Linear, LoopMode::PingPong, 1.0);
        assert_eq!(value(&once, 5.0), 2.0);
        assert!((value(&looped, 2.5) - 0.5).abs() < 1e-6);
        assert!((value(&ping, 2.5) - 1.5).abs() < 1e-6);
        assert!((value(&ping, 4.5) - 0.5).abs() < 1e-6);
        // Still exact after weeks of running.
        let weeks = 3.0 * 7.0 * 86400.0 + 0.5;
        assert!((value(&looped, weeks) - 0.5).abs() < 1e-3);
    }

    #[test]
    fn before_the_first_key_holds_and_time_scale_applies() {
        let t = Track::new(vec![f(1.0, 3.0), f(2.0, 5.0)], Interpolation::Linear, LoopMode::PingPong, 0.5);
        assert_eq!(value(&t, 0.0), 3.0);
        assert!((value(&t, 3.0) - 4.0).abs() < 1e-6); // local time 1.5
    }

    #[test]
    fn vectors_interpolate_per_component() {
        let keys = vec![
            Key { time: 0.0, value: ParamValue::Vec2([0.0, 10.0]) },
            Key { time: 1.0, value: ParamValue::Vec2([1.0, 20.0]) },
        ];
        let t = Track::new(keys, Interpolation::Linear, LoopMode::Once, 1.0);
        assert_eq!(t.sample(0.5), ParamValue::Vec2([0.5, 15.0]));
    }
}
