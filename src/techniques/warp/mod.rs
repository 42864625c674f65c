//! Projection mapping as a node: the corner pin, the mesh warp and soft edge blending of one
//! output (see [`crate::geometry::warp`]), applied to any texture in the frame graph. Any scene
//! can end in it, so `render` produces warped frames off-screen and goldens test them.
//!
//! The corners and blend settings are live parameters (panel, OSC, MIDI, presets, recordings).
//! The `file` parameter names a warp file (RON): loading it — at start, when the path changes, or
//! on `reload` — sets those parameters from the file and takes its mesh; `save` writes the live
//! values and the mesh back. A file that cannot be read or parsed is one message, and the last
//! good warp stays on the wall.

use std::path::PathBuf;

use crate::assets::Assets;
use crate::checkpoint::{CheckpointError, NodeState};
use crate::files::Loader;
use crate::geometry::warp::{Corners, EdgeBlend, Homography, MAX_MESH_SIDE, MeshWarp, Region, WarpFile};
use crate::gpu::{Gpu, ShaderError};
use crate::graph::{FrameGraph, TextureHandle};
use crate::params::{ParamDecl, ParamSet, ParamValue, Text};
use crate::time::FrameTime;

use super::image_pass::{self, ImageKernel, ImagePass};
use super::{NodeSetup, Technique, TechniqueInfo};

/// The registry entry.
pub const INFO: TechniqueInfo = TechniqueInfo {
    name: "warp",
    chapter: "stage output: projection mapping",
    summary: "corner pin, mesh warp and soft edge blend of any texture, for projectors",
    params: Settings::decls,
    inputs: &["source"],
    shaders: &["warp.wgsl"],
    create,
    check: None,
    stage: Some(super::StageEdit {
        file: "file",
        corners: CORNERS,
        mesh_point: "mesh_point",
        grid: "grid",
        save: "save",
    }),
    declare: None,
};

/// Output format: linear HDR like every node.
pub const FORMAT: wgpu::TextureFormat = image_pass::FORMAT;

/// The example warps the bundled scenes use, by the path they give.
const BUNDLED: [(&str, &str); 3] = [
    ("warps/wall-left.ron", include_str!("../../../warps/wall-left.ron")),
    ("warps/wall-left-half.ron", include_str!("../../../warps/wall-left-half.ron")),
    ("warps/wall-right.ron", include_str!("../../../warps/wall-right.ron")),
];

/// The largest warp file read: a 16 × 16 mesh with blend settings is a few kilobytes.
const WARP_FILE_LIMIT: u64 = 1 << 20;

/// Pairs of control points the uniform block holds: the largest mesh with its extrapolated ring.
const POINT_PAIRS: usize = ((MAX_MESH_SIDE as usize + 2) * (MAX_MESH_SIDE as usize + 2)).div_ceil(2);

/// The corner parameters, in the order of the OSC aliases `/indra/output/<n>/corner/<i>`:
/// clockwise from the top left.
pub const CORNERS: [&str; 4] = ["corner_tl", "corner_tr", "corner_br", "corner_bl"];

crate::technique_params! {
    /// What a warp node reads each step.
    pub struct Settings {
        /// where the image's top-left corner lands (view units, y up)
        corner_tl: [f32; 2] = |n, doc| corner(n, [0.0, 1.0], doc),
        /// where the top-right corner lands
        corner_tr: [f32; 2] = |n, doc| corner(n, [1.0, 1.0], doc),
        /// where the bottom-right corner lands
        corner_br: [f32; 2] = |n, doc| corner(n, [1.0, 0.0], doc),
        /// where the bottom-left corner lands
        corner_bl: [f32; 2] = |n, doc| corner(n, [0.0, 0.0], doc),
        /// lower-left of the part of the source shown
        region_min: [f32; 2] = |n, doc| ParamDecl::new(n, ParamValue::Vec2([0.0, 0.0]), Some((0.0, 1.0)), doc),
        /// upper-right of the part of the source shown
        region_max: [f32; 2] = |n, doc| ParamDecl::new(n, ParamValue::Vec2([1.0, 1.0]), Some((0.0, 1.0)), doc),
        /// soft edge on the left, as a share of the image
        blend_left: f32 = edge_width,
        /// soft edge on the right
        blend_right: f32 = edge_width,
        /// soft edge at the top
        blend_top: f32 = edge_width,
        /// soft edge at the bottom
        blend_bottom: f32 = edge_width,
        /// blend ramp exponent: 1 linear, 2 S-curve
        blend_curve: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(2.0), Some((0.25, 8.0)), doc),
        /// exponent on the blend weight (1: exact in linear light)
        blend_gamma: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(1.0), Some((0.2, 4.0)), doc),
        /// black raised outside the blend zones to match the overlap
        black_lift: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(0.0), Some((0.0, 0.25)), doc),
        /// draw the mesh and its control points (for lining up)
        grid: bool = |n, doc| ParamDecl::new(n, ParamValue::Bool(false), None, doc),
        /// mesh control points across and up; a change resamples the mesh's shape
        mesh_size: [f32; 2] =
            |n, doc| ParamDecl::new(n, ParamValue::Vec2([2.0, 2.0]), Some((2.0, MAX_MESH_SIDE as f32)), doc),
        /// move mesh point (index, x, y): x, y in view units (an output window's edit mode writes it)
        mesh_point: [f32; 3] =
            |n, doc| ParamDecl::new(n, ParamValue::Vec3([-1.0, 0.0, 0.0]), Some((-1.0, 1024.0)), doc),
        /// warp file (RON) to load corners, blend and mesh from; empty: none
        file: Text = |n, doc| ParamDecl::text(n, "", doc),
        /// read the warp file again
        reload: bool = |n, doc| ParamDecl::trigger(n, doc),
        /// write the live corners, blend and mesh to the warp file
        save: bool = |n, doc| ParamDecl::trigger(n, doc),
    }
}

/// A corner's declaration: where it lands, in view units.
fn corner(name: &str, at: [f32; 2], doc: &str) -> ParamDecl {
    ParamDecl::new(name, ParamValue::Vec2(at), Some((-1.0, 2.0)), doc)
}

/// A soft edge's width, as a share of the image.
fn edge_width(name: &str, doc: &str) -> ParamDecl {
    ParamDecl::new(name, ParamValue::Float(0.0), Some((0.0, 0.5)), doc)
}

/// The shader's uniform block.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct WarpUniforms {
    /// View units → the unit square after the mesh (the inverse corner pin), as three padded
    /// columns.
    pub inverse_pin: [[f32; 4]; 3],
    /// Blend widths: left, right, top, bottom.
    pub blend: [f32; 4],
    /// Ramp exponent, gamma, black lift, grid on (1) or off (0).
    pub shape: [f32; 4],
    /// Mesh cells across and up, 1 when the mesh is the identity, 1 smooth or 0 linear.
    pub grid: [f32; 4],
    /// The part of the source shown: min x, min y, max x, max y (v up).
    pub region: [f32; 4],
    /// The control points and their extrapolated ring (see `MeshWarp::extended_points`), two
    /// to an entry.
    pub points: [[f32; 4]; POINT_PAIRS],
}

/// A warp node.
pub struct Warp {
    kernel: ImageKernel,
    pass: ImagePass,
    /// Where warp files are looked up, and may be saved.
    assets: Assets,
    /// Warp files being read and parsed off the render thread.
    loader: Loader<(Option<PathBuf>, WarpFile)>,
    /// Files this node read or wrote as warp files: a save may replace them.
    warp_files: std::collections::BTreeSet<PathBuf>,
    /// The mesh in use (a regular 2×2 grid without one).
    mesh: MeshWarp,
    /// The part of the source shown at the last step, for the pointer.
    region: Region,
    /// The `mesh_size` last applied (the loaded mesh's after a file load).
    applied_size: [u32; 2],
    /// The `mesh_point` last applied, so each write moves its point once.
    applied_point: [f32; 3],
    /// The corner pin of the last step (mesh handles and `mesh_point` are in view units).
    pin: Homography,
    /// The file path last loaded (or tried), so a bad path is reported once.
    requested: Option<String>,
    /// Values read from the file, for the scene to set (see [`Technique::take_loaded_values`]).
    loaded: Vec<(&'static str, ParamValue)>,
    messages: Vec<String>,
}

fn create(setup: &NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError> {
    Ok(Box::new(Warp::new(setup)?))
}

impl Warp {
    /// Builds the kernel from `warp.wgsl`.
    pub fn new(setup: &NodeSetup<'_>) -> Result<Self, ShaderError> {
        let device = &setup.gpu.device;
        let (origin, source) = setup.shader_source("warp.wgsl", &image_pass::bindings(1))?;
        let kernel = ImageKernel::new(device, (&origin, &source), "warp", 1, size_of::<WarpUniforms>() as u64)?;
        Ok(Self {
            pass: ImagePass::new(device, &kernel),
            kernel,
            assets: setup.assets.clone(),
            loader: Loader::new(setup.assets.load_wait()),
            warp_files: Default::default(),
            mesh: MeshWarp::regular(2, 2),
            applied_size: [2, 2],
            applied_point: [-1.0, 0.0, 0.0],
            pin: Corners::default().homography(),
            region: Region::default(),
            requested: None,
            loaded: Vec::new(),
            messages: Vec::new(),
        })
    }

    /// The mesh in use.
    pub fn mesh(&self) -> &MeshWarp {
        &self.mesh
    }

    /// Starts reading the warp file; [`Warp::take_loaded`] applies it when it is ready.
    fn load(&mut self, path: &str) {
        let (assets, name) = (self.assets.clone(), path.to_string());
        self.loader.request(path, move || read_warp(&assets, &name));
    }

    /// Applies a finished load: its values go to the parameters and its mesh is used; a file
    /// that failed leaves the last good warp.
    fn take_loaded(&mut self) {
        let Some((_, read)) = self.loader.poll() else { return };
        match read {
            Ok((file, warp)) => {
                self.warp_files.extend(file);
                self.mesh = warp.mesh.clone().unwrap_or_else(|| MeshWarp::regular(2, 2));
                self.applied_size = [self.mesh.columns, self.mesh.rows];
                self.loaded = loaded_values(&warp);
                let size = [self.mesh.columns as f32, self.mesh.rows as f32];
                self.loaded.push(("mesh_size", ParamValue::Vec2(size)));
            }
            Err(e) => self.messages.push(format!("{e}; keeping the last good warp")),
        }
    }

    /// Writes the live values and the mesh to the warp file (atomically), if the file rules
    /// allow saving there.
    fn save(&mut self, path: &str, settings: &Settings) {
        if path.is_empty() {
            self.messages.push("warp not saved: set the node's file parameter first".into());
            return;
        }
        let warp = warp_from(settings, Some(self.mesh.clone()));
        let file = match self.assets.locate_for_saving(path, "ron") {
            Ok(file) => file,
            Err(e) => return self.messages.push(format!("warp not saved: {e}")),
        };
        // A scene or preset is a .ron inside the allowed folders too: a save replaces only a
        // warp file — one that reads as a warp, or that this node read as one before (it may be
        // broken mid-edit) — or makes a new one, never another kind of file.
        let known = self.warp_files.contains(&file);
        if file.exists() && !known && read_warp(&self.assets, &file.display().to_string()).is_err() {
            let message = format!("warp not saved: {} exists and is not a warp file", file.display());
            return self.messages.push(message);
        }
        match crate::atomic_file::write(&file, warp.to_ron().as_bytes()) {
            Ok(()) => {
                self.messages.push(format!("warp saved to {}", file.display()));
                self.warp_files.insert(file);
            }
            Err(e) => self.messages.push(format!("cannot save the warp to {}: {e}", file.display())),
        }
    }

    /// Applies `mesh_size` (resampling the mesh's shape to the new grid) and `mesh_point` (one
    /// control point moved to a view position, through the inverse corner pin) when they change.
    fn edit_mesh(&mut self, settings: &Settings) {
        let size = settings.mesh_size.map(|v| (v.round() as u32).clamp(2, MAX_MESH_SIDE));
        if size != self.applied_size {
            let regular = MeshWarp::regular(size[0], size[1]);
            let points = regular.points.iter().map(|p| self.mesh.evaluate(p[0], p[1])).collect();
            self.mesh = MeshWarp { points, interpolation: self.mesh.interpolation, ..regular };
            self.applied_size = size;
        }
        let point = settings.mesh_point;
        if point != self.applied_point {
            self.applied_point = point;
            let index = point[0].round();
            let target = self.pin.inverse().and_then(|h| h.apply([f64::from(point[1]), f64::from(point[2])]));
            if let (Some(slot), Some(at)) = (self.mesh.points.get_mut(index.max(0.0) as usize), target)
                && index >= 0.0
            {
                *slot = [at[0] as f32, at[1] as f32];
            }
        }
    }
}

/// A warp node's checkpoint: its mesh, the size and point edits last applied, the file last read.
type Saved = (MeshWarp, [u32; 2], [f32; 3], Option<String>);

/// The source point the mesh sends to `target` (Newton's method from the target itself, with a
/// finite-difference Jacobian); None when it does not converge.
fn invert_mesh(mesh: &MeshWarp, target: [f32; 2]) -> Option<[f32; 2]> {
    let mut uv = target;
    for _ in 0..20 {
        let p = mesh.evaluate(uv[0], uv[1]);
        let r = [p[0] - target[0], p[1] - target[1]];
        if r[0].abs() < 1e-6 && r[1].abs() < 1e-6 {
            return Some(uv);
        }
        let h = 1e-3;
        let du = mesh.evaluate(uv[0] + h, uv[1]);
        let dv = mesh.evaluate(uv[0], uv[1] + h);
        let j = [[(du[0] - p[0]) / h, (dv[0] - p[0]) / h], [(du[1] - p[1]) / h, (dv[1] - p[1]) / h]];
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        if det.abs() < 1e-9 {
            return None;
        }
        uv[0] -= (j[1][1] * r[0] - j[0][1] * r[1]) / det;
        uv[1] -= (-j[1][0] * r[0] + j[0][0] * r[1]) / det;
    }
    let p = mesh.evaluate(uv[0], uv[1]);
    ((p[0] - target[0]).abs() < 1e-4 && (p[1] - target[1]).abs() < 1e-4).then_some(uv)
}

/// Reads and parses warp file `name` under the file rules, with the file it was read from; the
/// bundled examples are built in, so their scenes map the same from any folder.
fn read_warp(assets: &Assets, name: &str) -> Result<(Option<PathBuf>, WarpFile), String> {
    let bundled = BUNDLED.iter().find(|(bundled, _)| *bundled == name).map(|(_, text)| text.as_bytes());
    let read = assets.read_file(name, WARP_FILE_LIMIT, bundled).map_err(|e| format!("cannot read warp file: {e}"))?;
    let text =
        std::str::from_utf8(&read.bytes).map_err(|_| format!("cannot read warp file {}: not UTF-8", read.origin))?;
    Ok((read.path, WarpFile::parse(&read.origin, text)?))
}

/// The parameter values a warp file sets.
fn loaded_values(warp: &WarpFile) -> Vec<(&'static str, ParamValue)> {
    let c = &warp.corners;
    let b = &warp.blend;
    let mut values: Vec<(&'static str, ParamValue)> = CORNERS
        .iter()
        .zip([c.top_left, c.top_right, c.bottom_right, c.bottom_left])
        .map(|(n, p)| (*n, ParamValue::Vec2(p)))
        .collect();
    values.extend([
        ("region_min", ParamValue::Vec2(warp.region.min)),
        ("region_max", ParamValue::Vec2(warp.region.max)),
        ("blend_left", ParamValue::Float(b.left)),
        ("blend_right", ParamValue::Float(b.right)),
        ("blend_top", ParamValue::Float(b.top)),
        ("blend_bottom", ParamValue::Float(b.bottom)),
        ("blend_curve", ParamValue::Float(b.curve)),
        ("blend_gamma", ParamValue::Float(b.gamma)),
        ("black_lift", ParamValue::Float(warp.black_lift)),
    ]);
    values
}

/// The warp the settings describe, with `mesh`.
pub fn warp_from(s: &Settings, mesh: Option<MeshWarp>) -> WarpFile {
    WarpFile {
        region: Region { min: s.region_min, max: s.region_max },
        corners: Corners {
            top_left: s.corner_tl,
            top_right: s.corner_tr,
            bottom_right: s.corner_br,
            bottom_left: s.corner_bl,
        },
        blend: EdgeBlend {
            left: s.blend_left,
            right: s.blend_right,
            top: s.blend_top,
            bottom: s.blend_bottom,
            curve: s.blend_curve,
            gamma: s.blend_gamma,
        },
        black_lift: s.black_lift,
        mesh: mesh.filter(|m| *m != MeshWarp::regular(2, 2)),
    }
}

/// The uniforms for `settings` with `mesh`.
pub fn uniforms(settings: &Settings, mesh: &MeshWarp) -> WarpUniforms {
    let warp = warp_from(settings, None);
    let b = warp.blend;
    // A degenerate pin (corners on one line) shows nothing: every pixel is beyond its horizon.
    let inverse = warp.corners.homography().inverse();
    let inverse_pin =
        inverse.map_or([[0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0], [0.0, 0.0, -1.0, 0.0]], |h| h.to_wgsl_columns());
    let mut points = [[0.0; 4]; POINT_PAIRS];
    for (slot, pair) in points.iter_mut().zip(mesh.extended_points().chunks(2)) {
        let second = pair.get(1).copied().unwrap_or_default();
        *slot = [pair[0][0], pair[0][1], second[0], second[1]];
    }
    let smooth = mesh.interpolation == crate::geometry::warp::MeshInterpolation::Smooth;
    WarpUniforms {
        inverse_pin,
        blend: [b.left, b.right, b.top, b.bottom],
        shape: [b.curve, b.gamma, warp.black_lift, if settings.grid { 1.0 } else { 0.0 }],
        grid: [
            (mesh.columns - 1) as f32,
            (mesh.rows - 1) as f32,
            if mesh.is_identity() { 1.0 } else { 0.0 },
            if smooth { 1.0 } else { 0.0 },
        ],
        region: [warp.region.min[0], warp.region.min[1], warp.region.max[0], warp.region.max[1]],
        points,
    }
}

impl Technique for Warp {
    fn step(&mut self, params: &ParamSet, _time: &FrameTime) {
        let settings = Settings::read(params);
        // Edits first: a file loaded in this step replaces the mesh, and its size reaches the
        // parameters only after the step.
        let warp = warp_from(&settings, None);
        self.pin = warp.corners.homography();
        self.region = warp.region;
        self.edit_mesh(&settings);
        let path = settings.file.as_str().trim().to_string();
        let changed = self.requested.as_deref() != Some(path.as_str());
        if (changed || settings.reload) && !path.is_empty() {
            self.load(&path);
        }
        self.take_loaded();
        if changed && path.is_empty() && self.requested.is_some() {
            self.mesh = MeshWarp::regular(2, 2);
            self.applied_size = [2, 2];
            self.loaded.push(("mesh_size", ParamValue::Vec2([2.0, 2.0])));
        }
        self.requested = Some(path.clone());
        if settings.save {
            self.save(&path, &settings);
        }
    }

    fn handles(&self) -> Vec<[f32; 2]> {
        let view = |p: &[f32; 2]| self.pin.apply([f64::from(p[0]), f64::from(p[1])]);
        self.mesh.points.iter().filter_map(view).map(|v| [v[0] as f32, v[1] as f32]).collect()
    }

    fn take_loaded_values(&mut self) -> Vec<(&'static str, ParamValue)> {
        std::mem::take(&mut self.loaded)
    }

    fn take_messages(&mut self) -> Vec<String> {
        std::mem::take(&mut self.messages)
    }

    fn save_state(&self, _gpu: &Gpu, state: &mut NodeState) -> Result<(), CheckpointError> {
        // Mesh edits are writes applied once each; the file last read is not read again.
        let saved: Saved = (self.mesh.clone(), self.applied_size, self.applied_point, self.requested.clone());
        state.put("mesh", ron::to_string(&saved).expect("a mesh serialises").into_bytes());
        Ok(())
    }

    fn load_state(
        &mut self,
        _: &Gpu,
        params: &ParamSet,
        _: &FrameTime,
        state: &NodeState,
    ) -> Result<(), CheckpointError> {
        let text = std::str::from_utf8(state.get("mesh")?).map_err(|_| state.error("mesh", "is not text".into()))?;
        let (mesh, size, point, requested): Saved =
            ron::from_str(text).map_err(|e| state.error("mesh", format!("does not parse: {e}")))?;
        let sides_fit = [mesh.columns, mesh.rows].iter().all(|s| (2..=MAX_MESH_SIDE).contains(s));
        if !sides_fit || mesh.points.len() != (mesh.columns * mesh.rows) as usize {
            return Err(state.error("mesh", "is not a mesh this node makes".into()));
        }
        let warp = warp_from(&Settings::read(params), None);
        (self.pin, self.region) = (warp.corners.homography(), warp.region);
        (self.mesh, self.applied_size, self.applied_point, self.requested) = (mesh, size, point, requested);
        Ok(())
    }

    fn map_pointer(&self, view: [f32; 2]) -> Option<[f32; 2]> {
        // A pointer on the wall lands on the source point shown there (a fluid is stirred under
        // it): undo the corner pin exactly, then the mesh by Newton steps.
        let pinned = self.pin.inverse()?.apply([f64::from(view[0]), f64::from(view[1])])?;
        let target = [pinned[0] as f32, pinned[1] as f32];
        let uv = invert_mesh(&self.mesh, target)?;
        let (lo, hi) = (self.region.min, self.region.max);
        uv.iter()
            .all(|c| (0.0..=1.0).contains(c))
            .then(|| [lo[0] + uv[0] * (hi[0] - lo[0]), lo[1] + uv[1] * (hi[1] - lo[1])])
    }

    fn add_passes<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        params: &ParamSet,
        _time: &FrameTime,
        inputs: &[TextureHandle],
    ) -> TextureHandle {
        let uniforms = uniforms(&Settings::read(params), &self.mesh);
        let Some(&source) = inputs.first() else { return image_pass::black(graph) };
        self.pass.declare(graph, "warp", &self.kernel, uniforms, &[source])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_layout_matches_the_wgsl_struct() {
        let source = include_str!("warp.wgsl");
        assert_eq!(crate::gpu::wgsl_struct_size(source, "WarpUniforms"), Some(size_of::<WarpUniforms>() as u32));
    }

    #[test]
    fn a_warp_file_round_trips_through_the_parameters() {
        let mut params = ParamSet::new(super::Settings::decls());
        let warp = WarpFile {
            region: Region { min: [0.0, 0.1], max: [0.6, 1.0] },
            corners: Corners { top_left: [0.1, 0.95], bottom_right: [0.9, 0.02], ..Default::default() },
            blend: EdgeBlend { right: 0.2, curve: 3.0, gamma: 1.2, ..Default::default() },
            black_lift: 0.03,
            mesh: None,
        };
        for (name, value) in loaded_values(&warp) {
            assert!(params.set_at(params.index(name).unwrap(), value), "{name}");
        }
        params.snap();
        assert_eq!(warp_from(&Settings::read(&params), None), warp);
    }

    #[test]
    fn the_pointer_finds_the_source_point_through_pin_and_mesh() {
        let mut mesh = MeshWarp::regular(3, 3);
        mesh.points[4] = [0.56, 0.45];
        for uv in [[0.5f32, 0.5], [0.2, 0.7], [0.9, 0.1]] {
            let found = invert_mesh(&mesh, mesh.evaluate(uv[0], uv[1])).unwrap();
            assert!((found[0] - uv[0]).abs() < 1e-4 && (found[1] - uv[1]).abs() < 1e-4, "{uv:?} → {found:?}");
        }
    }
}

#[cfg(test)]
mod render_tests;
