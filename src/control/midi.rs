//! MIDI input: raw bytes (from midir, or a test) → events (CC 7- and 14-bit, notes, clock,
//! start/stop, program change) → parameter writes through the scene's mappings and the
//! performer's learned ones. No MIDI system (no `/dev/snd/seq`) is a logged fact, not an error.

use std::collections::VecDeque;
use std::path::PathBuf;

use super::midi_commands::{CommandBinding, command_address, note_mapping, parse_command_address, show_clip_notes};
use crate::params::{ParamDecl, ParamType, ParamValue, ParamWrite, ShowCommand, Source, Target};
use crate::scene::{MidiCurve, MidiMapping, Scene, resolve_target, ron_options};

/// One decoded MIDI message. Channels are 1–16.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MidiEvent {
    /// Control change.
    Cc {
        /// Channel 1–16.
        channel: u8,
        /// Controller 0–127.
        controller: u8,
        /// Value 0–127.
        value: u8,
    },
    /// Note on with velocity > 0.
    NoteOn {
        /// Channel 1–16.
        channel: u8,
        /// Note 0–127.
        note: u8,
        /// Velocity 1–127.
        velocity: u8,
    },
    /// Note off (or note on with velocity 0).
    NoteOff {
        /// Channel 1–16.
        channel: u8,
        /// Note 0–127.
        note: u8,
    },
    /// Program change (recalls the preset with that index).
    Program {
        /// Channel 1–16.
        channel: u8,
        /// Program 0–127.
        program: u8,
    },
    /// Timing clock, 24 per quarter note.
    Clock,
    /// Start.
    Start,
    /// Continue.
    Continue,
    /// Stop.
    Stop,
}

/// Turns a byte stream into events: running status, real-time bytes anywhere, SysEx skipped.
#[derive(Debug, Default)]
pub struct MidiParser {
    status: Option<u8>,
    data: Vec<u8>,
    in_sysex: bool,
}

impl MidiParser {
    /// Feeds bytes; returns the complete events they finish.
    pub fn feed(&mut self, bytes: &[u8]) -> Vec<MidiEvent> {
        let mut out = Vec::new();
        for &b in bytes {
            match b {
                0xF8 => out.push(MidiEvent::Clock),
                0xFA => out.push(MidiEvent::Start),
                0xFB => out.push(MidiEvent::Continue),
                0xFC => out.push(MidiEvent::Stop),
                0xF9 | 0xFD..=0xFF => {}
                0xF0 => self.in_sysex = true,
                0xF7 => self.in_sysex = false,
                0xF1..=0xF6 => {
                    // System common: cancels running status; its data bytes are ignored.
                    self.status = None;
                    self.data.clear();
                }
                0x80..=0xEF => {
                    self.in_sysex = false;
                    self.status = Some(b);
                    self.data.clear();
                }
                _ if self.in_sysex => {}
                data => {
                    let Some(status) = self.status else { continue };
                    self.data.push(data);
                    let needed = if matches!(status & 0xF0, 0xC0 | 0xD0) { 1 } else { 2 };
                    if self.data.len() == needed {
                        if let Some(e) = Self::event(status, &self.data) {
                            out.push(e);
                        }
                        self.data.clear();
                    }
                }
            }
        }
        out
    }

    fn event(status: u8, d: &[u8]) -> Option<MidiEvent> {
        let channel = (status & 0x0F) + 1;
        Some(match status & 0xF0 {
            0x80 => MidiEvent::NoteOff { channel, note: d[0] },
            0x90 if d[1] == 0 => MidiEvent::NoteOff { channel, note: d[0] },
            0x90 => MidiEvent::NoteOn { channel, note: d[0], velocity: d[1] },
            0xB0 => MidiEvent::Cc { channel, controller: d[0], value: d[1] },
            0xC0 => MidiEvent::Program { channel, program: d[0] },
            _ => return None,
        })
    }
}

/// GO or back, when a note-on is the show's cue note (any channel) and the show has cues.
pub fn cue_commands(event: MidiEvent, scene: &Scene) -> Vec<crate::params::ShowCommand> {
    use crate::params::ShowCommand;
    let (MidiEvent::NoteOn { note, .. }, Some(show)) = (event, &scene.show) else { return Vec::new() };
    let cues = !show.cues.is_empty();
    let go = (cues && show.cue_notes.go == Some(note)).then_some(ShowCommand::CueGo);
    let back = (cues && show.cue_notes.back == Some(note)).then_some(ShowCommand::CueBack);
    go.into_iter().chain(back).collect()
}

/// Tempo from MIDI clock (24 pulses per quarter note) and transport state.
#[derive(Debug, Default)]
pub struct MidiClock {
    pulses: VecDeque<f64>,
    /// Whether Start/Continue was seen more recently than Stop.
    pub playing: bool,
}

impl MidiClock {
    /// Records a clock pulse at `seconds`.
    pub fn pulse(&mut self, seconds: f64) {
        self.pulses.push_back(seconds);
        if self.pulses.len() > 49 {
            self.pulses.pop_front();
        }
    }

    /// Beats per minute over the last two beats, if enough pulses arrived.
    pub fn bpm(&self) -> Option<f64> {
        let (first, last) = (self.pulses.front()?, self.pulses.back()?);
        let intervals = self.pulses.len().checked_sub(1).filter(|&n| n >= 6)? as f64;
        let per_pulse = (last - first) / intervals;
        (per_pulse > 0.0).then(|| 60.0 / (per_pulse * 24.0))
    }
}

/// A mapping made live: which control, which parameter, how values scale.
#[derive(Clone, Debug, PartialEq)]
pub struct Binding {
    /// As written in the scene or the learn file.
    pub mapping: MidiMapping,
    /// The resolved parameter.
    pub target: Target,
}

/// Maps events to writes; pairs 14-bit controllers; learns new bindings.
#[derive(Debug, Default)]
pub struct MidiMapper {
    bindings: Vec<Binding>,
    /// Notes bound to show commands: clip triggers, effect chain edits.
    commands: Vec<CommandBinding>,
    /// The show command waiting for a note (MIDI learn).
    pub learning_command: Option<ShowCommand>,
    /// Last MSB per (channel, controller 0–31), for 14-bit pairs.
    msb: [[u8; 32]; 16],
    /// The parameter waiting for a control to be moved (MIDI learn).
    pub learning: Option<Target>,
    /// Tempo and transport.
    pub clock: MidiClock,
}

impl MidiMapper {
    /// The scene's mappings plus `learned` ones (those whose target no longer exists are dropped).
    pub fn new(scene: &Scene, learned: &[MidiMapping]) -> Self {
        let mut bindings: Vec<Binding> =
            scene.midi.iter().map(|(mapping, target)| Binding { mapping: mapping.clone(), target: *target }).collect();
        let mut commands = show_clip_notes(scene);
        for m in learned {
            if let Some(command) = parse_command_address(&m.target, scene).filter(|_| m.note.is_some()) {
                // A learned note replaces the show file's for that clip.
                commands.retain(|b| b.command != command);
                commands.push(CommandBinding { mapping: m.clone(), learned: true, command });
            } else if let Ok(target) = resolve_target(&scene.nodes, &m.target) {
                bindings.push(Binding { mapping: m.clone(), target });
            }
        }
        Self { bindings, commands, ..Default::default() }
    }

    /// Whether a parameter or a show command waits for a control to be moved.
    pub fn is_learning(&self) -> bool {
        self.learning.is_some() || self.learning_command.is_some()
    }

    /// The notes bound to show commands.
    pub fn command_bindings(&self) -> &[CommandBinding] {
        &self.commands
    }

    /// The panel's mark of `command`'s note (ASCII: egui's bundled fonts lack dot glyphs): " ?"
    /// while it waits for one, " M" once it has one.
    pub fn learn_mark(&self, command: ShowCommand) -> &'static str {
        if self.learning_command == Some(command) {
            " ?"
        } else if self.commands.iter().any(|b| b.command == command) {
            " M"
        } else {
            ""
        }
    }

    /// The show commands whose note `event` is.
    pub fn note_commands(&self, event: MidiEvent) -> Vec<ShowCommand> {
        let MidiEvent::NoteOn { channel, note, .. } = event else { return Vec::new() };
        self.commands
            .iter()
            .filter(|b| b.mapping.note == Some(note) && b.mapping.channel.is_none_or(|c| c == channel))
            .map(|b| b.command)
            .collect()
    }

    /// Every binding.
    pub fn bindings(&self) -> &[Binding] {
        &self.bindings
    }

    /// Whether parameter `param` of `node` has a MIDI binding.
    pub fn is_mapped(&self, node: usize, param: usize) -> bool {
        self.bindings.iter().any(|b| b.target.node == node && b.target.param == param)
    }

    /// Removes every binding of a parameter (unlearn).
    pub fn unlearn(&mut self, node: usize, param: usize) {
        self.bindings.retain(|b| !(b.target.node == node && b.target.param == param));
    }

    /// Handles one event at clock time `seconds`: learns if waiting, returns the writes it makes
    /// and a program number if one was selected.
    pub fn handle(&mut self, event: MidiEvent, scene: &Scene, seconds: f64) -> (Vec<ParamWrite>, Option<u8>) {
        match event {
            MidiEvent::Clock => self.clock.pulse(seconds),
            MidiEvent::Start | MidiEvent::Continue => self.clock.playing = true,
            MidiEvent::Stop => self.clock.playing = false,
            MidiEvent::Program { program, .. } => return (Vec::new(), Some(program)),
            _ => {}
        }
        if let (Some(command), MidiEvent::NoteOn { channel, note, .. }) = (self.learning_command, event) {
            self.learning_command = None;
            self.commands.retain(|b| b.command != command);
            if let Some(target) = command_address(&command) {
                log::info!("MIDI learn: note {note} on channel {channel} → {target}");
                let mapping = note_mapping(Some(channel), note, target);
                self.commands.push(CommandBinding { mapping, learned: true, command });
            }
            return (Vec::new(), None);
        }
        if let Some(target) = self.learning {
            if let Some(mapping) = learned_mapping(event, target, scene) {
                self.learning = None;
                self.unlearn(target.node, target.param);
                log::info!("MIDI learn: {:?} → {}", event, mapping.target);
                self.bindings.push(Binding { mapping, target });
            }
            return (Vec::new(), None);
        }
        let mut writes = Vec::new();
        for b in &self.bindings {
            if let Some(value) = self.value_for(b, event, scene) {
                let t = b.target;
                writes.push(ParamWrite {
                    node: t.node,
                    param: t.param,
                    component: t.component,
                    value,
                    source: Source::Midi,
                });
            }
        }
        if let MidiEvent::Cc { channel, controller, value } = event
            && controller < 32
        {
            self.msb[usize::from(channel - 1)][usize::from(controller)] = value;
        }
        (writes, None)
    }

    /// The value binding `b` gives for `event`, if the event is its control.
    fn value_for(&self, b: &Binding, event: MidiEvent, scene: &Scene) -> Option<ParamValue> {
        let m = &b.mapping;
        let on_channel = |c: u8| m.channel.is_none_or(|want| want == c);
        let decl = scene.nodes.get(b.target.node)?.params.decls().get(b.target.param)?;
        let position = match event {
            MidiEvent::Cc { channel, controller, value } if on_channel(channel) => match m.cc? {
                cc if m.fine && controller == cc => f32::from(value) * 128.0 / 16383.0,
                cc if m.fine && controller == cc + 32 => {
                    // Validated at load (fine needs cc < 32); a bad mapping reads no MSB.
                    let msb = *self.msb[usize::from(channel - 1)].get(usize::from(cc))?;
                    (f32::from(msb) * 128.0 + f32::from(value)) / 16383.0
                }
                cc if !m.fine && controller == cc => f32::from(value) / 127.0,
                _ => return None,
            },
            MidiEvent::NoteOn { channel, note, velocity } if on_channel(channel) && m.note == Some(note) => {
                f32::from(velocity) / 127.0
            }
            MidiEvent::NoteOff { channel, note } if on_channel(channel) && m.note == Some(note) => {
                // A note off releases gates (bools); it does not move numbers or fire triggers.
                return (decl.ty() == ParamType::Bool && b.target.component.is_none())
                    .then_some(ParamValue::Bool(false));
            }
            _ => return None,
        };
        Some(scale(position, m, decl, b.target.component.is_some(), event))
    }
}

/// A 0–1 control position as a value of `decl` through a mapping's range, curve and inversion.
fn scale(position: f32, m: &MidiMapping, decl: &ParamDecl, component: bool, event: MidiEvent) -> ParamValue {
    let pos = if m.invert { 1.0 - position } else { position }.clamp(0.0, 1.0);
    let (lo, hi) = m.range.or(decl.range).unwrap_or((0.0, 1.0));
    let x = match m.curve {
        MidiCurve::Linear => lo + pos * (hi - lo),
        MidiCurve::Exponential if lo > 0.0 && hi > 0.0 => lo * (hi / lo).powf(pos),
        MidiCurve::Exponential => lo + pos * pos * (hi - lo),
    };
    if component {
        return ParamValue::Float(x);
    }
    match decl.ty() {
        ParamType::Trigger => ParamValue::Trigger(matches!(event, MidiEvent::NoteOn { .. }) || pos >= 0.5),
        ParamType::Bool => ParamValue::Bool(matches!(event, MidiEvent::NoteOn { .. }) || pos >= 0.5),
        ParamType::Enum => ParamValue::Enum((pos * decl.options.len().saturating_sub(1) as f32).round() as u32),
        ty => ParamValue::from_components(ty, &vec![x; ty.components()]),
    }
}

/// The mapping a moved control creates for `target` in learn mode.
fn learned_mapping(event: MidiEvent, target: Target, scene: &Scene) -> Option<MidiMapping> {
    let node = scene.nodes.get(target.node)?;
    let mut name = format!("{}.{}", node.id, node.params.decls().get(target.param)?.name);
    if let Some(c) = target.component {
        name.push('.');
        name.push(['x', 'y', 'z', 'w'][c]);
    }
    let base = MidiMapping {
        channel: None,
        cc: None,
        note: None,
        target: name,
        range: None,
        curve: MidiCurve::Linear,
        invert: false,
        fine: false,
    };
    match event {
        // LSB controllers (32–63) are learned as their MSB's 7-bit control.
        MidiEvent::Cc { channel, controller, .. } => Some(MidiMapping {
            channel: Some(channel),
            cc: Some(if (32..64).contains(&controller) { controller - 32 } else { controller }),
            ..base
        }),
        MidiEvent::NoteOn { channel, note, .. } => {
            Some(MidiMapping { channel: Some(channel), note: Some(note), ..base })
        }
        _ => None,
    }
}

/// Learned mappings persist here between runs: a RON list of mappings.
#[derive(Clone, Debug)]
pub struct LearnStore {
    /// The file.
    pub path: PathBuf,
}

impl LearnStore {
    /// Mappings saved earlier. The file is hand-editable, so it is validated like a scene's
    /// mappings: a file that does not parse is ignored, and a mapping that is out of range is
    /// left out, each with one logged line naming the file (see [`LearnStore::load_checked`]).
    pub fn load(&self) -> Vec<MidiMapping> {
        let (mappings, problems) = self.load_checked();
        for p in problems {
            log::warn!("{p}");
        }
        mappings
    }

    /// The valid mappings of the file, and one sentence for each thing left out.
    pub fn load_checked(&self) -> (Vec<MidiMapping>, Vec<String>) {
        let Ok(text) = std::fs::read_to_string(&self.path) else { return (Vec::new(), Vec::new()) };
        let file = self.path.display();
        let all: Vec<MidiMapping> = match ron_options().from_str(&text) {
            Ok(all) => all,
            Err(e) => {
                let (line, col) = (e.span.start.line, e.span.start.col);
                return (Vec::new(), vec![format!("ignoring MIDI learn file {file}:{line}:{col}: {}", e.code)]);
            }
        };
        let mut problems = Vec::new();
        let valid = all
            .into_iter()
            .enumerate()
            .filter(|(i, m)| match m.problem() {
                Some(p) => {
                    problems.push(format!("{file}: mapping {} (to '{}') left out: {p}", i + 1, m.target));
                    false
                }
                None => true,
            })
            .map(|(_, m)| m)
            .collect();
        (valid, problems)
    }

    /// Saves the learned (non-scene) bindings of `mapper`.
    pub fn save(&self, mapper: &MidiMapper, scene: &Scene) -> Result<(), String> {
        let learned: Vec<&MidiMapping> = mapper
            .bindings()
            .iter()
            .map(|b| &b.mapping)
            .filter(|m| !scene.midi.iter().any(|(s, _)| s == *m))
            .chain(mapper.command_bindings().iter().filter(|b| b.learned).map(|b| &b.mapping))
            .collect();
        let text = ron::ser::to_string_pretty(&learned, Default::default()).map_err(|e| e.to_string())?;
        crate::atomic_file::write(&self.path, text.as_bytes())
            .map_err(|e| format!("cannot write {}: {e}", self.path.display()))
    }
}

pub use port::MidiInput;

/// MIDI ports through midir (ALSA on Linux, CoreMIDI, WinMM).
#[cfg(feature = "midi")]
mod port {
    use std::sync::mpsc::{Receiver, sync_channel};
    use std::time::Instant;

    /// Messages held for the render thread at most; a flood past that is dropped.
    const QUEUE: usize = 4096;

    /// Connections to MIDI input ports; bytes arrive on a channel drained by the render loop,
    /// each stamped on arrival (MTC is chased by when its quarter frames came, not when a frame
    /// read them).
    pub struct MidiInput {
        _connections: Vec<midir::MidiInputConnection<()>>,
        bytes: Receiver<(Instant, Vec<u8>)>,
        /// Names of the connected ports.
        pub ports: Vec<String>,
    }

    impl MidiInput {
        /// Connects to every input port (or those whose name contains `filter`) but those
        /// `exclude` names. Without a MIDI system this returns why, to be logged once; the show
        /// goes on.
        pub fn open(filter: Option<&str>, exclude: &dyn Fn(&str) -> bool) -> Result<Self, String> {
            let probe = midir::MidiInput::new("indra")
                .map_err(|e| format!("MIDI is not available ({e}); continuing without it"))?;
            let (tx, bytes) = sync_channel(QUEUE);
            let mut connections = Vec::new();
            let mut ports = Vec::new();
            for port in probe.ports() {
                let name = probe.port_name(&port).unwrap_or_default();
                if filter.is_some_and(|f| !name.to_lowercase().contains(&f.to_lowercase())) || exclude(&name) {
                    continue;
                }
                let input = midir::MidiInput::new("indra").map_err(|e| e.to_string())?;
                let tx = tx.clone();
                let stamp = move |_, message: &[u8], _: &mut ()| drop(tx.try_send((Instant::now(), message.to_vec())));
                match input.connect(&port, "indra-in", stamp, ()) {
                    Ok(c) => {
                        log::info!("MIDI in: {name}");
                        ports.push(name);
                        connections.push(c);
                    }
                    Err(e) => log::warn!("cannot open MIDI port {name}: {e}"),
                }
            }
            if ports.is_empty() {
                log::info!("no MIDI input ports{}", filter.map(|f| format!(" matching '{f}'")).unwrap_or_default());
            }
            Ok(Self { _connections: connections, bytes, ports })
        }

        /// Every message received since the last call, with when it arrived.
        pub fn drain(&self) -> Vec<(Instant, Vec<u8>)> {
            self.bytes.try_iter().collect()
        }
    }
}

/// A binary built without the `midi` feature (no sound library linked): there are no ports,
/// and opening says so once; everything else about MIDI (mappings, learn files) still loads.
#[cfg(not(feature = "midi"))]
mod port {
    /// No MIDI input in this build.
    pub struct MidiInput {
        /// Always empty.
        pub ports: Vec<String>,
    }

    impl MidiInput {
        /// Says that this binary has no MIDI.
        pub fn open(_filter: Option<&str>, _exclude: &dyn Fn(&str) -> bool) -> Result<Self, String> {
            Err(super::NOT_BUILT_IN.into())
        }

        /// Nothing ever arrives.
        pub fn drain(&self) -> Vec<(std::time::Instant, Vec<u8>)> {
            Vec::new()
        }
    }
}

/// What a binary built without the `midi` feature says about MIDI.
pub const NOT_BUILT_IN: &str =
    "MIDI is not built into this binary (built with --no-default-features); OSC and the panel still work";

/// Whether this binary can open MIDI ports.
pub const BUILT_IN: bool = cfg!(feature = "midi");
