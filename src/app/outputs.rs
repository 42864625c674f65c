//! The stage outputs' windows: one per `outputs` entry of the scene, each showing its node's
//! texture (warped by its warp node) on its monitor, and an edit mode for lining a corner pin up
//! on the wall. Edits are ordinary parameter writes, so they are recorded, sent back over OSC
//! and saved like any other.
//!
//! Keys in an output window: E edit mode on/off (shows the warp's grid), Tab next corner, arrows
//! nudge the picked corner or mesh point by a pixel (Shift: ten), S saves the warp file, F11
//! fullscreen. In edit mode a click near a corner or a mesh control point picks it and dragging
//! moves it; the mesh's density is the warp node's `mesh_size` parameter.

use std::sync::Arc;

use winit::event::{ElementState, KeyEvent, MouseButton, WindowEvent};
use winit::event_loop::ActiveEventLoop;
use winit::keyboard::{Key, ModifiersState, NamedKey};
use winit::window::{Fullscreen, Window, WindowId};

use crate::gpu::{Blit, BlitTarget, Gpu};
use crate::params::{ControlEvent, ParamValue, ParamWrite, Source};
use crate::scene::{SceneInstance, SceneOutput};

/// What edit mode moves: a corner of the pin, or a control point of the mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Pick {
    Corner(usize),
    MeshPoint(usize),
}

/// How close (in pixels) a click must be to a corner or mesh point to pick it.
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
    picked: Pick,
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
            .with_title(super::window_title(title, &format!(" — output {number}")))
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
        let config = super::surface::configure_surface(&surface, &window, gpu)?;
        log::info!("output {number}: window {}x{}", config.width, config.height);
        Ok(Self {
            number,
            window,
            surface,
            config,
            blit: Blit::new(&gpu.device),
            editing: false,
            picked: Pick::Corner(0),
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
                    return vec![warp.write(self.picked, self.view_position())];
                }
            }
            WindowEvent::MouseInput { state, button: MouseButton::Left, .. } => {
                self.dragging = false;
                if let (ElementState::Pressed, true, Some(warp)) = (state, self.editing, &warp)
                    && let Some(picked) = self.nearest(instance, warp)
                {
                    self.picked = picked;
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
                let next = match self.picked {
                    Pick::Corner(c) => (c + 1) % CORNER_COUNT,
                    Pick::MeshPoint(_) => 0,
                };
                self.picked = Pick::Corner(next);
                log::info!("output {}: corner {next} picked (clockwise from the top left)", self.number);
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
            (true, Some(warp)) => match warp.position(instance, self.picked) {
                Some(at) => vec![warp.write(self.picked, [at[0] + nudge[0], at[1] + nudge[1]])],
                None => Vec::new(),
            },
            _ => Vec::new(),
        }
    }

    /// The pointer in view units (0–1, y up).
    fn view_position(&self) -> [f32; 2] {
        let (w, h) = (self.config.width.max(1) as f32, self.config.height.max(1) as f32);
        [self.pointer[0] / w, 1.0 - self.pointer[1] / h]
    }

    /// The corner or mesh point within [`PICK_RADIUS`] pixels of the pointer, nearest first
    /// (a corner wins a tie: the pin is what one lines up first).
    fn nearest(&self, instance: &SceneInstance, warp: &WarpControls) -> Option<Pick> {
        let (w, h) = (self.config.width as f32, self.config.height as f32);
        let pointer = self.view_position();
        let mesh_points = instance.handles(warp.node).len();
        let picks = (0..CORNER_COUNT).map(Pick::Corner).chain((0..mesh_points).map(Pick::MeshPoint));
        picks
            .filter_map(|pick| {
                let at = warp.position(instance, pick)?;
                let (dx, dy) = ((at[0] - pointer[0]) * w, (at[1] - pointer[1]) * h);
                Some((pick, (dx * dx + dy * dy).sqrt()))
            })
            .filter(|&(_, d)| d <= PICK_RADIUS)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(pick, _)| pick)
    }
}

/// A corner pin's corners, clockwise from the top left (see [`crate::techniques::StageEdit`]).
const CORNER_COUNT: usize = 4;

/// The parameters of an output's warp node that edit mode writes.
struct WarpControls {
    node: usize,
    corners: [usize; 4],
    mesh_point: usize,
    grid: usize,
    save: usize,
}

impl WarpControls {
    /// Those of node `node`, if its technique maps outputs onto walls.
    fn of(instance: &SceneInstance, node: usize) -> Option<Self> {
        let scene_node = instance.scene().nodes.get(node)?;
        let edit = scene_node.technique.stage?;
        let index = |name: &str| scene_node.params.index(name);
        let [a, b, c, d] = edit.corners.map(index);
        Some(Self {
            node,
            corners: [a?, b?, c?, d?],
            mesh_point: index(edit.mesh_point)?,
            grid: index(edit.grid)?,
            save: index(edit.save)?,
        })
    }

    /// Where `pick` is now, in view units.
    fn position(&self, instance: &SceneInstance, pick: Pick) -> Option<[f32; 2]> {
        match pick {
            Pick::Corner(c) => match instance.params(self.node).value_at(self.corners[c]) {
                ParamValue::Vec2(v) => Some(v),
                _ => None,
            },
            Pick::MeshPoint(i) => instance.handles(self.node).get(i).copied(),
        }
    }

    fn set(&self, param: usize, value: ParamValue) -> ControlEvent {
        ControlEvent::Write(ParamWrite { node: self.node, param, component: None, value, source: Source::Ui })
    }

    /// Moves `pick` to `at` (view units).
    fn write(&self, pick: Pick, at: [f32; 2]) -> ControlEvent {
        match pick {
            Pick::Corner(c) => self.set(self.corners[c], ParamValue::Vec2(at)),
            Pick::MeshPoint(i) => self.set(self.mesh_point, ParamValue::Vec3([i as f32, at[0], at[1]])),
        }
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
