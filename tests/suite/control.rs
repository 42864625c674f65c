//! Live control without a network: MIDI fed as raw bytes through the real parser and mappings,
//! MIDI learn with its file, presets and morphs, who wins when sources collide, and a recorded
//! control session replayed off-screen frame-exactly.

use crate::common;

use std::path::PathBuf;

use indra::control::record::{Recorder, read_replay};
use indra::control::{ControlHub, ControlOptions};
use indra::offscreen::OffscreenRenderer;
use indra::params::{ParamValue, ParamWrite, Source};
use indra::scene::{ControlEvent, Scene, SceneInstance, Target, parse_scene};
use indra::time::FrameTime;

const SCENE: &str = r#"(
    name: "control test",
    size: (64, 64),
    nodes: [(id: "k", technique: "kleinian", params: { "t": (2.0, 0.0), "scale": 2.0 }, smoothing: { "scale": 0.1 })],
    output: "k",
    controls: (
        osc: { "/1/fader1": "k.scale" },
        midi: [
            (channel: 1, cc: 7, target: "k.scale", range: (1.0, 5.0)),
            (cc: 1, fine: true, target: "k.circle_radius", range: (0.0, 2.0)),
            (channel: 2, cc: 10, target: "k.iterations", curve: Exponential, range: (10.0, 1000.0), invert: true),
            (note: 60, target: "k.circle_inversion"),
            (cc: 20, target: "k.t.x", range: (1.9, 2.0)),
        ],
    ),
    tracks: [(target: "k.t.y", interpolation: Linear, repeat: PingPong, keys: [(0.0, 0.0), (1.0, 0.02)])],
)"#;

fn scene() -> Scene {
    parse_scene("control.ron", SCENE).unwrap_or_else(|e| panic!("{e}"))
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("indra-control-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A hub with no network, MIDI port or audio, its files in `dir`.
pub(crate) fn hub(dir: &std::path::Path, scene: &Scene) -> ControlHub {
    let options = ControlOptions {
        osc: None,
        midi: false,
        presets_dir: dir.join("presets"),
        learn_file: dir.join("midi-learn.ron"),
        audio_learn_file: dir.join("audio-learn.ron"),
        audio_in: None,
        ..ControlOptions::default()
    };
    ControlHub::start(&options, scene)
}

/// The single write's value for each event.
fn values(events: &[ControlEvent]) -> Vec<ParamValue> {
    events
        .iter()
        .map(|e| match e {
            ControlEvent::Write(w) => w.value,
            other => panic!("{other:?}"),
        })
        .collect()
}

#[test]
fn midi_bytes_reach_parameters_through_the_mappings() {
    let s = scene();
    let dir = temp("midi");
    let mut h = hub(&dir, &s);
    // CC 7 on channel 1 sweeps scale over (1, 5); running status carries the second message.
    assert_eq!(values(&h.midi_bytes(&[0xB0, 7, 127, 7, 0], &s, 0.0)), [ParamValue::Float(5.0), ParamValue::Float(1.0)]);
    assert!(h.midi_bytes(&[0xB1, 7, 127], &s, 0.0).is_empty(), "channel 2 is not mapped for CC 7");
    // A clock byte inside a message does not break it.
    assert_eq!(values(&h.midi_bytes(&[0xB0, 7, 0xF8, 127], &s, 0.0)), [ParamValue::Float(5.0)]);
    // 14-bit pair: MSB on CC 1, LSB on CC 33.
    let fine = values(&h.midi_bytes(&[0xB0, 1, 127, 0xB0, 33, 127], &s, 0.0));
    assert_eq!(fine.last(), Some(&ParamValue::Float(2.0)));
    let half = values(&h.midi_bytes(&[0xB0, 1, 64, 0xB0, 33, 0], &s, 0.0));
    assert!(matches!(half[1], ParamValue::Float(x) if (x - 2.0 * 8192.0 / 16383.0).abs() < 1e-6), "{half:?}");
    // Exponential and inverted: 0 → the top of the range, 127 → the bottom.
    let iters = values(&h.midi_bytes(&[0xB1, 10, 0, 0xB1, 10, 127, 0xB1, 10, 64], &s, 0.0));
    let expected_mid = (10.0f32 * 100f32.powf(1.0 - 64.0 / 127.0)).round() as i32;
    assert_eq!(iters, [ParamValue::Int(1000), ParamValue::Int(10), ParamValue::Int(expected_mid)]);
    // A note gates a bool; a component mapping moves one component.
    assert_eq!(
        values(&h.midi_bytes(&[0x90, 60, 100, 0x80, 60, 0], &s, 0.0)),
        [ParamValue::Bool(true), ParamValue::Bool(false)]
    );
    let comp = h.midi_bytes(&[0xB5, 20, 127], &s, 0.0);
    assert!(matches!(&comp[0], ControlEvent::Write(w) if w.component == Some(0) && w.value == ParamValue::Float(2.0)));
}

#[test]
fn midi_clock_gives_tempo_and_transport() {
    let s = scene();
    let mut h = hub(&temp("clock"), &s);
    h.midi_bytes(&[0xFA], &s, 0.0);
    for i in 0..48 {
        h.midi_bytes(&[0xF8], &s, f64::from(i) * 0.5 / 24.0);
    }
    let bpm = h.mapper.clock.bpm().unwrap();
    assert!((bpm - 120.0).abs() < 0.01 && h.mapper.clock.playing, "{bpm}");
    h.midi_bytes(&[0xFC], &s, 2.0);
    assert!(!h.mapper.clock.playing);
}

#[test]
fn midi_learn_binds_the_next_control_and_persists() {
    let s = scene();
    let dir = temp("learn");
    let mut h = hub(&dir, &s);
    let samples = s.nodes[0].params.index("samples").unwrap();
    h.learn(Target { node: 0, param: samples, component: None });
    assert!(h.midi_bytes(&[0xB3, 21, 64], &s, 0.0).is_empty(), "the learning move sets nothing");
    assert!(h.mapper.learning.is_none() && h.mapper.is_mapped(0, samples));
    assert_eq!(values(&h.midi_bytes(&[0xB3, 21, 127], &s, 0.0)), [ParamValue::Int(64)]);
    // A new session loads the learned mapping.
    let mut again = hub(&dir, &s);
    assert_eq!(values(&again.midi_bytes(&[0xB3, 21, 0], &s, 0.0)), [ParamValue::Int(1)]);
    again.unlearn(0, samples, &s);
    assert!(hub(&dir, &s).midi_bytes(&[0xB3, 21, 0], &s, 0.0).is_empty(), "unlearn persists too");
}

#[test]
fn audio_learn_maps_a_source_and_persists() {
    let s = scene();
    let dir = temp("audio-learn");
    let gpu = common::gpu();
    let inst = instance(&gpu, &s);
    let mut h = hub(&dir, &s);
    let scale = s.nodes[0].params.index("scale").unwrap();
    assert_eq!(h.audio_mapped(0, scale), (false, false));
    h.learn_audio(Target { node: 0, param: scale, component: None }, indra::scene::AudioSource::Beat, inst.view());
    assert_eq!(h.audio_mapped(0, scale), (true, true));
    let saved = std::fs::read_to_string(dir.join("audio-learn.ron")).unwrap();
    assert!(saved.contains("Beat") && saved.contains("\"k.scale\""), "{saved}");
    // A new session has it; unlearning persists too.
    let mut again = hub(&dir, &s);
    assert_eq!(again.audio_mapped(0, scale), (true, true));
    again.unlearn_audio(0, scale, &s);
    assert_eq!(hub(&dir, &s).audio_mapped(0, scale), (false, false));
}

fn instance(gpu: &indra::gpu::Gpu, s: &Scene) -> SceneInstance {
    SceneInstance::new(gpu, &common::assets(), s.clone(), (64, 64)).unwrap()
}

fn at(frame: u64) -> FrameTime {
    FrameTime { frame, seconds: frame as f64 * 0.1, dt: 0.1, seed: 0 }
}

fn write(param: usize, value: ParamValue, source: Source) -> ControlEvent {
    ControlEvent::Write(ParamWrite { node: 0, param, component: None, value, source })
}

#[test]
fn presets_save_recall_and_morph() {
    let gpu = common::gpu();
    let s = scene();
    let dir = temp("presets");
    let mut h = hub(&dir, &s);
    let mut inst = instance(&gpu, &s);
    let (scale, inversion) =
        (s.nodes[0].params.index("scale").unwrap(), s.nodes[0].params.index("circle_inversion").unwrap());
    inst.apply(&[
        write(scale, ParamValue::Float(4.0), Source::Ui),
        write(inversion, ParamValue::Bool(true), Source::Ui),
    ]);
    h.save_preset("bright", inst.view());
    inst.apply(&[
        write(scale, ParamValue::Float(1.0), Source::Ui),
        write(inversion, ParamValue::Bool(false), Source::Ui),
    ]);
    inst.advance(&at(0));
    // Morph over 1 s: halfway at 0.5 s the number is halfway, the bool has not switched yet.
    let recall = h.recall("bright", 1.0, &s);
    inst.apply(&recall);
    for f in 1..=6 {
        inst.advance(&at(f));
    }
    let p = inst.params(0);
    assert!(
        (match p.target_at(scale) {
            ParamValue::Float(x) => x,
            _ => 0.0,
        } - 2.5)
            .abs()
            < 1e-4
    );
    assert_eq!(p.target_at(inversion), ParamValue::Bool(false));
    for f in 7..=12 {
        inst.advance(&at(f));
    }
    assert_eq!(
        (inst.params(0).target_at(scale), inst.params(0).target_at(inversion)),
        (ParamValue::Float(4.0), ParamValue::Bool(true))
    );
    assert_eq!(h.presets.names(), ["bright"]);
    assert!(h.recall("missing", 0.0, &s).is_empty());
    assert!(h.notices.iter().any(|n| n.contains("no preset 'missing'")));
    // MIDI program change 0 recalls the first preset by name.
    assert!(matches!(h.midi_bytes(&[0xC0, 0], &s, 0.0).as_slice(), [ControlEvent::Morph { .. }]));
}

#[test]
fn live_input_takes_a_parameter_over_from_its_track_until_resumed() {
    let gpu = common::gpu();
    let s = scene();
    let mut inst = instance(&gpu, &s);
    let t = s.nodes[0].params.index("t").unwrap();
    inst.advance(&at(5)); // track: t.y = 0.01 at 0.5 s
    assert_eq!(inst.params(0).target_at(t), ParamValue::Vec2([2.0, 0.01]));
    let live = ControlEvent::Write(ParamWrite {
        node: 0,
        param: t,
        component: Some(1),
        value: ParamValue::Float(0.03),
        source: Source::Osc,
    });
    inst.apply(&[live]);
    inst.advance(&at(6));
    assert_eq!(inst.params(0).target_at(t), ParamValue::Vec2([2.0, 0.03]), "the track no longer moves it");
    assert!(inst.is_overridden(0, t) && !inst.is_animated(0, t));
    inst.apply(&[ControlEvent::ResumeTracks]);
    inst.advance(&at(7));
    assert!(matches!(inst.params(0).target_at(t), ParamValue::Vec2([_, y]) if (y - 0.014).abs() < 1e-6));
    // Within one frame the last writer wins, whatever its source.
    let scale = s.nodes[0].params.index("scale").unwrap();
    inst.apply(&[write(scale, ParamValue::Float(3.0), Source::Ui), write(scale, ParamValue::Float(4.5), Source::Midi)]);
    assert_eq!(inst.params(0).target_at(scale), ParamValue::Float(4.5));
}

#[test]
fn smoothing_glides_towards_a_stepped_control() {
    let gpu = common::gpu();
    let s = scene();
    let mut inst = instance(&gpu, &s);
    let scale = s.nodes[0].params.index("scale").unwrap();
    inst.apply(&[write(scale, ParamValue::Float(4.0), Source::Osc)]);
    inst.advance(&at(1)); // dt 0.1 = one time constant
    let v = match inst.params(0).value_at(scale) {
        ParamValue::Float(x) => x,
        _ => 0.0,
    };
    assert!((v - (2.0 + 2.0 * (1.0 - (-1.0f32).exp()))).abs() < 1e-4, "{v}");
}

/// A scripted session: OSC, MIDI, a preset morph and a resume, at various frames.
fn script(s: &Scene, dir: &std::path::Path) -> Vec<(u64, Vec<ControlEvent>)> {
    let mut h = hub(dir, s);
    let gpu = common::gpu();
    let inst = instance(&gpu, s);
    h.save_preset("zoomed", inst.view());
    let scale = s.nodes[0].params.index("scale").unwrap();
    vec![
        (2, vec![write(scale, ParamValue::Float(3.3), Source::Osc)]),
        (3, h.midi_bytes(&[0xB0, 7, 100, 0x90, 60, 90], s, 0.3)),
        (4, vec![ControlEvent::Tempo { bpm: 90.0, resync: true }]),
        (5, h.recall("zoomed", 0.2, s)),
        (7, vec![ControlEvent::ResumeTracks, write(scale, ParamValue::Float(1.5), Source::Ui)]),
    ]
}

fn render(s: &Scene, events: &std::collections::BTreeMap<u64, Vec<ControlEvent>>) -> Vec<Vec<u8>> {
    let mut r =
        OffscreenRenderer::new(common::gpu(), &common::assets(), s.clone(), Some((64, 64)), Some(0.1), None).unwrap();
    for (f, e) in events {
        r.schedule(*f, e.clone());
    }
    (0..10).map(|_| r.render_next().unwrap().rgba).collect()
}

#[test]
fn a_recorded_session_replays_frame_exactly() {
    let s = scene();
    let dir = temp("replay");
    let session = script(&s, &dir);
    let path = dir.join("session.ron");
    std::fs::write(&path, "an earlier recording\n").unwrap();
    let mut recorder = Recorder::create(&path).unwrap();
    for (frame, events) in &session {
        recorder.record(*frame, events, &s).unwrap();
    }
    // Until it finishes, the earlier recording is whole (a kill now would leave it).
    assert_eq!(std::fs::read_to_string(&path).unwrap(), "an earlier recording\n");
    drop(recorder);
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().ends_with(".recording"))
        .collect();
    assert!(leftovers.is_empty(), "the temporary recording is renamed, not left: {leftovers:?}");
    let replay = read_replay(&path, &s, &crate::common::assets()).unwrap();
    let original: std::collections::BTreeMap<u64, Vec<ControlEvent>> = session.into_iter().collect();
    assert_eq!(replay, original, "recording loses nothing");
    let (a, b) = (render(&s, &replay), render(&s, &replay));
    assert!(a == b, "two replays give identical bytes");
    assert!(a != render(&s, &Default::default()), "the session changes the pictures");
    // A malformed line is an error that names it.
    std::fs::write(&path, "(frame: 1, event: Nonsense)\n").unwrap();
    assert!(read_replay(&path, &s, &crate::common::assets()).unwrap_err().contains("session.ron:1:"));
}

#[test]
fn a_hub_starts_without_midi_hardware_or_ports() {
    let s = scene();
    let dir = temp("nomidi");
    let options = ControlOptions {
        osc: Some("127.0.0.1:0".into()),
        midi: true,
        presets_dir: dir.join("p"),
        learn_file: dir.join("l.ron"),
        ..ControlOptions::default()
    };
    let h = ControlHub::start(&options, &s);
    assert!(h.status().contains("MIDI"), "{}", h.status());
    assert!(h.osc.is_some());
    // A port already taken is a notice, not a failure.
    let taken = h.osc.as_ref().unwrap().local_addr().to_string();
    let second = ControlHub::start(&ControlOptions { osc: Some(taken), midi: false, ..options }, &s);
    assert!(second.osc.is_none() && second.notices.iter().any(|n| n.contains("cannot listen for OSC")));
}

const LFO_SCENE: &str = r#"(
    name: "lfo test",
    size: (64, 64),
    bpm: 150,
    nodes: [(id: "k", technique: "kleinian")],
    output: "k",
    controls: (lfo: [
        (target: "k.scale", shape: Saw, rate: Hz(0.5), range: (1.0, 3.0)),
        (target: "k.offset.y", shape: Square, rate: Beats(1.0), range: (0.0, 2.0), phase: 0.25),
    ]),
)"#;

fn float(inst: &SceneInstance, name: &str) -> f32 {
    inst.params(0).float(name)
}

#[test]
fn lfos_move_parameters_in_hertz_and_in_beats_of_the_tempo() {
    let gpu = common::gpu();
    let s = parse_scene("lfo.ron", LFO_SCENE).unwrap_or_else(|e| panic!("{e}"));
    let mut inst = instance(&gpu, &s);
    for f in 0..12 {
        inst.advance(&at(f));
        // Saw at 0.5 Hz over (1, 3): 1 + 2·frac(0.05 f).
        let saw = 1.0 + 2.0 * (0.05 * f as f64).fract() as f32;
        assert!((float(&inst, "scale") - saw).abs() < 1e-5, "frame {f}: {}", float(&inst, "scale"));
        // 150 bpm at dt 0.1 is 0.25 beats a step; the square is high for the first half beat.
        let cycles = 0.25 * f as f64 + 0.25;
        let high = cycles.fract() < 0.5;
        assert_eq!(inst.params(0).vec2("offset")[1], if high { 2.0 } else { 0.0 }, "frame {f}");
    }
    assert!((inst.tempo().beats - 3.0).abs() < 1e-6, "{}", inst.tempo().beats);
    // A tap lands the beat: 3.0 stays 3.0; a slower tempo slows the beat LFO.
    inst.apply(&[ControlEvent::Tempo { bpm: 60.0, resync: true }]);
    inst.advance(&at(12));
    assert_eq!(inst.tempo().bpm, 60.0);
    assert!((inst.tempo().beats - 3.1).abs() < 1e-6, "{}", inst.tempo().beats);
    // A live write takes the parameter from its LFO until tracks resume.
    let scale = s.nodes[0].params.index("scale").unwrap();
    inst.apply(&[write(scale, ParamValue::Float(7.0), Source::Osc)]);
    inst.advance(&at(13));
    assert_eq!(float(&inst, "scale"), 7.0);
    inst.apply(&[ControlEvent::ResumeTracks]);
    inst.advance(&at(14));
    assert!((float(&inst, "scale") - (1.0 + 2.0 * 0.7)).abs() < 1e-5);
}

#[test]
fn bad_lfos_and_tempos_are_located_errors() {
    for (bad, said) in [
        ("(target: \"k.circle_inversion\", rate: Hz(1.0), range: (0.0, 1.0))", "is a bool"),
        ("(target: \"k.scale\", rate: Hz(0.0), range: (0.0, 1.0))", "positive rate"),
        ("(target: \"k.zoom\", rate: Beats(1.0), range: (0.0, 1.0))", "no parameter 'zoom'"),
        ("(target: \"k.scale\", shape: Wobble, rate: Hz(1.0), range: (0.0, 1.0))", "Wobble"),
    ] {
        let text = LFO_SCENE.replace("(target: \"k.scale\", shape: Saw, rate: Hz(0.5), range: (1.0, 3.0))", bad);
        let e = parse_scene("lfo.ron", &text).err().unwrap_or_else(|| panic!("{bad} was accepted")).to_string();
        assert!(e.contains(said) && e.contains("lfo.ron:"), "{bad}: {e}");
    }
    let e = parse_scene("lfo.ron", &LFO_SCENE.replace("bpm: 150", "bpm: 1000")).err().unwrap().to_string();
    assert!(e.contains("bpm 1000"), "{e}");
}
