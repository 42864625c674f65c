//! Recording and replaying control streams: every control event applied to the scene (from the
//! UI, OSC, MIDI, presets) is written with the fixed-step frame it applied before, one RON value
//! per line, by node and parameter *name*. Replaying applies the same events before the same
//! frames off-screen, which reproduces the session frame-exactly — a live set becomes a
//! regression test and a frame-exact export.

use std::collections::BTreeMap;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::assets::Assets;
use crate::params::{
    Addressing, ControlEvent, ParamSet, ParamWrite, RawValue, ShowCommand, Source, raw_from_value, value_from_raw,
};
use crate::scene::Scene;
use crate::scene::show::chain_edit::edited_show;

/// One line of a control-stream file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Recorded {
    /// The fixed-step frame the event applied before.
    pub frame: u64,
    /// What happened, by names.
    pub event: ControlEvent<Named>,
}

/// Control events by names and raw values, so recordings survive node reordering and edits of a
/// parameter's type: the same [`ControlEvent`], addressed as a file needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Named;

impl Addressing for Named {
    type Write = NamedWrite;
    type Values = Vec<(String, String, RawValue)>;
}

/// A parameter write by names.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NamedWrite {
    /// Node id.
    pub node: String,
    /// Parameter name.
    pub param: String,
    /// Component index, if one.
    pub component: Option<usize>,
    /// The value.
    pub value: RawValue,
    /// Who wrote it.
    pub source: Source,
}

/// RON as recordings are written: a write's fields directly inside `Write(…)`, as they were when
/// the event had a type of its own.
fn ron_options() -> ron::Options {
    ron::Options::default().with_default_extension(ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES)
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
            let text = ron_options().to_string(&Recorded { frame, event }).map_err(|e| e.to_string())?;
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

fn to_recorded(event: &ControlEvent, scene: &Scene) -> Option<ControlEvent<Named>> {
    Some(match event {
        ControlEvent::Write(w) => {
            let (node, param, decl) = named(scene, w.node, w.param)?;
            let value = match w.component {
                Some(_) => RawValue::Number(f64::from(w.value.components()[0])),
                None => raw_from_value(&w.value, decl),
            };
            ControlEvent::Write(NamedWrite { node, param, component: w.component, value, source: w.source })
        }
        ControlEvent::Morph { values, seconds } => ControlEvent::Morph {
            values: values
                .iter()
                .map(|(n, p, v)| named(scene, *n, *p).map(|(node, param, decl)| (node, param, raw_from_value(v, decl))))
                .collect::<Option<_>>()?,
            seconds: *seconds,
        },
        ControlEvent::ResumeTracks => ControlEvent::ResumeTracks,
        ControlEvent::Tempo { bpm, resync } => ControlEvent::Tempo { bpm: *bpm, resync: *resync },
        ControlEvent::Phase { phase, quantum } => ControlEvent::Phase { phase: *phase, quantum: *quantum },
        ControlEvent::Show(command) => ControlEvent::Show(*command),
        ControlEvent::Audio(snapshot) => ControlEvent::Audio(snapshot.clone()),
        ControlEvent::Lane(lane) => ControlEvent::Lane(lane.clone()),
    })
}

/// The largest recording read: hours of dense control at a few hundred bytes an event.
const REPLAY_FILE_LIMIT: u64 = 256 << 20;

/// Reads a recording for `scene` (its effect edits followed with `assets`): events by frame.
/// Errors name the line. A last line cut short (a crash mid-write: no newline after it) is left
/// out, so the take replays up to its last complete line.
pub fn read_replay(path: &Path, scene: &Scene, assets: &Assets) -> Result<BTreeMap<u64, Vec<ControlEvent>>, String> {
    let bytes = crate::files::read_limited(path, REPLAY_FILE_LIMIT).map_err(|e| format!("cannot read {e}"))?;
    let text = String::from_utf8_lossy(&bytes);
    let cut_short = !text.is_empty() && !text.ends_with('\n');
    let lines: Vec<&str> = text.lines().collect();
    let mut out: BTreeMap<u64, Vec<ControlEvent>> = BTreeMap::new();
    let mut current = std::borrow::Cow::Borrowed(scene);
    for (i, line) in lines.iter().enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let at = |msg: String| format!("{}:{}: {msg}", path.display(), i + 1);
        let rec: Recorded = match ron_options().from_str(line) {
            Ok(rec) => rec,
            Err(_) if cut_short && i + 1 == lines.len() => {
                log::warn!("{}:{}: the last line is cut short; replaying up to the line before", path.display(), i + 1);
                break;
            }
            Err(e) => return Err(at(e.to_string())),
        };
        let event = from_recorded(&rec.event, &current).map_err(at)?;
        // After a chain edit, the events that follow name the parameters of the edited show.
        if let ControlEvent::Show(ShowCommand::Effect { layer, edit }) = event {
            let defaults: Vec<ParamSet> = current.nodes.iter().map(|n| n.params.clone()).collect();
            match edited_show(assets, &current, &defaults, layer, edit) {
                Ok(edited) => current = std::borrow::Cow::Owned(edited),
                Err(e) => log::warn!("{}:{}: the effect edit will be refused: {e}", path.display(), i + 1),
            }
        }
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

fn from_recorded(event: &ControlEvent<Named>, scene: &Scene) -> Result<ControlEvent, String> {
    Ok(match event {
        ControlEvent::Write(NamedWrite { node, param, component, value, source }) => {
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
        ControlEvent::Morph { values, seconds } => ControlEvent::Morph {
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
        ControlEvent::ResumeTracks => ControlEvent::ResumeTracks,
        ControlEvent::Tempo { bpm, resync } => ControlEvent::Tempo { bpm: finite("bpm", *bpm)?, resync: *resync },
        ControlEvent::Phase { phase, quantum } => {
            ControlEvent::Phase { phase: finite("phase", *phase)?, quantum: finite("quantum", *quantum)? }
        }
        // Numbers past the show's layers, clips or cues are refused where the show applies them.
        ControlEvent::Show(command) => ControlEvent::Show(*command),
        ControlEvent::Audio(snapshot) => {
            let fits = |v: &[f32]| v.len() <= 4096 && v.iter().all(|x| x.is_finite());
            if !(fits(&snapshot.wave) && fits(&snapshot.spectrum)) {
                return Err("an audio snapshot must have at most 4096 finite values of each kind".into());
            }
            ControlEvent::Audio(snapshot.clone())
        }
        // Targets and values are checked where the show applies the lane, as a file's are.
        ControlEvent::Lane(lane) => ControlEvent::Lane(lane.clone()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_recorded_write_reads_as_recordings_always_have() {
        let event = ControlEvent::Write(NamedWrite {
            node: "glow".into(),
            param: "intensity".into(),
            component: None,
            value: RawValue::Number(0.5),
            source: Source::Osc,
        });
        let line = ron_options().to_string(&Recorded { frame: 3, event: event.clone() }).unwrap();
        assert_eq!(line, r#"(frame:3,event:Write(node:"glow",param:"intensity",component:None,value:0.5,source:Osc))"#);
        let back: Recorded = ron_options().from_str(&line).unwrap();
        assert_eq!(back, Recorded { frame: 3, event });
        let show: Recorded = ron_options().from_str("(frame: 1, event: Show(CueGo))").unwrap();
        assert_eq!(show.event, ControlEvent::Show(crate::params::ShowCommand::CueGo));
    }
}
