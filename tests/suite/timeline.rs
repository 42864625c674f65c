//! A show's timeline: lanes drive a layer's opacity, the master and a restarting clip's
//! parameter to their keyframes on the show's clock; markers fire a clip, a column and a cue on
//! their frames; frame N is the same played or sought through them; a broken timeline is
//! refused with located errors.

use crate::common::{assets, gpu};
use indra::offscreen::OffscreenRenderer;
use indra::params::ParamValue;
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
