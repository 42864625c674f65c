//! DMX in as a control source: channels of a lighting desk's universes (Art-Net or sACN,
//! received by [`crate::dmx::DmxIn`]) drive parameters as MIDI faders do — 8-bit, or a
//! coarse/fine pair for 16 bits — and trigger the clip grid. The file that says which is also
//! the "personality" the desk operator patches from (docs/lights.md).

use std::collections::BTreeMap;
use std::path::Path;

use serde::Deserialize;

use crate::dmx::{DmxIn, DmxInCounts, ListenConfig, Universes};
use crate::params::{ControlEvent, ParamType, ParamValue, ParamWrite, ShowCommand, Source, Target};
use crate::scene::Scene;

/// The largest DMX-in file read.
const MAX_FILE_BYTES: u64 = 1 << 20;
/// Universes 1 to this are listened to for learning, beside those the file maps.
const LEARN_UNIVERSES: u16 = 16;

/// A DMX-in file: where to listen and what each channel does.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DmxInFile {
    /// Where to listen and how to merge.
    pub listen: ListenConfig,
    /// Channels that drive parameters.
    #[serde(default)]
    pub map: Vec<ChannelMap>,
    /// Channels that pick a layer's clip.
    #[serde(default)]
    pub clips: Vec<ClipChannel>,
}

/// One channel (or a coarse/fine pair) → one parameter.
#[derive(Clone, Debug, Deserialize, serde::Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ChannelMap {
    /// The universe (Art-Net port-address, sACN universe).
    pub universe: u16,
    /// The channel, 1–512 (with `fine`, the coarse byte; the next channel is the fine byte).
    pub channel: u16,
    /// 16 bits: this channel and the next.
    #[serde(default)]
    pub fine: bool,
    /// The parameter: `node.param` or `node.param.x`.
    pub target: String,
    /// The values 0 and full map to (default: the parameter's range).
    #[serde(default)]
    pub range: Option<(f32, f32)>,
}

/// A channel whose value picks the clip a layer plays: 0 leaves the layer as it is, 1 plays
/// its first clip, 2 the second, …; 255 empties it. The clip starts when the value changes.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ClipChannel {
    /// The universe.
    pub universe: u16,
    /// The channel, 1–512.
    pub channel: u16,
    /// The layer, from 1 as on the panel.
    pub layer: usize,
}

impl DmxInFile {
    /// Reads and checks a DMX-in file: one sentence with its place for what is wrong.
    pub fn load(path: &Path) -> Result<Self, String> {
        let text = crate::files::read_text(path, MAX_FILE_BYTES)?;
        let origin = path.display();
        let file: Self = crate::files::parse_ron(&text, &origin.to_string())?;
        let last = |fine: bool| if fine { 511 } else { 512 };
        for m in &file.map {
            if !(1..=last(m.fine)).contains(&m.channel) {
                return Err(format!("{origin}: '{}': channel {} must be 1–{}", m.target, m.channel, last(m.fine)));
            }
        }
        if let Some(c) = file.clips.iter().find(|c| !(1..=512).contains(&c.channel) || c.layer == 0) {
            return Err(format!("{origin}: clips: channel {} must be 1–512 and layer from 1", c.channel));
        }
        Ok(file)
    }

    /// Every universe the file reads.
    pub fn universes(&self) -> Vec<u16> {
        let mut list: Vec<u16> =
            self.map.iter().map(|m| m.universe).chain(self.clips.iter().map(|c| c.universe)).collect();
        list.sort_unstable();
        list.dedup();
        list
    }
}

/// DMX in, running: the receiver and the file's mappings resolved against the scene.
pub struct DmxControl {
    input: DmxIn,
    file: DmxInFile,
    targets: Vec<Option<Target>>,
    /// The last value each mapping and clip channel acted on.
    last: BTreeMap<(u16, u16), u16>,
    /// Mappings learned from the panel, applied after the file's (so a learned one wins).
    learned: Vec<ChannelMap>,
    /// Where learned mappings are kept.
    learn_file: Option<std::path::PathBuf>,
    /// The parameter waiting for a channel to move, and its name.
    learning: Option<(Target, String)>,
    /// The universes as the last frame saw them (learn binds the first channel that moves).
    previous: Option<Universes>,
}

impl DmxControl {
    /// Starts receiving as `file` says; its mappings are resolved against `scene` (a target
    /// the scene lacks is one notice, the rest work).
    /// Mappings learned before are read from `learn_file` (where new ones are kept) and come
    /// after the file's.
    pub fn start(
        file: DmxInFile,
        learn_file: Option<std::path::PathBuf>,
        scene: &Scene,
        notices: &mut Vec<String>,
    ) -> Result<Self, String> {
        let mut learned = Vec::new();
        if let Some(path) = learn_file.as_deref().filter(|p| p.exists()) {
            let read = crate::files::read_limited(path, MAX_FILE_BYTES).map_err(|e| e.to_string()).and_then(|b| {
                crate::dmx::ron_options()
                    .from_bytes::<Vec<ChannelMap>>(&b)
                    .map_err(|e| format!("{}: {e}", path.display()))
            });
            match read {
                Ok(list) => learned = list,
                Err(e) => notices.push(format!("DMX learn: {e} (learning afresh)")),
            }
        }
        // Learning listens to every universe the desk might use; mapping needs only the file's.
        let mut universes = file.universes();
        universes.extend(learned.iter().map(|m| m.universe));
        universes.extend(1..=LEARN_UNIVERSES);
        universes.sort_unstable();
        universes.dedup();
        let input = DmxIn::start(&file.listen, &universes)?;
        // Every channel starts at 0, as the receiver's state does.
        let previous = Some(universes.iter().map(|u| (*u, [0; crate::dmx::UNIVERSE_CHANNELS])).collect());
        let mut control = Self {
            input,
            file,
            targets: Vec::new(),
            last: BTreeMap::new(),
            learned,
            learn_file,
            learning: None,
            previous,
        };
        control.set_scene(scene, notices);
        Ok(control)
    }

    /// Waits for a channel to move and binds it to `target` (named `name`, `node.param`).
    pub fn learn(&mut self, target: Target, name: String) {
        self.learning = Some((target, name));
    }

    /// The parameter waiting for a channel, if any.
    pub fn learning(&self) -> Option<Target> {
        self.learning.as_ref().map(|(t, _)| *t)
    }

    /// Whether a channel drives `target`.
    pub fn maps(&self, target: Target) -> bool {
        self.targets.contains(&Some(target))
    }

    /// Binds the first channel that moved since the last frame to the parameter learning.
    fn bind_moved(&mut self, universes: &Universes, notices: &mut Vec<String>) {
        let Some(previous) = self.previous.replace(universes.clone()) else { return };
        if self.learning.is_none() {
            return;
        }
        let moved = universes.iter().find_map(|(u, channels)| {
            let before = previous.get(u)?;
            let i = channels.iter().zip(before).position(|(a, b)| a != b)?;
            Some((*u, i as u16 + 1))
        });
        let (Some((universe, channel)), Some((_, name))) = (moved, self.learning.take()) else { return };
        self.learned.retain(|m| m.target != name);
        self.learned.push(ChannelMap { universe, channel, fine: false, target: name.clone(), range: None });
        // Resolved again before the events.
        self.targets = Vec::new();
        let message = format!("DMX learn: universe {universe} channel {channel} → {name}");
        log::info!("{message}");
        notices.push(message);
        if let Err(e) = self.save_learned() {
            notices.push(e);
        }
    }

    /// Writes the learned mappings to the learn file.
    fn save_learned(&self) -> Result<(), String> {
        let Some(path) = &self.learn_file else { return Ok(()) };
        let text = ron::ser::to_string_pretty(&self.learned, Default::default()).map_err(|e| e.to_string())?;
        crate::atomic_file::write(path, text.as_bytes()).map_err(|e| format!("cannot write {}: {e}", path.display()))
    }

    /// Resolves the mappings against a new scene.
    pub fn set_scene(&mut self, scene: &Scene, notices: &mut Vec<String>) {
        self.targets = self
            .file
            .map
            .iter()
            .chain(&self.learned)
            .map(|m| {
                crate::scene::resolve_target(&scene.nodes, &m.target)
                    .map_err(|e| notices.push(format!("DMX in: {e}")))
                    .ok()
            })
            .collect();
    }

    /// The events of every mapped channel whose value changed since the last frame (a channel
    /// that moves while a parameter learns is bound to it first).
    pub fn events(&mut self, scene: &Scene, notices: &mut Vec<String>) -> Vec<ControlEvent> {
        let Some(universes) = self.input.changed() else { return Vec::new() };
        self.bind_moved(&universes, notices);
        if self.targets.len() != self.file.map.len() + self.learned.len() {
            self.set_scene(scene, notices);
        }
        let mut events = Vec::new();
        for (m, target) in self.file.map.iter().chain(&self.learned).zip(&self.targets) {
            let Some(target) = target else { continue };
            let Some(raw) = channel_value(&universes, m.universe, m.channel, m.fine) else { continue };
            let before = self.last.insert((m.universe, m.channel), raw);
            if before == Some(raw) {
                continue;
            }
            let full = if m.fine { 65535.0 } else { 255.0 };
            let was = before.map(|b| f32::from(b) / full);
            if let Some(value) = scale(f32::from(raw) / full, was, m.range, *target, scene) {
                events.push(ControlEvent::Write(ParamWrite {
                    node: target.node,
                    param: target.param,
                    component: target.component,
                    value,
                    source: Source::Dmx,
                }));
            }
        }
        for c in &self.file.clips {
            let Some(raw) = channel_value(&universes, c.universe, c.channel, false) else { continue };
            let before = self.last.insert((c.universe, c.channel), raw);
            if before == Some(raw) || raw == 0 {
                continue;
            }
            let clip = if raw == 255 { None } else { Some(usize::from(raw) - 1) };
            events.push(ControlEvent::Show(ShowCommand::Trigger { layer: c.layer - 1, clip }));
        }
        events
    }

    /// Packets taken in, malformed and ignored.
    pub fn counts(&self) -> DmxInCounts {
        self.input.counts()
    }
}

/// A channel's value (16 bits from a coarse/fine pair).
fn channel_value(universes: &Universes, universe: u16, channel: u16, fine: bool) -> Option<u16> {
    let channels = universes.get(&universe)?;
    let i = usize::from(channel) - 1;
    Some(if fine { u16::from_be_bytes([channels[i], channels[i + 1]]) } else { u16::from(channels[i]) })
}

/// A 0–1 position as a value of the target: across the range; a trigger fires and a switch
/// turns on as the position rises through half.
fn scale(
    position: f32,
    was: Option<f32>,
    range: Option<(f32, f32)>,
    target: Target,
    scene: &Scene,
) -> Option<ParamValue> {
    let decl = scene.nodes.get(target.node)?.params.decls().get(target.param)?;
    let (lo, hi) = range.or(decl.range).unwrap_or((0.0, 1.0));
    let x = lo + position * (hi - lo);
    if target.component.is_some() {
        return Some(ParamValue::Float(x));
    }
    Some(match decl.ty() {
        ParamType::Trigger => {
            if position < 0.5 || was.is_some_and(|w| w >= 0.5) {
                return None;
            }
            ParamValue::Trigger(true)
        }
        ParamType::Bool => ParamValue::Bool(position >= 0.5),
        ParamType::Enum => ParamValue::Enum((position * decl.options.len().saturating_sub(1) as f32).round() as u32),
        ty => ParamValue::from_components(ty, &vec![x; ty.components()]),
    })
}
