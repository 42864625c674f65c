//! The parameter address space: where a parameter is (node and parameter index, what control
//! events carry), what a live source asks of the running scene, and how positions carry over a
//! hot reload by stable identity (node id and parameter name), so nothing held across a reload —
//! queued events, a recording, MIDI learn, a replay script — ever points at the wrong parameter
//! or past the end.

use super::{ParamSet, ParamValue, ParamWrite};

/// A parameter, or one float component of it, of a scene node.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Target {
    /// Node index.
    pub node: usize,
    /// Parameter index in the node.
    pub param: usize,
    /// Component (`t.x` → 0), if any.
    pub component: Option<usize>,
}

/// Values for (node, param) pairs: a preset, or a morph's destination.
pub type NodeValues = Vec<(usize, usize, ParamValue)>;

/// How a [`ControlEvent`] names parameters and values: by index and typed, as the running scene
/// applies them ([`Indexed`], the default), or by name and raw, as a recording stores them so it
/// survives edits of the scene (`control::record::Named`). One event type, two addressings.
pub trait Addressing {
    /// A parameter write.
    type Write: Clone + std::fmt::Debug + PartialEq;
    /// A morph's destination values.
    type Values: Clone + std::fmt::Debug + PartialEq;
}

/// Parameters by node and parameter index, values typed: what the running scene applies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Indexed;

impl Addressing for Indexed {
    type Write = ParamWrite;
    type Values = NodeValues;
}

/// Something a controller, the UI or a replay asks of the running scene.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(bound(
    serialize = "A::Write: serde::Serialize, A::Values: serde::Serialize",
    deserialize = "A::Write: serde::Deserialize<'de>, A::Values: serde::Deserialize<'de>"
))]
pub enum ControlEvent<A: Addressing = Indexed> {
    /// Set one parameter (or component).
    Write(A::Write),
    /// Move to these values over `seconds` (0: at once) — a preset recall.
    Morph {
        /// (node, param, value).
        values: A::Values,
        /// Morph duration.
        seconds: f64,
    },
    /// Give every parameter a live source took over back to its track.
    ResumeTracks,
    /// Set the show's tempo (tap, OSC, MIDI clock); `resync` puts the beat on this step.
    Tempo {
        /// Beats per minute.
        bpm: f64,
        /// Snap the beat position to the nearest whole beat.
        resync: bool,
    },
    /// Move the show's beat position to `phase` within a bar of `quantum` beats, by the shortest
    /// way (Ableton Link's shared phase).
    Phase {
        /// The beat within the bar, 0 up to `quantum`.
        phase: f64,
        /// Beats per bar.
        quantum: f64,
    },
    /// A show command: trigger a clip or a column, move through the cue list.
    Show(ShowCommand),
    /// What the audio analysis heard this frame, for nodes that sample sound as a texture.
    Audio(AudioSnapshot),
    /// A show's timeline lane set to these keys (the panel's lane view, a recorded fader move).
    Lane(LaneKeys),
}

/// A timeline lane as the lane view leaves it: named by its target and with values as a show
/// file writes them, so one event serves the running show, a recording and the saved file.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LaneKeys {
    /// The parameter, as a lane's `target` is written (`layer/1.opacity`, `<clip>/<node>.<param>.x`).
    pub target: String,
    /// (seconds, or beats, value) pairs; none removes the lane.
    pub keys: Vec<(f32, super::RawValue)>,
    /// Between keys.
    pub interpolation: super::Interpolation,
    /// After the last key.
    pub repeat: super::LoopMode,
    /// Whether key times are beats of the show's tempo.
    pub beats: bool,
}

/// A frame of sound as shaders sample it (ISF `audio` and `audioFFT` inputs).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AudioSnapshot {
    /// The newest samples, −1 to 1, oldest first.
    pub wave: Vec<f32>,
    /// The spectrum in linear-frequency bins from 0 Hz to half the sample rate, 0 (−60 dBFS or
    /// less) to 1 (0 dBFS).
    pub spectrum: Vec<f32>,
}

/// What a performer asks of a show's clips and cues. Layers, clips, columns and cues are
/// numbered from 0 here (from 1 in OSC addresses and on the panel).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum ShowCommand {
    /// Start clip `clip` on layer `layer` through its transition (`None`: empty the layer).
    Trigger {
        /// The layer.
        layer: usize,
        /// The clip within the layer.
        clip: Option<usize>,
    },
    /// Trigger clip `n` on every layer that has one (a Resolume column).
    Column(usize),
    /// The next cue (the first, before any).
    CueGo,
    /// The previous cue.
    CueBack,
    /// Cue `n`.
    CueGoto(usize),
    /// Edit the effect chain of layer `layer` (`None`: the master's); see [`EffectEdit`].
    Effect {
        /// The layer, or the master.
        layer: Option<usize>,
        /// What changes.
        edit: EffectEdit,
    },
}

/// A change to an effect chain's structure (its effects' switches and values are parameters).
/// Effects are numbered from 0 here (from 1 in OSC addresses and on the panel).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum EffectEdit {
    /// Append an effect: an ISF filter file or a technique that takes one image.
    Add(super::Text),
    /// Remove effect `n`.
    Remove(usize),
    /// Move effect `from` to place `to`.
    Move {
        /// Where it is.
        from: usize,
        /// Where it goes.
        to: usize,
    },
}

impl ControlEvent {
    /// This event for the reloaded scene `remap` leads to: positions moved to where the same
    /// node id and parameter name now are; writes to parameters that are gone are dropped (None),
    /// a morph keeps the values that still have a place.
    pub fn remapped(&self, remap: &Remap) -> Option<ControlEvent> {
        match self {
            ControlEvent::Write(w) => {
                let (node, param) = remap.param(w.node, w.param)?;
                Some(ControlEvent::Write(ParamWrite { node, param, ..*w }))
            }
            ControlEvent::Morph { values, seconds } => Some(ControlEvent::Morph {
                values: values.iter().filter_map(|&(n, p, v)| remap.param(n, p).map(|(n, p)| (n, p, v))).collect(),
                seconds: *seconds,
            }),
            ControlEvent::ResumeTracks => Some(ControlEvent::ResumeTracks),
            ControlEvent::Tempo { .. }
            | ControlEvent::Phase { .. }
            | ControlEvent::Show(_)
            | ControlEvent::Audio(_)
            | ControlEvent::Lane(_) => Some(self.clone()),
        }
    }
}

/// How the parameter positions of one version of a scene map onto the next (a hot reload): by
/// node id and parameter name, and only where the parameter kept its type.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Remap {
    /// Old node → old parameter → new (node, parameter), if it still exists.
    map: Vec<Vec<Option<(usize, usize)>>>,
}

impl Remap {
    /// The map from `old` nodes to `new` nodes, each given as (node id, its parameters).
    pub fn between<'a>(
        old: impl IntoIterator<Item = (&'a str, &'a ParamSet)>,
        new: impl IntoIterator<Item = (&'a str, &'a ParamSet)> + Clone,
    ) -> Self {
        let map = old
            .into_iter()
            .map(|(id, params)| {
                let moved = new.clone().into_iter().enumerate().find(|(_, (new_id, _))| *new_id == id);
                params
                    .decls()
                    .iter()
                    .map(|decl| {
                        let (n, (_, new_params)) = moved?;
                        let p = new_params.index(&decl.name)?;
                        (new_params.decls()[p].ty() == decl.ty()).then_some((n, p))
                    })
                    .collect()
            })
            .collect();
        Self { map }
    }

    /// Where parameter `param` of old node `node` is now, if anywhere.
    pub fn param(&self, node: usize, param: usize) -> Option<(usize, usize)> {
        *self.map.get(node)?.get(param)?
    }

    /// This map followed by `next` (two scene changes in a row, as one).
    #[must_use]
    pub fn then(&self, next: &Remap) -> Remap {
        let map = self
            .map
            .iter()
            .map(|params| params.iter().map(|to| to.and_then(|(n, p)| next.param(n, p))).collect())
            .collect();
        Remap { map }
    }

    /// Where an old target is now, if anywhere (components keep their index).
    pub fn target(&self, t: Target) -> Option<Target> {
        self.param(t.node, t.param).map(|(node, param)| Target { node, param, component: t.component })
    }

    /// Remaps `events` in order, dropping those whose parameter is gone; returns how many were
    /// dropped (for one logged notice).
    pub fn events(&self, events: &mut Vec<ControlEvent>) -> usize {
        let before = events.len();
        *events = events.iter().filter_map(|e| e.remapped(self)).collect();
        before - events.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::{ParamDecl, Source};

    fn set(names: &[&str]) -> ParamSet {
        ParamSet::new(names.iter().map(|n| ParamDecl::new(n, ParamValue::Float(0.0), None, "")).collect())
    }

    #[test]
    fn positions_follow_ids_and_names_and_vanished_ones_drop() {
        let (a, b) = (set(&["x", "y"]), set(&["z"]));
        let (b2, a2) = (set(&["z"]), set(&["y", "w"]));
        // Old: [a, b]; new: [b, a] with a's "x" gone and "y" moved to index 0.
        let remap = Remap::between([("a", &a), ("b", &b)], [("b", &b2), ("a", &a2)]);
        assert_eq!(remap.param(0, 0), None);
        assert_eq!(remap.param(0, 1), Some((1, 0)));
        assert_eq!(remap.param(1, 0), Some((0, 0)));
        assert_eq!(remap.param(5, 0), None, "out of range is gone, never a panic");
        let write = |node, param| {
            ControlEvent::Write(ParamWrite {
                node,
                param,
                component: None,
                value: ParamValue::Float(1.0),
                source: Source::Ui,
            })
        };
        let mut events = vec![write(0, 0), write(0, 1), ControlEvent::ResumeTracks, write(7, 7)];
        assert_eq!(remap.events(&mut events), 2);
        assert_eq!(events, [write(1, 0), ControlEvent::ResumeTracks]);
    }

    #[test]
    fn a_parameter_that_changed_type_is_not_carried_over() {
        let old = set(&["x"]);
        let new = ParamSet::new(vec![ParamDecl::new("x", ParamValue::Int(0), None, "")]);
        assert_eq!(Remap::between([("n", &old)], [("n", &new)]).param(0, 0), None);
    }
}
