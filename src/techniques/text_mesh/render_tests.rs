//! Glyph-outline scene: golden render of the default text, and a new text sent as an OSC string
//! (`/indra/text/text`, routed by the real router) re-meshes the next frame.

use crate::common;

use indra::control::osc::OscReceiver;
use indra::control::osc_route::{OscRouter, Routed};
use indra::offscreen::OffscreenRenderer;
use indra::scene::load_scene;
use rosc::{OscMessage, OscType};

const SIZE: (u32, u32) = (320, 180);

#[test]
fn golden_text_and_a_new_text_over_osc() {
    let scene = load_scene(&common::assets(), "text_mesh").unwrap();
    let rx = OscReceiver::bind("127.0.0.1:0").unwrap();
    let message = OscMessage { addr: "/indra/text/text".into(), args: vec![OscType::String("BPM 128".into())] };
    let Some(Routed::Event(event)) = OscRouter::new(&scene).route(&message, &scene, &rx) else {
        panic!("the text message did not route");
    };
    let mut r = OffscreenRenderer::new(common::gpu(), &common::assets(), scene, Some(SIZE), None, None).unwrap();
    r.schedule(1, vec![event]);
    let before = r.render_next().unwrap();
    let after = r.render_next().unwrap();
    common::golden_beside(file!(), 0.01, 0.3)
        .check("text_mesh_default", SIZE, &before.rgba)
        .unwrap_or_else(|e| panic!("{e}"));
    common::golden_beside(file!(), 0.01, 0.3)
        .check("text_mesh_osc", SIZE, &after.rgba)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(before.rgba != after.rgba);
}
