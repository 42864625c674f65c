//! Rendering a scene frame by frame without a window.

use std::path::Path;

use crate::assets::Assets;
use crate::checkpoint::{Checkpoint, CheckpointError, Header};
use crate::dmx::PixelMap;
use crate::gpu::DEFAULT_STALL_TIMEOUT;
use crate::gpu::{Blit, Gpu, read_texture_rgba8};
use crate::graph::{FrameStats, GraphRuntime, PersistentTexture};
use crate::live::{GpuGuard, GpuState, GpuTrouble, LiveReload, ReloadReport};
use crate::params::ControlEvent;
use crate::scene::{Player, Scene, SceneInstance, SeekError};
use crate::time::{FixedClock, FrameTime};

/// One rendered frame, read back as sRGB-encoded RGBA8 rows.
pub struct RenderedFrame {
    /// The frame's time.
    pub time: FrameTime,
    /// Width × height × 4 bytes, top row first.
    pub rgba: Vec<u8>,
    /// Size in pixels.
    pub size: (u32, u32),
    /// What the frame graph reported.
    pub stats: FrameStats,
}

/// Renders a scene off-screen on a fixed clock: frame n is at time n × dt, whatever the speed,
/// through the same frame step as the window ([`Player`]).
pub struct OffscreenRenderer {
    gpu: Gpu,
    player: Player,
    runtime: GraphRuntime,
    blit: Blit,
    size: (u32, u32),
    target: PersistentTexture,
    guard: GpuGuard,
    /// The newest frame's submission, for callers that keep frames in flight (`bench`).
    submitted: Option<wgpu::SubmissionIndex>,
    /// Which output is read back: 0 the scene's output, n its n-th extra output.
    shown: usize,
    /// A DMX patch's pixel map and the output it samples.
    pixel_map: Option<(PixelMap, usize)>,
}

impl OffscreenRenderer {
    /// Instantiates `scene` at `size` with step `dt` and `seed` (defaults: the scene's).
    pub fn new(
        gpu: Gpu,
        assets: &Assets,
        scene: Scene,
        size: Option<(u32, u32)>,
        dt: Option<f32>,
        seed: Option<u64>,
    ) -> Result<Self, crate::gpu::ShaderError> {
        let size = size.unwrap_or(scene.size);
        let clock = FixedClock::new(dt.unwrap_or(scene.dt), seed.unwrap_or(scene.seed));
        let mut instance = SceneInstance::new(&gpu, assets, scene, size)?;
        let mut runtime = GraphRuntime::new(&gpu.device, &gpu.queue);
        // A show's clips draw a throwaway frame each before the first: no trigger allocates.
        instance.warm_up(&mut runtime).map_err(|e| crate::gpu::ShaderError {
            origin: instance.scene().origin.clone(),
            line: 1,
            column: 1,
            message: format!("preparing the clips: {e}"),
        })?;
        let blit = Blit::new(&gpu.device);
        let target = display_target(&gpu, size);
        let guard = GpuGuard::new(DEFAULT_STALL_TIMEOUT);
        Ok(Self {
            gpu,
            player: Player::new(instance, clock),
            runtime,
            blit,
            size,
            target,
            guard,
            submitted: None,
            shown: 0,
            pixel_map: None,
        })
    }

    /// Waits (within the watchdog's limit) for the last frame; reports a lost or stuck device,
    /// as the window checks between frames.
    pub fn check_gpu(&mut self) -> GpuState {
        self.guard.check(&self.gpu)
    }

    /// Sets how long a frame may take before [`OffscreenRenderer::check_gpu`] calls it stalled,
    /// and how long a stalled frame may take before the device counts as stuck.
    pub fn set_gpu_limits(&mut self, stall: std::time::Duration, stuck: std::time::Duration) {
        self.guard = GpuGuard::with_limits(stall, stuck);
    }

    /// After a stall: rolls `live`'s newest shader reload back on this device, as the window
    /// does ([`crate::live::roll_back_stall`]). Returns the message for the user.
    pub fn roll_back_stall(&mut self, trouble: &GpuTrouble, live: Option<&mut LiveReload>) -> String {
        crate::live::roll_back_stall(trouble, &self.gpu, &mut self.player, live, self.size)
    }

    /// Moves to a new device after `trouble`, exactly as the window does ([`crate::live::recover`]):
    /// parameters, clock and script kept, nodes rebuilt from `live`'s last good shaders (else
    /// `assets`). Returns the message for the user.
    pub fn recover(
        &mut self,
        trouble: &GpuTrouble,
        live: Option<&mut LiveReload>,
        assets: &Assets,
    ) -> Result<String, String> {
        let (gpu, message) = crate::live::recover(trouble, &self.gpu, None, &mut self.player, live, assets, self.size)?;
        self.runtime = GraphRuntime::new(&gpu.device, &gpu.queue);
        self.blit = Blit::new(&gpu.device);
        self.target = display_target(&gpu, self.size);
        self.guard.reset();
        self.gpu = gpu;
        Ok(message)
    }

    /// Goes on from a scene sought off this thread (as a window chasing timecode does): its
    /// next frame is the sought one. The scene must be this renderer's, at its size.
    pub fn take_over(&mut self, sought: crate::live::Sought) {
        self.player = sought.player;
        self.runtime = sought.runtime;
    }

    /// Reads back output `n` from now on: 0 is the scene's output (the first window), 1… its
    /// `outputs` (the other windows, warped as they are shown).
    pub fn show_output(&mut self, n: usize) -> Result<(), String> {
        let count = self.player.instance().scene().outputs.len();
        if n > count {
            let name = &self.player.instance().scene().name;
            return Err(format!("'{name}' has outputs 0 to {count}; there is no output {n}"));
        }
        self.shown = n;
        Ok(())
    }

    /// The live scene (to change parameters between frames).
    pub fn instance_mut(&mut self) -> &mut SceneInstance {
        self.player.instance_mut()
    }

    /// The device.
    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    /// The graph runtime (pass timings, pool).
    pub fn runtime(&self) -> &GraphRuntime {
        &self.runtime
    }

    /// Advances to frame `frame` without drawing the frames before it: every fixed step runs
    /// (simulation only, scheduled events at their own frames), so the next rendered frame is
    /// the same bytes as when played from 0. Forward only.
    pub fn seek(&mut self, frame: u64) -> Result<(), SeekError> {
        self.player.seek(&self.gpu, &mut self.runtime, self.size, frame)
    }

    /// What a checkpoint of this render pins, at the next frame (see
    /// [`Player::checkpoint_header`]).
    pub fn checkpoint_header(&self, controls: &str) -> Header {
        self.player.checkpoint_header(&self.gpu, self.size, controls)
    }

    /// A checkpoint of the state before the next frame (waits for the GPU); `controls` as for
    /// [`OffscreenRenderer::checkpoint_header`].
    pub fn checkpoint(&self, controls: &str) -> Result<Checkpoint, CheckpointError> {
        let _ = self.gpu.device.poll(wgpu::PollType::wait_indefinitely());
        let sections = self.player.save_state(&self.gpu)?;
        Ok(Checkpoint { header: self.checkpoint_header(controls), sections })
    }

    /// Goes on from `checkpoint` (made by a render of the same scene, checked by the caller
    /// against [`OffscreenRenderer::checkpoint_header`]): the next frame is its frame. Only a
    /// renderer that has drawn nothing yet may take one.
    pub fn restore(&mut self, checkpoint: &Checkpoint) -> Result<(), CheckpointError> {
        self.player.load_state(&self.gpu, checkpoint)?;
        let _ = self.gpu.device.poll(wgpu::PollType::wait_indefinitely());
        Ok(())
    }

    /// Schedules control events to apply just before frame `frame` steps (a replayed control
    /// stream, or a test's script). Events for frames already stepped are dropped.
    pub fn schedule(&mut self, frame: u64, events: Vec<ControlEvent>) {
        self.player.schedule(frame, events);
    }

    /// The frame the next render draws.
    pub fn next_frame(&self) -> u64 {
        self.player.now().frame
    }

    /// Records and submits one frame, without reading it back (benchmarks).
    pub fn render_only(&mut self) -> Result<(FrameTime, FrameStats), crate::graph::GraphError> {
        let time = self.player.step();
        let mut encoder =
            self.gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("offscreen_frame") });
        let (blit, target, shown, size) = (&mut self.blit, &self.target, self.shown, self.size);
        let pixel_map = self.pixel_map.as_ref();
        let mut encoded = false;
        let output = self.player.encode(&self.gpu, &mut self.runtime, &mut encoder, self.size, |graph| {
            if let Some((map, image)) = pixel_map {
                let source = if *image == 0 { graph.output() } else { graph.extra_output(image - 1) };
                if let Some(source) = source {
                    map.add_pass(graph, source);
                }
            }
            // The display encode is a pass of the frame: timed with the others, after them.
            let source = if shown == 0 { graph.output() } else { graph.extra_output(shown - 1) };
            let Some(source) = source else { return };
            let written = graph.import_texture("display/target", target);
            graph.add_pass("display/encode").read(source).write(written).record(move |ctx| {
                let (from, to) = (ctx.view(source).clone(), ctx.view(written).clone());
                blit.record_compute(ctx.device, ctx.encoder, &from, &to, size);
            });
            encoded = true;
        })?;
        if !encoded {
            let resource = format!("output {}", self.shown);
            return Err(crate::graph::GraphError::ReadOfUnwritten { pass: "<output>".into(), resource });
        }
        let index = self.gpu.queue.submit([encoder.finish()]);
        self.submitted = Some(index.clone());
        self.guard.submitted(index);
        self.runtime.after_submit();
        Ok((time, output.stats))
    }

    /// Samples a DMX patch's fixtures on `image` (0 the output, n the n-th extra output) in
    /// every frame from now on; [`OffscreenRenderer::read_pixel_map`] reads them.
    pub fn set_pixel_map(&mut self, map: PixelMap, image: usize) -> Result<(), String> {
        let count = self.player.instance().scene().outputs.len();
        if image > count {
            return Err(format!("the patch samples image {image}, but the scene has outputs 0 to {count}"));
        }
        self.pixel_map = Some((map, image));
        Ok(())
    }

    /// The newest frame's sampled fixture pixels (waits for the GPU).
    pub fn read_pixel_map(&self) -> Option<Result<Vec<[u16; 3]>, crate::gpu::ReadbackError>> {
        let (map, _) = self.pixel_map.as_ref()?;
        Some(map.read_now(&self.gpu.device, &self.gpu.queue))
    }

    /// The submission of the newest frame `render_only` recorded.
    pub fn last_submission(&self) -> Option<wgpu::SubmissionIndex> {
        self.submitted.clone()
    }

    /// Waits until the GPU has done submission `index` (one of [`Self::last_submission`]).
    pub fn wait_for(&self, index: wgpu::SubmissionIndex) {
        let wait = wgpu::PollType::Wait { submission_index: Some(index), timeout: None };
        let _ = self.gpu.device.poll(wait);
    }

    /// Renders the next frame and reads it back.
    pub fn render_next(&mut self) -> Result<RenderedFrame, RenderError> {
        let (time, stats) = self.render_only()?;
        let rgba = read_texture_rgba8(&self.gpu.device, &self.gpu.queue, &self.target.texture)?;
        Ok(RenderedFrame { time, rgba, size: self.size, stats })
    }

    /// Applies edited shader and scene files picked up by `live` (hot reload, off-screen).
    pub fn poll_reload(&mut self, live: &mut LiveReload) -> ReloadReport {
        live.poll(&mut self.player, &self.gpu, self.size)
    }

    /// Waits for the GPU and folds outstanding pass timings into the medians.
    pub fn finish_timings(&mut self) {
        self.runtime.drain_timings(&self.gpu.device);
    }

    /// Waits for outstanding timings, then forgets them all (seek and warm-up frames must not
    /// enter a benchmark's medians).
    pub fn restart_timings(&mut self) {
        self.runtime.drain_timings(&self.gpu.device);
        self.runtime.reset_timings();
    }
}

/// The texture a frame is encoded into for readback.
fn display_target(gpu: &Gpu, size: (u32, u32)) -> PersistentTexture {
    PersistentTexture::new(&gpu.device, "offscreen_target", size, crate::gpu::DISPLAY_FORMAT)
}

/// Why an off-screen frame could not be produced; each is one sentence for the user.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The frame's declarations cannot run.
    #[error(transparent)]
    Graph(#[from] crate::graph::GraphError),
    /// The device was lost before the frame came back.
    #[error(transparent)]
    Readback(#[from] crate::gpu::ReadbackError),
}

/// Writes RGBA8 rows as a PNG.
pub fn write_png(path: &Path, size: (u32, u32), rgba: &[u8]) -> Result<(), String> {
    std::fs::write(path, encode_png(size, rgba)?).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// RGBA8 rows as the bytes of a PNG file (what [`write_png`] writes, for callers that also hash
/// them).
pub fn encode_png(size: (u32, u32), rgba: &[u8]) -> Result<Vec<u8>, String> {
    let mut bytes = Vec::new();
    let (png, rgba8) = (image::ImageFormat::Png, image::ExtendedColorType::Rgba8);
    image::write_buffer_with_format(&mut std::io::Cursor::new(&mut bytes), rgba, size.0, size.1, rgba8, png)
        .map_err(|e| format!("cannot encode a PNG: {e}"))?;
    Ok(bytes)
}
