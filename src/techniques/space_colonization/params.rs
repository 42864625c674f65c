//! Space colonization parameters (the book's, with its defaults and ranges) and the uniform
//! blocks built from them.

use crate::params::{InputRole, ParamDecl, ParamSet, ParamValue};

/// Search strategies, in the order of the `search` enum parameter.
pub const SEARCHES: [&str; 2] = ["BruteForce", "Grid"];
/// Views, in the order of the `view` enum parameter.
pub const VIEWS: [&str; 3] = ["Lines", "Tubes", "TubesLit"];
/// Attraction sources, in the order of the `source` enum parameter.
pub const SOURCES: [&str; 2] = ["Sphere", "Model"];
/// Multisampling choices, in the order of the `msaa` enum parameter.
pub const MSAA_MODES: [&str; 2] = ["off", "on"];
/// Most grid cells (the cell grows past the reach before the grid grows past this).
pub const MAX_CELLS: u32 = 1 << 21;

/// Parameters with the sample's defaults (seed-reference §1). Distances are in units of the
/// lattice's `unit` (2 / side for the sphere, as the sample measures them); the sample's growth
/// and kill defaults of 0.2 sat below their own 0.25 minimum (bug 7) and are 0.25 here.
pub fn params() -> Vec<ParamDecl> {
    use ParamValue::*;
    vec![
        ParamDecl::choice(
            "source",
            &SOURCES,
            0,
            "attractions in a jittered lattice sphere, or inside the model's volume",
        ),
        ParamDecl::new(
            "side",
            Int(16),
            Some((8.0, 128.0)),
            "lattice points per axis: side 28 gives 10,144 attractions, 126 gives 1,022,208 (restarts)",
        ),
        ParamDecl::new("seed_count", Int(6), Some((1.0, 64.0)), "branches to start from (restarts)"),
        ParamDecl::new("variation", Int(0), Some((0.0, 1e6)), "another jitter and other seeds (restarts)"),
        ParamDecl::text(
            "model",
            "assets/models/RiggedFigure.gltf",
            "glTF 2.0 skinned model (.gltf or .glb) for the Model source",
        ),
        ParamDecl::new("voxels", Int(64), Some((16.0, 256.0)), "model voxels along its longest side (restarts)"),
        ParamDecl::new(
            "spacing",
            Float(1.0),
            Some((0.5, 4.0)),
            "least distance between model attractions, in voxels (restarts)",
        ),
        ParamDecl::new(
            "unit_scale",
            Float(2.5),
            Some((0.5, 10.0)),
            "model distance unit, in voxels (the sample's unitScale)",
        ),
        ParamDecl::new(
            "animation_speed",
            Float(0.5),
            Some((0.0, 4.0)),
            "speed of the model's clip, played back and forth",
        ),
        ParamDecl::new("show_model", Bool(false), None, "draw the model's skin as a faint glow over the branches"),
        ParamDecl::new("floor", Bool(false), None, "a lit floor under the model"),
        ParamDecl::new("floor_color", Color([0.868, 0.868, 0.868, 1.0]), None, "floor colour"),
        ParamDecl::new("update_every", Int(1), Some((1.0, 5.0)), "frames between growth updates (the sample's frame)"),
        ParamDecl::new("steps", Int(1), Some((1.0, 16.0)), "growth steps per update (the sample's iterations)"),
        ParamDecl::new("mass_min", Float(0.25), Some((0.0, 1.0)), "lightest node: grows slowest"),
        ParamDecl::new("mass_max", Float(1.0), Some((0.0, 1.0)), "heaviest node: grows fastest"),
        ParamDecl::new("influence", Float(0.25), Some((0.25, 3.0)), "how far an attraction reaches, in units"),
        ParamDecl::new("growth_distance", Float(0.25), Some((0.25, 1.0)), "length of a new branch segment, in units"),
        ParamDecl::new(
            "kill_distance",
            Float(0.25),
            Some((0.25, 1.0)),
            "attractions this close to a node die, in units",
        ),
        ParamDecl::new(
            "growth_speed",
            Float(22.0),
            Some((0.0, 200.0)),
            "how fast a new segment grows out (t per second per mass)",
        ),
        ParamDecl::choice("search", &SEARCHES, 1, "nearest-node search: a uniform grid, or every node (the sample's)"),
        ParamDecl::choice(
            "view",
            &VIEWS,
            0,
            "additive lines, tubes coloured by normal, or lit tubes with glowing tips",
        ),
        ParamDecl::new("thickness", Float(0.1), Some((0.001, 0.1)), "tube radius").with_unit("m"),
        ParamDecl::new("color", Color([1.0, 1.0, 1.0, 1.0]), None, "line or tube colour"),
        ParamDecl::new("emission", Float(2.0), Some((0.0, 10.0)), "glow of the growing tips (lit tubes)"),
        ParamDecl::new(
            "light_dir",
            Vec3([-0.3, 0.8, -0.5]),
            Some((-1.0, 1.0)),
            "direction towards the light (lit tubes)",
        ),
        ParamDecl::new("background", Color([0.067, 0.092, 0.132, 1.0]), None, "background colour"),
        ParamDecl::new("scale", Float(6.0), Some((0.01, 100.0)), "object scale (the sphere's radius is half of it)"),
        ParamDecl::new("spin", Float(0.0), Some((-180.0, 180.0)), "turn about the vertical axis").with_unit("°/s"),
        ParamDecl::new("camera_position", Vec3([0.0, 0.0, -10.0]), Some((-100.0, 100.0)), "camera position")
            .with_unit("m"),
        ParamDecl::new("camera_pitch", Float(0.0), Some((-89.0, 89.0)), "camera looks down by").with_unit("°"),
        ParamDecl::new("fov", Float(40.0), Some((5.0, 120.0)), "vertical field of view").with_unit("°"),
        ParamDecl::choice(
            "msaa",
            &MSAA_MODES,
            1,
            "multisampling (the scene's msaa, 4 samples by default) keeps thin branches steady",
        ),
        ParamDecl::trigger("reset", "start the growth again (R in the window)").with_role(InputRole::Key('r')),
    ]
}

/// The growth shader's uniform block (`Growth` in `shaders/space_colonization.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GrowthUniforms {
    /// Attractions in the buffer.
    pub attraction_count: u32,
    /// Node slots (the free pool is `capacity − node count`).
    pub capacity: u32,
    /// Nodes that are roots (their slots come first).
    pub seed_count: u32,
    /// Cells of the grid.
    pub cell_count: u32,
    /// Cells per axis.
    pub dims: [u32; 3],
    /// 1: search every node; 0: the grid.
    pub brute_force: u32,
    /// The grid's lowest corner.
    pub origin: [f32; 3],
    /// The grid's cell side (≥ influence and kill distances).
    pub cell_size: f32,
    /// Influence distance, local units.
    pub influence: f32,
    /// Growth distance, local units.
    pub growth: f32,
    /// Kill distance, local units.
    pub kill: f32,
    /// dt · growth speed: t gained per unit mass this step.
    pub grow_step: f32,
    /// Lightest mass.
    pub mass_min: f32,
    /// Heaviest mass.
    pub mass_max: f32,
    /// Mixed into the mass hash.
    pub hash_seed: u32,
    /// Indices of one tube (the indexed draw's count).
    pub tube_indices: u32,
}

/// A uniform grid over the cloud: origin, cell side and cells per axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridLayout {
    /// Lowest corner.
    pub origin: [f32; 3],
    /// Cell side.
    pub cell_size: f32,
    /// Cells per axis.
    pub dims: [u32; 3],
}

impl GridLayout {
    /// Cells of side ≥ `reach` covering `lo..hi`, at most [`MAX_CELLS`] of them.
    pub fn covering(lo: [f32; 3], hi: [f32; 3], reach: f32) -> Self {
        let extent: [f32; 3] = std::array::from_fn(|i| (hi[i] - lo[i]).max(1e-6));
        let mut cell = reach.max(extent.iter().cloned().fold(0.0, f32::max) / 1024.0);
        loop {
            let dims: [u32; 3] = std::array::from_fn(|i| ((extent[i] / cell).ceil() as u32).max(1));
            if dims.iter().map(|&d| u64::from(d)).product::<u64>() <= u64::from(MAX_CELLS) {
                return Self { origin: lo, cell_size: cell, dims };
            }
            cell *= 1.25;
        }
    }

    /// Number of cells.
    pub fn cells(&self) -> u32 {
        self.dims.iter().product()
    }
}

/// Growth settings of one step, in local units (`unit` = the source's distance unit).
pub fn growth_uniforms(p: &ParamSet, unit: f32, dt: f32) -> GrowthUniforms {
    let influence = p.float("influence") * unit;
    let kill = p.float("kill_distance") * unit;
    let (lo, hi) = (p.float("mass_min"), p.float("mass_max"));
    GrowthUniforms {
        brute_force: u32::from(p.choice("search") == 0),
        influence,
        growth: p.float("growth_distance") * unit,
        kill,
        grow_step: dt * p.float("growth_speed"),
        mass_min: lo.min(hi),
        mass_max: lo.max(hi),
        ..bytemuck::Zeroable::zeroed()
    }
}

/// The draw shader's uniform block (`View` in `shaders/space_colonization_draw.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ViewUniforms {
    /// Projection × view.
    pub view_proj: [[f32; 4]; 4],
    /// Camera position.
    pub camera: [f32; 4],
    /// Linear colour.
    pub color: [f32; 4],
    /// Towards the light; w: emission of a tip at t = 0.
    pub light: [f32; 4],
    /// Tube radius (world units).
    pub thickness: f32,
    /// Root nodes (edge e ends at node seed_count + e).
    pub seed_count: u32,
    /// 1: lit tubes.
    pub lit: u32,
    /// Strength of the model's glow (0: not drawn).
    pub ghost: f32,
    /// Local → world of the model's mesh (after skinning).
    pub model: [[f32; 4]; 4],
    /// Linear floor colour; w: the floor's half size (0: no floor).
    pub floor: [f32; 4],
}

/// The pose kernel's uniform block (`Pose` in the growth shader).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PoseUniforms {
    /// Local → world.
    pub model: [[f32; 4]; 4],
    /// 1: skin nodes with the joint matrices first.
    pub skinned: u32,
    /// Padding.
    pub _pad: [u32; 3],
}

/// The object's transform: scale, then the spin about y.
pub fn model(p: &ParamSet, seconds: f64) -> glam::Mat4 {
    let angle = (p.float("spin") as f64 * seconds).to_radians() as f32;
    glam::Mat4::from_rotation_y(angle) * glam::Mat4::from_scale(glam::Vec3::splat(p.float("scale")))
}

/// The camera: at `camera_position`, looking along +z tilted down by `camera_pitch` (the
/// sample's left-handed Unity camera).
pub fn view_proj(p: &ParamSet, aspect: f32) -> (glam::Vec3, glam::Mat4) {
    let c = p.get("camera_position").components();
    let eye = glam::Vec3::new(c[0], c[1], c[2]);
    let pitch = p.float("camera_pitch").to_radians();
    let forward = glam::Vec3::new(0.0, -pitch.sin(), pitch.cos());
    let view = glam::camera::lh::view::look_to_mat4(eye, forward, glam::Vec3::Y);
    let proj = glam::camera::lh::proj::directx::perspective(p.float("fov").to_radians(), aspect, 0.05, 500.0);
    (eye, proj * view)
}
