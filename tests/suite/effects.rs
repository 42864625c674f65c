//! Effect chains on a show's clips, layers and master: a layer's effect against the same ISF
//! filter as a node of a scene; bypass and a dry mix byte for byte the image without the effect;
//! dry/wet at one half the linear mix; two effects that do not commute, in both orders; the
//! chain's parameters at their addresses and written live; seek = play; a golden of a two-effect
//! chain; located errors for effects a show cannot play.

use crate::common::{self, assets, golden, gpu};
use indra::control::address::{AddressMap, Route};
use indra::offscreen::OffscreenRenderer;
use indra::params::{ControlEvent, EffectEdit, ParamValue, ParamWrite, ShowCommand, Source, Text};
use indra::scene::show::parse_show;
use indra::scene::{Scene, parse_scene_with};
use indra::techniques::srgb_to_linear;

const SIZE: (u32, u32) = (64, 36);

fn show_from(text: &str) -> Scene {
    parse_show(&assets(), "effects-show.ron", text, false).unwrap_or_else(|e| panic!("{e}"))
}

/// A one-layer show of the classic limit set with `chains` spliced in: the clip's, the layer's
/// and the master's effect lists (RON, empty for none).
fn limit_set_show(clip: &str, layer: &str, master: &str) -> String {
    format!(
        r#"(
    name: "effects",
    size: (64, 36),
    seed: 1,
    layers: [(clips: [(scene: "kleinian_classic", effects: [{clip}])], effects: [{layer}])],
    effects: [{master}],
)"#
    )
}

fn frame_of(text: &str, frame: u64) -> Vec<u8> {
    common::render_scene(show_from(text), SIZE, frame).rgba
}

const KALEIDOSCOPE: &str = r#"(effect: "shaders/isf/Kaleidoscope.fs", params: { "sides": 5.0, "angle": 0.3 })"#;
const DIAGONALIZE: &str = r#"(effect: "shaders/isf/Diagonalize.fs", params: { "width": 0.2 })"#;

fn max_difference(a: &[u8], b: &[u8]) -> u8 {
    a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max().unwrap_or(0)
}

#[test]
fn a_layer_effect_is_the_filter_applied_to_the_layer_alone() {
    let show = frame_of(&limit_set_show("", KALEIDOSCOPE, ""), 0);
    // The same filter as a node of a scene, over the same limit set.
    let scene = r#"(
        name: "alone", size: (64, 36), seed: 1,
        nodes: [
            (id: "limit_set", technique: "kleinian",
             params: { "t": (2.0, 0.0), "iterations": 200, "scale": 2.4, "offset": (-2.0, -0.2), "samples": 4 }),
            (id: "fx", technique: "isf",
             params: { "file": "shaders/isf/Kaleidoscope.fs", "sides": 5.0, "angle": 0.3 },
             inputs: { "inputImage": "limit_set" }),
        ],
        output: "fx",
    )"#;
    let alone = common::render_scene(parse_scene_with(&assets(), "alone.ron", scene).unwrap(), SIZE, 0).rgba;
    let plain = frame_of(&limit_set_show("", "", ""), 0);
    assert!(max_difference(&alone, &plain) > 32, "the filter changes nothing: the test would prove nothing");
    assert_eq!(max_difference(&show, &alone), 0, "the layer's effect differs from the filter as a node");
    // On one opaque layer, the clip's chain and the master's give the same picture.
    assert!(frame_of(&limit_set_show(KALEIDOSCOPE, "", ""), 0) == show, "the clip's chain differs");
    assert!(frame_of(&limit_set_show("", "", KALEIDOSCOPE), 0) == show, "the master's chain differs");
}

#[test]
fn a_bypassed_or_dry_effect_gives_the_image_without_it_byte_for_byte() {
    let plain = frame_of(&limit_set_show("", "", ""), 0);
    let bypassed = KALEIDOSCOPE.replace("(effect:", "(bypass: true, effect:");
    let dry = KALEIDOSCOPE.replace("(effect:", "(mix: 0.0, effect:");
    for chain in [&bypassed, &dry] {
        assert!(frame_of(&limit_set_show(chain, chain, chain), 0) == plain, "{chain} changed the image");
    }
}

#[test]
fn dry_wet_at_one_half_is_the_linear_mix_of_dry_and_wet() {
    let dry = frame_of(&limit_set_show("", "", ""), 0);
    let wet = frame_of(&limit_set_show("", KALEIDOSCOPE, ""), 0);
    let half = frame_of(&limit_set_show("", &KALEIDOSCOPE.replace("(effect:", "(mix: 0.5, effect:"), ""), 0);
    let lin = |b: u8| srgb_to_linear(f32::from(b) / 255.0);
    let mut worst = 0.0f32;
    for i in (0..dry.len()).filter(|i| i % 4 != 3) {
        worst = worst.max((lin(half[i]) - 0.5 * (lin(dry[i]) + lin(wet[i]))).abs());
    }
    // 8-bit sRGB steps are up to ~0.01 in linear light near white.
    assert!(worst < 0.02, "the half mix differs from the linear mix by up to {worst}");
}

#[test]
fn two_effects_that_do_not_commute_give_two_images_in_their_two_orders() {
    let forward = frame_of(&limit_set_show("", &format!("{KALEIDOSCOPE}, {DIAGONALIZE}"), ""), 0);
    let backward = frame_of(&limit_set_show("", &format!("{DIAGONALIZE}, {KALEIDOSCOPE}"), ""), 0);
    assert!(max_difference(&forward, &backward) > 32, "the order of the chain does not matter");
    let again = frame_of(&limit_set_show("", &format!("{KALEIDOSCOPE}, {DIAGONALIZE}"), ""), 0);
    assert!(again == forward, "the same chain gave another image");
}

/// A write from a live source to parameter `name` of node `node`.
fn write(scene: &Scene, node: &str, name: &str, value: ParamValue) -> ControlEvent {
    let n = scene.node_index(node).unwrap_or_else(|| panic!("no node {node}"));
    let param = scene.nodes[n].params.index(name).unwrap_or_else(|| panic!("{node} has no {name}"));
    ControlEvent::Write(ParamWrite { node: n, param, component: None, value, source: Source::Osc })
}

#[test]
fn the_chains_parameters_have_addresses_and_take_live_writes() {
    let text = limit_set_show(DIAGONALIZE, KALEIDOSCOPE, DIAGONALIZE);
    let scene = show_from(&text);
    let map = AddressMap::new(&scene);
    for address in [
        "/indra/layer/1/fx/1/sides",
        "/indra/layer/1/fx/1/bypass",
        "/indra/layer/1/fx/1/mix",
        "/indra/master/fx/1/width",
        "/indra/kleinian_classic/fx/1/mix",
    ] {
        assert!(matches!(map.route(address), Some(Route::Param(_))), "no parameter at {address}");
    }
    // Bypassing every effect live, then the layer's mix to 0.5: the same frames as the file's.
    let mut r = OffscreenRenderer::new(gpu(), &assets(), scene.clone(), Some(SIZE), None, None).unwrap();
    let off = ParamValue::Bool(true);
    let writes =
        ["kleinian_classic/fx/1", "layer/1/fx/1", "master/fx/1"].map(|node| write(&scene, node, "bypass", off));
    r.schedule(2, writes.to_vec());
    r.schedule(4, vec![write(&scene, "layer/1/fx/1", "bypass", ParamValue::Bool(false))]);
    let frames: Vec<Vec<u8>> = (0..5).map(|_| r.render_next().unwrap().rgba).collect();
    assert!(frames[0] != frames[2], "bypassing changed nothing");
    assert!(frames[2] == frame_of(&limit_set_show("", "", ""), 2), "bypassed live is not the plain image");
    assert!(frames[4] == frame_of(&limit_set_show("", KALEIDOSCOPE, ""), 4), "the layer's effect did not come back");
}

#[test]
fn a_show_with_effects_renders_frame_n_the_same_played_or_sought() {
    // A moving effect (the pulse runs on the clock) on a clip that restarts, over a layer change.
    let pulse = r#"(effect: "shaders/isf/Shockwave Pulse.fs", mix: 0.7)"#;
    let text = format!(
        r#"(
    name: "moving effects", size: (48, 32), seed: 3,
    transition: (kind: "crossfade", seconds: 0.1),
    layers: [(clips: [(scene: "kleinian_classic", effects: [{pulse}]), (scene: "star_glow", effects: [{DIAGONALIZE}])],
              effects: [{KALEIDOSCOPE}])],
    effects: [(effect: "star_glow", mix: 0.5)],
)"#
    );
    let scene = show_from(&text);
    let scripted = || {
        let mut r = OffscreenRenderer::new(gpu(), &assets(), scene.clone(), Some((48, 32)), None, None).unwrap();
        r.schedule(3, vec![ControlEvent::Show(ShowCommand::Trigger { layer: 0, clip: Some(1) })]);
        r.schedule(9, vec![ControlEvent::Show(ShowCommand::Trigger { layer: 0, clip: Some(0) })]);
        r.schedule(11, vec![write(&scene, "layer/1/fx/1", "mix", ParamValue::Float(0.25))]);
        r
    };
    let mut played = scripted();
    let played: Vec<Vec<u8>> = (0..16).map(|_| played.render_next().unwrap().rgba).collect();
    assert!(played[1] != played[2], "nothing moves: the comparison proves nothing");
    for start in [5, 10, 12] {
        let mut sought = scripted();
        sought.seek(start).unwrap();
        for frame in start..16 {
            assert!(sought.render_next().unwrap().rgba == played[frame as usize], "frame {frame} from {start} differs");
        }
    }
}

#[test]
fn golden_a_two_effect_chain() {
    // The limit set through a kaleidoscope, then diagonal stripes mixed in at 0.6.
    let chain = format!("{KALEIDOSCOPE}, {}", DIAGONALIZE.replace("(effect:", "(mix: 0.6, effect:"));
    let text = limit_set_show("", &chain, "").replace("(64, 36)", "(160, 90)");
    let frame = common::render_scene(show_from(&text), (160, 90), 0);
    golden(0.01, 0.3).check("show_two_effect_chain", frame.size, &frame.rgba).unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn effects_a_show_cannot_play_are_located_errors() {
    let cases = [
        (r#"(effect: "shaders/isf/Mosaic.fs")"#, "takes 2 images"),
        (r#"(effect: "kleinian")"#, "takes 0 images"),
        (r#"(effect: "no_such_thing")"#, "not an ISF filter (.fs), a WGSL effect"),
        (r#"(effect: "kleinian.wgsl")"#, "starts with `// extends: effect.wgsl`"),
        (r#"(effect: "shaders/isf/Nope.fs")"#, "Nope.fs"),
        (r#"(effect: "star_glow", mix: 1.5)"#, "mix 1.5 must be 0–1"),
        (r#"(effect: "star_glow", params: { "glare": 1.0 })"#, "glare"),
    ];
    for (effect, expected) in cases {
        let text = limit_set_show("", effect, "");
        let e = parse_show(&assets(), "bad.ron", &text, false).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains(expected) && e.contains("bad.ron:5:"), "{effect}: expected '{expected}', got: {e}");
    }
    let many = vec![DIAGONALIZE; 17].join(", ");
    let e = parse_show(&assets(), "bad.ron", &limit_set_show("", "", &many), false).err().unwrap().to_string();
    assert!(e.contains("a chain has at most 16"), "{e}");
}

#[test]
fn every_bundled_isf_filter_and_image_technique_is_an_effect() {
    let assets = assets();
    let mut filters = 0;
    for file in indra::techniques::isf::shader_names(&assets) {
        let effect = format!(r#"(effect: "{file}")"#);
        match parse_show(&assets, "all.ron", &limit_set_show("", &effect, ""), false) {
            Ok(_) => filters += 1,
            // Generators and transitions are not filters; nothing else may be refused.
            Err(e) => assert!(e.to_string().contains("images"), "{file}: {e}"),
        }
    }
    assert_eq!(filters, 43, "bundled ISF filters accepted as effects");
    let library = indra::scene::show::effects::library::read_library(&assets);
    assert_eq!(library.iter().filter(|n| n.ends_with(".fs")).count(), 43, "{library:?}");
    for wgsl in ["effect_mirror.wgsl", "effect_grade.wgsl"] {
        assert!(library.iter().any(|n| n == wgsl), "{wgsl} is not in the library");
        parse_show(&assets, "all.ron", &limit_set_show("", &format!(r#"(effect: "{wgsl}")"#), ""), false)
            .unwrap_or_else(|e| panic!("{wgsl}: {e}"));
    }
    for technique in ["star_glow", "warp", "tessellation", "fader"] {
        let effect = format!(r#"(effect: "{technique}")"#);
        parse_show(&assets, "all.ron", &limit_set_show("", &effect, ""), false)
            .unwrap_or_else(|e| panic!("{technique}: {e}"));
    }
}

/// A chain edit of layer 1's chain (`None`: the master's).
fn edit(layer: Option<usize>, edit: EffectEdit) -> ControlEvent {
    ControlEvent::Show(ShowCommand::Effect { layer, edit })
}

const PLAIN_DIAGONALIZE: &str = r#"(effect: "shaders/isf/Diagonalize.fs")"#;

#[test]
fn effects_added_moved_and_removed_live_give_the_chain_the_file_would() {
    let scene = show_from(&limit_set_show("", KALEIDOSCOPE, ""));
    let mut r = OffscreenRenderer::new(gpu(), &assets(), scene, Some(SIZE), None, None).unwrap();
    let diagonalize = Text::new("shaders/isf/Diagonalize.fs");
    r.schedule(2, vec![edit(Some(0), EffectEdit::Add(diagonalize))]);
    r.schedule(4, vec![edit(Some(0), EffectEdit::Move { from: 1, to: 0 })]);
    r.schedule(5, vec![edit(Some(0), EffectEdit::Move { from: 0, to: 1 })]);
    r.schedule(6, vec![edit(Some(0), EffectEdit::Remove(1)), edit(None, EffectEdit::Add(diagonalize))]);
    // Refused, told, and the show plays on: no effect 9, no such file.
    r.schedule(7, vec![edit(Some(0), EffectEdit::Remove(8)), edit(Some(0), EffectEdit::Add(Text::new("nope.fs")))]);
    let frames: Vec<Vec<u8>> = (0..8).map(|_| r.render_next().unwrap().rgba).collect();
    let want = |layer: String, master: &str, frame| frame_of(&limit_set_show("", &layer, master), frame);
    assert!(frames[1] == want(KALEIDOSCOPE.into(), "", 1), "before the edits");
    assert!(frames[2] == want(format!("{KALEIDOSCOPE}, {PLAIN_DIAGONALIZE}"), "", 2), "after the add");
    assert!(frames[4] == want(format!("{PLAIN_DIAGONALIZE}, {KALEIDOSCOPE}"), "", 4), "after the move");
    assert!(frames[4] != frames[3], "the move changed nothing");
    assert!(frames[5] == frames[3], "moving the effect back did not restore the picture");
    assert!(frames[6] == want(KALEIDOSCOPE.into(), PLAIN_DIAGONALIZE, 6), "after the remove and the master's add");
    assert!(frames[7] == frames[6], "a refused edit changed the picture");
    let messages = r.instance_mut().take_messages().join("\n");
    assert!(messages.contains("no effect 9") && messages.contains("nope.fs"), "{messages}");
    let scene = r.instance_mut().scene().clone();
    assert!(AddressMap::new(&scene).route("/indra/master/fx/1/width").is_some(), "the tree lacks the new effect");
}

#[test]
fn the_first_effect_added_to_a_show_mixes_dry_and_wet_as_the_file_would() {
    // A show without effects has no dry/wet mix: the first edit's build must compile it.
    let plain = show_from(&limit_set_show("", "", ""));
    let mut r = OffscreenRenderer::new(gpu(), &assets(), plain, Some(SIZE), None, None).unwrap();
    r.schedule(1, vec![edit(Some(0), EffectEdit::Add(Text::new("shaders/isf/Kaleidoscope.fs")))]);
    let edited = show_from(&limit_set_show("", r#"(effect: "shaders/isf/Kaleidoscope.fs")"#, ""));
    r.schedule(2, vec![write(&edited, "layer/1/fx/1", "mix", ParamValue::Float(0.5))]);
    let frames: Vec<Vec<u8>> = (0..4).map(|_| r.render_next().unwrap().rgba).collect();
    let half = r#"(effect: "shaders/isf/Kaleidoscope.fs", mix: 0.5)"#;
    assert!(frames[3] == frame_of(&limit_set_show("", half, ""), 3), "the live half mix differs from the file's");
}

#[test]
fn an_edit_leaves_a_waiting_trigger_and_a_running_fade_where_they_were() {
    // A beat every 9 frames: the trigger at frame 1 waits for frame 9, then fades over 9.
    let text = r#"(
    name: "fading",
    size: (64, 36),
    seed: 1,
    bpm: 400.0,
    transition: (kind: "crossfade", beats: 1.0, quantize: Beat),
    layers: [(clips: [(scene: "kleinian_classic"), (scene: "kleinian")])],
)"#;
    let play = |edits: &[(u64, EffectEdit)]| {
        let mut r = OffscreenRenderer::new(gpu(), &assets(), show_from(text), Some(SIZE), None, None).unwrap();
        r.schedule(1, vec![ControlEvent::Show(ShowCommand::Trigger { layer: 0, clip: Some(1) })]);
        for &(frame, e) in edits {
            r.schedule(frame, vec![edit(Some(0), e)]);
        }
        (0..20).map(|_| r.render_next().unwrap().rgba).collect::<Vec<_>>()
    };
    let plain = play(&[]);
    let add = EffectEdit::Add(Text::new("shaders/isf/Kaleidoscope.fs"));
    // Added and removed while the trigger waits, and again halfway through the fade.
    let edited = play(&[(3, add), (4, EffectEdit::Remove(0)), (12, add), (13, EffectEdit::Remove(0))]);
    assert!(plain[12] != plain[8] && plain[12] != plain[19], "frame 12 is not inside the fade");
    assert!(edited[3] != plain[3] && edited[12] != plain[12], "the added effect did not show");
    for frame in (4..12).chain(13..20) {
        assert!(edited[frame] == plain[frame], "frame {frame}: the edit moved the trigger or the fade");
    }
}

#[test]
fn frame_n_is_the_same_played_or_sought_across_adds_moves_and_bypasses() {
    let pulse = Text::new("shaders/isf/Shockwave Pulse.fs");
    let scene = show_from(&limit_set_show("", KALEIDOSCOPE, ""));
    let scripted = || {
        let mut r = OffscreenRenderer::new(gpu(), &assets(), scene.clone(), Some(SIZE), None, None).unwrap();
        r.schedule(3, vec![edit(Some(0), EffectEdit::Add(pulse))]);
        r.schedule(6, vec![edit(Some(0), EffectEdit::Move { from: 1, to: 0 })]);
        // After the move the pulse is effect 1: its bypass, by the positions of the edited show.
        let edited = show_from(&limit_set_show("", &format!(r#"(effect: "{}"), {KALEIDOSCOPE}"#, pulse.as_str()), ""));
        r.schedule(9, vec![write(&edited, "layer/1/fx/1", "bypass", ParamValue::Bool(true))]);
        r
    };
    let mut played = scripted();
    let played: Vec<Vec<u8>> = (0..12).map(|_| played.render_next().unwrap().rgba).collect();
    assert!(played[3] != played[2] && played[6] != played[5] && played[9] != played[8], "an edit changed nothing");
    for start in [4, 7, 10] {
        let mut sought = scripted();
        sought.seek(start).unwrap();
        for frame in start..12 {
            assert!(sought.render_next().unwrap().rgba == played[frame as usize], "frame {frame} from {start} differs");
        }
    }
}

/// Ends a running show with Ctrl-C (cleanly, its recording complete), then replays the take
/// `recording` over the show `text` in a render: the frame after the take's last event, and its
/// number.
fn end_and_replay(show: &mut crate::live_show::Show, recording: &std::path::Path, text: &str) -> (Vec<u8>, u64) {
    show.interrupt();
    let scene = show_from(text);
    let script = indra::control::record::read_replay(recording, &scene, &assets()).unwrap();
    let last = *script.keys().last().expect("the take holds the edits");
    let mut r = OffscreenRenderer::new(gpu(), &assets(), scene, Some(SIZE), None, None).unwrap();
    for (frame, events) in script {
        r.schedule(frame, events);
    }
    r.seek(last + 1).unwrap();
    (r.render_next().unwrap().rgba, last)
}

#[test]
fn effects_edited_over_osc_in_a_running_show_change_the_tree_and_replay_to_the_same_picture() {
    use crate::live_show::{VirtualDisplay, send};
    use rosc::OscType;
    let display = VirtualDisplay::start();
    let (mut show, port, _, query, recording) =
        crate::live_show::start_recorded(&display, "effects-osc", &limit_set_show("", "", ""));
    let (mut socket, _) = tungstenite::connect(format!("ws://{query}/")).unwrap();
    let osc = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let text = |s: &str| vec![OscType::String(s.into())];
    send(&osc, port, "/indra/layer/1/fx/add", text("shaders/isf/Kaleidoscope.fs"));
    show.wait_for("layer/1's effect chain: Add");
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(30);
    while !crate::osc::next_message(&mut socket, std::time::Duration::from_secs(5))
        .is_some_and(|m| matches!(m, tungstenite::Message::Text(t) if t.contains("PATH_CHANGED")))
    {
        assert!(std::time::Instant::now() < deadline, "no PATH_CHANGED after the effect was added");
    }
    let (_, tree) = crate::osc::http_get(query, "/");
    let fx = &tree["CONTENTS"]["indra"]["CONTENTS"]["layer"]["CONTENTS"]["1"]["CONTENTS"]["fx"]["CONTENTS"];
    assert!(!fx["1"]["CONTENTS"]["sides"].is_null() && !fx["remove"].is_null(), "the tree lacks the effect: {fx}");
    // Its value, a second effect, a move, a bypass and a remove on the master's empty chain
    // (refused: there is nothing to remove), each over OSC.
    send(&osc, port, "/indra/layer/1/fx/1/sides", vec![OscType::Float(5.0)]);
    send(&osc, port, "/indra/layer/1/fx/add", text("shaders/isf/Diagonalize.fs"));
    show.wait_for("Add(\"shaders/isf/Diagonalize.fs\")");
    send(&osc, port, "/indra/layer/1/fx/move", vec![OscType::Int(2), OscType::Int(1)]);
    show.wait_for("Move");
    send(&osc, port, "/indra/layer/1/fx/bypass", vec![OscType::Int(2), OscType::Int(1)]);
    send(&osc, port, "/indra/master/fx/remove", vec![OscType::Int(1)]);
    show.wait_for("no effect 1 to remove");
    std::thread::sleep(std::time::Duration::from_millis(500));
    // The take replays in a render to the chain the performer built: Diagonalize, then the
    // kaleidoscope with 5 sides, bypassed.
    let (replayed, last) = end_and_replay(&mut show, &recording, &limit_set_show("", "", ""));
    let chain = format!(
        r#"{PLAIN_DIAGONALIZE}, (effect: "shaders/isf/Kaleidoscope.fs", params: {{ "sides": 5.0 }}, bypass: true)"#
    );
    assert!(replayed == frame_of(&limit_set_show("", &chain, ""), last + 1), "the replay differs from the chain built");
    let bypass_off = chain.replace("bypass: true", "bypass: false");
    assert!(replayed != frame_of(&limit_set_show("", &bypass_off, ""), last + 1), "the bypass was not replayed");
}

#[test]
fn a_wgsl_effect_mirrors_the_left_half_by_its_amount() {
    let plain = frame_of(&limit_set_show("", "", ""), 0);
    let mirror = |amount: f32| {
        let effect = format!(r#"(effect: "effect_mirror.wgsl", params: {{ "amount": {amount:?} }})"#);
        frame_of(&limit_set_show("", &effect, ""), 0)
    };
    assert!(mirror(0.0) == plain, "amount 0 changed the image");
    let full = mirror(1.0);
    let (w, h) = (SIZE.0 as usize, SIZE.1 as usize);
    let at = |img: &[u8], x: usize, y: usize| img[(y * w + x) * 4..(y * w + x) * 4 + 3].to_vec();
    for y in 0..h {
        for x in 0..w / 2 {
            // The left half is the image; the right half its mirror.
            assert_eq!(at(&full, x, y), at(&plain, x, y), "left ({x}, {y})");
            assert_eq!(at(&full, w - 1 - x, y), at(&plain, x, y), "right ({}, {y})", w - 1 - x);
        }
    }
    assert!(full != plain, "the limit set is symmetric: the test would prove nothing");
}

#[test]
fn a_preset_holds_a_layers_chain_and_its_recall_rebuilds_it_and_morphs_its_values() {
    use crate::live_show::{VirtualDisplay, send};
    use rosc::OscType;
    let display = VirtualDisplay::start();
    let saved_chain = format!(r#"{KALEIDOSCOPE}, (effect: "shaders/isf/Diagonalize.fs", params: {{ "width": 0.35 }})"#);
    let (mut show, port, dir, query, recording) =
        crate::live_show::start_recorded(&display, "effects-preset", &limit_set_show("", &saved_chain, ""));
    // The show's presets are in `dir/presets` (live_show passes it).
    let presets = dir.join("presets");
    let osc = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let text = |s: &str| vec![OscType::String(s.into())];
    send(&osc, port, "/indra/preset/save", text("look"));
    show.wait_for("saved preset");
    let saved = std::fs::read_to_string(presets.join("look.ron")).unwrap();
    assert!(saved.contains("chains") && saved.contains("Kaleidoscope.fs"), "the preset lacks the chain: {saved}");

    // The performer changes the chain: the kaleidoscope out, a solarize in, Diagonalize wider.
    send(&osc, port, "/indra/layer/1/fx/remove", vec![OscType::Int(1)]);
    show.wait_for("Remove(0)");
    send(&osc, port, "/indra/layer/1/fx/add", text("shaders/isf/Solarize.fs"));
    show.wait_for("Add(\"shaders/isf/Solarize.fs\")");
    send(&osc, port, "/indra/layer/1/fx/1/width", vec![OscType::Float(0.1)]);
    // The recall edits the chain back (Solarize out, the kaleidoscope in and first), then morphs
    // the values: the kaleidoscope's 5 sides (its default is 6) and Diagonalize's 0.35.
    send(&osc, port, "/indra/preset/recall", text("look"));
    show.wait_for("Remove(1)");
    show.wait_for("Add(\"shaders/isf/Kaleidoscope.fs\")");
    show.wait_for("Move { from: 1, to: 0 }");
    let published = |path: &str| {
        let (status, leaf) = crate::osc::http_get(query, path);
        (status == 200).then(|| leaf["VALUE"][0].as_f64()).flatten()
    };
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(30);
    loop {
        let (sides, width) = (published("/indra/layer/1/fx/1/sides"), published("/indra/layer/1/fx/2/width"));
        let solarize = published("/indra/layer/1/fx/3/mix");
        if sides == Some(5.0) && width.is_some_and(|w| (w - 0.35).abs() < 1e-6) && solarize.is_none() {
            break;
        }
        assert!(
            std::time::Instant::now() < deadline,
            "after the recall: sides {sides:?}, width {width:?}, a third {solarize:?}"
        );
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    std::thread::sleep(std::time::Duration::from_millis(300));
    // The take replays to the saved look: the recall's edits and its morph are in it.
    let (replayed, last) = end_and_replay(&mut show, &recording, &limit_set_show("", &saved_chain, ""));
    assert!(replayed == frame_of(&limit_set_show("", &saved_chain, ""), last + 1), "the replay is not the saved look");
}

#[test]
fn a_note_learned_for_a_chain_edit_sends_it_and_is_kept_for_the_next_run() {
    let two_layers = limit_set_show("", KALEIDOSCOPE, "")
        .replace("layers: [", r#"layers: [(clips: [(scene: "kleinian_classic", id: "second")]), "#);
    let scene = show_from(&two_layers);
    let dir = crate::live_show::scratch_dir("effects-learn");
    let add = ShowCommand::Effect { layer: Some(1), edit: EffectEdit::Add(Text::new("shaders/isf/Diagonalize.fs")) };
    let remove = ShowCommand::Effect { layer: None, edit: EffectEdit::Remove(0) };
    let mut hub = crate::control::hub(&dir, &scene);
    // The note being learned binds and does nothing else; then it sends the edit.
    hub.learn_command(add);
    assert!(hub.midi_bytes(&[0x90, 36, 100], &scene, 0.0).is_empty(), "the learned note fired at once");
    hub.learn_command(remove);
    assert!(hub.midi_bytes(&[0x90, 37, 100], &scene, 0.0).is_empty());
    assert_eq!(hub.midi_bytes(&[0x90, 36, 100], &scene, 0.0), [ControlEvent::Show(add)]);
    assert_eq!(hub.midi_bytes(&[0x90, 37, 100], &scene, 0.0), [ControlEvent::Show(remove)]);
    let saved = std::fs::read_to_string(dir.join("midi-learn.ron")).unwrap();
    assert!(
        saved.contains("layer/2/fx/add shaders/isf/Diagonalize.fs") && saved.contains("master/fx/remove 1"),
        "{saved}"
    );
    // The next run reads them back; a show without that layer drops the layer's.
    let mut next = crate::control::hub(&dir, &scene);
    assert_eq!(next.midi_bytes(&[0x90, 36, 1], &scene, 0.0), [ControlEvent::Show(add)]);
    let one_layer = show_from(&limit_set_show("", "", ""));
    let mut other = crate::control::hub(&dir, &one_layer);
    assert!(other.midi_bytes(&[0x90, 36, 1], &one_layer, 0.0).is_empty());
    assert_eq!(other.midi_bytes(&[0x90, 37, 1], &one_layer, 0.0), [ControlEvent::Show(remove)]);
}
