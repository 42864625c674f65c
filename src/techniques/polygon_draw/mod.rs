//! The book's DrawTest [UGP4 ch.5]: draw polygons point by point; closing one re-triangulates
//! all of them together, so rings inside rings become holes and islands by nesting. The fill is
//! textured by a generated UV checker (UVs from the bounding rectangle of all polygons, as in the
//! book) with the triangle wireframe on top; the loop being drawn cycles its hue.
//!
//! Input is parameters only, so OSC, MIDI, recordings and tests can draw as well as the mouse:
//! `cursor` (view position, 0–1, y up) then the `add` trigger appends a vertex, `close` ends the
//! polygon, `undo` removes the last polygon, `clear` removes all. In the window a left click
//! sets `cursor` and fires `add`, a right click fires `close`, U and C fire `undo` and `clear`.
//! Shader: `polygon_draw.wgsl`.

use super::mesh2d_draw::{self as gpu, DrawStyle};
use crate::checkpoint::{CheckpointError, NodeState};
use crate::geometry::triangulate::{Mesh2D, Triangulator};
use crate::gpu::{Gpu, ShaderError};
use crate::graph::{FrameGraph, TextureHandle};
use crate::params::{InputRole, ParamDecl, ParamSet, ParamValue};
use crate::time::FrameTime;

use super::{NodeSetup, Technique, TechniqueInfo};

/// The registry entry.
pub const INFO: TechniqueInfo = TechniqueInfo {
    name: "polygon_draw",
    chapter: "5: Triangulation by ear clipping",
    summary: "draw polygons with the mouse or OSC; holes and islands by nesting, UV checker + wireframe",
    params: Settings::decls,
    inputs: &[],
    shaders: &["polygon_draw.wgsl"],
    create,
    check: None,
    stage: None,
    declare: None,
};

crate::param_enum! {
    /// What a drawing node starts with.
    pub enum Start {
        /// The book's nested test shapes.
        Book = "book",
        /// Nothing.
        Empty = "empty",
    }
}

crate::technique_params! {
    /// What a drawing node reads each step; the view is the sample's orthographic camera of
    /// size 5.
    pub struct Settings {
        /// where `add` puts a vertex: view position, y up
        cursor: [f32; 2] = |n, doc| {
            ParamDecl::new(n, ParamValue::Vec2([0.5, 0.5]), Some((0.0, 1.0)), doc).with_role(InputRole::Pointer)
        },
        /// append a vertex at the cursor to the polygon being drawn (left click)
        add: bool = |n, doc| ParamDecl::trigger(n, doc).with_role(InputRole::PrimaryClick),
        /// close the polygon being drawn and re-triangulate everything (right click)
        close: bool = |n, doc| ParamDecl::trigger(n, doc).with_role(InputRole::SecondaryClick),
        /// remove the last closed polygon (U in the window)
        undo: bool = |n, doc| ParamDecl::trigger(n, doc).with_role(InputRole::Key('u')),
        /// remove every polygon (C in the window)
        clear: bool = |n, doc| ParamDecl::trigger(n, doc).with_role(InputRole::Key('c')),
        /// start with the book's nested test shapes, or nothing
        start: Start = |n, doc| ParamDecl::choice(n, Start::OPTIONS, 0, doc),
        /// draw the triangle edges over the fill
        wireframe: bool = |n, doc| ParamDecl::new(n, ParamValue::Bool(true), None, doc),
        /// checker cells across the UV range
        checker: i32 = |n, doc| ParamDecl::new(n, ParamValue::Int(8), Some((1.0, 64.0)), doc),
        /// half the view height in world units
        view_size: f32 = |n, doc| ParamDecl::new(n, ParamValue::Float(5.0), Some((0.5, 100.0)), doc),
    }
}

impl Settings {
    /// How the mesh is drawn.
    pub fn style(&self) -> DrawStyle {
        DrawStyle { wireframe: self.wireframe, checker: self.checker, view_size: self.view_size }
    }
}

/// The sample's TriangulationTest data (seed-reference §5): an outer ring, two holes, three
/// islands inside the holes — clockwise, y up.
pub fn book_shapes() -> Vec<Vec<[f64; 2]>> {
    let rect = |x0: f64, y0: f64, x1: f64, y1: f64| vec![[x0, y0], [x0, y1], [x1, y1], [x1, y0]];
    vec![
        rect(-2.0, -2.0, 5.0, 2.0),
        rect(-1.0, -1.0, 1.0, 1.0),
        rect(2.0, -1.0, 4.0, 1.0),
        rect(-0.5, -0.5, 0.5, 0.5),
        rect(2.25, -0.75, 3.0, -0.25),
        rect(3.0, 0.25, 3.75, 0.75),
    ]
}

/// A drawing node.
pub struct PolygonDraw {
    gpu: gpu::Renderer,
    polygons: Vec<Vec<[f64; 2]>>,
    drawing: Vec<[f64; 2]>,
    triangulator: Triangulator,
    mesh: Mesh2D,
    /// The `start` option the polygons were seeded from.
    started: Option<u32>,
    /// Whether the GPU buffers are behind the polygons.
    dirty: bool,
    /// Width / height of the output, to map the cursor (view units) to world units.
    aspect: f32,
    messages: Vec<String>,
}

fn create(setup: &NodeSetup<'_>) -> Result<Box<dyn Technique>, ShaderError> {
    Ok(Box::new(PolygonDraw {
        gpu: gpu::Renderer::new(setup)?,
        polygons: Vec::new(),
        drawing: Vec::new(),
        triangulator: Triangulator::new(),
        mesh: Mesh2D::default(),
        started: None,
        dirty: true,
        aspect: setup.output_size.0 as f32 / setup.output_size.1.max(1) as f32,
        messages: Vec::new(),
    }))
}

impl PolygonDraw {
    /// The closed polygons, in world units.
    pub fn polygons(&self) -> &[Vec<[f64; 2]>] {
        &self.polygons
    }

    /// The current triangulation of all closed polygons.
    pub fn mesh(&self) -> &Mesh2D {
        &self.mesh
    }

    fn retriangulate(&mut self) {
        self.mesh = match self.triangulator.rings(&self.polygons) {
            Ok(mesh) => mesh,
            Err(e) => {
                self.messages.push(e.to_string());
                Mesh2D::default()
            }
        };
        self.messages.extend(self.mesh.report.warnings());
        self.dirty = true;
    }

    /// Applies the triggers of one fixed step (each fires for exactly one step).
    fn apply_triggers(&mut self, p: &Settings) {
        let aspect = self.aspect;
        let start = p.start.index();
        let mut changed = false;
        if self.started != Some(start) {
            self.started = Some(start);
            self.polygons = if start == 0 { book_shapes() } else { Vec::new() };
            self.drawing.clear();
            changed = true;
        }
        if p.clear {
            self.polygons.clear();
            self.drawing.clear();
            changed = true;
        }
        if p.undo && self.polygons.pop().is_some() {
            changed = true;
        }
        if p.add {
            let [cx, cy] = p.cursor;
            let half = f64::from(p.view_size);
            let world = [(f64::from(cx) * 2.0 - 1.0) * half * f64::from(aspect), (f64::from(cy) * 2.0 - 1.0) * half];
            if self.drawing.last() != Some(&world) {
                self.drawing.push(world);
                self.dirty = true;
            }
        }
        if p.close {
            if self.drawing.len() >= 3 {
                self.polygons.push(std::mem::take(&mut self.drawing));
                changed = true;
            } else if !self.drawing.is_empty() {
                self.messages.push(format!("a polygon needs 3 points; this one has {}", self.drawing.len()));
            }
        }
        if changed {
            self.retriangulate();
        }
    }
}

impl Technique for PolygonDraw {
    fn step(&mut self, params: &ParamSet, _time: &FrameTime) {
        self.apply_triggers(&Settings::read(params));
    }

    fn take_messages(&mut self) -> Vec<String> {
        std::mem::take(&mut self.messages)
    }

    fn save_state(&self, _gpu: &Gpu, state: &mut NodeState) -> Result<(), CheckpointError> {
        // Drawn polygons and the one being drawn: each is one ring, the rings in order.
        let rings: Vec<&Vec<[f64; 2]>> = self.polygons.iter().chain([&self.drawing]).collect();
        state.put_pod("ring_lengths", &rings.iter().map(|r| r.len() as u64).collect::<Vec<_>>());
        state.put_pod("points", &rings.iter().flat_map(|r| r.iter().copied()).collect::<Vec<_>>());
        state.put_option("started", self.started);
        Ok(())
    }

    fn load_state(&mut self, _: &Gpu, _: &ParamSet, _: &FrameTime, state: &NodeState) -> Result<(), CheckpointError> {
        let lengths = state.get_pod::<u64>("ring_lengths")?;
        let mut points = state.get_pod::<[f64; 2]>("points")?.into_iter();
        if lengths.is_empty() || lengths.iter().sum::<u64>() != points.len() as u64 {
            return Err(state.error("ring_lengths", "do not add up to the points saved".into()));
        }
        let mut rings: Vec<Vec<[f64; 2]>> =
            lengths.iter().map(|&n| points.by_ref().take(n as usize).collect()).collect();
        self.drawing = rings.pop().unwrap_or_default();
        self.polygons = rings;
        self.started = state.get_option("started")?;
        self.retriangulate();
        Ok(())
    }

    fn add_passes<'r>(
        &'r mut self,
        graph: &mut FrameGraph<'r>,
        params: &ParamSet,
        time: &FrameTime,
        _inputs: &[TextureHandle],
    ) -> TextureHandle {
        let (w, h) = graph.output_size();
        self.aspect = w as f32 / h.max(1) as f32;
        let settings = Settings::read(params);
        // A frame drawn before any step still shows the start shapes.
        if self.started.is_none() {
            self.apply_triggers(&settings);
        }
        if std::mem::take(&mut self.dirty) {
            self.gpu.upload(&self.mesh, &self.drawing);
        }
        self.gpu.add_pass(graph, "polygon_draw", &settings.style(), time)
    }
}

#[cfg(test)]
mod render_tests;
