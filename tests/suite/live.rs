//! Hot reload end to end, off-screen, through the real file watcher: a broken shader or scene
//! keeps the last good image (the golden) and reports the error with its line; the fix brings
//! the new version in.

use crate::common;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use indra::assets::Assets;
use indra::control::{ControlHub, ControlOptions};
use indra::live::{LiveReload, ReloadReport};
use indra::offscreen::{OffscreenRenderer, RenderedFrame};
use indra::params::{ControlEvent, ParamValue, ParamWrite, Source, Target};
use indra::scene::{Player, SceneInstance, load_scene};
use indra::time::FixedClock;

/// A private copy of the project's scenes/ and shaders/ to edit.
fn sandbox(name: &str) -> PathBuf {
    common::sandbox(&format!("live-{name}"))
}

fn renderer(root: &Path) -> (OffscreenRenderer, LiveReload) {
    let assets = Assets::new(Some(root.to_path_buf()));
    let scene = load_scene(&assets, "kleinian_classic").unwrap();
    let live = LiveReload::new(&assets).unwrap();
    (OffscreenRenderer::new(common::gpu(), &assets, scene, Some((256, 256)), None, None).unwrap(), live)
}

/// The next frame. `kleinian_classic` is static (its golden holds at every frame), so each call
/// shows what is live now.
fn shown(r: &mut OffscreenRenderer) -> RenderedFrame {
    r.render_next().unwrap()
}

/// Polls until the watcher reports something (or 5 s pass).
pub(crate) fn wait_for_reload(r: &mut OffscreenRenderer, live: &mut LiveReload) -> ReloadReport {
    let start = Instant::now();
    loop {
        let report = r.poll_reload(live);
        if !report.applied.is_empty() || !report.errors.is_empty() || start.elapsed() > Duration::from_secs(5) {
            return report;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

pub(crate) fn edit(path: &Path, from: &str, to: &str) {
    let text = std::fs::read_to_string(path).unwrap();
    assert!(text.contains(from), "{from} not in {}", path.display());
    std::fs::write(path, text.replacen(from, to, 1)).unwrap();
}

#[test]
fn a_broken_shader_keeps_the_last_good_image_and_the_fix_applies() {
    let root = sandbox("shader");
    let (mut r, mut live) = renderer(&root);
    let golden = common::golden_in(concat!(env!("CARGO_MANIFEST_DIR"), "/src/techniques/kleinian/golden"), 0.01, 0.3);
    golden.check("kleinian_classic_f0000", (256, 256), &shown(&mut r).rgba).unwrap();

    let shader = root.join("shaders/kleinian.wgsl");
    edit(&shader, "    var z = start;", "    var z = start +;");
    let line = std::fs::read_to_string(&shader).unwrap().lines().position(|l| l.contains("start +;")).unwrap() + 1;
    let report = wait_for_reload(&mut r, &mut live);
    assert_eq!(report.errors.len(), 1, "{report:?}");
    assert!(report.errors[0].contains(&format!("kleinian.wgsl:{line}:")), "{}", report.errors[0]);
    golden.check("kleinian_classic_f0000", (256, 256), &shown(&mut r).rgba).expect("the last good shader still runs");

    // Saving the same mistake again is not reported twice.
    std::fs::write(&shader, std::fs::read_to_string(&shader).unwrap()).unwrap();
    std::thread::sleep(Duration::from_millis(300));
    assert!(r.poll_reload(&mut live).errors.is_empty());

    // The fix swaps hit and background colours: the image must equal the old shader with the
    // colours swapped by parameters.
    edit(&shader, "    var z = start +;", "    var z = start;");
    edit(
        &shader,
        "select(params.back_color, params.hit_color, hit)",
        "select(params.hit_color, params.back_color, hit)",
    );
    let report = wait_for_reload(&mut r, &mut live);
    assert_eq!((report.applied.len(), report.fixed.len()), (1, 1), "{report:?}");
    let swapped = shown(&mut r);
    let mut reference = load_scene(&common::assets(), "kleinian_classic").unwrap();
    reference.set_from_str("limit_set.hit_color=0.5,0.5,0.5").unwrap();
    reference.set_from_str("limit_set.back_color=1,0,0").unwrap();
    assert!(swapped.rgba == common::render_scene(reference, (256, 256), 0).rgba, "the fixed shader is live");
    std::fs::remove_dir_all(root).unwrap();
}

#[test]
fn a_shader_edit_that_moves_a_binding_is_a_located_error_and_the_show_goes_on() {
    let root = sandbox("binding");
    let (mut r, mut live) = renderer(&root);
    let before = shown(&mut r);
    let shader = root.join("shaders/kleinian.wgsl");
    edit(&shader, "@group(0) @binding(1) var output", "@group(0) @binding(3) var output");
    let line = std::fs::read_to_string(&shader).unwrap().lines().position(|l| l.contains("var output")).unwrap() + 1;
    let report = wait_for_reload(&mut r, &mut live);
    assert_eq!(report.errors.len(), 1, "{report:?}");
    let e = &report.errors[0];
    assert!(
        e.contains(&format!("kleinian.wgsl:{line}:")) && e.contains("'output'") && e.contains("@binding(1)"),
        "{e}"
    );
    assert!(shown(&mut r).rgba == before.rgba, "the last good shader still runs");
    std::fs::remove_dir_all(root).unwrap();
}

#[test]
fn a_broken_scene_keeps_running_and_the_fix_applies() {
    let root = sandbox("scene");
    let (mut r, mut live) = renderer(&root);
    let before = shown(&mut r);
    let scene = root.join("scenes/kleinian_classic.ron");
    edit(&scene, "\"scale\": 2.4,", "\"scale\": 2.4,,");
    let report = wait_for_reload(&mut r, &mut live);
    assert_eq!(report.errors.len(), 1, "{report:?}");
    assert!(report.errors[0].contains("kleinian_classic.ron:"), "{}", report.errors[0]);
    assert!(shown(&mut r).rgba == before.rgba, "the running scene is untouched");

    edit(&scene, "\"scale\": 2.4,,", "\"scale\": 3.0,");
    let report = wait_for_reload(&mut r, &mut live);
    assert!(report.scene_changed && report.fixed.len() == 1, "{report:?}");
    let after = shown(&mut r);
    let mut reference = load_scene(&common::assets(), "kleinian_classic").unwrap();
    reference.set_from_str("limit_set.scale=3.0").unwrap();
    assert!(after.rgba == common::render_scene(reference, (256, 256), 0).rgba, "the edited default is live");
    std::fs::remove_dir_all(root).unwrap();
}

#[test]
fn a_file_broken_at_start_up_is_picked_up_when_fixed() {
    let root = sandbox("startup");
    let (mut r, mut live) = renderer(&root);
    let shader = root.join("shaders/kleinian.wgsl");
    live.mark_broken(shader.clone(), "broken at start-up".into());
    std::fs::write(&shader, std::fs::read_to_string(&shader).unwrap() + "\n// fixed\n").unwrap();
    let report = wait_for_reload(&mut r, &mut live);
    assert_eq!(report.fixed, [shader.display().to_string()]);
    assert_eq!(live.broken().count(), 0);
    std::fs::remove_dir_all(root).unwrap();
}

#[test]
fn an_atomic_save_by_rename_is_picked_up() {
    // Editors often write a temporary file and rename it over the original.
    let root = sandbox("rename");
    let (mut r, mut live) = renderer(&root);
    let before = shown(&mut r);
    let scene = root.join("scenes/kleinian_classic.ron");
    let temp = root.join("scenes/.kleinian_classic.ron.tmp");
    std::fs::write(&temp, std::fs::read_to_string(&scene).unwrap().replace("\"scale\": 2.4,", "\"scale\": 2.0,"))
        .unwrap();
    std::fs::rename(&temp, &scene).unwrap();
    let report = wait_for_reload(&mut r, &mut live);
    assert!(report.scene_changed, "{report:?}");
    assert!(shown(&mut r).rgba != before.rgba);
    std::fs::remove_dir_all(root).unwrap();
}

const TWO_NODES: &str = r#"(
    name: "show",
    size: (64, 64),
    nodes: [
        (id: "k", technique: "kleinian"),
        (id: "glow", technique: "star_glow", inputs: { "source": "k" }),
    ],
    output: "glow",
)"#;

/// The edit drops `glow` and puts a new node before `k`, so `k` moves from index 0 to 1.
const EDITED: &str = r#"(
    name: "show",
    size: (64, 64),
    nodes: [(id: "extra", technique: "kleinian"), (id: "k", technique: "kleinian")],
    output: "k",
)"#;

fn write(node: usize, param: usize, value: ParamValue) -> ControlEvent {
    ControlEvent::Write(ParamWrite { node, param, component: None, value, source: Source::Ui })
}

#[test]
fn a_reload_that_drops_a_node_while_its_events_are_queued_learned_and_recorded() {
    let root = std::env::temp_dir().join(format!("indra-live-drop-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&root).unwrap();
    let path = root.join("show.ron");
    std::fs::write(&path, TWO_NODES).unwrap();
    let (gpu, assets) = (common::gpu(), common::assets());
    let scene = load_scene(&assets, path.to_str().unwrap()).unwrap();
    let (intensity, scale) =
        (scene.nodes[1].params.index("intensity").unwrap(), scene.nodes[0].params.index("scale").unwrap());
    let mut player = Player::new(SceneInstance::new(&gpu, &assets, scene, (64, 64)).unwrap(), FixedClock::new(0.02, 1));
    let options = ControlOptions {
        osc: None,
        midi: false,
        record: Some(root.join("controls.ron")),
        learn_file: root.join("midi-learn.ron"),
        presets_dir: root.join("presets"),
        ..Default::default()
    };
    let mut hub = ControlHub::start(&options, player.instance().scene());
    // While the edit lands: glow's intensity is waiting for MIDI learn, queued, scheduled, and
    // the recording is running.
    hub.learn(Target { node: 1, param: intensity, component: None });
    let mut queued = vec![write(1, intensity, ParamValue::Float(2.0)), write(0, scale, ParamValue::Float(3.0))];
    player.schedule(5, vec![write(1, intensity, ParamValue::Float(1.0))]);
    hub.record(0, &queued, player.instance().scene());

    std::fs::write(&path, EDITED).unwrap();
    let mut live = LiveReload::new(&Assets::new(Some(root.clone()))).unwrap();
    let report = live.apply(std::slice::from_ref(&path), &mut player, &gpu, (64, 64));
    assert!(report.errors.is_empty() && report.scene_changed, "{report:?}");
    let remap = report.remap.expect("a replaced scene comes with its remap");

    // Queued: glow's write is dropped, k's follows k to index 1.
    assert_eq!(remap.events(&mut queued), 1);
    assert_eq!(queued, [write(1, scale, ParamValue::Float(3.0))]);
    hub.set_scene(player.instance().scene(), Some(&remap));
    assert_eq!(hub.mapper.learning, None, "learn waits for a parameter that is gone: it stops");
    // Recording goes on with the new positions; a stale position is left out, never a panic.
    hub.record(1, &queued, player.instance().scene());
    hub.record(2, &[write(7, 3, ParamValue::Float(1.0))], player.instance().scene());
    player.apply(&queued);
    for _ in 0..8 {
        player.step(); // frame 5's scheduled write was dropped with its node
    }
    let k = player.instance().params(1);
    assert_eq!(k.target_at(scale), ParamValue::Float(3.0), "the remapped write reached k at its new index");
    // The recording replaces controls.ron when it finishes (the hub, and its recorder, end).
    drop(hub);
    let recorded = std::fs::read_to_string(root.join("controls.ron")).unwrap();
    let lines: Vec<&str> = recorded.lines().collect();
    assert_eq!(lines.len(), 3, "{recorded}");
    assert!(lines[2].contains("frame:1") && lines[2].contains("\"k\"") && lines[2].contains("scale"), "{}", lines[2]);
    std::fs::remove_dir_all(root).unwrap();
}

#[test]
fn a_shader_that_extends_another_reloads_live_and_its_errors_point_into_it() {
    let root = sandbox("extends");
    let assets = Assets::new(Some(root.clone()));
    let scene = load_scene(&assets, "tessellation_image").unwrap();
    let mut live = LiveReload::new(&assets).unwrap();
    let mut r = OffscreenRenderer::new(common::gpu(), &assets, scene, Some((96, 54)), None, None).unwrap();
    let green = |frame: &RenderedFrame| frame.rgba.chunks(4).filter(|p| p[1] > 200 && p[0] < 60 && p[2] < 60).count();
    assert_eq!(green(&shown(&mut r)), 0);

    // tessellation_raster.wgsl uses tessellation.wgsl's functions: alone it would not validate.
    let shader = root.join("shaders/tessellation_raster.wgsl");
    edit(&shader, "        var colour = u.background.rgb;", "        var colour = vec3<f32>(0.0, 1.0, 0.0);");
    let report = wait_for_reload(&mut r, &mut live);
    assert!(report.errors.is_empty() && !report.applied.is_empty(), "{report:?}");
    assert!(green(&shown(&mut r)) > 500, "the edited background shows");

    edit(&shader, "vec3<f32>(0.0, 1.0, 0.0);", "vec3<f32>(0.0, 1.0, true);");
    let line = std::fs::read_to_string(&shader).unwrap().lines().position(|l| l.contains("1.0, true")).unwrap() + 1;
    let report = wait_for_reload(&mut r, &mut live);
    assert_eq!(report.errors.len(), 1, "{report:?}");
    assert!(report.errors[0].contains(&format!("tessellation_raster.wgsl:{line}:")), "{}", report.errors[0]);
    assert!(green(&shown(&mut r)) > 500, "the last good shader still runs");
}

#[test]
fn an_edit_to_a_shared_base_is_checked_through_the_shaders_that_extend_it() {
    // splat_draw.wgsl holds the compute draw's entry points over hooks each technique's raster
    // shader defines: alone it is no whole shader, so reload validates it through them.
    let root = sandbox("base");
    let assets = Assets::new(Some(root.clone()));
    let mut live = LiveReload::new(&assets).unwrap();
    let scene = load_scene(&assets, "poisson_2d").unwrap();
    let size = (96, 64);
    let mut r = OffscreenRenderer::new(common::gpu(), &assets, scene, Some(size), None, None).unwrap();
    let as_shipped =
        |frame: u64| common::render_scene(load_scene(&common::assets(), "poisson_2d").unwrap(), size, frame).rgba;
    r.render_next().unwrap();

    let base = root.join("shaders/splat_draw.wgsl");
    let call = "resolve_shade(&r, splat_shade(r.key, r.centre));";
    edit(&base, call, "resolve_shade(&r, vec3<f32>(1.0) - splat_shade(r.key, r.centre));");
    let report = wait_for_reload(&mut r, &mut live);
    assert!(report.errors.is_empty() && !report.applied.is_empty(), "{report:?}");
    let inverted = r.render_next().unwrap();
    assert!(inverted.rgba != as_shipped(inverted.time.frame), "the edited base is live");

    // A hook no extender defines is an error located in the base; the show goes on.
    edit(&base, "vec3<f32>(1.0) - splat_shade(", "splat_shaded(");
    let line = std::fs::read_to_string(&base).unwrap().lines().position(|l| l.contains("splat_shaded(")).unwrap() + 1;
    let report = wait_for_reload(&mut r, &mut live);
    assert_eq!(report.errors.len(), 1, "{report:?}");
    assert!(report.errors[0].contains(&format!("splat_draw.wgsl:{line}:")), "{}", report.errors[0]);
    let still = r.render_next().unwrap();
    assert!(still.rgba != as_shipped(still.time.frame), "the last good base still runs");

    edit(&base, "splat_shaded(", "splat_shade(");
    let report = wait_for_reload(&mut r, &mut live);
    assert!(report.errors.is_empty() && !report.applied.is_empty(), "{report:?}");
    let fixed = r.render_next().unwrap();
    assert!(fixed.rgba == as_shipped(fixed.time.frame), "the shipped base again");
    std::fs::remove_dir_all(root).unwrap();
}
