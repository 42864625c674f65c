//! Space colonization parameters (the book's, with its defaults and ranges) and the uniform
//! blocks built from them.

use crate::params::{InputRole, ParamDecl, ParamValue, Text};
use crate::techniques::{Msaa, Rasterizer};

/// Most grid cells (the cell grows past the reach before the grid grows past this).
pub const MAX_CELLS: u32 = 1 << 21;

crate::param_enum! {
    /// Where the attractions are.
    pub enum Source {
        /// A jittered lattice sphere.
        Sphere = "Sphere",
        /// Inside the model's volume.
        Model = "Model",
    }
}

crate::param_enum! {
    /// How each attraction finds its nearest node.
    pub enum Search {
        /// Every node (the sample's way).
        BruteForce = "BruteForce",
        /// A uniform grid.
        Grid = "Grid",
    }
}

crate::param_enum! {
    /// How branches are drawn.
    pub enum View {
        /// Additive lines.
        Lines = "Lines",
        /// Tubes coloured by their normals.
        Tubes = "Tubes",
        /// Lit tubes with glowing tips.
        TubesLit = "TubesLit",
    }
}

crate::technique_params! {
    /// What a space colonization node reads each step, with the sample's defaults
    /// (seed-reference §1). Distances are in units of the lattice's `unit` (2 / side for the
    /// sphere, as the sample measures them); the sample's growth and kill defaults of 0.2 sat
    /// below their own 0.25 minimum (bug 7) and are 0.25 here.
    pub struct Settings {
        /// attractions in a jittered lattice sphere, or inside the model's volume
        source: Source = |n, doc| ParamDecl::choice(n, Source::OPTIONS, 0, doc),
        /// lattice points per axis: side 28 gives 10,144 attractions, 126 gives 1,022,208 (restarts)
        side: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(16), Some((8.0, 128.0)), doc),
        /// branches to start from (restarts)
        seed_count: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(6), Some((1.0, 64.0)), doc),
        /// another jitter and other seeds (restarts)
        variation: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(0), Some((0.0, 1e6)), doc),
        /// glTF 2.0 skinned model (.gltf or .glb) for the Model source
        model: Text = |n, doc| ParamDecl::text(n, "assets/models/RiggedFigure.gltf", doc),
        /// model voxels along its longest side (restarts)
        voxels: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(64), Some((16.0, 256.0)), doc),
        /// least distance between model attractions, in voxels (restarts)
        spacing: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(1.0), Some((0.5, 4.0)), doc),
        /// model distance unit, in voxels (the sample's unitScale)
        unit_scale: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(2.5), Some((0.5, 10.0)), doc),
        /// speed of the model's clip, played back and forth
        animation_speed: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.5), Some((0.0, 4.0)), doc),
        /// draw the model's skin as a faint glow over the branches
        show_model: bool = |n, doc| ParamDecl::new(n, ParamValue::Bool(false), None, doc),
        /// a lit floor under the model
        floor: bool = |n, doc| ParamDecl::new(n, ParamValue::Bool(false), None, doc),
        /// floor colour
        floor_color: [f32; 4] = |n, doc| ParamDecl::new(n, ParamValue::Color([0.868, 0.868, 0.868, 1.0]), None, doc),
        /// frames between growth updates (the sample's frame)
        update_every: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(1), Some((1.0, 5.0)), doc),
        /// growth steps per update (the sample's iterations)
        steps: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(1), Some((1.0, 16.0)), doc),
        /// lightest node: grows slowest
        mass_min: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.25), Some((0.0, 1.0)), doc),
        /// heaviest node: grows fastest
        mass_max: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(1.0), Some((0.0, 1.0)), doc),
        /// how far an attraction reaches, in units
        influence: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.25), Some((0.25, 3.0)), doc),
        /// length of a new branch segment, in units
        growth_distance: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.25), Some((0.25, 1.0)), doc),
        /// attractions this close to a node die, in units
        kill_distance: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.25), Some((0.25, 1.0)), doc),
        /// how fast a new segment grows out (t per second per mass)
        growth_speed: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(22.0), Some((0.0, 200.0)), doc),
        /// nearest-node search: a uniform grid, or every node (the sample's)
        search: Search = |n, doc| ParamDecl::choice(n, Search::OPTIONS, 1, doc),
        /// additive lines, tubes coloured by normal, or lit tubes with glowing tips
        view: View = |n, doc| ParamDecl::choice(n, View::OPTIONS, 0, doc),
        /// tube radius
        thickness: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.1), Some((0.001, 0.1)), doc).with_unit("m"),
        /// line or tube colour
        color: [f32; 4] = |n, doc| ParamDecl::new(n, ParamValue::Color([1.0, 1.0, 1.0, 1.0]), None, doc),
        /// glow of the growing tips (lit tubes)
        emission: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(2.0), Some((0.0, 10.0)), doc),
        /// direction towards the light (lit tubes)
        light_dir: [f32; 3] = |n, doc| ParamDecl::new(n, ParamValue::Vec3([-0.3, 0.8, -0.5]), Some((-1.0, 1.0)), doc),
        /// background colour
        background: [f32; 4] = |n, doc| ParamDecl::new(n, ParamValue::Color([0.067, 0.092, 0.132, 1.0]), None, doc),
        /// object scale (the sphere's radius is half of it)
        scale: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(6.0), Some((0.01, 100.0)), doc),
        /// turn about the vertical axis
        spin: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.0), Some((-180.0, 180.0)), doc).with_unit("°/s"),
        /// camera position
        camera_position: [f32; 3] =
            |n, doc| ParamDecl::new(n, ParamValue::Vec3([0.0, 0.0, -10.0]), Some((-100.0, 100.0)), doc).with_unit("m"),
        /// camera looks down by
        camera_pitch: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.0), Some((-89.0, 89.0)), doc).with_unit("°"),
        /// vertical field of view
        fov: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(40.0), Some((5.0, 120.0)), doc).with_unit("°"),
        /// multisampling (the scene's msaa, 4 samples by default) keeps thin branches steady
        msaa: Msaa = |n, doc| ParamDecl::choice(n, Msaa::OPTIONS, 1, doc),
        /// how tubes are drawn — compute: exact capsules found per sample in a visibility buffer
        /// (where the adapter has 64-bit atomics; the floor and the model's glow stay on the
        /// pipeline); pipeline: eight-sided tubes through the hardware rasterizer
        rasterizer: Rasterizer = |n, doc| ParamDecl::choice(n, Rasterizer::OPTIONS, 0, doc),
        /// start the growth again (R in the window)
        reset: bool = |n, doc| ParamDecl::trigger(n, doc).with_role(InputRole::Key('r')),
    }
}

/// The growth shader's uniform block (`Growth` in `space_colonization.wgsl`).
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
pub fn growth_uniforms(p: &Settings, unit: f32, dt: f32) -> GrowthUniforms {
    let influence = p.influence * unit;
    let kill = p.kill_distance * unit;
    let (lo, hi) = (p.mass_min, p.mass_max);
    GrowthUniforms {
        brute_force: u32::from(p.search == Search::BruteForce),
        influence,
        growth: p.growth_distance * unit,
        kill,
        grow_step: dt * p.growth_speed,
        mass_min: lo.min(hi),
        mass_max: lo.max(hi),
        ..bytemuck::Zeroable::zeroed()
    }
}

/// The draw shader's uniform block (`View` in `space_colonization_draw.wgsl`).
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
pub fn model(p: &Settings, seconds: f64) -> glam::Mat4 {
    let angle = (p.spin as f64 * seconds).to_radians() as f32;
    glam::Mat4::from_rotation_y(angle) * glam::Mat4::from_scale(glam::Vec3::splat(p.scale))
}

/// The camera: at `camera_position`, looking along +z tilted down by `camera_pitch` (the
/// sample's left-handed Unity camera).
pub fn view_proj(p: &Settings, aspect: f32) -> (glam::Vec3, glam::Mat4) {
    let eye = glam::Vec3::from(p.camera_position);
    let pitch = p.camera_pitch.to_radians();
    let forward = glam::Vec3::new(0.0, -pitch.sin(), pitch.cos());
    let view = glam::camera::lh::view::look_to_mat4(eye, forward, glam::Vec3::Y);
    let proj = glam::camera::lh::proj::directx::perspective(p.fov.to_radians(), aspect, 0.05, 500.0);
    (eye, proj * view)
}
