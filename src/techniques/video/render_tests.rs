//! Clips made by the local ffmpeg, through the whole engine: HAP, HAP Alpha and HAP Q on the GPU
//! (and the CPU fallback) against ffmpeg's own decode; a burnt-in frame counter through speed,
//! reverse, ping-pong, in/out points and scrubbing; seek = play and repeat renders for HAP and
//! H.264; a bad clip is a message and black, and a good one then plays; the demo scenes' goldens.

use crate::common::clips::{COUNTER_SIZE, clip_dir, counter_source, ffmpeg_frames, make_clip, read_counter};
use crate::common::{assets, golden_beside, gpu, read_float_texture};
use indra::assets::Assets;
use indra::gpu::Gpu;
use indra::graph::{FrameGraph, GraphRuntime};
use indra::offscreen::OffscreenRenderer;
use indra::params::ParamSet;
use indra::scene::{load_scene, parse_scene, parse_value_override};
use indra::techniques::video::{self, Video};
use indra::techniques::{NodeSetup, Technique};
use indra::time::FrameTime;

/// Assets that may open the test clips.
fn clip_assets() -> Assets {
    assets().allowing(clip_dir())
}

fn params(settings: &[(&str, &str)]) -> ParamSet {
    let mut params = ParamSet::new(video::Settings::decls());
    for (name, value) in settings {
        let i = params.index(name).unwrap();
        params.set_at(i, parse_value_override(value, &params.decls()[i]).unwrap());
    }
    params
}

/// One video node outside a scene: steps it through frame `last` and reads its linear,
/// premultiplied image back at each of `frames`.
struct Node {
    gpu: Gpu,
    node: Video,
    runtime: GraphRuntime,
    size: (u32, u32),
    frame: u64,
}

impl Node {
    fn new(size: (u32, u32), settings: &[(&str, &str)], allow_blocks: bool) -> Self {
        let gpu = gpu();
        let assets = clip_assets();
        let params = params(settings);
        let setup =
            NodeSetup { gpu: &gpu, assets: &assets, id: "clip", output_size: size, msaa: 1, params: &params, seed: 1 };
        let node = Video::new(&setup, allow_blocks).unwrap();
        let runtime = GraphRuntime::new(&gpu.device, &gpu.queue);
        Self { gpu, node, runtime, size, frame: 0 }
    }

    /// Steps to `frame` (25 steps a second) and renders it.
    fn render(&mut self, frame: u64, settings: &[(&str, &str)]) -> Vec<[f32; 4]> {
        let params = params(settings);
        let time = |frame: u64| FrameTime { frame, seconds: frame as f64 * 0.04, dt: 0.04, seed: 1 };
        while self.frame < frame {
            self.frame += 1;
            self.node.step(&params, &time(self.frame));
        }
        if frame == 0 {
            self.node.step(&params, &time(0));
        }
        let mut graph = FrameGraph::new(self.size);
        let output = self.node.add_passes(&mut graph, &params, &time(frame), &[]);
        graph.set_output(output);
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        let out = self.runtime.execute(&self.gpu.device, &self.gpu.queue, graph, &mut encoder).unwrap();
        self.gpu.queue.submit([encoder.finish()]);
        read_float_texture(&self.gpu, &out.texture)
    }
}

/// `base` with `changes` after it (later settings win).
fn with<'a>(base: &[(&'a str, &'a str)], changes: &[(&'a str, &'a str)]) -> Vec<(&'a str, &'a str)> {
    base.iter().chain(changes).copied().collect()
}

fn to_srgb8(linear: f32) -> u8 {
    let c = linear.clamp(0.0, 1.0);
    let encoded = if c <= 0.0031308 { c * 12.92 } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
    (encoded * 255.0).round() as u8
}

#[test]
fn hap_formats_on_the_gpu_and_the_cpu_fallback_match_ffmpegs_decode() {
    let size = (72, 40);
    let source = "testsrc=size=72x40:rate=25:duration=0.4,format=rgba,geq=r='r(X,Y)':g='g(X,Y)':b='b(X,Y)':a='X*255/W'";
    for (name, format) in [("gpu_hap.mov", "hap"), ("gpu_hap_alpha.mov", "hap_alpha"), ("gpu_hap_q.mov", "hap_q")] {
        let path = make_clip(name, source, &["-c:v", "hap", "-format", format]);
        let reference = &ffmpeg_frames(&path, size)[6];
        let file = path.display().to_string();
        let settings = [("file", file.as_str()), ("fit", "stretch"), ("playing", "false"), ("position", "0")];
        for allow_blocks in [true, false] {
            let mut node = Node::new(size, &settings, allow_blocks);
            // Frame 6 of 10 by scrubbing: 6/9 of the way from the first frame to the last.
            let scrub = with(&settings, &[("position", "0.6")]);
            let _ = node.render(1, &scrub);
            let image = node.render(2, &scrub);
            let mut worst = 0u8;
            let mut sum = 0u64;
            for (ours, theirs) in image.iter().zip(reference.chunks_exact(4)) {
                let alpha = (ours[3].clamp(0.0, 1.0) * 255.0).round() as u8;
                worst = worst.max(alpha.abs_diff(theirs[3]));
                if theirs[3] > 64 {
                    for c in 0..3 {
                        let d = to_srgb8(ours[c] / ours[3]).abs_diff(theirs[c]);
                        worst = worst.max(d);
                        sum += u64::from(d);
                    }
                }
            }
            let mean = sum as f64 / (3 * size.0 * size.1) as f64;
            assert!(
                mean < 1.5 && worst <= 12,
                "{format} (blocks on the GPU: {allow_blocks}): mean {mean:.2}, worst {worst} of 255"
            );
        }
    }
}

/// A scene playing `clip` at 64×16 with `settings`, 25 frames a second.
fn counter_scene(clip: &std::path::Path, settings: &str) -> indra::scene::Scene {
    let ron = format!(
        r#"(name: "counter", size: (64, 16), seed: 1, dt: 0.04,
            nodes: [(id: "clip", technique: "video", params: {{ "file": "{}", "fit": "stretch", {settings} }})],
            output: "clip")"#,
        clip.display()
    );
    parse_scene("counter.ron", &ron).unwrap()
}

/// The counter each of `count` frames from `start` shows.
fn counters(clip: &std::path::Path, settings: &str, start: u64, count: usize) -> Vec<usize> {
    let mut r = OffscreenRenderer::new(gpu(), &clip_assets(), counter_scene(clip, settings), None, None, None).unwrap();
    r.seek(start).unwrap();
    (0..count).map(|_| read_counter(&r.render_next().unwrap().rgba, 8)).collect()
}

#[test]
fn the_counter_shows_frame_n_through_speed_reverse_ping_pong_and_in_out_points() {
    let clip = make_clip("counter_play.mov", &counter_source(25, 2.0), &["-c:v", "hap"]);
    assert_eq!(counters(&clip, "", 0, 6), [0, 1, 2, 3, 4, 5]);
    assert_eq!(counters(&clip, r#""speed": 2.0"#, 0, 4), [0, 2, 4, 6]);
    assert_eq!(counters(&clip, r#""speed": -1.0"#, 0, 4), [49, 48, 47, 46], "speed −1 plays backwards from the end");
    assert_eq!(counters(&clip, r#""speed": 0.5"#, 0, 5), [0, 0, 1, 1, 2]);
    assert_eq!(
        counters(&clip, r#""loop_mode": "ping_pong", "in_point": 0.2, "out_point": 0.3"#, 0, 12),
        [10, 11, 12, 13, 14, 13, 12, 11, 10, 11, 12, 13],
        "ping-pong between the in point (frame 10) and the out point (frame 15)"
    );
    assert_eq!(
        counters(&clip, r#""loop_mode": "loop", "in_point": 0.9, "out_point": 1.0"#, 0, 7),
        [45, 46, 47, 48, 49, 45, 46]
    );
    assert_eq!(
        counters(&clip, r#""loop_mode": "once", "in_point": 0.9"#, 3, 4),
        [48, 49, 49, 49],
        "once holds the end"
    );
    assert_eq!(
        counters(&clip, r#""playing": false, "position": 0.5"#, 0, 3),
        [25, 25, 25],
        "paused at a scrubbed place"
    );
}

#[test]
fn scrubbing_and_restart_move_the_playhead_live() {
    let clip = make_clip("counter_scrub.mov", &counter_source(25, 2.0), &["-c:v", "hap"]);
    let file = clip.display().to_string();
    let base = [("file", file.as_str()), ("fit", "stretch")];
    let mut node = Node::new(COUNTER_SIZE, &base, true);
    let shown = |image: Vec<[f32; 4]>| {
        let rgba: Vec<u8> = image.iter().flat_map(|p| p.map(to_srgb8)).collect();
        read_counter(&rgba, 8)
    };
    assert_eq!(shown(node.render(0, &base)), 0);
    assert_eq!(shown(node.render(3, &base)), 3);
    // A controller moves the position: a jump, and play goes on from there.
    let scrubbed = with(&base, &[("position", "0.5")]);
    assert_eq!(shown(node.render(4, &scrubbed)), 25, "half of the 2 s clip");
    assert_eq!(shown(node.render(6, &scrubbed)), 27);
    let restart = with(&scrubbed, &[("restart", "true")]);
    assert_eq!(shown(node.render(7, &restart)), 0, "restart goes back to the in point");
    assert_eq!(shown(node.render(8, &scrubbed)), 1);
}

#[test]
fn seek_equals_play_and_two_renders_are_identical_for_hap_and_h264() {
    let source = counter_source(25, 4.0);
    let hap = make_clip("counter_seek.mov", &source, &["-c:v", "hap"]);
    let h264 = make_clip("counter_seek.mp4", &source, &["-c:v", "libx264", "-g", "25", "-pix_fmt", "yuv420p"]);
    for clip in [hap, h264] {
        let settings = r#""speed": 1.5, "loop_mode": "ping_pong""#;
        let render = |start: u64, count: usize| {
            let mut r = OffscreenRenderer::new(gpu(), &clip_assets(), counter_scene(&clip, settings), None, None, None)
                .unwrap();
            r.seek(start).unwrap();
            (0..count).map(|_| r.render_next().unwrap().rgba).collect::<Vec<_>>()
        };
        let played = render(0, 80);
        let sought = render(77, 3);
        assert_eq!(&played[77..80], &sought[..], "{}: frames 77–79 sought = played", clip.display());
        assert_eq!(render(0, 80), played, "{}: a second render is the same bytes", clip.display());
        // Frame 70 at 1.5×: 4.2 s of play in a 4 s clip that turns on its last frame (3.96 s),
        // so 0.24 s back from there: 3.72 s, frame 93.
        assert_eq!(read_counter(&played[70], 8), 93, "{}", clip.display());
    }
}

#[test]
fn a_bad_clip_is_one_message_and_black_and_a_good_one_then_plays() {
    let notes = clip_dir().join("not_a_clip.mov");
    std::fs::write(&notes, "a text file named like a clip").unwrap();
    let file = notes.display().to_string();
    let mut node = Node::new(COUNTER_SIZE, &[("file", &file)], true);
    let image = node.render(0, &[("file", &file)]);
    assert!(image.iter().all(|p| *p == [0.0; 4]), "black while there is no clip");
    let messages = node.node.take_messages();
    assert_eq!(messages.len(), 1, "{messages:?}");
    assert!(messages[0].contains("not_a_clip.mov") && messages[0].contains("not a video"), "{messages:?}");
    let missing = [("file", "no/such/clip.mov")];
    let _ = node.render(1, &missing);
    assert!(node.node.take_messages().iter().any(|m| m.contains("no file 'no/such/clip.mov'")));

    let good = make_clip("counter_recover.mov", &counter_source(25, 1.0), &["-c:v", "hap"]);
    let good = good.display().to_string();
    let _ = node.render(2, &[("file", &good), ("fit", "stretch")]);
    let image = node.render(3, &[("file", &good), ("fit", "stretch")]);
    let rgba: Vec<u8> = image.iter().flat_map(|p| p.map(to_srgb8)).collect();
    assert_eq!(read_counter(&rgba, 8), 1, "the new clip plays from its start");
}

#[test]
fn contain_and_cover_keep_the_clips_shape() {
    // A 64×16 clip (4:1) in a 32×32 image: contain leaves bars above and below, cover crops.
    let clip = make_clip("white.mov", "color=white:size=64x16:rate=25:duration=0.2", &["-c:v", "hap"]);
    let file = clip.display().to_string();
    for (fit, lit_rows) in [("contain", 12..20), ("cover", 0..32), ("stretch", 0..32)] {
        let settings = [("file", file.as_str()), ("fit", fit)];
        let image = Node::new((32, 32), &settings, true).render(0, &settings);
        for y in 0..32 {
            let lit = image[(y * 32 + 16) as usize][0] > 0.5;
            assert_eq!(lit, lit_rows.contains(&y), "{fit}: row {y}");
        }
    }
}

#[test]
fn golden_demo_clips_through_star_glow_the_relief_and_the_wall() {
    for (scene, frame) in [("video_star_glow", 12), ("video_tessellation", 40), ("video_projection", 20)] {
        let image = crate::common::render_scene(load_scene(&assets(), scene).unwrap(), (192, 108), frame);
        golden_beside(file!(), 0.01, 0.3).check(scene, image.size, &image.rgba).unwrap();
    }
}

#[test]
fn numbered_png_and_jpeg_sequences_play_as_clips_skipping_gaps() {
    for ext in ["png", "jpg"] {
        let folder = clip_dir().join(format!("sequence_{ext}"));
        let _ = std::fs::remove_dir_all(&folder);
        std::fs::create_dir_all(&folder).unwrap();
        let out = std::process::Command::new("ffmpeg")
            .args(["-v", "error", "-f", "lavfi", "-i", &counter_source(25, 0.4), "-start_number", "0", "-q:v", "1"])
            .arg(folder.join(format!("f_%03d.{ext}")))
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        // A gap: frame 3 missing is skipped, not shown black.
        std::fs::remove_file(folder.join(format!("f_003.{ext}"))).unwrap();
        std::fs::write(folder.join("notes.txt"), "not a frame").unwrap();
        let pattern = folder.join(format!("f_%03d.{ext}"));
        assert_eq!(counters(&pattern, r#""sequence_fps": 25.0"#, 0, 6), [0, 1, 2, 4, 5, 6], "{ext}");
        assert_eq!(counters(&pattern, r#""sequence_fps": 12.5"#, 0, 4), [0, 0, 1, 1], "{ext} at half the rate");
    }
}
