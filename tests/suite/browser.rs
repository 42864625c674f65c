//! The browser control surface in a real browser: Debian's headless Chromium, driven over the
//! DevTools protocol (a WebSocket, through the tungstenite indra already uses — no WebDriver
//! server or async runtime needed), against `indra run --web` in a virtual display. Mouse
//! events are real input events: a click on a slider's track moves it as a finger would.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use serde_json::{Value, json};

use crate::chromium::{Chromium, Page, base64_decode};
use crate::live_show::{Show, VirtualDisplay, scratch_dir};
use crate::osc::http_get;

/// The address of every value and trigger a client may reach in an OSCQuery tree.
fn leaves(tree: &Value, out: &mut Vec<(String, Value)>) {
    if let Some(path) = tree["FULL_PATH"].as_str()
        && tree["TYPE"].is_string()
    {
        out.push((path.to_string(), tree.clone()));
    }
    if let Some(contents) = tree["CONTENTS"].as_object() {
        for child in contents.values() {
            leaves(child, out);
        }
    }
}

/// A parameter's value as the show publishes it (the tree is republished every few frames).
fn published(query: SocketAddr, path: &str) -> Option<f64> {
    let (status, leaf) = http_get(query, path);
    (status == 200).then(|| leaf["VALUE"][0].as_f64()).flatten()
}

fn wait_for_published(query: SocketAddr, path: &str, want: f64, tolerance: f64) {
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        let got = published(query, path);
        if got.is_some_and(|v| (v - want).abs() <= tolerance) {
            return;
        }
        assert!(Instant::now() < deadline, "{path} is {got:?}, not {want}");
        std::thread::sleep(Duration::from_millis(100));
    }
}

const SHOW: &str = r#"(
    name: "browser show",
    size: (64, 36),
    layers: [(name: "main", clips: [
        (scene: "kleinian_classic", id: "red", params: { "limit_set.hit_color": (0.9, 0.1, 0.1, 1.0) }),
        (scene: "kleinian_classic", id: "blue", params: { "limit_set.hit_color": (0.1, 0.2, 0.9, 1.0) }),
    ])],
    cues: [(name: "red", clips: [(1, 1)]), (name: "blue", clips: [(1, 2)]), (name: "red again", clips: [(1, 1)])],
)"#;

const TOKEN: &str = "browser-test-token";

/// Where the phone-sized screenshot goes (the README's comes from here).
fn screenshot_path() -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join("web-phone.png")
}

#[test]
fn a_browser_controls_the_show_and_follows_every_other_source() {
    let display = VirtualDisplay::start();
    let dir = scratch_dir("browser");
    let file = dir.join("show.ron");
    std::fs::write(&file, SHOW).unwrap();
    let query = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap();
    // Two other sites on this host: one the performer allows as an OSCQuery web client.
    let (foreign, allowed) = (SitePage::start(query), SitePage::start(query));
    let recording = dir.join("controls.ron");
    let args: Vec<std::ffi::OsString> = vec![
        "--web".into(),
        query.to_string().into(),
        "--web-token".into(),
        TOKEN.into(),
        "--record-controls".into(),
        recording.clone().into(),
        "--oscquery-cors".into(),
        allowed.origin().into(),
    ];
    let args: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_os_str()).collect();
    let (mut show, osc_port) = Show::start(&display, &dir, file.to_str().unwrap(), &args);
    show.wait_for("control surface on");
    show.wait_for("plays clip 'red'");

    // Without the token there is no page (its WebSocket is tested in osc.rs).
    let raw = |head: &str| {
        let mut s = TcpStream::connect(query).unwrap();
        s.write_all(head.as_bytes()).unwrap();
        let mut reply = String::new();
        let _ = s.read_to_string(&mut reply);
        reply
    };
    assert!(raw("GET / HTTP/1.1\r\nAccept: text/html\r\n\r\n").starts_with("HTTP/1.1 401"));
    assert!(raw("GET /?token=guess-guess-guess HTTP/1.1\r\nAccept: text/html\r\n\r\n").starts_with("HTTP/1.1 401"));

    let url = format!("http://{query}/?token={TOKEN}");
    let browser = Chromium::start(&dir.join("profile-a"));
    let other_browser = Chromium::start(&dir.join("profile-b"));
    let mut page = browser.open(&url);
    let mut other = other_browser.open(&url);
    for p in [&mut page, &mut other] {
        p.wait_until("document.body.dataset.state === 'live' && document.querySelectorAll('[data-path]').length > 10");
    }

    // The page holds a control for every value and trigger of the tree.
    let (_, tree) = http_get(query, "/");
    let mut all = Vec::new();
    leaves(&tree, &mut all);
    let shown: Vec<String> =
        serde_json::from_value(page.eval("[...document.querySelectorAll('[data-path]')].map(e => e.dataset.path)"))
            .unwrap();
    let missing: Vec<&String> = all.iter().map(|(p, _)| p).filter(|p| !shown.contains(p)).collect();
    assert!(missing.is_empty(), "no control for {missing:?}");
    assert!(all.len() > 20, "{} leaves", all.len());

    // A click on a slider's track moves the parameter in the show.
    let (path, leaf) = all
        .iter()
        .find(|(p, l)| p.starts_with("/indra/red/") && l["TYPE"] == "f" && l["RANGE"][0]["MAX"].is_number())
        .expect("a bounded float of the playing clip")
        .clone();
    let (lo, hi) = (leaf["RANGE"][0]["MIN"].as_f64().unwrap(), leaf["RANGE"][0]["MAX"].as_f64().unwrap());
    let slider = format!("[data-path=\"{path}\"] input");
    let value_of =
        |p: &mut Page| p.eval(&format!("Number(document.querySelector({slider:?}).value)")).as_f64().unwrap();
    page.click(&slider, 0.8);
    let moved = value_of(&mut page);
    assert!((moved - (lo + 0.8 * (hi - lo))).abs() < 0.05 * (hi - lo), "{path}: clicked to {moved} in {lo}..{hi}");
    wait_for_published(query, &path, moved, 1e-3 * (hi - lo));
    // … and the second browser follows.
    other.wait_until(&format!("Math.abs(Number(document.querySelector({slider:?}).value) - {moved}) < 1e-6"));

    // An OSC message from another program moves the slider in both browsers.
    let target = lo + 0.25 * (hi - lo);
    let sent = Command::new("oscsend")
        .args(["127.0.0.1", &osc_port.to_string(), &path, "f", &target.to_string()])
        .status()
        .expect("oscsend runs (liblo-tools)");
    assert!(sent.success());
    for p in [&mut page, &mut other] {
        p.wait_until(&format!("Math.abs(Number(document.querySelector({slider:?}).value) - {target}) < 1e-3"));
    }

    // GO fires once: the show moves one cue on, to blue, and stays there.
    page.click("button[data-path=\"/indra/cue/go\"]", 0.5);
    show.wait_for("plays clip 'blue'");
    std::thread::sleep(Duration::from_secs(2));
    let log = show.wait_for("plays clip 'blue'");
    assert_eq!(log.matches("plays clip 'red'").count(), 1, "GO fired more than once:\n{log}");
    // The browser's writes are ordinary control events: in the recording, once each.
    // (While the show runs, its recording is written beside the target, renamed when it ends.)
    let taking = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .find(|e| e.file_name().to_string_lossy().starts_with(".controls.ron."))
        .expect("the recording in progress");
    let recorded = std::fs::read_to_string(taking.path()).unwrap();
    assert_eq!(recorded.matches("CueGo").count(), 1, "{recorded}");
    assert!(recorded.contains(&path.rsplit('/').next().unwrap().to_string()), "{recorded}");

    // Another site's page in the same browser (its cookie stored) cannot write: its socket is
    // refused, and it cannot read the tree; an allowed client reads the tree and LISTENs, and
    // its socket, without the token, writes nothing.
    let before = published(query, &path);
    let mut attacker = browser.open(&foreign.url(&path, hi));
    attacker.wait_until("document.title.startsWith('done')");
    assert_eq!(attacker.eval("document.title"), "done socket:refused tree:blocked");
    let mut client = browser.open(&allowed.url(&path, hi));
    client.wait_until("document.title.startsWith('done')");
    assert_eq!(client.eval("document.title"), "done socket:closed tree:read");
    std::thread::sleep(Duration::from_secs(1));
    assert_eq!(published(query, &path), before, "another site's page changed {path}");

    // The page fits a phone: 375 px wide with nothing to scroll sideways.
    page.call(
        "Emulation.setDeviceMetricsOverride",
        json!({ "width": 375, "height": 812, "deviceScaleFactor": 2, "mobile": true }),
    );
    page.eval("window.scrollTo(0, 0)");
    page.wait_until("document.documentElement.scrollWidth <= 375");
    let shot = page.call("Page.captureScreenshot", json!({ "format": "png" }));
    let png = base64_decode(shot["data"].as_str().unwrap());
    let image = image::load_from_memory(&png).unwrap();
    assert_eq!(image.width(), 750, "a 375-px screen at 2×");
    std::fs::write(screenshot_path(), png).unwrap();
}

/// A page of another site on this host (a port of its own) that tries what a hostile page
/// would against the show's server: open a WebSocket and write a parameter, and read the tree
/// with `fetch`. It says in its title what happened.
struct SitePage {
    addr: SocketAddr,
}

impl SitePage {
    /// Serves the page on a free port, against the server at `target`, until the test ends.
    fn start(target: SocketAddr) -> Self {
        let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap();
        let page = format!(
            "<!doctype html><title>running</title><script>
            const said = {{}};
            const done = () => {{ if (said.socket && said.tree) document.title = `done socket:${{said.socket}} tree:${{said.tree}}`; }};
            fetch('http://{target}/?HOST_INFO').then(r => r.json()).then(() => {{ said.tree = 'read'; done(); }},
                () => {{ said.tree = 'blocked'; done(); }});
            const ws = new WebSocket('ws://{target}/');
            ws.binaryType = 'arraybuffer';
            let opened = false;
            ws.onopen = () => {{ opened = true;
                // The address and value from the page's URL (`?path=/indra/…&value=0.5`), as OSC bytes.
                const query = new URLSearchParams(location.search);
                const [path, value] = [query.get('path'), query.get('value')];
                const text = s => {{ const b = new TextEncoder().encode(s); const n = Math.ceil((b.length + 1) / 4) * 4;
                    const o = new Uint8Array(n); o.set(b); return o; }};
                const a = text(path), t = text(',f'), v = new Uint8Array(4);
                new DataView(v.buffer).setFloat32(0, Number(value));
                const m = new Uint8Array(a.length + t.length + 4); m.set(a); m.set(t, a.length); m.set(v, a.length + t.length);
                ws.send(m.buffer); }};
            ws.onclose = () => {{ said.socket = opened ? 'closed' : 'refused'; done(); }};
            </script>"
        );
        std::thread::spawn(move || {
            for stream in listener.incoming().flatten() {
                let mut stream = stream;
                let mut head = [0u8; 4096];
                let _ = stream.read(&mut head);
                let reply = format!(
                    "HTTP/1.1 200 OK\r\nContent-Type: text/html\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{page}",
                    page.len()
                );
                let _ = stream.write_all(reply.as_bytes());
            }
        });
        Self { addr }
    }

    /// Its origin, as a browser names it.
    fn origin(&self) -> String {
        format!("http://{}", self.addr)
    }

    /// The page's URL, asking it to write `value` to `path`.
    fn url(&self, path: &str, value: f64) -> String {
        format!("{}/?path={path}&value={value}", self.origin())
    }
}
