//! A running scene's part of a checkpoint: the control layer's state — every parameter as set
//! and as smoothed, which parameters a live source took from their tracks, a running preset
//! morph, the tempo clock, a show's play state — in one section, and each node's own state
//! (`Technique::save_state`) in sections of its own. Tracks and LFOs are functions of the clock,
//! so the clock (the checkpoint's frame) is their whole state.

use super::SceneInstance;
use crate::checkpoint::{Checkpoint, CheckpointError, NodeState};
use crate::gpu::Gpu;
use crate::params::{Morph, NodeValues, ParamValue, TempoClock};
use crate::scene::show::ShowState;
use crate::time::FrameTime;

/// The section that holds [`ControlState`].
const CONTROL: &str = "control";

/// The control layer's state between two steps.
#[derive(serde::Serialize, serde::Deserialize)]
struct ControlState {
    /// Per node: each parameter's target, then its smoothed value.
    params: Vec<(Vec<ParamValue>, Vec<ParamValue>)>,
    animate: bool,
    overridden: Vec<(usize, usize)>,
    morph: Option<Morph>,
    pending_morph: Option<(NodeValues, f64)>,
    tempo: TempoClock,
    show: Option<ShowState>,
}

/// The section prefix of node `i` (its name too, so a checkpoint reads as what it holds).
fn owner(i: usize, name: &str) -> String {
    format!("node/{i}/{name}")
}

impl SceneInstance {
    /// The checkpoint sections of the state between two steps. The GPU must be idle with every
    /// step's work recorded (as after a seek).
    pub fn save_state(&self, gpu: &Gpu) -> Result<Vec<(String, Vec<u8>)>, CheckpointError> {
        let control = ControlState {
            params: self.params.iter().map(|p| (p.parts().0.to_vec(), p.parts().1.to_vec())).collect(),
            animate: self.animate,
            overridden: self.overridden.iter().copied().collect(),
            morph: self.morph.clone(),
            pending_morph: self.pending_morph.clone(),
            tempo: self.tempo,
            show: self.show.as_ref().map(|s| s.state().clone()),
        };
        let text = ron::to_string(&control).map_err(|e| CheckpointError::Section {
            section: CONTROL.into(),
            why: format!("could not be written: {e}"),
        })?;
        let mut sections = vec![(CONTROL.to_string(), text.into_bytes())];
        for (i, node) in self.nodes.iter().enumerate() {
            let mut state = NodeState::new(&owner(i, &self.scene.nodes[i].id));
            node.save_state(gpu, &mut state)?;
            sections.extend(state.into_sections());
        }
        Ok(sections)
    }

    /// Takes the state of `checkpoint` into this instance, just made for the same scene; `last`
    /// is the time of the checkpoint's last step. Nothing of a refused section is half taken:
    /// the caller drops the instance on an error.
    pub fn load_state(&mut self, gpu: &Gpu, checkpoint: &Checkpoint, last: &FrameTime) -> Result<(), CheckpointError> {
        let bad = |why: String| CheckpointError::Section { section: CONTROL.into(), why };
        let text = checkpoint.section(CONTROL).ok_or_else(|| bad("missing".into()))?;
        let text = std::str::from_utf8(text).map_err(|_| bad("is not text".into()))?;
        let control: ControlState = ron::from_str(text).map_err(|e| bad(format!("does not parse: {e}")))?;
        if control.params.len() != self.params.len() {
            return Err(bad(format!("has {} nodes, the scene {}", control.params.len(), self.params.len())));
        }
        for (i, (targets, values)) in control.params.iter().enumerate() {
            if !self.params[i].set_parts(targets, values) {
                return Err(bad(format!("node {i} ('{}') has other parameters", self.scene.nodes[i].id)));
            }
        }
        let slot = |&(n, p): &(usize, usize)| n < self.params.len() && p < self.params[n].decls().len();
        let fits = control.overridden.iter().all(slot)
            && control.morph.as_ref().is_none_or(|m| m.entries.iter().all(|e| slot(&(e.0, e.1))))
            && control.pending_morph.as_ref().is_none_or(|(v, _)| v.iter().all(|e| slot(&(e.0, e.1))));
        if !fits {
            return Err(bad("names a parameter the scene does not have".into()));
        }
        match (&mut self.show, control.show) {
            (Some(show), Some(state)) if state.fits(show.plan()) => show.restore_state(state),
            (None, None) => {}
            _ => return Err(bad("holds the play state of another show".into())),
        }
        self.animate = control.animate;
        self.overridden = control.overridden.into_iter().collect();
        (self.morph, self.pending_morph, self.tempo) = (control.morph, control.pending_morph, control.tempo);
        for (i, node) in self.nodes.iter_mut().enumerate() {
            let state = NodeState::from_checkpoint(&owner(i, &self.scene.nodes[i].id), checkpoint);
            let local = self.show.as_ref().map_or(Some(*last), |s| s.node_time(i, last));
            node.load_state(gpu, &self.params[i], &local.unwrap_or(*last), &state)?;
        }
        Ok(())
    }
}
