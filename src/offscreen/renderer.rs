//! Rendering a scene frame by frame without a window.

use std::collections::BTreeMap;
use std::path::Path;

use crate::assets::Assets;
use crate::gpu::{Blit, BlitTarget, DISPLAY_FORMAT, Gpu, read_texture_rgba8};
use crate::graph::{FrameStats, GraphRuntime};
use crate::live::{LiveReload, ReloadReport};
use crate::scene::{ControlEvent, Scene, SceneInstance};
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

/// Renders a scene off-screen on a fixed clock: frame n is at time n × dt, whatever the speed.
pub struct OffscreenRenderer {
    gpu: Gpu,
    instance: SceneInstance,
    runtime: GraphRuntime,
    blit: Blit,
    clock: FixedClock,
    size: (u32, u32),
    target: wgpu::Texture,
    script: BTreeMap<u64, Vec<ControlEvent>>,
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
        let instance = SceneInstance::new(&gpu, assets, scene, size)?;
        let runtime = GraphRuntime::new(&gpu.device, &gpu.queue);
        let blit = Blit::new(&gpu.device);
        let target = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("offscreen_target"),
            size: wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DISPLAY_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        Ok(Self { gpu, instance, runtime, blit, clock, size, target, script: BTreeMap::new() })
    }

    /// The live scene (to change parameters between frames).
    pub fn instance_mut(&mut self) -> &mut SceneInstance {
        &mut self.instance
    }

    /// The device.
    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    /// The graph runtime (pass timings, pool).
    pub fn runtime(&self) -> &GraphRuntime {
        &self.runtime
    }

    /// Jumps to frame `frame` without rendering the ones before. Stateless scenes render the
    /// same frame either way; simulations need every step, so use this only before frame 0.
    pub fn seek(&mut self, frame: u64) {
        self.clock.seek(frame);
    }

    /// Schedules control events to apply just before frame `frame` steps (a replayed control
    /// stream, or a test's script). Events for frames already rendered are ignored.
    pub fn schedule(&mut self, frame: u64, events: Vec<ControlEvent>) {
        self.script.entry(frame).or_default().extend(events);
    }

    /// Records and submits one frame, without reading it back (benchmarks).
    pub fn render_only(&mut self) -> Result<(FrameTime, FrameStats), crate::graph::GraphError> {
        let time = self.clock.now();
        if let Some(events) = self.script.remove(&time.frame) {
            self.instance.apply(&events);
        }
        self.instance.advance(&time);
        let mut encoder =
            self.gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("offscreen_frame") });
        let output = self.instance.encode(&self.gpu, &mut self.runtime, &mut encoder, self.size, &time)?;
        let target_view = self.target.create_view(&Default::default());
        self.blit.record(
            &self.gpu.device,
            &self.gpu.queue,
            &mut encoder,
            &output.view,
            BlitTarget { view: &target_view, format: DISPLAY_FORMAT, size: self.size },
        );
        self.gpu.queue.submit([encoder.finish()]);
        self.runtime.after_submit();
        self.clock.step();
        Ok((time, output.stats))
    }

    /// Renders the next frame and reads it back.
    pub fn render_next(&mut self) -> Result<RenderedFrame, crate::graph::GraphError> {
        let (time, stats) = self.render_only()?;
        let rgba = read_texture_rgba8(&self.gpu.device, &self.gpu.queue, &self.target);
        Ok(RenderedFrame { time, rgba, size: self.size, stats })
    }

    /// Applies edited shader and scene files picked up by `live` (hot reload, off-screen).
    pub fn poll_reload(&mut self, live: &mut LiveReload) -> ReloadReport {
        live.poll(&mut self.instance, &self.gpu, self.size)
    }

    /// Waits for the GPU and folds outstanding pass timings into the medians.
    pub fn finish_timings(&mut self) {
        self.runtime.drain_timings(&self.gpu.device);
    }
}

/// Writes RGBA8 rows as a PNG.
pub fn write_png(path: &Path, size: (u32, u32), rgba: &[u8]) -> Result<(), String> {
    image::save_buffer(path, rgba, size.0, size.1, image::ExtendedColorType::Rgba8)
        .map_err(|e| format!("cannot write {}: {e}", path.display()))
}
