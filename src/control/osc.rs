//! OSC input: a UDP receiver on its own thread decodes packets (rosc) into batches — a bundle is
//! one batch, applied in one frame — that the render loop drains once per frame without ever
//! blocking. Bundles time-tagged in the future wait until due. Malformed packets, unknown
//! addresses and wrong arguments are counted and logged once per kind, never a panic.

use std::collections::HashSet;
use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TrySendError, sync_channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, SystemTime};

use rosc::{OscMessage, OscPacket, OscType};

/// What went in and what was rejected, shared between the receiver thread and the render loop.
#[derive(Debug, Default)]
pub struct OscCounters {
    /// UDP packets received.
    pub packets: AtomicU64,
    /// Messages decoded (inside bundles too).
    pub messages: AtomicU64,
    /// Packets that did not decode.
    pub malformed: AtomicU64,
    /// Messages to addresses nothing answers to.
    pub unknown_address: AtomicU64,
    /// Messages whose arguments do not fit the parameter.
    pub bad_arguments: AtomicU64,
    /// Messages applied to parameters or commands.
    pub applied: AtomicU64,
    /// Batches dropped: the queue to the render loop was full (a flood), or a time tag lay more
    /// than [`MAX_AHEAD`] in the future.
    pub dropped: AtomicU64,
}

impl OscCounters {
    /// (packets, messages, malformed, unknown address, bad arguments, applied, dropped).
    pub fn snapshot(&self) -> [u64; 7] {
        [
            &self.packets,
            &self.messages,
            &self.malformed,
            &self.unknown_address,
            &self.bad_arguments,
            &self.applied,
            &self.dropped,
        ]
        .map(|c| c.load(Ordering::Relaxed))
    }
}

/// Batches the receiver thread may queue for the render loop; a flood beyond it is dropped and
/// counted, so memory stays flat however fast packets come and however slow frames are.
pub const MAX_QUEUED: usize = 8192;
/// Bytes the queued batches may take in memory together (see [`Batch::bytes`]): 60 KB
/// datagrams used to fill the count bound with half a gigabyte.
pub const MAX_QUEUED_BYTES: usize = 8 << 20;
/// Future-tagged batches held at once; more are dropped and counted.
pub const MAX_SCHEDULED: usize = 4096;
/// Bytes the future-tagged batches may take together.
pub const MAX_SCHEDULED_BYTES: usize = 8 << 20;
/// The furthest ahead a time tag may schedule a bundle; later ones are dropped and counted.
pub const MAX_AHEAD: Duration = Duration::from_secs(3600);

/// Messages that apply together, at `due` (None: at once).
#[derive(Clone, Debug, PartialEq)]
pub struct Batch {
    /// When to apply (a future bundle time tag), if not immediately.
    pub due: Option<SystemTime>,
    /// The messages, in packet order.
    pub messages: Vec<OscMessage>,
}

impl Batch {
    /// The memory this batch holds, about: its strings and blobs, and a fixed cost per message
    /// and argument.
    pub fn bytes(&self) -> usize {
        let argument = |a: &OscType| {
            size_of::<OscType>()
                + match a {
                    OscType::String(s) => s.len(),
                    OscType::Blob(b) => b.len(),
                    _ => 0,
                }
        };
        size_of::<Batch>()
            + self
                .messages
                .iter()
                .map(|m| size_of::<OscMessage>() + m.addr.len() + m.args.iter().map(argument).sum::<usize>())
                .sum::<usize>()
    }
}

/// Decodes one UDP payload into batches: a message is a batch; a bundle (with nested bundles
/// flattened under the outermost time tag that is in the future) is one batch.
pub fn decode(bytes: &[u8]) -> Result<Vec<Batch>, String> {
    // Before rosc: its decoder (and dropping or printing what it builds) recurses per level.
    super::osc_guard::check_nesting(bytes)?;
    let (rest, packet) = rosc::decoder::decode_udp(bytes).map_err(|e| format!("{e:?}"))?;
    if !rest.is_empty() {
        return Err(format!("{} trailing bytes after the packet", rest.len()));
    }
    let mut batch = Batch { due: None, messages: Vec::new() };
    flatten(packet, &mut batch);
    Ok(vec![batch])
}

fn flatten(packet: OscPacket, batch: &mut Batch) {
    match packet {
        OscPacket::Message(m) => batch.messages.push(m),
        OscPacket::Bundle(b) => {
            // (0, 1) means "immediately"; anything else is an absolute NTP time.
            let immediate = b.timetag.seconds == 0 && b.timetag.fractional == 1;
            if !immediate && batch.due.is_none() {
                batch.due = ntp_to_system(b.timetag);
            }
            for p in b.content {
                flatten(p, batch);
            }
        }
    }
}

/// An OSC (NTP) time tag as a system time. NTP seconds wrap every 2³² s (the next era starts in
/// 2036): a tag that would fall before 1970, or more than half an era before now, is read in the
/// next era, so tags after 2036 stay in the future instead of wrapping to 1900 (and applying at
/// once).
fn ntp_to_system(t: rosc::OscTime) -> Option<SystemTime> {
    ntp_to_system_near(t, SystemTime::now())
}

fn ntp_to_system_near(t: rosc::OscTime, now: SystemTime) -> Option<SystemTime> {
    const NTP_TO_UNIX_SECONDS: i64 = 2_208_988_800;
    const ERA: i64 = 1 << 32;
    let now_unix = now.duration_since(SystemTime::UNIX_EPOCH).map_or(0, |d| d.as_secs() as i64);
    let mut unix = i64::from(t.seconds) - NTP_TO_UNIX_SECONDS;
    while unix < 0 || unix < now_unix - ERA / 2 {
        unix += ERA;
    }
    let seconds = u64::try_from(unix).ok()?;
    let nanos = (u64::from(t.fractional) * 1_000_000_000) >> 32;
    SystemTime::UNIX_EPOCH.checked_add(Duration::new(seconds, nanos as u32))
}

/// Requested kernel receive buffer for the OSC socket.
const RECEIVE_BUFFER_BYTES: usize = 4 << 20;

/// The UDP receiver thread and the queue it fills, which other transports (OSCQuery's
/// WebSocket) fill too through an [`OscInlet`].
pub struct OscReceiver {
    local: SocketAddr,
    queue: Receiver<(Batch, usize)>,
    /// Future batches with their bytes.
    scheduled: Vec<(Batch, usize)>,
    /// Bytes of the batches in `scheduled`.
    scheduled_bytes: usize,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    /// The sending end of `queue` with its byte count, the counters and the log of problems,
    /// shared with every transport.
    inlet: OscInlet,
}

impl OscReceiver {
    /// Binds `addr` (e.g. `127.0.0.1:9000`; port 0 picks a free one) and starts receiving.
    pub fn bind(addr: &str) -> Result<Self, String> {
        let socket = UdpSocket::bind(addr).map_err(|e| format!("cannot listen for OSC on {addr}: {e}"))?;
        // A multi-touch controller sends bursts; a 4 MiB kernel buffer absorbs them while this
        // thread catches up (the OS may cap it lower; that is not an error).
        let _ = socket2::SockRef::from(&socket).set_recv_buffer_size(RECEIVE_BUFFER_BYTES);
        socket.set_read_timeout(Some(Duration::from_millis(50))).map_err(|e| e.to_string())?;
        let local = socket.local_addr().map_err(|e| e.to_string())?;
        let mut receiver = Self::queue_only(local);
        let (inlet, stop) = (receiver.inlet.clone(), receiver.stop.clone());
        let thread = std::thread::Builder::new()
            .name("indra-osc".into())
            .spawn(move || receive_loop(&socket, &inlet, &stop))
            .map_err(|e| e.to_string())?;
        receiver.thread = Some(thread);
        log::info!("OSC listening on {local}");
        Ok(receiver)
    }

    /// A receiver with no UDP socket, filled only through its [`OscInlet`] (OSC over OSCQuery's
    /// WebSocket with UDP input off). `local_addr` is the unspecified address, port 0.
    pub fn without_socket() -> Self {
        Self::queue_only(SocketAddr::from(([0, 0, 0, 0], 0)))
    }

    fn queue_only(local: SocketAddr) -> Self {
        let (tx, queue) = sync_channel(MAX_QUEUED);
        let inlet =
            OscInlet { queue: Queue { tx, bytes: Arc::default() }, counters: Arc::default(), logged: Arc::default() };
        Self {
            local,
            queue,
            scheduled: Vec::new(),
            scheduled_bytes: 0,
            stop: Arc::new(AtomicBool::new(false)),
            thread: None,
            inlet,
        }
    }

    /// Where other transports hand in their packets, to be checked, counted, queued and
    /// routed exactly as UDP's are.
    pub fn inlet(&self) -> OscInlet {
        self.inlet.clone()
    }

    /// The bound address (useful with port 0).
    pub fn local_addr(&self) -> SocketAddr {
        self.local
    }

    /// The shared counters.
    pub fn counters(&self) -> &Arc<OscCounters> {
        &self.inlet.counters
    }

    /// Every batch that is due at `now`, in arrival order; later ones wait (at most
    /// [`MAX_SCHEDULED`], none more than [`MAX_AHEAD`] ahead: the rest are dropped and counted).
    pub fn drain(&mut self, now: SystemTime) -> Vec<Batch> {
        let horizon = now + MAX_AHEAD;
        for (batch, bytes) in self.queue.try_iter() {
            self.inlet.queue.bytes.fetch_sub(bytes, Ordering::Relaxed);
            let too_late = batch.due.is_some_and(|t| t > horizon);
            let full = batch.due.is_some_and(|t| t > now)
                && (self.scheduled.len() >= MAX_SCHEDULED || self.scheduled_bytes + bytes > MAX_SCHEDULED_BYTES);
            if too_late || full {
                self.inlet.counters.dropped.fetch_add(1, Ordering::Relaxed);
                let why = if too_late { "a time tag more than an hour ahead" } else { "too many future bundles" };
                log_once(&self.inlet.logged, why, &format!("bundle dropped: {why}"));
                continue;
            }
            self.scheduled_bytes += bytes;
            self.scheduled.push((batch, bytes));
        }
        let (due, later): (Vec<_>, Vec<_>) =
            self.scheduled.drain(..).partition(|(b, _)| b.due.is_none_or(|t| t <= now));
        self.scheduled = later;
        self.scheduled_bytes -= due.iter().map(|(_, bytes)| bytes).sum::<usize>();
        due.into_iter().map(|(batch, _)| batch).collect()
    }

    /// Bytes waiting: queued by the receiver thread and scheduled for later.
    pub fn pending_bytes(&self) -> usize {
        self.inlet.queue.bytes.load(Ordering::Relaxed) + self.scheduled_bytes
    }

    /// Logs `message` the first time its `kind` is seen.
    pub fn log_once(&self, kind: &str, message: &str) {
        log_once(&self.inlet.logged, kind, message);
    }
}

impl Drop for OscReceiver {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Distinct problems logged at most (each once); after that a flood of distinct bad addresses
/// is only counted, so neither memory nor the log grows with it.
const MAX_LOGGED_KINDS: usize = 64;
/// Longest message logged, in characters (addresses and arguments come from the network).
const MAX_LOGGED_CHARS: usize = 200;

fn log_once(logged: &Mutex<HashSet<String>>, kind: &str, message: &str) {
    let Ok(mut seen) = logged.lock() else { return };
    if seen.contains(truncate(kind)) || seen.len() > MAX_LOGGED_KINDS {
        return;
    }
    if seen.len() == MAX_LOGGED_KINDS {
        seen.insert(String::new());
        log::warn!("OSC: {MAX_LOGGED_KINDS} kinds of problems logged; from now on they are only counted");
        return;
    }
    seen.insert(truncate(kind).to_string());
    log::warn!("OSC: {} (further ones are only counted)", truncate(message));
}

/// At most [`MAX_LOGGED_CHARS`] characters of `text`, cut at a character boundary.
fn truncate(text: &str) -> &str {
    text.char_indices().nth(MAX_LOGGED_CHARS).map_or(text, |(i, _)| &text[..i])
}

/// The argument types of a message, shallowly (`f, i, [3 values]`): never the nested values.
pub(super) fn describe_args(args: &[OscType]) -> String {
    let one = |a: &OscType| match a {
        OscType::Array(array) => format!("[{} values]", array.content.len()),
        OscType::String(s) => format!("{:?}", s.chars().take(20).collect::<String>()),
        OscType::Blob(b) => format!("blob of {} bytes", b.len()),
        // The rest hold no nested or unbounded data.
        other => format!("{other:?}"),
    };
    let mut parts: Vec<String> = args.iter().take(8).map(one).collect();
    if args.len() > 8 {
        parts.push(format!("… {} more", args.len() - 8));
    }
    parts.join(", ")
}

/// The receiving end of the queue: batches with their [`Batch::bytes`], counted once, and the
/// bytes the queue holds.
#[derive(Clone)]
struct Queue {
    tx: SyncSender<(Batch, usize)>,
    bytes: Arc<AtomicUsize>,
}

impl Queue {
    /// Queues `batch` if the queue has room for it by count and by bytes.
    fn push(&self, batch: Batch) -> Result<(), TrySendError<()>> {
        let bytes = batch.bytes();
        if self.bytes.load(Ordering::Relaxed) + bytes > MAX_QUEUED_BYTES {
            return Err(TrySendError::Full(()));
        }
        self.bytes.fetch_add(bytes, Ordering::Relaxed);
        self.tx.try_send((batch, bytes)).map_err(|e| {
            self.bytes.fetch_sub(bytes, Ordering::Relaxed);
            match e {
                TrySendError::Full(_) => TrySendError::Full(()),
                TrySendError::Disconnected(_) => TrySendError::Disconnected(()),
            }
        })
    }
}

/// Where an OSC packet enters, whatever carried it (a UDP datagram, a WebSocket message): it is
/// decoded, counted and queued for the render loop under one set of limits and counters.
#[derive(Clone)]
pub struct OscInlet {
    queue: Queue,
    counters: Arc<OscCounters>,
    logged: Arc<Mutex<HashSet<String>>>,
}

/// What became of a packet handed to an [`OscInlet`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Intake {
    /// Queued; `stats`: it asks for `/indra/stats`, which the transport may answer at once.
    Queued {
        /// The packet holds a `/indra/stats` message.
        stats: bool,
    },
    /// It did not decode (counted malformed).
    Malformed,
    /// The queue was full (counted dropped).
    Dropped,
    /// The receiver is gone.
    Closed,
}

impl OscInlet {
    /// Checks, counts and queues one packet from `from` (named in the log).
    pub fn take(&self, bytes: &[u8], from: &dyn std::fmt::Display) -> Intake {
        let counters = &self.counters;
        counters.packets.fetch_add(1, Ordering::Relaxed);
        let batches = match decode(bytes) {
            Ok(batches) => batches,
            Err(e) => {
                counters.malformed.fetch_add(1, Ordering::Relaxed);
                log_once(&self.logged, "malformed", &format!("malformed packet from {from}: {e}"));
                return Intake::Malformed;
            }
        };
        let mut intake = Intake::Queued { stats: false };
        for batch in batches {
            counters.messages.fetch_add(batch.messages.len() as u64, Ordering::Relaxed);
            let stats = batch.messages.iter().any(|m| m.addr == "/indra/stats");
            match self.queue.push(batch) {
                Ok(()) => {
                    if let Intake::Queued { stats: asked } = &mut intake {
                        *asked |= stats;
                    }
                }
                Err(TrySendError::Full(())) => {
                    counters.dropped.fetch_add(1, Ordering::Relaxed);
                    log_once(&self.logged, "queue full", "the render loop is behind; packets are dropped and counted");
                    intake = Intake::Dropped;
                }
                Err(TrySendError::Disconnected(())) => return Intake::Closed,
            }
        }
        intake
    }

    /// The shared counters.
    pub fn counters(&self) -> &OscCounters {
        &self.counters
    }
}

fn receive_loop(socket: &UdpSocket, inlet: &OscInlet, stop: &AtomicBool) {
    let mut buf = vec![0u8; 65536];
    while !stop.load(Ordering::Relaxed) {
        let Ok((len, from)) = socket.recv_from(&mut buf) else { continue };
        match inlet.take(&buf[..len], &from) {
            // Stats are answered here, so a client can ask even while frames are slow.
            Intake::Queued { stats: true } => reply_stats(socket, from, inlet.counters()),
            Intake::Closed => return,
            Intake::Queued { stats: false } | Intake::Malformed | Intake::Dropped => {}
        }
    }
}

fn reply_stats(socket: &UdpSocket, to: SocketAddr, counters: &OscCounters) {
    let args = counters.snapshot().iter().map(|&c| OscType::Long(c as i64)).collect();
    let packet = OscPacket::Message(OscMessage { addr: "/indra/stats".into(), args });
    if let Ok(bytes) = rosc::encoder::encode(&packet) {
        let _ = socket.send_to(&bytes, to);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_tags_after_2036_stay_in_the_future() {
        let now = SystemTime::UNIX_EPOCH + Duration::from_secs(1_796_000_000); // 2026-12
        let at = |unix: u64| {
            let ntp = unix + 2_208_988_800;
            ntp_to_system_near(rosc::OscTime { seconds: (ntp % (1 << 32)) as u32, fractional: 0 }, now)
        };
        let year_2100 = 4_102_444_800; // 2100-01-01
        assert_eq!(at(year_2100), Some(SystemTime::UNIX_EPOCH + Duration::from_secs(year_2100)));
        let soon = 1_796_000_010;
        assert_eq!(at(soon), Some(SystemTime::UNIX_EPOCH + Duration::from_secs(soon)));
        // A raw value that would be 1900 is the next era's (2036), never "at once".
        let wrapped = ntp_to_system_near(rosc::OscTime { seconds: 1_000, fractional: 0 }, now).unwrap();
        assert!(wrapped > now, "{wrapped:?}");
    }
}
