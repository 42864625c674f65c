//! The seek a show chasing timecode makes when the code jumps (the desk located elsewhere, or
//! ran far ahead of the show): a fresh instance of the running scene is built and stepped to the
//! code's frame on a thread of its own, while the window keeps its frame; the render thread only
//! swaps the result in. Seeks are exact (frame n is the same bytes however it is reached), so
//! the frame shown after the swap is the frame a render from 0 shows there.
//!
//! The code runs on while the seek works: the thread keeps stepping until it is within a few
//! frames of where the code is now (the render thread tells it each frame), so the window takes
//! over with steps of its own rather than a second seek. On its way it keeps checkpoints in
//! memory ([`SeekCheckpoints`]), and starts from the latest one before the code when there is
//! one, so a second jump deep into a long show does not step from frame 0 again.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, TryRecvError, sync_channel};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::assets::Assets;
use crate::checkpoint::Checkpoint;
use crate::gpu::Gpu;
use crate::graph::GraphRuntime;
use crate::scene::{Player, Scene, SceneInstance};
use crate::time::FixedClock;

use super::SeekCheckpoints;

/// Steps the seek runs between looks at where the code is (and at a cancel).
const STEPS_PER_LOOK: u64 = 32;

/// How close to the code's frame the seek hands over: the window steps the rest.
pub const HAND_OVER_WITHIN: u64 = 2;

/// How often the seek checks that it gains on the code: one that does not (a scene whose steps
/// are slower than real time) hands over where it got to, so the show moves on screen, in jumps,
/// rather than holding for good.
const GAIN_CHECK: Duration = Duration::from_secs(2);

/// A scene stepped to a frame off the render thread, ready to be shown.
pub struct Sought {
    /// The scene on its clock: its next step is the frame sought.
    pub player: Player,
    /// The graph runtime its frames were recorded with (its pool is sized for the window).
    pub runtime: GraphRuntime,
    /// The frame it stepped from: 0, or a checkpoint's.
    pub from: u64,
}

/// A seek in progress on its own thread.
pub struct BackgroundSeek {
    /// The frame the code is at now, as the render thread last said.
    wanted: Arc<AtomicU64>,
    cancel: Arc<AtomicBool>,
    done: Receiver<Result<Sought, String>>,
    thread: Option<JoinHandle<()>>,
}

impl BackgroundSeek {
    /// Starts building `scene` with `assets` for a window of `size` and stepping it until its
    /// next step is within [`HAND_OVER_WITHIN`] frames of `frame` (which [`Self::want`] moves),
    /// from the latest of `checkpoints` before it, keeping more on the way.
    pub fn start(
        gpu: &Gpu,
        assets: &Assets,
        scene: Scene,
        size: (u32, u32),
        frame: u64,
        checkpoints: &SeekCheckpoints,
    ) -> Self {
        let wanted = Arc::new(AtomicU64::new(frame));
        let cancel = Arc::new(AtomicBool::new(false));
        let (send, done) = sync_channel(1);
        let (gpu, assets) = (gpu.clone(), assets.clone());
        let (want, stop, kept) = (wanted.clone(), cancel.clone(), checkpoints.clone());
        let thread = std::thread::Builder::new()
            .name("indra-chase-seek".into())
            .spawn(move || {
                let result = seek(&gpu, &assets, scene, size, &want, &stop, &kept);
                // The window may have gone on without this seek: nobody to tell then.
                let _ = send.send(result);
            })
            .map_err(|e| log::warn!("cannot start a seek thread: {e}"))
            .ok();
        Self { wanted, cancel, done, thread }
    }

    /// The code is at `frame` now: the seek runs on towards it.
    pub fn want(&self, frame: u64) {
        self.wanted.store(frame, Ordering::Relaxed);
    }

    /// The seek's result once it is done (`None` while it runs).
    pub fn try_take(&mut self) -> Option<Result<Sought, String>> {
        match self.done.try_recv() {
            Ok(result) => Some(result),
            Err(TryRecvError::Empty) => None,
            // The thread could not start, or ended without sending (it panicked).
            Err(TryRecvError::Disconnected) => Some(Err("the seek thread ended without a result".into())),
        }
    }

    /// Stops the seek and waits for its thread (at exit: no GPU work after the device goes).
    pub fn finish(mut self) {
        self.cancel.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

impl Drop for BackgroundSeek {
    /// A seek no longer wanted stops at its next look; the render thread never waits for it.
    fn drop(&mut self) {
        self.cancel.store(true, Ordering::Relaxed);
    }
}

/// The seek's work: build, then step towards the code until close to it (or cancelled).
fn seek(
    gpu: &Gpu,
    assets: &Assets,
    scene: Scene,
    size: (u32, u32),
    wanted: &AtomicU64,
    cancel: &AtomicBool,
    checkpoints: &SeekCheckpoints,
) -> Result<Sought, String> {
    let clock = FixedClock::new(scene.dt, scene.seed);
    let mut instance = SceneInstance::new(gpu, assets, scene, size).map_err(|e| e.to_string())?;
    let mut runtime = GraphRuntime::new(&gpu.device, &gpu.queue);
    // As the window's instance did at start: a show's clips draw a throwaway frame each.
    instance.warm_up(&mut runtime).map_err(|e| format!("preparing the clips: {e}"))?;
    let mut player = Player::new(instance, clock);
    let pinned = player.checkpoint_header(gpu, size, "");
    let mut from = 0;
    if let Some(checkpoint) = checkpoints.nearest(&pinned, wanted.load(Ordering::Relaxed)) {
        if let Err(e) = player.load_state(gpu, &checkpoint) {
            checkpoints.forget();
            return Err(format!("the seek's checkpoint: {e}"));
        }
        from = checkpoint.header.frame;
    }
    let (mut checked, mut gap) = (Instant::now(), u64::MAX);
    loop {
        if cancel.load(Ordering::Relaxed) {
            return Err("cancelled".into());
        }
        let next = player.now().frame;
        let goal = wanted.load(Ordering::Relaxed);
        let behind = goal.saturating_sub(next);
        if behind <= HAND_OVER_WITHIN {
            return Ok(Sought { player, runtime, from });
        }
        if checked.elapsed() > GAIN_CHECK {
            if behind >= gap {
                log::warn!("a seek steps slower than the code runs: showing frame {next}, {behind} behind");
                return Ok(Sought { player, runtime, from });
            }
            (checked, gap) = (Instant::now(), behind);
        }
        let stop = checkpoints.next_stop(&pinned, next);
        let to = goal.min(next + STEPS_PER_LOOK).min(stop);
        player.seek(gpu, &mut runtime, size, to).map_err(|e| e.to_string())?;
        if to == stop {
            let _ = gpu.device.poll(wgpu::PollType::wait_indefinitely());
            let sections = player.save_state(gpu).map_err(|e| format!("a checkpoint of the seek: {e}"))?;
            checkpoints.keep(Checkpoint { header: player.checkpoint_header(gpu, size, ""), sections });
        }
    }
}
