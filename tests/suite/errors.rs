//! Panics a user could reach, now each one clear sentence: a hand-edited MIDI learn file, a lost
//! device during a render, a `--set` value written as in a scene file. (A surface offering no
//! formats is tested in `app::surface`; the window needs a display.)

use crate::common;

use indra::control::midi::LearnStore;
use indra::control::{ControlHub, ControlOptions};
use indra::offscreen::OffscreenRenderer;
use indra::params::ParamValue;
use indra::scene::{ControlEvent, load_scene, parse_scene};

const SCENE: &str = r#"(
    name: "errors",
    size: (64, 64),
    nodes: [(id: "k", technique: "kleinian")],
    output: "k",
)"#;

#[test]
fn a_hand_edited_midi_learn_file_is_validated_at_load() {
    let dir = std::env::temp_dir().join(format!("indra-errors-learn-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("midi-learn.ron");
    // A 14-bit pair on CC 40 (its LSB would be CC 72) used to index past a 32-entry table, and
    // channel 17 does not exist; the third mapping is fine and must survive.
    std::fs::write(
        &path,
        r#"[
            (cc: 40, fine: true, target: "k.scale"),
            (channel: 17, cc: 3, target: "k.scale"),
            (cc: 5, target: "k.circle_radius"),
        ]"#,
    )
    .unwrap();
    let (valid, problems) = LearnStore { path: path.clone() }.load_checked();
    assert_eq!(valid.len(), 1, "{valid:?}");
    assert_eq!(problems.len(), 2, "{problems:?}");
    assert!(problems[0].contains("midi-learn.ron") && problems[0].contains("cc 40"), "{}", problems[0]);
    assert!(problems[1].contains("channel"), "{}", problems[1]);

    // The hub loads the same file and survives the exact bytes that used to crash it.
    let scene = parse_scene("errors.ron", SCENE).unwrap();
    let options =
        ControlOptions { osc: None, midi: false, learn_file: path, presets_dir: dir.join("p"), ..Default::default() };
    let mut hub = ControlHub::start(&options, &scene);
    assert!(hub.midi_bytes(&[0xB0, 40, 64, 0xB0, 72, 1], &scene, 0.0).is_empty());
    let events = hub.midi_bytes(&[0xB0, 5, 127], &scene, 0.0);
    assert!(matches!(&events[..], [ControlEvent::Write(w)] if w.value == ParamValue::Float(20.0)), "{events:?}");
}

#[test]
fn a_lost_device_ends_a_render_with_a_sentence() {
    let scene = load_scene(&common::assets(), "kleinian").unwrap();
    let mut r = OffscreenRenderer::new(common::gpu(), &common::assets(), scene, Some((32, 32)), None, None).unwrap();
    r.render_next().expect("a frame before the loss");
    r.gpu().device.destroy();
    let e = r.render_next().err().expect("no frame comes back from a lost device").to_string();
    assert!(e.contains("GPU was lost") && e.contains("--start"), "{e}");
}

#[test]
fn set_takes_a_vector_as_a_scene_file_writes_it() {
    let mut scene = load_scene(&common::assets(), "kleinian").unwrap();
    let t = |scene: &indra::scene::Scene| scene.nodes[0].params.get("t");
    for written in ["limit_set.t=(1.95, 0.01)", "limit_set.t=[1.95,0.01]", "limit_set.t=1.95,0.01"] {
        scene.set_from_str("limit_set.t=2,0").unwrap();
        scene.set_from_str(written).unwrap_or_else(|e| panic!("{written}: {e}"));
        assert_eq!(t(&scene), ParamValue::Vec2([1.95, 0.01]), "{written}");
    }
    let e = scene.set_from_str("limit_set.t=(1.9, x)").unwrap_err();
    assert!(e.contains("'x'") && e.contains("(1.0, 0.5)"), "{e}");
}

#[test]
fn nan_from_a_live_source_is_refused_once_with_a_message() {
    use indra::params::{ParamWrite, Source};
    let scene = load_scene(&common::assets(), "kleinian").unwrap();
    let mut instance = indra::scene::SceneInstance::new(&common::gpu(), &common::assets(), scene, (32, 32)).unwrap();
    let colour = instance.params(0).index("hit_color").unwrap();
    let before = instance.params(0).target_at(colour);
    let nan = ParamValue::Color([1.0, f32::NAN, 0.0, 1.0]);
    let write =
        ControlEvent::Write(ParamWrite { node: 0, param: colour, component: None, value: nan, source: Source::Osc });
    instance.apply(&[write.clone(), write]);
    assert_eq!(instance.params(0).target_at(colour), before, "an unbounded colour keeps its value");
    let messages = instance.take_messages();
    assert_eq!(messages.len(), 1, "{messages:?}");
    assert!(messages[0].contains("limit_set.hit_color") && messages[0].contains("finite"), "{}", messages[0]);
}
