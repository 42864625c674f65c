//! OSC messages turned into what they ask for, against one scene's address map: parameter
//! writes (address patterns matched once and remembered), show commands, presets, takes and
//! tap tempo. Arguments that do not fit are counted and logged once per address.

use std::sync::atomic::Ordering;

use rosc::{OscMessage, OscType};

use super::address::{AddressMap, Command, EffectOp, Route, is_pattern};
use super::osc::{OscReceiver, describe_args};
use crate::params::{
    ControlEvent, EffectEdit, ParamDecl, ParamType, ParamValue, ParamWrite, ShowCommand, Source, Target, Text,
};
use crate::scene::Scene;
use crate::scene::show::chain_edit::{MAX_EFFECT_NAME, chain_owner};
use crate::scene::show::effects::BYPASS;

/// An OSC message turned into what it asks for.
#[derive(Clone, Debug, PartialEq)]
pub enum Routed {
    /// Apply to the scene.
    Event(ControlEvent),
    /// Save a preset under this name.
    SavePreset(String),
    /// Recall a preset, morphing over `seconds`.
    RecallPreset(String, f64),
    /// Start or stop the video recording.
    Record(RecordRequest),
    /// A tap of tap tempo (timed where it is received).
    TapTempo,
    /// Accepted, nothing to do: a trigger button's release (`connect 0`).
    Released,
}

/// Start or stop recording the show to a video file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RecordRequest {
    /// Start, into a file of this name (a bare file name) or the default one.
    Start(Option<String>),
    /// Finish the recording.
    Stop,
}

/// Distinct address patterns whose matches are remembered (a controller repeats its patterns;
/// a flood of new ones only ever costs this much memory).
const PATTERN_CACHE: usize = 256;

/// New address patterns matched per frame: each is compared with every address of the scene,
/// so a flood of distinct patterns must not stall the render loop. The rest are counted unknown.
pub const NEW_PATTERNS_PER_FRAME: usize = 64;

/// Translates messages into control events against one scene's address map.
pub struct OscRouter {
    map: AddressMap,
    /// Pattern → the parameters it matched (None: not a valid pattern).
    patterns: std::collections::HashMap<String, Option<Vec<Target>>>,
    /// New patterns matched since [`OscRouter::begin_frame`].
    new_patterns: usize,
}

impl OscRouter {
    /// A router for `scene`.
    pub fn new(scene: &Scene) -> Self {
        Self { map: AddressMap::new(scene), patterns: Default::default(), new_patterns: 0 }
    }

    /// Starts a frame's routing (resets the budget of new patterns).
    pub fn begin_frame(&mut self) {
        self.new_patterns = 0;
    }

    /// Routes one message — to every parameter it matches when its address is a pattern;
    /// rejected ones bump a counter and are logged once per kind.
    pub fn route_all(&mut self, msg: &OscMessage, scene: &Scene, rx: &OscReceiver) -> Vec<Routed> {
        if !is_pattern(&msg.addr) {
            return self.route(msg, scene, rx).into_iter().collect();
        }
        let counters = rx.counters();
        if !self.patterns.contains_key(&msg.addr) {
            if self.new_patterns >= NEW_PATTERNS_PER_FRAME {
                counters.unknown_address.fetch_add(1, Ordering::Relaxed);
                rx.log_once("pattern budget", "too many new OSC address patterns in one frame; the rest were dropped");
                return Vec::new();
            }
            self.new_patterns += 1;
            if self.patterns.len() >= PATTERN_CACHE {
                self.patterns.clear();
            }
            self.patterns.insert(msg.addr.clone(), self.map.route_pattern(&msg.addr).ok());
        }
        let targets = match self.patterns.get(&msg.addr) {
            Some(Some(targets)) if !targets.is_empty() => targets.clone(),
            _ => {
                counters.unknown_address.fetch_add(1, Ordering::Relaxed);
                rx.log_once(&format!("unknown {}", msg.addr), &format!("no parameter matches {}", msg.addr));
                return Vec::new();
            }
        };
        let routed: Vec<Routed> = targets.iter().filter_map(|t| write_for(*t, &msg.args, scene)).collect();
        count(!routed.is_empty(), msg, rx);
        routed
    }

    /// Routes one message to a plain address; rejected ones bump a counter and are logged once
    /// per kind.
    pub fn route(&self, msg: &OscMessage, scene: &Scene, rx: &OscReceiver) -> Option<Routed> {
        let counters = rx.counters();
        if msg.addr == "/indra/stats" {
            return None;
        }
        let Some(route) = self.map.route(&msg.addr) else {
            counters.unknown_address.fetch_add(1, Ordering::Relaxed);
            rx.log_once(&format!("unknown {}", msg.addr), &format!("no parameter answers to {}", msg.addr));
            return None;
        };
        let routed = match route {
            Route::Command(Command::CueGoto) => cue_goto(&msg.args, scene),
            Route::Command(command) => route_command(command, &msg.args),
            Route::Param(t) => write_for(t, &msg.args, scene),
            Route::Show(command) => show_trigger(command, &msg.args),
            Route::Effect(layer, op) => effect_edit(layer, op, &msg.args, scene),
        };
        count(routed.is_some(), msg, rx);
        routed
    }
}

/// Counts a message as applied, or as having bad arguments (logged once per address).
fn count(applied: bool, msg: &OscMessage, rx: &OscReceiver) {
    let counters = rx.counters();
    if applied {
        counters.applied.fetch_add(1, Ordering::Relaxed);
        return;
    }
    rx.log_once(
        &format!("args {}", msg.addr),
        &format!("{} does not take the arguments ({})", msg.addr, describe_args(&msg.args)),
    );
    counters.bad_arguments.fetch_add(1, Ordering::Relaxed);
}

/// The write of `args` to target `t`, if they fit its type.
fn write_for(t: Target, args: &[OscType], scene: &Scene) -> Option<Routed> {
    let decl = &scene.nodes[t.node].params.decls()[t.param];
    let value = match t.component {
        Some(_) => numbers(args).filter(|n| n.len() == 1).map(|n| ParamValue::Float(n[0] as f32)),
        None => coerce_args(args, decl),
    };
    value.map(|value| {
        let write = ParamWrite { node: t.node, param: t.param, component: t.component, value, source: Source::Osc };
        Routed::Event(ControlEvent::Write(write))
    })
}

fn route_command(command: Command, args: &[OscType]) -> Option<Routed> {
    let name = match args.first() {
        Some(OscType::String(s)) => Some(s.clone()),
        _ => None,
    };
    // Infinity or NaN in a command would pin what it starts (a morph that never ends): refused
    // like a wrong argument, as parameter values are.
    let non_finite = |a: &OscType| match a {
        OscType::Float(x) => !x.is_finite(),
        OscType::Double(x) => !x.is_finite(),
        _ => false,
    };
    if args.iter().any(non_finite) {
        return None;
    }
    let seconds = numbers(&args[args.len().min(1)..]).and_then(|n| n.first().copied()).unwrap_or(0.0);
    match command {
        Command::Resume => Some(Routed::Event(ControlEvent::ResumeTracks)),
        Command::PresetSave => name.map(Routed::SavePreset),
        Command::PresetRecall => name.map(|n| Routed::RecallPreset(n, seconds.max(0.0))),
        Command::RecordStart => Some(Routed::Record(RecordRequest::Start(name))),
        Command::RecordStop => Some(Routed::Record(RecordRequest::Stop)),
        Command::TempoBpm => numbers(args)
            .filter(|n| n.len() == 1 && n[0].is_finite())
            .map(|n| Routed::Event(ControlEvent::Tempo { bpm: n[0], resync: false })),
        Command::TempoTap => Some(Routed::TapTempo),
        // Needs the show to resolve a name: see `cue_goto`.
        Command::CueGoto => None,
    }
}

/// A show trigger: with no argument, or a true / non-zero one (a button's press); a false or
/// zero one is its release (Resolume's `connect 1` then `connect 0`).
fn show_trigger(command: ShowCommand, args: &[OscType]) -> Option<Routed> {
    let pressed = match args.first() {
        None => true,
        Some(OscType::Bool(b)) => *b,
        // An impulse (`I`): what OSCQuery clients such as Vidvox's oscqueryhtml send for a
        // leaf typed `I`.
        Some(OscType::Inf) => true,
        Some(_) => numbers(&args[..1]).is_some_and(|n| n[0] != 0.0 && n[0].is_finite()),
    };
    Some(if pressed { Routed::Event(ControlEvent::Show(command)) } else { Routed::Released })
}

/// `/indra/<layer/n|master>/fx/<op> …`: an edit of the chain (add s, remove i, move i j), or a
/// write of an effect's bypass (bypass i b); numbers from 1.
fn effect_edit(layer: Option<usize>, op: EffectOp, args: &[OscType], scene: &Scene) -> Option<Routed> {
    let place = |arg: &OscType| {
        let n = numbers(std::slice::from_ref(arg))?[0];
        (n.fract() == 0.0 && (1.0..=64.0).contains(&n)).then(|| n as usize - 1)
    };
    let edit = match (op, args) {
        (EffectOp::Add, [OscType::String(effect)]) if effect.len() <= MAX_EFFECT_NAME => {
            EffectEdit::Add(Text::new(effect))
        }
        (EffectOp::Remove, [n]) => EffectEdit::Remove(place(n)?),
        (EffectOp::Move, [from, to]) => EffectEdit::Move { from: place(from)?, to: place(to)? },
        (EffectOp::Bypass, [n, on]) => {
            let id = format!("{}/fx/{}", chain_owner(layer), place(n)? + 1);
            let node = scene.node_index(&id)?;
            let param = scene.nodes[node].params.index(BYPASS)?;
            let on = numbers(std::slice::from_ref(on)).filter(|v| v[0].is_finite())?[0] != 0.0;
            let value = ParamValue::Bool(on);
            let write = ParamWrite { node, param, component: None, value, source: Source::Osc };
            return Some(Routed::Event(ControlEvent::Write(write)));
        }
        _ => return None,
    };
    Some(Routed::Event(ControlEvent::Show(ShowCommand::Effect { layer, edit })))
}

/// `/indra/cue/goto i|s`: the cue numbered from 1 or named.
fn cue_goto(args: &[OscType], scene: &Scene) -> Option<Routed> {
    let show = scene.show.as_ref()?;
    let cue = match args {
        [OscType::String(name)] => show.cue_named(name),
        [other] => numbers(std::slice::from_ref(other))
            .map(|n| n[0])
            .filter(|n| n.fract() == 0.0 && *n >= 1.0 && *n <= show.cues.len() as f64)
            .map(|n| n as usize - 1),
        _ => None,
    }?;
    Some(Routed::Event(ControlEvent::Show(ShowCommand::CueGoto(cue))))
}

/// Numeric arguments as f64 (f, d, i, h, T/F); `None` if any is not numeric.
fn numbers(args: &[OscType]) -> Option<Vec<f64>> {
    args.iter()
        .map(|a| match a {
            OscType::Float(x) => Some(f64::from(*x)),
            OscType::Double(x) => Some(*x),
            OscType::Int(i) => Some(f64::from(*i)),
            OscType::Long(i) => Some(*i as f64),
            OscType::Bool(b) => Some(if *b { 1.0 } else { 0.0 }),
            _ => None,
        })
        .collect()
}

/// Arguments as a value of `decl`'s type: N numbers for N components (colours 3 or 4), a
/// string or index for enums, a string for text, T/F or 0/1 for bools, anything for triggers.
/// Ranges clamp later.
pub fn coerce_args(args: &[OscType], decl: &ParamDecl) -> Option<ParamValue> {
    match decl.ty() {
        ParamType::Trigger => match numbers(args) {
            Some(n) if n.len() == 1 && n[0] == 0.0 => None,
            _ => Some(ParamValue::Trigger(true)),
        },
        ParamType::Enum => match args {
            [OscType::String(name)] => decl.option_index(name).map(ParamValue::Enum),
            _ => numbers(args)
                .filter(|n| n.len() == 1 && n[0] >= 0.0 && (n[0] as usize) < decl.options.len())
                .map(|n| ParamValue::Enum(n[0] as u32)),
        },
        // Text takes one string (TouchOSC text fields); a number is written as text.
        ParamType::Text => match args {
            [OscType::String(text)] => Some(ParamValue::Text(crate::params::Text::new(text))),
            _ => numbers(args)
                .filter(|n| n.len() == 1)
                .map(|n| ParamValue::Text(crate::params::Text::new(&n[0].to_string()))),
        },
        ParamType::Bool => numbers(args).filter(|n| n.len() == 1).map(|n| ParamValue::Bool(n[0] != 0.0)),
        ParamType::Int => numbers(args).filter(|n| n.len() == 1).map(|n| ParamValue::Int(n[0].round() as i32)),
        ty => numbers(args).and_then(|n| ty.value_from(&n)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_show_trigger_is_pressed_by_nothing_true_non_zero_or_an_impulse() {
        let go = |args: &[OscType]| show_trigger(ShowCommand::CueGo, args);
        let fired = Some(Routed::Event(ControlEvent::Show(ShowCommand::CueGo)));
        for pressed in [&[][..], &[OscType::Inf], &[OscType::Bool(true)], &[OscType::Int(1)], &[OscType::Float(0.5)]] {
            assert_eq!(go(pressed), fired, "{pressed:?}");
        }
        for released in [OscType::Bool(false), OscType::Int(0), OscType::Float(f32::NAN)] {
            assert_eq!(go(std::slice::from_ref(&released)), Some(Routed::Released), "{released:?}");
        }
    }

    #[test]
    fn commands_with_infinite_or_nan_numbers_are_refused() {
        let name = OscType::String("p1".into());
        for bad in [OscType::Float(f32::INFINITY), OscType::Double(f64::NAN), OscType::Float(f32::NEG_INFINITY)] {
            assert!(route_command(Command::PresetRecall, &[name.clone(), bad.clone()]).is_none(), "{bad:?}");
            assert!(route_command(Command::TempoBpm, &[bad]).is_none());
        }
        let good = route_command(Command::PresetRecall, &[name, OscType::Float(2.0)]);
        assert!(matches!(good, Some(Routed::RecallPreset(n, s)) if n == "p1" && s == 2.0));
    }
}
