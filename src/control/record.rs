//! Recording and replaying control streams: every control event applied to the scene (from the
//! UI, OSC, MIDI, presets) is written with the fixed-step frame it applied before, one RON value
//! per line, by node and parameter *name*. Replaying applies the same events before the same
//! frames off-screen, which reproduces the session frame-exactly — a live set becomes a
//! regression test and a frame-exact export.

use std::collections::BTreeMap;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::params::{ControlEvent, ParamWrite, RawValue, ShowCommand, Source, raw_from_value, value_from_raw};
use crate::scene::Scene;

/// One line of a control-stream file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Recorded {
    /// The fixed-step frame the event applied before.
    pub frame: u64,
    /// What happened.
    pub event: RecordedEvent,
}

/// An event by names, so recordings survive node reordering.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum RecordedEvent {
    /// A parameter write.
    Write {
        /// Node id.
        node: String,
        /// Parameter name.
        param: String,
        /// Component index, if one.
        component: Option<usize>,
        /// The value.
        value: RawValue,
        /// Who wrote it.
        source: Source,
    },
    /// A preset recall: (node, param, value) over seconds.
    Morph {
        /// The values.
        values: Vec<(String, String, RawValue)>,
        /// Duration.
        seconds: f64,
    },
    /// Tracks resumed.
    ResumeTracks,
    /// The tempo set (tap, OSC, MIDI clock).
    Tempo {
        /// Beats per minute.
        bpm: f64,
        /// Whether the beat snapped to this step.
        resync: bool,
    },
    /// The beat moved to a phase of the bar (Ableton Link).
    Phase {
        /// The beat within the bar.
        phase: f64,
        /// Beats per bar.
        quantum: f64,
    },
    /// A show command (clip, column or cue), numbered from 0.
    Show(ShowCommand),
}

/// Writes events as they are applied — into a temporary file beside the target, renamed over it
/// when the recording finishes (dropped): a show killed mid-recording leaves the previous
/// recording whole and this one in `.<name>.<pid>.recording` (replayable up to its last line).
pub struct Recorder {
    out: BufWriter<std::fs::File>,
    temp: PathBuf,
    target: PathBuf,
    finished: bool,
    /// Events written so far.
    pub count: usize,
}

impl Recorder {
    /// Starts a recording that will replace `path` when it finishes.
    pub fn create(path: &Path) -> Result<Self, String> {
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let temp = path.with_file_name(format!(".{name}.{}.recording", std::process::id()));
        let file = std::fs::File::create(&temp).map_err(|e| format!("cannot record to {}: {e}", path.display()))?;
        Ok(Self { out: BufWriter::new(file), temp, target: path.to_path_buf(), finished: false, count: 0 })
    }

    /// Flushes to disk and renames the recording over its target (done on drop if not before).
    pub fn finish(&mut self) -> Result<(), String> {
        if self.finished {
            return Ok(());
        }
        self.finished = true;
        let done = self.out.flush().and_then(|()| self.out.get_ref().sync_all());
        done.and_then(|()| std::fs::rename(&self.temp, &self.target))
            .map_err(|e| format!("cannot finish the recording {}: {e}", self.target.display()))
    }

    /// Writes `events` applied before `frame`, and flushes (a crash loses at most one frame).
    /// An event whose parameter the scene does not have is left out with a logged line, never
    /// a panic (events are remapped on reload, so this is a guard, not a path).
    pub fn record(&mut self, frame: u64, events: &[ControlEvent], scene: &Scene) -> Result<(), String> {
        for event in events {
            let Some(event) = to_recorded(event, scene) else {
                log::warn!("not recorded (no such parameter in '{}'): {event:?}", scene.name);
                continue;
            };
            let text = ron::to_string(&Recorded { frame, event }).map_err(|e| e.to_string())?;
            writeln!(self.out, "{text}").map_err(|e| e.to_string())?;
            self.count += 1;
        }
        if !events.is_empty() {
            self.out.flush().map_err(|e| e.to_string())?;
        }
        Ok(())
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        if let Err(e) = self.finish() {
            log::error!("{e}");
        }
    }
}

/// Node id, parameter name and declaration of a position, if the scene has it.
fn named(scene: &Scene, node: usize, param: usize) -> Option<(String, String, &crate::params::ParamDecl)> {
    let n = scene.nodes.get(node)?;
    let decl = n.params.decls().get(param)?;
    Some((n.id.clone(), decl.name.clone(), decl))
}

fn to_recorded(event: &ControlEvent, scene: &Scene) -> Option<RecordedEvent> {
    Some(match event {
        ControlEvent::Write(w) => {
            let (node, param, decl) = named(scene, w.node, w.param)?;
            let value = match w.component {
                Some(_) => RawValue::Number(f64::from(w.value.components()[0])),
                None => raw_from_value(&w.value, decl),
            };
            RecordedEvent::Write { node, param, component: w.component, value, source: w.source }
        }
        ControlEvent::Morph { values, seconds } => RecordedEvent::Morph {
            values: values
                .iter()
                .map(|(n, p, v)| named(scene, *n, *p).map(|(node, param, decl)| (node, param, raw_from_value(v, decl))))
                .collect::<Option<_>>()?,
            seconds: *seconds,
        },
        ControlEvent::ResumeTracks => RecordedEvent::ResumeTracks,
        ControlEvent::Tempo { bpm, resync } => RecordedEvent::Tempo { bpm: *bpm, resync: *resync },
        ControlEvent::Phase { phase, quantum } => RecordedEvent::Phase { phase: *phase, quantum: *quantum },
        ControlEvent::Show(command) => RecordedEvent::Show(*command),
    })
}

/// The largest recording read: hours of dense control at a few hundred bytes an event.
const REPLAY_FILE_LIMIT: u64 = 256 << 20;

/// Reads a recording for `scene`: events by frame. Errors name the line. A last line cut short
/// (a crash mid-write: no newline after it) is left out, so the take replays up to its last
/// complete line.
pub fn read_replay(path: &Path, scene: &Scene) -> Result<BTreeMap<u64, Vec<ControlEvent>>, String> {
    let bytes = crate::files::read_limited(path, REPLAY_FILE_LIMIT).map_err(|e| format!("cannot read {e}"))?;
    let text = String::from_utf8_lossy(&bytes);
    let cut_short = !text.is_empty() && !text.ends_with('\n');
    let lines: Vec<&str> = text.lines().collect();
    let mut out: BTreeMap<u64, Vec<ControlEvent>> = BTreeMap::new();
    for (i, line) in lines.iter().enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let at = |msg: String| format!("{}:{}: {msg}", path.display(), i + 1);
        let rec: Recorded = match ron::from_str(line) {
            Ok(rec) => rec,
            Err(_) if cut_short && i + 1 == lines.len() => {
                log::warn!("{}:{}: the last line is cut short; replaying up to the line before", path.display(), i + 1);
                break;
            }
            Err(e) => return Err(at(e.to_string())),
        };
        let event = from_recorded(&rec.event, scene).map_err(at)?;
        out.entry(rec.frame).or_default().push(event);
    }
    Ok(out)
}

/// `x` if it is a finite number, else why not.
fn finite(what: &str, x: f64) -> Result<f64, String> {
    if x.is_finite() { Ok(x) } else { Err(format!("{what} {x} is not a finite number")) }
}

fn resolve(scene: &Scene, node: &str, param: &str) -> Result<(usize, usize), String> {
    let n = scene.node_index(node).ok_or_else(|| format!("no node '{node}' in scene '{}'", scene.name))?;
    let p = scene.nodes[n].params.index(param).ok_or_else(|| format!("node '{node}' has no parameter '{param}'"))?;
    Ok((n, p))
}

fn from_recorded(event: &RecordedEvent, scene: &Scene) -> Result<ControlEvent, String> {
    Ok(match event {
        RecordedEvent::Write { node, param, component, value, source } => {
            let (n, p) = resolve(scene, node, param)?;
            let decl = &scene.nodes[n].params.decls()[p];
            let typed = match component {
                Some(c) if *c >= decl.ty().components() || !decl.is_smoothable() => {
                    return Err(format!("{node}.{param} is a {} and has no component {c}", decl.ty().name()));
                }
                Some(_) => match value {
                    RawValue::Number(x) => crate::params::ParamValue::Float(*x as f32),
                    other => return Err(format!("component value {other:?} is not a number")),
                },
                None => value_from_raw(value, decl).ok_or_else(|| format!("{value:?} does not fit {node}.{param}"))?,
            };
            ControlEvent::Write(ParamWrite { node: n, param: p, component: *component, value: typed, source: *source })
        }
        RecordedEvent::Morph { values, seconds } => ControlEvent::Morph {
            values: values
                .iter()
                .map(|(node, param, raw)| {
                    let (n, p) = resolve(scene, node, param)?;
                    let decl = &scene.nodes[n].params.decls()[p];
                    Ok((n, p, value_from_raw(raw, decl).ok_or_else(|| format!("{raw:?} does not fit {node}.{param}"))?))
                })
                .collect::<Result<_, String>>()?,
            seconds: finite("morph seconds", *seconds)
                .and_then(|s| if s >= 0.0 { Ok(s) } else { Err(format!("morph seconds {s} is negative")) })?,
        },
        RecordedEvent::ResumeTracks => ControlEvent::ResumeTracks,
        RecordedEvent::Tempo { bpm, resync } => ControlEvent::Tempo { bpm: finite("bpm", *bpm)?, resync: *resync },
        RecordedEvent::Phase { phase, quantum } => {
            ControlEvent::Phase { phase: finite("phase", *phase)?, quantum: finite("quantum", *quantum)? }
        }
        // Numbers past the show's layers, clips or cues are refused where the show applies them.
        RecordedEvent::Show(command) => ControlEvent::Show(*command),
    })
}
