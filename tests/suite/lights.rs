//! DMX end to end against real counterparts on loopback: Debian's OLA (`olad` with its Art-Net
//! plugin) receives what `indra render --dmx-out` sends and its values are checked against the
//! pixel map computed here from the rendered PNG; PyPI's sacn parses indra's E1.31 packets
//! (priority, sequence, sync) and drives a parameter of a live show through DMX in, read back
//! over OSCQuery. `tools/setup-system test` installs OLA and `tools/test` PyPI's sacn; without
//! them these tests say they were skipped — except on CI, where a missing peer fails them.

use std::net::UdpSocket;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use crate::common::text;
use crate::live_show::{Show, VirtualDisplay, mib, scratch_dir};
use crate::osc::http_get;

/// olad listens on fixed ports: one at a time in this process.
static OLA: Mutex<()> = Mutex::new(());

fn indra() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_indra"));
    c.env("INDRA_ROOT", env!("CARGO_MANIFEST_DIR")).args(["--backend", "vulkan"]);
    c
}

/// Says why a peer is missing; fails on CI.
fn skip(problem: &str) {
    assert!(std::env::var_os("CI").is_none(), "CI runs the DMX tests: {problem}");
    eprintln!("skipped: {problem}");
}

/// A running olad with only its Art-Net plugin, on loopback; killed when dropped.
struct Olad {
    child: Child,
}

impl Olad {
    fn start(dir: &Path) -> Option<Self> {
        if Command::new("olad").arg("--version").output().is_err() {
            skip("no olad (tools/setup-system test installs ola)");
            return None;
        }
        let config = dir.join("ola");
        std::fs::create_dir_all(&config).unwrap();
        let artnet = "enabled = true\nip = 127.0.0.1\nuse_loopback = true\nuse_limited_broadcast = false\n\
                      always_broadcast = false\nnet = 0\nsubnet = 0\noutput_ports = 4\n";
        std::fs::write(config.join("ola-artnet.conf"), artnet).unwrap();
        for plugin in [
            "dummy",
            "e131",
            "espnet",
            "gpio",
            "karate",
            "kinet",
            "milinst",
            "opendmx",
            "openpixelcontrol",
            "osc",
            "pathport",
            "renard",
            "sandnet",
            "shownet",
            "spi",
            "stageprofi",
            "uartdmx",
            "usbdmx",
            "usbpro",
            "dmx4linux",
            "ftdidmx",
            "nanoleaf",
        ] {
            std::fs::write(config.join(format!("ola-{plugin}.conf")), "enabled = false\n").unwrap();
        }
        // olad refuses to run as root: as root it runs as nobody.
        let mut command = if is_root() {
            let _ = Command::new("chmod").args(["-R", "a+rwX"]).arg(dir).status();
            let mut c = Command::new("setpriv");
            c.args(["--reuid=65534", "--regid=65534", "--clear-groups", "olad"]);
            c
        } else {
            Command::new("olad")
        };
        let child = command
            .arg("-c")
            .arg(&config)
            .args(["-l", "2"])
            .stdout(Stdio::null())
            .stderr(std::fs::File::create(dir.join("olad.log")).unwrap())
            .spawn()
            .expect("olad starts");
        let olad = Self { child };
        let deadline = Instant::now() + Duration::from_secs(20);
        while Command::new("ola_patch")
            .args(["-d", "1", "-p", "0", "-i", "-u", "1"])
            .output()
            .map_or(true, |o| !o.status.success())
        {
            assert!(
                Instant::now() < deadline,
                "olad did not start: {}",
                std::fs::read_to_string(dir.join("olad.log")).unwrap_or_default()
            );
            std::thread::sleep(Duration::from_millis(200));
        }
        Some(olad)
    }

    /// Universe `u` as olad holds it (its HTTP API).
    fn dmx(&self, universe: u16) -> Vec<u8> {
        let addr = "127.0.0.1:9090".parse().unwrap();
        let (_, json) = http_get(addr, &format!("/get_dmx?u={universe}"));
        json["dmx"].as_array().unwrap().iter().map(|v| v.as_u64().unwrap() as u8).collect()
    }
}

impl Drop for Olad {
    fn drop(&mut self) {
        let _ = Command::new("kill").arg(self.child.id().to_string()).status();
        let _ = self.child.wait();
    }
}

fn is_root() -> bool {
    Command::new("id").arg("-u").output().is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
}

fn sacn_python() -> Option<String> {
    let python = std::env::var("INDRA_SACN_PYTHON").unwrap_or_else(|_| "python3".into());
    if Command::new(&python).args(["-c", "import sacn"]).output().is_ok_and(|o| o.status.success()) {
        return Some(python);
    }
    skip(&format!("{python} has no sacn (tools/test installs it in target/dmx-peer)"));
    None
}

fn peer() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/dmx/sacn_peer.py")
}

/// The patch the render tests send: a strip of 16, a serpentine 4×3 matrix in GRB at channel
/// 100, and a 16-bit point at channel 200.
fn patch(out: &str) -> String {
    format!(
        "(\n    {out},\n    on_stop: Hold,\n    fixtures: [\n        \
         (name: \"strip\", shape: Strip(from: (0.1, 0.5), to: (0.9, 0.5), pixels: 16), universe: 1),\n        \
         (name: \"wall\", shape: Matrix(at: (0.0, 0.0), size: (1.0, 1.0), columns: 4, rows: 3, order: Serpentine), \
         universe: 1, address: 100, format: Grb),\n        \
         (name: \"lamp\", shape: Point(at: (0.5, 0.4), size: 0.1), universe: 1, address: 200, bits: 16),\n    ],\n)\n"
    )
}

/// What the patch's 37 channels groups should hold for an image, computed here from the PNG:
/// each LED's box of texel centres (the one under its centre where it covers none), every
/// stride-th texel (at most 16 along a side), averaged in linear light, encoded as sRGB.
fn expected_universe(png: &Path) -> Vec<u8> {
    let image = image::open(png).unwrap().to_rgb8();
    let (w, h) = (image.width() as f32, image.height() as f32);
    let average = |min: (f32, f32), max: (f32, f32)| -> [f32; 3] {
        let axis = |lo: f32, hi: f32, size: f32| {
            let (a, b) = ((lo * size - 0.5).ceil() as i32, (hi * size - 0.5).floor() as i32);
            let (a, b) = if a > b {
                let c = (((lo + hi) * 0.5) * size).floor() as i32;
                (c, c)
            } else {
                (a, b)
            };
            let last = size as i32 - 1;
            let (a, b) = (a.clamp(0, last), b.clamp(a.clamp(0, last), last));
            let stride = ((b - a + 1 + 15) / 16).max(1);
            (a..=b).step_by(stride as usize).collect::<Vec<i32>>()
        };
        let (xs, ys) = (axis(min.0, max.0, w), axis(min.1, max.1, h));
        let mut sum = [0.0f64; 3];
        for &y in &ys {
            for &x in &xs {
                let p = image.get_pixel(x as u32, y as u32);
                for c in 0..3 {
                    sum[c] += srgb_to_linear(f64::from(p[c]) / 255.0);
                }
            }
        }
        let n = (xs.len() * ys.len()) as f64;
        sum.map(|s| linear_to_srgb(s / n) as f32)
    };
    let mut u = vec![0u8; 512];
    let byte = |v: f32| (v * 255.0).round() as u8;
    for k in 0..16 {
        let x = 0.1 + 0.8 * k as f32 / 15.0;
        let side = 0.8 / 15.0;
        let c = average((x - side / 2.0, 0.5 - side / 2.0), (x + side / 2.0, 0.5 + side / 2.0));
        u[3 * k..3 * k + 3].copy_from_slice(&c.map(byte));
    }
    let mut k = 0;
    for row in 0..3 {
        for i in 0..4 {
            let column = if row % 2 == 1 { 3 - i } else { i };
            let min = (column as f32 / 4.0, row as f32 / 3.0);
            let c = average(min, (min.0 + 0.25, min.1 + 1.0 / 3.0));
            let at = 99 + 3 * k;
            u[at..at + 3].copy_from_slice(&[byte(c[1]), byte(c[0]), byte(c[2])]);
            k += 1;
        }
    }
    let c = average((0.45, 0.35), (0.55, 0.45));
    for (i, v) in c.iter().enumerate() {
        let fine = (v * 65535.0).round() as u16;
        u[199 + 2 * i..201 + 2 * i].copy_from_slice(&fine.to_be_bytes());
    }
    u
}

fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

fn linear_to_srgb(c: f64) -> f64 {
    if c <= 0.0031308 { c * 12.92 } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 }
}

/// The channels of `got` and `want` differ by at most `tolerance` (the PNG's 8-bit texels stand
/// for the float image the GPU sampled), fine bytes of 16-bit values aside.
fn assert_close(got: &[u8], want: &[u8], tolerance: u8) {
    let fine = [200, 202, 204];
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        if fine.contains(&i) {
            continue;
        }
        assert!(g.abs_diff(*w) <= tolerance, "channel {} is {g}, the PNG says {w}\ngot  {got:?}\nwant {want:?}", i + 1);
    }
}

fn render(dir: &Path, patch_file: &Path, extra: &[&str]) -> std::process::Output {
    let o = indra()
        .args(["render", "star_glow", "--size", "320x180", "--frames", "20", "--out"])
        .arg(dir.join("frames"))
        .arg("--dmx-out")
        .arg(patch_file)
        .args(extra)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    o
}

#[test]
fn olad_receives_the_pixel_map_of_the_rendered_frame_over_artnet() {
    let _one = OLA.lock().unwrap_or_else(|e| e.into_inner());
    let dir = scratch_dir("dmx-ola");
    let Some(olad) = Olad::start(&dir) else { return };
    let patch_file = dir.join("patch.ron");
    std::fs::write(&patch_file, patch("artnet: Some((to: [\"127.0.0.1\"]))")).unwrap();
    render(&dir, &patch_file, &[]);
    let want = expected_universe(&dir.join("frames/star_glow_00019.png"));
    let deadline = Instant::now() + Duration::from_secs(10);
    let got = loop {
        let got = olad.dmx(1);
        if got.len() >= 205 || Instant::now() > deadline {
            break got;
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    assert!(got.len() >= 205, "olad holds {} channels of universe 1", got.len());
    assert!(want[..48].iter().any(|v| *v > 0), "the strip sees a black frame: a test of nothing");
    assert_close(&got[..205], &want[..205], 2);

    // A patch that blacks out on stop leaves every channel at 0.
    std::fs::write(&patch_file, patch("artnet: Some((to: [\"127.0.0.1\"]))").replace("Hold", "Blackout")).unwrap();
    render(&dir, &patch_file, &[]);
    let deadline = Instant::now() + Duration::from_secs(10);
    while olad.dmx(1).iter().any(|v| *v != 0) {
        assert!(Instant::now() < deadline, "no blackout after the render: {:?}", olad.dmx(1));
        std::thread::sleep(Duration::from_millis(100));
    }
}

#[test]
fn an_sacn_receiver_sees_indras_priority_sequence_and_sync() {
    let Some(python) = sacn_python() else { return };
    let dir = scratch_dir("dmx-sacn");
    let port = UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let patch_file = dir.join("patch.ron");
    let to = format!("sacn: Some((to: [\"127.0.0.1:{port}\"], priority: 150, sync_universe: Some(9)))");
    std::fs::write(&patch_file, patch(&to)).unwrap();
    let receiver = Command::new(&python)
        .arg(peer())
        .args(["receive", "127.0.0.1", &port.to_string(), "6"])
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(500));
    render(&dir, &patch_file, &[]);
    let o = receiver.wait_with_output().unwrap();
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap_or_else(|_| panic!("{}", text(&o)));
    let data = report["data"].as_array().unwrap();
    assert!(data.len() >= 3, "{report}");
    let sequences: Vec<u64> = data.iter().map(|d| d["sequence"].as_u64().unwrap()).collect();
    for d in data {
        assert_eq!((d["universe"].as_u64(), d["priority"].as_u64(), d["sync"].as_u64()), (Some(1), Some(150), Some(9)));
    }
    for pair in sequences.windows(2) {
        assert_eq!(pair[1], (pair[0] + 1) % 256, "sequence numbers step by one: {sequences:?}");
    }
    let syncs = report["syncs"].as_array().unwrap();
    assert!(!syncs.is_empty() && syncs.iter().all(|s| s["sync"] == 9), "{report}");
    let want = expected_universe(&dir.join("frames/star_glow_00019.png"));
    let last: Vec<u8> =
        data.last().unwrap()["channels"].as_array().unwrap().iter().map(|v| v.as_u64().unwrap() as u8).collect();
    assert_close(&last[..48], &want[..48], 2);
}

#[test]
fn the_dmx_bytes_of_frame_n_are_the_same_on_a_second_render_and_from_start_n() {
    let dir = scratch_dir("dmx-record");
    let patch_file = dir.join("patch.ron");
    // Nobody listens on port 9 of loopback: the record is what is checked.
    std::fs::write(&patch_file, patch("artnet: Some((to: [\"127.0.0.1:9\"]))")).unwrap();
    let record = |name: &str, start: &str, frames: &str| {
        let file = dir.join(name);
        let o = indra()
            .args(["render", "star_glow", "--size", "320x180", "--start", start, "--frames", frames, "--out"])
            .arg(dir.join(name).with_extension("frames"))
            .arg("--dmx-out")
            .arg(&patch_file)
            .arg("--dmx-record")
            .arg(&file)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", text(&o));
        std::fs::read(file).unwrap()
    };
    let first = record("a.dmx", "0", "12");
    assert_eq!(first.len(), 12 * (8 + 2 + 512), "one universe a frame");
    assert_eq!(record("b.dmx", "0", "12"), first, "a second render sends the same bytes");
    let tail = record("c.dmx", "8", "4");
    assert_eq!(tail, first[8 * 522..], "frames 8–11 from --start 8 equal those played from 0");
}

#[test]
fn a_desk_drives_a_live_parameter_through_sacn_in_with_16_bits_and_a_flood_changes_nothing() {
    let Some(python) = sacn_python() else { return };
    let display = VirtualDisplay::start();
    let dir = scratch_dir("dmx-in");
    let free = || UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    // sACN's port is fixed (the peer sends to 5568); Art-Net's may be any.
    let (artnet_port, query_port) = (free(), free());
    let file = dir.join("desk.ron");
    let desk = format!(
        "(\n    listen: (sacn: Some(\"127.0.0.1\"), artnet: Some(\"127.0.0.1:{artnet_port}\")),\n    \
         map: [(universe: 3, channel: 10, fine: true, target: \"glow.intensity\", range: (0.0, 4.0))],\n)\n"
    );
    std::fs::write(&file, desk).unwrap();
    let query = format!("127.0.0.1:{query_port}");
    let args = ["--dmx-in".as_ref(), file.as_os_str(), "--oscquery".as_ref(), query.as_ref()];
    let (mut show, _) = Show::start(&display, &dir, "star_glow", &args);
    show.wait_for("OSCQuery");
    let intensity = || {
        let (_, leaf) = http_get(query.parse().unwrap(), "/indra/glow/intensity");
        leaf["VALUE"][0].as_f64().unwrap()
    };
    // 0x9C40 of 0xFFFF: 2.44144 of 4 — an 8-bit channel could only land on 2.43137 or 2.44706.
    let o =
        Command::new(&python).arg(peer()).args(["send", "127.0.0.1", "3", "2", "10=156", "11=64"]).output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let want = 4.0 * f64::from(0x9C40u16) / 65535.0;
    let deadline = Instant::now() + Duration::from_secs(20);
    while (intensity() - want).abs() > 1e-4 {
        assert!(Instant::now() < deadline, "intensity is {}, the desk sent {want}", intensity());
        std::thread::sleep(Duration::from_millis(100));
    }
    // Malformed packets and a flood of valid ones for a universe nobody maps, on Art-Net.
    let before = show.resident();
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    let mut artdmx = b"Art-Net\0\x00\x50\x00\x0e\x00\x00\x07\x00\x02\x00".to_vec();
    artdmx.extend_from_slice(&[255; 512]);
    for i in 0..100_000u32 {
        let packet: &[u8] = match i % 3 {
            0 => &artdmx,
            1 => &artdmx[..20],
            _ => b"Art-Net\0\xff\xff garbage",
        };
        let _ = socket.send_to(packet, ("127.0.0.1", artnet_port));
    }
    std::thread::sleep(Duration::from_secs(2));
    assert!(show.child.try_wait().unwrap().is_none(), "the show ended under the flood");
    assert!((intensity() - want).abs() < 1e-4, "the flood moved the parameter");
    let grown = show.resident().saturating_sub(before);
    assert!(grown < 64 << 20, "the flood grew the show by {:.0} MiB", mib(grown));
}

#[test]
fn dmx_learn_binds_the_channel_that_moves_and_keeps_it_for_the_next_start() {
    use indra::control::dmx_in::{DmxControl, DmxInFile};
    use indra::params::{ControlEvent, ParamValue, Target};
    let scene = indra::scene::parse_scene(
        "t.ron",
        r#"(name: "t", size: (8, 8), dt: 0.1, nodes: [(id: "fluid", technique: "grid_fluid")], output: "fluid")"#,
    )
    .unwrap();
    let param = scene.nodes[0].params.decls().iter().position(|d| d.name == "velocity_coef").unwrap();
    let target = Target { node: 0, param, component: None };
    let range = scene.nodes[0].params.decls()[param].range.unwrap();
    let dir = scratch_dir("dmx-learn");
    let port = UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let text = format!("(listen: (artnet: \"127.0.0.1:{port}\"))");
    let path = dir.join("desk.ron");
    std::fs::write(&path, text).unwrap();
    let learn_file = dir.join("dmx-learn.ron");
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    let send = |universe: u8, channel: usize, value: u8| {
        let mut packet = b"Art-Net\0\x00\x50\x00\x0e\x00\x00".to_vec();
        packet.extend_from_slice(&[universe, 0, 2, 0]);
        let mut channels = [0u8; 512];
        channels[channel - 1] = value;
        packet.extend_from_slice(&channels);
        socket.send_to(&packet, ("127.0.0.1", port)).unwrap();
    };
    // Frames until `done` says yes (the receiver is a thread of its own).
    let frames = |control: &mut DmxControl, notices: &mut Vec<String>, done: &dyn Fn(&[ControlEvent]) -> bool| {
        let deadline = Instant::now() + Duration::from_secs(10);
        loop {
            let events = control.events(&scene, notices);
            if done(&events) {
                return events;
            }
            assert!(Instant::now() < deadline, "nothing came: {notices:?}");
            std::thread::sleep(Duration::from_millis(20));
        }
    };
    let mut notices = Vec::new();
    let mut control =
        DmxControl::start(DmxInFile::load(&path).unwrap(), Some(learn_file.clone()), &scene, &mut notices).unwrap();
    send(2, 7, 0);
    frames(&mut control, &mut notices, &|_| true);
    control.learn(target, "fluid.velocity_coef".into());
    send(2, 7, 40);
    let bound = |n: &Vec<String>| n.iter().any(|m| m.contains("universe 2 channel 7"));
    let deadline = Instant::now() + Duration::from_secs(10);
    while !bound(&notices) {
        assert!(Instant::now() < deadline, "no channel was learned: {notices:?}");
        control.events(&scene, &mut notices);
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(control.maps(target) && control.learning().is_none());
    drop(control);

    // A new start reads what was learned: the channel at full drives the top of the range.
    let mut control =
        DmxControl::start(DmxInFile::load(&path).unwrap(), Some(learn_file), &scene, &mut notices).unwrap();
    send(2, 7, 255);
    let wrote_top = |events: &[ControlEvent]| {
        events
            .iter()
            .any(|e| matches!(e, ControlEvent::Write(w) if w.param == param && w.value == ParamValue::Float(range.1)))
    };
    frames(&mut control, &mut notices, &wrote_top);
}

#[test]
fn an_ofl_moving_head_follows_its_parameters_and_keeps_its_profile_defaults() {
    let dir = scratch_dir("dmx-lamp");
    let profile = Path::new(env!("CARGO_MANIFEST_DIR")).join("patches/fixtures/generic-spot.json");
    let patch_file = dir.join("lamp.ron");
    let patch = format!(
        "(artnet: (to: [\"127.0.0.1:9\"]), lamps: [(name: \"spot\", profile: {:?}, mode: \"9-channel\", \
         universe: 7, address: 100, drive: {{\"Dimmer\": \"glow.intensity\", \"Pan\": \"glow.intensity\"}})])",
        profile.display().to_string()
    );
    std::fs::write(&patch_file, patch).unwrap();
    let channels = |intensity: &str| {
        let record = dir.join(format!("{intensity}.dmx"));
        let o = indra()
            .args(["render", "star_glow", "--size", "64x36", "--frames", "2", "--set"])
            .arg(format!("glow.intensity={intensity}"))
            .arg("--out")
            .arg(dir.join("frames"))
            .arg("--dmx-out")
            .arg(&patch_file)
            .arg("--dmx-record")
            .arg(&record)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", text(&o));
        let bytes = std::fs::read(record).unwrap();
        assert_eq!(u16::from_le_bytes([bytes[8], bytes[9]]), 7, "one universe: the lamp's");
        bytes[10 + 99..10 + 108].to_vec()
    };
    // glow.intensity's range is 0–10: 2.5 is a quarter. Pan has a fine channel (16 bits),
    // Dimmer has none; Tilt stays at its 50 % default, Shutter at 255, the colours at 0.
    assert_eq!(channels("2.5"), vec![0x40, 0x00, 0x80, 0x00, 64, 0, 0, 0, 255]);
    assert_eq!(channels("10")[..5], [0xff, 0xff, 0x80, 0x00, 255]);
}

#[test]
fn two_desks_merge_highest_takes_precedence_and_a_channel_picks_a_layers_clip() {
    use indra::control::dmx_in::{DmxControl, DmxInFile};
    use indra::params::{ControlEvent, ShowCommand};
    let dir = scratch_dir("dmx-merge");
    let port = UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let path = dir.join("desk.ron");
    let file =
        format!("(listen: (artnet: \"127.0.0.1:{port}\", merge: Htp), clips: [(universe: 1, channel: 5, layer: 2)])");
    std::fs::write(&path, file).unwrap();
    let scene = indra::scene::show::load_show(&crate::common::assets(), "shows/set.ron", true).unwrap();
    let mut notices = Vec::new();
    let mut control = DmxControl::start(DmxInFile::load(&path).unwrap(), None, &scene, &mut notices).unwrap();
    // Two sources (two loopback addresses), each with channels of its own set.
    let desk = |from: &str, values: &[(usize, u8)]| {
        let socket = UdpSocket::bind((from, 0)).unwrap();
        let mut packet = b"Art-Net\0\x00\x50\x00\x0e\x00\x00\x01\x00\x02\x00".to_vec();
        let mut channels = [0u8; 512];
        for &(c, v) in values {
            channels[c - 1] = v;
        }
        packet.extend_from_slice(&channels);
        socket.send_to(&packet, ("127.0.0.1", port)).unwrap();
    };
    // The higher value first, then the lower from another desk: HTP keeps 2 (layer 2 plays its
    // second clip and nothing else); LTP would end on 1 and trigger the first clip.
    desk("127.0.0.1", &[(5, 2)]);
    std::thread::sleep(Duration::from_millis(100));
    desk("127.0.0.2", &[(5, 1)]);
    let trigger = |clip| ControlEvent::Show(ShowCommand::Trigger { layer: 1, clip: Some(clip) });
    let deadline = Instant::now() + Duration::from_secs(10);
    let mut seen = Vec::new();
    while !seen.contains(&trigger(1)) || control.counts().packets < 2 {
        assert!(Instant::now() < deadline, "no trigger of clip 2: {seen:?} {notices:?}");
        seen.extend(control.events(&scene, &mut notices));
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(300));
    seen.extend(control.events(&scene, &mut notices));
    assert!(!seen.contains(&trigger(0)), "the lower desk's value took over: {seen:?}");
    assert_eq!(control.counts().malformed, 0);
}
