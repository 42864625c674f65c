//! OSCQuery's LISTEN extension: controllers connected over a WebSocket name the addresses they
//! want (`{"COMMAND": "LISTEN", "DATA": "/indra/glow/intensity"}`, `IGNORE` to stop) and receive
//! each change of those values as a binary OSC message; a new namespace (another scene) is
//! announced as `{"COMMAND": "PATH_CHANGED", "DATA": "/indra"}`. The render thread only queues:
//! a session that falls [`QUEUE`] messages behind loses the overflow, never the show's time.
//!
//! A session that may control the show (see [`super::web`]) sends binary OSC packets on the same
//! socket, as the OSCQuery proposal allows; they go through the [`OscInlet`] UDP packets go
//! through. A session that sends OSC without that right, or more than [`MAX_PACKET_RATE`]
//! packets a second, is closed: a flood ends that session only.

use std::collections::HashSet;
use std::net::TcpStream;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TryRecvError, sync_channel};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use rosc::{OscMessage, OscPacket};
use serde_json::{Value, json};
use tungstenite::{Message, WebSocket};

use super::osc::{Intake, OscInlet};

/// Messages a session may have waiting.
pub const QUEUE: usize = 1024;
/// Addresses one session may listen to.
pub const MAX_PATHS: usize = 4096;
/// The longest address a session may listen to (indra's are far shorter).
pub const MAX_PATH_LEN: usize = 256;
/// The bytes of all the addresses one session listens to together.
pub const MAX_PATH_BYTES: usize = 64 * 1024;
/// How often a session is pinged; a WebSocket client answers with a pong by itself.
pub const PING_EVERY: Duration = Duration::from_secs(3);
/// Packets a controlling session may send in one second (a phone's fingers on sliders send
/// well under 200); past that the session is closed.
pub const MAX_PACKET_RATE: u32 = 1000;
/// A session from which no whole message (a pong included) arrived for this long is closed:
/// a client that stopped half-way through a frame, or vanished, frees its place.
pub const SESSION_IDLE: Duration = Duration::from_secs(10);

/// What goes out to a session.
enum Outgoing {
    Osc(Vec<u8>),
    Text(String),
}

/// One connected controller: what it listens to and its queue.
struct Session {
    id: u64,
    paths: Arc<Mutex<HashSet<String>>>,
    queue: SyncSender<Outgoing>,
}

/// The connected controllers.
#[derive(Default)]
pub struct Listeners {
    sessions: Mutex<Vec<Session>>,
    dropped: AtomicU64,
    next_id: AtomicU64,
    closed: AtomicBool,
}

impl Listeners {
    /// Whether any controller is connected.
    pub fn any(&self) -> bool {
        self.sessions.lock().is_ok_and(|s| !s.is_empty())
    }

    /// Messages not delivered because a session's queue was full.
    pub fn dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
    }

    /// Queues each message for every session listening to its address; returns how many were
    /// queued. Never blocks.
    pub fn send(&self, messages: &[OscMessage]) -> usize {
        let Ok(sessions) = self.sessions.lock() else { return 0 };
        let mut queued = 0;
        for message in messages {
            let mut bytes = None;
            for session in sessions.iter() {
                if !session.paths.lock().is_ok_and(|p| p.contains(&message.addr)) {
                    continue;
                }
                let bytes = bytes.get_or_insert_with(|| {
                    rosc::encoder::encode(&OscPacket::Message(message.clone())).unwrap_or_default()
                });
                match session.queue.try_send(Outgoing::Osc(bytes.clone())) {
                    Ok(()) => queued += 1,
                    Err(_) => {
                        self.dropped.fetch_add(1, Ordering::Relaxed);
                    }
                }
            }
        }
        queued
    }

    /// Tells every session that the namespace under `path` changed.
    pub fn path_changed(&self, path: &str) {
        let text = json!({ "COMMAND": "PATH_CHANGED", "DATA": path }).to_string();
        if let Ok(sessions) = self.sessions.lock() {
            for s in sessions.iter() {
                let _ = s.queue.try_send(Outgoing::Text(text.clone()));
            }
        }
    }

    /// Ends every session (the server is going away).
    pub fn close(&self) {
        self.closed.store(true, Ordering::Relaxed);
    }

    /// Serves one WebSocket session until the client leaves or the server closes; its OSC
    /// packets go to `control` when it may control the show, and end it otherwise.
    pub fn serve(&self, mut socket: WebSocket<TcpStream>, control: Option<&OscInlet>) {
        let (queue, outgoing) = sync_channel(QUEUE);
        let paths = Arc::new(Mutex::new(HashSet::new()));
        let id = self.next_id.fetch_add(1, Ordering::Relaxed);
        if let Ok(mut sessions) = self.sessions.lock() {
            sessions.push(Session { id, paths: paths.clone(), queue });
        }
        let (mut heard, mut pinged) = (Instant::now(), Instant::now());
        let mut rate = Rate::default();
        let from = format!("WebSocket session {id}");
        while !self.closed.load(Ordering::Relaxed) && heard.elapsed() < SESSION_IDLE {
            match socket.read() {
                Ok(Message::Text(text)) => {
                    heard = Instant::now();
                    command(&text, &paths);
                }
                Ok(Message::Binary(bytes)) => {
                    heard = Instant::now();
                    let Some(inlet) = control else {
                        log::warn!("OSCQuery: {from} sent OSC without the access token; closed");
                        break;
                    };
                    if !rate.allows(heard) {
                        log::warn!("OSCQuery: {from} sent more than {MAX_PACKET_RATE} packets a second; closed");
                        break;
                    }
                    if inlet.take(&bytes, &from) == Intake::Closed {
                        break;
                    }
                }
                Ok(Message::Close(_)) => break,
                Ok(_) => heard = Instant::now(),
                Err(tungstenite::Error::Io(e))
                    if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {}
                Err(_) => break,
            }
            if pinged.elapsed() >= PING_EVERY {
                pinged = Instant::now();
                if socket.write(Message::Ping(Vec::new().into())).is_err() {
                    break;
                }
            }
            if deliver(&mut socket, &outgoing).is_err() {
                break;
            }
        }
        if let Ok(mut sessions) = self.sessions.lock() {
            sessions.retain(|s| s.id != id);
        }
        let _ = socket.close(None);
        let _ = socket.flush();
    }
}

/// Packets counted in the current one-second window.
#[derive(Default)]
struct Rate {
    window: Option<Instant>,
    packets: u32,
}

impl Rate {
    /// Counts a packet at `now`; false once the window holds more than [`MAX_PACKET_RATE`].
    fn allows(&mut self, now: Instant) -> bool {
        if self.window.is_none_or(|start| now.duration_since(start) >= Duration::from_secs(1)) {
            (self.window, self.packets) = (Some(now), 0);
        }
        self.packets += 1;
        self.packets <= MAX_PACKET_RATE
    }
}

/// Applies a LISTEN or IGNORE command; anything else is ignored (the spec lets clients send
/// commands a server does not know).
fn command(text: &str, paths: &Mutex<HashSet<String>>) {
    let Ok(value) = serde_json::from_str::<Value>(text) else { return };
    let (Some(command), Some(path)) = (value["COMMAND"].as_str(), value["DATA"].as_str()) else { return };
    let Ok(mut paths) = paths.lock() else { return };
    match command {
        "LISTEN" if path.len() <= MAX_PATH_LEN && paths.len() < MAX_PATHS => {
            let bytes: usize = paths.iter().map(String::len).sum();
            if bytes + path.len() <= MAX_PATH_BYTES {
                paths.insert(path.to_string());
            }
        }
        "IGNORE" => {
            paths.remove(path);
        }
        _ => {}
    }
}

/// Sends what is queued for the session.
fn deliver(socket: &mut WebSocket<TcpStream>, outgoing: &Receiver<Outgoing>) -> Result<(), tungstenite::Error> {
    loop {
        match outgoing.try_recv() {
            Ok(Outgoing::Osc(bytes)) => socket.write(Message::Binary(bytes.into()))?,
            Ok(Outgoing::Text(text)) => socket.write(Message::Text(text.into()))?,
            Err(TryRecvError::Empty | TryRecvError::Disconnected) => break,
        }
    }
    socket.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_packet_rate_is_counted_per_second() {
        let mut rate = Rate::default();
        let start = Instant::now();
        assert!((0..MAX_PACKET_RATE).all(|_| rate.allows(start)));
        assert!(!rate.allows(start + Duration::from_millis(999)));
        assert!(rate.allows(start + Duration::from_secs(1)), "a new second starts afresh");
    }

    #[test]
    fn listened_addresses_are_bounded_in_length_and_in_total_bytes() {
        let paths = Mutex::new(HashSet::new());
        let listen = |path: &str| command(&json!({ "COMMAND": "LISTEN", "DATA": path }).to_string(), &paths);
        listen(&format!("/{}", "a".repeat(64 * 1024)));
        assert!(paths.lock().unwrap().is_empty(), "a 64 KiB address is refused");
        for i in 0..MAX_PATHS {
            listen(&format!("/indra/{i:0>240}"));
        }
        let held = paths.lock().unwrap().iter().map(String::len).sum::<usize>();
        assert!(held <= MAX_PATH_BYTES && held > MAX_PATH_BYTES - MAX_PATH_LEN, "{held} bytes held");
    }
}
