//! Every bundled ISF file against the reference ISF renderer: npm's `interactive-shader-format`
//! (Vidvox's WebGL implementation) in Debian's headless Chromium, on its software WebGL
//! (SwiftShader). Both get the same two input pictures, the same inputs and the same fixed clock
//! (13 frames at 25 fps, so feedback buffers count too), and the last frames are compared by FLIP.
//! Files the reference cannot render as indra does are listed with the reason, and the test fails
//! if a listed one starts to agree: the list stays true. Bounds and outliers: `docs/isf.md`.

use std::path::Path;

use serde_json::{Value, json};

use crate::chromium::Chromium;
use crate::common::{assets, gpu};
use crate::live_show::scratch_dir;
use indra::offscreen::{OffscreenRenderer, flip_score, write_png};
use indra::scene::parse_scene_with;

/// The size both render at: small for CI, large enough for multipass filters' quarter targets.
const SIZE: (u32, u32) = (192, 108);
/// Frames rendered; the last is compared.
const FRAMES: u64 = 13;
/// The fixed step, seconds.
const DT: f64 = 0.04;
/// The largest mean FLIP error that counts as the same picture. What is left under it is where a
/// filter samples between texels of high contrast: indra's images are linear and filtered in
/// linear light, a GL host's are display values (Circle Splash Distortion's rays, 0.114, are the
/// most); and the reference's 8-bit buffers where a pass asks for FLOAT.
const MAX_MEAN: f32 = 0.12;

/// Why a later pass's reading of a target differs (see OUTLIERS).
const LAGS: &str = "the reference binds every target before the first pass, so a later pass reads what an earlier \
                    one wrote the frame before; a state that changes every frame shows a frame late";
/// Why WebGL 1 cannot compile a file that desktop GL hosts (and indra) take.
const GLSL_ES_100: &str = "WebGL 1's GLSL ES 1.00 refuses it; desktop GL hosts compile it";

/// Files the reference renders differently by design, with why (`docs/isf.md` says the same).
const OUTLIERS: &[(&str, &str)] = &[
    ("Strobe", LAGS),
    ("Flipbook", LAGS),
    ("Trail Mask", LAGS),
    ("Noise", "a fract(sin(x) · 43758) hash of pixel positions: sin's last bits differ between GPUs"),
    ("Chroma Desaturation Mask", GLSL_ES_100),
    ("Color Replacement", GLSL_ES_100),
    ("Duotone From Histogram", GLSL_ES_100),
    ("Erode", GLSL_ES_100),
    ("Hexagonalize", GLSL_ES_100),
    ("Mosaic", GLSL_ES_100),
    ("Random Characters", GLSL_ES_100),
    ("v002 Light Leak", GLSL_ES_100),
    ("Rotate", "the reference does not declare ISF v1's vv_FragNormCoord for it"),
    ("Neon", "the reference refuses its header (DESCRIPTION twice), which hosts read"),
    ("FFT Spectrogram", "the reference has no audio inputs"),
    ("Test Pattern Generator", "the reference has no audio inputs"),
    ("Waveform Displace", "the reference has no audio inputs"),
];

/// An opaque input picture with hue, brightness, hard edges and fine detail, so that what a
/// filter does to each shows. `variant` 1 is another picture (a transition's end image).
fn picture(variant: u32) -> Vec<u8> {
    let (w, h) = SIZE;
    let mut rgba = Vec::with_capacity((w * h * 4) as usize);
    for y in 0..h {
        for x in 0..w {
            let (u, v) = (x as f32 / (w - 1) as f32, y as f32 / (h - 1) as f32);
            let (u, v) = if variant == 0 { (u, v) } else { (1.0 - v, u) };
            let hue = u * 6.0;
            let channel = |offset: f32| ((hue + offset).rem_euclid(6.0) - 3.0).abs().clamp(1.0, 2.0) - 1.0;
            let light = 0.25 + 0.75 * (1.0 - v);
            let mut rgb = [channel(0.0) * light, channel(4.0) * light, channel(2.0) * light];
            let (dx, dy) = (u - 0.5, (v - 0.5) * h as f32 / w as f32);
            let r = (dx * dx + dy * dy).sqrt();
            if (0.16..0.2).contains(&r) {
                rgb = [1.0; 3];
            } else if r < 0.16 && ((x / 6) + (y / 6)) % 2 == 0 {
                rgb = [0.05, 0.05, 0.1];
            }
            rgba.extend(rgb.map(|c| (c * 255.0).round() as u8));
            rgba.push(255);
        }
    }
    rgba
}

/// The header's inputs (the JSON in the first comment).
fn inputs(fragment: &str) -> Vec<Value> {
    let start = fragment.find("/*").expect("an ISF header") + 2;
    let end = start + fragment[start..].find("*/").expect("a closed header");
    let header: Value = serde_json::from_str(&fragment[start..end]).unwrap_or_default();
    header["INPUTS"].as_array().cloned().unwrap_or_default()
}

/// indra's render of `file` (its last frame, RGBA8, top row first).
fn indra_render(assets: &indra::assets::Assets, dir: &Path, file: &str, inputs: &[Value]) -> Result<Vec<u8>, String> {
    let images: Vec<&str> = inputs.iter().filter(|i| i["TYPE"] == "image").filter_map(|i| i["NAME"].as_str()).collect();
    let source = |k: usize, name: &str| if name == "endImage" || k > 0 { "b" } else { "a" };
    let wiring: Vec<String> = images.iter().enumerate().map(|(k, n)| format!("{n:?}: {:?}", source(k, n))).collect();
    let mut nodes = String::new();
    for id in ["a", "b"] {
        if images.iter().enumerate().any(|(k, n)| source(k, n) == id) {
            let path = dir.join(format!("{id}.png"));
            nodes.push_str(&format!(
                "(id: {id:?}, technique: \"image\", params: {{ \"path\": {:?} }}),\n",
                path.display()
            ));
        }
    }
    let progress = if is_transition(inputs) { ", \"progress\": 0.5" } else { "" };
    let ron = format!(
        "(name: \"isf reference\", size: ({}, {}), seed: 1, dt: {DT},
          nodes: [{nodes} (id: \"isf\", technique: \"isf\", params: {{ \"file\": {file:?}{progress} }},
                   inputs: {{ {} }})],
          output: \"isf\")",
        SIZE.0,
        SIZE.1,
        wiring.join(", ")
    );
    let scene = parse_scene_with(assets, "isf-reference.ron", &ron).map_err(|e| e.to_string())?;
    let mut r = OffscreenRenderer::new(gpu(), assets, scene, Some(SIZE), None, None).map_err(|e| e.to_string())?;
    let mut last = None;
    for _ in 0..FRAMES {
        last = Some(r.render_next().map_err(|e| e.to_string())?);
    }
    Ok(last.expect("frames").rgba)
}

/// A transition: a `progress` input and the two images.
fn is_transition(inputs: &[Value]) -> bool {
    let has = |name: &str| inputs.iter().any(|i| i["NAME"] == name);
    has("progress") && has("startImage") && has("endImage")
}

#[test]
fn every_bundled_isf_file_renders_as_the_reference_renderer_does() {
    let Some(package) = std::env::var_os("INDRA_ISF_REFERENCE") else {
        assert!(std::env::var_os("CI").is_none(), "CI runs the ISF reference test: INDRA_ISF_REFERENCE is unset");
        return eprintln!("skipped: no reference ISF renderer (tools/setup-isf-reference installs it)");
    };
    let package = Path::new(&package);
    let mut sources = serde_json::Map::new();
    for folder in ["lib", "vendor"] {
        for entry in std::fs::read_dir(package.join(folder)).expect("the reference renderer's package").flatten() {
            let text = std::fs::read_to_string(entry.path()).unwrap();
            sources.insert(format!("{folder}/{}", entry.file_name().to_string_lossy()), Value::String(text));
        }
    }
    let dir = scratch_dir("isf-reference");
    let pictures = [picture(0), picture(1)];
    for (id, rgba) in ["a", "b"].iter().zip(&pictures) {
        write_png(&dir.join(format!("{id}.png")), SIZE, rgba).unwrap();
    }
    let assets = assets().allowing(&dir);

    let chromium = Chromium::start(&dir.join("profile"));
    let mut page = chromium.open("about:blank");
    page.eval(include_str!("../isf_reference/harness.js"));
    page.eval(&format!("isfReferenceLoad({})", Value::Object(sources)));
    page.eval(&format!("window.pictures = {}; true", json!([pictures[0], pictures[1]])));

    let files: Vec<(&str, &str)> = indra::assets::bundled_isf().filter(|(p, _)| p.ends_with(".fs")).collect();
    let vertex = |fs: &str| indra::assets::bundled_isf().find(|(p, _)| *p == fs.replace(".fs", ".vs")).map(|(_, t)| t);
    let (mut agree, mut differ, mut scores) = (Vec::new(), Vec::new(), Vec::new());
    for (file, fragment) in &files {
        let inputs = inputs(fragment);
        let values = if is_transition(&inputs) { json!({ "progress": 0.5 }) } else { json!({}) };
        let job = json!({
            "fragment": fragment, "vertex": vertex(file), "width": SIZE.0, "height": SIZE.1,
            "frames": FRAMES, "dt": DT, "date": [2026, 1, 1, 0], "values": values,
        });
        let call =
            format!("(() => {{ const job = {job}; job.images = window.pictures; return isfReferenceRender(job); }})()");
        let reference = page.try_eval(&call).unwrap_or_else(
            |e| json!({ "error": format!("reference threw {}", e["exceptionDetails"]["exception"]["description"]) }),
        );
        let name = Path::new(file).file_stem().unwrap().to_string_lossy().to_string();
        let outcome = match (reference["rgba"].as_array(), indra_render(&assets, &dir, file, &inputs)) {
            (None, _) => Err(format!("{}", reference["error"])),
            (_, Err(e)) => Err(format!("indra: {e}")),
            (Some(bytes), Ok(ours)) => {
                let theirs: Vec<u8> = bytes.iter().map(|b| b.as_u64().unwrap_or(0) as u8).collect();
                let (score, error) = flip_score(&theirs, &ours, SIZE, 0.99);
                let error: Vec<u8> = error.chunks(3).flat_map(|p| [p[0], p[1], p[2], 255]).collect();
                for (kind, rgba) in [("reference", &theirs), ("indra", &ours), ("flip", &error)] {
                    write_png(&dir.join(format!("{name}-{kind}.png")), SIZE, rgba).unwrap();
                }
                scores.push((name.clone(), score.mean));
                if score.mean <= MAX_MEAN { Ok(()) } else { Err(format!("mean FLIP {:.4}", score.mean)) }
            }
        };
        match outcome {
            Ok(()) => agree.push(name),
            Err(why) => differ.push((name, why)),
        }
    }
    scores.sort_by(|a, b| b.1.total_cmp(&a.1));
    println!("mean FLIP against the reference, worst first: {scores:.4?}");
    println!("pictures in {}", dir.display());
    let listed = |name: &str| OUTLIERS.iter().any(|(n, _)| *n == name);
    let unexpected: Vec<_> = differ.iter().filter(|(n, _)| !listed(n)).collect();
    let now_agree: Vec<_> = agree.iter().filter(|n| listed(n)).collect();
    assert!(unexpected.is_empty(), "differ from the reference: {unexpected:#?}");
    assert!(now_agree.is_empty(), "listed as outliers but agree now (take them off the list): {now_agree:?}");
    assert_eq!(agree.len() + differ.len(), files.len());
}
