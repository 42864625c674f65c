//! A small HTTP/1.x server for GET requests with hard limits, for OSCQuery on a venue network
//! where anything can connect. It replaces tiny_http, whose request body reader allocates a buffer
//! the size of the declared `Content-Length` when it is dropped (one request with
//! `Content-Length: 99999999999` aborted the show) and which had no header, time or connection
//! limits. Here:
//! - headers are read into a fixed 16 KiB buffer; more is `431`, nothing is sized by the client;
//! - only GET is served (`405` otherwise); a request that declares a body is `413`, unread;
//! - each connection has its own thread with 2 s read and write timeouts, so a stalled client
//!   delays nobody else; at most 32 connections are served at once, more are closed at once;
//! - one request per connection (`Connection: close`).

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

/// Largest request head (request line + headers) read.
pub const MAX_HEAD: usize = 16 * 1024;
/// Connections served at once.
pub const MAX_CONNECTIONS: usize = 32;
/// Read and write timeout of a connection.
pub const TIMEOUT: Duration = Duration::from_secs(2);

/// What a handler answers for a request target (path and query): status and JSON body.
pub type Handler = dyn Fn(&str) -> (u16, String) + Send + Sync;

/// A running server; stops when dropped.
pub struct HttpServer {
    local: SocketAddr,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl HttpServer {
    /// Listens on `addr` (port 0 picks one) and answers GETs with `handler`.
    pub fn start(addr: &str, name: &str, handler: Arc<Handler>) -> Result<Self, String> {
        let listener = TcpListener::bind(addr).map_err(|e| format!("cannot serve {name} on {addr}: {e}"))?;
        listener.set_nonblocking(true).map_err(|e| e.to_string())?;
        let local = listener.local_addr().map_err(|e| e.to_string())?;
        let stop = Arc::new(AtomicBool::new(false));
        let thread = {
            let stop = stop.clone();
            std::thread::Builder::new()
                .name(format!("indra-{name}"))
                .spawn(move || accept_loop(&listener, &stop, &handler))
                .map_err(|e| e.to_string())?
        };
        Ok(Self { local, stop, thread: Some(thread) })
    }

    /// The bound address.
    pub fn local_addr(&self) -> SocketAddr {
        self.local
    }
}

impl Drop for HttpServer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn accept_loop(listener: &TcpListener, stop: &AtomicBool, handler: &Arc<Handler>) {
    let active = Arc::new(AtomicUsize::new(0));
    while !stop.load(Ordering::Relaxed) {
        let Ok((stream, _)) = listener.accept() else {
            std::thread::sleep(Duration::from_millis(20));
            continue;
        };
        // Past the cap the connection is closed unread: idle floods cost no threads.
        if active.load(Ordering::Relaxed) >= MAX_CONNECTIONS {
            drop(stream);
            continue;
        }
        active.fetch_add(1, Ordering::Relaxed);
        let (active, handler) = (active.clone(), handler.clone());
        let spawned = std::thread::Builder::new().name("indra-http-conn".into()).spawn(move || {
            serve(stream, &handler);
            active.fetch_sub(1, Ordering::Relaxed);
        });
        if spawned.is_err() {
            log::warn!("HTTP: cannot start a connection thread; connection dropped");
        }
    }
}

/// Answers one request on `stream`, within the limits.
fn serve(mut stream: TcpStream, handler: &Arc<Handler>) {
    let _ = stream.set_nonblocking(false);
    let _ = stream.set_read_timeout(Some(TIMEOUT));
    let _ = stream.set_write_timeout(Some(TIMEOUT));
    let (status, body) = match read_head(&mut stream) {
        Ok(head) => answer(&head, handler),
        Err(status) => (status, String::from("{}")),
    };
    let reason = match status {
        200 => "OK",
        404 => "Not Found",
        405 => "Method Not Allowed",
        413 => "Content Too Large",
        431 => "Request Header Fields Too Large",
        _ => "Bad Request",
    };
    let _ = write!(
        stream,
        "HTTP/1.1 {status} {reason}\r\nContent-Type: application/json\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    );
}

/// The request head (up to the blank line), or the status to answer with.
fn read_head(stream: &mut TcpStream) -> Result<String, u16> {
    let mut head = [0u8; MAX_HEAD];
    let mut len = 0;
    loop {
        if len == MAX_HEAD {
            return Err(431);
        }
        let n = stream.read(&mut head[len..]).map_err(|_| 400u16)?;
        if n == 0 {
            return Err(400);
        }
        len += n;
        if let Some(end) = head[..len].windows(4).position(|w| w == b"\r\n\r\n") {
            return String::from_utf8(head[..end].to_vec()).map_err(|_| 400);
        }
    }
}

/// The status and body for a request head.
fn answer(head: &str, handler: &Arc<Handler>) -> (u16, String) {
    let mut lines = head.split("\r\n");
    let mut request = lines.next().unwrap_or("").split(' ');
    let (method, target) = (request.next().unwrap_or(""), request.next().unwrap_or(""));
    if method != "GET" {
        return (405, "{}".into());
    }
    let declares_body = lines.filter_map(|l| l.split_once(':')).any(|(name, value)| {
        let name = name.trim();
        name.eq_ignore_ascii_case("transfer-encoding")
            || (name.eq_ignore_ascii_case("content-length") && value.trim() != "0")
    });
    if declares_body {
        return (413, "{}".into());
    }
    handler(target)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn echo() -> Arc<Handler> {
        Arc::new(|target: &str| (200, format!("{{\"target\":\"{target}\"}}")))
    }

    #[test]
    fn gets_are_answered_and_everything_else_is_refused_by_status() {
        let h = echo();
        assert_eq!(answer("GET /a?b HTTP/1.1\r\nHost: x", &h), (200, "{\"target\":\"/a?b\"}".into()));
        assert_eq!(answer("POST / HTTP/1.1", &h).0, 405);
        assert_eq!(answer("GET / HTTP/1.1\r\nContent-Length: 99999999999", &h).0, 413);
        assert_eq!(answer("GET / HTTP/1.1\r\ntransfer-encoding: chunked", &h).0, 413);
        assert_eq!(answer("GET / HTTP/1.1\r\nContent-Length: 0", &h).0, 200);
    }
}
