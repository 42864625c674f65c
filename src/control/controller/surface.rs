//! What a controller's presses and fader moves do to a show, and which light each of its pads
//! and buttons shows: pure functions of the profile, the page, and the show's state, so that
//! they are tested without a port.

use super::profile::{Action, Control, FaderTarget, Light, Profile, Takeover};
use crate::control::midi::MidiEvent;
use crate::params::{ControlEvent, ParamValue, ParamWrite, ShowCommand, Source};
use crate::scene::SceneView;
use crate::scene::show::Show;

/// A fader's takeover state.
#[derive(Clone, Copy, Debug, Default)]
struct FaderState {
    /// Its last position 0–1.
    last: Option<f32>,
    /// The parameter position it last wrote (it holds the parameter while that stays so).
    wrote: Option<f32>,
}

/// One connected controller's state: its page of the grid, shift, and fader takeover.
#[derive(Debug)]
pub struct Surface {
    /// The profile it follows.
    pub profile: Profile,
    /// The grid's page: (clip page, layer page).
    pub page: (usize, usize),
    shift: bool,
    faders: Vec<FaderState>,
}

/// What one event asks for beyond control events.
#[derive(Debug, Default, PartialEq)]
pub struct Handled {
    /// Control events to apply.
    pub events: Vec<ControlEvent>,
    /// A tap of tap tempo.
    pub tap: bool,
    /// Whether the profile knew the control (otherwise it goes to learned mappings).
    pub used: bool,
}

/// The state a clip pad shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PadState {
    /// No clip.
    Empty,
    /// A clip, not playing.
    Loaded,
    /// The clip its layer plays.
    Playing,
    /// Waiting for its beat or bar, in the blink's lit half.
    Queued,
    /// A clip that could not be loaded.
    Broken,
}

impl Surface {
    /// A surface on page (0, 0).
    pub fn new(profile: Profile) -> Self {
        let faders = vec![FaderState::default(); profile.faders.len()];
        Self { profile, page: (0, 0), shift: false, faders }
    }

    /// What `event` does to the show `view` plays.
    pub fn handle(&mut self, event: MidiEvent, view: &SceneView<'_>) -> Handled {
        let (control, value) = match event {
            MidiEvent::NoteOn { channel, note, velocity } => (Control::Note(channel, note), Some(velocity)),
            MidiEvent::NoteOff { channel, note } => (Control::Note(channel, note), Some(0)),
            MidiEvent::Cc { channel, controller, value } => (Control::Cc(channel, controller), Some(value)),
            _ => (Control::Note(0, 0), None),
        };
        let Some(value) = value else { return Handled::default() };
        let mut out = Handled::default();
        if self.profile.shift == Some(control) {
            self.shift = value > 0;
            out.used = true;
            return out;
        }
        if let Some(i) = self.profile.faders.iter().position(|f| f.control == control) {
            out.used = true;
            out.events.extend(self.fader(i, f32::from(value) / 127.0, view));
            return out;
        }
        let pressed = value > 0;
        let button = self.profile.buttons.iter().find(|b| b.control == control && b.shifted == self.shift).copied();
        if let Some(button) = button {
            out.used = true;
            if pressed {
                self.press(button.action, view, &mut out);
            }
            return out;
        }
        if let Some((column, row, _)) = self.profile.grid.pads().find(|(_, _, pad)| *pad == control) {
            out.used = true;
            if pressed
                && let Some((show, _)) = view.show
                && let Some((layer, clip)) = self.clip_at(show, column, row)
            {
                out.events.push(ControlEvent::Show(ShowCommand::Trigger { layer, clip: Some(clip) }));
            }
        }
        out
    }

    /// The layer and clip (within the layer) under pad (`column`, `row`) on this page.
    fn clip_at(&self, show: &Show, column: u8, row: u8) -> Option<(usize, usize)> {
        let (layer, clip) = self.cell(column, row);
        show.layers.get(layer).filter(|l| clip < l.clips.len()).map(|_| (layer, clip))
    }

    /// The layer and clip index (within the layer) pad (`column`, `row`) stands for.
    fn cell(&self, column: u8, row: u8) -> (usize, usize) {
        (self.paged_row(row + 1), self.paged_column(column + 1))
    }

    /// The show column of the page's `n`-th column (from 1).
    fn paged_column(&self, n: u8) -> usize {
        self.page.0 * usize::from(self.profile.grid.columns) + usize::from(n.max(1) - 1)
    }

    /// The show layer of the page's `n`-th row (from 1, the bottom).
    fn paged_row(&self, n: u8) -> usize {
        self.page.1 * usize::from(self.profile.grid.rows) + usize::from(n.max(1) - 1)
    }

    /// Pages there are: (clip pages, layer pages).
    fn pages(&self, show: Option<&Show>) -> (usize, usize) {
        let Some(show) = show else { return (1, 1) };
        let longest = show.layers.iter().map(|l| l.clips.len()).max().unwrap_or(0);
        let grid = &self.profile.grid;
        (longest.div_ceil(usize::from(grid.columns)).max(1), show.layers.len().div_ceil(usize::from(grid.rows)).max(1))
    }

    fn press(&mut self, action: Action, view: &SceneView<'_>, out: &mut Handled) {
        let show = view.show.map(|(show, _)| show);
        let pages = self.pages(show);
        let mut command = |c: ShowCommand| out.events.push(ControlEvent::Show(c));
        match action {
            Action::Go if show.is_some_and(|s| !s.cues.is_empty()) => command(ShowCommand::CueGo),
            Action::Back if show.is_some_and(|s| !s.cues.is_empty()) => command(ShowCommand::CueBack),
            Action::Tap => out.tap = true,
            Action::PageLeft => self.page.0 = self.page.0.saturating_sub(1),
            Action::PageRight => self.page.0 = (self.page.0 + 1).min(pages.0 - 1),
            Action::PageDown => self.page.1 = self.page.1.saturating_sub(1),
            Action::PageUp => self.page.1 = (self.page.1 + 1).min(pages.1 - 1),
            Action::Column(n) => {
                let column = self.paged_column(n);
                if show.is_some_and(|s| column < s.columns.len()) {
                    command(ShowCommand::Column(column));
                }
            }
            Action::Stop(n) => {
                let layer = self.paged_row(n);
                if show.is_some_and(|s| layer < s.layers.len()) {
                    command(ShowCommand::Trigger { layer, clip: None });
                }
            }
            Action::BypassLayer(..) | Action::BypassMaster(_) => {
                if let Some((node, param, on)) = bypass_of(action, view) {
                    out.events.push(write(node, param, ParamValue::Bool(on)));
                }
            }
            Action::Blend(n) => {
                let node = show.and_then(|s| s.layers.get(usize::from(n.max(1) - 1))).map(|l| l.node);
                if let Some(node) = node
                    && let Some(param) = view.params(node).index("blend")
                {
                    let options = view.params(node).decls()[param].options.len().max(1) as u32;
                    let ParamValue::Enum(now) = view.params(node).target_at(param) else { return };
                    out.events.push(write(node, param, ParamValue::Enum((now + 1) % options)));
                }
            }
            Action::Go | Action::Back => {}
        }
    }

    /// Fader `i` moved to `position` (0–1): the write, if takeover lets it through.
    fn fader(&mut self, i: usize, position: f32, view: &SceneView<'_>) -> Option<ControlEvent> {
        let (node, param) = fader_target(self.profile.faders[i].target, view)?;
        let decl = &view.params(node).decls()[param];
        let (low, high) = decl.range.unwrap_or((0.0, 1.0));
        let ParamValue::Float(now) = view.params(node).target_at(param) else { return None };
        let now = if high > low { (now - low) / (high - low) } else { 0.0 };
        let state = &mut self.faders[i];
        let last = state.last.replace(position);
        let holds = state.wrote.is_some_and(|w| (w - now).abs() < 1e-4);
        let crossed = last.is_some_and(|l| (l - now) * (position - now) <= 0.0);
        let takes = match self.profile.takeover {
            Takeover::Jump => true,
            Takeover::Pickup => holds || crossed || (position - now).abs() <= 1.0 / 127.0,
        };
        if !takes {
            state.wrote = None;
            return None;
        }
        state.wrote = Some(position);
        Some(write(node, param, ParamValue::Float(low + position * (high - low))))
    }

    /// The state of pad (`column`, `row`) now (a queued clip blinks: lit the first half of
    /// each beat).
    pub fn pad_state(&self, view: &SceneView<'_>, column: u8, row: u8) -> PadState {
        let Some((show, state)) = view.show else { return PadState::Empty };
        let Some((layer, clip)) = self.clip_at(show, column, row) else { return PadState::Empty };
        let global = show.layers[layer].clips[clip];
        if show.clips[global].nodes.is_empty() {
            return PadState::Broken;
        }
        // The step's own beat, so that the blink and the start it waits for agree to the frame.
        if state.queued(layer) == Some(Some(global)) && state.beats().rem_euclid(1.0) < 0.5 {
            return PadState::Queued;
        }
        if state.playing(layer) == Some(global) { PadState::Playing } else { PadState::Loaded }
    }

    /// Every light the controller should show now: each pad's, then each lit button's.
    pub fn lights(&self, view: &SceneView<'_>) -> Vec<(Control, Light)> {
        let colours = &self.profile.colours;
        let mut lights: Vec<(Control, Light)> = (self.profile.grid.pads())
            .map(|(column, row, pad)| {
                let light = match self.pad_state(view, column, row) {
                    PadState::Empty => colours.empty,
                    PadState::Loaded => colours.loaded,
                    PadState::Playing => colours.playing,
                    PadState::Queued => colours.queued,
                    PadState::Broken => colours.broken,
                };
                (pad, light)
            })
            .collect();
        for button in self.profile.buttons.iter().filter(|b| !b.shifted) {
            let (Some(on), Some(off)) = (button.on, button.off) else { continue };
            lights.push((button.control, if self.button_lit(button.action, view) { on } else { off }));
        }
        lights
    }

    /// Whether a button's light is on: what it would do can be done, or what it toggles is on.
    fn button_lit(&self, action: Action, view: &SceneView<'_>) -> bool {
        let show = view.show.map(|(show, _)| show);
        let state = view.show.map(|(_, state)| state);
        let pages = self.pages(show);
        match action {
            Action::Go => show.is_some_and(|s| !s.cues.is_empty()),
            Action::Back => state.and_then(|s| s.cue()).is_some_and(|c| c > 0),
            Action::Tap => view.tempo.beats.rem_euclid(1.0) < 0.25,
            Action::PageLeft => self.page.0 > 0,
            Action::PageRight => self.page.0 + 1 < pages.0,
            Action::PageDown => self.page.1 > 0,
            Action::PageUp => self.page.1 + 1 < pages.1,
            Action::Column(n) => show.is_some_and(|s| self.paged_column(n) < s.columns.len()),
            Action::Stop(n) => state.is_some_and(|s| s.playing(self.paged_row(n)).is_some()),
            Action::BypassLayer(..) | Action::BypassMaster(_) => bypass_of(action, view).is_some_and(|(.., on)| on),
            Action::Blend(_) => false,
        }
    }
}

/// A controller's parameter write.
fn write(node: usize, param: usize, value: ParamValue) -> ControlEvent {
    ControlEvent::Write(ParamWrite { node, param, component: None, value, source: Source::Midi })
}

/// The node and parameter a fader moves, if the show has them.
fn fader_target(target: FaderTarget, view: &SceneView<'_>) -> Option<(usize, usize)> {
    let (show, _) = view.show?;
    let (node, name) = match target {
        FaderTarget::Layer(n) => (show.layers.get(usize::from(n.max(1) - 1))?.node, "opacity"),
        FaderTarget::Master => (show.master, "level"),
    };
    Some((node, view.params(node).index(name)?))
}

/// The effect a bypass button toggles: its node, its `bypass` parameter, and whether the
/// effect is on now (not bypassed) — which is also the `bypass` value a press writes.
fn bypass_of(action: Action, view: &SceneView<'_>) -> Option<(usize, usize, bool)> {
    let (show, _) = view.show?;
    let node = match action {
        Action::BypassLayer(layer, k) => {
            *show.layers.get(usize::from(layer.max(1) - 1))?.effects.get(usize::from(k.max(1) - 1))?
        }
        Action::BypassMaster(k) => *show.master_effects.get(usize::from(k.max(1) - 1))?,
        _ => return None,
    };
    let param = view.params(node).index(crate::scene::show::effects::BYPASS)?;
    let bypassed = matches!(view.params(node).target_at(param), ParamValue::Bool(true));
    Some((node, param, !bypassed))
}
