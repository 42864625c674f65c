//! A headless Chromium (Debian's) driven over the DevTools protocol: a WebSocket, through the
//! tungstenite indra already uses — no WebDriver server or async runtime needed. Used by the
//! browser control surface's tests and by the ISF reference renderer's.

use std::io::{Read, Write};
use std::net::TcpStream;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::{Value, json};

/// A headless Chromium with its own profile, killed when dropped.
pub struct Chromium {
    child: Child,
    port: u16,
}

impl Chromium {
    pub fn start(profile: &Path) -> Self {
        let child = Command::new("chromium")
            .args(["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--remote-debugging-port=0"])
            .arg(format!("--user-data-dir={}", profile.display()))
            .arg("about:blank")
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("chromium runs (tools/setup-system test installs it)");
        // Chromium writes the port it picked into the profile.
        let deadline = Instant::now() + Duration::from_secs(60);
        let port = loop {
            if let Some(port) = std::fs::read_to_string(profile.join("DevToolsActivePort"))
                .ok()
                .and_then(|t| t.lines().next().and_then(|l| l.parse().ok()))
            {
                break port;
            }
            assert!(Instant::now() < deadline, "Chromium did not start its DevTools server");
            std::thread::sleep(Duration::from_millis(100));
        };
        Self { child, port }
    }

    /// A new tab showing `url`.
    pub fn open(&self, url: &str) -> Page {
        let mut s = TcpStream::connect(("127.0.0.1", self.port)).unwrap();
        // The Host header names the port DevTools puts in the page's WebSocket URL.
        write!(s, "PUT /json/new?{url} HTTP/1.1\r\nHost: 127.0.0.1:{}\r\n\r\n", self.port).unwrap();
        // DevTools' server may keep the connection open: read the head, then its Content-Length.
        s.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
        let mut bytes = Vec::new();
        let mut buf = [0u8; 4096];
        let reply = loop {
            let n = s.read(&mut buf).unwrap();
            bytes.extend_from_slice(&buf[..n]);
            let text = String::from_utf8_lossy(&bytes).to_string();
            if let Some((head, body)) = text.split_once("\r\n\r\n") {
                let length = head
                    .lines()
                    .find_map(|l| l.to_ascii_lowercase().strip_prefix("content-length:").map(|v| v.trim().to_string()))
                    .and_then(|v| v.parse::<usize>().ok());
                if n == 0 || length.is_some_and(|l| body.len() >= l) {
                    break text;
                }
            }
            assert!(n > 0, "DevTools closed the connection: {text}");
        };
        let body = reply.split("\r\n\r\n").nth(1).unwrap_or_default();
        let target: Value = serde_json::from_str(body).unwrap_or_else(|e| panic!("{e}: {reply}"));
        let ws = target["webSocketDebuggerUrl"].as_str().unwrap().to_string();
        let (socket, _) = tungstenite::connect(ws).unwrap();
        Page { socket, next: 1 }
    }
}

impl Drop for Chromium {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// One tab, driven over its DevTools WebSocket.
pub struct Page {
    socket: tungstenite::WebSocket<tungstenite::stream::MaybeTlsStream<TcpStream>>,
    next: u64,
}

impl Page {
    /// Calls a DevTools method and returns its result (events on the way are skipped).
    pub fn call(&mut self, method: &str, params: Value) -> Value {
        let id = self.next;
        self.next += 1;
        let request = json!({ "id": id, "method": method, "params": params }).to_string();
        self.socket.send(tungstenite::Message::Text(request.into())).unwrap();
        loop {
            let message = self.socket.read().unwrap();
            let Ok(text) = message.to_text() else { continue };
            let reply: Value = serde_json::from_str(text).unwrap_or_default();
            if reply["id"] == id {
                assert!(reply["error"].is_null(), "{method}: {reply}");
                return reply["result"].clone();
            }
        }
    }

    /// The value of a JavaScript expression (awaited if a promise).
    pub fn eval(&mut self, expression: &str) -> Value {
        self.try_eval(expression).unwrap_or_else(|e| panic!("{expression}: {e}"))
    }

    /// The value of a JavaScript expression, or the exception it threw.
    pub fn try_eval(&mut self, expression: &str) -> Result<Value, Value> {
        let result = self
            .call("Runtime.evaluate", json!({ "expression": expression, "returnByValue": true, "awaitPromise": true }));
        if result["exceptionDetails"].is_null() { Ok(result["result"]["value"].clone()) } else { Err(result) }
    }

    /// Waits (at most 60 s) until `condition` is true in the page.
    pub fn wait_until(&mut self, condition: &str) {
        let deadline = Instant::now() + Duration::from_secs(60);
        // Until the page has loaded, its elements may not exist yet: an exception is "not yet".
        while self.try_eval(condition) != Ok(Value::Bool(true)) {
            if Instant::now() > deadline {
                let state = self.eval("[document.body.dataset.state, document.querySelectorAll('[data-path]').length]");
                panic!("never true in the page (state, controls: {state}): {condition}");
            }
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// A left click at `fraction` (0–1) across the element `selector`, scrolled into view.
    pub fn click(&mut self, selector: &str, fraction: f64) {
        let rect = self.eval(&format!(
            "(() => {{ const e = document.querySelector({selector:?}); e.scrollIntoView({{ block: 'center' }});
               const r = e.getBoundingClientRect(); return [r.left, r.top, r.width, r.height]; }})()"
        ));
        let [left, top, width, height] = [0, 1, 2, 3].map(|i| rect[i].as_f64().unwrap());
        let (x, y) = (left + width * fraction, top + height / 2.0);
        for kind in ["mousePressed", "mouseReleased"] {
            let event = json!({ "type": kind, "x": x, "y": y, "button": "left", "clickCount": 1 });
            self.call("Input.dispatchMouseEvent", event);
        }
    }
}

/// Standard base64 (DevTools sends screenshots so); ten lines rather than a dependency.
pub fn base64_decode(text: &str) -> Vec<u8> {
    let value = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        _ => 63,
    };
    let digits: Vec<u8> = text.bytes().filter(|&c| c != b'=').map(value).collect();
    digits
        .chunks(4)
        .flat_map(|c| {
            let n = c.iter().enumerate().fold(0u32, |n, (i, &d)| n | u32::from(d) << (18 - 6 * i));
            n.to_be_bytes()[1..c.len()].to_vec()
        })
        .collect()
}
