//! A lost or stuck GPU does not end the show: the device-lost callback and the frame watchdog
//! notice it, the shader reload that caused it is rolled back, and every node moves to a new
//! device with its parameters — through the same `live::recover` the window uses.

use crate::common;

use std::path::PathBuf;
use std::time::{Duration, Instant};

use indra::assets::Assets;
use indra::live::{GpuState, GpuTrouble, LiveReload, ReloadReport};
use indra::offscreen::OffscreenRenderer;
use indra::params::{ControlEvent, ParamValue, ParamWrite, Source};
use indra::scene::load_scene;

const SIZE: (u32, u32) = (64, 64);

/// A private copy of the project's scenes/ and shaders/ to edit.
fn sandbox(name: &str) -> PathBuf {
    common::sandbox(&format!("recovery-{name}"))
}

/// Checks the device until something other than `skip` shows (wgpu reports a loss while
/// polling), at most 20 s.
fn state_after(r: &mut OffscreenRenderer, skip: GpuState) -> GpuState {
    let start = Instant::now();
    loop {
        let state = r.check_gpu();
        if state != skip {
            return state;
        }
        assert!(start.elapsed() < Duration::from_secs(20), "still {skip:?}");
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// The trouble a check reports next.
fn trouble(r: &mut OffscreenRenderer) -> GpuTrouble {
    match state_after(r, GpuState::Ready) {
        GpuState::Trouble(t) => t,
        other => panic!("expected trouble, got {other:?}"),
    }
}

/// Sets `limit_set.hit_color` as OSC would.
/// Polls hot reload until a file is applied (or 5 s pass).
fn wait_for_applied(r: &mut OffscreenRenderer, live: &mut LiveReload) -> ReloadReport {
    let start = Instant::now();
    loop {
        let report = r.poll_reload(live);
        if !report.applied.is_empty() || start.elapsed() > Duration::from_secs(5) {
            return report;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn hit_color(r: &mut OffscreenRenderer, rgb: [f32; 3]) {
    let scene = r.instance_mut().scene().clone();
    let node = scene.nodes.iter().position(|n| n.id == "limit_set").unwrap();
    let param = scene.nodes[node].params.index("hit_color").unwrap();
    let value = ParamValue::Color([rgb[0], rgb[1], rgb[2], 1.0]);
    let write = ParamWrite { node, param, component: None, value, source: Source::Osc };
    r.instance_mut().apply(&[ControlEvent::Write(write)]);
}

#[test]
fn a_destroyed_device_is_replaced_and_the_show_keeps_its_parameters() {
    let assets = common::assets();
    let scene = load_scene(&assets, "kleinian_classic").unwrap();
    let mut r = OffscreenRenderer::new(common::gpu(), &assets, scene, Some(SIZE), None, None).unwrap();
    r.render_next().unwrap();
    hit_color(&mut r, [1.0, 0.0, 0.0]);
    assert_eq!(r.check_gpu(), GpuState::Ready, "a healthy device is no trouble");
    r.gpu().device.destroy();
    let t = trouble(&mut r);
    assert!(matches!(t, GpuTrouble::Lost(_)), "{t:?}");
    let message = r.recover(&t, None, &assets).unwrap();
    assert!(message.contains("lost") && message.contains("parameters kept"), "{message}");
    let frame = r.render_next().unwrap();
    assert_eq!(frame.time.frame, 1, "the clock goes on");
    let mut reference = load_scene(&assets, "kleinian_classic").unwrap();
    reference.set_from_str("limit_set.hit_color=1,0,0").unwrap();
    assert!(frame.rgba == common::render_scene(reference, SIZE, 1).rgba, "same picture, same parameters");
    assert_eq!(r.check_gpu(), GpuState::Ready);
}

/// A validating shader edit that keeps every pixel busy far longer than any frame may take
/// (on lavapipe, which never resets a device, this is a frozen show without the watchdog).
/// lavapipe ends a loop after 65,535 iterations, so each iteration does a long unrolled run.
fn spinning_store() -> String {
    let body = "        spin = spin ^ (spin << 13u);\n        spin = spin ^ (spin >> 17u);\n        spin = spin ^ (spin << 5u) ^ k;\n";
    format!(
        "    var spin = id.x * 9781u + id.y * 6271u + params.seed;
    for (var k = 0u; k < params.iterations * 300u; k = k + 1u) {{
{}    }}
    color = vec4<f32>(f32(spin & 255u) / 255.0);
    textureStore(output, vec2<i32>(id.xy), color);",
        body.repeat(100)
    )
}

/// A renderer on a sandbox whose `kleinian.wgsl` has just been replaced, live, by one that
/// spins for seconds per frame; the stall limit is 0.3 s, the device is stuck after `stuck`. Returns the renderer, the reload, the
/// sandbox, the good shader text and the frame drawn before the edit.
fn stalling(name: &str, stuck: Duration) -> (OffscreenRenderer, LiveReload, PathBuf, String) {
    let root = sandbox(name);
    let assets = Assets::new(Some(root.clone()));
    let scene = load_scene(&assets, "kleinian_classic").unwrap();
    let mut live = LiveReload::new(&assets).unwrap();
    let mut r = OffscreenRenderer::new(common::gpu(), &assets, scene, Some(SIZE), None, None).unwrap();
    r.set_gpu_limits(Duration::from_millis(300), stuck);
    r.render_next().unwrap();
    hit_color(&mut r, [0.0, 1.0, 0.0]);
    let shader = root.join("shaders/kleinian.wgsl");
    let good = std::fs::read_to_string(&shader).unwrap();
    assert!(good.contains(STORE));
    std::fs::write(&shader, good.replace(STORE, &spinning_store())).unwrap();
    let report = wait_for_applied(&mut r, &mut live);
    assert_eq!(report.applied.len(), 1, "the spinning shader validates and goes live: {report:?}");
    (r, live, root, good)
}

/// The store of `render_edges`, which `kleinian_classic` (4 samples, adaptive) runs.
const STORE: &str = "    textureStore(output, vec2<i32>(id.xy), color);";

/// What the scene shows with the good shader and the green hit colour set before the stall.
fn good_green_frame() -> Vec<u8> {
    let mut reference = load_scene(&common::assets(), "kleinian_classic").unwrap();
    reference.set_from_str("limit_set.hit_color=0,1,0").unwrap();
    common::render_scene(reference, SIZE, 2).rgba
}

#[test]
fn a_stalling_shader_reload_is_rolled_back_and_the_show_resumes_when_the_gpu_catches_up() {
    let (mut r, mut live, root, good) = stalling("stall", Duration::from_secs(120));
    r.render_only().unwrap();
    let t = trouble(&mut r);
    assert!(matches!(t, GpuTrouble::Stalled(_)), "{t:?}");
    let message = r.roll_back_stall(&t, Some(&mut live));
    assert!(message.contains("rolled back") && message.contains("kleinian.wgsl"), "{message}");
    // The stuck frame finishes (lavapipe ends it eventually); meanwhile checks say wait.
    assert_eq!(r.check_gpu(), GpuState::Waiting);
    assert_eq!(state_after(&mut r, GpuState::Waiting), GpuState::Ready);
    assert!(r.render_next().unwrap().rgba == good_green_frame(), "the shader before the edit, the new colour");

    // Saving the same text again is not tried again; a different edit is.
    let shader = root.join("shaders/kleinian.wgsl");
    std::fs::write(&shader, good.replace(STORE, &spinning_store())).unwrap();
    std::thread::sleep(Duration::from_millis(400));
    assert!(r.poll_reload(&mut live).applied.is_empty(), "the stalling version is not applied again");
    std::fs::write(&shader, &good).unwrap();
    let report = wait_for_applied(&mut r, &mut live);
    assert_eq!((report.applied.len(), report.fixed.len()), (1, 1), "{report:?}");
    std::fs::remove_dir_all(root).unwrap();
}

#[test]
fn a_device_stuck_past_four_limits_is_replaced() {
    let (mut r, mut live, root, _) = stalling("stuck", Duration::from_millis(1200));
    r.render_only().unwrap();
    let t = trouble(&mut r);
    r.roll_back_stall(&t, Some(&mut live));
    let stuck = match state_after(&mut r, GpuState::Waiting) {
        GpuState::Trouble(t) => t,
        other => panic!("the spinning frame outlasts 1.2 s, yet: {other:?}"),
    };
    assert!(matches!(stuck, GpuTrouble::Stuck(w) if w >= Duration::from_millis(1200)), "{stuck:?}");
    let message = r.recover(&stuck, Some(&mut live), &common::assets()).unwrap();
    assert!(message.contains("new device"), "{message}");
    assert!(r.render_next().unwrap().rgba == good_green_frame(), "rebuilt from the rolled-back shader");
    std::fs::remove_dir_all(root).unwrap();
}

#[test]
fn a_simulation_restarts_on_the_new_device_and_keeps_running() {
    let assets = common::assets();
    let mut scene = load_scene(&assets, "cloth").unwrap();
    scene.set_from_str("cloth.resolution=16").unwrap();
    let mut r = OffscreenRenderer::new(common::gpu(), &assets, scene, Some(SIZE), None, None).unwrap();
    let before = r.render_next().unwrap();
    r.seek(30).unwrap();
    r.gpu().device.destroy();
    let t = trouble(&mut r);
    let message = r.recover(&t, None, &assets).unwrap();
    assert!(!message.contains("rolled back"), "no reload to blame: {message}");
    let after = r.render_next().unwrap();
    assert_eq!(after.time.frame, 30);
    // The cloth starts again from its initial shape (the same coverage as frame 0) and moves on.
    let covered = |rgba: &[u8]| rgba.chunks(4).filter(|p| p[..3] != rgba[..3]).count();
    let (first, restarted) = (covered(&before.rgba), covered(&after.rgba));
    assert!(first > 100 && restarted.abs_diff(first) * 20 < first, "cloth drawn again: {first} vs {restarted} px");
    r.seek(40).unwrap();
    assert!(r.render_next().unwrap().rgba != after.rgba, "the simulation runs on the new device");
    assert_eq!(r.check_gpu(), GpuState::Ready);
}

/// An ISF generator with a `spin` input; `body` is its `main`.
fn isf_generator(body: &str) -> String {
    format!(
        "/*{{ \"INPUTS\": [ {{ \"NAME\": \"spin\", \"TYPE\": \"float\", \"DEFAULT\": 200.0, \"MIN\": 0.0, \"MAX\": 200.0 }} ] }}*/\n\
         void main() {{\n{body}\n}}\n"
    )
}

/// The same spinning loop as [`spinning_store`], in ISF's GLSL: 60,000 trips of 100 rounds a
/// pixel at the default `spin` (lavapipe ends a loop at 65,535), seconds a frame.
fn spinning_isf() -> String {
    let body = "        s = s ^ (s << 13u);\n        s = s ^ (s >> 17u);\n        s = s ^ (s << 5u) ^ uint(k);\n";
    isf_generator(&format!(
        "    uint s = uint(gl_FragCoord.x) * 9781u + uint(gl_FragCoord.y) * 6271u;
    for (int k = 0; k < int(spin) * 300; k++) {{
{}    }}
    gl_FragColor = vec4(float(s & 255u) / 255.0);",
        body.repeat(100)
    ))
}

#[test]
fn a_stalling_isf_edit_is_rolled_back_and_a_new_device_never_reads_it_again() {
    let root = sandbox("isf-stall");
    let isf = root.join("shaders/isf/spin.fs");
    std::fs::create_dir_all(isf.parent().unwrap()).unwrap();
    let calm = isf_generator("    gl_FragColor = vec4(isf_FragNormCoord.x, 0.25, 0.5 + spin * 0.0, 1.0);");
    std::fs::write(&isf, &calm).unwrap();
    let scene_file = root.join("scenes/spin.ron");
    std::fs::write(
        &scene_file,
        r#"(name: "spin", size: (64, 64), nodes: [(id: "isf", technique: "isf", params: { "file": "shaders/isf/spin.fs" })], output: "isf")"#,
    )
    .unwrap();
    let assets = Assets::new(Some(root.clone()));
    let scene = load_scene(&assets, "spin").unwrap();
    let mut live = LiveReload::new(&assets).unwrap();
    let mut r = OffscreenRenderer::new(common::gpu(), &assets, scene, Some(SIZE), None, None).unwrap();
    r.set_gpu_limits(Duration::from_millis(300), Duration::from_millis(1200));
    let good = r.render_next().unwrap().rgba;
    std::fs::write(&isf, spinning_isf()).unwrap();
    let report = wait_for_applied(&mut r, &mut live);
    assert_eq!(report.applied.len(), 1, "the spinning shader compiles and goes live: {report:?}");
    r.render_only().unwrap();
    let t = trouble(&mut r);
    assert!(matches!(t, GpuTrouble::Stalled(_)), "{t:?}");
    let message = r.roll_back_stall(&t, Some(&mut live));
    assert!(message.contains("rolled back") && message.contains("spin.fs"), "{message}");
    // The stuck frame outlasts the device's limit: the show moves to a new device, built from
    // the version before the edit, not from the file on disk (which still spins).
    let stuck = match state_after(&mut r, GpuState::Waiting) {
        GpuState::Trouble(t) => t,
        other => panic!("the spinning frame outlasts 1.2 s, yet: {other:?}"),
    };
    let message = r.recover(&stuck, Some(&mut live), &assets).unwrap();
    assert!(message.contains("new device"), "{message}");
    assert!(r.render_next().unwrap().rgba == good, "the ISF shader before the edit");
    // Saved again unchanged, it is not tried again.
    std::fs::write(&isf, spinning_isf()).unwrap();
    std::thread::sleep(Duration::from_millis(400));
    assert!(r.poll_reload(&mut live).applied.is_empty(), "the stalling version is not applied again");
    std::fs::remove_dir_all(root).unwrap();
}
