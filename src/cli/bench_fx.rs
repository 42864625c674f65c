//! `indra bench --fx-every`: an effect added to layer 1 and removed again, in turns, each edit
//! built ahead on a worker thread from a snapshot of the running show and applied at the first
//! frame after it is due and ready — what a live show does with an edit from the panel or OSC.

use std::sync::mpsc::Receiver;

use indra::offscreen::OffscreenRenderer;
use indra::params::{ControlEvent, EffectEdit, ShowCommand, Text};
use indra::scene::Replacement;

/// The effect's turns: the next edit, its build, and when it is due.
pub struct EffectToggle {
    effect: Text,
    /// The layer's effects before the bench's (the added one goes after them).
    place: usize,
    every: u64,
    added: bool,
    due: u64,
    building: Option<(ShowCommand, Receiver<Result<Replacement, String>>)>,
}

impl EffectToggle {
    /// Turns of `effect` on layer 1 of `renderer`'s show, one every `every` measured frames.
    pub fn new(renderer: &mut OffscreenRenderer, effect: &str, every: u64) -> Self {
        let place = renderer.instance_mut().show().and_then(|(s, _)| s.layers.first()).map_or(0, |l| l.effects.len());
        Self { effect: Text::new(effect), place, every, added: false, due: every, building: None }
    }

    /// Before measured frame `i`: starts the next edit's build, and schedules the edit when it
    /// is due and built. Returns whether this frame applies an edit.
    pub fn before_frame(&mut self, renderer: &mut OffscreenRenderer, i: u64) -> Result<bool, String> {
        let Some((command, receiver)) = &self.building else {
            let edit = if self.added { EffectEdit::Remove(self.place) } else { EffectEdit::Add(self.effect) };
            let command = ShowCommand::Effect { layer: Some(0), edit };
            let receiver = renderer.instance_mut().build_ahead(command)?;
            self.building = Some((command, receiver));
            return Ok(false);
        };
        if i < self.due {
            return Ok(false);
        }
        let Ok(built) = receiver.try_recv() else { return Ok(false) };
        let command = *command;
        self.building = None;
        renderer.instance_mut().offer_prepared(command, built?);
        let frame = renderer.next_frame();
        renderer.schedule(frame, vec![ControlEvent::Show(command)]);
        self.added = !self.added;
        self.due = i + self.every;
        Ok(true)
    }

    /// Waits for the edit being built, if any: a build still running at exit would call the
    /// driver as it unloads.
    pub fn finish(self) {
        if let Some((_, receiver)) = self.building {
            let _ = receiver.recv();
        }
    }
}
