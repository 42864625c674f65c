//! Checkpoints hold the whole state: for every scene in `scenes/` and every show in `shows/`
//! (ones added later are picked up), the frames after a checkpoint — written to bytes and read
//! back into a new renderer — are the same bytes as the frames played from 0. Scenes a performer
//! drives (a drawn polygon, a stirred fluid, a dragged warp point, show triggers) are checked with
//! the control events of such a performance on both sides of the checkpoint.

use std::path::Path;

use crate::common;

use indra::assets::AssetKind;
use indra::checkpoint::Checkpoint;
use indra::offscreen::OffscreenRenderer;
use indra::params::{ParamValue, ParamWrite, ShowCommand, Source};
use indra::scene::{ControlEvent, Scene, load_scene};

const SIZE: (u32, u32) = (80, 48);
/// The checkpoint's frame, and the frames compared after it.
const AT: u64 = 9;
const AFTER: u64 = 7;

type Script = Vec<(u64, Vec<ControlEvent>)>;

fn renderer(scene: Scene, script: &Script) -> OffscreenRenderer {
    let mut r =
        OffscreenRenderer::new(common::gpu(), &common::assets(), scene, Some(SIZE), None, None).expect("scene builds");
    for (frame, events) in script {
        r.schedule(*frame, events.clone());
    }
    r
}

/// Plays `scene` to `AT + AFTER`, and again from a checkpoint at `AT` taken to bytes and back;
/// panics where a frame after the checkpoint differs.
fn check(name: &str, scene: Scene, script: &Script) {
    let started = std::time::Instant::now();
    // Taken mid-play (`indra bake` takes them mid-seek: tests/cli.rs checks that path).
    let mut played = renderer(scene.clone(), script);
    let render =
        |r: &mut OffscreenRenderer, n| (0..n).map(|_| r.render_next().expect("frame renders").rgba).collect::<Vec<_>>();
    render(&mut played, AT);
    let bytes = played.checkpoint("").unwrap_or_else(|e| panic!("{name}: {e}")).to_bytes();
    let frames = render(&mut played, AFTER);
    let checkpoint = Checkpoint::from_bytes(Path::new(name), &bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(checkpoint.header.frame, AT);
    let mut resumed =
        OffscreenRenderer::new(common::gpu(), &common::assets(), scene, Some(SIZE), None, None).expect("scene builds");
    resumed.restore(&checkpoint).unwrap_or_else(|e| panic!("{name}: {e}"));
    for (frame, events) in script.iter().filter(|(f, _)| *f >= AT) {
        resumed.schedule(*frame, events.clone());
    }
    assert_eq!(resumed.next_frame(), AT);
    for frame in AT..AT + AFTER {
        let got = resumed.render_next().expect("frame renders").rgba;
        let want = &frames[(frame - AT) as usize];
        let differing = got.chunks(4).zip(want.chunks(4)).filter(|(p, q)| p != q).count();
        assert!(differing == 0, "{name}: frame {frame} from the checkpoint differs in {differing} pixels");
    }
    eprintln!("{name}: {} KiB checkpoint, {:.1} s", bytes.len() / 1024, started.elapsed().as_secs_f64());
}

fn write(scene: &Scene, target: &str, value: ParamValue) -> ControlEvent {
    let t = indra::scene::resolve_target(&scene.nodes, target).unwrap_or_else(|e| panic!("{target}: {e}"));
    ControlEvent::Write(ParamWrite {
        node: t.node,
        param: t.param,
        component: t.component,
        value,
        source: Source::Replay,
    })
}

/// A performance of a scene a performer drives, either side of the checkpoint, if it is one.
fn performance(name: &str, scene: &Scene) -> Script {
    let pulse = |target: &str| write(scene, target, ParamValue::Trigger(true));
    let at = |x: f32, y: f32| write(scene, "draw.cursor", ParamValue::Vec2([x, y]));
    match name {
        "polygon_draw.ron" => vec![
            (2, vec![at(0.2, 0.2), pulse("draw.add")]),
            (4, vec![at(0.7, 0.3), pulse("draw.add")]),
            (6, vec![at(0.5, 0.8), pulse("draw.add")]),
            (8, vec![pulse("draw.close")]),
            (10, vec![at(0.1, 0.9), pulse("draw.add")]),
            (12, vec![at(0.3, 0.6), pulse("draw.add")]),
        ],
        "tessellation_fluid.ron" => {
            let stir = |x: f32| write(scene, "fluid.cursor", ParamValue::Vec2([x, 0.5]));
            let drag = |on: bool| write(scene, "fluid.drag", ParamValue::Bool(on));
            (2..14).map(|f| (f, vec![stir(0.2 + 0.05 * f as f32), drag(f < 13)])).collect()
        }
        "projection_mapping.ron" => {
            let point = |f: f32| write(scene, "wall.mesh_point", ParamValue::Vec3([1.0, 0.1 * f, 0.2]));
            (3..12).step_by(2).map(|f| (f, vec![point(f as f32 / 14.0)])).collect()
        }
        _ => Vec::new(),
    }
}

#[test]
fn every_scene_goes_on_from_a_checkpoint_as_it_plays() {
    let assets = common::assets();
    for name in assets.names(AssetKind::Scene) {
        let mut scene = load_scene(&assets, &name).unwrap_or_else(|e| panic!("{e}"));
        if let Some((_, sets, _)) = crate::seek::CI_SETTINGS.iter().find(|(s, _, _)| *s == name) {
            for set in *sets {
                scene.set_from_str(set).unwrap_or_else(|e| panic!("{name}: {e}"));
            }
        }
        let script = performance(&name, &scene);
        check(&name, scene, &script);
    }
}

#[test]
fn every_show_goes_on_from_a_checkpoint_mid_switch() {
    let assets = common::assets();
    for name in assets.names(AssetKind::Show) {
        let scene = load_scene(&assets, &format!("shows/{name}")).unwrap_or_else(|e| panic!("{e}"));
        let show = scene.show.clone().expect("a show");
        // A cue far into the list, then the next one: the checkpoint falls in its crossfade,
        // with a clip that restarted on its trigger running.
        let script: Script = if show.cues.is_empty() {
            let layer = 0;
            let clips = show.layers[layer].clips.len();
            let trigger = |clip| ControlEvent::Show(ShowCommand::Trigger { layer, clip: Some(clip) });
            vec![(2, vec![trigger(clips.saturating_sub(1))]), (6, vec![trigger(clips / 2)])]
        } else {
            vec![
                (2, vec![ControlEvent::Show(ShowCommand::CueGoto(show.cues.len() / 3))]),
                (6, vec![ControlEvent::Show(ShowCommand::CueGo)]),
            ]
        };
        check(&format!("shows/{name}"), scene, &script);
    }
}
