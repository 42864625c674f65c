//! What a show's clips hold on the GPU, read from wgpu's own allocator report: the images and
//! buffers a clip draws through (multisampled targets, glow levels, intermediates, the compute
//! draws' visibility buffers) come from the frame graph's shared pools, so a clip off screen
//! holds none, and a layer of eight clips needs the transient memory of one.

use crate::common::{assets, gpu};
use indra::offscreen::OffscreenRenderer;
use indra::params::{ControlEvent, ShowCommand};
use indra::scene::show::parse_show;

/// The labels the frame graph gives the textures and buffers of its pools.
const POOLED: [&str; 2] = ["graph_transient", "graph_transient_buffer"];

/// One layer of `n` copies of the star_glow scene (cubes drawn multisampled in compute, through
/// a visibility buffer, then the glow's levels), cutting between them.
fn layer_of(n: usize) -> String {
    let clips: Vec<String> = (0..n).map(|i| format!(r#"(scene: "star_glow", id: "c{i}")"#)).collect();
    format!(
        r#"(name: "memory", size: (320, 180), seed: 1, transition: (kind: "cut"), layers: [(clips: [{}])])"#,
        clips.join(", ")
    )
}

/// Bytes of the pools' textures, of their buffers, and of everything else the device has
/// allocated.
fn allocated(renderer: &OffscreenRenderer) -> (u64, u64, u64) {
    let report = renderer.gpu().device.generate_allocator_report().expect("Vulkan reports its allocations");
    let labelled = |label: &str| report.allocations.iter().filter(|a| a.name == label).map(|a| a.size).sum::<u64>();
    let (textures, buffers) = (labelled(POOLED[0]), labelled(POOLED[1]));
    (textures, buffers, report.total_allocated_bytes - textures - buffers)
}

/// The show of `n` clips after playing each clip in turn for a few frames.
fn played(n: usize) -> (u64, u64, u64) {
    let scene = parse_show(&assets(), "memory.ron", &layer_of(n), false).unwrap_or_else(|e| panic!("{e}"));
    let mut renderer = OffscreenRenderer::new(gpu(), &assets(), scene, None, None, None).expect("show builds");
    for clip in 1..=n {
        let frame = renderer.next_frame();
        renderer.schedule(frame, vec![ControlEvent::Show(ShowCommand::Trigger { layer: 1, clip: Some(clip) })]);
        for _ in 0..3 {
            renderer.render_only().unwrap();
        }
    }
    allocated(&renderer)
}

#[test]
fn clips_off_screen_hold_no_transient_image() {
    let (one_textures, one_buffers, one_other) = played(1);
    let (eight_textures, eight_buffers, eight_other) = played(8);
    eprintln!(
        "pooled textures {one_textures} / {eight_textures}, buffers {one_buffers} / {eight_buffers} bytes, \
         the rest {one_other} / {eight_other} (1 / 8 clips)"
    );
    assert!(one_textures > 0, "the clip draws through pooled images");
    assert!(one_buffers > 0, "the clip's compute draw covers samples in a pooled visibility buffer");
    assert_eq!(eight_textures, one_textures, "eight clips played in turn share one clip's transient images");
    assert_eq!(eight_buffers, one_buffers, "and one clip's visibility buffer");
    // What each further clip keeps is its own state (uniforms, instances, a fresh copy's), far
    // less than the images and buffers it draws through.
    let one_pooled = one_textures + one_buffers;
    let per_clip = (eight_other - one_other) / 7;
    assert!(per_clip < one_pooled / 4, "each clip keeps {per_clip} bytes; the pools hold {one_pooled}");
}
