//! The panel's lane view, under the clip grid: the show's timeline on a ruler (its markers, the
//! play position) and each lane's curve with its keys. Drag a key to move it, double-click to add
//! one, right-click one to remove it; drag on the ruler to put the show there (sought off the
//! render thread, as a jump in the timecode is); arm a lane and move its parameter to record the
//! move into it; save the lanes into the show file. Every edit is a `ControlEvent::Lane`, so a
//! recording of the set holds it and a replay makes it on the same frame.

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::sync::mpsc::{Receiver, TryRecvError};

use egui::{Color32, Pos2, Rect, Sense, Stroke, pos2, vec2};

use crate::params::{ControlEvent, Interpolation, LaneKeys, LoopMode, ParamType, Track};
use crate::scene::show::{LaneTake, ShowSource, lane_file, raw_keys, scalar_keys};
use crate::scene::{BoundTrack, SceneInstance, resolve_target};
use crate::time::FrameTime;

/// A lane's height in points.
const ROW: f32 = 44.0;
/// The ruler's height.
const RULER: f32 = 18.0;
/// How near the pointer must be to a key to take it, in points.
const GRAB: f32 = 7.0;
/// Seconds a tick of the ruler may be apart, the finest first.
const TICKS: [f64; 14] = [0.1, 0.25, 0.5, 1.0, 2.0, 5.0, 10.0, 15.0, 30.0, 60.0, 120.0, 300.0, 600.0, 1800.0];

/// The lane view's state between frames.
pub struct LaneView {
    /// Seconds across the view (the zoom).
    span: f64,
    /// The show's time at the view's left edge.
    left: f64,
    /// Whether the view keeps the play position in sight.
    follow: bool,
    /// The key being dragged.
    drag: Option<KeyDrag>,
    /// Where the pointer is on the ruler while the play position is dragged.
    ghost: Option<f64>,
    /// Where the performer dropped the play position (seconds): the window seeks there.
    pub place: Option<f64>,
    /// Whether a timecode sets the position (no placing by hand then).
    pub chasing: bool,
    /// Lanes armed to record, by target, with what they recorded so far.
    armed: BTreeMap<String, LaneTake>,
    /// The target of a lane to add, as typed.
    new_target: String,
    /// A save on its way to the file, and how the last one went.
    saving: Option<Receiver<Result<String, String>>>,
    status: Option<String>,
}

impl Default for LaneView {
    fn default() -> Self {
        Self {
            span: 30.0,
            left: 0.0,
            follow: true,
            drag: None,
            ghost: None,
            place: None,
            chasing: false,
            armed: BTreeMap::new(),
            new_target: String::new(),
            saving: None,
            status: None,
        }
    }
}

/// A key being dragged: the lane's keys as they are while it moves.
struct KeyDrag {
    target: String,
    index: usize,
    keys: Vec<(f32, f32)>,
}

/// Where a lane's times and values are on screen.
#[derive(Clone, Copy, Debug)]
struct Axes {
    rect: Rect,
    /// Show seconds at the left edge, and across.
    left: f64,
    span: f64,
    /// Seconds of the show per unit of key time (beats at the tempo now, a time scale).
    scale: f64,
    /// Values at the bottom and top.
    low: f32,
    high: f32,
}

impl Axes {
    fn x(&self, key_time: f32) -> f32 {
        let seconds = f64::from(key_time) * self.scale;
        self.rect.left() + ((seconds - self.left) / self.span) as f32 * self.rect.width()
    }

    fn key_time(&self, x: f32) -> f32 {
        let seconds = self.left + f64::from((x - self.rect.left()) / self.rect.width()) * self.span;
        (seconds / self.scale).max(0.0) as f32
    }

    fn y(&self, value: f32) -> f32 {
        let s = if self.high > self.low { (value - self.low) / (self.high - self.low) } else { 0.5 };
        self.rect.bottom() - s.clamp(0.0, 1.0) * self.rect.height()
    }

    fn value(&self, y: f32) -> f32 {
        let s = ((self.rect.bottom() - y) / self.rect.height()).clamp(0.0, 1.0);
        self.low + s * (self.high - self.low)
    }

    /// The key nearest `at`, if one is within grabbing distance.
    fn key_at(&self, keys: &[(f32, f32)], at: Pos2) -> Option<usize> {
        let distance = |&(t, v): &(f32, f32)| pos2(self.x(t), self.y(v)).distance(at);
        let (index, key) = keys.iter().enumerate().min_by(|a, b| distance(a.1).total_cmp(&distance(b.1)))?;
        (distance(key) <= GRAB).then_some(index)
    }
}

/// `keys` with key `index` moved to `to`, kept between its neighbours so the order holds.
fn moved(keys: &[(f32, f32)], index: usize, to: (f32, f32)) -> Vec<(f32, f32)> {
    let mut keys = keys.to_vec();
    let low = index.checked_sub(1).map_or(0.0, |i| keys[i].0.next_up());
    let high = keys.get(index + 1).map_or(f32::MAX, |k| k.0.next_down());
    keys[index] = (to.0.clamp(low, high.max(low)), to.1);
    keys
}

/// `keys` with a key added at `key`, in time order (none added on another's time).
fn added(keys: &[(f32, f32)], key: (f32, f32)) -> Option<Vec<(f32, f32)>> {
    let at = keys.partition_point(|k| k.0 < key.0);
    if keys.get(at).is_some_and(|k| k.0 == key.0) {
        return None;
    }
    let mut keys = keys.to_vec();
    keys.insert(at, key);
    Some(keys)
}

impl LaneView {
    /// Records what the armed lanes' parameters hold from step `frame` on (called once per
    /// displayed frame, after its events and before its steps): a lane records from the first
    /// frame the performer has its parameter.
    pub fn record(&mut self, instance: &SceneInstance, frame: u64) {
        for (target, take) in &mut self.armed {
            let Some(lane) = lane(instance, target) else { continue };
            if instance.is_overridden(lane.node, lane.param) {
                let value = instance.params(lane.node).target_at(lane.param);
                take.hold(frame, value.components()[lane.component.unwrap_or(0)]);
            }
        }
    }

    /// Draws the view for the show `instance` plays at `now` (nothing for a scene); returns the
    /// edits the performer made.
    pub fn draw(&mut self, ui: &mut egui::Ui, instance: &SceneInstance, now: FrameTime) -> Vec<ControlEvent> {
        let mut events = Vec::new();
        if instance.show().is_none() {
            return events;
        }
        self.poll_save();
        egui::CollapsingHeader::new("timeline").default_open(true).show(ui, |ui| {
            ui.horizontal(|ui| {
                ui.add(egui::Slider::new(&mut self.span, 2.0..=3600.0).logarithmic(true).text("s shown"));
                ui.checkbox(&mut self.follow, "follow");
            });
            if self.follow {
                self.left = (now.seconds - self.span * 0.25).max(0.0);
            } else {
                ui.add(egui::Slider::new(&mut self.left, 0.0..=86_400.0).logarithmic(true).text("from s"));
            }
            let width = ui.available_width().max(120.0);
            self.ruler(ui, instance, now, width);
            let lanes: Vec<&BoundTrack> = instance.scene().tracks.iter().filter(|t| t.show_clock).collect();
            for lane in lanes {
                ui.push_id(&lane.target, |ui| events.extend(self.lane(ui, instance, lane, now, width)));
            }
            events.extend(self.add_lane(ui, instance));
            ui.horizontal(|ui| {
                let saving = self.saving.is_some();
                if ui
                    .add_enabled(!saving, egui::Button::new("save lanes"))
                    .on_hover_text("write the lanes into the show file")
                    .clicked()
                {
                    self.save(instance.show_source());
                }
                if let Some(status) = &self.status {
                    ui.small(status);
                }
            });
        });
        events
    }

    /// The ruler: ticks, markers, the play position; dragging on it places the show.
    fn ruler(&mut self, ui: &mut egui::Ui, instance: &SceneInstance, now: FrameTime, width: f32) {
        let sense = if self.chasing { Sense::hover() } else { Sense::click_and_drag() };
        let (rect, response) = ui.allocate_exact_size(vec2(width, RULER), sense);
        let axes = Axes { rect, left: self.left, span: self.span, scale: 1.0, low: 0.0, high: 1.0 };
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 0.0, Color32::from_gray(30));
        let step = TICKS.iter().copied().find(|s| self.span / s <= 10.0).unwrap_or(3600.0);
        let mut tick = (self.left / step).ceil() * step;
        while tick <= self.left + self.span {
            let x = axes.x(tick as f32);
            painter
                .line_segment([pos2(x, rect.bottom() - 5.0), pos2(x, rect.bottom())], Stroke::new(1.0, Color32::GRAY));
            let label = format!("{}:{:04.1}", (tick / 60.0).floor(), tick.rem_euclid(60.0));
            painter.text(
                pos2(x + 2.0, rect.top()),
                egui::Align2::LEFT_TOP,
                label,
                egui::FontId::monospace(9.0),
                Color32::GRAY,
            );
            tick += step;
        }
        if let Some((show, _)) = instance.show() {
            for marker in &show.timeline.markers {
                let x = axes.x((marker.frame as f64 * f64::from(now.dt)) as f32);
                painter.line_segment([pos2(x, rect.top()), pos2(x, rect.bottom())], Stroke::new(2.0, Color32::GOLD));
                painter.text(
                    pos2(x + 2.0, rect.center().y),
                    egui::Align2::LEFT_TOP,
                    &marker.name,
                    egui::FontId::proportional(9.0),
                    Color32::GOLD,
                );
            }
        }
        let mark = |at: f64, color| {
            let x = axes.x(at as f32);
            painter.line_segment([pos2(x, rect.top()), pos2(x, rect.bottom())], Stroke::new(2.0, color));
        };
        mark(now.seconds, Color32::RED);
        // Where the press is, or was at release (a slow frame may see the whole drag at once).
        let pointer = response.interact_pointer_pos().or(ui.input(|i| i.pointer.latest_pos()));
        let pointer = pointer.map(|p| f64::from(axes.key_time(p.x)));
        if response.dragged() {
            self.ghost = pointer;
        }
        if let Some(ghost) = self.ghost {
            mark(ghost, Color32::YELLOW);
        }
        if response.drag_stopped() || response.clicked() {
            self.place = pointer.or(self.ghost);
            self.ghost = None;
        }
        let hint = if self.chasing { "the timecode sets the position" } else { "drag to put the show at another time" };
        response.on_hover_text(hint);
    }

    /// One lane: its name, record and remove buttons, and its curve with keys to edit.
    fn lane(
        &mut self,
        ui: &mut egui::Ui,
        instance: &SceneInstance,
        lane: &BoundTrack,
        now: FrameTime,
        width: f32,
    ) -> Vec<ControlEvent> {
        let mut events = Vec::new();
        let keys = scalar_keys(&lane.track);
        let recordable = keys.is_some() && !lane.beats && lane.track.time_scale == 1.0;
        let edit = |keys: Vec<(f32, f32)>| edit(lane, &keys);
        ui.horizontal(|ui| {
            let armed = self.armed.contains_key(&lane.target);
            let hint = "record: arm, then move the parameter; disarm to keep the take";
            let arm = ui.add_enabled(recordable, egui::Button::selectable(armed, "● rec")).on_hover_text(hint);
            if arm.clicked() {
                match self.armed.remove(&lane.target) {
                    None => drop(self.armed.insert(lane.target.clone(), LaneTake::new(now.dt))),
                    Some(mut take) if !take.is_empty() => {
                        take.end(now.frame.saturating_sub(1));
                        let old = keys.clone().unwrap_or_default();
                        let sample = |t: f64| lane.track.sample(t).components()[0];
                        events.push(edit(take.keys(&old, sample, lane.track.interpolation)));
                    }
                    Some(_) => {}
                }
            }
            if ui.small_button("x").on_hover_text("remove this lane").clicked() {
                events.push(edit(Vec::new()));
            }
            let unit = if lane.beats { " (beats)" } else { "" };
            ui.label(format!("{}{unit}", lane.target));
        });
        let Some(keys) = keys else {
            ui.small("a lane of several values: edit it in the show file");
            return events;
        };
        let (rect, response) = ui.allocate_exact_size(vec2(width, ROW), Sense::click_and_drag());
        let bpm = instance.tempo().bpm.max(1.0);
        let scale = if lane.beats { 60.0 / bpm } else { 1.0 } / f64::from(lane.track.time_scale);
        let decl = &instance.params(lane.node).decls()[lane.param];
        let (low, high) = decl.range.unwrap_or_else(|| {
            let (lo, hi) = keys.iter().fold((f32::MAX, f32::MIN), |(lo, hi), k| (lo.min(k.1), hi.max(k.1)));
            if hi > lo { (lo, hi) } else { (lo - 1.0, lo + 1.0) }
        });
        let axes = Axes { rect, left: self.left, span: self.span, scale, low, high };
        let dragging = self.drag.as_ref().filter(|d| d.target == lane.target).map(|d| d.keys.clone());
        let shown = dragging.unwrap_or_else(|| keys.clone());
        self.paint(ui, &axes, &shown, lane, now);
        let pointer = response.interact_pointer_pos();
        // The key under the press, not under the pointer when the drag is seen to start.
        let pressed = ui.input(|i| i.pointer.press_origin()).or(pointer);
        if let Some(at) = pressed.filter(|_| response.drag_started())
            && let Some(index) = axes.key_at(&keys, at)
        {
            self.drag = Some(KeyDrag { target: lane.target.clone(), index, keys: keys.clone() });
        }
        if let (Some(at), Some(drag)) = (pointer, self.drag.as_mut().filter(|d| d.target == lane.target)) {
            drag.keys = moved(&keys, drag.index, (axes.key_time(at.x), axes.value(at.y)));
            if response.drag_stopped() {
                events.push(edit(std::mem::take(&mut drag.keys)));
                self.drag = None;
            }
        }
        if let Some(at) = pointer.filter(|_| response.double_clicked())
            && axes.key_at(&keys, at).is_none()
            && let Some(keys) = added(&keys, (axes.key_time(at.x), axes.value(at.y)))
        {
            events.push(edit(keys));
        }
        if let Some(index) = pointer.filter(|_| response.secondary_clicked()).and_then(|at| axes.key_at(&keys, at))
            && keys.len() > 1
        {
            let mut keys = keys;
            keys.remove(index);
            events.push(edit(keys));
        }
        response.on_hover_text("drag a key · double-click: add a key · right-click a key: remove it");
        events
    }

    /// A lane's curve (as `keys` make it), its keys and the play position.
    fn paint(&self, ui: &egui::Ui, axes: &Axes, keys: &[(f32, f32)], lane: &BoundTrack, now: FrameTime) {
        let painter = ui.painter_at(axes.rect);
        let armed = self.armed.contains_key(&lane.target);
        painter.rect_filled(axes.rect, 0.0, if armed { Color32::from_rgb(60, 20, 20) } else { Color32::from_gray(20) });
        // The lane's own track, unless a key is being dragged (its keys are then `keys`).
        let scale = lane.track.time_scale;
        let track = if self.drag.as_ref().is_some_and(|d| d.target == lane.target) {
            let with =
                |(time, value): (f32, f32)| crate::params::Key { time, value: crate::params::ParamValue::Float(value) };
            let keys = keys.iter().copied().map(with).collect();
            Cow::Owned(Track::new(keys, lane.track.interpolation, lane.track.repeat, scale))
        } else {
            Cow::Borrowed(&lane.track)
        };
        let points = (0..=axes.rect.width() as usize / 2)
            .map(|i| {
                let x = axes.rect.left() + i as f32 * 2.0;
                pos2(x, axes.y(track.sample(f64::from(axes.key_time(x) / scale)).components()[0]))
            })
            .collect();
        painter.line(points, Stroke::new(1.5, Color32::LIGHT_BLUE));
        for &(time, value) in keys {
            painter.circle_filled(pos2(axes.x(time), axes.y(value)), 3.5, Color32::WHITE);
        }
        let x = axes.rect.left() + ((now.seconds - axes.left) / axes.span) as f32 * axes.rect.width();
        painter.line_segment([pos2(x, axes.rect.top()), pos2(x, axes.rect.bottom())], Stroke::new(1.0, Color32::RED));
    }

    /// A field to name a parameter and a button that gives it a lane, holding its value now.
    fn add_lane(&mut self, ui: &mut egui::Ui, instance: &SceneInstance) -> Option<ControlEvent> {
        let mut event = None;
        ui.horizontal(|ui| {
            ui.add(egui::TextEdit::singleline(&mut self.new_target).hint_text("layer/1.opacity").desired_width(140.0));
            if !ui.button("add lane").clicked() {
                return;
            }
            let scene = instance.scene();
            match resolve_target(&scene.nodes, &self.new_target) {
                Err(e) => self.status = Some(format!("no lane: {e}")),
                Ok(t) => {
                    let decl = &instance.params(t.node).decls()[t.param];
                    let value = instance.params(t.node).target_at(t.param).components().first().copied();
                    match value {
                        Some(v) if t.component.is_some() || matches!(decl.ty(), ParamType::Float | ParamType::Int) => {
                            event = Some(ControlEvent::Lane(LaneKeys {
                                target: std::mem::take(&mut self.new_target),
                                keys: raw_keys(&[(0.0, v)]),
                                interpolation: Interpolation::Step,
                                repeat: LoopMode::Once,
                                beats: false,
                            }));
                        }
                        _ => self.status = Some(format!("no lane: name one number ({}.x, …)", self.new_target)),
                    }
                }
            }
        });
        event
    }

    /// Writes the lanes of the show's `source` into its file on a thread of its own.
    fn save(&mut self, source: Option<(&ShowSource, &str)>) {
        let Some((source, path)) = source.map(|(s, p)| (s, std::path::PathBuf::from(p))).filter(|(_, p)| p.is_file())
        else {
            self.status = Some("the show is built in: copy its file and run that to save lanes".into());
            return;
        };
        let (text, lanes) = (source.text.clone(), source.file.timeline.lanes.clone());
        let (sender, receiver) = std::sync::mpsc::channel();
        let spawned = std::thread::Builder::new().name("indra-lane-save".into()).spawn(move || {
            let saved = lane_file::with_lanes(&text, &lanes)
                .and_then(|text| crate::atomic_file::write(&path, text.as_bytes()).map_err(|e| e.to_string()))
                .map(|()| format!("{} lanes saved to {}", lanes.len(), path.display()));
            let _ = sender.send(saved);
        });
        match spawned {
            Ok(_) => self.saving = Some(receiver),
            Err(e) => self.status = Some(format!("lanes not saved: no thread ({e})")),
        }
    }

    fn poll_save(&mut self) {
        let Some(receiver) = &self.saving else { return };
        match receiver.try_recv() {
            Err(TryRecvError::Empty) => return,
            Ok(Ok(done)) => self.status = Some(done),
            Ok(Err(e)) => self.status = Some(format!("lanes not saved: {e}")),
            Err(TryRecvError::Disconnected) => self.status = Some("lanes not saved: the save stopped".into()),
        }
        self.saving = None;
    }
}

/// The lane on `target` that `instance`'s timeline has.
fn lane<'a>(instance: &'a SceneInstance, target: &str) -> Option<&'a BoundTrack> {
    instance.scene().tracks.iter().find(|t| t.show_clock && t.target == target)
}

/// `lane` given `keys` (none: removed), the rest of it as it is.
fn edit(lane: &BoundTrack, keys: &[(f32, f32)]) -> ControlEvent {
    ControlEvent::Lane(LaneKeys {
        target: lane.target.clone(),
        keys: raw_keys(keys),
        interpolation: lane.track.interpolation,
        repeat: lane.track.repeat,
        beats: lane.beats,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn axes() -> Axes {
        let rect = Rect::from_min_size(pos2(100.0, 50.0), vec2(400.0, 40.0));
        Axes { rect, left: 10.0, span: 20.0, scale: 1.0, low: 0.0, high: 2.0 }
    }

    #[test]
    fn the_axes_map_times_and_values_to_points_and_back() {
        let a = axes();
        assert_eq!((a.x(10.0), a.x(30.0), a.x(20.0)), (100.0, 500.0, 300.0));
        assert_eq!((a.y(0.0), a.y(2.0), a.y(1.0), a.y(9.0)), (90.0, 50.0, 70.0, 50.0));
        assert_eq!((a.key_time(300.0), a.value(70.0)), (20.0, 1.0));
        let beats = Axes { scale: 0.5, ..a }; // 120 BPM: a beat is half a second
        assert_eq!((beats.x(40.0), beats.key_time(300.0)), (300.0, 40.0));
    }

    #[test]
    fn a_key_is_taken_near_the_pointer_and_moved_only_between_its_neighbours() {
        let (a, keys) = (axes(), [(12.0, 0.0), (20.0, 1.0), (25.0, 2.0)]);
        assert_eq!(a.key_at(&keys, pos2(303.0, 72.0)), Some(1));
        assert_eq!(a.key_at(&keys, pos2(250.0, 72.0)), None, "no key near");
        let dragged = moved(&keys, 1, (40.0, 0.5));
        assert!(dragged[1].0 < 25.0 && dragged[1].0 > 24.99 && dragged[1].1 == 0.5, "{dragged:?}");
        assert_eq!(moved(&keys, 0, (-3.0, 1.0))[0], (0.0, 1.0), "not before the show's start");
        assert_eq!(added(&keys, (21.0, 0.5)).unwrap()[2], (21.0, 0.5));
        assert_eq!(added(&keys, (20.0, 0.5)), None, "not on another key's time");
    }
}
