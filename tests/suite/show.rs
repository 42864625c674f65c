//! Shows: layers of clips, transitions, columns and cues. Blend modes and transitions against CPU
//! references on known texels; a show's crossfade against the mix of its two clips rendered
//! alone; quantized triggers landing on the beat's frame; frame N the same played or sought
//! across transitions and restarts, for test shows and every bundled show; a broken clip left
//! out while the rest plays; goldens of a transition's midpoint and of a two-layer blend.

use std::sync::Arc;

use crate::common::{self, assets, golden, gpu};
use indra::assets::AssetKind;
use indra::gpu::Gpu;
use indra::graph::{FrameGraph, GraphRuntime, TextureHandle};
use indra::offscreen::OffscreenRenderer;
use indra::params::{ControlEvent, ParamSet, ParamValue, ShowCommand};
use indra::scene::show::{Layer, LayerView, Mixer, Show, parse_show};
use indra::scene::{Scene, load_scene};
use indra::techniques::{NodeSetup, blend, srgb_to_linear};
use indra::time::FrameTime;

pub(crate) const SIZE: (u32, u32) = (32, 16);

/// Texels with every kind of value a node gives: dark, mid, bright, HDR above 1, and (in `over`)
/// alpha from transparent to opaque.
fn texels(seed: u32, with_alpha: bool) -> Vec<[f32; 4]> {
    (0..SIZE.0 * SIZE.1)
        .map(|i| {
            let h = (i.wrapping_mul(2_654_435_761) ^ seed.wrapping_mul(40_503)) as f32 / u32::MAX as f32;
            let c = |k: u32| ((h * (k as f32 + 1.7) * 9.31).fract()) * 1.6;
            let a = if with_alpha { (h * 5.3).fract() } else { 1.0 };
            [c(0), c(1), c(2), a]
        })
        .collect()
}

/// Runs `graph` (its output set) and returns the output texels.
fn execute(gpu: &Gpu, mut graph: FrameGraph<'_>, output: TextureHandle) -> Vec<[f32; 4]> {
    graph.set_output(output);
    let mut runtime = GraphRuntime::new(&gpu.device, &gpu.queue);
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let frame = runtime.execute(&gpu.device, &gpu.queue, graph, &mut encoder).unwrap();
    gpu.queue.submit([encoder.finish()]);
    common::read_float_texture(gpu, &frame.texture)
}

/// Half-float precision on values up to ~2 plus the inputs' own rounding.
fn close(got: f32, want: f32) -> bool {
    (got - want).abs() <= 4e-3 * want.abs().max(1.0)
}

fn f16(x: f32) -> f32 {
    half::f16::from_f32(x).to_f32()
}

/// The blend modes as documented, in linear light, over an opaque image below.
fn blend_reference(mode: u32, below: [f32; 4], over: [f32; 4], opacity: f32) -> [f32; 4] {
    let a = opacity * over[3].clamp(0.0, 1.0);
    let mut out = [0.0; 4];
    for c in 0..3 {
        let (x, y) = (below[c], over[c]);
        let mixed = match mode {
            0 => y,
            1 => x + y,
            2 => x + y - x * y,
            3 => x * y,
            4 => (x - y).abs(),
            5 => x.max(y),
            _ => unreachable!(),
        };
        out[c] = x + (mixed - x) * a;
    }
    out[3] = below[3] + a * (1.0 - below[3]);
    out
}

#[test]
fn each_blend_mode_matches_a_cpu_reference() {
    let gpu = gpu();
    let assets = assets();
    let (below, over) = (texels(1, false), texels(2, true));
    let modes = blend::BlendMode::OPTIONS;
    assert_eq!(modes, ["normal", "add", "screen", "multiply", "difference", "lighten"]);
    for (mode, name) in modes.iter().enumerate() {
        for opacity in [0.0, 0.37, 1.0] {
            let mut params = ParamSet::new(blend::Settings::decls());
            params.set_at(params.index("blend").unwrap(), ParamValue::Enum(mode as u32));
            params.set_at(params.index("opacity").unwrap(), ParamValue::Float(opacity));
            params.snap();
            let setup = NodeSetup {
                gpu: &gpu,
                assets: &assets,
                id: "layer",
                output_size: SIZE,
                msaa: 1,
                params: &params,
                seed: 0,
            };
            let mut node = (blend::INFO.create)(&setup).unwrap();
            let time = FrameTime { frame: 0, seconds: 0.0, dt: 1.0 / 60.0, seed: 0 };
            let (ta, tb) = (common::float_texture(&gpu, SIZE, &below), common::float_texture(&gpu, SIZE, &over));
            let mut graph = FrameGraph::new(SIZE);
            let (a, b) = (graph.import_texture("below", &ta), graph.import_texture("over", &tb));
            let output = node.add_passes(&mut graph, &params, &time, &[a, b]);
            let got = execute(&gpu, graph, output);
            for (i, texel) in got.iter().enumerate() {
                let (x, y) = (below[i].map(f16), over[i].map(f16));
                let want = blend_reference(mode as u32, x, y, opacity);
                for c in 0..4 {
                    assert!(
                        close(texel[c], want[c]),
                        "{name} at opacity {opacity}, texel {i} channel {c}: {} (want {})",
                        texel[c],
                        want[c]
                    );
                }
            }
        }
    }
}

/// A show of one layer with `kinds` transitions (enough to build a [`Mixer`]).
pub(crate) fn mixer_show(kinds: &[&str]) -> Show {
    Show {
        layers: vec![Layer { name: "one".into(), node: 0, clips: Vec::new(), start: None, effects: Vec::new() }],
        clips: Vec::new(),
        columns: Vec::new(),
        cues: Vec::new(),
        loop_cues: true,
        master: 1,
        master_effects: Vec::new(),
        effects: Vec::new(),
        mix_kind: None,
        file: None,
        cue_notes: Default::default(),
        kinds: kinds.iter().map(|k| k.to_string()).collect(),
        sources: Vec::new(),
        broken: Vec::new(),
        timeline: Default::default(),
    }
}

pub(crate) fn mix(
    gpu: &Gpu,
    mixer: &mut Mixer,
    kind: usize,
    progress: f32,
    a: &[[f32; 4]],
    b: &[[f32; 4]],
) -> Vec<[f32; 4]> {
    let view = LayerView { from: Some(0), to: Some(1), progress, kind: Some(kind), seconds: 0.0 };
    let (ta, tb) = (common::float_texture(gpu, SIZE, a), common::float_texture(gpu, SIZE, b));
    let mut graph = FrameGraph::new(SIZE);
    let (ha, hb) = (graph.import_texture("from", &ta), graph.import_texture("to", &tb));
    let output = mixer.frame().declare(&mut graph, 0, &view, ha, hb);
    execute(gpu, graph, output)
}

#[test]
fn a_crossfade_at_progress_p_is_the_linear_mix_of_its_two_images() {
    let gpu = gpu();
    let mut mixer = Mixer::new(&gpu, &assets(), &mixer_show(&["crossfade"])).unwrap();
    let (a, b) = (texels(3, true), texels(4, true));
    for p in [0.0, 0.25, 0.5, 0.9, 1.0] {
        let got = mix(&gpu, &mut mixer, 0, p, &a, &b);
        for (i, texel) in got.iter().enumerate() {
            for c in 0..4 {
                let want = (1.0 - p) * f16(a[i][c]) + p * f16(b[i][c]);
                assert!(close(texel[c], want), "p {p}, texel {i} channel {c}: {} (want {want})", texel[c]);
            }
        }
    }
}

#[test]
fn every_bundled_transition_starts_on_the_outgoing_image_and_ends_on_the_incoming() {
    let gpu = gpu();
    let kinds = ["crossfade", "fade_black", "wipe", "luma"];
    let mut mixer = Mixer::new(&gpu, &assets(), &mixer_show(&kinds)).unwrap();
    let (a, b) = (texels(5, false), texels(6, false));
    for (k, kind) in kinds.iter().enumerate() {
        for (p, side) in [(0.0, &a), (1.0, &b)] {
            let got = mix(&gpu, &mut mixer, k, p, &a, &b);
            for (i, texel) in got.iter().enumerate() {
                for c in 0..3 {
                    assert!(
                        close(texel[c], f16(side[i][c])),
                        "{kind} at p {p}: texel {i} is {texel:?}, want {:?}",
                        side[i]
                    );
                }
            }
        }
        // Halfway, a wipe shows the outgoing image on the left and the incoming on the right.
        if *kind == "wipe" {
            let got = mix(&gpu, &mut mixer, k, 0.5, &a, &b);
            let at = |x: u32, y: u32| (y * SIZE.0 + x) as usize;
            assert!(close(got[at(2, 5)][0], f16(b[at(2, 5)][0])), "left of the edge shows the incoming clip");
            assert!(close(got[at(29, 5)][0], f16(a[at(29, 5)][0])), "right of the edge shows the outgoing clip");
        }
        // Halfway through a fade through black, the picture is black.
        if *kind == "fade_black" {
            let got = mix(&gpu, &mut mixer, k, 0.5, &a, &b);
            assert!(got.iter().all(|t| t[..3].iter().all(|&v| v.abs() < 1e-3)), "fade_black at 0.5 is not black");
        }
    }
}

/// A show in the project's folder context, from RON text (clips name bundled scenes).
fn show_from(text: &str) -> Scene {
    parse_show(&assets(), "test-show.ron", text, false).unwrap_or_else(|e| panic!("{e}"))
}

fn renderer(scene: Scene, size: (u32, u32)) -> OffscreenRenderer {
    OffscreenRenderer::new(gpu(), &assets(), scene, Some(size), None, None).expect("show builds")
}

fn trigger(layer: usize, clip: usize) -> ControlEvent {
    ControlEvent::Show(ShowCommand::Trigger { layer, clip: Some(clip) })
}

/// Two static limit sets in different colours on one layer, crossfading over a second.
const TWO_COLOURS: &str = r#"(
    name: "two colours",
    size: (64, 36),
    seed: 1,
    transition: (kind: "crossfade", seconds: 1.0),
    layers: [(clips: [
        (scene: "kleinian_classic", id: "red", params: { "limit_set.hit_color": (0.9, 0.1, 0.1, 1.0) }),
        (scene: "kleinian_classic", id: "blue", params: { "limit_set.hit_color": (0.1, 0.2, 0.9, 1.0), "limit_set.back_color": (0.9, 0.9, 0.2, 1.0) }),
    ])],
)"#;

#[test]
fn a_show_crossfade_shows_the_linear_mix_of_its_clips_rendered_alone() {
    let size = (64, 36);
    let mut r = renderer(show_from(TWO_COLOURS), size);
    r.schedule(2, vec![trigger(0, 1)]);
    // Triggered at frame 2, a one-second crossfade at 60 steps a second is halfway at frame 32.
    r.seek(32).unwrap();
    let middle = r.render_next().unwrap();
    // Each clip runs on its own clock from its trigger: red from frame 0, blue from frame 2.
    let alone = |id: &str, frame: u64| {
        let scene = load_scene(&assets(), "kleinian_classic").unwrap();
        let mut scene = scene;
        let colours = if id == "red" {
            vec!["limit_set.hit_color=0.9,0.1,0.1,1"]
        } else {
            vec!["limit_set.hit_color=0.1,0.2,0.9,1", "limit_set.back_color=0.9,0.9,0.2,1"]
        };
        for c in colours {
            scene.set_from_str(c).unwrap();
        }
        common::render_scene(scene, size, frame).rgba
    };
    let (red, blue) = (alone("red", 32), alone("blue", 30));
    assert!(red != blue, "the two clips look alike: the test would prove nothing");
    let mut worst = 0.0f32;
    for i in (0..red.len()).filter(|i| i % 4 != 3) {
        let lin = |b: u8| srgb_to_linear(f32::from(b) / 255.0);
        let want = 0.5 * lin(red[i]) + 0.5 * lin(blue[i]);
        worst = worst.max((lin(middle.rgba[i]) - want).abs());
    }
    // 8-bit sRGB steps are up to ~0.01 in linear light near white.
    assert!(worst < 0.02, "the midpoint differs from the linear mix by up to {worst}");
}

#[test]
fn a_quantized_trigger_lands_on_the_beat_frame() {
    // 120 bpm at 60 steps a second: a beat every 30 frames, a bar every 120.
    for (quantize, lands) in [("Beat", 30), ("Bar", 120)] {
        let text =
            TWO_COLOURS.replace(r#"kind: "crossfade", seconds: 1.0"#, &format!(r#"kind: "cut", quantize: {quantize}"#));
        let mut r = renderer(show_from(&text), (16, 16));
        r.schedule(10, vec![trigger(0, 1)]);
        let mut switched = None;
        for frame in 0..130 {
            r.render_only().unwrap();
            let (_, state) = r.instance_mut().show().unwrap();
            if state.playing(0) == Some(1) {
                switched = Some(frame);
                break;
            }
        }
        assert_eq!(switched, Some(lands), "{quantize}: the clip came in at frame {switched:?}");
    }
}

/// A simulation (cloth, restarting) and a limit set on one layer, and a glow on a second layer
/// in Add: triggered back and forth with short crossfades.
const SIMULATION_SHOW: &str = r#"(
    name: "simulation",
    size: (48, 32),
    transition: (kind: "crossfade", seconds: 0.1),
    layers: [
        (clips: [(scene: "kleinian"), (scene: "cloth")]),
        (blend: "add", opacity: 0.5, clips: [(scene: "star_glow", policy: Continue)]),
    ],
)"#;

fn scripted(scene: Scene) -> OffscreenRenderer {
    let mut r = renderer(scene, (48, 32));
    r.schedule(3, vec![trigger(0, 1)]);
    r.schedule(12, vec![trigger(0, 0)]);
    // The cloth again: it restarts from its first frame (a fresh copy made while hidden).
    r.schedule(17, vec![trigger(0, 1)]);
    r.schedule(21, vec![ControlEvent::Show(ShowCommand::Trigger { layer: 1, clip: None })]);
    r
}

#[test]
fn frame_n_is_the_same_played_or_sought_across_transitions_and_restarts() {
    let scene = show_from(SIMULATION_SHOW);
    let mut played = scripted(scene.clone());
    let played: Vec<Vec<u8>> = (0..28).map(|_| played.render_next().unwrap().rgba).collect();
    for start in [5, 14, 19] {
        let mut sought = scripted(scene.clone());
        sought.seek(start).unwrap();
        for frame in start..28 {
            let got = sought.render_next().unwrap().rgba;
            assert!(got == played[frame as usize], "frame {frame} sought from {start} differs from played");
        }
    }
    assert!(played[8] != played[0], "the cloth never came in");
}

#[test]
fn a_restarted_clip_replays_its_first_frames() {
    // Cuts, so the layer shows the clip alone: frames after each trigger must match.
    let text = SIMULATION_SHOW
        .replace(r#"kind: "crossfade", seconds: 0.1"#, r#"kind: "cut""#)
        .replace(r#"(blend: "add", opacity: 0.5, clips: [(scene: "star_glow", policy: Continue)]),"#, "");
    let mut r = renderer(show_from(&text), (48, 32));
    r.schedule(2, vec![trigger(0, 1)]);
    r.schedule(9, vec![trigger(0, 0)]);
    r.schedule(14, vec![trigger(0, 1)]);
    let frames: Vec<Vec<u8>> = (0..20).map(|_| r.render_next().unwrap().rgba).collect();
    for k in 0..5 {
        assert!(frames[2 + k] == frames[14 + k], "frame {k} of the cloth differs between its first and second start");
    }
    assert!(frames[2] != frames[6], "the cloth does not move: the comparison proves nothing");
}

#[test]
fn every_bundled_show_renders_frame_n_the_same_played_or_sought() {
    let assets = assets();
    let names = assets.names(AssetKind::Show);
    assert!(names.iter().any(|n| n == "book.ron") && names.iter().any(|n| n == "set.ron"), "{names:?}");
    for name in names {
        let started = std::time::Instant::now();
        let scene = load_scene(&assets, &format!("shows/{name}")).unwrap_or_else(|e| panic!("{e}"));
        let mut played = renderer(scene.clone(), (40, 24));
        let played: Vec<Vec<u8>> = (0..8).map(|_| played.render_next().unwrap().rgba).collect();
        let mut sought = renderer(scene, (40, 24));
        sought.seek(4).unwrap();
        for (frame, want) in played.iter().enumerate().skip(4) {
            assert!(&sought.render_next().unwrap().rgba == want, "{name}: frame {frame} sought differs");
        }
        eprintln!("{name}: {:.1} s", started.elapsed().as_secs_f64());
    }
}

#[test]
fn the_book_show_walks_its_cues_and_crossfades() {
    let scene = load_scene(&assets(), "shows/book").unwrap();
    let show = Arc::clone(scene.show.as_ref().unwrap());
    assert_eq!(show.clips.len(), show.cues.len(), "one cue per demo");
    let mut r = renderer(scene, (16, 16));
    // Cue 2 goes at 20 s (frame 1200) and crossfades over 2 s.
    r.seek(1230).unwrap();
    r.render_only().unwrap();
    let (_, state) = r.instance_mut().show().unwrap();
    assert_eq!(state.cue(), Some(1));
    let view = state.view(0);
    assert!((view.progress - 0.25).abs() < 0.01 && view.from == Some(0) && view.to == Some(1), "{view:?}");
}

#[test]
fn a_broken_clip_is_left_out_and_the_rest_plays() {
    let text =
        TWO_COLOURS.replace(r#"(scene: "kleinian_classic", id: "blue""#, r#"(scene: "no_such_scene", id: "blue""#);
    // `check` and renders refuse it, located at the clip.
    let e = parse_show(&assets(), "test-show.ron", &text, false).expect_err("a missing scene is an error").to_string();
    assert!(e.contains("test-show.ron:8:") && e.contains("clip 'blue'") && e.contains("no_such_scene"), "{e}");
    // A running show leaves it out, says so, and plays the rest.
    let scene = parse_show(&assets(), "test-show.ron", &text, true).unwrap();
    let mut r = renderer(scene, (32, 18));
    let messages = r.instance_mut().take_messages();
    assert!(messages.iter().any(|m| m.contains("clip 'blue' is left out")), "{messages:?}");
    let before = r.render_next().unwrap().rgba;
    r.schedule(1, vec![trigger(0, 1)]);
    r.schedule(3, vec![trigger(0, 0)]);
    for _ in 1..80 {
        r.render_next().unwrap();
    }
    let after = r.render_next().unwrap().rgba;
    assert!(before == after, "the good clip plays again after the broken one was triggered");
    assert!(before.chunks(4).any(|p| p[0] > 100), "the good clip is not on screen");
}

/// A layer of `n` clips, each of its own id, as a show file writes them.
fn crowded_layer(n: usize) -> String {
    (0..n).map(|i| format!(r#"(scene: "kleinian_classic", id: "c{i}")"#)).collect::<Vec<_>>().join(", ")
}

#[test]
fn a_show_refuses_what_it_cannot_play_with_located_errors() {
    let cases = [
        (TWO_COLOURS.replace("crossfade", "no_such_transition"), "transition 'no_such_transition'"),
        (TWO_COLOURS.replace(r#"id: "blue""#, r#"id: "red""#), "clip id 'red' is used twice"),
        (TWO_COLOURS.replace(r#"id: "blue""#, r#"id: "layer""#), "reserved"),
        (TWO_COLOURS.replace("layers: [(clips", r#"cues: [(clips: [(2, 1)])], layers: [(clips"#), "layer 2"),
        (TWO_COLOURS.replace("layers: [(clips", r#"layers: [(blend: "overlay", clips"#), "blend 'overlay'"),
        // A layer past the clip cap after a good one: it was skipped, and the blend nodes were
        // then indexed by the file's layer number (a panic that took a reloading show down).
        (TWO_COLOURS.replace("    ])],", &format!("    ]), (clips: [{}])],", crowded_layer(65))), "65 clips"),
    ];
    for (text, expected) in cases {
        let e = parse_show(&assets(), "bad.ron", &text, false).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains(expected) && e.contains("bad.ron:"), "expected '{expected}', got: {e}");
    }
}

#[test]
fn golden_transition_midpoint_and_two_layer_blend() {
    // A luma dissolve halfway from the limit set to the tessellated relief.
    let text = r#"(
        name: "golden transition",
        size: (160, 90),
        transition: (kind: "luma", seconds: 1.0),
        layers: [(clips: [(scene: "kleinian_classic"), (scene: "tessellation_kleinian")])],
    )"#;
    let mut r = renderer(show_from(text), (160, 90));
    r.schedule(1, vec![trigger(0, 1)]);
    r.seek(31).unwrap();
    let frame = r.render_next().unwrap();
    golden(0.01, 0.3).check("show_luma_midpoint", frame.size, &frame.rgba).unwrap_or_else(|e| panic!("{e}"));
    // The limit set under spinning glints in Add at 0.8.
    let text = r#"(
        name: "golden layers",
        size: (160, 90),
        layers: [
            (clips: [(scene: "kleinian_classic")]),
            (blend: "add", opacity: 0.8, clips: [(scene: "star_glow")]),
        ],
    )"#;
    let mut r = renderer(show_from(text), (160, 90));
    r.seek(20).unwrap();
    let frame = r.render_next().unwrap();
    golden(0.01, 0.3).check("show_two_layers_add", frame.size, &frame.rgba).unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn an_osc_trigger_changes_the_playing_clip_and_the_oscquery_tree() {
    use crate::live_show::{Show, VirtualDisplay, scratch_dir, send};
    let display = VirtualDisplay::start();
    let dir = scratch_dir("show-osc");
    let file = dir.join("two.ron");
    std::fs::write(&file, TWO_COLOURS.replace(r#"kind: "crossfade", seconds: 1.0"#, r#"kind: "cut""#)).unwrap();
    let query = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap();
    let query_arg = std::ffi::OsString::from(query.to_string());
    let args = [std::ffi::OsStr::new("--oscquery"), query_arg.as_os_str()];
    let (mut show, port) = Show::start(&display, &dir, file.to_str().unwrap(), &args);
    show.wait_for("OSCQuery on");
    show.wait_for("plays clip 'red'");
    let has = |tree: &serde_json::Value, clip: &str| !tree["CONTENTS"]["indra"]["CONTENTS"][clip].is_null();
    // The tree is published with the first frames; wait until it is there.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    let tree = loop {
        let (status, tree) = crate::osc::http_get(query, "/");
        if status == 200 && has(&tree, "red") {
            break tree;
        }
        assert!(std::time::Instant::now() < deadline, "no tree with the playing clip: {status} {tree}");
        std::thread::sleep(std::time::Duration::from_millis(200));
    };
    assert!(!has(&tree, "blue"), "a hidden clip is in the tree");
    assert!(!tree["CONTENTS"]["indra"]["CONTENTS"]["layer"]["CONTENTS"]["1"]["CONTENTS"]["clip"].is_null());
    let (mut socket, _) = tungstenite::connect(format!("ws://{query}/")).unwrap();
    let osc = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    send(&osc, port, "/indra/layer/1/clip/2/connect", vec![rosc::OscType::Int(1)]);
    show.wait_for("plays clip 'blue'");
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(30);
    loop {
        assert!(std::time::Instant::now() < deadline, "no PATH_CHANGED after the clip change");
        let Some(tungstenite::Message::Text(text)) =
            crate::osc::next_message(&mut socket, std::time::Duration::from_secs(5))
        else {
            continue;
        };
        let said: serde_json::Value = serde_json::from_str(&text).unwrap_or_default();
        if said["COMMAND"] == "PATH_CHANGED" {
            break;
        }
    }
    let (_, tree) = crate::osc::http_get(query, "/");
    assert!(has(&tree, "blue") && !has(&tree, "red"), "the tree does not follow the clip change: {tree}");
    // A number past the show's clips is an unknown address, never a panic.
    send(&osc, port, "/indra/layer/1/clip/9/connect", vec![]);
    send(&osc, port, "/indra/layer/4/opacity", vec![rosc::OscType::Float(0.5)]);
    send(&osc, port, "/indra/layer/1/clip/1/connect", vec![]);
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(30);
    loop {
        let log = show.wait_for("plays clip 'blue'");
        if log.matches("plays clip 'red'").count() >= 2 {
            assert!(!log.contains("panicked"), "{log}");
            break;
        }
        assert!(std::time::Instant::now() < deadline, "the show did not go back to red:\n{log}");
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
}

#[test]
fn a_show_reloads_when_a_clip_changes_and_keeps_playing_through_a_broken_edit() {
    use crate::live::{edit, wait_for_reload};
    let root = common::sandbox("show-reload");
    std::fs::create_dir_all(root.join("shows")).unwrap();
    let show_file = root.join("shows/live.ron");
    std::fs::write(&show_file, TWO_COLOURS).unwrap();
    let assets = indra::assets::Assets::new(Some(root.clone()));
    let scene = load_scene(&assets, "shows/live").unwrap();
    let mut live = indra::live::LiveReload::new(&assets).unwrap();
    let mut r = OffscreenRenderer::new(gpu(), &assets, scene, Some((48, 27)), None, None).unwrap();
    let before = r.render_next().unwrap().rgba;
    // An edit of a clip's scene reloads the show.
    edit(&root.join("scenes/kleinian_classic.ron"), r#""scale": 2.4"#, r#""scale": 1.2"#);
    let report = wait_for_reload(&mut r, &mut live);
    assert!(report.errors.is_empty() && !report.applied.is_empty(), "{report:?}");
    let zoomed = r.render_next().unwrap().rgba;
    assert!(zoomed != before, "the clip's edit did not reach the show");
    // A broken clip keeps the last good show playing, with the error located at the clip.
    edit(&root.join("scenes/kleinian_classic.ron"), r#""scale": 1.2,"#, r#""scale": 1.2,,"#);
    let report = wait_for_reload(&mut r, &mut live);
    assert!(report.errors.iter().any(|e| e.contains("clip 'red'")), "{report:?}");
    assert!(r.render_next().unwrap().rgba == zoomed, "a broken clip changed the picture");
    // The show file's own edit applies.
    edit(&root.join("scenes/kleinian_classic.ron"), r#""scale": 1.2,,"#, r#""scale": 1.2,"#);
    let fixed = |r: &mut OffscreenRenderer, live: &mut indra::live::LiveReload| {
        // The watcher may report an earlier save again first: wait for the one that applies.
        let mut reports = Vec::new();
        for _ in 0..4 {
            let report = wait_for_reload(r, live);
            if report.errors.is_empty() && !report.applied.is_empty() {
                return;
            }
            reports.push(report);
        }
        panic!("the fixed show was not applied: {reports:?}");
    };
    fixed(&mut r, &mut live);
    edit(&show_file, "seed: 1,", "seed: 1, master: 0.0,");
    fixed(&mut r, &mut live);
    let black = r.render_next().unwrap().rgba;
    assert!(black.chunks(4).all(|p| p[..3] == [0, 0, 0]), "the master fader at 0 is not black");
}

#[test]
fn show_commands_survive_a_recording_and_midi_notes_trigger_clips() {
    let scene = show_from(&TWO_COLOURS.replace(r#"id: "blue","#, r#"id: "blue", note: 40, channel: 2,"#));
    // A note-on on the clip's channel triggers it; another channel or note does not.
    let dir = crate::live_show::scratch_dir("show-record");
    let triggered = |bytes: &[u8]| crate::control::hub(&dir, &scene).midi_bytes(bytes, &scene, 0.0);
    assert_eq!(triggered(&[0x91, 40, 100]), [ControlEvent::Show(ShowCommand::Trigger { layer: 0, clip: Some(1) })]);
    assert!(triggered(&[0x90, 40, 100]).is_empty() && triggered(&[0x91, 41, 100]).is_empty());
    // The show's GO note, on any channel, when it has cues.
    let cued = show_from(
        &TWO_COLOURS
            .replace("layers:", "go_note: 60, back_note: 59, cues: [(clips: [(1, 1)]), (clips: [(1, 2)])], layers:"),
    );
    let mut hub = crate::control::hub(&dir, &cued);
    assert_eq!(hub.midi_bytes(&[0x95, 60, 1], &cued, 0.0), [ControlEvent::Show(ShowCommand::CueGo)]);
    assert_eq!(hub.midi_bytes(&[0x90, 59, 1], &cued, 0.0), [ControlEvent::Show(ShowCommand::CueBack)]);
    // MIDI learn of a clip: the next note binds (and does not trigger), then triggers it, and
    // the binding is saved for the next run.
    let mut hub = crate::control::hub(&dir, &scene);
    hub.learn_clip(0, 0);
    assert!(hub.midi_bytes(&[0x93, 50, 90], &scene, 0.0).is_empty(), "the learned note fired at once");
    assert_eq!(hub.midi_bytes(&[0x93, 50, 90], &scene, 0.0), [trigger(0, 0)]);
    let saved = std::fs::read_to_string(dir.join("midi-learn.ron")).unwrap();
    assert!(saved.contains("layer/1/clip/1"), "{saved}");
    assert_eq!(crate::control::hub(&dir, &scene).midi_bytes(&[0x93, 50, 90], &scene, 0.0), [trigger(0, 0)]);
    // Recorded and read back, a show command is the same command at the same frame.
    let path = dir.join("take.ron");
    let mut recorder = indra::control::record::Recorder::create(&path).unwrap();
    let events =
        [trigger(0, 1), ControlEvent::Show(ShowCommand::CueGoto(0)), ControlEvent::Show(ShowCommand::Column(1))];
    recorder.record(12, &events, &scene).unwrap();
    recorder.finish().unwrap();
    let replay = indra::control::record::read_replay(&path, &scene, &assets()).unwrap();
    assert_eq!(replay.get(&12).map(Vec::as_slice), Some(&events[..]));
}
