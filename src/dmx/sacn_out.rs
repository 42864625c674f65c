//! sACN (ANSI E1.31) out through the `sacn` crate, which keeps the per-universe sequence
//! numbers, priority, synchronisation packets and stream termination of the standard.

use std::net::SocketAddr;

use sacn::source::SacnSource;

use super::patch::SacnOut;

/// sACN's UDP port.
pub const SACN_PORT: u16 = 5568;

/// Sends one patch's universes over sACN.
pub struct SacnSender {
    source: SacnSource,
    /// Unicast receivers; empty: each universe's multicast group.
    targets: Vec<SocketAddr>,
    priority: u8,
    sync_universe: Option<u16>,
    universes: Vec<u16>,
}

impl SacnSender {
    /// Opens the source and registers `universes` (and the sync universe).
    pub fn open(config: &SacnOut, universes: &[u16]) -> Result<Self, String> {
        let targets = super::socket_addresses(&config.to, SACN_PORT).map_err(|e| format!("sacn.to: {e}"))?;
        let bind = match &config.bind {
            Some(bind) => super::socket_address(bind, 0).map_err(|e| format!("sacn.bind: {e}"))?,
            None => SocketAddr::from(([0, 0, 0, 0], 0)),
        };
        let mut source = SacnSource::with_ip(&config.name, bind)
            .map_err(|e| format!("cannot open an sACN source at {bind}: {e}"))?;
        // Universe discovery goes to a multicast group of its own: only when sending multicast.
        source.set_is_sending_discovery(targets.is_empty());
        let mut registered = universes.to_vec();
        registered.extend(config.sync_universe);
        source.register_universes(&registered).map_err(|e| format!("sACN universes: {e}"))?;
        Ok(Self {
            source,
            targets,
            priority: config.priority,
            sync_universe: config.sync_universe,
            universes: universes.to_vec(),
        })
    }

    /// Sends one universe to every receiver (or its multicast group).
    pub fn send(&mut self, universe: u16, channels: &[u8]) {
        let mut data = Vec::with_capacity(channels.len() + 1);
        data.push(0); // the DMX start code
        data.extend_from_slice(channels);
        let priority = Some(self.priority);
        if self.targets.is_empty() {
            let _ = self.source.send(&[universe], &data, priority, None, self.sync_universe);
        }
        for target in &self.targets {
            let _ = self.source.send(&[universe], &data, priority, Some(*target), self.sync_universe);
        }
    }

    /// Ends a frame: the sync packet, when the patch names a sync universe.
    pub fn end_frame(&mut self) {
        let Some(universe) = self.sync_universe else { return };
        if self.targets.is_empty() {
            let _ = self.source.send_sync_packet(universe, None);
        }
        for target in &self.targets {
            let _ = self.source.send_sync_packet(universe, Some(*target));
        }
    }

    /// Ends every stream (receivers let go at once rather than after their timeout).
    pub fn terminate(&mut self) {
        for &universe in &self.universes {
            let _ = self.source.terminate_stream(universe, 0);
        }
    }
}
