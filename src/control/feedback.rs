//! OSC out: after each frame, every parameter whose value changed (from any source — UI, MIDI,
//! tracks, presets) is sent to the controller, so its faders follow. [`ParamChanges`] finds the
//! changes once per frame for every receiver (this, and OSCQuery's LISTEN).

use std::collections::HashMap;
use std::net::{SocketAddr, ToSocketAddrs, UdpSocket};

use rosc::{OscMessage, OscPacket, OscType};

use super::address::param_address;
use crate::params::ParamValue;
use crate::scene::SceneView;

/// Which parameter values changed since they were last seen, as the OSC messages that carry
/// them (triggers have no value and never appear).
#[derive(Default)]
pub struct ParamChanges {
    last: HashMap<(usize, usize), ParamValue>,
}

impl ParamChanges {
    /// Forgets what was seen (after a scene change: everything counts as changed).
    pub fn reset(&mut self) {
        self.last.clear();
    }

    /// One message per parameter whose value differs from the last one seen.
    pub fn collect(&mut self, instance: SceneView<'_>) -> Vec<OscMessage> {
        let mut messages = Vec::new();
        for (n, node) in instance.scene.nodes.iter().enumerate() {
            let params = instance.params(n);
            for (p, decl) in params.decls().iter().enumerate() {
                let value = params.target_at(p);
                if matches!(value, ParamValue::Trigger(_)) || self.last.get(&(n, p)) == Some(&value) {
                    continue;
                }
                let args = match &value {
                    ParamValue::Int(i) => vec![OscType::Int(*i)],
                    ParamValue::Bool(b) => vec![OscType::Bool(*b)],
                    ParamValue::Enum(_) => vec![OscType::String(decl.format(&value))],
                    ParamValue::Text(t) => vec![OscType::String(t.as_str().to_string())],
                    other => other.components().into_iter().map(OscType::Float).collect(),
                };
                messages.push(OscMessage { addr: param_address(&node.id, &decl.name), args });
                self.last.insert((n, p), value);
            }
        }
        messages
    }
}

/// Sends parameter changes to one OSC destination.
pub struct OscFeedback {
    socket: UdpSocket,
    target: SocketAddr,
}

impl OscFeedback {
    /// Sends to `target` (`host:port`).
    pub fn connect(target: &str) -> Result<Self, String> {
        let target = target
            .to_socket_addrs()
            .map_err(|e| format!("cannot resolve OSC output {target}: {e}"))?
            .next()
            .ok_or_else(|| format!("OSC output {target} resolves to no address"))?;
        let bind = if target.is_ipv4() { "0.0.0.0:0" } else { "[::]:0" };
        let socket = UdpSocket::bind(bind).map_err(|e| format!("cannot open a UDP socket for OSC output: {e}"))?;
        Ok(Self { socket, target })
    }

    /// Sends `messages` (a frame's changes); returns how many went out.
    pub fn send(&self, messages: &[OscMessage]) -> usize {
        let mut sent = 0;
        for message in messages {
            if let Ok(bytes) = rosc::encoder::encode(&OscPacket::Message(message.clone()))
                && self.socket.send_to(&bytes, self.target).is_ok()
            {
                sent += 1;
            }
        }
        sent
    }
}
