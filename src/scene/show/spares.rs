//! Fresh copies of restarting clips, made before they are needed. A clip that restarts must show
//! its first frame the moment it is triggered, but building its nodes (pipelines, buffers) takes
//! up to seconds for the costly scenes. So when a restart clip leaves the screen, a fresh copy is
//! built — on a worker thread in a live show, at once in renders — and swapped in while it is
//! hidden; the trigger then finds it ready. Only retriggering the clip that is playing, or a
//! trigger within moments of its leaving, waits for a build.

use std::sync::mpsc;

use crate::assets::Assets;
use crate::files::LoadWait;
use crate::gpu::{Gpu, ShaderError};
use crate::params::ParamSet;
use crate::scene::SceneNode;
use crate::techniques::{NodeSetup, Technique};

/// A clip's nodes, built.
pub type Nodes = Vec<Box<dyn Technique>>;

/// Everything building a clip's nodes needs, owned (it may travel to a worker thread).
pub struct Build {
    /// The device.
    pub gpu: Gpu,
    /// The shaders the show runs with.
    pub assets: Assets,
    /// The clip's nodes and their parameters now.
    pub nodes: Vec<(SceneNode, ParamSet)>,
    /// The show's size.
    pub output_size: (u32, u32),
    /// The show's samples per pixel.
    pub msaa: u32,
    /// The show's seed.
    pub seed: u64,
}

impl Build {
    /// Builds every node, in order.
    pub fn run(self) -> Result<Nodes, ShaderError> {
        let Build { gpu, assets, nodes, output_size, msaa, seed } = &self;
        nodes
            .iter()
            .map(|(node, params)| {
                let setup = NodeSetup {
                    gpu,
                    assets,
                    id: &node.id,
                    output_size: *output_size,
                    msaa: *msaa,
                    params,
                    seed: *seed,
                };
                (node.technique.create)(&setup)
            })
            .collect()
    }
}

/// Where a clip's fresh copy stands.
enum Slot {
    /// The clip's nodes have not run since they were built.
    Fresh,
    /// They have run; no copy is on its way.
    Stale,
    /// A copy is being built on a worker thread.
    Building(mpsc::Receiver<Result<Nodes, ShaderError>>),
}

/// One slot per clip of the show.
pub struct Spares {
    slots: Vec<Slot>,
}

impl Spares {
    /// Every clip fresh (just built).
    pub fn new(clips: usize) -> Self {
        Self { slots: (0..clips).map(|_| Slot::Fresh).collect() }
    }

    /// Starts building a fresh copy of `clip` (it just left the screen): at once when `wait` is
    /// [`LoadWait::Finish`] (renders, tests), else on a worker thread. Returns nodes built at once.
    pub fn prepare(&mut self, clip: usize, build: Build, wait: LoadWait) -> Option<Result<Nodes, ShaderError>> {
        let slot = self.slots.get_mut(clip)?;
        if !matches!(slot, Slot::Stale) {
            return None;
        }
        if wait == LoadWait::Finish {
            return Some(build.run());
        }
        let (send, receive) = mpsc::channel();
        let spawned = std::thread::Builder::new().name("indra-clip-prepare".into()).spawn(move || {
            let _ = send.send(build.run());
        });
        match spawned {
            Ok(_) => {
                *slot = Slot::Building(receive);
                None
            }
            // No thread to be had: the clip restarts from its running state.
            Err(_) => Some(Err(failure("no thread to prepare a clip on"))),
        }
    }

    /// Marks `clip`'s nodes as fresh (a copy was just swapped in).
    pub fn mark_fresh(&mut self, clip: usize) {
        if let Some(slot) = self.slots.get_mut(clip) {
            *slot = Slot::Fresh;
        }
    }

    /// Marks every clip stale (its nodes ran, or were rebuilt for another device).
    pub fn mark_stale(&mut self, clip: usize) {
        if let Some(slot) = self.slots.get_mut(clip) {
            *slot = Slot::Stale;
        }
    }

    /// Copies finished on worker threads since the last call: (clip, nodes or error).
    pub fn finished(&mut self) -> Vec<(usize, Result<Nodes, ShaderError>)> {
        let mut done = Vec::new();
        for (clip, slot) in self.slots.iter_mut().enumerate() {
            if let Slot::Building(receive) = slot {
                match receive.try_recv() {
                    Ok(result) => done.push((clip, result)),
                    Err(mpsc::TryRecvError::Empty) => continue,
                    Err(mpsc::TryRecvError::Disconnected) => {
                        done.push((clip, Err(failure("a clip's preparation stopped"))));
                    }
                }
                *slot = Slot::Stale;
            }
        }
        done
    }

    /// `clip` starts now: `Ok(None)` if its nodes are fresh; else fresh nodes — the copy on its
    /// way (waited for) or one built now by `build`.
    pub fn take_for_start(&mut self, clip: usize, build: impl FnOnce() -> Build) -> Result<Option<Nodes>, ShaderError> {
        let Some(slot) = self.slots.get_mut(clip) else { return Ok(None) };
        let previous = std::mem::replace(slot, Slot::Stale);
        match previous {
            Slot::Fresh => Ok(None),
            Slot::Building(receive) => match receive.recv() {
                Ok(result) => result.map(Some),
                Err(_) => build().run().map(Some),
            },
            Slot::Stale => build().run().map(Some),
        }
    }
}

fn failure(message: &str) -> ShaderError {
    ShaderError { origin: "show".into(), line: 1, column: 1, message: message.into() }
}
