//! Multisampling of the rasterising nodes: at the scene's default 4 samples the image is much
//! closer to a 4×4 supersampled reference than at 1 sample (edges, and the rims of Poisson's
//! discs, are anti-aliased, not just different), `msaa: 1` turns it off, and a sample count other than 1, 2, 4 or 8 is a located
//! scene error.

use crate::common;

use indra::scene::load_scene;

fn srgb_to_linear(c: u8) -> f64 {
    let c = f64::from(c) / 255.0;
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

fn linear_to_srgb(c: f64) -> u8 {
    let c = if c <= 0.0031308 { c * 12.92 } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
    (c * 255.0).round().clamp(0.0, 255.0) as u8
}

/// `scene` (with `sets`) at frame `frame` and `size`, with `msaa` samples.
fn render((scene, sets): (&str, &[&str]), size: (u32, u32), frame: u64, msaa: u32) -> Vec<u8> {
    let mut s = load_scene(&common::assets(), scene).unwrap();
    for set in sets {
        s.set_from_str(set).unwrap();
    }
    s.msaa = msaa;
    common::render_scene(s, size, frame).rgba
}

/// A 4×4 box filter in linear light (what ideal coverage gives).
fn downsample(rgba: &[u8], size: (u32, u32), by: u32) -> Vec<u8> {
    let (w, h) = (size.0 / by, size.1 / by);
    let mut out = Vec::with_capacity((w * h * 4) as usize);
    for y in 0..h {
        for x in 0..w {
            for c in 0..4 {
                let mut sum = 0.0;
                for dy in 0..by {
                    for dx in 0..by {
                        let i = (((y * by + dy) * size.0 + x * by + dx) * 4 + c) as usize;
                        sum += if c == 3 { f64::from(rgba[i]) / 255.0 } else { srgb_to_linear(rgba[i]) };
                    }
                }
                let mean = sum / f64::from(by * by);
                out.push(if c == 3 { (mean * 255.0).round() as u8 } else { linear_to_srgb(mean) });
            }
        }
    }
    out
}

#[test]
fn four_samples_come_close_to_supersampling_and_one_does_not() {
    // Triangle edges: the cloth's silhouette, the cubes of the StarGlow scene (without the glow,
    // whose kernels are sized in pixels); and edges cut in the fragment shader, the rims of
    // Poisson's discs and spheres (covered per sample: a discard alone left them as stair-stepped
    // as one sample). Lines are a pixel wide at any size, so they do not compare this way.
    let size = (96, 64);
    let cases: [((&str, &[&str]), u64); 4] = [
        (("cloth", &[]), 30),
        (("star_glow", &["glow.intensity=0"]), 0),
        (("poisson_2d", &[]), 40),
        (("poisson_3d", &[]), 40),
    ];
    for (scene, frame) in cases {
        let reference = downsample(&render(scene, (size.0 * 4, size.1 * 4), frame, 1), (size.0 * 4, size.1 * 4), 4);
        let error =
            |msaa| indra::offscreen::flip_score(&reference, &render(scene, size, frame, msaa), size, 0.99).0.mean;
        let (one, four) = (error(1), error(4));
        let scene = scene.0;
        eprintln!("{scene}: FLIP against 4×4 supersampling — 1 sample {one:.4}, 4 samples {four:.4}");
        assert!(four < 0.7 * one, "{scene}: 4 samples ({four}) should be much closer to supersampling than 1 ({one})");
    }
}

#[test]
fn a_sample_count_other_than_1_2_4_or_8_is_a_located_error() {
    let ron = r#"(name: "m", size: (32, 32), msaa: 3,
        nodes: [(id: "k", technique: "kleinian")], output: "k")"#;
    let e = indra::scene::parse_scene("m.ron", ron).expect_err("msaa 3 is refused").to_string();
    assert!(e.contains("msaa") && e.contains("1, 2, 4 or 8"), "{e}");
    let ok = indra::scene::parse_scene("m.ron", &ron.replace("msaa: 3", "msaa: 8")).unwrap();
    assert_eq!(ok.msaa, 8);
}
