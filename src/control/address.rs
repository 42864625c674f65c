//! Where an OSC address leads: a parameter (or one component of it) or an engine command.
//! Every parameter answers at `/indra/<node>/<param>`, vector components at
//! `/indra/<node>/<param>/<x|y|z|w>` (colours also `r g b a`), plus the scene's aliases.
//! An incoming address may be an OSC address pattern (`*`, `?`, `[a-z]`, `{a,b}`): it reaches
//! every parameter address it matches (rosc's matcher), never a command — `/indra/record/*` must
//! not start and stop a recording at once.

use std::collections::HashMap;

use crate::params::ParamType;
use crate::params::{ShowCommand, Target};
use crate::scene::Scene;

/// Engine commands with fixed addresses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Command {
    /// `/indra/preset/recall s [f]`: recall preset `s`, morphing over `f` seconds.
    PresetRecall,
    /// `/indra/preset/save s`: save the current values as preset `s`.
    PresetSave,
    /// `/indra/resume`: give taken-over parameters back to their tracks.
    Resume,
    /// `/indra/record/start [s]`: record the show to a video (optionally named `s`).
    RecordStart,
    /// `/indra/record/stop`: finish the recording.
    RecordStop,
    /// `/indra/tempo/bpm f`: set the tempo.
    TempoBpm,
    /// `/indra/tempo/tap`: a tap of tap tempo.
    TempoTap,
    /// `/indra/cue/goto i|s`: a show's cue by number (from 1) or name.
    CueGoto,
}

/// What an address resolves to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Route {
    /// A parameter or component.
    Param(Target),
    /// An engine command.
    Command(Command),
    /// A show's clip, column or cue command (the address holds its numbers).
    Show(ShowCommand),
    /// An edit of a layer's effect chain (`None`: the master's); the arguments say which.
    Effect(Option<usize>, EffectOp),
}

/// What an effect chain address does with its arguments.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EffectOp {
    /// `…/fx/add s`: append the effect (an ISF filter file or a technique) `s`.
    Add,
    /// `…/fx/remove i`: remove effect i (from 1).
    Remove,
    /// `…/fx/move i j`: move effect i to place j (from 1).
    Move,
    /// `…/fx/bypass i b`: bypass effect i (from 1), or not.
    Bypass,
}

impl EffectOp {
    /// Each, with the last part of its address.
    pub const ALL: [(EffectOp, &'static str); 4] =
        [(EffectOp::Add, "add"), (EffectOp::Remove, "remove"), (EffectOp::Move, "move"), (EffectOp::Bypass, "bypass")];
}

/// The address tree of one scene.
#[derive(Clone, Debug, Default)]
pub struct AddressMap {
    routes: HashMap<String, Route>,
}

impl AddressMap {
    /// Every default address of `scene`, its aliases and the engine commands.
    pub fn new(scene: &Scene) -> Self {
        let mut routes = HashMap::new();
        for (n, node) in scene.nodes.iter().enumerate() {
            for (p, decl) in node.params.decls().iter().enumerate() {
                let base = param_address(&node.id, &decl.name);
                routes.insert(base.clone(), Route::Param(Target { node: n, param: p, component: None }));
                let names: &[&str] = match decl.ty() {
                    ParamType::Color => &["r", "g", "b", "a"],
                    ty if ty.components() > 1 => &["x", "y", "z", "w"],
                    _ => &[],
                };
                for (c, name) in names.iter().enumerate().take(decl.ty().components()) {
                    routes.insert(
                        format!("{base}/{name}"),
                        Route::Param(Target { node: n, param: p, component: Some(c) }),
                    );
                }
            }
        }
        for (address, target) in &scene.osc_aliases {
            routes.insert(address.clone(), Route::Param(*target));
        }
        routes.insert("/indra/preset/recall".into(), Route::Command(Command::PresetRecall));
        routes.insert("/indra/preset/save".into(), Route::Command(Command::PresetSave));
        routes.insert("/indra/resume".into(), Route::Command(Command::Resume));
        routes.insert("/indra/record/start".into(), Route::Command(Command::RecordStart));
        routes.insert("/indra/record/stop".into(), Route::Command(Command::RecordStop));
        routes.insert("/indra/tempo/bpm".into(), Route::Command(Command::TempoBpm));
        routes.insert("/indra/tempo/tap".into(), Route::Command(Command::TempoTap));
        if let Some(show) = &scene.show {
            for (l, layer) in show.layers.iter().enumerate() {
                for c in 0..layer.clips.len() {
                    let trigger = ShowCommand::Trigger { layer: l, clip: Some(c) };
                    routes.insert(format!("/indra/layer/{}/clip/{}/connect", l + 1, c + 1), Route::Show(trigger));
                }
                let clear = ShowCommand::Trigger { layer: l, clip: None };
                routes.insert(format!("/indra/layer/{}/clear", l + 1), Route::Show(clear));
            }
            let chains = (0..show.layers.len()).map(|l| (Some(l), format!("layer/{}", l + 1)));
            for (layer, owner) in chains.chain([(None, "master".to_string())]) {
                for (op, name) in EffectOp::ALL {
                    routes.insert(format!("/indra/{owner}/fx/{name}"), Route::Effect(layer, op));
                }
            }
            for c in 0..show.columns.len() {
                routes.insert(format!("/indra/column/{}/connect", c + 1), Route::Show(ShowCommand::Column(c)));
            }
            if !show.cues.is_empty() {
                routes.insert("/indra/cue/go".into(), Route::Show(ShowCommand::CueGo));
                routes.insert("/indra/cue/back".into(), Route::Show(ShowCommand::CueBack));
                routes.insert("/indra/cue/goto".into(), Route::Command(Command::CueGoto));
            }
        }
        Self { routes }
    }

    /// The route of `address`, if any.
    pub fn route(&self, address: &str) -> Option<Route> {
        self.routes.get(address).copied()
    }

    /// Every parameter (or component) whose address matches OSC address pattern `pattern`, in
    /// address order (so the writes, and a recording of them, are the same every time).
    pub fn route_pattern(&self, pattern: &str) -> Result<Vec<Target>, String> {
        check_pattern_cost(pattern)?;
        let matcher = rosc::address::Matcher::new(pattern).map_err(|e| format!("{pattern}: {e}"))?;
        let mut matched: Vec<(&String, Target)> = self
            .routes
            .iter()
            .filter_map(|(address, route)| match route {
                Route::Param(t) => Some((address, *t)),
                Route::Command(_) | Route::Show(_) | Route::Effect(..) => None,
            })
            .filter(|(address, _)| {
                rosc::address::OscAddress::new((*address).clone()).is_ok_and(|a| matcher.match_address(&a))
            })
            .collect();
        matched.sort_by(|a, b| a.0.cmp(b.0));
        let mut targets: Vec<Target> = matched.into_iter().map(|(_, t)| t).collect();
        // An alias and the default address of one parameter are one write.
        let mut seen = std::collections::HashSet::new();
        targets.retain(|t| seen.insert(*t));
        Ok(targets)
    }

    /// Number of addresses.
    pub fn len(&self) -> usize {
        self.routes.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.routes.is_empty()
    }
}

/// The longest address pattern matched (indra's addresses are far shorter).
pub const MAX_PATTERN_LEN: usize = 256;
/// The most alternatives (`{a,b,…}` items and `[…]` sets) in one pattern.
pub const MAX_PATTERN_ALTERNATIVES: usize = 64;
/// The most `*` wildcards in one pattern (each can make the matcher backtrack).
pub const MAX_PATTERN_STARS: usize = 8;

/// Refuses a pattern whose matching could cost more than a frame can spare: measured, 11,000
/// alternatives after a `*` at 300 packets a second took 2.5 frames of matching a frame.
fn check_pattern_cost(pattern: &str) -> Result<(), String> {
    let alternatives = pattern.matches([',', '{', '[']).count();
    let stars = pattern.matches('*').count();
    if pattern.len() > MAX_PATTERN_LEN {
        return Err(format!("a pattern of {} bytes; at most {MAX_PATTERN_LEN}", pattern.len()));
    }
    if alternatives > MAX_PATTERN_ALTERNATIVES {
        return Err(format!("a pattern with {alternatives} alternatives; at most {MAX_PATTERN_ALTERNATIVES}"));
    }
    if stars > MAX_PATTERN_STARS {
        return Err(format!("a pattern with {stars} wildcards; at most {MAX_PATTERN_STARS}"));
    }
    Ok(())
}

/// Whether `address` is an OSC address pattern rather than a plain address.
pub fn is_pattern(address: &str) -> bool {
    address.contains(['*', '?', '[', ']', '{', '}'])
}

/// `/indra/<node>/<param>`.
pub fn param_address(node: &str, param: &str) -> String {
    format!("/indra/{node}/{param}")
}
