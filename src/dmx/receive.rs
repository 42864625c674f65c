//! DMX in: Art-Net and sACN universes from a lighting desk, merged per universe, read by the
//! control layer as the newest state. Each protocol has a receive thread; a flood only
//! overwrites the state (memory stays what the listened universes need), and a malformed or
//! unlistened packet is counted and dropped.

use std::collections::{BTreeMap, HashMap};
use std::net::{IpAddr, SocketAddr};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use artnet_protocol::ArtCommand;
use serde::Deserialize;

use super::layout::{UNIVERSE_CHANNELS, Universes};

/// An Art-Net source not heard for this long leaves the merge (the Art-Net 4 merge timeout).
const SOURCE_TIMEOUT: Duration = Duration::from_secs(10);
/// The most sources merged on one universe; more are counted and dropped.
const MAX_SOURCES: usize = 4;

/// How two sources sending one universe are merged.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
pub enum Merge {
    /// Highest takes precedence: each channel the highest of the sources.
    #[default]
    Htp,
    /// Latest takes precedence: the newest packet's channels. sACN takes the highest priority
    /// first in both.
    Ltp,
}

/// Where DMX in listens.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ListenConfig {
    /// The local address Art-Net is received on (port 6454 unless given); none: no Art-Net.
    #[serde(default)]
    pub artnet: Option<String>,
    /// The local address sACN is received on (port 5568; multicast groups are joined on the
    /// interface of this address); none: no sACN.
    #[serde(default)]
    pub sacn: Option<String>,
    /// How sources are merged.
    #[serde(default)]
    pub merge: Merge,
}

/// What DMX in has seen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DmxInCounts {
    /// Packets of a listened universe taken in.
    pub packets: u64,
    /// Packets that were not Art-Net or sACN DMX, or were cut short.
    pub malformed: u64,
    /// Packets of universes nobody listens to, or from a source past the merge's limit.
    pub ignored: u64,
}

/// One universe's merge state.
#[derive(Default)]
struct Incoming {
    sources: HashMap<IpAddr, (Instant, Vec<u8>)>,
    merged: Vec<u8>,
}

#[derive(Default)]
struct State {
    universes: BTreeMap<u16, Incoming>,
    /// Bumped on every change; the reader compares.
    generation: u64,
}

#[derive(Default)]
struct Shared {
    state: Mutex<State>,
    stop: AtomicBool,
    packets: AtomicU64,
    malformed: AtomicU64,
    ignored: AtomicU64,
}

/// Receiving DMX from the network.
pub struct DmxIn {
    shared: Arc<Shared>,
    threads: Vec<JoinHandle<()>>,
    seen: u64,
}

impl DmxIn {
    /// Binds the sockets the config names (errors at once) and starts receiving `universes`.
    pub fn start(config: &ListenConfig, universes: &[u16]) -> Result<Self, String> {
        let shared = Arc::new(Shared::default());
        {
            let mut state = shared.state.lock().expect("new");
            for &u in universes {
                state.universes.insert(u, Incoming { merged: vec![0; UNIVERSE_CHANNELS], ..Default::default() });
            }
        }
        let mut threads = Vec::new();
        if let Some(at) = &config.artnet {
            let at = super::socket_address(at, super::ARTNET_PORT).map_err(|e| format!("artnet: {e}"))?;
            let socket = super::bind_udp(at).map_err(|e| format!("cannot receive Art-Net on {at}: {e}"))?;
            socket.set_read_timeout(Some(Duration::from_millis(200))).map_err(|e| e.to_string())?;
            let (shared, merge) = (shared.clone(), config.merge);
            threads.push(spawn("dmx-in-artnet", move || receive_artnet(&socket, &shared, merge))?);
        }
        if let Some(at) = &config.sacn {
            let at = super::socket_address(at, super::SACN_PORT).map_err(|e| format!("sacn: {e}"))?;
            let mut receiver = sacn::receive::SacnReceiver::with_ip(at, Some(MAX_SOURCES))
                .map_err(|e| format!("cannot receive sACN on {at}: {e}"))?;
            receiver.listen_universes(universes).map_err(|e| format!("sACN universes: {e}"))?;
            if config.merge == Merge::Htp {
                receiver.set_merge_fn(sacn::receive::htp_dmx_merge).map_err(|e| e.to_string())?;
            }
            let shared = shared.clone();
            threads.push(spawn("dmx-in-sacn", move || receive_sacn(&mut receiver, &shared))?);
        }
        if threads.is_empty() {
            return Err("DMX in names neither `artnet` nor `sacn` to listen on".into());
        }
        Ok(Self { shared, threads, seen: 0 })
    }

    /// The merged universes when something changed since the last call; never waits long (the
    /// receive threads hold the lock only to copy one packet in).
    pub fn changed(&mut self) -> Option<Universes> {
        let state = self.shared.state.lock().ok()?;
        if state.generation == self.seen {
            return None;
        }
        self.seen = state.generation;
        Some(
            state
                .universes
                .iter()
                .map(|(u, incoming)| {
                    let mut channels = [0u8; UNIVERSE_CHANNELS];
                    channels[..incoming.merged.len()].copy_from_slice(&incoming.merged);
                    (*u, channels)
                })
                .collect(),
        )
    }

    /// Counts so far.
    pub fn counts(&self) -> DmxInCounts {
        DmxInCounts {
            packets: self.shared.packets.load(Ordering::Relaxed),
            malformed: self.shared.malformed.load(Ordering::Relaxed),
            ignored: self.shared.ignored.load(Ordering::Relaxed),
        }
    }
}

impl Drop for DmxIn {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        for thread in self.threads.drain(..) {
            let _ = thread.join();
        }
    }
}

fn spawn(name: &str, f: impl FnOnce() + Send + 'static) -> Result<JoinHandle<()>, String> {
    std::thread::Builder::new().name(name.into()).spawn(f).map_err(|e| format!("cannot start {name}: {e}"))
}

fn receive_artnet(socket: &std::net::UdpSocket, shared: &Shared, merge: Merge) {
    let mut buffer = [0u8; 1024];
    while !shared.stop.load(Ordering::Relaxed) {
        let Ok((n, from)) = socket.recv_from(&mut buffer) else { continue };
        match ArtCommand::from_buffer(&buffer[..n]) {
            Ok(ArtCommand::Output(output)) => {
                let universe = u16::from(output.port_address);
                take_in(shared, universe, from, output.data.as_ref(), merge);
            }
            // Polls, syncs and the rest of Art-Net are not DMX data.
            Ok(_) => {}
            Err(_) => {
                shared.malformed.fetch_add(1, Ordering::Relaxed);
            }
        }
    }
}

fn receive_sacn(receiver: &mut sacn::receive::SacnReceiver, shared: &Shared) {
    while !shared.stop.load(Ordering::Relaxed) {
        match receiver.recv(Some(Duration::from_millis(200))) {
            Ok(data) => {
                for d in data {
                    // The crate merged sources by priority (and HTP where asked): one state.
                    let channels = d.values.get(1..).unwrap_or_default();
                    let from = SocketAddr::from(([0, 0, 0, 0], 0));
                    take_in(shared, d.universe, from, channels, Merge::Ltp);
                }
            }
            Err(sacn::error::errors::SacnError::Io(e))
                if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {}
            Err(_) => {
                shared.malformed.fetch_add(1, Ordering::Relaxed);
            }
        }
    }
}

/// Merges one packet's channels into its universe.
fn take_in(shared: &Shared, universe: u16, from: SocketAddr, channels: &[u8], merge: Merge) {
    let Ok(mut state) = shared.state.lock() else { return };
    let Some(incoming) = state.universes.get_mut(&universe) else {
        shared.ignored.fetch_add(1, Ordering::Relaxed);
        return;
    };
    let now = Instant::now();
    incoming.sources.retain(|_, (seen, _)| now - *seen < SOURCE_TIMEOUT);
    if !incoming.sources.contains_key(&from.ip()) && incoming.sources.len() >= MAX_SOURCES {
        shared.ignored.fetch_add(1, Ordering::Relaxed);
        return;
    }
    let channels = &channels[..channels.len().min(UNIVERSE_CHANNELS)];
    incoming.sources.insert(from.ip(), (now, channels.to_vec()));
    let merged = match merge {
        Merge::Ltp => {
            let mut m = vec![0; UNIVERSE_CHANNELS];
            m[..channels.len()].copy_from_slice(channels);
            m
        }
        Merge::Htp => {
            let mut m = vec![0u8; UNIVERSE_CHANNELS];
            for (_, data) in incoming.sources.values() {
                for (out, v) in m.iter_mut().zip(data) {
                    *out = (*out).max(*v);
                }
            }
            m
        }
    };
    shared.packets.fetch_add(1, Ordering::Relaxed);
    if merged != incoming.merged {
        incoming.merged = merged;
        state.generation += 1;
    }
}
