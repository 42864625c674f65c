//! A binary built without the `midi` feature has no controller ports: starting says so once,
//! and profiles still load and check.

use super::profile::{Control, Profile};

/// The MIDI client name of the controllers' connections.
pub const CLIENT: &str = "indra-controller";

/// The lights a profile's controller should show: (control, message).
pub type Lights = Vec<(Control, [u8; 3])>;

/// No controller ports in this build.
pub struct ControllerPorts;

impl ControllerPorts {
    /// Says that this binary has no MIDI.
    pub fn start(_profiles: Vec<Profile>) -> Result<Self, String> {
        Err(crate::control::midi::NOT_BUILT_IN.into())
    }

    /// Nothing ever arrives.
    pub fn drain(&self) -> Vec<(usize, Vec<u8>)> {
        Vec::new()
    }

    /// Never connected.
    pub fn connected(&self, _i: usize) -> bool {
        false
    }

    /// Lights go nowhere.
    pub fn offer(&self, _i: usize, _lights: Lights) {}

    /// Nothing is counted.
    pub fn counts(&self) -> (u64, u64, u64) {
        (0, 0, 0)
    }
}
