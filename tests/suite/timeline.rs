//! A show's timeline: lanes drive a layer's opacity, the master and a restarting clip's
//! parameter to their keyframes on the show's clock; markers fire a clip, a column and a cue on
//! their frames; frame N is the same played or sought through them; a broken timeline is
//! refused with located errors.

use crate::common::{assets, gpu};
use indra::offscreen::OffscreenRenderer;
use indra::params::{ControlEvent, LaneKeys, ParamValue};
use indra::scene::Scene;
use indra::scene::show::parse_show;

/// Two limit sets on a layer (cuts between them), two cues, and a timeline: the layer fades in
/// over the first second, the master steps down at 2 s, the blue clip's colour follows a lane
/// of the show's time; clip 2 at 0.5 s, column 1 at 1 s, cue 2 at 1.5 s.
const TIMED: &str = r#"(
    name: "timed",
    size: (16, 16),
    seed: 1,
    transition: (kind: "cut"),
    layers: [(start: 1, clips: [
        (scene: "kleinian_classic", id: "red"),
        (scene: "kleinian_classic", id: "blue"),
    ])],
    cues: [
        (name: "red", clips: [(1, 1)]),
        (name: "blue", clips: [(1, 2)]),
    ],
    timeline: (
        lanes: [
            (target: "layer/1.opacity", keys: [(0.0, 0.0), (1.0, 1.0)], interpolation: Linear),
            (target: "master.level", keys: [(0.0, 1.0), (2.0, 0.25)], interpolation: Step),
            (target: "blue/limit_set.hit_color.x", keys: [(0.0, 0.0), (2.0, 1.0)], interpolation: Linear),
        ],
        markers: [
            (at: 1.5, name: "to blue", cue: 2),
            (at: 0.5, clip: (1, 2)),
            (at: 1.0, name: "column", column: 1),
        ],
        chase: (start: "01:00:00:00", freewheel: 1.0),
    ),
)"#;

fn show_from(text: &str) -> Scene {
    parse_show(&assets(), "timeline.ron", text, false).unwrap_or_else(|e| panic!("{e}"))
}

fn float(value: ParamValue) -> f32 {
    value.components()[0]
}

#[test]
fn lanes_drive_parameters_on_the_show_clock_and_markers_fire_on_their_frames() {
    let scene = show_from(TIMED);
    let show = scene.show.clone().unwrap();
    assert_eq!(show.timeline.chase.map(|c| (c.start.to_string(), c.freewheel)), Some(("01:00:00:00".into(), 1.0)));
    let (layer, master) = (scene.node_index("layer/1").unwrap(), scene.node_index("master").unwrap());
    let blue = scene.node_index("blue/limit_set").unwrap();
    let mut r = OffscreenRenderer::new(gpu(), &assets(), scene, Some((16, 16)), None, None).unwrap();
    let mut playing = Vec::new();
    for frame in 0..=150u64 {
        r.render_only().unwrap();
        let instance = r.instance_mut();
        let seconds = frame as f32 / 60.0;
        let opacity = float(instance.params(layer).get("opacity"));
        assert!((opacity - seconds.min(1.0)).abs() < 1e-4, "frame {frame}: opacity {opacity}");
        let level = float(instance.params(master).get("level"));
        assert_eq!(level, if frame < 120 { 1.0 } else { 0.25 }, "frame {frame}: master");
        // The lane runs on the show's clock, though the clip restarts when triggered (0.5 s).
        let red = instance.params(blue).get("hit_color").components()[0];
        assert!((red - seconds.min(2.0) / 2.0).abs() < 1e-4, "frame {frame}: the blue clip's red {red}");
        let (_, state) = instance.show().unwrap();
        playing.push((state.playing(0), state.cue()));
    }
    assert_eq!(playing[29].0, Some(0), "red until its marker");
    assert_eq!(playing[30].0, Some(1), "clip 2 at 0.5 s (frame 30)");
    assert_eq!(playing[60].0, Some(0), "column 1 at 1 s");
    assert_eq!(playing[90], (Some(1), Some(1)), "cue 2 at 1.5 s");
}

#[test]
fn a_timed_show_renders_frame_n_the_same_played_or_sought() {
    let render = |seek: bool| {
        let mut r = OffscreenRenderer::new(gpu(), &assets(), show_from(TIMED), Some((16, 16)), None, None).unwrap();
        if seek {
            r.seek(100).unwrap();
        } else {
            for _ in 0..100 {
                r.render_only().unwrap();
            }
        }
        r.render_next().unwrap().rgba
    };
    let played = render(false);
    assert!(played == render(true), "frame 100 sought differs from frame 100 played");
    assert!(played.chunks(4).any(|p| p[..3] != played[..3]), "a blank frame proves nothing");
}

#[test]
fn a_broken_timeline_is_refused_with_located_errors() {
    let cases = [
        (r#"target: "layer/1.opacity""#, r#"target: "layer/3.opacity""#, "lane"),
        ("(at: 1.5, name: \"to blue\", cue: 2)", "(at: 1.5, name: \"to blue\", cue: 9)", "cue 9"),
        ("(at: 0.5, clip: (1, 2))", "(at: 0.5, clip: (1, 2), column: 1)", "one thing"),
        ("(at: 0.5, clip: (1, 2))", "(at: -1.0, clip: (1, 2))", "at -1"),
        (r#"start: "01:00:00:00""#, r#"start: "1:00""#, "chase start"),
    ];
    for (from, to, says) in cases {
        let text = TIMED.replace(from, to);
        assert_ne!(text, TIMED, "{from}");
        let e = parse_show(&assets(), "timeline.ron", &text, false).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains(says) && e.contains("timeline.ron:"), "{to}: {e}");
    }
}

#[test]
fn a_lane_in_beats_follows_the_shows_tempo() {
    // A 4-beat ramp that loops: one bar of the music, whatever its tempo.
    let lane = r#"(target: "layer/1.opacity", beats: true, keys: [(0.0, 0.0), (4.0, 1.0)], interpolation: Linear, repeat: Loop)"#;
    for bpm in [120.0f64, 90.0] {
        let text = TIMED
            .replace(r#"(target: "layer/1.opacity", keys: [(0.0, 0.0), (1.0, 1.0)], interpolation: Linear)"#, lane)
            .replace("seed: 1,", &format!("seed: 1, bpm: {bpm:.1},"));
        let scene = show_from(&text);
        let layer = scene.node_index("layer/1").unwrap();
        let mut r = OffscreenRenderer::new(gpu(), &assets(), scene, Some((16, 16)), None, None).unwrap();
        for frame in 0..=300u64 {
            r.render_only().unwrap();
            let beats = frame as f64 / 60.0 * bpm / 60.0;
            let opacity = float(r.instance_mut().params(layer).get("opacity"));
            // At a bar's end the ramp wraps: 1 and 0 are the same point of the loop.
            let off = (f64::from(opacity) - beats % 4.0 / 4.0).abs();
            assert!(off.min(1.0 - off) < 1e-3, "{bpm} BPM, frame {frame}: opacity {opacity}");
        }
    }
}

/// A show whose master a lane steps between 0.2 and 0.8 every second.
const STEPPED: &str = r#"(
    name: "stepped", size: (16, 16), seed: 1,
    layers: [(start: 1, clips: [(scene: "kleinian_classic")])],
    timeline: (lanes: [
        (target: "master.level", keys: [(0.0, 0.2), (1.0, 0.8), (2.0, 0.2)], interpolation: Step, repeat: Loop),
    ]),
)"#;

#[test]
fn a_lane_is_read_back_over_oscquery_and_a_fader_move_over_it_replays_on_its_frame() {
    use crate::live_show::{VirtualDisplay, send, start_recorded};
    use std::time::{Duration, Instant};
    let display = VirtualDisplay::start();
    let (mut show, port, _, query, take) = start_recorded(&display, "timeline-live", STEPPED);
    let level = || crate::osc::http_get(query, "/indra/master/level").1["VALUE"][0].as_f64().unwrap_or(f64::NAN);
    // The lane's two values, and nothing else, for three seconds (once the tree has the first
    // frame's values: before it, the master's 1).
    let lane_value = |value: f64| [0.2, 0.8].iter().any(|v| (value - v).abs() < 1e-6);
    let deadline = Instant::now() + Duration::from_secs(30);
    while !lane_value(level()) {
        assert!(Instant::now() < deadline, "the lane never reached the master: {}", level());
        std::thread::sleep(Duration::from_millis(20));
    }
    let mut seen = std::collections::BTreeSet::new();
    let until = Instant::now() + Duration::from_secs(3);
    while Instant::now() < until {
        let value = level();
        assert!(lane_value(value), "the master read {value}");
        seen.insert((value * 10.0).round() as u32);
        std::thread::sleep(Duration::from_millis(50));
    }
    assert_eq!(seen.into_iter().collect::<Vec<_>>(), [2, 8], "the lane steps between its keys");
    // A fader move takes the master over from the lane.
    let osc = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    send(&osc, port, "/indra/master", vec![rosc::OscType::Float(0.5)]);
    let deadline = Instant::now() + Duration::from_secs(30);
    while (level() - 0.5).abs() > 1e-6 {
        assert!(Instant::now() < deadline, "the fader move never showed: {}", level());
        std::thread::sleep(Duration::from_millis(50));
    }
    let until = Instant::now() + Duration::from_millis(1500);
    while Instant::now() < until {
        assert!((level() - 0.5).abs() < 1e-6, "the lane took the master back: {}", level());
        std::thread::sleep(Duration::from_millis(50));
    }
    // The take, replayed in a render: the lane's steps up to the move's frame, 0.5 from it on.
    show.interrupt();
    let scene = show_from(STEPPED);
    let master = scene.node_index("master").unwrap();
    let script = indra::control::record::read_replay(&take, &scene, &assets()).unwrap();
    let moved = *script.keys().next().expect("the take holds the fader move");
    let mut r = OffscreenRenderer::new(gpu(), &assets(), scene, Some((16, 16)), None, None).unwrap();
    for (frame, events) in script {
        r.schedule(frame, events);
    }
    for frame in 0..moved + 180 {
        r.render_only().unwrap();
        let got = float(r.instance_mut().params(master).get("level"));
        let lane = if frame % 120 < 60 { 0.2 } else { 0.8 };
        let want = if frame < moved { lane } else { 0.5 };
        assert_eq!(got, want, "frame {frame} (the move at {moved})");
    }
}

/// The master's level each step and every 20th frame's pixels, for `frames` steps of `scene`
/// with `events` applied before the steps they name.
fn levels(scene: Scene, frames: u64, events: &[(u64, ControlEvent)]) -> (Vec<f32>, Vec<Vec<u8>>) {
    let master = scene.node_index("master").unwrap();
    let mut r = OffscreenRenderer::new(gpu(), &assets(), scene, Some((16, 16)), None, None).unwrap();
    for (frame, event) in events {
        r.schedule(*frame, vec![event.clone()]);
    }
    let (mut levels, mut images) = (Vec::new(), Vec::new());
    for frame in 0..frames {
        if frame % 20 == 0 {
            images.push(r.render_next().unwrap().rgba);
        } else {
            r.render_only().unwrap();
        }
        levels.push(float(r.instance_mut().params(master).get("level")));
    }
    (levels, images)
}

#[test]
fn a_fader_move_recorded_into_a_lane_replays_at_every_step_and_from_the_saved_file() {
    use indra::params::{ParamWrite, Source};
    use indra::scene::show::{LaneTake, lane_file::with_lanes, raw_keys, scalar_keys};
    let scene = show_from(TIMED);
    let master = scene.node_index("master").unwrap();
    let level = scene.nodes[master].params.index("level").unwrap();
    let lane = scene.tracks.iter().find(|t| t.show_clock && t.target == "master.level").unwrap().clone();
    // The performance, as the window plays it (two steps a displayed frame): the lane plays, the
    // performer moves the master from frame 60 on over the lane's step at 120, and disarms the
    // take at 180, which hands the master back to the lane with the take in it.
    let fader = |frame: u64| 0.3 + 0.004 * (frame / 2 % 40) as f32;
    let mut r = OffscreenRenderer::new(gpu(), &assets(), scene.clone(), Some((16, 16)), None, None).unwrap();
    let mut take = LaneTake::new(1.0 / 60.0);
    let (mut performed, mut images, mut edit) = (Vec::new(), Vec::new(), None);
    for frame in 0..300u64 {
        let instance = r.instance_mut();
        if frame % 2 == 0 && (60..180).contains(&frame) {
            let value = ParamValue::Float(fader(frame));
            instance.apply(&[ControlEvent::Write(ParamWrite {
                node: master,
                param: level,
                component: None,
                value,
                source: Source::Ui,
            })]);
        }
        if frame == 180 {
            take.end(179);
            let old = scalar_keys(&lane.track).unwrap();
            let keys = take.keys(&old, |t| lane.track.sample(t).components()[0], lane.track.interpolation);
            let event = ControlEvent::Lane(LaneKeys {
                target: lane.target.clone(),
                keys: raw_keys(&keys),
                interpolation: lane.track.interpolation,
                repeat: lane.track.repeat,
                beats: false,
            });
            instance.apply(std::slice::from_ref(&event));
            edit = Some(event);
        }
        if frame % 2 == 0 && instance.is_overridden(master, level) {
            take.hold(frame, float(instance.params(master).target_at(level)));
        }
        if frame % 20 == 0 {
            images.push(r.render_next().unwrap().rgba);
        } else {
            r.render_only().unwrap();
        }
        performed.push(float(r.instance_mut().params(master).get("level")));
    }
    assert_eq!(performed[100], fader(100), "the performer had the master");
    assert_eq!((performed[59], performed[250]), (1.0, 0.25), "the lane before and after the take");
    let edit = edit.unwrap();
    let (replayed, replayed_images) = levels(scene.clone(), 300, &[(0, edit.clone())]);
    assert_eq!(replayed, performed, "the lane with the take, from the show's start");
    assert!(replayed_images == images, "the frames it renders are the performed ones");
    // Saved into the file: the show read from it plays the performance with no events at all.
    let mut r = OffscreenRenderer::new(gpu(), &assets(), scene, Some((16, 16)), None, None).unwrap();
    r.instance_mut().apply(&[edit]);
    let (source, _) = r.instance_mut().show_source().unwrap();
    let saved = with_lanes(&source.text, &source.file.timeline.lanes).unwrap();
    assert!(saved.contains("(target: \"blue/limit_set.hit_color.x\""), "the other lanes stay: {saved}");
    assert_eq!(levels(show_from(&saved), 300, &[]), (performed, images), "the saved show plays the take");
}

#[test]
fn lanes_edited_live_are_checked_as_a_files_are_and_removing_one_leaves_its_parameter() {
    let scene = show_from(TIMED);
    let lane = |target: &str, keys: &[(f32, f64)]| {
        ControlEvent::Lane(LaneKeys {
            target: target.into(),
            keys: keys.iter().map(|&(t, v)| (t, indra::params::RawValue::Number(v))).collect(),
            interpolation: indra::params::Interpolation::Linear,
            repeat: indra::params::LoopMode::Once,
            beats: false,
        })
    };
    let refused = [
        lane("nowhere.level", &[(0.0, 1.0)]),
        lane("master.level", &[(-1.0, 1.0)]),
        lane("master.nothing", &[(0.0, 1.0)]),
        lane("layer/1.opacity.x", &[(0.0, 1.0)]),
        lane("red/limit_set.hit_color.x", &[]),
    ];
    let mut r = OffscreenRenderer::new(gpu(), &assets(), scene.clone(), Some((16, 16)), None, None).unwrap();
    r.instance_mut().apply(&refused);
    let messages = r.instance_mut().take_messages();
    assert_eq!(messages.len(), refused.len(), "one message each: {messages:#?}");
    assert_eq!(r.instance_mut().scene().tracks.len(), scene.tracks.len(), "nothing changed");
    // The master's lane removed at frame 150 (at 0.25 since 2 s): it stays where the lane left it,
    // and a lane added on the red clip's colour drives it.
    let events =
        [(150, lane("master.level", &[])), (150, lane("red/limit_set.hit_color.y", &[(0.0, 0.0), (10.0, 1.0)]))];
    let (levels_after, _) = levels(scene.clone(), 200, &events);
    assert!(levels_after[150..].iter().all(|l| *l == 0.25), "{:?}", &levels_after[150..]);
    let red = scene.node_index("red/limit_set").unwrap();
    let mut r = OffscreenRenderer::new(gpu(), &assets(), scene, Some((16, 16)), None, None).unwrap();
    for (frame, event) in events {
        r.schedule(frame, vec![event]);
    }
    for _ in 0..=180 {
        r.render_only().unwrap();
    }
    let green = r.instance_mut().params(red).get("hit_color").components()[1];
    assert!((green - 0.3).abs() < 1e-4, "the added lane at 3 s of 10: {green}");
}
