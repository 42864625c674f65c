//! NDI end to end against the real runtime and a real peer: PyPI's cyndilib (which ships the NDI
//! runtime, `libndi.so`) receives what `indra render --ndi-out` sends, and sends what indra's
//! `ndi` node shows. Both ends run in a network namespace of their own (`unshare --net`, loopback
//! only), so nothing is announced on the machine's network; `tests/ndi/peer.py` is the peer and
//! says how discovery works there.
//!
//! `tools/test` installs cyndilib in `target/ndi-peer` (for the tests, never the product) and
//! exports `INDRA_NDI_PYTHON` and `NDI_RUNTIME_DIR_V6`. Without them these tests say they were
//! skipped — except on CI (`CI` set), where a missing peer fails them.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::text;

/// The peer's Python, or why the tests cannot run here.
pub(crate) fn peer_python() -> Option<String> {
    let python = std::env::var("INDRA_NDI_PYTHON").unwrap_or_else(|_| "python3".into());
    let has_cyndilib = Command::new(&python).args(["-c", "import cyndilib"]).output().is_ok_and(|o| o.status.success());
    let namespaces = Command::new("unshare").args(["--net", "--map-root-user", "true"]).output();
    let problem = match (has_cyndilib, namespaces) {
        (false, _) => format!("{python} has no cyndilib (tools/test installs it in target/ndi-peer)"),
        (true, Ok(o)) if o.status.success() => return Some(python),
        (true, _) => "`unshare --net --map-root-user` is not allowed here".into(),
    };
    assert!(std::env::var_os("CI").is_none(), "CI runs the NDI tests: {problem}");
    eprintln!("skipped: {problem}");
    None
}

pub(crate) fn out_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("indra-ndi-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs the peer in `mode` with indra as `indra_args` (and `env`) inside a fresh network
/// namespace; returns the peer's report and indra's log.
pub(crate) fn run_peer(
    python: &str,
    mode: &str,
    dir: &Path,
    indra_args: &[&str],
    env: &[(&str, &str)],
) -> (serde_json::Value, String) {
    let peer = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/ndi/peer.py");
    let o = Command::new("unshare")
        .args(["--net", "--map-root-user", python])
        .arg(&peer)
        .arg(mode)
        .arg(dir)
        .arg("--")
        .arg(env!("CARGO_BIN_EXE_indra"))
        .args(indra_args)
        .env("INDRA_ROOT", env!("CARGO_MANIFEST_DIR"))
        .envs(env.iter().copied())
        .output()
        .expect("unshare runs");
    let log = std::fs::read_to_string(dir.join("indra.log")).unwrap_or_default();
    assert!(o.status.success(), "the peer failed: {}\nindra: {log}", text(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    let report = stdout.lines().last().and_then(|l| serde_json::from_str(l).ok());
    (report.unwrap_or_else(|| panic!("no report from the peer: {}", text(&o))), log)
}

pub(crate) fn png_rgb(path: &Path) -> Vec<u8> {
    image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb8().into_raw()
}

/// Mean absolute difference of RGB values (0–255) between RGBA `received` and RGB `rendered`.
pub(crate) fn mean_difference(received: &[u8], rendered: &[u8]) -> f64 {
    let sum: u64 = received
        .chunks_exact(4)
        .zip(rendered.chunks_exact(3))
        .flat_map(|(a, b)| (0..3).map(move |c| u64::from(a[c].abs_diff(b[c]))))
        .sum();
    sum as f64 / rendered.len() as f64
}

#[test]
fn frames_indra_sends_arrive_in_a_cyndilib_receiver_as_rendered() {
    let Some(python) = peer_python() else { return };
    let dir = out_dir("out");
    let png = dir.join("png");
    let args = ["render", "kleinian", "--size", "96x54", "--frames", "240", "--ndi-out", "indra-out", "--backend"];
    let args: Vec<&str> = args.into_iter().chain(["vulkan", "--out", png.to_str().unwrap()]).collect();
    let (report, log) = run_peer(&python, "receive", &dir, &args, &[]);
    assert_eq!(report["indra_exit"], 0, "{log}");
    assert_eq!(report["found"], true, "the receiver never saw indra's source: {log}");
    let frames = report["frames"].as_array().unwrap();
    assert!(frames.len() >= 4, "only {} frame(s) arrived: {report}", frames.len());
    for f in frames {
        assert_eq!(f["size"], serde_json::json!([96, 54]), "{f}");
        assert_eq!(f["fourcc"], "RGBX", "{f}");
        let received = std::fs::read(f["file"].as_str().unwrap()).unwrap();
        assert_eq!(received.len(), 96 * 54 * 4, "{f}");
        // The timecode names the frame: it matches that frame's PNG (within NDI's SpeedHQ
        // compression) better than any frame near it.
        let n = f["frame"].as_u64().unwrap();
        let difference = |m: u64| mean_difference(&received, &png_rgb(&png.join(format!("kleinian_{m:05}.png"))));
        let own = difference(n);
        assert!(own < 6.0, "frame {n} arrived {own:.2} away from its render");
        for m in n.saturating_sub(6)..=(n + 6).min(239) {
            if m != n {
                let other = difference(m);
                assert!(own < other, "frame {n} ({own:.2}) is nearer frame {m}'s render ({other:.2})");
            }
        }
    }
}

#[test]
fn an_ndi_node_shows_a_cyndilib_sender_and_keeps_its_last_frame_when_it_stops() {
    let Some(python) = peer_python() else { return };
    let dir = out_dir("in");
    let png = dir.join("png");
    std::fs::write(
        dir.join("ndi_in.ron"),
        r#"(name: "NDI in", size: (96, 64), seed: 1, dt: 0.0166667,
            nodes: [(id: "feed", technique: "ndi", params: { "fit": "stretch" })], output: "feed")"#,
    )
    .unwrap();
    let scene = dir.join("ndi_in.ron");
    // 330 frames paced by indra's own NDI sender: 5.5 s, the peer sending for the first 3.
    let args =
        ["render", scene.to_str().unwrap(), "--frames", "330", "--ndi-out", "indra-paced", "--backend", "vulkan"];
    let args: Vec<&str> =
        args.into_iter().chain(["--set", "feed.source={url}", "--out", png.to_str().unwrap()]).collect();
    let (report, log) = run_peer(&python, "send", &dir, &args, &[]);
    assert_eq!(report["indra_exit"], 0, "{log}");
    let listed = report["list_ndi"].as_str().unwrap();
    assert!(listed.contains("(pysend)  127.0.0.1:"), "--list-ndi: {listed}");
    assert!(report["sent"].as_u64().unwrap() > 30, "{report}");

    let pixel = |frame: u64, x: usize, y: usize| {
        let rgb = png_rgb(&png.join(format!("ndi_in_{frame:05}.png")));
        let i = (y * 96 + x) * 3;
        [rgb[i], rgb[i + 1], rgb[i + 2]]
    };
    assert_eq!(pixel(0, 10, 10), [0, 0, 0], "nothing has arrived at the first frame");
    // The sender's quadrants (tests/ndi/peer.py), in place and in colour, within compression.
    let quadrants =
        [((10, 10), [230, 40, 40]), ((80, 10), [40, 200, 60]), ((10, 50), [50, 70, 220]), ((80, 50), [240, 220, 60])];
    for frame in [120, 329] {
        for ((x, y), want) in quadrants {
            let got = pixel(frame, x, y);
            assert!(
                got.iter().zip(want).all(|(g, w)| g.abs_diff(w) <= 16),
                "frame {frame} ({x}, {y}): {got:?} for {want:?}"
            );
        }
    }
    let stopped = log.matches("stopped sending; showing its last frame").count();
    assert_eq!(stopped, 1, "one notice when the sender stops: {log}");
}

#[test]
fn without_the_runtime_ndi_is_one_sentence_and_a_scene_still_renders() {
    let dir = out_dir("missing");
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_indra"))
            .args(args)
            .args(["--backend", "vulkan"])
            .env("INDRA_ROOT", env!("CARGO_MANIFEST_DIR"))
            .env("NDI_RUNTIME_DIR_V6", dir.join("nowhere"))
            .env_remove("LD_LIBRARY_PATH")
            .output()
            .unwrap()
    };
    // Only where no runtime is installed system-wide (CI has none; the peer's is named by the
    // variable this test points elsewhere).
    if Path::new("/usr/lib/libndi.so.6").exists() || Path::new("/usr/local/lib/libndi.so.6").exists() {
        return eprintln!("skipped: an NDI runtime is installed on this machine");
    }
    let o = run(&["render", "kleinian", "--size", "32x18", "--ndi-out", "x", "--out", dir.to_str().unwrap()]);
    assert!(!o.status.success());
    let said = text(&o);
    assert!(said.contains("no NDI runtime was found") && said.contains("NDI_RUNTIME_DIR_V6"), "{said}");

    std::fs::write(
        dir.join("ndi_in.ron"),
        r#"(name: "NDI in", size: (32, 18), seed: 1, dt: 0.0166667,
            nodes: [(id: "feed", technique: "ndi", params: { "source": "STAGE (OBS)" })], output: "feed")"#,
    )
    .unwrap();
    let o = run(&["render", dir.join("ndi_in.ron").to_str().unwrap(), "--frames", "3", "--out", dir.to_str().unwrap()]);
    let said = text(&o);
    assert!(o.status.success(), "{said}");
    assert_eq!(said.matches("no NDI runtime was found").count(), 1, "said once: {said}");
    assert_eq!(png_rgb(&dir.join("ndi_in_00002.png")).iter().max(), Some(&0), "black without a source");
}
