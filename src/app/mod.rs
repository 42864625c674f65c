//! The windowed runtime: a winit event loop, a wgpu surface, the scene drawn full-window on a
//! fixed-step clock, and an egui overlay with the generated parameter panel, pass timings and
//! errors. F11 toggles fullscreen, Esc leaves it (never the show), F1 hides the panel, F2 gives
//! taken-over parameters back to their tracks, 1–9 recall presets.

mod chain_edits;
mod chase;
mod effects_panel;
mod input;
mod lane_view;
mod lights_panel;
mod outputs;
mod panel;
mod param_widget;
mod running;
mod show_panel;
mod surface;
mod web_panel;
mod window;

use crate::assets::Assets;
use crate::control::ControlOptions;
use crate::gpu::GpuOptions;
use crate::scene::Scene;

/// How the window opens.
#[derive(Clone, Debug)]
pub struct WindowOptions {
    /// Start in borderless fullscreen.
    pub fullscreen: bool,
    /// Monitor index to go fullscreen on (default: the window's current one).
    pub monitor: Option<usize>,
    /// Watch `shaders/` and `scenes/` and reload edits.
    pub watch: bool,
    /// Record the show to this video from the start; also where later takes go (panel, OSC).
    pub record_video: Option<std::path::PathBuf>,
    /// Send the output to this network stream from the start (see `run --stream`).
    pub stream: Option<String>,
    /// Send the output as this NDI source from the start (see `run --ndi-out`).
    pub ndi_out: Option<String>,
    /// Offer the output as this PipeWire video source from the start (see `run --pipewire-out`).
    pub pipewire_out: Option<String>,
    /// Send the fixtures of this DMX patch the output's pixels (see `run --dmx-out`).
    pub dmx_out: Option<std::path::PathBuf>,
}

/// A window title showing `scene` (cut to a scene name's greatest length: the display server
/// refuses long titles, and a refusal used to panic the window).
pub(crate) fn window_title(scene: &str, suffix: &str) -> String {
    let name: String = scene.chars().take(crate::scene::MAX_NAME_CHARS).collect();
    format!("indra — {name}{suffix}")
}

/// Where takes go when `--record-video` named no file.
pub const DEFAULT_RECORDING: &str = "indra-recording.mp4";

/// Opens `scene` in a window and runs until the window is closed.
pub fn run(
    assets: Assets,
    gpu: GpuOptions,
    scene: Scene,
    options: WindowOptions,
    control: ControlOptions,
    notices: Vec<String>,
) -> Result<(), String> {
    let event_loop = winit::event_loop::EventLoop::new().map_err(|e| {
        format!(
            "cannot open a window ({e}); on a machine without a display use `indra render`, or run under `xvfb-run`"
        )
    })?;
    let mut app = window::WindowApp::new(assets, gpu, scene, options, control, notices);
    // Ctrl-C / SIGTERM close the window the normal way (a second one ends the process at once).
    let interrupted = app.interrupt_flag();
    let handler = ctrlc::set_handler(move || {
        if interrupted.swap(true, std::sync::atomic::Ordering::SeqCst) {
            std::process::exit(130);
        }
    });
    if let Err(e) = handler {
        log::warn!("Ctrl-C will end the process without closing cleanly: {e}");
    }
    event_loop.run_app(&mut app).map_err(|e| format!("the window's event loop failed: {e}"))?;
    app.into_result()
}
