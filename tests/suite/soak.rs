//! A show that runs for weeks, tried for minutes: a window under Xvfb playing a show of several
//! clips with transitions and a looping cue list while OSC floods its clip triggers, its
//! resident memory sampled every 2 s (flat after the first 30 s: under 5 MB between the medians
//! of 30–60 s and of the last 30 s); and a flood of retriggers that must neither stall the render
//! loop nor queue without bound.

use std::net::UdpSocket;
use std::time::{Duration, Instant};

use rosc::{OscBundle, OscMessage, OscPacket, OscTime, OscType};

use crate::window::{Show, VirtualDisplay, scratch_dir};

/// Four clips on two layers (StarGlow's fused passes, an ISF generator, a HAP clip, the
/// tessellated relief: what leaked on lavapipe), crossfades and a luma wipe, and a cue list
/// that walks them every 1.5 s for ever.
const SOAK_SHOW: &str = r#"(
    name: "soak",
    size: (160, 90),
    seed: 1,
    transition: (kind: "crossfade", seconds: 0.5),
    layers: [
        (name: "base", clips: [
            (scene: "kleinian_star_glow", id: "glow"),
            (scene: "isf_star_glow", id: "sparks", transition: (kind: "luma", seconds: 0.4)),
            (scene: "video_star_glow", id: "video"),
        ]),
        (name: "top", blend: "add", opacity: 0.5, clips: [(scene: "tessellation_kleinian", id: "relief")]),
    ],
    cues: [
        (name: "one", clips: [(1, 1), (2, 1)], hold: Seconds(1.5)),
        (name: "two", clips: [(1, 2), (2, 0)], hold: Seconds(1.5)),
        (name: "three", clips: [(1, 3), (2, 1)], hold: Seconds(1.5)),
    ],
    loop_cues: true,
)"#;

/// Resident memory of process `pid`, in bytes.
fn resident(pid: u32) -> u64 {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap_or_default();
    let kib = status.lines().find_map(|l| l.strip_prefix("VmRSS:")).and_then(|v| v.split_whitespace().next());
    kib.and_then(|k| k.parse::<u64>().ok()).map_or(0, |k| k * 1024)
}

/// One OSC bundle of `count` messages to `addr`.
fn bundle(addr: &str, count: usize) -> Vec<u8> {
    let message = OscPacket::Message(OscMessage { addr: addr.into(), args: vec![OscType::Int(1)] });
    let bundle = OscBundle { timetag: OscTime { seconds: 0, fractional: 1 }, content: vec![message; count] };
    rosc::encoder::encode(&OscPacket::Bundle(bundle)).unwrap()
}

fn mib(bytes: u64) -> f64 {
    bytes as f64 / f64::from(1u32 << 20)
}

#[test]
fn a_show_under_trigger_floods_keeps_its_memory_flat_for_three_minutes() {
    const RUN: Duration = Duration::from_secs(200);
    const SETTLE: Duration = Duration::from_secs(30);
    let display = VirtualDisplay::start();
    let dir = scratch_dir("soak");
    let file = dir.join("soak.ron");
    std::fs::write(&file, SOAK_SHOW).unwrap();
    let (mut show, port) = Show::start(&display, &dir, file.to_str().unwrap(), &[]);
    show.wait_for("plays clip 'glow'");
    let osc = UdpSocket::bind("127.0.0.1:0").unwrap();
    let start = Instant::now();
    let mut samples: Vec<(Duration, u64)> = Vec::new();
    let mut next_sample = Duration::ZERO;
    let mut round = 0u32;
    while start.elapsed() < RUN {
        // Every second: a burst of triggers on the base layer, alternating clips, as a
        // controller's pads mashed; every fifth, a bundle of 200 retriggers of one clip.
        let clip = 1 + round % 3;
        for k in 0..20 {
            let addr = format!("/indra/layer/1/clip/{}/connect", 1 + (clip + k) % 3);
            let _ = osc.send_to(&bundle(&addr, 1), ("127.0.0.1", port));
        }
        if round.is_multiple_of(5) {
            let _ = osc.send_to(&bundle(&format!("/indra/layer/1/clip/{clip}/connect"), 200), ("127.0.0.1", port));
        }
        round += 1;
        if start.elapsed() >= next_sample {
            samples.push((start.elapsed(), resident(show.pid())));
            next_sample += Duration::from_secs(2);
        }
        std::thread::sleep(Duration::from_secs(1));
    }
    samples.push((start.elapsed(), resident(show.pid())));
    let log = show.wait_for("plays clip");
    assert!(!log.contains("panicked"), "{log}");
    let table: Vec<String> = samples.iter().map(|(t, b)| format!("{:>4} s {:7.1} MiB", t.as_secs(), mib(*b))).collect();
    assert!(samples.iter().all(|(_, b)| *b > 0), "the show ended:\n{log}");
    // A clip's fresh copy in flight holds its buffers for a moment (±15 MB here), so one sample
    // says little: the median of the 30 s after the first 30 s against the median of the last
    // 30 s, which a leak of a fraction of that per minute would still move.
    let median_between = |from: Duration, to: Duration| {
        let mut window: Vec<u64> = samples.iter().filter(|(t, _)| *t >= from && *t < to).map(|s| s.1).collect();
        window.sort_unstable();
        window[window.len() / 2]
    };
    let settled = median_between(SETTLE, SETTLE * 2);
    let end = median_between(RUN - SETTLE, RUN + SETTLE);
    println!(
        "soak RSS, medians: {:.1} MiB at 30–60 s, {:.1} MiB over the last 30 s of {} s\n{}",
        mib(settled),
        mib(end),
        RUN.as_secs(),
        table.join("\n")
    );
    assert!(
        end < settled + (5 << 20),
        "RSS grew {:.1} MiB after the first 30 s:\n{}",
        mib(end.saturating_sub(settled)),
        table.join("\n")
    );
}

#[test]
fn a_bundle_of_a_thousand_retriggers_never_stalls_the_show() {
    let display = VirtualDisplay::start();
    let dir = scratch_dir("flood");
    let file = dir.join("flood.ron");
    let show_text = r#"(
        name: "flood",
        size: (64, 36),
        layers: [(clips: [
            (scene: "tessellation_kleinian", id: "relief"),
            (scene: "kleinian_classic", id: "calm"),
            (scene: "kleinian_classic", id: "marker"),
        ])],
    )"#;
    std::fs::write(&file, show_text).unwrap();
    let (mut show, port) = Show::start(&display, &dir, file.to_str().unwrap(), &[]);
    show.wait_for("plays clip 'relief'");
    let osc = UdpSocket::bind("127.0.0.1:0").unwrap();
    // A thousand retriggers of the playing clip in one 40-KB bundle, then 5 s of alternating
    // triggers at ~200 a second: one build in flight per clip, never one on the render thread.
    osc.send_to(&bundle("/indra/layer/1/clip/1/connect", 1000), ("127.0.0.1", port)).unwrap();
    let flood_end = Instant::now() + Duration::from_secs(5);
    let mut k = 0;
    while Instant::now() < flood_end {
        let _ = osc.send_to(&bundle(&format!("/indra/layer/1/clip/{}/connect", 1 + k % 2), 1), ("127.0.0.1", port));
        k += 1;
        std::thread::sleep(Duration::from_millis(5));
    }
    // The render loop answers at once: a clip the flood never named shows within seconds (a
    // frame that built a clip a thousand times took over a minute).
    let asked = Instant::now();
    osc.send_to(&bundle("/indra/layer/1/clip/3/connect", 1), ("127.0.0.1", port)).unwrap();
    loop {
        let log = show.wait_for("plays clip");
        assert!(!log.contains("panicked"), "{log}");
        if log.contains("plays clip 'marker'") {
            break;
        }
        assert!(asked.elapsed() < Duration::from_secs(20), "no answer 20 s after the flood:\n{log}");
        std::thread::sleep(Duration::from_millis(100));
    }
    assert!(resident(show.pid()) < 2 << 30, "the flood took {:.0} MiB", mib(resident(show.pid())));
}
