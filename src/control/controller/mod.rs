//! Pad controllers that answer back: a profile per device (bundled for the APC40 mkII, APC mini
//! mk2, Launchpad X and Launchpad Mini mk3, or the performer's own) maps its clip grid, faders
//! and buttons onto the show, and lights its pads with the show's state. Profiles are chosen
//! by port name, or by `--controller`; a controller may be plugged in, out and in again while
//! the show runs.

#[cfg(feature = "midi")]
pub mod port;
#[cfg(not(feature = "midi"))]
#[path = "port_none.rs"]
pub mod port;
pub mod profile;
pub mod surface;

use std::path::Path;

use self::surface::Surface;
use super::midi::{MidiEvent, MidiParser};
use crate::params::ControlEvent;
use crate::scene::SceneView;

/// The controllers of a running show.
pub struct Controllers {
    surfaces: Vec<Surface>,
    parsers: Vec<MidiParser>,
    ports: port::ControllerPorts,
}

/// What controllers asked for since the last frame.
#[derive(Debug, Default)]
pub struct Polled {
    /// Control events.
    pub events: Vec<ControlEvent>,
    /// Taps of tap tempo.
    pub taps: usize,
    /// Events of controls no profile maps (for learned mappings).
    pub unused: Vec<MidiEvent>,
}

impl Controllers {
    /// Watches for the controllers `choice` names (see [`profile::choose`]).
    pub fn start(choice: Option<&str>, user_dir: &Path) -> Result<Self, String> {
        let profiles = profile::choose(choice, user_dir)?;
        let parsers = profiles.iter().map(|_| MidiParser::default()).collect();
        let surfaces = profiles.iter().cloned().map(Surface::new).collect();
        Ok(Self { surfaces, parsers, ports: port::ControllerPorts::start(profiles)? })
    }

    /// Whether a profile serves port `name` (other MIDI input leaves such ports alone).
    pub fn serves(&self, name: &str) -> bool {
        self.surfaces.iter().any(|s| s.profile.serves(name))
    }

    /// What the controllers sent since the last call, against the show `view` plays.
    pub fn poll(&mut self, view: &SceneView<'_>) -> Polled {
        let mut polled = Polled::default();
        for (i, bytes) in self.ports.drain() {
            let (Some(surface), Some(parser)) = (self.surfaces.get_mut(i), self.parsers.get_mut(i)) else { continue };
            for event in parser.feed(&bytes) {
                let handled = surface.handle(event, view);
                polled.events.extend(handled.events);
                polled.taps += usize::from(handled.tap);
                if !handled.used {
                    polled.unused.push(event);
                }
            }
        }
        polled
    }

    /// Offers each connected controller the lights of the show's state now (the port thread
    /// sends those that changed).
    pub fn show(&self, view: &SceneView<'_>) {
        for (i, surface) in self.surfaces.iter().enumerate().filter(|(i, _)| self.ports.connected(*i)) {
            let lights = surface.lights(view).into_iter().map(|(c, light)| (c, c.light_message(light))).collect();
            self.ports.offer(i, lights);
        }
    }

    /// The connected controllers and their pages, for the status line.
    pub fn status(&self) -> Option<String> {
        let connected: Vec<String> = (self.surfaces.iter().enumerate())
            .filter(|(i, _)| self.ports.connected(*i))
            .map(|(_, s)| format!("{} (page {},{})", s.profile.name, s.page.0 + 1, s.page.1 + 1))
            .collect();
        let (sent, missed, dropped) = self.ports.counts();
        (!connected.is_empty()).then(|| {
            format!("controllers: {} · {sent} lights sent, {missed} skipped, {dropped} dropped", connected.join(", "))
        })
    }
}

#[cfg(test)]
mod tests;
