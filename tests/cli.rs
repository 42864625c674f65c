//! The `indra` binary end to end: render, check, list, bench, and one clear sentence for every
//! kind of bad input.

mod common;

use std::path::PathBuf;
use std::process::Command;

use common::{indra, text};

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("indra-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn render_writes_a_png_sequence_of_the_requested_size() {
    let out = temp_dir("render");
    let o = indra(&[
        "render",
        "kleinian",
        "--frames",
        "3",
        "--start",
        "10",
        "--size",
        "64x48",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let mut names: Vec<String> =
        std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    // The frames and their sums, as sha256sum writes them.
    assert_eq!(
        names,
        ["kleinian_00010-00012.sha256", "kleinian_00010.png", "kleinian_00011.png", "kleinian_00012.png"]
    );
    let manifest = std::fs::read_to_string(out.join("kleinian_00010-00012.sha256")).unwrap();
    let first = std::fs::read(out.join("kleinian_00010.png")).unwrap();
    assert!(
        manifest.starts_with(&format!("{}  kleinian_00010.png\n", indra::checkpoint::sha256_hex(&first))),
        "{manifest}"
    );
    assert_eq!(manifest.lines().count(), 3);
    let img = image::open(out.join("kleinian_00011.png")).unwrap();
    assert_eq!((img.width(), img.height()), (64, 48));
}

#[test]
fn render_start_reaches_the_frame_playing_reaches_and_splits_join() {
    // A simulation: `--start 30 --frames 1` must be frame 30 of the one-run render, and a
    // render split as 0..20 + 20..40 (two machines) must equal 0..40 in one run.
    let (whole, first, second, sought) =
        (temp_dir("seek-whole"), temp_dir("seek-a"), temp_dir("seek-b"), temp_dir("seek-c"));
    let render = |dir: &PathBuf, start: &str, frames: &str| {
        let args = [
            "render",
            "cloth",
            "--size",
            "64x40",
            "--start",
            start,
            "--frames",
            frames,
            "--out",
            dir.to_str().unwrap(),
        ];
        let o = indra(&args);
        assert!(o.status.success(), "{}", text(&o));
    };
    render(&whole, "0", "40");
    render(&first, "0", "20");
    render(&second, "20", "20");
    render(&sought, "30", "1");
    let png = |dir: &PathBuf, frame: u32| std::fs::read(dir.join(format!("cloth_{frame:05}.png"))).unwrap();
    for frame in 0..40 {
        let half = if frame < 20 { &first } else { &second };
        assert!(png(&whole, frame) == png(half, frame), "frame {frame} of the split render differs");
    }
    assert!(png(&whole, 30) == png(&sought, 30), "--start 30 differs from frame 30 played");
    assert!(png(&whole, 30) != png(&whole, 0), "the cloth did not move: the test would prove nothing");
}

#[test]
fn render_set_overrides_a_parameter() {
    let base = temp_dir("set-base");
    let changed = temp_dir("set-changed");
    let run = |dir: &PathBuf, extra: &[&str]| {
        let mut args = vec!["render", "kleinian_classic", "--size", "64x64", "--out", dir.to_str().unwrap()];
        args.extend_from_slice(extra);
        let o = indra(&args);
        assert!(o.status.success(), "{}", text(&o));
        std::fs::read(dir.join("kleinian_classic_00000.png")).unwrap()
    };
    assert_ne!(run(&base, &[]), run(&changed, &["--set", "limit_set.hit_color=0,0,1"]));
}

#[test]
fn check_passes_on_the_bundled_files() {
    let o = indra(&["check"]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("0 with errors"), "{}", text(&o));
}

#[test]
fn check_reports_a_broken_scene_with_file_line_and_column() {
    let dir = temp_dir("check-scene");
    let path = dir.join("broken.ron");
    let source = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/kleinian.ron")).unwrap();
    std::fs::write(&path, source.replace("\"scale\": 1.9", "\"scael\": 1.9")).unwrap();
    let o = indra(&["check", path.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let line = source.lines().position(|l| l.contains("\"scale\": 1.9")).unwrap() + 1;
    let expected = format!("broken.ron:{line}:17: technique 'kleinian' has no parameter 'scael'");
    assert!(text(&o).contains(&expected), "expected «{expected}» in:\n{}", text(&o));
}

#[test]
fn check_reports_a_broken_shader_with_its_line() {
    let dir = temp_dir("check-shader");
    let path = dir.join("broken.wgsl");
    std::fs::write(&path, "@compute @workgroup_size(8, 8, 1)\nfn main() {\n    let x = vec2<f32>(1.0) +;\n}\n")
        .unwrap();
    let o = indra(&["check", path.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o).contains("broken.wgsl:3:"), "{}", text(&o));
}

#[test]
fn list_shows_osc_addresses_of_every_scene() {
    let o = indra(&["list"]);
    assert!(o.status.success());
    let t = text(&o);
    for scene in ["kleinian", "kleinian_circle_inversion", "kleinian_classic"] {
        assert!(t.contains(&format!("{scene} — ")), "{scene} missing from:\n{t}");
    }
    assert!(t.contains("/indra/limit_set/t") && t.contains("(animated)"), "{t}");
}

#[test]
fn bench_prints_pass_medians_and_frame_time() {
    let o = indra(&[
        "bench",
        "kleinian",
        "--size",
        "64x64",
        "--frames",
        "6",
        "--warmup",
        "2",
        "--start",
        "30",
        "--set",
        "limit_set.samples=2",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let t = text(&o);
    assert!(t.contains("frame wall time (median)") && t.contains("set        limit_set.samples=2"), "{t}");
    assert!(t.contains("from frame 30"), "{t}");
    assert!(t.contains("kleinian/limit_set") || t.contains("wall-clock only"), "{t}");
    assert!(t.contains("step + record (CPU median)"), "{t}");
    assert!(t.contains("first pass to last (GPU)") || t.contains("wall-clock only"), "{t}");
    // One frame in flight: the same passes, timed as the interval between frames.
    let o = indra(&["bench", "kleinian", "--size", "64x64", "--frames", "6", "--warmup", "2", "--pipelined"]);
    let t = text(&o);
    assert!(o.status.success() && t.contains("frame interval (median)") && !t.contains("frame wall time"), "{t}");
    assert!(t.contains("kleinian/limit_set") || t.contains("wall-clock only"), "{t}");
}

#[test]
fn bad_numbers_get_one_sentence_and_a_non_zero_exit() {
    let out = temp_dir("bad-numbers");
    let dir = out.to_str().unwrap();
    for (args, expect) in [
        (vec!["render", "kleinian", "--dt", "nan", "--out", dir], "--dt"),
        (vec!["render", "kleinian", "--dt", "0", "--out", dir], "--dt"),
        (vec!["render", "kleinian", "--start", "18446744073709551615", "--frames", "2", "--out", dir], "--start"),
        (vec!["bench", "kleinian", "--frames", "18446744073709551615"], "--frames"),
        (vec!["render", "kleinian", "--set", "limit_set.scale=NaN", "--out", dir], "finite"),
        (vec!["render", "kleinian", "--set", "limit_set.hit_color=(1.0, inf, 0.0)", "--out", dir], "finite"),
    ] {
        let o = indra(&args);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", text(&o));
        let t = text(&o);
        assert!(t.contains(expect) && !t.contains("panicked"), "{args:?}: {t}");
    }
}

#[test]
fn bad_input_gets_one_clear_sentence() {
    let missing = indra(&["render", "no_such_scene"]);
    assert_eq!(missing.status.code(), Some(1));
    assert!(text(&missing).contains("no scene named 'no_such_scene.ron'"), "{}", text(&missing));

    let bad_size = indra(&["render", "kleinian", "--size", "0x5"]);
    assert_eq!(bad_size.status.code(), Some(2));
    assert!(text(&bad_size).contains("is not WxH"), "{}", text(&bad_size));

    let bad_set = indra(&["render", "kleinian", "--set", "limit_set.zoom=2"]);
    assert_eq!(bad_set.status.code(), Some(1));
    assert!(text(&bad_set).contains("has no parameter 'zoom'"), "{}", text(&bad_set));

    for t in [&missing, &bad_set] {
        assert!(!text(t).contains("panicked"), "{}", text(t));
    }
}

#[test]
fn no_gpu_says_how_to_get_one() {
    let o = Command::new(env!("CARGO_BIN_EXE_indra"))
        .args(["--backend", "vulkan", "render", "kleinian"])
        .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
        .env("VK_DRIVER_FILES", "/nonexistent/icd.json")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("no GPU adapter found") && text(&o).contains("mesa-vulkan-drivers"), "{}", text(&o));
}

#[test]
fn no_display_says_what_to_do_instead() {
    let o = Command::new(env!("CARGO_BIN_EXE_indra"))
        .arg("run")
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("cannot open a window") && text(&o).contains("indra render"), "{}", text(&o));
}

#[test]
fn render_replays_a_recorded_control_stream() {
    let dir = temp_dir("replay");
    let recording = dir.join("show.ron");
    std::fs::write(
        &recording,
        "(frame: 1, event: Write(node: \"limit_set\", param: \"hit_color\", component: None, value: [0.0, 1.0, 0.0], source: Osc))\n",
    )
    .unwrap();
    let render = |extra: &[&str], out: &std::path::Path| {
        let mut args =
            vec!["render", "kleinian_classic", "--frames", "3", "--size", "32x32", "--out", out.to_str().unwrap()];
        args.extend_from_slice(extra);
        let o = indra(&args);
        assert!(o.status.success(), "{}", text(&o));
        (0..3).map(|f| std::fs::read(out.join(format!("kleinian_classic_{f:05}.png"))).unwrap()).collect::<Vec<_>>()
    };
    let plain = render(&[], &dir.join("plain"));
    let replayed = render(&["--replay", recording.to_str().unwrap()], &dir.join("replayed"));
    assert_eq!(plain[0], replayed[0], "nothing happens before frame 1");
    assert_ne!(plain[1], replayed[1], "the recorded write applies at frame 1");
    std::fs::write(&recording, "(frame: 1, event: Write(node: \"nobody\"))\n").unwrap();
    let bad =
        indra(&["render", "kleinian_classic", "--replay", recording.to_str().unwrap(), "--out", dir.to_str().unwrap()]);
    assert_eq!(bad.status.code(), Some(1));
    assert!(text(&bad).contains("show.ron:1:"), "{}", text(&bad));
}

#[test]
fn triangulate_reads_json_and_svg_and_writes_the_mesh() {
    let dir = temp_dir("triangulate");
    let fixture = format!("{}/tests/fixtures/earcut/dude.json", env!("CARGO_MANIFEST_DIR"));
    let o = indra(&["triangulate", &fixture]);
    assert!(o.status.success(), "{}", text(&o));
    // dude: 104 vertices, 2 holes → 106 triangles, exact area.
    assert!(
        text(&o).contains("3 rings (1 filled, 2 holes, 0 Steiner points), 104 vertices → 106 triangles"),
        "{}",
        text(&o)
    );
    let deviation: f64 = text(&o).split("area deviation ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
    assert!(deviation < 1e-12, "{}", text(&o));

    let svg = dir.join("square.svg");
    std::fs::write(
        &svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg"><path d="M0 0 H10 V10 H0 Z M2 2 h6 v6 h-6 z"/></svg>"#,
    )
    .unwrap();
    let mesh = dir.join("square.json");
    let o = indra(&["triangulate", svg.to_str().unwrap(), "--out", mesh.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&mesh).unwrap()).unwrap();
    assert_eq!(json["indices"].as_array().unwrap().len(), 8 * 3);
    assert_eq!(json["positions"].as_array().unwrap().len(), 8);
    assert_eq!(json["uvs"][2], serde_json::json!([1.0, 1.0]));
}

#[test]
fn triangulate_reads_earcut_layout_and_steiner_points() {
    let dir = temp_dir("triangulate-layout");
    let path = dir.join("square.json");
    // Outer ring, a hole, a Steiner point inside the filled area.
    std::fs::write(&path, "[[[0,0],[10,0],[10,10],[0,10]], [[2,2],[4,2],[4,4],[2,4]], [[7,7]]]").unwrap();
    for layout in ["nesting", "earcut"] {
        let o = indra(&["triangulate", path.to_str().unwrap(), "--layout", layout]);
        assert!(o.status.success(), "{}", text(&o));
        // 8 ring vertices and 1 hole: 8 triangles, and 2 more for the Steiner point.
        let expected = "3 rings (1 filled, 1 holes, 1 Steiner points), 9 vertices → 10 triangles";
        assert!(text(&o).contains(expected) && text(&o).contains("area deviation 0.000e0"), "{layout}: {}", text(&o));
    }
    // The same rings listed hole first: nesting finds the outer ring anyway; earcut's layout
    // takes the first ring as the outer one and says the area does not add up.
    std::fs::write(&path, "[[[2,2],[4,2],[4,4],[2,4]], [[0,0],[10,0],[10,10],[0,10]]]").unwrap();
    let nesting = indra(&["triangulate", path.to_str().unwrap()]);
    assert!(text(&nesting).contains("area deviation 0.000e0"), "{}", text(&nesting));
    let earcut = indra(&["triangulate", path.to_str().unwrap(), "--layout", "earcut"]);
    assert!(earcut.status.success() && text(&earcut).contains("warning: triangles cover"), "{}", text(&earcut));
}

#[test]
fn triangulate_fills_a_bow_tie_and_says_it_crosses_itself() {
    // Was: "ring 0 left out: its points are collinear" and no triangles.
    let dir = temp_dir("triangulate-bow-tie");
    let path = dir.join("bow-tie.json");
    std::fs::write(&path, "[[[-5.33, -3], [5.33, 3], [5.33, -3], [-5.33, 3]]]").unwrap();
    let o = indra(&["triangulate", path.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("→ 2 triangles") && text(&o).contains("area deviation 0.000e0"), "{}", text(&o));
    assert!(text(&o).contains("ring 0 crosses itself") && !text(&o).contains("collinear"), "{}", text(&o));
}

#[test]
fn triangulate_bad_input_is_one_clear_message() {
    let dir = temp_dir("triangulate-bad");
    let bad = dir.join("bad.json");
    std::fs::write(&bad, "[[[0, 0], [1, 0]").unwrap();
    let o = indra(&["triangulate", bad.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(text(&o).contains("JSON rings (an array of rings of [x, y])"), "{}", text(&o));
    let path = dir.join("bad.svgd");
    std::fs::write(&path, "M0 0 L10 x").unwrap();
    let o = indra(&["triangulate", path.to_str().unwrap()]);
    assert!(!o.status.success() && text(&o).contains("SVG path data"), "{}", text(&o));
    // Was: exit 0 with "area deviation NaN" (a curve through 1e300).
    std::fs::write(&path, "M0 0 C 1e300 1e300 -1e300 1e300 0 10 Z").unwrap();
    let o = indra(&["triangulate", path.to_str().unwrap()]);
    assert!(!o.status.success() && text(&o).contains("is too large"), "{}", text(&o));
    assert_eq!(text(&o).lines().count(), 1, "{}", text(&o));
}

#[test]
fn in_range_values_too_large_together_and_hostile_files_get_one_sentence() {
    let dir = temp_dir("hostile-values");
    let scene = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/poisson_3d.ron")).unwrap();
    let huge = dir.join("huge_poisson.ron");
    let edited = scene
        .replace("\"radius\": 10.0", "\"radius\": 0.5")
        .replace("(200.0, 200.0, 200.0)", "(10000.0, 10000.0, 10000.0)");
    std::fs::write(&huge, edited).unwrap();
    let long_name = dir.join("long_name.ron");
    std::fs::write(&long_name, scene.replace("\"Poisson disk 3-D\"", &format!("\"{}\"", "n".repeat(300)))).unwrap();
    let long_id = dir.join("long_id.ron");
    let id = "p".repeat(100);
    std::fs::write(
        &long_id,
        scene
            .replace("id: \"poisson\"", &format!("id: \"{id}\""))
            .replace("output: \"poisson\"", &format!("output: \"{id}\"")),
    )
    .unwrap();
    for (file, says) in [(&huge, "raise the radius"), (&long_name, "at most 200"), (&long_id, "at most 64")] {
        let o = indra(&["check", file.to_str().unwrap()]);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(1), "{t}");
        assert!(t.contains(says) && !t.contains("panicked") && !t.contains("memory allocation"), "{t}");
    }

    let bench = indra(&["bench", "kleinian", "--frames", "0"]);
    assert!(bench.status.code() == Some(1) && text(&bench).contains("--frames 0"), "{}", text(&bench));
    let warmup = indra(&["bench", "kleinian", "--frames", "10", "--warmup", "999999999999"]);
    assert!(text(&warmup).contains("--warmup"), "{}", text(&warmup));

    let out = dir.join("out");
    let replay = |lines: &str| {
        let file = dir.join("take.ron");
        std::fs::write(&file, lines).unwrap();
        let args = ["render", "kleinian_classic", "--frames", "2", "--size", "16x16", "--out", out.to_str().unwrap()];
        indra(&[&args[..], &["--replay", file.to_str().unwrap()]].concat())
    };
    let device = indra(&["render", "kleinian_classic", "--replay", "/dev/zero", "--out", out.to_str().unwrap()]);
    assert!(text(&device).contains("not a regular file"), "{}", text(&device));
    let write = "(frame: 1, event: Write(node: \"limit_set\", param: \"hit_color\", component: None, value: [0.0, 1.0, 0.0], source: Osc))\n";
    for (take, says) in [
        ("(frame: 1, event: Morph(values: [], seconds: inf))\n", "not a finite number"),
        (
            "(frame: 1, event: Write(node: \"limit_set\", param: \"offset\", component: Some(99), value: 1.0, source: Osc))\n",
            "no component 99",
        ),
        (
            "(frame: 1, event: Write(node: \"limit_set\", param: \"iterations\", component: Some(0), value: 1.0, source: Osc))\n",
            "no component 0",
        ),
    ] {
        let o = replay(take);
        assert!(o.status.code() == Some(1) && text(&o).contains(says), "{take}: {}", text(&o));
    }
    // A take whose last line a crash cut short replays up to its last complete line.
    let cut = replay(&format!("{write}(frame: 2, event: Wri"));
    assert!(cut.status.success(), "{}", text(&cut));

    let zero_area = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/earcut/infinite-loop-jhl.json");
    let o = indra(&["triangulate", zero_area, "--layout", "earcut"]);
    let t = text(&o);
    assert!(o.status.success() && !t.contains("inf") && !t.contains("crosses itself"), "{t}");
}

#[test]
fn a_show_renders_its_cue_list_the_same_whole_split_or_sought() {
    // A cue list of a limit set and a cloth: cue 2 goes at 0.2 s (frame 12) and crossfades over
    // 0.2 s, cue 1 comes back at frame 24 and the cloth restarts at frame 36; frames 5–45 span it.
    let dir = temp_dir("show-file");
    let show = dir.join("cues.ron");
    std::fs::write(
        &show,
        r#"(name: "cues", size: (64, 36), transition: (kind: "crossfade", seconds: 0.2),
            layers: [(clips: [(scene: "kleinian"), (scene: "cloth")])],
            cues: [(clips: [(1, 1)], hold: Seconds(0.2)), (clips: [(1, 2)], hold: Seconds(0.2))])"#,
    )
    .unwrap();
    let (whole, first, second) = (temp_dir("show-whole"), temp_dir("show-a"), temp_dir("show-b"));
    let render = |out: &PathBuf, start: &str, frames: &str| {
        let args = [
            "render",
            show.to_str().unwrap(),
            "--size",
            "48x27",
            "--start",
            start,
            "--frames",
            frames,
            "--out",
            out.to_str().unwrap(),
        ];
        let o = indra(&args);
        assert!(o.status.success(), "{}", text(&o));
    };
    render(&whole, "5", "40");
    render(&first, "5", "14");
    render(&second, "19", "26");
    let png = |dir: &PathBuf, frame: u32| std::fs::read(dir.join(format!("cues_{frame:05}.png"))).unwrap();
    for frame in 5..45 {
        let part = if frame < 19 { &first } else { &second };
        assert!(png(&whole, frame) == png(part, frame), "frame {frame} of the split show render differs");
    }
    assert!(png(&whole, 8) != png(&whole, 20), "the cue list did not change the picture");
}

#[test]
fn check_and_list_take_shows_and_locate_a_bad_clip() {
    let o = indra(&["list"]);
    let t = text(&o);
    assert!(t.contains("shows/set — ") && t.contains("/indra/layer/2/clip/1/connect"), "{t}");
    let dir = temp_dir("check-show");
    let path = dir.join("broken-show.ron");
    let source = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/shows/set.ron")).unwrap();
    std::fs::write(&path, source.replace("(scene: \"kleinian\",", "(scene: \"kleinain\",")).unwrap();
    let o = indra(&["check", path.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let line = source.lines().position(|l| l.contains("(scene: \"kleinian\",")).unwrap() + 1;
    let expected = format!("broken-show.ron:{line}:21: clip 'kleinain'");
    assert!(text(&o).contains(&expected), "expected «{expected}» in:\n{}", text(&o));
}

#[test]
fn a_clip_without_ffmpeg_is_one_sentence_and_the_render_goes_on() {
    let dir = temp_dir("no-ffmpeg");
    let clip = dir.join("clip.mp4");
    let made = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-f", "lavfi", "-i", "testsrc=size=64x32:rate=25:duration=0.2", "-c:v", "libx264"])
        .arg(&clip)
        .output()
        .expect("ffmpeg runs");
    assert!(made.status.success());
    let scene = dir.join("clip.ron");
    let ron = format!(
        r#"(name: "clip", size: (64, 32), seed: 1, dt: 0.04,
            nodes: [(id: "clip", technique: "video", params: {{ "file": "{}" }})], output: "clip")"#,
        clip.display()
    );
    std::fs::write(&scene, ron).unwrap();
    let out_dir = dir.join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_indra"))
        .args(["render", scene.to_str().unwrap(), "--frames", "2", "--backend", "vulkan", "--out"])
        .arg(&out_dir)
        .env("INDRA_FFPROBE", dir.join("no-such-ffprobe"))
        .output()
        .unwrap();
    let said = text(&o);
    assert!(o.status.success(), "the render goes on: {said}");
    assert!(said.contains("no-such-ffprobe was not found") && said.contains("apt-get install ffmpeg"), "{said}");
    assert_eq!(said.matches("was not found").count(), 1, "said once: {said}");
    assert_eq!(std::fs::read_dir(&out_dir).unwrap().count(), 3, "both frames written (black), and their sums");
}
