//! Chapter 2, Kleinian limit sets: golden renders of every scene at two times, determinism,
//! the limit set's own symmetries, and agreement with the CPU version of the algorithm.

use crate::common::{bright, render_named, render_text};
use indra::techniques::kleinian::reference::{in_limit_set, pixel_to_plane};

const SIZE: (u32, u32) = (256, 256);

fn check_golden(scene: &str, frame: u64) {
    let rendered = render_named(scene, SIZE, frame);
    crate::common::golden_beside(file!(), 0.01, 0.3)
        .check(&format!("{scene}_f{frame:04}"), SIZE, &rendered.rgba)
        .unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn golden_kleinian_at_two_times() {
    // Frame 0: t at (1.98795, 0.005859); frame 30 (0.5 s): halfway along the eased curve.
    check_golden("kleinian", 0);
    check_golden("kleinian", 30);
}

#[test]
fn golden_kleinian_circle_inversion_at_two_times() {
    // 0 s: inversion about the origin; 11 s: between the 9 s and 13 s keys of the clip.
    check_golden("kleinian_circle_inversion", 0);
    check_golden("kleinian_circle_inversion", 660);
}

#[test]
fn golden_kleinian_classic_is_static() {
    check_golden("kleinian_classic", 0);
    check_golden("kleinian_classic", 120);
}

#[test]
fn same_scene_seed_and_frame_give_identical_bytes() {
    let a = render_named("kleinian_circle_inversion", SIZE, 300);
    let b = render_named("kleinian_circle_inversion", SIZE, 300);
    assert!(a.rgba == b.rgba, "two renders of frame 300 differ");
    let other = render_named("kleinian_circle_inversion", SIZE, 301);
    assert!(a.rgba != other.rgba, "the animation should change the image between frames");
}

/// t = (2, 0), one centred sample, white hits on black, x ∈ [-1, 3], y ∈ [0, 2] at 128 px/unit.
const CLASSIC_BINARY: &str = r#"(
    name: "classic binary", size: (512, 256),
    nodes: [(id: "k", technique: "kleinian", params: {
        "t": (2.0, 0.0), "iterations": 200, "scale": 2.0, "offset": (-1.0, 0.0), "samples": 1,
        "hit_color": (1.0, 1.0, 1.0), "back_color": (0.0, 0.0, 0.0),
    })],
    output: "k",
)"#;

fn agreement(pairs: impl Iterator<Item = (bool, bool)>) -> f64 {
    let (mut same, mut total) = (0u32, 0u32);
    for (a, b) in pairs {
        same += u32::from(a == b);
        total += 1;
    }
    f64::from(same) / f64::from(total)
}

#[test]
fn classic_limit_set_is_periodic_with_period_two() {
    let f = render_text(CLASSIC_BINARY, (512, 256));
    // One period (2 units) is exactly 256 px: column x and x + 256 see the same set.
    let same = agreement(
        (0..256).flat_map(|y| (0..256).map(move |x| (x, y))).map(|(x, y)| (bright(&f, x, y), bright(&f, x + 256, y))),
    );
    assert!(same > 0.995, "only {:.4} of pixels agree one period apart", same);
}

#[test]
fn classic_limit_set_is_point_symmetric_about_minus_v_over_2_u_over_2() {
    let f = render_text(CLASSIC_BINARY, (512, 256));
    // z → (−v, u) − z = (0, 2) − z maps pixel (x, y) to (255 − x, 255 − y) in this framing.
    let same = agreement(
        (0..256)
            .flat_map(|y| (0..256).map(move |x| (x, y)))
            .map(|(x, y)| (bright(&f, x, y), bright(&f, 255 - x, 255 - y))),
    );
    assert!(same > 0.995, "only {:.4} of pixels agree under the point reflection", same);
}

#[test]
fn nothing_outside_the_strip_and_something_inside() {
    // y ∈ [-1, 3] over 256 rows: 64 rows per unit. The strip 0 ≤ y ≤ 2 is rows 64..192.
    let src =
        CLASSIC_BINARY.replace("\"scale\": 2.0, \"offset\": (-1.0, 0.0)", "\"scale\": 4.0, \"offset\": (-1.0, -1.0)");
    let f = render_text(&src, (256, 256));
    let hits_in_rows = |rows: std::ops::Range<u32>| {
        rows.flat_map(|y| (0..256).map(move |x| (x, y))).filter(|&(x, y)| bright(&f, x, y)).count()
    };
    assert_eq!(hits_in_rows(0..63), 0, "hits above y = 2");
    assert_eq!(hits_in_rows(193..256), 0, "hits below y = 0");
    let inside = hits_in_rows(64..192) as f64 / (128.0 * 256.0);
    assert!((0.05..0.6).contains(&inside), "hit fraction inside the strip is {inside:.3}");
}

#[test]
fn gpu_agrees_with_the_cpu_algorithm() {
    for (t, scale) in [([2.0f32, 0.0f32], 2.0f32), ([1.94, 0.02], 1.9)] {
        let src = CLASSIC_BINARY
            .replace("\"t\": (2.0, 0.0)", &format!("\"t\": ({}, {})", t[0], t[1]))
            .replace("\"scale\": 2.0, \"offset\": (-1.0, 0.0)", &format!("\"scale\": {scale}, \"offset\": (0.0, 0.0)"))
            .replace("\"iterations\": 200", "\"iterations\": 50");
        let f = render_text(&src, SIZE);
        let same = agreement((0..SIZE.1).flat_map(|y| (0..SIZE.0).map(move |x| (x, y))).map(|(x, y)| {
            let p = pixel_to_plane(x, y, SIZE.1, scale, [0.0, 0.0]);
            (bright(&f, x, y), in_limit_set(p, t, 50))
        }));
        assert!(same > 0.995, "t = {t:?}: GPU and CPU agree on only {same:.4} of pixels");
    }
}

#[test]
fn the_separation_band_changes_no_pixel() {
    // Step 3 skips Leys' separation line (and its exp) outside the band u/2 ± |bend| the line
    // cannot leave. A copy of the shader that always evaluates the line must give the same
    // bytes: at the book's t, at the classic set (bend 0), at an exponent that grows instead
    // of decaying (u < 1.47: no band), and at the far ends of t's range.
    use indra::assets::{Asset, AssetKind};
    use indra::offscreen::OffscreenRenderer;
    use indra::scene::parse_scene;
    let assets = crate::common::assets();
    let shader = assets.load(AssetKind::Shader, "kleinian.wgsl").unwrap();
    let band = "let bounded = decay <= 0.0;";
    assert!(shader.source.contains(band), "the band moved");
    let always = assets.with_shader(Asset { source: shader.source.replace(band, "let bounded = false;"), ..shader });
    for t in [[1.98795f32, 0.005859f32], [1.94, 0.02], [2.0, 0.0], [1.3, 0.4], [2.5, -2.5], [2.5, 2.5], [1.9, -0.3]] {
        let src = CLASSIC_BINARY
            .replace("\"t\": (2.0, 0.0)", &format!("\"t\": ({}, {})", t[0], t[1]))
            .replace("\"samples\": 1", "\"samples\": 4");
        let [banded, exact] = [&assets, &always].map(|assets| {
            let scene = parse_scene("band test", &src).unwrap();
            let mut r =
                OffscreenRenderer::new(crate::common::gpu(), assets, scene, Some((160, 96)), None, None).unwrap();
            r.render_next().unwrap().rgba
        });
        assert!(banded == exact, "t = {t:?}: the band changed the image");
        assert!(banded.chunks(4).any(|p| p[0] > 128) || t[0] < 1.5, "t = {t:?}: nothing drawn, nothing tested");
    }
}

#[test]
fn adaptive_sampling_holds_the_image_at_odd_sizes() {
    // Adaptive sampling takes the samples only where a pixel's 4 × 4 neighbourhood of corners
    // is not all one class. Against every pixel sampled: the pixels it samples are the same
    // bytes, the rest are the pure colours, and what it can miss (a feature slipping between
    // all 16 corners and past the first sample) stays rare. Sizes that are no multiple of the
    // 32-corner words or the 8 × 8 workgroups check the packing and the margin.
    let full_sampled = CLASSIC_BINARY.replace("\"t\": (2.0, 0.0)", "\"t\": (1.98795, 0.005859)").replace(
        "\"iterations\": 200, \"scale\": 2.0, \"offset\": (-1.0, 0.0), \"samples\": 1",
        "\"iterations\": 200, \"scale\": 1.9, \"offset\": (0.0, 0.0), \"samples\": 10, \"adaptive\": false",
    );
    assert!(full_sampled.contains("\"adaptive\": false"), "the template moved");
    let adaptive = full_sampled.replace("\"adaptive\": false", "\"adaptive\": true");
    for size in [(256, 256), (97, 61), (30, 41), (291, 37)] {
        let [every, edges] = [&full_sampled, &adaptive].map(|src| render_text(src, size));
        let pixels = every.rgba.chunks(4).zip(edges.rgba.chunks(4));
        let (mut same, mut mixed_every, mut mixed_edges) = (0usize, 0usize, 0usize);
        for (a, b) in pixels {
            same += usize::from(a == b);
            mixed_every += usize::from(a[0] != 0 && a[0] != 255);
            mixed_edges += usize::from(b[0] != 0 && b[0] != 255);
        }
        let total = (size.0 * size.1) as usize;
        let differ = total - same;
        assert!(differ * 100 <= total, "{size:?}: {differ} of {total} pixels differ");
        assert!(mixed_every > 0, "{size:?}: no edge in the picture, nothing tested");
        assert!(mixed_edges * 10 >= mixed_every * 9, "{size:?}: {mixed_edges} of {mixed_every} edge pixels kept");
        // FLIP spreads one pixel's change over its neighbours: only a picture of some size says
        // what a viewer would see.
        if size.0 >= 128 && size.1 >= 128 {
            let (score, _) = indra::offscreen::flip_score(&every.rgba, &edges.rgba, (size.0, size.1), 0.99);
            assert!(score.mean < 0.005, "{size:?}: mean FLIP {}", score.mean);
        }
    }
}
