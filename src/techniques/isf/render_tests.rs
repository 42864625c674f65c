//! ISF through the whole engine: every bundled sample renders a deterministic, non-uniform frame;
//! orientation as GL hosts show it; feedback buffers accumulate and seek exactly; a half-size
//! multipass target; the demo scenes' goldens; broken files are located errors.

use std::path::PathBuf;

use crate::common::{assets, gpu};
use indra::assets::Assets;
use indra::offscreen::{OffscreenRenderer, RenderedFrame};
use indra::scene::parse_scene_with;

/// A folder of test shaders, open to file parameters.
fn shader_dir(test: &str) -> (PathBuf, Assets) {
    let dir = std::env::temp_dir().join(format!("indra-isf-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let assets = assets().allowing(&dir);
    (dir, assets)
}

/// Renders frames `0..=last` of scene text `ron` at `size`; returns the frames asked for.
fn render(assets: &Assets, ron: &str, size: (u32, u32), frames: &[u64]) -> Vec<RenderedFrame> {
    let scene = parse_scene_with(assets, "isf.ron", ron).unwrap_or_else(|e| panic!("{e}\n{ron}"));
    let mut r = OffscreenRenderer::new(gpu(), assets, scene, Some(size), None, None).unwrap_or_else(|e| panic!("{e}"));
    let mut out = Vec::new();
    let last = frames.iter().copied().max().unwrap_or(0);
    for f in 0..=last {
        let frame = r.render_next().unwrap_or_else(|e| panic!("{e}"));
        if frames.contains(&f) {
            out.push(frame);
        }
    }
    out
}

/// A one-node scene playing `file` (and any more nodes and wiring given).
fn scene(file: &std::path::Path, more: &str, inputs: &str) -> String {
    format!(
        r#"(name: "isf", size: (16, 16), seed: 1, dt: 0.04,
            nodes: [{more} (id: "isf", technique: "isf", params: {{ "file": "{}" }}, inputs: {{ {inputs} }})],
            output: "isf")"#,
        file.display()
    )
}

/// The red channel (sRGB, 0–255) at (x, y) of a 16-wide frame.
fn red(frame: &RenderedFrame, x: u32, y: u32) -> u8 {
    frame.rgba[((y * frame.size.0 + x) * 4) as usize]
}

#[test]
fn a_gradient_is_bright_at_the_top_as_gl_hosts_show_it() {
    let (dir, assets) = shader_dir("orientation");
    // Three ways to read "up": the normalised coordinate, gl_FragCoord, and sampling an input
    // (through a persistent buffer, so a buffer's own orientation counts too).
    let norm = dir.join("norm.fs");
    std::fs::write(&norm, "/*{}*/\nvoid main() { gl_FragColor = vec4(vec3(isf_FragNormCoord.y), 1.0); }\n").unwrap();
    let frag = dir.join("frag.fs");
    std::fs::write(&frag, "/*{}*/\nvoid main() { gl_FragColor = vec4(vec3(gl_FragCoord.y / RENDERSIZE.y), 1.0); }\n")
        .unwrap();
    let through = dir.join("through.fs");
    std::fs::write(
        &through,
        r#"/*{ "INPUTS": [ { "NAME": "inputImage", "TYPE": "image" } ],
              "PASSES": [ { "TARGET": "kept", "PERSISTENT": true }, {} ] }*/
void main() {
    if (PASSINDEX == 0) gl_FragColor = IMG_THIS_PIXEL(inputImage);
    else gl_FragColor = IMG_NORM_PIXEL(kept, isf_FragNormCoord);
}
"#,
    )
    .unwrap();
    let source = format!(r#"(id: "gradient", technique: "isf", params: {{ "file": "{}" }}),"#, norm.display());
    for ron in [scene(&norm, "", ""), scene(&frag, "", ""), scene(&through, &source, r#""inputImage": "gradient""#)] {
        let frame = &render(&assets, &ron, (16, 16), &[0])[0];
        let (top, bottom) = (red(frame, 8, 0), red(frame, 8, 15));
        assert!(top > 240 && bottom < 40, "top {top}, bottom {bottom}: {ron}");
        // Display values pass through unchanged: the middle row is half grey as the shader wrote.
        let middle = red(frame, 8, 8);
        assert!(middle.abs_diff(120) <= 4, "middle {middle} (0.47 → 120)");
    }
}

#[test]
fn every_bundled_sample_renders_a_deterministic_non_uniform_frame() {
    let assets = assets();
    let mut failures = Vec::new();
    let names: Vec<&str> = indra::assets::bundled_isf().map(|(p, _)| p).filter(|p| p.ends_with(".fs")).collect();
    // Shaders that sample sound hear a 440 Hz tone.
    let (dir, _) = shader_dir("samples");
    let wav = dir.join("tone.wav");
    write_tone(&wav, 440.0, 1.0);
    let audio = indra::control::audio::AudioFile::open(&wav).unwrap();
    for name in &names {
        let ron = indra::techniques::isf::scene_for(&assets, name).unwrap();
        let frames = |last: u64| {
            let scene = parse_scene_with(&assets, "isf.ron", &ron).unwrap();
            let script = indra::control::audio::file_script(&audio, &scene, last + 1, f64::from(scene.dt));
            let mut r = OffscreenRenderer::new(gpu(), &assets, scene, Some((32, 32)), None, None).unwrap();
            for (frame, events) in script {
                r.schedule(frame, events);
            }
            (0..=last).map(|_| r.render_next().unwrap()).last().into_iter().collect::<Vec<_>>()
        };
        let (a, b) = (frames(12), frames(12));
        let first = &a[0].rgba[..4];
        if a[0].rgba != b[0].rgba {
            failures.push(format!("{name}: two renders differ"));
        } else if a[0].rgba.chunks(4).all(|p| p == first) {
            failures.push(format!("{name}: a uniform frame"));
        }
    }
    let passed = names.len() - failures.len();
    println!("{passed} of {} samples render: failures {failures:#?}", names.len());
    assert!(passed * 100 >= names.len() * 95, "{failures:#?}");
}

#[test]
fn a_bare_file_gets_a_scene_with_its_inputs_wired() {
    let assets = Assets::new(None);
    let filter = indra::techniques::isf::scene_for(&assets, "shaders/isf/Kaleidoscope.fs").unwrap();
    assert!(filter.contains("\"inputImage\": \"pattern\""), "{filter}");
    let transition = indra::techniques::isf::scene_for(&assets, "shaders/isf/Directional Wipe.fs").unwrap();
    assert!(transition.contains("\"startImage\": \"limit_set\", \"endImage\": \"pattern\""), "{transition}");
    assert!(transition.contains("isf.progress"), "{transition}");
    for text in [filter, transition] {
        parse_scene_with(&assets, "bare.ron", &text).unwrap_or_else(|e| panic!("{e}\n{text}"));
    }
}

#[test]
fn pow_and_smoothstep_give_what_gl_hosts_give_where_glsl_leaves_them_open() {
    let (dir, assets) = shader_dir("gl-as-hosts");
    let file = dir.join("edges.fs");
    // Red: smoothstep with equal edges, a step; green: a negative base to an odd power, |x|^y;
    // blue: reversed edges, a falling ramp.
    std::fs::write(
        &file,
        "/*{}*/\nvoid main() { float x = isf_FragNormCoord.x;\n\
         gl_FragColor = vec4(smoothstep(0.5, 0.5, x), pow(-0.5, 1.0), smoothstep(0.8, 0.2, x), 1.0); }\n",
    )
    .unwrap();
    let frame = &render(&assets, &scene(&file, "", ""), (16, 16), &[0])[0];
    let (left, right) = (rgb(frame, 0, 8), rgb(frame, 15, 8));
    assert_eq!((left[0], right[0]), (0, 255), "the step at 0.5: left {left:?}, right {right:?}");
    assert!(left[1].abs_diff(128) <= 1 && right[1].abs_diff(128) <= 1, "pow(-0.5, 1.0) = 0.5: {left:?} {right:?}");
    assert_eq!((left[2], right[2]), (255, 0), "reversed edges fall: left {left:?}, right {right:?}");
}

/// Whether two colours are within one step of rounding.
fn near(a: [u8; 3], b: [u8; 3]) -> bool {
    a.iter().zip(&b).all(|(x, y)| x.abs_diff(*y) <= 1)
}

/// The sRGB red, green and blue (0–255) at (x, y).
fn rgb(frame: &RenderedFrame, x: u32, y: u32) -> [u8; 3] {
    let i = ((y * frame.size.0 + x) * 4) as usize;
    [frame.rgba[i], frame.rgba[i + 1], frame.rgba[i + 2]]
}

#[test]
fn a_feedback_buffer_accumulates_and_a_sought_frame_equals_the_played_one() {
    let (dir, assets) = shader_dir("feedback");
    let file = dir.join("accumulate.fs");
    // Each frame adds 1/64 to a persistent float buffer; the output shows it.
    std::fs::write(
        &file,
        r#"/*{ "PASSES": [ { "TARGET": "sum", "PERSISTENT": true, "FLOAT": true }, {} ] }*/
void main() {
    if (PASSINDEX == 0) gl_FragColor = IMG_THIS_PIXEL(sum) + vec4(1.0 / 64.0, 0.0, 0.0, 1.0 / 64.0);
    else gl_FragColor = vec4(IMG_NORM_PIXEL(sum, isf_FragNormCoord).rrr, 1.0);
}
"#,
    )
    .unwrap();
    let ron = scene(&file, "", "");
    let played = render(&assets, &ron, (16, 16), &[0, 15, 31]);
    // Display value (n + 1) / 64 after frame n: 1/64, 16/64, 32/64 → sRGB bytes 4, 64, 128.
    let reds: Vec<u8> = played.iter().map(|f| red(f, 5, 5)).collect();
    assert!(reds[0].abs_diff(4) <= 1 && reds[1].abs_diff(64) <= 1 && reds[2].abs_diff(128) <= 1, "{reds:?}");
    // Seek: frame 31 reached by --start equals frame 31 played from 0.
    let scene = parse_scene_with(&assets, "isf.ron", &ron).unwrap();
    let mut r = OffscreenRenderer::new(gpu(), &assets, scene, Some((16, 16)), None, None).unwrap();
    r.seek(31).unwrap();
    assert!(r.render_next().unwrap().rgba == played[2].rgba, "seek = play");
}

#[test]
fn a_half_size_target_renders_at_half_size() {
    let (dir, assets) = shader_dir("multipass");
    let file = dir.join("half.fs");
    // Pass 0 writes its RENDERSIZE and a one-pixel stripe into a half-size buffer; pass 1 reads
    // it texel by texel: the stripes come out two pixels wide.
    std::fs::write(
        &file,
        r#"/*{ "PASSES": [ { "TARGET": "half", "WIDTH": "floor($WIDTH / 2.0)", "HEIGHT": "$HEIGHT/2" }, {} ] }*/
void main() {
    if (PASSINDEX == 0) {
        gl_FragColor = vec4(RENDERSIZE.x / 16.0, mod(floor(gl_FragCoord.x), 2.0), IMG_SIZE(half).y / 16.0, 1.0);
    } else {
        gl_FragColor = IMG_PIXEL(half, floor(gl_FragCoord.xy / 2.0) + 0.5);
    }
}
"#,
    )
    .unwrap();
    let frame = &render(&assets, &scene(&file, "", ""), (16, 16), &[0])[0];
    let row: Vec<u8> = (0..8).map(|x| rgb(frame, x, 3)[1]).collect();
    assert_eq!(row, [0, 0, 255, 255, 0, 0, 255, 255], "two-pixel stripes");
    let [r, _, b] = rgb(frame, 3, 3);
    assert!(r.abs_diff(128) <= 1 && b.abs_diff(128) <= 1, "the pass saw an 8×8 target: {r} {b}");
}

#[test]
fn every_input_type_is_a_parameter_with_its_address() {
    let (dir, assets) = shader_dir("inputs");
    let file = dir.join("inputs.fs");
    std::fs::write(
        &file,
        r#"/*{ "INPUTS": [
    { "NAME": "amount", "TYPE": "float", "MIN": 0, "MAX": 2, "DEFAULT": 1 },
    { "NAME": "mode", "TYPE": "long", "VALUES": [2, 7], "LABELS": ["low", "high"], "DEFAULT": 7 },
    { "NAME": "invert", "TYPE": "bool", "DEFAULT": false },
    { "NAME": "flash", "TYPE": "event" },
    { "NAME": "tint", "TYPE": "color", "DEFAULT": [1, 0, 0, 1] },
    { "NAME": "spot", "TYPE": "point2D", "DEFAULT": [4, 4], "MIN": [0, 0], "MAX": [16, 16] }
] }*/
void main() {
    float m = mode == 7 ? 1.0 : 0.0;
    vec4 c = tint * amount * 0.5;
    if (invert) c.rgb = 1.0 - c.rgb;
    if (flash) c.g = 1.0;
    c.b = m * step(distance(gl_FragCoord.xy, spot), 2.0);
    gl_FragColor = vec4(c.rgb, 1.0);
}
"#,
    )
    .unwrap();
    let ron = scene(&file, "", "");
    let scene = parse_scene_with(&assets, "isf.ron", &ron).unwrap();
    let node = &scene.nodes[scene.node_index("isf").unwrap()];
    let names: Vec<&str> = node.params.decls().iter().map(|d| d.name.as_str()).collect();
    assert_eq!(names, ["file", "date", "amount", "mode", "invert", "flash", "tint", "spot"]);
    for name in &names[2..] {
        // Each is a target of OSC (/indra/isf/<name>), MIDI, tracks and LFOs.
        indra::scene::resolve_target(&scene.nodes, &format!("isf.{name}")).unwrap();
    }
    // Values reach the shader: defaults, then each changed from the command line's syntax.
    let at = |sets: &[&str]| {
        let mut s = scene.clone();
        for set in sets {
            s.set_from_str(set).unwrap();
        }
        let mut r = OffscreenRenderer::new(gpu(), &assets, s, Some((16, 16)), None, None).unwrap();
        r.render_next().unwrap()
    };
    let base = at(&[]);
    assert!(near(rgb(&base, 10, 10), [128, 0, 0]), "tint × amount × 0.5: {:?}", rgb(&base, 10, 10));
    assert_eq!(rgb(&base, 4, 11)[2], 255, "spot at (4, 4) from the bottom, mode 'high' = 7");
    let changed = at(&["isf.amount=2", "isf.mode=low", "isf.invert=true", "isf.tint=0,1,0,1", "isf.spot=12,12"]);
    assert_eq!(rgb(&changed, 10, 10), [255, 0, 0], "inverted green at full amount");
    assert_eq!(rgb(&changed, 12, 3)[2], 0, "mode 'low' hides the spot");
    // An event fires for the one frame it arrives in (as from OSC), then rests.
    let t = indra::scene::resolve_target(&scene.nodes, "isf.flash").unwrap();
    let mut r = OffscreenRenderer::new(gpu(), &assets, scene.clone(), Some((16, 16)), None, None).unwrap();
    let fire = indra::params::ParamWrite {
        node: t.node,
        param: t.param,
        component: None,
        value: indra::params::ParamValue::Trigger(true),
        source: indra::params::Source::Ui,
    };
    r.schedule(1, vec![indra::params::ControlEvent::Write(fire)]);
    let greens: Vec<u8> = (0..3).map(|_| rgb(&r.render_next().unwrap(), 10, 10)[1]).collect();
    assert_eq!(greens, [0, 255, 0], "the event fired in frame 1 only");
}

/// Polls `live` until it applies or reports something (or 5 s pass).
fn wait_for_reload(r: &mut OffscreenRenderer, live: &mut indra::live::LiveReload) -> indra::live::ReloadReport {
    let start = std::time::Instant::now();
    loop {
        let report = r.poll_reload(live);
        if !report.applied.is_empty() || !report.errors.is_empty() || start.elapsed().as_secs() > 5 {
            return report;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

#[test]
fn a_broken_isf_file_is_a_located_error_and_the_fix_reloads_with_its_new_inputs() {
    let (root, _) = shader_dir("reload");
    std::fs::create_dir_all(root.join("shaders/isf")).unwrap();
    let file = root.join("shaders/isf/live.fs");
    let good = "/*{ \"INPUTS\": [ { \"NAME\": \"level\", \"TYPE\": \"float\", \"DEFAULT\": 0.5 } ] }*/\n\
                void main() {\n    gl_FragColor = vec4(level, 0.0, 0.0, 1.0);\n}\n";
    std::fs::write(&file, good).unwrap();
    let assets = Assets::new(Some(root.clone()));
    let scene = indra::scene::load_scene(&assets, "shaders/isf/live.fs").unwrap();
    let mut live = indra::live::LiveReload::new(&assets).unwrap();
    let mut r = OffscreenRenderer::new(gpu(), &assets, scene, Some((16, 16)), None, None).unwrap();
    let before = r.render_next().unwrap();
    assert!(near(rgb(&before, 8, 8), [128, 0, 0]));

    std::fs::write(&file, good.replace("vec4(level, 0.0, 0.0, 1.0)", "vec4(level, 0.0, 0.0, 1.0) +")).unwrap();
    let report = wait_for_reload(&mut r, &mut live);
    assert_eq!(report.errors.len(), 1, "{report:?}");
    assert!(report.errors[0].contains("live.fs:3:"), "located at the line: {}", report.errors[0]);
    assert!(r.render_next().unwrap().rgba == before.rgba, "the last good version runs on");

    let fixed = good
        .replace(
            "\"DEFAULT\": 0.5 }",
            "\"DEFAULT\": 0.5 }, { \"NAME\": \"green\", \"TYPE\": \"float\", \"DEFAULT\": 1 }",
        )
        .replace("vec4(level, 0.0, 0.0, 1.0)", "vec4(level, green, 0.0, 1.0)");
    std::fs::write(&file, fixed).unwrap();
    // The fix is parsed, compiled and built off the render thread: the poll that takes the
    // change up returns before it is installed, and frames go on with the running version.
    let start = std::time::Instant::now();
    while live.building().is_none() {
        let report = r.poll_reload(&mut live);
        assert!(report.applied.is_empty() && start.elapsed().as_secs() < 5, "{report:?}");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    assert!(r.render_next().unwrap().rgba == before.rgba, "the running version draws while the fix builds");
    let report = wait_for_reload(&mut r, &mut live);
    assert!(report.scene_changed && report.fixed.len() == 1, "{report:?}");
    assert!(near(rgb(&r.render_next().unwrap(), 8, 8), [128, 255, 0]), "the new input is live");
    let instance = r.instance_mut();
    assert!(instance.scene().nodes[instance.scene().output].params.index("green").is_some());
    std::fs::remove_dir_all(root).unwrap();
}

#[test]
fn an_audio_fft_input_peaks_in_the_bin_of_a_sine() {
    let (dir, assets) = shader_dir("fft");
    let wav = dir.join("sine.wav");
    write_tone(&wav, 1000.0, 1.0);
    // Each output column shows one bin of a 128-bin spectrum.
    let file = dir.join("fft.fs");
    std::fs::write(
        &file,
        r#"/*{ "INPUTS": [ { "NAME": "spectrum", "TYPE": "audioFFT", "MAX": 128 }, { "NAME": "wave", "TYPE": "audio" } ] }*/
void main() {
    float bin = IMG_NORM_PIXEL(spectrum, vec2(isf_FragNormCoord.x, 0.5)).r;
    float level = abs(IMG_NORM_PIXEL(wave, vec2(isf_FragNormCoord.x, 0.5)).r - 0.5) * 2.0;
    gl_FragColor = vec4(bin, level, 0.0, 1.0);
}
"#,
    )
    .unwrap();
    let scene = parse_scene_with(&assets, "isf.ron", &scene(&file, "", "")).unwrap();
    assert!(scene.hears_audio(), "an audio input makes the scene listen");
    let audio = indra::control::audio::AudioFile::open(&wav).unwrap();
    let script = indra::control::audio::file_script(&audio, &scene, 12, 0.04);
    let mut r = OffscreenRenderer::new(gpu(), &assets, scene, Some((128, 4)), None, None).unwrap();
    for (frame, events) in script {
        r.schedule(frame, events);
    }
    let mut frame = r.render_next().unwrap();
    for _ in 0..10 {
        frame = r.render_next().unwrap();
    }
    let row: Vec<u8> = (0..128).map(|x| rgb(&frame, x, 1)[0]).collect();
    let loudest = (0..128).max_by_key(|&x| row[x]).unwrap();
    // 128 bins over 0–24 kHz: 187.5 Hz each, so 1 kHz is bin 5.
    assert_eq!(loudest, 5, "{row:?}");
    assert!(row[5] > 150 && row[60] < 40, "a peak over a quiet floor: {row:?}");
    let waving = (0..128).filter(|&x| rgb(&frame, x, 1)[1] > 100).count();
    assert!(waving > 20, "the waveform moves: {waving} columns");
}

/// A mono 48 kHz WAV of a sine at `hz`, half of full scale, `seconds` long.
fn write_tone(path: &std::path::Path, hz: f32, seconds: f32) {
    let spec = hound::WavSpec {
        channels: 1,
        sample_rate: 48_000,
        bits_per_sample: 16,
        sample_format: hound::SampleFormat::Int,
    };
    let mut w = hound::WavWriter::create(path, spec).unwrap();
    for i in 0..(48_000.0 * seconds) as u32 {
        let s = (std::f32::consts::TAU * hz * i as f32 / 48_000.0).sin() * 0.5;
        w.write_sample((s * 32767.0) as i16).unwrap();
    }
    w.finalize().unwrap();
}

#[test]
fn golden_demo_scenes_a_generator_into_star_glow_a_filter_over_the_cloth_and_feedback() {
    for (scene, frame) in [("isf_star_glow", 20), ("isf_cloth", 60), ("isf_feedback", 40)] {
        let loaded = indra::scene::load_scene(&assets(), scene).unwrap();
        let image = crate::common::render_scene(loaded, (192, 108), frame);
        crate::common::golden_beside(file!(), 0.01, 0.3).check(scene, image.size, &image.rgba).unwrap();
    }
}

#[test]
fn an_isf_transition_runs_between_a_shows_clips() {
    let (dir, assets) = shader_dir("transition");
    let file = dir.join("rise.fs");
    // A wipe from the bottom: below `progress` (of the height, y up) the incoming clip shows.
    std::fs::write(
        &file,
        r#"/*{ "INPUTS": [ { "NAME": "startImage", "TYPE": "image" }, { "NAME": "endImage", "TYPE": "image" },
              { "NAME": "progress", "TYPE": "float" } ] }*/
void main() {
    gl_FragColor = isf_FragNormCoord.y < progress ? IMG_THIS_PIXEL(endImage) : IMG_THIS_PIXEL(startImage);
}
"#,
    )
    .unwrap();
    let show = format!(
        r#"(name: "isf transition", size: (32, 32), seed: 1,
            transition: (kind: "{}", seconds: 1.0),
            layers: [(clips: [
                (scene: "kleinian_classic", id: "red", params: {{ "limit_set.hit_color": (0.9, 0.1, 0.1, 1.0), "limit_set.back_color": (0.9, 0.1, 0.1, 1.0) }}),
                (scene: "kleinian_classic", id: "blue", params: {{ "limit_set.hit_color": (0.1, 0.2, 0.9, 1.0), "limit_set.back_color": (0.1, 0.2, 0.9, 1.0) }}),
            ])])"#,
        file.display()
    );
    let scene = indra::scene::show::parse_show(&assets, "isf-show.ron", &show, false).unwrap_or_else(|e| panic!("{e}"));
    let mut r = OffscreenRenderer::new(gpu(), &assets, scene, Some((32, 32)), None, None).unwrap();
    let trigger = indra::params::ShowCommand::Trigger { layer: 0, clip: Some(1) };
    r.schedule(2, vec![indra::params::ControlEvent::Show(trigger)]);
    // Halfway at frame 32 (a one-second transition at 60 steps a second from frame 2).
    r.seek(32).unwrap();
    let middle = r.render_next().unwrap();
    let (top, bottom) = (rgb(&middle, 16, 4), rgb(&middle, 16, 28));
    assert!(top[0] > 200 && top[2] < 100, "the top still shows the outgoing red clip: {top:?}");
    assert!(bottom[2] > 200 && bottom[0] < 100, "the bottom shows the incoming blue clip: {bottom:?}");
    // A kind that is not a transition is refused where the show names it.
    let filter = show.replace(&file.display().to_string(), "shaders/isf/Kaleidoscope.fs");
    let e = indra::scene::show::parse_show(&assets, "isf-show.ron", &filter, false).err().unwrap().to_string();
    assert!(e.contains("not an ISF transition"), "{e}");
}

#[test]
fn an_imported_image_is_read_beside_the_shader_the_right_way_up() {
    let (dir, assets) = shader_dir("imported");
    // Two pixels: red on top, blue below.
    let mut image = image::RgbaImage::new(1, 2);
    image.put_pixel(0, 0, image::Rgba([255, 0, 0, 255]));
    image.put_pixel(0, 1, image::Rgba([0, 0, 255, 255]));
    image.save(dir.join("two.png")).unwrap();
    let file = dir.join("imported.fs");
    let shader = r#"/*{ "IMPORTED": { "two": { "PATH": "two.png" } } }*/
void main() { gl_FragColor = IMG_NORM_PIXEL(two, vec2(0.5, isf_FragNormCoord.y > 0.5 ? 0.75 : 0.25)); }
"#;
    std::fs::write(&file, shader).unwrap();
    let frame = &render(&assets, &scene(&file, "", ""), (16, 16), &[0])[0];
    assert_eq!((rgb(frame, 8, 2), rgb(frame, 8, 13)), ([255, 0, 0], [0, 0, 255]));
    // A missing file is one message naming it; the scene does not start.
    std::fs::write(&file, shader.replace("two.png", "gone.png")).unwrap();
    let scene = parse_scene_with(&assets, "isf.ron", &scene(&file, "", "")).unwrap();
    let e = OffscreenRenderer::new(gpu(), &assets, scene, Some((16, 16)), None, None).err().unwrap().to_string();
    assert!(e.contains("IMPORTED 'two'") && e.contains("gone.png"), "{e}");
}

#[test]
fn a_nodes_targets_are_bounded_together_and_counted_in_the_scene_budget() {
    let (dir, assets) = shader_dir("targets");
    let target = |name: &str, (w, h): (u32, u32)| {
        format!(
            "{{ \"TARGET\": \"{name}\", \"PERSISTENT\": true, \"FLOAT\": true, \"WIDTH\": \"{w}\", \"HEIGHT\": \"{h}\" }}"
        )
    };
    let file = |name: &str, passes: &[String]| {
        let path = dir.join(name);
        let body = format!(
            "/*{{ \"PASSES\": [ {}, {{ }} ] }}*/\nvoid main() {{ gl_FragColor = vec4(1.0); }}\n",
            passes.join(", ")
        );
        std::fs::write(&path, body).unwrap();
        path
    };
    // Four persistent 8192² float targets (the 835-byte file that took a process to 4.2 GB):
    // each under the old per-pass bound, refused together by check.
    let four: Vec<String> = ["a", "b", "c", "d"].iter().map(|n| target(n, (8192, 8192))).collect();
    let hostile = file("four.fs", &four);
    let e = super::IsfFiles::read(&assets, hostile.to_str().unwrap()).unwrap().compile().unwrap_err().to_string();
    assert!(e.contains("MiB together") && e.contains("four.fs:"), "{e}");
    // One persistent 8192×4096 float target per node (256 MiB, ping-ponged: 512 MiB) passes
    // alone; seventeen such nodes pass each check but not the scene's 8 GiB budget.
    let one = file("one.fs", &[target("a", (8192, 4096))]);
    let node = |i: usize| format!(r#"(id: "n{i}", technique: "isf", params: {{ "file": "{}" }})"#, one.display());
    let ron = |n: usize| {
        let nodes: Vec<String> = (0..n).map(node).collect();
        format!(r#"(name: "many", size: (64, 64), nodes: [{}], output: "n0")"#, nodes.join(", "))
    };
    let few = parse_scene_with(&assets, "few.ron", &ron(2)).unwrap_or_else(|e| panic!("{e}"));
    // Per node: the target twice and the output pass (8-bit, at the scene's 64×64).
    assert_eq!(few.own_texture_bytes, 2 * (8192 * 4096 * 8 * 2 + 64 * 64 * 4));
    let e = parse_scene_with(&assets, "many.ron", &ron(17)).expect_err("over the budget").to_string();
    assert!(e.contains("GiB of textures"), "{e}");
}
