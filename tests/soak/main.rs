//! A show that runs for weeks, tried for minutes: a window under Xvfb playing a show of several
//! clips with transitions and a looping cue list while OSC floods its clip triggers, its
//! resident memory sampled twice a second.
//!
//! A test binary of its own, so that it runs alone: it measures one process's memory, and the
//! suite's other tests beside it changed the show's pace as they started and ended (on CI's two
//! cores the show's median memory rose 6 MiB in three minutes while its floor did not).
//! `INDRA_SOAK_SECONDS=3600 cargo test --test soak -- --nocapture` soaks for an hour.

use std::net::UdpSocket;
use std::time::{Duration, Instant};

#[path = "../support/live_show.rs"]
mod live_show;

use live_show::{Show, VirtualDisplay, bundle, mib, scratch_dir};

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

/// How long the show plays: 200 s, or `INDRA_SOAK_SECONDS`.
fn run_time() -> Duration {
    let seconds = std::env::var("INDRA_SOAK_SECONDS").ok().and_then(|s| s.parse().ok()).unwrap_or(200);
    Duration::from_secs(seconds)
}

/// The `q` quantile (0–1) of the samples taken in `from..to`.
fn quantile(samples: &[(Duration, u64)], from: Duration, to: Duration, q: f64) -> u64 {
    let mut window: Vec<u64> = samples.iter().filter(|(t, _)| *t >= from && *t < to).map(|s| s.1).collect();
    window.sort_unstable();
    window[((window.len() - 1) as f64 * q).round() as usize]
}

#[test]
fn a_show_under_trigger_floods_keeps_its_memory_flat() {
    const SETTLE: Duration = Duration::from_secs(30);
    const SAMPLE_EVERY: Duration = Duration::from_millis(500);
    let run = run_time().max(SETTLE * 3);
    let display = VirtualDisplay::start();
    let dir = scratch_dir("soak");
    let file = dir.join("soak.ron");
    std::fs::write(&file, SOAK_SHOW).unwrap();
    let (mut show, port) = Show::start(&display, &dir, file.to_str().unwrap(), &[]);
    show.wait_for("plays clip 'glow'");
    let osc = UdpSocket::bind("127.0.0.1:0").unwrap();
    let start = Instant::now();
    let mut samples: Vec<(Duration, u64)> = Vec::new();
    let mut round = 0u32;
    while start.elapsed() < run {
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
        for _ in 0..2 {
            samples.push((start.elapsed(), show.resident()));
            std::thread::sleep(SAMPLE_EVERY);
        }
    }
    samples.push((start.elapsed(), show.resident()));
    let log = show.wait_for("plays clip");
    assert!(!log.contains("panicked"), "{log}");
    assert!(samples.iter().all(|(_, b)| *b > 0), "the show ended:\n{log}");
    let table: Vec<String> =
        samples.iter().step_by(4).map(|(t, b)| format!("{:>5} s {:7.1} MiB", t.as_secs(), mib(*b))).collect();
    // While a clip's fresh copy is being built its buffers and the driver's shader code are held
    // (+15–25 MiB for a moment), and the busier the machine the longer each build takes, so the
    // median follows the machine's load. What a leak raises is the floor the memory comes back
    // to between builds: the 10th percentile of the 30 s after the first 30 s against that of
    // the last 30 s.
    let floor = |from, to| quantile(&samples, from, to, 0.1);
    let settled = floor(SETTLE, SETTLE * 2);
    let end = floor(run - SETTLE, run + SETTLE);
    let median_end = quantile(&samples, run - SETTLE, run + SETTLE, 0.5);
    println!(
        "soak RSS over {} s: floor {:.1} MiB at 30–60 s, {:.1} MiB over the last 30 s (median {:.1} MiB)\n{}",
        run.as_secs(),
        mib(settled),
        mib(end),
        mib(median_end),
        table.join("\n")
    );
    assert!(
        end < settled + (5 << 20),
        "the floor of RSS rose {:.1} MiB after the first 30 s:\n{}",
        mib(end.saturating_sub(settled)),
        table.join("\n")
    );
}
