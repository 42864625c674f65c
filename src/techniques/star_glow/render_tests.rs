//! Chapter 4, StarGlow: the streak cascade's analytic weights, the composite formulas on known
//! pixels, book vs fused layouts, transient reuse in the frame graph, and golden renders.

use crate::common;

use crate::common::{assets, gpu, render_scene};
use indra::gpu::Gpu;
use indra::graph::{FrameGraph, GraphRuntime};
use indra::params::ParamSet;
use indra::scene::load_scene;
use indra::techniques::{NodeSetup, star_glow};
use indra::time::FrameTime;

const SIZE: (u32, u32) = (64, 64);

/// Runs one StarGlow node over `source` (RGBA f32 per texel) and returns its RGBA output.
fn glow(gpu: &Gpu, source: &[[f32; 4]], settings: &[(&str, &str)]) -> Vec<[f32; 4]> {
    glow_sized(gpu, SIZE, source, settings).0
}

/// [`glow`] at any size; also returns how many passes the node ran.
fn glow_sized(gpu: &Gpu, size: (u32, u32), source: &[[f32; 4]], settings: &[(&str, &str)]) -> (Vec<[f32; 4]>, usize) {
    let assets = assets();
    let mut node = (star_glow::INFO.create)(&NodeSetup {
        gpu,
        assets: &assets,
        id: "glow",
        output_size: size,
        msaa: 1,
        params: &ParamSet::new(star_glow::Settings::decls()),
        seed: 1,
    })
    .unwrap();
    let mut params = ParamSet::new(star_glow::Settings::decls());
    for (name, value) in settings {
        let i = params.index(name).unwrap();
        params.set_at(i, indra::scene::parse_value_override(value, &params.decls()[i]).unwrap());
    }
    let texture = common::float_texture(gpu, size, source);
    let mut runtime = GraphRuntime::new(&gpu.device, &gpu.queue);
    let mut graph = FrameGraph::new(size);
    let input = graph.import_texture("source", &texture);
    let time = FrameTime { frame: 0, seconds: 0.0, dt: 1.0 / 60.0, seed: 0 };
    let output = node.add_passes(&mut graph, &params, &time, &[input]);
    graph.set_output(output);
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let frame = runtime.execute(&gpu.device, &gpu.queue, graph, &mut encoder).unwrap();
    gpu.queue.submit([encoder.finish()]);
    (common::read_float_texture(gpu, &frame.texture), frame.stats.passes_executed)
}

fn single_texel(at: (u32, u32), value: f32) -> Vec<[f32; 4]> {
    (0..SIZE.0 * SIZE.1)
        .map(|i| if (i % SIZE.0, i / SIZE.0) == at { [value, value, value, 1.0] } else { [0.0, 0.0, 0.0, 1.0] })
        .collect()
}

const STREAK_ONLY: [(&str, &str); 8] = [
    ("resolution_independent", "false"),
    ("threshold", "0"),
    ("intensity", "1"),
    ("divide", "1"),
    ("attenuation", "0.5"),
    ("streaks", "1"),
    ("composite", "Debug"),
    ("iteration", "2"),
];

/// One bright texel of value 2 at (32, 40): after `iteration` levels the streak holds 2·att^k at
/// k texels *opposite* to the tap direction, for k < 4^iteration, and nothing elsewhere.
fn check_cascade(layout: &str, angle: &str, along: impl Fn(u32) -> (u32, u32)) {
    let gpu = gpu();
    let mut settings = STREAK_ONLY.to_vec();
    settings.extend([("layout", layout), ("angle", angle)]);
    let out = glow(&gpu, &single_texel((32, 40), 2.0), &settings);
    let mut expected = vec![0.0f32; out.len()];
    for k in 0..16 {
        let (x, y) = along(k);
        expected[(y * SIZE.0 + x) as usize] = 2.0 * 0.5f32.powi(k as i32);
    }
    for (i, (o, e)) in out.iter().zip(&expected).enumerate() {
        let (x, y) = (i as u32 % SIZE.0, i as u32 / SIZE.0);
        assert!(
            (o[0] - e).abs() <= 2e-3 * e.max(1.0),
            "{layout}, angle {angle}: texel ({x}, {y}) = {} expected {e}",
            o[0]
        );
    }
}

#[test]
fn a_bright_texel_streaks_with_weights_att_pow_k_opposite_to_the_offset() {
    // Angle 0: taps step down (+y), so the streak extends upwards from the texel.
    check_cascade("Book", "0", |k| (32, 40 - k));
    check_cascade("Fused", "0", |k| (32, 40 - k));
    // Angle 270: (0, -1) turned by 630° steps left (-x), so the streak extends to the right.
    check_cascade("Book", "270", |k| (32 + k, 40));
    check_cascade("Fused", "270", |k| (32 + k, 40));
    // Three streaks over three levels (64 taps each): both layouts agree texel for texel.
    let gpu = gpu();
    let image = single_texel((20, 30), 3.0);
    let run = |layout| {
        let mut s = STREAK_ONLY.to_vec();
        s.extend([
            ("layout", layout),
            ("streaks", "3"),
            ("iteration", "3"),
            ("angle", "17"),
            ("composite", "Additive"),
        ]);
        glow(&gpu, &image, &s)
    };
    let (book, fused) = (run("Book"), run("Fused"));
    for (b, f) in book.iter().zip(&fused) {
        assert!((b[0] - f[0]).abs() <= 2e-3 * b[0].abs().max(1.0), "book {} vs fused {}", b[0], f[0]);
    }
}

#[test]
fn both_layouts_clamp_taps_to_the_edge_alike() {
    // A bright texel in a corner: taps past the edge read the edge texel again (Unity's
    // clamp-to-edge render textures), so the streaks along the border pile up. The book layout
    // taps one texture per direction, the fused layout one layer of an array per direction:
    // whole-texel steps (angle 0) and blended ones (angle 17) must agree texel for texel, and the
    // pile-up must be there (a repeating sampler would wrap the taps onto black texels).
    let gpu = gpu();
    let image = single_texel((63, 0), 2.0);
    for angle in ["0", "17"] {
        let run = |layout| {
            let mut s = STREAK_ONLY.to_vec();
            s.extend([("layout", layout), ("streaks", "4"), ("iteration", "3"), ("angle", angle)]);
            glow(&gpu, &image, &s)
        };
        let (book, fused) = (run("Book"), run("Fused"));
        for (i, (b, f)) in book.iter().zip(&fused).enumerate() {
            let (x, y) = (i as u32 % SIZE.0, i as u32 / SIZE.0);
            assert!(
                (b[0] - f[0]).abs() <= 2e-3 * b[0].abs().max(1.0),
                "angle {angle}, ({x}, {y}): book {} fused {}",
                b[0],
                f[0]
            );
        }
        if angle == "0" {
            // The first streak taps to the right (+x), past the edge: the corner texel, then three
            // taps clamped onto it.
            let corner = fused[63][0];
            assert!(corner > 2.0 + 2.0 * 0.5, "the taps past the edge read the corner again: {corner}");
        }
    }
}

/// A source of sparse bright texels (a quarter of them, up to 4 × `scale` in steps of
/// `scale` / 256, which f16 holds exactly for a power-of-two scale; some at the edges), texel i
/// taking the value of texel `pick(i)` of the pattern.
fn scattered_texels(size: (u32, u32), scale: f32, pick: impl Fn(u32) -> u32) -> Vec<[f32; 4]> {
    (0..size.0 * size.1)
        .map(pick)
        .map(|i| {
            let h = i.wrapping_mul(2_654_435_761).rotate_left(13).wrapping_mul(40_503);
            let v = if h % 4 == 0 { (h >> 22) as f32 / 256.0 * scale } else { 0.0 };
            [v, v * 0.5, v * (h % 3) as f32 / 2.0, 1.0]
        })
        .collect()
}

/// One scan case: output size, streaks, angle, iterations, attenuation, divide, source scale.
type ScanCase = ((u32, u32), u32, f32, i32, f64, u32, f32);

/// The glow by its definition at texel `i` (divide 1), in f64: each streak d sums att^k × the
/// source at p + k·s·step_d (clamped to the image) for k < 4^iteration, and the streaks are
/// screen-accumulated in order.
fn glow_by_definition(
    source: &[[f32; 4]],
    (size, streaks, angle, iteration, att, ..): ScanCase,
    s: i64,
    i: i64,
) -> [f64; 3] {
    let (w, h) = (i64::from(size.0), i64::from(size.1));
    let mut glow = [0.0f64; 3];
    for d in 1..=streaks {
        let [x, y] = star_glow::streak_step(d, streaks, angle);
        let (dx, dy) = (x.round() as i64, y.round() as i64);
        let mut streak = [0.0f64; 3];
        for k in 0..4i64.pow(iteration as u32) {
            let px = (i % w + k * s * dx).clamp(0, w - 1);
            let py = (i / w + k * s * dy).clamp(0, h - 1);
            let texel = source[(py * w + px) as usize];
            for c in 0..3 {
                streak[c] += att.powi(k as i32) * f64::from(texel[c]);
            }
        }
        for c in 0..3 {
            glow[c] += streak[c] * (1.0 - glow[c]).max(0.0);
        }
    }
    glow
}

#[test]
fn the_scan_gives_the_streaks_by_their_definition() {
    // Where every streak steps whole texels along an axis and reaches past the image, Auto takes
    // the scan (bright, scan, screen, composite). At divide 1 it must give the glow by its
    // definition within three f16 roundings (the streak, the glow, the composite), and closer than
    // the cascade (Fused), which rounds every level; at divide 2 it must give the cascade's image
    // (the composite upsamples both alike). Single streaks in each of the four directions carry
    // large HDR sums; several streaks are kept below 1, where the screen blend cannot magnify a
    // rounding (above 1 it weighs the next streak by 1 - the sum so far). Lines of one chunk and
    // of several (over 256), steps of 1 and of 2 texels (resolution independent at 2160 rows),
    // attenuation 1 (counts), 0 (one tap) and between. Widths are powers of two, and at 2160
    // rows the lines across the streaks are alike: the composite's texel centres, (p + 0.5) /
    // size in f32, are exact only at powers of two, and elsewhere it blends ~1e-4 of a
    // neighbour, as the cascade's taps do (its unit steps miss the axis by ~1e-7 per texel of
    // reach) — a thousandth of sums in the thousands.
    let gpu = gpu();
    let cases: [ScanCase; 8] = [
        ((64, 64), 1, 0.0, 3, 1.0, 1, 1.0),
        ((64, 64), 1, 90.0, 4, 0.5, 1, 1.0),
        ((64, 64), 1, 180.0, 3, 0.0, 1, 1.0),
        ((1024, 8), 1, 270.0, 5, 0.9, 1, 1.0),
        ((512, 2160), 1, 90.0, 5, 1.0, 1, 1.0),
        ((512, 2160), 2, 90.0, 5, 0.97, 1, 1.0 / 1024.0),
        ((64, 64), 4, 0.0, 3, 1.0, 1, 1.0 / 64.0),
        ((8, 2160), 1, 0.0, 5, 1.0, 2, 1.0),
    ];
    for case in cases {
        let (size, streaks, angle, iteration, att, divide, scale) = case;
        let independent = size.1 == 2160;
        let along_x = angle as u32 % 180 == 90;
        let image = scattered_texels(size, scale, |i| match (independent, along_x) {
            (false, _) => i,
            (true, true) => i % size.0,
            (true, false) => i / size.0 * size.0,
        });
        let values = [
            independent.to_string(),
            streaks.to_string(),
            angle.to_string(),
            iteration.to_string(),
            att.to_string(),
            divide.to_string(),
        ];
        let run = |layout| {
            let names = ["resolution_independent", "streaks", "angle", "iteration", "attenuation", "divide"];
            let mut s: Vec<(&str, &str)> = names.into_iter().zip(values.iter().map(String::as_str)).collect();
            s.extend([("threshold", "0"), ("intensity", "1"), ("composite", "Debug"), ("layout", layout)]);
            glow_sized(&gpu, size, &image, &s)
        };
        let ((scan, scan_passes), (cascade, cascade_passes)) = (run("Auto"), run("Fused"));
        let name =
            format!("{size:?}, {streaks} streaks at {angle}°, {iteration} iterations, att {att}, divide {divide}");
        assert_eq!((scan_passes, cascade_passes), (4, 2 + iteration as usize), "{name}");
        let relative = |got: f32, want: f64| (f64::from(got) - want).abs() / want.abs().max(scale as f64);
        if divide > 1 {
            let worst = (scan.iter().zip(&cascade))
                .flat_map(|(a, b)| (0..3).map(move |c| relative(a[c], f64::from(b[c]))))
                .fold(0.0, f64::max);
            eprintln!("{name}: scan {worst:.1e} from the cascade");
            assert!(worst <= 8.0 * 2f64.powi(-10), "{name}: scan off the cascade by {worst:.1e}");
            continue;
        }
        // Every texel of the small cases, every 61st of the large (the definition is slow).
        let stride = if size.0 * size.1 > 10_000 { 61 } else { 1 };
        let step = if independent { 2 } else { 1 };
        let (mut scan_error, mut cascade_error, mut largest) = (0.0f64, 0.0f64, 0.0f64);
        for i in (0..scan.len()).step_by(stride) {
            let want = glow_by_definition(&image, case, step, i as i64);
            for c in 0..3 {
                scan_error = scan_error.max(relative(scan[i][c], want[c]));
                cascade_error = cascade_error.max(relative(cascade[i][c], want[c]));
                largest = largest.max(want[c]);
            }
        }
        eprintln!(
            "{name}: scan {scan_error:.1e}, cascade {cascade_error:.1e} from the definition (largest {largest:.1})"
        );
        assert!(largest > 2.0 * scale as f64, "{name}: the glow is there");
        assert!(scan_error <= 3.0 * 2f64.powi(-10), "{name}: scan off by {scan_error:.1e}");
        assert!(
            scan_error <= cascade_error.max(2f64.powi(-10)),
            "{name}: scan {scan_error:.1e}, cascade {cascade_error:.1e}"
        );
    }
}

#[test]
fn the_scan_is_left_to_the_cascade_where_it_would_differ() {
    // Steps that are not whole texels (256 rows: 0.237 texels a step), a diagonal streak, and
    // streaks that end inside the image: Auto keeps the cascade (bright, 3 levels, composite).
    let gpu = gpu();
    let image = scattered_texels(SIZE, 1.0, |i| i);
    let cases: [&[(&str, &str)]; 3] =
        [&[("resolution_independent", "true")], &[("streaks", "4"), ("angle", "45")], &[("iteration", "2")]];
    for case in cases {
        let mut s = vec![("resolution_independent", "false"), ("divide", "1"), ("iteration", "3"), ("streaks", "4")];
        s.extend_from_slice(case);
        let (_, passes) = glow_sized(&gpu, SIZE, &image, &s);
        let levels = if case.contains(&("iteration", "2")) { 2 } else { 3 };
        assert_eq!(passes, 2 + levels, "{case:?}");
    }
}

#[test]
fn composite_formulas_on_known_pixels() {
    let gpu = gpu();
    let s = [0.5f32, 0.25, 0.125];
    let source: Vec<[f32; 4]> = vec![[s[0], s[1], s[2], 1.0]; (SIZE.0 * SIZE.1) as usize];
    // Attenuation 0 and one level: the glow equals the source exactly.
    let base = [
        ("resolution_independent", "false"),
        ("threshold", "0"),
        ("intensity", "1"),
        ("divide", "1"),
        ("attenuation", "0"),
        ("streaks", "1"),
        ("iteration", "1"),
        ("color", "1,0,0"),
    ];
    let mean = (s[0] + s[1] + s[2]) / 3.0;
    let cases: [(&str, [f32; 3]); 5] = [
        ("Additive", [1.0, 0.5, 0.25]),
        ("Screen", [s[0] + s[0] * (1.0 - s[0]), s[1] + s[1] * (1.0 - s[1]), s[2] + s[2] * (1.0 - s[2])]),
        ("ColoredAdditive", [s[0] + mean, s[1], s[2]]),
        ("ColoredScreen", [s[0] + mean * (1.0 - s[0]), s[1], s[2]]),
        ("Debug", s),
    ];
    for (kind, want) in cases {
        let mut settings = base.to_vec();
        settings.push(("composite", kind));
        let out = glow(&gpu, &source, &settings);
        let px = out[(20 * SIZE.0 + 20) as usize];
        for c in 0..3 {
            assert!((px[c] - want[c]).abs() < 2e-3, "{kind}: channel {c} = {} expected {}", px[c], want[c]);
        }
    }
}

#[test]
fn hdr_values_are_not_clamped() {
    let gpu = gpu();
    let mut settings = STREAK_ONLY.to_vec();
    settings.push(("layout", "Book"));
    let out = glow(&gpu, &single_texel((10, 10), 6.0), &settings);
    assert!((out[(10 * SIZE.0 + 10) as usize][0] - 6.0).abs() < 1e-2, "the glow keeps its HDR value");
}

fn render_star_glow(sets: &[&str], frame: u64) -> indra::offscreen::RenderedFrame {
    let mut scene = load_scene(&assets(), "star_glow").unwrap();
    for s in sets {
        scene.set_from_str(s).unwrap();
    }
    render_scene(scene, (256, 256), frame)
}

#[test]
fn fused_layout_matches_the_book_layout() {
    for iteration in ["1", "2", "3"] {
        let set = format!("glow.iteration={iteration}");
        // The cubes through the pipeline: one draw pass (the compute draw is two).
        let book = render_star_glow(&[&set, "glow.layout=Book", "cubes.rasterizer=pipeline"], 60);
        let fused = render_star_glow(&[&set, "glow.layout=Fused", "cubes.rasterizer=pipeline"], 60);
        let levels: usize = iteration.parse().unwrap();
        // Each frame ends in the display encode (one pass).
        assert_eq!(
            fused.stats.passes_executed,
            1 + 2 + levels + 1,
            "cube draw + bright, one pass per level, composite"
        );
        assert_eq!(
            book.stats.passes_executed,
            1 + 2 + 5 * (levels + 1) + 1,
            "5 streaks: level passes and accumulations"
        );
        let (score, _) = indra::offscreen::flip_score(&book.rgba, &fused.rgba, (256, 256), 0.99);
        // Only f16 rounding differs: the book layout stores each streak before accumulating it.
        assert!(score.mean < 0.005 && score.percentile < 0.05, "iteration {iteration}: {score:?}");
    }
}

#[test]
fn book_layout_reuses_transient_textures() {
    // The sample's defaults: 4 streaks × 5 levels → 26 StarGlow passes; the cubes through the
    // pipeline (one pass, its multisampled targets).
    let sets = ["glow.layout=Book", "glow.streaks=4", "glow.iteration=5", "glow.divide=3", "cubes.rasterizer=pipeline"];
    let f = render_star_glow(&sets, 0);
    let s = &f.stats;
    // 27 and the display encode.
    assert_eq!((s.passes_declared, s.passes_executed), (28, 28));
    let (full, depth, small) = (256 * 256 * 8, 256 * 256 * 4, 86 * 86 * 8);
    // The cubes' 4× multisampled colour and depth, their resolved image, the output, and 25
    // small textures (bright, 20 levels, 4 accumulations).
    let cubes = 4 * full + 4 * depth + full;
    assert_eq!(s.transient_bytes_requested, cubes + full + 25 * small);
    // At most four small textures are alive at once: bright, the level being read, the level
    // being written (or the accumulation read), the accumulation written.
    assert_eq!(s.transient_bytes_allocated, cubes + full + 4 * small);
}

#[test]
fn zero_intensity_adds_no_passes() {
    let off = render_star_glow(&["glow.intensity=0"], 30);
    assert_eq!(off.stats.passes_executed, 3, "only the cube draw runs (raster, resolve), then the display encode");
    let on = render_star_glow(&[], 30);
    assert_ne!(off.rgba, on.rgba);
}

#[test]
fn golden_star_glow_at_two_times() {
    for frame in [0, 90] {
        let f = render_star_glow(&[], frame);
        crate::common::golden_beside(file!(), 0.01, 0.3)
            .check(&format!("star_glow_f{frame:04}"), (256, 256), &f.rgba)
            .unwrap_or_else(|e| panic!("{e}"));
    }
}

#[test]
fn golden_kleinian_star_glow_at_two_times() {
    for frame in [0, 240] {
        let f = common::render_named("kleinian_star_glow", (256, 256), frame);
        crate::common::golden_beside(file!(), 0.01, 0.3)
            .check(&format!("kleinian_star_glow_f{frame:04}"), (256, 256), &f.rgba)
            .unwrap_or_else(|e| panic!("{e}"));
    }
}
