//! `--pipewire-out` end to end against a real PipeWire: Debian's `pipewire` and `wireplumber`
//! run as plain processes on a session bus of their own, in a runtime folder of their own (what
//! CI can run without a desktop), and a GStreamer `pipewiresrc` pipeline — what OBS and browsers
//! sit on — reads indra's frames. tools/setup-system installs them; without them these tests say
//! they were skipped, except on CI (`CI` set), where they fail.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::common::text;

/// A PipeWire daemon and session manager on a private bus, stopped when dropped.
pub(crate) struct PipeWireSession {
    /// The runtime folder holding the daemon's socket (the children's `XDG_RUNTIME_DIR`).
    pub(crate) runtime_dir: PathBuf,
    /// The private session bus (`DBUS_SESSION_BUS_ADDRESS`).
    pub(crate) bus: String,
    children: Vec<Child>,
}

impl PipeWireSession {
    /// Starts dbus-daemon, pipewire and wireplumber; `None` (said, or a failure on CI) where they
    /// are not installed.
    pub(crate) fn start(name: &str) -> Option<Self> {
        let missing: Vec<&str> = ["dbus-daemon", "pipewire", "wireplumber", "pw-cli", "gst-launch-1.0"]
            .into_iter()
            .filter(|p| {
                Command::new("sh")
                    .args(["-c", &format!("command -v {p}")])
                    .output()
                    .map_or(true, |o| !o.status.success())
            })
            .collect();
        if !missing.is_empty() {
            assert!(std::env::var_os("CI").is_none(), "CI runs the PipeWire tests; missing {missing:?}");
            eprintln!("skipped: {missing:?} not installed (tools/setup-system test installs them)");
            return None;
        }
        let runtime_dir = std::env::temp_dir().join(format!("indra-pw-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&runtime_dir);
        std::fs::create_dir_all(&runtime_dir).unwrap();
        std::fs::set_permissions(&runtime_dir, std::os::unix::fs::PermissionsExt::from_mode(0o700)).unwrap();
        let bus = format!("unix:path={}", runtime_dir.join("bus").display());
        let spawn = |program: &str, args: &[&str]| {
            let log = std::fs::File::create(runtime_dir.join(format!("{program}.log"))).unwrap();
            Command::new(program)
                .args(args)
                .env("XDG_RUNTIME_DIR", &runtime_dir)
                .env("DBUS_SESSION_BUS_ADDRESS", &bus)
                .stdout(Stdio::null())
                .stderr(log)
                .spawn()
                .unwrap_or_else(|e| panic!("{program}: {e}"))
        };
        let mut session = Self { runtime_dir: runtime_dir.clone(), bus: bus.clone(), children: Vec::new() };
        session.children.push(spawn("dbus-daemon", &["--session", "--nofork", "--address", &bus]));
        session.wait_for(&runtime_dir.join("bus"));
        session.children.push(spawn("pipewire", &[]));
        session.wait_for(&runtime_dir.join("pipewire-0"));
        session.children.push(spawn("wireplumber", &[]));
        // The session manager links streams once it has loaded its policy.
        std::thread::sleep(Duration::from_secs(2));
        Some(session)
    }

    fn wait_for(&self, socket: &Path) {
        let deadline = Instant::now() + Duration::from_secs(10);
        while !socket.exists() {
            assert!(Instant::now() < deadline, "{} did not appear", socket.display());
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// `command` with this session's runtime folder and bus.
    pub(crate) fn command(&self, program: &str) -> Command {
        let mut command = Command::new(program);
        command.env("XDG_RUNTIME_DIR", &self.runtime_dir).env("DBUS_SESSION_BUS_ADDRESS", &self.bus);
        command
    }

    /// Reads `count` frames of the PipeWire source `node` as RGBA (a GStreamer consumer, as OBS's
    /// is) once the node is there (waiting until `deadline`): a consumer started before its
    /// target exists links to nothing and never reads.
    pub(crate) fn receive(&self, node: &str, count: u32, deadline: Instant) -> Vec<u8> {
        let wanted = format!("node.name = \"{node}\"");
        loop {
            let listed = self.command("pw-cli").args(["ls", "Node"]).output().unwrap();
            if String::from_utf8_lossy(&listed.stdout).contains(&wanted) {
                break;
            }
            assert!(Instant::now() < deadline, "the PipeWire node '{node}' did not appear");
            std::thread::sleep(Duration::from_millis(100));
        }
        let o = self
            .command("timeout")
            .args(["20", "gst-launch-1.0", "-q", "pipewiresrc", &format!("target-object={node}")])
            .args([&format!("num-buffers={count}"), "!", "videoconvert", "!", "video/x-raw,format=RGBA"])
            .args(["!", "fdsink", "fd=1"])
            .output()
            .unwrap();
        o.stdout
    }
}

impl Drop for PipeWireSession {
    fn drop(&mut self) {
        for child in self.children.iter_mut().rev() {
            let _ = child.kill();
            let _ = child.wait();
        }
        let _ = std::fs::remove_dir_all(&self.runtime_dir);
    }
}

fn png_rgb(path: &Path) -> Vec<u8> {
    image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb8().into_raw()
}

#[test]
fn a_gstreamer_consumer_reads_the_rendered_frames_from_the_pipewire_source_byte_for_byte() {
    let Some(session) = PipeWireSession::start("render") else { return };
    let dir = session.runtime_dir.join("out");
    // 240 frames paced to 60 fps: 4 s during which the consumer joins and reads.
    let mut indra = session
        .command(env!("CARGO_BIN_EXE_indra"))
        .args(["--backend", "vulkan", "render", "kleinian", "--size", "96x54", "--frames", "240"])
        .args(["--pipewire-out", "indra-test", "--out"])
        .arg(&dir)
        .env("INDRA_ROOT", env!("CARGO_MANIFEST_DIR"))
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let received = session.receive("indra-test", 10, Instant::now() + Duration::from_secs(30));
    let o = wait_output(&mut indra);
    assert!(o.status.success(), "{}", text(&o));
    let frame_bytes = 96 * 54 * 4;
    assert_eq!(received.len(), 10 * frame_bytes, "ten 96×54 RGBA frames: {}", text(&o));
    let rendered: Vec<Vec<u8>> = (0..240).map(|n| png_rgb(&dir.join(format!("kleinian_{n:05}.png")))).collect();
    // Raw video: every frame is exactly one rendered frame, and they come in order.
    let mut last = None;
    for frame in received.chunks_exact(frame_bytes) {
        let rgb: Vec<u8> = frame.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
        let matches: Vec<usize> = (0..240).filter(|&n| rendered[n] == rgb).collect();
        let Some(&n) = matches.iter().find(|&&n| last.is_none_or(|l| n > l)) else {
            panic!("a received frame is no rendered frame after {last:?} (equal to {matches:?})");
        };
        last = Some(n);
    }
}

#[test]
fn without_a_pipewire_daemon_the_source_is_one_sentence() {
    let empty = std::env::temp_dir().join(format!("indra-pw-none-{}", std::process::id()));
    std::fs::create_dir_all(&empty).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_indra"))
        .args(["--backend", "vulkan", "render", "kleinian", "--size", "32x18", "--pipewire-out", "x", "--out"])
        .arg(&empty)
        .env("INDRA_ROOT", env!("CARGO_MANIFEST_DIR"))
        .env("XDG_RUNTIME_DIR", &empty)
        .env_remove("PIPEWIRE_RUNTIME_DIR")
        .env_remove("PIPEWIRE_REMOTE")
        .output()
        .unwrap();
    assert!(!o.status.success());
    let said = text(&o);
    assert!(said.contains("no PipeWire daemon is running"), "{said}");
    assert!(!empty.join("kleinian_00000.png").exists(), "refused before rendering");
}

fn wait_output(child: &mut Child) -> std::process::Output {
    let deadline = Instant::now() + Duration::from_secs(120);
    while child.try_wait().unwrap().is_none() {
        if Instant::now() > deadline {
            let _ = child.kill();
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let mut stderr = Vec::new();
    if let Some(mut pipe) = child.stderr.take() {
        let _ = std::io::Read::read_to_end(&mut pipe, &mut stderr);
    }
    std::process::Output { status: child.wait().unwrap(), stdout: Vec::new(), stderr }
}
