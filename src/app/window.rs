//! The winit application: the window and surface made on `resumed`, events routed to the open
//! window (its input in [`super::input`], its frame in [`super::running`]), and an orderly end.

use std::sync::atomic::{AtomicBool, Ordering};

use std::sync::Arc;
use std::time::Instant;

use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::ActiveEventLoop;
use winit::window::{Window, WindowId};

use super::WindowOptions;
use super::outputs::{OutputWindow, fullscreen_on};
use super::panel::Overlay;
use super::running::{Running, egui_parts};
use crate::assets::Assets;
use crate::control::{ControlHub, ControlOptions, RecordRequest};
use crate::gpu::{Blit, DEFAULT_STALL_TIMEOUT, Gpu, GpuOptions};
use crate::graph::GraphRuntime;
use crate::live::{GpuGuard, LiveReload};
use crate::offscreen::capture::DEFAULT_IN_FLIGHT;
use crate::offscreen::{FrameOutlet, LiveRecorder, PipeWireOut, VideoWriter};
use crate::scene::{Player, Scene, SceneInstance};
use crate::time::FixedClock;

/// The winit handler; creates the window on `resumed`, as winit 0.30 asks.
pub struct WindowApp {
    assets: Assets,
    gpu_options: GpuOptions,
    scene: Option<Scene>,
    options: WindowOptions,
    control: ControlOptions,
    notices: Vec<String>,
    running: Option<Running>,
    failure: Option<String>,
    /// Set by Ctrl-C or SIGTERM: the window closes like a click on its close button, so that
    /// recordings finish and everything is dropped in order.
    interrupted: Arc<AtomicBool>,
}

impl WindowApp {
    /// A handler that will show `scene`, controlled as `control` says; `notices` are shown in
    /// the overlay from the first frame (e.g. a scene file that was broken at start-up).
    pub fn new(
        assets: Assets,
        gpu_options: GpuOptions,
        scene: Scene,
        options: WindowOptions,
        control: ControlOptions,
        notices: Vec<String>,
    ) -> Self {
        Self {
            assets,
            gpu_options,
            scene: Some(scene),
            options,
            control,
            notices,
            running: None,
            failure: None,
            interrupted: Arc::new(AtomicBool::new(false)),
        }
    }

    /// The flag a signal handler sets to close the window cleanly.
    pub fn interrupt_flag(&self) -> Arc<AtomicBool> {
        self.interrupted.clone()
    }

    /// Ok when the window was closed normally, or why it could not run.
    pub fn into_result(self) -> Result<(), String> {
        self.failure.map_or(Ok(()), Err)
    }

    fn start(&mut self, event_loop: &ActiveEventLoop) -> Result<Running, String> {
        let scene = self.scene.take().ok_or("the window was already started")?;
        let attributes = Window::default_attributes()
            .with_title(super::window_title(&scene.name, ""))
            .with_inner_size(winit::dpi::PhysicalSize::new(scene.size.0, scene.size.1));
        let window =
            Arc::new(event_loop.create_window(attributes).map_err(|e| format!("cannot create a window: {e}"))?);
        if self.options.fullscreen {
            window.set_fullscreen(Some(fullscreen_on(event_loop, &window, self.options.monitor)));
        }
        let mut desc = crate::gpu::instance_descriptor(self.gpu_options.backend);
        desc.display = Some(Box::new(event_loop.owned_display_handle()));
        let wgpu_instance = wgpu::Instance::new(desc);
        let surface =
            wgpu_instance.create_surface(window.clone()).map_err(|e| format!("cannot draw into the window: {e}"))?;
        let gpu = pollster::block_on(Gpu::with_instance(wgpu_instance, &self.gpu_options, Some(&surface)))
            .map_err(|e| e.to_string())?;
        let config = super::surface::configure_surface(&surface, &window, &gpu)?;
        log::info!("window {}x{} on {}", config.width, config.height, gpu.adapter_label());
        for (i, m) in event_loop.available_monitors().enumerate() {
            log::info!("monitor {i}: {}", m.name().unwrap_or_default());
        }
        let clock = FixedClock::new(scene.dt, scene.seed);
        let size = (config.width, config.height);
        let mut overlay = Overlay::default();
        overlay.tuning = gpu.tuning.summary();
        log::info!("{}", overlay.tuning);
        for n in self.notices.drain(..) {
            overlay.report(n);
        }
        let mut live =
            if self.options.watch { LiveReload::new(&self.assets).map_err(|e| overlay.report(e)).ok() } else { None };
        // A shader broken on disk at start-up: run the built-in copy, show the error, and pick the
        // file up once it is fixed.
        let instance = match SceneInstance::new(&gpu, &self.assets, scene.clone(), size) {
            Ok(instance) => instance,
            Err(e) => {
                overlay.report(format!("{e} — running the built-in copy until the file is fixed"));
                if let Some(live) = live.as_mut() {
                    live.mark_broken(e.origin.clone().into(), e.to_string());
                }
                SceneInstance::new(&gpu, &self.assets.builtin_only(), scene, size)
                    .map_err(|e| format!("the scene's shaders do not compile: {e}"))?
            }
        };
        let hub = ControlHub::start(&self.control, instance.scene());
        let mut outputs = Vec::new();
        for (i, spec) in instance.scene().outputs.iter().enumerate().filter(|(_, o)| !o.headless) {
            match OutputWindow::open(event_loop, &gpu, &instance.scene().name, i + 1, spec, instance.scene().size) {
                Ok(output) => outputs.push(output),
                Err(e) => overlay.report(e),
            }
        }
        let mut runtime = GraphRuntime::new(&gpu.device, &gpu.queue);
        let mut instance = instance;
        // A show's clips draw a throwaway frame each before the first: no trigger allocates.
        if let Err(e) = instance.warm_up(&mut runtime) {
            overlay.report(format!("preparing the clips: {e}"));
        }
        let blit = Blit::new(&gpu.device);
        let (egui_state, egui_renderer) = egui_parts(&window, &gpu, config.format);
        let mut hub = hub;
        if self.options.record_video.is_some() {
            hub.record_requests.push(RecordRequest::Start(None));
        }
        // Sends start with the show; a receiver, ffmpeg, daemon or NDI runtime that is missing is
        // one message and the show goes on.
        let size = (config.width, config.height);
        let fps = 1.0 / f64::from(clock.now().dt);
        let mut sends = Vec::new();
        let mut start_send = |what: Option<usize>,
                              outlet: Result<Box<dyn FrameOutlet>, String>,
                              started: String,
                              failed: String| match outlet.and_then(|o| {
            LiveRecorder::start_outlet(&gpu.device, size, o, DEFAULT_IN_FLIGHT).map_err(|e| e.to_string())
        }) {
            Ok(send) => {
                log::info!("{started}");
                sends.push((what, send));
            }
            Err(e) => overlay.report(format!("{failed}: {e}")),
        };
        if let Some(url) = &self.options.stream {
            let settings = crate::offscreen::VideoSettings::stream(url, size, fps, false);
            let writer = VideoWriter::start(settings).map(|w| Box::new(w) as Box<dyn FrameOutlet>);
            start_send(
                None,
                writer.map_err(|e| e.to_string()),
                format!("streaming to {url}"),
                format!("cannot stream to {url}"),
            );
        }
        // The output (`--pipewire-out`, `--ndi-out`), then each scene output that names sends.
        let scene_outputs = instance.scene().outputs.iter().enumerate().map(|(i, o)| (Some(i), &o.pipewire, &o.ndi));
        for (what, pipewire, ndi) in
            [(None, &self.options.pipewire_out, &self.options.ndi_out)].into_iter().chain(scene_outputs)
        {
            let image = what.map_or_else(|| "the output".to_string(), |i| format!("output {}", i + 1));
            if let Some(name) = pipewire {
                let source = PipeWireOut::start(name, size, fps, false).map(|p| Box::new(p) as Box<dyn FrameOutlet>);
                let said = format!("offering {image} as the PipeWire source '{name}'");
                start_send(what, source, said, format!("cannot offer PipeWire '{name}'"));
            }
            if let Some(name) = ndi {
                let said = format!("sending {image} as the NDI source '{name}'");
                start_send(
                    what,
                    crate::offscreen::ndi_outlet(name, size, fps, false),
                    said,
                    format!("cannot send NDI '{name}'"),
                );
            }
        }
        let lights =
            self.options.dmx_out.as_ref().and_then(|patch| match crate::dmx::LiveLights::start(&gpu.device, patch) {
                Ok(lights) => {
                    log::info!("sending DMX as {} says", patch.display());
                    Some(lights)
                }
                Err(e) => {
                    overlay.report(format!("no DMX out: {e}"));
                    None
                }
            });
        Ok(Running {
            lights,
            chase: Default::default(),
            window,
            surface,
            config,
            gpu,
            player: Player::new(instance, clock),
            runtime,
            blit,
            last: Instant::now(),
            egui_state,
            egui_renderer,
            overlay,
            hub,
            live,
            chain_edits: Default::default(),
            ui_events: Vec::new(),
            pointer: [0.0, 0.0],
            dragging: false,
            assets: self.assets.clone(),
            guard: GpuGuard::new(DEFAULT_STALL_TIMEOUT),
            retry: None,
            waiting_since: None,
            video: None,
            sends,
            finishing: Vec::new(),
            take_starts: std::collections::VecDeque::new(),
            outputs,
            video_base: self.options.record_video.clone().unwrap_or_else(|| super::DEFAULT_RECORDING.into()),
        })
    }
}

impl ApplicationHandler for WindowApp {
    fn exiting(&mut self, _event_loop: &ActiveEventLoop) {
        // The video is finished before the process ends, so the file is complete.
        if let Some(r) = self.running.as_mut() {
            r.stop_recording();
            r.wait_for_takes();
            // A build still running when the process ends would call the driver as it unloads.
            r.chain_edits.finish();
            r.chase.finish();
            for (_, send) in std::mem::take(&mut r.sends) {
                match send.finish(&r.gpu.device) {
                    Ok(report) => log::info!("send ended: {report}"),
                    Err(e) => log::warn!("a send ended badly: {e}"),
                }
            }
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if self.interrupted.load(Ordering::Relaxed) {
            log::info!("interrupted: closing the window (a recording in progress is finished)");
            event_loop.exit();
        }
    }

    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.running.is_some() {
            return;
        }
        match self.start(event_loop) {
            Ok(running) => {
                running.window.request_redraw();
                self.running = Some(running);
            }
            Err(e) => {
                self.failure = Some(e);
                event_loop.exit();
            }
        }
    }
    fn window_event(&mut self, event_loop: &ActiveEventLoop, id: WindowId, event: WindowEvent) {
        let Some(r) = self.running.as_mut() else {
            return;
        };
        if id != r.window.id() {
            r.output_event(event_loop, id, &event);
            return;
        }
        let consumed = r.egui_state.on_window_event(&r.window, &event).consumed;
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                r.config.width = size.width.max(1);
                r.config.height = size.height.max(1);
                r.surface.configure(&r.gpu.device, &r.config);
            }
            WindowEvent::RedrawRequested => {
                r.frame();
                r.window.request_redraw();
            }
            other => r.input(event_loop, &other, consumed, self.options.monitor),
        }
    }
}
