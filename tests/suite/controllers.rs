//! Pad controllers end to end on a real MIDI system: JACK (`jackd` with its dummy driver, no
//! sound card needed) carries the messages between a live show — built with `jack`, midir's
//! JACK backend — and simulated controllers, JACK clients from PyPI's JACK-Client
//! (`tests/midi/controllers.py`) that name their ports as the real devices do. What a pad does
//! is read back over OSCQuery; what the show lights is what each client received. Without
//! jackd, the peer or the feature these tests say they were skipped — except on CI.

use std::io::{BufRead, BufReader, Write};
use std::net::UdpSocket;
use std::path::Path;
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::time::{Duration, Instant};

use crate::live_show::{Show, VirtualDisplay, scratch_dir};
use crate::osc::http_get;

/// Says why a peer is missing; fails on CI.
pub(crate) fn skip(problem: &str) {
    assert!(std::env::var_os("CI").is_none(), "CI runs the controller tests: {problem}");
    eprintln!("skipped: {problem}");
}

/// A JACK server of its own name on the dummy driver; killed when dropped.
pub(crate) struct Jack {
    child: Child,
    pub(crate) name: String,
    /// One JACK test at a time: their timings are measured, and two shows at once on a
    /// two-core machine starve both.
    _turn: std::sync::MutexGuard<'static, ()>,
}

static TURN: std::sync::Mutex<()> = std::sync::Mutex::new(());

impl Jack {
    pub(crate) fn start() -> Option<Self> {
        if !cfg!(feature = "midi-jack") {
            skip("this test build has no JACK MIDI (tools/test builds with --features jack)");
            return None;
        }
        // A server per test: tests run in parallel, and one show's controllers must not see
        // another's devices.
        static SERVERS: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        let n = SERVERS.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        let name = format!("indra-test-{}-{n}", std::process::id());
        let turn = TURN.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        clear_stale_registrations();
        let log = std::env::temp_dir().join(format!("{name}.log"));
        let spawned = Command::new("jackd")
            // Synchronous: each cycle waits for every client, so a client a busy machine delays
            // loses no MIDI (a skipped cycle's events are gone); a slow one is waited for 2 s
            // before JACK gives up on it (and a killed one, at the end, as long).
            .args(["--no-realtime", "--sync", "-t", "2000", "-n", &name, "-d", "dummy", "-r", "48000", "-p", "256"])
            .env("JACK_NO_AUDIO_RESERVATION", "1")
            .stdout(Stdio::null())
            .stderr(std::fs::File::create(&log).unwrap())
            .spawn();
        let Ok(child) = spawned else {
            skip("no jackd (tools/setup-system test installs jackd2)");
            return None;
        };
        let jack = Self { child, name, _turn: turn };
        let deadline = Instant::now() + Duration::from_secs(10);
        while !Command::new("jack_lsp")
            .env("JACK_DEFAULT_SERVER", &jack.name)
            .output()
            .is_ok_and(|o| o.status.success())
        {
            let said = std::fs::read_to_string(&log).unwrap_or_default();
            // Stale places were cleared above; these are servers still running.
            let hint = if said.contains("Too many servers") {
                "\n(JACK's registry is full of running servers: `pgrep -a jackd` lists them)"
            } else {
                ""
            };
            assert!(Instant::now() < deadline, "jackd did not start:\n{said}{hint}");
            std::thread::sleep(Duration::from_millis(100));
        }
        Some(jack)
    }
}

/// JACK's registry holds eight servers and frees a dead one's place only for a server of the
/// same name; a jackd killed before it could unregister (a test machine reused, a run cut off)
/// keeps its place for good. With no jackd running at all, every registration is stale, and
/// the registry and the servers' segments are removed.
fn clear_stale_registrations() {
    let running =
        std::fs::read_dir("/proc").into_iter().flatten().flatten().any(|entry| {
            std::fs::read_to_string(entry.path().join("comm")).is_ok_and(|name| name.trim_end() == "jackd")
        });
    if running {
        return;
    }
    for entry in std::fs::read_dir("/dev/shm").into_iter().flatten().flatten() {
        if entry.file_name().to_string_lossy().starts_with("jack") {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

impl Drop for Jack {
    fn drop(&mut self) {
        // Asked to stop, jackd takes its server out of JACK's registry (a killed one is left
        // there, and the registry holds a few).
        let _ = Command::new("kill").args(["-TERM", &self.child.id().to_string()]).status();
        let deadline = Instant::now() + Duration::from_secs(15);
        while Instant::now() < deadline && matches!(self.child.try_wait(), Ok(None)) {
            std::thread::sleep(Duration::from_millis(50));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The simulated controllers: one Python process, one JACK client per device.
pub(crate) struct Devices {
    child: Child,
    input: ChildStdin,
    output: BufReader<ChildStdout>,
}

impl Devices {
    pub(crate) fn start(jack: &Jack, specs: &[&str]) -> Option<Self> {
        let python = std::env::var("INDRA_MIDI_PYTHON").unwrap_or_else(|_| "python3".into());
        if !Command::new(&python).args(["-c", "import jack"]).output().is_ok_and(|o| o.status.success()) {
            skip(&format!("{python} has no JACK-Client (tools/test installs it in target/midi-peer)"));
            return None;
        }
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/midi/controllers.py");
        let mut child = Command::new(python)
            .arg(script)
            .args(specs)
            .env("JACK_DEFAULT_SERVER", &jack.name)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .unwrap();
        let (input, output) = (child.stdin.take().unwrap(), BufReader::new(child.stdout.take().unwrap()));
        let mut devices = Self { child, input, output };
        assert_eq!(devices.answer(), "ready");
        Some(devices)
    }

    fn answer(&mut self) -> serde_json::Value {
        let mut line = String::new();
        self.output.read_line(&mut line).unwrap();
        serde_json::from_str(&line).unwrap_or_else(|e| panic!("the peer said {line:?}: {e}"))
    }

    pub(crate) fn command(&mut self, line: &str) -> serde_json::Value {
        writeln!(self.input, "{line}").unwrap();
        self.answer()
    }

    /// Sends `bytes` from device `name` (spaces as `_`).
    pub(crate) fn send(&mut self, name: &str, bytes: &[u8]) {
        let hex: String = bytes.iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(self.command(&format!("send {} {hex}", name.replace(' ', "_"))), "sent");
    }

    /// A press and release of a note-on pad or button.
    pub(crate) fn press(&mut self, name: &str, status: u8, number: u8) {
        // A note on of velocity 0 is a release, as a control change of 0 is.
        self.send(name, &[status, number, 127, status, number, 0]);
    }

    /// What device `name` received since the last take: (seconds, bytes).
    pub(crate) fn take(&mut self, name: &str) -> Vec<(f64, Vec<u8>)> {
        let answer = self.command(&format!("take {}", name.replace(' ', "_")));
        let list = answer.as_array().unwrap_or_else(|| panic!("{answer}"));
        (list.iter())
            .map(|m| {
                let hex = m[1].as_str().unwrap();
                let bytes =
                    (0..hex.len()).step_by(2).map(|i| u8::from_str_radix(&hex[i..i + 2], 16).unwrap()).collect();
                (m[0].as_f64().unwrap(), bytes)
            })
            .collect()
    }

    /// Waits (at most 30 s) until device `name` has been sent `message`; returns every message
    /// it received meanwhile.
    pub(crate) fn wait_for(&mut self, name: &str, message: &[u8]) -> Vec<(f64, Vec<u8>)> {
        self.wait_for_all(name, &[message])
    }

    /// [`Devices::wait_for`] for several messages, in any order.
    pub(crate) fn wait_for_all(&mut self, name: &str, messages: &[&[u8]]) -> Vec<(f64, Vec<u8>)> {
        let deadline = Instant::now() + Duration::from_secs(30);
        let mut seen = Vec::new();
        loop {
            seen.extend(self.take(name));
            if messages.iter().all(|message| seen.iter().any(|(_, m)| m == message)) {
                return seen;
            }
            let got: Vec<&Vec<u8>> = seen.iter().rev().take(40).map(|(_, m)| m).collect();
            assert!(Instant::now() < deadline, "{name} was never sent {messages:02x?}; it got, last first: {got:02x?}");
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Drop for Devices {
    fn drop(&mut self) {
        let _ = writeln!(self.input, "quit");
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Two layers: nine clips on the first (more than an 8×8 grid's columns), two that wait for the
/// bar on the second; 120 BPM, so a beat is 0.5 s.
const SHOW: &str = r#"(
    name: "pads", size: (32, 32), bpm: 120.0,
    layers: [
        (name: "one", clips: [(scene: "kleinian", id: "k1"), (scene: "kleinian", id: "k2"), (scene: "kleinian", id: "k3"),
            (scene: "kleinian", id: "k4"), (scene: "kleinian", id: "k5"), (scene: "kleinian", id: "k6"),
            (scene: "kleinian", id: "k7"), (scene: "kleinian", id: "k8"), (scene: "kleinian", id: "k9")]),
        (name: "two", start: 0, transition: (kind: "crossfade", beats: 1.0, quantize: Bar),
            clips: [(scene: "kleinian", id: "w1"), (scene: "kleinian", id: "w2")]),
    ],
    cues: [(name: "first", clips: [(1, 1)])],
)"#;

const LPX: &str = "Launchpad X";
const MINI: &str = "Launchpad Mini";
const APC_MINI: &str = "APC mini mk2";
const APC40: &str = "APC40 mkII";
const GRID: &str = "indra grid";

#[test]
fn controllers_trigger_clips_light_their_pads_page_fade_and_come_back_after_an_unplug() {
    let Some(jack) = Jack::start() else { return };
    let specs = [
        "Launchpad X=LPX MIDI Out,LPX MIDI In",
        "Launchpad Mini=LPMiniMK3 MIDI Out,LPMiniMK3 MIDI In",
        "APC mini mk2=APC mini mk2 Out,APC mini mk2 In",
        "APC40 mkII=APC40 mkII Out,APC40 mkII In",
        "indra grid=pads out,pads in",
    ];
    let Some(mut devices) = Devices::start(&jack, &specs) else { return };
    let display = VirtualDisplay::start();
    let dir = scratch_dir("controllers");
    std::fs::write(dir.join("pads.ron"), SHOW).unwrap();
    let query_port = UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let query = format!("127.0.0.1:{query_port}");
    let show_file = dir.join("pads.ron");
    let env = [("JACK_DEFAULT_SERVER", jack.name.as_ref())];
    let (mut show, _) = Show::start_with_midi(
        &display,
        &dir,
        show_file.to_str().unwrap(),
        &["--oscquery".as_ref(), query.as_ref()],
        &env,
    );
    for name in ["Launchpad X", "Launchpad Mini MK3", "APC mini mk2", "APC40 mkII", "Generic grid"] {
        show.wait_for(&format!("controller {name}: output"));
    }
    let get = |path: &str| http_get(query.parse().unwrap(), path).1["VALUE"][0].as_f64().unwrap_or(f64::NAN);
    let playing = |layer: usize| get(&format!("/indra/layer/{layer}/playing"));
    let wait_playing = |layer: usize, clip: f64| {
        let deadline = Instant::now() + Duration::from_secs(20);
        while playing(layer) != clip {
            assert!(Instant::now() < deadline, "layer {layer} plays {} (wanted {clip})", playing(layer));
            std::thread::sleep(Duration::from_millis(50));
        }
    };
    wait_playing(1, 1.0);

    // At connect each device got its mode SysEx once (Akai's Ableton mode, Novation's
    // Programmer mode; the APC mini mk2 needs none), then its pads: clip 1 of layer 1 playing
    // (green, 21), clip 2 loaded (orange, 9).
    let hello = |device: u8| vec![0xF0, 0x00, 0x20, 0x29, 0x02, device, 0x0E, 0x01, 0xF7];
    let apc40_hello = vec![0xF0, 0x47, 0x7F, 0x29, 0x60, 0x00, 0x04, 0x41, 0x01, 0x00, 0x00, 0xF7];
    for (name, sysex, playing_pad, loaded_pad) in [
        (LPX, Some(hello(0x0C)), [0x90, 11, 21], [0x90, 12, 9]),
        (MINI, Some(hello(0x0D)), [0x90, 11, 21], [0x90, 12, 9]),
        (APC_MINI, None, [0x96, 0x00, 21], [0x92, 0x01, 9]),
        (APC40, Some(apc40_hello.clone()), [0x90, 0x00, 21], [0x90, 0x01, 9]),
    ] {
        let seen = devices.wait_for_all(name, &[&loaded_pad, &playing_pad]);
        let sysex_count = seen.iter().filter(|(_, m)| m[0] == 0xF0).count();
        match sysex {
            Some(sysex) => {
                assert_eq!(seen[0].1, sysex, "{name}: the mode switch comes first: {:02x?}", &seen[..6]);
                assert_eq!(sysex_count, 1, "{name}: the mode switch is sent once");
            }
            None => assert_eq!(sysex_count, 0, "{name}: no SysEx"),
        }
    }

    // Each device's pad triggers its clip: it lights "playing", the clip before "loaded".
    for (name, pad, clip, lit, dim) in [
        (LPX, [0x90, 12], 2.0, [0x90, 12, 21], [0x90, 11, 9]),
        (APC_MINI, [0x90, 0x02], 3.0, [0x96, 0x02, 21], [0x92, 0x01, 9]),
        (APC40, [0x90, 0x03], 4.0, [0x90, 0x03, 21], [0x90, 0x02, 9]),
        (MINI, [0x90, 11], 1.0, [0x90, 11, 21], [0x90, 14, 9]),
    ] {
        devices.take(name);
        devices.press(name, pad[0], pad[1]);
        wait_playing(1, clip);
        devices.wait_for_all(name, &[&lit, &dim]);
    }

    // A quantized trigger blinks in tempo until its bar: lit (yellow, 13) the first half of each
    // beat, its other state (loaded) the second; then it lights "playing". The second trigger
    // goes right after a bar, so it waits (and blinks) most of a bar — on every device.
    devices.press(LPX, 0x90, 21);
    wait_playing(2, 1.0);
    for name in [LPX, MINI, APC_MINI, APC40, GRID] {
        devices.take(name);
    }
    devices.press(LPX, 0x90, 22);
    for (name, note, queued, lit) in [
        (LPX, 22, 13, [0x90, 22, 21]),
        (MINI, 22, 13, [0x90, 22, 21]),
        (APC_MINI, 9, 13, [0x96, 9, 21]),
        (APC40, 9, 13, [0x90, 9, 21]),
        (GRID, 41, 64, [0x99, 41, 127]),
    ] {
        let seen = devices.wait_for(name, &lit);
        let pad: Vec<(f64, Vec<u8>)> = seen.into_iter().filter(|(_, m)| m[0] & 0xF0 == 0x90 && m[1] == note).collect();
        let toggles: Vec<f64> = pad.windows(2).filter(|w| w[0].1 != w[1].1).map(|w| w[1].0).collect();
        assert!(pad.iter().any(|(_, m)| m[2] == queued), "{name}: the queued pad never blinked: {pad:02x?}");
        // Measured where the messages arrive, on a machine busy with other tests: a toggle may
        // come a few frames late (CI saw one 75 ms late), which shortens one gap and lengthens
        // the next by as much. So the median gap is held to the half beat, and the number of
        // toggles to the half beats their span covers (a blink at twice or half the rate, or
        // one that flickers, fails both).
        let mut gaps: Vec<f64> = toggles.windows(2).map(|g| (g[1] - g[0]) / 0.5).collect();
        assert!(gaps.len() >= 4, "{name}: too few blinks to time: {pad:02x?}");
        let halves = (toggles[toggles.len() - 1] - toggles[0]) / 0.25;
        gaps.sort_by(f64::total_cmp);
        let median = gaps[gaps.len() / 2];
        let says = format!("{name}: blinks of {gaps:.2?} beats: {pad:02x?}");
        assert!((median - 0.5).abs() < 0.1 && (halves - gaps.len() as f64).abs() < 0.6, "{says}");
    }
    wait_playing(2, 2.0);

    // Paging: the generic grid's four columns show clips 1–4; a page right shows clips 5–8 (5
    // loaded at column 1), and its pad plays clip 5.
    devices.take(GRID);
    devices.press(GRID, 0x99, 66);
    devices.wait_for(GRID, &[0x99, 36, 20]);
    devices.press(GRID, 0x99, 36);
    wait_playing(1, 5.0);
    devices.wait_for(GRID, &[0x99, 36, 127]);
    // The 8×8 and 8×5 grids page right to clip 9 (the APC mini mk2 with shift and track 4).
    devices.press(LPX, 0xB0, 94);
    devices.press(MINI, 0xB0, 94);
    devices.press(APC40, 0x90, 0x60);
    devices.send(APC_MINI, &[0x90, 0x7A, 127, 0x90, 0x67, 127, 0x90, 0x67, 0, 0x90, 0x7A, 0]);
    let loaded = [(LPX, [0x90, 11, 9]), (MINI, [0x90, 11, 9]), (APC_MINI, [0x92, 0, 9]), (APC40, [0x90, 0, 9])];
    for (name, message) in loaded {
        devices.wait_for(name, &message);
    }
    devices.press(APC40, 0x90, 0x00);
    wait_playing(1, 9.0);
    let nine = [(LPX, [0x90, 11, 21]), (MINI, [0x90, 11, 21]), (APC_MINI, [0x96, 0, 21]), (APC40, [0x90, 0, 21])];
    for (name, message) in nine {
        devices.wait_for(name, &message);
    }

    // Faders move a layer's opacity and the master once they have picked the value up (1.0
    // at start).
    let opacity = || get("/indra/layer/1/opacity");
    devices.send(APC_MINI, &[0xB0, 0x30, 40]);
    std::thread::sleep(Duration::from_millis(500));
    assert_eq!(opacity(), 1.0, "a fader far from the value does not jump it");
    devices.send(APC_MINI, &[0xB0, 0x30, 127, 0xB0, 0x30, 64]);
    devices.send(APC40, &[0xB0, 0x0E, 127, 0xB0, 0x0E, 32]);
    let deadline = Instant::now() + Duration::from_secs(20);
    while (opacity() - 64.0 / 127.0).abs() > 1e-3 || (get("/indra/master/level") - 32.0 / 127.0).abs() > 1e-3 {
        let master = get("/indra/master/level");
        assert!(Instant::now() < deadline, "layer 1's opacity is {}, the master {master}", opacity());
        std::thread::sleep(Duration::from_millis(50));
    }

    // Unplugged and plugged in again, each device gets its mode and its lights back (the page
    // it was on).
    for (name, profile, port) in [
        (LPX, LPX, "LPX MIDI In"),
        (MINI, "Launchpad Mini MK3", "LPMiniMK3 MIDI In"),
        (APC_MINI, APC_MINI, "APC mini mk2 In"),
        (APC40, APC40, "APC40 mkII In"),
    ] {
        assert_eq!(devices.command(&format!("unplug {}", name.replace(' ', "_"))), "unplugged");
        show.wait_for(&format!("controller {profile}: output {name}:{port} went away"));
        devices.take(name);
    }
    for (name, sysex, lit) in [
        (LPX, Some(hello(0x0C)), [0x90, 11, 21]),
        (MINI, Some(hello(0x0D)), [0x90, 11, 21]),
        (APC_MINI, None, [0x96, 0, 21]),
        (APC40, Some(apc40_hello.clone()), [0x90, 0, 21]),
    ] {
        assert_eq!(devices.command(&format!("plug {}", name.replace(' ', "_"))), "plugged");
        let mut seen = devices.wait_for(name, &lit);
        std::thread::sleep(Duration::from_millis(500));
        seen.extend(devices.take(name));
        match sysex {
            Some(sysex) => assert_eq!(seen[0].1, sysex, "{name}: the mode switch again, first"),
            None => assert!(seen.iter().all(|(_, m)| m[0] != 0xF0), "{name}: no SysEx"),
        }
        assert!(seen.len() >= 40, "{name}: the whole grid again: {seen:02x?}");
    }
    assert!(show.child.try_wait().unwrap().is_none(), "the show is still running");
}
