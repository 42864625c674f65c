//! Projection mapping on the GPU: the corner pin puts source points at the pixels the
//! homography says, complementary soft edges sum to the source in linear light, warp files load,
//! save and survive a broken edit, and the bundled scene matches its golden.

use crate::common;

use crate::common::{assets, gpu, render_named};
use indra::assets::Assets;
use indra::geometry::warp::{Corners, MeshWarp, WarpFile};
use indra::gpu::Gpu;
use indra::graph::{FrameGraph, GraphRuntime};
use indra::params::{ParamSet, ParamValue, Text};
use indra::techniques::{NodeSetup, Technique, warp};
use indra::time::FrameTime;

const SIZE: (u32, u32) = (256, 256);
const TIME: FrameTime = FrameTime { frame: 0, seconds: 0.0, dt: 1.0 / 60.0, seed: 0 };

/// A warp node with its parameters.
struct Node {
    node: Box<dyn Technique>,
    params: ParamSet,
}

impl Node {
    fn new(gpu: &Gpu) -> Self {
        Self::with_assets(gpu, &assets())
    }

    fn with_assets(gpu: &Gpu, assets: &Assets) -> Self {
        let params = ParamSet::new(warp::Settings::decls());
        let setup = NodeSetup { gpu, assets, id: "wall", output_size: SIZE, msaa: 1, params: &params, seed: 1 };
        Self { node: (warp::INFO.create)(&setup).unwrap(), params: ParamSet::new(warp::Settings::decls()) }
    }

    fn set(&mut self, name: &str, value: ParamValue) {
        assert!(self.params.set_at(self.params.index(name).unwrap(), value), "{name}");
    }

    /// One fixed step, with values loaded from a file set as the scene would.
    fn step(&mut self) -> Vec<String> {
        self.params.snap();
        self.node.step(&self.params, &TIME);
        for (name, value) in self.node.take_loaded_values() {
            self.set(name, value);
        }
        self.params.snap();
        self.params.end_step();
        self.node.take_messages()
    }

    /// Warps `source` (RGBA, linear, SIZE) and returns the output's RGBA in linear light.
    fn draw(&mut self, gpu: &Gpu, source: &[[f32; 4]]) -> Vec<[f32; 4]> {
        let texture = common::float_texture(gpu, SIZE, source);
        let mut runtime = GraphRuntime::new(&gpu.device, &gpu.queue);
        let mut graph = FrameGraph::new(SIZE);
        let input = graph.import_texture("source", &texture);
        let output = self.node.add_passes(&mut graph, &self.params, &TIME, &[input]);
        graph.set_output(output);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let frame = runtime.execute(&gpu.device, &gpu.queue, graph, &mut encoder).unwrap();
        gpu.queue.submit([encoder.finish()]);
        common::read_float_texture(gpu, &frame.texture)
    }
}

/// Source points (u, v up) the pin tests follow.
const POINTS: [[f32; 2]; 5] = [[0.5, 0.5], [0.25, 0.25], [0.75, 0.3], [0.3, 0.78], [0.8, 0.8]];

/// A black source with a small Gaussian spot (σ = 2 texels) centred on each of `POINTS`.
fn spots() -> Vec<[f32; 4]> {
    (0..SIZE.0 * SIZE.1)
        .map(|i| {
            let (x, y) = ((i % SIZE.0) as f32 + 0.5, (i / SIZE.0) as f32 + 0.5);
            let value: f32 = POINTS
                .iter()
                .map(|p| {
                    let (cx, cy) = (p[0] * SIZE.0 as f32, (1.0 - p[1]) * SIZE.1 as f32);
                    (-((x - cx).powi(2) + (y - cy).powi(2)) / 8.0).exp()
                })
                .sum();
            [value, value, value, 1.0]
        })
        .collect()
}

/// The brightness-weighted centre (in pixels, y down) of what lies within 8 px of `near`.
fn centroid(image: &[[f32; 4]], near: [f64; 2]) -> [f64; 2] {
    let (mut sum, mut x, mut y) = (0.0, 0.0, 0.0);
    for py in 0..SIZE.1 {
        for px in 0..SIZE.0 {
            let (cx, cy) = (f64::from(px) + 0.5, f64::from(py) + 0.5);
            if (cx - near[0]).abs() > 8.0 || (cy - near[1]).abs() > 8.0 {
                continue;
            }
            let w = f64::from(image[(py * SIZE.0 + px) as usize][0]);
            sum += w;
            x += w * cx;
            y += w * cy;
        }
    }
    [x / sum, y / sum]
}

/// Where `warp` sends source point `p`, in pixels (y down).
fn expected_pixel(warp: &WarpFile, p: [f32; 2]) -> [f64; 2] {
    let view = warp.map(p[0], p[1]).unwrap();
    [view[0] * f64::from(SIZE.0), (1.0 - view[1]) * f64::from(SIZE.1)]
}

fn set_corners(node: &mut Node, corners: &Corners) {
    for (name, at) in
        warp::CORNERS.iter().zip([corners.top_left, corners.top_right, corners.bottom_right, corners.bottom_left])
    {
        node.set(name, ParamValue::Vec2(at));
    }
}

#[test]
fn the_corner_pin_puts_source_points_on_the_pixels_the_homography_gives() {
    let gpu = gpu();
    let mut node = Node::new(&gpu);
    let corners = Corners {
        top_left: [0.08, 0.9],
        top_right: [0.95, 0.97],
        bottom_right: [0.85, 0.04],
        bottom_left: [0.12, 0.15],
    };
    set_corners(&mut node, &corners);
    node.step();
    let image = node.draw(&gpu, &spots());
    let warp = WarpFile { corners, ..Default::default() };
    for p in POINTS {
        let want = expected_pixel(&warp, p);
        let got = centroid(&image, want);
        let error = ((got[0] - want[0]).powi(2) + (got[1] - want[1]).powi(2)).sqrt();
        assert!(error < 0.1, "source {p:?}: spot at {got:?}, the homography says {want:?} ({error:.3} px)");
    }
    // Outside the pinned quad the projector shows black.
    assert_eq!(image[0], [0.0, 0.0, 0.0, 1.0]);
}

#[test]
fn a_mesh_from_a_warp_file_moves_points_where_the_mesh_says() {
    let gpu = gpu();
    let dir = common::sandbox("warp-mesh");
    let mut mesh = MeshWarp::regular(3, 3);
    mesh.points[4] = [0.55, 0.46];
    mesh.points[1] = [0.5, 0.04];
    let corners = Corners { top_left: [0.05, 0.95], ..Default::default() };
    let warp = WarpFile { corners, mesh: Some(mesh), ..Default::default() };
    let file = dir.join("wall.ron");
    std::fs::write(&file, warp.to_ron()).unwrap();
    let mut node = Node::with_assets(&gpu, &assets().allowing(&dir));
    node.set("file", ParamValue::Text(Text::new(file.to_str().unwrap())));
    assert!(node.step().is_empty());
    assert_eq!(node.params.vec2("corner_tl"), [0.05, 0.95], "the file's corners became the parameters");
    let image = node.draw(&gpu, &spots());
    for p in POINTS {
        let want = expected_pixel(&warp, p);
        let got = centroid(&image, want);
        let error = ((got[0] - want[0]).powi(2) + (got[1] - want[1]).powi(2)).sqrt();
        // The smooth surface is drawn as 16 flat pieces per cell: a little off between them.
        assert!(error < 0.25, "source {p:?}: spot at {got:?}, the mesh says {want:?} ({error:.3} px)");
    }
}

#[test]
fn complementary_soft_edges_sum_to_the_source_in_linear_light() {
    // Projector A fades out over its right quarter, B fades in over its left quarter; both show
    // the same content there, so A(x) + B(x − 0.75 W) must be the source, texel by texel.
    let gpu = gpu();
    let source: Vec<[f32; 4]> = (0..SIZE.0 * SIZE.1).map(|_| [0.7, 0.35, 0.1, 1.0]).collect();
    let mut a = Node::new(&gpu);
    a.set("blend_right", ParamValue::Float(0.25));
    a.set("blend_curve", ParamValue::Float(3.0));
    a.step();
    let mut b = Node::new(&gpu);
    b.set("blend_left", ParamValue::Float(0.25));
    b.set("blend_curve", ParamValue::Float(3.0));
    b.step();
    let (image_a, image_b) = (a.draw(&gpu, &source), b.draw(&gpu, &source));
    let row = 100 * SIZE.0 as usize;
    let mut zone = 0;
    for x in 192..256usize {
        let (pa, pb) = (image_a[row + x], image_b[row + x - 192]);
        for c in 0..3 {
            let sum = pa[c] + pb[c];
            assert!((sum - source[0][c]).abs() < 4e-3, "x {x}, channel {c}: {} + {} = {sum}", pa[c], pb[c]);
        }
        zone += usize::from(pa[0] > 0.01 && pa[0] < 0.69);
    }
    assert!(zone > 32, "the overlap is a ramp, not a cut ({zone} texels in between)");
    assert!((image_a[row + 100][0] - 0.7).abs() < 1e-3, "outside the zone the source is untouched");
}

#[test]
fn the_black_lift_raises_black_outside_the_blend_zones_only() {
    let gpu = gpu();
    let black: Vec<[f32; 4]> = (0..SIZE.0 * SIZE.1).map(|_| [0.0, 0.0, 0.0, 1.0]).collect();
    let mut node = Node::new(&gpu);
    node.set("blend_left", ParamValue::Float(0.25));
    node.set("black_lift", ParamValue::Float(0.05));
    node.step();
    let image = node.draw(&gpu, &black);
    let row = 128 * SIZE.0 as usize;
    assert!((image[row + 200][0] - 0.05).abs() < 1e-3, "lifted: {:?}", image[row + 200]);
    assert_eq!(image[row + 20][0], 0.0, "the overlap keeps its (doubled) projector black");
}

#[test]
fn a_broken_warp_file_keeps_the_last_good_warp_and_save_writes_what_is_live() {
    let gpu = gpu();
    let dir = common::sandbox("warp-file");
    let file = dir.join("wall.ron");
    let good = WarpFile { corners: Corners { bottom_left: [0.1, 0.1], ..Default::default() }, ..Default::default() };
    std::fs::write(&file, good.to_ron()).unwrap();
    let mut node = Node::with_assets(&gpu, &assets().allowing(&dir));
    node.set("file", ParamValue::Text(Text::new(file.to_str().unwrap())));
    assert!(node.step().is_empty());
    assert_eq!(node.params.vec2("corner_bl"), [0.1, 0.1]);

    std::fs::write(&file, "(corners: (top_left: (0.0, 1.0)").unwrap();
    node.set("reload", ParamValue::Trigger(true));
    let messages = node.step();
    assert_eq!(messages.len(), 1, "{messages:?}");
    assert!(messages[0].contains("wall.ron:1:") && messages[0].contains("keeping the last good warp"), "{messages:?}");
    assert_eq!(node.params.vec2("corner_bl"), [0.1, 0.1], "the last good corners stay");

    node.set("corner_tr", ParamValue::Vec2([0.9, 0.8]));
    node.set("blend_top", ParamValue::Float(0.1));
    node.set("save", ParamValue::Trigger(true));
    let messages = node.step();
    assert!(messages.iter().any(|m| m.starts_with("warp saved to")), "{messages:?}");
    let saved = WarpFile::parse("wall.ron", &std::fs::read_to_string(&file).unwrap()).unwrap();
    assert_eq!(saved.corners.top_right, [0.9, 0.8]);
    assert_eq!(saved.corners.bottom_left, [0.1, 0.1]);
    assert_eq!(saved.blend.top, 0.1);

    node.set("file", ParamValue::Text(Text::new(dir.join("missing.ron").to_str().unwrap())));
    let messages = node.step();
    assert!(messages.len() == 1 && messages[0].contains("cannot read warp file"), "{messages:?}");
    assert!(node.step().is_empty(), "a bad path is said once");
}

#[test]
fn projection_mapping_matches_its_golden_with_and_without_the_grid() {
    let frame = render_named("projection_mapping", (192, 108), 30);
    crate::common::golden_beside(file!(), 0.01, 0.3).check("projection_mapping", frame.size, &frame.rgba).unwrap();
    let mut scene = indra::scene::load_scene(&assets(), "projection_mapping").unwrap();
    scene.set_from_str("wall.grid=true").unwrap();
    let frame = common::render_scene(scene, (192, 108), 30);
    crate::common::golden_beside(file!(), 0.01, 0.3).check("projection_mapping_grid", frame.size, &frame.rgba).unwrap();
}

#[test]
fn scene_outputs_get_a_warp_node_each_and_corner_addresses() {
    let scene = indra::scene::load_scene(&assets(), "two_projectors").unwrap();
    assert_eq!(scene.outputs.len(), 2);
    let map = indra::control::AddressMap::new(&scene);
    for (n, file) in [(1, "warps/wall-left-half.ron"), (2, "warps/wall-right.ron")] {
        let output = &scene.outputs[n - 1];
        let node = &scene.nodes[output.node];
        assert_eq!((node.id.as_str(), node.technique.name), (format!("output{n}").as_str(), "warp"));
        assert_eq!(node.params.get("file"), ParamValue::Text(Text::new(file)));
        assert_eq!((output.monitor, output.fullscreen), (Some(n), true));
        for (c, name) in warp::CORNERS.iter().enumerate() {
            let route = map.route(&format!("/indra/output/{n}/corner/{c}"));
            let target =
                indra::params::Target { node: output.node, param: node.params.index(name).unwrap(), component: None };
            assert_eq!(route, Some(indra::control::Route::Param(target)), "output {n} corner {c}");
        }
    }
    let broken = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/two_projectors.ron"))
        .unwrap()
        .replace("(warp: \"warps/wall-right.ron\"", "(source: \"nowhere\", warp: \"warps/wall-right.ron\"");
    let e = indra::scene::parse_scene("two.ron", &broken).err().unwrap().to_string();
    assert!(e.contains("'nowhere'"), "{e}");
}

#[test]
fn each_projector_output_matches_its_golden() {
    for n in [1, 2] {
        let scene = indra::scene::load_scene(&assets(), "two_projectors").unwrap();
        let mut r =
            indra::offscreen::OffscreenRenderer::new(gpu(), &assets(), scene, Some((192, 108)), None, None).unwrap();
        r.show_output(n).unwrap();
        r.seek(30).unwrap();
        let frame = r.render_next().unwrap();
        crate::common::golden_beside(file!(), 0.01, 0.3)
            .check(&format!("two_projectors_output{n}"), frame.size, &frame.rgba)
            .unwrap();
    }
}

#[test]
fn mesh_points_move_where_the_pointer_puts_them_and_save_with_the_warp() {
    let gpu = gpu();
    let dir = common::sandbox("warp-edit");
    let file = dir.join("wall.ron");
    let mut node = Node::with_assets(&gpu, &assets().allowing(&dir));
    let corners =
        Corners { top_left: [0.1, 0.9], top_right: [0.9, 0.95], bottom_right: [0.95, 0.1], bottom_left: [0.05, 0.0] };
    set_corners(&mut node, &corners);
    node.set("file", ParamValue::Text(Text::new(file.to_str().unwrap())));
    node.step();
    assert_eq!(node.node.handles().len(), 4, "no mesh: the four corners of the unit square");

    node.set("mesh_size", ParamValue::Vec2([3.0, 3.0]));
    node.step();
    let handles = node.node.handles();
    let warp = WarpFile { corners, ..Default::default() };
    assert_eq!(handles.len(), 9);
    let centre = warp.map(0.5, 0.5).unwrap();
    assert!((handles[4][0] - centre[0] as f32).abs() < 1e-5 && (handles[4][1] - centre[1] as f32).abs() < 1e-5);

    // Drag the centre point to a view position: it lands exactly there, through the pin.
    node.set("mesh_point", ParamValue::Vec3([4.0, 0.55, 0.42]));
    node.step();
    let moved = node.node.handles()[4];
    assert!((moved[0] - 0.55).abs() < 1e-5 && (moved[1] - 0.42).abs() < 1e-5, "{moved:?}");
    let image = node.draw(&gpu, &spots());
    let at = centroid(&image, [0.55 * 256.0, (1.0 - 0.42) * 256.0]);
    assert!(
        (at[0] - 0.55 * 256.0).abs() < 0.5 && (at[1] - 0.58 * 256.0).abs() < 0.5,
        "the source centre shows at {at:?}"
    );

    node.set("save", ParamValue::Trigger(true));
    node.step();
    let saved = WarpFile::parse("wall.ron", &std::fs::read_to_string(&file).unwrap()).unwrap();
    let mesh = saved.mesh.expect("the edited mesh is saved");
    assert_eq!((mesh.columns, mesh.rows), (3, 3));

    // A fresh node loading the file shows the same handles and takes the mesh's size.
    let mut again = Node::with_assets(&gpu, &assets().allowing(&dir));
    again.set("file", ParamValue::Text(Text::new(file.to_str().unwrap())));
    again.step();
    again.step();
    assert_eq!(again.params.vec2("mesh_size"), [3.0, 3.0]);
    for (a, b) in again.node.handles().iter().zip(node.node.handles()) {
        assert!((a[0] - b[0]).abs() < 1e-5 && (a[1] - b[1]).abs() < 1e-5);
    }
}

#[test]
fn outputs_from_the_command_line_get_the_same_warp_nodes_and_addresses() {
    let mut scene = indra::scene::load_scene(&assets(), "projection_mapping").unwrap();
    scene.add_output("warp=warps/wall-right.ron, monitor=2, fullscreen").unwrap();
    scene.add_output("source=limit_set, headless, ndi=clean feed, pipewire=clean").unwrap();
    assert_eq!(scene.outputs.len(), 2);
    let sends = &scene.outputs[1];
    assert_eq!(
        (sends.ndi.as_deref(), sends.pipewire.as_deref(), sends.headless),
        (Some("clean feed"), Some("clean"), true)
    );
    assert!(scene.outputs[0].ndi.is_none() && !scene.outputs[0].headless);
    let warped = &scene.nodes[scene.outputs[0].node];
    assert_eq!((warped.id.as_str(), warped.technique.name), ("output1", "warp"));
    assert_eq!((scene.outputs[0].monitor, scene.outputs[0].fullscreen), (Some(2), true));
    assert_eq!(scene.nodes[scene.outputs[1].node].id, "limit_set");
    let map = indra::control::AddressMap::new(&scene);
    assert!(map.route("/indra/output/1/corner/3").is_some() && map.route("/indra/output/2/corner/0").is_none());
    for (bad, said) in [
        ("colour=red", "'colour=red'"),
        ("source=nowhere", "'nowhere'"),
        ("monitor=left", "not a number"),
        ("headless", "sends nowhere"),
    ] {
        let e = scene.clone().add_output(bad).unwrap_err();
        assert!(e.contains(said), "{bad}: {e}");
    }
    // The added output renders what its warp makes of the scene's image.
    let render = |n: usize| {
        let mut r =
            indra::offscreen::OffscreenRenderer::new(gpu(), &assets(), scene.clone(), Some((96, 54)), None, None)
                .unwrap();
        r.show_output(n).unwrap();
        r.render_next().unwrap().rgba
    };
    let (main, projector) = (render(0), render(1));
    assert_ne!(main, projector);
    assert_eq!(&projector[..4], &[0, 0, 0, 255], "the right projector's region leaves its top-left corner black");
}

#[test]
fn a_warp_file_outside_the_allowed_folders_is_neither_read_nor_written() {
    let gpu = gpu();
    let dir = common::sandbox("warp-confined");
    let victim = dir.join("victim.conf");
    std::fs::write(&victim, "keep me").unwrap();
    let mut node = Node::new(&gpu);
    node.set("file", ParamValue::Text(Text::new(victim.to_str().unwrap())));
    let messages = node.step();
    assert!(messages.len() == 1 && messages[0].contains("outside the folders"), "{messages:?}");
    node.set("save", ParamValue::Trigger(true));
    let messages = node.step();
    assert!(messages.len() == 1 && messages[0].starts_with("warp not saved"), "{messages:?}");
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "keep me", "the file outside is untouched");

    // Inside the allowed folders a save replaces only a warp file: not a scene, not a preset.
    let scene = dir.join("scenes/show.ron");
    std::fs::write(&scene, "(name: \"show\", nodes: [], output: \"x\")").unwrap();
    let mut node = Node::with_assets(&gpu, &assets().allowing(&dir));
    node.set("file", ParamValue::Text(Text::new(scene.to_str().unwrap())));
    node.step();
    node.set("save", ParamValue::Trigger(true));
    let messages = node.step();
    assert!(messages.iter().any(|m| m.contains("is not a warp file")), "{messages:?}");
    assert!(std::fs::read_to_string(&scene).unwrap().starts_with("(name:"), "the scene is untouched");

    // Allowed folders still refuse pipes and devices, at once: the step does not wait on them.
    #[cfg(unix)]
    {
        let fifo = dir.join("pipe.ron");
        assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
        let mut node = Node::with_assets(&gpu, &assets().allowing(&dir).allowing("/dev"));
        for path in [fifo.to_str().unwrap(), "/dev/zero"] {
            node.set("file", ParamValue::Text(Text::new(path)));
            let started = std::time::Instant::now();
            let messages = node.step();
            assert!(messages.len() == 1 && messages[0].contains("not a regular file"), "{path}: {messages:?}");
            assert!(started.elapsed() < std::time::Duration::from_secs(5), "{path} held the step");
        }
    }
    std::fs::remove_dir_all(dir).unwrap();
}
