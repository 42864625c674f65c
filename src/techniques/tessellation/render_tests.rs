//! Chapter 6 on lavapipe: the GPU's edge factors, culling and patch levels against a CPU
//! reference of the book's formulas for random cameras; crack-freeness (every edge shared by two
//! patches gets exactly the same displaced points from both sides, also where their levels
//! differ); golden renders of the three scenes at two times; a bad image path keeps the show.

use crate::common;

use std::collections::{BTreeMap, BTreeSet};

use indra::geometry::SplitMix64;
use indra::graph::{FrameGraph, GraphRuntime, PersistentTexture};
use indra::offscreen::OffscreenRenderer;
use indra::params::{ParamSet, ParamValue};
use indra::scene::load_scene;
use indra::techniques::tessellation::{self, Tessellation, reference};
use indra::techniques::{NodeSetup, Technique};
use indra::time::FixedClock;

/// A random height field (RGBA8, height in red), smooth enough to matter, rough enough to crack.
fn height_texture(gpu: &indra::gpu::Gpu, seed: u64) -> PersistentTexture {
    let (w, h) = (61, 47);
    let mut rng = SplitMix64::new(seed);
    let data: Vec<u8> = (0..w * h).flat_map(|_| [(rng.unit() * 255.0) as u8, 0, 0, 255]).collect();
    let t = PersistentTexture::new(&gpu.device, "test_heights", (w, h), wgpu::TextureFormat::Rgba8Unorm);
    gpu.queue.write_texture(
        t.texture.as_image_copy(),
        &data,
        wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(4 * w), rows_per_image: Some(h) },
        wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
    );
    t
}

/// A tessellation node with random camera settings, one frame run over `height`.
fn frame(
    gpu: &indra::gpu::Gpu,
    node: &mut Tessellation,
    height: &PersistentTexture,
    params: &ParamSet,
    size: (u32, u32),
) {
    let mut runtime = GraphRuntime::new(&gpu.device, &gpu.queue);
    let time = FixedClock::new(0.02, 1).now();
    let mut graph = FrameGraph::new(size);
    let input = graph.import_texture("height", height);
    let out = node.add_passes(&mut graph, params, &time, &[input]);
    graph.set_output(out);
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    runtime.execute(&gpu.device, &gpu.queue, graph, &mut encoder).expect("the frame runs");
    gpu.queue.submit([encoder.finish()]);
}

fn random_params(rng: &mut SplitMix64, grid: i32) -> ParamSet {
    let mut p = ParamSet::new(tessellation::Settings::decls());
    let mut set = |name: &str, value: ParamValue| p.set_at(p.index(name).unwrap(), value);
    set("grid", ParamValue::Int(grid));
    set("camera_yaw", ParamValue::Float(rng.unit() as f32 * 120.0 - 60.0));
    set("camera_pitch", ParamValue::Float(rng.unit() as f32 * 100.0 - 30.0));
    set("camera_distance", ParamValue::Float(4.0 + rng.unit() as f32 * 20.0));
    set("fov", ParamValue::Float(30.0 + rng.unit() as f32 * 60.0));
    set("edge_length", ParamValue::Float(2.0 + rng.unit() as f32 * 30.0));
    set("displacement", ParamValue::Float(rng.unit() as f32 * 2.0));
    p.snap();
    p
}

fn node(gpu: &indra::gpu::Gpu) -> Tessellation {
    let assets = common::assets();
    Tessellation::new(&NodeSetup {
        gpu,
        assets: &assets,
        id: "surface",
        output_size: (320, 200),
        msaa: 4,
        params: &ParamSet::new(tessellation::Settings::decls()),
        seed: 1,
    })
    .unwrap()
}

#[test]
fn edge_factors_culling_and_levels_match_the_books_formulas_for_random_cameras() {
    let gpu = common::gpu();
    let mut tess = node(&gpu);
    let height = height_texture(&gpu, 7);
    let mut rng = SplitMix64::new(0x5eed_1234);
    let (mut culled, mut compared) = (0, 0);
    for round in 0..12 {
        let params = random_params(&mut rng, 6 + round % 5);
        frame(&gpu, &mut tess, &height, &params, (320, 200));
        let u = tess.uniforms().unwrap();
        let (gpu_factors, gpu_levels) = (tess.read_factors(), tess.read_levels());
        let cpu_factors = reference::edge_factors(&u);
        assert_eq!(gpu_factors.len(), cpu_factors.len());
        for (e, (g, c)) in gpu_factors.iter().zip(&cpu_factors).enumerate() {
            assert!((g - c).abs() <= 1e-4 * c.max(1.0), "round {round} edge {e}: GPU {g}, CPU {c}");
        }
        for p in 0..u.patch_count {
            // A factor within rounding of a whole number may ceil either way: skip that patch.
            let (_, edges) = reference::patch(u.grid, p);
            let f = edges.map(|e| cpu_factors[e as usize]);
            let mean = (f[0] + f[1] + f[2]) / 3.0;
            if f.iter().chain([&mean]).any(|x| (x - x.round()).abs() < 1e-3) {
                continue;
            }
            let expected = reference::patch_level(&u, &cpu_factors, p);
            assert_eq!(gpu_levels[p as usize], expected, "round {round} patch {p}");
            culled += usize::from(expected == 0);
            compared += 1;
        }
    }
    assert!(compared > 500 && culled > 10, "compared {compared} patches, {culled} culled");
}

/// One patch's view of an edge: its level and the exact bits of its displaced boundary points.
type Side = (u32, BTreeSet<[u32; 3]>);

#[test]
fn displaced_neighbours_never_open_a_crack() {
    let gpu = common::gpu();
    let mut tess = node(&gpu);
    let mut rng = SplitMix64::new(0xc0ffee);
    let (mut edges_checked, mut mixed_levels) = (0, 0);
    for round in 0..10 {
        let height = height_texture(&gpu, 100 + round);
        let params = random_params(&mut rng, 8);
        frame(&gpu, &mut tess, &height, &params, (320, 200));
        let u = tess.uniforms().unwrap();
        let levels = tess.read_levels();
        let points = tess.boundary_points(&height.view);
        // Edge → for each patch on it, the set of its displaced boundary points (exact bits).
        let mut sides: BTreeMap<u32, Vec<Side>> = BTreeMap::new();
        for p in 0..u.patch_count {
            if levels[p as usize] == 0 {
                continue;
            }
            let (_, edges) = reference::patch(u.grid, p);
            for (k, &e) in edges.iter().enumerate() {
                let first = (p as usize * 3 + k) * 65;
                let set = points[first..first + 65]
                    .iter()
                    .filter(|q| q[3] == 1.0)
                    .map(|q| [q[0].to_bits(), q[1].to_bits(), q[2].to_bits()])
                    .collect();
                sides.entry(e).or_default().push((levels[p as usize], set));
            }
        }
        for (e, patches) in &sides {
            if let [(na, a), (nb, b)] = &patches[..] {
                assert_eq!(a, b, "round {round}: edge {e} differs between patches of level {na} and {nb}");
                edges_checked += 1;
                mixed_levels += usize::from(na != nb);
            }
        }
    }
    // The snapping matters where levels differ: the random cameras must produce such edges.
    assert!(edges_checked > 500 && mixed_levels > 25, "{edges_checked} shared edges, {mixed_levels} across levels");
}

const SIZE: (u32, u32) = (256, 144);

fn check_golden(scene: &str, frames: &[u64]) {
    let mut r = OffscreenRenderer::new(
        common::gpu(),
        &common::assets(),
        load_scene(&common::assets(), scene).unwrap(),
        Some(SIZE),
        None,
        None,
    )
    .unwrap();
    for &f in frames {
        r.seek(f).unwrap();
        let rendered = r.render_next().unwrap();
        common::golden_beside(file!(), 0.01, 0.3)
            .check(&format!("{scene}_f{f:04}"), SIZE, &rendered.rgba)
            .unwrap_or_else(|e| panic!("{e}"));
    }
}

#[test]
fn golden_tessellation_fluid_while_it_is_stirred() {
    check_golden("tessellation_fluid", &[45, 90]);
}

#[test]
fn golden_tessellation_kleinian_at_two_times() {
    check_golden("tessellation_kleinian", &[0, 60]);
}

#[test]
fn golden_tessellation_image_at_two_times() {
    check_golden("tessellation_image", &[0, 180]);
}

#[test]
fn a_bad_image_path_is_one_message_and_the_show_goes_on() {
    let mut scene = load_scene(&common::assets(), "tessellation_image").unwrap();
    scene.set_from_str("map.path=no/such/heights.png").unwrap();
    let mut r = OffscreenRenderer::new(common::gpu(), &common::assets(), scene, Some((64, 36)), None, None).unwrap();
    for _ in 0..3 {
        r.render_next().expect("frames still render");
    }
    let messages = r.instance_mut().take_messages();
    assert_eq!(messages.len(), 1, "{messages:?}");
    assert!(messages[0].contains("no/such/heights.png") && messages[0].starts_with("map:"), "{}", messages[0]);
}

#[test]
fn a_drag_stirs_the_fluid_under_the_pointer_on_the_plane() {
    let scene = load_scene(&common::assets(), "tessellation_fluid").unwrap();
    let size = (320, 180);
    let mut r = OffscreenRenderer::new(common::gpu(), &common::assets(), scene, Some(size), None, None).unwrap();
    r.render_next().unwrap();
    let instance = r.instance_mut();
    let (fluid, surface) = (0, 1);
    let u = tessellation::TessUniforms::from_params(instance.params(surface), size);
    let view = [0.4, 0.3];
    let expected = tessellation::pick(&u, view).expect("the plane is under the pointer");
    let events = instance.drag(view, true, indra::params::Source::Ui);
    let cursor = instance.params(fluid).index("cursor").unwrap();
    let written = events.iter().find_map(|e| match e {
        indra::params::ControlEvent::Write(w) if w.node == fluid && w.param == cursor => Some(w.value),
        _ => None,
    });
    let Some(ParamValue::Vec2(at)) = written else { panic!("no cursor write in {events:?}") };
    assert!((at[0] - expected[0]).abs() < 1e-5 && (at[1] - expected[1]).abs() < 1e-5, "{at:?} vs {expected:?}");
    assert!((at[0] - view[0]).abs() > 0.01 || (at[1] - view[1]).abs() > 0.01, "mapped, not the raw screen position");
}

/// Renders frame 0 of `tessellation_image` at `size` with `settings` (`node.param=value`), once
/// drawn in compute and once by the raster pipeline.
fn both_draws(settings: &[String], size: (u32, u32)) -> [Vec<u8>; 2] {
    ["compute", "pipeline"].map(|rasterizer| {
        let mut scene = load_scene(&common::assets(), "tessellation_image").unwrap();
        for s in settings.iter().map(String::as_str).chain([format!("surface.rasterizer={rasterizer}").as_str()]) {
            scene.set_from_str(s).unwrap_or_else(|e| panic!("{s}: {e}"));
        }
        common::render_scene(scene, size, 0).rgba
    })
}

#[test]
fn the_compute_draw_matches_the_pipeline_draw() {
    let size = (203, 117);
    // (settings, largest mean FLIP): the wireframe's lines are placed from derivatives, which
    // the pipeline takes over 2×2 pixel quads and the compute draw per pixel.
    let cases: &[(&[&str], f32)] = &[
        (&[], 0.01),
        (&["surface.view=shaded", "surface.msaa=off"], 0.01),
        // Too many possible triangles to keep their corners: the resolve evaluates them again.
        (&["surface.grid=40", "surface.edge_length=12"], 0.01),
        (&["surface.view=wireframe", "surface.edge_length=12"], 0.08),
        // Large triangles (the queue) and a camera inside the relief (near-plane clipping).
        (&["surface.grid=1", "surface.edge_length=50", "surface.view=wireframe"], 0.04),
        (&["surface.camera_distance=5", "surface.camera_pitch=0", "surface.view=shaded"], 0.01),
        (&["surface.camera_distance=5.5", "surface.camera_pitch=0", "surface.displacement=2"], 0.01),
    ];
    for (case, bound) in cases {
        let settings: Vec<String> =
            case.iter().map(|s| s.to_string()).chain(["surface.background=[1.0, 1.0, 1.0, 1.0]".into()]).collect();
        let [compute, pipeline] = both_draws(&settings, size);
        let drawn = pipeline.chunks(4).filter(|p| p[..3] != [255, 255, 255]).count();
        assert!(drawn > (size.0 * size.1 / 5) as usize, "{case:?}: only {drawn} pixels drawn");
        let (score, _) = indra::offscreen::flip_score(&pipeline, &compute, size, 0.99);
        assert!(score.mean < *bound, "{case:?}: mean FLIP {} (bound {bound})", score.mean);
    }
}

#[test]
fn the_compute_draw_leaves_no_crack_between_triangles() {
    // Magenta behind a rough, strongly displaced relief seen from random cameras without
    // multisampling: every pixel the pipeline covers, away from the silhouette, must be covered
    // in compute too (a crack or a dropped edge shows the background).
    let size = (160, 96);
    let mut rng = SplitMix64::new(0xc4ac);
    let (mut inner, mut cases) = (0, 0);
    for _ in 0..6 {
        let settings: Vec<String> = [
            "surface.msaa=off".to_string(),
            "surface.background=[1.0, 0.0, 1.0, 1.0]".to_string(),
            format!("surface.grid={}", 2 + (rng.unit() * 10.0) as u32),
            format!("surface.edge_length={}", 1.0 + rng.unit() * 20.0),
            format!("surface.displacement={}", rng.unit() * 3.0),
            format!("surface.camera_yaw={}", rng.unit() * 120.0 - 60.0),
            format!("surface.camera_pitch={}", rng.unit() * 60.0),
            format!("surface.camera_distance={}", 3.0 + rng.unit() * 8.0),
        ]
        .to_vec();
        let [compute, pipeline] = both_draws(&settings, size);
        let background = |image: &[u8], x: i64, y: i64| {
            let (x, y) = (x.clamp(0, size.0 as i64 - 1), y.clamp(0, size.1 as i64 - 1));
            let i = 4 * (y as usize * size.0 as usize + x as usize);
            image[i] > 250 && image[i + 1] < 5 && image[i + 2] > 250
        };
        for y in 0..size.1 as i64 {
            for x in 0..size.0 as i64 {
                let interior = (-1..=1).all(|dy| (-1..=1).all(|dx| !background(&pipeline, x + dx, y + dy)));
                if interior {
                    inner += 1;
                    assert!(!background(&compute, x, y), "{settings:?}: a crack at ({x}, {y})");
                }
            }
        }
        cases += 1;
    }
    assert!(inner > cases * 2000, "only {inner} interior pixels in {cases} views");
}
