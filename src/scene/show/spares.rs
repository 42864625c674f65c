//! Fresh copies of restarting clips, made before they are needed. A clip that restarts must show
//! its first frame the moment it is triggered, but building its nodes (pipelines, buffers) takes
//! up to seconds for the costly scenes. So when a restart clip leaves the screen, a fresh copy is
//! built — on a worker thread in a live show, at once in renders — and swapped in while it is
//! hidden; the trigger then finds it ready. In a live show the render thread never builds nor
//! waits: retriggering the clip that is playing, or a trigger within moments of its leaving,
//! restarts the clip's clock at once and swaps its fresh nodes in when their build is done (a
//! few frames later); at most [`MAX_BUILDS_IN_FLIGHT`] builds run at once, one per clip, and the
//! rest wait in line, so a flood of triggers costs a bounded number of threads and buffers.

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
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

/// Clip builds running on worker threads at once, over the whole show. A build holds a clip's
/// pipelines and buffers while it runs, so this also bounds what a trigger flood allocates.
pub const MAX_BUILDS_IN_FLIGHT: usize = 2;

/// Where a clip's fresh copy stands. `restart` marks a copy the clip waits for while it plays
/// (it was retriggered meanwhile): it is swapped in on arrival, on screen or not.
enum Slot {
    /// The clip's nodes have not run since they were built.
    Fresh,
    /// They have run; no copy is on its way.
    Stale,
    /// A copy waits for a place among the builds in flight.
    Queued { build: Box<Build>, restart: bool },
    /// A copy is being built on a worker thread.
    Building { receive: mpsc::Receiver<Result<Nodes, ShaderError>>, restart: bool },
}

/// A finished copy: its clip, the nodes (or why not), and whether the clip waits for it while
/// it plays.
pub struct Finished {
    /// The clip.
    pub clip: usize,
    /// Its fresh nodes, or the build's error.
    pub result: Result<Nodes, ShaderError>,
    /// Swap it in even on screen: the clip was retriggered while it was built.
    pub restart: bool,
}

/// One slot per clip of the show.
pub struct Spares {
    slots: Vec<Slot>,
    /// Builds running on worker threads (each thread counts itself out when it ends, so a
    /// copy dropped by a reload still holds its place until its thread is done).
    in_flight: Arc<AtomicUsize>,
}

impl Spares {
    /// Every clip fresh (just built).
    pub fn new(clips: usize) -> Self {
        Self { slots: (0..clips).map(|_| Slot::Fresh).collect(), in_flight: Arc::default() }
    }

    /// Starts a fresh copy of `clip` (it just left the screen): built at once when `wait` is
    /// [`LoadWait::Finish`] (renders, tests), else queued for a worker thread. Returns nodes
    /// built at once.
    pub fn prepare(&mut self, clip: usize, build: Build, wait: LoadWait) -> Option<Result<Nodes, ShaderError>> {
        let slot = self.slots.get_mut(clip)?;
        if !matches!(slot, Slot::Stale) {
            return None;
        }
        if wait == LoadWait::Finish {
            return Some(build.run());
        }
        *slot = Slot::Queued { build: Box::new(build), restart: false };
        self.launch();
        None
    }

    /// Counts its builds with `old`'s (the spares of the show this one replaces): the threads
    /// `old` started still run, and still hold their places among [`MAX_BUILDS_IN_FLIGHT`].
    pub fn continue_from(&mut self, old: &Spares) {
        self.in_flight = old.in_flight.clone();
    }

    /// Takes `clip`'s slot from `old` (the clip's nodes carried over unchanged) unless it is
    /// stale: fresh nodes stay fresh, and a copy on its way keeps coming instead of being built
    /// again. Returns whether it took it.
    pub fn take_slot(&mut self, old: &mut Spares, clip: usize) -> bool {
        let (Some(slot), Some(before)) = (self.slots.get_mut(clip), old.slots.get_mut(clip)) else { return false };
        if matches!(before, Slot::Stale) {
            return false;
        }
        *slot = std::mem::replace(before, Slot::Stale);
        true
    }

    /// Marks `clip`'s nodes as fresh (a copy was just swapped in).
    pub fn mark_fresh(&mut self, clip: usize) {
        if let Some(slot) = self.slots.get_mut(clip) {
            *slot = Slot::Fresh;
        }
    }

    /// Whether `clip`'s nodes have not run since they were built.
    pub fn is_fresh(&self, clip: usize) -> bool {
        matches!(self.slots.get(clip), Some(Slot::Fresh))
    }

    /// Marks `clip` stale (its nodes ran, or were rebuilt for another device); a copy on its way
    /// is dropped.
    pub fn mark_stale(&mut self, clip: usize) {
        if let Some(slot) = self.slots.get_mut(clip) {
            *slot = Slot::Stale;
        }
    }

    /// Copies finished on worker threads since the last call; queued copies take the places
    /// that freed.
    pub fn finished(&mut self) -> Vec<Finished> {
        let mut done = Vec::new();
        for (clip, slot) in self.slots.iter_mut().enumerate() {
            let Slot::Building { receive, restart } = slot else { continue };
            let result = match receive.try_recv() {
                Ok(result) => result,
                Err(mpsc::TryRecvError::Empty) => continue,
                Err(mpsc::TryRecvError::Disconnected) => Err(failure("a clip's preparation stopped")),
            };
            done.push(Finished { clip, result, restart: *restart });
            *slot = Slot::Stale;
        }
        self.launch();
        done
    }

    /// `clip` starts now. `Ok(None)` when its nodes are fresh, or (live) when its copy is on its
    /// way: the clip runs on its nodes until [`Spares::finished`] hands the copy over marked
    /// `restart`. Under [`LoadWait::Finish`] the copy is waited for or built now by `build`.
    pub fn take_for_start(
        &mut self,
        clip: usize,
        wait: LoadWait,
        build: impl FnOnce() -> Build,
    ) -> Result<Option<Nodes>, ShaderError> {
        let Some(slot) = self.slots.get_mut(clip) else { return Ok(None) };
        if wait == LoadWait::Background {
            match slot {
                Slot::Fresh => *slot = Slot::Stale,
                Slot::Queued { restart, .. } | Slot::Building { restart, .. } => *restart = true,
                Slot::Stale => {
                    *slot = Slot::Queued { build: Box::new(build()), restart: true };
                    self.launch();
                }
            }
            return Ok(None);
        }
        match std::mem::replace(slot, Slot::Stale) {
            Slot::Fresh => Ok(None),
            Slot::Building { receive, .. } => match receive.recv() {
                Ok(result) => result.map(Some),
                Err(_) => build().run().map(Some),
            },
            Slot::Queued { build, .. } => build.run().map(Some),
            Slot::Stale => build().run().map(Some),
        }
    }

    /// Starts queued copies on worker threads while fewer than [`MAX_BUILDS_IN_FLIGHT`] run.
    fn launch(&mut self) {
        for slot in &mut self.slots {
            if self.in_flight.load(Ordering::Relaxed) >= MAX_BUILDS_IN_FLIGHT {
                return;
            }
            if !matches!(slot, Slot::Queued { .. }) {
                continue;
            }
            let Slot::Queued { build, restart } = std::mem::replace(slot, Slot::Stale) else { continue };
            let (send, receive) = mpsc::channel();
            let in_flight = self.in_flight.clone();
            in_flight.fetch_add(1, Ordering::Relaxed);
            let spawned = crate::gpu::spawn_worker("indra-clip-prepare", move || {
                let _ = send.send(build.run());
                in_flight.fetch_sub(1, Ordering::Relaxed);
                release_free_memory();
            });
            if spawned.is_err() {
                // No thread to be had: the clip runs on from its state; told when it ends.
                self.in_flight.fetch_sub(1, Ordering::Relaxed);
                let (send, failed) = mpsc::channel();
                let _ = send.send(Err(failure("no thread to prepare a clip on")));
                *slot = Slot::Building { receive: failed, restart };
                continue;
            }
            *slot = Slot::Building { receive, restart };
        }
    }
}

/// Gives the allocator's free pages back to the system. A clip build allocates and frees
/// hundreds of megabytes in large blocks (pipelines, buffers, the driver's shader code) on
/// threads that come and go; glibc keeps what they freed in its arenas, so a show that switches
/// clips for hours grew by steps of tens of megabytes without holding any more (heaptrack: the
/// live heap flat at 413–433 MB while RSS rose). Costs a few milliseconds, on this worker thread.
fn release_free_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only walks and trims glibc's own arenas; it takes no pointer.
    unsafe {
        libc::malloc_trim(0);
    }
}

fn failure(message: &str) -> ShaderError {
    ShaderError { origin: "show".into(), line: 1, column: 1, message: message.into() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_replacing_show_takes_the_slots_that_are_not_stale() {
        let mut old = Spares::new(3);
        old.mark_stale(0);
        let mut new = Spares::new(3);
        new.continue_from(&old);
        assert!(!new.take_slot(&mut old, 0), "a stale slot was taken");
        assert!(new.take_slot(&mut old, 1) && new.is_fresh(1) && !old.is_fresh(1));
        assert!(!new.take_slot(&mut old, 7), "a clip the show lacks");
        assert!(Arc::ptr_eq(&new.in_flight, &old.in_flight), "the builds in flight are counted apart");
    }
}
