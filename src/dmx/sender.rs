//! The DMX sender thread: takes the newest frame's pixels from the render thread (which never
//! waits on it), encodes them into universes, and sends each universe at the patch's rate when
//! it changes and at least once a second when it does not (the refresh Art-Net and E1.31 ask
//! for). On stop it sends a blackout or holds, as the patch says.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::artnet::ArtNetSender;
use super::layout::{Layout, Universes};
use super::patch::OnStop;
use super::sacn_out::SacnSender;

/// A universe that did not change is sent again after this long.
pub const REFRESH: Duration = Duration::from_millis(1000);

/// One frame's sampled pixels and lamp positions.
type Offered = (Vec<[u16; 3]>, Vec<Option<f32>>);

/// What the render thread and the sender share.
#[derive(Default)]
struct Shared {
    /// The newest frame's sampled pixels and lamp positions, replaced by each offer (latest
    /// wins).
    latest: Mutex<Option<Offered>>,
    stop: AtomicBool,
    /// Packets sent (each universe to each protocol counts one).
    packets: AtomicU64,
    /// Frames offered while the sender held the slot: dropped, not waited for.
    missed: AtomicU64,
}

/// A running DMX output.
pub struct DmxOut {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
    polls: Arc<AtomicU64>,
}

/// The protocols one output sends on.
struct Wire {
    artnet: Option<ArtNetSender>,
    sacn: Option<SacnSender>,
}

impl Wire {
    fn send(&mut self, universe: u16, channels: &[u8]) -> u64 {
        let mut sent = 0;
        if let Some(a) = self.artnet.as_mut() {
            a.send(universe, channels);
            sent += 1;
        }
        if let Some(s) = self.sacn.as_mut() {
            s.send(universe, channels);
            sent += 1;
        }
        sent
    }

    fn end_frame(&mut self) {
        if let Some(a) = self.artnet.as_mut() {
            a.end_frame();
        }
        if let Some(s) = self.sacn.as_mut() {
            s.end_frame();
        }
    }
}

impl DmxOut {
    /// Opens the patch's sockets here (so a bad address fails at once) and starts sending.
    pub fn start(layout: Layout) -> Result<Self, String> {
        let universes = layout.universes();
        let artnet = layout.patch.artnet.as_ref().map(|c| ArtNetSender::open(c, &universes)).transpose()?;
        let sacn = layout.patch.sacn.as_ref().map(|c| SacnSender::open(c, &universes)).transpose()?;
        let shared = Arc::new(Shared::default());
        let polls = Arc::new(AtomicU64::new(0));
        let (sending, counting) = (shared.clone(), polls.clone());
        let thread = std::thread::Builder::new()
            .name("dmx-out".into())
            .spawn(move || run(layout, Wire { artnet, sacn }, &sending, &counting))
            .map_err(|e| format!("cannot start the DMX sender: {e}"))?;
        Ok(Self { shared, thread: Some(thread), polls })
    }

    /// Hands over a frame's sampled pixels and the positions of the parameters its lamps follow
    /// ([`Layout::lamp_targets`]); never waits (a frame offered while the sender is taking the
    /// previous one is dropped and counted).
    pub fn offer(&self, pixels: Vec<[u16; 3]>, lamps: Vec<Option<f32>>) {
        match self.shared.latest.try_lock() {
            Ok(mut slot) => *slot = Some((pixels, lamps)),
            Err(_) => {
                self.shared.missed.fetch_add(1, Ordering::Relaxed);
            }
        }
    }

    /// Packets sent so far.
    pub fn packets(&self) -> u64 {
        self.shared.packets.load(Ordering::Relaxed)
    }

    /// ArtPolls answered so far.
    pub fn polls_answered(&self) -> u64 {
        self.polls.load(Ordering::Relaxed)
    }
}

impl Drop for DmxOut {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// The sender's loop: one tick per 1/rate seconds.
fn run(layout: Layout, mut wire: Wire, shared: &Shared, polls: &AtomicU64) {
    let period = Duration::from_secs_f32(1.0 / layout.patch.rate);
    let mut current: Option<Universes> = None;
    let mut last_sent: Vec<(u16, Option<Instant>, [u8; 512])> =
        layout.universes().into_iter().map(|u| (u, None, [0; 512])).collect();
    let mut next = Instant::now();
    while !shared.stop.load(Ordering::Relaxed) {
        let frame = shared.latest.lock().map(|mut slot| slot.take()).unwrap_or(None);
        if let Some((pixels, lamps)) = frame {
            current = Some(layout.encode(&pixels, &lamps));
        }
        if let Some(universes) = &current {
            let now = Instant::now();
            let mut any = false;
            for (universe, sent_at, sent) in &mut last_sent {
                let channels = &universes[universe];
                let due = sent_at.is_none_or(|t| now - t >= REFRESH);
                if due || channels != sent {
                    let count = wire.send(*universe, channels);
                    shared.packets.fetch_add(count, Ordering::Relaxed);
                    *sent_at = Some(now);
                    *sent = *channels;
                    any = true;
                }
            }
            if any {
                wire.end_frame();
            }
        }
        polls.store(wire.artnet.as_ref().map_or(0, ArtNetSender::polls_answered), Ordering::Relaxed);
        next += period;
        let now = Instant::now();
        if next > now {
            std::thread::sleep(next - now);
        } else {
            next = now;
        }
    }
    if layout.patch.on_stop == OnStop::Blackout {
        for (universe, channels) in layout.blackout() {
            wire.send(universe, &channels);
        }
        wire.end_frame();
        if let Some(s) = wire.sacn.as_mut() {
            s.terminate();
        }
    }
}
