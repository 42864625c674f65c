//! Network stream latency: from a frame handed to `--stream`'s encoder (as the live recorder
//! hands it, paced at 60 fps) to the same frame decoded by an ffmpeg receiver on loopback, for
//! SRT (with its default 120 ms receive buffer, and with 20 ms), UDP and RTMP; and from a frame
//! handed to `--pipewire-out`'s source to a GStreamer `pipewiresrc` consumer, where a PipeWire
//! daemon runs (`tools/bench-pipewire`). Each frame carries its number in eight black-or-white blocks, which survive
//! H.264; the receiver's raw frames are read as they come and matched to their send times.
//! Run: `cargo bench --bench stream` (needs ffmpeg with SRT; prints medians and 95th percentiles).

use std::io::Read;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use indra::offscreen::{PipeWireOut, VideoSettings, VideoWriter};

/// Frame side: eight 8-pixel blocks across the top carry the number.
const SIDE: u32 = 64;
const FRAMES: u32 = 240;
const FPS: f64 = 60.0;

/// Frame `n` as RGBA: block b of the top row white when bit b of n is set.
fn frame(n: u32) -> Vec<u8> {
    let mut rgba = vec![64u8; (SIDE * SIDE * 4) as usize];
    for y in 0..16 {
        for x in 0..SIDE {
            let bit = (n >> (x / 8)) & 1;
            let v = if bit == 1 { 255 } else { 0 };
            let i = ((y * SIDE + x) * 4) as usize;
            rgba[i..i + 3].fill(v);
            rgba[i + 3] = 255;
        }
    }
    rgba
}

/// The number a received grey frame carries (the middle of each block's top rows).
fn number(gray: &[u8]) -> u32 {
    (0..8).map(|b| u32::from(gray[(6 * SIDE + b * 8 + 4) as usize] > 128) << b).sum()
}

/// Frames handed to `send` at 60 fps, numbered, against their arrival in `receiver` (a
/// process writing 64×64 grey frames to its standard output): latencies in ms, sorted.
fn measure(mut receiver: Command, mut send: impl FnMut(&[u8]), finish: impl FnOnce()) -> Vec<f64> {
    let mut receiver = receiver.stdout(Stdio::piped()).spawn().expect("the receiver runs");
    let mut out = receiver.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut arrivals = Vec::new();
        let mut buf = vec![0u8; (SIDE * SIDE) as usize];
        while out.read_exact(&mut buf).is_ok() {
            arrivals.push((number(&buf), Instant::now()));
        }
        arrivals
    });
    std::thread::sleep(Duration::from_millis(500));
    let start = Instant::now();
    let mut sent = Vec::new();
    for n in 0..FRAMES {
        let due = start + Duration::from_secs_f64(f64::from(n) / FPS);
        std::thread::sleep(due.saturating_duration_since(Instant::now()));
        sent.push(Instant::now());
        send(&frame(n));
    }
    finish();
    std::thread::sleep(Duration::from_millis(500));
    let _ = receiver.kill();
    let _ = receiver.wait();
    let arrivals = reader.join().unwrap();
    // Numbers wrap at 256: match each arrival to the latest frame sent before it with that number.
    let mut ms: Vec<f64> = arrivals
        .iter()
        .filter_map(|(n, at)| {
            let k = (0..FRAMES).rev().find(|&k| k % 256 == *n && sent[k as usize] <= *at)?;
            Some(at.duration_since(sent[k as usize]).as_secs_f64() * 1000.0)
        })
        .collect();
    ms.sort_by(f64::total_cmp);
    ms
}

fn latencies(scheme: &str) -> Vec<f64> {
    if scheme == "pipewire" {
        return pipewire_latencies();
    }
    let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let (listen, send) = match scheme {
        "srt" => (format!("srt://127.0.0.1:{port}?mode=listener"), format!("srt://127.0.0.1:{port}?mode=caller")),
        // SRT's receive buffer (120 ms unless told) lowered to 20 ms on both ends.
        "srt20" => (
            format!("srt://127.0.0.1:{port}?mode=listener&latency=20000"),
            format!("srt://127.0.0.1:{port}?mode=caller&latency=20000"),
        ),
        "rtmp" => (format!("rtmp://127.0.0.1:{port}/live/b"), format!("rtmp://127.0.0.1:{port}/live/b")),
        _ => (format!("udp://127.0.0.1:{port}"), format!("udp://127.0.0.1:{port}")),
    };
    let mut receiver = Command::new("ffmpeg");
    // A low-latency receiver: no input buffering, a short probe.
    receiver.args(["-v", "error", "-fflags", "nobuffer", "-flags", "low_delay", "-probesize", "32768"]);
    receiver.args(["-analyzeduration", "200000", "-threads", "1"]);
    if scheme == "rtmp" {
        receiver.args(["-listen", "1", "-f", "flv"]);
    } else {
        receiver.args(["-f", "mpegts"]);
    }
    receiver.args(["-i", &listen, "-f", "rawvideo", "-pix_fmt", "gray", "-"]);
    let settings = VideoSettings::stream(&send, (SIDE, SIDE), FPS, false);
    let writer = std::cell::RefCell::new(None::<VideoWriter>);
    measure(
        receiver,
        |rgba| {
            // ffmpeg starts once the receiver listens (`measure` waits half a second first).
            let mut writer = writer.borrow_mut();
            let writer = writer.get_or_insert_with(|| VideoWriter::start(settings.clone()).expect("the stream starts"));
            writer.write(rgba).expect("the encoder takes the frame");
        },
        || drop(writer.take().map(VideoWriter::finish)),
    )
}

/// The PipeWire source (`--pipewire-out`) read by a GStreamer consumer, on the session in
/// `XDG_RUNTIME_DIR` (tools/bench-pipewire starts one).
fn pipewire_latencies() -> Vec<f64> {
    let mut source = PipeWireOut::start("indra-bench", (SIDE, SIDE), FPS, false).expect("a PipeWire daemon runs");
    // The node appears with the first frame's format, and a consumer started before its target
    // exists never links: one frame, then wait for the node.
    source.write(&frame(255)).expect("the source takes a frame");
    let deadline = Instant::now() + Duration::from_secs(10);
    while !Command::new("pw-cli")
        .args(["ls", "Node"])
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).contains("node.name = \"indra-bench\""))
    {
        assert!(Instant::now() < deadline, "the node did not appear");
        std::thread::sleep(Duration::from_millis(50));
    }
    let mut receiver = Command::new("gst-launch-1.0");
    receiver.args(["-q", "pipewiresrc", "target-object=indra-bench", "!", "videoconvert", "!"]);
    receiver.args(["video/x-raw,format=GRAY8", "!", "fdsink", "fd=1", "sync=false"]);
    let source = std::cell::RefCell::new(Some(source));
    measure(
        receiver,
        |rgba| source.borrow_mut().as_mut().expect("open").write(rgba).expect("the source takes the frame"),
        || drop(source.borrow_mut().take().map(PipeWireOut::finish)),
    )
}

fn main() {
    // PipeWire needs a daemon (tools/bench-pipewire runs this bench with one).
    let pipewire =
        std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| std::path::Path::new(&d).join("pipewire-0").exists());
    for scheme in ["srt", "srt20", "udp", "rtmp", "pipewire"].into_iter().filter(|s| *s != "pipewire" || pipewire) {
        let ms = latencies(scheme);
        if ms.is_empty() {
            println!("{scheme:<5} no frames arrived");
            continue;
        }
        let at = |q: f64| ms[((ms.len() - 1) as f64 * q) as usize];
        println!(
            "{scheme:<5} frame handed to the encoder → decoded by the receiver: median {:.1} ms, p95 {:.1} ms ({} of {FRAMES} frames)",
            at(0.5),
            at(0.95),
            ms.len()
        );
    }
}
