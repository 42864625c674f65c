//! Effect chain edits in a live show (add, remove, move): each is built on a worker thread from
//! a snapshot of the running show — parsing, effect files, pipelines — one at a time in the order
//! they came, and applied at the start of the frame after it is ready, so the frame an effect
//! appears in is not late. The edit is then applied (and recorded) like any control event.

use std::collections::VecDeque;
use std::sync::mpsc::{Receiver, TryRecvError};

use crate::params::{ControlEvent, ShowCommand};
use crate::scene::{Replacement, SceneInstance};

/// The most edits waiting for their build; past it an edit is dropped, told. A preset's recall
/// may change two chains of 16 effects: removals, additions and moves.
pub const MAX_QUEUED_EDITS: usize = 64;

/// The chain edits asked for and the one being built.
#[derive(Default)]
pub struct ChainEdits {
    queue: VecDeque<ShowCommand>,
    building: Option<(ShowCommand, Receiver<Result<Replacement, String>>)>,
}

impl ChainEdits {
    /// Takes the chain edits out of `events` into the queue; returns what to tell the performer.
    pub fn take_from(&mut self, events: &mut Vec<ControlEvent>) -> Vec<String> {
        let mut messages = Vec::new();
        events.retain(|event| match event {
            ControlEvent::Show(command @ ShowCommand::Effect { .. }) => {
                if self.queue.len() < MAX_QUEUED_EDITS {
                    self.queue.push_back(*command);
                } else {
                    messages.push(format!("{command:?} dropped: {MAX_QUEUED_EDITS} effect edits are waiting"));
                }
                false
            }
            _ => true,
        });
        messages
    }

    /// Starts the next build if none runs; returns the edit whose build is ready (offered to
    /// `instance`, to apply now), or why it could not be built.
    pub fn poll(&mut self, instance: &mut SceneInstance) -> Option<Result<ControlEvent, String>> {
        if let Some((command, receiver)) = &self.building {
            let command = *command;
            let done = match receiver.try_recv() {
                Ok(result) => result,
                Err(TryRecvError::Empty) => return None,
                Err(TryRecvError::Disconnected) => Err("its build stopped".into()),
            };
            self.building = None;
            return Some(match done {
                Ok(replacement) => {
                    instance.offer_prepared(command, replacement);
                    Ok(ControlEvent::Show(command))
                }
                Err(e) => Err(format!("the effect edit was refused: {e}")),
            });
        }
        let command = self.queue.pop_front()?;
        match instance.build_ahead(command) {
            Ok(receiver) => self.building = Some((command, receiver)),
            // No thread to be had: the edit is built when it is applied.
            Err(_) if instance.show().is_some() => return Some(Ok(ControlEvent::Show(command))),
            Err(e) => return Some(Err(e)),
        }
        None
    }

    /// Whether no edit waits or builds.
    pub fn is_idle(&self) -> bool {
        self.queue.is_empty() && self.building.is_none()
    }

    /// Waits (at most [`FINISH_WAIT`]) for the build under way, if any, and drops it: the show is
    /// ending.
    pub fn finish(&mut self) {
        if let Some((_, receiver)) = self.building.take() {
            let _ = receiver.recv_timeout(FINISH_WAIT);
        }
        self.queue.clear();
    }
}

/// How long the end of the show waits for an edit's build.
pub const FINISH_WAIT: std::time::Duration = std::time::Duration::from_secs(10);
