//! The performer's keys, pointer and clicks on the show's window: function keys, GO, tap tempo,
//! presets, the keys techniques declare, and drags and clicks the panel did not take.

use winit::event::{ElementState, KeyEvent, WindowEvent};
use winit::event_loop::ActiveEventLoop;
use winit::keyboard::{Key, NamedKey};

use super::outputs::fullscreen_on;
use super::running::Running;
use crate::params::ControlEvent;

impl Running {
    /// Acts on one input `event` of the main window; `consumed` when the panel took it.
    /// `monitor` is where F11 goes fullscreen.
    pub(super) fn input(
        &mut self,
        event_loop: &ActiveEventLoop,
        event: &WindowEvent,
        consumed: bool,
        monitor: Option<usize>,
    ) {
        match event {
            WindowEvent::KeyboardInput {
                event: KeyEvent { logical_key: Key::Named(key), state: ElementState::Pressed, repeat: false, .. },
                ..
            } => match key {
                // Function keys work even while a slider has keyboard focus.
                NamedKey::F11 => {
                    let next = match self.window.fullscreen() {
                        Some(_) => None,
                        None => Some(fullscreen_on(event_loop, &self.window, monitor)),
                    };
                    self.window.set_fullscreen(next);
                }
                NamedKey::F1 => self.overlay.panel_visible = !self.overlay.panel_visible,
                NamedKey::F2 => self.ui_events.push(ControlEvent::ResumeTracks),
                // Space is GO in a show with a cue list (not while typing in the panel).
                NamedKey::Space
                    if !consumed && self.player.instance().show().is_some_and(|(s, _)| !s.cues.is_empty()) =>
                {
                    self.ui_events.push(ControlEvent::Show(crate::params::ShowCommand::CueGo));
                }
                // Esc leaves fullscreen and nothing else: a stray key must not end a show.
                NamedKey::Escape if !consumed => self.window.set_fullscreen(None),
                _ => {}
            },
            // Number keys 1–9 recall the presets in name order (morphing as set in the panel).
            WindowEvent::KeyboardInput {
                event: KeyEvent { logical_key: Key::Character(c), state: ElementState::Pressed, repeat: false, .. },
                ..
            } if !consumed => {
                if c.eq_ignore_ascii_case("t") {
                    self.ui_events.extend(self.hub.tap_tempo());
                }
                // Keys the scene's techniques declared (R reset, U undo, C clear, …).
                if let Some(key) = c.chars().next().filter(char::is_ascii_alphabetic) {
                    self.ui_events.extend(self.player.instance().key(key, crate::params::Source::Ui));
                }
                if let Some(i) = c.parse::<usize>().ok().filter(|i| (1..=9).contains(i))
                    && let Some(name) = self.hub.preset_names().get(i - 1).cloned()
                {
                    let seconds = f64::from(self.overlay.morph_seconds);
                    let scene = self.player.instance().scene().clone();
                    self.ui_events.extend(self.hub.recall(&name, seconds, &scene));
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                self.pointer = [position.x as f32, position.y as f32];
                if self.dragging {
                    let view = self.view_position();
                    self.ui_events.extend(self.player.instance().pointer_moved(view, crate::params::Source::Ui));
                }
            }
            // Clicks the panel did not take go to the scene (drawing nodes add/close points,
            // fluids are stirred while the left button is held).
            WindowEvent::MouseInput { state, button, .. } if !consumed || *state == ElementState::Released => {
                let view = self.view_position();
                let source = crate::params::Source::Ui;
                let pressed = *state == ElementState::Pressed;
                if *button == winit::event::MouseButton::Left && self.dragging != pressed {
                    self.dragging = pressed;
                    self.ui_events.extend(self.player.instance().drag(view, pressed, source));
                }
                let primary = match button {
                    winit::event::MouseButton::Left => Some(true),
                    winit::event::MouseButton::Right => Some(false),
                    _ => None,
                };
                if let Some(primary) = primary.filter(|_| pressed) {
                    self.ui_events.extend(self.player.instance().pointer(view, primary, source));
                }
            }
            _ => {}
        }
    }
}
