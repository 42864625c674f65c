//! A show's timeline: **lanes** — automation on any parameter the show has (a clip's, a
//! layer's, an effect's, the master's), on the show's own clock or its beat — and **markers**, which fire
//! the cue list's cues, clips and columns at their time; and the timecode the timeline chases.
//! Lanes and markers are functions of the frame, so renders, seeks, checkpoints and recordings
//! take them as they take a scene's tracks.
//!
//! ```ron
//! timeline: (
//!     lanes: [(target: "layer/1.opacity", keys: [(0.0, 0.0), (4.0, 1.0)], interpolation: Linear)],
//!     markers: [(at: 12.0, cue: 2), (at: 20.0, clip: (1, 3)), (at: 30.0, column: 2)],
//!     chase: (start: "01:00:00:00", freewheel: 2.0),
//! )
//! ```

use serde::Deserialize;

use super::Show;
use crate::params::ShowCommand;
use crate::scene::model::{BoundTrack, SceneNode};
use crate::scene::schema::TrackFile;
use crate::scene::validate::bind_track;
use crate::timecode::Timecode;
use crate::timecode::chase::{ChaseSettings, MAX_FREEWHEEL};

/// The most lanes a timeline may have.
pub const MAX_LANES: usize = 1024;
/// The most markers.
pub const MAX_MARKERS: usize = 4096;
/// The latest a marker may be: a day, as timecode runs.
pub(super) const MAX_SECONDS: f64 = 86_400.0;

/// The `timeline` section of a show file.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimelineFile {
    /// Automation, as a scene's tracks are written; targets as `layer/1.opacity`,
    /// `master.level` or `<clip>/<node>.<param>`; times in seconds of the show.
    #[serde(default)]
    pub lanes: Vec<TrackFile>,
    /// Markers, in any order.
    #[serde(default)]
    pub markers: Vec<MarkerFile>,
    /// The timecode the timeline chases, when it does.
    #[serde(default)]
    pub chase: Option<ChaseFile>,
}

/// A marker as written: a time and one thing it does.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MarkerFile {
    /// Seconds of the show.
    pub at: f64,
    /// A name for the panel.
    #[serde(default)]
    pub name: String,
    /// Goes to cue n (from 1).
    #[serde(default)]
    pub cue: Option<usize>,
    /// Triggers clip (layer, clip) (from 1; clip 0 empties the layer).
    #[serde(default)]
    pub clip: Option<(usize, usize)>,
    /// Triggers column n (from 1).
    #[serde(default)]
    pub column: Option<usize>,
}

/// How the timeline chases a code, as written.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChaseFile {
    /// The code's label at the show's first frame (`HH:MM:SS:FF`).
    pub start: String,
    /// Seconds the show runs on when the code drops out (default 2).
    #[serde(default = "two_seconds")]
    pub freewheel: f64,
}

fn two_seconds() -> f64 {
    2.0
}

/// A marker, validated: at the start of `frame`, `command` is asked of the show.
#[derive(Clone, Debug, PartialEq)]
pub struct Marker {
    /// The show's frame.
    pub frame: u64,
    /// Its name.
    pub name: String,
    /// What it does.
    pub command: ShowCommand,
}

/// A validated timeline's markers and chase (its lanes are the flat scene's tracks).
#[derive(Clone, Debug, Default)]
pub struct Timeline {
    /// Markers by frame (stable: two on one frame fire in the file's order).
    pub markers: Vec<Marker>,
    /// The chase, if the show has one.
    pub chase: Option<ChaseSettings>,
}

/// What a timeline's lanes and problems are.
pub type Built = (Vec<BoundTrack>, Timeline, Vec<(String, String)>);

/// Validates `file` against the flat show's `nodes` and `show` (its layers, columns and cues)
/// at step `dt`: its lanes as tracks on the show's clock, its markers and chase, and its
/// problems as (anchor, sentence) pairs.
pub fn build_timeline(file: &TimelineFile, nodes: &[SceneNode], show: &Show, dt: f32) -> Built {
    let (mut lanes, mut problems) = (Vec::new(), Vec::new());
    let mut timeline = Timeline::default();
    if file.lanes.len() > MAX_LANES || file.markers.len() > MAX_MARKERS {
        let message = format!("a timeline has at most {MAX_LANES} lanes and {MAX_MARKERS} markers");
        return (lanes, timeline, vec![("timeline".into(), message)]);
    }
    for lane in &file.lanes {
        match bind_track(nodes, lane, true) {
            Ok(track) => lanes.push(track),
            Err(e) => problems.extend(e.into_iter().map(|m| (format!("\"{}\"", lane.target), format!("lane: {m}")))),
        }
    }
    for (i, marker) in file.markers.iter().enumerate() {
        let anchor = if marker.name.is_empty() { "markers".to_string() } else { format!("\"{}\"", marker.name) };
        match self::marker(marker, show, dt) {
            Ok(m) => timeline.markers.push(m),
            Err(e) => problems.push((anchor, format!("marker {}: {e}", i + 1))),
        }
    }
    timeline.markers.sort_by_key(|m| m.frame);
    if let Some(chase) = &file.chase {
        match Timecode::parse(&chase.start) {
            Err(e) => problems.push(("chase".into(), format!("chase start: {e}"))),
            Ok(_) if !(0.0..=MAX_FREEWHEEL).contains(&chase.freewheel) => problems.push((
                "freewheel".into(),
                format!("freewheel {} must be 0 to {MAX_FREEWHEEL} seconds", chase.freewheel),
            )),
            Ok(start) => timeline.chase = Some(ChaseSettings { start, freewheel: chase.freewheel }),
        }
    }
    (lanes, timeline, problems)
}

/// One marker, or why not.
fn marker(m: &MarkerFile, show: &Show, dt: f32) -> Result<Marker, String> {
    if !(0.0..=MAX_SECONDS).contains(&m.at) {
        return Err(format!("at {} must be 0 to {MAX_SECONDS} seconds", m.at));
    }
    let command = match (m.cue, m.clip, m.column) {
        (Some(n), None, None) if (1..=show.cues.len()).contains(&n) => ShowCommand::CueGoto(n - 1),
        (Some(n), None, None) => return Err(format!("cue {n}: the show has {} cues", show.cues.len())),
        (None, Some((layer, clip)), None) => {
            let Some(l) = layer.checked_sub(1).filter(|&l| l < show.layers.len()) else {
                return Err(format!("layer {layer}: the show has {} layers", show.layers.len()));
            };
            if clip > show.layers[l].clips.len() {
                return Err(format!("clip {clip}: layer {layer} has {} clips", show.layers[l].clips.len()));
            }
            ShowCommand::Trigger { layer: l, clip: clip.checked_sub(1) }
        }
        (None, None, Some(n)) if (1..=show.columns.len()).contains(&n) => ShowCommand::Column(n - 1),
        (None, None, Some(n)) => return Err(format!("column {n}: the show has {} columns", show.columns.len())),
        _ => return Err("a marker does one thing: give it a cue, a clip or a column".into()),
    };
    // The frame whose time is nearest: markers written on a grid of seconds land on frames.
    let frame = (m.at / f64::from(dt)).round() as u64;
    Ok(Marker { frame, name: m.name.clone(), command })
}

impl Show {
    /// The markers that fire at the start of `frame`.
    pub fn markers_at(&self, frame: u64) -> &[Marker] {
        let from = self.timeline.markers.partition_point(|m| m.frame < frame);
        let to = self.timeline.markers.partition_point(|m| m.frame <= frame);
        &self.timeline.markers[from..to]
    }
}
