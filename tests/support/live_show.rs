//! A live show for the tests: `indra run` in a window on its own virtual X display (Xvfb,
//! installed by tools/setup-system test), its log in a file the test reads. Shared by the suite
//! and the soak, which runs as a test binary of its own; each uses a part.
#![allow(dead_code)]

use std::io::Read;
use std::net::UdpSocket;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// An Xvfb server on a free display number, killed when dropped.
pub(crate) struct VirtualDisplay {
    server: Child,
    /// The X display's name, e.g. `:1042`.
    pub(crate) display: String,
}

impl VirtualDisplay {
    pub(crate) fn start() -> Self {
        // Tests run in parallel in one process: each call takes its own range of numbers.
        static CALLS: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        for attempt in 0..20 {
            let number = 1000 + (std::process::id() % 30_000) + call * 50 + attempt;
            let socket = format!("/tmp/.X11-unix/X{number}");
            if Path::new(&socket).exists() {
                continue;
            }
            let mut server = Command::new("Xvfb")
                .args([&format!(":{number}"), "-screen", "0", "1280x800x24", "-nolisten", "tcp"])
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .expect("Xvfb runs (tools/setup-system test installs xvfb)");
            let deadline = Instant::now() + Duration::from_secs(10);
            while Instant::now() < deadline {
                // The socket is ours only if our server is still running (a lost race exits).
                if Path::new(&socket).exists() {
                    std::thread::sleep(Duration::from_millis(200));
                    if let Ok(None) = server.try_wait() {
                        return Self { server, display: format!(":{number}") };
                    }
                    break;
                }
                if let Ok(Some(_)) = server.try_wait() {
                    break;
                }
                std::thread::sleep(Duration::from_millis(50));
            }
            let _ = server.kill();
            let _ = server.wait();
        }
        panic!("no virtual display could be started");
    }
}

impl Drop for VirtualDisplay {
    fn drop(&mut self) {
        let _ = self.server.kill();
        let _ = self.server.wait();
    }
}

/// `indra run` in the virtual display, its log going to a file the test reads.
pub(crate) struct Show {
    /// The `indra run` process.
    pub(crate) child: Child,
    /// Its log file (standard error).
    pub(crate) log: PathBuf,
}

impl Show {
    /// Starts `indra run <scene> <args>` on `display`, with OSC on a free loopback port and its
    /// presets, learn file and log in `dir`. Returns the show and its OSC port.
    pub(crate) fn start(display: &VirtualDisplay, dir: &Path, scene: &str, args: &[&std::ffi::OsStr]) -> (Self, u16) {
        Self::start_with_env(display, dir, scene, args, &[])
    }

    /// [`Show::start`] with more environment variables for the show.
    pub(crate) fn start_with_env(
        display: &VirtualDisplay,
        dir: &Path,
        scene: &str,
        args: &[&std::ffi::OsStr],
        env: &[(&str, &std::ffi::OsStr)],
    ) -> (Self, u16) {
        Self::start_with_midi(display, dir, scene, [&["--no-midi".as_ref()], args].concat().as_slice(), env)
    }

    /// [`Show::start_with_env`] with MIDI on (controllers and ports from `env`'s MIDI system).
    pub(crate) fn start_with_midi(
        display: &VirtualDisplay,
        dir: &Path,
        scene: &str,
        args: &[&std::ffi::OsStr],
        env: &[(&str, &std::ffi::OsStr)],
    ) -> (Self, u16) {
        let port = UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
        let log = dir.join("show.log");
        let child = Command::new(env!("CARGO_BIN_EXE_indra"))
            .args(["--backend", "vulkan", "run", scene, "--no-watch"])
            .args(["--osc", &format!("127.0.0.1:{port}")])
            .args(args)
            .arg("--presets")
            .arg(dir.join("presets"))
            .arg("--midi-learn")
            .arg(dir.join("learn.ron"))
            .env("INDRA_ROOT", env!("CARGO_MANIFEST_DIR"))
            .env("DISPLAY", &display.display)
            .env_remove("WAYLAND_DISPLAY")
            .env("RUST_LOG", "info")
            .envs(env.iter().copied())
            .stdout(Stdio::null())
            .stderr(std::fs::File::create(&log).unwrap())
            .spawn()
            .unwrap();
        (Self { child, log }, port)
    }

    /// The show's process id.
    pub(crate) fn pid(&self) -> u32 {
        self.child.id()
    }

    /// The show's resident memory in bytes (0 once it has ended).
    pub(crate) fn resident(&self) -> u64 {
        let status = std::fs::read_to_string(format!("/proc/{}/status", self.pid())).unwrap_or_default();
        let kib = status.lines().find_map(|l| l.strip_prefix("VmRSS:")).and_then(|v| v.split_whitespace().next());
        kib.and_then(|k| k.parse::<u64>().ok()).map_or(0, |k| k * 1024)
    }

    /// Ends the show with Ctrl-C, as a performer would (a recording is completed), and waits
    /// (at most 30 s) until it has.
    pub(crate) fn interrupt(&mut self) {
        let _ = Command::new("kill").args(["-INT", &self.pid().to_string()]).status();
        let deadline = Instant::now() + Duration::from_secs(30);
        while self.child.try_wait().unwrap().is_none() {
            assert!(Instant::now() < deadline, "the show did not end on Ctrl-C");
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// Waits (at most 90 s: debug build on lavapipe) until the log holds `text`; returns the log.
    pub(crate) fn wait_for(&mut self, text: &str) -> String {
        let deadline = Instant::now() + Duration::from_secs(90);
        loop {
            let mut log = String::new();
            if let Ok(mut f) = std::fs::File::open(&self.log) {
                let _ = f.read_to_string(&mut log);
            }
            if log.contains(text) {
                return log;
            }
            if let Ok(Some(status)) = self.child.try_wait() {
                panic!("the show ended ({status}) before saying '{text}':\n{log}");
            }
            assert!(Instant::now() < deadline, "no '{text}' after 90 s:\n{log}");
            std::thread::sleep(Duration::from_millis(100));
        }
    }
}

impl Drop for Show {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The show `text`, written to `<scratch>/<name>.ron` and started with OSCQuery on a free local
/// port and its control events recorded, once its first clip plays: the show, its OSC port, its
/// folder, the OSCQuery address and the recording's path.
pub(crate) fn start_recorded(
    display: &VirtualDisplay,
    name: &str,
    text: &str,
) -> (Show, u16, PathBuf, std::net::SocketAddr, PathBuf) {
    let dir = scratch_dir(name);
    let file = dir.join(format!("{name}.ron"));
    std::fs::write(&file, text).unwrap();
    let query = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap();
    let recording = dir.join("take.ron");
    let args: Vec<std::ffi::OsString> =
        vec!["--oscquery".into(), query.to_string().into(), "--record-controls".into(), recording.clone().into()];
    let args: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_os_str()).collect();
    let (mut show, port) = Show::start(display, &dir, file.to_str().unwrap(), &args);
    show.wait_for("OSCQuery on");
    show.wait_for("plays clip");
    (show, port, dir, query, recording)
}

/// An empty folder of this test process under the temporary folder.
pub(crate) fn scratch_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("indra-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

pub(crate) fn send(socket: &UdpSocket, port: u16, addr: &str, args: Vec<rosc::OscType>) {
    let packet = rosc::OscPacket::Message(rosc::OscMessage { addr: addr.into(), args });
    socket.send_to(&rosc::encoder::encode(&packet).unwrap(), ("127.0.0.1", port)).unwrap();
}

/// One OSC bundle of `count` copies of the message `addr 1`, as a controller's pads send them.
pub(crate) fn bundle(addr: &str, count: usize) -> Vec<u8> {
    use rosc::{OscBundle, OscMessage, OscPacket, OscTime, OscType};
    let message = OscPacket::Message(OscMessage { addr: addr.into(), args: vec![OscType::Int(1)] });
    let bundle = OscBundle { timetag: OscTime { seconds: 0, fractional: 1 }, content: vec![message; count] };
    rosc::encoder::encode(&OscPacket::Bundle(bundle)).unwrap()
}

/// Bytes in mebibytes, for messages.
pub(crate) fn mib(bytes: u64) -> f64 {
    bytes as f64 / f64::from(1u32 << 20)
}
