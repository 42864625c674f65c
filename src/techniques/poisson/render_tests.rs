//! Chapter 7 scenes: golden renders of the growing 2-D and 3-D sets, seeking equals playing, and
//! a live radius change restarts the run exactly like a scene that starts with that radius.
//! (The sampler's own invariants — minimum distance, maximality, coverage, the annulus law — are
//! tested in `src/geometry/poisson.rs`.)

use crate::common;

use indra::offscreen::OffscreenRenderer;
use indra::params::{ParamValue, ParamWrite, Source};
use indra::scene::{ControlEvent, load_scene};

const SIZE: (u32, u32) = (256, 144);

fn renderer(scene: &str, sets: &[&str]) -> OffscreenRenderer {
    let mut s = load_scene(&common::assets(), scene).unwrap();
    for set in sets {
        s.set_from_str(set).unwrap();
    }
    OffscreenRenderer::new(common::gpu(), &common::assets(), s, Some(SIZE), None, None).unwrap()
}

fn play(r: &mut OffscreenRenderer, frames: u64) -> Vec<u8> {
    (0..frames).map(|_| r.render_next().unwrap().rgba).last().unwrap()
}

#[test]
fn golden_poisson_2d_growing_and_complete() {
    let mut r = renderer("poisson_2d", &[]);
    for (frames, name) in [(120, "poisson_2d_f0119"), (880, "poisson_2d_f0999")] {
        let rgba = play(&mut r, frames);
        common::golden_beside(file!(), 0.01, 0.3).check(name, SIZE, &rgba).unwrap_or_else(|e| panic!("{e}"));
    }
}

#[test]
fn golden_poisson_3d_growing() {
    let mut r = renderer("poisson_3d", &[]);
    let rgba = play(&mut r, 400);
    common::golden_beside(file!(), 0.01, 0.3).check("poisson_3d_f0399", SIZE, &rgba).unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn seeking_renders_what_playing_renders() {
    let played = play(&mut renderer("poisson_2d", &[]), 91);
    let mut seeker = renderer("poisson_2d", &[]);
    seeker.seek(90).unwrap();
    let sought = seeker.render_next().unwrap().rgba;
    assert!(played == sought, "frame 90 differs between playing and seeking");
    // And the set really grew in between (not a blank image twice).
    let early = play(&mut renderer("poisson_2d", &[]), 2);
    let lit = |rgba: &[u8]| rgba.chunks(4).filter(|p| p[0] as u32 + p[1] as u32 + p[2] as u32 > 60).count();
    assert!(lit(&played) > 20 * lit(&early).max(1), "{} vs {}", lit(&played), lit(&early));
}

#[test]
fn a_live_radius_change_restarts_the_run() {
    // Frame 50 changes the radius to 8; 40 frames later the image equals that of a scene that
    // started with radius 8 and played 40 frames.
    let mut live = renderer("poisson_2d", &[]);
    let node = 0;
    let param = live.instance_mut().params(node).index("radius").unwrap();
    live.schedule(
        50,
        vec![ControlEvent::Write(ParamWrite {
            node,
            param,
            component: None,
            value: ParamValue::Float(8.0),
            source: Source::Osc,
        })],
    );
    let changed = play(&mut live, 90);
    let fresh = play(&mut renderer("poisson_2d", &["poisson.radius=8"]), 40);
    assert!(changed == fresh, "a restarted run differs from a fresh one");
}

/// A scene, its frame, its settings, its multisampling and its size.
type Comparison = (&'static str, u64, &'static [&'static str], u32, (u32, u32));

#[test]
fn the_compute_draw_matches_the_pipeline() {
    // The discs drawn in compute against the instanced quads through the hardware rasterizer:
    // discs that overlap (draw scale 2: the first drawn wins a tie of depths, as the pipeline's
    // depth test keeps it), spheres that hide each other, one sample per pixel, discs large
    // enough for the workgroup kernel (odd size, 4 px to 60 px across) and tiny ones.
    let cases: &[Comparison] = &[
        ("poisson_2d", 150, &[], 4, (203, 117)),
        ("poisson_2d", 150, &["poisson.draw_scale=2.0"], 4, (203, 117)),
        ("poisson_2d", 60, &["poisson.draw_scale=2.0", "poisson.radius=30.0"], 4, (331, 190)),
        ("poisson_2d", 150, &["poisson.draw_scale=0.3"], 1, (203, 117)),
        ("poisson_3d", 120, &["poisson.draw_scale=2.0"], 4, (203, 117)),
        ("poisson_3d", 120, &[], 1, (331, 190)),
    ];
    for (scene, frame, sets, msaa, size) in cases {
        let [compute, pipeline] = ["compute", "pipeline"].map(|rasterizer| {
            let mut s = load_scene(&common::assets(), scene).unwrap();
            s.msaa = *msaa;
            for set in *sets {
                s.set_from_str(set).unwrap();
            }
            s.set_from_str(&format!("poisson.rasterizer={rasterizer}")).unwrap();
            let mut r = OffscreenRenderer::new(common::gpu(), &common::assets(), s, Some(*size), None, None).unwrap();
            r.seek(*frame).unwrap();
            r.render_next().unwrap().rgba
        });
        let lit = compute.chunks(4).filter(|p| p[0] as u32 + p[1] as u32 + p[2] as u32 > 60).count();
        assert!(lit > 50, "{scene} {sets:?}: only {lit} lit pixels, nothing to compare");
        let (score, _) = indra::offscreen::flip_score(&pipeline, &compute, *size, 0.99);
        assert!(score.mean < 0.005, "{scene} {sets:?} msaa {msaa}: mean FLIP {} against the pipeline", score.mean);
    }
}
