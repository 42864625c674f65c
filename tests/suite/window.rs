//! The live show in a real window, on a virtual X display (Xvfb, installed by
//! tools/setup-system test): recording to video from the command line, stopping and starting
//! takes over OSC, and a complete file after SIGTERM.

use std::net::UdpSocket;
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use crate::live_show::{Show, VirtualDisplay, scratch_dir, send};

fn frames(path: &Path) -> u64 {
    let o = Command::new("ffprobe")
        .args(["-v", "error", "-count_frames", "-show_entries", "stream=nb_read_frames", "-of", "csv=p=0"])
        .arg(path)
        .output()
        .expect("ffprobe runs (tools/setup-system test installs ffmpeg)");
    // MPEG-TS lists the stream under its program too: the first count is the stream's.
    let out = String::from_utf8_lossy(&o.stdout);
    out.lines()
        .find(|l| !l.trim().is_empty())
        .and_then(|l| l.trim().parse().ok())
        .unwrap_or_else(|| panic!("{} is no video", path.display()))
}

#[test]
fn the_show_records_takes_started_and_stopped_over_osc_and_finishes_on_sigterm() {
    let display = VirtualDisplay::start();
    let dir = scratch_dir("window");
    let video = dir.join("show.mp4");
    let (mut show, port) = Show::start(&display, &dir, "star_glow", &["--record-video".as_ref(), video.as_os_str()]);
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();

    show.wait_for("recording to");
    std::thread::sleep(Duration::from_secs(2));
    send(&socket, port, "/indra/record/stop", vec![]);
    let log = show.wait_for("recorded ");
    let first: u64 = log
        .split("recorded ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no frame count in:\n{log}"));
    assert!(first > 0, "{log}");
    assert_eq!(frames(&dir.join("show.mp4")), first, "the file holds what the show reported");

    // A take named over the network lands beside the first; a path is refused.
    send(&socket, port, "/indra/record/start", vec![rosc::OscType::String("../escape.mp4".into())]);
    send(&socket, port, "/indra/record/start", vec![rosc::OscType::String("encore".into())]);
    show.wait_for("encore.mp4");
    std::thread::sleep(Duration::from_secs(2));
    let terminated = Command::new("kill").args(["-TERM", &show.child.id().to_string()]).status().unwrap();
    assert!(terminated.success());
    let deadline = Instant::now() + Duration::from_secs(60);
    let status = loop {
        if let Some(status) = show.child.try_wait().unwrap() {
            break status;
        }
        assert!(Instant::now() < deadline, "the show did not end after SIGTERM");
        std::thread::sleep(Duration::from_millis(100));
    };
    let log = std::fs::read_to_string(&show.log).unwrap();
    assert!(status.success(), "{status}:\n{log}");
    assert!(log.contains("is not a plain file name"), "{log}");
    assert!(!dir.parent().unwrap().join("escape.mp4").exists());
    assert!(frames(&dir.join("encore.mp4")) > 0, "the take stopped by SIGTERM is a complete file:\n{log}");
}

/// The virtual screen as RGB bytes (ffmpeg's X11 grabber), `size` pixels from the top left.
#[test]
fn the_show_streams_over_srt_from_the_start_until_sigterm() {
    let display = VirtualDisplay::start();
    let dir = scratch_dir("window-stream");
    let port = std::net::UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let received = dir.join("received.ts");
    let mut receiver = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-f", "mpegts", "-i", &format!("srt://127.0.0.1:{port}?mode=listener")])
        .args(["-c", "copy", received.to_str().unwrap()])
        .spawn()
        .expect("ffmpeg is needed for this test: run tools/setup-system test");
    std::thread::sleep(Duration::from_millis(500));
    let url = format!("srt://127.0.0.1:{port}?mode=caller");
    let (mut show, _) = Show::start(&display, &dir, "kleinian", &["--stream".as_ref(), url.as_ref()]);
    show.wait_for("streaming to");
    std::thread::sleep(Duration::from_secs(3));
    assert!(Command::new("kill").args(["-TERM", &show.child.id().to_string()]).status().unwrap().success());
    let log = show.wait_for("send ended");
    let deadline = Instant::now() + Duration::from_secs(30);
    while receiver.try_wait().unwrap().is_none() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(100));
    }
    let _ = receiver.kill();
    let size = std::fs::metadata(&received).map(|m| m.len()).unwrap_or(0);
    assert!(size > 0, "nothing arrived:\n{log}");
    let n = frames(&received);
    let sent: u64 = log
        .split("send ended: recorded ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no frame count in:\n{log}"));
    // All but the few in flight when the show closed the stream.
    assert!(n > 10 && n + 10 >= sent, "{n} of {sent} frames arrived:\n{log}");
}

fn grab(display: &str, size: (u32, u32)) -> Vec<u8> {
    let o = Command::new("ffmpeg")
        .args(["-v", "error", "-f", "x11grab", "-video_size", &format!("{}x{}", size.0, size.1), "-i", display])
        .args(["-frames:v", "1", "-f", "rawvideo", "-pix_fmt", "rgb24", "-"])
        .output()
        .expect("ffmpeg runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    o.stdout
}

#[test]
fn projector_outputs_open_their_windows_and_follow_corner_addresses() {
    let display = VirtualDisplay::start();
    let dir = scratch_dir("outputs");
    let (mut show, port) = Show::start(&display, &dir, "two_projectors", &[]);
    show.wait_for("output 1: window");
    show.wait_for("output 2: window");
    // Without a window manager every window sits at the top left, the last opened (output 2)
    // on top. Its warp puts image in the top-left 40×40 pixels; moving corner 0 (top left)
    // inwards over OSC must leave them black.
    let lit = |screen: &[u8]| -> u32 {
        (0..40).flat_map(|y| screen[y * 1280 * 3..(y * 1280 + 40) * 3].iter()).map(|&b| u32::from(b)).sum()
    };
    let deadline = Instant::now() + Duration::from_secs(60);
    while lit(&grab(&display.display, (1280, 720))) == 0 {
        assert!(Instant::now() < deadline, "output 2 never showed its image");
        std::thread::sleep(Duration::from_millis(250));
    }
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    let corner = vec![rosc::OscType::Float(0.3), rosc::OscType::Float(0.7)];
    send(&socket, port, "/indra/output/2/corner/0", corner);
    let deadline = Instant::now() + Duration::from_secs(60);
    while lit(&grab(&display.display, (1280, 720))) != 0 {
        assert!(Instant::now() < deadline, "the corner did not move:\n{}", std::fs::read_to_string(&show.log).unwrap());
        std::thread::sleep(Duration::from_millis(250));
    }
}

#[cfg(unix)]
#[test]
fn the_network_can_neither_name_files_outside_nor_freeze_the_show_with_them() {
    let display = VirtualDisplay::start();
    let dir = scratch_dir("hostile-files");
    let victim = dir.join("victim.conf");
    std::fs::write(&victim, "keep me").unwrap();
    // The pipe lies in a folder the performer opened: it is refused as no regular file.
    let allowed = dir.join("allowed");
    std::fs::create_dir_all(&allowed).unwrap();
    let fifo = allowed.join("pipe.ron");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let takes = dir.join("takes");
    let base = takes.join("show.mp4");
    let args = ["--record-video".as_ref(), base.as_os_str(), "--allow-path".as_ref(), allowed.as_os_str()];
    let (mut show, port) = Show::start(&display, &dir, "projection_mapping", &args);
    show.wait_for("recording to");
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    let text = |p: &Path| vec![rosc::OscType::String(p.to_str().unwrap().into())];

    // A pipe: refused without opening it for reading; the show goes on to the next message.
    send(&socket, port, "/indra/wall/file", text(&fifo));
    show.wait_for("not a regular file");
    send(&socket, port, "/indra/wall/file", text(&victim));
    show.wait_for("outside the folders");
    send(&socket, port, "/indra/wall/save", vec![rosc::OscType::Int(1)]);
    let log = show.wait_for("warp not saved");
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "keep me", "{log}");

    // 300 start/stop pairs: a few takes, and the show still answers at once.
    for i in 0..300 {
        send(&socket, port, "/indra/record/start", vec![rosc::OscType::String(format!("t{i}.mp4"))]);
        send(&socket, port, "/indra/record/stop", vec![]);
    }
    send(&socket, port, "/indra/wall/file", text(&dir.join("after-the-flood.ron")));
    let started = Instant::now();
    let log = show.wait_for("after-the-flood.ron");
    assert!(started.elapsed() < Duration::from_secs(20), "the flood held the show {:?}", started.elapsed());
    assert!(log.contains("take not started"), "{log}");
    let written = std::fs::read_dir(&takes).unwrap().count();
    assert!((1..=6).contains(&written), "{written} takes written:\n{log}");
}

/// `run --ndi-out`: the window's output reaches a cyndilib receiver (in a network namespace of
/// its own) from the readback ring, stamped with its show frame, which matches that frame
/// rendered off-screen; SIGTERM ends the show and the send cleanly.
#[test]
fn the_show_sends_its_output_as_ndi_and_each_frame_is_its_render() {
    use crate::ndi::{mean_difference, out_dir, peer_python, png_rgb, run_peer};
    let Some(python) = peer_python() else { return };
    let display = VirtualDisplay::start();
    let dir = out_dir("window");
    let args =
        ["--backend", "vulkan", "run", "kleinian", "--no-midi", "--no-watch", "--no-osc", "--ndi-out", "indra-out"];
    let (report, log) =
        run_peer(&python, "receive-live", &dir, &args, &[("DISPLAY", &display.display), ("RUST_LOG", "info")]);
    assert_eq!(report["found"], true, "the receiver never saw the show's source: {log}");
    assert!(log.contains("sending the output as the NDI source 'indra-out'"), "{log}");
    assert!(log.contains("send ended: recorded"), "SIGTERM ends the send: {log}");
    let frames = report["frames"].as_array().unwrap();
    assert!(frames.len() >= 4, "{report}");
    let f = &frames[frames.len() / 2];
    let (w, h) = (f["size"][0].as_u64().unwrap(), f["size"][1].as_u64().unwrap());
    let n = f["frame"].as_u64().unwrap();
    let received = std::fs::read(f["file"].as_str().unwrap()).unwrap();
    assert_eq!(received.len() as u64, w * h * 4);
    // The same frames off-screen: the received one is frame n, not a neighbour.
    let first = n.saturating_sub(2);
    let png = dir.join("png");
    let o = crate::common::indra(&[
        "render",
        "kleinian",
        "--size",
        &format!("{w}x{h}"),
        "--start",
        &first.to_string(),
        "--frames",
        "5",
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", crate::common::text(&o));
    let difference = |m: u64| mean_difference(&received, &png_rgb(&png.join(format!("kleinian_{m:05}.png"))));
    let own = difference(n);
    assert!(own < 6.0, "frame {n} arrived {own:.2} away from its render");
    for m in (first..first + 5).filter(|&m| m != n) {
        assert!(own < difference(m), "frame {n} ({own:.2}) is nearer frame {m}'s render ({:.2})", difference(m));
    }
}

/// `run --pipewire-out`: the window's output is a PipeWire video source a GStreamer consumer reads
/// while the show runs, and so is one node's image through a headless output (no window of its
/// own); SIGTERM withdraws both cleanly.
#[cfg(target_os = "linux")]
#[test]
fn the_show_offers_its_output_and_a_node_as_pipewire_sources_until_sigterm() {
    let Some(session) = crate::pipewire::PipeWireSession::start("window") else { return };
    let display = VirtualDisplay::start();
    let dir = scratch_dir("window-pipewire");
    let env =
        [("XDG_RUNTIME_DIR", session.runtime_dir.as_os_str()), ("DBUS_SESSION_BUS_ADDRESS", session.bus.as_ref())];
    let args = ["--pipewire-out", "indra-window", "--output-window", "source=limit_set,headless,pipewire=indra-node"];
    let args: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_ref()).collect();
    let (mut show, _) = Show::start_with_env(&display, &dir, "kleinian_star_glow", &args, &env);
    show.wait_for("offering the output as the PipeWire source 'indra-window'");
    let log = show.wait_for("offering output 1 as the PipeWire source 'indra-node'");
    assert!(!log.contains("output 1: window"), "a headless output opens no window:\n{log}");
    for node in ["indra-window", "indra-node"] {
        let received = session.receive(node, 5, Instant::now() + Duration::from_secs(30));
        assert!(!received.is_empty() && received.len() % 5 == 0, "{node}: {} bytes", received.len());
        let frame = &received[..received.len() / 5];
        assert!(frame.chunks_exact(4).any(|p| p != &frame[..4]), "{node}: the limit set, not a flat frame");
    }
    assert!(Command::new("kill").args(["-TERM", &show.child.id().to_string()]).status().unwrap().success());
    show.wait_for("send ended");
    let _ = show.child.wait();
    let log = std::fs::read_to_string(&show.log).unwrap();
    assert_eq!(log.matches("send ended: recorded").count(), 2, "{log}");
}
