//! A flood of retriggers that must neither stall the render loop nor queue without bound: a
//! thousand in one bundle, then hundreds a second, and the show still answers a new trigger.

use std::net::UdpSocket;
use std::time::{Duration, Instant};

use crate::live_show::{Show, VirtualDisplay, bundle, mib, scratch_dir};

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
    assert!(show.resident() < 2 << 30, "the flood took {:.0} MiB", mib(show.resident()));
}
