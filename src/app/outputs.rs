//! The stage outputs' windows: one per `outputs` entry of the scene, each showing its node's
//! texture (warped by its warp node) on its monitor, and an edit mode for lining a corner pin up
//! on the wall. Edits are ordinary parameter writes, so they are recorded, sent back over OSC
//! and saved like any other.
//!
//! Keys in an output window: E edit mode on/off (shows the warp's grid), Tab next corner, arrows
//! nudge the corner by a pixel (Shift: ten), S saves the warp file, F11 fullscreen. In edit mode
//! a click near a corner picks it and dragging moves it.

use std::sync::Arc;

use winit::event::{ElementState, KeyEvent, MouseButton, WindowEvent};
use winit::event_loop::ActiveEventLoop;
use winit::keyboard::{Key, ModifiersState, NamedKey};
use winit::window::{Fullscreen, Window, WindowId};

use crate::gpu::{Blit, BlitTarget, Gpu};
use crate::params::{ControlEvent, ParamValue, ParamWrite, Source};
use crate::scene::{SceneInstance, SceneOutput};
use crate::techniques::warp::CORNERS;

/// How close (in pixels) a click must be to a corner to pick it.
const PICK_RADIUS: f32 = 40.0;

/// One output window.
pub struct OutputWindow {
    /// Its number in the scene's `outputs` (from 1).
    pub number: usize,
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    /// Its own display encode: the blit's size uniform is per target.
    blit: Blit,
    /// Edit mode, the picked corner, and whether it is being dragged.
    editing: bool,
    corner: usize,
    dragging: bool,
    pointer: [f32; 2],
    modifiers: ModifiersState,
}

impl OutputWindow {
    /// Opens output `number` (`spec`) of the scene called `title`, `size` pixels unless
    /// fullscreen, on `gpu`'s adapter.
    pub fn open(
        event_loop: &ActiveEventLoop,
        gpu: &Gpu,
        title: &str,
        number: usize,
        spec: &SceneOutput,
        size: (u32, u32),
    ) -> Result<Self, String> {
        let attributes = Window::default_attributes()
            .with_title(format!("indra — {title} — output {number}"))
            .with_inner_size(winit::dpi::PhysicalSize::new(size.0, size.1));
        let window =
            Arc::new(event_loop.create_window(attributes).map_err(|e| format!("cannot open output {number}: {e}"))?);
        if spec.fullscreen {
            window.set_fullscreen(Some(fullscreen_on(event_loop, &window, spec.monitor)));
        }
        let surface = gpu
            .instance
            .create_surface(window.clone())
            .map_err(|e| format!("cannot draw into output {number}'s window: {e}"))?;
        let caps = surface.get_capabilities(&gpu.adapter);
        let (format, alpha_mode) = super::surface::choose_surface_format(&caps, &gpu.adapter_label())?;
        let inner = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            color_space: wgpu::SurfaceColorSpace::Auto,
            width: inner.width.max(1),
            height: inner.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode,
            view_formats: vec![],
        };
        surface.configure(&gpu.device, &config);
        log::info!("output {number}: window {}x{}", config.width, config.height);
        Ok(Self {
            number,
            window,
            surface,
            config,
            blit: Blit::new(&gpu.device),
            editing: false,
            corner: 0,
            dragging: false,
            pointer: [0.0, 0.0],
            modifiers: ModifiersState::empty(),
        })
    }

    /// The winit id of its window.
    pub fn id(&self) -> WindowId {
        self.window.id()
    }

    /// Configures the surface for `gpu` again (after the device was replaced).
    pub fn reconfigure(&mut self, gpu: &Gpu) {
        self.blit = Blit::new(&gpu.device);
        self.surface.configure(&gpu.device, &self.config);
    }

    /// Records the display encode of `source` into this window's next surface texture; the
    /// caller submits `encoder` and then presents what this returns.
    pub fn draw(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        source: &wgpu::TextureView,
    ) -> Option<wgpu::SurfaceTexture> {
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f) | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&gpu.device, &self.config);
                return None;
            }
            _ => return None,
        };
        let view = frame.texture.create_view(&Default::default());
        let target =
            BlitTarget { view: &view, format: self.config.format, size: (self.config.width, self.config.height) };
        self.blit.record(&gpu.device, &gpu.queue, encoder, source, target);
        Some(frame)
    }

    /// Shows a drawn frame.
    pub fn present(&self, frame: wgpu::SurfaceTexture, queue: &wgpu::Queue) {
        self.window.pre_present_notify();
        queue.present(frame);
    }

    /// Handles an event of this window; returns the parameter writes it makes (edit mode) for
    /// the output's node `node` of `instance`.
    pub fn event(
        &mut self,
        event_loop: &ActiveEventLoop,
        event: &WindowEvent,
        gpu: &Gpu,
        instance: &SceneInstance,
        node: usize,
    ) -> Vec<ControlEvent> {
        let warp = WarpControls::of(instance, node);
        match event {
            WindowEvent::Resized(size) => {
                self.config.width = size.width.max(1);
                self.config.height = size.height.max(1);
                self.surface.configure(&gpu.device, &self.config);
            }
            WindowEvent::ModifiersChanged(m) => self.modifiers = m.state(),
            WindowEvent::KeyboardInput {
                event: KeyEvent { logical_key, state: ElementState::Pressed, .. }, ..
            } => {
                return self.key(event_loop, logical_key, instance, warp.as_ref());
            }
            WindowEvent::CursorMoved { position, .. } => {
                self.pointer = [position.x as f32, position.y as f32];
                if let (true, Some(warp)) = (self.dragging, &warp) {
                    return vec![warp.write(self.corner, self.view_position())];
                }
            }
            WindowEvent::MouseInput { state, button: MouseButton::Left, .. } => {
                self.dragging = false;
                if let (ElementState::Pressed, true, Some(warp)) = (state, self.editing, &warp)
                    && let Some(corner) = self.nearest_corner(instance, warp)
                {
                    self.corner = corner;
                    self.dragging = true;
                }
            }
            _ => {}
        }
        Vec::new()
    }

    fn key(
        &mut self,
        event_loop: &ActiveEventLoop,
        key: &Key,
        instance: &SceneInstance,
        warp: Option<&WarpControls>,
    ) -> Vec<ControlEvent> {
        let step = if self.modifiers.shift_key() { 10.0 } else { 1.0 };
        let (w, h) = (self.config.width.max(1) as f32, self.config.height.max(1) as f32);
        let nudge = match key {
            Key::Named(NamedKey::F11) => {
                let next = match self.window.fullscreen() {
                    Some(_) => None,
                    None => Some(fullscreen_on(event_loop, &self.window, None)),
                };
                self.window.set_fullscreen(next);
                return Vec::new();
            }
            Key::Named(NamedKey::Tab) => {
                self.corner = (self.corner + 1) % CORNERS.len();
                log::info!("output {}: corner {} ({}) picked", self.number, self.corner, CORNERS[self.corner]);
                return Vec::new();
            }
            Key::Named(NamedKey::ArrowLeft) => [-step / w, 0.0],
            Key::Named(NamedKey::ArrowRight) => [step / w, 0.0],
            Key::Named(NamedKey::ArrowUp) => [0.0, step / h],
            Key::Named(NamedKey::ArrowDown) => [0.0, -step / h],
            Key::Character(c) if c.eq_ignore_ascii_case("e") => {
                self.editing = !self.editing;
                return warp.map(|w| w.set(w.grid, ParamValue::Bool(self.editing))).into_iter().collect();
            }
            Key::Character(c) if c.eq_ignore_ascii_case("s") => {
                return warp.map(|w| w.set(w.save, ParamValue::Trigger(true))).into_iter().collect();
            }
            _ => return Vec::new(),
        };
        match (self.editing, warp) {
            (true, Some(warp)) => {
                let at = warp.position(instance, self.corner);
                vec![warp.write(self.corner, [at[0] + nudge[0], at[1] + nudge[1]])]
            }
            _ => Vec::new(),
        }
    }

    /// The pointer in view units (0–1, y up).
    fn view_position(&self) -> [f32; 2] {
        let (w, h) = (self.config.width.max(1) as f32, self.config.height.max(1) as f32);
        [self.pointer[0] / w, 1.0 - self.pointer[1] / h]
    }

    /// The corner within [`PICK_RADIUS`] pixels of the pointer, nearest first.
    fn nearest_corner(&self, instance: &SceneInstance, warp: &WarpControls) -> Option<usize> {
        let (w, h) = (self.config.width as f32, self.config.height as f32);
        let pointer = self.view_position();
        (0..CORNERS.len())
            .map(|c| {
                let at = warp.position(instance, c);
                let (dx, dy) = ((at[0] - pointer[0]) * w, (at[1] - pointer[1]) * h);
                (c, (dx * dx + dy * dy).sqrt())
            })
            .filter(|&(_, d)| d <= PICK_RADIUS)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(c, _)| c)
    }
}

/// The parameters of an output's warp node that edit mode writes.
struct WarpControls {
    node: usize,
    corners: [usize; 4],
    grid: usize,
    save: usize,
}

impl WarpControls {
    /// Those of node `node`, if it is a warp node.
    fn of(instance: &SceneInstance, node: usize) -> Option<Self> {
        let scene_node = instance.scene().nodes.get(node)?;
        if scene_node.technique.name != crate::techniques::warp::INFO.name {
            return None;
        }
        let index = |name: &str| scene_node.params.index(name);
        let [a, b, c, d] = CORNERS.map(index);
        Some(Self { node, corners: [a?, b?, c?, d?], grid: index("grid")?, save: index("save")? })
    }

    fn position(&self, instance: &SceneInstance, corner: usize) -> [f32; 2] {
        match instance.params(self.node).value_at(self.corners[corner]) {
            ParamValue::Vec2(v) => v,
            _ => [0.0, 0.0],
        }
    }

    fn set(&self, param: usize, value: ParamValue) -> ControlEvent {
        ControlEvent::Write(ParamWrite { node: self.node, param, component: None, value, source: Source::Ui })
    }

    fn write(&self, corner: usize, at: [f32; 2]) -> ControlEvent {
        self.set(self.corners[corner], ParamValue::Vec2(at))
    }
}

/// Borderless fullscreen on monitor `monitor` (or the window's own).
pub fn fullscreen_on(event_loop: &ActiveEventLoop, window: &Window, monitor: Option<usize>) -> Fullscreen {
    let chosen = monitor.and_then(|i| event_loop.available_monitors().nth(i));
    if monitor.is_some() && chosen.is_none() {
        log::warn!("no monitor {}; using the window's own", monitor.unwrap_or_default());
    }
    Fullscreen::Borderless(chosen.or_else(|| window.current_monitor()))
}
