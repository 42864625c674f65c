//! The gl-transitions library as show transitions: every bundled file compiles through the ISF
//! path, starts on the outgoing image and ends on the incoming one (within 1/255, except those
//! listed with why), and mixes the same way twice.

use crate::common::{assets, gpu};
use crate::show::{SIZE, mix, mixer_show};
use indra::scene::show::Mixer;

/// The gl-transitions built into the binary, as the paths a show names them by.
fn bundled() -> Vec<&'static str> {
    indra::assets::bundled_isf().map(|(p, _)| p).filter(|p| p.ends_with(".glsl")).collect()
}

/// Opaque texels in 0–1 (the range gl-transitions are written for).
fn image(seed: u32) -> Vec<[f32; 4]> {
    (0..SIZE.0 * SIZE.1)
        .map(|i| {
            let h = (i.wrapping_mul(2_654_435_761) ^ seed.wrapping_mul(40_503)) as f32 / u32::MAX as f32;
            let c = |k: u32| (h * (k as f32 + 1.7) * 9.31).fract();
            [c(0), c(1), c(2), 1.0]
        })
        .collect()
}

/// Transitions that do not start or end on their images, and why (checked: each still fails).
const NOT_AT_THEIR_ENDS: &[(&str, &str)] = &[
    ("AdvancedMosaic", "its mosaic cells are 0.005 of the width at both ends (10 px at 1920), never the image"),
    ("tangentMotionBlur", "its motion blur never reaches zero: both ends are blurred"),
];

#[test]
fn every_gl_transition_compiles_and_starts_and_ends_on_its_images() {
    let (gpu, assets) = (gpu(), assets());
    let names = bundled();
    assert_eq!(names.len(), 123, "the MIT transitions of gl-transitions 1.71.0");
    let (a, b) = (image(5), image(6));
    let mut failures = Vec::new();
    for name in names {
        let mut mixer = match Mixer::new(&gpu, &assets, &mixer_show(&[name])) {
            Ok(m) => m,
            Err(e) => {
                failures.push(format!("{name}: does not compile: {e}"));
                continue;
            }
        };
        let mut worst = [0.0f32; 2];
        for (k, (p, side)) in [(0.0, &a), (1.0, &b)].into_iter().enumerate() {
            let got = mix(&gpu, &mut mixer, 0, p, &a, &b);
            for (t, want) in got.iter().zip(side.iter()) {
                for c in 0..3 {
                    worst[k] = worst[k].max((t[c] - want[c]).abs());
                }
            }
        }
        let half = mix(&gpu, &mut mixer, 0, 0.5, &a, &b);
        if half != mix(&gpu, &mut mixer, 0, 0.5, &a, &b) {
            failures.push(format!("{name}: two mixes at 0.5 differ"));
        }
        let listed = NOT_AT_THEIR_ENDS.iter().any(|(n, _)| name.ends_with(&format!("/{n}.glsl")));
        let at_ends = worst.iter().all(|&w| w <= 1.0 / 255.0);
        if at_ends == listed {
            failures.push(format!("{name}: off by {:.4} at 0 and {:.4} at 1 (listed: {listed})", worst[0], worst[1]));
        }
    }
    assert!(failures.is_empty(), "{} of 123:\n{}", failures.len(), failures.join("\n"));
}

#[test]
fn a_show_plays_a_gl_transition_the_same_sought_and_golden_at_its_midpoint() {
    use indra::offscreen::OffscreenRenderer;
    use indra::params::{ControlEvent, ShowCommand};
    let text = r#"(
        name: "gl-transition", size: (160, 90), seed: 1,
        transition: (kind: "shaders/gl-transitions/directionalwarp.glsl", seconds: 1.0),
        layers: [(clips: [(scene: "kleinian_classic"), (scene: "tessellation_kleinian")])],
    )"#;
    let scene = indra::scene::show::parse_show(&assets(), "gl.ron", text, false).unwrap_or_else(|e| panic!("{e}"));
    let scripted = || {
        let mut r = OffscreenRenderer::new(gpu(), &assets(), scene.clone(), Some((160, 90)), None, None).unwrap();
        r.schedule(1, vec![ControlEvent::Show(ShowCommand::Trigger { layer: 0, clip: Some(1) })]);
        r
    };
    let mut played = scripted();
    let played: Vec<_> = (0..32).map(|_| played.render_next().unwrap()).collect();
    let mut sought = scripted();
    sought.seek(31).unwrap();
    assert!(sought.render_next().unwrap().rgba == played[31].rgba, "the midpoint sought differs from played");
    assert!(played[31].rgba != played[0].rgba, "the transition shows nothing new");
    let frame = &played[31];
    crate::common::golden(0.01, 0.3)
        .check("show_gl_transition_midpoint", frame.size, &frame.rgba)
        .unwrap_or_else(|e| panic!("{e}"));
}
