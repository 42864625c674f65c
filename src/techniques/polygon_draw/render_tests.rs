//! Chapter 5 drawing scene: the book's nested shapes, and a drawing made only of OSC messages
//! (`/indra/draw/cursor`, `/add`, `/close`, `/undo`, `/clear`, routed by the real router) —
//! a square with a square hole and a triangle island in the hole — checked by golden renders and
//! by pixels: fill where the polygon is, black in the hole, the island filled, gone after undo.

use crate::common;

use indra::control::osc::OscReceiver;
use indra::control::osc_route::{OscRouter, Routed};
use indra::offscreen::{OffscreenRenderer, RenderedFrame};
use indra::params::ParamValue;
use indra::scene::{ControlEvent, Scene, load_scene};
use rosc::{OscMessage, OscType};

const SIZE: (u32, u32) = (320, 180);

fn scene() -> Scene {
    load_scene(&common::assets(), "polygon_draw").unwrap()
}

/// The events one OSC message becomes.
fn osc(scene: &Scene, rx: &OscReceiver, addr: &str, args: Vec<OscType>) -> Vec<ControlEvent> {
    let router = OscRouter::new(scene);
    match router.route(&OscMessage { addr: addr.into(), args }, scene, rx) {
        Some(Routed::Event(e)) => vec![e],
        other => panic!("{addr} routed to {other:?}"),
    }
}

fn lit(frame: &RenderedFrame, x: f32, y: f32) -> bool {
    // (x, y) in view units, y up.
    let px = (x * SIZE.0 as f32) as u32;
    let py = ((1.0 - y) * SIZE.1 as f32) as u32;
    let i = ((py * SIZE.0 + px) * 4) as usize;
    frame.rgba[i..i + 3].iter().map(|&c| u32::from(c)).sum::<u32>() > 30
}

#[test]
fn golden_book_nested_shapes() {
    let frame = common::render_scene(scene(), SIZE, 0);
    common::golden_beside(file!(), 0.01, 0.3)
        .check("polygon_draw_book", SIZE, &frame.rgba)
        .unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn drawing_over_osc_makes_holes_and_islands() {
    let scene = scene();
    let rx = OscReceiver::bind("127.0.0.1:0").unwrap();
    let mut script: Vec<Vec<ControlEvent>> = vec![osc(&scene, &rx, "/indra/draw/clear", vec![])];
    let mut polygon = |points: &[[f32; 2]]| {
        for p in points {
            let mut e = osc(&scene, &rx, "/indra/draw/cursor", vec![OscType::Float(p[0]), OscType::Float(p[1])]);
            e.extend(osc(&scene, &rx, "/indra/draw/add", vec![]));
            script.push(e);
        }
        script.push(osc(&scene, &rx, "/indra/draw/close", vec![]));
    };
    polygon(&[[0.2, 0.1], [0.8, 0.1], [0.8, 0.9], [0.2, 0.9]]);
    polygon(&[[0.35, 0.3], [0.35, 0.7], [0.65, 0.7], [0.65, 0.3]]);
    polygon(&[[0.45, 0.4], [0.55, 0.4], [0.5, 0.6]]);
    // Start an open loop (drawn, not filled) to the right.
    for p in [[0.85, 0.2], [0.95, 0.5]] {
        let mut e = osc(&scene, &rx, "/indra/draw/cursor", vec![OscType::Float(p[0]), OscType::Float(p[1])]);
        e.extend(osc(&scene, &rx, "/indra/draw/add", vec![]));
        script.push(e);
    }
    script.push(osc(&scene, &rx, "/indra/draw/undo", vec![]));

    let mut r = OffscreenRenderer::new(common::gpu(), &common::assets(), scene, Some(SIZE), None, None).unwrap();
    let undo_frame = script.len() as u64 - 1;
    for (frame, events) in script.into_iter().enumerate() {
        r.schedule(frame as u64, events);
    }
    let frames: Vec<RenderedFrame> = (0..=undo_frame).map(|_| r.render_next().unwrap()).collect();
    let drawn = &frames[undo_frame as usize - 1];
    common::golden_beside(file!(), 0.01, 0.3)
        .check("polygon_draw_osc", SIZE, &drawn.rgba)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(lit(drawn, 0.27, 0.5), "outer fill");
    assert!(!lit(drawn, 0.4, 0.62), "inside the hole");
    assert!(lit(drawn, 0.5, 0.47), "island");
    assert!(!lit(drawn, 0.1, 0.5), "outside everything");
    // Undo removes the island only.
    let undone = &frames[undo_frame as usize];
    assert!(!lit(undone, 0.5, 0.47), "island after undo");
    assert!(lit(undone, 0.27, 0.5), "outer fill after undo");
}

#[test]
fn mouse_and_keys_come_from_the_declared_roles() {
    let gpu = common::gpu();
    let scene = load_scene(&common::assets(), "polygon_draw").unwrap();
    let instance = indra::scene::SceneInstance::new(&gpu, &common::assets(), scene, SIZE).unwrap();
    let params = instance.params(0);
    let written = |events: Vec<ControlEvent>| -> Vec<(String, ParamValue)> {
        events
            .into_iter()
            .map(|e| match e {
                ControlEvent::Write(w) => (params.decls()[w.param].name.clone(), w.value),
                other => panic!("{other:?}"),
            })
            .collect()
    };
    let click = written(instance.pointer([0.25, 0.75], true, indra::params::Source::Ui));
    assert_eq!(
        click,
        [("cursor".to_string(), ParamValue::Vec2([0.25, 0.75])), ("add".to_string(), ParamValue::Trigger(true))]
    );
    let right = written(instance.pointer([0.5, 0.5], false, indra::params::Source::Ui));
    assert_eq!(right[1], ("close".to_string(), ParamValue::Trigger(true)));
    assert_eq!(
        written(instance.key('U', indra::params::Source::Ui)),
        [("undo".to_string(), ParamValue::Trigger(true))]
    );
    assert!(instance.key('x', indra::params::Source::Ui).is_empty(), "an undeclared key does nothing");
}
