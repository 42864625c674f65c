//! A small HTTP/1.x server for GET requests with hard limits, for OSCQuery on a venue network
//! where anything can connect. It replaces tiny_http, whose request body reader allocates a buffer
//! the size of the declared `Content-Length` when it is dropped (one request with
//! `Content-Length: 99999999999` aborted the show) and which had no header, time or connection
//! limits. Here:
//! - headers are read into a fixed 16 KiB buffer; more is `431`, nothing is sized by the client;
//! - only GET is served (`405` otherwise); a request that declares a body is `413`, unread;
//! - each connection has its own thread with 2 s read and write timeouts, and the whole request
//!   head must arrive within [`HEAD_DEADLINE`] (a client sending a byte a second is cut off, not
//!   kept for as long as it likes), so a stalled client delays nobody else; at most 32
//!   connections are served at once and [`MAX_PER_PEER`] from one address, more are closed at
//!   once, so one slow machine cannot take the places of the others;
//! - one request per connection (`Connection: close`);
//! - a `GET` that asks to upgrade to a WebSocket (RFC 6455) is handed, after the handshake, to the
//!   server's socket handler, if it has one: at most [`Routes::max_sockets`] at once (`503` past
//!   that), messages capped at [`MAX_SOCKET_MESSAGE`] bytes, reads polled every [`SOCKET_POLL`].
//!
//! - requests that name another host are `421` and WebSocket upgrades from another site's page
//!   `403` ([`super::site`]: DNS rebinding and cross-site sockets); replies to a third-party
//!   origin the performer allowed carry its CORS headers.
//!
//! It grew a page (the browser control surface) rather than giving way to hyper or axum: what a
//! page needs on top is a content type, two headers and the request's headers for the access
//! token — a few lines — while a server framework would bring an async runtime into the build
//! and its own limits to re-prove against the hostile-input tests this one passes.

use std::collections::HashMap;
use std::io::{Read, Write};
use std::net::{IpAddr, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use tungstenite::WebSocket;
use tungstenite::protocol::{Role, WebSocketConfig};

use super::site::{Origin, SiteGuard, SiteRules};

/// Largest request head (request line + headers) read.
pub const MAX_HEAD: usize = 16 * 1024;
/// Connections served at once.
pub const MAX_CONNECTIONS: usize = 32;
/// Read and write timeout of a connection.
pub const TIMEOUT: Duration = Duration::from_secs(2);
/// How long the whole request head may take to arrive.
pub const HEAD_DEADLINE: Duration = Duration::from_secs(2);
/// Connections served at once from one address.
pub const MAX_PER_PEER: usize = 12;

/// WebSocket sessions open at once, unless the routes say otherwise.
pub const MAX_SOCKETS: usize = 8;
/// Largest WebSocket message (and frame) accepted.
pub const MAX_SOCKET_MESSAGE: usize = 64 * 1024;
/// How long a WebSocket read waits before the session gets to send.
pub const SOCKET_POLL: Duration = Duration::from_millis(20);

/// A request as a handler sees it: its target and its header lines.
#[derive(Clone, Copy, Debug)]
pub struct Request<'a> {
    /// The request target: path and query (`/indra/glow?VALUE`).
    pub target: &'a str,
    /// The head after the request line.
    headers: &'a str,
}

impl<'a> Request<'a> {
    /// A request for `target` with `headers` (`Name: value` lines joined by CRLF).
    pub fn new(target: &'a str, headers: &'a str) -> Self {
        Self { target, headers }
    }

    /// The path part of the target.
    pub fn path(&self) -> &'a str {
        self.target.split_once('?').map_or(self.target, |(path, _)| path)
    }

    /// The query part of the target (after `?`; empty without one).
    pub fn query(&self) -> &'a str {
        self.target.split_once('?').map_or("", |(_, query)| query)
    }

    /// The value of query parameter `name` (`?token=abc&x` → `abc` for `token`), undecoded.
    pub fn query_param(&self, name: &str) -> Option<&'a str> {
        value_of(self.query(), '&', name)
    }

    /// The first header called `name` (any case), trimmed.
    pub fn header(&self, name: &str) -> Option<&'a str> {
        self.headers
            .split("\r\n")
            .filter_map(|l| l.split_once(':'))
            .find(|(n, _)| n.trim().eq_ignore_ascii_case(name))
            .map(|(_, value)| value.trim())
    }

    /// The value of cookie `name`, if the request carries it.
    pub fn cookie(&self, name: &str) -> Option<&'a str> {
        value_of(self.header("cookie")?, ';', name)
    }
}

/// The value of `name` in a list of `name=value` pairs split by `separator`.
fn value_of<'a>(list: &'a str, separator: char, name: &str) -> Option<&'a str> {
    list.split(separator).filter_map(|pair| pair.trim().split_once('=')).find(|(n, _)| *n == name).map(|(_, v)| v)
}

/// What a handler answers: a status, a body and its type, and extra headers.
#[derive(Clone, Debug, PartialEq)]
pub struct Reply {
    /// HTTP status code.
    pub status: u16,
    /// The body's `Content-Type`.
    pub content_type: &'static str,
    /// The body.
    pub body: std::borrow::Cow<'static, [u8]>,
    /// More header lines (`Set-Cookie`, `Content-Security-Policy`, …).
    pub headers: Vec<(&'static str, String)>,
}

impl Reply {
    /// `body` of `content_type` with `status`, no extra headers.
    pub fn text(status: u16, content_type: &'static str, body: String) -> Self {
        Self { status, content_type, body: body.into_bytes().into(), headers: Vec::new() }
    }

    /// A JSON body with `status`.
    pub fn json(status: u16, body: String) -> Self {
        Self::text(status, "application/json", body)
    }

    /// An empty JSON object with `status` (errors say it by status alone).
    pub fn status(status: u16) -> Self {
        Self::json(status, "{}".into())
    }

    /// A file built into the binary.
    pub fn file(content_type: &'static str, body: &'static [u8]) -> Self {
        Self { status: 200, content_type, body: body.into(), headers: Vec::new() }
    }
}

/// What a handler answers for a request.
pub type Handler = dyn Fn(&Request<'_>) -> Reply + Send + Sync;

/// Serves one upgraded WebSocket session; it owns the connection until it returns. Reads time
/// out every [`SOCKET_POLL`] (an `Io` error of kind `WouldBlock` or `TimedOut`), so the session
/// can send between reads. It gets the request that asked for the upgrade (for its access token)
/// and where the page that asked comes from (never [`Origin::Foreign`]: those are refused).
pub type SocketHandler = dyn Fn(&Request<'_>, Origin, WebSocket<TcpStream>) + Send + Sync;

/// What the server answers: GETs, and optionally WebSocket sessions.
#[derive(Clone)]
pub struct Routes {
    /// Answers plain GETs.
    pub get: Arc<Handler>,
    /// Serves upgraded connections; without one, an upgrade is an ordinary GET.
    pub socket: Option<Arc<SocketHandler>>,
    /// WebSocket sessions open at once (default [`MAX_SOCKETS`]); more are answered `503`.
    pub max_sockets: usize,
    /// Names and origins opened beyond the server's own.
    pub sites: SiteRules,
}

/// A running server; stops when dropped.
pub struct HttpServer {
    local: SocketAddr,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl HttpServer {
    /// Listens on `addr` (port 0 picks one) and answers with `routes`.
    pub fn start(addr: &str, name: &str, routes: Routes) -> Result<Self, String> {
        let listener = TcpListener::bind(addr).map_err(|e| format!("cannot serve {name} on {addr}: {e}"))?;
        listener.set_nonblocking(true).map_err(|e| e.to_string())?;
        let local = listener.local_addr().map_err(|e| e.to_string())?;
        let stop = Arc::new(AtomicBool::new(false));
        let thread = {
            let stop = stop.clone();
            std::thread::Builder::new()
                .name(format!("indra-{name}"))
                .spawn(move || accept_loop(&listener, &stop, &routes, &Arc::new(SiteGuard::new(local, &routes.sites))))
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

fn accept_loop(listener: &TcpListener, stop: &AtomicBool, routes: &Routes, guard: &Arc<SiteGuard>) {
    let active = Arc::new(AtomicUsize::new(0));
    let peers: Arc<Mutex<HashMap<IpAddr, usize>>> = Arc::default();
    let sockets = Arc::new(AtomicUsize::new(0));
    while !stop.load(Ordering::Relaxed) {
        let Ok((stream, from)) = listener.accept() else {
            std::thread::sleep(Duration::from_millis(20));
            continue;
        };
        // Past the caps the connection is closed unread: idle floods cost no threads.
        if active.load(Ordering::Relaxed) >= MAX_CONNECTIONS || !take_place(&peers, from.ip()) {
            drop(stream);
            continue;
        }
        active.fetch_add(1, Ordering::Relaxed);
        let (active, peers, sockets, routes) = (active.clone(), peers.clone(), sockets.clone(), routes.clone());
        let guard = guard.clone();
        let spawned = std::thread::Builder::new().name("indra-http-conn".into()).spawn(move || {
            serve(stream, &routes, &guard, &sockets);
            active.fetch_sub(1, Ordering::Relaxed);
            leave_place(&peers, from.ip());
        });
        if spawned.is_err() {
            log::warn!("HTTP: cannot start a connection thread; connection dropped");
        }
    }
}

/// Counts a connection from `ip`, if it has fewer than [`MAX_PER_PEER`].
fn take_place(peers: &Mutex<HashMap<IpAddr, usize>>, ip: IpAddr) -> bool {
    let Ok(mut peers) = peers.lock() else { return false };
    let count = peers.entry(ip).or_default();
    if *count >= MAX_PER_PEER {
        return false;
    }
    *count += 1;
    true
}

/// Un-counts a connection from `ip`.
fn leave_place(peers: &Mutex<HashMap<IpAddr, usize>>, ip: IpAddr) {
    let Ok(mut peers) = peers.lock() else { return };
    if let Some(count) = peers.get_mut(&ip) {
        *count -= 1;
        if *count == 0 {
            peers.remove(&ip);
        }
    }
}

/// Answers one request on `stream`, within the limits, or serves the WebSocket it upgrades to.
fn serve(mut stream: TcpStream, routes: &Routes, guard: &SiteGuard, sockets: &AtomicUsize) {
    let _ = stream.set_nonblocking(false);
    let _ = stream.set_read_timeout(Some(TIMEOUT));
    let _ = stream.set_write_timeout(Some(TIMEOUT));
    let head = match read_head(&mut stream) {
        Ok(head) => head,
        Err(status) => {
            let _ = write_reply(&mut stream, &Reply::status(status));
            return;
        }
    };
    let (method, request) = parse(&head);
    if !guard.host_ok(request.header("host")) {
        let _ = write_reply(&mut stream, &Reply::status(421));
        return;
    }
    let origin = guard.origin(request.header("origin"));
    let mut reply = match (&routes.socket, websocket_key(method, &request)) {
        (Some(_), Some(_)) if origin == Origin::Foreign => Reply::status(403),
        (Some(handler), Some(key)) => {
            if sockets.fetch_add(1, Ordering::Relaxed) < routes.max_sockets {
                upgrade(stream, &request, origin, key, handler);
                sockets.fetch_sub(1, Ordering::Relaxed);
                return;
            }
            sockets.fetch_sub(1, Ordering::Relaxed);
            Reply::status(503)
        }
        _ => answer(method, &request, &routes.get),
    };
    reply.headers.extend(SiteGuard::cors_headers(request.header("origin"), origin));
    let _ = write_reply(&mut stream, &reply);
}

/// Writes `reply` as a whole HTTP/1.1 response that closes the connection.
fn write_reply(stream: &mut TcpStream, reply: &Reply) -> std::io::Result<()> {
    let status = reply.status;
    let reason = match status {
        200 => "OK",
        401 => "Unauthorized",
        403 => "Forbidden",
        421 => "Misdirected Request",
        404 => "Not Found",
        405 => "Method Not Allowed",
        408 => "Request Timeout",
        413 => "Content Too Large",
        503 => "Service Unavailable",
        431 => "Request Header Fields Too Large",
        _ => "Bad Request",
    };
    let mut head = format!(
        "HTTP/1.1 {status} {reason}\r\nContent-Type: {}\r\nContent-Length: {}\r\nConnection: close\r\n",
        reply.content_type,
        reply.body.len()
    );
    for (name, value) in &reply.headers {
        head.push_str(&format!("{name}: {value}\r\n"));
    }
    head.push_str("\r\n");
    stream.write_all(head.as_bytes())?;
    stream.write_all(&reply.body)?;
    stream.flush()
}

/// The `Sec-WebSocket-Key` of a GET that asks for a WebSocket (version 13), if it does.
fn websocket_key<'a>(method: &str, request: &Request<'a>) -> Option<&'a str> {
    let upgrade = request.header("upgrade").is_some_and(|v| v.eq_ignore_ascii_case("websocket"));
    (method == "GET" && upgrade && request.header("sec-websocket-version") == Some("13"))
        .then(|| request.header("sec-websocket-key"))?
}

/// The method of a request head and the request it makes.
fn parse(head: &str) -> (&str, Request<'_>) {
    let (line, headers) = head.split_once("\r\n").unwrap_or((head, ""));
    let mut parts = line.split(' ');
    let (method, target) = (parts.next().unwrap_or(""), parts.next().unwrap_or(""));
    (method, Request::new(target, headers))
}

/// Completes the handshake and hands the session to `handler`.
fn upgrade(mut stream: TcpStream, request: &Request<'_>, origin: Origin, key: &str, handler: &Arc<SocketHandler>) {
    let accept = tungstenite::handshake::derive_accept_key(key.as_bytes());
    let answered = write!(
        stream,
        "HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Accept: {accept}\r\n\r\n"
    );
    if answered.is_err() || stream.set_read_timeout(Some(SOCKET_POLL)).is_err() {
        return;
    }
    let config =
        WebSocketConfig::default().max_message_size(Some(MAX_SOCKET_MESSAGE)).max_frame_size(Some(MAX_SOCKET_MESSAGE));
    handler(request, origin, WebSocket::from_raw_socket(stream, Role::Server, Some(config)));
}

/// The request head (up to the blank line), or the status to answer with: `408` when it has
/// not all arrived within [`HEAD_DEADLINE`], however steadily its bytes trickle in.
fn read_head(stream: &mut TcpStream) -> Result<String, u16> {
    let deadline = Instant::now() + HEAD_DEADLINE;
    let mut head = [0u8; MAX_HEAD];
    let mut len = 0;
    loop {
        if len == MAX_HEAD {
            return Err(431);
        }
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() || stream.set_read_timeout(Some(left.min(TIMEOUT))).is_err() {
            return Err(408);
        }
        let n = match stream.read(&mut head[len..]) {
            Ok(n) => n,
            Err(e) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {
                return Err(408);
            }
            Err(_) => return Err(400),
        };
        if n == 0 {
            return Err(400);
        }
        len += n;
        if let Some(end) = head[..len].windows(4).position(|w| w == b"\r\n\r\n") {
            return String::from_utf8(head[..end].to_vec()).map_err(|_| 400);
        }
    }
}

/// The reply to a request made with `method`.
fn answer(method: &str, request: &Request<'_>, handler: &Arc<Handler>) -> Reply {
    if method != "GET" {
        return Reply::status(405);
    }
    let declares_body = request.header("transfer-encoding").is_some()
        || request.header("content-length").is_some_and(|length| length != "0");
    if declares_body {
        return Reply::status(413);
    }
    handler(request)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn echo() -> Arc<Handler> {
        Arc::new(|request: &Request<'_>| Reply::json(200, format!("{{\"target\":\"{}\"}}", request.target)))
    }

    #[test]
    fn gets_are_answered_and_everything_else_is_refused_by_status() {
        let handler = echo();
        let answer = |head: &str| {
            let (method, request) = parse(head);
            super::answer(method, &request, &handler)
        };
        assert_eq!(answer("GET /a?b HTTP/1.1\r\nHost: x"), Reply::json(200, "{\"target\":\"/a?b\"}".into()));
        assert_eq!(answer("POST / HTTP/1.1").status, 405);
        assert_eq!(answer("GET / HTTP/1.1\r\nContent-Length: 99999999999").status, 413);
        assert_eq!(answer("GET / HTTP/1.1\r\ntransfer-encoding: chunked").status, 413);
        assert_eq!(answer("GET / HTTP/1.1\r\nContent-Length: 0").status, 200);
    }

    #[test]
    fn a_request_reads_its_query_headers_and_cookies() {
        let head = "GET /p?token=ab%2F&x HTTP/1.1\r\nHost: h\r\nCookie: a=1; indra_token=zz\r\nACCEPT: text/html";
        let request = parse(head).1;
        assert_eq!((request.path(), request.query()), ("/p", "token=ab%2F&x"));
        assert_eq!(request.query_param("token"), Some("ab%2F"));
        assert_eq!(request.query_param("x"), None, "a bare key has no value");
        assert_eq!(request.header("accept"), Some("text/html"));
        assert_eq!(request.cookie("indra_token"), Some("zz"));
        assert_eq!(request.cookie("b"), None);
    }

    #[test]
    fn only_a_get_asking_for_websocket_version_13_upgrades() {
        let ask = |head: &str| {
            let (method, request) = parse(head);
            websocket_key(method, &request).map(str::to_string)
        };
        let good = "GET / HTTP/1.1\r\nUpgrade: WebSocket\r\nConnection: Upgrade\r\nSec-WebSocket-Version: 13\r\nSec-WebSocket-Key: abc==";
        assert_eq!(ask(good).as_deref(), Some("abc=="));
        assert_eq!(ask(&good.replace("GET", "POST")), None);
        assert_eq!(ask(&good.replace("13", "8")), None);
        assert_eq!(ask(&good.replace("WebSocket\r", "h2c\r")), None);
        assert_eq!(ask("GET / HTTP/1.1\r\nUpgrade: websocket\r\nSec-WebSocket-Version: 13"), None, "no key");
    }
}
