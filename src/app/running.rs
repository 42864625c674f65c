//! The open window's state and its frame: the step, the draw, the panel, the outputs and sends,
//! takes started and stopped, reloads, and a lost device replaced.

use std::sync::Arc;
use std::time::{Duration, Instant};

use winit::event::WindowEvent;
use winit::event_loop::ActiveEventLoop;
use winit::window::{Window, WindowId};

use super::outputs::OutputWindow;
use super::panel::{Overlay, draw_ui};
use crate::assets::Assets;
use crate::control::{ControlHub, RecordRequest};
use crate::gpu::{Blit, BlitTarget, Gpu};
use crate::graph::GraphRuntime;
use crate::live::{GpuGuard, GpuState, GpuTrouble, LiveReload};
use crate::offscreen::capture::{DEFAULT_IN_FLIGHT, take_path};
use crate::offscreen::{FinishingTake, LiveRecorder};
use crate::scene::Player;

/// Everything that exists once the window does.
pub(super) struct Running {
    pub(super) window: Arc<Window>,
    pub(super) surface: wgpu::Surface<'static>,
    pub(super) config: wgpu::SurfaceConfiguration,
    pub(super) gpu: Gpu,
    /// The scene on its fixed clock: the frame step shared with `render` and the tests.
    pub(super) player: Player,
    pub(super) runtime: GraphRuntime,
    pub(super) blit: Blit,
    pub(super) last: Instant,
    pub(super) egui_state: egui_winit::State,
    pub(super) egui_renderer: egui_wgpu::Renderer,
    pub(super) overlay: Overlay,
    pub(super) hub: ControlHub,
    pub(super) live: Option<LiveReload>,
    /// Effect chain edits built ahead.
    pub(super) chain_edits: super::chain_edits::ChainEdits,
    /// Panel events of the last frame, applied before the next step.
    pub(super) ui_events: Vec<crate::scene::ControlEvent>,
    /// Last cursor position over the window, in physical pixels.
    pub(super) pointer: [f32; 2],
    /// Whether the left button is held over the scene (drag roles follow the pointer).
    pub(super) dragging: bool,
    /// Where shaders come from when no live reload pins them (recovery rebuilds from these).
    pub(super) assets: Assets,
    /// Notices a lost or stuck device between frames.
    pub(super) guard: GpuGuard,
    /// A device to replace that could not be replaced yet, and when to try again.
    pub(super) retry: Option<(GpuTrouble, Instant)>,
    /// Since when frames wait for a stalled one to finish.
    pub(super) waiting_since: Option<Instant>,
    /// Where the output is sent from the start: the network stream (`run --stream`), the
    /// PipeWire source (`run --pipewire-out`) and the NDI source (`run --ndi-out`).
    /// Each with what it sends: `None` the output, `Some(n)` the scene's output `n + 1`.
    pub(super) sends: Vec<(Option<usize>, LiveRecorder)>,
    /// The video recording in progress.
    pub(super) video: Option<LiveRecorder>,
    /// Takes stopped whose files ffmpeg is still closing, off the render thread.
    pub(super) finishing: Vec<FinishingTake>,
    /// When the takes of the last minute started (a flood of start/stop is refused).
    pub(super) take_starts: std::collections::VecDeque<Instant>,
    /// Where takes go (`--record-video`, else [`super::DEFAULT_RECORDING`]).
    pub(super) video_base: std::path::PathBuf,
    /// The windows of the scene's other outputs (projectors).
    pub(super) outputs: Vec<OutputWindow>,
    /// The DMX patch the output's pixels go to (`--dmx-out`).
    pub(super) lights: Option<crate::dmx::LiveLights>,
    /// Following the timecode the show chases (`--mtc-in`).
    pub(super) chase: super::chase::WindowChase,
}

/// The most takes started in a minute.
const MAX_TAKES_PER_MINUTE: usize = 6;

/// The most takes whose files ffmpeg may be closing at once.
const MAX_TAKES_CLOSING: usize = 2;

/// The panel's line for a send (stream, NDI): where, frames sent, frames the network lost us.
fn send_status(send: &LiveRecorder) -> String {
    let counts = send.counts();
    format!("⇢ {}  {} frame(s) sent, {} dropped", send.path().display(), counts.queued, counts.dropped())
}

/// The panel's line for a running take: file, length in show time, lost frames.
fn recording_status(video: &LiveRecorder, dt: f32) -> String {
    let counts = video.counts();
    let seconds = counts.offered as f64 * f64::from(dt);
    let lost = match counts.dropped() {
        0 => String::new(),
        n => format!(", {n} frame(s) not recorded"),
    };
    format!("● {}  {:.0}:{:04.1}{lost}", video.path().display(), (seconds / 60.0).floor(), seconds % 60.0)
}

/// egui's input state and renderer for `window` on `gpu` (made again on a new device).
pub(super) fn egui_parts(
    window: &Window,
    gpu: &Gpu,
    format: wgpu::TextureFormat,
) -> (egui_winit::State, egui_wgpu::Renderer) {
    let max_side = gpu.device.limits().max_texture_dimension_2d as usize;
    let context = egui::Context::default();
    context.set_fonts(super::panel::panel_fonts());
    let state = egui_winit::State::new(
        context,
        egui::ViewportId::ROOT,
        window,
        Some(window.scale_factor() as f32),
        None,
        Some(max_side),
    );
    let renderer = egui_wgpu::Renderer::new(&gpu.device, format, egui_wgpu::RendererOptions::default());
    (state, renderer)
}

impl Running {
    /// The pointer in view units (0–1, y up), as pointer parameters take it.
    pub(super) fn view_position(&self) -> [f32; 2] {
        let (w, h) = (self.config.width.max(1) as f32, self.config.height.max(1) as f32);
        [self.pointer[0] / w, 1.0 - self.pointer[1] / h]
    }

    /// Steps the clock by real time, renders the scene and the overlay, presents.
    pub(super) fn frame(&mut self) {
        if !self.device_ready() {
            return;
        }
        let now = Instant::now();
        let assets = self.live.as_ref().map_or(&self.assets, |live| live.running_assets());
        let from = super::chase::SeekFrom { gpu: &self.gpu, assets, size: (self.config.width, self.config.height) };
        let timecode = self.hub.timecode(now);
        self.overlay.lanes.chasing = timecode.is_some();
        let steps = match timecode {
            Some(chasing) => self.chase.steps(chasing, &mut self.player, &mut self.runtime, from, &mut self.overlay),
            None => {
                // The performer dropped the play position on the lane view's ruler.
                if let Some(seconds) = self.overlay.lanes.place.take() {
                    let frame = crate::timecode::chase::frame_at(seconds, f64::from(self.player.now().dt));
                    self.chase.place(frame, &self.player, from);
                }
                let elapsed = (now - self.last).as_secs_f64();
                self.chase.free_steps(elapsed, &mut self.player, &mut self.runtime, &mut self.overlay)
            }
        };
        self.last = now;
        self.reload();
        let mut events = std::mem::take(&mut self.ui_events);
        events.extend(self.hub.poll(self.player.instance().view(), self.player.last_step().seconds));
        self.edit_chains(&mut events);
        self.hub.record(self.player.now().frame, &events, self.player.instance().scene());
        self.player.apply(&events);
        self.overlay.lanes.record(self.player.instance(), self.player.now().frame);
        self.act_on_record_requests();
        for _ in 0..steps {
            self.player.step();
        }
        if let Some(lights) = self.lights.as_mut() {
            let instance = self.player.instance();
            let positions = lights.lamp_targets().iter().map(|t| instance.position_of(t)).collect();
            lights.set_lamps(positions);
        }
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f) | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&self.gpu.device, &self.config);
                return;
            }
            other => {
                log::debug!("no surface texture this frame: {other:?}");
                return;
            }
        };
        let target = frame.texture.create_view(&Default::default());
        let size = (self.config.width, self.config.height);
        let mut projected = Vec::new();
        let mut encoder =
            self.gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("window_frame") });
        let lights = self.lights.as_ref();
        let drawn = self.player.encode(&self.gpu, &mut self.runtime, &mut encoder, size, |graph| {
            if let Some(lights) = lights {
                lights.add_pass(graph);
            }
        });
        match drawn {
            Ok(output) => {
                if let Some(lights) = self.lights.as_mut() {
                    lights.after_encode(&mut encoder, self.player.last_step().frame);
                }
                self.blit.record(
                    &self.gpu.device,
                    &self.gpu.queue,
                    &mut encoder,
                    &output.view,
                    BlitTarget { view: &target, format: self.config.format, size },
                );
                let shown = self.player.last_step().frame;
                if let Some(video) = self.video.as_mut() {
                    video.capture(&self.gpu.device, &mut encoder, &output.view, steps, shown);
                }
                for (what, send) in &mut self.sends {
                    let image = match what {
                        None => Some(&output.view),
                        Some(n) => output.extras.get(*n).and_then(Option::as_ref).map(|(_, view)| view),
                    };
                    if let Some(view) = image {
                        send.capture(&self.gpu.device, &mut encoder, view, steps, shown);
                    }
                }
                for (i, window) in self.outputs.iter_mut().enumerate() {
                    let Some(Some((_, view))) = output.extras.get(window.number - 1) else { continue };
                    if let Some(shown) = window.draw(&self.gpu, &mut encoder, view) {
                        projected.push((i, shown));
                    }
                }
                self.overlay.stats = Some(output.stats);
            }
            Err(e) => self.overlay.report(format!("frame graph: {e}")),
        }
        for e in self.gpu.take_uncaptured_errors() {
            self.overlay.report(format!("GPU: {e}"));
        }
        self.overlay.timings = self.runtime.timings();
        let extra = self.draw_overlay(&mut encoder, &target, size);
        let submitted = self.gpu.queue.submit(extra.into_iter().chain([encoder.finish()]));
        self.guard.submitted(submitted);
        self.runtime.after_submit();
        if let Some(video) = self.video.as_mut() {
            video.after_submit();
            video.poll(&self.gpu.device);
            self.overlay.recording = Some(recording_status(video, self.player.last_step().dt));
        }
        self.overlay.sending.clear();
        if let Some(lights) = self.lights.as_mut() {
            lights.after_submit(&self.gpu.device);
            self.overlay.sending.push(lights.status());
        }
        for (_, send) in &mut self.sends {
            send.after_submit();
            send.poll(&self.gpu.device);
            self.overlay.sending.push(send_status(send));
        }
        // The frame must finish before it is shown: waiting here, within the watchdog's limit,
        // is what catches a stuck GPU on drivers whose present would otherwise block for good
        // (lavapipe). The unshown frame is dropped and the next one recovers.
        let state = self.guard.check(&self.gpu);
        if state != GpuState::Ready {
            self.act_on(state);
            return;
        }
        self.window.pre_present_notify();
        self.gpu.queue.present(frame);
        for (i, shown) in projected {
            self.outputs[i].present(shown, &self.gpu.queue);
        }
        self.hub.after_frame(self.player.instance().view(), self.player.last_step().seconds);
        for m in self.player.instance_mut().take_messages() {
            self.overlay.report(m);
        }
        for n in std::mem::take(&mut self.hub.notices) {
            self.overlay.report(n);
        }
    }

    /// Whether the device can take a frame now (see [`Running::act_on`]).
    fn device_ready(&mut self) -> bool {
        if let Some((trouble, at)) = self.retry.clone() {
            return Instant::now() >= at && self.move_to_new_device(trouble);
        }
        let state = self.guard.check(&self.gpu);
        self.act_on(state)
    }

    /// Acts on the device's state; returns whether a frame may be drawn. A stall rolls the
    /// newest shader reload back and waits for the GPU (frames are skipped, the window stays
    /// responsive); a lost or stuck device is replaced.
    fn act_on(&mut self, state: GpuState) -> bool {
        match state {
            GpuState::Ready => {
                if let Some(since) = self.waiting_since.take() {
                    let waited = since.elapsed().as_secs_f64();
                    self.overlay
                        .report(format!("the GPU finished the stuck frame after {waited:.1} s; the show goes on"));
                }
                true
            }
            GpuState::Waiting => false,
            GpuState::Trouble(trouble @ GpuTrouble::Stalled(_)) => {
                let size = (self.config.width, self.config.height);
                let live = self.live.as_mut();
                let message = crate::live::roll_back_stall(&trouble, &self.gpu, &mut self.player, live, size);
                self.overlay.report(message);
                self.waiting_since = Some(Instant::now());
                false
            }
            GpuState::Trouble(trouble) => self.move_to_new_device(trouble),
        }
    }

    /// Moves the show to a new device; while none can be made, tries again every second.
    fn move_to_new_device(&mut self, trouble: GpuTrouble) -> bool {
        let size = (self.config.width, self.config.height);
        let live = self.live.as_mut();
        match crate::live::recover(&trouble, &self.gpu, Some(&self.surface), &mut self.player, live, &self.assets, size)
        {
            Ok((gpu, message)) => {
                // The take's buffers lived on the old device: it ends here, with what it has. So
                // did a seek's scene.
                self.stop_recording();
                self.chase.cancel();
                self.surface.configure(&gpu.device, &self.config);
                for output in &mut self.outputs {
                    output.reconfigure(&gpu);
                }
                self.runtime = GraphRuntime::new(&gpu.device, &gpu.queue);
                self.blit = Blit::new(&gpu.device);
                if let Some(lights) = self.lights.as_mut()
                    && let Err(e) = lights.move_to(&gpu.device)
                {
                    self.overlay.report(format!("DMX out stopped on the new device: {e}"));
                    self.lights = None;
                }
                (self.egui_state, self.egui_renderer) = egui_parts(&self.window, &gpu, self.config.format);
                self.overlay.tuning = gpu.tuning.summary();
                self.gpu = gpu;
                self.guard.reset();
                self.retry = None;
                self.waiting_since = None;
                self.overlay.report(message);
                true
            }
            Err(e) => {
                if self.retry.is_none() {
                    self.overlay.report(format!("{e}; trying again every second"));
                }
                self.retry = Some((trouble, Instant::now() + std::time::Duration::from_secs(1)));
                false
            }
        }
    }

    /// An event of an output window: edit-mode writes go with the panel's; closing one closes
    /// that output only (the show goes on).
    pub(super) fn output_event(&mut self, event_loop: &ActiveEventLoop, id: WindowId, event: &WindowEvent) {
        let Some(i) = self.outputs.iter().position(|o| o.id() == id) else { return };
        if matches!(event, WindowEvent::CloseRequested) {
            let output = self.outputs.remove(i);
            log::info!("output {} closed; the show goes on", output.number);
            return;
        }
        let node = self.player.instance().scene().outputs.get(self.outputs[i].number - 1).map(|o| o.node);
        if let Some(node) = node {
            let events = self.outputs[i].event(event_loop, event, &self.gpu, self.player.instance(), node);
            self.ui_events.extend(events);
        }
    }

    /// Starts or stops the recording as the panel and OSC asked, in order, and reports takes
    /// whose files are complete.
    fn act_on_record_requests(&mut self) {
        let mut still = Vec::new();
        for mut take in std::mem::take(&mut self.finishing) {
            match take.poll() {
                Some(report) => self.take_finished(report),
                None => still.push(take),
            }
        }
        self.finishing = still;
        let mut requests = std::mem::take(&mut self.hub.record_requests);
        if std::mem::take(&mut self.overlay.record_clicked) {
            requests.push(if self.video.is_some() { RecordRequest::Stop } else { RecordRequest::Start(None) });
        }
        for request in requests {
            match request {
                RecordRequest::Start(name) => self.start_recording(name.as_deref()),
                RecordRequest::Stop => self.stop_recording(),
            }
        }
    }

    /// Starts a take at the window's size and the scene's frame rate; problems go to the overlay.
    /// At most [`MAX_TAKES_PER_MINUTE`] takes start a minute, and none while
    /// [`MAX_TAKES_CLOSING`] are still being closed: a flood of start/stop pairs from the
    /// network writes a few files, not hundreds.
    fn start_recording(&mut self, name: Option<&str>) {
        if let Some(video) = &self.video {
            self.overlay.report(format!("already recording to {}", video.path().display()));
            return;
        }
        let now = Instant::now();
        while self.take_starts.front().is_some_and(|t| now.duration_since(*t) > Duration::from_secs(60)) {
            self.take_starts.pop_front();
        }
        if self.take_starts.len() >= MAX_TAKES_PER_MINUTE || self.finishing.len() >= MAX_TAKES_CLOSING {
            self.overlay.report(format!(
                "take not started: at most {MAX_TAKES_PER_MINUTE} takes a minute, and {MAX_TAKES_CLOSING} closing at once"
            ));
            return;
        }
        self.take_starts.push_back(now);
        let started = take_path(&self.video_base, name).and_then(|path| {
            let settings = crate::offscreen::VideoSettings {
                path,
                size: (self.config.width, self.config.height),
                fps: 1.0 / f64::from(self.player.last_step().dt),
                codec: None,
                quality: None,
                audio: None,
                stream: false,
                pace: false,
            };
            LiveRecorder::start(&self.gpu.device, settings, DEFAULT_IN_FLIGHT).map_err(|e| e.to_string())
        });
        match started {
            Ok(video) => {
                log::info!("recording to {}", video.path().display());
                self.overlay.recording = Some(recording_status(&video, self.player.last_step().dt));
                self.video = Some(video);
            }
            Err(e) => self.overlay.report(format!("cannot record: {e}")),
        }
    }

    /// Stops the take: its last frames are read back here, and ffmpeg closes the file on a
    /// thread of its own ([`Running::take_finished`] says how it went).
    pub(super) fn stop_recording(&mut self) {
        let Some(video) = self.video.take() else { return };
        self.overlay.recording = None;
        self.finishing.push(video.finish_in_background(&self.gpu.device));
    }

    /// Waits for every take still closing (the show is ending: the files must be complete).
    pub(super) fn wait_for_takes(&mut self) {
        for take in std::mem::take(&mut self.finishing) {
            let report = take.wait();
            self.take_finished(report);
        }
    }

    /// Says how a take went.
    fn take_finished(&mut self, report: Result<crate::offscreen::CaptureReport, crate::offscreen::VideoError>) {
        match report {
            Ok(report) => {
                log::info!("{report}");
                // Lost frames are worth a warning; a clean take is just the panel's last line.
                if report.counts.dropped() > 0 {
                    self.overlay.report(report.to_string());
                }
                self.overlay.last_take = Some(report.to_string());
            }
            Err(e) => self.overlay.report(format!("the recording failed: {e}")),
        }
    }

    /// Applies edited shader and scene files; errors go to the overlay, once each.
    /// Queues the chain edits among `events` to be built ahead, and applies one whose build is
    /// ready: recorded, applied, and everything holding parameter positions moved (`events`, the
    /// control maps).
    fn edit_chains(&mut self, events: &mut Vec<crate::scene::ControlEvent>) {
        for message in self.chain_edits.take_from(events) {
            self.overlay.report(message);
        }
        match self.chain_edits.poll(self.player.instance_mut()) {
            None => {}
            Some(Err(message)) => self.overlay.report(message),
            Some(Ok(edit)) => {
                let edit = [edit];
                self.hub.record(self.player.now().frame, &edit, self.player.instance().scene());
                self.player.apply(&edit);
                if let Some(remap) = self.player.instance_mut().take_replaced() {
                    remap.events(events);
                    self.hub.set_scene(self.player.instance().scene(), Some(&remap));
                }
            }
        }
        // A preset's values morph once the chains are as the preset holds them.
        if self.chain_edits.is_idle()
            && let Some(morph) = self.hub.recall_after_chain_edits(self.player.instance().scene())
        {
            events.push(morph);
        }
    }

    fn reload(&mut self) {
        let Some(live) = self.live.as_mut() else { return };
        let size = (self.config.width, self.config.height);
        let report = live.poll(&mut self.player, &self.gpu, size);
        for e in report.errors {
            self.overlay.report(e);
        }
        for f in &report.applied {
            log::info!("reloaded {f}");
        }
        if !report.applied.is_empty() {
            self.chase.cancel();
        }
        if !report.fixed.is_empty() {
            self.overlay.clear_errors();
        }
        if let Some(remap) = &report.remap {
            // Everything that holds parameter positions follows the reload, or lets go.
            let dropped = remap.events(&mut self.ui_events);
            if dropped > 0 {
                log::warn!("{dropped} queued control event(s) dropped: their parameters left the scene");
            }
        }
        if report.scene_changed {
            self.hub.set_scene(self.player.instance().scene(), report.remap.as_ref());
            self.window.set_title(&super::window_title(&self.player.instance().scene().name, ""));
        }
    }

    /// Runs the egui frame and records its draw on top of the scene.
    fn draw_overlay(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        size: (u32, u32),
    ) -> Vec<wgpu::CommandBuffer> {
        let input = self.egui_state.take_egui_input(&self.window);
        let ctx = self.egui_state.egui_ctx().clone();
        let now = self.player.now();
        let (instance, overlay) = (self.player.instance_mut(), &mut self.overlay);
        let mut events = Vec::new();
        let hub = &mut self.hub;
        let (mut lights, queue) = (self.lights.as_mut(), &self.gpu.queue);
        let mut output = ctx.run_ui(input, |ui| {
            let lights = lights.as_mut().map(|l| (&mut **l, queue));
            events = draw_ui(ui, instance, overlay, hub, now, lights);
        });
        self.ui_events.extend(events);
        self.egui_state.handle_platform_output(&self.window, output.platform_output);
        let primitives = ctx.tessellate(output.shapes, output.pixels_per_point);
        let (device, queue) = (&self.gpu.device, &self.gpu.queue);
        // egui asserts that every delta is consumed: drain, never just read.
        for (id, deltas) in output.textures_delta.set.drain() {
            for delta in &deltas {
                self.egui_renderer.update_texture(device, queue, id, delta);
            }
        }
        let screen =
            egui_wgpu::ScreenDescriptor { size_in_pixels: [size.0, size.1], pixels_per_point: output.pixels_per_point };
        let extra = self.egui_renderer.update_buffers(device, queue, encoder, &primitives, &screen);
        {
            let mut pass = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("egui_pass"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: target,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
                    })],
                    ..Default::default()
                })
                .forget_lifetime();
            self.egui_renderer.render(&mut pass, &primitives, &screen);
        }
        for id in output.textures_delta.free.drain() {
            self.egui_renderer.free_texture(&id);
        }
        extra
    }
}
