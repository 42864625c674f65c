//! The tessellated surface's parameters (the book's material and scene), and the uniform block
//! they become: camera, frustum planes, light, material.

use glam::{Mat4, Vec3, Vec4};

use crate::params::{ParamDecl, ParamSet, ParamValue};
use crate::techniques::srgb_to_linear;

/// The base plane's side, world units (Unity's Plane).
pub const PLANE_SIZE: f32 = 10.0;

/// View modes.
pub const VIEWS: &[&str] = &["shaded", "wireframe", "level"];
/// Multisampling choices (index 1 = 4×).
pub const MSAA_MODES: &[&str] = &["off", "on"];
/// How the surface is drawn (index 0: in compute, where the adapter allows).
pub const RASTERIZERS: &[&str] = &["compute", "pipeline"];
/// Which channel of the input is the height.
pub const CHANNELS: &[&str] = &["red", "luminance"];

/// Parameters with the book's scene and material values (seed-reference §6).
pub fn params() -> Vec<ParamDecl> {
    use ParamValue::*;
    vec![
        ParamDecl::new("grid", Int(10), Some((1.0, 64.0)), "base plane quads per side (10: the book's 200 triangles)"),
        ParamDecl::new("edge_length", Float(15.0), Some((1.0, 50.0)), "target edge length on screen").with_unit("px"),
        ParamDecl::new("displacement", Float(0.3), Some((0.0, 40.0)), "height × this along the normal, world units"),
        ParamDecl::new("inward", Bool(false), None, "displace against the normal (the sample's V/F shader)"),
        ParamDecl::choice("height_channel", CHANNELS, 0, "which channel of the input texture is the height"),
        ParamDecl::choice("view", VIEWS, 0, "shaded, wireframe over shading, or tessellation level as colour"),
        ParamDecl::choice(
            "msaa",
            MSAA_MODES,
            1,
            "multisampling: on uses the scene's msaa (4 samples by default); off is faster where fill is slow",
        ),
        ParamDecl::choice(
            "rasterizer",
            RASTERIZERS,
            0,
            "compute: a visibility buffer filled in compute (fast where the raster path is narrow, as on \
             the H100/H200; needs 64-bit atomics, else pipeline); pipeline: the hardware rasterizer",
        ),
        ParamDecl::new("camera_distance", Float(10.0), Some((1.0, 100.0)), "camera distance from the origin"),
        ParamDecl::new("camera_yaw", Float(0.0), Some((-180.0, 180.0)), "camera orbit about y").with_unit("°"),
        ParamDecl::new("camera_pitch", Float(0.0), Some((-89.0, 89.0)), "camera orbit elevation").with_unit("°"),
        ParamDecl::new("fov", Float(60.0), Some((10.0, 120.0)), "vertical field of view").with_unit("°"),
        ParamDecl::new("albedo", Color([0.0, 0.0, 0.0, 1.0]), None, "diffuse colour (the book's is black)"),
        ParamDecl::new("spec_color", Color([1.0, 1.0, 1.0, 0.5]), None, "specular colour"),
        ParamDecl::new("specular", Float(0.366), Some((0.01, 1.0)), "specular exponent / 128"),
        ParamDecl::new("gloss", Float(0.276), Some((0.0, 1.0)), "specular strength"),
        ParamDecl::new("light_intensity", Float(3.2), Some((0.0, 10.0)), "directional light intensity"),
        ParamDecl::new("light_pitch", Float(80.0), Some((-90.0, 90.0)), "light elevation").with_unit("°"),
        ParamDecl::new("light_yaw", Float(-30.0), Some((-180.0, 180.0)), "light heading").with_unit("°"),
        ParamDecl::new("background", Color([1.0, 1.0, 1.0, 1.0]), None, "clear colour (the book's is white)"),
    ]
}

/// `Tess` in `shaders/tessellation.wgsl`.
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
    /// Index into [`VIEWS`].
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

/// Camera position and view-projection for `params` at `aspect`.
pub fn camera(params: &ParamSet, aspect: f32) -> (Vec3, Mat4) {
    let (yaw, pitch) = (params.float("camera_yaw").to_radians(), params.float("camera_pitch").to_radians());
    let eye =
        params.float("camera_distance") * Vec3::new(yaw.sin() * pitch.cos(), pitch.sin(), yaw.cos() * pitch.cos());
    let view = glam::camera::rh::view::look_at_mat4(eye, Vec3::ZERO, Vec3::Y);
    let proj =
        glam::camera::rh::proj::directx::perspective(params.float("fov").to_radians(), aspect.max(1e-3), 0.1, 200.0);
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
        let grid = params.int("grid").clamp(1, 64) as u32;
        let (eye, view_proj) = camera(params, size.0 as f32 / size.1.max(1) as f32);
        let (pitch, yaw) = (params.float("light_pitch").to_radians(), params.float("light_yaw").to_radians());
        // Unity's light forward after (pitch, yaw), with z mirrored into the right-handed world.
        let light = Vec3::new(pitch.cos() * yaw.sin(), -pitch.sin(), -pitch.cos() * yaw.cos());
        let linear = |name: &str| {
            let c = params.color(name);
            [srgb_to_linear(c[0]), srgb_to_linear(c[1]), srgb_to_linear(c[2]), c[3]]
        };
        let sign = if params.bool("inward") { -1.0 } else { 1.0 };
        Self {
            model: model().to_cols_array_2d(),
            view_proj: view_proj.to_cols_array_2d(),
            planes: frustum_planes(view_proj).map(|p| p.to_array()),
            camera: eye.extend(1.0).to_array(),
            light_dir: light.extend(0.0).to_array(),
            albedo: linear("albedo"),
            spec_color: linear("spec_color"),
            background: linear("background"),
            grid,
            patch_count: 2 * grid * grid,
            edge_count: edge_count(grid),
            view_mode: params.choice("view"),
            edge_px: params.float("edge_length").max(0.5),
            screen_height: size.1 as f32,
            displacement: sign * params.float("displacement"),
            light_intensity: params.float("light_intensity"),
            specular: params.float("specular"),
            gloss: params.float("gloss"),
            luminance: u32::from(params.choice("height_channel") == 1),
            plane_size: PLANE_SIZE,
        }
    }
}
