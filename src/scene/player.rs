//! The one frame step, shared by the window, `render`, `bench` and the tests: control events due
//! at this frame (in order) → tracks, preset morphs, smoothing, triggers → node steps, on the
//! fixed clock; then, for a frame that is shown, the encode.
//!
//! Seeking runs every fixed step from the current frame to the target, applying scheduled events
//! at their own frames (so a trigger fires once each), and records only simulation work for the
//! skipped frames — nothing is drawn or read back. Frame N is therefore the same bytes whether
//! it is played from 0, sought, or rendered as the second half of a split render.

use std::collections::BTreeMap;

use super::instance::SceneInstance;
use crate::checkpoint::{Checkpoint, CheckpointError, Header};
use crate::gpu::Gpu;
use crate::graph::{FrameGraph, FrameOutput, GraphError, GraphRuntime};
use crate::params::{ControlEvent, Remap};
use crate::time::{FixedClock, FrameTime};

/// Steps between waits for the GPU while seeking, so a long seek never queues unbounded work.
const SEEK_SUBMITS_PER_WAIT: u64 = 64;

/// A scene instance on its fixed clock, with a script of control events by frame.
pub struct Player {
    instance: SceneInstance,
    clock: FixedClock,
    script: BTreeMap<u64, Vec<ControlEvent>>,
    /// The time of the last step: what the next encode draws.
    last: FrameTime,
}

impl Player {
    /// A player at frame 0 of `clock`.
    pub fn new(instance: SceneInstance, clock: FixedClock) -> Self {
        let last = clock.now();
        Self { instance, clock, script: BTreeMap::new(), last }
    }

    /// The running scene.
    pub fn instance(&self) -> &SceneInstance {
        &self.instance
    }

    /// The running scene, to change it between steps.
    pub fn instance_mut(&mut self) -> &mut SceneInstance {
        &mut self.instance
    }

    /// The time of the next step.
    pub fn now(&self) -> FrameTime {
        self.clock.now()
    }

    /// The time of the last step (the frame an encode draws now).
    pub fn last_step(&self) -> FrameTime {
        self.last
    }

    /// Adds real elapsed seconds; returns how many whole steps to run now (window).
    pub fn accumulate(&mut self, elapsed: f64) -> u32 {
        self.clock.accumulate(elapsed)
    }

    /// Schedules events to apply just before step `frame` (a replayed control stream, a test's
    /// script). Events for frames already stepped are dropped with a logged notice.
    pub fn schedule(&mut self, frame: u64, events: Vec<ControlEvent>) {
        if frame < self.clock.now().frame {
            log::warn!("{} control event(s) for frame {frame} dropped: that frame has been stepped", events.len());
            return;
        }
        self.script.entry(frame).or_default().extend(events);
    }

    /// Moves scheduled events to where their parameters are after a hot reload; events for
    /// parameters that are gone are dropped with one logged notice.
    pub fn remap(&mut self, remap: &Remap) {
        let dropped: usize = self.script.values_mut().map(|events| remap.events(events)).sum();
        if dropped > 0 {
            log::warn!("{dropped} scheduled control event(s) dropped: their parameters left the scene");
        }
    }

    /// Applies live events now; they take effect from the next step.
    pub fn apply(&mut self, events: &[ControlEvent]) {
        self.instance.apply(events);
    }

    /// Runs one fixed step: the events scheduled for it, then tracks, smoothing, triggers and
    /// every node's step. Returns the step's time.
    pub fn step(&mut self) -> FrameTime {
        let time = self.clock.now();
        if let Some(events) = self.script.remove(&time.frame) {
            self.instance.apply(&events);
        }
        self.instance.advance(&time);
        self.last = time;
        self.clock.step();
        time
    }

    /// Steps up to frame `frame` (the next step is `frame`), recording only the simulation work
    /// of the skipped steps. A seek goes forward only: to go back, start a new player.
    pub fn seek(
        &mut self,
        gpu: &Gpu,
        runtime: &mut GraphRuntime,
        output_size: (u32, u32),
        frame: u64,
    ) -> Result<(), SeekError> {
        let from = self.clock.now().frame;
        if frame < from {
            return Err(SeekError::Backwards { from, to: frame });
        }
        for skipped in from..frame {
            let time = self.step();
            // Asked each step: a chain edit on the way may add a node that simulates.
            if !self.instance.simulates_on_gpu() {
                continue;
            }
            let mut encoder =
                gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("seek_step") });
            self.instance.encode_simulation(gpu, runtime, &mut encoder, output_size, &time)?;
            // One submit per step: techniques upload per-step uniforms with `write_buffer`,
            // which lands before the next submit.
            gpu.queue.submit([encoder.finish()]);
            runtime.after_submit();
            if (skipped - from + 1).is_multiple_of(SEEK_SUBMITS_PER_WAIT) {
                let _ = gpu.device.poll(wgpu::PollType::wait_indefinitely());
            }
        }
        Ok(())
    }

    /// What a checkpoint of this player pins, at the next step: the scene (its validated form,
    /// edits included, but not the folder it was read from), `controls` (a hash of the
    /// scheduled events), the output size, step, seed, and `gpu`'s adapter and driver.
    pub fn checkpoint_header(&self, gpu: &Gpu, size: (u32, u32), controls: &str) -> Header {
        let mut scene = self.instance.scene().clone();
        scene.origin.clear();
        let info = gpu.adapter.get_info();
        let now = self.now();
        Header {
            format: crate::checkpoint::FORMAT,
            indra: env!("CARGO_PKG_VERSION").to_string(),
            scene: scene.name.clone(),
            scene_hash: crate::checkpoint::sha256_hex(format!("{scene:?}").as_bytes()),
            controls_hash: crate::checkpoint::sha256_hex(controls.as_bytes()),
            adapter: format!("{} ({:?})", info.name, info.backend),
            driver: format!("{} {}", info.driver, info.driver_info).trim().to_string(),
            frame: now.frame,
            size,
            dt_bits: now.dt.to_bits(),
            seed: now.seed,
        }
    }

    /// The checkpoint sections of the state before the next step (see
    /// [`SceneInstance::save_state`]); the GPU must be idle.
    pub fn save_state(&self, gpu: &Gpu) -> Result<Vec<(String, Vec<u8>)>, CheckpointError> {
        self.instance.save_state(gpu)
    }

    /// Takes the state of `checkpoint`, made before step `checkpoint.header.frame`, into this
    /// player (just made for the same scene): the next step is that frame. Scheduled events
    /// before it are dropped: the checkpoint holds what they did.
    pub fn load_state(&mut self, gpu: &Gpu, checkpoint: &Checkpoint) -> Result<(), CheckpointError> {
        let frame = checkpoint.header.frame;
        self.clock.seek(frame.saturating_sub(1));
        let last = self.clock.now();
        self.clock.seek(frame);
        self.instance.load_state(gpu, checkpoint, &last)?;
        self.last = last;
        self.script = self.script.split_off(&frame);
        Ok(())
    }

    /// Records the frame of the last step into `encoder`, with the passes `finish` adds to it
    /// (see [`SceneInstance::encode`]); the caller submits.
    pub fn encode<'r>(
        &'r mut self,
        gpu: &Gpu,
        runtime: &mut GraphRuntime,
        encoder: &mut wgpu::CommandEncoder,
        output_size: (u32, u32),
        finish: impl FnOnce(&mut FrameGraph<'r>),
    ) -> Result<FrameOutput, GraphError> {
        let time = self.last;
        self.instance.encode(gpu, runtime, encoder, output_size, &time, finish)
    }
}

/// Why a seek could not reach its frame.
#[derive(Debug, thiserror::Error)]
pub enum SeekError {
    /// The target lies before the current frame.
    #[error("cannot seek back from frame {from} to frame {to}; start a new render from frame {to}")]
    Backwards {
        /// The current frame.
        from: u64,
        /// The frame asked for.
        to: u64,
    },
    /// A skipped step's simulation could not be recorded.
    #[error(transparent)]
    Graph(#[from] GraphError),
}
