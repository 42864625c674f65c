//! The cube field (chapter 4's demo scene): the cubes drawn in compute against the pipeline's
//! 12 triangles per cube. (Its goldens are StarGlow's, `star_glow/render_tests.rs`.)

use crate::common;

use indra::offscreen::OffscreenRenderer;
use indra::scene::load_scene;

/// A frame, its settings, its multisampling and its size.
type Comparison = (u64, &'static [&'static str], u32, (u32, u32));

#[test]
fn the_compute_draw_matches_the_pipeline() {
    // The book's field, its far end (the largest cubes, spinning fastest), one sample per pixel,
    // and cubes flying through the camera: cut open by the near plane (the inside shows), and
    // with corners behind the camera (the whole image is their box).
    let cases: &[Comparison] = &[
        (300, &[], 4, (203, 117)),
        (300, &["cubes.cube_size=1.0", "cubes.spin=720.0", "cubes.fov=120.0"], 4, (203, 117)),
        (240, &["cubes.cube_size=0.5"], 1, (331, 190)),
        (200, &["cubes.speed=10.0", "cubes.emitter_distance=12.0", "cubes.cube_size=0.4"], 4, (203, 117)),
    ];
    for (frame, sets, msaa, size) in cases {
        let [compute, pipeline] = ["compute", "pipeline"].map(|rasterizer| {
            let mut s = load_scene(&common::assets(), "star_glow").unwrap();
            s.msaa = *msaa;
            for set in *sets {
                s.set_from_str(set).unwrap();
            }
            s.set_from_str(&format!("cubes.rasterizer={rasterizer}")).unwrap();
            // The cubes alone: StarGlow would spread any difference over its streaks.
            s.set_from_str("glow.intensity=0.0").unwrap();
            let mut r = OffscreenRenderer::new(common::gpu(), &common::assets(), s, Some(*size), None, None).unwrap();
            r.seek(*frame).unwrap();
            r.render_next().unwrap().rgba
        });
        assert!(compute != pipeline, "{sets:?}: the two draws should be different code");
        let lit = compute.chunks(4).filter(|p| p[0] as u32 + p[1] as u32 + p[2] as u32 > 60).count();
        assert!(lit > 200, "{sets:?}: only {lit} lit pixels, nothing to compare");
        let (score, _) = indra::offscreen::flip_score(&pipeline, &compute, *size, 0.99);
        assert!(score.mean < 0.01, "{sets:?} msaa {msaa}: mean FLIP {} against the pipeline", score.mean);
    }
}
