//! The tessellated surface's parameters (the book's material and scene), and the uniform block
//! they become: camera, frustum planes, light, material.

use glam::{Mat4, Vec3, Vec4};

use crate::params::{ParamDecl, ParamSet, ParamValue};
pub use crate::techniques::Rasterizer;
use crate::techniques::{Msaa, srgb_to_linear};

/// The base plane's side, world units (Unity's Plane).
pub const PLANE_SIZE: f32 = 10.0;

crate::param_enum! {
    /// What the surface shows.
    pub enum View {
        /// The lit surface.
        Shaded = "shaded",
        /// The wireframe over the shading.
        Wireframe = "wireframe",
        /// The tessellation level as colour.
        Level = "level",
    }
}

crate::param_enum! {
    /// Which channel of the input is the height.
    pub enum Channel {
        /// Red.
        Red = "red",
        /// Luminance.
        Luminance = "luminance",
    }
}

crate::technique_params! {
    /// What a tessellated surface reads each frame, with the book's scene and material values
    /// (seed-reference §6).
    pub struct Settings {
        /// base plane quads per side (10: the book's 200 triangles)
        grid: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(10), Some((1.0, 64.0)), doc),
        /// target edge length on screen
        edge_length: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(15.0), Some((1.0, 50.0)), doc).with_unit("px"),
        /// height × this along the normal, world units
        displacement: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.3), Some((0.0, 40.0)), doc),
        /// displace against the normal (the sample's V/F shader)
        inward: bool = |n, doc| ParamDecl::new(n, ParamValue::Bool(false), None, doc),
        /// which channel of the input texture is the height
        height_channel: Channel = |n, doc| ParamDecl::choice(n, Channel::OPTIONS, 0, doc),
        /// shaded, wireframe over shading, or tessellation level as colour
        view: View = |n, doc| ParamDecl::choice(n, View::OPTIONS, 0, doc),
        /// multisampling: on uses the scene's msaa (4 samples by default); off is faster where fill is slow
        msaa: Msaa = |n, doc| ParamDecl::choice(n, Msaa::OPTIONS, 1, doc),
        /// compute: a visibility buffer filled in compute (fast where the raster path is narrow, as on
        /// the H100/H200; needs 64-bit atomics, else pipeline); pipeline: the hardware rasterizer
        rasterizer: Rasterizer = |n, doc| ParamDecl::choice(n, Rasterizer::OPTIONS, 0, doc),
        /// camera distance from the origin
        camera_distance: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(10.0), Some((1.0, 100.0)), doc),
        /// camera orbit about y
        camera_yaw: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.0), Some((-180.0, 180.0)), doc).with_unit("°"),
        /// camera orbit elevation
        camera_pitch: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.0), Some((-89.0, 89.0)), doc).with_unit("°"),
        /// vertical field of view
        fov: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(60.0), Some((10.0, 120.0)), doc).with_unit("°"),
        /// diffuse colour (the book's is black)
        albedo: [f32; 4] = |n, doc| ParamDecl::new(n, ParamValue::Color([0.0, 0.0, 0.0, 1.0]), None, doc),
        /// specular colour
        spec_color: [f32; 4] = |n, doc| ParamDecl::new(n, ParamValue::Color([1.0, 1.0, 1.0, 0.5]), None, doc),
        /// specular exponent / 128
        specular: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.366), Some((0.01, 1.0)), doc),
        /// specular strength
        gloss: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.276), Some((0.0, 1.0)), doc),
        /// directional light intensity
        light_intensity: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(3.2), Some((0.0, 10.0)), doc),
        /// light elevation
        light_pitch: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(80.0), Some((-90.0, 90.0)), doc).with_unit("°"),
        /// light heading
        light_yaw: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(-30.0), Some((-180.0, 180.0)), doc).with_unit("°"),
        /// clear colour (the book's is white)
        background: [f32; 4] = |n, doc| ParamDecl::new(n, ParamValue::Color([1.0, 1.0, 1.0, 1.0]), None, doc),
    }
}

/// `Tess` in `tessellation.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TessUniforms {
    /// Plane to world.
    pub model: [[f32; 4]; 4],
    /// World to clip.
    pub view_proj: [[f32; 4]; 4],
    /// Left, right, bottom, top frustum planes (normalised, inside ≥ 0).
    pub planes: [[f32; 4]; 4],
    /// Camera position.
    pub camera: [f32; 4],
    /// Direction the light travels.
    pub light_dir: [f32; 4],
    /// Linear albedo.
    pub albedo: [f32; 4],
    /// Linear specular colour.
    pub spec_color: [f32; 4],
    /// Linear clear colour.
    pub background: [f32; 4],
    /// Quads per side.
    pub grid: u32,
    /// 2 × grid².
    pub patch_count: u32,
    /// Edges of the grid.
    pub edge_count: u32,
    /// A [`View`]'s index.
    pub view_mode: u32,
    /// Target edge length, pixels.
    pub edge_px: f32,
    /// Output height, pixels.
    pub screen_height: f32,
    /// Signed displacement.
    pub displacement: f32,
    /// Light intensity.
    pub light_intensity: f32,
    /// Exponent / 128.
    pub specular: f32,
    /// Specular strength.
    pub gloss: f32,
    /// 1: height is the luminance.
    pub luminance: u32,
    /// Plane side.
    pub plane_size: f32,
}

/// Edges of a `grid`² plane split into triangles: horizontal, vertical and diagonal.
pub fn edge_count(grid: u32) -> u32 {
    2 * (grid + 1) * grid + grid * grid
}

/// The book's plane transform (Unity (0, 1.23, −2.18), rotation (48°, 180°, 0)), in indra's
/// right-handed world (z towards the camera).
pub fn model() -> Mat4 {
    Mat4::from_translation(Vec3::new(0.0, 1.23, 2.18))
        * Mat4::from_rotation_y(std::f32::consts::PI)
        * Mat4::from_rotation_x((-48.0f32).to_radians())
}

/// Camera position and view-projection for `s` at `aspect`.
pub fn camera(s: &Settings, aspect: f32) -> (Vec3, Mat4) {
    let (yaw, pitch) = (s.camera_yaw.to_radians(), s.camera_pitch.to_radians());
    let eye = s.camera_distance * Vec3::new(yaw.sin() * pitch.cos(), pitch.sin(), yaw.cos() * pitch.cos());
    let view = glam::camera::rh::view::look_at_mat4(eye, Vec3::ZERO, Vec3::Y);
    let proj = glam::camera::rh::proj::directx::perspective(s.fov.to_radians(), aspect.max(1e-3), 0.1, 200.0);
    (eye, proj * view)
}

/// Left, right, bottom and top planes of `view_proj`, normalised so that distances are in world
/// units (Gribb & Hartmann).
pub fn frustum_planes(view_proj: Mat4) -> [Vec4; 4] {
    let (r0, r1, r3) = (view_proj.row(0), view_proj.row(1), view_proj.row(3));
    [r3 + r0, r3 - r0, r3 + r1, r3 - r1].map(|p| p / p.truncate().length().max(1e-12))
}

impl TessUniforms {
    /// The block for `params` on an output of `size` pixels.
    pub fn from_params(params: &ParamSet, size: (u32, u32)) -> Self {
        let s = Settings::read(params);
        let grid = s.grid.clamp(1, 64) as u32;
        let (eye, view_proj) = camera(&s, size.0 as f32 / size.1.max(1) as f32);
        let (pitch, yaw) = (s.light_pitch.to_radians(), s.light_yaw.to_radians());
        // Unity's light forward after (pitch, yaw), with z mirrored into the right-handed world.
        let light = Vec3::new(pitch.cos() * yaw.sin(), -pitch.sin(), -pitch.cos() * yaw.cos());
        let linear = |c: [f32; 4]| [srgb_to_linear(c[0]), srgb_to_linear(c[1]), srgb_to_linear(c[2]), c[3]];
        let sign = if s.inward { -1.0 } else { 1.0 };
        Self {
            model: model().to_cols_array_2d(),
            view_proj: view_proj.to_cols_array_2d(),
            planes: frustum_planes(view_proj).map(|p| p.to_array()),
            camera: eye.extend(1.0).to_array(),
            light_dir: light.extend(0.0).to_array(),
            albedo: linear(s.albedo),
            spec_color: linear(s.spec_color),
            background: linear(s.background),
            grid,
            patch_count: 2 * grid * grid,
            edge_count: edge_count(grid),
            view_mode: s.view.index(),
            edge_px: s.edge_length.max(0.5),
            screen_height: size.1 as f32,
            displacement: sign * s.displacement,
            light_intensity: s.light_intensity,
            specular: s.specular,
            gloss: s.gloss,
            luminance: u32::from(s.height_channel == Channel::Luminance),
            plane_size: PLANE_SIZE,
        }
    }
}
