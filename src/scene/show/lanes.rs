//! Timeline lanes edited while the show runs: a [`LaneKeys`] event (the panel's lane view, a
//! fader move recorded into a lane) replaces a lane's keys, adds a lane or removes one, in the
//! running scene and in the show's source — so a chain edit, which rebuilds the show from its
//! source, keeps the edit, and the lane view can save it to the file. A [`LaneTake`] turns a fader
//! move into keys that give, at every step, the value the fader gave.

use std::sync::Arc;

use super::timeline::{MAX_LANES, MAX_SECONDS};
use crate::params::{Interpolation, LaneKeys, RawValue, Track};
use crate::scene::model::Scene;
use crate::scene::schema::TrackFile;
use crate::scene::validate::bind_track;

/// The most keys one lane may have: ten minutes of a fader recorded at 60 steps a second, each
/// step a change (a few hundred KiB).
pub const MAX_LANE_KEYS: usize = 36_000;

/// Applies `lane` to the show `scene` is: the lane on its target gets its keys (or is added, or
/// removed when it has none). Returns the parameter it drives (node, param), for the live
/// override on it to end: an edited lane plays at once. Refused (with why) for a scene, a target
/// the show lacks, keys of the wrong type, too many keys or lanes, or times out of range.
pub fn apply_lane(scene: &mut Scene, lane: &LaneKeys) -> Result<(usize, usize), String> {
    let name = scene.name.clone();
    let show =
        scene.show.as_mut().ok_or_else(|| format!("a lane on '{}': '{name}' is a scene, not a show", lane.target))?;
    if lane.keys.len() > MAX_LANE_KEYS {
        return Err(format!(
            "a lane has at most {MAX_LANE_KEYS} keys; '{}' was given {}",
            lane.target,
            lane.keys.len()
        ));
    }
    if let Some((time, _)) = lane.keys.iter().find(|(t, _)| !(0.0..=MAX_SECONDS as f32).contains(t)) {
        return Err(format!("lane '{}': a key at {time} is not 0 to {MAX_SECONDS}", lane.target));
    }
    let position = scene.tracks.iter().position(|t| t.show_clock && t.target == lane.target);
    let time_scale = position.map_or(1.0, |i| scene.tracks[i].track.time_scale);
    let file = TrackFile {
        target: lane.target.clone(),
        interpolation: lane.interpolation,
        repeat: lane.repeat,
        time_scale,
        beats: lane.beats,
        keys: lane.keys.clone(),
    };
    let driven = if lane.keys.is_empty() {
        let i = position.ok_or_else(|| format!("the show has no lane on '{}' to remove", lane.target))?;
        let removed = scene.tracks.remove(i);
        (removed.node, removed.param)
    } else {
        let bound = bind_track(&scene.nodes, &file, true).map_err(|e| format!("lane: {}", e.join("; ")))?;
        let driven = (bound.node, bound.param);
        match position {
            Some(i) => scene.tracks[i] = bound,
            None if scene.tracks.iter().filter(|t| t.show_clock).count() >= MAX_LANES => {
                return Err(format!("a timeline has at most {MAX_LANES} lanes"));
            }
            None => scene.tracks.push(bound),
        }
        driven
    };
    // The source too: a chain edit rebuilds the show from it, and saving writes its lanes.
    if let Some(source) = Arc::make_mut(show).file.as_mut() {
        let lanes = &mut Arc::make_mut(source).file.timeline.lanes;
        let at = lanes.iter().position(|l| l.target == lane.target);
        match (at, lane.keys.is_empty()) {
            (Some(i), true) => {
                lanes.remove(i);
            }
            (Some(i), false) => lanes[i] = file,
            (None, false) => lanes.push(file),
            (None, true) => {}
        }
    }
    Ok(driven)
}

/// The keys of a lane whose values are one number each (a float, an integer or one component):
/// what the lane view draws and edits. `None` for other lanes.
pub fn scalar_keys(track: &Track) -> Option<Vec<(f32, f32)>> {
    track.keys.iter().map(|k| (k.value.components().len() == 1).then(|| (k.time, k.value.components()[0]))).collect()
}

/// `keys` (time, number) as a lane event's values.
pub fn raw_keys(keys: &[(f32, f32)]) -> Vec<(f32, RawValue)> {
    keys.iter().map(|&(t, v)| (t, RawValue::Number(f64::from(v)))).collect()
}

/// A fader move being recorded into a lane, on the show's fixed clock: the value the parameter
/// holds from each step on, kept where it changes.
#[derive(Clone, Debug)]
pub struct LaneTake {
    dt: f64,
    /// (frame, value from that step on), one per change.
    changes: Vec<(u64, f32)>,
    /// The last step the take saw.
    last: u64,
}

impl LaneTake {
    /// A take on a show stepping every `dt` seconds.
    pub fn new(dt: f32) -> Self {
        Self { dt: f64::from(dt), changes: Vec::new(), last: 0 }
    }

    /// The parameter holds `value` from step `frame` on (told once per displayed frame, before
    /// its steps run). Values are kept only where they change, up to [`MAX_LANE_KEYS`].
    pub fn hold(&mut self, frame: u64, value: f32) {
        if !value.is_finite() || (!self.changes.is_empty() && frame < self.last) {
            return;
        }
        if self.changes.last().is_none_or(|&(_, v)| v != value) && self.changes.len() < MAX_LANE_KEYS / 2 - 4 {
            self.changes.push((frame, value));
        }
        self.last = frame;
    }

    /// The take went on to step `frame` (the last step before it ended).
    pub fn end(&mut self, frame: u64) {
        self.last = self.last.max(frame);
    }

    /// Whether the take holds nothing yet.
    pub fn is_empty(&self) -> bool {
        self.changes.is_empty()
    }

    /// The lane's keys with this take in it: `old`'s keys (seconds) before and after the take's
    /// span, with a key at each edge where the lane was (`old_value` samples the lane as it
    /// was), and inside it a key where the value changed — and, on a lane that interpolates, one
    /// holding that value up to the step before the next change, so every step reads a flat
    /// stretch and gets the value the fader gave. A take replays exactly on any lane; the lane
    /// before and after it is as it was on a `Step` or `Linear` lane, and eases into and out of
    /// the take on a `Smooth` one.
    pub fn keys(
        &self,
        old: &[(f32, f32)],
        old_value: impl Fn(f64) -> f32,
        interpolation: Interpolation,
    ) -> Vec<(f32, f32)> {
        let Some(&(first, _)) = self.changes.first() else { return old.to_vec() };
        let edge = if first > 0 && !old.is_empty() { first - 1 } else { first };
        let mut keys: Vec<(f32, f32)> =
            old.iter().copied().filter(|&(t, _)| f64::from(t) < self.seconds(edge)).collect();
        if edge < first {
            keys.push((self.up(edge), old_value(self.seconds(edge))));
        }
        for (i, &(frame, value)) in self.changes.iter().enumerate() {
            let until = self.changes.get(i + 1).map_or(self.last, |&(next, _)| next - 1);
            keys.push((self.down(frame), value));
            if interpolation != Interpolation::Step && self.up(until) > self.down(frame) {
                keys.push((self.up(until), value));
            }
        }
        // After the take the lane goes on as it was (a new lane holds the take's last value).
        if !old.is_empty() {
            let after = self.last + 1;
            keys.push((self.down(after), old_value(self.seconds(after))));
            keys.extend(old.iter().copied().filter(|&(t, _)| f64::from(t) > self.seconds(after)));
        }
        keys
    }

    fn seconds(&self, frame: u64) -> f64 {
        frame as f64 * self.dt
    }

    /// The latest key time at or before step `frame`'s time: the step reads the key's value.
    fn down(&self, frame: u64) -> f32 {
        let t = self.seconds(frame);
        let f = t as f32;
        if f64::from(f) > t { f.next_down() } else { f }
    }

    /// The earliest key time at or after step `frame`'s time.
    fn up(&self, frame: u64) -> f32 {
        let t = self.seconds(frame);
        let f = t as f32;
        if f64::from(f) < t { f.next_up() } else { f }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::{Key, LoopMode, ParamValue};

    fn track(keys: &[(f32, f32)], interpolation: Interpolation) -> Track {
        let keys = keys.iter().map(|&(time, v)| Key { time, value: ParamValue::Float(v) }).collect();
        Track::new(keys, interpolation, LoopMode::Once, 1.0)
    }

    fn at(track: &Track, frame: u64, dt: f32) -> f32 {
        track.sample(frame as f64 * f64::from(dt)).components()[0]
    }

    /// A fader a performer moves: held, stepped, ramped, held again, once per displayed frame
    /// of two steps.
    fn fader(frame: u64) -> f32 {
        match frame {
            0..100 => 0.25,
            100..160 => (frame / 2) as f32 * 0.01,
            160..190 => 0.9,
            _ => 0.1,
        }
    }

    #[test]
    fn a_take_replays_the_faders_value_at_every_step_on_a_step_lane_and_an_interpolating_one() {
        let dt = 1.0 / 60.0;
        let (from, to) = (5_000u64, 5_200u64); // past a minute: key times are not exact in f32
        for interpolation in [Interpolation::Step, Interpolation::Linear, Interpolation::Smooth] {
            let old = [(0.0, 0.0), (200.0, 1.0)];
            let before = track(&old, interpolation);
            let mut take = LaneTake::new(dt);
            for frame in (from..to).step_by(2) {
                take.hold(frame, fader(frame - from));
            }
            take.end(to - 1);
            let keys = take.keys(&old, |t| before.sample(t).components()[0], interpolation);
            assert!(keys.windows(2).all(|w| w[0].0 < w[1].0), "{interpolation:?}: keys in time order");
            let after = track(&keys, interpolation);
            for frame in from..to {
                let step = frame - (frame - from) % 2;
                assert_eq!(at(&after, frame, dt), fader(step - from), "{interpolation:?}, frame {frame}");
            }
            for frame in (0..from).chain(to..to + 600).filter(|_| interpolation != Interpolation::Smooth) {
                let (now, was) = (at(&after, frame, dt), at(&before, frame, dt));
                assert!((now - was).abs() < 1e-5, "{interpolation:?}: frame {frame} outside the take moved");
            }
            assert_eq!(at(&after, 12_000, dt), 1.0, "{interpolation:?}: the lane's last key is kept");
            assert!(keys.len() < 90, "{interpolation:?}: a held value is one key, not one per step");
        }
    }

    #[test]
    fn a_take_into_a_new_lane_holds_its_first_value_before_and_its_last_after() {
        let mut take = LaneTake::new(0.5);
        take.hold(4, 0.3);
        take.hold(6, 0.7);
        take.hold(8, 0.7);
        let keys = take.keys(&[], |_| 0.0, Interpolation::Step);
        assert_eq!(keys, [(2.0, 0.3), (3.0, 0.7)]);
        take.hold(7, 0.1);
        assert_eq!(take.keys(&[], |_| 0.0, Interpolation::Step), keys, "a step back in time is ignored");
        take.hold(9, f32::NAN);
        assert_eq!(take.keys(&[], |_| 0.0, Interpolation::Step), keys, "so is a value that is not a number");
    }
}
